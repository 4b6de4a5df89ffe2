//! Stages the integrators share: the mobility product and the constraint metric, bond
//! vectors, flow, constraint forces, spins, the position projection onto the bonds and
//! the report (the overdamped projection with its contacts is in `contacts.rs`).

use super::StepReport;
use crate::bonds::Bond;
use crate::cell::Periodic;
use crate::constraints::{self, Metric, Problem, Scratch, SolveStats, SolverKind};
use crate::error::StepError;
use crate::geometry::Hydrodynamics;
use crate::linalg::{Mob, MobMut};
use crate::parallel::Parallel;
use crate::params::Params;
use crate::real::Real;

pub(super) use crate::geometry::{HeldSums, PSE_ASSEMBLED, Sums, held_ewald};

/// The step's geometry ([`Hydrodynamics`]) from its parameters and its periodic sums
/// `ew` ([`Sums`]): the one place a stage turns the parameters into it.
#[inline(always)]
pub(super) fn hydro<'a, T: Real>(p: &Params<T>, ew: Sums<'a, T>) -> Hydrodynamics<'a, T> {
    Hydrodynamics::at(p.place(), p.hydro, p.viscosity, ew)
}

/// `u = mu_tt(pos) f`: assembled into `mu` and applied in one pass, in bands through
/// `par` (`bands` holds their partial sums, [`crate::parallel`]), or matrix-free (then
/// `mu` is empty and nothing is stored); in a box with the step's Ewald sums `ew`.
#[allow(clippy::too_many_arguments)]
pub(super) fn mobility_product<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    mu: MobMut<'_, T>,
    f: &[T::V3],
    u: &mut [T::V3],
    par: &dyn Parallel,
    bands: &mut [T::V3],
) -> Result<(), StepError> {
    if p.matrix_free {
        return free_product(p, ew, pos, radius, f, u, (par, bands));
    }
    hydro(p, ew).assemble_apply(par, pos, radius, mu, f, u, bands)
}

/// The hydrodynamic constraint metric `D_l = scale mu G^T e_l`: matrix-free when asked;
/// read from the packed mobility where it is used for Krylov (one product per
/// iteration, no table); tabulated once into `disp` (`n x B`) for the dense solvers,
/// which read every `D_l(p)` at every iteration. Inlined, so that the solve sees which
/// metric it gets ([`constraints::solve`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn mobility_metric<'a, T: Real>(
    p: &Params<T>,
    ew: Sums<'a, T>,
    bonds: &[Bond<T>],
    pos: &'a [T::V3],
    radius: &'a [T],
    mu: Mob<'a, T>,
    grad: &'a [T::V3],
    scale: T,
    disp: &'a mut [T::V3],
    (par, compact): (&'a dyn Parallel, &'a [T::M3]),
) -> Metric<'a, T> {
    if p.matrix_free {
        return Metric::Free {
            hydro: hydro(p, ew),
            pos,
            radius,
            grad,
            scale,
            par,
        };
    }
    if p.solver.kind.resolve(bonds.len()) == SolverKind::Krylov {
        return Metric::Mobility {
            mu,
            grad,
            scale,
            par,
            // The compact copy when the step keeps one (`Params::compact_products`).
            compact: (!compact.is_empty()).then_some(compact),
        };
    }
    let n = pos.len();
    // Without a wall every block is symmetric: the table reads lower triangles only.
    // With the near field the blocks are the Stokesian dynamics mobility's, in general
    // not symmetric.
    let sym = hydro(p, ew).symmetric() && !p.near_on();
    constraints::tabulate(mu, bonds, grad, scale, n, sym, disp);
    let disp = &disp[..n * bonds.len()];
    Metric::Dense { disp, n, grad }
}

/// `u = mu_tt(pos) f` matrix-free: every pair block evaluated where it is used (above
/// the wall if there is one, in the box with the step's Ewald sums `ew`). In free space
/// and above a wall in the bands of the stored product through `par` (`bands`: their
/// scratch), with its bits.
pub(super) fn free_product<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
    (par, bands): (&dyn Parallel, &mut [T::V3]),
) -> Result<(), StepError> {
    hydro(p, ew).product(par, pos, radius, f, u, bands)
}

