#!/usr/bin/env python3
"""Reads the trajectory files of `host-demo run` output folders back with the real
tools (ASE, the `gsd` package and OVITO's Python module) and checks them against the
run's own record (`summary.json`): species, masses, velocities, positions, bonds,
frame count. A run in a periodic box (`[box]`) must also give the box to every tool:
extended XYZ `Lattice=` with `pbc="T T T"` and unwrapped positions, GSD
`configuration/box` with positions wrapped into it and `particles/image`, so that
wrapped + image * L is the XYZ's unwrapped position (to f32 rounding). Exits non-zero
on the first disagreement.

    python host-demo/tools/readback.py OUT_DIR [OUT_DIR ...]

OVITO is optional (`--no-ovito`) for machines where its wheel does not install.
"""

import json
import math
import sys
from pathlib import Path

import numpy as np


def fail(msg):
    print(f"readback: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)


def expected(out):
    s = json.loads((out / "summary.json").read_text())
    scene = s["resolved_scene"]
    parts = scene["particles"]
    mass = np.array([4.0 / 3.0 * math.pi * p["radius"] ** 3 * p["density"] for p in parts])
    radius = np.array([p["radius"] for p in parts])
    bonds = np.array([[b["i"], b["j"]] for b in scene["bonds"]], dtype=np.uint32).reshape(-1, 2)
    cell = np.array(scene["box"]["size"]) if "box" in scene else None
    return s, scene["species"], mass, radius, bonds, cell


def read_csv_times(out):
    lines = (out / "observables.csv").read_text().splitlines()[1:]
    return np.array([float(l.split(",")[0]) for l in lines])


def check_ase(out, species, mass, radius, times, cell):
    import ase.io

    frames = ase.io.read(out / "trajectory.xyz", index=":")
    check(len(frames) == len(times), f"ASE: {len(frames)} frames, observables.csv {len(times)}")
    types = sorted(set(species), key=species.index)
    for k, a in enumerate(frames):
        if cell is None:
            check(not a.pbc.any(), f"ASE frame {k}: pbc {a.pbc} without a box")
        else:
            check(a.pbc.all(), f"ASE frame {k}: pbc {a.pbc} in a box")
            check(np.array_equal(a.cell.array, np.diag(cell)), f"ASE frame {k}: cell {a.cell.array} != box {cell}")
        check(len(a) == len(species), f"ASE frame {k}: {len(a)} atoms")
        # 4/3 pi r^3 rho: the same number as the run's to rounding (another order of operations).
        check(np.allclose(a.get_masses(), mass, rtol=1e-14, atol=0), f"ASE frame {k}: masses {a.get_masses()} != {mass}")
        check(np.array_equal(a.arrays["radius"], radius), f"ASE frame {k}: radii")
        check(a.info["Time"] == times[k], f"ASE frame {k}: Time {a.info['Time']} != {times[k]}")
        # ASE's velocities are momenta / masses: equal to the exact `velo` column to rounding.
        v = a.get_velocities()
        check(np.allclose(v, a.arrays["velo"], rtol=1e-12, atol=1e-300), f"ASE frame {k}: velocities")
        ids = [types.index(s) + 1 for s in species]
        check(list(a.numbers) == ids, f"ASE frame {k}: Z {list(a.numbers)} != type numbers {ids}")
    return frames


def check_gsd(out, species, mass, radius, bonds, ase_frames, cell):
    import gsd.hoomd

    types = sorted(set(species), key=species.index)
    with gsd.hoomd.open(out / "trajectory.gsd", "r") as traj:
        check(len(traj) == len(ase_frames), f"gsd: {len(traj)} frames, xyz {len(ase_frames)}")
        for k, f in enumerate(traj):
            p = f.particles
            check(p.N == len(species), f"gsd frame {k}: N = {p.N}")
            check(list(p.types) == types, f"gsd frame {k}: types {p.types} != {types}")
            check([p.types[t] for t in p.typeid] == species, f"gsd frame {k}: typeid")
            a = ase_frames[k]
            check(np.array_equal(p.mass, a.get_masses().astype(np.float32)), f"gsd frame {k}: mass")
            check(np.array_equal(p.diameter, (2 * radius).astype(np.float32)), f"gsd frame {k}: diameter")
            box = f.configuration.box
            if cell is None:
                check(np.array_equal(p.position, a.positions.astype(np.float32)), f"gsd frame {k}: positions")
            else:
                # Wrapped into the box centred on the origin, with the image flags that
                # give back the XYZ's unwrapped positions.
                check(np.array_equal(box[:3], cell.astype(np.float32)), f"gsd frame {k}: box {box} != {cell}")
                check(np.all(box[3:] == 0), f"gsd frame {k}: a tilted box")
                half = cell.astype(np.float32) / 2
                check(np.all((p.position >= -half) & (p.position < half)), f"gsd frame {k}: a position outside the box")
                unwrapped = p.position.astype(np.float64) + p.image * cell
                err = np.abs(unwrapped - a.positions)
                scale = np.abs(a.positions) + cell
                check(np.all(err <= 4 * np.finfo(np.float32).eps * scale), f"gsd frame {k}: position + image L != unwrapped (max {err.max()})")
            check(np.array_equal(p.velocity, a.arrays["velo"].astype(np.float32)), f"gsd frame {k}: velocities")
            check(f.bonds.N == len(bonds), f"gsd frame {k}: {f.bonds.N} bonds")
            check(np.array_equal(f.bonds.group, bonds), f"gsd frame {k}: bond groups")
            check(f.log["time"][0] == a.info["Time"], f"gsd frame {k}: log/time")
            check(np.all(np.abs(p.position) < np.array(box[:3]) / 2), f"gsd frame {k}: a particle outside the box")


def check_ovito_cell(d, cell, what):
    """OVITO's simulation cell: the box, periodic on every axis (or none periodic)."""
    if cell is None:
        return
    check(d.cell is not None, f"OVITO {what}: no simulation cell")
    check(np.allclose(np.diag(d.cell[:, :3]), cell, rtol=1e-6), f"OVITO {what}: cell {d.cell[...]} != {cell}")
    check(all(d.cell.pbc), f"OVITO {what}: pbc {d.cell.pbc}")


def check_ovito(out, species, mass, bonds, nframes, cell):
    from ovito.io import import_file

    pipe = import_file(str(out / "trajectory.xyz"))
    check(pipe.source.num_frames == nframes, f"OVITO xyz: {pipe.source.num_frames} frames")
    d = pipe.compute(nframes - 1)
    ptype = d.particles["Particle Type"]
    names = [ptype.type_by_id(t).name for t in ptype[...]]
    check(names == species, f"OVITO xyz: types {names[:4]}...")
    check(np.allclose(d.particles["Mass"][...], mass, rtol=1e-14, atol=0), "OVITO xyz: Mass")
    check("Velocity" in d.particles, "OVITO xyz: no standard Velocity property")
    check("Radius" in d.particles, "OVITO xyz: no standard Radius property")
    check_ovito_cell(d, cell, "xyz")

    pipe = import_file(str(out / "trajectory.gsd"))
    check(pipe.source.num_frames == nframes, f"OVITO gsd: {pipe.source.num_frames} frames")
    d = pipe.compute(nframes - 1)
    check(d.particles.count == len(species), "OVITO gsd: particle count")
    got = d.particles.bonds.topology[...] if d.particles.bonds is not None else np.zeros((0, 2))
    check(np.array_equal(np.asarray(got, dtype=np.uint32).reshape(-1, 2), bonds), "OVITO gsd: bonds")
    check(np.allclose(d.particles["Mass"][...], mass, rtol=1e-6), "OVITO gsd: Mass")
    check("Velocity" in d.particles, "OVITO gsd: Velocity")
    check_ovito_cell(d, cell, "gsd")
    if cell is not None:
        check("Periodic Image" in d.particles, "OVITO gsd: no Periodic Image property")


def main(argv):
    use_ovito = "--no-ovito" not in argv
    dirs = [Path(a) for a in argv if not a.startswith("--")]
    if not dirs:
        fail("usage: readback.py OUT_DIR [OUT_DIR ...] [--no-ovito]")
    for out in dirs:
        s, species, mass, radius, bonds, cell = expected(out)
        times = read_csv_times(out)
        check(times[-1] == s["final_observables"]["time"], "observables.csv ends at another time than summary.json")
        frames = check_ase(out, species, mass, radius, times, cell)
        check_gsd(out, species, mass, radius, bonds, frames, cell)
        if use_ovito:
            check_ovito(out, species, mass, bonds, len(frames), cell)
        tools = "ASE, gsd" + (", OVITO" if use_ovito else "")
        boxed = "" if cell is None else f", periodic box {list(cell)}"
        print(f"readback: {out}: {len(frames)} frames of {len(species)} particles, "
              f"{len(bonds)} bonds, types {sorted(set(species), key=species.index)}{boxed}: read by {tools}")


if __name__ == "__main__":
    main(sys.argv[1:])
