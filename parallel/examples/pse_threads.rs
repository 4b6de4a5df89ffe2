//! The PSE product (`mobility::pse`, f64, tolerance 1e-4) of N unit spheres at volume
//! fraction 0.1 on 1 and on more threads: wall time per product, the speedup, and
//! whether the bits agree.
//!
//! `cargo run --release -p hydrorattle-parallel --example pse_threads -- [N] [THREADS]`
//! (defaults 100000, 2). Best of three products per thread count (the machine may be
//! shared).

use std::time::Instant;

use hydrorattle::glam::DVec3;
use hydrorattle::mobility::pse::{Part, Pse};
use hydrorattle::{Parallel, Periodic, Serial};
use hydrorattle_heap::PseBuffers;
use hydrorattle_parallel::Threads;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    let (n, threads) = (
        *args.first().unwrap_or(&100_000),
        *args.get(1).unwrap_or(&2),
    );
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / 0.1).cbrt();
    // SplitMix64 positions and forces.
    let mut s = 7u64;
    let mut unit = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let pos: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(unit() * l, unit() * l, unit() * l))
        .collect();
    let f: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5))
        .collect();
    let rad = vec![1.0; n];
    let pse = Pse::new(Periodic::new([l; 3]).unwrap(), 1.0, 1e-4).unwrap();
    let size = pse.storage(n);
    let mut arrays = PseBuffers::new(size);
    let mut run = |par: &dyn Parallel| {
        let mut store = arrays.storage().with_parallel(par);
        let mut out = vec![DVec3::ZERO; n];
        let best = (0..3)
            .map(|_| {
                let t = Instant::now();
                pse.apply(Part::Both, 1.0, &pos, &rad, &f, &mut out, &mut store)
                    .unwrap();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min);
        (best, out)
    };
    let (t1, one) = run(&Serial);
    let pool = Threads::new(threads).unwrap();
    let (tn, many) = run(&pool);
    println!(
        "N {n}, grid {:?}: 1 thread {t1:.3} s, {threads} threads {tn:.3} s, speedup {:.2}, same bits: {}",
        pse.grid(),
        t1 / tn,
        one == many
    );
}
