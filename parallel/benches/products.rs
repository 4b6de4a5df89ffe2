//! Criterion benchmarks of the product paths, `f64` kernel, on the kernel
//! bench's N-bead chain (`benches/kernel/shared.rs`: head 2^(1/3), tails 1, bonds 1.5 (a_i + a_j)):
//!
//! * `block/{stored,stored9,compact,recompute}/k{1,2,4}/N` (N = 1024, 4096, one thread):
//!   one block product of `k` vectors (`parallel::products`, `noise::reduced::apply_k`,
//!   `parallel::free_products`). Per vector it reads `1 / k` of the bytes (stored: the
//!   free-space symmetric blocks, 48 a pair; stored9: the same blocks in nine entries,
//!   as a wall's are stored, 72; compact: 24) or evaluates `1 / k` of the pair blocks
//!   (recompute: 63 flops a pair, then 36 a vector).
//! * `paths/{stored,stored9,compact,recompute}/{portable,avx2}/t{1,2}/N` (N = 1024, 4096, 8192):
//!   one product by each path, the portable kernel function or the runtime-selected AVX2
//!   copy (`hydrorattle_parallel::wide`), on 1 and 2 threads.
//!
//! ns per pair is the median over `N (N + 1) / 2` (and, for a block product, over `k`);
//! GB/s is the bytes per pair over it. `cargo bench -p hydrorattle-parallel --bench
//! products -- 'block/'` (or `'paths/'`, or a narrower filter).

use criterion::{BenchmarkId, Criterion, SamplingMode, Throughput};
use hydrorattle::glam::DVec3;
use hydrorattle::linalg::Sym;
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Parallel, Serial, band_scratch};
use hydrorattle::{Hydro, Real};
use hydrorattle_parallel::{Threads, wide};
use std::hint::black_box;
use std::time::Duration;

/// The kernel bench's chain of `n` beads.
fn chain(n: usize) -> (Vec<DVec3>, Vec<f64>) {
    let (mut pos, mut rad) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut at, mut prev) = (DVec3::ZERO, 0.0);
    for k in 0..n {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if k > 0 {
            let t = 0.6 * k as f64;
            at += DVec3::new(t.cos(), t.sin(), 0.8).normalize() * 1.5 * (a + prev);
        }
        pos.push(at);
        rad.push(a);
        prev = a;
    }
    (pos, rad)
}

/// A path's data at one size.
struct Data {
    n: usize,
    pos: Vec<DVec3>,
    rad: Vec<f64>,
    mu: Vec<Sym<f64>>,
    mu9: Vec<<f64 as Real>::M3>,
    copy: Vec<<f64 as Real>::M3>,
    xs: [Vec<DVec3>; 4],
}

