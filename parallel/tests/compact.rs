//! The product paths on a thread pool: the recompute path (`parallel::free_product`,
//! `Params::matrix_free`) gives the stored banded product's bits, and the mixed-precision constraint solve
//! (`Params::compact_products`: `f32` products, `f64` residuals) meets the solver's tolerance, measured here from the
//! positions, and gives the same bits on any thread count.

use hydrorattle::glam::DVec3;
use hydrorattle::parallel::{self, Parallel, Serial, band_scratch, bands};
use hydrorattle::{Bond, Hydro, Layout, NoForce, Params, Real, State, StepReport, step_slices};
use hydrorattle_heap::Buffers;
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
    let start = helix(n);
    let bonds: Vec<Bond<f64>> = (1..n)
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: (start[i] - start[i - 1]).length(),
        })
        .collect();
    let (radius, density) = (vec![1.0; n], vec![4.5; n]);
    let mut p = Params::<f64>::new(0.05);
    p.compact_products = compact;
    p.matrix_free = free;
    assert_eq!(p.compact_copy(n, n - 1), compact);
    let mut store = Buffers::<f64>::new(Layout::for_params(&p, n, n - 1));
    let mut ws = store.workspace().with_parallel(par);
    let mut pos = start.clone();
    let (mut vel, mut omega, mut time) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n], 0.0);
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
        last = Some(step_slices(state, &bonds, &p, &mut ws, &mut NoForce).unwrap());
    }
    // The tolerance, measured from the positions: every bond's relative length error.
    let worst = bonds
        .iter()
        .map(|b| ((pos[b.i] - pos[b.j]).length() - b.length).abs() / b.length)
        .fold(0.0, f64::max);
    assert!(worst <= p.solver.tolerance, "bond error {worst:e}");
    (pos, last.unwrap())
}

#[test]
fn mixed_precision_constraints_meet_the_tolerance_with_the_same_bits_on_any_thread_count() {
    let n = 1024;
    let (exact, exact_report) = settle(n, 3, (false, false), &Serial);
    let (serial, report) = settle(n, 3, (true, false), &Serial);
    // Both meet the tolerance; they differ by the rounded mobility's share of the
    // constraint moves (~1e-7 of them), far below a step's move (~0.02 per step).
    let gap = serial
        .iter()
        .zip(&exact)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f64::max);
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
