//! The periodic box's part of a step's checks: the box against the kernel's features,
//! the wall, the hydrodynamic level, the radii and the bonds; then the step's sums
//! (Ewald, or PSE with its own conditions), derived here once and held for every
//! product, assembly and metric block of the step. Apart from the other input checks
//! because it is the one check that hands something on, and the mobility alone
//! (`integrate::geometry`) asks it too ([`check_box`]).

use crate::bonds::Bond;
use crate::cell::Periodic;
use crate::error::{ParticleError, StepError};
use crate::integrate::stages::{HeldSums, PSE_ASSEMBLED};
use crate::mobility::Hydro;
use crate::params::{Method, Params};
use crate::particles::State;
use crate::real::Real;

/// Checks the periodic box: every radius, the box itself ([`check_box`]), every bond
/// (and FENE's maximum extension) shorter than half the smallest edge, so that the
/// minimum image of a bond at its length is the bond; then the step's sums, Ewald or PSE
/// ([`Params::pse`]), derived here once and held for every product, assembly and metric
/// block of the step (`None` without a box, or with free draining).
pub(super) fn check_periodic<T: Real>(
    p: &Params<T>,
    state: &State<'_, T>,
    bonds: &[Bond<T>],
) -> Result<HeldSums<T>, StepError> {
    let Some(c) = p.place().cell() else {
        return fast_sums(p, state, bonds.len());
    };
    let summed = box_geometry(p, state.radius)?;
    if let Some(particle) = unresolved(state.pos, state.radius) {
        return Err(ParticleError::Unresolved { particle }.into());
    }
    let [x, y, z] = c.size();
    let half = x.min(y).min(z) * T::HALF;
    if let Some(bond) = bonds.iter().position(|b| !(b.length < half)) {
        return Err(crate::error::BondError::BadLength { bond }.into());
    }
    if p.method == Method::Springs && p.fene.is_some_and(|q| !(q < half)) {
        return Err(StepError::BadParameter(
            "fene (maximum extension below half the periodic box's smallest edge)",
        ));
    }
    match (summed, p.pse) {
        (None, _) => Ok(None),
        (Some(c), None) => ewald_sums(c, state.radius),
        (Some(c), Some(tol)) => pse_sums(p, c, state, bonds.len(), tol),
    }
}

/// The first sphere with a coordinate whose spacing in the precision (`eps |x|`, within
/// a factor 2 of its ulp) reaches half its radius: there the minimum image
/// `x - round(x / L) L` keeps nothing of where the sphere is in its box, and every pair
/// geometry (the mobility's blocks, the overlap checks) would be rounding. Positions are
/// not wrapped into the box, so this bounds how far they may be carried, not where they
/// are given; a scene this far out is refused by name instead of by the nonsense its
/// first pair block would report (nested spheres).
pub(in crate::integrate) fn unresolved<T: Real>(pos: &[T::V3], radius: &[T]) -> Option<usize> {
    pos.iter().zip(radius).position(|(&r, &a)| {
        let [x, y, z] = T::xyz(r);
        !(T::EPSILON * x.abs().max(y.abs()).max(z.abs()) < a * T::HALF)
    })
}

/// The box's part of [`check_periodic`] that needs no bonds (the mobility alone,
/// `integrate::geometry`, asks it too), with the box's Ewald sums.
pub(in crate::integrate) fn check_box<T: Real>(
    p: &Params<T>,
    radius: &[T],
) -> Result<HeldSums<T>, StepError> {
    match box_geometry(p, radius)? {
        Some(c) => ewald_sums(c, radius),
        None => Ok(None),
    }
}

/// The kernel built with its `periodic` feature; no wall (its image system is free
/// space's); not the Oseen level (the Ewald sum is RPY's); every radius below half the
/// smallest edge. The box when its images interact (not with free draining, which has
/// no pair blocks).
fn box_geometry<T: Real>(p: &Params<T>, radius: &[T]) -> Result<Option<Periodic<T>>, StepError> {
    let Some(c) = p.place().cell() else {
        return Ok(None);
    };
    if !cfg!(feature = "periodic") {
        return Err(StepError::Unsupported(
            "a periodic box: the kernel was built without its `periodic` feature",
        ));
    }
    if p.place().wall().is_some() {
        return Err(StepError::Unsupported("a periodic box with a wall"));
    }
    if p.hydro == Hydro::Oseen {
        return Err(StepError::Unsupported(
            "a periodic box with Hydro::Oseen (the Ewald sum is RPY's)",
        ));
    }
    let [x, y, z] = c.size();
    let half = x.min(y).min(z) * T::HALF;
    if let Some(particle) = radius.iter().position(|&a| !(a < half)) {
        return Err(StepError::Particle(ParticleError::BadRadius { particle }));
    }
    Ok((p.hydro != Hydro::FreeDraining).then_some(c))
}

