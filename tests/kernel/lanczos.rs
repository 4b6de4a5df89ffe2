//! The Lanczos square root of the mobility, checked against what
//! does not come from it:
//! * the block Cholesky factor `L` (`L L^T = M`): `y = M^(1/2) z` exactly when `L^-1 y`
//!   preserves inner products (`L^-1 M^(1/2)` is orthogonal) and `z_j . y_k` is
//!   symmetric (the positive symmetric root of `M` is unique);
//! * `M^(-1/2) z` times `M` gives back `M^(1/2) z`;
//! * free draining: `M^(1/2) z = z / sqrt(6 pi eta a_i)` exactly;
//! * the thermal step's displacements have covariance `2 kT dt M` (sampled, fixed seed,
//!   each entry within 5 of its standard errors `sqrt((S_ii S_jj + S_ij^2) / K)`).

use crate::common;

use common::*;
use hydrorattle::linalg::{self, tri};
use hydrorattle::mobility::assemble_tt;
use hydrorattle::noise::lanczos::{self, Lanczos, LanczosError};
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, NoiseSqrt, ParticleSet, Real,
    SolverKind, Stage, StepError, step,
};
use hydrorattle_heap::Buffers;

/// A polydisperse RPY helix of 64 beads (head of radius 2, tails 1, then every fifth
/// tail of radius 0.6).
fn beads() -> Vec<Sphere> {
    let mut s = helix(64, 2.0, 4.0, 1.0, 1.2);
    for (k, b) in s.iter_mut().enumerate().skip(1) {
        if k % 5 == 0 {
            b.radius = 0.6;
        }
    }
    s
}

/// The packed mobility of `spheres` at viscosity 1.
fn mobility<T: Real>(spheres: &[Sphere], hydro: Hydro) -> Vec<T::M3> {
    let pos: Vec<T::V3> = spheres.iter().map(|s| T::v3_from(s.pos)).collect();
    let radius: Vec<T> = spheres.iter().map(|s| T::from_f64(s.radius)).collect();
    let mut mu = vec![T::M3_ZERO; tri(spheres.len())];
    assemble_tt(hydro, T::ONE, &pos, &radius, &mut mu).unwrap();
    mu
}

fn vdot<T: Real>(a: &[T::V3], b: &[T::V3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| dot(f64s::<T>(x), f64s::<T>(y)))
        .sum()
}

/// `(M^(1/2) z, M^(-1/2) z, iterations)` by Lanczos with settings `s`.
#[allow(clippy::type_complexity)]
fn roots<T: Real>(
    mu: &[T::M3],
    z: &[T::V3],
    s: Lanczos<T>,
) -> Result<(Vec<T::V3>, Vec<T::V3>, u32), LanczosError> {
    let n = z.len();
    let cap = s.max_iterations as usize;
    let mut basis = vec![T::V3_ZERO; lanczos::vectors(cap, n)];
    let mut work = vec![T::ZERO; lanczos::scalars(cap)];
    let (mut y, mut w) = (vec![T::V3_ZERO; n], vec![T::V3_ZERO; n]);
    let product = |v: &[T::V3], out: &mut [T::V3]| linalg::sym_matvec::<T>(mu, n, v, out);
    let m = lanczos::sqrt(s, product, z, &mut basis, &mut work, &mut y, Some(&mut w))?;
    Ok((y, w, m))
}

