//! Brownian dynamics: thermal noise in the overdamped step, checked against
//! exact equilibrium and transport results that do not come from the kernel.
//!
//! Units: `kT = 1`. Every statistical check states its tolerance and also asserts its
//! own power: the standard error (from block means, which absorb time correlation) must
//! be small enough that the wrong answer named in the test would fail. Fixed seeds make
//! every run the same; the tolerances are several standard errors wide so that a
//! different seed would pass too.
//!
//! Exact values used (derived in docs/BROWNIAN.md):
//! * lone sphere: `D = kT / (6 pi eta a)`;
//! * two free spheres: `<dx_1 dx_2^T> = 2 kT dt mu_12` with the far-field RPY pair block
//!   `mu_12 = [(1 + (a1^2 + a2^2) / 3s^2) I + (1 - (a1^2 + a2^2) / s^2) e e] / (8 pi eta s)`;
//! * dimer of equal spheres `a`, bond `d`: its midpoint (the centre of mobility) diffuses
//!   with `D_t = kT (1/a + 1/d) / (12 pi eta)` at every orientation (the trace of
//!   `(mu_11 + mu_12) / 2` does not depend on it); its axis with
//!   `D_r = 2 kT [1/(6 pi eta a) - (1 + 2a^2 / 3d^2) / (8 pi eta d)] / d^2`, so
//!   `<u(0).u(t)> = exp(-2 D_r t)`;
//! * freely jointed trimer, `c` = cosine of the angle between its bond vectors: flexible
//!   (stiff bonds) `p(c) = 1/2`, `<c^2> = 1/3`; rigid bonds `p(c) ~ sqrt(1 - c^2/4)`,
//!   `<c^2> = (pi/3 - sqrt(3)/4) / (pi/3 + sqrt(3)/2) = 0.32102`.

use crate::common;

use common::thermal::*;
use common::*;
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, ParticleSet, Real, SolverKind,
    StepError, step, step_slices,
};
use hydrorattle_heap::Buffers;
use std::f64::consts::PI;

fn sphere(pos: [f64; 3], radius: f64) -> Sphere {
    Sphere {
        pos,
        radius,
        density: 0.0,
    }
}

fn pos<T: Real, const N: usize>(ps: &ParticleSet<T, N>, i: usize) -> [f64; 3] {
    f64s::<T>(ps.pos[i])
}

/// A lone sphere: `<|dx|^2> = 6 D dt` per step with `D = kT / (6 pi eta a)`.
/// 100 000 steps: standard error `sqrt(2/3 / 1e5)` = 0.26 % of `D`; tolerance 1.5 %.
fn lone_sphere<T: Real>() {
    let (a, eta, dt, steps) = (1.3, 0.7, 0.5, 100_000);
    let mut ps: ParticleSet<T, 1> = particles(&[sphere([0.0; 3], a)]);
    let bonds: BondSet<T, 1> = BondSet::new();
    let p = thermal::<T>(dt, eta, Hydro::Rpy, Drift::Midpoint);
    let mut prev = pos(&ps, 0);
    let mut sq = Vec::with_capacity(steps);
    sample(&mut ps, &bonds, &p, 1, steps, |ps| {
        let x = pos(ps, 0);
        sq.push(dot(sub(x, prev), sub(x, prev)) / (6.0 * dt));
        prev = x;
    });
    let exact = 1.0 / (6.0 * PI * eta * a);
    let (d, se) = block_mean(&sq, 50);
    eprintln!("lone sphere: D = {d:.6} +- {se:.6}, exact {exact:.6}");
    assert!(se < 0.005 * exact, "too few samples: se {se}");
    assert!((d / exact - 1.0).abs() < 0.015, "D {d} vs {exact}");
}

