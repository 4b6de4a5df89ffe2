//! Brownian steps with Stokesian dynamics' near field (`Params::near`, noise by
//! Cholesky): the equilibria the Boltzmann weight gives, whatever the mobility.
//!
//! * A sphere above the wall under gravity: its heights follow `exp(-W h / kT)`. The
//!   near field's perpendicular mobility near the wall is Brenner's, which vanishes at
//!   contact (lubrication) and so has a large divergence there; the midpoint drift must
//!   supply `kT d mu_perp / dh` exactly, or the heights follow
//!   `exp(-W h / kT) / mu_perp(h)` instead, in the limit of small steps (the uncorrected
//!   scheme's bias is asserted too, so the test can tell). Statistic as in `wall_barometric.rs`: the mean excess
//!   height above `h0`, `E[h - h0 | h > h0]`, which is the decay length `kT / W = 1`
//!   whatever `h0`.
//! * A freely jointed trimer whose beads are within the near field's cutoff of each
//!   other: its bond angle follows the flexible (stiff-bond) distribution, uniform in
//!   the cosine `c`, `<c^2> = 1/3`, not the rigid one (0.32102). Long: `#[ignore]`d,
//!   outside `.ci/run`. Its minimum gap is 0.5 radii: at 0.1 the time step does not
//!   resolve the end beads' squeeze and the angle is biased (docs/NEAR.md).
//!
//! Units: `a = 1`, `eta = 1`, `kT = 1`, weight `W = 1` (density `3 / (4 pi)`, `g = 1`).

use crate::common;
use crate::stokesian::brenner;

use std::f64::consts::PI;

use common::thermal::*;
use common::*;
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, NoiseSqrt, ParticleSet, Real,
    SolverKind, Wall,
};
use hydrorattle_heap::Buffers;

/// The threshold above contact: `h0 = a + 0.5`.
pub(crate) const ABOVE: f64 = 0.5;

/// Heights above the wall (at 0) of a lone Brownian sphere with the near field, one
/// sample every `every` steps.
fn heights<T: Real>(drift: Drift, dt: f64, steps: usize, every: usize, seed: u64) -> Vec<f64> {
    heights_by::<T>(false, drift, dt, steps, every, seed)
}

/// [`heights`] by the dense near field or, `iterative`, by its iterative products
/// (`Params::matrix_free`, the noise's Lanczos root of the far field), the wall's link
/// then a constraint of the step.
pub(crate) fn heights_by<T: Real>(
    iterative: bool,
    drift: Drift,
    dt: f64,
    steps: usize,
    every: usize,
    seed: u64,
) -> Vec<f64> {
    let mut p = params::<T>(dt, Method::Overdamped, SolverKind::Auto);
    p.wall = Some(Wall::new(T::ZERO));
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift,
    });
    p.noise_sqrt = NoiseSqrt::Cholesky;
    p.near = Some(NearField::default());
    if iterative {
        p.matrix_free = true;
        p.noise_sqrt = NoiseSqrt::Lanczos;
    }
    let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
        pos: [0.0, 0.0, 2.0],
        radius: 1.0,
        density: 3.0 / (4.0 * PI),
    }]);
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(seed);
    let mut out = Vec::with_capacity(steps / every);
    for k in 0..steps {
        step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise)
            .unwrap_or_else(|e| panic!("{drift:?} step {k}: {e}"));
        if k % every == 0 {
            out.push(f64s::<T>(ps.pos[0])[2]);
        }
    }
    out
}

/// `E[h - h0 | h > h0]` and its standard error from `blocks` consecutive blocks.
pub(crate) fn excess(h: &[f64], h0: f64, blocks: usize) -> (f64, f64) {
    let len = h.len() / blocks;
    let means: Vec<f64> = h
        .chunks_exact(len)
        .map(|c| {
            let above: Vec<f64> = c.iter().filter(|&&x| x > h0).map(|x| x - h0).collect();
            above.iter().sum::<f64>() / above.len() as f64
        })
        .collect();
    mean_se(&means)
}

