//! Constraint solves on one generic problem: the SHAKE/RATTLE sweep of the paper
//! (`sweep.rs`), Newton on the dense Jacobian (`newton.rs`) and chord Newton with
//! preconditioned conjugate gradients for many bonds (`krylov.rs`).
//!
//! A unit multiplier on bond `l` moves bead `p` by `D_l(p)` ([`Metric`]). The position
//! problem finds `lambda` with `|x_i - x_j|^2 = d^2` for `x = x* + sum_l lambda_l D_l`
//! (paper eq. 3); the velocity problem finds `kappa` with `b_k . (v_i - v_j) = 0` for
//! `v = v* + sum_l kappa_l D_l` (paper eq. 4), `b_k` the bond vectors at the new positions.
//!
//! The list may hold wall links ([`Bond::wall`]) after the bonds: a sphere held at its
//! radius above the plane `z = 0` (positions in the wall's frame) by the linear
//! constraint `2 a (z_i - a) = 0`. Its multiplier pushes on the sphere alone, along
//! `g = (0, 0, a)`; everything else (metrics, Jacobians, solvers) treats it as a link
//! whose other end does not move along the normal ([`Bond::relative`]). Pin rows
//! ([`Bond::pin`]) are such links along x, y or z, measured from their anchors
//! ([`Problem::Positions`]), and are equalities among the bonds.

mod active;
mod dependent;
mod graph;
mod krylov;
mod metric;
mod newton;
mod onesided;
mod products;
mod sweep;

pub use krylov::{BAND, krylov, krylov_with};
pub use products::{Exact, Products};

/// Krylov scratch scalars per bond.
pub(crate) const fn krylov_scratch_per_bond() -> usize {
    krylov::SCALARS_PER_BOND
}
pub use metric::Metric;
pub(crate) use metric::{apply_drag, tabulate};
pub use newton::newton;
pub use sweep::sweep;

use crate::bonds::Bond;
use crate::cell::Periodic;
use crate::error::{Stage, StepError};
use crate::real::Real;

/// [`SolverKind::Auto`] picks the dense [`SolverKind::Newton`] solve up to this many
/// constraint rows (bonds, contact capacity and wall links:
/// [`Params::solver_kind`](crate::Params::solver_kind)) and [`SolverKind::Krylov`] above. Measured crossover (`cargo bench --bench
/// kernel -- solver`): see `docs/BENCHMARKS.md`.
pub const DENSE_BONDS_MAX: usize = 32;

/// Which algorithm solves for the multipliers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolverKind {
    /// Cyclic sweeps, one constraint at a time in bond order (the paper's SHAKE/RATTLE).
    Sweep,
    /// Newton iterations on the dense `bonds x bonds` Jacobian (LU, reused while it
    /// keeps converging fast): `O(B^2)` storage, `O(B^3)` per factorisation.
    Newton,
    /// Chord Newton with banded-preconditioned conjugate gradients (with contacts or
    /// wall links: preconditioned by the incomplete Cholesky of the rows that share a
    /// sphere): `O(B)` storage, one mobility product per iteration.
    Krylov,
    /// [`SolverKind::Newton`] up to [`DENSE_BONDS_MAX`] constraint rows,
    /// [`SolverKind::Krylov`] above (the default); with contacts, Newton up to
    /// [`PILE_NEWTON_MAX`] spheres and [`PILE_NEWTON_ROWS_MAX`] rows
    /// ([`SolverKind::resolve_contacts`]). A step resolves it once, from every row it
    /// may solve ([`Params::solver_kind`](crate::Params::solver_kind)).
    #[default]
    Auto,
}

/// With contacts, [`SolverKind::Auto`] picks [`SolverKind::Newton`] up to this many
/// spheres: the largest settling pile measured (535 spheres), where Newton's one
/// factorisation a step still costs less than half of Krylov's products. A contact list's rows couple through
/// the pair mobility, which decays only as `1/r`, so Krylov's preconditioner on the
/// constraint graph leaves most of the coupling out, and its products a step grow with
/// the pile (about 370, 570 and 1,330 at 100, 300 and 535 spheres). Measured (`cargo run
/// --release --example pile_cost 150 50 100 300 500`): see `docs/CONTACTS.md`.
pub const PILE_NEWTON_MAX: usize = 540;

