//! What a free-space `auto` weighs: the time of one step's mobility work by each way
//! of giving it its products, from a cost model whose constants were measured
//! (`cargo run --release --example free_cost`, rows and fitted constants in
//! `bench/results/free_cost.csv`; chart `docs/free_crossover.png`, docs/FREE.md).
//!
//! * dense: the stored mobility is assembled once a step (twice with the midpoint
//!   drift), `DENSE_ASSEMBLY_BLOCK` a packed block (`tri(N) = N (N + 1) / 2` of them),
//!   and each product reads it, `DENSE_PRODUCT_BLOCK` a block; the thermal noise up
//!   to `LANCZOS_CROSSOVER` spheres is its block Cholesky factor, `CHOLESKY_CUBE N^3`;
//! * compact: the same assembly, its `f32` copy written on the way
//!   (`COMPACT_COPY_BLOCK`) and the constraint products read from the copy
//!   (`COMPACT_PRODUCT_BLOCK`);
//! * matrix-free: every product evaluates every pair again, `FREE_BLOCK` a block;
//! * fast (`mobility::free_fast`): `FAST_FIXED + FAST_GRID M log2 M + FAST_NEAR (N + 2
//!   pairs) + FAST_SPREAD N P^3`, with `M` the padded grid's points, `P^3` the window's
//!   and `pairs` the pairs within the cutoff, all from the parameters a step derives
//!   (`integrate::fast_parameters`: `FreeFast::new`'s rule over the padded box, the
//!   spreading widened where its grid passes the bounds, as along a long chain); the
//!   pairs counted, as the constants were fitted (a run's choice, [`choose_for`], and
//!   its weighing before each step, `free_reweigh`), or estimated from the spheres'
//!   bounding box where there are no positions ([`choose`], [`near_pairs`]).
//!
//! * rotation: the pair paths' spins, one pass of the pairs' rotation blocks a step
//!   (`SPIN_BLOCK` a packed block); the inertial method's grand assembly
//!   (`GRAND_ASSEMBLY_BLOCK` a block of `tri(2N)`); the fast path's products under the
//!   grand parameters (`FreeFast::new_grand`, the same constants) and its spins, one
//!   grand product (`GRAND_*`, the fast product's terms).
//!
//! Each fit minimises the relative residuals of its rows of the record, every shape
//! together (`python3 bench/free_fit.py COMMIT`): unit spheres in a ball at volume
//! fractions 0.01, 0.1 and 0.3 and a helical chain, N = 10 to 1e4, CPU seconds a call
//! (best of two), the fast products in the steady state (the kernel's transform kept),
//! the fast model over tolerances 1e-4 and 1e-6 and both parameter rules together.
//! Worst misfits: 1.6 (fast), 1.4 (dense, grand product), 1.5 (matrix-free), 2.3
//! (grand assembly, at N = 10). The test `the_choice_matches_the_measured_rows` checks
//! the choice against the measured rows themselves.
//!
//! * thermal noise: the Lanczos iterations modelled by [`free_noise`] (measured on
//!   whole Brownian steps, `cargo run --release --example free_brownian`), a product
//!   each; the pair paths' midpoint a second mobility.
//!
//! A step takes one product, or dozens with a constraint solve and Lanczos noise (the
//! solve's count measured for the box, [`box_cost`](super::box_cost)); the stored paths pay
//! their assembly once and then a few nanoseconds a block a product, the matrix-free
//! and fast paths pay every product in full. What each path can run decides first
//! ([`step_cost`] is `None` for a path the step cannot take), then storage (a path whose storage passes the limit is never taken,
//! checked before anything is allocated), then the modelled time.

use hydrorattle::mobility::free_fast::FreeFast;
use hydrorattle::{Method, Params, SolverKind};

use super::box_cost::{PRODUCTS_MIDPOINT, PRODUCTS_SOLVE};
use super::free_noise;
use super::sizing::{Plan, TooLarge};
use super::{Drift, Sqrt};

