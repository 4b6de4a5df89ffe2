//! The overdamped position projection, and the hard-sphere contacts it holds as
//! one-sided constraints ([`Params::contacts`]).
//!
//! A contact is a link `(i, j)` of length `a_i + a_j` solved with the bonds, through the
//! same metric (the start-of-step mobility) and the same solver. Which pairs are in
//! contact is found by an active-set iteration on the projection's KKT conditions:
//!
//! 1. start from the pairs touching at the start of the step (the last step's contacts,
//!    which it left at contact distance);
//! 2. project the unconstrained move onto the bonds and the active contacts;
//! 3. add every pair that overlaps at the end, or that crossed (its straight path from
//!    the start came within contact and the pair turned by more than a right angle: one
//!    sphere passed through the other within the step); if none does,
//!    release the contact whose multiplier pulls hardest (a contact can only push),
//!    one per round;
//! 4. repeat until nothing changes: every active contact pushes, no other pair overlaps.
//!
//! Each round projects from the unconstrained move again, so the result does not
//! depend on the path. No stiffness: the contacts do not limit `dt`. A step so large
//! that a pair would end in contact on the far side of where it started is refused
//! ([`StepError::Degenerate`], indexed past the bonds), as a bond turned too far is.
//!
//! **The wall** ([`Params::wall`]) takes part in the same iteration: a sphere whose
//! centre would end below `height + a_i` gets a wall link ([`Bond::wall`]: the linear
//! constraint `z_i = height + a_i`, pushing on that sphere alone along `+z`), released
//! like a contact when its multiplier would pull the sphere down. The projection runs in
//! the wall's frame: the candidate is moved by `-height` along `z` before each solve and
//! back at the end (exact for `height = 0`; otherwise the candidate's `z` is rounded
//! twice). With or without [`Params::contacts`]; with a wall, the pool of one-sided
//! constraints holds one wall link per sphere beside the contacts' capacity
//! ([`Params::constraints`]).

use super::{bond_vectors, mobility_metric, project_positions};
use crate::bonds::Bond;
use crate::cell::{Periodic, image};
use crate::constraints::{Scratch, SolveStats};
use crate::error::{Stage, StepError};
use crate::params::{Contacts, Params, Wall};
use crate::real::Real;

/// The slices the overdamped position projection works in.
pub(super) struct Projection<'l, 'v, 'a, T: Real> {
    pub links: &'l mut [Bond<T>],
    pub grad: &'v mut [T::V3],
    pub disp: &'v mut [T::V3],
    pub lambda: &'v mut [T],
    pub scratch: &'v mut Scratch<'a, T>,
    /// The step's Ewald parameters in a box ([`super::stages::Sums`]).
    pub ewald: super::stages::Sums<'v, T>,
    /// The compact copy of the mobility the constraint products read
    /// ([`Params::compact_products`]); empty: they read the mobility.
    pub compact: &'v [T::M3],
}

/// What the overdamped position projection did.
pub(super) struct Projected<'l, T: Real> {
    /// The solve (of the last active-set round with contacts).
    pub stats: SolveStats<T>,
    /// The constraints held: the bonds, then the contacts (rows of `grad`, `lambda`).
    pub held: &'l [Bond<T>],
    /// Contacts held (0 without contacts).
    pub contacts: u32,
    /// Wall links held (0 without a wall).
    pub wall_contacts: u32,
    /// Active-set rounds (0 without contacts).
    pub rounds: u32,
}

