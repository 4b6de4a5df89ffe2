//! Brownian steps with the iterative near field (`Params::near` with
//! `Params::matrix_free`: the far field's Lanczos root, the close pairs' factors and one
//! solve; the dense near path's midpoint drift), against what nobody here computed with
//! the iterative code:
//!
//! * the noise's covariance against `2 kT dt M_SD,tt` of the dense Stokesian dynamics
//!   mobility (`stokesian::mobility_in`, two dense inversions), for clusters with close
//!   pairs in free space and in a box: entry by entry within five standard errors, and
//!   the whitened norm `dx^T M^-1 dx / (2 kT dt)`, whose mean is `3n` exactly;
//! * a lone sphere's diffusion coefficient against Stokes and Einstein's
//!   `kT / (6 pi eta a)`, and in a box against Hasimoto's finite-size correction;
//! * a pair near contact held by a spring in equilibrium: the mean and spread of its
//!   distance against the Boltzmann weight `r^2 exp(-k (r - r0)^2 / 2 kT)`, which the
//!   midpoint's drift `kT div M_SD` must supply (the uncorrected scheme is asserted
//!   biased, so the test can tell);
//! * the same bits on rerun, and the refusals that remain, typed, the state unchanged.
//!
//! Units: `eta = 1` unless said, `kT = 1`, no gravity.
#![cfg(all(feature = "near", feature = "periodic"))]

use crate::common;

use std::f64::consts::PI;

use common::thermal::*;
use common::*;
use hydrorattle::mobility::periodic::Ewald;
use hydrorattle::stokesian::{Far, NearField, mobility_in, storage};
use hydrorattle::{
    Bond, BondSet, Drift, Hydro, Layout, Noise, ParticleSet, Periodic, Real, Stage, StepError,
    StepReport, Wall,
};
use hydrorattle_heap::Buffers;

/// Hasimoto's coefficient of the box's first-order correction (`stokesian_box.rs`).
const HASIMOTO: f64 = 2.837297;

/// Thermal parameters with the iterative near field (`kT = 1`, no gravity), in the
/// cubic box of edge `l` if given.
fn iterative<T: Real>(dt: f64, eta: f64, drift: Drift, l: Option<f64>) -> hydrorattle::Params<T> {
    let mut p = thermal::<T>(dt, eta, Hydro::Rpy, drift);
    p.near = Some(NearField::default());
    p.matrix_free = true;
    p.rotation = true;
    p.allow_overlap = true;
    p.periodic = l.map(|l| Periodic::new([T::from_f64(l); 3]).unwrap());
    p
}

/// The dense `M_SD,tt` (`3n x 3n`, row-major) of `spheres`, in the box of edge `l`.
fn dense_tt<T: Real>(eta: f64, spheres: &[Sphere], l: Option<f64>) -> Vec<f64> {
    let n = spheres.len();
    let (nb, nd) = storage(n);
    let mut packed = vec![T::M3_ZERO; nb];
    let mut out = vec![T::ZERO; nd];
    let pos: Vec<T::V3> = spheres.iter().map(|s| T::v3_from(s.pos)).collect();
    let rad: Vec<T> = spheres.iter().map(|s| T::from_f64(s.radius)).collect();
    let a_max = spheres.iter().map(|s| s.radius).fold(0.0, f64::max);
    let ew = l.map(|l| {
        let cell = Periodic::new([T::from_f64(l); 3]).unwrap();
        Ewald::new(cell, T::from_f64(a_max)).unwrap()
    });
    let far = ew.as_ref().map_or(Far::FREE, Far::periodic);
    let nf = NearField::default();
    mobility_in(T::from_f64(eta), far, &pos, &rad, nf, &mut packed, &mut out).unwrap();
    let m = 6 * n;
    let mut tt = vec![0.0; 9 * n * n];
    for r in 0..3 * n {
        for c in 0..3 * n {
            tt[r * 3 * n + c] = out[r * m + c].to_f64();
        }
    }
    tt
}

/// The inverse of the symmetric positive definite `a` (`k x k`), by Gauss-Jordan.
fn inverse(a: &[f64], k: usize) -> Vec<f64> {
    let mut m = a.to_vec();
    let mut inv: Vec<f64> = (0..k * k)
        .map(|i| if i / k == i % k { 1.0 } else { 0.0 })
        .collect();
    for c in 0..k {
        let piv = m[c * k + c];
        for j in 0..k {
            m[c * k + j] /= piv;
            inv[c * k + j] /= piv;
        }
        for r in 0..k {
            if r != c {
                let f = m[r * k + c];
                for j in 0..k {
                    m[r * k + j] -= f * m[c * k + j];
                    inv[r * k + j] -= f * inv[c * k + j];
                }
            }
        }
    }
    inv
}

