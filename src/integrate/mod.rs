//! The integrators and [`step`].
//!
//! `step` is a short list of stages: check the inputs, integrate into the workspace,
//! accept the candidate state, commit it. A failure at any stage returns the error
//! with the caller's state untouched.
//!
//! One file per integrator: `integrate/overdamped.rs` (HydroSHAKE, first and second
//! order), `integrate/rattle.rs` (the paper's velocity-Verlet HydroRATTLE),
//! `integrate/stable.rs` (implicit drag, optional rotation), `integrate/springs.rs`.
//! This file holds `step`; `checks.rs` the input checks and the acceptance of a
//! candidate, `stages.rs` the stages the integrators share, `tensions.rs` the inertial
//! step's tensions solved again (reported, never integrated), `contacts.rs` the hard
//! contacts of the position projection.

#[cfg(feature = "fast-free")]
pub use fast::{FAST_MARGIN, fast_parameters, fast_storage, fast_vectors};

mod brownian;
mod checks;
mod contacts;
#[cfg(feature = "fast-free")]
mod fast;
pub mod geometry;
mod near;
#[cfg(feature = "near")]
mod near_iter;
mod overdamped;
mod pins;
#[cfg(feature = "pse")]
mod pse_noise;
mod rattle;
mod springs;
mod stable;
mod stages;
mod tensions;

use brownian::overdamped_thermal;
use overdamped::{overdamped, overdamped2};
use rattle::rattle_explicit;
use springs::springs;
use stable::rattle_stable;
use stages::*;
use tensions::{displacement_tensions, project_velocity};

use checks::{accept, check_all};
use contacts::{Projection, project_overdamped};

use crate::bonds::{Bond, BondSet, max_residual_in};
use crate::constraints::{Solver, SolverKind};
use crate::error::StepError;
use crate::forces::ExternalForce;
use crate::params::{Method, Params};
use crate::particles::{ParticleSet, State};
use crate::real::Real;
use crate::workspace::Workspace;

/// The PSE storage a step of these spheres needs with `p`
/// ([`Workspace::with_pse`](crate::Workspace::with_pse)): `Some` where the step sums
/// its box by PSE ([`Params::pse`], a box whose images interact), from the same
/// parameters the step derives; `None` where it needs none. A host sizes its arrays
/// with it before the first step (the radii do not change during a run). With the
/// iterative near field ([`Params::near`] with [`Params::matrix_free`]), whose far field
/// is PSE's grand product, it is [`Pse::storage_grand`](crate::mobility::pse::Pse::storage_grand)'s.
#[cfg(feature = "pse")]
pub fn pse_storage<T: Real>(
    p: &Params<T>,
    radius: &[T],
) -> Result<Option<crate::geometry::PseSize>, StepError> {
    let grand = p.near_on() && p.matrix_free;
    match (stages::ewald_cell(p), p.pse) {
        (Some(c), Some(tol)) => Ok(Some(crate::geometry::pse_size(c, radius, (tol, grand))?)),
        _ => Ok(None),
    }
}

/// What a successful step measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport<T> {
    /// Position-constraint iterations (sweeps or Newton steps) of the final solve.
    pub iterations: u32,
    /// Velocity-constraint iterations (RATTLE stage; the projection of the thermal noise
    /// at the midpoint, [`Drift::Midpoint`](crate::Drift::Midpoint)), 0 where there is
    /// none.
    pub velocity_iterations: u32,
    /// Largest relative bond-length error `| |r_ij| - d | / d` after the step (springs
    /// of rest length zero have none and are skipped).
    pub residual: T,
    /// Largest bond tension magnitude `|lambda_k| d_k` (force units); for springs the
    /// largest spring force, Hookean `k | |r_ij| - d |` or FENE
    /// `k |r_ij| / (1 - |r_ij|^2 / Q0^2)`.
    pub max_tension: T,
    /// Hard-sphere contacts held at the end of the step ([`Params::contacts`]; 0
    /// without).
    pub contacts: u32,
    /// Spheres held on the wall at the end of the step ([`Params::wall`]; 0 without).
    pub wall_contacts: u32,
    /// Active-set rounds of the contact projection (constraint solves; 0 without
    /// contacts or a wall).
    pub contact_rounds: u32,
    /// Lanczos iterations of the thermal noise's square root ([`Params::noise_sqrt`]);
    /// 0 without noise or with the Cholesky factor. On the PSE path
    /// ([`Params::pse`]): the near field's Lanczos iterations plus, with bonds and the
    /// midpoint, the conjugate-gradient iterations of its solve `M^-1 L w`. With the
    /// iterative near field ([`Params::near`] with [`Params::matrix_free`]): the
    /// Lanczos iterations of the far field's root `M_far^(-1/2)` (its noise's share).
    pub noise_iterations: u32,
    /// Times the step formed the dense Stokesian dynamics mobility `M_SD`
    /// ([`Params::near`]; 0 without): each is two dense inversions of `6n x 6n` when a
    /// pair or a sphere is inside its cutoff. The first-order step forms it once, at the
    /// start; the predictor-corrector twice; a Brownian step with the midpoint twice.
    /// 0 with the iterative near field, which forms none ([`Params::matrix_free`]).
    #[cfg(feature = "near")]
    pub near_formations: u32,
    /// Close pairs the iterative near field corrected at the step's start
    /// ([`Params::near`] with [`Params::matrix_free`]; 0 otherwise).
    #[cfg(feature = "near")]
    pub near_pairs: u32,
    /// Iterative Stokesian dynamics products the step made (one a mobility: the
    /// first-order step one, the predictor-corrector two; a Brownian step three, the
    /// velocities, the noise's solve and the midpoint's; with bonds or pins also one a
    /// Krylov iteration of the constraint solve and, with rotation, one for the spins;
    /// 0 without the iterative near field). The far field's grand mobility is assembled
    /// once a configuration (a Brownian step two: the start and the midpoint; the
    /// constrained step's products share the start's).
    #[cfg(feature = "near")]
    pub near_products: u32,
    /// Conjugate-gradient iterations of those products, summed; the far field's
    /// products are these plus two a product.
    #[cfg(feature = "near")]
    pub near_iterations: u32,
    /// Dense factorisations of the constraint Jacobian in the step's position
    /// projection (its last one where there are two; every contact round): the Newton
    /// solve's cost count (0 for the sweep and Krylov).
    pub factorizations: u32,
}