/// `dt = 0.5`, 600 000 steps per scheme, a sample every 10 steps, 40 blocks (about
/// 20 s per scheme in release): the midpoint within 3 standard errors of the exact 1,
/// the uncorrected scheme more than 3 from it, below it (towards its biased
/// equilibrium; at this `dt`, where a step's move near contact is comparable to the
/// gap, it lies beyond that equilibrium: 0.65 for 0.79 in `f64`). The test's power: the
/// exact and the biased equilibria are more than 5 standard errors apart.
fn barometric_with_the_near_field<T: Real>() {
    let h0 = 1.0 + ABOVE;
    let (exact, biased) = (1.0, thermal::biased_mean(h0, 20_000, brenner));
    let mut results = Vec::new();
    for (drift, seed) in [(Drift::Midpoint, 5), (Drift::Uncorrected, 6)] {
        let h = heights::<T>(drift, 0.5, 600_000, 10, seed);
        let (m, se) = excess(&h, h0, 40);
        eprintln!(
            "near field, {drift:?}: E[h - h0 | h > h0] = {m:.4} +- {se:.4} (exact {exact}, uncorrected equilibrium {biased:.4})"
        );
        results.push((m, se));
    }
    let ((mid, se_mid), (unc, se_unc)) = (results[0], results[1]);
    assert!(
        (exact - biased).abs() > 5.0 * se_mid,
        "too few samples (se {se_mid})"
    );
    assert!(
        (mid - exact).abs() < 3.0 * se_mid,
        "midpoint {mid} +- {se_mid} vs {exact}"
    );
    assert!(
        exact - unc > 3.0 * se_unc,
        "uncorrected {unc} +- {se_unc} shows no bias towards {biased}"
    );
}

both_precisions! {
    barometric => barometric_with_the_near_field;
}

/// The cosine `c` of the bond angle of a freely jointed trimer (unit radii, bonds 3:
/// gaps of one radius, inside the cutoff) after each of `steps` steps, with the near
/// field of minimum gap `min_gap` (the roughness parameter, which keeps the squeeze
/// resistance of the end beads, which may overlap, finite; `None`: RPY alone).
fn trimer_cosines(min_gap: Option<f64>, dt: f64, steps: usize, seed: u64) -> Vec<f64> {
    trimer_cosines_by(false, min_gap, dt, steps, seed)
}

/// [`trimer_cosines`] by the dense near field or, `iterative`, by its iterative
/// products (`Params::matrix_free`, the noise's Lanczos root of the far field).
pub(crate) fn trimer_cosines_by(
    iterative: bool,
    min_gap: Option<f64>,
    dt: f64,
    steps: usize,
    seed: u64,
) -> Vec<f64> {
    let d = 3.0;
    let mut ps: ParticleSet<f64, 3> = particles(&[
        Sphere {
            pos: [0.0; 3],
            radius: 1.0,
            density: 0.0,
        },
        Sphere {
            pos: [d, 0.0, 0.0],
            radius: 1.0,
            density: 0.0,
        },
        Sphere {
            pos: [d, d, 0.0],
            radius: 1.0,
            density: 0.0,
        },
    ]);
    let bonds: BondSet<f64, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
    let mut p = thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
    p.allow_overlap = true;
    p.noise_sqrt = NoiseSqrt::Cholesky;
    p.near = min_gap.map(|min_gap| NearField {
        min_gap,
        ..NearField::default()
    });
    if iterative {
        p.matrix_free = true;
        p.noise_sqrt = NoiseSqrt::Lanczos;
    }
    let mut cs = Vec::with_capacity(steps);
    sample(&mut ps, &bonds, &p, seed, steps, |ps| {
        let at = |i: usize| ps.pos[i].to_array();
        let b1 = sub(at(0), at(1));
        let b2 = sub(at(1), at(2));
        cs.push(dot(b1, b2) / (norm(b1) * norm(b2)));
    });
    cs
}

/// `<c^2>` of the trimer of [`trimer_cosines`] and its standard error; with the share
/// of time the bond angle's cosine spends below -0.8 (the end beads overlap below
/// -7/9), uniform 0.1, and its standard error.
fn trimer(min_gap: f64, dt: f64, steps: usize, seed: u64) -> [(f64, f64); 2] {
    let cs = trimer_cosines(Some(min_gap), dt, steps, seed);
    let c2: Vec<f64> = cs.iter().map(|c| c * c).collect();
    [block_mean(&c2, 50), block_mean(&below(&cs), 50)]
}

/// 1 where the cosine `c` is below -0.8, else 0.
pub(crate) fn below(cs: &[f64]) -> Vec<f64> {
    cs.iter().map(|&c| f64::from(u8::from(c < -0.8))).collect()
}

