//! The product paths on a thread pool: the recompute path (`parallel::free_product`,
//! `Params::matrix_free`) gives the stored banded product's bits, and the mixed-precision constraint solve
//! (`Params::compact_products`: `f32` products, `f64` residuals) meets the solver's tolerance, measured here from the
//! positions, and gives the same bits on any thread count: in free space and in a
//! periodic box with the stored Ewald mobility, where its trajectory also stays within
//! a stated bound of the `f64` products' (pinned digest); in thermal steps, from the
//! Lanczos noise's reduced copy. Above a wall and with PSE the
//! flag is ignored (`Params::compact_copy`): the `f64` products' bits and storage.
//!
//! The box's runs assemble the Ewald mobility of 700 spheres at every step (about
//! 2.5 s on one core): the `f64` run and one compact run use two threads.

use hydrorattle::glam::DVec3;
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Parallel, Serial, band_scratch, bands};
use hydrorattle::{
    Bond, Brownian, Drift, Hydro, Layout, NoForce, Noise, Params, Periodic, Real, StepReport, Wall,
    step_slices,
};
use hydrorattle_heap::{Buffers, Spheres};
use hydrorattle_parallel::Threads;

/// `n` beads of radius 1 on a helix (radius 3, rise 2.5 per bead), bonds of length 3.
fn helix(n: usize) -> Vec<DVec3> {
    let phi = 2.0 * ((9.0f64 - 6.25).sqrt() / 6.0).asin();
    (0..n)
        .map(|k| {
            let a = phi * k as f64;
            DVec3::new(3.0 * a.cos(), 3.0 * a.sin(), 2.5 * k as f64)
        })
        .collect()
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
}

#[test]
fn recomputed_products_are_the_stored_products_bits_on_any_thread_count() {
    for n in [100, 700] {
        let pos = helix(n);
        // Radii 0.8 .. 1.2: pairs of unequal spheres.
        let radius: Vec<f64> = (0..n)
            .map(|i| 0.8 + 0.4 * ((i * 7) % 5) as f64 / 4.0)
            .collect();
        let x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new((i as f64).sin(), (0.3 * i as f64).cos(), 0.5))
            .collect();
        let mut mu = vec![f64::M3_ZERO; n * (n + 1) / 2];
        let mut z = vec![DVec3::ZERO; band_scratch(n)];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
        let mut stored = vec![DVec3::ZERO; n];
        parallel::product::<f64>(&Serial, &mu, n, &x, &mut stored, &mut z);
        for t in [1, 2, 3] {
            let pool = Threads::new(t).unwrap();
            let mut y = vec![DVec3::ZERO; n];
            parallel::free_product::<f64>(
                &pool,
                Hydro::Rpy,
                1.0,
                &pos,
                &radius,
                &x,
                &mut y,
                &mut z,
            )
            .unwrap();
            assert_eq!(
                bits(&y),
                bits(&stored),
                "N = {n} ({} bands), {t} threads",
                bands(n)
            );
        }
    }
    // A nested pair: the assembly's error.
    let mut pos = helix(700);
    pos[650] = pos[20];
    let radius = vec![1.0; 700];
    let (x, mut y, mut z) = (
        vec![DVec3::ONE; 700],
        vec![DVec3::ZERO; 700],
        vec![DVec3::ZERO; band_scratch(700)],
    );
    let mut mu = vec![f64::M3_ZERO; 700 * 701 / 2];
    let want = parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut mu);
    let got =
        parallel::free_product::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &x, &mut y, &mut z);
    assert!(want.is_err());
    assert_eq!(got, want);
}

/// Steps of a settling `n`-bead helix through `par` (with `compact_products`, with
/// `matrix_free`); positions and the last report.
fn settle(
    n: usize,
    steps: usize,
    (compact, free): (bool, bool),
    par: &dyn Parallel,
) -> (Vec<DVec3>, StepReport<f64>) {
    let mut p = Params::<f64>::new(0.05);
    p.compact_products = compact;
    p.matrix_free = free;
    assert_eq!(p.compact_copy(n, n - 1), compact);
    chain_steps(&p, &helix(n), steps, par)
}