/// With contacts, [`SolverKind::Auto`] picks [`SolverKind::Newton`] only up to this
/// many constraint rows: its Jacobian holds `rows^2` scalars (155 MB in `f64` at this
/// bound; the 535-sphere pile with 7 contact slots a sphere has 4,315 rows), so a larger
/// contact capacity takes Krylov's `O(rows)` storage instead.
pub const PILE_NEWTON_ROWS_MAX: usize = 4400;

impl SolverKind {
    /// The algorithm that runs for `rows` constraint rows ([`SolverKind::Auto`]
    /// resolved).
    pub const fn resolve(self, rows: usize) -> Self {
        match self {
            Self::Auto if rows <= DENSE_BONDS_MAX => Self::Newton,
            Self::Auto => Self::Krylov,
            kind => kind,
        }
    }

    /// The algorithm that runs for `rows` constraint rows on `n` spheres with contacts
    /// ([`SolverKind::Auto`] resolved): Newton up to [`PILE_NEWTON_MAX`] spheres and
    /// [`PILE_NEWTON_ROWS_MAX`] rows, else as [`SolverKind::resolve`].
    pub const fn resolve_contacts(self, rows: usize, n: usize) -> Self {
        match self {
            Self::Auto if n <= PILE_NEWTON_MAX && rows <= PILE_NEWTON_ROWS_MAX => Self::Newton,
            kind => kind.resolve(rows),
        }
    }
}

/// Tolerance and iteration cap for a constraint solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solver<T> {
    /// Algorithm.
    pub kind: SolverKind,
    /// Largest accepted relative bond-length error `| |r_ij| - d | / d` (positions), or
    /// relative length change per step `dt |b.(v_i - v_j)| / d^2` (velocities). At
    /// least [`Solver::min_tolerance`]: rounding alone makes smaller values unreachable,
    /// and a step refuses them (`StepError::BadParameter`) instead of iterating to the cap.
    pub tolerance: T,
    /// Iteration cap (sweeps, Newton steps, or Krylov chord steps; Krylov also stops
    /// after `10 x max_iterations` operator products); reaching it is an error.
    pub max_iterations: u32,
}

impl<T: Real> Solver<T> {
    /// The smallest tolerance a step accepts: 16 machine epsilons (1.9e-6 in f32,
    /// 3.6e-15 in f64). A bond's length is computed from two rounded positions, so its
    /// relative error cannot be driven much below a few epsilons.
    pub fn min_tolerance() -> T {
        T::EPSILON * T::from_f64(16.0)
    }
}

/// Which condition to enforce.
#[derive(Clone, Copy, Debug)]
pub enum Problem<'a, T: Real> {
    /// `|x_i - x_j|^2 - d^2 = 0` (SHAKE), `x_i - x_j` the minimum image in a periodic
    /// box.
    Positions {
        /// The periodic box, if any ([`Params::periodic`](crate::Params::periodic)).
        cell: Option<Periodic<T>>,
        /// The rows from this one on are one-sided (contacts and wall links:
        /// `sigma >= 0`, a non-negative multiplier, complementary; `docs/CONTACTS.md`),
        /// the rows before it equalities. `usize::MAX`: none.
        one_sided: usize,
        /// The anchors of the pin rows ([`Bond::pin`]): the positions at the start of
        /// the step, indexed by sphere (empty where no row is a pin).
        #[cfg(feature = "pins")]
        anchor: &'a [T::V3],
        /// The ceiling's height in the frame of the positions (a slit's upper plane,
        /// which the ceiling links hold: [`Bond::ceiling`]); zero without one.
        #[cfg(feature = "slit")]
        ceiling: T,
    },
    /// `b_k . (x_i - x_j) = 0` with `b_k` the new bond vectors (RATTLE); `dt` scales the
    /// residual to a relative length change per step.
    Velocities {
        /// Bond vectors at the new positions.
        bond: &'a [T::V3],
        /// Time step.
        dt: T,
    },
}

