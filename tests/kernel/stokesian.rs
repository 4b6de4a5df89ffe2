//! The dense Stokesian dynamics mobility against values computed independently here:
//! Stimson and Jeffery's (1926) exact series for two equal spheres, Brenner's (1961)
//! exact series for a sphere approaching a wall, the published side-by-side values, the
//! RPY grand mobility beyond the cutoff, and positive definiteness as a property.
#![cfg(feature = "near")]

use hydrorattle::Hydro;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::assemble_grand;
use hydrorattle::real::Real;
use hydrorattle::stokesian::{NearField, SdError, mobility, storage};
use proptest::prelude::*;

/// The dense `6n x 6n` SD mobility, viscosity 1.
pub(crate) fn sd<T: Real>(
    wall: Option<f64>,
    pos: &[[f64; 3]],
    a: &[f64],
) -> Result<Vec<T>, SdError> {
    let (nb, nd) = storage(pos.len());
    let mut packed = vec![T::M3_ZERO; nb];
    let mut out = vec![T::ZERO; nd];
    let p: Vec<T::V3> = pos.iter().map(|&x| T::v3_from(x)).collect();
    let r: Vec<T> = a.iter().map(|&x| T::from_f64(x)).collect();
    let w = wall.map(T::from_f64);
    mobility(
        T::ONE,
        w,
        &p,
        &r,
        NearField::default(),
        &mut packed,
        &mut out,
    )?;
    Ok(out)
}

/// Stimson and Jeffery's drag factor of two equal spheres (radius 1) falling along
/// their line of centres, centres `s` apart: `U / U0 = 1 / lambda`.
pub(crate) fn stimson_jeffery(s: f64) -> f64 {
    let al = (s / 2.0).acosh();
    let mut sum = 0.0;
    for n in 1..2000 {
        let nf = n as f64;
        let k = 2.0 * nf + 1.0;
        let num = 4.0 * (0.5 * k * al).sinh().powi(2) - k * k * al.sinh().powi(2);
        let den = 2.0 * (k * al).sinh() + k * (2.0 * al).sinh();
        let t = nf * (nf + 1.0) / ((2.0 * nf - 1.0) * (2.0 * nf + 3.0)) * (1.0 - num / den);
        sum += t;
        if t.abs() < 1e-16 * sum.abs() {
            break;
        }
    }
    1.0 / (4.0 / 3.0 * al.sinh() * sum)
}

/// Brenner's exact drag factor of a sphere (radius 1) moving towards a wall, centre at
/// height `h`: the perpendicular mobility is `1 / lambda` times Stokes'.
pub(crate) fn brenner(h: f64) -> f64 {
    let al = h.acosh();
    let mut sum = 0.0;
    for n in 1..20000 {
        let nf = n as f64;
        let k = 2.0 * nf + 1.0;
        let num = 2.0 * (k * al).sinh() + k * (2.0 * al).sinh();
        let den = 4.0 * (0.5 * k * al).sinh().powi(2) - k * k * al.sinh().powi(2);
        let t = nf * (nf + 1.0) / ((2.0 * nf - 1.0) * (2.0 * nf + 3.0)) * (num / den - 1.0);
        if !t.is_finite() {
            break;
        }
        sum += t;
        if t.abs() < 1e-16 * sum.abs() {
            break;
        }
    }
    1.0 / (4.0 / 3.0 * al.sinh() * sum)
}

/// Stokes' mobility of the unit sphere in the unit fluid.
const U0: f64 = 1.0 / (6.0 * std::f64::consts::PI);

#[test]
fn two_spheres_fall_as_stimson_and_jeffery_say() {
    for s in [2.01, 2.05, 2.1, 2.5, 3.0, 4.0, 5.0] {
        let m = sd::<f64>(None, &[[0.0; 3], [0.0, 0.0, s]], &[1.0, 1.0]).unwrap();
        // Equal forces along z on both: U_0z = M[2][2] + M[2][5].
        let u = (m[2 * 12 + 2] + m[2 * 12 + 5]) / U0;
        let exact = stimson_jeffery(s);
        println!("s = {s}: U/U0 = {u:.5}, Stimson and Jeffery {exact:.5}");
        assert!(
            (u / exact - 1.0).abs() < 5e-3,
            "s = {s}: {u} against {exact}"
        );
    }
}

#[test]
fn two_spheres_side_by_side_at_2_1() {
    let m = sd::<f64>(None, &[[0.0; 3], [0.0, 0.0, 2.1]], &[1.0, 1.0]).unwrap();
    // Equal forces along x on both: the velocity U_0x and the spin W_0y.
    let u = (m[0] + m[3]) / U0;
    let w = (m[(6 + 1) * 12] + m[(6 + 1) * 12 + 3]) / U0;
    println!("side by side s = 2.1: U/U0 = {u:.5}, spin a/U0 = {w:.5}");
    assert!((u / 1.3917 - 1.0).abs() < 5e-3, "{u}");
    assert!((w.abs() / 0.137 - 1.0).abs() < 0.02, "{w}");
}

