//! The integrators and [`step`].
//!
//! `step` is a short list of stages: check the inputs, integrate into the workspace,
//! accept the candidate state, commit it. A failure at any stage returns the error
//! with the caller's state untouched.
//!
//! One file per integrator: `integrate/overdamped.rs` (HydroSHAKE, first and second
//! order), `integrate/rattle.rs` (the paper's velocity-Verlet HydroRATTLE),
//! `integrate/stable.rs` (implicit drag, optional rotation), `integrate/springs.rs`.
//! This file holds `step` and the stages they share.

mod brownian;
mod contacts;
mod overdamped;
mod rattle;
mod springs;
mod stable;

use brownian::overdamped_thermal;
use overdamped::{overdamped, overdamped2};
use rattle::rattle_explicit;
use springs::springs;
use stable::rattle_stable;

use crate::bonds::{Bond, BondSet, max_residual};
use crate::constraints::{self, Metric, Problem, Scratch, SolveStats, Solver, SolverKind};
use crate::error::{ParticleError, StepError};
use crate::forces::ExternalForce;
use crate::linalg;
use crate::mobility::{self, Hydro};
use crate::noise::Noise;
use crate::params::{Method, Params};
use crate::particles::{ParticleSet, State, sphere_volume};
use crate::real::Real;
use crate::workspace::Workspace;

/// What a successful step measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport<T> {
    /// Position-constraint iterations (sweeps or Newton steps) of the final solve.
    pub iterations: u32,
    /// Velocity-constraint iterations (RATTLE stage), 0 where there is none.
    pub velocity_iterations: u32,
    /// Largest relative bond-length error `| |r_ij| - d | / d` after the step.
    pub residual: T,
    /// Largest bond tension magnitude `|lambda_k| d_k` (force units); for springs
    /// `k | |r_ij| - d |`.
    pub max_tension: T,
    /// Hard-sphere contacts held at the end of the step ([`Params::contacts`]; 0
    /// without).
    pub contacts: u32,
    /// Active-set rounds of the contact projection (constraint solves; 0 without
    /// contacts).
    pub contact_rounds: u32,
}

/// Read-only view of the state at the start of a step.
pub(super) struct Start<'a, T: Real> {
    pub(super) pos: &'a [T::V3],
    pub(super) vel: &'a [T::V3],
    pub(super) omega: &'a [T::V3],
    pub(super) radius: &'a [T],
    pub(super) density: &'a [T],
}

/// Advances the particles of a [`ParticleSet`] by one step of `p.method`: the
/// fixed-capacity front door of [`step_slices`].
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
pub fn step_slices<T: Real, E: ExternalForce<T>>(
    state: State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    advance(state, bonds, p, ws, ext, None)
}

/// [`step`] with thermal noise ([`Params::brownian`]) drawn from the caller's generator.
pub fn step_thermal<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
    noise: &mut Noise,
) -> Result<StepReport<T>, StepError> {
    advance(ps.state(), bonds.as_slice(), p, ws, ext, Some(noise))
}

/// [`step_slices`] with thermal noise ([`Params::brownian`]) drawn from the caller's
/// generator. The step draws from a copy of `noise` and stores the copy only when it
/// succeeds: a refused step leaves the state and the generator as they were. With no
/// [`Params::brownian`], or a zero temperature, this is [`step_slices`] bit for bit and
/// draws nothing.
pub fn step_slices_thermal<T: Real, E: ExternalForce<T>>(
    state: State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
    noise: &mut Noise,
) -> Result<StepReport<T>, StepError> {
    advance(state, bonds, p, ws, ext, Some(noise))
}