/// The wall's height when the step has one and the kernel its `wall` feature (without
/// it the wall's code compiles away; `check_wall` refuses the wall then).
#[inline(always)]
pub(super) fn wall_height<T: Real>(p: &Params<T>) -> Option<T> {
    p.place().step_wall()
}

/// The periodic box when the step has one and the kernel its `periodic` feature
/// (without it the box's code compiles away; `check_periodic` refuses the box then).
#[inline(always)]
pub(super) fn cell<T: Real>(p: &Params<T>) -> Option<Periodic<T>> {
    p.place().step_cell()
}

/// The box when its images interact through the mobility: not with free draining,
/// whose mobility has self blocks only (the same in a box as outside it).
#[inline(always)]
pub(super) fn ewald_cell<T: Real>(p: &Params<T>) -> Option<Periodic<T>> {
    p.place().summed_cell(p.hydro)
}

/// `mu_tt(pos)` into the packed lower triangle `mu`: free space, above the wall, or in
/// the periodic box (with the step's Ewald sums `ew`).
pub(super) fn assemble_tt<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    mu: MobMut<'_, T>,
) -> Result<(), StepError> {
    hydro(p, ew).assemble_tt(pos, radius, mu)
}

/// `g_l = r_i - r_j` for every bond (its minimum image in a periodic box `cell`);
/// `(0, 0, a)` for a wall link (the wall's normal, scaled as the link's relative vector
/// at contact: [`Bond::wall`]); `s e` for a pin row along axis `e` ([`Bond::pin`]).
pub(super) fn bond_vectors<T: Real>(
    bonds: &[Bond<T>],
    pos: &[T::V3],
    cell: Option<Periodic<T>>,
    out: &mut [T::V3],
) {
    for (g, b) in out.iter_mut().zip(bonds) {
        *g = match b.one_sphere() {
            true => crate::bonds::along::<T>(b.axis(), b.length),
            false => crate::cell::image(cell.as_ref(), pos[b.i] - pos[b.j]),
        };
    }
}

/// `u_i += U_inf(r_i)`.
pub(super) fn add_flow<T: Real>(p: &Params<T>, pos: &[T::V3], u: &mut [T::V3]) {
    for (ui, &r) in u.iter_mut().zip(pos) {
        *ui += p.flow_at(r);
    }
}

/// Largest `|lambda_k| d_k`.
pub(super) fn max_tension<T: Real>(bonds: &[Bond<T>], lambda: &[T]) -> T {
    bonds
        .iter()
        .zip(lambda)
        .fold(T::ZERO, |m, (b, &l)| m.max((l * b.length).abs()))
}

/// `f_i += sum_l lambda_l (+-g_l)`: the constraint forces.
pub(super) fn add_constraint_forces<T: Real>(
    bonds: &[Bond<T>],
    grad: &[T::V3],
    lambda: &[T],
    f: &mut [T::V3],
) {
    for (l, b) in bonds.iter().enumerate() {
        f[b.i] += grad[l] * lambda[l];
        if !b.one_sphere() {
            f[b.j] -= grad[l] * lambda[l];
        }
    }
}

/// Angular velocities of torque-free spheres: `W_i = Omega_inf + sum_j rt_ij f_j`, with
/// `f` the force each sphere exerts on the fluid; `Omega_inf` alone when not resolved.
/// In a box, the `rt` blocks are the step's Ewald sums `ew`.
pub(super) fn spin<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    out: &mut [T::V3],
) -> Result<(), StepError> {
    out.fill(p.vorticity);
    if !p.rotation {
        return Ok(());
    }
    // The fast free-space product's own grand product (PSE in a box, which has no
    // rt products, is refused with rotation in the step's checks).
    #[cfg(feature = "fast-free")]
    if let Some(fast) = ew.and_then(|s| s.pse())
        && p.place().cell().is_none()
    {
        fast.spin(p.viscosity, (pos, radius), f, out)?;
        out.iter_mut().for_each(|w| *w += p.vorticity);
        return Ok(());
    }
    hydro(p, ew).add_spin(pos, radius, f, out)
}