/// `steps` steps with `p` of a chain of radius-1 beads (density 4.5) from `start`, its
/// bonds at their start lengths, through `par`: the positions and the last report,
/// after checking every bond's length against the solver's tolerance, each length
/// computed here from the positions (in a box by the minimum image
/// `d - L round(d / L)`).
fn chain_steps(
    p: &Params<f64>,
    start: &[DVec3],
    steps: usize,
    par: &dyn Parallel,
) -> (Vec<DVec3>, StepReport<f64>) {
    let n = start.len();
    let bonds: Vec<Bond<f64>> = (1..n)
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: (start[i] - start[i - 1]).length(),
        })
        .collect();
    let mut store = Buffers::<f64>::new(Layout::for_params(p, n, n - 1));
    let mut ws = store.workspace().with_parallel(par);
    let mut s = Spheres::at_rest(start.to_vec(), vec![1.0; n], vec![4.5; n]);
    // Thermal runs draw from the same seed.
    s.noise = p.brownian.map(|_| Noise::new(11));
    let mut last = None;
    for _ in 0..steps {
        last = Some(step_slices(s.state(), &bonds, p, &mut ws, &mut NoForce).unwrap());
    }
    let pos = s.pos;
    // The tolerance, measured from the positions: every bond's relative length error.
    let edge = p.periodic.map(|c| DVec3::from(c.size()));
    let image = |d: DVec3| edge.map_or(d, |l| d - l * (d / l).round());
    let worst = bonds
        .iter()
        .map(|b| (image(pos[b.i] - pos[b.j]).length() - b.length).abs() / b.length)
        .fold(0.0, f64::max);
    assert!(
        worst <= p.solver.tolerance,
        "compact {}: bond error {worst:e}",
        p.compact_products
    );
    (pos, last.unwrap())
}

#[test]
fn mixed_precision_constraints_meet_the_tolerance_with_the_same_bits_on_any_thread_count() {
    let n = 1024;
    let (exact, exact_report) = settle(n, 3, (false, false), &Serial);
    let (serial, report) = settle(n, 3, (true, false), &Serial);
    // Both meet the tolerance; they differ by the rounded mobility's share of the
    // constraint moves (~1e-7 of them), far below a step's move (~0.02 per step).
    let gap = largest_gap(&serial, &exact);
    assert!(gap < 5e-8, "compact vs f64 products: {gap:e}");
    assert!(serial != exact, "the compact path must have been taken");
    eprintln!(
        "N = {n}: constraint products per step {} (f64) and {} (f32); gap {gap:.1e}",
        exact_report.iterations, report.iterations
    );
    for t in [2, 3] {
        let pool = Threads::new(t).unwrap();
        let (threaded, _) = settle(n, 3, (true, false), &pool);
        assert_eq!(bits(&threaded), bits(&serial), "{t} threads");
    }
}

