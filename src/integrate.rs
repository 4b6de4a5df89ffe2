//! The integrators and [`step`].
//!
//! `step` is a short list of stages: check the inputs, integrate into the workspace,
//! accept the candidate state, commit it. A failure at any stage returns the error
//! with the caller's state untouched.

use crate::bonds::{Bond, BondSet, max_residual};
use crate::constraints::{self, Metric, Problem, Scratch, SolveStats};
use crate::error::{ParticleError, Stage, StepError};
use crate::forces::{self, ExternalForce};
use crate::linalg;
use crate::mobility::{self, Hydro};
use crate::params::{Method, Params};
use crate::particles::{ParticleSet, sphere_volume};
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
}

/// Read-only view of the state at the start of a step.
struct Start<'a, T: Real> {
    pos: &'a [T::V3],
    vel: &'a [T::V3],
    omega: &'a [T::V3],
    radius: &'a [T],
    density: &'a [T],
}

/// Advances the particles by one step of `p.method`.
///
/// Stages: (1) check parameters, particles and bonds; (2) integrate into `ws` (forces,
/// mobility, unconstrained move, constraint solves); (3) accept the candidate (finite,
/// no nesting, no overlap unless allowed); (4) commit it into `ps`. On error `ps` is
/// exactly as it was.
pub fn step<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ws: &mut Workspace<T, N, B>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let n = ps.len();
    let bonds = bonds.as_slice();
    // 1. Inputs.
    check_inputs(ps, bonds, p)?;
    // 2. Integrate into the workspace.
    let s = Start {
        pos: &ps.pos[..n],
        vel: &ps.vel[..n],
        omega: &ps.omega[..n],
        radius: &ps.radius[..n],
        density: &ps.density[..n],
    };
    let integrated = match p.method {
        Method::Overdamped => overdamped(p, &s, bonds, ws, ext),
        Method::Overdamped2 => overdamped2(p, &s, bonds, ws, ext),
        Method::Rattle => rattle_explicit(p, &s, bonds, ws, ext),
        Method::RattleStable => rattle_stable(p, &s, bonds, ws, ext),
        Method::Springs => springs(p, &s, bonds, ws, ext),
    };
    // 3. Accept.
    let (new_pos, new_vel, new_omega) = (&ws.new_pos[..n], &ws.new_vel[..n], &ws.new_omega[..n]);
    let mut report = integrated
        .and_then(|r| accept(new_pos, new_vel, new_omega, s.radius, p.allow_overlap).map(|()| r))
        .inspect_err(|e| log::debug!("step at t = {} refused, state kept: {e}", ps.time))?;
    log::trace!(
        "t = {}: {} position / {} velocity iterations",
        ps.time,
        report.iterations,
        report.velocity_iterations
    );
    report.residual = max_residual(bonds, new_pos).1;
    // 4. Commit.
    ps.pos[..n].copy_from_slice(new_pos);
    ps.vel[..n].copy_from_slice(new_vel);
    ps.omega[..n].copy_from_slice(new_omega);
    ps.time += p.dt;
    Ok(report)
}