/// Projects `x` onto the bonds along `metric`; the multipliers start from zero and end
/// in `lambda`. The rows from `one_sided` on (contacts and wall links; `usize::MAX`:
/// none) are inequalities ([`Problem::Positions`]); pin rows ([`Bond::pin`]) are held
/// at their spheres' positions in `anchor` (the step's start). Inlined into every projection, so that the solver choice folds where
/// the parameters are constant ([`constraints::solve`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn project_positions<T: Real>(
    p: &Params<T>,
    bonds: &[Bond<T>],
    metric: &Metric<'_, T>,
    x: &mut [T::V3],
    lambda: &mut [T],
    scratch: &mut Scratch<'_, T>,
    one_sided: usize,
    anchor: &[T::V3],
) -> Result<SolveStats<T>, StepError> {
    lambda.fill(T::ZERO);
    let _ = anchor; // Read only with the `pins` feature.
    constraints::solve(
        Problem::Positions {
            cell: cell(p),
            one_sided,
            #[cfg(feature = "pins")]
            anchor,
            #[cfg(feature = "slit")]
            ceiling: super::contacts::ceiling(p),
        },
        metric,
        bonds,
        &p.solver,
        x,
        lambda,
        scratch,
    )
}

/// Refuses a step too short for the positions' precision: where no sphere's
/// unconstrained move `dt |u_i|` (its largest component) reaches the spacing of its coordinates (`eps` times
/// its largest coordinate, within a factor 2 of the ulp), the new positions round to
/// the old ones and the velocities `(x' - x) / dt` come out zero, or (a move of a few
/// spacings) wrong by the rounding of the difference (dt 1e-16 on a pile about the
/// origin gave a centre-of-mass speed of 0.015 for 0.12): such a step computes
/// nothing, and it is refused (a parameter error, not retried) rather than reported as
/// a state at rest. Velocities are taken from positions because that is what the step
/// moves; refusing keeps every step that does move bit for bit as it was. A scene
/// without motion (every `u_i` zero) is not refused, nor a sphere whose move is not
/// finite (the acceptance names it). The overdamped schemes (both orders) and the
/// deterministic spring step judge their unconstrained velocity at the start; the
/// inertial schemes are not judged (from rest their first move is `a dt^2 / 2`, below
/// the spacing at steps that are legitimate), nor the Brownian ones (the thermal move
/// goes as `sqrt(dt)`).
pub(super) fn check_resolved<T: Real>(pos: &[T::V3], u: &[T::V3], dt: T) -> Result<(), StepError> {
    let mut moving = false;
    for (&x, &v) in pos.iter().zip(u) {
        let speed = largest::<T>(v);
        let moved = speed * dt;
        // A move `> 0` is a speed `> 0`; one that underflows to zero is still a move
        // below the spacing.
        moving |= speed > T::ZERO;
        if moved > T::ZERO && moved.is_finite() && moved >= T::EPSILON * largest::<T>(x) {
            return Ok(());
        }
    }
    match moving {
        true => Err(StepError::BadParameter(
            "dt (so short that no sphere moves by its coordinates' spacing)",
        )),
        false => Ok(()),
    }
}

/// The largest component's magnitude ([`check_resolved`]), not the norm: the norm's
/// square overflows for speeds above the square root of the largest number (gravity
/// of 1e160), which would read as no move at all. Out of line: called twice a sphere,
/// and firmware keeps one copy of it.
#[inline(never)]
fn largest<T: Real>(v: T::V3) -> T {
    let [a, b, c] = T::xyz(v);
    a.abs().max(b.abs()).max(c.abs())
}

/// `v = (x' - x) / dt`.
pub(super) fn step_velocity<T: Real>(start: &[T::V3], end: &[T::V3], dt: T, v: &mut [T::V3]) {
    for ((v, &a), &b) in v.iter_mut().zip(start).zip(end) {
        *v = (b - a) / dt;
    }
}

pub(super) fn report<T: Real>(
    stats: SolveStats<T>,
    velocity_iterations: u32,
    bonds: &[Bond<T>],
    lambda: &[T],
) -> StepReport<T> {
    StepReport {
        iterations: stats.iterations,
        velocity_iterations,
        residual: stats.residual,
        max_tension: max_tension(bonds, lambda),
        contacts: 0,
        wall_contacts: 0,
        contact_rounds: 0,
        noise_iterations: 0,
        #[cfg(feature = "near")]
        near_formations: 0,
        #[cfg(feature = "near")]
        near_pairs: 0,
        #[cfg(feature = "near")]
        near_products: 0,
        #[cfg(feature = "near")]
        near_iterations: 0,
        factorizations: stats.factorizations,
    }
}