/// The stages of every step; `noise` is the generator of a thermal step.
fn advance<T: Real, E: ExternalForce<T>>(
    state: State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
    noise: Option<&mut Noise>,
) -> Result<StepReport<T>, StepError> {
    let n = state.len();
    // 1. Inputs and storage.
    check_inputs(&state, bonds, p)?;
    let thermal = check_thermal(p, noise.is_some())?;
    let resolved = check_contacts(p, bonds.len(), thermal.is_some())?;
    let p = &resolved;
    let s = Start {
        pos: state.pos,
        vel: state.vel,
        omega: state.omega,
        radius: state.radius,
        density: state.density,
    };
    // 2. Integrate into the workspace (a thermal step draws from a copy of the generator).
    let mut drawn = noise.as_deref().cloned();
    let integrated = {
        let v = ws.views(p, n, bonds.len())?;
        match (p.method, thermal, drawn.as_mut()) {
            (Method::Overdamped, Some(b), Some(g)) => {
                overdamped_thermal(p, b, &s, bonds, v, ext, g)
            }
            (Method::Overdamped, ..) => overdamped(p, &s, bonds, v, ext),
            (Method::Overdamped2, ..) => overdamped2(p, &s, bonds, v, ext),
            (Method::Rattle, ..) => rattle_explicit(p, &s, bonds, v, ext),
            (Method::RattleStable, ..) => rattle_stable(p, &s, bonds, v, ext),
            (Method::Springs, ..) => springs(p, &s, bonds, v, ext),
        }
    };
    // 3. Accept. The candidate state heads the vector storage (see `Workspace::views`).
    let (new_pos, rest) = ws.vectors.split_at(n);
    let (new_vel, rest) = rest.split_at(n);
    let new_omega = &rest[..n];
    let mut report = integrated
        .and_then(|r| accept(new_pos, new_vel, new_omega, s.radius, p).map(|()| r))
        .inspect_err(|e| log::debug!("step at t = {} refused, state kept: {e}", *state.time))?;
    log::trace!(
        "t = {}: {} position / {} velocity iterations",
        *state.time,
        report.iterations,
        report.velocity_iterations
    );
    report.residual = max_residual(bonds, new_pos).1;
    // 4. Commit (the generator too, if it was drawn from).
    state.pos.copy_from_slice(new_pos);
    state.vel.copy_from_slice(new_vel);
    state.omega.copy_from_slice(new_omega);
    *state.time += p.dt;
    if let (Some(g), Some(d)) = (noise, drawn) {
        if thermal.is_some() {
            *g = d;
        }
    }
    Ok(report)
}

/// The thermal settings when this step has noise (`brownian` with `kT > 0`), after
/// checking that the temperature is valid and the combination is implemented.
fn check_thermal<T: Real>(
    p: &Params<T>,
    has_generator: bool,
) -> Result<Option<crate::params::Brownian<T>>, StepError> {
    let Some(b) = p.brownian else {
        return Ok(None);
    };
    if !(b.temperature >= T::ZERO && b.temperature.is_finite()) {
        return Err(StepError::BadParameter(
            "brownian.temperature (finite, >= 0)",
        ));
    }
    if b.temperature == T::ZERO {
        return Ok(None);
    }
    if p.method != Method::Overdamped {
        return Err(StepError::Unsupported(
            "thermal noise with a method other than Overdamped",
        ));
    }
    if p.matrix_free {
        return Err(StepError::Unsupported(
            "thermal noise without a stored mobility (matrix_free: no Lanczos square root)",
        ));
    }
    if !has_generator {
        return Err(StepError::Unsupported(
            "thermal noise without a generator (call step_thermal / step_slices_thermal)",
        ));
    }
    Ok(Some(b))
}

/// The parameters a step runs with: as given, or with contacts the solver resolved for
/// the bonds plus the contact capacity (so that the storage and the solver agree however
/// many contacts a step holds). Refuses contacts where they are not implemented.
fn check_contacts<T: Real>(
    p: &Params<T>,
    bonds: usize,
    thermal: bool,
) -> Result<Params<T>, StepError> {
    let Some(c) = p.contacts else {
        return Ok(*p);
    };
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "contacts with a method other than Overdamped or Overdamped2",
        ));
    }
    if thermal {
        return Err(StepError::Unsupported("contacts with thermal noise"));
    }
    if c.max_rounds == 0 {
        return Err(StepError::BadParameter("contacts.max_rounds (> 0)"));
    }
    let mut q = *p;
    q.solver.kind = p.solver.kind.resolve(p.constraints(bonds));
    Ok(q)
}