/// Seconds per dense assembly, fixed part.
pub const DENSE_ASSEMBLY_FIXED: f64 = 6.1590e-6;
/// Seconds per dense assembly per packed block (one pair evaluation).
pub const DENSE_ASSEMBLY_BLOCK: f64 = 1.3133e-8;
/// Seconds per product from the stored mobility, fixed part.
pub const DENSE_PRODUCT_FIXED: f64 = 6.8759e-6;
/// Seconds per product from the stored mobility per packed block.
pub const DENSE_PRODUCT_BLOCK: f64 = 7.1921e-9;
/// Seconds per block Cholesky factor, fixed part.
pub const CHOLESKY_FIXED: f64 = 7.5213e-6;
/// Seconds per block Cholesky factor per `N^3`.
pub const CHOLESKY_CUBE: f64 = 1.3150e-9;
/// Seconds per writing of the compact copy (with its product), fixed part.
pub const COMPACT_COPY_FIXED: f64 = 1.0383e-5;
/// Seconds per writing of the compact copy (with its product) per packed block.
pub const COMPACT_COPY_BLOCK: f64 = 1.5587e-8;
/// Seconds per product from the compact copy, fixed part.
pub const COMPACT_PRODUCT_FIXED: f64 = 0.0000e0;
/// Seconds per product from the compact copy per packed block.
pub const COMPACT_PRODUCT_BLOCK: f64 = 4.2589e-9;
/// Seconds per matrix-free product, fixed part.
pub const FREE_FIXED: f64 = 7.3744e-6;
/// Seconds per matrix-free product per packed block (one pair evaluation).
pub const FREE_BLOCK: f64 = 1.9236e-8;
/// Seconds per spin pass (a step's rotations on the pair paths), fixed part.
pub const SPIN_FIXED: f64 = 7.2211e-6;
/// Seconds per spin pass per packed block (one pair's rotation-from-force blocks).
pub const SPIN_BLOCK: f64 = 6.1746e-8;
/// Seconds per grand assembly (inertia with rotation), fixed part.
pub const GRAND_ASSEMBLY_FIXED: f64 = 4.0169e-6;
/// Seconds per grand assembly per packed block of the `2N x 2N` grand mobility.
pub const GRAND_ASSEMBLY_BLOCK: f64 = 3.4042e-8;
/// Seconds per fast product, fixed part.
pub const FAST_FIXED: f64 = 0.0000e0;
/// Seconds per fast product per `M log2 M` of its padded grid (the FFTs).
pub const FAST_GRID: f64 = 4.5541e-9;
/// Seconds per fast product per sphere and per near pair counted twice.
pub const FAST_NEAR: f64 = 1.3997e-7;
/// Seconds per fast product per window point of a sphere (spreading and interpolation).
pub const FAST_SPREAD: f64 = 6.2554e-9;
/// Seconds per fast grand product (forces and torques), fixed part.
pub const GRAND_FIXED: f64 = 0.0000e0;
/// Seconds per fast grand product per `M log2 M` of its padded grid.
pub const GRAND_GRID: f64 = 4.5676e-9;
/// Seconds per fast grand product per sphere and per near pair counted twice.
pub const GRAND_NEAR: f64 = 1.8799e-7;
/// Seconds per fast grand product per window point of a sphere.
pub const GRAND_SPREAD: f64 = 1.0828e-8;

/// `N (N + 1) / 2` as a real: the packed blocks of `n` spheres.
fn blocks(n: usize) -> f64 {
    let n = n as f64;
    n * (n + 1.0) / 2.0
}

/// A way of giving a free-space step its mobility products.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FreeChoice {
    /// The stored mobility (`matrix_free = false`).
    Dense,
    /// The stored mobility with its compact `f32` copy for the constraint products
    /// (`compact_products = true`).
    Compact,
    /// Every pair evaluated again in each product (`matrix_free = true`).
    MatrixFree,
    /// The fast `O(N log N)` product (`mobility::free_fast`, matrix-free).
    Fast,
}

