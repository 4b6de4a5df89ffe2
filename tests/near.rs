//! The near-field resistance functions against values computed independently here:
//! Stimson and Jeffery's (1926) exact bispherical series for two equal spheres along
//! their line of centres, published exact values for other motions, the Rotne-Prager-
//! Yamakawa far field, and the exact near-contact forms of the closed-form functions.
#![cfg(feature = "near")]

use hydrorattle::Hydro;
use hydrorattle::mobility::{pair_blocks, self_rr, self_tt};
use hydrorattle::near::{NearError, pair_resistance, scalars};
use hydrorattle::real::Real;

type Mat = Vec<Vec<f64>>;

/// Gauss-Jordan inverse with partial pivoting (the test's own, independent of the kernel).
fn inverse(m: &Mat) -> Mat {
    let n = m.len();
    let mut a: Mat = m
        .iter()
        .map(|r| {
            let mut r = r.clone();
            r.extend((0..n).map(|_| 0.0));
            r
        })
        .collect();
    for i in 0..n {
        a[i][n + i] = 1.0;
    }
    for c in 0..n {
        let p = (c..n)
            .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
            .unwrap();
        a.swap(c, p);
        let d = a[c][c];
        for v in a[c].iter_mut() {
            *v /= d;
        }
        for r in 0..n {
            if r != c {
                let f = a[r][c];
                if f != 0.0 {
                    let row = a[c].clone();
                    for (v, w) in a[r].iter_mut().zip(row) {
                        *v -= f * w;
                    }
                }
            }
        }
    }
    a.into_iter().map(|r| r[n..].to_vec()).collect()
}

fn entry<T: Real>(m: &T::M3, i: usize, j: usize) -> f64 {
    T::m3_entries(m)[j * 3 + i].to_f64()
}

/// The pair's 12x12 resistance, rows and columns (U1, U2, W1, W2).
fn resistance<T: Real>(a1: f64, a2: f64, d: [f64; 3]) -> Mat {
    let p = pair_resistance::<T>(T::ONE, T::from_f64(a1), T::from_f64(a2), T::v3_from(d)).unwrap();
    let mut m = vec![vec![0.0; 12]; 12];
    for (bi, row) in p.r.iter().enumerate() {
        for (bj, b) in row.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    m[3 * bi + i][3 * bj + j] = entry::<T>(b, i, j);
                }
            }
        }
    }
    m
}

/// Velocities (U1, U2, W1, W2) of two spheres under forces and torques (F1, F2, T1, T2).
fn mobility_apply(r: &Mat, load: [f64; 12]) -> Vec<f64> {
    let m = inverse(r);
    m.iter()
        .map(|row| row.iter().zip(load).map(|(a, b)| a * b).sum())
        .collect()
}

/// Stimson and Jeffery's (1926) drag factor of two equal spheres moving together along
/// their line of centres, centre distance `s` radii: the bispherical series.
fn stimson_jeffery(s: f64) -> f64 {
    let al = (s / 2.0).acosh();
    let mut sum = 0.0;
    for n in 1..20000 {
        let nf = n as f64;
        let k = 2.0 * nf + 1.0;
        let num = 4.0 * ((nf + 0.5) * al).sinh().powi(2) - k * k * al.sinh().powi(2);
        let den = 2.0 * (k * al).sinh() + k * (2.0 * al).sinh();
        let term = nf * (nf + 1.0) / ((2.0 * nf - 1.0) * (2.0 * nf + 3.0)) * (1.0 - num / den);
        sum += term;
        if term.abs() < 1e-17 * sum.abs() || !den.is_finite() {
            break;
        }
    }
    4.0 / 3.0 * al.sinh() * sum
}

#[test]
fn equal_spheres_fall_along_the_line_of_centres_as_stimson_and_jeffery() {
    for s in [2.01, 2.05, 2.1, 2.5, 3.0, 4.0, 6.0] {
        let exact = 1.0 / stimson_jeffery(s);
        let u = mobility_apply(&resistance::<f64>(1.0, 1.0, [0.0, 0.0, s]), {
            let mut l = [0.0; 12];
            l[2] = 1.0;
            l[5] = 1.0;
            l
        });
        let u0 = self_tt(1.0, 1.0);
        let got = u[2] / u0;
        let err = (got / exact - 1.0).abs();
        println!(
            "s = {s}: U/U0 = {got:.5}, Stimson-Jeffery {exact:.5}, error {:.2e}",
            err
        );
        assert!(err < 5e-3, "s = {s}: {got} against {exact}");
        assert!((u[5] / u0 - got).abs() < 1e-9);
    }
}