/// A cluster of five unequal spheres with close pairs (gaps 0.05 to 0.3 mean radii)
/// about `c`.
fn cluster(c: [f64; 3]) -> Vec<Sphere> {
    let at = |x: f64, y: f64, z: f64, radius: f64| Sphere {
        pos: add(c, [x, y, z]),
        radius,
        density: 0.0,
    };
    vec![
        at(0.0, 0.0, 0.0, 1.0),
        at(2.05, 0.0, 0.0, 1.0),
        at(0.3, 2.4, 0.0, 1.2),
        at(2.3, 1.8, 1.4, 0.8),
        at(-1.0, 0.5, 2.0, 1.1),
    ]
}

/// One Brownian step of `ps` without bonds or forces.
fn free_step<T: Real, const N: usize>(
    ps: &mut ParticleSet<T, N>,
    p: &hydrorattle::Params<T>,
    ws: &mut hydrorattle::Workspace<'_, T>,
    noise: &mut Noise,
) -> Result<StepReport<T>, StepError> {
    let bonds: BondSet<T, 1> = BondSet::new();
    step_thermal(ps, &bonds, p, ws, &mut hydrorattle::NoForce, noise)
}

/// `samples` single steps of `spheres` from the same start (the generator running on):
/// the displacements over `sqrt(2 kT dt)`, and the last report.
fn kicks<T: Real>(
    p: &hydrorattle::Params<T>,
    spheres: &[Sphere],
    samples: usize,
    seed: u64,
) -> (Vec<Vec<f64>>, StepReport<T>) {
    let n = spheres.len();
    let start: ParticleSet<T, 8> = particles(spheres);
    let mut buf = Buffers::<T>::new(Layout::for_params(p, n, 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(seed);
    let scale = (2.0 * p.dt.to_f64()).sqrt();
    let mut out = Vec::with_capacity(samples);
    let mut last = StepReport::default();
    for k in 0..samples {
        let mut ps = start.clone();
        last = free_step(&mut ps, p, &mut ws, &mut noise)
            .unwrap_or_else(|e| panic!("sample {k}: {e}"));
        let dx: Vec<f64> = (0..n)
            .flat_map(|i| sub(f64s::<T>(ps.pos[i]), f64s::<T>(start.pos[i])))
            .map(|d| d / scale)
            .collect();
        out.push(dx);
    }
    (out, last)
}

/// The sample covariance of the kicks against `M_SD,tt` (entry by entry within five
/// standard errors of a Gaussian sample), and the whitened norm's mean against `3n`
/// (within five standard errors, `sqrt(6n / S)`), in free space and in a box, with the
/// uncorrected drift (the covariance is then `M_SD,tt` at any step) and, in `f64`, with
/// the midpoint at a step small enough for its `O(dt)` terms to vanish.
fn covariance<T: Real>() {
    let samples = 4000;
    let mut cases = vec![
        (None, Drift::Uncorrected, 1e-3),
        (Some(11.0), Drift::Uncorrected, 1e-3),
    ];
    if !is_single::<T>() {
        cases.push((None, Drift::Midpoint, 1e-9));
    }
    for (k, (l, drift, dt)) in cases.into_iter().enumerate() {
        let eta = 0.8;
        let spheres = cluster(l.map_or([0.0; 3], |l| [l / 2.0 - 0.5; 3]));
        let (n, m) = (spheres.len(), 3 * spheres.len());
        let want = dense_tt::<T>(eta, &spheres, l);
        let p = iterative::<T>(dt, eta, drift, l);
        let (dx, r) = kicks::<T>(&p, &spheres, samples, 40 + k as u64);
        let what = format!("{l:?} {drift:?}");
        println!(
            "{what}: pairs {}, products {}, PCG iterations {}, Lanczos iterations {}",
            r.near_pairs, r.near_products, r.near_iterations, r.noise_iterations
        );
        assert!(r.near_pairs >= 4, "{what}: close pairs {}", r.near_pairs);
        let products = if drift == Drift::Midpoint { 3 } else { 2 };
        assert_eq!(r.near_products, products, "{what}");
        assert!(r.noise_iterations > 1, "{what}");
        let s = samples as f64;
        let mut worst: f64 = 0.0;
        for a in 0..m {
            for b in 0..=a {
                let c = dx.iter().map(|x| x[a] * x[b]).sum::<f64>() / s;
                let w = want[a * m + b];
                let se = ((want[a * m + a] * want[b * m + b] + w * w) / s).sqrt();
                worst = worst.max((c - w).abs() / se);
            }
        }
        let inv = inverse(&want, m);
        let q: f64 = dx
            .iter()
            .map(|x| {
                (0..m)
                    .map(|a| x[a] * (0..m).map(|b| inv[a * m + b] * x[b]).sum::<f64>())
                    .sum::<f64>()
            })
            .sum::<f64>()
            / s;
        let se_q = (2.0 * m as f64 / s).sqrt();
        println!(
            "{what}: worst entry {worst:.2} standard errors, whitened mean {q:.3} (want {m} +- {se_q:.3})"
        );
        assert!(worst < 5.0, "{what}: an entry {worst} standard errors off");
        assert!((q - m as f64).abs() < 5.0 * se_q, "{what}: {q} vs {m}");
        let _ = n;
    }
}

/// `<|dx|^2> / (6 dt)` of a lone sphere (radius 1.5, `eta = 0.7`) over 20 000 steps
/// against `kT / (6 pi eta a)` in free space, and against Hasimoto's
/// `(1 - 2.837297 a/L + 4 pi / 3 (a/L)^3)` of it in a box of edge 30 (a step's kicks are
/// independent: the relative standard error is `sqrt(2/3 / S)`, 0.58 %); within four.
fn stokes_einstein<T: Real>() {
    let (a, eta, steps) = (1.5, 0.7, 20_000);
    for l in [None, Some(30.0)] {
        let d0 = 1.0 / (6.0 * PI * eta * a);
        let want = match l {
            None => d0,
            Some(l) => {
                let x = a / l;
                d0 * (1.0 - HASIMOTO * x + 4.0 * PI / 3.0 * x * x * x)
            }
        };
        let p = iterative::<T>(0.05, eta, Drift::Midpoint, l);
        let c = l.map_or(0.0, |l| l / 2.0);
        let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
            pos: [c; 3],
            radius: a,
            density: 0.0,
        }]);
        let mut buf = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
        let mut ws = buf.workspace();
        let mut noise = Noise::new(7);
        let mut sum = 0.0;
        for _ in 0..steps {
            let before = f64s::<T>(ps.pos[0]);
            free_step(&mut ps, &p, &mut ws, &mut noise).unwrap();
            let d = sub(f64s::<T>(ps.pos[0]), before);
            sum += dot(d, d);
        }
        let d = sum / steps as f64 / (6.0 * 0.05);
        let se = want * (2.0 / 3.0 / steps as f64).sqrt();
        println!("lone sphere {l:?}: D = {d:.6} (want {want:.6} +- {se:.6})");
        assert!((d - want).abs() < 4.0 * se, "{l:?}: {d} vs {want}");
    }
}

