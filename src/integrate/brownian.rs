//! Overdamped HydroSHAKE with thermal noise (constrained Brownian dynamics).
//!
//! The unconstrained move gets a displacement with covariance `2 kT dt mu`, drawn as
//! `L xi` with `L L^T = mu` (block Cholesky of the packed mobility) and `xi` standard
//! normal; the constraint projection then runs as in the deterministic step. What the
//! constrained motion also needs is the Ito drift `kT div(P mu)`, `P mu` the mobility
//! projected onto the constraints (`P = I - mu G^T (G mu G^T)^-1 G`):
//!
//! * [`Drift::Midpoint`] gets it from a Fixman-type midpoint. With
//!   `x~ = x + sqrt(kT dt / 2) L xi`, the noise `sqrt(2 kT dt) P(x~) mu(x~) L^-T xi` has
//!   covariance `2 kT dt P mu` to leading order (`L^-T L^-1 = mu^-1`) and mean
//!   `kT dt d_k (P mu)_ik` (`E[(L xi)_k (L^-T xi)_j] = delta_kj`). `P(x~) mu(x~) v` is a
//!   linear constraint solve at `x~`: `v` through `mu(x~)`, minus the part that changes
//!   a bond length at `x~`.
//! * [`Drift::Uncorrected`] adds `sqrt(2 kT dt) L xi` and nothing else.
//!
//! The RPY mobility (and Oseen's, and free draining) has zero divergence in free space,
//! so the unconstrained drift `kT div mu` vanishes: no term for it here. The midpoint
//! would supply it anyway (it differentiates `P mu` as a whole).

use core::cell::Cell;

use super::{
    Projection, Start, StepReport, add_constraint_forces, add_flow, bond_vectors, free_product,
    mobility_metric, mobility_product, project_overdamped, report, spin, step_velocity,
};
use crate::bonds::Bond;
use crate::constraints::{self, Problem, Scratch};
use crate::error::{Stage, StepError};
use crate::forces::{self, ExternalForce};
use crate::linalg::{self, Block, Mob, MobMut, with_blocks};
use crate::mobility::Hydro;
use crate::noise::Noise;
use crate::noise::lanczos::{self, LanczosError};
use crate::noise::reduced;
use crate::parallel::{self, Parallel};
use crate::params::{Brownian, Drift, Params};
use crate::real::Real;
use crate::workspace::Views;