#[test]
fn equal_spheres_side_by_side_at_2_1_fall_and_spin_as_published() {
    let u = mobility_apply(&resistance::<f64>(1.0, 1.0, [2.1, 0.0, 0.0]), {
        let mut l = [0.0; 12];
        l[2] = 1.0;
        l[5] = 1.0;
        l
    });
    let u0 = self_tt(1.0, 1.0);
    let fall = u[2] / u0;
    let spin = u[7] / u0;
    println!("side by side s = 2.1: U/U0 = {fall:.5}, spin a/U0 = {spin:.5}");
    assert!((fall / 1.3917 - 1.0).abs() < 5e-3, "{fall}");
    assert!((spin.abs() / 0.137 - 1.0).abs() < 0.02, "{spin}");
    assert!(
        (u[10] + u[7]).abs() < 1e-9,
        "the two spin in opposite senses"
    );
}

/// The pair's 12x12 RPY grand mobility, rows (U1, U2, W1, W2), columns (F1, F2, T1, T2).
fn rpy(a1: f64, a2: f64, d: [f64; 3]) -> Mat {
    let p = pair_blocks::<f64>(Hydro::Rpy, 1.0, a1, a2, f64::v3_from(d.map(|v| -v))).unwrap();
    let mut m = vec![vec![0.0; 12]; 12];
    let mut put = |bi: usize, bj: usize, b: &glam::DMat3, t: bool| {
        for i in 0..3 {
            for j in 0..3 {
                m[3 * bi + i][3 * bj + j] = if t { entry::<f64>(b, j, i) } else { entry::<f64>(b, i, j) };
            }
        }
    };
    let id = glam::DMat3::IDENTITY;
    put(0, 0, &(id * self_tt(1.0, a1)), false);
    put(1, 1, &(id * self_tt(1.0, a2)), false);
    put(2, 2, &(id * self_rr(1.0, a1)), false);
    put(3, 3, &(id * self_rr(1.0, a2)), false);
    put(0, 1, &p.tt, false);
    put(1, 0, &p.tt, true);
    put(2, 1, &p.rt_ij, false);
    put(3, 0, &p.rt_ji, false);
    put(1, 2, &p.rt_ij, true);
    put(0, 3, &p.rt_ji, true);
    put(2, 3, &p.rr, false);
    put(3, 2, &p.rr, true);
    m
}

/// Largest difference between the exact pair mobility and RPY's, each entry relative to
/// the geometric mean of its row's and column's self mobilities.
fn far_gap(a1: f64, a2: f64, d: [f64; 3]) -> f64 {
    let exact = inverse(&resistance::<f64>(a1, a2, d));
    let far = rpy(a1, a2, d);
    let diag = |i: usize| far[i][i];
    let mut worst = 0.0f64;
    for i in 0..12 {
        for j in 0..12 {
            worst = worst.max((exact[i][j] - far[i][j]).abs() / (diag(i) * diag(j)).sqrt());
        }
    }
    worst
}

#[test]
fn the_far_field_agrees_with_rpy_to_the_order_rpy_is_exact() {
    // RPY is exact through r^-3 (translation), r^-2 (coupling) and r^-3 (rotation): the
    // difference must fall at least as r^-4, so doubling the distance divides it by >= 12.
    for (a1, a2) in [(1.0, 1.0), (1.0, 2.0), (2.0, 1.0), (1.0, 4.0), (1.0, 10.0), (10.0, 1.0)] {
        let dir = [0.36, -0.48, 0.8];
        let mean = 0.5 * (a1 + a2);
        let mut last = f64::NAN;
        for k in [8.0, 16.0, 32.0] {
            let r = k * mean;
            let gap = far_gap(a1, a2, dir.map(|v| v * r));
            println!("a1 {a1}, a2 {a2}, r = {k} (a1+a2)/2: gap {gap:.3e}, ratio {:.1}", last / gap);
            if last.is_finite() {
                assert!(last / gap > 12.0, "{a1} {a2} {k}: {last} -> {gap}");
            }
            last = gap;
        }
        assert!(last < 1e-4 * (a1.max(a2) / a1.min(a2)), "{last}");
    }
}
