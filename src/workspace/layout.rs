//! How much storage a step needs: counted per method, rotation flag, solver, beads and
//! bonds, in a `const fn`, so firmware sizes a [`Storage`](super::Storage) at compile
//! time and a host sizes `Buffers` at run time from the same numbers.

use crate::constraints::{SolverKind, scratch_size};
use crate::error::Layout;
use crate::linalg::tri;
use crate::noise::lanczos;
use crate::parallel::band_scratch;
use crate::params::{Method, Params};
use crate::real::Real;

/// Scalars a symmetric 3x3 block of a stored mobility takes ([`Sym`](crate::linalg::Sym)).
pub(crate) const SYM: usize = 6;

/// Whether a step of `p` stores its mobility as symmetric blocks, six scalars each in
/// the scalar array ([`Sym`](crate::linalg::Sym)): the overdamped methods in free space
/// and in a periodic box, whose translational blocks are symmetric in bits (the Ewald
/// blocks tested in `mobility::periodic`). Above a wall, and for the inertial methods
/// (whose factors and rotational blocks are not symmetric) the stored mobility keeps
/// nine-scalar blocks in the block array.
pub(crate) const fn symmetric<T: Real>(p: &Params<T>) -> bool {
    p.place().symmetric()
        && !p.near_on()
        && matches!(
            p.method,
            Method::Overdamped | Method::Overdamped2 | Method::Springs
        )
}

/// Blocks the near field's packed far-field grand mobility takes ([`Params::near`]).
pub(crate) const fn near_blocks(n: usize) -> usize {
    tri(2 * n)
}

/// Scalars the near field's dense `6n x 6n` mobility takes ([`Params::near`]), and with
/// `kept` (a Brownian step with rotation) the start's `3n x 3n` rotation-translation
/// blocks after it, which the spins read once the midpoint's mobility has taken the
/// dense matrix.
pub(crate) const fn near_scalars(n: usize, kept: bool) -> usize {
    36 * n * n + if kept { 9 * n * n } else { 0 }
}

/// Whether the near field's products are iterative ([`Params::near`] with
/// [`Params::matrix_free`]): `M_SD` is never formed, so none of the dense storage.
pub(crate) const fn near_iterative<T: Real>(p: &Params<T>) -> bool {
    p.near_on() && p.matrix_free
}

/// Whether the iterative near field's far field is a matrix-free grand product (the
/// fast free-space product's: [`Params::pse`] in free space, kernel feature
/// `fast-free`; PSE's in a box, feature `pse`), so that no packed grand mobility is
/// stored (`integrate::near_iter::solve`).
pub(crate) const fn near_far_product<T: Real>(p: &Params<T>) -> bool {
    let place = p.place();
    let boxed = place.cell().is_some();
    let fast = (boxed && cfg!(feature = "pse")) || (!boxed && cfg!(feature = "fast-free"));
    fast && near_iterative(p) && p.pse.is_some() && place.surfaces().is_empty()
}

/// Scalars one close pair of the iterative near field takes: its factor, its
/// preconditioner's block and five Krylov vectors (`stokesian::iterative::sizes`).
const NEAR_PAIR_SCALARS: usize = 2 * 144 + 5 * 12;

/// The iterative near field's storage for `n` spheres, room for
/// [`NEAR_PAIRS_PER_SPHERE`](crate::params::NEAR_PAIRS_PER_SPHERE) close pairs a sphere:
/// `[blocks, vectors, scalars, indices]`. The far field's packed grand mobility
/// (`tri(2n)` blocks, assembled once a mobility; none where `packed` is false, the far
/// field a matrix-free product: [`near_far_product`]), the product's force-torque and
/// velocity-spin vectors and its own `6n` vectors, the pairs' scalars, and the pairs'
/// indices with the pair search's cell list (`3n + 1`); with `constraints` a scalar
/// each, their squeeze resistances (`integrate::near_iter::constrained`).
pub(crate) const fn near_iterative_sizes(n: usize, constraints: usize, packed: bool) -> [usize; 4] {
    let pairs = crate::params::NEAR_PAIRS_PER_SPHERE * n;
    [
        if packed { tri(2 * n) } else { 0 },
        10 * n,
        NEAR_PAIR_SCALARS * pairs + constraints,
        2 * pairs + 3 * n + 1,
    ]
}