/// One overdamped step with thermal noise at `b.temperature > 0` (stored mobility).
pub(super) fn overdamped_thermal<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    b: Brownian<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
    noise: &mut Noise,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
    // The normal deviates and the midpoint borrow the candidate velocities and spins,
    // which are written only at the end.
    let Views {
        mut mu,
        mu2,
        fac,
        force,
        work_a: u,
        work_b: dx,
        new_pos,
        new_vel: xi,
        new_omega: mid,
        grad,
        grad_new: grad_mid,
        disp,
        lambda,
        kappa,
        mut scratch,
        par,
        bands,
        basis,
        krylov_t,
        links,
        near,
        ..
    } = v;
    let formed = Cell::new(0);
    let mut near = (near.0, near.1, &formed);
    // Deterministic velocity at the start: U_inf + mu F. When the noise's products will
    // read the reduced copy of `mu`, each band of the assembly writes its part of the
    // copy while its blocks are in cache.
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    let copied = reads_copy(p, n);
    if copied {
        let pairs = (p.hydro, p.viscosity, s.pos, s.radius);
        let copy = (&mut *fac, reduced::copy_start as fn(usize) -> usize);
        with_blocks!(mut mu.reborrow(), a => {
            let pack = reduced::pack_rows::<T, _>;
            parallel::assemble_apply_then(par, pairs, a, force, u, bands, copy, pack)
        })
        .map_err(StepError::from)?;
    } else if p.near_on() {
        let at_start = mu.reborrow();
        super::near::assemble_apply(p, s.ewald, s.pos, s.radius, at_start, force, u, &mut near)?;
        if p.rotation {
            super::near::keep_spin(n, &mut near);
        }
    } else {
        let at_start = mu.reborrow();
        mobility_product(p, s.ewald, s.pos, s.radius, at_start, force, u, par, bands)?;
    }
    let mu = mu.into_ref();
    add_flow(p, s.pos, u);
    let held = Held {
        bonds,
        grad_mid,
        disp,
        kappa,
        scratch: &mut scratch,
    };
    let krylov = Krylov {
        basis,
        work: krylov_t,
        par,
        bands,
        copied,
        at_mid: mu2,
        near: (&mut *near.0, &mut *near.1, near.2),
    };
    let (noise_iterations, midpoint) =
        kick(p, b, s, mu, fac, xi, mid, dx, noise, Some(held), krylov)?;
    // r* = r + dt (U_inf + mu F) + noise, projected as in the deterministic step (with
    // the wall's links when there is one). With `Params::compact_products` the
    // projection's Krylov products read the reduced copy of `mu` the noise has read
    // (still in `fac`: the midpoint's mobility went to `mu2`), not a second copy.
    let compact = p.compact_copy(n, bonds.len());
    debug_assert!(!compact || copied);
    let free = |x: &mut [T::V3]| {
        for i in 0..n {
            x[i] = s.pos[i] + u[i] * dt + dx[i];
        }
    };
    let views = Projection {
        links,
        grad: &mut *grad,
        disp,
        lambda: &mut *lambda,
        scratch: &mut scratch,
        ewald: s.ewald,
        compact: if compact { &*fac } else { &[] },
    };
    let r = project_overdamped(p, bonds, s.pos, s.radius, mu, views, new_pos, free)?;
    step_velocity(s.pos, new_pos, dt, xi);
    add_constraint_forces(r.held, grad, lambda, force);
    if p.near_on() {
        // The midpoint's mobility has taken the dense storage: the start's kept blocks.
        let at_start = (&mut near, super::near::Spins::Kept);
        super::near::spin(p, s.ewald, s.pos, s.radius, force, mid, at_start)?;
    } else {
        spin(p, s.ewald, s.pos, s.radius, force, mid)?;
    }
    Ok(StepReport {
        noise_iterations,
        #[cfg(feature = "near")]
        near_formations: formed.get(),
        contacts: r.contacts,
        wall_contacts: r.wall_contacts,
        contact_rounds: r.rounds,
        ..report(r.stats, midpoint, bonds, lambda)
    })
}

/// The bonds the midpoint's noise is projected onto (constraints), and its storage.
pub(super) struct Held<'a, 'b, T: Real> {
    pub(super) bonds: &'a [Bond<T>],
    pub(super) grad_mid: &'a mut [T::V3],
    pub(super) disp: &'a mut [T::V3],
    pub(super) kappa: &'a mut [T],
    pub(super) scratch: &'a mut Scratch<'b, T>,
}

/// The Lanczos basis and its scalars ([`Views::basis`], [`Views::krylov_t`]; empty with
/// the Cholesky factor), how the stored mobility's products run ([`Views::par`],
/// [`Views::bands`]; the start's product is done with them when the noise is drawn),
/// whether the factor's storage already holds the reduced copy of `mu`
/// ([`reads_copy`]), and the storage of the midpoint's mobility with Lanczos noise
/// ([`Views::mu2`]; empty with the Cholesky factor, whose blocks take it).
pub(super) struct Krylov<'a, T: Real> {
    pub(super) basis: &'a mut [T::V3],
    pub(super) work: &'a mut [T],
    pub(super) par: &'a dyn Parallel,
    pub(super) bands: &'a mut [T::V3],
    pub(super) copied: bool,
    pub(super) at_mid: MobMut<'a, T>,
    /// The near field's storage ([`Views::near`]; empty without it).
    pub(super) near: super::near::Store<'a, T>,
}

/// Whether the noise's products read the reduced copy of the stored mobility
/// (`noise::reduced`), kept in the factor's storage (a step by Lanczos has no factor):
/// [`reduced::for_noise`], which sizes that storage too. Inlined, with the precision
/// tested first, so that an `f32` kernel (firmware) links no copy.
#[inline(always)]
fn reads_copy<T: Real>(p: &Params<T>, n: usize) -> bool {
    let copy = reduced::for_noise(p, n);
    // The `const` test agrees with the step's own tests of the wall and the Ewald box
    // (which also heed the kernel's features: a step they refuse never gets here).
    let symmetric = super::wall_height(p).is_none() && super::ewald_cell(p).is_none();
    debug_assert!(!copy || symmetric);
    copy
}