fn against_cholesky<T: Real>() {
    let spheres = beads();
    let n = spheres.len();
    let mu = mobility::<T>(&spheres, Hydro::Rpy);
    let mut fac = mu.clone();
    linalg::cholesky::<T>(&mut fac, n).unwrap();
    let s = Lanczos::<T>::default();
    // Stated tolerance, with room for the estimate (change between iterations) and
    // round-off in T.
    let tol = 10.0 * s.tolerance.to_f64();
    let mut noise = Noise::new(7);
    let mut zs = Vec::new();
    let mut ys = Vec::new();
    let mut us = Vec::new();
    for _ in 0..4 {
        let mut z = vec![T::V3_ZERO; n];
        noise.fill::<T>(&mut z);
        let (y, w, m) = roots::<T>(&mu, &z, s).unwrap();
        println!("n = {n}: {m} Lanczos iterations");
        assert!(m > 2 && m < s.max_iterations, "iterations {m}");
        // M M^(-1/2) z = M^(1/2) z.
        let mut mw = vec![T::V3_ZERO; n];
        linalg::sym_matvec::<T>(&mu, n, &w, &mut mw);
        let diff: Vec<T::V3> = mw.iter().zip(&y).map(|(&a, &b)| a - b).collect();
        let rel = (vdot::<T>(&diff, &diff) / vdot::<T>(&y, &y)).sqrt();
        assert!(rel < tol, "M M^-1/2 z vs M^1/2 z: {rel:.2e} > {tol:.0e}");
        let mut u = y.clone();
        linalg::solve_lower::<T>(&fac, n, &mut u);
        zs.push(z);
        ys.push(y);
        us.push(u);
    }
    for j in 0..4 {
        for k in 0..4 {
            let scale = (vdot::<T>(&zs[j], &zs[j]) * vdot::<T>(&zs[k], &zs[k])).sqrt();
            // L^-1 M^(1/2) is orthogonal.
            let e = (vdot::<T>(&us[j], &us[k]) - vdot::<T>(&zs[j], &zs[k])).abs() / scale;
            assert!(e < tol, "({j},{k}): L^-1 y inner product off by {e:.2e}");
            // M^(1/2) is symmetric.
            let yscale = (vdot::<T>(&ys[j], &ys[j]) * vdot::<T>(&zs[k], &zs[k])).sqrt();
            let e = (vdot::<T>(&zs[j], &ys[k]) - vdot::<T>(&zs[k], &ys[j])).abs() / yscale;
            assert!(e < tol, "({j},{k}): z_j . y_k asymmetric by {e:.2e}");
        }
    }
}

fn free_draining_exact<T: Real>() {
    let spheres = beads();
    let n = spheres.len();
    let mu = mobility::<T>(&spheres, Hydro::FreeDraining);
    let mut z = vec![T::V3_ZERO; n];
    Noise::new(3).fill::<T>(&mut z);
    let (y, w, m) = roots::<T>(&mu, &z, Lanczos::default()).unwrap();
    // Three distinct radii: the Krylov space has dimension 3.
    assert!(m <= 4, "{m} iterations for three distinct eigenvalues");
    let tol = pick::<T>(1e-5, 1e-12);
    for i in 0..n {
        let d = 1.0 / (6.0 * std::f64::consts::PI * spheres[i].radius);
        let (zi, yi, wi) = (f64s::<T>(z[i]), f64s::<T>(y[i]), f64s::<T>(w[i]));
        for c in 0..3 {
            assert!((yi[c] - zi[c] * d.sqrt()).abs() < tol * zi[c].abs().max(1.0) * d.sqrt());
            assert!((wi[c] - zi[c] / d.sqrt()).abs() < tol * zi[c].abs().max(1.0) / d.sqrt());
        }
    }
}

const DT: f64 = 0.02;

/// Thermal parameters by Lanczos: no gravity, `kT = 1`, viscosity 1.
fn thermal<T: Real>(drift: Drift) -> hydrorattle::Params<T> {
    let mut p = params::<T>(DT, Method::Overdamped, SolverKind::Auto);
    p.gravity = T::V3_ZERO;
    p.allow_overlap = true;
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift,
    });
    p.noise_sqrt = NoiseSqrt::Lanczos;
    p
}