/// Two free spheres (radii 1 and 1.5, 3 apart along x), one step from the same start
/// 300 000 times: the displacement covariance is `2 kT dt mu`, blocks from the
/// far-field RPY formula. Standard error at most 0.75 % (asserted; about 0.4 % for the
/// cross terms along the line of centres, 0.6 % across, 0.25 % self); tolerance 3 % on
/// every entry (4 standard errors). The cross terms are zero without hydrodynamic
/// interactions, and a noise drawn from the wrong square root would mix the entries.
#[test]
fn sphere_pair_covariance() {
    let (a1, a2, s, eta, dt, steps) = (1.0, 1.5, 3.0, 1.0, 0.01, 300_000);
    let start: ParticleSet<f64, 2> = particles(&[sphere([0.0; 3], a1), sphere([s, 0.0, 0.0], a2)]);
    let bonds: BondSet<f64, 1> = BondSet::new();
    let p = thermal::<f64>(dt, eta, Hydro::Rpy, Drift::Midpoint);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 2, 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(2);
    // Products: 1x*2x, 1y*2y, 1x*1x, 2y*2y (divided by 2 dt).
    let mut prods: [Vec<f64>; 4] = Default::default();
    for _ in 0..steps {
        let mut ps = start.clone();
        step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise).unwrap();
        let d1 = sub(pos(&ps, 0), pos(&start, 0));
        let d2 = sub(pos(&ps, 1), pos(&start, 1));
        let k = 1.0 / (2.0 * dt);
        for (v, x) in
            prods
                .iter_mut()
                .zip([d1[0] * d2[0], d1[1] * d2[1], d1[0] * d1[0], d2[1] * d2[1]])
        {
            v.push(x * k);
        }
    }
    let q = (a1 * a1 + a2 * a2) / (s * s);
    let pair = 1.0 / (8.0 * PI * eta * s);
    let exact = [
        pair * ((1.0 + q / 3.0) + (1.0 - q)),
        pair * (1.0 + q / 3.0),
        1.0 / (6.0 * PI * eta * a1),
        1.0 / (6.0 * PI * eta * a2),
    ];
    for (name, (v, e)) in ["mu12 xx", "mu12 yy", "mu11 xx", "mu22 yy"]
        .iter()
        .zip(prods.iter().zip(exact))
    {
        let (m, se) = block_mean(v, 50);
        eprintln!("pair {name}: {m:.6} +- {se:.6}, exact {e:.6}");
        assert!(se < 0.0075 * e, "{name}: too few samples");
        assert!((m / e - 1.0).abs() < 0.03, "{name}: {m} vs {e}");
    }
}

/// The dimer's exact coefficients (equal spheres `a`, bond `d`).
fn dimer_exact(a: f64, d: f64, eta: f64) -> (f64, f64) {
    let dt = (1.0 / a + 1.0 / d) / (12.0 * PI * eta);
    let perp = (1.0 + 2.0 * a * a / (3.0 * d * d)) / (8.0 * PI * eta * d);
    let dr = 2.0 * (1.0 / (6.0 * PI * eta * a) - perp) / (d * d);
    (dt, dr)
}

/// Free rigid dimer (RPY, `a = 1`, `d = 3`, `eta = 1`, `D_r dt = 0.0043`), 1 000 000
/// steps, default (midpoint) drift.
/// * Midpoint: `<|dx|^2> / (6 dt)` per step, standard error about 0.15 %; tolerance 1 %
///   (free draining would give `kT / (12 pi eta a)`, 25 % lower).
/// * Axis: `D_r = -ln C(tau) / (2 tau)` at `tau = 100 dt` (`C ~ 0.42`), standard error
///   about 1 %; tolerance 4 % (free draining: 37 % higher).
#[test]
fn dimer_translation_and_rotation() {
    let (a, d, eta, dt, steps, lag) = (1.0, 3.0, 1.0, 0.5, 1_000_000, 100);
    let mut ps: ParticleSet<f64, 2> = particles(&[sphere([0.0; 3], a), sphere([d, 0.0, 0.0], a)]);
    let bonds: BondSet<f64, 1> = BondSet::chain(&ps.pos[..2]).unwrap();
    let p = thermal::<f64>(dt, eta, Hydro::Rpy, Drift::Midpoint);
    let mid = |ps: &ParticleSet<f64, 2>| scale(add(pos(ps, 0), pos(ps, 1)), 0.5);
    let axis = |ps: &ParticleSet<f64, 2>| {
        let b = sub(pos(ps, 0), pos(ps, 1));
        scale(b, 1.0 / norm(b))
    };
    let mut prev = mid(&ps);
    let mut sq = Vec::with_capacity(steps);
    let mut axes = Vec::with_capacity(steps);
    sample(&mut ps, &bonds, &p, 3, steps, |ps| {
        let m = mid(ps);
        sq.push(dot(sub(m, prev), sub(m, prev)) / (6.0 * dt));
        prev = m;
        axes.push(axis(ps));
    });
    let (dt_exact, dr_exact) = dimer_exact(a, d, eta);
    let (dtr, se) = block_mean(&sq, 50);
    eprintln!("dimer D_t = {dtr:.6} +- {se:.6}, exact {dt_exact:.6}");
    assert!(se < 0.003 * dt_exact, "too few samples: se {se}");
    assert!(
        (dtr / dt_exact - 1.0).abs() < 0.01,
        "D_t {dtr} vs {dt_exact}"
    );
    let corr: Vec<f64> = (0..steps - lag)
        .map(|k| dot(axes[k], axes[k + lag]))
        .collect();
    let (c, se) = block_mean(&corr, 50);
    let tau = lag as f64 * dt;
    let dr = -c.ln() / (2.0 * tau);
    let dr_se = se / c / (2.0 * tau);
    eprintln!(
        "dimer C({tau}) = {c:.5} +- {se:.5}: D_r = {dr:.6} +- {dr_se:.6}, exact {dr_exact:.6}"
    );
    assert!(dr_se < 0.015 * dr_exact, "too few samples: se {dr_se}");
    assert!((dr / dr_exact - 1.0).abs() < 0.04, "D_r {dr} vs {dr_exact}");
}

