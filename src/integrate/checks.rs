//! The first and third stages of a step: checking the inputs (parameters, particles,
//! bonds, thermal noise, contacts) before anything is touched, and accepting the
//! candidate state before it is committed.

use crate::bonds::Bond;
use crate::cell::{Periodic, image};
use crate::cell_list::CellList;
use crate::constraints::Solver;
use crate::error::{ParticleError, StepError};
use crate::mobility::Hydro;
use crate::parallel::{BANDS, Parallel, band_start, bands, map_bands};
use crate::params::{Method, Params};
use crate::particles::{State, sphere_volume};
use crate::real::Real;

use super::stages::HeldSums;

/// The thermal settings when this step has noise (`brownian` with `kT > 0`), after
/// checking that the temperature is valid and the combination is implemented.
pub(super) fn check_thermal<T: Real>(
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
    if !matches!(
        p.method,
        Method::Overdamped | Method::Springs | Method::RattleStable
    ) {
        return Err(StepError::Unsupported(
            "thermal noise with Rattle or Overdamped2 (Overdamped, Springs and RattleStable take it)",
        ));
    }
    if p.method == Method::RattleStable && p.noise_sqrt == crate::params::NoiseSqrt::Lanczos {
        return Err(StepError::Unsupported(
            "noise_sqrt = Lanczos with RattleStable (it factors its drag densely: Cholesky only)",
        ));
    }
    if p.matrix_free && p.noise_sqrt == crate::params::NoiseSqrt::Cholesky {
        return Err(StepError::Unsupported(
            "a Cholesky factor of the noise without a stored mobility (matrix_free: use Lanczos or Auto)",
        ));
    }
    let l = p.lanczos;
    if p.noise_sqrt != crate::params::NoiseSqrt::Cholesky
        && (l.max_iterations == 0 || !(l.tolerance > T::ZERO && l.tolerance.is_finite()))
    {
        return Err(StepError::BadParameter(
            "lanczos (tolerance finite and > 0, max_iterations > 0)",
        ));
    }
    if !has_generator {
        return Err(StepError::Unsupported(
            "thermal noise without a generator (State::noise / ParticleSet::noise)",
        ));
    }
    Ok(Some(b))
}

/// Checks the wall: a finite height; the kernel built with its `wall` feature (the
/// wall's mobility, `mobility::wall`) and its `contacts` feature (the wall is held as
/// a one-sided constraint); a method whose position projection holds it (Overdamped,
/// Overdamped2); and no sphere below its contact height `height + a_i` (beyond the
/// contacts' tolerance: the last step's wall contacts end within it).
pub(super) fn check_wall<T: Real>(p: &Params<T>, state: &State<'_, T>) -> Result<(), StepError> {
    let Some(w) = p.wall else {
        return Ok(());
    };
    if !w.height.is_finite() {
        return Err(StepError::BadParameter("wall.height (finite)"));
    }
    if !cfg!(feature = "wall") {
        return Err(StepError::Unsupported(
            "a wall: the kernel was built without its `wall` feature",
        ));
    }
    if !cfg!(feature = "contacts") {
        return Err(StepError::Unsupported(
            "a wall: the kernel was built without its `contacts` feature",
        ));
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return Err(StepError::Unsupported(
            "a wall with a method other than Overdamped or Overdamped2",
        ));
    }
    match below_wall(state.pos, state.radius, w.height, p.solver.tolerance) {
        Some(particle) => Err(ParticleError::BelowWall { particle }.into()),
        None => Ok(()),
    }
}

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
    let Some(c) = p.periodic else {
        return Ok(None);
    };
    let summed = box_geometry(p, state.radius)?;
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

