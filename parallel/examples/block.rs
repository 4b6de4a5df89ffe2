//! Block products and the runtime AVX2 copies, timed against each other on a shared
//! machine (docs/BENCHMARKS.md, "Block products and runtime AVX2").
//!
//! `cargo run --release -p hydrorattle-parallel --example block -- [N] [THREADS] [ROUNDS] [PATH]`
//! (defaults 4096, 2, 3, every path; PATH `stored`, `compact` or `recompute` times that one).
//!
//! For each path (the stored `f64` blocks, the compact `f32` copy, the recompute path),
//! each build of its band loop (the portable kernel function, the AVX2 copy of
//! `hydrorattle_parallel::wide`), 1 and THREADS threads, and `k` = 1, 2 and 4 vectors a
//! pass: the best of ROUNDS products, the configurations taken in turn within each round
//! so that a change of the machine's load reaches them all alike. Prints ns per pair per
//! vector (the time over `k N (N + 1) / 2`) and the bytes a vector's product streams per
//! second (72 or 24 bytes a pair over `k`), by the wall clock, and the CPU time the
//! process's threads ran for it (Linux's `/proc/self/task/*/schedstat`; on a shared
//! machine the wall clock also counts the time a thread waited for a core, the CPU time
//! does not: on one thread it is the cost to read). The bits of the AVX2 copy and of each
//! block product against the portable single product are compared on every run.

use std::time::Instant;

use hydrorattle::glam::DVec3;
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Parallel, Serial, band_scratch};
use hydrorattle::{Hydro, Real};
use hydrorattle_parallel::{Threads, wide};

/// The three paths and their bytes per pair (0: nothing read).
const PATHS: [(&str, f64); 3] = [("stored", 72.0), ("compact", 24.0), ("recompute", 0.0)];

mod common;
use common::cpu_ns;

struct Data {
    n: usize,
    pos: Vec<DVec3>,
    radius: Vec<f64>,
    mu: Vec<<f64 as Real>::M3>,
    copy: Vec<<f64 as Real>::M3>,
    xs: Vec<Vec<DVec3>>,
    ys: Vec<Vec<DVec3>>,
    z: Vec<DVec3>,
}

impl Data {
    /// One product of the first `K` vectors by `path`, AVX2 or portable, through `par`.
    fn run<const K: usize>(&mut self, path: &str, avx2: bool, par: &dyn Parallel) {
        let n = self.n;
        let x: [&[DVec3]; K] = core::array::from_fn(|q| &self.xs[q][..]);
        let mut it = self.ys.iter_mut();
        let y: [&mut [DVec3]; K] = core::array::from_fn(|_| &mut it.next().unwrap()[..]);
        let (z, mu, copy) = (&mut self.z[..], &self.mu[..], &self.copy[..]);
        let (pos, rad) = (&self.pos[..], &self.radius[..]);
        match (path, avx2) {
            ("stored", false) => parallel::products::<f64, K>(par, mu, n, x, y, z),
            ("stored", true) => wide::products::<K>(par, mu, n, x, y, z),
            ("compact", false) => reduced::apply_k::<f64, K>(par, copy, n, x, y, z),
            ("compact", true) => wide::compact_products::<K>(par, copy, n, x, y, z),
            ("recompute", false) => {
                parallel::free_products::<f64, K>(par, Hydro::Rpy, 1.0, pos, rad, x, y, z).unwrap()
            }
            _ => wide::free_products::<K>(par, Hydro::Rpy, 1.0, pos, rad, x, y, z).unwrap(),
        }
    }

    fn bits(&self, q: usize) -> Vec<[u64; 3]> {
        self.ys[q]
            .iter()
            .map(|v| v.to_array().map(f64::to_bits))
            .collect()
    }
}

fn main() {
    let arg = |k: usize, d: usize| {
        std::env::args()
            .nth(k)
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let (n, threads, rounds) = (arg(1, 4096), arg(2, 2), arg(3, 3));
    let only = std::env::args().nth(4).unwrap_or_default();
    let pos = common::helix(n);
    let radius = vec![1.0; n];
    let xs: Vec<Vec<DVec3>> = (0..4)
        .map(|q| {
            (0..n)
                .map(|i| DVec3::new((i as f64 + q as f64).sin(), 0.5, 1.0 - q as f64))
                .collect()
        })
        .collect();
    let mut mu = vec![f64::M3_ZERO; n * (n + 1) / 2];
    parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
    let (mut y, mut z) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; 4 * band_scratch(n)]);
    let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
    reduced::copy_apply::<f64>(&Serial, &mu, n, &mut copy, &xs[0], &mut y, &mut z);
    let mut d = Data {
        n,
        pos,
        radius,
        mu,
        copy,
        xs,
        ys: vec![vec![DVec3::ZERO; n]; 4],
        z,
    };
    let pools = [Threads::new(1).unwrap(), Threads::new(threads).unwrap()];
    // Every configuration, its best time and whether its bits agreed every time.
    let mut configs = Vec::new();
    for (path, bytes) in PATHS.into_iter().filter(|p| p.0.contains(only.as_str())) {
        for avx2 in [false, true] {
            for t in 0..2 {
                for k in [1usize, 2, 4] {
                    let best = [f64::INFINITY; 2];
                    configs.push((path, bytes, avx2, t, k, best, true));
                }
            }
        }
    }
    // The portable single products: the bits every configuration must give.
    let reference: Vec<Vec<Vec<[u64; 3]>>> = PATHS
        .iter()
        .map(|&(path, _)| {
            (0..4)
                .map(|q| {
                    d.xs.swap(0, q);
                    d.run::<1>(path, false, &Serial);
                    d.xs.swap(0, q);
                    d.bits(0)
                })
                .collect()
        })
        .collect();
    for _ in 0..rounds {
        for c in configs.iter_mut() {
            let (path, _, avx2, t, k, best, same) = c;
            let par = &pools[*t];
            let (t0, c0) = (Instant::now(), cpu_ns());
            match *k {
                1 => d.run::<1>(path, *avx2, par),
                2 => d.run::<2>(path, *avx2, par),
                _ => d.run::<4>(path, *avx2, par),
            }
            best[0] = best[0].min(t0.elapsed().as_secs_f64());
            best[1] = best[1].min((cpu_ns() - c0) as f64 * 1e-9);
            let p = PATHS.iter().position(|&(name, _)| name == *path).unwrap();
            *same &= (0..*k).all(|q| d.bits(q) == reference[p][q]);
        }
    }
    println!(
        "N = {n}, best of {rounds} (AVX2 copies available: {})",
        wide::avx2()
    );
    let pairs = (n * (n + 1) / 2) as f64;
    for (path, bytes, avx2, t, k, best, same) in configs {
        let [ns, cpu] = best.map(|s| s / (pairs * k as f64) * 1e9);
        let rate = match bytes {
            0.0 => String::new(),
            b => format!(", {:.2} GB/s", b / k as f64 / ns),
        };
        println!(
            "{path:9} {:8} {} thread(s) k = {k}: {ns:.2} ns/pair/vector{rate} (CPU {cpu:.2} ns), bits {}",
            if avx2 { "avx2" } else { "portable" },
            pools[t].threads(),
            if same { "identical" } else { "DIFFERENT" }
        );
    }
}
