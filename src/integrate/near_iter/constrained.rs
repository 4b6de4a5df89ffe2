//! `Overdamped` with constraints (bonds, pins, hard contacts, the wall's links) on the
//! iterative near field: the constraint move goes along the Stokesian dynamics mobility, `r' = r* + dt
//! M_SD,tt G^T lambda`, as the dense near step's does, with `M_SD` known only through
//! products. The contacts are the dense path's: the same active-set rounds
//! (`integrate/contacts.rs`, [`project_along`]), each round's solve the Krylov solve
//! with the one-sided rows inside it (`docs/CONTACTS.md`), along these products.
//!
//! The close pairs are found and factored once, at the start; every mobility the step
//! needs is then one product of that factored near field ([`Sd`]): the unconstrained
//! velocity, each product of the Krylov constraint solve (its metric's product,
//! [`crate::constraints::Products`]), and with [`Params::rotation`] the spins of the
//! total force at the end. The solve's entries (its band preconditioner, its curvature
//! bound) are read from the far field's translational blocks, the first `n` block rows
//! of the packed grand mobility assembled for the products (with a matrix-free far field,
//! free space's RPY blocks evaluated where they are read: `solve::far_metric`): an approximation that
//! changes how fast the solve converges, never where it ends, since every move it makes
//! is a product of `M_SD`. The band lacks the lubrication between bonded beads (their
//! relative mobility along the bond is several times smaller in `M_SD` than in the far
//! field), so the preconditioner adds each bond's squeeze resistance `K_k` (from its
//! pair's near-field correction): with `R_near` about `G^T K G`, the constraint matrix
//! is about `(A_far^-1 + K)^-1`, whose inverse `A_far^-1 + K` is the band's solve plus a
//! diagonal, positive definite. A contact is a close pair too (its squeeze resistance
//! at the minimum gap dominates its row). This halves the solve's products (to the
//! dense path's, whose band reads `M_SD`); adding pair mobility corrections to the
//! band's blocks instead doubles them (a bead's self-mobility is reduced once per close
//! neighbour, and the band's diagonal can turn negative).
//!
//! The sweep and Newton read every entry `D_l(p)` at every iteration: they get the
//! table of `M_SD`'s columns along the round's rows (one product a row, formed each
//! round, `Metric::Dense` as the dense path tabulates its stored `M_SD`), cheaper than
//! the Krylov solve's products where the rows are few; `Auto` resolves to Krylov
//! (`Params::solver_kind`). A wall link's squeeze resistance is its sphere's wall
//! correction along the normal (a pin has none). `Overdamped2` (`constrained2.rs`)
//! solves its velocity projections here too ([`Iterative::velocities`]), and the
//! thermal step its midpoint's (`noise.rs`). A product that does not converge ends the step with
//! [`StepError::NoConvergence`] at [`Stage::Mobility`](crate::Stage::Mobility), the
//! caller's state unchanged.

use super::solve::{self, At, FarField, far_metric};
use super::{Counts, Store, spins};
use crate::bonds::Bond;
use crate::constraints::{
    self, Metric, Problem, Products, Scratch, SolveStats, SolverKind, krylov_with,
};
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::integrate::contacts::{Along, Round, project_along};
use crate::integrate::{
    Start, StepReport, Sums, add_constraint_forces, add_flow, bond_vectors, cell, check_resolved,
    report, step_velocity,
};
use crate::params::Params;
use crate::real::Real;
use crate::workspace::Views;

/// The constraint solve's products: `M_SD` at the start ([`solve::at`]), counted.
pub(super) struct Sd<'a, 's, T: Real> {
    pub(super) at: &'a mut At<'s, T>,
    pub(super) p: &'a Params<T>,
    pub(super) counts: &'a mut Counts,
    /// Each row's squeeze resistance over `c dt |g|^2`: the preconditioner's diagonal
    /// (the rows of the round being solved).
    pub(super) stiff: &'a mut [T],
}

