//! The near-field resistance functions against values computed independently here:
//! Stimson and Jeffery's (1926) exact bispherical series for two equal spheres along
//! their line of centres, published exact values for other motions, the Rotne-Prager-
//! Yamakawa far field, and the exact near-contact forms of the closed-form functions.
#![cfg(feature = "near")]
// Index loops over rows and columns read like the formulas.
#![allow(clippy::needless_range_loop)]

use hydrorattle::Hydro;
use hydrorattle::mobility::{pair_blocks, self_rr, self_tt};
use hydrorattle::near::wall::wall_scalars;
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
                m[3 * bi + i][3 * bj + j] = if t {
                    entry::<f64>(b, j, i)
                } else {
                    entry::<f64>(b, i, j)
                };
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
    for (a1, a2) in [
        (1.0, 1.0),
        (1.0, 2.0),
        (2.0, 1.0),
        (1.0, 4.0),
        (1.0, 10.0),
        (10.0, 1.0),
    ] {
        let dir = [0.36, -0.48, 0.8];
        let mean = 0.5 * (a1 + a2);
        let mut last = f64::NAN;
        for k in [8.0, 16.0, 32.0] {
            let r = k * mean;
            let gap = far_gap(a1, a2, dir.map(|v| v * r));
            println!(
                "a1 {a1}, a2 {a2}, r = {k} (a1+a2)/2: gap {gap:.3e}, ratio {:.1}",
                last / gap
            );
            if last.is_finite() {
                assert!(last / gap > 12.0, "{a1} {a2} {k}: {last} -> {gap}");
            }
            last = gap;
        }
        assert!(last < 1e-4 * (a1.max(a2) / a1.min(a2)), "{last}");
    }
}

/// Brenner's (1961) exact perpendicular drag factor for a sphere at `h / a` above a
/// wall, as he writes it: `(4/3) sinh a sum n(n+1)/((2n-1)(2n+3)) [num / den - 1]`.
fn brenner(h_over_a: f64) -> f64 {
    let al = h_over_a.acosh();
    let mut sum = 0.0;
    for n in 1..100_000 {
        let nf = n as f64;
        let k = 2.0 * nf + 1.0;
        let num = 2.0 * (k * al).sinh() + k * (2.0 * al).sinh();
        let den = 4.0 * ((nf + 0.5) * al).sinh().powi(2) - k * k * al.sinh().powi(2);
        if !num.is_finite() || !den.is_finite() {
            break;
        }
        let term = nf * (nf + 1.0) / ((2.0 * nf - 1.0) * (2.0 * nf + 3.0)) * (num / den - 1.0);
        sum += term;
        if term.abs() < 1e-16 * sum {
            break;
        }
    }
    4.0 / 3.0 * al.sinh() * sum
}

#[test]
fn a_sphere_approaching_the_wall_moves_as_brenner() {
    for h in [
        1.001, 1.01, 1.02, 1.05, 1.1, 1.2, 1.5, 2.0, 3.0, 5.0, 10.0, 900.0, 1100.0,
    ] {
        let exact = brenner(h);
        let w = wall_scalars::<f64>(1.0, h).unwrap();
        let w32 = wall_scalars::<f32>(1.0, h as f32).unwrap();
        let err = (w.xa / exact - 1.0).abs();
        println!(
            "h/a = {h}: X^A_w = {:.6}, Brenner {exact:.6}, error {err:.1e}",
            w.xa
        );
        assert!(err < 5e-3, "{h}");
        assert!((w32.xa as f64 / exact - 1.0).abs() < 5e-3, "{h} f32");
    }
    // Cox and Brenner's asymptote takes over below delta = 1e-3 without a visible step.
    let below = hydrorattle::near::wall::perpendicular(0.999_999e-3);
    let exact = brenner(1.0 + 0.999_999e-3);
    println!("delta 1e-3: asymptote {below:.6}, series {exact:.6}");
    assert!((below / exact - 1.0).abs() < 1e-4);
}

