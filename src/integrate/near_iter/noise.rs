//! A Brownian `Overdamped` step with the iterative near field: the noise of covariance
//! `2 kT dt M_SD` and the drift `kT dt div M_SD`, with no matrix stored beyond the far
//! field's packed blocks the products already hold.
//!
//! **Noise: Fiore and Swan's split**, not a Lanczos root of `M_SD` itself. With
//! `R = M_far^-1 + R_near` and `R_near = L L^T` (the close pairs' factors the product
//! has made), `b = M_far^(-1/2) z' + L z` (`z'`, `z` standard normal over the `6n`
//! forces and torques and the `12` unknowns of each close pair) has covariance `R`, so
//! `M_SD b` has covariance `M_SD R M_SD = M_SD`, and its translational part `M_SD,tt`.
//! The far field's `M_far^(-1/2) z'` is a Lanczos root on the packed grand mobility
//! (products of `O(n^2)`, no solve), the near field's `L z` is exact, and the one solve
//! is an ordinary product. A Lanczos root of `M_SD` would make each of its iterations a
//! conjugate-gradient solve, on an operator whose lubrication modes make it badly
//! conditioned (more iterations): `docs/NEAR.md` has the counts.
//!
//! **Drift: the dense near path's Fixman midpoint** (`integrate::brownian`), so the two
//! paths are one method. With `x = M_SD b` (covariance `M_SD`) and
//! `E[x b^T] = M_SD R = I`, the midpoint `x~ = r + sqrt(kT dt / 2) x_t` and the move
//! `sqrt(2 kT dt) (M_SD(x~) b)_t` have covariance `2 kT dt M_SD,tt` and mean
//! `kT dt div M_SD,tt` to leading order (the derivation of `brownian.rs` with the
//! non-square factor `M_SD [M_far^(-1/2), L]` and `b` in place of `L^-T xi`).
//! [`Drift::Uncorrected`] moves by `sqrt(2 kT dt) x_t` alone.
//!
//! **Cost**: two assemblies of the far field (start, midpoint), three products (the
//! velocities and the noise's solve share the start's factors), and the far field's
//! Lanczos iterations ([`StepReport::noise_iterations`]). With constraints (bonds,
//! pins, the wall's links) the dense near step's constrained step (`brownian.rs`): the
//! midpoint's noise projected onto the bonds along `M_SD,tt(x~)` (its mean then
//! `kT dt div (P M_SD,tt)`), and the start's far field assembled a third time for the
//! move's projection along `M_SD,tt(r)`. The Lanczos root stops at
//! [`Params::lanczos`]'s tolerance within its iterations; not converging is
//! [`StepError::NoConvergence`], the caller's state unchanged.

use super::constrained::{self, Iterative};
use super::{Counts, STORAGE, Store, report, solve, spins};
use crate::bonds::Bond;
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::integrate::contacts::project_along;
use crate::integrate::{Start, StepReport, add_constraint_forces, add_flow, step_velocity};
use crate::noise::{Noise, lanczos};
use crate::params::{Brownian, Drift, Params};
use crate::real::Real;
use crate::workspace::{Views, near_noise_sizes};

/// `s` split into its head and its last `k` elements.
fn tail<X>(s: &mut [X], k: usize) -> Result<(&mut [X], &mut [X]), StepError> {
    let at = s.len().checked_sub(k).ok_or(STORAGE)?;
    Ok(s.split_at_mut(at))
}