/// The order [`choose`] weighs the paths in (a tie keeps the earlier).
pub const CHOICES: [FreeChoice; 4] = [
    FreeChoice::Dense,
    FreeChoice::Compact,
    FreeChoice::MatrixFree,
    FreeChoice::Fast,
];

/// The spheres a choice is made for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spheres {
    /// How many.
    pub n: usize,
    /// Bonds (constraint rows beside the contacts the plan carries).
    pub bonds: usize,
    /// The edges of the box that bounds their centres.
    pub extent: [f64; 3],
    /// The largest radius.
    pub a_max: f64,
    /// RPY hydrodynamics (the fast product computes RPY only).
    pub rpy: bool,
}

impl Spheres {
    /// The spheres of `scene` as they start: the bonds and pins as constraint rows,
    /// the bounding box of the centres.
    pub fn of(scene: &super::Scene) -> Spheres {
        let ps = &scene.particles;
        let pos: Vec<[f64; 3]> = ps.iter().map(|p| p.position).collect();
        let a_max = ps.iter().fold(0.0, |m: f64, p| m.max(p.radius));
        let rpy = scene.model.hydrodynamics == super::Hydrodynamics::Rpy;
        Spheres::at(&pos, a_max, scene.bonds.len() + scene.pinned.len(), rpy)
    }

    /// The spheres centred at `pos`, of radius up to `a_max`, with `bonds` constraint
    /// rows (`rpy`: RPY hydrodynamics): the bounding box of the centres.
    pub fn at(pos: &[[f64; 3]], a_max: f64, bonds: usize, rpy: bool) -> Spheres {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in pos {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        Spheres {
            n: pos.len(),
            bonds,
            extent: [0, 1, 2].map(|c| (hi[c] - lo[c]).max(0.0)),
            a_max,
            rpy,
        }
    }
}

/// The modelled time of one product by each path, seconds, from the spheres alone; the
/// fast path's `None` where the kernel refuses its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeCost {
    /// An assembly of the stored mobility.
    pub assembly: f64,
    /// A product from the stored mobility.
    pub dense: f64,
    /// The block Cholesky factor of the stored mobility.
    pub cholesky: f64,
    /// The compact copy's writing (with one product).
    pub copy: f64,
    /// A product from the compact copy.
    pub compact: f64,
    /// A matrix-free product.
    pub matrix_free: f64,
    /// A step's spins on the pair paths (rotation).
    pub spin: f64,
    /// An assembly of the grand mobility (inertia with rotation).
    pub grand_assembly: f64,
    /// A fast product at the tolerance.
    pub fast: Option<f64>,
    /// With rotation: a fast product under the grand parameters
    /// ([`FreeFast::new_grand`]), and a grand product (a step's spins).
    pub fast_grand: Option<(f64, f64)>,
}

/// The pairs within `r_cut` of `n` spheres spread evenly over the box of edges
/// `extent` (padded by a radius each side): each sphere's ball of neighbours clipped to
/// the box, axis by axis (a chain's ball is a segment of it, a sheet's a disk).
pub fn near_pairs(n: usize, extent: [f64; 3], a_max: f64, r_cut: f64) -> f64 {
    let mut share = 1.0;
    let mut clipped = 0;
    for e in extent {
        let e = e + 2.0 * a_max;
        if 2.0 * r_cut < e {
            share *= 2.0 * r_cut / e;
            clipped += 1;
        }
    }
    // The ball's share of its bounding cube in the clipped directions.
    share *= [
        1.0,
        1.0,
        std::f64::consts::FRAC_PI_4,
        std::f64::consts::PI / 6.0,
    ][clipped];
    let n = n as f64;
    0.5 * n * (n - 1.0).max(0.0) * share
}

/// The fast product's parameters for `s` at `tolerance` (with `grand`, the grand
/// product's), as a step derives them from the spheres' bounding box: where the rule's
/// grid passes its bounds (a long chain), the spreading widened until one fits
/// (`integrate::fast_parameters`); `None` where the kernel refuses them.
pub(super) fn fast_params(s: &Spheres, tolerance: f64, grand: bool) -> Option<FreeFast<f64>> {
    hydrorattle::integrate::fast_parameters(tolerance, grand, s.a_max, s.extent, s.n).ok()
}