/// The thermal displacement `dx` of one step from the packed mobility `mu` at the
/// start (see the module): `fac` takes its Cholesky factor (then, with the midpoint,
/// the mobility at the midpoint in its nine-scalar blocks) or, by Lanczos, the reduced
/// copy of `mu` ([`reads_copy`]; the midpoint's mobility then goes to
/// `krylov.at_mid`), `xi` the deviates, `mid` the midpoint. With `held`
/// the midpoint's noise is projected onto its bonds; without (springs), it is
/// `sqrt(2 kT dt) mu(x~) L^-T xi`, whose mean is `kT dt div mu` (zero for RPY).
/// With the Lanczos square root ([`Params::lanczos_noise`]) `L` is the symmetric
/// `mu^(1/2)`, drawn from products with `mu` in the basis `krylov`, and the returned
/// counts are its iterations (0 with Cholesky) and those of the midpoint's projection
/// (0 without). With [`Params::matrix_free`] `mu` and
/// `fac` are empty: every product (the Lanczos ones at the start, the midpoint's)
/// evaluates the pair blocks where it uses them.
#[allow(clippy::too_many_arguments)]
pub(super) fn kick<T: Real>(
    p: &Params<T>,
    b: Brownian<T>,
    s: &Start<'_, T>,
    mu: Mob<'_, T>,
    fac: &mut [T::M3],
    xi: &mut [T::V3],
    mid: &mut [T::V3],
    dx: &mut [T::V3],
    noise: &mut Noise,
    held: Option<Held<'_, '_, T>>,
    krylov: Krylov<'_, T>,
) -> Result<(u32, u32), StepError> {
    let (n, dt, kt) = (s.pos.len(), p.dt, b.temperature);
    let lanczos = p.lanczos_noise(n);
    if !lanczos {
        // L L^T = mu.
        with_blocks!(mu, a => {
            for (f, b) in fac.iter_mut().zip(a) {
                *f = b.full();
            }
        });
        linalg::cholesky::<T>(fac, n).map_err(|error| StepError::Linalg {
            stage: Stage::Mobility,
            error,
        })?;
    }
    let amplitude = (T::TWO * kt * dt).sqrt();
    let Krylov {
        basis,
        work,
        par,
        bands,
        copied,
        at_mid,
        mut near,
    } = krylov;

    // In a box without bonds to project onto, the midpoint's mean is `kT dt div M`,
    // zero for the box's RPY mobility (each Fourier mode is transverse, `P(k) k = 0`),
    // so the midpoint (a second assembly on the Ewald path, a solve of some 30 to 50
    // products on PSE's) is left out: the uncorrected draw, whose covariance is `M`
    // exactly. In free space the midpoint stays (the run's bits are kept there). With
    // the near field the box's mobility is `M_SD`, whose divergence is not zero (the
    // pairs' lubrication varies with their gaps): the midpoint stays, for its drift.
    let bonded = held.as_ref().is_some_and(|h| !h.bonds.is_empty());
    let drift = match s.ewald.is_some() && !bonded && !p.near_on() {
        true => Drift::Uncorrected,
        false => b.drift,
    };
    // On the PSE path the noise is PSE's own (`pse_noise`): no product with the whole
    // mobility but the midpoint's solve.
    #[cfg(feature = "pse")]
    if let Some(sums) = s.ewald.and_then(|e| e.pse()) {
        let vectors = (&mut *xi, &mut *mid, &mut *dx);
        let iterations = super::pse_noise::draw(p, drift, s, sums, noise, vectors, basis, work)?;
        let projected = match drift {
            Drift::Uncorrected => {
                dx.iter_mut().for_each(|d| *d *= amplitude);
                0
            }
            Drift::Midpoint => {
                let mids = (mu, storage_at_mid(lanczos, at_mid, fac), xi, mid, dx);
                midpoint(p, b, s, mids, held, (par, bands, &mut near), lanczos)?
            }
        };
        return Ok((iterations, projected));
    }
    noise.fill::<T>(xi);
    // `w = mu v` at the start: the stored mobility in bands, or matrix-free (the start
    // has passed a product at these positions already, so no pair is nested). In free
    // space (symmetric blocks) a large f64 mobility is read from a reduced copy instead
    // (`noise::reduced`) in the factor's storage, written there by the start's assembly
    // (`krylov.copied`) or else by the first product.
    let reduced = reads_copy(p, n);
    let mut copied = reduced && copied;
    let product = |v: &[T::V3], w: &mut [T::V3]| {
        if p.matrix_free {
            let _ = free_product(p, s.ewald, s.pos, s.radius, v, w, (par, &mut *bands));
        } else if reduced && copied {
            reduced::apply::<T>(par, fac, n, v, w, bands);
        } else if reduced {
            with_blocks!(mu, a => reduced::copy_apply::<T>(par, a, n, fac, v, w, bands));
            copied = true;
        } else {
            with_blocks!(mu, a => parallel::product::<T>(par, a, n, v, w, bands));
        }
    };
    let (mut iterations, mut projected) = (0, 0);
    match drift {
        Drift::Uncorrected => {
            if lanczos {
                iterations = lanczos::sqrt(p.lanczos, product, xi, basis, work, dx, None)
                    .map_err(refused)?;
            } else {
                linalg::lower_mul::<T>(fac, n, xi, dx);
            }
            for d in dx.iter_mut() {
                *d *= amplitude;
            }
        }
        Drift::Midpoint => {
            // x~ = x + sqrt(kT dt / 2) L xi; then xi <- sqrt(2 kT dt) L^-T xi.
            if lanczos {
                iterations =
                    lanczos::sqrt(p.lanczos, product, xi, basis, work, mid, Some(&mut *dx))
                        .map_err(refused)?;
                xi.copy_from_slice(dx);
            } else {
                linalg::lower_mul::<T>(fac, n, xi, mid);
                linalg::solve_upper::<T>(fac, n, xi);
            }
            let mids = (mu, storage_at_mid(lanczos, at_mid, fac), xi, mid, dx);
            projected = midpoint(p, b, s, mids, held, (par, bands, &mut near), lanczos)?;
        }
    }
    Ok((iterations, projected))
}

