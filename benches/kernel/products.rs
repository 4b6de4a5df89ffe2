//! One product `mu_tt x` by each path (`products/...`): stored f64 blocks, the compact
//! f32 copy, and the recompute path, one thread.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion};
use hydrorattle::Real;
use hydrorattle::mobility::Hydro;

use crate::shared::chain_geometry;

/// Sizes of the product-path benches.
const PATH_SIZES: [usize; 3] = [1024, 4096, 8192];

/// One product `y = mu_tt x` by each path on one thread (`products/{stored_f64,
/// compact_f32,recompute}/N`): the stored `f64` blocks (symmetric: 48 bytes a pair), the compact
/// `f32` copy (24 bytes) and the recompute path (pairs evaluated, nothing read).
/// Criterion reports the bytes a product streams as its throughput (the recompute
/// path's as pairs); ns per pair is the time over `N (N + 1) / 2`.
pub(crate) fn product_paths(c: &mut Criterion) {
    use criterion::Throughput;
    use hydrorattle::noise::reduced;
    use hydrorattle::parallel::{self, Serial, band_scratch};
    for &n in &PATH_SIZES {
        let (p, rad) = chain_geometry(n);
        let pos: Vec<glam::DVec3> = p.iter().map(|&x| f64::v3_from(x)).collect();
        let x: Vec<glam::DVec3> = (0..n)
            .map(|i| glam::DVec3::new((i as f64).sin(), 0.5, 1.0))
            .collect();
        let (mut y, mut z) = (
            vec![glam::DVec3::ZERO; n],
            vec![glam::DVec3::ZERO; band_scratch(n)],
        );
        let pairs = (n * (n + 1) / 2) as u64;
        let mut mu: Vec<hydrorattle::linalg::Sym<f64>> = vec![[0.0; 6]; n * (n + 1) / 2];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &rad, &mut mu).unwrap();
        let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
        reduced::copy_apply::<f64>(&Serial, &mu, n, &mut copy, &x, &mut y, &mut z);
        let mut g = c.benchmark_group("products/stored_f64");
        g.throughput(Throughput::Bytes(48 * pairs));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| parallel::product::<f64>(&Serial, black_box(&mu), n, &x, &mut y, &mut z))
        });
        g.finish();
        drop(mu);
        let mut g = c.benchmark_group("products/compact_f32");
        g.throughput(Throughput::Bytes(24 * pairs));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| reduced::apply::<f64>(&Serial, black_box(&copy), n, &x, &mut y, &mut z))
        });
        g.finish();
        drop(copy);
        let mut g = c.benchmark_group("products/recompute");
        g.throughput(Throughput::Elements(pairs));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                parallel::free_product::<f64>(
                    &Serial,
                    Hydro::Rpy,
                    1.0,
                    black_box(&pos),
                    &rad,
                    &x,
                    &mut y,
                    &mut z,
                )
                .unwrap()
            })
        });
        g.finish();
    }
}