#[test]
fn parallel_wall_functions_follow_goldman_cox_brenner_and_stay_positive_definite() {
    // Goldman, Cox and Brenner (1967): near contact F/(6 pi eta a U) = (8/15) ln(1/d) +
    // 0.9588, T/(8 pi eta a^2 U) = (1/10) ln(1/d) - 0.1895, T/(8 pi eta a^3 W) =
    // (2/5) ln(1/d) + 0.3817: the slopes exact (lubrication theory), the constants their
    // fits to O'Neill's values, good to about 1e-2 (the exact limits are 0.9543, -0.1929
    // and 0.3710: tools/near-gen's tests).
    let slope = [8.0 / 15.0, 0.1, 0.4];
    for d in [1e-7, 1e-5, 1e-4, 1e-3] {
        let w = wall_scalars::<f64>(1.0, 1.0 + d).unwrap();
        let w2 = wall_scalars::<f64>(1.0, 1.0 + 2.0 * d).unwrap();
        let l = (1.0 / d).ln();
        let gcb = [8.0 / 15.0 * l + 0.9588, 0.1 * l - 0.1895, 0.4 * l + 0.3817];
        let (v, v2) = ([w.ya, w.yb, w.yc], [w2.ya, w2.yb, w2.yc]);
        for f in 0..3 {
            assert!(
                (v[f] - gcb[f]).abs() < 0.012,
                "{d} {f}: {} vs {}",
                v[f],
                gcb[f]
            );
            // The slope, where the O(delta ln delta) remainder's is small.
            let s = (v[f] - v2[f]) / 2f64.ln();
            assert!(
                d > 1e-4 || (s - slope[f]).abs() < 2e-3,
                "{d} {f}: slope {s}"
            );
        }
    }
    // Far: the reflections' mobilities (Faxen's parallel translation; rotation 1 - 5/16
    // (a/h)^3; a torque-free sphere turns at (3/32) (a/h)^4 U / a), here at h = 100 a,
    // beyond the exact table (whose last gap is 10^1.7).
    let k: f64 = 1.0 / 100.0;
    let w = wall_scalars::<f64>(1.0, 100.0).unwrap();
    let det = w.ya * w.yc - 4.0 / 3.0 * w.yb * w.yb;
    let mt = w.yc / det;
    assert!(
        (mt - (1.0 - 9.0 / 16.0 * k + k.powi(3) / 8.0
            - 45.0 / 256.0 * k.powi(4)
            - k.powi(5) / 16.0))
            .abs()
            < 1e-12
    );
    assert!((w.yb / w.yc - 3.0 / 32.0 * k.powi(4) / (1.0 - 9.0 / 16.0 * k)).abs() < 1e-9);
    // Continuous where the near form and the far series meet the table.
    for edge in [1e-5, 10f64.powf(1.7)] {
        let lo = wall_scalars::<f64>(1.0, 1.0 + edge * (1.0 - 1e-9)).unwrap();
        let hi = wall_scalars::<f64>(1.0, 1.0 + edge * (1.0 + 1e-9)).unwrap();
        for (x, y) in [(lo.ya, hi.ya), (lo.yb, hi.yb), (lo.yc, hi.yc)] {
            assert!((x - y).abs() < 1e-8 * lo.ya, "{edge}: {x} {y}");
        }
    }
    // Positive definite (the 2x2 block [[6 Y^A, 8 Y^B], [8 Y^B, 8 Y^C]]: 3 Y^A Y^C > 4
    // (Y^B)^2) and decreasing all the way, in f64 and f32.
    let mut last = [f64::INFINITY; 3];
    for i in 0..=1000 {
        let d = 10f64.powf(-7.0 + 10.0 * i as f64 / 1000.0);
        let w = wall_scalars::<f64>(1.0, 1.0 + d).unwrap();
        assert!(
            w.ya > 0.0 && w.yc > 0.0 && 3.0 * w.ya * w.yc > 4.0 * w.yb * w.yb,
            "{d}"
        );
        assert!(w.ya < last[0] && w.yc < last[2], "{d}");
        last = [w.ya, w.yb, w.yc];
        let w = wall_scalars::<f32>(1.0, 1.0 + d as f32).unwrap();
        if d > 1e-6 {
            assert!(3.0 * w.ya * w.yc > 4.0 * w.yb * w.yb && w.yb >= 0.0, "{d}");
        }
    }
}

