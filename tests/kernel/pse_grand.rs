//! PSE's grand product (`Pse::apply_grand`: forces and torques in, velocities and
//! rotations out) against the Ewald path's assembled grand mobility
//! (`periodic::assemble_grand`, summed to rounding, applied block by block) on random
//! polydisperse configurations with overlapping pairs; a lone sphere's rotation in a
//! cubic box against its closed form; the translation part against `Pse::apply`.

use crate::common;
use crate::pse::rel_err;

use common::boxes::{config_radii, to_t};
use common::fuzz::Rng;
use hydrorattle::Real;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::periodic::{Ewald, Periodic, PeriodicError, assemble_grand};
use hydrorattle::mobility::pse::{Part, Pse, PseError, PseStorage};
use hydrorattle_heap::PseBuffers;

/// Forces then torques in `[-1, 1]^3`, `2n` of them.
fn loads(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed ^ 0x0F0F);
    (0..2 * n)
        .map(|_| [0, 1, 2].map(|_| rng.range(-1.0, 1.0)))
        .collect()
}

/// `(U, W) = M (F, T)` by the Ewald path's grand mobility (packed lower triangle of
/// `2n x 2n`), in f64.
fn ewald_grand(size: [f64; 3], pos: &[[f64; 3]], rad: &[f64], x: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = pos.len();
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let ew = Ewald::new(Periodic::new(size).unwrap(), a_max).unwrap();
    let (p, r) = to_t::<f64>(pos, rad);
    let mut m = vec![f64::M3_ZERO; tri(2 * n)];
    assemble_grand(&ew, 1.0, &p, &r, &mut m).unwrap();
    let x: Vec<_> = x.iter().map(|&v| f64::v3_from(v)).collect();
    let mut y = vec![f64::V3_ZERO; 2 * n];
    for i in 0..2 * n {
        for j in 0..=i {
            let b = m[tri(i) + j];
            y[i] += b * x[j];
            if j < i {
                y[j] += f64::m3_tmul(b, x[i]);
            }
        }
    }
    y.iter().map(|&v| f64::v3_to_f64(v)).collect()
}

/// PSE's grand product, velocities then rotations, with the storage it sizes.
fn pse_grand<T: Real>(
    pse: &Pse<T>,
    (pos, rad): (&[T::V3], &[T]),
    x: &[T::V3],
) -> Result<Vec<T::V3>, PseError> {
    let n = pos.len();
    let mut arrays = PseBuffers::new(pse.storage_grand(n));
    let mut store = arrays.storage();
    let mut y = vec![T::V3_ZERO; 2 * n];
    let (f, t) = x.split_at(n);
    let (u, w) = y.split_at_mut(n);
    pse.apply_grand(T::ONE, (pos, rad), f, t, u, w, &mut store)?;
    Ok(y)
}

/// The worst of (velocity, rotation) error over tolerance on random polydisperse
/// configurations (radii 0.5 to 1.5, half the spheres overlapping another), cubic and
/// rectangular boxes, and a suspension at volume fraction about 0.1; each within the
/// tolerance.
fn against_ewald<T: Real>(tols: &[f64]) -> f64 {
    let mut worst = 0.0f64;
    for (size, n, seed) in [
        ([16.0; 3], 40, 1u64),
        ([14.0, 18.0, 22.0], 60, 2),
        ([11.0, 24.0, 13.0], 50, 4),
        ([22.0; 3], 200, 6),
    ] {
        let (pos, rad) = config_radii(n, seed, size, [0.5, 1.5], true);
        let n = pos.len();
        let x = loads(n, seed);
        let want = ewald_grand(size, &pos, &rad, &x);
        let a_max = T::from_f64(rad.iter().cloned().fold(0.0, f64::max));
        let (p, r) = to_t::<T>(&pos, &rad);
        let xt: Vec<_> = x.iter().map(|&v| T::v3_from(v)).collect();
        for &tol in tols {
            let pse = Pse::new(Periodic::new(size.map(T::from_f64)).unwrap(), a_max, tol).unwrap();
            let got: Vec<[f64; 3]> = pse_grand(&pse, (&p, &r), &xt)
                .unwrap()
                .iter()
                .map(|&v| T::v3_to_f64(v))
                .collect();
            let eu = rel_err(&got[..n], &want[..n]);
            let ew = rel_err(&got[n..], &want[n..]);
            println!(
                "box {size:?} n {n} tol {tol:e}: velocity {eu:.2e} ({:.3} tol), rotation {ew:.2e} ({:.3} tol)",
                eu / tol,
                ew / tol
            );
            assert!(
                eu < tol && ew < tol,
                "box {size:?} tol {tol:e}: {eu:e} {ew:e}"
            );
            worst = worst.max(eu / tol).max(ew / tol);
        }
    }
    worst
}

