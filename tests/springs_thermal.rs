//! The bead-spring model at temperature (issue 19, item 2): a Hookean dumbbell's
//! equilibrium against its exact distribution.
//!
//! Two spheres joined by a spring `U = H (Q - d)^2 / 2` in free space: whatever the
//! mobility, the equilibrium of the bond vector `Q` is `p(Q) ~ Q^2 exp(-U / kT)` (the
//! RPY mobility has zero divergence, so no drift term is missing). Hence
//! `<Q^2> = M4 / M2` with `Mk = int_0^inf Q^k exp(-H (Q - d)^2 / 2kT) dQ`, computed
//! here by Simpson's rule (d = 0 gives the classic `3 kT / H`). Checked with free
//! draining (uncorrected noise) and with RPY (Fixman midpoint), each within 3 block
//! standard errors, and the standard error asserted small enough (below 1 %) that a
//! wrong noise amplitude (twice the variance) would fail by far.

use hydrorattle::glam::DVec3;
use hydrorattle::{
    Bond, BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, Params, Particle,
    ParticleSet, step,
};
use hydrorattle_heap::Buffers;

/// `<Q^2>` of `p(Q) ~ Q^2 exp(-h (Q - d)^2 / 2)` (h = H / kT), Simpson on [0, d + 12/sqrt h].
fn exact_q2(h: f64, d: f64) -> f64 {
    let top = d + 12.0 / h.sqrt();
    let m = 20_000;
    let w = top / m as f64;
    let (mut m2, mut m4) = (0.0, 0.0);
    for k in 0..=m {
        let q = k as f64 * w;
        let c = if k == 0 || k == m {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let e = (-h * (q - d) * (q - d) / 2.0).exp();
        m2 += c * q * q * e;
        m4 += c * q.powi(4) * e;
    }
    m4 / m2
}

/// Mean and block standard error (50 blocks).
fn block_mean(x: &[f64]) -> (f64, f64) {
    let blocks = 50;
    let len = x.len() / blocks;
    let means: Vec<f64> = x
        .chunks_exact(len)
        .map(|c| c.iter().sum::<f64>() / len as f64)
        .collect();
    let m = means.iter().sum::<f64>() / blocks as f64;
    let var = means.iter().map(|b| (b - m) * (b - m)).sum::<f64>() / (blocks - 1) as f64;
    (m, (var / blocks as f64).sqrt())
}

/// `<Q^2>` of a dumbbell of unit spheres, spring `h` (kT = 1), rest length `d`.
fn dumbbell(hydro: Hydro, drift: Drift, h: f64, d: f64, seed: u64) -> (f64, f64) {
    let mut ps = ParticleSet::<f64, 2>::new();
    ps.push(Particle::new(DVec3::ZERO, 1.0, 0.0)).unwrap();
    ps.push(Particle::new(DVec3::new(d.max(2.5), 0.0, 0.0), 1.0, 0.0))
        .unwrap();
    let mut bonds = BondSet::<f64, 1>::new();
    bonds
        .push(
            Bond {
                i: 0,
                j: 1,
                length: d,
            },
            2,
        )
        .unwrap();
    // eta = 1/(6 pi): a lone sphere's mobility is 1; the bond relaxes at rate 2 h.
    let mut p = Params::<f64>::new(0.005);
    p.method = Method::Springs;
    p.viscosity = 1.0 / (6.0 * std::f64::consts::PI);
    p.gravity = DVec3::ZERO;
    p.hydro = hydro;
    p.allow_overlap = true;
    p.spring_stiffness = h;
    p.brownian = Some(Brownian {
        temperature: 1.0,
        drift,
    });
    ps.noise = Some(Noise::new(seed));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 2, 1));
    let mut ws = buf.workspace();
    let steps = 1_000_000;
    let mut q2 = Vec::with_capacity(steps);
    for k in 0..steps {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        if k >= 2_000 {
            q2.push((ps.pos[0] - ps.pos[1]).length_squared());
        }
    }
    block_mean(&q2)
}

#[test]
fn hookean_dumbbell_equilibrium_free_draining_and_rpy() {
    let (h, d) = (1.0, 3.0);
    let exact = exact_q2(h, d);
    // The closed form at d = 0 checks the quadrature: <Q^2> = 3 kT / H.
    assert!((exact_q2(2.0, 0.0) - 1.5).abs() < 1e-9);
    for (hydro, drift, seed) in [
        (Hydro::FreeDraining, Drift::Uncorrected, 1),
        (Hydro::Rpy, Drift::Midpoint, 2),
    ] {
        let (m, se) = dumbbell(hydro, drift, h, d, seed);
        eprintln!("{hydro:?} {drift:?}: <Q^2> = {m:.4} +- {se:.4}, exact {exact:.4}");
        assert!(se < 0.01 * exact, "too few samples: se {se}");
        assert!(
            (m - exact).abs() < 3.0 * se,
            "{hydro:?}: {m} vs {exact} (se {se})"
        );
    }
}
