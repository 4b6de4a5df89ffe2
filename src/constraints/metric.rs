//! How a unit multiplier on bond `l` displaces the beads: `D_l(p)`.
//!
//! Every metric pushes along the bond vectors `g_l` of the step's start (the
//! SHAKE/RATTLE convention). The mass metric moves only the bond's two beads; the
//! hydrodynamic metrics move every bead, but none of them is ever stored as a dense
//! `beads x bonds` array except [`Metric::Dense`], which the small dense solve of the
//! implicit-drag integrator uses.
//!
//! A wall link ([`Bond::wall`](crate::bonds::Bond::wall)) pushes on its sphere alone:
//! its `j` term is absent (`D_l(p) = scale mu_pi g_l`), and the change of its relative
//! vector is the normal component of its sphere's displacement
//! ([`Bond::relative`](crate::bonds::Bond::relative)). A pin row
//! ([`Bond::pin`](crate::bonds::Bond::pin)) is the same along its axis.
//!
//! The metric's operations live by how they read it: one entry at a time
//! (`metric/entries.rs`: the sweep and the dense Newton solve, and the Krylov
//! preconditioner's band), all multipliers at once (`metric/product.rs`: the Krylov
//! solver's product, one mobility product a call), and the dense table built once a
//! step (`metric/table.rs`). The seam follows the solvers: each reads one of the three,
//! and each has its own storage and inlining concerns. The block reads they share are
//! here.

mod entries;
mod product;
mod table;

pub(crate) use product::apply_drag;
pub(crate) use table::tabulate;

use crate::geometry::{GENERAL_BLOCKS, Hydrodynamics};
use crate::linalg::{Block, Mob, tri};
use crate::parallel::Parallel;
use crate::real::Real;

/// How a unit multiplier on bond `l` displaces bead `p`.
#[derive(Clone, Copy, Debug)]
pub enum Metric<'a, T: Real> {
    /// Inverse-mass metric (the paper's eqs. 3-4): `+scale g_l / m_i` on `i`,
    /// `-scale g_l / m_j` on `j`, zero elsewhere.
    Mass {
        /// `1 / m` per bead.
        inv_mass: &'a [T],
        /// Constraint gradients `g_l = r_i - r_j`, one per bond.
        grad: &'a [T::V3],
        /// Overall factor (`dt^2 / 2` for positions).
        scale: T,
    },
    /// Hydrodynamic metric from the packed translational mobility:
    /// `D_l(p) = (mu_pi - mu_pj) (scale g_l)`, read block by block where it is used.
    Mobility {
        /// Packed `mu_tt` (`tri(n)` blocks, symmetric in free space and in a box).
        mu: Mob<'a, T>,
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
        /// Overall factor (`dt` for positions).
        scale: T,
        /// How its products run ([`crate::parallel::product`]).
        par: &'a dyn Parallel,
        /// The compact `f32` copy of `mu` ([`crate::noise::reduced`]) when the
        /// products of [`Metric::apply_all`] read it (mixed precision,
        /// [`Params::compact_products`](crate::Params::compact_products)); `None`:
        /// they read `mu`. Everything else reads `mu`.
        compact: Option<&'a [T::M3]>,
    },
    /// The same hydrodynamic metric without a stored mobility: each pair block is
    /// evaluated where it is used (matrix-free; bit-identical to [`Metric::Mobility`]).
    /// The positions must have passed a product at these positions ([`tt_product`](crate::mobility::tt_product)),
    /// which refuses nested spheres.
    Free {
        /// The geometry: free space, the wall, or the box with the step's periodic sums
        /// (derived once per step, not per block: `geometry/periodic/held.rs`); PSE has
        /// products only (its `D_l(p)` entries are zero: the step refuses the solvers
        /// that read them).
        hydro: Hydrodynamics<'a, T>,
        /// Bead centres.
        pos: &'a [T::V3],
        /// Bead radii.
        radius: &'a [T],
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
        /// Overall factor (`dt` for positions).
        scale: T,
        /// How its free-space products run ([`crate::parallel::free_product`], the bits
        /// of the stored product on any number of threads).
        par: &'a dyn Parallel,
    },
    /// Precomputed displacements `disp[l * beads + p]` (`bonds x beads`, bond-major: a
    /// multiplier's moves of all beads are contiguous, so the table is written in order
    /// and an update of all multipliers keeps a few beads' running sums in registers,
    /// adjacent beads' coordinates side by side, [`Metric::apply_each`]).
    Dense {
        /// Displacements, bond-major.
        disp: &'a [T::V3],
        /// Beads.
        n: usize,
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
    },
    /// Implicit-drag metric `D_l = dt Q g_l`, `Q = (R + M/dt)^-1 = dt S^-1 K^-1 S mu`
    /// with `K = dt I + S mu S` factorised (the stable inertial integrator). Only its
    /// action on a whole multiplier vector is available: one mobility product and one
    /// Cholesky solve. Solved by the Krylov solver only.
    Drag {
        /// Packed mobility (`tri(m)` blocks, `m = n` or `2n` with rotation).
        mu: &'a [T::M3],
        /// Cholesky factor of `K`, packed.
        fac: &'a [T::M3],
        /// `S`: `sqrt(m)` per bead, then `sqrt(I)` per bead with rotation (length `m`).
        sq: &'a [T],
        /// Time step.
        dt: T,
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
    },
}