impl Data {
    fn new(n: usize) -> Self {
        let (pos, rad) = chain(n);
        let xs: [Vec<DVec3>; 4] = core::array::from_fn(|q| {
            (0..n)
                .map(|i| DVec3::new((i as f64 + q as f64).sin(), 0.5, 1.0 - q as f64))
                .collect()
        });
        let mut mu = vec![[0.0; 6]; n * (n + 1) / 2];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &rad, &mut mu).unwrap();
        let mut mu9 = vec![f64::M3_ZERO; n * (n + 1) / 2];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &rad, &mut mu9).unwrap();
        let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
        let (mut y, mut z) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; band_scratch(n)]);
        reduced::copy_apply::<f64>(&Serial, &mu, n, &mut copy, &xs[0], &mut y, &mut z);
        Self {
            n,
            pos,
            rad,
            mu,
            mu9,
            copy,
            xs,
        }
    }

    fn pairs(&self) -> u64 {
        (self.n * (self.n + 1) / 2) as u64
    }

    /// One block product of the first `K` vectors by `path` through `par`, `wide`
    /// choosing the AVX2 copy.
    fn run<const K: usize>(&self, path: &str, avx2: bool, par: &dyn Parallel, out: &mut Out) {
        let n = self.n;
        let x: [&[DVec3]; K] = core::array::from_fn(|q| &self.xs[q][..]);
        let mut it = out.ys.iter_mut();
        let y: [&mut [DVec3]; K] = core::array::from_fn(|_| &mut it.next().unwrap()[..]);
        let (z, mu, copy) = (
            &mut out.z[..],
            black_box(&self.mu[..]),
            black_box(&self.copy),
        );
        let (pos, rad) = (black_box(&self.pos[..]), &self.rad[..]);
        match (path, avx2) {
            ("stored", false) => parallel::products::<f64, K>(par, mu, n, x, y, z),
            ("stored", true) => wide::products::<K>(par, mu, n, x, y, z),
            ("stored9", false) => parallel::products::<f64, K>(par, &self.mu9, n, x, y, z),
            ("stored9", true) => wide::products::<K>(par, &self.mu9, n, x, y, z),
            ("compact", false) => reduced::apply_k::<f64, K>(par, copy, n, x, y, z),
            ("compact", true) => wide::compact_products::<K>(par, copy, n, x, y, z),
            ("recompute", false) => {
                parallel::free_products::<f64, K>(par, Hydro::Rpy, 1.0, pos, rad, x, y, z).unwrap()
            }
            _ => wide::free_products::<K>(par, Hydro::Rpy, 1.0, pos, rad, x, y, z).unwrap(),
        }
    }
}

/// Outputs and scratch for up to four vectors.
struct Out {
    ys: [Vec<DVec3>; 4],
    z: Vec<DVec3>,
}

impl Out {
    fn new(n: usize) -> Self {
        Self {
            ys: core::array::from_fn(|_| vec![DVec3::ZERO; n]),
            z: vec![DVec3::ZERO; 4 * band_scratch(n)],
        }
    }
}

const PATHS: [(&str, u64); 4] = [
    ("stored", 48),
    ("stored9", 72),
    ("compact", 24),
    ("recompute", 0),
];

fn block(c: &mut Criterion) {
    for n in [1024, 4096] {
        let (data, mut out) = (Data::new(n), Out::new(n));
        for (path, bytes) in PATHS {
            let mut g = c.benchmark_group(format!("block/{path}"));
            g.sampling_mode(SamplingMode::Flat);
            for k in [1usize, 2, 4] {
                // Bytes read per product: one pass over the blocks for all k vectors.
                g.throughput(match bytes {
                    0 => Throughput::Elements(data.pairs() * k as u64),
                    b => Throughput::Bytes(b * data.pairs()),
                });
                let id = BenchmarkId::new(format!("k{k}"), n);
                g.bench_function(id, |b| match k {
                    1 => b.iter(|| data.run::<1>(path, false, &Serial, &mut out)),
                    2 => b.iter(|| data.run::<2>(path, false, &Serial, &mut out)),
                    _ => b.iter(|| data.run::<4>(path, false, &Serial, &mut out)),
                });
            }
            g.finish();
        }
    }
}

fn paths(c: &mut Criterion) {
    let pools = [Threads::new(1).unwrap(), Threads::new(2).unwrap()];
    for n in [1024, 4096, 8192] {
        let (data, mut out) = (Data::new(n), Out::new(n));
        for (path, bytes) in PATHS {
            for avx2 in [false, true] {
                let build = if avx2 { "avx2" } else { "portable" };
                let mut g = c.benchmark_group(format!("paths/{path}/{build}"));
                g.sampling_mode(SamplingMode::Flat);
                g.throughput(match bytes {
                    0 => Throughput::Elements(data.pairs()),
                    b => Throughput::Bytes(b * data.pairs()),
                });
                for pool in &pools {
                    let id = BenchmarkId::new(format!("t{}", pool.threads()), n);
                    g.bench_function(id, |b| b.iter(|| data.run::<1>(path, avx2, pool, &mut out)));
                }
                g.finish();
            }
        }
    }
}

fn main() {
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500))
        .configure_from_args();
    block(&mut c);
    paths(&mut c);
    c.final_summary();
}