/// `<c^2>` of a freely jointed trimer (unit radii, bonds 3, phantom beads) and its
/// standard error.
fn trimer(hydro: Hydro, drift: Drift, steps: usize, seed: u64) -> (f64, f64) {
    let d = 3.0;
    let mut ps: ParticleSet<f64, 3> = particles(&[
        sphere([0.0; 3], 1.0),
        sphere([d, 0.0, 0.0], 1.0),
        sphere([d, d, 0.0], 1.0),
    ]);
    let bonds: BondSet<f64, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
    // eta = 1/(6 pi): a bead's mobility is 1, D = 1, a bond turns at D_r = 2/9.
    let mut p = thermal::<f64>(0.045, 1.0 / (6.0 * PI), hydro, drift);
    p.allow_overlap = true;
    let mut c2 = Vec::with_capacity(steps);
    sample(&mut ps, &bonds, &p, seed, steps, |ps| {
        let b1 = sub(pos(ps, 0), pos(ps, 1));
        let b2 = sub(pos(ps, 1), pos(ps, 2));
        let c = dot(b1, b2) / (norm(b1) * norm(b2));
        c2.push(c * c);
    });
    block_mean(&c2, 50)
}

/// The bond-angle distribution of a freely jointed trimer, 1 200 000 steps per case
/// (`D_r dt = 0.01`), `<cos^2>` against the flexible value 1/3 and the rigid value
/// 0.32102 (0.0123 apart). Standard error at most 0.0018 (asserted; 0.0011 free
/// draining, 0.0016 RPY); tolerance 0.005, so a result within tolerance of one value is
/// more than 4 standard errors from the other (also asserted).
/// * free draining, uncorrected: the rigid distribution (exact for a constant mobility);
/// * free draining, midpoint: the flexible one;
/// * RPY, midpoint: the flexible one (the drift includes the hydrodynamic terms).
#[test]
fn trimer_bond_angle_distribution() {
    let rigid = (PI / 3.0 - 3f64.sqrt() / 4.0) / (PI / 3.0 + 3f64.sqrt() / 2.0);
    let flexible = 1.0 / 3.0;
    let cases = [
        (Hydro::FreeDraining, Drift::Uncorrected, rigid, flexible),
        (Hydro::FreeDraining, Drift::Midpoint, flexible, rigid),
        (Hydro::Rpy, Drift::Midpoint, flexible, rigid),
    ];
    let runs: Vec<_> = cases
        .iter()
        .enumerate()
        .map(|(k, &(h, dr, ..))| {
            std::thread::spawn(move || trimer(h, dr, 1_200_000, 10 + k as u64))
        })
        .collect();
    for (run, (hydro, drift, want, other)) in runs.into_iter().zip(cases) {
        let (m, se) = run.join().unwrap();
        eprintln!("trimer {hydro:?} {drift:?}: <c^2> = {m:.5} +- {se:.5}, want {want:.5}");
        assert!(
            se < 0.0018,
            "{hydro:?} {drift:?}: too few samples (se {se})"
        );
        assert!(
            (m - want).abs() < 0.005,
            "{hydro:?} {drift:?}: {m} vs {want}"
        );
        assert!(
            (m - other).abs() > 4.0 * se,
            "{hydro:?} {drift:?}: cannot tell"
        );
    }
}