#[test]
fn a_sphere_approaches_the_wall_as_brenner_says() {
    for h in [
        1.01, 1.02, 1.05, 1.1, 1.3, 1.5, 2.0, 3.0, 4.0, 4.9, 5.0, 7.0, 10.0,
    ] {
        let m = sd::<f64>(Some(0.0), &[[0.0, 0.0, h]], &[1.0]).unwrap();
        let u = m[2 * 6 + 2] / U0;
        let exact = brenner(h);
        println!("h/a = {h}: perpendicular mobility {u:.6}, Brenner {exact:.6}");
        assert!(
            (u / exact - 1.0).abs() < 5e-3,
            "h = {h}: {u} against {exact}"
        );
    }
}

/// The packed grand mobility expanded to the dense matrix.
fn dense(packed: &[glam::DMat3], n: usize) -> Vec<f64> {
    let m = 6 * n;
    let mut d = vec![0.0; m * m];
    for bi in 0..2 * n {
        for bj in 0..=bi {
            let b = packed[tri(bi) + bj];
            for r in 0..3 {
                for c in 0..3 {
                    d[(3 * bi + r) * m + 3 * bj + c] = b.col(c)[r];
                    d[(3 * bj + c) * m + 3 * bi + r] = b.col(c)[r];
                }
            }
        }
    }
    d
}

#[test]
fn beyond_the_cutoffs_it_is_rpy_bit_for_bit() {
    // Gaps of 4.5 mean radii or more (cutoff 4), and over 4 radii above the wall (cutoff 4).
    let pos = [[0.0, 0.0, 6.0], [6.5, 0.0, 6.0], [0.0, 8.125, 8.0]];
    let a = [1.0, 1.0, 1.5];
    let p: Vec<_> = pos.iter().map(|&x| f64::v3_from(x)).collect();
    let mut packed = vec![glam::DMat3::ZERO; tri(6)];
    assemble_grand(Hydro::Rpy, 1.0, &p, &a, &mut packed).unwrap();
    assert_eq!(sd::<f64>(None, &pos, &a).unwrap(), dense(&packed, 3));
    hydrorattle::mobility::wall::assemble_grand(Hydro::Rpy, 1.0, 0.0, &p, &a, &mut packed).unwrap();
    assert_eq!(sd::<f64>(Some(0.0), &pos, &a).unwrap(), dense(&packed, 3));
    // One pair just inside the cutoff: no longer RPY.
    let close = [[0.0, 0.0, 6.0], [5.9, 0.0, 6.0]];
    let p: Vec<_> = close.iter().map(|&x| f64::v3_from(x)).collect();
    assemble_grand(Hydro::Rpy, 1.0, &p, &a[..2], &mut packed).unwrap();
    assert_ne!(sd::<f64>(None, &close, &a[..2]).unwrap(), dense(&packed, 2));
}

/// Smallest pivot of the test's own Cholesky of `m`, relative to its diagonal: positive
/// for a positive definite matrix. Also checks symmetry.
pub fn smallest_pivot(m: &[f64], n: usize) -> f64 {
    let mut a = m.to_vec();
    let mut worst = f64::INFINITY;
    for i in 0..n {
        for j in 0..i {
            let (x, y) = (m[i * n + j], m[j * n + i]);
            assert!((x - y).abs() <= 1e-5 * (m[i * n + i] * m[j * n + j]).sqrt());
        }
    }
    for j in 0..n {
        let d = a[j * n + j] - (0..j).map(|k| a[j * n + k].powi(2)).sum::<f64>();
        worst = worst.min(d / m[j * n + j]);
        if d.is_nan() || d <= 0.0 {
            return d;
        }
        let l = d.sqrt();
        a[j * n + j] = l;
        for i in j + 1..n {
            let s = a[i * n + j] - (0..j).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>();
            a[i * n + j] = s / l;
        }
    }
    worst
}

/// Whether any pair is nested (one sphere inside the other), which RPY refuses; above
/// the wall at `w` with the centres lifted to one radius above it, as the wall's
/// mobility evaluates them.
fn nested(pos: &[[f64; 3]], a: &[f64], w: Option<f64>) -> bool {
    let mut pos = pos.to_vec();
    if let Some(w) = w {
        for (p, a) in pos.iter_mut().zip(a) {
            p[2] = p[2].max(w + a);
        }
    }
    (0..pos.len()).any(|i| {
        (0..i).any(|j| {
            let d: f64 = (0..3).map(|k| (pos[i][k] - pos[j][k]).powi(2)).sum();
            d.sqrt() <= (a[i] - a[j]).abs()
        })
    })
}

fn spheres() -> impl Strategy<Value = (Vec<[f64; 3]>, Vec<f64>, bool)> {
    (3usize..7).prop_flat_map(|n| {
        (
            prop::collection::vec(prop::array::uniform3(0.0f64..5.0), n),
            prop::collection::vec(0.5f64..2.0, n),
            any::<bool>(),
        )
    })
}