/// Cheap checks (O(N + B)); pair checks happen in assembly and in [`accept`].
fn check_inputs<T: Real>(
    state: &State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
) -> Result<(), StepError> {
    let n = state.len();
    let lengths = [
        state.vel.len(),
        state.omega.len(),
        state.radius.len(),
        state.density.len(),
    ];
    if lengths.iter().any(|&l| l != n) {
        return Err(StepError::StateLength);
    }
    if !(p.dt > T::ZERO && p.dt.is_finite()) {
        return Err(StepError::BadTimeStep);
    }
    let bad = |ok: bool, name| {
        if ok {
            Ok(())
        } else {
            Err(StepError::BadParameter(name))
        }
    };
    bad(
        p.viscosity > T::ZERO && p.viscosity.is_finite(),
        "viscosity",
    )?;
    bad(p.fluid_density.is_finite(), "fluid_density")?;
    bad(T::v3_is_finite(p.gravity), "gravity")?;
    bad(T::v3_is_finite(p.flow_velocity), "flow_velocity")?;
    bad(T::v3_is_finite(p.vorticity), "vorticity")?;
    bad(
        p.solver.tolerance >= Solver::min_tolerance() && p.solver.tolerance.is_finite(),
        "tolerance (at least 16 machine epsilons, finite)",
    )?;
    // Time must stay finite and advance (a huge time would swallow dt).
    bad(
        state.time.is_finite()
            && *state.time + p.dt > *state.time
            && (*state.time + p.dt).is_finite(),
        "time (finite, and advanced by dt)",
    )?;
    bad(p.solver.max_iterations > 0, "max_iterations")?;
    bad(
        !p.matrix_free || matches!(p.method, Method::Overdamped | Method::Springs),
        "matrix_free (Overdamped and Springs only)",
    )?;
    if p.method == Method::Springs {
        bad(
            p.spring_stiffness > T::ZERO && p.spring_stiffness.is_finite(),
            "spring_stiffness",
        )?;
    }
    let inertial = matches!(p.method, Method::Rattle | Method::RattleStable);
    for i in 0..n {
        let finite = T::v3_is_finite(state.pos[i])
            && T::v3_is_finite(state.vel[i])
            && T::v3_is_finite(state.omega[i])
            && state.radius[i].is_finite()
            && state.density[i].is_finite();
        if !finite {
            return Err(ParticleError::NonFinite { particle: i }.into());
        }
        if state.radius[i] <= T::ZERO {
            return Err(ParticleError::BadRadius { particle: i }.into());
        }
        if state.density[i] < T::ZERO {
            return Err(ParticleError::BadDensity { particle: i }.into());
        }
        if inertial && sphere_volume(state.radius[i]) * state.density[i] <= T::ZERO {
            return Err(ParticleError::Massless { particle: i }.into());
        }
    }
    for (bond, b) in bonds.iter().enumerate() {
        crate::bonds::check_one(bond, b, n)?;
    }
    Ok(())
}

/// Finite, no nested spheres, no overlap unless allowed (squared distances: no sqrt).
/// With contacts, spheres touch to within the solver's tolerance, which is accepted.
fn accept<T: Real>(
    pos: &[T::V3],
    vel: &[T::V3],
    omega: &[T::V3],
    radius: &[T],
    p: &Params<T>,
) -> Result<(), StepError> {
    let allow_overlap = p.allow_overlap;
    let reach = match p.contacts {
        Some(_) => T::ONE - p.solver.tolerance * T::TWO,
        None => T::ONE,
    };
    for i in 0..pos.len() {
        if !(T::v3_is_finite(pos[i]) && T::v3_is_finite(vel[i]) && T::v3_is_finite(omega[i])) {
            return Err(StepError::NonFinite { particle: i });
        }
    }
    for i in 0..pos.len() {
        for j in i + 1..pos.len() {
            let s2 = T::norm2(pos[i] - pos[j]);
            let (dif, sum) = (radius[i] - radius[j], (radius[i] + radius[j]) * reach);
            if s2 <= dif * dif || (!allow_overlap && s2 < sum * sum) {
                return Err(StepError::Overlap { i, j });
            }
        }
    }
    Ok(())
}

/// `u = mu_tt(pos) f`: from the assembled mobility in `mu`, or matrix-free (then `mu`
/// is empty and nothing is stored).
pub(super) fn mobility_product<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    mu: &mut [T::M3],
    f: &[T::V3],
    u: &mut [T::V3],
) -> Result<(), StepError> {
    if p.matrix_free {
        return mobility::tt_product(p.hydro, p.viscosity, pos, radius, f, u)
            .map_err(StepError::from);
    }
    assemble_tt(p, pos, radius, mu)?;
    linalg::sym_matvec::<T>(mu, pos.len(), f, u);
    Ok(())
}

/// The hydrodynamic constraint metric `D_l = scale mu G^T e_l`: matrix-free when asked;
/// read from the packed mobility where it is used for Krylov (one product per
/// iteration, no table); tabulated once into `disp` (`n x B`) for the dense solvers,
/// which read every `D_l(p)` at every iteration.
#[allow(clippy::too_many_arguments)]
pub(super) fn mobility_metric<'a, T: Real>(
    p: &Params<T>,
    bonds: &[Bond<T>],
    pos: &'a [T::V3],
    radius: &'a [T],
    mu: &'a [T::M3],
    grad: &'a [T::V3],
    scale: T,
    disp: &'a mut [T::V3],
) -> Metric<'a, T> {
    if p.matrix_free {
        return Metric::Free {
            level: p.hydro,
            eta: p.viscosity,
            pos,
            radius,
            grad,
            scale,
        };
    }
    if p.solver.kind.resolve(bonds.len()) == SolverKind::Krylov {
        return Metric::Mobility { mu, grad, scale };
    }
    let n = pos.len();
    constraints::tabulate(mu, bonds, grad, scale, n, disp);
    Metric::Dense { disp, n, grad }
}