/// Where the midpoint's mobility is assembled: `at_mid` by Lanczos, the factor's
/// blocks `fac` by Cholesky.
///
/// Why: the Cholesky factor's nine-scalar blocks are free once `L xi` and `L^-T xi`
/// are drawn, so a step by Cholesky (at most [`LANCZOS_CROSSOVER`] beads by default:
/// the mobility sits in cache, and bandwidth is no matter) assembles `mu(x~)` there and
/// needs no more storage. By Lanczos there is no factor: the midpoint has storage of
/// its own ([`Views::mu2`], sized by [`Layout::noise_sqrt`](crate::Layout::noise_sqrt)),
/// symmetric six-scalar blocks where the mobility's are (free space, a box), so that
/// the midpoint's products stream 48 bytes a pair in `f64` instead of 72 (with the
/// same bits, `linalg::block`), and nine-scalar blocks above a wall. It cannot share
/// `fac`, which holds the reduced copy of `mu` until the midpoint ([`reads_copy`]):
/// the kernel views blocks as scalars nowhere (that would need `unsafe`), and the
/// copy's slots and the symmetric blocks are of different types.
///
/// [`LANCZOS_CROSSOVER`]: crate::params::LANCZOS_CROSSOVER
fn storage_at_mid<'a, T: Real>(
    lanczos: bool,
    at_mid: MobMut<'a, T>,
    fac: &'a mut [T::M3],
) -> MobMut<'a, T> {
    if lanczos { at_mid } else { MobMut::Full(fac) }
}

