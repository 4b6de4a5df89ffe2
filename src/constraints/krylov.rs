//! Chord Newton with preconditioned conjugate gradients: the constraint solve for many
//! bonds, `O(N^2)` per iteration instead of the dense solve's `O(B^3)`.
//!
//! Each outer (chord) iteration solves `A delta = -sigma(x)` with the fixed matrix
//! `A_kl = c g_k . (D_l(i_k) - D_l(j_k))` built on the step's start bond vectors `g`
//! (`c = 2` for positions, `1` for velocities). `A = c G D` with `D = metric G^T` is
//! symmetric positive definite for every metric here (mass, mobility, implicit drag),
//! so conjugate gradients apply; the chord's linear convergence factor is the bond
//! rotation within one step, `|x_i - x_j - g| / |g|`, small at any usable `dt`.
//!
//! * One PCG iteration is one [`Metric::apply_all`]: `G^T p`, a mobility product (and a
//!   drag solve), `G`. The bead displacement of each direction is accumulated, so the
//!   update costs no extra product.
//! * Preconditioner: the band `|k - l| <= BAND` of `A` (in bond order) factorised by
//!   Cholesky. For a chain, ring or tree numbered along its branches this holds the
//!   near-field coupling of neighbouring bonds (the hydrodynamic coupling between bonds
//!   decays as `1/s^3`), so the iteration count barely grows with the chain length.
//!   If the band is not positive definite, its diagonal (Jacobi) is used instead.
//!   With one-sided rows (contacts, wall links: a pile, whose rows of one sphere sit
//!   anywhere in the list) the preconditioner is instead the incomplete Cholesky of
//!   `A` on the constraint graph, rows coupled where they share a sphere (`graph.rs`).
//! * Reported iterations are PCG iterations, i.e. operator products: the cost count.
//! * With a compact metric (`Metric::Mobility::compact`) the products read an `f32`
//!   copy of the mobility; the residual is still evaluated on the positions in `f64`, so the
//!   tolerance holds as it does for the `f64` products.
//! * One-sided rows (contacts, wall links) are inequalities: each chord iteration
//!   decides which are equalities (`onesided.rs`, the primal-dual active set); the
//!   others are masked out of the conjugate gradients (zero residual, zero product
//!   rows, a diagonal row of the preconditioner, rebuilt when the set changes).

use super::products::{Exact, Products};
use super::{Metric, Problem, Scratch, SolveStats, Solver, dependent, graph, onesided};
use crate::bonds::Bond;
use crate::error::{LinalgError, StepError};
use crate::linalg::band;
use crate::parallel::{BANDED_MIN, by_rows};
use crate::real::Real;

/// Half-bandwidth of the preconditioner, in bonds. 10 rather than 3 holds the coupling
/// of a helix's neighbouring turns (about 9 beads per turn on the bench helix): products
/// per Overdamped step (`examples/scale`, dt = 0.01, first 10 steps) 9 -> 6 at N = 256
/// and 10 -> 6 at N = 1024 (6 bonds: 7). The band costs `O(B BAND^2)`, nothing against
/// a product.
pub const BAND: usize = 10;

/// Each chord iteration reduces its linear residual by this factor (or to a quarter
/// of the tolerance, whichever is reached first).
const INNER_REDUCTION: f64 = 1e-3;

/// The solve stops as diverging when its residual exceeds the first one this many
/// times (the chord's contraction factor is then above one: bonds that turned too far
/// in one step for a projection along the start-of-step bond vectors).
const DIVERGED: f64 = 100.0;

/// Scalars of scratch per bond: `r, z, p, q, delta` and the band.
pub const SCALARS_PER_BOND: usize = 5 + BAND + 1;

/// Solves by chord Newton + PCG, accumulating the multipliers into `mult` and moving `x`.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn krylov<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    krylov_with(
        problem,
        (metric, &mut Exact),
        bonds,
        solver,
        x,
        mult,
        scratch,
    )
}