/// Block `(q, p)` of a packed symmetric matrix, `mu_pq^T`: read as it is stored for
/// `q > p`, transposed for `q <= p` (exact; the free-space blocks are symmetric, so
/// this is their stored block bit for bit, while a wall's pair blocks are not,
/// [`wall`](crate::mobility::wall)).
#[inline(always)]
fn sym_block<T: Real, B: Block<T>>(mu: &[B], p: usize, q: usize) -> T::M3 {
    if q <= p {
        // Symmetric blocks (and every block where no geometry has general ones): no
        // transpose needed.
        let b = mu[tri(p) + q].full();
        if GENERAL_BLOCKS && B::SCALARS == 9 {
            T::transpose(b)
        } else {
            b
        }
    } else {
        mu[tri(q) + p].full()
    }
}

/// `(a - c)^T g`: `(A_pi - A_pj) g` from the blocks [`sym_block`] gives (the wall's
/// pair blocks are not symmetric). For symmetric blocks these are the bits of
/// `(a - c) * g` (the same products summed in glam's order, the entries equal to their
/// transposes).
/// `sym` says the blocks are known symmetric (no wall in this step): then, as without
/// the `wall` feature, only their lower triangles are read.
#[inline(always)]
fn sym_diff_mul<T: Real>(a: T::M3, c: T::M3, g: T::V3, sym: bool) -> T::V3 {
    let d = |r, col| T::m3_get(a, r, col) - T::m3_get(c, r, col);
    let [x, y, z] = T::xyz(g);
    if !GENERAL_BLOCKS || sym {
        // Symmetric blocks only: the lower triangles suffice (12 loads and 6
        // subtractions instead of 18 and 9), the same bits (M4 firmware's hot loop).
        let (d00, d10, d20) = (d(0, 0), d(1, 0), d(2, 0));
        let (d11, d21, d22) = (d(1, 1), d(2, 1), d(2, 2));
        return T::v3(
            d00 * x + d10 * y + d20 * z,
            d10 * x + d11 * y + d21 * z,
            d20 * x + d21 * y + d22 * z,
        );
    }
    T::v3(
        d(0, 0) * x + d(1, 0) * y + d(2, 0) * z,
        d(0, 1) * x + d(1, 1) * y + d(2, 1) * z,
        d(0, 2) * x + d(1, 2) * y + d(2, 2) * z,
    )
}

impl<T: Real> Metric<'_, T> {
    /// The bond vector multiplier `l` pushes along.
    #[inline]
    pub fn grad(&self, l: usize) -> T::V3 {
        match *self {
            Metric::Mass { grad, .. }
            | Metric::Mobility { grad, .. }
            | Metric::Free { grad, .. }
            | Metric::Dense { grad, .. }
            | Metric::Drag { grad, .. } => grad[l],
        }
    }
}