pub(super) fn assemble_tt<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    mu: &mut [T::M3],
) -> Result<(), StepError> {
    mobility::assemble_tt(p.hydro, p.viscosity, pos, radius, mu).map_err(StepError::from)
}

/// `g_l = r_i - r_j` for every bond.
pub(super) fn bond_vectors<T: Real>(bonds: &[Bond<T>], pos: &[T::V3], out: &mut [T::V3]) {
    for (g, b) in out.iter_mut().zip(bonds) {
        *g = pos[b.i] - pos[b.j];
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
        f[b.j] -= grad[l] * lambda[l];
    }
}

/// Angular velocities of torque-free spheres: `W_i = Omega_inf + sum_j rt_ij f_j`, with
/// `f` the force each sphere exerts on the fluid; `Omega_inf` alone when not resolved.
pub(super) fn spin<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    out: &mut [T::V3],
) -> Result<(), StepError> {
    out.fill(p.vorticity);
    if !p.rotation || p.hydro == Hydro::FreeDraining {
        return Ok(());
    }
    for i in 0..pos.len() {
        for j in 0..i {
            let b =
                mobility::pair_blocks(p.hydro, p.viscosity, radius[i], radius[j], pos[i] - pos[j])
                    .ok_or(StepError::Particle(ParticleError::Nested { i: j, j: i }))?;
            out[i] += b.rt_ij * f[j];
            out[j] += b.rt_ji * f[i];
        }
    }
    Ok(())
}

/// Projects `x` onto the bonds along `metric`; the multipliers start from zero and end
/// in `lambda`.
pub(super) fn project_positions<T: Real>(
    p: &Params<T>,
    bonds: &[Bond<T>],
    metric: &Metric<'_, T>,
    x: &mut [T::V3],
    lambda: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    lambda.fill(T::ZERO);
    constraints::solve(
        Problem::Positions,
        metric,
        bonds,
        &p.solver,
        x,
        lambda,
        scratch,
    )
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
        contact_rounds: 0,
    }
}

/// The slices the overdamped position projection works in.
pub(super) struct Projection<'l, 'v, 'a, T: Real> {
    pub links: &'l mut [Bond<T>],
    pub grad: &'v mut [T::V3],
    pub disp: &'v mut [T::V3],
    pub lambda: &'v mut [T],
    pub scratch: &'v mut Scratch<'a, T>,
}

/// What the overdamped position projection did.
pub(super) struct Projected<'l, T: Real> {
    /// The solve (of the last active-set round with contacts).
    pub stats: SolveStats<T>,
    /// The constraints held: the bonds, then the contacts (rows of `grad`, `lambda`).
    pub held: &'l [Bond<T>],
    /// Contacts held (0 without contacts).
    pub contacts: u32,
    /// Active-set rounds (0 without contacts).
    pub rounds: u32,
}

/// The overdamped position projection along the mobility at `start` (`mu`, scaled by
/// `dt`): `free` writes the unconstrained move into `x`, which is then projected onto
/// the bonds, or onto the bonds and the hard-sphere contacts when [`Params::contacts`]
/// is on.
#[allow(clippy::too_many_arguments)]
pub(super) fn project_overdamped<'l, T: Real>(
    p: &Params<T>,
    bonds: &'l [Bond<T>],
    start: &[T::V3],
    radius: &[T],
    mu: &[T::M3],
    v: Projection<'l, '_, '_, T>,
    x: &mut [T::V3],
    free: impl Fn(&mut [T::V3]),
) -> Result<Projected<'l, T>, StepError> {
    let Some(c) = p.contacts else {
        bond_vectors(bonds, start, v.grad);
        let metric = mobility_metric(p, bonds, start, radius, mu, v.grad, p.dt, v.disp);
        free(x);
        let stats = project_positions(p, bonds, &metric, x, v.lambda, v.scratch)?;
        return Ok(Projected {
            stats,
            held: bonds,
            contacts: 0,
            rounds: 0,
        });
    };
    contacts::project_with_contacts(p, c, bonds, start, radius, mu, p.dt, v, x, free)
}