impl<T: Real> Problem<'_, T> {
    /// Residual of bond `k`, its derivative direction (w.r.t. `x_i - x_j`), and the
    /// normalised magnitude compared with the tolerance.
    #[inline]
    fn eval(&self, b: &Bond<T>, k: usize, x: &[T::V3]) -> (T, T::V3, T) {
        self.eval_with::<true>(b, k, x)
    }

    /// [`Problem::eval`], its magnitude (a square root and a division a bond) only with
    /// `NORM` (zero without): the Newton right-hand sides, which do not read it, call
    /// it out of line, where it was computed and discarded.
    #[inline]
    fn eval_with<const NORM: bool>(&self, b: &Bond<T>, k: usize, x: &[T::V3]) -> (T, T::V3, T) {
        let rel = match *self {
            Problem::Positions { cell, .. } => b.separation(x, cell.as_ref()),
            Problem::Velocities { .. } => b.relative(x),
        };
        let d2 = b.length * b.length;
        match *self {
            // A pin row's linear constraint `2 s (x_i - anchor_i) . e` (see [`Bond::pin`]):
            // the wall link's with the anchor in place of the plane (no image taken).
            #[cfg(feature = "pins")]
            Problem::Positions { anchor, .. } if b.is_pin() => {
                let e = b.axis();
                let off = T::xyz(x[b.i])[e] - T::xyz(anchor[b.i])[e];
                let two_s = T::TWO * b.length;
                (
                    two_s * off,
                    crate::bonds::along::<T>(e, two_s),
                    lazy::<T, NORM>(|| (off / b.length).abs()),
                )
            }
            // A ceiling link's: the wall link's measured from the ceiling (`d < 0`).
            #[cfg(feature = "slit")]
            Problem::Positions { ceiling, .. } if b.is_ceiling() => {
                let z = T::xyz(x[b.i])[2] - ceiling;
                let two_d = T::TWO * b.length;
                (
                    two_d * (z - b.length),
                    T::v3(T::ZERO, T::ZERO, two_d),
                    lazy::<T, NORM>(|| ((z - b.length) / b.length).abs()),
                )
            }
            // A wall link's linear constraint `2 d (z - d)` (see [`Bond::wall`]); its
            // gradient `(0, 0, 2 d)` is the chord's `c g` (`g = (0, 0, d)`).
            Problem::Positions { .. } if b.is_wall() => {
                let z = T::xyz(rel)[2];
                let two_d = T::TWO * b.length;
                (
                    two_d * (z - b.length),
                    T::v3(T::ZERO, T::ZERO, two_d),
                    lazy::<T, NORM>(|| ((z - b.length) / b.length).abs()),
                )
            }
            Problem::Positions { .. } => {
                let r2 = T::norm2(rel);
                // The relative length error `| |r| - d | / d` the tolerance is stated in
                // (`|r^2 - d^2| / (2 d^2)` would understate a compressed bond's error).
                (
                    r2 - d2,
                    rel * T::TWO,
                    lazy::<T, NORM>(|| (r2.sqrt() - b.length).abs() / b.length),
                )
            }
            Problem::Velocities { bond, dt } => {
                let c = T::dot(bond[k], rel);
                (c, bond[k], lazy::<T, NORM>(|| (c * dt).abs() / d2))
            }
        }
    }

    /// `|value|` normalised as the tolerance is (a linear residual of bond `b`).
    #[inline]
    fn normalise(&self, b: &Bond<T>, value: T) -> T {
        let d2 = b.length * b.length;
        match *self {
            Problem::Positions { .. } => value.abs() / (T::TWO * d2),
            Problem::Velocities { dt, .. } => (value * dt).abs() / d2,
        }
    }

    /// `c` in the chord matrix `A = c G D`: the derivative of the residual along `g`.
    fn chord_factor(&self) -> T {
        match self {
            Problem::Positions { .. } => T::TWO,
            Problem::Velocities { .. } => T::ONE,
        }
    }

    /// The first one-sided row of `rows`: `usize::MAX` where there is none (a
    /// constant where contacts are compiled out, so that every one-sided branch folds
    /// away).
    #[inline(always)]
    fn one_sided(&self, rows: usize) -> usize {
        match *self {
            Problem::Positions { one_sided, .. }
                if cfg!(feature = "contacts") && one_sided < rows =>
            {
                one_sided
            }
            _ => usize::MAX,
        }
    }

    fn stage(&self) -> Stage {
        match self {
            Problem::Positions { .. } => Stage::Positions,
            Problem::Velocities { .. } => Stage::Velocities,
        }
    }

    fn no_convergence(&self, iterations: u32, residual: T) -> StepError {
        StepError::NoConvergence {
            stage: self.stage(),
            iterations,
            residual: residual.to_f64(),
        }
    }
}