/// Hurwitz zeta `sum_{n>=0} (n + q)^-3` (direct sum plus the Euler-Maclaurin tail).
fn zeta3(q: f64) -> f64 {
    let n = 2000;
    let mut s: f64 = (0..n).map(|k| (k as f64 + q).powi(-3)).sum();
    let x = n as f64 + q;
    s += 0.5 / (x * x) + 0.5 / (x * x * x) + 0.25 / x.powi(4);
    s
}

#[test]
fn axial_rotation_matches_its_near_contact_and_far_forms() {
    // Near contact (Jeffrey and Onishi 1984, as corrected by Townsend 2018), sizes 1:1 to
    // 1:10: X^C_11 = l^3/(1+l)^3 zeta(3, l/(1+l)) - l^2/(4(1+l)) xi ln(1/xi),
    // X^C_12 = -8/(1+l)^3 (l^3/(1+l)^3 zeta(3) - l^2/(4(1+l)) xi ln(1/xi)).
    let xi: f64 = 1e-5;
    for l in [1.0, 2.0, 4.0, 10.0, 0.5, 0.25, 0.1] {
        let r = 0.5 * (1.0 + l) * (2.0 + xi);
        let s = scalars::<f64>(1.0, l, r).unwrap();
        let c = (l / (1.0 + l)).powi(3);
        let lg = l * l / (4.0 * (1.0 + l)) * xi * (1.0 / xi).ln();
        let x11 = c * zeta3(l / (1.0 + l)) - lg;
        let x12 = -8.0 / (1.0 + l).powi(3) * (c * zeta3(1.0) - lg);
        println!(
            "l = {l}: X^C_11 {:.7} vs {x11:.7}, X^C_12 {:.7} vs {x12:.7}",
            s.xc11, s.xc12
        );
        assert!((s.xc11 - x11).abs() < 1e-4 * x11 && (s.xc12 - x12).abs() < 1e-4 * x12.abs());
    }
    // A sphere against the wall: zeta(3) at contact; far away 1 + (a/h)^3 / 8.
    let w = wall_scalars::<f64>(1.0, 1.0 + 1e-6).unwrap();
    assert!((w.xc - zeta3(1.0)).abs() < 1e-4);
    let w = wall_scalars::<f64>(1.0, 30.0).unwrap();
    assert!((w.xc - (1.0 + 1.0 / (8.0 * 27000.0))).abs() < 1e-8);
}

#[test]
fn the_functions_refuse_contact_bad_sizes_and_non_numbers() {
    assert_eq!(
        scalars::<f64>(1.0, 1.0, 2.0).unwrap_err(),
        NearError::Contact
    );
    assert_eq!(
        scalars::<f64>(1.0, 1.0, 1.0).unwrap_err(),
        NearError::Contact
    );
    assert_eq!(
        scalars::<f64>(1.0, 20.0, 30.0).unwrap_err(),
        NearError::SizeRatio
    );
    assert_eq!(
        scalars::<f64>(1.0, f64::NAN, 30.0).unwrap_err(),
        NearError::NotPositive
    );
    assert_eq!(
        scalars::<f32>(-1.0, 1.0, 3.0).unwrap_err(),
        NearError::NotPositive
    );
    assert_eq!(
        wall_scalars::<f64>(1.0, 1.0).unwrap_err(),
        NearError::Contact
    );
    assert_eq!(
        wall_scalars::<f64>(1.0, f64::INFINITY).unwrap_err(),
        NearError::NotPositive
    );
    // At the edges of the size range both ways round.
    assert!(scalars::<f64>(1.0, 10.0, 11.001).is_ok() && scalars::<f64>(10.0, 1.0, 11.001).is_ok());
}