/// The fast product's work terms for `s` under `ff` with `pairs` pairs within its cutoff:
/// `[1, M log2 M, N + 2 pairs, N P^3]`.
fn fast_terms(s: &Spheres, ff: &FreeFast<f64>, pairs: f64) -> [f64; 4] {
    let g = ff.grid();
    let m = (g[0] * g[1] * g[2]) as f64;
    let p3 = (ff.support() as f64).powi(3);
    let n = s.n as f64;
    [1.0, m * m.log2(), n + 2.0 * pairs, n * p3]
}

/// `c . x`.
fn dot(c: [f64; 4], x: [f64; 4]) -> f64 {
    c.iter().zip(x).map(|(c, x)| c * x).sum()
}

/// The fast translation product's constants.
const FAST: [f64; 4] = [FAST_FIXED, FAST_GRID, FAST_NEAR, FAST_SPREAD];
/// The fast grand product's constants.
const GRAND: [f64; 4] = [GRAND_FIXED, GRAND_GRID, GRAND_NEAR, GRAND_SPREAD];

impl FreeCost {
    /// The spheres `s` with the fast product at `tolerance`, its near pairs estimated
    /// as if spread evenly over their bounding box ([`near_pairs`]).
    pub fn of(s: &Spheres, tolerance: f64) -> FreeCost {
        FreeCost::counted(s, tolerance, &|r_cut| {
            near_pairs(s.n, s.extent, s.a_max, r_cut)
        })
    }

    /// [`FreeCost::of`] with the fast product's near pairs `pairs(r_cut)` given (a
    /// count of the spheres as they are, where a run's cloud has left its box's mean).
    pub fn counted(s: &Spheres, tolerance: f64, pairs: &dyn Fn(f64) -> f64) -> FreeCost {
        let (b, n) = (blocks(s.n), s.n as f64);
        let terms = |ff: &FreeFast<f64>| fast_terms(s, ff, pairs(ff.r_cut()));
        let fast = fast_params(s, tolerance, false).map(|ff| dot(FAST, terms(&ff)));
        let fast_grand = fast_params(s, tolerance, true).map(|ff| {
            let x = terms(&ff);
            (dot(FAST, x), dot(GRAND, x))
        });
        FreeCost {
            assembly: DENSE_ASSEMBLY_FIXED + DENSE_ASSEMBLY_BLOCK * b,
            dense: DENSE_PRODUCT_FIXED + DENSE_PRODUCT_BLOCK * b,
            cholesky: CHOLESKY_FIXED + CHOLESKY_CUBE * n * n * n,
            copy: COMPACT_COPY_FIXED + COMPACT_COPY_BLOCK * b,
            compact: COMPACT_PRODUCT_FIXED + COMPACT_PRODUCT_BLOCK * b,
            matrix_free: FREE_FIXED + FREE_BLOCK * b,
            spin: SPIN_FIXED + SPIN_BLOCK * b,
            grand_assembly: GRAND_ASSEMBLY_FIXED + GRAND_ASSEMBLY_BLOCK * blocks(2 * s.n),
            fast,
            fast_grand,
        }
    }
}

/// `plan` with the mobility path `choice`.
fn with_path(plan: &Plan, choice: FreeChoice) -> Plan {
    let mut p = *plan;
    p.matrix_free = matches!(choice, FreeChoice::MatrixFree | FreeChoice::Fast);
    p.compact_products = choice == FreeChoice::Compact;
    p
}