/// Cheap checks (O(N + B)); pair checks happen in assembly and in [`accept`].
fn check_inputs<T: Real, const N: usize>(
    ps: &ParticleSet<T, N>,
    bonds: &[Bond<T>],
    p: &Params<T>,
) -> Result<(), StepError> {
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
        p.solver.tolerance > T::ZERO && p.solver.tolerance.is_finite(),
        "tolerance",
    )?;
    bad(p.solver.max_iterations > 0, "max_iterations")?;
    if p.method == Method::Springs {
        bad(
            p.spring_stiffness > T::ZERO && p.spring_stiffness.is_finite(),
            "spring_stiffness",
        )?;
    }
    let n = ps.len();
    for i in 0..n {
        let finite = T::v3_is_finite(ps.pos[i])
            && T::v3_is_finite(ps.vel[i])
            && T::v3_is_finite(ps.omega[i])
            && ps.radius[i].is_finite()
            && ps.density[i].is_finite();
        if !finite {
            return Err(ParticleError::NonFinite { particle: i }.into());
        }
        if ps.radius[i] <= T::ZERO {
            return Err(ParticleError::BadRadius { particle: i }.into());
        }
        if ps.density[i] < T::ZERO {
            return Err(ParticleError::BadDensity { particle: i }.into());
        }
        let inertial = matches!(p.method, Method::Rattle | Method::RattleStable);
        if inertial && ps.mass(i) <= T::ZERO {
            return Err(ParticleError::Massless { particle: i }.into());
        }
    }
    // Bonds were validated on insertion; only the particle count can disagree.
    for (bond, b) in bonds.iter().enumerate() {
        if b.i.max(b.j) >= n {
            let particle = b.i.max(b.j);
            return Err(crate::error::BondError::OutOfRange { bond, particle }.into());
        }
    }
    Ok(())
}

/// Finite, no nested spheres, no overlap unless allowed (squared distances: no sqrt).
fn accept<T: Real>(
    pos: &[T::V3],
    vel: &[T::V3],
    omega: &[T::V3],
    radius: &[T],
    allow_overlap: bool,
) -> Result<(), StepError> {
    for i in 0..pos.len() {
        if !(T::v3_is_finite(pos[i]) && T::v3_is_finite(vel[i]) && T::v3_is_finite(omega[i])) {
            return Err(StepError::NonFinite { particle: i });
        }
    }
    for i in 0..pos.len() {
        for j in i + 1..pos.len() {
            let s2 = T::norm2(pos[i] - pos[j]);
            let (dif, sum) = (radius[i] - radius[j], radius[i] + radius[j]);
            if s2 <= dif * dif || (!allow_overlap && s2 < sum * sum) {
                return Err(StepError::Overlap { i, j });
            }
        }
    }
    Ok(())
}

/// Packed `n x n` (or `2n x 2n`) block storage.
fn blocks<T: Real, const N: usize>(m: &mut [[[T::M3; N]; N]; 4], nb: usize) -> &mut [T::M3] {
    &mut m.as_flattened_mut().as_flattened_mut()[..nb * nb]
}

/// Generalised vector of `len` blocks.
fn gvec<T: Real, const N: usize>(v: &mut [[T::V3; N]; 2], len: usize) -> &mut [T::V3] {
    &mut v.as_flattened_mut()[..len]
}

fn assemble_tt<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    mu: &mut [T::M3],
) -> Result<(), StepError> {
    mobility::assemble_tt(p.hydro, p.viscosity, pos, radius, mu).map_err(StepError::from)
}

/// `g_l = r_i - r_j` for every bond.
fn bond_vectors<T: Real>(bonds: &[Bond<T>], pos: &[T::V3], out: &mut [T::V3]) {
    for (g, b) in out.iter_mut().zip(bonds) {
        *g = pos[b.i] - pos[b.j];
    }
}

/// Hydrodynamic metric `D_l(p) = scale (mu_pi - mu_pj) g_l`, bond-major with stride `n`.
///
/// `mu_tt` is symmetric with symmetric blocks, so `mu_pi = mu_ip`: rows `i` and `j` are
/// read contiguously instead of two strided columns.
fn mobility_disp<T: Real>(
    mu: &[T::M3],
    n: usize,
    bonds: &[Bond<T>],
    grad: &[T::V3],
    scale: T,
    disp: &mut [T::V3],
) {
    for (l, b) in bonds.iter().enumerate() {
        let g = grad[l] * scale;
        let (row_i, row_j) = (&mu[b.i * n..b.i * n + n], &mu[b.j * n..b.j * n + n]);
        for ((d, &mi), &mj) in disp[l * n..l * n + n].iter_mut().zip(row_i).zip(row_j) {
            *d = mi * g - mj * g;
        }
    }
}

