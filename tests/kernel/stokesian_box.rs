//! The Stokesian dynamics mobility in the periodic box: against free space with the
//! box's known `O(a/L)` correction, invariance under translation across a face, and
//! positive definiteness as a property.
#![cfg(all(feature = "near", feature = "periodic"))]

use hydrorattle::cell::Periodic;
use hydrorattle::mobility::periodic::Ewald;
use hydrorattle::real::Real;
use hydrorattle::stokesian::{Far, NearField, SdError, mobility_in, storage};
use proptest::prelude::*;

use crate::stokesian::smallest_pivot;

/// Hasimoto's constant: a sphere's mobility in a cubic box of edge `L` is
/// `(1 - HASIMOTO a / L + O((a/L)^3)) / (6 pi eta a)`, and every pair's translation block
/// at separations `r << L` shifts by the same `-HASIMOTO / (6 pi eta L)` (the constant
/// term of the periodic Oseen tensor's expansion about `r = 0`).
const HASIMOTO: f64 = 2.837297;

/// The dense `6n x 6n` SD mobility, viscosity 1, in the cubic box of edge `l` (free
/// space for `None`).
fn sd<T: Real>(l: Option<f64>, pos: &[[f64; 3]], a: &[f64]) -> Result<Vec<T>, SdError> {
    let (nb, nd) = storage(pos.len());
    let mut packed = vec![T::M3_ZERO; nb];
    let mut out = vec![T::ZERO; nd];
    let p: Vec<T::V3> = pos.iter().map(|&x| T::v3_from(x)).collect();
    let r: Vec<T> = a.iter().map(|&x| T::from_f64(x)).collect();
    let a_max = a.iter().cloned().fold(0.0, f64::max);
    let ew = l.map(|l| {
        let cell = Periodic::new([T::from_f64(l); 3]).unwrap();
        Ewald::new(cell, T::from_f64(a_max)).unwrap()
    });
    let far = ew.as_ref().map_or(Far::FREE, Far::periodic);
    let near = NearField::default();
    mobility_in(T::ONE, far, &p, &r, near, &mut packed, &mut out)?;
    Ok(out)
}

#[test]
fn a_close_pair_in_a_large_box_is_free_space_plus_hasimoto() {
    let l = 100.0;
    let pos = [[50.0, 50.0, 50.0], [52.1, 50.0, 50.0]];
    let a = [1.0, 1.0];
    let (free, boxed) = (
        sd::<f64>(None, &pos, &a).unwrap(),
        sd::<f64>(Some(l), &pos, &a).unwrap(),
    );
    let mu0 = 1.0 / (6.0 * std::f64::consts::PI);
    let shift = HASIMOTO / l * mu0;
    let m = 12;
    // Velocity of sphere 0 along `k` under unit forces `f` on both spheres along `k`.
    let u = |m_: &[f64], k: usize, f: [f64; 2]| f[0] * m_[k * m + k] + f[1] * m_[k * m + 3 + k];
    for k in 0..3 {
        // Together: each of the two blocks shifts by `-shift`, the velocity by `-2 shift`
        // (the near field changes how little that is, by its small share of the
        // collective drag).
        let d = u(&boxed, k, [1.0, 1.0]) - u(&free, k, [1.0, 1.0]);
        println!("axis {k}: together {:.6e} against {:.6e}", d, -2.0 * shift);
        assert!((d / (-2.0 * shift) - 1.0).abs() < 0.1, "axis {k}: {d}");
        if k == 0 {
            // Along the line of centres no spin couples in, and to first order
            // `dM_SD = M_SD M^-1 dM M^-1 M_SD` gives exactly `-2 shift (U_SD / U_RPY)^2`,
            // `U_RPY` the closed form of two RPY spheres moving together, `U_SD` free
            // space's (checked against Stimson and Jeffery in `stokesian.rs`).
            let r = 2.1;
            let rpy = mu0 + (1.0 - 2.0 / (3.0 * r * r)) / (4.0 * std::f64::consts::PI * r);
            let want = -2.0 * shift * (u(&free, 0, [1.0, 1.0]) / rpy).powi(2);
            println!("axis 0: together {d:.6e} against first order {want:.6e}");
            assert!((d / want - 1.0).abs() < 0.01, "{d} against {want}");
        }
        // Apart (equal and opposite): the uniform shift cancels; what is left is of
        // order (a/L)^3 and (r/L)^2 a/L, far below the shift.
        let d = u(&boxed, k, [1.0, -1.0]) - u(&free, k, [1.0, -1.0]);
        println!("axis {k}: apart {d:.3e}");
        assert!(d.abs() < 1e-3 * shift, "axis {k}: {d}");
    }
}

