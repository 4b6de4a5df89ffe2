//! Brownian motion in a periodic box, `kT = 1`, f64,
//! against values that do not come from the kernel:
//!
//! * a lone sphere's diffusion coefficient in cubic boxes `L/a = 5, 10, 20` against
//!   Hasimoto's expansion `D(L) = D0 (1 - 2.8372974794806 a/L + (4 pi/3)(a/L)^3)`
//!   (Hasimoto 1959; the constant written here, not taken from the kernel);
//! * a freely jointed chain (rigid bonds, phantom beads, RPY in a box smaller than the
//!   chain's contour) against `<R^2> = B b^2` (independent uniform bond directions: the
//!   stiff-bond equilibrium that `Drift::Midpoint` samples, `tests/kernel/brownian.rs`).
//!
//! Estimators and standard errors are stated at each test; every check also asserts
//! its own power (the standard error small enough that the named wrong answer fails).
//! `cargo test --release --test kernel periodic_brownian:: -- --nocapture` (about 40 s on 2
//! cores). Measured (seeds fixed):
//!
//! | L/a | D/D0 (30 000 steps) | Hasimoto | |
//! |-----|---------------------|----------|---|
//! | 5   | 0.46889 +- 0.00221  | 0.46605  | +1.29 se |
//! | 10  | 0.71939 +- 0.00339  | 0.72046  | -0.32 se |
//! | 20  | 0.85955 +- 0.00405  | 0.85866  | +0.22 se |
//!
//! Chain in a box of edge 10: `<R^2>` = 37.41 +- 1.23 (8 chains of 8 000 steps, +1.14
//! se) and 36.31 +- 0.42 (16 chains of 50 000 steps, `--ignored`, +0.74 se; 628 s on
//! the shared 2 cores), against 36.
//! The helpers (thermal parameters, sampling loop, block means, the zigzag chain and
//! the retried step) are those of `tests/kernel/brownian.rs` and `tests/kernel/weak_order.rs`, in
//! `tests/kernel/common/thermal.rs`.

use crate::common;

use common::thermal::*;
use common::*;
use hydrorattle::{BondSet, Drift, Hydro, Layout, Noise, ParticleSet, Periodic};
use hydrorattle_heap::Buffers;
use std::f64::consts::PI;

/// Hasimoto (1959): `D(L) / D0` of a sphere in a simple cubic array at `x = a/L`.
fn hasimoto(x: f64) -> f64 {
    1.0 - 2.8372974794806 * x + 4.0 * PI / 3.0 * x.powi(3)
}

/// The test's own minimum image in a cubic box of edge `l`.
fn image(d: [f64; 3], l: f64) -> [f64; 3] {
    d.map(|x| x - l * (x / l).round())
}

fn env(key: &str, default: usize) -> usize {
    std::env::var(key).map_or(default, |s| s.parse().unwrap())
}