/// The step's Ewald parameters.
#[cfg(feature = "periodic")]
fn ewald_sums<T: Real>(c: Periodic<T>, radius: &[T]) -> Result<HeldSums<T>, StepError> {
    Ok(Some(crate::geometry::Held::ewald(c, radius)?))
}

/// Without the `periodic` feature the box was refused above.
#[cfg(not(feature = "periodic"))]
fn ewald_sums<T: Real>(_: Periodic<T>, _: &[T]) -> Result<HeldSums<T>, StepError> {
    Ok(None)
}

/// PSE ([`Params::pse`]): products only, so the step must need nothing else (matrix
/// free; with constraints the Krylov solver; no Cholesky noise, which `matrix_free`
/// refuses already); then its parameters from the tolerance.
fn pse_sums<T: Real>(
    p: &Params<T>,
    c: Periodic<T>,
    state: &State<'_, T>,
    bonds: usize,
    tol: f64,
) -> Result<HeldSums<T>, StepError> {
    if !cfg!(feature = "pse") {
        return Err(StepError::Unsupported(
            "PSE (Params::pse): the kernel was built without its `pse` feature",
        ));
    }
    let rotation = "PSE with rotation (its rt and rr products are not built: Ewald sums them)";
    // With the iterative near field the spins are its own, from PSE's grand product
    // (`integrate/near_iter/solve.rs`): rotation is served there.
    let p = &Params {
        rotation: p.rotation && !(p.near_on() && p.matrix_free),
        ..*p
    };
    products_only(p, state.len(), bonds, (PSE_ASSEMBLED, rotation))?;
    #[cfg(feature = "pse")]
    return Ok(Some(crate::geometry::Held::pse(c, state.radius, tol)?));
    #[cfg(not(feature = "pse"))]
    {
        let _ = (c, tol);
        Ok(None)
    }
}

/// A fast product gives products only: the step must need nothing else (matrix free;
/// with constraints the Krylov solver; no Cholesky noise, which `matrix_free` refuses
/// already), else `assembled`; no rotation (translation products only), else `rotation`.
fn products_only<T: Real>(
    p: &Params<T>,
    n: usize,
    bonds: usize,
    (assembled, rotation): (&'static str, &'static str),
) -> Result<(), StepError> {
    let constrained = p.method != Method::Springs && p.constraints(n, bonds) > 0;
    let krylov = p.solver_kind(n, bonds) == crate::constraints::SolverKind::Krylov;
    if !p.matrix_free || (constrained && !krylov) {
        return Err(StepError::Unsupported(assembled));
    }
    if p.rotation {
        return Err(StepError::Unsupported(rotation));
    }
    Ok(())
}

/// Why the fast free-space product cannot serve a stage that needs the assembled
/// mobility.
const FAST_ASSEMBLED: &str = "the fast free-space product (Params::pse without a box) where \
     the step needs the assembled mobility (without matrix_free, Cholesky noise, the Sweep \
     or Newton solver, RattleStable): it gives products only";

/// Free space with [`Params::pse`]: the fast free-space product (kernel feature
/// `fast-free`), RPY only, products only, no wall; its parameters derived
/// from the cloud at the step's start (`geometry/free/fast.rs`). `None` without `pse`, and
/// with free draining (no pair blocks to replace).
fn fast_sums<T: Real>(
    p: &Params<T>,
    state: &State<'_, T>,
    bonds: usize,
) -> Result<HeldSums<T>, StepError> {
    let Some(tol) = p.pse else {
        return Ok(None);
    };
    if !p.place().surfaces().is_empty() {
        return Err(StepError::Unsupported(
            "the fast free-space product (Params::pse without a box) above a wall",
        ));
    }
    if p.hydro == Hydro::FreeDraining {
        return Ok(None);
    }
    if !cfg!(feature = "fast-free") {
        return Err(StepError::Unsupported(
            "the fast free-space product (Params::pse without a box): the kernel was built without its `fast-free` feature",
        ));
    }
    if p.hydro == Hydro::Oseen {
        return Err(StepError::Unsupported(
            "the fast free-space product with Hydro::Oseen (it is RPY's)",
        ));
    }
    // Rotation is served: the spins come from the grand product (`geometry/free/fast.rs`),
    // as does the iterative near field's far field (`integrate/near_iter/solve.rs`).
    let unrotated = Params {
        rotation: false,
        ..*p
    };
    products_only(&unrotated, state.len(), bonds, (FAST_ASSEMBLED, ""))?;
    #[cfg(feature = "fast-free")]
    return Ok(Some(crate::geometry::Held::Fast(
        crate::geometry::free::fast::params(
            (tol, super::super::fast::grand(p)),
            state.pos,
            state.radius,
            [usize::MAX; 2],
        )?,
    )));
    #[cfg(not(feature = "fast-free"))]
    {
        let _ = tol;
        Ok(None)
    }
}