/// The box's part of [`check_periodic`] that needs no bonds (the mobility alone,
/// `integrate::geometry`, asks it too), with the box's Ewald sums.
pub(super) fn check_box<T: Real>(p: &Params<T>, radius: &[T]) -> Result<HeldSums<T>, StepError> {
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
    let Some(c) = p.periodic else {
        return Ok(None);
    };
    if !cfg!(feature = "periodic") {
        return Err(StepError::Unsupported(
            "a periodic box: the kernel was built without its `periodic` feature",
        ));
    }
    if p.wall.is_some() {
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
    let e = super::periodic::ewald(c, radius)?;
    Ok(Some(super::periodic::Held::Ewald(e)))
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
    let constrained = p.method != Method::Springs && p.constraints(state.len(), bonds) > 0;
    let krylov = p.solver_kind(state.len(), bonds) == crate::constraints::SolverKind::Krylov;
    if !p.matrix_free || (constrained && !krylov) {
        return Err(StepError::Unsupported(super::stages::PSE_ASSEMBLED));
    }
    if p.rotation {
        return Err(StepError::Unsupported(
            "PSE with rotation (its rt and rr products are not built: Ewald sums them)",
        ));
    }
    #[cfg(feature = "pse")]
    return Ok(Some(super::periodic::Held::Pse(super::periodic::pse(
        c,
        state.radius,
        tol,
    )?)));
    #[cfg(not(feature = "pse"))]
    {
        let _ = (c, tol);
        Ok(None)
    }
}

/// The first sphere whose centre is below `height + a_i (1 - 2 tol)`, less the
/// rounding of the numbers compared (4 epsilons of `|z| + |height| + a_i`): far from
/// the origin a sphere put or held at contact is off by an ulp of its coordinates,
/// which can exceed `2 tol a_i`.
fn below_wall<T: Real>(pos: &[T::V3], radius: &[T], height: T, tol: T) -> Option<usize> {
    let reach = T::ONE - tol * T::TWO;
    let ulps = T::EPSILON * T::from_f64(4.0);
    pos.iter().zip(radius).position(|(&r, &a)| {
        let z = T::xyz(r)[2];
        let rounding = (z.abs() + height.abs() + a) * ulps;
        !(z - height + rounding >= a * reach)
    })
}

/// Stage 1 of a step: every check of its inputs, in order; the thermal settings when
/// the step has noise, and the step's Ewald parameters in a box.
pub(super) fn check_all<T: Real>(
    state: &State<'_, T>,
    bonds: &[Bond<T>],
    p: &Params<T>,
    has_generator: bool,
) -> Result<(Option<crate::params::Brownian<T>>, HeldSums<T>), StepError> {
    check_inputs(state, bonds, p)?;
    let thermal = check_thermal(p, has_generator)?;
    super::pins::check(p, bonds, state.pos, state.radius, thermal.is_some())?;
    check_contacts(p, thermal.is_some())?;
    // The box first: a box with a wall is refused as such, not by the wall's check.
    let sums = check_periodic(p, state, bonds)?;
    check_wall(p, state)?;
    Ok((thermal, sums))
}

/// Refuses contacts where they are not implemented.
pub(super) fn check_contacts<T: Real>(p: &Params<T>, thermal: bool) -> Result<(), StepError> {
    let Some(c) = p.contacts else {
        return Ok(());
    };
    if !cfg!(feature = "contacts") {
        return Err(StepError::Unsupported(
            "contacts: the kernel was built without its `contacts` feature",
        ));
    }
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
    Ok(())
}

/// Cheap checks (O(N + B)); pair checks happen in assembly and in [`accept`].
pub(super) fn check_inputs<T: Real>(
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
        bad(
            p.fene.is_none_or(|q| q > T::ZERO && (q * q).is_finite()),
            "fene (maximum extension > 0, its square finite)",
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
        if !(state.radius[i] >= T::MIN_POSITIVE) {
            return Err(ParticleError::BadRadius { particle: i }.into());
        }
        if state.density[i] < T::ZERO {
            return Err(ParticleError::BadDensity { particle: i }.into());
        }
        if inertial && sphere_volume(state.radius[i]) * state.density[i] <= T::ZERO {
            return Err(ParticleError::Massless { particle: i }.into());
        }
    }
    let springs = p.method == Method::Springs;
    for (bond, b) in bonds.iter().enumerate() {
        crate::bonds::check_one(bond, b, n)?;
        // A constraint of length zero has no direction to hold.
        if b.length == T::ZERO && !springs {
            return Err(crate::error::BondError::BadLength { bond }.into());
        }
    }
    Ok(())
}

/// Finite, no nested spheres, no overlap unless allowed (squared distances: no sqrt;
/// the minimum image in a periodic box), no sphere below the wall. With contacts, spheres touch to within the solver's
/// tolerance, which is accepted; so do spheres on the wall. The pair check
/// runs in the mobility's bands through `par` (it was the step's largest serial part,
/// ~4 % at N = 4096 on one thread) and reports the pair a single pass in order meets
/// first, on any number of threads: over every pair, or from
/// [`CELLS_MIN`](crate::cell_list::CELLS_MIN) spheres on over the neighbours a cell list
/// in `cells` finds ([`crate::cell_list`], cells as wide as the largest contact
/// distance), which is the same pair.
pub(super) fn accept<T: Real>(
    pos: &[T::V3],
    vel: &[T::V3],
    omega: &[T::V3],
    radius: &[T],
    p: &Params<T>,
    par: &dyn Parallel,
    cells: &mut [usize],
) -> Result<(), StepError> {
    for i in 0..pos.len() {
        if !(T::v3_is_finite(pos[i]) && T::v3_is_finite(vel[i]) && T::v3_is_finite(omega[i])) {
            return Err(StepError::NonFinite { particle: i });
        }
    }
    if let Some(w) = p.wall
        && let Some(particle) = below_wall(pos, radius, w.height, p.solver.tolerance)
    {
        return Err(ParticleError::BelowWall { particle }.into());
    }
    let n = pos.len();
    // Without the `cells` feature (firmware) this is the all-pairs check alone.
    let list = if cfg!(feature = "cells") && n >= crate::cell_list::CELLS_MIN {
        let cutoff = crate::cell_list::largest(radius) * T::TWO;
        CellList::build(pos, super::cell(p).as_ref(), cutoff, cells)
    } else {
        None
    };
    let first = if let Some((list, _)) = list {
        let rows = |t: usize| n * t / BANDS..n * (t + 1) / BANDS;
        match bands(n) {
            1 => first_near(pos, radius, p, &list, 0..n),
            _ => map_bands(par, n, |t| first_near(pos, radius, p, &list, rows(t)))
                .into_iter()
                .flatten()
                .flatten()
                .min(),
        }
    } else if bands(n) == 1 {
        first_clash(pos, radius, p, 0..n)
    } else {
        // Each band's first pair in the order `(i, j)`, `i < j`, then the first of those.
        let found = map_bands(par, n, |t| {
            first_clash(pos, radius, p, band_start(n, t)..band_start(n, t + 1))
        });
        found.into_iter().flatten().flatten().min()
    };
    match first {
        Some((i, j)) => Err(StepError::Overlap { i, j }),
        None => Ok(()),
    }
}

/// The first pair `(i, j)`, `i < j`, in that order, of nested (or, unless allowed,
/// overlapping) spheres among the pairs whose later sphere `j` is in `rows`.
fn first_clash<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    p: &Params<T>,
    rows: core::ops::Range<usize>,
) -> Option<(usize, usize)> {
    let allow_overlap = p.allow_overlap;
    let cell = super::cell(p);
    let reach = match p.contacts {
        Some(_) => T::ONE - p.solver.tolerance * T::TWO,
        None => T::ONE,
    };
    let mut first: Option<(usize, usize)> = None;
    for j in rows {
        let (pj, aj) = (pos[j], radius[j]);
        // A later row can only improve on `first` with a smaller `i`.
        let end = first.map_or(j, |(i, _)| i.min(j));
        for (i, (&pi, &ai)) in pos[..end].iter().zip(radius).enumerate() {
            let s2 = T::norm2(image(cell.as_ref(), pi - pj));
            let (dif, sum) = (ai - aj, (ai + aj) * reach);
            if s2 <= dif * dif || (!allow_overlap && s2 < sum * sum) {
                first = Some((i, j));
                break;
            }
        }
    }
    first
}