/// A lone unit sphere (`eta = 1/(6 pi)`: `D0 = 1`, `dt = 0.5`) in cubic boxes of edge
/// `L = 5, 10, 20`, `STEPS` steps each (default 30 000).
///
/// Estimator: `D = <|dx|^2> / (6 dt)` over the per-step displacements (the test's own
/// minimum image; a step moves about 1.7, far below `L/2`). A lone sphere's mobility
/// does not depend on where it is in the box, so the steps are independent and each
/// `|dx|^2 / (2 D dt)` is chi-squared with 3 degrees of freedom: the standard error is
/// `D sqrt(2 / (3 n))` (0.47 % at 30 000), and the block estimate (50 blocks) is
/// asserted to agree with it within 30 %. Tolerance 3 standard errors. Power: at
/// `L = 20` the free value `D0` is more than 20 standard errors away, and at `L = 5`
/// Hasimoto without its `(a/L)^3` term more than 10 (both asserted).
#[test]
fn lone_sphere_diffusion_follows_hasimoto() {
    let (dt, steps) = (0.5, env("STEPS", 30_000));
    for (k, l) in [5.0, 10.0, 20.0].into_iter().enumerate() {
        let mut ps: ParticleSet<f64, 1> = particles(&[Sphere {
            pos: [0.3, -1.2, 2.0],
            radius: 1.0,
            density: 0.0,
        }]);
        let bonds: BondSet<f64, 1> = BondSet::new();
        let mut p = thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
        p.periodic = Some(Periodic::new([l; 3]).unwrap());
        let mut prev = f64s::<f64>(ps.pos[0]);
        let mut sq = Vec::with_capacity(steps);
        sample(&mut ps, &bonds, &p, 100 + k as u64, steps, |ps| {
            let x = f64s::<f64>(ps.pos[0]);
            let d = image(sub(x, prev), l);
            sq.push(dot(d, d) / (6.0 * dt));
            prev = x;
        });
        let want = hasimoto(1.0 / l);
        let (d, se_blocks) = block_mean(&sq, 50);
        let se = d * (2.0 / (3.0 * steps as f64)).sqrt();
        eprintln!(
            "L/a = {l}: D/D0 = {d:.5} +- {se:.5} (blocks {se_blocks:.5}), Hasimoto {want:.5}, {:+.2} se",
            (d - want) / se
        );
        assert!(
            (se_blocks / se - 1.0).abs() < 0.3,
            "block se {se_blocks} vs chi^2 se {se}"
        );
        assert!((d - want).abs() < 3.0 * se, "L = {l}: D {d} vs {want}");
        match l {
            20.0 => assert!((1.0 - want) > 20.0 * se, "cannot tell the box"),
            5.0 => assert!(4.0 * PI / 3.0 / 125.0 > 10.0 * se, "cannot tell a^3/L^3"),
            _ => {}
        }
    }
}

/// Beads of the chain test.
const N: usize = 5;

/// One chain's run in a cubic box of edge `l`: `R^2` (end to end, the sum of the
/// bonds' minimum images) sampled every `every` steps after `burn` steps.
fn chain_r2(l: f64, dt: f64, seed: u64, steps: usize, burn: usize, every: usize) -> Vec<f64> {
    let (mut ps, bonds) = zigzag_chain::<N, { N - 1 }>(N, 3.0);
    let mut p = thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
    p.allow_overlap = true;
    p.periodic = Some(Periodic::new([l; 3]).unwrap());
    ps.noise = Some(Noise::new(seed));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, N, N - 1));
    let mut ws = buf.workspace();
    let mut out = Vec::new();
    for k in 0..steps {
        step_retrying(&mut ps, &bonds, &p, &mut ws);
        if k >= burn && (k - burn).is_multiple_of(every) {
            let r = (1..N).fold([0.0; 3], |acc, j| {
                add(
                    acc,
                    image(sub(f64s::<f64>(ps.pos[j]), f64s::<f64>(ps.pos[j - 1])), l),
                )
            });
            out.push(dot(r, r));
        }
    }
    out
}

/// `<R^2>` and its standard error over `chains` independent chains (seeds `200..`),
/// each chain's time average one sample, on two threads.
fn chains_r2(l: f64, dt: f64, chains: u64, steps: usize) -> (f64, f64) {
    // Bond orientations decorrelate within about 10 time units (R^2's autocorrelation
    // is 0.28 at 10, 0.12 at 20): burn 20 time units, sample every 0.5.
    let (burn, every) = ((20.0 / dt) as usize, (0.5 / dt) as usize);
    over_seeds(chains, |seed| {
        mean_se(&chain_r2(l, dt, 200 + seed, steps, burn, every)).0
    })
}