// Without the near field its counters are not there: a firmware's report (and the
// zeroing and copying of it every step) stays nine words.
#[cfg(not(feature = "near"))]
const _: () = assert!(core::mem::size_of::<StepReport<f32>>() == 9 * 4);

/// Read-only view of the state at the start of a step.
pub(super) struct Start<'a, T: Real> {
    pub(super) pos: &'a [T::V3],
    pub(super) vel: &'a [T::V3],
    pub(super) omega: &'a [T::V3],
    pub(super) radius: &'a [T],
    pub(super) density: &'a [T],
    /// The step's Ewald parameters in a periodic box ([`stages::Sums`]).
    pub(super) ewald: Sums<'a, T>,
}

/// Advances the particles of a [`ParticleSet`] by one step of `p.method`: the
/// fixed-capacity front door of [`step_slices`]. A step at temperature
/// ([`Params::brownian`]) draws from the set's generator ([`ParticleSet::noise`]).
pub fn step<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    step_slices(ps.state(), bonds.as_slice(), p, ws, ext)
}

/// Advances `n` particles held in caller-owned slices by one step of `p.method`.
///
/// Stages: (1) check parameters, particles and bonds, and carve the workspace for this
/// method (a too-small workspace is [`StepError::Storage`]); (2) integrate into the
/// workspace (forces, mobility, unconstrained move, constraint solves); (3) accept the
/// candidate (finite, no nesting, no overlap unless allowed); (4) commit it into
/// `state`. On error `state` is exactly as it was.
///
/// Bonds are checked for range, self-bonds and lengths on every call; duplicates are
/// the caller's to avoid ([`BondSet`] refuses them), and make the dense Jacobian singular.
///
/// With thermal noise ([`Params::brownian`], `kT > 0`) the step draws from
/// [`State::noise`], a copy of which it writes back only when it succeeds: a refused
/// step leaves the state and the generator as they were. Without a temperature the
/// generator is not touched, and the step is the deterministic one bit for bit.
pub fn step_slices<T: Real, E: ExternalForce<T>>(
    state: State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    advance(state, bonds, p, ws, ext)
}

/// Stage 1 of [`step_slices`] alone: the checks a step makes of its inputs before it
/// touches anything (parameters, particles, bonds, thermal noise, contacts, wall), with
/// no integration. A driver asks it before it creates any output, so that an input the
/// step would refuse is refused with the same predicate up front. `state.noise` stands
/// for the generator a thermal step needs.
pub fn check_step<T: Real>(
    state: &State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
) -> Result<(), StepError> {
    check_all(state, bonds, p, state.noise.is_some()).map(|_| ())
}