/// [`first_clash`] over the cell list's neighbours (the same test, kept beside the
/// all-pairs loop rather than shared so that firmware's code stays as it was): the
/// first pair `(i, j)`, `i < j`, whose earlier sphere `i` is in `rows` (the smallest
/// `i` with a clash, then its smallest `j`).
fn first_near<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    p: &Params<T>,
    list: &CellList<'_>,
    rows: core::ops::Range<usize>,
) -> Option<(usize, usize)> {
    let (allow_overlap, cell) = (p.allow_overlap, super::cell(p));
    let reach = match p.contacts {
        Some(_) => T::ONE - p.solver.tolerance * T::TWO,
        None => T::ONE,
    };
    let clashes = |(pi, ai): (T::V3, T), (pj, aj): (T::V3, T)| {
        let s2 = T::norm2(image(cell.as_ref(), pi - pj));
        let (dif, sum) = (ai - aj, (ai + aj) * reach);
        s2 <= dif * dif || (!allow_overlap && s2 < sum * sum)
    };
    for i in rows {
        let mut first: Option<usize> = None;
        let (pi, ai) = (pos[i], radius[i]);
        list.near::<T>(pi, |j| {
            let later = j > i && first.is_none_or(|f| j < f);
            if later && clashes((pi, ai), (pos[j], radius[j])) {
                first = Some(j);
            }
        });
        if let Some(j) = first {
            return Some((i, j));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::Serial;
    use glam::DVec3;

    /// The banded pair check (600 spheres: 16 bands) reports the pair a single pass in
    /// the order `(i, j)`, `i < j`, meets first (a brute-force loop here), also when a
    /// later band holds it and an earlier band holds another; with and without the cell
    /// list, in free space and in a box.
    #[test]
    fn banded_check_reports_the_first_pair_in_order() {
        const N: usize = 600;
        assert!(bands(N) > 1);
        let line: [DVec3; N] = core::array::from_fn(|k| DVec3::new(3.0 * k as f64, 0.0, 0.0));
        let (radius, zero) = ([1.0; N], [DVec3::ZERO; N]);
        let p = Params::<f64>::new(0.01);
        // A box long enough that no image comes near (the line is 1800 long).
        let boxed = crate::cell::Periodic::new([4000.0, 17.0, 17.0]).unwrap();
        let first = |pos: &[DVec3]| {
            (0..N)
                .flat_map(|i| (i + 1..N).map(move |j| (i, j)))
                .find(|&(i, j)| (pos[i] - pos[j]).length_squared() < 4.0)
        };
        let cases: [&[(usize, usize)]; 5] = [
            &[],
            &[(300, 200)],
            &[(300, 200), (590, 10)],
            &[(590, 10), (599, 10)],
            &[(599, 11), (598, 10), (40, 30)],
        ];
        for moves in cases {
            let mut pos = line;
            for &(m, to) in moves {
                pos[m] = line[to] + DVec3::new(0.0, 1.5, 0.0);
            }
            let want = first(&pos).map_or(Ok(()), |(i, j)| Err(StepError::Overlap { i, j }));
            // With a cell list (free space, and a box of 8 cells per axis), and
            // without one (no storage: every pair).
            let mut cells = [0; 3 * N + 1];
            for q in [
                p,
                Params {
                    periodic: Some(boxed),
                    ..p
                },
            ] {
                for store in [&mut cells[..], &mut []] {
                    let got = accept(&pos, &zero, &zero, &radius, &q, &Serial, store);
                    assert_eq!(got, want, "{moves:?}");
                }
            }
        }
    }
}