/// 1 200 000 steps (about 75 s in release on one core), minimum gap 0.5: `<c^2>`
/// within 0.005 of the flexible 1/3, more than 4 standard errors from the rigid 0.32102,
/// standard error below 0.0018 (0.32969 +- 0.00158 measured).
///
/// Why 0.5 and not a smaller gap: a step moves the end beads apart along their line of
/// centres by about `sqrt(2 kT dt mu_rel)`, where lubrication makes their relative
/// mobility `mu_rel` about `4 xi` (unit bead mobility) at the gap `xi`; the midpoint's
/// drift is right only where that move is small against the gap, `dt << xi / 8`. At
/// `dt = 0.045` the move is 0.19 at a gap of 0.1 (0.13 at `dt = 0.0225`, 0.27 at
/// 0.09), so a minimum gap of 0.1 gives 0.3242, 0.3234 and 0.3245 at those steps
/// (standard errors 0.002 to 0.004): a bias that does not shrink until the step
/// resolves the gap, all of it where the end beads overlap (`c < -0.8`; the density of
/// `c` is flat elsewhere). At a gap of 0.5 the move is 0.42 (less: the lubrication form
/// overestimates `mu_rel` there), and the law is met.
#[test]
#[ignore = "about 75 s"]
fn trimer_bond_angle_with_the_near_field() {
    let rigid = (PI / 3.0 - 3f64.sqrt() / 4.0) / (PI / 3.0 + 3f64.sqrt() / 2.0);
    let flexible = 1.0 / 3.0;
    let [(m, se), _] = trimer(0.5, 0.045, 1_200_000, 21);
    eprintln!("trimer with the near field: <c^2> = {m:.5} +- {se:.5}, want {flexible:.5}");
    assert!(se < 0.0018, "too few samples (se {se})");
    assert!((m - flexible).abs() < 0.005, "{m} vs {flexible}");
    assert!((m - rigid).abs() > 4.0 * se, "cannot tell");
}

/// The trimer (minimum gap 0.5) at `dt` = 0.045, 0.015 and 0.005 over the same time
/// span (18 000 units): `<c^2>` and the share of time below `c = -0.8`, against the
/// flexible law's 1/3 and 0.1; and the near field's own part of that share: the run
/// again without the near field (RPY alone) from the same seed, and the difference of
/// the two, step by step, with its standard error from 50 blocks. The two runs share
/// their random draws and the angle follows them (their block shares correlate at
/// 0.97), so the difference is four to five times more precise than either share, and
/// a deviation of one seed's noise cancels in it (docs/NEAR.md). Long: minutes.
#[test]
#[ignore = "minutes: the trimer against the time step"]
fn trimer_in_dt() {
    for dt in [0.045, 0.015, 0.005] {
        let steps = (18_000.0 / dt) as usize;
        let cs = trimer_cosines(Some(0.5), dt, steps, 21);
        let c2: Vec<f64> = cs.iter().map(|c| c * c).collect();
        let (near, rpy) = (below(&cs), below(&trimer_cosines(None, dt, steps, 21)));
        let diff: Vec<f64> = near.iter().zip(&rpy).map(|(a, b)| a - b).collect();
        let [(m, se), (share, se_share)] = [block_mean(&c2, 50), block_mean(&near, 50)];
        let ((alone, se_alone), (d, se_d)) = (block_mean(&rpy, 50), block_mean(&diff, 50));
        eprintln!(
            "dt {dt}: <c^2> = {m:.5} +- {se:.5} ({:+.1} se from 1/3), P(c < -0.8) = {share:.5} +- {se_share:.5} ({:+.1} se from 0.1); RPY alone {alone:.5} +- {se_alone:.5}, near field less RPY alone {d:+.5} +- {se_d:.5}",
            (m - 1.0 / 3.0) / se,
            (share - 0.1) / se_share
        );
    }
}