fn check_pd<T: Real>(pos: &[[f64; 3]], a: &[f64], wall: bool) -> Result<f64, TestCaseError> {
    // Above the wall at z = -1: every centre above it, some spheres crossing it.
    let w = wall.then_some(-1.0);
    let n = 6 * pos.len();
    match sd::<T>(w, pos, a) {
        Ok(m) => {
            let m: Vec<f64> = m.iter().map(|v| v.to_f64()).collect();
            let p = smallest_pivot(&m, n);
            prop_assert!(p > 0.0, "not positive definite: pivot {p}");
            Ok(p)
        }
        Err(e) => {
            prop_assert!(nested(pos, a, w), "{e:?} without nested spheres");
            Ok(1.0)
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn positive_definite_f64_overlaps_included((pos, a, wall) in spheres()) {
        check_pd::<f64>(&pos, &a, wall)?;
    }

    #[test]
    fn positive_definite_f32_overlaps_included((pos, a, wall) in spheres()) {
        check_pd::<f32>(&pos, &a, wall)?;
    }
}

#[test]
fn overlapping_pairs_get_the_minimum_gap_correction() {
    // Squeeze mobility: equal and opposite forces along the line of centres.
    let squeeze = |m: &[f64]| m[2 * 12 + 2] - m[2 * 12 + 5];
    let rpy = |s: f64| {
        let p = [f64::v3_from([0.0; 3]), f64::v3_from([0.0, 0.0, s])];
        let mut packed = vec![glam::DMat3::ZERO; tri(4)];
        assemble_grand(Hydro::Rpy, 1.0, &p, &[1.0, 1.0], &mut packed).unwrap();
        squeeze(&dense(&packed, 2))
    };
    let at = |s: f64| squeeze(&sd::<f64>(None, &[[0.0; 3], [0.0, 0.0, s]], &[1.0, 1.0]).unwrap());
    for s in [1.999, 1.9, 1.5, 1.0, 0.1] {
        let (m, r) = (at(s), rpy(s));
        println!(
            "s = {s}: squeeze mobility {m:.4e}, RPY {r:.4e}, at s = 2.01 {:.4e}",
            at(2.01)
        );
        // The lubrication of the minimum gap (1e-3): far below RPY's and below that at
        // a gap of 1e-2 (a fifth of it: the squeeze mobility goes as the gap).
        assert!(m > 0.0 && m < 0.1 * r && m < 0.2 * at(2.01), "s = {s}: {m}");
    }
    // The correction is that of the minimum gap: at the minimum gap itself the same up
    // to the far field's change, which is small against the lubrication.
    let (m, c) = (at(1.5), at(2.001));
    assert!((m / c - 1.0).abs() < 0.05, "{m} against {c}");
}

#[test]
fn bad_storage_and_parameters_are_errors() {
    let p = [f64::v3_from([0.0; 3])];
    let mut packed = vec![glam::DMat3::ZERO; 3];
    let mut out = vec![0.0; 35];
    let near = NearField::default();
    let r = mobility(1.0, None, &p, &[1.0], near, &mut packed, &mut out);
    assert_eq!(r, Err(SdError::Storage));
    let mut out = vec![0.0; 36];
    let bad = NearField {
        min_gap: 0.0,
        ..near
    };
    let r = mobility(1.0, None, &p, &[1.0], bad, &mut packed, &mut out);
    assert_eq!(r, Err(SdError::Params));
    let far = [f64::v3_from([0.0; 3]), f64::v3_from([0.0, 0.0, 40.0])];
    let mut packed = vec![glam::DMat3::ZERO; tri(4)];
    let mut out = vec![0.0; 144];
    let r = mobility(1.0, None, &far, &[1.0, 11.0], near, &mut packed, &mut out);
    assert!(r.is_ok(), "beyond the cutoff any size ratio: {r:?}");
    let close = [f64::v3_from([0.0; 3]), f64::v3_from([0.0, 0.0, 13.0])];
    let r = mobility(1.0, None, &close, &[1.0, 11.0], near, &mut packed, &mut out);
    assert!(
        matches!(r, Err(SdError::Near { i: 0, j: 1, .. })),
        "size ratio 11 near: {r:?}"
    );
}

#[test]
fn the_series_side_by_side_give_the_same_bits() {
    use hydrorattle::near::Func;
    use hydrorattle::near::series::{far, far_all};
    for l in [0.1, 0.37, 1.0, 2.5, 10.0] {
        for x in [1e-6, 0.01, 0.2, 0.45, 0.5] {
            let all = far_all(l, x);
            for (k, f) in Func::ALL.into_iter().enumerate() {
                assert_eq!(all[k].to_bits(), far(f, l, x).to_bits(), "{f:?} {l} {x}");
            }
        }
    }
}
