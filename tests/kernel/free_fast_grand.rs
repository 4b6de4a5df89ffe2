//! The fast free-space grand product (`FreeFast::apply_grand`: forces and torques in,
//! velocities and rotations out) against the dense grand mobility
//! (`mobility::assemble_grand`, applied block by block) on random polydisperse clouds
//! with overlapping pairs; a lone sphere's rotation by Stokes' law.
#![cfg(feature = "fast-free")]

use hydrorattle::Real;
use hydrorattle::glam::DVec3;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::free_fast::{FreeError, FreeFast};
use hydrorattle::mobility::{Hydro, assemble_grand};
use hydrorattle_heap::FreeBuffers;

use crate::common::fuzz::Rng;

/// `n` spheres of radius in `[0.5, 1]` in a cube of edge `edge`, centres at least 0.55
/// apart (never nested, many overlapping); forces and torques in `[-1, 1]^3`.
#[allow(clippy::type_complexity)]
fn cloud(n: usize, edge: f64, seed: u64) -> (Vec<DVec3>, Vec<f64>, Vec<DVec3>, Vec<DVec3>, usize) {
    let mut s = Rng(seed);
    let mut pos: Vec<DVec3> = Vec::new();
    let mut rad = Vec::new();
    while pos.len() < n {
        let p = DVec3::new(s.unit(), s.unit(), s.unit()) * edge;
        if pos.iter().all(|q| (p - *q).length() > 0.55) {
            pos.push(p);
            rad.push(s.range(0.5, 1.0));
        }
    }
    let mut overlaps = 0;
    for i in 0..n {
        for j in 0..i {
            overlaps += usize::from((pos[i] - pos[j]).length() < rad[i] + rad[j]);
        }
    }
    let mut v = || DVec3::new(s.range(-1.0, 1.0), s.range(-1.0, 1.0), s.range(-1.0, 1.0));
    let f = (0..n).map(|_| v()).collect();
    let t = (0..n).map(|_| v()).collect();
    (pos, rad, f, t, overlaps)
}

/// The dense grand product `(U, W) = M (F, T)` (packed lower triangle of `2n x 2n`).
fn dense(pos: &[DVec3], rad: &[f64], f: &[DVec3], t: &[DVec3]) -> Vec<DVec3> {
    let n = pos.len();
    let mut m = vec![f64::M3_ZERO; tri(2 * n)];
    assemble_grand(Hydro::Rpy, 1.0, pos, rad, &mut m).unwrap();
    let x: Vec<DVec3> = f.iter().chain(t).copied().collect();
    let mut y = vec![DVec3::ZERO; 2 * n];
    for i in 0..2 * n {
        for j in 0..=i {
            let b = m[tri(i) + j];
            y[i] += b * x[j];
            if j < i {
                y[j] += b.transpose() * x[i];
            }
        }
    }
    y
}

/// The fast grand product, velocities then rotations, with the storage it sizes.
fn fast(
    ff: &FreeFast<f64>,
    (pos, rad): (&[DVec3], &[f64]),
    f: &[DVec3],
    t: &[DVec3],
) -> Result<Vec<DVec3>, FreeError> {
    let n = pos.len();
    let size = ff.storage_grand(n);
    let mut arrays = FreeBuffers::new(size);
    let mut store = arrays.storage();
    let (mut u, mut w) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    ff.apply_grand(1.0, (pos, rad), f, t, &mut u, &mut w, &mut store)?;
    Ok(u.into_iter().chain(w).collect())
}

/// `|a - b| / |b|` over the rows `range`.
fn rel_err(a: &[DVec3], b: &[DVec3]) -> f64 {
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared())
        .sum();
    let den: f64 = b.iter().map(|y| y.length_squared()).sum();
    (num / den).sqrt()
}

fn params(rad: &[f64], pos: &[DVec3], tol: f64) -> FreeFast<f64> {
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let lo = pos.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
    let hi = pos.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
    FreeFast::new_grand(a_max, tol, (hi - lo).to_array(), pos.len()).unwrap()
}

/// Random polydisperse clouds with overlapping pairs, dense (cell list) and dilute, at
/// tolerances 1e-3 to 1e-8: velocities and rotations each within the tolerance, and
/// the velocities from forces alone equal to `apply`'s.
#[test]
fn grand_matches_dense_within_tolerance() {
    for (n, edge, seed) in [(300, 12.0, 11), (150, 25.0, 12), (40, 6.0, 13)] {
        let (pos, rad, f, t, overlaps) = cloud(n, edge, seed);
        assert!(overlaps > 0, "no overlapping pair");
        let want = dense(&pos, &rad, &f, &t);
        for tol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
            let ff = params(&rad, &pos, tol);
            let got = fast(&ff, (&pos, &rad), &f, &t).unwrap();
            let (eu, ew) = (
                rel_err(&got[..n], &want[..n]),
                rel_err(&got[n..], &want[n..]),
            );
            println!(
                "grand n {n} edge {edge} overlaps {overlaps} tol {tol:e}: velocity {eu:.2e}, rotation {ew:.2e} (estimate {:.2e})",
                ff.estimate()
            );
            assert!(eu <= tol && ew <= tol, "n {n} tol {tol:e}: {eu:e} {ew:e}");
        }
    }
}

/// With no torque the velocities are the translation product's, to rounding; a lone
/// sphere turns by Stokes' law `W = T / (8 pi eta a^3)` and a force turns nothing, to
/// tolerances 1e-3 to 1e-8; parameters from `FreeFast::new` are refused.
#[test]
fn grand_reduces_to_translation_and_stokes() {
    let (pos, rad, f, _, _) = cloud(200, 10.0, 14);
    let n = pos.len();
    let ff = params(&rad, &pos, 1e-6);
    let zero = vec![DVec3::ZERO; n];
    let got = fast(&ff, (&pos, &rad), &f, &zero).unwrap();
    let size = ff.storage(n);
    let mut arrays = FreeBuffers::new(size);
    let mut store = arrays.storage();
    let mut u = vec![DVec3::ZERO; n];
    ff.apply(1.0, &pos, &rad, &f, &mut u, &mut store).unwrap();
    let e = rel_err(&got[..n], &u);
    assert!(e < 1e-12, "{e:e}");
    let plain = FreeFast::<f64>::new(1.0, 1e-6, [10.0; 3], n).unwrap();
    assert!(matches!(
        fast(&plain, (&pos, &rad), &f, &zero),
        Err(FreeError::BadParameter(_))
    ));
    for tol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        let a = 0.7;
        let ff = FreeFast::<f64>::new_grand(a, tol, [0.0; 3], 1).unwrap();
        let (p, t) = ([DVec3::new(1.0, -2.0, 3.0)], [DVec3::new(0.3, -0.7, 1.1)]);
        let got = fast(&ff, (&p, &[a]), &[DVec3::new(0.5, 0.2, -0.4)], &t).unwrap();
        let want = t[0] / (8.0 * std::f64::consts::PI * a * a * a);
        let e = (got[1] - want).length() / want.length();
        println!("lone sphere rotation tol {tol:e}: {e:.2e}");
        assert!(e <= tol, "tol {tol:e}: {e:e}");
    }
}