/// Thermal steps (kT = 1, midpoint drift, Lanczos noise from the reduced copy of the
/// mobility, `noise::reduced::for_noise`): with `compact_products` the projection's
/// Krylov products read that same copy. No second copy (the layout is the one without
/// the flag); the bonds meet the tolerance (`chain_steps`); the same bits on 1 and 2
/// threads; the trajectory near the `f64` products' from the same seed. The uncorrected
/// drift keeps no copy: the flag changes no bit there.
#[test]
fn thermal_steps_reuse_the_noises_copy_for_their_constraint_products() {
    let (n, steps) = (N, 3);
    let thermal = |compact: bool, drift: Drift| {
        let mut p = Params::<f64>::new(0.05);
        let mut b = Brownian::new(1.0);
        b.drift = drift;
        p.brownian = Some(b);
        p.compact_products = compact;
        p
    };
    let (exact, compact) = (
        thermal(false, Drift::Midpoint),
        thermal(true, Drift::Midpoint),
    );
    assert!(compact.compact_copy(n, n - 1) && !exact.compact_copy(n, n - 1));
    assert_eq!(
        Layout::for_params(&compact, n, n - 1),
        Layout::for_params(&exact, n, n - 1),
        "the noise's copy is reused, not made twice"
    );
    let two = Threads::new(2).unwrap();
    let (reference, exact_report) = chain_steps(&exact, &helix(n), steps, &two);
    let (serial, report) = chain_steps(&compact, &helix(n), steps, &Serial);
    let (threaded, _) = chain_steps(&compact, &helix(n), steps, &two);
    assert_eq!(bits(&threaded), bits(&serial), "1 and 2 threads");
    // Pinned on this branch (`bcompact`); regenerate only for a deliberate change of
    // the arithmetic.
    assert_eq!(
        digest(&serial),
        0x6c18_a207_f97b_c634,
        "golden digest of the compact thermal steps"
    );
    // The noise is the same draw in both runs (both read the copy for it); they differ
    // by the rounded mobility's share of the constraint moves, each product right to
    // ~3e-7 relative, bounded as in the box: `steps x 1e-6 x moved`.
    let runs = (&reference[..], &serial[..], exact_report, report);
    near_f64("thermal", &helix(n), steps, runs);
    // The uncorrected drift: no copy, the f64 products' bits.
    let (on, off) = (
        thermal(true, Drift::Uncorrected),
        thermal(false, Drift::Uncorrected),
    );
    assert!(!on.compact_copy(n, n - 1));
    let (with, _) = chain_steps(&on, &helix(n), 1, &two);
    let (without, _) = chain_steps(&off, &helix(n), 1, &two);
    assert_eq!(bits(&with), bits(&without));
}

#[test]
fn matrix_free_steps_are_the_stored_steps_bits_on_any_thread_count() {
    // 700 beads: sixteen bands, the Krylov solve.
    let n = 700;
    let (stored, _) = settle(n, 2, (false, false), &Serial);
    for t in [1, 2, 3] {
        let pool = Threads::new(t).unwrap();
        let (free, _) = settle(n, 2, (false, true), &pool);
        assert_eq!(bits(&free), bits(&stored), "{t} threads");
    }
}

/// Beads of the runs: the fewest that take the copy (`REDUCED_MIN`).
const N: usize = 700;

/// Edge of the cubic box: a 9^3 lattice of spacing 3.
const EDGE: f64 = 27.0;

/// `n` beads on a snake through the 9^3 lattice of spacing 3 that fills the box (each
/// row and each layer reversing the previous one, so consecutive beads are neighbours),
/// jittered by up to 0.2 off the sites: volume fraction 0.15, images at every
/// distance, no two spheres (radius 1) closer than 2.3.
fn snake(n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|k| {
            let (x, y, z) = (k % 9, (k / 9) % 9, k / 81);
            let x = if (k / 9) % 2 == 1 { 8 - x } else { x };
            let y = if z % 2 == 1 { 8 - y } else { y };
            let t = k as f64;
            let jitter = DVec3::new((1.3 * t).sin(), (0.7 * t).cos(), (2.1 * t).sin());
            3.0 * DVec3::new(x as f64, y as f64, z as f64) + 1.5 + 0.2 * jitter
        })
        .collect()
}

/// Settling overdamped steps in the box (`dt` 0.05, Krylov: `Auto` at 699 bonds).
fn boxed(compact: bool) -> Params<f64> {
    let mut p = Params::<f64>::new(0.05);
    p.periodic = Some(Periodic::new([EDGE; 3]).unwrap());
    p.compact_products = compact;
    p
}

/// FNV-1a over the coordinates' bits: a golden digest of a configuration.
fn digest(v: &[DVec3]) -> u64 {
    bits(v)
        .iter()
        .flatten()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &c| {
            (h ^ c).wrapping_mul(0x100_0000_01b3)
        })
}

/// Largest coordinate difference of two configurations.
fn largest_gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f64::max)
}