/// Outcome of a converged solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats<T> {
    /// Sweeps or Newton steps taken.
    pub iterations: u32,
    /// Largest normalised residual left.
    pub residual: T,
    /// Dense factorisations of the Jacobian (Newton; 0 for the sweep and Krylov).
    pub factorizations: u32,
}

/// Solver scratch, each part sized by [`Layout`](crate::workspace::Layout) for the
/// solver that runs (empty otherwise).
pub struct Scratch<'a, T: Real> {
    /// Newton: the Jacobian (`bonds^2`, row-major).
    pub jac: &'a mut [T],
    /// Newton: right-hand side / update (`bonds`).
    pub rhs: &'a mut [T],
    /// Newton: LU pivots (`bonds`).
    pub piv: &'a mut [usize],
    /// Krylov: preconditioner band and CG vectors (`krylov::SCALARS_PER_BOND x bonds`).
    pub krylov: &'a mut [T],
    /// Krylov: bead-space vectors (`2n + 2m`, and the mobility product's band scratch).
    pub beads: &'a mut [T::V3],
    /// How the mobility products of the hydrodynamic metric run.
    pub par: &'a dyn crate::parallel::Parallel,
    /// Newton with one-sided rows: the factor of the active rows that the last solve
    /// left in `jac` and `piv`, for the next solve on the same chord matrix.
    pub carry: Carry,
}

/// Newton's factor of the active rows carried from one solve to the next
/// (`docs/CONTACTS.md`, "Large piles"): the contact rounds of a step solve on the same
/// chord matrix (the same start, metric and rows, a round's new rows appended at the
/// end of the list, a released one taken out of it), so the next round's factor is
/// the last one brought to its set row by row instead of a factorisation from scratch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Carry {
    /// Set by the caller: the next solve's rows are the last solve's (same entries)
    /// with `released` taken out and new rows appended; otherwise the factor is built
    /// from scratch.
    pub keep: bool,
    /// The row (the last solve's index) taken out of the list since, if any.
    pub released: Option<usize>,
    /// Set by Newton: the rows in the factor and the stride (the last solve's rows) it
    /// is stored with; `None` where it left none.
    pub held: Option<(usize, usize)>,
}

/// Scratch sizes `[scalars, vectors, indices]` of `kind` for `n` beads, `m` block rows
/// of the mobility and `bonds` bonds.
pub const fn scratch_size(kind: SolverKind, n: usize, m: usize, bonds: usize) -> [usize; 3] {
    match kind.resolve(bonds) {
        SolverKind::Newton => [
            bonds * bonds + bonds,
            0,
            index_scratch(SolverKind::Newton, n, bonds),
        ],
        SolverKind::Krylov => [
            krylov::SCALARS_PER_BOND * bonds,
            2 * n + 2 * m + crate::parallel::band_scratch(m),
            index_scratch(SolverKind::Krylov, n, bonds),
        ],
        _ => [0, 0, 0],
    }
}

/// Index scratch of `kind` (resolved) for `bonds` rows on `n` spheres: Newton's LU
/// pivots, and with contacts compiled in the one-sided rows' states (Newton, Krylov)
/// and the pattern of Krylov's preconditioner on the constraint graph (`graph.rs`).
pub(crate) const fn index_scratch(kind: SolverKind, n: usize, bonds: usize) -> usize {
    match kind {
        SolverKind::Newton => bonds + onesided::STATE_PER_ROW * bonds,
        SolverKind::Krylov => onesided::STATE_PER_ROW * bonds + graph::indices(n, bonds),
        _ => 0,
    }
}

