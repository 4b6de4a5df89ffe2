//! Hard contacts with thermal noise: two hard spheres in a periodic box sample the
//! equilibrium of hard spheres, the uniform density over every relative position that
//! does not overlap (Boltzmann's weight with no energy but the contact's).
//!
//! Reference (closed form, not from the kernel): for two spheres of radius `a` in a
//! cubic box of edge `L`, the minimum-image distance `r` of a uniform relative position
//! outside the excluded ball `r < 2a` has, for `2a <= R <= L/2`,
//! `P(r < R) = (4 pi / 3)(R^3 - (2a)^3) / (L^3 - (4 pi / 3)(2a)^3)`.
//!
//! The projection that holds a contact is a reflecting boundary of weak order 1/2, so
//! the density in a layer of about one step's length at contact is off by `O(sqrt dt)`;
//! the statistics are taken as in `wall_barometric.rs`: the probability of a shell away
//! from contact given that the pair is outside a threshold `r0` a little above contact,
//! `P(r < R | r > r0)`, which the uniform density fixes whatever happens below `r0`,
//! and the smallest distance ever seen (never below contact). Standard errors from
//! block means. Power: a pair that ignored its contact (phantom spheres) would give
//! `P(r < 3) = (4 pi / 3) 27 / L^3 = 0.221` against the hard pair's 0.166, asserted to be
//! many standard errors apart.
//!
//! With the near field the mobility has a divergence (the squeeze resistance slows the
//! pair's approach), so the midpoint drift is what keeps the density uniform: the long
//! run (`--ignored`) checks the midpoint against the exact shell and the uncorrected
//! draw's excess near contact. Free draining and RPY have no divergence (the RPY tensor
//! is divergence-free outside contact), so every drift gives the same bits there.
//!
//! `cargo test --release --test kernel -- contacts_brownian:: --nocapture` (about 30 s);
//! the long run `-- --ignored --nocapture` (about 3 minutes). Measured (seeds fixed):
//!
//! | path | dt | steps | `P(r < 3 \| r > 2.2)` (exact 0.1465) | `P(r < 3)` (exact 0.1663; phantom 0.2209) |
//! |---|---|---|---|---|
//! | free draining | 0.04 | 4 x 10^5 | 0.1451 +- 0.0024 | 0.1836 +- 0.0031 |
//! | free draining | 0.01 | 10^6 | 0.1447 +- 0.0029 | 0.1745 +- 0.0036 |
//! | free draining | 0.0025 | 2 x 10^6 | 0.1488 +- 0.0032 | 0.1732 +- 0.0038 |
//! | RPY, Ewald, stored | 0.02 | 6 x 10^4 | 0.1393 +- 0.0084 | 0.1640 +- 0.0102 |
//! | RPY, PSE (1e-6) | 0.02 | 2 x 10^4 | 0.1571 +- 0.0149 | 0.1838 +- 0.0178 |
//! | near field, iterative | 0.02 | 2 x 10^4 | 0.1846 +- 0.0233 | 0.2076 +- 0.0266 |
//!
//! and the near field, dense, 5 x 10^5 steps at `dt = 0.02`: `P(r < 2.5 | r > 2.05)` =
//! 0.0600 +- 0.0018 with the midpoint (exact 0.0617, -0.9 se), 0.0793 +- 0.0028
//! uncorrected (+6.2 se).

use crate::common;

use common::thermal::*;
use common::*;
#[cfg(feature = "fast-free")]
use hydrorattle::glam::DVec3;
use hydrorattle::integrate::{fast_storage, pse_storage};
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    BondSet, Contacts, Drift, Hydro, Layout, NoForce, Noise, Params, ParticleSet, Periodic,
};
use hydrorattle_heap::{Buffers, FreeBuffers, PseBuffers};
use std::f64::consts::PI;

/// The box's edge, in radii: a pair can touch one image at a time, and a step cannot
/// carry it past half the box from contact (where the minimum image would change).
const L: f64 = 8.0;

/// The test's own minimum-image distance of the pair.
fn distance(ps: &ParticleSet<f64, 2>) -> f64 {
    let (x, y) = (f64s::<f64>(ps.pos[0]), f64s::<f64>(ps.pos[1]));
    let d = sub(x, y).map(|c| c - L * (c / L).round());
    dot(d, d).sqrt()
}

/// `P(r < R)` of the uniform density outside contact (module documentation).
fn exact_below(r: f64) -> f64 {
    let ball = |x: f64| 4.0 * PI / 3.0 * x.powi(3);
    (ball(r) - ball(2.0)) / (L.powi(3) - ball(2.0))
}

/// `P(r < R | r > r0)` of the same density.
fn exact_shell(r0: f64, r: f64) -> f64 {
    (exact_below(r) - exact_below(r0)) / (1.0 - exact_below(r0))
}