impl<T: Real> Products<T> for Sd<'_, '_, T> {
    /// `out = dt M_SD,tt G^T c`: the metric's forces, one product.
    fn apply(
        &mut self,
        metric: &Metric<'_, T>,
        bonds: &[Bond<T>],
        c: &[T],
        out: &mut [T::V3],
        _: &mut [T::V3],
    ) -> Result<(), StepError> {
        let fill = |f: &mut [T::V3]| match metric.forces(bonds, c, f) {
            true => Ok(()),
            false => Err(StepError::Unsupported(
                "the iterative near field's constraint products along a metric without forces",
            )),
        };
        self.at.velocities_of(self.p, fill, out, None, self.counts)
    }

    fn precondition(&self, r: &[T], z: &mut [T]) {
        for ((z, &r), &k) in z.iter_mut().zip(r).zip(self.stiff.iter()) {
            *z += k * r;
        }
    }
}

/// Each round of the projection ([`project_along`]: the bonds, and the contacts the
/// rounds hold) by the Krylov solve, its products [`Sd`]'s, its entries the far
/// field's `mu_tt` (the grand mobility's first `n` block rows); and the velocity
/// projection of `Overdamped2` ([`Iterative::velocities`]) the same way.
pub(super) struct Iterative<'a, 's, T: Real> {
    pub(super) sd: Sd<'a, 's, T>,
    /// The far field at the products' configuration: the solve's entries.
    pub(super) far: FarField<'s, T>,
    /// Where the products are: the squeeze resistances' configuration, and the
    /// step's sums.
    pub(super) spheres: (&'a [T::V3], &'a [T]),
    pub(super) ewald: Sums<'a, T>,
    /// The sweep's and Newton's table of `M_SD`'s columns (`n x rows`; empty for
    /// Krylov).
    pub(super) table: &'a mut [T::V3],
}

impl<T: Real> Along<T> for Iterative<'_, '_, T> {
    fn project(&mut self, p: &Params<T>, r: Round<'_, '_, T>) -> Result<SolveStats<T>, StepError> {
        let Round {
            rows,
            grad,
            x,
            lambda,
            scratch,
            nb,
            start,
        } = r;
        let problem = Problem::Positions {
            cell: cell(p),
            one_sided: nb,
            #[cfg(feature = "pins")]
            anchor: start,
            #[cfg(feature = "slit")]
            ceiling: crate::integrate::contacts::ceiling(p),
        };
        let _ = start; // Read only with the `pins` feature.
        // The chord matrix `2 G dt M G^T`: `c = 2`, scale `dt`.
        let scaled = (p.dt, T::TWO * p.dt);
        self.solve(p, problem, rows, grad, scaled, x, lambda, scratch)
    }
}

impl<'a, 's, T: Real> Iterative<'a, 's, T> {
    /// The solves along the products of `at` (at `spheres`, with the step's sums
    /// `ewald`), counted in `counts`; `stiff` the rows' preconditioner diagonal, `table`
    /// the sweep's and Newton's.
    pub(super) fn new(
        at: &'a mut At<'s, T>,
        p: &'a Params<T>,
        counts: &'a mut Counts,
        stiff: &'a mut [T],
        spheres: (&'a [T::V3], &'a [T]),
        ewald: Sums<'a, T>,
        table: &'a mut [T::V3],
    ) -> Self {
        Self {
            far: at.far_field(),
            sd: Sd {
                at,
                p,
                counts,
                stiff,
            },
            spheres,
            ewald,
            table,
        }
    }