/// What a step of `plan` asks of the mobility, and how each path answers it: the
/// modelled seconds of one step by `choice`, or `None` where the path cannot run it.
///
/// * the stored paths: every method; compact only where the kernel keeps the copy
///   (`Params::compact_copy`: first-order overdamped, `f64`, Krylov, from
///   `REDUCED_MIN` spheres), and it changes only the constraint products;
/// * matrix-free and fast: `Overdamped`, `Overdamped2` (two evaluations a step) and
///   `Springs` (the inertial methods factorise the mobility), no wall, no near field, no Cholesky noise, and with constraints
///   the Krylov solver (the dense solvers read the metric entry by entry); fast also
///   needs RPY and a grid the kernel accepts;
/// * rotation: the pair paths add a pass of the pairs' rotation blocks a step (the
///   inertial method instead assembles the grand mobility, `tri(2N)` blocks); the fast
///   path runs every product under the grand parameters ([`FreeFast::new_grand`]) and
///   its spins are one grand product;
/// * thermal noise ([`free_noise`]): the stored paths by the Cholesky factor up to the
///   kernel's crossover, else every path by Lanczos, whose modelled iterations each
///   cost a product (the stored paths' from the reduced copy where the kernel reads
///   it); the pair paths keep the midpoint (the inverse root, a second mobility), the
///   fast path without bonds draws once ([`within_cap`] says whether the modelled
///   iterations stay under the kernel's cap).
pub fn step_cost(plan: &Plan, s: &Spheres, cost: &FreeCost, choice: FreeChoice) -> Option<f64> {
    let p: Params<f64> = with_path(plan, choice).params(s.n);
    let rows = p.constraints(s.n, s.bonds);
    let krylov = p.solver_kind(s.n, s.bonds) == SolverKind::Krylov;
    let thermal = plan.brownian.is_some_and(|t| t.temperature > 0.0);
    let drift = thermal && plan.brownian.is_some_and(|t| t.drift == Drift::Midpoint);
    let fast = choice == FreeChoice::Fast;
    // The midpoint's projection onto the constraints (a second solve).
    let projection = drift && rows > 0;
    // A thermal step's midpoint: always on the pair paths in free space (a second
    // mobility); on the fast path only with bonds (without, the uncorrected draw).
    let midpoint = drift && (!fast || s.bonds > 0);
    let solve = if rows > 0 { PRODUCTS_SOLVE } else { 0.0 };
    let lanczos = thermal && p.lanczos_noise(s.n);
    // The fast path's midpoint solves `M^-1 M^(1/2) w` by conjugate gradients: its
    // Lanczos run gives the root alone.
    let inverse = midpoint && !fast;
    let iterations = if lanczos {
        free_noise::iterations(s, inverse)
    } else {
        0.0
    };
    let mid = match (projection, fast && midpoint) {
        (true, _) | (false, true) => PRODUCTS_MIDPOINT,
        _ => 0.0,
    };
    // Products beside the noise's: the step's own, the solve's, the midpoint's (its
    // mobility applied once, and the projection or the fast path's solve).
    let at_mid = if midpoint && !fast { 1.0 } else { 0.0 };
    // `Overdamped2` (no noise): two evaluations, the predictor's and the corrector's,
    // each with its velocity solve, and the position projection's solve.
    let second = plan.method == Method::Overdamped2;
    let products = match second {
        true => 2.0 + 3.0 * solve,
        false => 1.0 + solve + mid + at_mid,
    };
    let assemblies = if midpoint || second { 2.0 } else { 1.0 };
    // With rotation the inertial method assembles the grand mobility and reads its
    // spins from it; the others add one pass of the pairs' rotation blocks a step.
    let grand = plan.rotation && plan.method == Method::RattleStable;
    let assembly = if grand {
        cost.grand_assembly
    } else {
        cost.assembly
    };
    let spin = if plan.rotation && !grand {
        cost.spin
    } else {
        0.0
    };
    // The stored paths' noise: the Cholesky factor and its two triangular products, or
    // Lanczos on the stored mobility, from `REDUCED_MIN` spheres (midpoint drift, f64)
    // on its reduced copy, written by the first product.
    let reduced = lanczos
        && inverse
        && plan.precision == super::Precision::F64
        && matches!(plan.method, Method::Overdamped | Method::Springs)
        && hydrorattle::noise::reduced::usable::<f64>(s.n);
    let stored_noise = match (thermal, lanczos, reduced) {
        (false, _, _) => 0.0,
        (true, false, _) => cost.cholesky + 2.0 * cost.dense,
        (true, true, true) => cost.copy + (iterations - 1.0) * cost.compact,
        (true, true, false) => iterations * cost.dense,
    };
    let free_ok = matches!(
        plan.method,
        Method::Overdamped | Method::Overdamped2 | Method::Springs
    ) && !plan.wall
        && !plan.slit
        && !plan.near
        && (!thermal || plan.brownian.is_none_or(|t| t.sqrt != Sqrt::Cholesky))
        && (rows == 0 || krylov);
    let every = products + iterations;
    match choice {
        FreeChoice::Dense => {
            Some(assembly * assemblies + cost.dense * products + stored_noise + spin)
        }
        FreeChoice::Compact => p.compact_copy(s.n, s.bonds).then(|| {
            let constrained = solve + mid;
            cost.assembly * assemblies
                + cost.copy * assemblies
                + cost.dense * (products - constrained)
                + cost.compact * constrained
                + stored_noise
                + spin
        }),
        FreeChoice::MatrixFree => free_ok.then_some(cost.matrix_free * every + spin),
        // With rotation every product runs under the grand parameters, and the spins
        // are one grand product.
        FreeChoice::Fast if plan.rotation => cost
            .fast_grand
            .filter(|_| free_ok && s.rpy)
            .map(|(t, g)| t * every + g),
        FreeChoice::Fast => cost.fast.filter(|_| free_ok && s.rpy).map(|t| t * every),
    }
}