/// A setting of [`trimer_histogram`] from the environment, or `default`.
fn setting(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// The density of the bond angle's cosine over `[-1, 1]` (flat 1 for the flexible
/// law) in the bins `edges` from `cs`, each with its standard error from 50 blocks.
fn density(cs: &[f64], edges: &[f64]) -> Vec<(f64, f64)> {
    edges
        .windows(2)
        .map(|w| {
            let inside: Vec<f64> = cs
                .iter()
                .map(|&c| f64::from(u8::from(c >= w[0] && c < w[1])))
                .collect();
            let (m, se) = block_mean(&inside, 50);
            let flat = (w[1] - w[0]) / 2.0;
            (m / flat, se / flat)
        })
        .collect()
}

/// The trimer's bond-angle histogram, for telling where a deviation from the flexible
/// law sits. Settings from the environment: `TRIMER_DT` (0.015), `TRIMER_SPAN` (time
/// units, 18 000), `TRIMER_GAP` (the minimum gap, 0.5; `off`: RPY alone, no near field),
/// `TRIMER_SEED` (21), `TRIMER_TSV` (a file to write the numbers to as the
/// tab-separated rows `bench/record.py` takes). Prints `<c^2>` and the share below
/// -0.8 with standard errors from 10 to 400 blocks (a block is 45 to 1 800 time units
/// at the default span, against a bond's turning time of a few units, so the errors
/// should agree), and the density of `c` in ten bins over `[-1, 1]` and four over
/// `[-1, -0.8]`; `TRIMER_BLOCKS` (a file for the share below -0.8 in each of 1 000
/// consecutive blocks). Run:
/// `TRIMER_DT=0.005 cargo test --release --test kernel near_brownian::trimer_histogram -- --ignored --nocapture`.
#[test]
#[ignore = "minutes: a diagnostic run, settings from the environment"]
fn trimer_histogram() {
    let dt: f64 = setting("TRIMER_DT", "0.015").parse().unwrap();
    let span: f64 = setting("TRIMER_SPAN", "18000").parse().unwrap();
    let gap = setting("TRIMER_GAP", "0.5");
    let min_gap = (gap != "off").then(|| gap.parse::<f64>().unwrap());
    let seed: u64 = setting("TRIMER_SEED", "21").parse().unwrap();
    let steps = (span / dt) as usize;
    let cs = trimer_cosines(min_gap, dt, steps, seed);
    let c2: Vec<f64> = cs.iter().map(|c| c * c).collect();
    let low = below(&cs);
    let field = min_gap.map_or("RPY alone".to_string(), |g| format!("minimum gap {g}"));
    let measurement = format!(
        "freely jointed trimer (bonds 3, unit radii, phantom beads), {field}, midpoint, Cholesky noise, standard errors from 50 blocks"
    );
    let case = format!("dt {dt}, {steps} steps, seed {seed}");
    let mut rows = Vec::new();
    for blocks in [10, 25, 50, 100, 200, 400] {
        let ((m, se), (l, se_l)) = (block_mean(&c2, blocks), block_mean(&low, blocks));
        eprintln!(
            "{case}, {blocks} blocks: <c^2> = {m:.5} +- {se:.5} ({:+.1} se from 1/3), P(c < -0.8) = {l:.5} +- {se_l:.5} ({:+.1} se from 0.1)",
            (m - 1.0 / 3.0) / se,
            (l - 0.1) / se_l
        );
        if blocks == 50 {
            rows.push(("<c^2>".to_string(), format!("{m:.5} +- {se:.5}")));
            rows.push((
                "share below c = -0.8".to_string(),
                format!("{l:.5} +- {se_l:.5}"),
            ));
        }
    }
    let coarse: Vec<f64> = (0..=10).map(|k| -1.0 + 0.2 * k as f64).collect();
    let fine: Vec<f64> = (0..=4).map(|k| -1.0 + 0.05 * k as f64).collect();
    for edges in [&coarse[..], &fine[..]] {
        for (w, (d, se)) in edges.windows(2).zip(density(&cs, edges)) {
            eprintln!(
                "  c in {:+.2}..{:+.2}: density {d:.4} +- {se:.4} ({:+.1} se from 1)",
                w[0],
                w[1],
                (d - 1.0) / se
            );
            rows.push((
                format!("density of c in {:+.2}..{:+.2} (flat 1)", w[0], w[1]),
                format!("{d:.4} +- {se:.4}"),
            ));
        }
    }
    if let Ok(path) = std::env::var("TRIMER_BLOCKS") {
        // The share below -0.8 in 1 000 consecutive blocks, to compare two runs.
        let len = low.len() / 1000;
        let text: String = low
            .chunks_exact(len)
            .map(|b| format!("{}\n", b.iter().sum::<f64>() / len as f64))
            .collect();
        std::fs::write(path, text).unwrap();
    }
    if let Ok(path) = std::env::var("TRIMER_TSV") {
        let text: String = rows
            .iter()
            .map(|(q, v)| format!("{measurement}\t{case}\t{q}\t{v}\n"))
            .collect();
        std::fs::write(path, text).unwrap();
    }
}
