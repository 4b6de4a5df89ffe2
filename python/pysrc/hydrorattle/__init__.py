"""HydroRATTLE from Python: bonded rigid spheres of unequal size in a viscous fluid.

The kernel (Rust, ``no_std``) computes far-field hydrodynamics from the polydisperse
Rotne-Prager-Yamakawa grand mobility and holds bond lengths with SHAKE/RATTLE
constraint solves. This package calls it with NumPy arrays:

* :func:`mobility`, :func:`mobility_dot`: the mobility matrix and its product;
* :class:`System`: particles and bonds stepped by the kernel (:meth:`System.step`,
  :meth:`System.run`);
* :func:`load_scene`, :func:`run_scene`, :func:`resume_run`, :func:`read_run`: the
  scene files and runs of the ``host-demo`` CLI, through the same library code (same
  files, same bits; Ctrl-C stops a run with a checkpoint, as the CLI's).

Units are the caller's, consistent: with lengths in ``L``, viscosity in ``eta`` and
forces in ``F``, velocities come out in ``F / (eta L)``, times in ``eta L^2 / F``. The
project's scenes use the tail radius, the viscosity and a tail's buoyant weight as
units (a lone tail settles at speed 1).

Every array returned is a new float64 (or int64) array: a copy, never a view of the
kernel's state, which only a successful step changes.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator, NamedTuple, Optional, Union

import numpy as np

from . import _hydrorattle as _core
from ._hydrorattle import (
    ConvergenceError,
    ContactsFullError,
    DegenerateError,
    InvalidStateError,
    LinalgError,
    NonFiniteError,
    OverlapError,
    Report,
    SceneError,
    StepError,
    SystemBusyError,
    UnstableError,
    UnsupportedError,
    __version__,
)

__all__ = [
    "__version__",
    "mobility",
    "mobility_dot",
    "System",
    "Frame",
    "Report",
    "Run",
    "load_scene",
    "run_scene",
    "resume_run",
    "read_run",
    "StepError",
    "InvalidStateError",
    "ConvergenceError",
    "LinalgError",
    "DegenerateError",
    "NonFiniteError",
    "OverlapError",
    "UnstableError",
    "ContactsFullError",
    "UnsupportedError",
    "SceneError",
    "SystemBusyError",
]

PathLike = Union[str, "os.PathLike[str]"]
Force = Callable[[np.ndarray], Any]


def _real_array(a: Any, what: str) -> np.ndarray:
    """`a` as an array of reals: complex numbers (whose imaginary part a float64
    conversion would drop), booleans and non-numbers are a ``TypeError`` naming ``what``."""
    x = np.asarray(a)
    if np.iscomplexobj(x) or x.dtype.kind not in "iuf":
        raise TypeError(f"{what} must hold real numbers, not {x.dtype}")
    return x


def _rows(a: Any, what: str) -> np.ndarray:
    """`a` as a C-contiguous float64 ``(N, 3)`` array (no copy when it already is one)."""
    x = np.ascontiguousarray(_real_array(a, what), dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"{what} must have shape (N, 3), not {x.shape}")
    return x


def _column(a: Any, what: str, n: int) -> np.ndarray:
    """`a` as a contiguous float64 ``(n,)`` array (a scalar is repeated)."""
    x = _real_array(a, what).astype(np.float64, copy=False)
    x = np.full(n, float(x)) if x.ndim == 0 else np.ascontiguousarray(x)
    if x.shape != (n,):
        raise ValueError(f"{what} must have shape ({n},) to match the positions, not {x.shape}")
    return x


def _wall(h: Any) -> Optional[float]:
    """A wall height as a float (``None``: no wall)."""
    return None if h is None else _real(h, "wall")


def _box(b: Any) -> Optional["tuple[float, float, float]"]:
    """Three box edges as floats (``None``: no box)."""
    if b is None:
        return None
    edges = np.asarray(b)
    if edges.shape != (3,):
        raise ValueError(f"box must be three edges (Lx, Ly, Lz), not shape {edges.shape}")
    lx, ly, lz = (_real(x, "box") for x in edges)
    return (lx, ly, lz)


#: Loads above this (2^64) go through :func:`mobility_dot` scaled to at most 1.
_SCALE_ABOVE = 2.0**64


def _all_finite(out: Any) -> bool:
    """Whether every value of an array (or of a tuple of arrays) is finite."""
    parts = out if isinstance(out, tuple) else (out,)
    return all(bool(np.isfinite(x).all()) for x in parts)


def _real(x: Any, what: str) -> float:
    """A real number (a bool or a complex number is a ``TypeError`` naming ``what``)."""
    if isinstance(x, (bool, np.bool_)) or np.iscomplexobj(x):
        raise TypeError(f"{what} must be a real number, not {type(x).__name__}")
    try:
        return float(x)
    except (TypeError, ValueError):
        raise TypeError(f"{what} must be a real number, not {type(x).__name__}") from None


def _count(k: Any, what: str) -> int:
    """A non-negative integer (``TypeError`` for a non-integer, ``ValueError`` below 0)."""
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)):
        raise TypeError(f"{what} must be an integer, not {type(k).__name__}")
    if k < 0:
        raise ValueError(f"{what} must be >= 0, not {k}")
    return int(k)


def mobility(
    positions: Any,
    radii: Any,
    viscosity: float = 1.0,
    hydro: str = "rpy",
    rotation: bool = False,
    precision: str = "f64",
    wall: Optional[float] = None,
    box: Optional["tuple[float, float, float]"] = None,
    threads: int = 0,
    near_field: bool = False,
) -> np.ndarray:
    """The dense mobility matrix of spheres at ``positions`` with ``radii``.

    Parameters
    ----------
    positions : array_like, shape (N, 3)
        Sphere centres (length units ``L``).
    radii : array_like, shape (N,) or scalar
        Sphere radii (``L``, > 0). Overlapping spheres are allowed (the RPY overlapping
        branch); one sphere inside another is not.
    viscosity : float
        Fluid viscosity ``eta`` (> 0).
    hydro : {"rpy", "oseen", "free-draining"}
        Polydisperse Rotne-Prager-Yamakawa (Zuk et al. 2014), Oseen, or no interactions.
    rotation : bool
        With rotation, the ``(6N, 6N)`` grand mobility ``[[tt, tr], [rt, rr]]``.
    precision : {"f64", "f32"}
        Precision of the arithmetic and of the result's dtype.
    wall : float, optional
        Height ``H`` of a no-slip plane wall ``z = H`` below every centre: the
        wall-corrected RPY mobility (Swan & Brady's image system, docs/WALL.md), as
        ``System(..., wall=H)`` steps with. Rotation is supported.
    box : (Lx, Ly, Lz), optional
        A rectangular periodic box: the Ewald-summed RPY mobility (docs/PERIODIC.md),
        as ``System(..., box=...)`` steps with; with ``rotation`` the box's ``tr`` and
        ``rr`` blocks too. Every radius below half the smallest edge, every centre
        within ``1/sqrt(eps)`` edges of the origin (``6.7e7`` in f64, ``2896`` in f32);
        not with ``wall`` or ``hydro="oseen"`` (``ValueError``).
    threads : int
        Threads writing the dense output from 512 beads on (0: every core; the same
        values on any number). Above 32 MiB of output (N = 683 in f64) every new array
        is fresh memory whose first write page-faults (NumPy's own ``np.empty`` pays
        the same); threads take those faults in parallel.
    near_field : bool
        The Stokesian dynamics mobility: the inverse of ``M_far^-1 + R_near``, RPY's
        grand mobility (with the wall's images if ``wall``) corrected by the exact
        two-sphere resistance of every pair within 4 mean radii of touching and the
        exact sphere-wall resistance of every sphere within 4 radii of the wall
        (docs/NEAR.md). Exact for two spheres (Stimson and Jeffery) and for one sphere
        at the wall (Brenner). Gaps below 1e-3 radii, overlaps included, get the
        correction of that gap. Dense, ``O(N^3)``: 0.3 s at N = 100 and 3 s at
        N = 200 on one core (docs/NEAR.md). RPY only; a pair inside the cutoff
        needs a size ratio within 0.1 to 10. With ``box`` the far field is the
        Ewald-summed RPY and pairs meet at their minimum image (shorter than half
        the smallest edge); ``wall`` and ``box`` together are a ``ValueError``.
        Without ``rotation`` the translational
        block of the full inverse (the mobility of torque-free spheres).
        ``threads`` is not used.

    Returns
    -------
    ndarray, shape (3N, 3N) or (6N, 6N)
        ``U = M F``: translational velocities (``F / (eta L)``) from forces; with
        rotation also spins from torques. Ordered all translations, then all rotations,
        each particle-major then x, y, z: entry ``[3 i + a, 3 j + b]`` couples particle
        ``i``'s component ``a`` to particle ``j``'s ``b``; rotations start at row ``3N``.
        This is pygrpy's ``grpy_tensors.mu`` order (its ``(2, N, 3, 2, N, 3)`` tensor
        reshaped); libMobility's interleaved per-particle layouts must be permuted.
        A lone sphere's block is Stokes' ``1 / (6 pi eta a)``.

    Raises
    ------
    ValueError
        Wrong shapes, NaN or infinite values, a radius <= 0, nested spheres, a centre
        below the wall; the message names the particle (``index`` attribute: the
        particle or pair). A refused geometry (``box`` with ``wall`` or Oseen) with
        the kernel's message and ``kind``.
    MemoryError
        The arrays the call needs (the packed blocks and the output) exceed this
        machine's memory and swap, or cannot be allocated; the message gives their
        sizes. Checked before any work.
    """
    pos = _rows(positions, "positions")
    return _core.mobility(
        pos,
        _column(radii, "radii", len(pos)),
        viscosity,
        hydro,
        rotation,
        precision,
        _wall(wall),
        _box(box),
        _count(threads, "threads"),
        bool(near_field),
    )


def mobility_dot(
    positions: Any,
    radii: Any,
    forces: Any,
    torques: Any = None,
    viscosity: float = 1.0,
    hydro: str = "rpy",
    rotation: bool = False,
    precision: str = "f64",
    wall: Optional[float] = None,
    box: Optional["tuple[float, float, float]"] = None,
    threads: int = 0,
    method: str = "auto",
    tolerance: Optional[float] = None,
) -> Union[np.ndarray, "tuple[np.ndarray, np.ndarray]"]:
    """Velocities of spheres under ``forces`` (and ``torques``), ``M [F; T]``.

    Arguments as :func:`mobility`; ``forces`` and ``torques`` are ``(N, 3)`` (force
    units ``F``, torque ``F L``). Without torques and rotation the product is
    matrix-free (``O(N)`` memory, ``O(N^2)`` time, the same bits as the stored matrix
    times the forces) and returns the ``(N, 3)`` velocities (``F / (eta L)``). With
    torques or ``rotation=True`` it returns ``(velocities, spins)`` (spins in
    ``F / (eta L^2)``) through the packed grand mobility (``O(N^2)`` memory).
    ``wall`` and ``box`` as :func:`mobility`.

    ``method`` (in a box): ``"ewald"``, the exact Ewald sum (``O(N^2)``, to rounding);
    ``"pse"``, the positively split Ewald fast path (``O(N log N)``, relative error
    below ``tolerance``, translation and the RPY level only); ``"auto"`` (default),
    PSE where it can serve (no torques or rotation, ``hydro="rpy"``) and its grid fits
    the kernel's bounds, the Ewald sum otherwise: the rule of a scene's
    ``[box] method = "auto"``. ``tolerance``: PSE's relative error, ``1e-12`` to
    ``0.1`` (default ``1e-6``, as in scenes). ``"dense"`` is the exact product of each
    geometry (the pair sum in free space and above a wall, the Ewald sum in a box).
    In free space ``"fast"`` is the fast free-space RPY product (``O(N log N)``,
    relative error below ``tolerance``, ``1e-10`` to ``0.1``, default ``1e-4`` as a
    scene's ``[free_space]``; the RPY level only: a box, a wall or another ``hydro``
    are a ``ValueError``; with torques or ``rotation=True`` its grand product gives
    ``(velocities, spins)`` without the packed grand mobility); ``"auto"`` there is the
    exact pair sum (``"pse"`` is a ``ValueError``).

    ``threads``: the matrix-free product in free space and the PSE product run on this
    many threads (0: every core) from ``N = 512`` on; the result has the same bits on
    any number of threads (and below 512 in free space those of the stored matrix times
    the forces). Above a wall, by the Ewald sum in a box and with rotation it runs on
    one thread.

    Loads above ``2^64`` (where the product could overflow on the way: ``1e308`` in
    a box, whose Ewald sum adds terms larger than the result, or past f32's range) are
    taken scaled by a power of two to at most 1 and scaled back; velocities that overflow the precision themselves raise
    ``OverflowError``. The arrays the call allocates (the packed grand mobility with
    rotation, PSE's grid, the fast product's grid) are sized first: ``MemoryError`` with their sizes where they
    exceed this machine's memory and swap or cannot be allocated.
    """
    pos = _rows(positions, "positions")
    n = len(pos)
    f = _rows(forces, "forces")
    t = None if torques is None else _rows(torques, "torques")
    args = (
        viscosity,
        hydro,
        rotation,
        precision,
        _wall(wall),
        _box(box),
        _count(threads, "threads"),
        method,
        None if tolerance is None else _real(tolerance, "tolerance"),
    )
    a = _column(radii, "radii", n)
    # Loads so large that the product may overflow on the way (the Ewald sum's terms
    # near f64's range; f32's range itself): the product is linear, so it is taken of
    # the loads scaled by a power of two (exact) to at most 1, and scaled back.
    largest = max(np.abs(f).max(initial=0.0), 0.0 if t is None else np.abs(t).max(initial=0.0))
    if not largest > _SCALE_ABOVE:
        return _core.mobility_dot(pos, a, f, t, *args)
    k = int(np.frexp(largest)[1])
    scaled = _core.mobility_dot(
        pos, a, np.ldexp(f, -k), None if t is None else np.ldexp(t, -k), *args
    )
    with np.errstate(over="ignore"):
        out = tuple(np.ldexp(x, k) for x in scaled) if isinstance(scaled, tuple) else np.ldexp(scaled, k)
    if not _all_finite(out):
        dtype = (out[0] if isinstance(out, tuple) else out).dtype
        raise OverflowError(
            f"the velocities of loads up to {largest:g} overflow {dtype}: scale the forces down"
        )
    return out


class Frame(NamedTuple):
    """One configuration yielded by :meth:`System.run` (arrays are copies)."""

    #: Simulated time.
    time: float
    #: Centres, ``(N, 3)``.
    positions: np.ndarray
    #: Velocities, ``(N, 3)``.
    velocities: np.ndarray
    #: Angular velocities, ``(N, 3)``.
    spins: np.ndarray
    #: Report of the last step (None for the first frame).
    report: Optional[Report]


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} into a scene")


def _scene_text(sections: "dict[str, dict[str, Any]]") -> str:
    out = []
    for name, keys in sections.items():
        out.append(f"[{name}]")
        out.extend(f"{k} = {_toml_value(v)}" for k, v in keys.items())
        out.append("")
    return "\n".join(out)


def _bond_pairs(bonds: Any) -> np.ndarray:
    """Bonds as a C-contiguous int64 ``(B, 2)`` array: integers, or floats that are whole
    numbers (``[[0, 1.5]]`` is a ``ValueError``, not the bond ``[0, 1]``)."""
    if bonds is None:
        return np.zeros((0, 2), dtype=np.int64)
    x = np.asarray(bonds)
    if x.size == 0:
        x = x.reshape(-1, 2) if x.ndim < 2 else x
    if np.iscomplexobj(x) or x.dtype.kind not in "iuf":
        raise TypeError(f"bonds must hold integer particle indices, not {x.dtype}")
    if x.dtype.kind == "f":
        bad = ~np.isfinite(x) | (x != np.trunc(x))
        if bad.any():
            k = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ValueError(f"bonds{list(k)}: particle index {x[k]} is not an integer")
    if x.ndim != 2 or x.shape[1] != 2:
        raise ValueError(f"bonds must have shape (B, 2), not {x.shape}")
    # Past int64 (a uint64 index of 2^64 - 1, a float of 1e30) the cast would wrap or
    # saturate: name the index as given.
    big = x > np.iinfo(np.int64).max
    if big.any():
        k = tuple(int(i) for i in np.argwhere(big)[0])
        raise ValueError(f"bond {k[0]}: particle index {x[k]} out of range")
    return np.ascontiguousarray(x, dtype=np.int64)


class System:
    """Particles and bonds stepped by the kernel.

    ``System(positions, radii, densities, bonds=None, lengths=None, precision="f64",
    **params)``: ``positions`` ``(N, 3)`` (C-contiguous float64 is read without a copy;
    other dtypes and layouts are converted), ``radii`` and ``densities`` ``(N,)`` or
    scalars, ``bonds`` a ``(B, 2)`` integer array of particle pairs held at fixed
    ``lengths`` (``(B,)``; measured from the positions when omitted).

    ``params`` mirror the kernel's ``Params`` with its names and defaults: ``dt``
    (required), ``method`` ("overdamped", "overdamped2", "rattle", "rattle-stable",
    "springs"; default "overdamped"), ``viscosity`` (1), ``fluid_density`` (0),
    ``gravity`` ((0, 0, -1)), ``flow`` ((0, 0, 0)), ``vorticity`` ((0, 0, 0)), ``hydro``
    ("rpy"), ``rotation`` (False), ``matrix_free`` (False), ``compact_products`` (False: the
    Krylov constraint products read an f32 copy of the mobility, a third of the bytes,
    with the residual kept in f64 so the bonds still meet ``tolerance``; taken only by
    f64 "overdamped" from 700 beads without a wall (nor PSE in a box), deterministic or
    thermal with the midpoint drift and Lanczos noise (no Ewald box), whose reduced copy
    it reuses, and ignored elsewhere), ``solver`` ("auto",
    "sweep", "newton", "krylov"), ``tolerance`` (1e-10 in f64, 1e-5 in f32),
    ``max_iterations`` (100), ``allow_overlap`` (False), ``spring_stiffness`` (1e3), ``fene`` (None:
    Hookean springs; ``Q0``: FENE springs of maximum extension ``Q0``),
    ``stability_guard`` (False), ``contacts`` (None, or the hard-contact capacity),
    ``wall`` (None, or the height ``H`` of a no-slip plane wall ``z = H`` below every
    sphere: its mobility and its one-sided constraint; "overdamped" and "overdamped2"),
    ``box`` (None, or the edges ``(Lx, Ly, Lz)`` of a periodic box: the Ewald-summed
    mobility, rotation too, and minimum-image bonds and overlaps; not with ``wall``),
    ``resolve_tensions`` (True in f32, False in f64: the inertial methods' tensions
    solved again from the step's displacements, two more constraint solves per step,
    needed in f32 where the position multipliers are rounding noise),
    ``threads`` (0: every core; the mobility's bands from 512 beads on, the same bits
    on any number),
    ``temperature`` (None: no thermal noise; ``kT``), ``drift`` ("midpoint",
    "uncorrected"), ``seed`` (1), ``noise_sqrt`` ("auto": Lanczos above
    ``LANCZOS_CROSSOVER`` beads, "cholesky", "lanczos"), ``lanczos_tolerance`` (1e-3,
    the noise's estimated relative error) and ``lanczos_max_iterations`` (64),
    ``near_field`` (False; True or a dict of ``cutoff``, ``wall_cutoff``, ``min_gap``
    in radii, defaults 4, 4, 1e-3: steps with the Stokesian dynamics mobility of
    :func:`mobility` ``(..., near_field=True)``, the RPY far field plus the exact
    two-sphere and sphere-wall lubrication, as its constraint metric and noise too;
    "overdamped" and "overdamped2", free space or ``wall``, noise by Cholesky; dense,
    docs/NEAR.md). A particle's mass is ``4/3 pi a^3 density``; gravity
    acts on the buoyant mass (``density - fluid_density``).

    Everything the first step would refuse is refused here: a parameter of the wrong
    type is a ``TypeError`` naming it (flags take ``True``/``False`` or 1/0), a value out
    of range a ``ValueError`` naming it (``dt=0``, ``seed=-1``), and the kernel's checks
    of parameters, particles and bonds (spheres overlapping at the start unless
    ``allow_overlap``, in a box through its faces too, coincident centres always, a
    sphere below the wall, a refused combination) a ``ValueError`` with the kernel's
    message, ``kind`` and ``index``. Storage past the limit (8 GiB, as the CLI's
    default ``--max-storage``) is a ``ValueError`` giving its size. Bond indices
    must be integers (``1.5`` is refused), arrays real (complex is a ``TypeError``).

    Constructors for the CLI's shapes: :meth:`from_scene` (a scene file, read by the
    CLI's parser, every default as the CLI's) and :meth:`helix`.
    """

    _core: Any

    def __init__(
        self,
        positions: Any,
        radii: Any,
        densities: Any,
        bonds: Any = None,
        lengths: Any = None,
        precision: str = "f64",
        **params: Any,
    ) -> None:
        pos = _rows(positions, "positions")
        n = len(pos)
        b = _bond_pairs(bonds)
        ls = None if lengths is None else _column(lengths, "lengths", len(b))
        self._core = _core.Core.build(
            pos,
            _column(radii, "radii", n),
            _column(densities, "densities", n),
            b,
            ls,
            precision,
            params,
        )

    @classmethod
    def _of(cls, core: Any) -> "System":
        s = cls.__new__(cls)
        s._core = core
        return s

    @classmethod
    def from_scene(cls, path: PathLike) -> "System":
        """The system of a scene file (TOML, the CLI's format), in the scene's
        precision, with the scene's parameters exactly as ``host-demo run`` sets them.
        A bad file raises :class:`SceneError` with ``file`` and ``line``."""
        return cls._of(_core.Core.from_scene_file(os.fspath(path)))

    @classmethod
    def from_scene_text(cls, text: str, origin: str = "<scene>") -> "System":
        """As :meth:`from_scene`, from the scene's TOML text."""
        return cls._of(_core.Core.from_scene_text(text, origin))

    @classmethod
    def helix(cls, **keys: Any) -> "System":
        """A helical chain as the CLI builds it: the ``[helix]`` keys (``tails``,
        ``head_ratio``, ``dhat``, ``head_end``, ``radius``, ``pitch``, ``density``) as
        keyword arguments, any other scene section as a dict (``fluid``, ``gravity``,
        ``model``, ``contact``, ``brownian``, ``integrator``, ``output``, ``wall``). Missing keys
        take the scene file's defaults. Example: ``System.helix(tails=24,
        head_ratio=2.0, dhat=1.05, integrator={"method": "overdamped2", "dt": 0.1})``.
        """
        sections: "dict[str, dict[str, Any]]" = {"helix": {}}
        for k, v in keys.items():
            if isinstance(v, dict):
                sections[k] = v
            else:
                sections["helix"][k] = v
        integrator = sections.setdefault("integrator", {})
        if "dt" not in integrator:
            raise TypeError("System.helix needs integrator={'dt': ...}")
        # A System steps as asked: the scene's duration only has to be valid.
        integrator.setdefault("duration", integrator["dt"])
        return cls.from_scene_text(_scene_text(sections), "<System.helix>")

    @property
    def positions(self) -> np.ndarray:
        """Centres, ``(N, 3)`` float64 (a copy)."""
        return self._core.positions

    @positions.setter
    def positions(self, value: Any) -> None:
        self.set_state(positions=value)

    @property
    def velocities(self) -> np.ndarray:
        """Translational velocities, ``(N, 3)`` float64 (a copy)."""
        return self._core.velocities

    @velocities.setter
    def velocities(self, value: Any) -> None:
        self.set_state(velocities=value)

    @property
    def spins(self) -> np.ndarray:
        """Angular velocities, ``(N, 3)`` float64 (a copy; zero unless ``rotation``)."""
        return self._core.spins

    @spins.setter
    def spins(self, value: Any) -> None:
        self.set_state(spins=value)

    def set_state(
        self,
        positions: Any = None,
        velocities: Any = None,
        spins: Any = None,
        time: Optional[float] = None,
    ) -> None:
        """Replaces the parts of the state given (all or nothing: finite ``(N, 3)``
        arrays, rounded to the system's precision; ``time`` any finite number, a
        negative one too: it is the clock the steps advance, nothing depends on its
        sign). Positions off the bond lengths are
        pulled back onto them by the next step (its constraint solve targets the
        lengths); one sphere inside another is refused by it."""
        conv = lambda a, w: None if a is None else _rows(a, w)  # noqa: E731
        self._core.set_state(
            conv(positions, "positions"),
            conv(velocities, "velocities"),
            conv(spins, "spins"),
            None if time is None else _real(time, "time"),
        )

    def copy(self) -> "System":
        """An independent system in the same state (noise generator included)."""
        return System._of(self._core.copy())

    __copy__ = copy

    def to_atoms(self) -> Any:
        """The system as an ASE ``Atoms`` (needs ``ase``): every sphere an atom "X" at
        its centre with its velocity and mass (``4/3 pi a^3 density``), the radii and
        densities in the arrays ``radius`` and ``density``, the spins in ``spin``; the
        bonds ``(B, 2)``, their lengths and the time in ``info``; a periodic box as the
        cell (its edges on the diagonal) with ``pbc`` on every axis, the positions
        unwrapped as the system keeps them. :meth:`from_atoms` reads it back."""
        from ase import Atoms  # noqa: PLC0415 (optional dependency)

        a, rho = self.radii, self.densities
        cell = self.box
        atoms = Atoms(
            symbols=["X"] * len(a),
            positions=self.positions,
            masses=4.0 / 3.0 * math.pi * a**3 * rho,
            cell=None if cell is None else np.diag(cell),
            pbc=cell is not None,
        )
        atoms.set_velocities(self.velocities)
        atoms.new_array("radius", a)
        atoms.new_array("density", rho)
        atoms.new_array("spin", self.spins)
        atoms.info["bonds"] = self.bonds
        atoms.info["lengths"] = self.lengths
        atoms.info["time"] = self.time
        return atoms

    @classmethod
    def from_atoms(
        cls, atoms: Any, radii: Any = None, densities: Any = None, **params: Any
    ) -> "System":
        """A system of an ASE ``Atoms``: centres and velocities from it; radii from
        ``radii`` or its ``radius`` array; densities from ``densities``, its ``density``
        array, or its masses over the spheres' volumes; bonds and lengths from
        ``params`` or its ``info`` (as :meth:`to_atoms` writes them); spins and time
        from its ``spin`` array and ``info["time"]`` when present; a periodic box from
        its cell when it is periodic on every axis (an orthorhombic cell: its diagonal
        is the box; ``box=`` in ``params`` takes precedence). ``params`` as the
        constructor's (``dt`` required)."""
        n = len(atoms)
        pbc = np.asarray(atoms.pbc, dtype=bool)
        if pbc.any() and "box" not in params:
            if not pbc.all():
                raise ValueError(
                    f"from_atoms: atoms periodic along some axes only (pbc = {tuple(pbc)}); "
                    "a System's box is periodic along all three"
                )
            cell = np.asarray(atoms.cell[:], dtype=float)
            if np.any(cell != np.diag(np.diag(cell))):
                raise ValueError(
                    "from_atoms: a System's box is rectangular: the cell must be diagonal"
                )
            params["box"] = tuple(float(x) for x in np.diag(cell))
        if radii is None:
            if "radius" not in atoms.arrays:
                raise ValueError("from_atoms needs radii=, or a 'radius' array on the atoms")
            radii = atoms.arrays["radius"]
        a = _column(radii, "radii", n)
        if densities is None:
            if "density" in atoms.arrays:
                densities = atoms.arrays["density"]
            else:
                densities = atoms.get_masses() / (4.0 / 3.0 * math.pi * a**3)
        params.setdefault("bonds", atoms.info.get("bonds"))
        params.setdefault("lengths", atoms.info.get("lengths"))
        s = cls(atoms.get_positions(), a, densities, **params)
        spins = atoms.arrays.get("spin")
        s.set_state(velocities=atoms.get_velocities(), spins=spins, time=atoms.info.get("time"))
        return s

    def __deepcopy__(self, memo: Any) -> "System":
        return self.copy()

    def __reduce__(self) -> "tuple[Any, tuple[str]]":
        """Pickling (``pickle``, ``multiprocessing``, ``joblib``) carries the whole
        system as text: state, bonds, parameters, the noise generator, counters and the
        last tensions, every float's bits. The unpickled system continues with the
        same bits as the original, in any process of the same build."""
        return (_restore_system, (self._core.save_json(),))

    @property
    def radii(self) -> np.ndarray:
        """Radii, ``(N,)`` (a copy)."""
        return self._core.radii

    @property
    def densities(self) -> np.ndarray:
        """Material densities, ``(N,)`` (a copy)."""
        return self._core.densities

    @property
    def bonds(self) -> np.ndarray:
        """Bonded pairs, ``(B, 2)`` int64 (a copy)."""
        return self._core.bonds

    @property
    def lengths(self) -> np.ndarray:
        """Bond lengths, ``(B,)`` (a copy)."""
        return self._core.lengths

    @property
    def tensions(self) -> Optional[np.ndarray]:
        """Bond tensions after the last accepted step, ``(B,)`` (a copy; force units,
        positive when a bond pulls its ends together): ``-lambda_k d_k`` for rigid bonds
        (the constraint force along the bond), the spring law at the current length for
        ``method="springs"``. ``None`` before the first step and for ``"overdamped2"``,
        whose last projection's multipliers are only a correction to the predictor's."""
        return self._core.tensions

    @property
    def time(self) -> float:
        """Simulated time."""
        return self._core.time

    @property
    def dt(self) -> float:
        """Time step."""
        return self._core.dt

    @property
    def precision(self) -> str:
        """"f64" or "f32"."""
        return self._core.precision

    @property
    def box(self) -> Optional["tuple[float, float, float]"]:
        """The periodic box's edges ``(Lx, Ly, Lz)``, or None."""
        cell = self._core.cell
        return None if cell is None else tuple(cell)

    def __len__(self) -> int:
        return len(self._core.radii)

    def __repr__(self) -> str:
        return (
            f"System(N={len(self)}, bonds={len(self._core.lengths)}, t={self.time}, "
            f"dt={self.dt}, precision={self.precision!r})"
        )

    def step(
        self,
        n: int = 1,
        force: Optional[Force] = None,
        callback: Optional[Callable[["System"], Any]] = None,
        every: int = 1,
    ) -> Report:
        """Makes ``n`` steps inside Rust; returns the last step's :class:`Report`
        (constraint iterations, residual, largest tension).

        ``callback(system)`` runs after every ``every``-th step of the call, with the
        GIL held and the system readable (positions, tensions, observables; it must not
        call ``step`` or ``set_state``, which raise :class:`SystemBusyError`). Its cost
        is the Python call and what it reads: taking the GIL back and calling an empty
        callback is about a microsecond (the steps in between run without the GIL). An
        exception it raises stops the call (``completed`` on it; the steps made are
        kept).

        Threads: another thread reading this system while it steps waits for the end
        of the current step and sees the state between two steps (a consistent
        snapshot); a second ``step`` or a ``set_state`` from another thread while a
        ``step(n)`` runs raises :class:`SystemBusyError`, as does a ``force`` callable
        that reads the system it is stepping (it reads the positions it is passed).

        Without ``force`` the GIL is released for the whole call (other Python threads
        run; two systems step in parallel in two threads), and Ctrl-C interrupts it
        between two steps: ``KeyboardInterrupt`` is raised with the state as after the
        last completed step.

        ``force``: a callable ``f(positions) -> forces`` taking the candidate ``(N, 3)``
        positions (a new float64 array) and returning ``(N, 3)`` forces added to
        gravity (and any soft contact). It is called once per force evaluation (once
        per step for the first-order methods, twice for "overdamped2"), with the GIL
        held; its cost is the Python call plus two ``(N, 3)`` array conversions (a few
        microseconds at N = 25; see docs/PYTHON.md). An exception it raises aborts the step
        and propagates, leaving the state unchanged.

        At temperature a step the kernel refuses (a rare large kick the constraint
        solve cannot project) is retried as 2, 4, ... up to 128 shorter steps along a
        Brownian bridge, as the CLI does (docs/BROWNIAN.md, "A refused step"): the
        report's ``retried_steps`` counts the steps of this call made that way,
        ``retry_substeps`` the shorter steps they took. Only a step whose deepest split
        fails too raises.

        Raises a :class:`StepError` subclass (``kind``, ``stage``, ``index``,
        ``value``, ``completed``; ``kind`` and ``stage`` are the kernel's snake_case
        names, e.g. ``"no_convergence"``, ``"particle_bad_radius"``, ``"positions"``)
        when a step fails: the state (positions, velocities, spins, time, noise
        generator) is then exactly as it was before that step; the steps of this call
        before it are kept, and ``completed`` says how many there were. An exception
        from ``force`` or Ctrl-C carries ``completed`` too.
        """
        bound = None if callback is None else (lambda: callback(self))
        return self._core.step(_count(n, "n"), force, bound, _count(every, "every"))

    def run(
        self, until: float, every: int = 1, force: Optional[Force] = None
    ) -> Iterator[Frame]:
        """Steps to simulated time ``until``, yielding a :class:`Frame` now and every
        ``every`` steps (and at the end). Stepping happens between the yields: stop
        iterating to stop the run."""
        every = max(1, int(every))
        total = max(0, math.ceil((until - self.time) / self.dt - 1e-9))
        yield self._frame(None)
        done = 0
        while done < total:
            k = min(every, total - done)
            report = self.step(k, force)
            done += k
            yield self._frame(report)

    def _frame(self, report: Optional[Report]) -> Frame:
        c = self._core
        return Frame(c.time, c.positions, c.velocities, c.spins, report)

    def state_bits(self) -> "list[int]":
        """The exact bits of positions, velocities, spins, time and the noise
        generator's next draw: equal lists mean bit-identical states."""
        return self._core.state_bits()


def _restore_system(text: str) -> System:
    """The system :meth:`System.__reduce__` saved (module level: pickle finds it)."""
    return System._of(_core.Core.restore_json(text))


def load_scene(path: PathLike) -> "dict[str, Any]":
    """The scene file at ``path`` read by the CLI's parser, every default filled in
    (particles generated, bond lengths resolved), as a dict. A bad file raises
    :class:`SceneError` (a ``ValueError``) with ``file``, ``line`` and ``column``."""
    return json.loads(_core.load_scene_json(os.fspath(path)))


def run_scene(
    path: PathLike, out: PathLike, checkpoint_every: Optional[float] = None
) -> "dict[str, Any]":
    """Runs the scene file ``path`` into the folder ``out`` exactly as
    ``host-demo run PATH --out OUT`` does: the same files, byte for byte apart from the
    wall times in ``summary.json`` (trajectory.xyz, trajectory.gsd, observables.csv,
    scene.toml, summary.json; the pictures are the CLI's alone). Returns the summary.
    The run goes on in a thread of its own with the GIL released. Raises
    :class:`SceneError` for a bad file and ``RuntimeError`` when the run stops early.

    Ctrl-C stops it between two steps as it stops ``host-demo run``: the run writes a
    checkpoint at the step it reached and ``KeyboardInterrupt`` is raised, with
    ``checkpoint`` (its path), ``step`` and ``time``; :func:`resume_run` (or
    ``host-demo resume``) continues it to the same bytes as a run never stopped."""
    return json.loads(_core.run_scene(os.fspath(path), os.fspath(out), checkpoint_every))


def resume_run(
    out: PathLike, until: Optional[float] = None, checkpoint_every: Optional[float] = None
) -> "dict[str, Any]":
    """Continues the run in folder ``out`` from its checkpoint to simulated time
    ``until`` (default: the end its ``scene.toml`` names), as ``host-demo resume OUT
    --until T`` does: the files end as those of one run to ``until``. Returns the
    summary; Ctrl-C as in :func:`run_scene`. A folder without a checkpoint raises
    ``RuntimeError``."""
    return json.loads(
        _core.resume_run(
            os.fspath(out),
            None if until is None else _real(until, "until"),
            checkpoint_every,
        )
    )


@dataclass
class Run:
    """A run's files read back (:func:`read_run`)."""

    #: Frame times, ``(F,)``.
    time: np.ndarray
    #: Centres, ``(F, N, 3)``.
    positions: np.ndarray
    #: Velocities, ``(F, N, 3)``.
    velocities: np.ndarray
    #: Radii, ``(N,)``.
    radii: np.ndarray
    #: Masses, ``(N,)``.
    masses: np.ndarray
    #: Type name of each particle.
    species: "list[str]"
    #: ``summary.json`` (empty when absent).
    summary: "dict[str, Any]" = field(default_factory=dict)

    def atoms(self) -> "list[Any]":
        """The frames as ASE ``Atoms`` (needs ``ase``): species as chemical symbols are
        not elements, so each atom is "X" with the species in the ``species`` array,
        radii, masses and velocities set."""
        from ase import Atoms  # noqa: PLC0415 (optional dependency)

        out = []
        for t, p, v in zip(self.time, self.positions, self.velocities):
            a = Atoms(symbols=["X"] * len(p), positions=p, masses=self.masses)
            a.set_velocities(v)
            a.new_array("radius", self.radii)
            a.new_array("species", np.array(self.species))
            a.info["time"] = float(t)
            out.append(a)
        return out


def read_run(out: PathLike) -> Run:
    """The trajectory of the run in folder ``out`` (``trajectory.xyz``, exact) as
    NumPy arrays, with its summary; :meth:`Run.atoms` gives ASE ``Atoms``."""
    d = _core.read_trajectory(os.fspath(out))
    summary_path = os.path.join(os.fspath(out), "summary.json")
    summary = {}
    if os.path.exists(summary_path):
        with open(summary_path, encoding="utf-8") as f:
            summary = json.load(f)
    return Run(summary=summary, **d)