/// Largest normalised residual over all bonds (positions: two square roots, see
/// [`max_residual`](crate::bonds::max_residual)).
fn worst<T: Real>(problem: &Problem<'_, T>, bonds: &[Bond<T>], x: &[T::V3]) -> T {
    if let Problem::Positions { cell, .. } = problem {
        let mut w = crate::bonds::max_residual_in(bonds, x, cell.as_ref()).1;
        // Pin rows (skipped above): their anchors' errors.
        if cfg!(feature = "pins") {
            for (k, b) in bonds.iter().enumerate().filter(|(_, b)| b.is_pin()) {
                w = w.max_sticky(problem.eval(b, k, x).2);
            }
        }
        return w;
    }
    let mut w = T::ZERO;
    for (k, b) in bonds.iter().enumerate() {
        w = w.max_sticky(problem.eval(b, k, x).2);
    }
    w
}

/// `f()` with `NORM`, zero without ([`Problem::eval_with`]).
#[inline(always)]
fn lazy<T: Real, const NORM: bool>(f: impl FnOnce() -> T) -> T {
    if NORM { f() } else { T::ZERO }
}

/// Solves for the multipliers, accumulating them into `mult` and moving `x`. The
/// implicit-drag metric has no cheap single-bond form and is always solved by Krylov.
///
/// Always inlined (it is only this choice): where the parameters and the metric are
/// known to the compiler (a firmware's `static`), only the solver that runs is linked;
/// otherwise the metric's variant decides at run time and every solver is (firmware
/// flash, `docs/BENCHMARKS.md`).
#[inline(always)]
pub fn solve<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    let kind = match metric {
        Metric::Drag { .. } => SolverKind::Krylov,
        _ => solver.kind.resolve(bonds.len()),
    };
    match kind {
        SolverKind::Sweep => sweep(problem, metric, bonds, solver, x, mult),
        SolverKind::Krylov => krylov(problem, metric, bonds, solver, x, mult, scratch),
        _ => newton(problem, metric, bonds, solver, x, mult, scratch),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// `eval_with::<false>` (the Newton right-hand sides) gives `eval`'s residual and
    /// direction bit for bit, and no magnitude, for every kind of row: bonds (stretched,
    /// compressed, NaN), wall links, pins; positions and velocities.
    #[test]
    fn eval_without_the_magnitude_keeps_the_residual_and_direction() {
        let x = [
            DVec3::new(0.1, -0.3, 1.7),
            DVec3::new(1.9, 0.4, 2.2),
            DVec3::new(0.2, 0.1, -0.4),
            DVec3::new(f64::NAN, 0.0, 1.0),
        ];
        let bond = |i, j, length: f64| Bond { i, j, length };
        let mut rows = [
            bond(0, 1, 1.5),
            bond(1, 2, 3.5),
            bond(2, 3, 1.0),
            Bond::wall(2, 0.7),
            Bond::wall(0, 0.9),
            bond(0, 2, 0.3),
        ]
        .to_vec();
        if cfg!(feature = "pins") {
            rows.extend(Bond::pins(1, 0.8));
        }
        let anchor = [DVec3::new(0.0, 0.2, 1.5), DVec3::new(1.7, 0.5, 2.0)];
        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
        let positions = Problem::Positions {
            cell: None,
            one_sided: usize::MAX,
            #[cfg(feature = "pins")]
            anchor: &anchor,
            #[cfg(feature = "slit")]
            ceiling: 0.0,
        };
        let _ = anchor;
        let grad: [DVec3; 9] = core::array::from_fn(|k| DVec3::new(0.3, -0.2 * k as f64, 1.1));
        let velocities = Problem::Velocities {
            bond: &grad,
            dt: 0.01,
        };
        for problem in [positions, velocities] as [Problem<f64>; 2] {
            for (k, b) in rows.iter().enumerate() {
                let (v0, d0, m0) = problem.eval(b, k, &x);
                let (v1, d1, m1) = problem.eval_with::<false>(b, k, &x);
                assert_eq!(v0.to_bits(), v1.to_bits(), "row {k}");
                assert_eq!(bits(d0), bits(d1), "row {k}");
                assert_eq!(m1, 0.0);
                // The full form does compute a magnitude.
                assert!(m0 != 0.0, "row {k}");
            }
        }
    }
}