#[test]
fn grand_against_ewald_f64() {
    let worst = against_ewald::<f64>(&[1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]);
    println!("worst error / tolerance {worst:.3}");
}

/// f32: the tolerances its rounding leaves room for (as the translation product's).
#[test]
fn grand_against_ewald_f32() {
    let worst = against_ewald::<f32>(&[1e-3, 1e-4]);
    println!("worst error / tolerance {worst:.3}");
}

/// With no torque the velocities are `Pse::apply`'s bit for bit (the same near-field
/// blocks and grid arithmetic); the forces' and torques' contributions add (the
/// product is linear, to rounding).
#[test]
fn translation_part_is_apply() {
    let size = [13.0, 14.0, 15.0];
    let (p, r) = config_radii(60, 7, size, [0.5, 1.5], true);
    let n = p.len();
    let pse = Pse::new(Periodic::new(size).unwrap(), 1.5f64, 1e-5).unwrap();
    let (pos, rad) = to_t::<f64>(&p, &r);
    let x: Vec<_> = loads(n, 7).iter().map(|&v| f64::v3_from(v)).collect();
    let mut forces_only = x.clone();
    forces_only[n..].fill(f64::V3_ZERO);
    let got = pse_grand(&pse, (&pos, &rad), &forces_only).unwrap();
    let mut arrays = PseBuffers::new(pse.storage(n));
    let mut store = arrays.storage();
    let mut u = vec![f64::V3_ZERO; n];
    pse.apply(Part::Both, 1.0, &pos, &rad, &x[..n], &mut u, &mut store)
        .unwrap();
    let bits = |v: &[<f64 as Real>::V3]| -> Vec<u64> {
        v.iter()
            .flat_map(|&x| f64::v3_to_f64(x).map(f64::to_bits))
            .collect()
    };
    assert_eq!(bits(&got[..n]), bits(&u));
    let mut torques_only = x.clone();
    torques_only[..n].fill(f64::V3_ZERO);
    let from_t = pse_grand(&pse, (&pos, &rad), &torques_only).unwrap();
    let both = pse_grand(&pse, (&pos, &rad), &x).unwrap();
    let sum: Vec<[f64; 3]> = got
        .iter()
        .zip(&from_t)
        .map(|(a, b)| f64::v3_to_f64(*a + *b))
        .collect();
    let both: Vec<[f64; 3]> = both.iter().map(|&v| f64::v3_to_f64(v)).collect();
    let e = rel_err(&sum, &both);
    assert!(e < 1e-14, "{e:e}");
}