#[test]
fn f32_and_f64_agree() {
    for (a1, a2, r) in [
        (1.0, 1.0, 2.01),
        (1.0, 3.0, 4.5),
        (2.0, 0.5, 2.6),
        (1.0, 10.0, 30.0),
    ] {
        let s = scalars::<f64>(a1, a2, r).unwrap();
        let t = scalars::<f32>(a1 as f32, a2 as f32, r as f32).unwrap();
        let pairs = [
            (s.xa11, t.xa11),
            (s.ya12, t.ya12),
            (s.yb11, t.yb11),
            (s.xc12, t.xc12),
            (s.yc12, t.yc12),
        ];
        for (x, y) in pairs {
            assert!((x - y as f64).abs() <= 1e-5 * x.abs().max(1e-2), "{x} {y}");
        }
    }
}

/// 3x3 blocks of a 12x12 matrix in the caller's precision.
fn blocks<T: Real>(m: &Mat) -> [[T::M3; 4]; 4] {
    core::array::from_fn(|bi| {
        core::array::from_fn(|bj| {
            let col = |j: usize| {
                let v = |i: usize| T::from_f64(m[3 * bi + i][3 * bj + j]);
                T::v3(v(0), v(1), v(2))
            };
            T::m3_cols(col(0), col(1), col(2))
        })
    })
}

fn flat<T: Real>(b: &[[T::M3; 4]; 4]) -> Mat {
    let mut m = vec![vec![0.0; 12]; 12];
    for bi in 0..4 {
        for bj in 0..4 {
            for i in 0..3 {
                for j in 0..3 {
                    m[3 * bi + i][3 * bj + j] = entry::<T>(&b[bi][bj], i, j);
                }
            }
        }
    }
    m
}

/// Smallest eigenvalue of a symmetric matrix scaled to unit diagonal `D^-1/2 A D^-1/2`
/// (`D` the diagonal of `scale`), by cyclic Jacobi rotations.
fn min_eig_scaled(a: &Mat, scale: &Mat) -> f64 {
    let n = a.len();
    let mut m: Mat = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| a[i][j] / (scale[i][i] * scale[j][j]).sqrt())
                .collect()
        })
        .collect();
    for _ in 0..60 {
        for p in 0..n {
            for q in p + 1..n {
                if m[p][q].abs() < 1e-300 {
                    continue;
                }
                let th = 0.5 * (2.0 * m[p][q]).atan2(m[q][q] - m[p][p]);
                let (c, s) = (th.cos(), th.sin());
                for k in 0..n {
                    let (kp, kq) = (m[k][p], m[k][q]);
                    m[k][p] = c * kp - s * kq;
                    m[k][q] = s * kp + c * kq;
                }
                for k in 0..n {
                    let (pk, qk) = (m[p][k], m[q][k]);
                    m[p][k] = c * pk - s * qk;
                    m[q][k] = s * pk + c * qk;
                }
            }
        }
    }
    (0..n).map(|i| m[i][i]).fold(f64::INFINITY, f64::min)
}