/// Whether a thermal step of `plan` by `choice` takes no more Lanczos iterations than
/// the kernel's cap (`Params::lanczos`, 64 by default), as modelled ([`free_noise`]):
/// the kernel refuses a step whose run has not converged by then. The pair paths'
/// midpoint needs the inverse root too, and more iterations (measured: refused at
/// 3000 spheres at volume fraction 0.3, where the fast path's root alone took 40).
/// `true` for a deterministic step and for the Cholesky factor.
pub fn within_cap(plan: &Plan, s: &Spheres, choice: FreeChoice) -> bool {
    let p: Params<f64> = with_path(plan, choice).params(s.n);
    let Some(t) = plan.brownian.filter(|t| t.temperature > 0.0) else {
        return true;
    };
    if !p.lanczos_noise(s.n) {
        return true;
    }
    let fast = choice == FreeChoice::Fast;
    let inverse = t.drift == Drift::Midpoint && !fast;
    free_noise::iterations(s, inverse) <= f64::from(p.lanczos.max_iterations)
}

/// The bytes a step of `plan` with `choice` keeps: the kernel's storage
/// ([`Plan::bytes`]), and the fast product's grid and lists.
pub fn storage(plan: &Plan, s: &Spheres, tolerance: f64, choice: FreeChoice) -> Option<usize> {
    let step = with_path(plan, choice).bytes(s.n, s.bonds)?;
    if choice != FreeChoice::Fast {
        return Some(step);
    }
    let ff = fast_params(s, tolerance, plan.rotation)?;
    let (z, vectors) = if plan.rotation {
        // The grand product's zero torques and discarded velocities.
        (ff.storage_grand(s.n), 2 * s.n)
    } else {
        (ff.storage(s.n), 0)
    };
    let grid = z.complex.checked_mul(16)? + z.reals.checked_mul(8)? + z.index.checked_mul(8)?;
    step.checked_add(grid)?
        .checked_add(vectors.checked_mul(24)?)
}

/// The path `auto` takes for a free-space step of `plan` on the spheres `s` with the
/// fast product at `tolerance`: the fastest modelled ([`step_cost`]) of those that
/// can run it and whose [`storage`] fits in `limit` bytes, with its modelled seconds a
/// step, preferring those whose Lanczos iterations stay [`within_cap`] (where none
/// does, the fastest of all that fit); refused, naming the smallest need, where none
/// fits.
pub fn choose(
    plan: &Plan,
    s: &Spheres,
    tolerance: f64,
    limit: usize,
) -> Result<(FreeChoice, f64), TooLarge> {
    choose_priced(plan, s, &FreeCost::of(s, tolerance), tolerance, limit)
}