/// A lone sphere's rotation in a cubic box, `8 pi eta a^3 W / T = 1 - (4 pi / 3)
/// (a/L)^3` (the closed form the Ewald path's tests check, the finite-size correction
/// of rotational diffusion of Linke, Köfinger and Hummer, J. Phys. Chem. Lett. 9, 2874,
/// 2018), and a lone sphere's force turns nothing nor its torque moves it.
#[test]
fn lone_sphere_rotation() {
    let a = 1.0;
    for l in [3.5, 5.0, 10.0, 20.0] {
        for tol in [1e-3, 1e-5, 1e-8] {
            let pse = Pse::new(Periodic::new([l; 3]).unwrap(), a, tol).unwrap();
            let t = f64::v3(0.3, -0.7, 1.1);
            let x = [f64::v3(0.5, 0.2, -0.4), t];
            let got = pse_grand(&pse, (&[f64::v3(1.0, -2.0, 3.0)], &[a]), &x).unwrap();
            let pi = core::f64::consts::PI;
            let want = t * ((1.0 - 4.0 * pi / 3.0 / (l * l * l)) / (8.0 * pi * a * a * a));
            let e = f64::norm2(got[1] - want).sqrt() / f64::norm2(want).sqrt();
            // The force's velocity (Hasimoto's series) is the translation product's.
            println!("L {l} tol {tol:e}: rotation {e:.2e}");
            assert!(e < tol, "L {l} tol {tol:e}: {e:e}");
            let t_only =
                pse_grand(&pse, (&[f64::v3(1.0, -2.0, 3.0)], &[a]), &[f64::V3_ZERO, t]).unwrap();
            let scale = f64::norm2(want).sqrt();
            assert!(
                f64::norm2(t_only[0]).sqrt() < tol * scale,
                "torque moved it"
            );
        }
    }
}

/// Typed errors: short storage (the translation product's is too small), mismatched
/// lengths, a bad viscosity, non-finite torques, a sphere nested in another's image.
#[test]
fn grand_errors() {
    let pse = Pse::new(Periodic::new([10.0; 3]).unwrap(), 1.0, 1e-4).unwrap();
    let pos = [f64::v3(1.0, 5.0, 5.0), f64::v3(4.0, 5.0, 5.0)];
    let rad = [1.0, 0.8];
    let f = [f64::v3(1.0, 0.0, 0.0); 2];
    let (mut u, mut w) = ([f64::V3_ZERO; 2], [f64::V3_ZERO; 2]);
    let mut arrays = PseBuffers::new(pse.storage(2));
    let mut store = arrays.storage();
    let e = pse.apply_grand(1.0, (&pos, &rad), &f, &f, &mut u, &mut w, &mut store);
    assert!(matches!(e, Err(PseError::Storage { .. })), "{e:?}");
    let mut arrays = PseBuffers::new(pse.storage_grand(2));
    let mut store = arrays.storage();
    assert!(
        pse.apply_grand(1.0, (&pos, &rad), &f, &f, &mut u, &mut w, &mut store)
            .is_ok()
    );
    let e = pse.apply_grand(1.0, (&pos, &rad), &f, &f[..1], &mut u, &mut w, &mut store);
    assert_eq!(e, Err(PseError::Length));
    let e = pse.apply_grand(1.0, (&pos, &rad), &f, &f, &mut u, &mut w[..1], &mut store);
    assert_eq!(e, Err(PseError::Length));
    let e = pse.apply_grand(-1.0, (&pos, &rad), &f, &f, &mut u, &mut w, &mut store);
    assert_eq!(
        e,
        Err(PseError::Periodic(PeriodicError::BadParameter("viscosity")))
    );
    let bad = [f, [f64::v3(f64::NAN, 0.0, 0.0), f[1]]];
    let e = pse.apply_grand(
        1.0,
        (&pos, &rad),
        &bad[0],
        &bad[1],
        &mut u,
        &mut w,
        &mut store,
    );
    assert!(matches!(e, Err(PseError::Periodic(_))), "{e:?}");
    let nested = [f64::v3(0.05, 5.0, 5.0), f64::v3(9.95, 5.0, 5.0)];
    let e = pse.apply_grand(
        1.0,
        (&nested, &[1.0, 0.5]),
        &f,
        &f,
        &mut u,
        &mut w,
        &mut store,
    );
    assert!(matches!(e, Err(PseError::Periodic(_))), "{e:?}");
    let mut short = PseStorage::new(
        &mut arrays.complex,
        &mut arrays.index,
        &mut arrays.vectors[..2],
    );
    let e = pse.apply_grand(1.0, (&pos, &rad), &f, &f, &mut u, &mut w, &mut short);
    assert!(
        matches!(
            e,
            Err(PseError::Storage {
                have: [_, _, 2],
                ..
            })
        ),
        "{e:?}"
    );
}