/// Distances of two unit spheres joined by a spring of stiffness `k` and rest length
/// `r0`, with the near field's minimum gap `min_gap`, one sample every `every` steps.
fn pair<T: Real>(
    drift: Drift,
    (k, r0, min_gap): (f64, f64, f64),
    dt: f64,
    steps: usize,
    every: usize,
) -> Vec<f64> {
    let mut p = iterative::<T>(dt, 1.0, drift, None);
    p.near = Some(NearField {
        min_gap: T::from_f64(min_gap),
        ..NearField::default()
    });
    let mut ps: ParticleSet<T, 2> = particles(&[
        Sphere {
            pos: [0.0; 3],
            radius: 1.0,
            density: 0.0,
        },
        Sphere {
            pos: [r0, 0.0, 0.0],
            radius: 1.0,
            density: 0.0,
        },
    ]);
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(if drift == Drift::Midpoint { 3 } else { 4 });
    let mut spring = |pos: &[T::V3], _: &[T], f: &mut [T::V3]| {
        let d = sub(f64s::<T>(pos[1]), f64s::<T>(pos[0]));
        let r = norm(d);
        let pull = scale(d, -k * (r - r0) / r);
        f[1] += T::v3_from(pull);
        f[0] -= T::v3_from(pull);
    };
    let mut out = Vec::with_capacity(steps / every);
    for s in 0..steps {
        step_thermal(&mut ps, &bonds, &p, &mut ws, &mut spring, &mut noise)
            .unwrap_or_else(|e| panic!("{drift:?} step {s}: {e}"));
        if s % every == 0 {
            out.push(norm(sub(f64s::<T>(ps.pos[1]), f64s::<T>(ps.pos[0]))));
        }
    }
    out
}