    /// Solves `problem` over `rows` (vectors `grad`) along `scale M_SD,tt G^T` into
    /// `x` and `lambda` (from zero): the Krylov solve, or the sweep and Newton on the
    /// table of `M_SD`'s columns. `chord` is the chord matrix's factor `c scale`.
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &mut self,
        p: &Params<T>,
        problem: Problem<'_, T>,
        rows: &[Bond<T>],
        grad: &[T::V3],
        (scale, chord): (T, T),
        x: &mut [T::V3],
        lambda: &mut [T],
        scratch: &mut Scratch<'_, T>,
    ) -> Result<SolveStats<T>, StepError> {
        let n = x.len();
        let far = far_metric(self.far, self.spheres, (grad, scale), scratch.par);
        lambda.fill(T::ZERO);
        if p.solver.kind == SolverKind::Krylov {
            for ((k, b), &g) in self.sd.stiff.iter_mut().zip(rows).zip(grad) {
                *k = squeeze(p, (self.spheres, self.ewald), b, g, chord);
            }
            let ops = (&far, &mut self.sd);
            return krylov_with(problem, ops, rows, &p.solver, x, lambda, scratch);
        }
        // The sweep and Newton read every entry `D_l(p)`: the table of `M_SD`'s columns
        // along the rows, one product a row (`Metric::Dense`, as the dense path
        // tabulates its stored `M_SD`).
        let table = self.table.get_mut(..n * rows.len()).ok_or(TABLE)?;
        for (l, column) in table.chunks_exact_mut(n).enumerate() {
            lambda[l] = T::ONE;
            let done = self.sd.apply(&far, rows, lambda, column, &mut []);
            lambda[l] = T::ZERO;
            done?;
        }
        let metric = Metric::Dense {
            disp: table,
            n,
            grad,
        };
        constraints::solve(problem, &metric, rows, &p.solver, x, lambda, scratch)
    }

    /// `Overdamped2`'s projected velocity at the products' configuration (the dense
    /// step's `projected_velocity`): `u = U_inf + M_SD,tt F` (checked to resolve a
    /// step where `judge`), then the bonds' length rates held at zero along
    /// `M_SD,tt G^T` (`G` the bond vectors there, into `grad`), the multipliers into
    /// `kappa`: the constraint forces `G^T kappa`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn velocities(
        &mut self,
        p: &Params<T>,
        bonds: &[Bond<T>],
        force: &[T::V3],
        (grad, kappa): (&mut [T::V3], &mut [T]),
        scratch: &mut Scratch<'_, T>,
        u: &mut [T::V3],
        judge: bool,
    ) -> Result<SolveStats<T>, StepError> {
        let pos = self.spheres.0;
        self.sd.at.velocities(p, force, u, None, self.sd.counts)?;
        add_flow(p, pos, u);
        if judge {
            check_resolved(pos, u, p.dt)?;
        }
        self.hold_rates(p, bonds, (grad, kappa), scratch, u, p.dt)
    }

    /// `u` projected at the products' configuration: the bonds' length rates held at
    /// zero along `M_SD,tt G^T` (`G` the bond vectors there, into `grad`; the
    /// multipliers into `kappa`), the residual scaled by `dt` (`Problem::Velocities`).
    pub(super) fn hold_rates(
        &mut self,
        p: &Params<T>,
        bonds: &[Bond<T>],
        (grad, kappa): (&mut [T::V3], &mut [T]),
        scratch: &mut Scratch<'_, T>,
        u: &mut [T::V3],
        dt: T,
    ) -> Result<SolveStats<T>, StepError> {
        bond_vectors(bonds, self.spheres.0, cell(p), grad);
        let problem = Problem::Velocities { bond: grad, dt };
        // The chord matrix `G M G^T`: `c = 1`, scale 1.
        let unit = (T::ONE, T::ONE);
        self.solve(p, problem, bonds, grad, unit, u, kappa, scratch)
    }
}

/// What a constrained step's last projection did: its solve, and the contacts, the
/// wall's links and the active-set rounds it held.
pub(super) type Held<T> = (SolveStats<T>, u32, u32, u32);

/// The projection's [`Held`] of `r`.
pub(super) fn held<T: Real>(r: &crate::integrate::contacts::Projected<'_, T>) -> Held<T> {
    (r.stats, r.contacts, r.wall_contacts, r.rounds)
}

/// A constrained step's report: the near field's `counts`, the last projection's
/// `held`, a midpoint projection's `velocity_iterations`, the multipliers of `bonds`.
pub(super) fn held_report<T: Real>(
    counts: &Counts,
    (stats, contacts, wall_contacts, rounds): Held<T>,
    velocity_iterations: u32,
    bonds: &[Bond<T>],
    lambda: &[T],
) -> StepReport<T> {
    StepReport {
        near_pairs: counts.pairs,
        near_products: counts.products,
        near_iterations: counts.iterations,
        contacts,
        wall_contacts,
        contact_rounds: rounds,
        ..report(stats, velocity_iterations, bonds, lambda)
    }
}

/// Sphere centres and radii.
type Spheres<'a, T> = (&'a [<T as Real>::V3], &'a [T]);

const TABLE: StepError =
    StepError::Unsupported("the iterative near field's sweep or Newton without its table");

