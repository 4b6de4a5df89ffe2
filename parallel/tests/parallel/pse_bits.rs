//! The PSE product (`mobility::pse`) and its grand product on a thread pool give the
//! bits of one thread: their
//! pieces (near-field rows, slabs of grid planes, interpolation rows) depend on the
//! sizes alone, and each value's arithmetic is the same in whichever piece it falls.

use hydrorattle::Real;
use hydrorattle::glam::DVec3;
use hydrorattle::mobility::pse::{Part, Pse};
use hydrorattle::parallel::{Parallel, Serial};
use hydrorattle::{Periodic, PeriodicError};
use hydrorattle_heap::PseBuffers;
use hydrorattle_parallel::Threads;

use crate::fuzz::Rng;

/// `M F` for every part and the grand product `M (F, T)` (torques `F` reversed), as
/// bits, with `par`.
fn product(pse: &Pse<f64>, pos: &[DVec3], f: &[DVec3], par: &dyn Parallel) -> Vec<u64> {
    let n = pos.len();
    let size = pse.storage_grand(n);
    let mut arrays = PseBuffers::new(size);
    let mut store = arrays.storage().with_parallel(par);
    let rad = vec![1.0; n];
    let mut bits = vec![];
    for part in [Part::Both, Part::Near, Part::Wave] {
        let mut out = vec![DVec3::ZERO; n];
        pse.apply(part, 1.0, pos, &rad, f, &mut out, &mut store)
            .unwrap();
        bits.extend(out.iter().flat_map(|u| u.to_array().map(f64::to_bits)));
    }
    let t: Vec<DVec3> = f.iter().rev().copied().collect();
    let (mut u, mut w) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    pse.apply_grand(1.0, (pos, &rad), f, &t, &mut u, &mut w, &mut store)
        .unwrap();
    bits.extend(
        u.iter()
            .chain(&w)
            .flat_map(|u| u.to_array().map(f64::to_bits)),
    );
    bits
}

#[test]
fn same_bits_on_any_thread_count() -> Result<(), PeriodicError> {
    // From fewer spheres and planes than pieces (empty pieces) to a few thousand.
    for (n, phi, tol) in [(3usize, 0.01, 1e-3), (300, 0.1, 1e-4), (3000, 0.1, 1e-5)] {
        let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / phi).cbrt();
        let mut s = Rng(n as u64);
        let pos: Vec<DVec3> = (0..n)
            .map(|_| f64::v3(s.unit() * l, s.unit() * l, s.unit() * l))
            .collect();
        let f: Vec<DVec3> = (0..n)
            .map(|_| f64::v3(s.unit() - 0.5, s.unit() - 0.5, s.unit() - 0.5))
            .collect();
        let pse = Pse::new(Periodic::new([l; 3])?, 1.0, tol).unwrap();
        let one = product(&pse, &pos, &f, &Serial);
        for t in [1, 2, 3, 4] {
            let pool = Threads::new(t).unwrap();
            assert!(product(&pse, &pos, &f, &pool) == one, "n {n}, {t} threads");
        }
    }
    Ok(())
}