/// `u_i += U_inf(r_i)`.
fn add_flow<T: Real>(p: &Params<T>, pos: &[T::V3], u: &mut [T::V3]) {
    for (ui, &r) in u.iter_mut().zip(pos) {
        *ui += p.flow_at(r);
    }
}

/// Largest `|lambda_k| d_k`.
fn max_tension<T: Real>(bonds: &[Bond<T>], lambda: &[T]) -> T {
    bonds
        .iter()
        .zip(lambda)
        .fold(T::ZERO, |m, (b, &l)| m.max((l * b.length).abs()))
}

/// `f_i += sum_l lambda_l (+-g_l)`: the constraint forces.
fn add_constraint_forces<T: Real>(
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
fn spin<T: Real>(
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

/// Overdamped HydroSHAKE, first order.
fn overdamped<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    ws: &mut Workspace<T, N, B>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, nb, dt) = (s.pos.len(), bonds.len(), p.dt);
    let mu = blocks::<T, N>(&mut ws.mu, n);
    let force = gvec::<T, N>(&mut ws.force, n);
    let u = gvec::<T, N>(&mut ws.work_a, n);
    let new_pos = &mut ws.new_pos[..n];
    let (grad, disp, lambda) = (
        &mut ws.grad[..nb],
        &mut ws.disp.as_flattened_mut()[..nb * n],
        &mut ws.lambda[..nb],
    );
    // Mobility and forces at the start; unconstrained move r* = r + dt (U_inf + mu F).
    assemble_tt(p, s.pos, s.radius, mu)?;
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    linalg::sym_matvec::<T>(mu, n, force, u);
    add_flow(p, s.pos, u);
    for i in 0..n {
        new_pos[i] = s.pos[i] + u[i] * dt;
    }
    // Constraint move through the full mobility: r' = r* + dt mu G^T lambda.
    bond_vectors(bonds, s.pos, grad);
    mobility_disp(mu, n, bonds, grad, dt, disp);
    lambda.fill(T::ZERO);
    let stats = constraints::solve(
        Problem::Positions,
        &Metric::Dense { disp, n },
        bonds,
        &p.solver,
        new_pos,
        lambda,
        &mut Scratch {
            jac: ws.jac.as_flattened_mut(),
            rhs: &mut ws.rhs,
            piv: &mut ws.piv,
        },
    )?;
    for i in 0..n {
        ws.new_vel[i] = (new_pos[i] - s.pos[i]) / dt;
    }
    add_constraint_forces(bonds, grad, lambda, force);
    spin(p, s.pos, s.radius, force, &mut ws.new_omega[..n])?;
    Ok(report(stats, 0, bonds, lambda))
}

fn report<T: Real>(
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
    }
}

/// Projected overdamped velocity at `pos`: `U = U_inf + mu (F + G^T kappa)` with `kappa`
/// such that every bond's length rate vanishes. `mu` and `force` must hold the mobility
/// and external forces at `pos`; the result is left in `u`.
#[allow(clippy::too_many_arguments)]
fn projected_velocity<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    mu: &[T::M3],
    force: &[T::V3],
    bonds: &[Bond<T>],
    grad: &mut [T::V3],
    disp: &mut [T::V3],
    kappa: &mut [T],
    scratch: &mut Scratch<'_, T>,
    u: &mut [T::V3],
) -> Result<SolveStats<T>, StepError> {
    let n = pos.len();
    linalg::sym_matvec::<T>(mu, n, force, u);
    add_flow(p, pos, u);
    bond_vectors(bonds, pos, grad);
    mobility_disp(mu, n, bonds, grad, T::ONE, disp);
    kappa.fill(T::ZERO);
    let problem = Problem::Velocities {
        bond: grad,
        dt: p.dt,
    };
    constraints::solve(
        problem,
        &Metric::Dense { disp, n },
        bonds,
        &p.solver,
        u,
        kappa,
        scratch,
    )
}

