//! The active-set loop of the position projection ([`project_along`]): project, add the
//! pairs and wall (or ceiling) links that overlap or crossed, release the one that pulls
//! hardest, until nothing changes; and the error reports of a round that fails (a step
//! too long for the linearisation, the deepest overlap when the rounds run out).

use super::search::{Active, add_pairs, add_wall};
use super::{Along, Projected, Round};
use crate::bonds::Bond;
use crate::cell::{Periodic, image};
use crate::constraints::{Scratch, SolveStats};
use crate::error::{Row, Stage, StepError};
use crate::integrate::{self, bond_vectors};
use crate::params::{Contacts, Params};
use crate::real::Real;
use crate::workspace::Links;

/// The position projection of [`project_overdamped`], each round solved by `along`.
///
/// Without contacts this is one round over the caller's bonds. Both cases share the
/// one call of the constraint solve: a second call site would stop the compiler from
/// inlining it where the parameters are a constant (firmware), and every solver would
/// be linked.
#[allow(clippy::type_complexity)]
pub(in crate::integrate) fn project_along<'l, T: Real, A: Along<T>>(
    p: &Params<T>,
    bonds: &'l [Bond<T>],
    (start, radius): (&[T::V3], &[T]),
    (links, grad, lambda, scratch): (Links<'l, T>, &mut [T::V3], &mut [T], &mut Scratch<'_, T>),
    x: &mut [T::V3],
    free: impl Fn(&mut [T::V3]),
    along: &mut A,
) -> Result<Projected<'l, T>, StepError> {
    let (links, cells) = links.split();
    // Constants without the `contacts` feature: the one-sided path folds away.
    let contacts = p.contacts.filter(|_| cfg!(feature = "contacts"));
    // The floor the wall links hold, as the geometry answers its hard surfaces
    // (`Place::surfaces`: the wall's plane).
    let wall = p
        .place()
        .surfaces()
        .floor()
        .filter(|_| cfg!(feature = "contacts"));
    // The ceiling the ceiling links hold (a slit's upper plane), and its height in the
    // floor's frame.
    let roof = p
        .place()
        .surfaces()
        .ceiling()
        .filter(|_| cfg!(feature = "slit") && cfg!(feature = "contacts"));
    let ceiling = roof.map(|c| c - wall.unwrap_or(T::ZERO));
    let nb = bonds.len();
    let cell = integrate::cell(p);
    // The pool of one-sided constraints: the contacts' capacity, one wall link per
    // sphere ([`Params::constraints`]).
    let pool = p.constraints(start.len(), nb) - nb;
    let one_sided = match (contacts, wall) {
        (None, None) => None,
        (c, _) => Some(c.unwrap_or(Contacts::new(0))),
    };
    let tol = p.solver.tolerance;
    let mut nc = 0;
    // Contacts released in this step, at the pool's far end (anti-cycling).
    let mut released = 0;
    if one_sided.is_some() {
        links[..nb].copy_from_slice(bonds);
        // The last step's contacts end within the tolerance of touching.
        let reach = T::ONE + tol * T::TWO;
        if contacts.is_some() {
            let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
            add_pairs(bonds, (start, start), radius, cell, reach, &mut set, cells)?;
        }
        if let Some(h) = wall {
            let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
            add_wall(start, (h, false), radius, reach, &mut set)?;
        }
        if let Some(c) = roof {
            let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
            add_wall(start, (c, true), radius, reach, &mut set)?;
        }
    }
    let mut round = 0;
    // Factorisations of every round's solve.
    let mut factorizations = 0;
    // Newton's factor is carried from round to round (the same chord matrix: the same
    // start, metric and rows), never into a step.
    scratch.carry = Default::default();
    loop {
        round += 1;
        let active = match one_sided {
            Some(_) => &links[..nb + nc],
            None => bonds,
        };
        bond_vectors(active, start, integrate::cell(p), grad);
        free(x);
        shift(x, wall, -T::ONE);
        // Contacts and wall links are inequalities inside the solve (`docs/CONTACTS.md`).
        let this = Round {
            rows: active,
            grad: &*grad,
            x: &mut *x,
            lambda: &mut *lambda,
            scratch: &mut *scratch,
            nb,
            start,
        };
        let stats = along
            .project(p, this)
            .map_err(|e| too_long(e, active, nb, start, wall, p))?;
        factorizations += stats.factorizations;
        let stats = SolveStats {
            factorizations,
            ..stats
        };
        let Some(c) = one_sided else {
            return Ok(Projected {
                stats,
                held: bonds,
                contacts: 0,
                wall_contacts: 0,
                rounds: 0,
            });
        };
        let reach = T::ONE - tol;
        let mut added = 0;
        let mut set = Active::new(nb, pool, links, &mut nc, &mut released);
        if contacts.is_some() {
            added += add_pairs(bonds, (start, x), radius, cell, reach, &mut set, cells)?;
        }
        if wall.is_some() {
            added += add_wall(x, (T::ZERO, false), radius, reach, &mut set)?;
        }
        if let Some(c) = ceiling {
            added += add_wall(x, (c, true), radius, reach, &mut set)?;
        }
        let let_go = match added {
            0 => set.release_pulling(lambda),
            _ => None,
        };
        scratch.carry.keep = true;
        scratch.carry.released = let_go;
        if added == 0 && let_go.is_none() {
            // Every contact must end on the side it started from (a sphere above the
            // wall: `grad = (0, 0, a)`, its relative vector `(0, 0, z)`; below the
            // ceiling: `(0, 0, -a)` and `(0, 0, z - c)`).
            for (k, l) in links[nb..nb + nc].iter().enumerate() {
                let r = match (l.is_ceiling(), ceiling) {
                    (true, Some(c)) => l.relative(x) - crate::bonds::along::<T>(2, c),
                    _ => l.separation(x, cell.as_ref()),
                };
                if !(T::dot(r, grad[nb + k]) > T::ZERO) {
                    return Err(StepError::Degenerate {
                        bond: nb + k,
                        row: Row::of(links, nb + k, nb),
                    });
                }
            }
            shift(x, wall, T::ONE);
            // The rows the solve let go (zero multipliers: apart, or dependent and
            // unloaded) are not held.
            let mut kept = 0;
            for k in nb..nb + nc {
                if lambda[k] != T::ZERO {
                    links[nb + kept] = links[k];
                    grad[nb + kept] = grad[k];
                    lambda[nb + kept] = lambda[k];
                    kept += 1;
                }
            }
            nc = kept;
            let links: &'l [Bond<T>] = links;
            let held = &links[..nb + nc];
            let walls = held.iter().filter(|l| l.is_wall()).count();
            return Ok(Projected {
                stats,
                held,
                contacts: (nc - walls) as u32,
                wall_contacts: walls as u32,
                rounds: round,
            });
        }
        if round >= c.max_rounds {
            return Err(StepError::NoConvergence {
                stage: Stage::Contacts,
                iterations: round,
                residual: deepest_overlap(x, radius, cell, (wall.is_some(), ceiling)).to_f64(),
            });
        }
    }
}

