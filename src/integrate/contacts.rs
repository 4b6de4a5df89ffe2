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

use super::{bond_vectors, mobility_metric, project_positions};
use crate::bonds::Bond;
use crate::constraints::Solver;
use crate::constraints::{Scratch, SolveStats};
use crate::error::{Stage, StepError};
use crate::params::{Contacts, Params};
use crate::real::Real;

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
    } = v;
    // A constant without the `contacts` feature: the contact path folds away.
    let contacts = p.contacts.filter(|_| cfg!(feature = "contacts"));
    // With contacts the solver is resolved once for the bonds plus the capacity, as the
    // storage was ([`Layout::for_params`](crate::Layout::for_params)), however many
    // contacts a round holds.
    let resolved;
    let p = match contacts {
        Some(c) => {
            resolved = Params {
                solver: Solver {
                    kind: p.solver.kind.resolve(bonds.len() + c.capacity),
                    ..p.solver
                },
                ..*p
            };
            &resolved
        }
        None => p,
    };
    let nb = bonds.len();
    let tol = p.solver.tolerance;
    let mut nc = 0;
    if let Some(c) = contacts {
        links[..nb].copy_from_slice(bonds);
        // The last step's contacts end within the tolerance of touching.
        add_pairs(
            bonds,
            start,
            start,
            radius,
            T::ONE + tol * T::TWO,
            c,
            links,
            &mut nc,
        )?;
    }
    let mut round = 0;
    loop {
        round += 1;
        let active = match contacts {
            Some(_) => &links[..nb + nc],
            None => bonds,
        };
        bond_vectors(active, start, grad);
        let par = scratch.par;
        let metric = mobility_metric(p, active, start, radius, mu, grad, p.dt, disp, par);
        free(x);
        let stats = project_positions(p, active, &metric, x, lambda, scratch)?;
        let Some(c) = contacts else {
            return Ok(Projected {
                stats,
                held: bonds,
                contacts: 0,
                rounds: 0,
            });
        };
        let added = add_pairs(bonds, start, x, radius, T::ONE - tol, c, links, &mut nc)?;
        if added == 0 && !release_pulling(nb, links, lambda, &mut nc) {
            // Every contact must end on the side it started from.
            for (k, l) in links[nb..nb + nc].iter().enumerate() {
                if !(T::dot(x[l.i] - x[l.j], grad[nb + k]) > T::ZERO) {
                    return Err(StepError::Degenerate { bond: nb + k });
                }
            }
            let links: &'l [Bond<T>] = links;
            return Ok(Projected {
                stats,
                held: &links[..nb + nc],
                contacts: nc as u32,
                rounds: round,
            });
        }
        if round >= c.max_rounds {
            return Err(StepError::NoConvergence {
                stage: Stage::Contacts,
                iterations: round,
                residual: deepest_overlap(x, radius).to_f64(),
            });
        }
    }
}

/// Appends every unbonded pair that ends closer than `reach` times its contact distance
/// or crossed within it on the straight path from `from` to `to`, and is not yet a
/// contact; returns how many were added.
#[allow(clippy::too_many_arguments)]
fn add_pairs<T: Real>(
    bonds: &[Bond<T>],
    from: &[T::V3],
    to: &[T::V3],
    radius: &[T],
    reach: T,
    c: Contacts,
    links: &mut [Bond<T>],
    nc: &mut usize,
) -> Result<usize, StepError> {
    let nb = bonds.len();
    let mut added = 0;
    for i in 0..to.len() {
        for j in 0..i {
            let sigma = radius[i] + radius[j];
            let far = sigma * reach;
            let (d0, d1) = (from[i] - from[j], to[i] - to[j]);
            let ends = T::norm2(d1) < far * far;
            let crossed = !(T::dot(d0, d1) > T::ZERO) && closest2::<T>(d0, d1) < far * far;
            if !(ends || crossed) {
                continue;
            }
            let joins = |b: &Bond<T>| (b.i == i && b.j == j) || (b.i == j && b.j == i);
            if bonds.iter().any(joins) || links[nb..nb + *nc].iter().any(joins) {
                continue;
            }
            if *nc == c.capacity {
                return Err(StepError::ContactsFull {
                    capacity: c.capacity,
                });
            }
            links[nb + *nc] = Bond {
                i,
                j,
                length: sigma,
            };
            *nc += 1;
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

/// Largest relative overlap `1 - |r_ij| / (a_i + a_j)` (for the error report).
fn deepest_overlap<T: Real>(pos: &[T::V3], radius: &[T]) -> T {
    let mut worst = T::ZERO;
    for i in 0..pos.len() {
        for j in 0..i {
            let sigma = radius[i] + radius[j];
            worst = worst.max(T::ONE - T::norm(pos[i] - pos[j]) / sigma);
        }
    }
    worst
}