/// One `Overdamped` step at `b.temperature > 0` with the iterative near field (see the
/// module): `r' = r + dt (U_inf + M_SD,tt F) + dx`, the spins `Omega_inf + M_SD,rt F`
/// at the start, as the deterministic step. With constraints (bonds, pins, contacts,
/// the wall's links) the dense near step's constrained Brownian step
/// (`integrate::brownian`): the midpoint's noise projected onto the bonds along
/// `M_SD,tt(x~)` (its mean then `kT dt div (P M_SD,tt)`), the move projected along
/// `dt M_SD,tt(r) G^T` as the deterministic step's (`constrained.rs`, the start's
/// products factored again), the spins of `F + G^T lambda`.
#[allow(clippy::too_many_arguments)]
pub(in crate::integrate) fn overdamped_thermal<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    b: Brownian<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
    noise: &mut Noise,
) -> Result<StepReport<T>, StepError> {
    let (n, dt, kt) = (s.pos.len(), p.dt, b.temperature);
    let Views {
        force,
        work_a: u,
        new_pos,
        new_vel,
        new_omega,
        grad,
        lambda,
        mut scratch,
        links,
        disp,
        near,
        near_iter,
        ..
    } = v;
    // Room for every row the step may solve (none without constraints).
    let rows = p.constraints(n, bonds.len());
    let [noise_v, noise_s] = near_noise_sizes(p, n);
    let (reals, work) = tail(near.1, noise_s)?;
    let (reals, stiff) = tail(reals, rows)?;
    let (vectors, rest) = tail(near_iter.0, noise_v)?;
    let mut store = Store::new((near.0, reals), (vectors, near_iter.1));
    let cap = p.lanczos.max_iterations as usize;
    let (basis, rest) = rest.split_at_mut(lanczos::vectors(cap, 2 * n));
    let (z, rest) = rest.split_at_mut(2 * n);
    let (root, rest) = rest.split_at_mut(2 * n);
    let (f, rest) = rest.split_at_mut(2 * n);
    let (x, mid) = rest.split_at_mut(2 * n);
    let mut counts = Counts::default();
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    // At the start: the velocities, then b = M_far^(-1/2) z' + L z and x = M_SD b.
    // (With constraints the spins wait for the constraint forces.)
    noise.fill::<T>(z);
    let start = (s.pos, s.radius);
    let iterations = solve::at(p, s.ewald, start, &mut store, |at| {
        let w = if rows == 0 {
            Some(&mut *new_omega)
        } else {
            None
        };
        at.velocities(p, force, u, w, &mut counts)?;
        // The far field's products, the first failure kept (Lanczos's product is
        // infallible; the assembled far field's never fails).
        let mut failed = None;
        let product = |v: &[T::V3], w: &mut [T::V3]| {
            if failed.is_none()
                && let Err(e) = at.far(v, w)
            {
                failed = Some(e);
            }
        };
        let root_it = lanczos::sqrt(p.lanczos, product, z, basis, work, root, Some(&mut *f));
        if let Some(e) = failed {
            return Err(e);
        }
        let root_it = root_it?;
        at.add_near_noise(&mut |v| noise.fill::<T>(v), f)?;
        at.apply(p, f, x, &mut counts)?;
        Ok(root_it)
    })?;
    add_flow(p, s.pos, u);
    let amplitude = (T::TWO * kt * dt).sqrt();
    let x = &mut x[..2 * n];
    // The midpoint projection's iterations, where it has projected (and scaled) the
    // noise.
    let mut held = None;
    if b.drift == Drift::Midpoint {
        // x~ = r + sqrt(kT dt / 2) x_t; then x = M_SD(x~) b.
        let half = (kt * dt * T::HALF).sqrt();
        let mid = &mut mid[..n];
        for ((m, &r), &d) in mid.iter_mut().zip(s.pos).zip(&*x) {
            *m = r + d * half;
        }
        let at_mid = (&*mid, s.radius);
        held = solve::at(p, s.ewald, at_mid, &mut store, |at| {
            at.apply(p, f, x, &mut counts)?;
            if rows == 0 || bonds.is_empty() {
                return Ok(None);
            }
            // The noise `dx = sqrt(2 kT dt) x_t` projected onto the bonds at x~ along
            // `M_SD,tt(x~)`, as the dense step projects it.
            let dx = &mut x[..n];
            dx.iter_mut().for_each(|d| *d *= amplitude);
            let table = &mut *disp;
            let mut along = Iterative::new(at, p, &mut counts, &mut *stiff, at_mid, s.ewald, table);
            let views = (&mut *grad, &mut *lambda);
            let stats = along.hold_rates(p, bonds, views, &mut scratch, dx, T::ONE)?;
            Ok(Some(stats.iterations))
        })?;
    }
    if rows == 0 {
        spins(p, new_omega);
        for i in 0..n {
            new_pos[i] = s.pos[i] + u[i] * dt + x[i] * amplitude;
        }
        step_velocity(s.pos, new_pos, dt, new_vel);
        return Ok(StepReport {
            noise_iterations: iterations,
            ..report(counts)
        });
    }
    // The noise, unless the midpoint's projection has scaled it.
    if held.is_none() {
        x[..n].iter_mut().for_each(|d| *d *= amplitude);
    }
    // r* = r + dt (U_inf + M_SD,tt F) + dx, projected along `M_SD` at the start
    // (factored again: the midpoint's products have taken the storage).
    let r = solve::at(p, s.ewald, start, &mut store, |at| {
        let mut along = Iterative::new(at, p, &mut counts, stiff, start, s.ewald, disp);
        let free = |y: &mut [T::V3]| {
            for i in 0..n {
                y[i] = s.pos[i] + u[i] * dt + x[i];
            }
        };
        let views = (links, &mut *grad, &mut *lambda, &mut scratch);
        let r = project_along(p, bonds, start, views, new_pos, free, &mut along)?;
        add_constraint_forces(r.held, grad, lambda, force);
        if p.rotation {
            let sd = &mut along.sd;
            sd.at
                .velocities(p, force, u, Some(&mut *new_omega), sd.counts)?;
        }
        Ok(constrained::held(&r))
    })?;
    spins(p, new_omega);
    step_velocity(s.pos, new_pos, dt, new_vel);
    Ok(StepReport {
        noise_iterations: iterations,
        ..constrained::held_report(&counts, r, held.unwrap_or(0), bonds, lambda)
    })
}