fn covariance<T: Real>() {
    const N: usize = 10;
    let spheres: Vec<Sphere> = beads().into_iter().take(N).collect();
    let p = thermal::<T>(Drift::Uncorrected);
    let start: ParticleSet<T, N> = particles(&spheres);
    let bonds = BondSet::<T, 1>::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, N, 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(11);
    let k = 4000;
    let dim = 3 * N;
    let mut c = vec![0.0; dim * dim];
    for s in 0..k {
        let mut ps = start.clone();
        let r = step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise)
            .unwrap_or_else(|e| panic!("step {s}: {e}"));
        assert!(r.noise_iterations > 1);
        let dx: Vec<f64> = (0..N)
            .flat_map(|i| sub(f64s::<T>(ps.pos[i]), f64s::<T>(start.pos[i])))
            .collect();
        for a in 0..dim {
            for b in 0..dim {
                c[a * dim + b] += dx[a] * dx[b] / k as f64;
            }
        }
    }
    // Exact: 2 kT dt M.
    let mu = mobility::<T>(&spheres, Hydro::Rpy);
    let exact = |a: usize, b: usize| {
        let m = f64s::<T>(T::m3_tmul(
            linalg::sym_get::<T>(&mu, b / 3, a / 3),
            T::v3_from(unit(b % 3)),
        ));
        2.0 * DT * m[a % 3]
    };
    let mut worst: f64 = 0.0;
    for a in 0..dim {
        for b in 0..dim {
            let s = exact(a, b);
            let se = ((exact(a, a) * exact(b, b) + s * s) / k as f64).sqrt();
            worst = worst.max((c[a * dim + b] - s).abs() / se);
        }
    }
    println!("largest deviation: {worst:.2} standard errors");
    assert!(worst < 5.0, "covariance off by {worst:.2} standard errors");
    // Power: the free-draining covariance (no interactions) must fail.
    let fd = mobility::<T>(&spheres, Hydro::FreeDraining);
    let m01 = f64s::<T>(T::m3_tmul(
        linalg::sym_get::<T>(&fd, 0, 1),
        T::v3_from(unit(0)),
    ));
    let se = ((exact(0, 0) * exact(3, 3) + exact(0, 3).powi(2)) / k as f64).sqrt();
    assert!(
        (exact(0, 3) - m01[0]).abs() > 10.0 * se,
        "test has no power"
    );
}

fn unit(c: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    e[c] = 1.0;
    e
}

fn cap_refused<T: Real>() {
    const N: usize = 64;
    let spheres = beads();
    let mut p = thermal::<T>(Drift::Midpoint);
    let mut ps: ParticleSet<T, N> = particles(&spheres);
    let pos: Vec<T::V3> = ps.pos[..N].to_vec();
    let bonds = BondSet::<T, 63>::chain(&pos).unwrap();
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, N, 63));
    p.lanczos.max_iterations = 3;
    let mut ws = buf.workspace();
    ps.noise = Some(Noise::new(5));
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    assert_failed_unchanged(
        &before,
        &ps,
        &r,
        |e| {
            matches!(
                e,
                StepError::NoConvergence {
                    stage: Stage::Mobility,
                    iterations: 3,
                    ..
                }
            )
        },
        "Lanczos past its cap",
    );
    assert_eq!(ps.noise, Some(Noise::new(5)), "generator moved");
    // With the default cap the same step goes through.
    p.lanczos = Lanczos::default();
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
    println!(
        "N = {N}, midpoint: {} Lanczos iterations",
        r.noise_iterations
    );
    assert!(r.noise_iterations > 3);
    assert_ne!(ps.noise, Some(Noise::new(5)));
}

fn determinism<T: Real>() {
    const N: usize = 64;
    let spheres = beads();
    let run = || {
        let p = thermal::<T>(Drift::Midpoint);
        let mut ps: ParticleSet<T, N> = particles(&spheres);
        let pos: Vec<T::V3> = ps.pos[..N].to_vec();
        let bonds = BondSet::<T, 63>::chain(&pos).unwrap();
        let mut buf = Buffers::<T>::new(Layout::for_params(&p, N, 63));
        let mut ws = buf.workspace();
        ps.noise = Some(Noise::new(9));
        let mut counts = Vec::new();
        for _ in 0..3 {
            counts.push(
                step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
                    .unwrap()
                    .noise_iterations,
            );
        }
        (snapshot(&ps), ps.noise.clone(), counts)
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b, "same seed, different bits");
    println!("iterations per step: {:?}", a.2);
}

both_precisions! {
    lanczos_against_cholesky => against_cholesky;
    lanczos_free_draining_exact => free_draining_exact;
    lanczos_covariance => covariance;
    lanczos_cap_refused => cap_refused;
    lanczos_determinism => determinism;
}