#[test]
fn compact_products_in_a_box_meet_the_tolerance_near_the_f64_trajectory_with_the_same_bits() {
    let steps = 3;
    let (exact, compact) = (boxed(false), boxed(true));
    assert!(compact.compact_copy(N, N - 1) && !exact.compact_copy(N, N - 1));
    let two = Threads::new(2).unwrap();
    // `chain_steps` checks the bonds of each run against the tolerance.
    let (reference, exact_report) = chain_steps(&exact, &snake(N), steps, &two);
    let (threaded, report) = chain_steps(&compact, &snake(N), steps, &two);
    let (serial, _) = chain_steps(&compact, &snake(N), steps, &Serial);
    assert_eq!(bits(&threaded), bits(&serial), "1 and 2 threads");
    // Pinned on this branch (`boxcompact`); regenerate only for a deliberate change of
    // the arithmetic.
    assert_eq!(
        digest(&serial),
        0xd5a7_0ab3_ec8f_03a3,
        "golden digest of the compact steps in the box"
    );
    // The two trajectories differ by the rounded mobility's share of the constraint
    // moves: each product is right to ~3e-7 relative (`geometry/periodic/held.rs`), the
    // constraint moves are at most the beads' moves, `moved`, so after `steps` steps
    // the gap is bounded by `steps x 1e-6 x moved` (a factor of three over the product
    // error for the solve's amplification).
    let runs = (&reference[..], &serial[..], exact_report, report);
    near_f64("box", &snake(N), steps, runs);
}

/// The compact run `compact` of `steps` steps from `start` within
/// `steps x 1e-6 x moved` of the `f64` products' run `exact` (`moved`: the largest
/// move of a coordinate in `exact`, at least 1e-3), and not equal to it (the compact
/// path was taken); prints both runs' constraint products of the last step.
fn near_f64(
    what: &str,
    start: &[DVec3],
    steps: usize,
    (exact, compact, exact_report, report): (&[DVec3], &[DVec3], StepReport<f64>, StepReport<f64>),
) {
    let moved = largest_gap(exact, start);
    let apart = largest_gap(compact, exact);
    eprintln!(
        "{what}, N = {}, {steps} steps: moved {moved:.3e}, compact vs f64 {apart:.2e}; \
         constraint products last step {} (f64) and {} (f32)",
        start.len(),
        exact_report.iterations,
        report.iterations
    );
    assert!(moved > 1e-3, "{what}: the beads must have moved: {moved:e}");
    assert!(
        apart <= steps as f64 * 1e-6 * moved,
        "{what}: compact vs f64 trajectory {apart:e} (moved {moved:e})"
    );
    assert!(apart > 0.0, "{what}: the compact path must have been taken");
}

#[test]
fn a_wall_or_pse_keeps_the_f64_products() {
    let mut pse = boxed(true);
    pse.pse = Some(1e-6);
    let mut pse_free = pse;
    pse_free.matrix_free = true;
    let mut wall = Params::<f64>::new(0.05);
    wall.wall = Some(Wall::new(0.0));
    wall.compact_products = true;
    for (what, p) in [("PSE", pse), ("PSE matrix-free", pse_free), ("wall", wall)] {
        assert!(!p.compact_copy(N, N - 1), "{what}");
        let mut off = p;
        off.compact_products = false;
        assert_eq!(
            Layout::for_params(&p, N, N - 1),
            Layout::for_params(&off, N, N - 1),
            "{what}: no room for a copy"
        );
    }
    // The box itself takes the copy: room for it beside the f64 storage.
    let (on, off) = (boxed(true), boxed(false));
    let (a, b) = (
        Layout::for_params(&on, N, N - 1),
        Layout::for_params(&off, N, N - 1),
    );
    assert_eq!(a.blocks, b.blocks + reduced::slots(N));
    // Above the wall the flag changes no bit of a step (the snake sits above z = 1.3).
    let mut off = wall;
    off.compact_products = false;
    let two = Threads::new(2).unwrap();
    let (with, _) = chain_steps(&wall, &snake(N), 1, &two);
    let (without, _) = chain_steps(&off, &snake(N), 1, &two);
    assert_eq!(bits(&with), bits(&without));
}