/// The iterative near field's Brownian storage (`integrate::near_iter::noise`; none
/// without [`Params::brownian`]): `[vectors, scalars]`. The far field's Lanczos basis
/// over the `2n` forces and torques (`(cap + 1) 2n` vectors) and its scalars, the
/// deviates, the root, the noise's forces and torques and its velocities and spins
/// (`2n` each), and the midpoint (`n`). `O(n)`: no stored mobility beyond the far
/// field's packed blocks the products already hold.
pub(crate) const fn near_noise_sizes<T: Real>(p: &Params<T>, n: usize) -> [usize; 2] {
    if p.brownian.is_none() {
        return [0, 0];
    }
    let cap = p.lanczos.max_iterations as usize;
    [lanczos::vectors(cap, 2 * n) + 9 * n, lanczos::scalars(cap)]
}

/// Whether the near field keeps the start's rotation-translation blocks
/// ([`near_scalars`]).
pub(crate) const fn near_kept<T: Real>(p: &Params<T>) -> bool {
    p.rotation && p.brownian.is_some()
}

/// Stored mobilities a method keeps as symmetric blocks when it stores them (the start's,
/// and `Overdamped2`'s at the predicted point).
const fn symmetric_mobilities(method: Method) -> usize {
    match method {
        Method::Overdamped | Method::Springs => 1,
        Method::Overdamped2 => 2,
        Method::Rattle | Method::RattleStable => 0,
    }
}

/// Block rows of the mobility: `2n` when rotation is resolved (only the stable inertial
/// integrator integrates it), `n` otherwise.
pub(crate) const fn block_rows(method: Method, rotation: bool, n: usize) -> usize {
    if rotation && matches!(method, Method::RattleStable) {
        2 * n
    } else {
        n
    }
}

impl Layout {
    /// Storage for `method` with the default solver ([`SolverKind::Auto`]), `n`
    /// particles and `bonds` bonds.
    pub const fn new(method: Method, rotation: bool, n: usize, bonds: usize) -> Self {
        Self::with_solver(method, rotation, SolverKind::Auto, n, bonds)
    }

    /// Storage for `method` with the solver `kind`.
    ///
    /// Every method stores the candidate state (`3n` vectors), the forces (`m`), the bond
    /// vectors and multipliers (`B` each), and:
    /// * `Overdamped`, `Springs`: one packed mobility `tri(n)` symmetric blocks, `6 tri(n)`
    ///   scalars (in free space and in a box; [`Layout::for_params`] moves it to
    ///   `tri(n)` blocks of nine above a wall);
    /// * `Overdamped2`: two (start and predicted point);
    /// * `Overdamped`, `Overdamped2` with a dense solver (sweep, Newton): the `n x B`
    ///   table of constraint displacements, which those solvers read at every
    ///   iteration (Krylov needs none);
    /// * `Rattle`: the mobility and its Cholesky factor;
    /// * `RattleStable`: the mobility and the drag factor over `m` block rows (`2n` with
    ///   rotation), plus the dense `n x B` constraint displacements unless the solver is
    ///   Krylov.
    ///
    /// The dense Newton solve adds `B^2 + B` scalars and `B` indices; Krylov adds
    /// `16 B` scalars (its band and vectors) and `2n + 2m` vectors, and with contacts
    /// compiled in `13 B + n` indices (the rows' states and the pattern of its
    /// preconditioner on the constraint graph); the sweep adds nothing. From
    /// [`CELLS_MIN`](crate::cell_list::CELLS_MIN) spheres on (with the `cells` feature)
    /// the pair searches' cell list adds `3n + 1` indices
    /// ([`cell_list::indices`](crate::cell_list::indices)).
    pub const fn with_solver(
        method: Method,
        rotation: bool,
        kind: SolverKind,
        n: usize,
        bonds: usize,
    ) -> Self {
        let m = block_rows(method, rotation, n);
        let b = bonds;
        let kind = kind.resolve(bonds);
        // Candidate state, forces, bond vectors, multipliers.
        let mut l = Layout {
            blocks: 0,
            vectors: 3 * n + m + b,
            scalars: b,
            indices: 0,
            links: 0,
        };
        match method {
            Method::Overdamped | Method::Springs => {
                l.scalars += SYM * tri(n);
                l.vectors += n + band_scratch(n);
            }
            Method::Overdamped2 => {
                l.scalars += 2 * SYM * tri(n) + b;
                l.vectors += 3 * n + b;
            }
            Method::Rattle | Method::RattleStable => {}
        }
        // The dense solvers read a table of the hydrodynamic displacements.
        let table = !matches!(kind, SolverKind::Krylov);
        match method {
            Method::Overdamped | Method::Overdamped2 if table => l.vectors += n * b,
            Method::Overdamped | Method::Overdamped2 | Method::Springs => {}
            Method::Rattle => {
                l.blocks = 2 * tri(n);
                l.vectors += 3 * n + b;
                l.scalars += n + b;
            }
            Method::RattleStable => {
                l.blocks = 2 * tri(m);
                l.vectors += 2 * m + b;
                l.scalars += m + b;
                if !matches!(kind, SolverKind::Krylov) {
                    l.vectors += n * b;
                }
            }
        }
        if !matches!(method, Method::Springs) {
            let [s, v, i] = scratch_size(kind, n, m, b);
            l.scalars += s;
            l.vectors += v;
            l.indices += i;
        }
        // The pair searches' cell list (the acceptance's overlap check, every method).
        l.indices += crate::cell_list::indices(n);
        l
    }