/// Overdamped second order: Heun predictor-corrector on the projected velocity, then
/// the same position projection as the first-order scheme.
fn overdamped2<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    ws: &mut Workspace<T, N, B>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, nb, dt) = (s.pos.len(), bonds.len(), p.dt);
    let mu0 = blocks::<T, N>(&mut ws.mu, n);
    let mu1 = blocks::<T, N>(&mut ws.fac, n);
    let force = gvec::<T, N>(&mut ws.force, n);
    let f0 = gvec::<T, N>(&mut ws.work_a, n);
    let f1 = gvec::<T, N>(&mut ws.work_b, n);
    let x_p = gvec::<T, N>(&mut ws.work_c, n);
    let new_pos = &mut ws.new_pos[..n];
    let (grad, grad_new) = (&mut ws.grad[..nb], &mut ws.grad_new[..nb]);
    let (disp, lambda, kappa) = (
        &mut ws.disp.as_flattened_mut()[..nb * n],
        &mut ws.lambda[..nb],
        &mut ws.kappa[..nb],
    );
    let mut sc = Scratch {
        jac: ws.jac.as_flattened_mut(),
        rhs: &mut ws.rhs[..],
        piv: &mut ws.piv[..],
    };
    // Predictor: projected velocity at r, one projected Euler step.
    assemble_tt(p, s.pos, s.radius, mu0)?;
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    projected_velocity(p, s.pos, mu0, force, bonds, grad, disp, kappa, &mut sc, f0)?;
    // Tension at the start of the step: the velocity projection's multipliers are forces.
    let tension = max_tension(bonds, kappa);
    for i in 0..n {
        x_p[i] = s.pos[i] + f0[i] * dt;
    }
    mobility_disp(mu0, n, bonds, grad, dt, disp);
    lambda.fill(T::ZERO);
    let metric = Metric::Dense { disp, n };
    constraints::solve(
        Problem::Positions,
        &metric,
        bonds,
        &p.solver,
        x_p,
        lambda,
        &mut sc,
    )?;
    // Corrector: projected velocity at the predicted point, trapezoidal average.
    assemble_tt(p, x_p, s.radius, mu1)?;
    forces::external(p, x_p, s.radius, s.density, ext, force)?;
    projected_velocity(
        p, x_p, mu1, force, bonds, grad_new, disp, kappa, &mut sc, f1,
    )?;
    for i in 0..n {
        new_pos[i] = s.pos[i] + (f0[i] + f1[i]) * (dt * T::HALF);
    }
    // Projection as in the first-order scheme: r' = r* + dt mu(r) G(r)^T lambda.
    mobility_disp(mu0, n, bonds, grad, dt, disp);
    lambda.fill(T::ZERO);
    let metric = Metric::Dense { disp, n };
    let stats = constraints::solve(
        Problem::Positions,
        &metric,
        bonds,
        &p.solver,
        new_pos,
        lambda,
        &mut sc,
    )?;
    for i in 0..n {
        ws.new_vel[i] = (new_pos[i] - s.pos[i]) / dt;
    }
    // Spin from the start-of-step forces (external plus the projection's).
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    add_constraint_forces(bonds, grad, lambda, force);
    spin(p, s.pos, s.radius, force, &mut ws.new_omega[..n])?;
    Ok(StepReport {
        max_tension: tension,
        ..report(stats, 0, bonds, lambda)
    })
}

/// `1/m` per particle into `inv_mass`.
fn inverse_masses<T: Real>(radius: &[T], density: &[T], inv_mass: &mut [T]) {
    for ((w, &a), &rho) in inv_mass.iter_mut().zip(radius).zip(density) {
        *w = T::ONE / (sphere_volume(a) * rho);
    }
}

