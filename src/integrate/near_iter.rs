//! Stokesian dynamics' near field in a step by iterative products ([`Params::near`]
//! with [`Params::matrix_free`]): `M_SD` is never formed. Each mobility the method
//! needs is one product `(U, W) = M_SD (F, 0)` of [`crate::stokesian::iterative`]
//! (Woodbury's identity, conjugate gradients over the close pairs), whose far field is
//! the grand mobility (`tri(2n)` blocks) assembled once at that configuration and
//! applied about twenty times: one assembly (each pair's four blocks in one
//! pass of the Ewald sums, 1.6 to 1.9 times the RPY step's `mu_tt` assembly) with cheap
//! products costs less than twenty matrix-free Ewald products (`docs/NEAR.md`). With
//! [`Params::pse`] the far field is instead a fast product's grand product, matrix-free
//! (free space's fast product, or PSE's in a box), and no `tri(2n)` blocks are stored
//! (`near_iter/solve.rs`, where the far field is chosen).
//!
//! Served: `Overdamped` (one product, at the start) and `Overdamped2` (two, at the
//! start and at the predicted point), and `Overdamped` with thermal noise
//! (`near_iter/noise.rs`: three products and a Lanczos root of the far field), in free
//! space or in the periodic box with the Ewald sums; `Overdamped` with bonds, pins and
//! hard contacts by the Krylov solve along `M_SD`: `near_iter/constrained.rs`, and so
//! above the wall, whose links are one-sided constraints (the far field the wall's
//! grand mobility, each sphere near it one more entry of the product's near field,
//! `stokesian::iterative`); `Overdamped2` with them (`near_iter/constrained2.rs`), and
//! thermal `Overdamped` with them (`near_iter/noise.rs`). The rest is refused by
//! [`super::near::check`]. The conjugate gradients stop at the
//! relative residual
//! [`Solver::tolerance`](crate::Solver::tolerance) within its `max_iterations`
//! (`Params::solver`, the step's one tolerance for its iterations); not converging is
//! [`StepError::NoConvergence`] at [`Stage::Mobility`], the caller's state unchanged.
//! The storage is the caller's ([`crate::Layout::for_params`]:
//! `near_iterative_sizes`), with room for
//! [`NEAR_PAIRS_PER_SPHERE`](crate::NEAR_PAIRS_PER_SPHERE) close pairs a sphere.

pub(super) mod constrained;
pub(super) mod constrained2;

use super::{Start, StepReport, Sums, add_flow, check_resolved, step_velocity};
use crate::error::{Stage, StepError};
use crate::forces::{self, ExternalForce};
use crate::params::{Method, Params};
use crate::real::Real;
use crate::stokesian::SdError;
use crate::workspace::Views;

mod noise;
mod solve;

pub(super) use noise::overdamped_thermal;

/// The iterative near field's storage ([`Views::near`] and `Views::near_iter`).
struct Store<'a, T: Real> {
    /// The far field's packed grand mobility (empty where the far field is a product).
    packed: &'a mut [T::M3],
    /// The close pairs' factors, preconditioner blocks and Krylov vectors.
    reals: &'a mut [T],
    /// The product's `2n` forces and torques, `2n` velocities and spins, and its own
    /// `6n` vectors.
    vectors: &'a mut [T::V3],
    /// The close pairs (two indices each) and the cell list.
    indices: &'a mut [usize],
}

impl<'a, T: Real> Store<'a, T> {
    fn new(v: (&'a mut [T::M3], &'a mut [T]), w: (&'a mut [T::V3], &'a mut [usize])) -> Self {
        Self {
            packed: v.0,
            reals: v.1,
            vectors: w.0,
            indices: w.1,
        }
    }
}

/// What the step's products did ([`StepReport`]'s near-field counts).
#[derive(Default)]
struct Counts {
    pairs: u32,
    products: u32,
    iterations: u32,
}

/// The step's error for the iterative product's.
fn error(e: SdError) -> StepError {
    match e {
        SdError::NotConverged {
            iterations,
            residual,
        } => StepError::NoConvergence {
            stage: Stage::Mobility,
            iterations,
            residual,
        },
        SdError::Storage => StepError::Unsupported(
            "the iterative near field with more close pairs than its storage holds (NEAR_PAIRS_PER_SPHERE a sphere)",
        ),
        e => super::near::sd_error(e),
    }
}

/// `u = M_SD,tt(pos) f` and, where `w` is given, `w = M_SD,rt(pos) f`: one iterative
/// product of torque-free spheres, the far field assembled at `pos` first.
#[allow(clippy::too_many_arguments)]
fn velocities<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    spheres: (&[T::V3], &[T]),
    f: &[T::V3],
    u: &mut [T::V3],
    w: Option<&mut [T::V3]>,
    store: &mut Store<'_, T>,
    counts: &mut Counts,
) -> Result<(), StepError> {
    solve::at(p, ew, spheres, store, |at| {
        at.velocities(p, f, u, w, counts)
    })
}

const STORAGE: StepError = StepError::Unsupported("the iterative near field without its storage");

/// Blocks of the packed grand mobility of `n` spheres.
const fn tri2(n: usize) -> usize {
    crate::linalg::tri(2 * n)
}

/// The spins `Omega_inf + M_SD,rt F` from the product's `M_SD,rt F` in `w` (with
/// [`Params::rotation`]; `Omega_inf` alone otherwise).
fn spins<T: Real>(p: &Params<T>, w: &mut [T::V3]) {
    for w in w.iter_mut() {
        *w = match p.rotation {
            true => p.vorticity + *w,
            false => p.vorticity,
        };
    }
}

fn report<T: Real>(c: Counts) -> StepReport<T> {
    StepReport {
        near_pairs: c.pairs,
        near_products: c.products,
        near_iterations: c.iterations,
        ..StepReport::default()
    }
}

/// `Overdamped` with the iterative near field, `r' = r + dt U(r)`, or `Overdamped2`,
/// Heun's predictor-corrector `r' = r + dt/2 (U(r) + U(r + dt U(r)))`, where
/// `U = U_inf + M_SD,tt F`; the spins `Omega_inf + M_SD,rt F` at the start (as the
/// dense step reports them).
pub(super) fn overdamped<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let Views {
        force,
        work_a: u0,
        work_b: u1,
        work_c: x_p,
        new_pos,
        new_vel,
        new_omega,
        near,
        near_iter,
        ..
    } = v;
    let mut store = Store::new(near, near_iter);
    let mut counts = Counts::default();
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    let w = Some(&mut *new_omega);
    let at_start = (s.pos, s.radius);
    velocities(p, s.ewald, at_start, force, u0, w, &mut store, &mut counts)?;
    add_flow(p, s.pos, u0);
    check_resolved(s.pos, u0, dt)?;
    spins(p, new_omega);
    if p.method == Method::Overdamped2 {
        // The predictor's point, its velocities, and the trapezoid into `u0`.
        for i in 0..n {
            x_p[i] = s.pos[i] + u0[i] * dt;
        }
        forces::external(p, x_p, s.radius, s.density, ext, force)?;
        let predicted = (&*x_p, s.radius);
        velocities(
            p,
            s.ewald,
            predicted,
            force,
            u1,
            None,
            &mut store,
            &mut counts,
        )?;
        add_flow(p, x_p, u1);
        for (a, &b) in u0.iter_mut().zip(&*u1) {
            *a = (*a + b) * T::HALF;
        }
    }
    for i in 0..n {
        new_pos[i] = s.pos[i] + u0[i] * dt;
    }
    step_velocity(s.pos, new_pos, dt, new_vel);
    Ok(report(counts))
}