/// A dependent set that the solve found contradictory ([`StepError::Infeasible`]) is
/// a claim about the linearisation at its iterate. Where every row already holds at
/// the start of the step, the start is a point that meets them all: the geometry is
/// feasible, and the step is too long for the linearisation (its rows turned too far):
/// [`StepError::Degenerate`] on the dependent set's first row, which a shorter step
/// can avoid. Other errors pass unchanged.
fn too_long<T: Real>(
    e: StepError,
    rows: &[Bond<T>],
    one_sided: usize,
    start: &[T::V3],
    wall: Option<T>,
    p: &Params<T>,
) -> StepError {
    let StepError::Infeasible { constraints, .. } = e else {
        return e;
    };
    // The last step left its rows within the tolerance and its other pairs overlapping
    // by at most that (measured as the solve measures them, which a sweep stops just
    // inside): four tolerances here, far below any contradiction a start can hold.
    let tol = p.solver.tolerance * T::from_f64(4.0);
    let cell = integrate::cell(p);
    let holds = rows.iter().enumerate().all(|(k, b)| {
        // A pin row is measured from the start: it holds there.
        if b.is_pin() {
            return true;
        }
        let (gap, d) = match b.is_wall() {
            // Below the ceiling `c`: `c - z - a` (the link's length is `-a`).
            true if b.is_ceiling() => {
                let c = p.place().surfaces().ceiling().unwrap_or(T::ZERO);
                (c - T::xyz(start[b.i])[2] + b.length, -b.length)
            }
            true => {
                let h = wall.unwrap_or(T::ZERO);
                (T::xyz(start[b.i])[2] - h - b.length, b.length)
            }
            false => (
                T::norm(b.separation(start, cell.as_ref())) - b.length,
                b.length,
            ),
        };
        let err = gap / d;
        match k >= one_sided {
            true => err >= -tol,
            false => err.abs() <= tol,
        }
    });
    match holds {
        true => StepError::Degenerate {
            bond: constraints[0],
            row: Row::of(rows, constraints[0], one_sided),
        },
        false => e,
    }
}

/// `z += sign * height` for every position (into the wall's frame with `sign = -1`,
/// back with `+1`); nothing without a wall.
fn shift<T: Real>(x: &mut [T::V3], wall: Option<T>, sign: T) {
    if let Some(h) = wall {
        let dz = T::v3(T::ZERO, T::ZERO, h * sign);
        for xi in x.iter_mut() {
            *xi += dz;
        }
    }
}

/// Largest relative overlap `1 - |r_ij| / (a_i + a_j)` (the minimum image in a box),
/// with a wall `1 - z_i / a_i` and with a ceiling at `c` `1 - (c - z_i) / a_i`
/// (positions in the wall's frame), for the error report.
fn deepest_overlap<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    cell: Option<Periodic<T>>,
    (wall, ceiling): (bool, Option<T>),
) -> T {
    let mut worst = T::ZERO;
    for i in 0..pos.len() {
        let z = T::xyz(pos[i])[2];
        if wall {
            worst = worst.max(T::ONE - z / radius[i]);
        }
        if let Some(c) = ceiling {
            worst = worst.max(T::ONE - (c - z) / radius[i]);
        }
        for j in 0..i {
            let sigma = radius[i] + radius[j];
            worst = worst.max(T::ONE - T::norm(image(cell.as_ref(), pos[i] - pos[j])) / sigma);
        }
    }
    worst
}
