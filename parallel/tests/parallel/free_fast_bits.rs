//! The fast free-space product (`mobility::free_fast`), and its grand product, on a
//! thread pool give the bits of one thread: its pieces (near rows and their partial sums, slabs of grid planes,
//! rounds of `z` lines, interpolation rows) depend on the sizes alone, and each value's
//! arithmetic is the same in whichever piece it falls. The kernel's transform too
//! (samples by slabs of planes, `x` and `y` passes by slabs, `z` lines by slabs of `y`
//! frequencies).

use hydrorattle::Real;
use hydrorattle::glam::DVec3;
use hydrorattle::mobility::free_fast::{FreeFast, transform_counts};
use hydrorattle::parallel::{Parallel, Serial};
use hydrorattle_heap::FreeBuffers;
use hydrorattle_parallel::Threads;

use crate::fuzz::Rng;

/// `M F` as bits, with `par`, twice on the same storage (the second with the kernel
/// kept), then the grand product with torques `f` reversed, then the reals the storage
/// holds: the kernel's transform, computed on `par`, and its header.
fn product(
    ff: &FreeFast<f64>,
    pos: &[DVec3],
    rad: &[f64],
    f: &[DVec3],
    par: &dyn Parallel,
) -> Vec<u64> {
    let n = pos.len();
    let size = ff.storage_grand(n);
    let mut arrays = FreeBuffers::new(size);
    let mut bits = vec![];
    {
        let mut store = arrays.storage().with_parallel(par);
        for _ in 0..2 {
            let mut out = vec![DVec3::ZERO; n];
            ff.apply(1.0, pos, rad, f, &mut out, &mut store).unwrap();
            bits.extend(out.iter().flat_map(|u| u.to_array().map(f64::to_bits)));
        }
        let t: Vec<DVec3> = f.iter().rev().copied().collect();
        let (mut u, mut w) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        ff.apply_grand(1.0, (pos, rad), f, &t, &mut u, &mut w, &mut store)
            .unwrap();
        bits.extend(
            u.iter()
                .chain(&w)
                .flat_map(|v| v.to_array().map(f64::to_bits)),
        );
    }
    let counts = transform_counts(&arrays.reals).expect("a transform held");
    assert_eq!(
        (counts.kept, counts.computed),
        (2, 1),
        "kept by the later products"
    );
    bits.extend(arrays.reals.iter().map(|x| x.to_bits()));
    bits
}

#[test]
fn same_bits_on_any_thread_count() {
    // From fewer spheres than pieces (no cell list, empty pieces) to a few thousand
    // polydisperse spheres with overlapping pairs.
    for (n, edge, tol) in [(3usize, 4.0, 1e-3), (300, 12.0, 1e-4), (3000, 30.0, 1e-6)] {
        let mut s = Rng(n as u64);
        // Radii in [0.9, 1], centres at least 0.1 apart (never nested), overlapping.
        let mut pos: Vec<DVec3> = Vec::with_capacity(n);
        while pos.len() < n {
            let p = f64::v3(s.unit() * edge, s.unit() * edge, s.unit() * edge);
            if pos.iter().all(|q| (p - *q).length() > 0.1) {
                pos.push(p);
            }
        }
        let rad: Vec<f64> = (0..n).map(|_| 0.9 + 0.1 * s.unit()).collect();
        let f: Vec<DVec3> = (0..n)
            .map(|_| f64::v3(s.unit() - 0.5, s.unit() - 0.5, s.unit() - 0.5))
            .collect();
        let ff = FreeFast::new_grand(1.0, tol, [edge; 3], n).unwrap();
        let one = product(&ff, &pos, &rad, &f, &Serial);
        for t in [1, 2, 3] {
            let pool = Threads::new(t).unwrap();
            assert!(
                product(&ff, &pos, &rad, &f, &pool) == one,
                "n {n}, {t} threads"
            );
        }
    }
}