/// The Figure 1 (c) chain (head radius 2, D = 1.05, settling) for 20 steps at `kT`
/// (`None`: the deterministic step), seed 5.
fn chain_after<T: Real>(kt: Option<f64>) -> ParticleSet<T, 25> {
    let mut ps: ParticleSet<T, 25> = particles(&helix(25, 2.0, 3.0, 0.5, 1.05));
    let bonds: BondSet<T, 24> = BondSet::chain(&ps.pos[..25]).unwrap();
    let mut p = params::<T>(0.02, Method::Overdamped, SolverKind::Newton);
    p.allow_overlap = true;
    p.brownian = kt.map(|t| Brownian::new(T::from_f64(t)));
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, 25, 24));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(5);
    for _ in 0..20 {
        match kt {
            Some(_) => step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise),
            None => step(&mut ps, &bonds, &p, &mut ws, &mut NoForce),
        }
        .unwrap();
    }
    ps
}

fn max_distance<T: Real, const N: usize>(a: &ParticleSet<T, N>, b: &ParticleSet<T, N>) -> f64 {
    (0..a.len())
        .map(|i| norm(sub(pos(a, i), pos(b, i))))
        .fold(0.0, f64::max)
}

/// As `kT -> 0` the run recovers the deterministic trajectory: after 20 steps of the
/// settling Figure 1 (c) chain, the largest bead deviation scales as `sqrt(kT)` (the
/// same deviates, scaled): `dev / sqrt(kT)` agrees within 5 % from `kT = 1e-2` to
/// `1e-8` (f64; to `1e-6` in f32, whose rounding then dominates), and `kT = 0` gives the
/// deterministic bits exactly.
fn deterministic_limit<T: Real>() {
    let base = chain_after::<T>(None);
    let temps: &[f64] = if is_single::<T>() {
        &[1e-2, 1e-4, 1e-6]
    } else {
        &[1e-2, 1e-4, 1e-6, 1e-8]
    };
    let scaled: Vec<f64> = temps
        .iter()
        .map(|&kt| max_distance(&chain_after::<T>(Some(kt)), &base) / kt.sqrt())
        .collect();
    eprintln!("kT {temps:?}: max deviation / sqrt(kT) = {scaled:?}");
    for w in scaled.windows(2) {
        assert!((w[1] / w[0] - 1.0).abs() < 0.05, "not sqrt(kT): {scaled:?}");
    }
    assert!(scaled[0] > 0.0);
    let zero = chain_after::<T>(Some(0.0));
    assert_eq!(
        snapshot(&zero),
        snapshot(&base),
        "kT = 0 differs from the deterministic step"
    );
}