/// Inertial HydroRATTLE as the paper writes it (explicit drag).
fn rattle_explicit<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    ws: &mut Workspace<T, N, B>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, nb, dt) = (s.pos.len(), bonds.len(), p.dt);
    let mu = blocks::<T, N>(&mut ws.mu, n);
    let fac = blocks::<T, N>(&mut ws.fac, n);
    let force = gvec::<T, N>(&mut ws.force, n);
    let drag = gvec::<T, N>(&mut ws.work_a, n);
    let acc = gvec::<T, N>(&mut ws.work_b, n);
    let r_star = gvec::<T, N>(&mut ws.work_c, n);
    let inv_mass = &mut ws.inv_mass[..n];
    let (new_pos, new_vel) = (&mut ws.new_pos[..n], &mut ws.new_vel[..n]);
    let (grad, grad_new) = (&mut ws.grad[..nb], &mut ws.grad_new[..nb]);
    let (lambda, kappa) = (&mut ws.lambda[..nb], &mut ws.kappa[..nb]);
    let mut sc = Scratch {
        jac: ws.jac.as_flattened_mut(),
        rhs: &mut ws.rhs[..],
        piv: &mut ws.piv[..],
    };
    inverse_masses(s.radius, s.density, inv_mass);
    // Resistance through the Cholesky factor of mu_tt: R dv = mu^-1 (v - U_inf).
    assemble_tt(p, s.pos, s.radius, mu)?;
    fac.copy_from_slice(mu);
    linalg::cholesky::<T>(fac, n).map_err(|error| StepError::Linalg {
        stage: Stage::Mobility,
        error,
    })?;
    if p.stability_guard {
        let limit = explicit_drag_limit(fac, n, inv_mass, r_star, acc);
        if p.dt > limit {
            return Err(StepError::Unstable {
                dt: dt.to_f64(),
                limit: limit.to_f64(),
            });
        }
    }
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    for i in 0..n {
        drag[i] = s.vel[i] - p.flow_at(s.pos[i]);
    }
    linalg::cholesky_solve::<T>(fac, n, drag);
    // a = (F_ext - R (v - U_inf)) / m;  r* = r + v dt + a dt^2 / 2.
    let half_dt2 = T::HALF * dt * dt;
    for i in 0..n {
        acc[i] = (force[i] - drag[i]) * inv_mass[i];
        r_star[i] = s.pos[i] + s.vel[i] * dt + acc[i] * half_dt2;
        new_pos[i] = r_star[i];
    }
    // SHAKE with the mass metric (eq. 3).
    bond_vectors(bonds, s.pos, grad);
    lambda.fill(T::ZERO);
    let metric = Metric::Mass {
        inv_mass,
        grad,
        scale: half_dt2,
    };
    let stats = constraints::solve(
        Problem::Positions,
        &metric,
        bonds,
        &p.solver,
        new_pos,
        lambda,
        &mut sc,
    )?;
    // v* = v + a dt + a_C dt / 2, then RATTLE (eq. 4) for the velocity multipliers.
    for i in 0..n {
        new_vel[i] = s.vel[i] + acc[i] * dt + (new_pos[i] - r_star[i]) / dt;
    }
    bond_vectors(bonds, new_pos, grad_new);
    kappa.fill(T::ZERO);
    let metric = Metric::Mass {
        inv_mass,
        grad: grad_new,
        scale: T::HALF * dt,
    };
    let problem = Problem::Velocities { bond: grad_new, dt };
    let vstats = constraints::solve(problem, &metric, bonds, &p.solver, new_vel, kappa, &mut sc)?;
    // Each sphere pushes on the fluid with R (v - U_inf).
    spin(p, s.pos, s.radius, drag, &mut ws.new_omega[..n])?;
    Ok(report(stats, vstats.iterations, bonds, lambda))
}