/// The stages of every step; the state's generator feeds a thermal step.
fn advance<T: Real, E: ExternalForce<T>>(
    mut state: State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let n = state.len();
    let noise = state.noise.take();
    // 1. Inputs and storage.
    // `p` stays the caller's reference: a firmware's `static` must stay visible to the
    // compiler, which then links only the method it runs.
    let (thermal, sums) = check_all(&state, bonds, p, noise.is_some())?;
    // The solver, resolved once from every row the step may solve, as the storage was
    // sized ([`Params::solver_kind`]): no stage re-resolves `Auto` from the rows it
    // holds in one round. A concrete kind (firmware's) keeps `p` the caller's reference.
    let resolved;
    let p = match p.solver.kind {
        SolverKind::Auto => {
            resolved = Params {
                solver: Solver {
                    kind: p.solver_kind(n, bonds.len()),
                    ..p.solver
                },
                ..*p
            };
            &resolved
        }
        _ => p,
    };
    // 2. Integrate into the workspace (a thermal step draws from a copy of the generator).
    let mut drawn = noise.as_deref().cloned();
    let integrated = {
        #[allow(unused_mut)] // Taken from only with the `pse` feature.
        let mut v = ws.views(p, n, bonds.len())?;
        // PSE's storage, the caller's (`Workspace::with_pse`), shared by the products.
        #[cfg(feature = "pse")]
        let store = {
            let slices = core::mem::take(&mut v.pse);
            let spheres = (&*state.pos, state.radius);
            crate::geometry::fast_store(sums.as_ref(), spheres, slices, v.par)?
        };
        let s = Start {
            pos: state.pos,
            vel: state.vel,
            omega: state.omega,
            radius: state.radius,
            density: state.density,
            #[cfg(feature = "pse")]
            ewald: crate::geometry::step_sums(sums.as_ref(), store.as_ref()),
            #[cfg(all(feature = "periodic", not(feature = "pse")))]
            ewald: crate::geometry::step_sums(sums.as_ref()),
            #[cfg(not(feature = "periodic"))]
            ewald: sums.as_ref(),
        };
        // The iterative near field (`near_iter.rs`; what it serves: `near::check`).
        #[cfg(feature = "near")]
        let iterative = p.near_on() && p.matrix_free;
        match (p.method, thermal, drawn.as_mut()) {
            #[cfg(feature = "near")]
            (Method::Overdamped, Some(b), Some(g)) if iterative => {
                near_iter::overdamped_thermal(p, b, &s, bonds, v, ext, g)
            }
            #[cfg(feature = "near")]
            (Method::Overdamped, ..) if iterative && p.constraints(n, bonds.len()) > 0 => {
                near_iter::constrained::overdamped(p, &s, bonds, v, ext)
            }
            #[cfg(feature = "near")]
            (Method::Overdamped2, ..) if iterative && p.constraints(n, bonds.len()) > 0 => {
                near_iter::constrained2::overdamped2(p, &s, bonds, v, ext)
            }
            #[cfg(feature = "near")]
            (Method::Overdamped | Method::Overdamped2, ..) if iterative => {
                near_iter::overdamped(p, &s, v, ext)
            }
            (Method::Overdamped, Some(b), Some(g)) => {
                overdamped_thermal(p, b, &s, bonds, v, ext, g)
            }
            (Method::Overdamped, ..) => overdamped(p, &s, bonds, v, ext),
            (Method::Overdamped2, ..) => overdamped2(p, &s, bonds, v, ext),
            (Method::Rattle, ..) => rattle_explicit(p, &s, bonds, v, ext),
            (Method::RattleStable, Some(b), Some(g)) => {
                rattle_stable(p, &s, bonds, v, ext, Some((b, g)))
            }
            (Method::RattleStable, ..) => rattle_stable(p, &s, bonds, v, ext, None),
            (Method::Springs, Some(b), Some(g)) => springs(p, &s, bonds, v, ext, Some((b, g))),
            (Method::Springs, ..) => springs(p, &s, bonds, v, ext, None),
        }
    };
    // Pinned coordinates back on their anchors (`pins.rs`).
    #[cfg(feature = "pins")]
    if integrated.is_ok() {
        let (pos, rest) = ws.vectors.split_at_mut(n);
        pins::restore(bonds, state.pos, pos, &mut rest[..n]);
    }
    // 3. Accept. The candidate state heads the vector storage (see `Workspace::views`).
    // Every index of the workspace is free by now: the pair check's cell list.
    let (par, cells) = (ws.parallel, &mut *ws.indices);
    let (new_pos, rest) = ws.vectors.split_at(n);
    let (new_vel, rest) = rest.split_at(n);
    let new_omega = &rest[..n];
    let mut report = integrated
        .and_then(|r| accept(new_pos, new_vel, new_omega, state.radius, p, par, cells).map(|()| r))
        .inspect_err(|e| log::debug!("step at t = {} refused, state kept: {e}", *state.time))?;
    log::trace!(
        "t = {}: {} position / {} velocity iterations",
        *state.time,
        report.iterations,
        report.velocity_iterations
    );
    // The first-order overdamped step without contacts or noise ends on the position
    // solve's last iterate, whose residual over the bonds the solve has just measured.
    let solved = p.method == Method::Overdamped
        && thermal.is_none()
        && p.contacts.is_none()
        && p.place().surfaces().is_empty();
    if !solved {
        report.residual = max_residual_in(bonds, new_pos, cell(p).as_ref()).1;
    }
    // 4. Commit (the generator too, if it was drawn from).
    state.pos.copy_from_slice(new_pos);
    state.vel.copy_from_slice(new_vel);
    state.omega.copy_from_slice(new_omega);
    *state.time += p.dt;
    if let (Some(g), Some(d)) = (noise, drawn)
        && thermal.is_some()
    {
        *g = d;
    }
    Ok(report)
}