/// The midpoint's half of [`kick`], from `mid = L xi` and `xi = L^-T xi` (any `L` with
/// `L L^T = mu` and the same draws: `E[(L xi) (L^-T xi)^T] = I` is what the drift
/// needs): `mid` becomes `x~ = x + sqrt(kT dt / 2) L xi`, `xi` is scaled by
/// `sqrt(2 kT dt)`, and `dx = P(x~) mu(x~) xi` (without `held`, unprojected), with
/// `mu(x~)` assembled into `at_mid` (empty matrix-free). Returns the projection's
/// iterations.
#[allow(clippy::type_complexity)]
fn midpoint<T: Real>(
    p: &Params<T>,
    b: Brownian<T>,
    s: &Start<'_, T>,
    (mu, mut at_mid, xi, mid, dx): (
        Mob<'_, T>,
        MobMut<'_, T>,
        &mut [T::V3],
        &mut [T::V3],
        &mut [T::V3],
    ),
    held: Option<Held<'_, '_, T>>,
    (par, bands, near): (&dyn Parallel, &mut [T::V3], &mut super::near::Store<'_, T>),
    lanczos: bool,
) -> Result<u32, StepError> {
    let (n, dt, kt) = (s.pos.len(), p.dt, b.temperature);
    let amplitude = (T::TWO * kt * dt).sqrt();
    let half = (kt * dt * T::HALF).sqrt();
    for (m, &r) in mid.iter_mut().zip(s.pos) {
        *m = r + *m * half;
    }
    for z in xi.iter_mut() {
        *z *= amplitude;
    }
    // dx = P(x~) mu(x~) xi: `at_mid` takes mu(x~), assembled and applied (matrix-free:
    // applied only), above the wall if there is one. Free draining's
    // mobility without a wall does not depend on the positions: mu(x~) is mu, and is
    // not assembled again.
    let mid = &*mid;
    let walls = !p.place().surfaces().is_empty();
    let same = p.hydro == Hydro::FreeDraining && !walls && !p.matrix_free;
    let mu_mid: Mob<'_, T> = if same {
        with_blocks!(mu, a => parallel::product::<T>(par, a, n, xi, dx, bands));
        mu
    } else if p.near_on() {
        // The near field's mobility at the midpoint: its drift supplies `div M_SD`.
        let assembled = at_mid.reborrow();
        super::near::assemble_apply(p, s.ewald, mid, s.radius, assembled, xi, dx, near)?;
        at_mid.into_ref()
    } else {
        let assembled = at_mid.reborrow();
        mobility_product(p, s.ewald, mid, s.radius, assembled, xi, dx, par, bands)?;
        at_mid.into_ref()
    };
    let Some(h) = held else {
        return Ok(0);
    };
    bond_vectors(h.bonds, mid, super::cell(p), h.grad_mid);
    h.kappa.fill(T::ZERO);
    let par = h.scratch.par;
    let metric = mobility_metric(
        p,
        s.ewald,
        h.bonds,
        mid,
        s.radius,
        mu_mid,
        h.grad_mid,
        T::ONE,
        h.disp,
        (par, &[]),
    );
    let solver = midpoint_solver(p, lanczos, h.bonds, h.grad_mid, dx);
    let problem = Problem::Velocities {
        bond: h.grad_mid,
        dt: T::ONE,
    };
    let stats = constraints::solve(problem, &metric, h.bonds, &solver, dx, h.kappa, h.scratch)?;
    Ok(stats.iterations)
}

/// The solver of the midpoint's projection `P(x~) mu(x~) xi` of the noise `dx` (before
/// projection). With the Lanczos root the noise is right only to the relative
/// tolerance `tol` of [`Params::lanczos`], so its projection is solved to the same
/// relative accuracy: to `tol` times the largest relative bond-length change `dx`
/// makes at `x~` (or the solver's tolerance if larger). What is left, a normal
/// component `tol` times smaller than the one removed, is removed by the step's own
/// projection up to `O(sqrt dt)` of itself. It saves about half the midpoint's
/// products (10 to 5 on a 1024-bead helix). With the exact Cholesky factor the
/// solver's tolerance stands.
fn midpoint_solver<T: Real>(
    p: &Params<T>,
    lanczos: bool,
    bonds: &[crate::bonds::Bond<T>],
    grad: &[T::V3],
    dx: &[T::V3],
) -> crate::constraints::Solver<T> {
    let mut solver = p.solver;
    if lanczos {
        let worst = bonds.iter().zip(grad).fold(T::ZERO, |w, (b, &g)| {
            let rate = T::dot(g, dx[b.i] - dx[b.j]).abs() / (b.length * b.length);
            w.max(rate)
        });
        if worst.is_finite() {
            solver.tolerance = solver.tolerance.max(worst * p.lanczos.tolerance);
        }
    }
    solver
}

/// A failed Lanczos square root as the step's error (at the mobility stage).
fn refused(e: LanczosError) -> StepError {
    e.into()
}

#[cfg(test)]
mod tests;