/// Linear stability limit of the explicit drag, `2 lambda_min(M^1/2 mu M^1/2)`, by
/// inverse iteration through the Cholesky factor of `mu` (40 iterations, fixed start).
fn explicit_drag_limit<T: Real>(
    fac: &[T::M3],
    n: usize,
    inv_mass: &[T],
    z: &mut [T::V3],
    y: &mut [T::V3],
) -> T {
    for (i, zi) in z.iter_mut().enumerate() {
        let t = T::ONE + T::from_f64(0.01 * i as f64);
        *zi = T::v3(t, T::HALF * t, T::ONE);
    }
    let mut rq = T::ZERO;
    for _ in 0..40 {
        let norm = z.iter().fold(T::ZERO, |a, &v| a + T::norm2(v)).sqrt();
        for (i, yi) in y.iter_mut().enumerate() {
            z[i] = z[i] / norm;
            *yi = z[i] * inv_mass[i].sqrt();
        }
        linalg::cholesky_solve::<T>(fac, n, y);
        rq = T::ZERO;
        for i in 0..n {
            y[i] *= inv_mass[i].sqrt();
            rq += T::dot(z[i], y[i]);
        }
        z.copy_from_slice(y);
    }
    T::TWO / rq
}

/// `y <- S^-1 dt K^-1 S y` with `K = dt I + S mu S` factorised in `fac`.
fn apply_drag<T: Real>(fac: &[T::M3], sq: &[T], dt: T, y: &mut [T::V3]) {
    for (v, &q) in y.iter_mut().zip(sq) {
        *v *= q;
    }
    linalg::cholesky_solve::<T>(fac, sq.len(), y);
    for (v, &q) in y.iter_mut().zip(sq) {
        *v *= dt / q;
    }
}

/// Inertial with implicit drag: `(R + M/dt) v' = F + F_C + M v/dt + R U_inf`, solved as
/// `v' = S^-1 dt K^-1 S (mu (F + F_C + M v/dt) + U_inf)`, `S = M^1/2`, `K = dt I + S mu S`.
/// With rotation the same on the 6N grand mobility (`M` holds masses and moments).
fn rattle_stable<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    ws: &mut Workspace<T, N, B>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, nb, dt) = (s.pos.len(), bonds.len(), p.dt);
    let m = if p.rotation { 2 * n } else { n };
    let mu = blocks::<T, N>(&mut ws.mu, m);
    let fac = blocks::<T, N>(&mut ws.fac, m);
    let rhs6 = gvec::<T, N>(&mut ws.force, m);
    let u = gvec::<T, N>(&mut ws.work_a, m);
    let t = gvec::<T, N>(&mut ws.work_b, m);
    let sq = &mut ws.sqrt_m.as_flattened_mut()[..m];
    let (new_pos, new_vel) = (&mut ws.new_pos[..n], &mut ws.new_vel[..n]);
    let (grad, grad_new) = (&mut ws.grad[..nb], &mut ws.grad_new[..nb]);
    let (disp, lambda, kappa) = (
        &mut ws.disp.as_flattened_mut()[..nb * n],
        &mut ws.lambda[..nb],
        &mut ws.kappa[..nb],
    );
    let mut sc = Scratch {
        jac: ws.jac.as_flattened_mut(),
        rhs: &mut ws.rhs[..],
        piv: &mut ws.piv[..],
    };
    // Mobility (translation or grand) and the drag operator K = dt I + S mu S.
    if p.rotation {
        mobility::assemble_grand(p.hydro, p.viscosity, s.pos, s.radius, mu)?;
    } else {
        assemble_tt(p, s.pos, s.radius, mu)?;
    }
    for i in 0..n {
        let mass = sphere_volume(s.radius[i]) * s.density[i];
        sq[i] = mass.sqrt();
        if p.rotation {
            sq[n + i] = (T::from_f64(0.4) * mass * s.radius[i] * s.radius[i]).sqrt();
        }
    }
    for i in 0..m {
        for j in 0..=i {
            fac[i * m + j] = mu[i * m + j] * (sq[i] * sq[j]);
        }
        fac[i * m + i] += T::m3_diag(dt);
    }
    linalg::cholesky::<T>(fac, m).map_err(|error| StepError::Linalg {
        stage: Stage::Drag,
        error,
    })?;
    // Unconstrained generalised velocity from F + M v / dt.
    forces::external(p, s.pos, s.radius, s.density, ext, &mut rhs6[..n])?;
    rhs6[n..].fill(T::V3_ZERO);
    for i in 0..m {
        let w = if i < n { s.vel[i] } else { s.omega[i - n] };
        rhs6[i] += w * (sq[i] * sq[i] / dt);
    }
    drag_velocity(p, s.pos, mu, fac, sq, rhs6, u);
    for i in 0..n {
        new_pos[i] = s.pos[i] + u[i] * dt;
    }
    // Constraint displacements D_l = dt S^-1 dt K^-1 S mu g_l (every bead moves).
    bond_vectors(bonds, s.pos, grad);
    for (l, b) in bonds.iter().enumerate() {
        for q in 0..m {
            t[q] = (mu[q * m + b.i] - mu[q * m + b.j]) * grad[l];
        }
        apply_drag(fac, sq, dt, t);
        for q in 0..n {
            disp[l * n + q] = t[q] * dt;
        }
    }
    lambda.fill(T::ZERO);
    let metric = Metric::Dense { disp, n };
    let stats = constraints::solve(
        Problem::Positions,
        &metric,
        bonds,
        &p.solver,
        new_pos,
        lambda,
        &mut sc,
    )?;
    for i in 0..n {
        new_vel[i] = (new_pos[i] - s.pos[i]) / dt;
    }
    // Angular velocities: the same solve with the constraint forces included.
    if p.rotation {
        add_constraint_forces(bonds, grad, lambda, &mut rhs6[..n]);
        drag_velocity(p, s.pos, mu, fac, sq, rhs6, u);
        ws.new_omega[..n].copy_from_slice(&u[n..]);
    } else {
        ws.new_omega[..n].fill(p.vorticity);
    }
    // RATTLE: make the velocities tangent to the bonds at the new positions.
    bond_vectors(bonds, new_pos, grad_new);
    kappa.fill(T::ZERO);
    let problem = Problem::Velocities { bond: grad_new, dt };
    let vstats = constraints::solve(problem, &metric, bonds, &p.solver, new_vel, kappa, &mut sc)?;
    Ok(report(stats, vstats.iterations, bonds, lambda))
}