/// Thermal `Overdamped` parameters of a pair of unit spheres (`D0 = 1`) with hard
/// contacts in the box, `set` choosing the path.
fn pair_params(drift: Drift, dt: f64, set: impl Fn(&mut Params<f64>)) -> Params<f64> {
    let mut p = thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, drift);
    p.periodic = Some(Periodic::new([L; 3]).unwrap());
    p.contacts = Some(Contacts::new(1));
    set(&mut p);
    p
}

/// The pair's distance after each of `steps` steps of `p`.
fn distances(p: &Params<f64>, steps: usize, seed: u64) -> Vec<f64> {
    let sphere = |pos| Sphere {
        pos,
        radius: 1.0,
        density: 0.0,
    };
    let mut ps: ParticleSet<f64, 2> = particles(&[sphere([0.0; 3]), sphere([2.3, 0.4, -0.2])]);
    let bonds: BondSet<f64, 1> = BondSet::new();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, 2, 0));
    let mut arrays = pse_storage(p, &[1.0; 2]).unwrap().map(PseBuffers::new);
    let mut ws = match arrays.as_mut() {
        Some(a) => a.attach(buf.workspace()),
        None => buf.workspace(),
    };
    let mut noise = Noise::new(seed);
    (0..steps)
        .map(|k| {
            step_thermal(&mut ps, &bonds, p, &mut ws, &mut NoForce, &mut noise)
                .unwrap_or_else(|e| panic!("step {k}: {e}"));
            distance(&ps)
        })
        .collect()
}

/// Block means (40 blocks) of `r0 < r < R` given `r > r0`, and of `r < R`.
fn shells(r: &[f64], r0: f64, big: f64) -> ((f64, f64), (f64, f64)) {
    let len = r.len() / 40;
    let (mut cond, mut below) = (Vec::new(), Vec::new());
    for c in r.chunks_exact(len) {
        let out = c.iter().filter(|&&x| x > r0).count() as f64;
        let inside = c.iter().filter(|&&x| x > r0 && x < big).count() as f64;
        cond.push(inside / out);
        below.push(c.iter().filter(|&&x| x < big).count() as f64 / len as f64);
    }
    (mean_se(&cond), mean_se(&below))
}

/// Runs `p` and checks the hard pair's equilibrium: never closer than contact, the
/// shell `2.2 < r < 3` within `k` standard errors of the uniform density's, and, with
/// `power`, the pair told from a phantom one by that many standard errors.
fn hard_pair(tag: &str, p: &Params<f64>, steps: usize, seed: u64, k: f64, power: Option<f64>) {
    let r = distances(p, steps, seed);
    let lowest = r.iter().copied().fold(f64::INFINITY, f64::min);
    let ((c, cse), (b, bse)) = shells(&r, 2.2, 3.0);
    let (want_c, want_b) = (exact_shell(2.2, 3.0), exact_below(3.0));
    let phantom = 4.0 * PI / 3.0 * 27.0 / L.powi(3);
    eprintln!(
        "{tag}: P(r<3|r>2.2) = {c:.4} +- {cse:.4} (exact {want_c:.4}, {:+.1} se); P(r<3) = {b:.4} +- {bse:.4} (exact {want_b:.4}, {:+.1} se; phantom {phantom:.4}); lowest {lowest:.9}",
        (c - want_c) / cse,
        (b - want_b) / bse,
    );
    assert!(
        lowest >= 2.0 - 1e-9,
        "{tag}: the pair overlapped ({lowest})"
    );
    assert!((c - want_c).abs() < k * cse, "{tag}: shell {c} +- {cse}");
    if let Some(power) = power {
        assert!(
            (phantom - b) > power * bse,
            "{tag}: not told from a phantom pair"
        );
    }
}

/// Free draining, `dt = 0.01` (a step moves each sphere `0.14` radii an axis), 10^6
/// steps (about 2 s); the contact layer's excess in `P(r < 3)` shrinks with `dt` as the
/// projection's weak order 1/2 says (0.0173 at `dt = 0.04`, 0.0082 at 0.01).
#[test]
fn free_draining_pair_samples_hard_spheres() {
    let mut p = pair_params(Drift::Midpoint, 0.01, |_| {});
    p.hydro = Hydro::FreeDraining;
    hard_pair("free draining", &p, 1_000_000, 7, 3.0, Some(8.0));
}

/// RPY in the box on each path that takes noise and contacts: the Ewald mobility
/// stored, PSE, and the iterative near field; shorter runs (4 standard errors; the
/// power against a phantom pair is the free-draining run's).
#[test]
fn every_path_samples_hard_spheres() {
    let stored = pair_params(Drift::Midpoint, 0.02, |_| {});
    hard_pair("RPY, Ewald, stored", &stored, 60_000, 11, 4.0, None);
    let pse = pair_params(Drift::Midpoint, 0.02, |p| {
        p.matrix_free = true;
        p.pse = Some(1e-6);
    });
    hard_pair("RPY, PSE", &pse, 20_000, 12, 4.0, None);
    let iterative = pair_params(Drift::Midpoint, 0.02, |p| {
        p.matrix_free = true;
        p.near = Some(NearField::default());
    });
    hard_pair("near field, iterative", &iterative, 20_000, 13, 4.0, None);
}