/// The spring of the pair near contact: stiffness (spread 0.12) and rest distance.
const SPRING: (f64, f64) = (1.0 / (0.12 * 0.12), 2.2);
/// The near-contact distance of the share [`PairStats::near`] measures.
const NEAR: f64 = 2.05;

/// What a run of the pair near contact measured, each with its standard error (40
/// blocks), or what the Boltzmann weight gives (standard errors 0).
#[derive(Debug, Clone, Copy)]
struct PairStats {
    /// `<r>`.
    mean: (f64, f64),
    /// `<(r - <r>_Boltzmann)^2>`.
    spread2: (f64, f64),
    /// The share of time below [`NEAR`].
    near: (f64, f64),
    /// The share of time in overlap (`r < 2`).
    overlap: (f64, f64),
}

impl PairStats {
    /// The Boltzmann weight's values (`r^2 exp(-k (r - r0)^2 / 2)`, by quadrature).
    fn boltzmann() -> PairStats {
        let (k, r0) = SPRING;
        let (mut z, mut m1, mut m2, mut below, mut over) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let h = 1e-4;
        for i in 1..200_000 {
            let r = i as f64 * h;
            let w = r * r * (-0.5 * k * (r - r0) * (r - r0)).exp();
            z += w;
            m1 += w * r;
            m2 += w * r * r;
            below += if r < NEAR { w } else { 0.0 };
            over += if r < 2.0 { w } else { 0.0 };
        }
        let (m1, m2) = (m1 / z, m2 / z);
        PairStats {
            mean: (m1, 0.0),
            spread2: (m2 - m1 * m1, 0.0),
            near: (below / z, 0.0),
            overlap: (over / z, 0.0),
        }
    }

    /// A run of `span` time units (a sample every 0.02) at `dt`.
    fn run(drift: Drift, min_gap: f64, dt: f64, span: f64) -> PairStats {
        let (k, r0) = SPRING;
        let every = (0.02 / dt).round() as usize;
        let r = pair::<f64>(drift, (k, r0, min_gap), dt, (span / dt) as usize, every);
        let m1 = PairStats::boltzmann().mean.0;
        let dev: Vec<f64> = r.iter().map(|x| (x - m1) * (x - m1)).collect();
        let below =
            |y: f64| -> Vec<f64> { r.iter().map(|&x| f64::from(u8::from(x < y))).collect() };
        PairStats {
            mean: block_mean(&r, 40),
            spread2: block_mean(&dev, 40),
            near: block_mean(&below(NEAR), 40),
            overlap: block_mean(&below(2.0), 40),
        }
    }

    /// Each quantity's distance from `want`'s in this run's standard errors.
    fn off(&self, want: &PairStats) -> [f64; 3] {
        let z = |(x, se): (f64, f64), (w, _): (f64, f64)| (x - w) / se;
        [
            z(self.mean, want.mean),
            z(self.spread2, want.spread2),
            z(self.near, want.near),
        ]
    }
}

/// A pair near contact (rest distance 2.2, spread 0.12: the overlap, about a
/// twenty-fifth of the time, is allowed, `Params::allow_overlap`, the near field
/// clamped at its minimum gap 0.02), `dt = 2e-3`, 800 time units (400 000 steps; under a
/// minute of one core) with the midpoint: the mean distance, its spread and the share of
/// time below `r = 2.05` within four standard errors (40 blocks) of the Boltzmann
/// weight's. Why the minimum gap 0.02: the step must resolve the gap where the pair's
/// mobility varies (`dt << xi 6 pi eta a^3 / (8 kT)`, docs/NEAR.md); at the default 1e-3
/// `dt = 2e-3` does not, and the midpoint's pair visits overlap several times less often
/// than the Boltzmann weight says (`pair_near_contact_in_dt`). The missing drift's bias
/// (the uncorrected scheme is squeezed towards contact, at every `dt`) is a few
/// standard errors of this run only, the pair's sojourns near contact being long: the
/// drift is told apart where it acts, in one step (`pair_drift`). `f64` only: the step
/// is the same in `f32` (the covariance and the bits are checked in both above).
#[test]
fn pair_near_contact() {
    let want = PairStats::boltzmann();
    let got = PairStats::run(Drift::Midpoint, 0.02, 2e-3, 800.0);
    let off = got.off(&want);
    println!("Boltzmann {want:?}\nmidpoint {got:?}, {off:.1?} standard errors");
    for (z, what) in off.into_iter().zip(["<r>", "spread", "share below 2.05"]) {
        assert!(
            z.abs() < 4.0,
            "{what}: {z:.1} standard errors off ({got:?})"
        );
    }
}