/// `u = S^-1 dt K^-1 S (mu f + U_inf)` for a generalised force `f` (length `m`).
fn drag_velocity<T: Real>(
    p: &Params<T>,
    pos: &[T::V3],
    mu: &[T::M3],
    fac: &[T::M3],
    sq: &[T],
    f: &[T::V3],
    u: &mut [T::V3],
) {
    let (m, n) = (f.len(), pos.len());
    linalg::sym_matvec::<T>(mu, m, f, u);
    add_flow(p, pos, &mut u[..n]);
    for w in &mut u[n..] {
        *w += p.vorticity;
    }
    apply_drag(fac, sq, p.dt, u);
}

/// Hookean springs, overdamped explicit Euler.
fn springs<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    ws: &mut Workspace<T, N, B>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    let mu = blocks::<T, N>(&mut ws.mu, n);
    let force = gvec::<T, N>(&mut ws.force, n);
    let u = gvec::<T, N>(&mut ws.work_a, n);
    assemble_tt(p, s.pos, s.radius, mu)?;
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    forces::springs(bonds, p.spring_stiffness, s.pos, force);
    linalg::sym_matvec::<T>(mu, n, force, u);
    add_flow(p, s.pos, u);
    for i in 0..n {
        ws.new_pos[i] = s.pos[i] + u[i] * dt;
        ws.new_vel[i] = u[i];
    }
    spin(p, s.pos, s.radius, force, &mut ws.new_omega[..n])?;
    let (_, worst) = max_residual(bonds, &ws.new_pos[..n]);
    let tension = bonds.iter().fold(T::ZERO, |a, b| a.max(b.length)) * worst * p.spring_stiffness;
    Ok(StepReport {
        iterations: 0,
        velocity_iterations: 0,
        residual: worst,
        max_tension: tension,
    })
}