/// The overdamped position projection along the mobility at `start` (`mu`, scaled by
/// `dt`): `free` writes the unconstrained move into `x` (once per round), which is then
/// projected onto the bonds, or onto the bonds and the hard-sphere contacts when
/// [`Params::contacts`] is on.
///
/// Without contacts this is one round over the caller's bonds. Both cases share the
/// one call of the constraint solve: a second call site would stop the compiler from
/// inlining it where the parameters are a constant (firmware), and every solver would
/// be linked.
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
    let Projection {
        links,
        grad,
        disp,
        lambda,
        scratch,
        ewald,
        compact,
    } = v;
    // Constants without the `contacts` feature: the one-sided path folds away.
    let contacts = p.contacts.filter(|_| cfg!(feature = "contacts"));
    let wall = p.wall.filter(|_| cfg!(feature = "contacts"));
    let nb = bonds.len();
    let cell = super::cell(p);
    // The pool of one-sided constraints: the contacts' capacity, one wall link per
    // sphere ([`Params::constraints`]).
    let pool = p.constraints(start.len(), nb) - nb;
    let one_sided = match (contacts, wall) {
        (None, None) => None,
        (c, _) => Some(c.unwrap_or(Contacts::new(0))),
    };
    let tol = p.solver.tolerance;
    let mut nc = 0;
    if one_sided.is_some() {
        links[..nb].copy_from_slice(bonds);
        // The last step's contacts end within the tolerance of touching.
        let reach = T::ONE + tol * T::TWO;
        if contacts.is_some() {
            add_pairs(
                bonds, start, start, radius, cell, reach, pool, links, &mut nc,
            )?;
        }
        if let Some(w) = wall {
            add_wall(nb, start, w.height, radius, reach, pool, links, &mut nc)?;
        }
    }
    let mut round = 0;
    loop {
        round += 1;
        let active = match one_sided {
            Some(_) => &links[..nb + nc],
            None => bonds,
        };
        bond_vectors(active, start, super::cell(p), grad);
        let par = scratch.par;
        let metric = mobility_metric(
            p,
            ewald,
            active,
            start,
            radius,
            mu,
            grad,
            p.dt,
            disp,
            (par, compact),
        );
        free(x);
        shift(x, wall, -T::ONE);
        let stats = project_positions(p, active, &metric, x, lambda, scratch)?;
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
        if contacts.is_some() {
            added += add_pairs(bonds, start, x, radius, cell, reach, pool, links, &mut nc)?;
        }
        if wall.is_some() {
            added += add_wall(nb, x, T::ZERO, radius, reach, pool, links, &mut nc)?;
        }
        if added == 0 && !release_pulling(nb, links, lambda, &mut nc) {
            // Every contact must end on the side it started from (a sphere above the
            // wall: `grad = (0, 0, a)`, its relative vector `(0, 0, z)`).
            for (k, l) in links[nb..nb + nc].iter().enumerate() {
                if !(T::dot(l.separation(x, cell.as_ref()), grad[nb + k]) > T::ZERO) {
                    return Err(StepError::Degenerate { bond: nb + k });
                }
            }
            shift(x, wall, T::ONE);
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
                residual: deepest_overlap(x, radius, cell, wall.is_some()).to_f64(),
            });
        }
    }
}

/// `z += sign * height` for every position (into the wall's frame with `sign = -1`,
/// back with `+1`); nothing without a wall.
fn shift<T: Real>(x: &mut [T::V3], wall: Option<Wall<T>>, sign: T) {
    if let Some(w) = wall {
        let dz = T::v3(T::ZERO, T::ZERO, w.height * sign);
        for xi in x.iter_mut() {
            *xi += dz;
        }
    }
}

/// Appends a wall link for every sphere whose centre is closer than `reach` times its
/// radius to the plane `z = height` (or below it) and has none yet; returns how many
/// were added.
#[allow(clippy::too_many_arguments)]
fn add_wall<T: Real>(
    nb: usize,
    pos: &[T::V3],
    height: T,
    radius: &[T],
    reach: T,
    pool: usize,
    links: &mut [Bond<T>],
    nc: &mut usize,
) -> Result<usize, StepError> {
    let mut added = 0;
    for (i, (&r, &a)) in pos.iter().zip(radius).enumerate() {
        if !(T::xyz(r)[2] - height < a * reach) {
            continue;
        }
        if links[nb..nb + *nc].iter().any(|l| l.is_wall() && l.i == i) {
            continue;
        }
        push(Bond::wall(i, a), nb, pool, links, nc)?;
        added += 1;
    }
    Ok(added)
}

/// Appends `link` to the one-sided constraints held (`nc` of them after the `nb`
/// bonds), unless the pool is full.
fn push<T: Real>(
    link: Bond<T>,
    nb: usize,
    pool: usize,
    links: &mut [Bond<T>],
    nc: &mut usize,
) -> Result<(), StepError> {
    if *nc == pool {
        return Err(StepError::ContactsFull { capacity: pool });
    }
    links[nb + *nc] = link;
    *nc += 1;
    Ok(())
}

