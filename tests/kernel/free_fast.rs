//! The fast free-space product (`mobility::free_fast`) against references it did not
//! produce: the dense free-space RPY product (`mobility::tt_product`) on random
//! polydisperse clouds with overlapping pairs, Stokes' law for a lone sphere, and the
//! same bits on reruns.
#![cfg(feature = "fast-free")]

use hydrorattle::mobility::free_fast::{FreeError, FreeFast};
use hydrorattle::mobility::{Hydro, tt_product};
use hydrorattle::{ParticleError, Real};
use hydrorattle_heap::FreeBuffers;

/// SplitMix64 in `[0, 1)`.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` spheres of radius in `[0.5, 1]` in a cube of edge `edge`, overlapping freely but
/// never nested; forces in `[-1, 1]^3`. Returns positions, radii, forces and the number
/// of overlapping pairs.
#[allow(clippy::type_complexity)]
fn cloud(n: usize, edge: f64, seed: u64) -> (Vec<[f64; 3]>, Vec<f64>, Vec<[f64; 3]>, usize) {
    let mut rng = Rng(seed);
    let (mut pos, mut rad) = (Vec::new(), Vec::new());
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| edge * rng.next());
        let a = 0.5 + 0.5 * rng.next();
        let nested = pos.iter().zip(&rad).any(|(q, b): (&[f64; 3], &f64)| {
            let s = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            s <= (a - b).abs() + 1e-3
        });
        if !nested {
            pos.push(p);
            rad.push(a);
        }
    }
    let mut overlaps = 0;
    for i in 0..n {
        for j in 0..i {
            let s = (0..3)
                .map(|d| (pos[i][d] - pos[j][d]).powi(2))
                .sum::<f64>()
                .sqrt();
            overlaps += usize::from(s < rad[i] + rad[j]);
        }
    }
    let f = (0..n)
        .map(|_| [0, 1, 2].map(|_| 2.0 * rng.next() - 1.0))
        .collect();
    (pos, rad, f, overlaps)
}

fn to_v<T: Real>(v: &[[f64; 3]]) -> Vec<T::V3> {
    v.iter().map(|&p| T::v3_from(p)).collect()
}

/// The dense product, f64.
fn dense(pos: &[[f64; 3]], rad: &[f64], f: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut y = vec![f64::V3_ZERO; pos.len()];
    tt_product(
        Hydro::Rpy,
        1.0,
        &to_v::<f64>(pos),
        rad,
        &to_v::<f64>(f),
        &mut y,
    )
    .unwrap();
    y.iter().map(|&v| f64::v3_to_f64(v)).collect()
}

/// The fast product in precision `T` (viscosity 1), twice on the same storage: the
/// result and whether the second gave the same bits.
fn fast<T: Real>(
    ff: &FreeFast<T>,
    pos: &[[f64; 3]],
    rad: &[f64],
    f: &[[f64; 3]],
) -> Result<(Vec<[f64; 3]>, bool), FreeError> {
    let size = ff.storage(pos.len());
    let mut arrays = FreeBuffers::new(size);
    let mut store = arrays.storage();
    let (p, f) = (to_v::<T>(pos), to_v::<T>(f));
    let r: Vec<T> = rad.iter().map(|&a| T::from_f64(a)).collect();
    let mut out = vec![T::V3_ZERO; pos.len()];
    ff.apply(T::ONE, &p, &r, &f, &mut out, &mut store)?;
    let mut again = vec![T::V3_ZERO; pos.len()];
    ff.apply(T::ONE, &p, &r, &f, &mut again, &mut store)?;
    let bits = |v: &[T::V3]| -> Vec<u64> {
        v.iter()
            .flat_map(|&x| T::v3_to_f64(x).map(f64::to_bits))
            .collect()
    };
    let same = bits(&out) == bits(&again);
    Ok((out.iter().map(|&v| T::v3_to_f64(v)).collect(), same))
}

/// `|a - b| / |b|` over all components.
fn rel_err(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for d in 0..3 {
            num += (x[d] - y[d]).powi(2);
            den += y[d].powi(2);
        }
    }
    (num / den).sqrt()
}

fn params<T: Real>(rad: &[f64], pos: &[[f64; 3]], tol: f64) -> Result<FreeFast<T>, FreeError> {
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let mut ext = [0.0f64; 3];
    for d in 0..3 {
        let lo = pos.iter().map(|p| p[d]).fold(f64::INFINITY, f64::min);
        let hi = pos.iter().map(|p| p[d]).fold(f64::NEG_INFINITY, f64::max);
        ext[d] = hi - lo;
    }
    FreeFast::new(T::from_f64(a_max), tol, ext.map(T::from_f64), pos.len())
}