fn sd_resistance_is_positive_definite<T: Real>(
    a1: f64,
    lambda: f64,
    gap: f64,
    dir: [f64; 3],
) -> (f64, f64) {
    let a2 = a1 * lambda;
    let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
    // A negative gap is an overlap, as a fraction of the smaller diameter (never nested).
    let r = if gap >= 0.0 {
        a1 + a2 + gap * 0.5 * (a1 + a2)
    } else {
        a1 + a2 + gap * 1.9 * a1.min(a2)
    };
    let d = dir.map(|v| v / n * r);
    let far = rpy(a1, a2, d);
    // The far field in the caller's precision, as a step would hold it.
    let far_t = blocks::<T>(&far);
    let far_inv = inverse(&flat::<T>(&far_t));
    let near = hydrorattle::near::near_correction::<T>(
        T::ONE,
        T::from_f64(a1),
        T::from_f64(a2),
        T::v3_from(d),
        &far_t,
    );
    let near = match near {
        Ok(b) => flat::<T>(&b),
        Err(e) => {
            // Overlap (or a gap rounded to contact in f32): no correction, R = M_far^-1.
            assert_eq!(e, NearError::Contact);
            vec![vec![0.0; 12]; 12]
        }
    };
    let sum: Mat = (0..12)
        .map(|i| (0..12).map(|j| far_inv[i][j] + near[i][j]).collect())
        .collect();
    let sym: Mat = (0..12)
        .map(|i| (0..12).map(|j| 0.5 * (sum[i][j] + sum[j][i])).collect())
        .collect();
    let nsym: Mat = (0..12)
        .map(|i| (0..12).map(|j| 0.5 * (near[i][j] + near[j][i])).collect())
        .collect();
    (min_eig_scaled(&sym, &sym), min_eig_scaled(&nsym, &sym))
}

#[test]
fn r_near_is_positive_semi_definite_on_a_grid() {
    // The reason M_far^-1 + sum R_near stays positive definite for any number of spheres:
    // every pair's R_near is itself positive semi-definite (the exact two-body resistance
    // exceeds the far field's), so adding it to the positive definite M_far^-1 keeps it so.
    let mut worst = (f64::INFINITY, 0.0, 0.0);
    for ll in [-1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 1.0] {
        for lg in [-4.0, -3.0, -2.0, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5] {
            let (sd, near) = sd_resistance_is_positive_definite::<f64>(
                1.0,
                10f64.powf(ll),
                10f64.powf(lg),
                [0.3, 0.5, 0.8],
            );
            assert!(sd > 0.0);
            if near < worst.0 {
                worst = (near, 10f64.powf(ll), 10f64.powf(lg));
            }
        }
    }
    println!(
        "smallest scaled eigenvalue of R_near: {:.2e} (lambda {:.2}, gap {:.1e})",
        worst.0, worst.1, worst.2
    );
    assert!(worst.0 > -1e-6);
}

mod positive_definite {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn m_far_inverse_plus_r_near_is_positive_definite_f64(
            a1 in 0.3f64..3.0, ll in -1.0f64..1.0, lg in -4.0f64..1.3, over in 0.0f64..1.0,
            x in -1.0f64..1.0, y in -1.0f64..1.0, z in 0.1f64..1.0, overlap in proptest::bool::weighted(0.1),
        ) {
            // Gaps from 1e-4 to 20 mean radii, and a tenth of the cases overlapping.
            let gap = if overlap { -over } else { 10f64.powf(lg) };
            let (sd, near) = sd_resistance_is_positive_definite::<f64>(a1, 10f64.powf(ll), gap, [x, y, z]);
            prop_assert!(sd > 0.0, "M_far^-1 + R_near: smallest scaled eigenvalue {sd}");
            prop_assert!(near > -1e-6, "R_near: smallest scaled eigenvalue {near}");
        }

        #[test]
        fn m_far_inverse_plus_r_near_is_positive_definite_f32(
            a1 in 0.3f64..3.0, ll in -1.0f64..1.0, lg in -3.0f64..1.3, over in 0.0f64..1.0,
            x in -1.0f64..1.0, y in -1.0f64..1.0, z in 0.1f64..1.0, overlap in proptest::bool::weighted(0.1),
        ) {
            let gap = if overlap { -over } else { 10f64.powf(lg) };
            let (sd, near) = sd_resistance_is_positive_definite::<f32>(a1, 10f64.powf(ll), gap, [x, y, z]);
            prop_assert!(sd > 0.0, "M_far^-1 + R_near: smallest scaled eigenvalue {sd}");
            prop_assert!(near > -1e-4, "R_near: smallest scaled eigenvalue {near}");
        }
    }
}