/// The drift where it is large: two unit spheres at a gap of 0.05 (`s = 2.05`), no
/// force, 150 000 single steps of `dt = 2e-3` from the same start a scheme (half a
/// minute of one core for both):
/// the mean relative displacement along their line of centres is
/// `kT dt div M_rel = kT dt (mu_par' + 2 (mu_par - mu_perp) / r)`, `M_rel` the
/// relative mobility of the dense `M_SD,tt` (its along and across values, the slope by
/// central differences), with the midpoint within four standard errors, and without it
/// zero within four; the prediction is more than eight standard errors from zero, so
/// the test tells the schemes apart. (The step resolves this gap: it moves the pair
/// `sqrt(2 kT dt mu_par)`, about an eighth of it.)
#[test]
fn pair_drift() {
    type T = f64;
    let (r, dt, samples) = (2.05, 2e-3, 150_000);
    let pair_at = |x: f64| {
        [0.0, x].map(|x| Sphere {
            pos: [x, 0.0, 0.0],
            radius: 1.0,
            density: 0.0,
        })
    };
    // The relative mobility `M11 + M22 - M12 - M21` along and across the line of centres.
    let rel = |x: f64| {
        let m = dense_tt::<T>(1.0, &pair_at(x), None);
        let block = |i: usize, j: usize, a: usize| m[(3 * i + a) * 6 + 3 * j + a];
        let rel = |a: usize| block(0, 0, a) + block(1, 1, a) - block(0, 1, a) - block(1, 0, a);
        (rel(0), rel(1))
    };
    let h = 1e-4;
    let (par, perp) = rel(r);
    let slope = (rel(r + h).0 - rel(r - h).0) / (2.0 * h);
    let want = dt * (slope + 2.0 * (par - perp) / r);
    let se_want = (2.0 * dt * par / samples as f64).sqrt();
    println!(
        "mu_par {par:.5}, mu_perp {perp:.5}, slope {slope:.5}: drift {want:.4e} ({:.1} standard errors)",
        want / se_want
    );
    assert!(want > 8.0 * se_want, "{want} vs {se_want}: cannot tell");
    for (drift, seed, expect) in [(Drift::Midpoint, 7, want), (Drift::Uncorrected, 8, 0.0)] {
        let p = iterative::<T>(dt, 1.0, drift, None);
        let (dx, _) = kicks(&p, &pair_at(r), samples, seed);
        let scale = (2.0 * dt).sqrt();
        let along: Vec<f64> = dx.iter().map(|x| (x[3] - x[0]) * scale).collect();
        let (m, se) = mean_se(&along);
        println!(
            "{drift:?}: {m:.4e} +- {se:.1e}, want {expect:.4e} ({:+.1} standard errors)",
            (m - expect) / se
        );
        assert!(
            (m - expect).abs() < 4.0 * se,
            "{drift:?}: {m} +- {se} vs {expect}"
        );
    }
}

/// Two runs of five Brownian steps of 20 spheres with close pairs in a box end on the
/// same bits.
fn same_bits<T: Real>() {
    let l = 14.0;
    let spheres: Vec<Sphere> = (0..20)
        .map(|k| {
            let (i, j, m) = ((k % 3) as f64, (k / 3 % 3) as f64, (k / 9) as f64);
            Sphere {
                pos: [2.0 + 2.15 * i, 2.0 + 2.2 * j, 2.0 + 2.1 * m + 0.1 * i],
                radius: 1.0,
                density: 0.0,
            }
        })
        .collect();
    let p = iterative::<T>(1e-3, 1.0, Drift::Midpoint, Some(l));
    let run = || {
        let mut ps: ParticleSet<T, 20> = particles(&spheres);
        let mut buf = Buffers::<T>::new(Layout::for_params(&p, 20, 0));
        let mut ws = buf.workspace();
        let mut noise = Noise::new(99);
        let mut r = StepReport::default();
        for _ in 0..5 {
            r = free_step(&mut ps, &p, &mut ws, &mut noise).unwrap();
        }
        (snapshot(&ps), r)
    };
    let (a, ra) = run();
    let (b, rb) = run();
    assert!(ra.near_pairs > 20, "pairs {}", ra.near_pairs);
    assert_eq!(a, b);
    assert_eq!(ra, rb);
}