    /// Storage for one step with parameters `p` (method, rotation flag, solver, the
    /// matrix-free flag, thermal noise and contacts), `n` particles and `bonds` bonds.
    /// Contacts count as constraints beside the bonds (up to their capacity), a hard
    /// surface (the wall) as one more per sphere ([`Params::constraints`]), and both add the list of links
    /// they are solved over.
    pub const fn for_params<T: Real>(p: &Params<T>, n: usize, bonds: usize) -> Self {
        let c = p.constraints(n, bonds);
        let mut l = Self::with_solver(p.method, p.rotation, p.solver_kind(n, bonds), n, c);
        if p.contacts.is_some() || !p.place().surfaces().is_empty() {
            l.links = c;
        }
        // (The iterative near field's noise has storage of its own: `near_noise_sizes`.)
        let l = if p.brownian.is_some() && !near_iterative(p) {
            l.thermal(p.method, n, c).noise_sqrt(p, n)
        } else {
            l
        };
        let l = if p.compact_copy(n, bonds) && !crate::noise::reduced::for_noise(p, n) {
            // The compact copy of the mobility (`Params::compact_products`), unless the
            // thermal noise's reduced copy is there already (`noise_sqrt`): it is reused.
            Self {
                blocks: l.blocks + crate::noise::reduced::slots(n),
                ..l
            }
        } else {
            l
        };
        let l = if p.matrix_free {
            l.matrix_free(p.method, p.solver_kind(n, bonds), n, c)
        } else {
            l
        };
        // Stokesian dynamics' near field: iterative products (`integrate::near_iter`),
        // or the far-field grand mobility's packed blocks and the dense `6n x 6n`
        // mobility formed from them (`stokesian::storage`).
        let l = if near_iterative(p) {
            let [blocks, vectors, scalars, indices] =
                near_iterative_sizes(n, c, !near_far_product(p));
            let [noise_vectors, noise_scalars] = near_noise_sizes(p, n);
            // The plain matrix-free `Overdamped2`'s band scratch, which its products here
            // (`integrate::near_iter`) do not read.
            let plain_bands = match p.method {
                Method::Overdamped2 => band_scratch(n),
                _ => 0,
            };
            // The sweep's and Newton's table of `M_SD`'s columns (`integrate::near_iter`),
            // which the matrix-free layout leaves out.
            let table = match (p.method, p.solver_kind(n, bonds)) {
                (
                    Method::Overdamped | Method::Overdamped2,
                    SolverKind::Sweep | SolverKind::Newton,
                ) => n * c,
                _ => 0,
            };
            Self {
                blocks: l.blocks + blocks,
                vectors: l.vectors - plain_bands + vectors + noise_vectors + table,
                scalars: l.scalars + scalars + noise_scalars,
                indices: l.indices + indices,
                ..l
            }
        } else if p.near_on() {
            Self {
                blocks: l.blocks + near_blocks(n),
                scalars: l.scalars + near_scalars(n, near_kept(p)),
                ..l
            }
        } else {
            l
        };
        if symmetric(p) {
            return l;
        }
        // Above a wall: the stored mobilities in blocks of nine.
        let stored = match p.method {
            Method::Overdamped | Method::Overdamped2 | Method::Springs if p.matrix_free => 0,
            _ if near_iterative(p) => 0,
            method => symmetric_mobilities(method),
        };
        l.general(stored, n)
    }