/// Appends every unbonded pair that ends closer than `reach` times its contact distance
/// or crossed within it on the straight path from `from` to `to`, and is not yet a
/// contact; returns how many were added. In a periodic box the path starts at the
/// minimum image of the pair's separation and moves with the pair's relative
/// displacement (the image is not taken again at its end, where a pair near half the
/// box apart would jump across the box and seem to pass through contact); the end
/// is compared by its minimum image.
#[allow(clippy::too_many_arguments)]
fn add_pairs<T: Real>(
    bonds: &[Bond<T>],
    from: &[T::V3],
    to: &[T::V3],
    radius: &[T],
    cell: Option<Periodic<T>>,
    reach: T,
    pool: usize,
    links: &mut [Bond<T>],
    nc: &mut usize,
) -> Result<usize, StepError> {
    let nb = bonds.len();
    let mut added = 0;
    for i in 0..to.len() {
        for j in 0..i {
            let sigma = radius[i] + radius[j];
            let far = sigma * reach;
            let (d0, d1) = match cell {
                Some(c) if cfg!(feature = "periodic") => {
                    let d0 = c.minimum_image(from[i] - from[j]);
                    (d0, d0 + ((to[i] - from[i]) - (to[j] - from[j])))
                }
                _ => (from[i] - from[j], to[i] - to[j]),
            };
            let ends = T::norm2(image(cell.as_ref(), d1)) < far * far;
            let crossed = !(T::dot(d0, d1) > T::ZERO) && closest2::<T>(d0, d1) < far * far;
            if !(ends || crossed) {
                continue;
            }
            let joins = |b: &Bond<T>| (b.i == i && b.j == j) || (b.i == j && b.j == i);
            if bonds.iter().any(joins) || links[nb..nb + *nc].iter().any(joins) {
                continue;
            }
            let link = Bond {
                i,
                j,
                length: sigma,
            };
            push(link, nb, pool, links, nc)?;
            added += 1;
        }
    }
    Ok(added)
}

/// Smallest squared length of `d0 + t (d1 - d0)` for `t` in `[0, 1]`.
fn closest2<T: Real>(d0: T::V3, d1: T::V3) -> T {
    let e = d1 - d0;
    let ee = T::norm2(e);
    let t = if ee > T::ZERO {
        (-T::dot(d0, e) / ee).max(T::ZERO).min(T::ONE)
    } else {
        T::ZERO
    };
    T::norm2(d0 + e * t)
}

/// Releases the contact whose multiplier pulls hardest (negative: a contact pushes
/// along `r_i - r_j` with a positive multiplier), keeping the others in order.
fn release_pulling<T: Real>(
    nb: usize,
    links: &mut [Bond<T>],
    lambda: &[T],
    nc: &mut usize,
) -> bool {
    let mut worst: Option<(usize, T)> = None;
    for k in 0..*nc {
        let l = lambda[nb + k];
        if l < T::ZERO && worst.is_none_or(|(_, w)| l < w) {
            worst = Some((k, l));
        }
    }
    let Some((k, _)) = worst else {
        return false;
    };
    links.copy_within(nb + k + 1..nb + *nc, nb + k);
    *nc -= 1;
    true
}

/// Largest relative overlap `1 - |r_ij| / (a_i + a_j)` (the minimum image in a box), and
/// with a wall `1 - z_i / a_i` (positions in the wall's frame), for the error report.
fn deepest_overlap<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    cell: Option<Periodic<T>>,
    wall: bool,
) -> T {
    let mut worst = T::ZERO;
    for i in 0..pos.len() {
        if wall {
            worst = worst.max(T::ONE - T::xyz(pos[i])[2] / radius[i]);
        }
        for j in 0..i {
            let sigma = radius[i] + radius[j];
            worst = worst.max(T::ONE - T::norm(image(cell.as_ref(), pos[i] - pos[j])) / sigma);
        }
    }
    worst
}