/// [`krylov`] with the products made by `op` ([`Products`]), the entries (the
/// band preconditioner, the curvature test, the one-sided rows) read from `metric`.
#[allow(clippy::too_many_arguments)]
pub fn krylov_with<T: Real, P: Products<T>>(
    problem: Problem<'_, T>,
    (metric, op): (&Metric<'_, T>, &mut P),
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    let (nb, n) = (bonds.len(), x.len());
    let c = problem.chord_factor();
    let (pre, rest) = scratch.krylov.split_at_mut(nb * (BAND + 1));
    let (r, rest) = rest.split_at_mut(nb);
    let (z, rest) = rest.split_at_mut(nb);
    let (p, rest) = rest.split_at_mut(nb);
    let (q, rest) = rest.split_at_mut(nb);
    let delta = &mut rest[..nb];
    let (w, rest) = scratch.beads.split_at_mut(n);
    let (acc, tmp) = rest.split_at_mut(n);
    // One-sided rows from `from` on (`usize::MAX`: none, the equality solve as it
    // always was).
    let from = problem.one_sided(nb);
    let one_sided = from < nb;
    let (state, rest) = scratch.piv.split_at_mut(if one_sided { nb } else { 0 });
    // With one-sided rows (a pile) the preconditioner is built on the constraint graph
    // (`graph.rs`), its pattern found once: the list does not change within a solve.
    // (A scratch sized for fewer rows or spheres, which `Layout` never gives, keeps the
    // band.)
    let on_graph = cfg!(feature = "contacts") && one_sided && rest.len() >= graph::indices(n, nb);
    let (cols, links) = rest.split_at_mut(if on_graph { graph::WIDTH * nb } else { 0 });
    if on_graph {
        graph::pattern(bonds, n, cols, links);
    }
    let cols = &*cols;
    let build = |pre: &mut [T], mask: (usize, &[usize])| match on_graph {
        true => graph::factor(metric, bonds, c, (pre, cols), mask),
        false => precondition(metric, bonds, c, pre, mask),
    };
    let apply = |pre: &[T], z: &mut [T]| match on_graph {
        true => graph::solve(pre, cols, z),
        false => band::solve(pre, nb, BAND, z),
    };
    // The band's largest diagonal entry: a bound on the curvature test below.
    let mut top = T::ZERO;
    if one_sided {
        onesided::reset(state);
    } else {
        top = build(pre, (nb, state));
    }
    let mut products = 0u32;
    let mut outer = 0u32;
    let mut initial = None;
    // Curvature below the rank tolerance (`sqrt(eps)`) of the diagonal's: a direction
    // of zero curvature to the precision that a step of `1 / curvature` can use (the
    // rounding of `q` is `eps |A| |p|`, and the move asked for would amplify it).
    let floor = dependent::rank_floor::<T>();
    // The last chord step met a direction `p` of (numerically) zero curvature: a
    // self-stress of dependent constraints, left in `p`.
    let mut previous: Option<T> = None;
    let mut null = false;
    let mut stalls = 0;
    loop {
        let (mut changed, mut pushes) = (false, true);
        if one_sided {
            changed = onesided::update(&problem, metric, bonds, from, x, mult, state);
            if changed || outer == 0 {
                top = build(pre, (from, state));
            }
        }
        // Nonlinear residual of the chord iteration.
        let mut worst = T::ZERO;
        for (k, b) in bonds.iter().enumerate() {
            let (value, _, norm) = problem.eval(b, k, x);
            r[k] = -value;
            worst = worst.max_sticky(norm);
        }
        if one_sided {
            let (w, p) = onesided::residual(&problem, bonds, from, x, mult, state);
            (worst, pushes) = (w, p);
            for k in from..nb {
                if !onesided::active(state[k]) {
                    r[k] = T::ZERO;
                }
            }
        }
        if !worst.is_finite() {
            return Err(problem.no_convergence(products, worst));
        }
        if worst <= solver.tolerance && pushes {
            return Ok(SolveStats {
                iterations: products,
                residual: worst,
                factorizations: 0,
            });
        }
        // Chord steps stopped by a self-stress that then fail to halve the residual,
        // three in a row: the dependent constraints ask for what the others forbid
        // (one such step may be a nonlinear remainder the next removes).
        stalls = match null && !changed && previous.is_some_and(|p| worst > p * T::HALF) {
            true => stalls + 1,
            false => 0,
        };
        if stalls > 0 && one_sided {
            // An active contact that the contradiction asks to open is let go
            // (`onesided.rs`); the set changes at the next update.
            if onesided::let_go(&problem, metric, bonds, from, p, x, state) {
                (previous, stalls, null) = (None, 0, false);
                continue;
            }
            // No active contact can open: infeasible to first order (Farkas).
            return Err(dependent::self_stress(metric, p));
        }
        if stalls == 3 {
            return Err(dependent::self_stress(metric, p));
        }
        previous = Some(worst);
        null = false;
        // A chord iteration that has grown the residual a hundredfold is diverging.
        let first = *initial.get_or_insert(worst);
        if outer == solver.max_iterations
            || products >= solver.max_iterations * 10
            || worst > first * T::from_f64(DIVERGED)
        {
            return Err(problem.no_convergence(products, worst));
        }
        outer += 1;
        let target = (worst * T::from_f64(INNER_REDUCTION)).max(solver.tolerance * T::HALF);
        // PCG on A delta = r from delta = 0.
        delta.fill(T::ZERO);
        acc.fill(T::V3_ZERO);
        if one_sided && (from..nb).any(|k| !onesided::active(state[k]) && mult[k] != T::ZERO) {
            // Rows released since the last solve: `delta_k = -lambda_k`, solved with
            // the active rows (their right-hand side gains `A_:k lambda_k`,
            // `onesided.rs`).
            for k in 0..nb {
                let off = k >= from && !onesided::active(state[k]);
                z[k] = if off { mult[k] } else { T::ZERO };
                delta[k] = -z[k];
            }
            op.apply(metric, bonds, z, w, tmp)?;
            products += 1;
            for (k, b) in bonds.iter().enumerate() {
                if k < from || onesided::active(state[k]) {
                    r[k] += T::dot(metric.grad(k), b.relative(w)) * c;
                }
            }
            for (a, &wi) in acc.iter_mut().zip(w.iter()) {
                *a -= wi;
            }
        }
        z.copy_from_slice(r);
        apply(pre, z);
        op.precondition(r, z);
        p.copy_from_slice(z);
        let mut rz = dot(r, z);
        for inner in 0..nb.max(1) {
            op.apply(metric, bonds, p, w, tmp)?;
            products += 1;
            for (k, b) in bonds.iter().enumerate() {
                q[k] = T::dot(metric.grad(k), b.relative(w)) * c;
            }
            for k in from..nb {
                if !onesided::active(state[k]) {
                    q[k] = T::ZERO;
                }
            }
            let pq = dot(p, q);
            // `p A p` against `p diag(A) p`: zero curvature along a self-stress of
            // dependent constraints (`docs/CONTACTS.md`). What is left of `r` along it
            // is the part no move can meet: the step is done. `p diag(A) p` is at most
            // `top |p|^2`: where `pq` clears twice that (rounding aside), the test
            // cannot hold and its reads of every bond's diagonal blocks, a cache miss
            // each in a large mobility (1 % of a 4096-bead step), are skipped.
            let clear = pq > floor * top.max(T::ZERO) * dot(p, p) * T::TWO;
            let curvature = match clear {
                true => T::ZERO,
                false => (0..nb).fold(T::ZERO, |s, k| {
                    s + p[k] * p[k] * T::dot(metric.grad(k), metric.relative(bonds, k, k)) * c
                }),
            };
            if !clear && pq.is_finite() && pq <= floor * curvature {
                null = true;
                break;
            }
            if !pq.is_finite() {
                // The iterate overflowed: a diverging chord iteration (the projection
                // has no solution near the start), not an indefinite matrix.
                return Err(problem.no_convergence(products, worst));
            }
            if !(pq > T::ZERO) {
                if inner == 0 {
                    return Err(StepError::Linalg {
                        stage: problem.stage(),
                        error: LinalgError::NotPositiveDefinite { row: 0 },
                    });
                }
                break;
            }
            let alpha = rz / pq;
            let mut lin = T::ZERO;
            for k in 0..nb {
                delta[k] += alpha * p[k];
                r[k] -= alpha * q[k];
                lin = lin.max_sticky(problem.normalise(&bonds[k], r[k]));
            }
            for (a, &wi) in acc.iter_mut().zip(w.iter()) {
                *a += wi * alpha;
            }
            if !(lin > target) {
                break;
            }
            z.copy_from_slice(r);
            apply(pre, z);
            op.precondition(r, z);
            let rz_new = dot(r, z);
            let beta = rz_new / rz;
            rz = rz_new;
            for k in 0..nb {
                p[k] = z[k] + beta * p[k];
            }
        }
        for (xi, &a) in x.iter_mut().zip(acc.iter()) {
            *xi += a;
        }
        for (m, &d) in mult.iter_mut().zip(delta.iter()) {
            *m += d;
        }
    }
}

/// Band of `A` factorised into `pre` (regularised where rows are dependent); its
/// diagonal square roots when the band is not positive semi-definite. `mask`: the
/// first one-sided row and the rows' states; an inactive row keeps only its diagonal.
/// Returns the band's largest diagonal entry (NaN-sticky).
fn precondition<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    c: T,
    pre: &mut [T],
    mask: (usize, &[usize]),
) -> T {
    let nb = bonds.len();
    let entry = |k: usize, l: usize| T::dot(metric.grad(k), metric.relative(bonds, k, l)) * c;
    match *metric {
        // A stored mobility's rows read blocks near its diagonal, a cache miss each at
        // large N (1 % of a 4096-bead step on one thread): in bands through the step's
        // `par`, each with a metric of its own on the same blocks (the metric holds
        // `par`, which need not cross threads). Rows are independent: the same bits.
        Metric::Mobility {
            mu,
            grad,
            scale,
            par,
            compact,
        } => by_rows(par, nb, BAND + 1, BANDED_MIN, pre, |k0, rows| {
            let serial = &crate::parallel::Serial;
            let own = Metric::Mobility {
                mu,
                grad,
                scale,
                par: serial,
                compact,
            };
            band_rows(&own, bonds, c, mask, k0, rows);
        }),
        _ => band_rows(metric, bonds, c, mask, 0, &mut pre[..nb * (BAND + 1)]),
    }
    let top = (0..nb).fold(T::ZERO, |m, k| m.max_sticky(pre[band::at(BAND, k, k)]));
    // Dependent constraints (`docs/CONTACTS.md`) make `A` singular: their pivots are
    // replaced by their diagonals, which keeps the preconditioner positive definite;
    // conjugate gradients on the singular but consistent `A delta = r` still converge
    // (to the solution in the range of `A`: the minimum-norm multipliers).
    let floor = super::dependent::rank_floor::<T>();
    if band::regularised(pre, nb, BAND, floor).is_ok() {
        return top;
    }
    log::debug!("krylov: band preconditioner not positive definite, using Jacobi");
    for k in 0..nb {
        for l in k.saturating_sub(BAND)..k {
            pre[band::at(BAND, k, l)] = T::ZERO;
        }
        // A's diagonal is positive (a bond's own metric); a degenerate bond gives 1.
        let d = entry(k, k);
        pre[band::at(BAND, k, k)] = if d > T::ZERO && d.is_finite() {
            d.sqrt()
        } else {
            T::ONE
        };
    }
    top
}

/// Rows `k0..` of [`precondition`]'s band into `rows` (whole rows of `BAND + 1` from
/// row `k0`), masked as there.
fn band_rows<T: Real>(
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    c: T,
    (from, state): (usize, &[usize]),
    k0: usize,
    rows: &mut [T],
) {
    let nb = bonds.len();
    let off = |k: usize| k >= from && !onesided::active(state[k]);
    let base = band::at(BAND, k0, k0) - BAND;
    for k in k0..k0 + rows.len() / (BAND + 1) {
        let first = k.saturating_sub(BAND);
        let row = &mut rows[band::at(BAND, k, first) - base..=band::at(BAND, k, k) - base];
        metric.jacobian_row(bonds, k, metric.grad(k) * c, first, row);
        if from < nb {
            for l in first..k {
                if off(k) || off(l) {
                    row[l - first] = T::ZERO;
                }
            }
        }
    }
}

fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    a.iter().zip(b).fold(T::ZERO, |s, (&x, &y)| s + x * y)
}