    /// This layout with `k` stored mobilities of `n` block rows in general blocks
    /// (`k tri(n)` blocks) instead of symmetric ones (`6 k tri(n)` scalars).
    const fn general(self, k: usize, n: usize) -> Self {
        Self {
            blocks: self.blocks + k * tri(n),
            scalars: self.scalars - SYM * k * tri(n),
            ..self
        }
    }

    /// This layout with room for thermal noise ([`Params::brownian`]), for the methods
    /// that take it (`Overdamped`, and `Springs` with the factor and one vector array;
    /// unchanged for the others): the mobility's Cholesky
    /// factor, later the mobility at the midpoint (`tri(n)` blocks), the noise
    /// displacement (`n` vectors), the bond vectors at the midpoint (`B` vectors) and
    /// the midpoint projection's multipliers (`B` scalars). The normal deviates and the
    /// midpoint itself live in the candidate velocities and spins until those are written.
    /// `RattleStable` at temperature needs nothing more: the mobility's factor lives in
    /// the drag factor's blocks until the drag operator is assembled there, the random
    /// force in a work array.
    pub const fn thermal(self, method: Method, n: usize, bonds: usize) -> Self {
        match method {
            Method::Overdamped => Self {
                blocks: self.blocks + tri(n),
                vectors: self.vectors + n + bonds,
                scalars: self.scalars + bonds,
                ..self
            },
            // The factor (then the midpoint's mobility) and the noise displacement.
            Method::Springs => Self {
                blocks: self.blocks + tri(n),
                vectors: self.vectors + n,
                ..self
            },
            _ => self,
        }
    }

    /// This thermal layout ([`Layout::thermal`]) adjusted for the square root
    /// [`Params::noise_sqrt`] picks at `n` beads: with Lanczos, the basis
    /// (`(cap + 1) n` vectors) and its small matrices (`2 cap^2 + 8 cap + 1` scalars),
    /// and no Cholesky factor. The midpoint's mobility then has storage of its own:
    /// `6 tri(n)` scalars of symmetric blocks where the stored mobility has them (free
    /// space, a box), `tri(n)` blocks above a wall, none with
    /// [`Drift::Uncorrected`](crate::Drift::Uncorrected) or [`Params::matrix_free`]
    /// (whose products at the midpoint store nothing); and an `f64` kernel of enough
    /// beads the reduced copy its noise reads (`noise::reduced`, about `tri(n) / 3`
    /// blocks). Unchanged with Cholesky (whose factor's blocks take the midpoint's
    /// mobility) and for methods without noise.
    pub const fn noise_sqrt<T: Real>(self, p: &Params<T>, n: usize) -> Self {
        let thermal = matches!(p.method, Method::Overdamped | Method::Springs);
        if !thermal || !p.lanczos_noise(n) {
            return self;
        }
        let cap = p.lanczos.max_iterations as usize;
        let uncorrected = match p.brownian {
            Some(b) => matches!(b.drift, crate::params::Drift::Uncorrected),
            None => false,
        };
        // Matrix-free, the midpoint's mobility is not stored either.
        let unstored = uncorrected || p.matrix_free;
        let (mid_blocks, mid_scalars) = match (unstored, symmetric(p)) {
            (true, _) => (0, 0),
            (false, true) => (0, SYM * tri(n)),
            (false, false) => (tri(n), 0),
        };
        let copy = if crate::noise::reduced::for_noise(p, n) {
            crate::noise::reduced::slots(n)
        } else {
            0
        };
        Self {
            blocks: self.blocks.saturating_sub(tri(n)) + mid_blocks + copy,
            vectors: self.vectors + lanczos::vectors(cap, n),
            scalars: self.scalars + lanczos::scalars(cap) + mid_scalars,
            ..self
        }
    }