/// What the iterative Brownian step still refuses, typed, the state and the generator
/// unchanged: `Overdamped2` at temperature, and a Lanczos root given too few iterations
/// (`NoConvergence` at the mobility stage); bonds and the wall step.
fn refusals<T: Real>() {
    let spheres = cluster([0.0; 3]);
    let n = spheres.len();
    let base = iterative::<T>(1e-3, 1.0, Drift::Midpoint, None);
    // One step from the cluster: its result, the state and generator before and after.
    let attempt = |p: &hydrorattle::Params<T>, bonds: &[Bond<T>]| {
        let mut ps: ParticleSet<T, 8> = particles(&spheres);
        let mut set: BondSet<T, 2> = BondSet::new();
        for &b in bonds {
            set.push(b, n).unwrap();
        }
        let mut buf = Buffers::<T>::new(Layout::for_params(p, n, bonds.len()));
        let mut ws = buf.workspace();
        let mut noise = Noise::new(5);
        let before = (snapshot(&ps), noise.save());
        let mut force = hydrorattle::NoForce;
        let r = step_thermal(&mut ps, &set, p, &mut ws, &mut force, &mut noise);
        (r, before, (snapshot(&ps), noise.save()))
    };
    let refused = |p: &hydrorattle::Params<T>, bonds: &[Bond<T>]| {
        let (r, before, after) = attempt(p, bonds);
        let e = r.expect_err("refused");
        assert_eq!(after, before, "{e:?}: state moved");
        e
    };
    let unsupported =
        |p: &hydrorattle::Params<T>, bonds: &[Bond<T>], what: &str| match refused(p, bonds) {
            StepError::Unsupported(m) => assert!(m.contains(what), "{m}"),
            other => panic!("{what}: {other:?}"),
        };
    let bond = Bond {
        i: 0,
        j: 1,
        length: T::from_f64(2.05),
    };
    // Bonds and the wall (its links one-sided constraints) step (refused before):
    // `near_con_brownian.rs`.
    let stepped = |p: &hydrorattle::Params<T>, bonds: &[Bond<T>]| {
        attempt(p, bonds).0.unwrap_or_else(|e| panic!("{e:?}"))
    };
    let r = stepped(&base, &[bond]);
    assert!(r.near_products > 0 && r.noise_iterations > 0, "{r:?}");
    let mut p = base;
    p.wall = Some(Wall::new(T::from_f64(-40.0)));
    let r = stepped(&p, &[]);
    assert!(r.near_products > 0 && r.noise_iterations > 0, "{r:?}");
    let mut p = base;
    p.method = hydrorattle::Method::Overdamped2;
    unsupported(&p, &[], "thermal noise");
    let mut p = base;
    p.lanczos.max_iterations = 2;
    match refused(&p, &[]) {
        StepError::NoConvergence {
            stage: Stage::Mobility,
            iterations: 2,
            ..
        } => {}
        other => panic!("two Lanczos iterations: {other:?}"),
    }
}

both_precisions! {
    covariance => covariance;
    stokes_einstein => stokes_einstein;
    same_bits => same_bits;
    refusals => refusals;
}

/// The pair near contact against the time step, at the near field's minimum gap 0.02
/// (the suite's) and the default 1e-3, 400 time units each: each scheme's mean, spread
/// and share below `r = 2.05` against the Boltzmann weight's, in standard errors, and
/// the share in overlap. About ten minutes of one core.
#[test]
#[ignore = "ten minutes: the pair near contact against the time step"]
fn pair_near_contact_in_dt() {
    let want = PairStats::boltzmann();
    println!("Boltzmann {want:?}");
    for min_gap in [0.02, 1e-3] {
        for dt in [2e-3, 5e-4] {
            for drift in [Drift::Midpoint, Drift::Uncorrected] {
                let got = PairStats::run(drift, min_gap, dt, 400.0);
                let (o, se_o) = got.overlap;
                println!(
                    "min_gap {min_gap} dt {dt:.0e} {drift:?}: {got:?}, {:.1?} se; in overlap {o:.4} +- {se_o:.4} (Boltzmann {:.4})",
                    got.off(&want),
                    want.overlap.0
                );
            }
        }
    }
}