/// [`choose`] with the paths' costs given (the fast product's near pairs counted).
fn choose_priced(
    plan: &Plan,
    s: &Spheres,
    cost: &FreeCost,
    tolerance: f64,
    limit: usize,
) -> Result<(FreeChoice, f64), TooLarge> {
    // The best under the cap, and the best of all.
    let mut best: [Option<(FreeChoice, f64)>; 2] = [None, None];
    let mut need: Option<usize> = None;
    for choice in CHOICES {
        let Some(t) = step_cost(plan, s, cost, choice) else {
            continue;
        };
        let bytes = storage(plan, s, tolerance, choice);
        if let Some(b) = bytes {
            need = Some(need.map_or(b, |m| m.min(b)));
        }
        if bytes.is_none_or(|b| b > limit) {
            continue;
        }
        let capped = within_cap(plan, s, choice);
        for (k, b) in best.iter_mut().enumerate() {
            if (k == 1 || capped) && b.is_none_or(|(_, bt)| t < bt) {
                *b = Some((choice, t));
            }
        }
    }
    best[0].or(best[1]).ok_or(TooLarge {
        particles: s.n,
        bonds: s.bonds,
        bytes: need,
        limit,
    })
}

/// [`choose`] for a free-space `scene` as it will run (its level applied): its plan
/// ([`Plan::of`]), its spheres ([`Spheres::of`]), the fast product at `tolerance` and
/// the step storage limit `limit`. The fast product's near pairs are counted from the
/// spheres' centres ([`count_pairs`](super::free_reweigh::count_pairs)), as the
/// model's constant was fitted (the even estimate undercounts a ball's).
pub fn choose_for(
    scene: &super::Scene,
    tolerance: f64,
    limit: usize,
) -> Result<(FreeChoice, f64), TooLarge> {
    let s = Spheres::of(scene);
    let pos: Vec<[f64; 3]> = scene.particles.iter().map(|p| p.position).collect();
    let count = |r_cut| super::free_reweigh::count_pairs(&pos, r_cut, u64::MAX) as f64;
    let cost = FreeCost::counted(&s, tolerance, &count);
    choose_priced(&Plan::of(scene), &s, &cost, tolerance, limit)
}

impl super::Scene {
    /// This scene with `[free_space] method = "auto"` resolved for the run: the path
    /// [`choose_for`] takes under [`DEFAULT_LIMIT`](super::sizing::DEFAULT_LIMIT)
    /// (`"dense"`, with `compact_products` or `matrix_free` where it picks those, or
    /// `"fast"`, matrix-free), so that the run's `scene.toml` names the path it ran.
    /// Where no path fits the limit it takes the fast path, whose storage the run then
    /// checks and refuses. Other scenes are returned as they are.
    pub fn with_free_resolved(mut self) -> super::Scene {
        use super::free_space::FreeMethod;
        let Some(f) = self.free_space.filter(|f| f.method == FreeMethod::Auto) else {
            return self;
        };
        let choice = choose_for(&self, f.tolerance, super::sizing::DEFAULT_LIMIT)
            .map_or(FreeChoice::Fast, |(c, _)| c);
        let method = match choice {
            FreeChoice::Dense => FreeMethod::Dense,
            FreeChoice::Compact => {
                self.integrator.compact_products = true;
                FreeMethod::Dense
            }
            FreeChoice::MatrixFree => {
                self.integrator.matrix_free = true;
                FreeMethod::Dense
            }
            FreeChoice::Fast => {
                self.integrator.matrix_free = true;
                FreeMethod::Fast
            }
        };
        if let Some(fs) = self.free_space.as_mut() {
            fs.method = method;
            // Only a run on the fast product weighs it again.
            fs.reweigh &= method == FreeMethod::Fast;
        }
        self
    }
}