#[test]
fn a_pair_across_a_face_is_the_same_pair_inside() {
    let l = 12.0;
    // The pair (0, 1) near contact (gap 0.05) across the face x = 0, a third sphere
    // further off; then the same spheres shifted by half the box.
    let across = [[l - 1.0, 3.0, 4.0], [1.05, 3.0, 4.2], [5.0, 7.0, 2.0]];
    let inside: Vec<[f64; 3]> = across
        .iter()
        .map(|p| [(p[0] + 0.5 * l) % l, p[1] + 1.0, p[2] + 2.0])
        .collect();
    let a = [1.0, 1.0, 1.5];
    let (x, y) = (
        sd::<f64>(Some(l), &across, &a).unwrap(),
        sd::<f64>(Some(l), &inside, &a).unwrap(),
    );
    let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = x
        .iter()
        .zip(&y)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!("largest difference {worst:.3e} of {scale:.3e}");
    assert!(worst < 1e-9 * scale, "{worst}");
    // The near field acts across the face: the pair's squeeze mobility (sphere 0's
    // velocity along x under opposite forces along x) is far below free-space RPY's
    // closed form at the same separation (the box changes it by `O((a/L)^3)` only).
    let r = (2.05f64 * 2.05 + 0.2 * 0.2).sqrt();
    let c = 2.05 / r;
    let pair = (1.0 + 2.0 / (3.0 * r * r) + (1.0 - 2.0 / (r * r)) * c * c)
        / (8.0 * std::f64::consts::PI * r);
    let rpy = 1.0 / (6.0 * std::f64::consts::PI) - pair;
    let squeeze = x[0] - x[3];
    println!("squeeze mobility {squeeze:.4e}, RPY {rpy:.4e}");
    assert!(
        squeeze > 0.0 && squeeze < 0.5 * rpy,
        "{squeeze} against RPY {rpy}"
    );
}

/// Whether two spheres are nested at their minimum image in the box of edge `l`.
fn nested(pos: &[[f64; 3]], a: &[f64], l: f64) -> bool {
    (0..pos.len()).any(|i| {
        (0..i).any(|j| {
            let d: f64 = (0..3)
                .map(|k| {
                    let x = pos[i][k] - pos[j][k];
                    (x - l * (x / l).round()).powi(2)
                })
                .sum();
            d.sqrt() <= (a[i] - a[j]).abs()
        })
    })
}

fn check_pd<T: Real>(pos: &[[f64; 3]], a: &[f64]) -> Result<(), TestCaseError> {
    let l = 8.0;
    match sd::<T>(Some(l), pos, a) {
        Ok(m) => {
            let m: Vec<f64> = m.iter().map(|v| v.to_f64()).collect();
            let p = smallest_pivot(&m, 6 * pos.len());
            prop_assert!(p > 0.0, "not positive definite: pivot {p}");
        }
        Err(e) => prop_assert!(nested(pos, a, l), "{e:?} without nested spheres"),
    }
    Ok(())
}

fn spheres() -> impl Strategy<Value = (Vec<[f64; 3]>, Vec<f64>)> {
    (2usize..6).prop_flat_map(|n| {
        (
            prop::collection::vec(prop::array::uniform3(0.0f64..8.0), n),
            prop::collection::vec(0.5f64..2.0, n),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn positive_definite_in_the_box_f64((pos, a) in spheres()) {
        check_pd::<f64>(&pos, &a)?;
    }

    #[test]
    fn positive_definite_in_the_box_f32((pos, a) in spheres()) {
        check_pd::<f32>(&pos, &a)?;
    }
}