/// Random polydisperse clouds with overlapping pairs, dense (cell list) and dilute,
/// at tolerances 1e-3 to 1e-8: within the tolerance in f64, and the same bits on a
/// second product over the same storage.
#[test]
fn matches_dense_within_tolerance_f64() {
    for (n, edge, seed) in [(300, 12.0, 1), (200, 30.0, 2), (40, 6.0, 3)] {
        let (pos, rad, f, overlaps) = cloud(n, edge, seed);
        assert!(n < 100 || overlaps > 0, "no overlapping pair");
        let want = dense(&pos, &rad, &f);
        for tol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
            let ff = params::<f64>(&rad, &pos, tol).unwrap();
            let (got, same) = fast(&ff, &pos, &rad, &f).unwrap();
            let err = rel_err(&got, &want);
            println!(
                "n {n} edge {edge} overlaps {overlaps} tol {tol:e}: error {err:.2e} (estimate {:.2e}, grid {:?}, support {})",
                ff.estimate(),
                ff.grid(),
                ff.support()
            );
            assert!(err <= tol, "n {n} tol {tol:e}: error {err:e}");
            assert!(same, "rerun changed the bits");
        }
    }
}

/// `f32` to the tolerances it reaches, and a tolerance below its floor refused.
#[test]
fn f32_reaches_its_floor_and_refuses_below() {
    let (pos, rad, f, _) = cloud(300, 12.0, 4);
    let want = dense(&pos, &rad, &f);
    for tol in [1e-3, 1e-4, 1e-5] {
        let ff = params::<f32>(&rad, &pos, tol).unwrap();
        let (got, same) = fast(&ff, &pos, &rad, &f).unwrap();
        let err = rel_err(&got, &want);
        println!("f32 tol {tol:e}: error {err:.2e}");
        assert!(err <= tol, "f32 tol {tol:e}: error {err:e}");
        assert!(same);
    }
    match params::<f32>(&rad, &pos, 1e-6) {
        Err(FreeError::Precision { floor }) => assert!(floor > 1e-6 && floor < 1e-5),
        other => panic!("{other:?}"),
    }
}

/// A lone sphere moves by Stokes' law, `U = F / (6 pi eta a)`, at every tolerance.
#[test]
fn lone_sphere_obeys_stokes() {
    for tol in [1e-3, 1e-6, 1e-8] {
        let a = 0.8;
        let ff = FreeFast::<f64>::new(a, tol, [0.0; 3], 1).unwrap();
        let (u, _) = fast(&ff, &[[1.0, -2.0, 3.0]], &[a], &[[0.3, -0.7, 1.1]]).unwrap();
        let stokes = [0.3, -0.7, 1.1].map(|c| c / (6.0 * std::f64::consts::PI * a));
        let err = rel_err(&u, &[stokes]);
        println!("lone sphere tol {tol:e}: {err:.2e}");
        assert!(err <= tol, "tol {tol:e}: {err:e}");
    }
}

/// Bad input: typed errors, nothing panics.
#[test]
fn bad_input_is_a_typed_error() {
    let (pos, rad, f, _) = cloud(10, 4.0, 5);
    let ff = params::<f64>(&rad, &pos, 1e-6).unwrap();
    let mut bad = pos.clone();
    bad[3][1] = f64::NAN;
    assert_eq!(
        fast(&ff, &bad, &rad, &f).unwrap_err(),
        FreeError::Particle(ParticleError::NonFinite { particle: 3 })
    );
    let mut far = pos.clone();
    far[2][0] += 100.0;
    assert_eq!(fast(&ff, &far, &rad, &f).unwrap_err(), FreeError::Extent);
    let mut nested = pos.clone();
    nested[7] = nested[4];
    let mut r = rad.clone();
    r[7] = r[4] * 0.5;
    assert!(matches!(
        fast(&ff, &nested, &r, &f),
        Err(FreeError::Particle(ParticleError::Nested { .. }))
    ));
    assert!(matches!(
        FreeFast::<f64>::new(1.0, 1e-13, [1.0; 3], 10),
        Err(FreeError::BadParameter(_))
    ));
}

/// The storage holds the spectrum of the cloud's planes and one octant of the kernel's
/// transform, not the padded grid: under a third of three complex values a padded
/// point, and under two reals a padded point (the padded grid's six).
#[test]
fn storage_is_a_fraction_of_the_padded_grid() {
    let ff = FreeFast::<f64>::new(1.0, 1e-4, [100.0; 3], 10_000).unwrap();
    let padded: usize = ff.grid().iter().product();
    let size = ff.storage(10_000);
    println!("padded {padded}: {size:?}");
    assert!(3 * size.complex < 3 * padded, "{size:?}");
    assert!(size.reals < 2 * padded, "{size:?}");
}
