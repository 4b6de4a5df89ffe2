//! Brownian motion above the wall: a lone sphere under gravity,
//! held above the wall by the wall's one-sided constraint, reaches the barometric
//! distribution of its height, `P(h) ~ exp(-m_b g h / kT)` above its contact height,
//! with the midpoint scheme; without the correction it does not.
//!
//! Why the midpoint matters here: the wall's mobility normal to it, `mu_perp(h)`, grows
//! with the height, so `div mu = d mu_perp / dh != 0` and the Ito drift `kT div mu`
//! pushes the sphere away from the wall. Without it (`Drift::Uncorrected`) the zero-flux
//! condition `mu F P = kT d(mu P)/dh` gives `P(h) ~ exp(-W h / kT) / mu_perp(h)` instead:
//! too much weight near the wall.
//!
//! The statistic: the mean excess height above a threshold `h0` a little above contact,
//! `E[h - h0 | h > h0]`. For an exponential density it is the decay length
//! `l = kT / W` whatever `h0` (no memory), so the near-wall region, where the projection
//! onto the wall (a reflecting boundary of weak order 1/2) distorts the density at
//! finite `dt`, is left out of it. The biased value is the same mean over
//! `exp(-(h - h0) / l) / mu_perp(h)`, by quadrature with Swan and Brady's
//! `mu_perp(h) = (1 - 9/8 x + 1/2 x^3 - 1/8 x^5) / (6 pi eta a)`, `x = a / h`.
//! Standard errors from block means (blocks much longer than the relaxation time
//! `l^2 / D`).
//!
//! Units: `a = 1`, `eta = 1`, `kT = 1`, `g = 1`, density `3 / (4 pi)`: the buoyant
//! weight is `W = 1`, the layer `l = 1` radius thick.

use crate::common;

use std::f64::consts::PI;

use common::*;
use hydrorattle::{
    BondSet, Brownian, Drift, Layout, Method, NoForce, Noise, NoiseSqrt, ParticleSet, Real,
    SolverKind, Wall,
};
use hydrorattle_heap::Buffers;

/// Height of the wall (not zero: the projection's frame moves).
const H: f64 = -0.75;
/// The threshold above contact: `h0 = a + 0.5 l`.
const ABOVE: f64 = 0.5;

/// Swan and Brady's perpendicular mobility of a unit sphere at height `h` (`eta = 1`).
fn mu_perp(h: f64) -> f64 {
    let x = 1.0 / h;
    (1.0 - 1.125 * x + 0.5 * x.powi(3) - 0.125 * x.powi(5)) / (6.0 * PI)
}

/// Heights above the wall of a lone Brownian sphere, one sample every `every` steps.
fn heights<T: Real>(drift: Drift, dt: f64, steps: usize, every: usize, seed: u64) -> Vec<f64> {
    let mut p = params::<T>(dt, Method::Overdamped, SolverKind::Auto);
    p.wall = Some(Wall::new(T::from_f64(H)));
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift,
    });
    p.noise_sqrt = NoiseSqrt::Cholesky;
    let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
        pos: [0.0, 0.0, H + 2.0],
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
            out.push(f64s::<T>(ps.pos[0])[2] - H);
        }
    }
    out
}

/// `E[h - h0 | h > h0]` and its standard error from `blocks` consecutive blocks, and
/// the smallest height seen.
fn excess(h: &[f64], h0: f64, blocks: usize) -> (f64, f64, f64) {
    let len = h.len() / blocks;
    let means: Vec<f64> = h
        .chunks_exact(len)
        .map(|c| {
            let above: Vec<f64> = c.iter().filter(|&&x| x > h0).map(|x| x - h0).collect();
            above.iter().sum::<f64>() / above.len() as f64
        })
        .collect();
    let m = means.iter().sum::<f64>() / blocks as f64;
    let var = means.iter().map(|b| (b - m) * (b - m)).sum::<f64>() / (blocks - 1) as f64;
    let lowest = h.iter().copied().fold(f64::INFINITY, f64::min);
    (m, (var / blocks as f64).sqrt(), lowest)
}

fn barometric<T: Real>(dt: f64, steps: usize) {
    let h0 = 1.0 + ABOVE;
    let (exact, biased) = (1.0, thermal::biased_mean(h0, 400_000, mu_perp));
    let tol = pick::<T>(2e-5, 1e-9) * 2.0;
    let mut results = Vec::new();
    for (drift, seed) in [(Drift::Midpoint, 3), (Drift::Uncorrected, 4)] {
        let h = heights::<T>(drift, dt, steps, 10, seed);
        let (m, se, lowest) = excess(&h, h0, 40);
        eprintln!(
            "{drift:?} dt {dt}: E[h - h0 | h > h0] = {m:.4} +- {se:.4} (exact {exact}, uncorrected equilibrium {biased:.4}); lowest {lowest:.3e}"
        );
        assert!(
            lowest >= 1.0 - tol,
            "{drift:?}: the sphere crossed the wall ({lowest})"
        );
        results.push((m, se));
    }
    let ((mid, se_mid), (unc, se_unc)) = (results[0], results[1]);
    // Power: the wrong answer (the uncorrected equilibrium) is more than 6 standard
    // errors from the right one.
    assert!(
        (exact - biased).abs() > 6.0 * se_mid.max(se_unc),
        "too few samples"
    );
    assert!(
        (mid - exact).abs() < 3.0 * se_mid,
        "midpoint {mid} +- {se_mid} vs {exact}"
    );
    assert!(
        (unc - exact).abs() > 3.0 * se_unc,
        "uncorrected {unc} +- {se_unc} shows no bias"
    );
    assert!(
        (unc - biased).abs() < 3.0 * se_unc,
        "uncorrected {unc} +- {se_unc} vs its equilibrium {biased}"
    );
}

/// `dt = 0.5` (a step moves the sphere by `sqrt(2 D dt) = 0.23 l`), 10^6 steps per
/// scheme, a sample every 10 steps, 40 blocks of 2500 samples (each about 30 relaxation
/// times `l^2 / D_perp`): about 1.5 s per scheme in release.
fn barometric_layer<T: Real>() {
    barometric::<T>(0.5, 1_000_000);
}

both_precisions! {
    layer => barometric_layer;
}