/// The 4x4 solve of one bispherical mode (the test's own Gaussian elimination).
fn solve4(mut m: [[f64; 5]; 4]) -> [f64; 4] {
    for c in 0..4 {
        let p = (c..4)
            .max_by(|&x, &y| m[x][c].abs().total_cmp(&m[y][c].abs()))
            .unwrap();
        m.swap(c, p);
        for r in 0..4 {
            if r != c {
                let f = m[r][c] / m[c][c];
                let row = m[c];
                for (v, w) in m[r].iter_mut().zip(row) {
                    *v -= f * w;
                }
            }
        }
    }
    core::array::from_fn(|i| m[i][4] / m[i][i])
}

/// Forces along the line of centres on two unequal spheres translating along it, from
/// the exact axisymmetric Stokes stream function in bispherical coordinates (the method
/// of Stimson and Jeffery 1926, for unequal spheres as in Maude 1961 and Brenner 1961):
/// `psi = (cosh xi - mu)^-3/2 sum_n U_n(xi) C_{n+1}^{-1/2}(mu)`, four constants per mode
/// from no-slip on `xi = alpha` (sphere 1, velocity `u1`) and `xi = -beta` (sphere 2,
/// `u2`), force `(2 sqrt 2 pi eta / c) sum (A + B + C + D)` on sphere 1 and
/// `sum (A - B + C - D)` on sphere 2 (on the fluid, `eta = 1`).
fn bispherical_axial(a1: f64, a2: f64, r: f64, u1: f64, u2: f64) -> (f64, f64) {
    let c = ((r - a1 - a2) * (r + a1 + a2) * (r - a1 + a2) * (r + a1 - a2)).sqrt() / (2.0 * r);
    let (al, be) = ((c / a1).asinh(), (c / a2).asinh());
    let (mut f1, mut f2) = (0.0, 0.0);
    for n in 1..200_000 {
        let nf = n as f64;
        let (p, q) = (nf - 0.5, nf + 1.5);
        // The no-slip data: the mode-n coefficient of (1/2) u c^2 (1 - mu^2)
        // (cosh xi - mu)^-1/2 and its derivative in |xi|, at |xi| = x.
        let data = |u: f64, x: f64| {
            let k = u * c * c / 2f64.sqrt() * nf * (nf + 1.0);
            let (ep, eq) = ((-p * x).exp(), (-q * x).exp());
            (
                k * (ep / (2.0 * nf - 1.0) - eq / (2.0 * nf + 3.0)),
                k * 0.5 * (eq - ep),
            )
        };
        let (v1, d1) = data(u1, al);
        let (v2, d2) = data(u2, be);
        // U_n in exponentials scaled to each sphere, all bounded by 1 on [-beta, alpha]:
        // A e^{p(xi-alpha)} + B e^{-p(xi+beta)} + C e^{q(xi-alpha)} + D e^{-q(xi+beta)}.
        let (ep, eq) = ((-p * (al + be)).exp(), (-q * (al + be)).exp());
        let [a, b, cc, d] = solve4([
            [1.0, ep, 1.0, eq, v1],
            [p, -p * ep, q, -q * eq, d1],
            [ep, 1.0, eq, 1.0, v2],
            [p * ep, -p, q * eq, -q, -d2],
        ]);
        // Back in Stimson and Jeffery's cosh/sinh constants: A + B + C + D on sphere 1,
        // A - B + C - D on sphere 2.
        let t1 = 2.0 * (a * (-p * al).exp() + cc * (-q * al).exp());
        let t2 = 2.0 * (b * (-p * be).exp() + d * (-q * be).exp());
        f1 += t1;
        f2 += t2;
        if t1.abs() + t2.abs() < 1e-16 * (f1.abs() + f2.abs()) {
            break;
        }
    }
    let k = 2.0 * 2f64.sqrt() * std::f64::consts::PI / c;
    (k * f1, k * f2)
}