/// Same seed, same bits: 200 steps of the RPY trimer (midpoint drift) hashed as in
/// `tests/kernel/determinism.rs`, two runs and a pinned digest per precision. Regenerate after
/// an intended change of arithmetic with `--nocapture`.
fn golden<T: Real>() {
    let run = || {
        let mut ps: ParticleSet<T, 3> = particles(&[
            sphere([0.0; 3], 1.0),
            sphere([3.0, 0.0, 0.0], 1.0),
            sphere([3.0, 3.0, 0.0], 1.0),
        ]);
        let bonds: BondSet<T, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
        let mut p = thermal::<T>(0.045, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
        p.allow_overlap = true;
        sample(&mut ps, &bonds, &p, 42, 200, |_| {});
        state_digest(&ps)
    };
    let (first, second) = (run(), run());
    assert_eq!(first, second, "two runs differ");
    let pin = if is_single::<T>() {
        0x82f2_04f4_385a_4f06u64
    } else {
        0x61d4_1efa_78fe_1593u64
    };
    eprintln!("golden brownian: got {first:#018x}, pinned {pin:#018x}");
    assert_eq!(first, pin, "golden digest changed");
}

/// The deviates are computed in f64 and rounded: an f32 run draws exactly the f64
/// run's deviates, rounded once.
#[test]
fn same_deviates_in_f32_and_f64() {
    let (mut a, mut b) = (Noise::new(9), Noise::new(9));
    let mut single = [glam::Vec3::ZERO; 333];
    let mut double = [glam::DVec3::ZERO; 333];
    a.fill::<f32>(&mut single);
    b.fill::<f64>(&mut double);
    for (s, d) in single.iter().zip(&double) {
        assert_eq!(s.to_array(), d.as_vec3().to_array());
    }
    assert_eq!(a, b, "generators diverged");
    // Moments of the deviates themselves: mean 0, variance 1, kurtosis 3 (se about
    // 0.002, 0.003, 0.015 for 10^6 deviates; tolerances 5 standard errors).
    let mut g = Noise::new(11);
    let x: Vec<f64> = (0..1_000_000).map(|_| g.normal()).collect();
    let m = x.iter().sum::<f64>() / 1e6;
    let v = x.iter().map(|y| y * y).sum::<f64>() / 1e6;
    let k = x.iter().map(|y| y.powi(4)).sum::<f64>() / 1e6;
    assert!(m.abs() < 0.005 && (v - 1.0).abs() < 0.0075 && (k - 3.0).abs() < 0.075);
}

/// Refusals are typed and leave the state and the generator untouched: thermal noise
/// with another method, a Cholesky factor without a stored mobility, without a generator, a bad temperature, storage
/// one block short, and a constraint solve that fails after the deviates were drawn.
#[test]
fn refusals_leave_state_and_generator() {
    let mut ps: ParticleSet<f64, 3> = particles(&[
        sphere([0.0; 3], 1.0),
        sphere([3.0, 0.0, 0.0], 1.0),
        sphere([3.0, 3.0, 0.0], 1.0),
    ]);
    let bonds: BondSet<f64, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
    let good = thermal::<f64>(0.1, 1.0, Hydro::Rpy, Drift::Midpoint);
    let mut buf = Buffers::<f64>::new(Layout::all(3, 2).max(Layout::for_params(&good, 3, 2)));
    let mut noise = Noise::new(4);
    let fresh = noise.clone();
    let before = snapshot(&ps);
    let unsupported = |e: &StepError| matches!(e, StepError::Unsupported(_));
    let mut check = |p: &hydrorattle::Params<f64>, pred: &dyn Fn(&StepError) -> bool, what| {
        let mut ws = buf.workspace();
        let r = step_thermal(&mut ps, &bonds, p, &mut ws, &mut NoForce, &mut noise);
        assert_failed_unchanged(&before, &ps, &r, pred, what);
        assert_eq!(noise, fresh, "{what}: generator advanced");
    };
    let mut p = good;
    p.method = Method::Overdamped2;
    check(&p, &unsupported, "Overdamped2");
    let mut p = good;
    p.matrix_free = true;
    p.noise_sqrt = hydrorattle::NoiseSqrt::Cholesky;
    check(&p, &unsupported, "matrix_free with a Cholesky factor");
    for bad in [f64::NAN, -1.0, f64::INFINITY] {
        let mut p = good;
        p.brownian = Some(Brownian::new(bad));
        check(
            &p,
            &|e| matches!(e, StepError::BadParameter(_)),
            "temperature",
        );
    }
    let mut p = good;
    p.solver.kind = SolverKind::Sweep;
    p.solver.max_iterations = 1;
    check(
        &p,
        &|e| matches!(e, StepError::NoConvergence { .. }),
        "solve",
    );
    // Storage one block short.
    let need = Layout::for_params(&good, 3, 2);
    let mut small = Buffers::<f64>::new(Layout {
        blocks: need.blocks - 1,
        ..need
    });
    let r = step_thermal(
        &mut ps,
        &bonds,
        &good,
        &mut small.workspace(),
        &mut NoForce,
        &mut noise,
    );
    assert_failed_unchanged(
        &before,
        &ps,
        &r,
        |e| matches!(e, StepError::Storage { .. }),
        "storage",
    );
    assert_eq!(noise, fresh, "storage: generator advanced");
    // Without a generator.
    let r = step_slices(
        ps.state(),
        bonds.as_slice(),
        &good,
        &mut buf.workspace(),
        &mut NoForce,
    );
    assert_failed_unchanged(&before, &ps, &r, unsupported, "no generator");
    // And a good step draws.
    step_thermal(
        &mut ps,
        &bonds,
        &good,
        &mut buf.workspace(),
        &mut NoForce,
        &mut noise,
    )
    .unwrap();
    assert_ne!(noise, fresh, "a thermal step must draw");
}

both_precisions! {
    lone_sphere_diffusion => lone_sphere;
    deterministic_limit_recovers_the_trajectory => deterministic_limit;
    same_seed_same_bits => golden;
}
