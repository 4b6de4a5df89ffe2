//! The compact `f32` copy of the mobility in a periodic box (`Params::compact_products`
//! with the stored Ewald mobility): a constrained step meets the solver's tolerance,
//! measured here from the positions; the trajectory stays within a stated bound of the
//! `f64` products' trajectory; the bits are the same on 1 and 2 threads. Above a wall
//! and with PSE the flag is ignored (`Params::compact_copy`): the `f64` products' bits
//! and storage.
//!
//! Each step assembles the Ewald mobility of 700 spheres (about 2.5 s on one core):
//! the f64 run and one compact run use two threads.

use hydrorattle::glam::DVec3;
use hydrorattle::noise::reduced;
use hydrorattle::{
    Bond, Layout, NoForce, Parallel, Params, Periodic, Serial, State, StepReport, Wall, step_slices,
};
use hydrorattle_heap::Buffers;
use hydrorattle_parallel::Threads;

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

/// The chain's bonds at their start lengths.
fn chain(start: &[DVec3]) -> Vec<Bond<f64>> {
    (1..start.len())
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: (start[i] - start[i - 1]).length(),
        })
        .collect()
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
}

/// Settling overdamped steps in the box (`dt` 0.05, Krylov: `Auto` at 699 bonds).
fn boxed(compact: bool) -> Params<f64> {
    let mut p = Params::<f64>::new(0.05);
    p.periodic = Some(Periodic::new([EDGE; 3]).unwrap());
    p.compact_products = compact;
    p
}

/// `steps` steps of the snake with `p` through `par`: the positions and the last report,
/// after checking every bond's length against the solver's tolerance, each length
/// computed here from the positions (minimum image: no bond is near half the box).
fn settle(p: &Params<f64>, steps: usize, par: &dyn Parallel) -> (Vec<DVec3>, StepReport<f64>) {
    let start = snake(N);
    let bonds = chain(&start);
    let (radius, density) = (vec![1.0; N], vec![4.5; N]);
    let mut store = Buffers::<f64>::new(Layout::for_params(p, N, N - 1));
    let mut ws = store.workspace().with_parallel(par);
    let mut pos = start.clone();
    let (mut vel, mut omega, mut time) = (vec![DVec3::ZERO; N], vec![DVec3::ZERO; N], 0.0);
    let mut last = None;
    for _ in 0..steps {
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        last = Some(step_slices(state, &bonds, p, &mut ws, &mut NoForce).unwrap());
    }
    let image = |d: DVec3| d - EDGE * (d / EDGE).round();
    let worst = bonds
        .iter()
        .map(|b| (image(pos[b.i] - pos[b.j]).length() - b.length).abs() / b.length)
        .fold(0.0, f64::max);
    assert!(
        worst <= p.solver.tolerance,
        "compact {}: bond error {worst:e} over the tolerance {:e}",
        p.compact_products,
        p.solver.tolerance
    );
    (pos, last.unwrap())
}

/// Largest coordinate difference of two configurations.
fn gap(a: &[DVec3], b: &[DVec3]) -> f64 {
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
    // `settle` checks the bonds of each run against the tolerance.
    let (reference, exact_report) = settle(&exact, steps, &two);
    let (threaded, report) = settle(&compact, steps, &two);
    let (serial, _) = settle(&compact, steps, &Serial);
    assert_eq!(bits(&threaded), bits(&serial), "1 and 2 threads");
    // Pinned on this branch (`boxcompact`); regenerate only for a deliberate change of
    // the arithmetic.
    let digest = bits(&serial)
        .iter()
        .flatten()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &c| {
            (h ^ c).wrapping_mul(0x100_0000_01b3)
        });
    assert_eq!(
        digest, 0xd5a7_0ab3_ec8f_03a3,
        "golden digest of the compact steps in the box"
    );
    // The two trajectories differ by the rounded mobility's share of the constraint
    // moves: each product is right to ~3e-7 relative (`integrate/periodic.rs`), the
    // constraint moves are at most the beads' moves, `moved`, so after `steps` steps
    // the gap is bounded by `steps x 1e-6 x moved` (a factor of three over the product
    // error for the solve's amplification).
    let start = snake(N);
    let moved = gap(&reference, &start);
    let apart = gap(&serial, &reference);
    eprintln!(
        "box, N = {N}, {steps} steps: moved {moved:.3e}, compact vs f64 {apart:.2e}; \
         constraint products last step {} (f64) and {} (f32)",
        exact_report.iterations, report.iterations
    );
    assert!(moved > 1e-3, "the beads must have moved: {moved:e}");
    assert!(
        apart <= steps as f64 * 1e-6 * moved,
        "compact vs f64 trajectory {apart:e} (moved {moved:e})"
    );
    assert!(apart > 0.0, "the compact path must have been taken");
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
    let (with, _) = settle(&wall, 1, &two);
    let (without, _) = settle(&off, 1, &two);
    assert_eq!(bits(&with), bits(&without));
}