    /// This layout without the stored (symmetric) mobility (and without the displacement table of
    /// the dense solvers), for the methods that run matrix-free
    /// ([`Params::matrix_free`]: `Overdamped`, `Springs`; `Overdamped2` without its two,
    /// with the products' band scratch instead); unchanged for the others.
    pub const fn matrix_free(
        self,
        method: Method,
        kind: SolverKind,
        n: usize,
        bonds: usize,
    ) -> Self {
        // The matrix-free products sum in the stored product's bands too
        // (`parallel::free_product`): their scratch stays.
        let table = match (method, kind.resolve(bonds)) {
            (Method::Overdamped | Method::Overdamped2, SolverKind::Sweep | SolverKind::Newton) => {
                n * bonds
            }
            _ => 0,
        };
        match method {
            Method::Overdamped | Method::Springs => Self {
                scalars: self.scalars - SYM * tri(n),
                vectors: self.vectors - table,
                ..self
            },
            Method::Overdamped2 => Self {
                scalars: self.scalars - 2 * SYM * tri(n),
                vectors: self.vectors - table + band_scratch(n),
                ..self
            },
            _ => self,
        }
    }

    /// Storage for every method, with and without rotation, with every solver, in free
    /// space and in a box (symmetric blocks) and above a wall (general blocks): one
    /// workspace a host can switch methods on.
    pub const fn all(n: usize, bonds: usize) -> Self {
        let methods = [
            Method::Overdamped,
            Method::Overdamped2,
            Method::Rattle,
            Method::RattleStable,
            Method::Springs,
        ];
        let kinds = [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov];
        let mut l = Layout {
            blocks: 0,
            vectors: 0,
            scalars: 0,
            indices: 0,
            links: 0,
        };
        let mut i = 0;
        while i < methods.len() * kinds.len() * 2 {
            let (method, kind) = (methods[i / 6], kinds[(i / 2) % 3]);
            let one = Self::with_solver(method, i % 2 == 1, kind, n, bonds);
            let general = one.general(symmetric_mobilities(method), n);
            l = l.max(one).max(general);
            i += 1;
        }
        l
    }

    /// Element-wise maximum: storage that serves both layouts (one workspace shared by
    /// several methods).
    pub const fn max(self, o: Self) -> Self {
        const fn mx(a: usize, b: usize) -> usize {
            if a > b { a } else { b }
        }
        Self {
            blocks: mx(self.blocks, o.blocks),
            vectors: mx(self.vectors, o.vectors),
            scalars: mx(self.scalars, o.scalars),
            indices: mx(self.indices, o.indices),
            links: mx(self.links, o.links),
        }
    }

    /// Bytes of this layout in precision `T`.
    pub const fn bytes<T: Real>(&self) -> usize {
        self.blocks * core::mem::size_of::<T::M3>()
            + self.vectors * core::mem::size_of::<T::V3>()
            + self.scalars * core::mem::size_of::<T>()
            + self.indices * core::mem::size_of::<usize>()
            + self.links * core::mem::size_of::<crate::bonds::Bond<T>>()
    }

    /// `true` when every count of `need` fits in `self`.
    pub const fn holds(&self, need: &Self) -> bool {
        need.blocks <= self.blocks
            && need.vectors <= self.vectors
            && need.scalars <= self.scalars
            && need.indices <= self.indices
            && need.links <= self.links
    }
}