#[test]
fn unequal_spheres_along_the_line_of_centres_match_the_exact_bispherical_solution() {
    use std::f64::consts::PI;
    // The same method reproduces Stimson and Jeffery for equal spheres...
    let (f1, f2) = bispherical_axial(1.0, 1.0, 2.1, 1.0, 1.0);
    assert!((f1 / (6.0 * PI) - stimson_jeffery(2.1)).abs() < 1e-9 && (f1 - f2).abs() < 1e-9);
    // ...and gives X^A_11 and X^A_12 for unequal ones (size ratios 2, 4 and 10, both ways).
    let mut worst = 0.0f64;
    for l in [2.0, 4.0, 10.0, 0.5, 0.25, 0.1] {
        for xi in [0.005, 0.02, 0.1, 0.3, 1.0, 2.0, 4.0] {
            let r = 0.5 * (1.0 + l) * (2.0 + xi);
            let (f11, _) = bispherical_axial(1.0, l, r, 1.0, 0.0);
            let (f12, _) = bispherical_axial(1.0, l, r, 0.0, 1.0);
            let x11 = f11 / (6.0 * PI);
            let x12 = f12 / (3.0 * PI * (1.0 + l));
            let s = scalars::<f64>(1.0, l, r).unwrap();
            let e11 = (s.xa11 / x11 - 1.0).abs();
            let e12 = (s.xa12 / x12 - 1.0).abs();
            println!(
                "lambda {l}, xi {xi}: X^A_11 {:.6} exact {x11:.6} ({e11:.1e}); X^A_12 {:.6} exact {x12:.6} ({e12:.1e})",
                s.xa11, s.xa12
            );
            worst = worst.max(e11).max(e12);
        }
    }
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn equal_spheres_reach_jeffrey_and_onishis_contact_constants() {
    // Jeffrey and Onishi (1984), equal spheres: X^A_11 = 1/(4 xi) + (9/40) ln(1/xi) +
    // 0.9954 + ..., Y^A_11 = (1/6) ln(1/xi) + 0.9983 + ..., Y^C_11 = (1/5) ln(1/xi) +
    // 0.7028 + ... (their tabulated constants; the g-functions at lambda = 1).
    let r = 2.0 + 1e-7;
    let xi = r - 2.0; // the gap the kernel sees (exact: Sterbenz)
    let s = scalars::<f64>(1.0, 1.0, r).unwrap();
    let l = (1.0 / xi).ln();
    let a = s.xa11 - 0.25 / xi - 9.0 / 40.0 * l;
    let y = s.ya11 - l / 6.0;
    let c = s.yc11 - l / 5.0;
    println!(
        "contact constants: X^A_11 {a:.5} (0.9954), Y^A_11 {y:.5} (0.9983), Y^C_11 {c:.5} (0.7028)"
    );
    assert!((a - 0.9954).abs() < 2e-4 && (y - 0.9983).abs() < 2e-4 && (c - 0.7028).abs() < 2e-4);
}

#[test]
fn far_and_huge_distances_give_finite_far_field_values() {
    for r in [1e3, 1e8, 1e150, 1e300] {
        let s = scalars::<f64>(1.0, 2.0, r).unwrap();
        let v = [
            s.xa11, s.xa12, s.ya11, s.ya12, s.yb11, s.yb12, s.xc11, s.xc12, s.yc11, s.yc12,
        ];
        assert!(v.iter().all(|x| x.is_finite()), "{r}: {v:?}");
        assert!(
            (s.xa11 - 1.0).abs() < 1e-4 && (s.xc11 - 1.0).abs() < 1e-4 && s.xa12.abs() < 1e-2,
            "{r}: {v:?}"
        );
        let w = wall_scalars::<f64>(1.0, r).unwrap();
        assert!(
            [w.xa, w.ya, w.yb, w.xc, w.yc].iter().all(|x| x.is_finite()),
            "{r}: {w:?}"
        );
    }
}