/// A freely jointed chain of 5 unit beads, bonds `b = 3` (`B = 4`, contour 12), rigid,
/// phantom (overlap allowed), RPY, `Drift::Midpoint`, bead mobility 1, `dt = 0.1`, in
/// a cubic box of edge 10 (smaller than the contour: the chain meets its own images).
/// Exact: `<R^2> = B b^2 = 36`.
///
/// Estimator: each chain's time average of `R^2` (sampled every 0.5 time units after 20)
/// is one sample; the mean over independent chains, its standard error from their
/// spread. CI: 8 chains of 8 000 steps (standard error about 3.5 %, asserted below 5 %,
/// so a 15 % error fails; about 40 s on 2 cores); tolerance 3 standard errors. `CHAINS` and `STEPS` override;
/// the full run is `#[ignore]`d (below).
#[test]
fn chain_end_to_end() {
    chain_check(env("CHAINS", 8) as u64, env("STEPS", 8_000), 0.05);
}

/// The full run: 16 chains of 50 000 steps (628 s on 2 shared cores; standard error
/// asserted below 2 %, so a 6 % error fails). `cargo test --release --test kernel periodic_brownian:: -- --ignored --nocapture`.
#[test]
#[ignore = "minutes: cargo test --release --test kernel periodic_brownian:: -- --ignored"]
fn chain_end_to_end_long() {
    chain_check(16, 50_000, 0.02);
}

fn chain_check(chains: u64, steps: usize, max_se: f64) {
    let exact = 4.0 * 9.0;
    let t = std::time::Instant::now();
    let (m, se) = chains_r2(10.0, 0.1, chains, steps);
    eprintln!(
        "chain in a box: <R^2> = {m:.3} +- {se:.3} (B b^2 = {exact}, {:+.2} se), {chains} chains of {steps} steps, {:.1} s",
        (m - exact) / se,
        t.elapsed().as_secs_f64()
    );
    assert!(se < max_se * exact, "too few samples: se {se}");
    assert!((m - exact).abs() < 3.0 * se, "<R^2> {m} vs {exact}");
}

/// In a box without bonds the midpoint's mean `kT dt div M` is zero (the box's RPY
/// mobility is divergence-free), so `Drift::Midpoint` takes the explicit
/// Euler-Maruyama draw `sqrt(2 kT dt) L xi` (one assembly a step, not two): the same
/// bits as `Drift::Uncorrected`, step after step, with the Cholesky and the Lanczos
/// noise and with the springs method's forces. In free space the two differ (the
/// midpoint is kept there), so the comparison has power.
#[test]
fn midpoint_in_a_box_without_bonds_is_euler_maruyama() {
    use hydrorattle::{Method, NoiseSqrt};
    let spheres = [
        ([0.3, -1.2, 2.0], 1.0),
        ([2.9, 0.4, 1.1], 0.8),
        ([-1.7, 1.5, -2.2], 1.2),
    ];
    let run = |drift: Drift, boxed: bool, sqrt: NoiseSqrt, method: Method| {
        let mut ps: ParticleSet<f64, 3> = particles(&spheres.map(|(pos, radius)| Sphere {
            pos,
            radius,
            density: 0.0,
        }));
        let bonds: BondSet<f64, 1> = BondSet::new();
        let mut p = thermal::<f64>(0.05, 1.0 / (6.0 * PI), Hydro::Rpy, drift);
        p.noise_sqrt = sqrt;
        p.method = method;
        if boxed {
            p.periodic = Some(Periodic::new([9.0, 10.0, 11.0]).unwrap());
        }
        let mut states = Vec::new();
        sample(&mut ps, &bonds, &p, 7, 20, |ps| states.push(snapshot(ps)));
        states
    };
    for sqrt in [NoiseSqrt::Cholesky, NoiseSqrt::Lanczos] {
        for method in [Method::Overdamped, Method::Springs] {
            let mid = run(Drift::Midpoint, true, sqrt, method);
            let em = run(Drift::Uncorrected, true, sqrt, method);
            assert!(mid == em, "{sqrt:?} {method:?}: box");
        }
        let free = |d| run(d, false, sqrt, Method::Overdamped);
        assert!(
            free(Drift::Midpoint) != free(Drift::Uncorrected),
            "{sqrt:?}: free space"
        );
    }
}