/// Bond `b`'s squeeze resistance `d^T (R_ii + R_jj - R_ij - R_ji) d / 4` (`d` along the
/// bond) from its pair's near-field correction, or a wall link's `d^T R_ii d` from its
/// sphere's wall correction (the sphere against the fixed wall), at `spheres` (the
/// step's sums `ew`), over `chord |g|^2` (`chord = c scale`, the chord matrix's factor).
fn squeeze<T: Real>(
    p: &Params<T>,
    (spheres, ew): (Spheres<'_, T>, Sums<'_, T>),
    b: &Bond<T>,
    g: T::V3,
    chord: T,
) -> T {
    let (Some(nf), Ok(far)) = (p.near, crate::integrate::near::far(p, ew)) else {
        return T::ZERO;
    };
    let (eta, (pos, radius)) = (p.viscosity, spheres);
    let (m, share) = match (b.is_wall(), far.wall()) {
        (true, Some(h)) => match crate::stokesian::wall_correction(eta, h, spheres, nf, b.i) {
            Ok(Some((r, _))) => (r[0][0], T::ONE),
            _ => return T::ZERO,
        },
        _ if b.one_sphere() => return T::ZERO,
        _ => match crate::stokesian::pair_correction(eta, far, pos, radius, nf, (b.i, b.j)) {
            Ok(Some(r)) => (r[0][0] + r[1][1] - r[0][1] - r[1][0], T::from_f64(0.25)),
            _ => return T::ZERO,
        },
    };
    let g2 = T::norm2(g);
    if !(g2 > T::ZERO) {
        return T::ZERO;
    }
    let d = g * (T::ONE / g2.sqrt());
    let k = T::dot(d, m * d) * share;
    (k / (chord * g2)).max(T::ZERO)
}

/// `Overdamped` with bonds, pins and contacts on the iterative near field: `r* = r +
/// dt U(r)`, `U = U_inf + M_SD,tt F`, projected onto the constraints along `dt M_SD,tt
/// G^T` by the Krylov solve, the contacts found by the active-set rounds of the dense
/// path (`integrate/contacts.rs`); the spins `Omega_inf + M_SD,rt (F + G^T lambda)`.
pub(in crate::integrate) fn overdamped<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    s: &Start<'_, T>,
    bonds: &[Bond<T>],
    v: Views<'_, T>,
    ext: &mut E,
) -> Result<StepReport<T>, StepError> {
    let (n, dt) = (s.pos.len(), p.dt);
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
    // Room for every row the step may solve: the bonds and the contacts' capacity.
    let rows = p.constraints(n, bonds.len());
    let (reals, stiff) = near.1.split_at_mut(near.1.len().saturating_sub(rows));
    let mut store = Store::new((near.0, reals), near_iter);
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    // The far field at the start, and the close pairs factored once.
    solve::at(p, s.ewald, (s.pos, s.radius), &mut store, |at| {
        let far = at.far_field();
        let mut counts = Counts::default();
        let sd = Sd {
            at,
            p,
            counts: &mut counts,
            stiff,
        };
        sd.at.velocities(p, force, u, None, sd.counts)?;
        add_flow(p, s.pos, u);
        check_resolved(s.pos, u, dt)?;
        let free = |x: &mut [T::V3]| {
            for i in 0..n {
                x[i] = s.pos[i] + u[i] * dt;
            }
        };
        // The projection: entries from the far field's `mu_tt`, moves from `M_SD`.
        let mut along = Iterative {
            sd,
            far,
            spheres: (s.pos, s.radius),
            ewald: s.ewald,
            table: disp,
        };
        let views = (links, &mut *grad, &mut *lambda, &mut scratch);
        let r = project_along(
            p,
            bonds,
            (s.pos, s.radius),
            views,
            new_pos,
            free,
            &mut along,
        )?;
        let sd = &mut along.sd;
        step_velocity(s.pos, new_pos, dt, new_vel);
        add_constraint_forces(r.held, grad, lambda, force);
        if p.rotation {
            sd.at
                .velocities(p, force, u, Some(&mut *new_omega), sd.counts)?;
        }
        spins(p, new_omega);
        Ok(held_report(sd.counts, held(&r), 0, bonds, lambda))
    })
}