/// Free space, where a pair diffuses apart and no equilibrium is there to compare
/// with: the stored mobility with Lanczos noise and the fast product, from a pair
/// `0.05` radii apart pressed together by opposite forces (`5 kT / a`, so that it
/// touches often), never overlap (4,000 steps; 400 on the fast product), and the contacts
/// hold every step.
#[cfg(feature = "fast-free")]
#[test]
fn free_space_paths_hold_contacts() {
    struct Press;
    impl hydrorattle::ExternalForce<f64> for Press {
        fn add(&mut self, pos: &[DVec3], _r: &[f64], f: &mut [DVec3]) {
            let d = (pos[1] - pos[0]).normalize();
            f[0] += d * 5.0;
            f[1] -= d * 5.0;
        }
    }
    // The fast product costs some 25 ms a step on two spheres (its grid): fewer steps.
    for (tag, lanczos, fast, steps) in [
        ("stored, Lanczos", true, false, 4_000),
        ("fast product", false, true, 400),
    ] {
        let mut p = thermal::<f64>(0.01, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
        p.contacts = Some(Contacts::new(1));
        if lanczos {
            p.noise_sqrt = hydrorattle::NoiseSqrt::Lanczos;
        }
        if fast {
            p.matrix_free = true;
            p.pse = Some(1e-6);
        }
        let sphere = |x| Sphere {
            pos: [x, 0.0, 0.0],
            radius: 1.0,
            density: 0.0,
        };
        let mut ps: ParticleSet<f64, 2> = particles(&[sphere(0.0), sphere(2.05)]);
        let bonds: BondSet<f64, 1> = BondSet::new();
        let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 2, 0));
        let mut arrays = fast_storage(&p, &ps.pos[..2], &[1.0; 2])
            .unwrap()
            .map(FreeBuffers::new);
        let mut ws = match arrays.as_mut() {
            Some(a) => a.attach(buf.workspace()),
            None => buf.workspace(),
        };
        let mut noise = Noise::new(5);
        let (mut touching, mut lowest) = (0, f64::INFINITY);
        for k in 0..steps {
            let r = step_thermal(&mut ps, &bonds, &p, &mut ws, &mut Press, &mut noise)
                .unwrap_or_else(|e| panic!("{tag}, step {k}: {e}"));
            let d = (ps.pos[1] - ps.pos[0]).length();
            lowest = lowest.min(d);
            touching += usize::from(r.contacts > 0);
            assert!(
                d <= 2.0 + 1e-9 || r.contacts == 0,
                "{tag}: a contact held apart"
            );
        }
        eprintln!("{tag}: {touching} of {steps} steps in contact, lowest {lowest:.12}");
        assert!(lowest >= 2.0 - 1e-9, "{tag}: overlap {lowest}");
        assert!(
            touching > steps / 10,
            "{tag}: the pair touched in {touching} steps only"
        );
    }
}

/// The dense near field, 5 x 10^5 steps a drift: the midpoint samples the hard pair's
/// uniform density near contact (`2.05 < r < 2.5` given `r > 2.05`); the uncorrected
/// draw (no `kT div M` drift) piles the pair up there.
#[test]
#[ignore]
fn near_field_needs_the_midpoint() {
    let (r0, big) = (2.05, 2.5);
    let want = exact_shell(r0, big);
    let mut got = Vec::new();
    for (drift, seed) in [(Drift::Midpoint, 21), (Drift::Uncorrected, 22)] {
        let p = pair_params(drift, 0.02, |p| p.near = Some(NearField::default()));
        let r = distances(&p, 500_000, seed);
        let lowest = r.iter().copied().fold(f64::INFINITY, f64::min);
        let ((c, se), _) = shells(&r, r0, big);
        eprintln!(
            "near field, {drift:?}: P(r<{big}|r>{r0}) = {c:.4} +- {se:.4} (exact {want:.4}, {:+.1} se); lowest {lowest:.9}",
            (c - want) / se
        );
        assert!(lowest >= 2.0 - 1e-9, "{drift:?}: overlap {lowest}");
        got.push((c, se));
    }
    let ((mid, se_mid), (unc, se_unc)) = (got[0], got[1]);
    assert!(
        (mid - want).abs() < 3.0 * se_mid,
        "midpoint {mid} +- {se_mid}"
    );
    assert!(
        (unc - want) > 3.0 * se_unc,
        "uncorrected {unc} +- {se_unc} shows no excess"
    );
}
