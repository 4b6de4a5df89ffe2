//! `Overdamped` with constraints (bonds, pins) on the iterative near field: the
//! constraint move goes along the Stokesian dynamics mobility, `r' = r* + dt M_SD,tt
//! G^T lambda`, as the dense near step's does, with `M_SD` known only through products.
//!
//! The close pairs are found and factored once, at the start; every mobility the step
//! needs is then one product of that factored near field ([`Sd`]): the unconstrained
//! velocity, each product of the Krylov constraint solve (its metric's product,
//! [`crate::constraints::Products`]), and with [`Params::rotation`] the spins of the
//! total force at the end. The solve's entries (its band preconditioner, its curvature
//! bound) are read from the far field's translational blocks, the first `n` block rows
//! of the packed grand mobility assembled for the products: an approximation that
//! changes how fast the solve converges, never where it ends, since every move it makes
//! is a product of `M_SD`.
//!
//! Only the Krylov solver runs here: the sweep and Newton read `D_l(p)` for every bond
//! at every iteration (a table of `n x B` entries, `B` products of `M_SD` to form), and
//! are refused by `near::check`, typed, as are `Overdamped2`, contacts, the wall and
//! noise. A product that does not converge ends the step with
//! [`StepError::NoConvergence`] at [`Stage::Mobility`](crate::Stage::Mobility), the
//! caller's state unchanged.

use super::{Counts, STORAGE, Store, error, spins, tri2};
use crate::bonds::Bond;
use crate::constraints::{Metric, Problem, Products, krylov_with};
use crate::error::StepError;
use crate::forces::{self, ExternalForce};
use crate::integrate::{
    Start, StepReport, add_constraint_forces, add_flow, bond_vectors, cell, check_resolved, report,
    step_velocity,
};
use crate::linalg::{Mob, tri};
use crate::params::Params;
use crate::real::Real;
use crate::stokesian::iterative::{Solver, Storage, packed_product};
use crate::workspace::Views;

/// The factored near field at the start and the far field's packed grand mobility:
/// `(U, W) = M_SD (F, 0)` by conjugate gradients, as often as the step asks.
struct Sd<'s, 'v, T: Real> {
    solver: Solver<'s, T>,
    packed: &'s [T::M3],
    /// The product's forces then torques, and its velocities then spins (`2n` each).
    fin: &'v mut [T::V3],
    out: &'v mut [T::V3],
    tol: T,
    cap: u32,
    counts: Counts,
}

impl<T: Real> Sd<'_, '_, T> {
    /// `out = M_SD (f, 0)` from the forces in `fin[..n]` (`fin[n..]` zero).
    fn run(&mut self) -> Result<(), StepError> {
        let (n, packed) = (self.fin.len() / 2, self.packed);
        let mut far = |x: &[T::V3], y: &mut [T::V3]| {
            packed_product::<T>(packed, n, x, y);
            Ok(())
        };
        let (tol, cap) = (self.tol, self.cap);
        let r = self
            .solver
            .product(&mut far, self.fin, self.out, tol, cap)
            .map_err(error)?;
        let c = &mut self.counts;
        if c.products == 0 {
            c.pairs = u32::try_from(r.pairs).unwrap_or(u32::MAX);
        }
        c.products += 1;
        c.iterations = c.iterations.saturating_add(r.iterations);
        Ok(())
    }

    /// `u = M_SD,tt f` and, where `w` is given, `w = M_SD,rt f`.
    fn velocities(
        &mut self,
        f: &[T::V3],
        u: &mut [T::V3],
        w: Option<&mut [T::V3]>,
    ) -> Result<(), StepError> {
        let n = f.len();
        self.fin[..n].copy_from_slice(f);
        self.run()?;
        u.copy_from_slice(&self.out[..n]);
        if let Some(w) = w {
            w.copy_from_slice(&self.out[n..]);
        }
        Ok(())
    }
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
        let n = out.len();
        if !metric.forces(bonds, c, &mut self.fin[..n]) {
            return Err(StepError::Unsupported(
                "the iterative near field's constraint products along a metric without forces",
            ));
        }
        self.run()?;
        out.copy_from_slice(&self.out[..n]);
        Ok(())
    }
}

/// `Overdamped` with bonds (and pins) on the iterative near field: `r* = r + dt U(r)`,
/// `U = U_inf + M_SD,tt F`, projected onto the constraints along `dt M_SD,tt G^T`
/// by the Krylov solve; the spins `Omega_inf + M_SD,rt (F + G^T lambda)`.
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
        near,
        near_iter,
        ..
    } = v;
    let Some(nf) = p.near else {
        return Err(StepError::Unsupported(
            "the near field's mobility without Params::near",
        ));
    };
    let store = Store::new(near, near_iter);
    forces::external(p, s.pos, s.radius, s.density, ext, force)?;
    // The far field at the start, and the close pairs factored once.
    let far = crate::integrate::near::far(p, s.ewald)?;
    let packed = store.packed.get_mut(..tri2(n)).ok_or(STORAGE)?;
    far.assemble_grand(p.viscosity, s.pos, s.radius, packed)
        .map_err(error)?;
    let (io, field) = store.vectors.split_at_mut_checked(4 * n).ok_or(STORAGE)?;
    let (fin, out) = io.split_at_mut(2 * n);
    fin[n..].fill(T::v3(T::ZERO, T::ZERO, T::ZERO));
    let cap = crate::params::NEAR_PAIRS_PER_SPHERE * n;
    let (pairs, cells) = store.indices.split_at_mut_checked(2 * cap).ok_or(STORAGE)?;
    let storage = Storage {
        pairs: pairs.as_chunks_mut::<2>().0,
        reals: store.reals,
        field,
        cells,
    };
    let solver = Solver::new(p.viscosity, far, s.pos, s.radius, nf, storage).map_err(error)?;
    let packed = &*packed;
    let mut sd = Sd {
        solver,
        packed,
        fin,
        out,
        tol: p.solver.tolerance,
        cap: p.solver.max_iterations,
        counts: Counts::default(),
    };
    sd.velocities(force, u, None)?;
    add_flow(p, s.pos, u);
    check_resolved(s.pos, u, dt)?;
    for i in 0..n {
        new_pos[i] = s.pos[i] + u[i] * dt;
    }
    // The projection: entries from the far field's `mu_tt` (the grand mobility's first
    // `n` block rows), moves from `M_SD`.
    bond_vectors(bonds, s.pos, cell(p), grad);
    let grad = &*grad;
    let metric = Metric::Mobility {
        mu: Mob::Full(&packed[..tri(n)]),
        grad,
        scale: dt,
        par: scratch.par,
        compact: None,
    };
    let problem = Problem::Positions {
        cell: cell(p),
        one_sided: usize::MAX,
        #[cfg(feature = "pins")]
        anchor: s.pos,
    };
    lambda.fill(T::ZERO);
    let (solver, ops) = (&p.solver, (&metric, &mut sd));
    let stats = krylov_with(problem, ops, bonds, solver, new_pos, lambda, &mut scratch)?;
    step_velocity(s.pos, new_pos, dt, new_vel);
    add_constraint_forces(bonds, grad, lambda, force);
    if p.rotation {
        sd.velocities(force, u, Some(&mut *new_omega))?;
    }
    spins(p, new_omega);
    Ok(StepReport {
        near_pairs: sd.counts.pairs,
        near_products: sd.counts.products,
        near_iterations: sd.counts.iterations,
        ..report(stats, 0, bonds, lambda)
    })
}
