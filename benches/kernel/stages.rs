//! The stage functions on `Vec`-backed slices: `assemble_tt`, `assemble_grand`,
//! `cholesky_tt`, `cholesky_solve_tt`, `sym_matvec_tt`, f64 and f32.

use std::hint::black_box;

use criterion::{BatchSize, BenchmarkId, Criterion};
use hydrorattle::Real;
use hydrorattle::linalg::{cholesky, cholesky_solve, sym_matvec};
use hydrorattle::mobility::{Hydro, assemble_grand, assemble_tt};

use crate::shared::chain_geometry;

/// Stage sizes.
const STAGE_SIZES: [usize; 4] = [8, 25, 100, 256];

pub(crate) fn stage_benches<T: Real>(c: &mut Criterion, prec: &str) {
    let data: Vec<(usize, Vec<T::V3>, Vec<T>)> = STAGE_SIZES
        .iter()
        .map(|&n| {
            let (p, r) = chain_geometry(n);
            (
                n,
                p.iter().map(|&x| T::v3_from(x)).collect(),
                r.iter().map(|&a| T::from_f64(a)).collect(),
            )
        })
        .collect();
    let eta = T::ONE;

    let mut g = c.benchmark_group(format!("assemble_tt/{prec}"));
    for (n, pos, rad) in &data {
        let mut out = vec![T::M3_ZERO; n * n];
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| assemble_tt(Hydro::Rpy, eta, black_box(pos), rad, &mut out).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("assemble_grand/{prec}"));
    for (n, pos, rad) in &data {
        let mut out = vec![T::M3_ZERO; 4 * n * n];
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| assemble_grand(Hydro::Rpy, eta, black_box(pos), rad, &mut out).unwrap())
        });
    }
    g.finish();

    // The factorisation overwrites its input: each iteration gets a fresh copy
    // (made outside the timed region).
    let mut g = c.benchmark_group(format!("cholesky_tt/{prec}"));
    for (n, pos, rad) in &data {
        let n = *n;
        let mut mu = vec![T::M3_ZERO; n * n];
        assemble_tt(Hydro::Rpy, eta, pos, rad, &mut mu).unwrap();
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter_batched_ref(
                || mu.clone(),
                |m| cholesky::<T>(black_box(m), n).unwrap(),
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("cholesky_solve_tt/{prec}"));
    for (n, pos, rad) in &data {
        let n = *n;
        let mut fac = vec![T::M3_ZERO; n * n];
        assemble_tt(Hydro::Rpy, eta, pos, rad, &mut fac).unwrap();
        cholesky::<T>(&mut fac, n).unwrap();
        let rhs = vec![T::v3(T::ZERO, T::ZERO, -T::ONE); n];
        let mut x = rhs.clone();
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                x.copy_from_slice(&rhs);
                cholesky_solve::<T>(black_box(&fac), n, &mut x);
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group(format!("sym_matvec_tt/{prec}"));
    for (n, pos, rad) in &data {
        let n = *n;
        let mut mu = vec![T::M3_ZERO; n * n];
        assemble_tt(Hydro::Rpy, eta, pos, rad, &mut mu).unwrap();
        let f = vec![T::v3(T::ZERO, T::ZERO, -T::ONE); n];
        let mut u = vec![T::V3_ZERO; n];
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| sym_matvec::<T>(black_box(&mu), n, &f, &mut u))
        });
    }
    g.finish();
}
