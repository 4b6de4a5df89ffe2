//! The mobility above a no-slip plane wall,
//! checked against results that do not come from the kernel:
//!
//! * a lone sphere against the method of reflections: Faxén's series parallel to the
//!   wall, `1 - 9/16 x + 1/8 x^3 - 45/256 x^4 - 1/16 x^5` (`x = a/h`), and Brenner's
//!   exact series across it (summed here to convergence);
//! * equal radii against Swan & Brady's published closed form (2007, written out here
//!   from the paper's expressions);
//! * unequal radii against the double average of Blake's Green's function over the two
//!   spheres' surfaces (Blake 1971, written out here; a Gauss-Legendre x trapezoid
//!   quadrature), which is what the Faxén operators give for spheres above the wall;
//! * far from the wall, the free-space RPY; far apart along the wall, the pair block
//!   decays as `d^-3` (Blake's far field) and the self blocks are the lone sphere's;
//! * positive definiteness over random polydisperse configurations (proptest);
//! * the Ito drift `kT d(mu_perp)/dh` of a lone sphere from the midpoint scheme, absent
//!   without it.

// 3x3 index loops read as the formulas do.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use hydrorattle::mobility::{self, wall};
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, ParticleSet, Real, Serial,
    SolverKind, Wall, linalg,
};
use hydrorattle_heap::Buffers;
use proptest::prelude::*;
use std::f64::consts::PI;

/// The kernel's `mu_tt` above the wall at `height`, dense `3n x 3n` in f64.
fn dense<T: Real>(level: Hydro, eta: f64, height: f64, s: &[([f64; 3], f64)]) -> Vec<Vec<f64>> {
    let n = s.len();
    let pos: Vec<T::V3> = s.iter().map(|c| T::v3_from(c.0)).collect();
    let rad: Vec<T> = s.iter().map(|c| T::from_f64(c.1)).collect();
    let (e, h) = (T::from_f64(eta), T::from_f64(height));
    let mut out = vec![T::M3_ZERO; n * (n + 1) / 2];
    wall::assemble(&Serial, level, e, h, &pos, &rad, &mut out).unwrap();
    let mut m = vec![vec![0.0; 3 * n]; 3 * n];
    for p in 0..n {
        for q in 0..n {
            let b = linalg::sym_get::<T>(&out, p, q);
            for r in 0..3 {
                for c in 0..3 {
                    m[3 * p + r][3 * q + c] = T::m3_get(b, r, c).to_f64();
                }
            }
        }
    }
    m
}

/// `(mu_par, mu_perp) 6 pi eta a` of a lone sphere of radius `a` at height `h`.
fn lone<T: Real>(a: f64, h: f64) -> (f64, f64) {
    let (height, eta) = (-0.75, 1.3);
    let m = dense::<T>(Hydro::Rpy, eta, height, &[([0.4, -0.2, height + h], a)]);
    let s = 6.0 * PI * eta * a;
    assert_eq!(m[0][0], m[1][1]);
    for (r, c) in [(0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1)] {
        assert_eq!(m[r][c], 0.0);
    }
    (m[0][0] * s, m[2][2] * s)
}

/// Faxén's parallel series to `(a/h)^5`.
fn faxen(x: f64) -> f64 {
    1.0 - 9.0 / 16.0 * x + x.powi(3) / 8.0 - 45.0 / 256.0 * x.powi(4) - x.powi(5) / 16.0
}

/// Brenner's (1961) exact perpendicular mobility `6 pi eta a U / F` at `h/a`: the
/// inverse of `(4/3) sinh(al) sum_n n(n+1)/((2n-1)(2n+3)) [(2 sinh((2n+1)al) +
/// (2n+1) sinh(2al)) / (4 sinh^2((n+1/2)al) - (2n+1)^2 sinh^2(al)) - 1]`,
/// `al = acosh(h/a)`, summed until the terms stop counting.
fn brenner(h_over_a: f64) -> f64 {
    let al = h_over_a.acosh();
    let mut sum = 0.0;
    for n in 1..400 {
        let k = n as f64;
        let num = 2.0 * ((2.0 * k + 1.0) * al).sinh() + (2.0 * k + 1.0) * (2.0 * al).sinh();
        let den =
            4.0 * ((k + 0.5) * al).sinh().powi(2) - (2.0 * k + 1.0).powi(2) * al.sinh().powi(2);
        let t = k * (k + 1.0) / ((2.0 * k - 1.0) * (2.0 * k + 3.0)) * (num / den - 1.0);
        sum += t;
        if t.abs() < 1e-18 * sum.abs() {
            break;
        }
    }
    1.0 / (4.0 / 3.0 * al.sinh() * sum)
}

/// The lone sphere against the series at h/a = 1.5, 2, 4, 10. The RPY-Blake self
/// mobility is Swan & Brady's `1 - 9/16 x + 1/8 x^3 - 1/16 x^5` (parallel) and
/// `1 - 9/8 x + 1/2 x^3 - 1/8 x^5` (perpendicular): exact to `x^3`, so
/// * parallel: it lacks Faxén's `-45/256 x^4` and nothing else: the difference is that
///   term (to rounding);
/// * perpendicular: it differs from Brenner's exact value at order `x^4` (Brenner's
///   expansion has `-57/100 x^4`): the difference is positive and below `0.57 x^4`, and
///   above `0.3 x^4` (so it is of that order, not smaller).
fn lone_sphere_series<T: Real>() {
    let tol = pick::<T>(2e-6, 1e-13);
    eprintln!("h/a   par(kernel)  Faxen     diff      perp(kernel) Brenner   diff      diff/x^4");
    for (h, a) in [(1.5, 1.0), (2.0, 0.5), (4.0, 2.0), (10.0, 1.0)] {
        let (par, perp) = lone::<T>(a, h * a);
        let x = 1.0 / h;
        let (f, b) = (faxen(x), brenner(h));
        eprintln!(
            "{h:<5} {par:.6}     {f:.6}  {:+.2e} {perp:.6}     {b:.6}  {:+.2e} {:.3}",
            par - f,
            perp - b,
            (perp - b) / x.powi(4)
        );
        let missing = 45.0 / 256.0 * x.powi(4);
        assert!((par - f - missing).abs() < tol, "parallel at h/a = {h}");
        let d = (perp - b) / x.powi(4);
        assert!(d > 0.3 && d < 0.57, "perpendicular at h/a = {h}: {d}");
    }
}

#[test]
fn lone_sphere_against_faxen_and_brenner_f64() {
    lone_sphere_series::<f64>();
}

#[test]
fn lone_sphere_against_faxen_and_brenner_f32() {
    lone_sphere_series::<f32>();
}

/// Swan & Brady (2007) equal-radius wall correction, in units of `1/(8 pi eta a)`, as
/// the paper writes it: `R = (r_i - r_j^image)/a`, `h_hat = h_j / R_z`,
/// `M = f1 I + f2 e e + f3 e z + f4 z e + f5 z z`.
fn swan_brady(ri: [f64; 3], rj: [f64; 3], a: f64, eta: f64) -> [[f64; 3]; 3] {
    let r = [
        (ri[0] - rj[0]) / a,
        (ri[1] - rj[1]) / a,
        (ri[2] + rj[2]) / a,
    ];
    let hh = rj[2] / a / r[2];
    let ir = 1.0 / norm(r);
    let e = scale(r, ir);
    let ez = e[2];
    let (ez2, ir3, ir5) = (ez * ez, ir.powi(3), ir.powi(5));
    let f1 = -(3.0 * (1.0 + 2.0 * hh * (1.0 - hh) * ez2) * ir + 2.0 * (1.0 - 3.0 * ez2) * ir3
        - 2.0 * (1.0 - 5.0 * ez2) * ir5)
        / 3.0;
    let f2 = -(3.0 * (1.0 - 6.0 * hh * (1.0 - hh) * ez2) * ir - 6.0 * (1.0 - 5.0 * ez2) * ir3
        + 10.0 * (1.0 - 7.0 * ez2) * ir5)
        / 3.0;
    let f3 = ez
        * (3.0 * hh * (1.0 - 6.0 * (1.0 - hh) * ez2) * ir - 6.0 * (1.0 - 5.0 * ez2) * ir3
            + 10.0 * (2.0 - 7.0 * ez2) * ir5)
        * 2.0
        / 3.0;
    let f4 = ez * (3.0 * hh * ir - 10.0 * ir5) * 2.0 / 3.0;
    let f5 = -(3.0 * hh * hh * ez2 * ir + 3.0 * ez2 * ir3 + (2.0 - 15.0 * ez2) * ir5) * 4.0 / 3.0;
    let z = [0.0, 0.0, 1.0];
    let c = 1.0 / (8.0 * PI * eta * a);
    let mut m = [[0.0; 3]; 3];
    for p in 0..3 {
        for q in 0..3 {
            let d = if p == q { 1.0 } else { 0.0 };
            m[p][q] = c
                * (f1 * d
                    + f2 * e[p] * e[q]
                    + f3 * e[p] * z[q]
                    + f4 * z[p] * e[q]
                    + f5 * z[p] * z[q]);
        }
    }
    m
}

/// Equal radii: the kernel's image block is Swan & Brady's, for configurations at
/// every angle to the wall (wall at z = 0).
fn equal_radii_swan_brady<T: Real>() {
    let tol = pick::<T>(3e-6, 1e-13);
    let (a, eta) = (1.2, 0.9);
    let mut worst = 0.0f64;
    for k in 0..40 {
        let t = k as f64;
        let ri = [
            3.0 * (0.7 * t).sin(),
            2.0 * (1.3 * t).cos(),
            1.3 + 2.5 * (0.37 * t).sin().abs(),
        ];
        let rj = [
            -1.0 + (0.5 * t).cos(),
            0.8 * (0.9 * t).sin(),
            1.2 + 4.0 * (0.21 * t).cos().abs(),
        ];
        let r = sub(ri, rj);
        let w = wall::image_tt::<T>(
            T::from_f64(eta),
            T::from_f64(a),
            T::from_f64(a),
            T::v3_from(r),
            T::from_f64(ri[2] + rj[2]),
            T::from_f64(rj[2]),
        );
        let sb = swan_brady(ri, rj, a, eta);
        let c = 1.0 / (8.0 * PI * eta * a);
        for p in 0..3 {
            for q in 0..3 {
                worst = worst.max((T::m3_get(w, p, q).to_f64() - sb[p][q]).abs() / c);
            }
        }
    }
    eprintln!("equal radii vs Swan & Brady: largest difference {worst:.2e} (units 1/(8 pi eta a))");
    assert!(worst < tol);
}

#[test]
fn equal_radii_are_swan_and_brady_f64() {
    equal_radii_swan_brady::<f64>();
}

#[test]
fn equal_radii_are_swan_and_brady_f32() {
    equal_radii_swan_brady::<f32>();
}

/// Blake's (1971) Green's function of a point force at `y` above the wall `z = 0`,
/// `8 pi eta G_ij(x, y)` (velocity `i` at `x`, force `j`):
/// `S(r) - S(R) + 2h M_jj d/dR_j [h R_i/R^3 - delta_i3/R - R_i R_3/R^3]`, `r = x - y`,
/// `R = x - (y1, y2, -h)`, `S(r) = I/r + r r/r^3`, `M = diag(1, 1, -1)`.
fn blake(x: [f64; 3], y: [f64; 3]) -> [[f64; 3]; 3] {
    let h = y[2];
    let r = sub(x, y);
    let big = [x[0] - y[0], x[1] - y[1], x[2] + h];
    let (rn, bn) = (norm(r), norm(big));
    let d = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
    let m = [1.0, 1.0, -1.0];
    let mut g = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let s_r = d(i, j) / rn + r[i] * r[j] / rn.powi(3);
            let s_big = d(i, j) / bn + big[i] * big[j] / bn.powi(3);
            // d/dR_j of the bracket.
            let b3 = bn.powi(3);
            let b5 = bn.powi(5);
            let dphi = h * (d(i, j) / b3 - 3.0 * big[i] * big[j] / b5) + d(i, 2) * big[j] / b3
                - (d(i, j) * big[2] + big[i] * d(2, j)) / b3
                + 3.0 * big[i] * big[2] * big[j] / b5;
            g[i][j] = s_r - s_big + 2.0 * h * m[j] * dphi;
        }
    }
    g
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre polynomial).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let mut x = (PI * (k as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for m in 2..=n {
                    let m = m as f64;
                    let p2 = ((2.0 * m - 1.0) * x * p1 - (m - 1.0) * p0) / m;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Points and weights (summing to 1) on the sphere of radius `a` about `c`.
fn sphere_points(c: [f64; 3], a: f64, gl: &[(f64, f64)], nphi: usize) -> Vec<([f64; 3], f64)> {
    let mut pts = Vec::new();
    for &(ct, w) in gl {
        let st = (1.0 - ct * ct).sqrt();
        for k in 0..nphi {
            let ph = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
            let n = [st * ph.cos(), st * ph.sin(), ct];
            pts.push((add(c, scale(n, a)), w / (2.0 * nphi as f64)));
        }
    }
    pts
}

/// Unequal radii: the kernel's block `(i, j)` (free space and image) is the average of
/// Blake's tensor over the surfaces of sphere `i` (field) and sphere `j` (source).
/// Quadrature: 20 Gauss-Legendre x 40 trapezoid points per sphere (measured: 14 x 28
/// leaves 5e-10 of the largest entry, 20 x 40 4e-13); tolerance 1e-11.
#[test]
fn unequal_radii_are_the_surface_average_of_blakes_tensor() {
    const NGL: usize = 20;
    let eta = 1.0;
    let cases = [
        ([0.0, 0.0, 2.5], 1.0, [4.0, 1.0, 3.2], 2.0),
        ([4.0, 1.0, 3.2], 2.0, [0.0, 0.0, 2.5], 1.0),
        ([0.3, -0.4, 1.2], 0.7, [0.5, 0.2, 4.4], 1.6),
        ([1.0, 2.0, 6.0], 0.5, [-2.0, 0.5, 2.1], 1.8),
    ];
    let gl = gauss_legendre(NGL);
    let mut worst = 0.0f64;
    for (ci, ai, cj, aj) in cases {
        let m = dense::<f64>(Hydro::Rpy, eta, 0.0, &[(ci, ai), (cj, aj)]);
        let (pi, pj) = (
            sphere_points(ci, ai, &gl, 2 * NGL),
            sphere_points(cj, aj, &gl, 2 * NGL),
        );
        let mut avg = [[0.0; 3]; 3];
        for &(x, wx) in &pi {
            for &(y, wy) in &pj {
                let g = blake(x, y);
                for p in 0..3 {
                    for q in 0..3 {
                        avg[p][q] += wx * wy * g[p][q] / (8.0 * PI * eta);
                    }
                }
            }
        }
        let big = avg.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
        for p in 0..3 {
            for q in 0..3 {
                let d = (m[p][3 + q] - avg[p][q]).abs() / big;
                worst = worst.max(d);
            }
        }
    }
    eprintln!("unequal radii vs surface average of Blake: largest relative difference {worst:.2e}");
    assert!(worst < 1e-11, "{worst}");
}

/// The test's own Blake tensor vanishes on the wall (no slip), so the average above
/// checks the kernel against the right Green's function.
#[test]
fn blakes_tensor_vanishes_on_the_wall() {
    for (x, y) in [
        ([1.0, 2.0, 0.0], [0.3, -0.5, 1.7]),
        ([-3.0, 0.1, 0.0], [0.0, 0.0, 0.4]),
    ] {
        let g = blake(x, y);
        assert!(g.iter().flatten().all(|v| v.abs() < 1e-15), "{g:?}");
    }
}

/// Far from the wall the pair block tends to the free-space RPY, the difference falling
/// as `1/h` (the image's distance); both blocks' images too.
fn far_from_wall<T: Real>() {
    let (ai, aj, eta) = (1.0, 1.7, 1.0);
    let mut diffs = Vec::new();
    let hs = [1e2, 1e3, 1e4];
    for h in hs {
        let s = [([0.0, 0.0, h], ai), ([2.0, 2.5, h + 1.5], aj)];
        let m = dense::<T>(Hydro::Rpy, eta, 0.0, &s);
        let r = T::v3_from(sub(s[1].0, s[0].0));
        let free = mobility::pair_tt::<T>(
            Hydro::Rpy,
            T::from_f64(eta),
            T::from_f64(aj),
            T::from_f64(ai),
            r,
        )
        .unwrap();
        let mut d = 0.0f64;
        let mut big = 0.0f64;
        for p in 0..3 {
            for q in 0..3 {
                let f = T::m3_get(free, p, q).to_f64();
                d = d.max((m[3 + p][q] - f).abs());
                big = big.max(f.abs());
            }
        }
        diffs.push(d / big);
    }
    let slope = loglog_slope(&hs, &diffs);
    eprintln!("far from the wall: relative difference {diffs:?}, slope {slope:.3}");
    assert!(diffs[2] < 1e-3);
    if !is_single::<T>() {
        assert!((slope + 1.0).abs() < 0.05, "{slope}");
    }
}

#[test]
fn pair_far_from_the_wall_is_free_space_rpy_f64() {
    far_from_wall::<f64>();
}

#[test]
fn pair_far_from_the_wall_is_free_space_rpy_f32() {
    far_from_wall::<f32>();
}

/// Two spheres far apart along the wall: the self blocks are the lone sphere's, and the
/// pair block decays as `d^-3` (the wall screens the Stokeslet: Blake's far field).
fn far_along_wall<T: Real>() {
    let (h1, h2, a1, a2) = (1.5, 2.5, 1.0, 1.4);
    let ds = [50.0, 100.0, 200.0, 400.0];
    let mut pair = Vec::new();
    for d in ds {
        let m = dense::<T>(
            Hydro::Rpy,
            1.0,
            0.0,
            &[([0.0, 0.0, h1], a1), ([d, 0.3 * d, h2], a2)],
        );
        let (p1, q1) = lone::<T>(a1, h1);
        let (p2, q2) = lone::<T>(a2, h2);
        let s1 = 6.0 * PI * a1;
        let s2 = 6.0 * PI * a2;
        let tol = pick::<T>(1e-6, 1e-14);
        for (k, s, par, perp) in [(0, s1, p1, q1), (3, s2, p2, q2)] {
            assert!((m[k][k] * s - par).abs() < tol && (m[k + 1][k + 1] * s - par).abs() < tol);
            assert!((m[k + 2][k + 2] * s - perp).abs() < tol);
        }
        let big = (0..3)
            .flat_map(|p| (0..3).map(move |q| (p, q)))
            .fold(0.0f64, |s, (p, q)| s.max(m[3 + p][q].abs()));
        pair.push(big);
    }
    let slope = loglog_slope(&ds, &pair);
    eprintln!("far along the wall: pair block {pair:?}, slope {slope:.3}");
    assert!((slope + 3.0).abs() < 0.05, "{slope}");
}

#[test]
fn far_apart_along_the_wall_f64() {
    far_along_wall::<f64>();
}

#[test]
fn far_apart_along_the_wall_f32() {
    far_along_wall::<f32>();
}

/// Reciprocity: block `(j, i)` is the transpose of block `(i, j)` evaluated from the
/// other side (the image formula with the roles swapped), at unequal radii.
#[test]
fn blocks_are_reciprocal() {
    let (ri, rj, ai, aj) = ([0.3, 0.1, 2.2], [-1.4, 2.0, 3.7], 0.9, 1.6);
    let w = |x: [f64; 3], y: [f64; 3], a: f64, b: f64| {
        wall::image_tt::<f64>(1.0, a, b, f64::v3_from(sub(x, y)), x[2] + y[2], y[2])
    };
    let (ij, ji) = (w(ri, rj, ai, aj), w(rj, ri, aj, ai));
    let big =
        |m: hydrorattle::glam::DMat3| m.to_cols_array().iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let d = big(ij - ji.transpose());
    assert!(d < 1e-16 * big(ij).max(1.0), "{d}");
    assert!(
        big(ij - ij.transpose()) > 1e-4 * big(ij),
        "not symmetric in general"
    );
}

/// Smallest eigenvalue sign by Cholesky of the kernel's own packed assembly.
fn cholesky_ok<T: Real>(level: Hydro, height: f64, s: &[([f64; 3], f64)]) -> bool {
    let n = s.len();
    let pos: Vec<T::V3> = s.iter().map(|c| T::v3_from(c.0)).collect();
    let rad: Vec<T> = s.iter().map(|c| T::from_f64(c.1)).collect();
    let mut out = vec![T::M3_ZERO; n * (n + 1) / 2];
    wall::assemble(
        &Serial,
        level,
        T::ONE,
        T::from_f64(height),
        &pos,
        &rad,
        &mut out,
    )
    .unwrap();
    linalg::cholesky::<T>(&mut out, n).is_ok()
}

/// Random polydisperse spheres above the wall: radii 0.3..2, no overlaps (or, with
/// `overlap`, overlapping but not nested: `allow_overlap`'s configurations), heights from
/// touching the wall to a few radii, packed in a box so that many pairs nearly touch;
/// with `lifts` some within `a` of the wall (damped, as the contacts' tolerance allows).
fn configuration(
    n: usize,
    seed: u64,
    height: f64,
    lifts: bool,
    overlap: bool,
) -> Vec<([f64; 3], f64)> {
    let mut rng = fuzz::Rng::case(seed, 0);
    let mut s: Vec<([f64; 3], f64)> = Vec::new();
    let side = 1.5 * (n as f64).sqrt() + 2.0;
    while s.len() < n {
        let a = 0.3 + 1.7 * rng.unit();
        let mut h = a * (1.0 + 3.0 * rng.unit() * rng.unit());
        if lifts && rng.unit() < 0.3 {
            h = a * (0.2 + 0.8 * rng.unit());
        }
        let c = [side * rng.unit(), side * rng.unit(), height + h];
        let apart = |b: f64| if overlap { (a - b).abs() + 0.05 } else { a + b };
        if s.iter().all(|&(p, b)| norm(sub(p, c)) >= apart(b)) {
            s.push((c, a));
        }
    }
    s
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Positive definite (Cholesky succeeds) for RPY and free draining, f64 and f32,
    /// spheres wholly above the wall or within a radius of it (damped), or overlapping
    /// each other (Zuk's branch; not with damped spheres, which could be lifted into
    /// each other).
    #[test]
    fn wall_mobility_is_positive_definite(n in 1usize..12, seed in 0u64..1_000_000, lifts in any::<bool>(), overlap in any::<bool>(), height in -5.0f64..5.0) {
        let s = configuration(n, seed, height, lifts && !overlap, overlap);
        for level in [Hydro::Rpy, Hydro::FreeDraining] {
            prop_assert!(cholesky_ok::<f64>(level, height, &s), "f64 {level:?} {s:?}");
            prop_assert!(cholesky_ok::<f32>(level, height, &s), "f32 {level:?} {s:?}");
        }
    }
}

/// A centre at or below the plane is refused with its index.
#[test]
fn a_centre_below_the_wall_is_refused() {
    let s = [
        ([0.0, 0.0, 3.0], 1.0),
        ([5.0, 0.0, 0.9], 1.0),
        ([0.0, 5.0, 0.5], 0.4),
    ];
    let pos: Vec<_> = s.iter().map(|c| f64::v3_from(c.0)).collect();
    let rad: Vec<f64> = s.iter().map(|c| c.1).collect();
    let mut out = vec![f64::M3_ZERO; 6];
    let e = wall::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, 1.0, &pos, &rad, &mut out).unwrap_err();
    assert_eq!(e, hydrorattle::ParticleError::BelowWall { particle: 1 });
    let mut y = vec![f64::V3_ZERO; 3];
    let e = wall::tt_product::<f64>(Hydro::Rpy, 1.0, 1.0, &pos, &rad, &pos, &mut y).unwrap_err();
    assert_eq!(e, hydrorattle::ParticleError::BelowWall { particle: 1 });
}

/// The matrix-free product has the bits of the stored mobility applied by `sym_matvec`
/// (below the banded size), and the block read from either side agrees.
fn matrix_free_bits<T: Real>() {
    let s = configuration(40, 7, 0.5, true, false);
    let n = s.len();
    let pos: Vec<T::V3> = s.iter().map(|c| T::v3_from(c.0)).collect();
    let rad: Vec<T> = s.iter().map(|c| T::from_f64(c.1)).collect();
    let x: Vec<T::V3> = (0..n)
        .map(|i| v3::<T>((i as f64).sin(), 1.0, 0.1 * i as f64))
        .collect();
    let (eta, h) = (T::from_f64(0.8), T::from_f64(0.5));
    let mut mu = vec![T::M3_ZERO; n * (n + 1) / 2];
    wall::assemble(&Serial, Hydro::Rpy, eta, h, &pos, &rad, &mut mu).unwrap();
    let mut stored = vec![T::V3_ZERO; n];
    linalg::sym_matvec::<T>(&mu, n, &x, &mut stored);
    let mut free = vec![T::V3_ZERO; n];
    wall::tt_product(Hydro::Rpy, eta, h, &pos, &rad, &x, &mut free).unwrap();
    for (a, b) in stored.iter().zip(&free) {
        assert_eq!(f64s::<T>(*a), f64s::<T>(*b));
    }
    for (p, q) in [(3, 17), (17, 3), (5, 5)] {
        let b = wall::tt_block_at(Hydro::Rpy, eta, h, &pos, &rad, p, q).unwrap();
        assert_eq!(b, linalg::sym_get::<T>(&mu, p, q));
    }
}

#[test]
fn matrix_free_has_the_stored_bits_f64() {
    matrix_free_bits::<f64>();
}

#[test]
fn matrix_free_has_the_stored_bits_f32() {
    matrix_free_bits::<f32>();
}

/// `kT d(mu_perp)/dh` of a sphere of radius `a` at height `h` (`eta = 1`, `kT = 1`), by
/// central differences of Swan & Brady's closed form `(1 - 9/8 x + 1/2 x^3 - 1/8 x^5) /
/// (6 pi a)`, `x = a/h`.
fn drift_perp(a: f64, h: f64) -> f64 {
    let mu = |h: f64| {
        let x = a / h;
        (1.0 - 1.125 * x + 0.5 * x.powi(3) - 0.125 * x.powi(5)) / (6.0 * PI * a)
    };
    let e = 1e-5;
    (mu(h + e) - mu(h - e)) / (2.0 * e)
}

/// The mean displacement of a lone sphere at height `h` over `steps` one-step runs from
/// the same start (gravity off, `kT = 1`): `(mean dz / dt, its standard error, mean
/// |dx, dy| / dt, its standard error)`.
fn mean_step<T: Real>(drift: Drift, a: f64, h: f64, dt: f64, steps: usize, seed: u64) -> [f64; 4] {
    let mut p = params::<T>(dt, Method::Overdamped, SolverKind::Auto);
    p.gravity = T::V3_ZERO;
    p.wall = Some(Wall::new(T::from_f64(-0.5)));
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift,
    });
    p.noise_sqrt = hydrorattle::NoiseSqrt::Cholesky;
    let start = [0.25, -0.5, h - 0.5];
    let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
        pos: start,
        radius: a,
        density: 0.0,
    }]);
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(seed);
    let (mut sz, mut szz, mut sx, mut sxx) = (0.0, 0.0, 0.0, 0.0);
    for k in 0..steps {
        ps.pos[0] = T::v3_from(start);
        step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        let d = sub(f64s::<T>(ps.pos[0]), start);
        sz += d[2];
        szz += d[2] * d[2];
        sx += d[0] + d[1];
        sxx += (d[0] + d[1]) * (d[0] + d[1]);
    }
    let m = steps as f64;
    let se = |s: f64, ss: f64| ((ss / m - (s / m) * (s / m)) / m).sqrt();
    [sz / m / dt, se(sz, szz) / dt, sx / m / dt, se(sx, sxx) / dt]
}

/// The Ito drift near the wall: over one step from height `h`, the midpoint scheme
/// moves a lone sphere by `kT dt d(mu_perp)/dh` on average (away from the wall), within
/// 4 standard errors; along the wall by nothing. The uncorrected scheme has no mean
/// displacement (within 4 standard errors) and misses the drift by more than 6. The
/// standard error is asserted below 7 % of the drift (the test's power).
/// Sphere `a = 1` at `h = 1.5`, `dt = 0.2`, 400 000 steps per scheme.
fn wall_drift<T: Real>() {
    let (a, h, dt, steps) = (1.0, 1.5, 0.2, 400_000);
    let exact = drift_perp(a, h);
    let [mid, se, along, se_along] = mean_step::<T>(Drift::Midpoint, a, h, dt, steps, 11);
    let [unc, se_u, _, _] = mean_step::<T>(Drift::Uncorrected, a, h, dt, steps, 12);
    eprintln!(
        "drift kT dmu_perp/dh = {exact:.5}: midpoint {mid:.5} +- {se:.5}, uncorrected {unc:.5} +- {se_u:.5}, along the wall {along:.5} +- {se_along:.5}"
    );
    assert!(se < 0.07 * exact, "too few samples: se {se}");
    assert!((mid - exact).abs() < 4.0 * se, "midpoint {mid} vs {exact}");
    assert!(along.abs() < 4.0 * se_along, "along the wall {along}");
    assert!(unc.abs() < 4.0 * se_u, "uncorrected {unc}");
    assert!(
        (unc - exact).abs() > 6.0 * se_u,
        "uncorrected {unc} vs {exact}"
    );
}

#[test]
fn midpoint_gives_the_wall_drift_f64() {
    wall_drift::<f64>();
}

#[test]
fn midpoint_gives_the_wall_drift_f32() {
    wall_drift::<f32>();
}

/// A lone sphere settling towards the wall: one overdamped step moves it by
/// `dt mu_perp(h) W` (buoyant weight `W`), with Swan & Brady's `mu_perp`; with rotation
/// its spin stays zero.
fn settles_with_mu_perp<T: Real>() {
    let (a, h, dt, rho) = (1.2, 2.0, 0.01, 3.0);
    let mut p = params::<T>(dt, Method::Overdamped, SolverKind::Auto);
    p.wall = Some(Wall::new(T::from_f64(1.0)));
    let ps = lone_step::<T>(&p, [0.0, 0.0, 1.0 + h], a, rho);
    let weight = 4.0 / 3.0 * PI * a.powi(3) * rho;
    let x = a / h;
    let mu = (1.0 - 1.125 * x + 0.5 * x.powi(3) - 0.125 * x.powi(5)) / (6.0 * PI * a);
    let dz = f64s::<T>(ps.pos[0])[2] - (1.0 + h);
    let rel = (dz / (-dt * mu * weight) - 1.0).abs();
    assert!(
        rel < pick::<T>(1e-4, 1e-12),
        "{dz} vs {}",
        -dt * mu * weight
    );
    p.rotation = true;
    let ps = lone_step::<T>(&p, [0.0, 0.0, 1.0 + h], a, rho);
    assert_eq!(
        f64s::<T>(ps.omega[0]),
        [0.0; 3],
        "a force along the normal turns nothing"
    );
}

#[test]
fn settles_with_the_perpendicular_mobility_f64() {
    settles_with_mu_perp::<f64>();
}

#[test]
fn settles_with_the_perpendicular_mobility_f32() {
    settles_with_mu_perp::<f32>();
}

/// `y = M x` for a dense matrix.
fn matvec(m: &[Vec<f64>], x: &[f64]) -> Vec<f64> {
    m.iter()
        .map(|row| row.iter().zip(x).map(|(a, b)| a * b).sum())
        .collect()
}

/// A settling trimer near the wall, one overdamped step at `dt = 0.5`, against the same
/// step solved here from the dense mobility: `r' = r + dt M (F + G^T lambda)` with the
/// two multipliers found by Newton in f64 so that both bonds keep their lengths. Every
/// solver (sweep, dense Newton, Krylov) and the matrix-free path read the wall's
/// non-symmetric pair blocks through the constraint metric; a block read untransposed
/// would move the result by far more than the tolerance. The matrix-free path has the
/// stored path's bits.
fn trimer_step<T: Real>() {
    let s = [
        ([0.0, 0.0, 2.2], 1.0),
        ([2.3, 0.9, 3.1], 1.5),
        ([3.0, 3.6, 2.0], 0.8),
    ];
    let (dt, rho) = (0.5, 2.0);
    let m = dense::<f64>(Hydro::Rpy, 1.0, 0.0, &s);
    let bonds = [(0usize, 1usize), (1, 2)];
    let len: Vec<f64> = bonds
        .iter()
        .map(|&(i, j)| norm(sub(s[i].0, s[j].0)))
        .collect();
    let g: Vec<[f64; 3]> = bonds.iter().map(|&(i, j)| sub(s[i].0, s[j].0)).collect();
    let mut f = vec![0.0; 9];
    for (k, c) in s.iter().enumerate() {
        f[3 * k + 2] = -4.0 / 3.0 * PI * c.1.powi(3) * rho;
    }
    let end = |lam: &[f64]| {
        let mut ff = f.clone();
        for (l, &(i, j)) in bonds.iter().enumerate() {
            for c in 0..3 {
                ff[3 * i + c] += lam[l] * g[l][c];
                ff[3 * j + c] -= lam[l] * g[l][c];
            }
        }
        let u = matvec(&m, &ff);
        (0..3)
            .map(|k| [0, 1, 2].map(|c| s[k].0[c] + dt * u[3 * k + c]))
            .collect::<Vec<_>>()
    };
    let resid = |lam: &[f64]| {
        let r = end(lam);
        bonds
            .iter()
            .enumerate()
            .map(|(l, &(i, j))| norm(sub(r[i], r[j])) - len[l])
            .collect::<Vec<_>>()
    };
    let mut lam = vec![0.0, 0.0];
    for _ in 0..50 {
        let r0 = resid(&lam);
        let e = 1e-6;
        let mut jac = [[0.0; 2]; 2];
        for c in 0..2 {
            let mut l2 = lam.clone();
            l2[c] += e;
            let r1 = resid(&l2);
            for k in 0..2 {
                jac[k][c] = (r1[k] - r0[k]) / e;
            }
        }
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        lam[0] -= (jac[1][1] * r0[0] - jac[0][1] * r0[1]) / det;
        lam[1] -= (-jac[1][0] * r0[0] + jac[0][0] * r0[1]) / det;
    }
    assert!(resid(&lam).iter().all(|r| r.abs() < 1e-12));
    let exact = end(&lam);
    let tol = pick::<T>(5e-5, 1e-9);
    let mut free_bits = Vec::new();
    for (kind, matrix_free) in [
        (SolverKind::Sweep, false),
        (SolverKind::Newton, false),
        (SolverKind::Krylov, false),
        (SolverKind::Krylov, true),
        (SolverKind::Newton, true),
    ] {
        let mut p = params::<T>(dt, Method::Overdamped, kind);
        p.wall = Some(Wall::new(T::ZERO));
        p.matrix_free = matrix_free;
        let spheres: Vec<Sphere> = s
            .iter()
            .map(|c| Sphere {
                pos: c.0,
                radius: c.1,
                density: rho,
            })
            .collect();
        let mut ps: ParticleSet<T, 3> = particles(&spheres);
        let bs: BondSet<T, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
        let mut buf = Buffers::<T>::new(Layout::for_params(&p, 3, 2));
        let mut ws = buf.workspace();
        hydrorattle::step(&mut ps, &bs, &p, &mut ws, &mut NoForce).unwrap();
        let worst = (0..3)
            .map(|k| norm(sub(f64s::<T>(ps.pos[k]), exact[k])))
            .fold(0.0, f64::max);
        eprintln!(
            "trimer above the wall, {kind:?} matrix_free {matrix_free}: {worst:.1e} from the dense solve"
        );
        assert!(worst < tol, "{kind:?} {matrix_free}: {worst}");
        if kind == SolverKind::Krylov {
            free_bits.push(snapshot(&ps));
        }
    }
    assert_eq!(
        free_bits[0], free_bits[1],
        "matrix-free Krylov has the stored bits"
    );
}

#[test]
fn trimer_step_matches_the_dense_solve_f64() {
    trimer_step::<f64>();
}

#[test]
fn trimer_step_matches_the_dense_solve_f32() {
    trimer_step::<f32>();
}

/// The kernel's grand mobility above the wall at `height`, dense `6n x 6n` in f64
/// (translations, then rotations).
fn dense_grand<T: Real>(level: Hydro, height: f64, s: &[([f64; 3], f64)]) -> Vec<Vec<f64>> {
    let m = 2 * s.len();
    let pos: Vec<T::V3> = s.iter().map(|c| T::v3_from(c.0)).collect();
    let rad: Vec<T> = s.iter().map(|c| T::from_f64(c.1)).collect();
    let mut out = vec![T::M3_ZERO; m * (m + 1) / 2];
    wall::assemble_grand(level, T::ONE, T::from_f64(height), &pos, &rad, &mut out).unwrap();
    let mut d = vec![vec![0.0; 3 * m]; 3 * m];
    for p in 0..m {
        for q in 0..m {
            let b = linalg::sym_get::<T>(&out, p, q);
            for r in 0..3 {
                for c in 0..3 {
                    d[3 * p + r][3 * q + c] = T::m3_get(b, r, c).to_f64();
                }
            }
        }
    }
    d
}

/// A lone sphere's rotation near the wall: the far-field coefficients of the method of
/// reflections (Goldman, Cox & Brenner 1967): rotation about an axis along the wall
/// `1 - 5/16 x^3`, about the normal `1 - 1/8 x^3` (units `1/(8 pi eta a^3)`), and the
/// translation-rotation coupling `3/32 x^4` (units `1/(6 pi eta a^2)`), in the sense of
/// rolling along the wall (`W = c z x F`); the self blocks are also the image formula
/// at `j = i` (`image_rot` with `R = 2h z`) plus the free sphere's.
fn lone_rotation<T: Real>() {
    let tol = pick::<T>(1e-6, 1e-14);
    for (h, a) in [(1.5, 1.0), (2.0, 0.5), (4.0, 2.0), (10.0, 1.0)] {
        let x = 1.0 / h;
        let g = dense_grand::<T>(Hydro::Rpy, 0.0, &[([0.3, 0.2, h * a], a)]);
        let rr = 8.0 * PI * a.powi(3);
        let rt = 6.0 * PI * a * a;
        assert!((g[3][3] * rr - (1.0 - 5.0 / 16.0 * x.powi(3))).abs() < tol);
        assert!((g[4][4] * rr - (1.0 - 5.0 / 16.0 * x.powi(3))).abs() < tol);
        assert!((g[5][5] * rr - (1.0 - x.powi(3) / 8.0)).abs() < tol);
        let c = 3.0 / 32.0 * x.powi(4);
        // W_y = c F_x, W_x = -c F_y (z x F), and tr = rt^T.
        assert!((g[4][0] * rt - c).abs() < tol && (g[3][1] * rt + c).abs() < tol);
        assert!((g[0][4] - g[4][0]).abs() == 0.0);
        for (r, q) in [(3, 0), (4, 1), (5, 0), (5, 1), (5, 2), (3, 2), (4, 2)] {
            assert_eq!(g[r][q], 0.0, "({r}, {q})");
        }
        let (img_rt, img_rr) = wall::image_rot::<T>(
            T::ONE,
            T::from_f64(a),
            T::V3_ZERO,
            T::from_f64(2.0 * h * a),
            T::from_f64(h * a),
        );
        let free_rr = 1.0 / rr;
        for r in 0..3 {
            for q in 0..3 {
                let d = if r == q { free_rr } else { 0.0 };
                let s = T::m3_get(img_rr, r, q).to_f64() + d;
                assert!(
                    (s - g[3 + r][3 + q]).abs() * rr < tol,
                    "rr ({r}, {q}) at h/a {h}"
                );
                let t = T::m3_get(img_rt, r, q).to_f64();
                assert!(
                    (t - g[3 + r][q]).abs() * rt < tol,
                    "rt ({r}, {q}) at h/a {h}"
                );
            }
        }
    }
}

#[test]
fn lone_sphere_rotation_f64() {
    lone_rotation::<f64>();
}

#[test]
fn lone_sphere_rotation_f32() {
    lone_rotation::<f32>();
}

/// `<G(x, y)>` over `y` on the sphere `pts` (Blake's tensor, divided by `8 pi eta`).
fn averaged(x: [f64; 3], pts: &[([f64; 3], f64)]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for &(y, w) in pts {
        let g = blake(x, y);
        for p in 0..3 {
            for q in 0..3 {
                m[p][q] += w * g[p][q] / (8.0 * PI);
            }
        }
    }
    m
}

/// The pair rotation blocks (unequal radii, free part and image) against Faxén's laws
/// applied here by finite differences to the test's Blake tensor: `rt_ij = 1/2 curl_x
/// <G(x, y)>_{y on sphere j}` at `x = r_i` (the average by quadrature), `rr_ij = 1/4
/// curl_x curl_y G(r_i, r_j)`; also `rt_ji`. Central differences, step 1e-4 (3e-4 for
/// the mixed second derivatives): agreement within 1e-6 of the block's largest entry.
#[test]
fn rotation_blocks_are_faxen_curls_of_blakes_tensor() {
    let eps = |i: usize, j: usize, k: usize| -> f64 {
        match (i, j, k) {
            (0, 1, 2) | (1, 2, 0) | (2, 0, 1) => 1.0,
            (0, 2, 1) | (2, 1, 0) | (1, 0, 2) => -1.0,
            _ => 0.0,
        }
    };
    let unit = |m: usize| {
        let mut e = [0.0; 3];
        e[m] = 1.0;
        e
    };
    let gl = gauss_legendre(20);
    let cases = [
        ([0.0, 0.0, 2.5], 1.0, [4.0, 1.0, 3.2], 2.0),
        ([0.3, -0.4, 1.2], 0.7, [0.5, 0.2, 4.4], 1.6),
        ([0.0, 0.0, 2.0], 1.0, [0.0, 0.0, 5.5], 1.3),
    ];
    let mut worst = 0.0f64;
    for (ci, ai, cj, aj) in cases {
        let g = dense_grand::<f64>(Hydro::Rpy, 0.0, &[(ci, ai), (cj, aj)]);
        // rt_ij = rows 9..12 (rotation of sphere 0... sphere i = 0), columns 3..6 (force on 1).
        for (xi, xj, aj_, row, col) in [(ci, cj, aj, 6, 3), (cj, ci, ai, 9, 0)] {
            let pts = sphere_points(xj, aj_, &gl, 40);
            let d = 1e-4;
            let mut rt = [[0.0; 3]; 3];
            for m in 0..3 {
                let gp = averaged(add(xi, scale(unit(m), d)), &pts);
                let gm = averaged(sub(xi, scale(unit(m), d)), &pts);
                for k in 0..3 {
                    for n in 0..3 {
                        for l in 0..3 {
                            rt[k][l] += 0.5 * eps(k, m, n) * (gp[n][l] - gm[n][l]) / (2.0 * d);
                        }
                    }
                }
            }
            let big = rt.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
            for k in 0..3 {
                for l in 0..3 {
                    worst = worst.max((g[row + k][col + l] - rt[k][l]).abs() / big);
                }
            }
        }
        // rr_ij: block (rotation of 0, torque on 1) at rows 6..9, columns 9..12.
        let d = 3e-4;
        let mut rr = [[0.0; 3]; 3];
        for p in 0..3 {
            for m in 0..3 {
                let (xp, xm) = (add(ci, scale(unit(p), d)), sub(ci, scale(unit(p), d)));
                let (yp, ym) = (add(cj, scale(unit(m), d)), sub(cj, scale(unit(m), d)));
                let (a, b, c, e) = (blake(xp, yp), blake(xp, ym), blake(xm, yp), blake(xm, ym));
                for k in 0..3 {
                    for l in 0..3 {
                        for q in 0..3 {
                            for n in 0..3 {
                                let s = eps(k, p, q) * eps(l, m, n);
                                if s != 0.0 {
                                    let dd =
                                        (a[q][n] - b[q][n] - c[q][n] + e[q][n]) / (4.0 * d * d);
                                    rr[k][l] += 0.25 * s * dd / (8.0 * PI);
                                }
                            }
                        }
                    }
                }
            }
        }
        let big = rr.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
        for k in 0..3 {
            for l in 0..3 {
                worst = worst.max((g[6 + k][9 + l] - rr[k][l]).abs() / big);
            }
        }
    }
    eprintln!(
        "rotation blocks vs Faxén curls of Blake's tensor: largest relative difference {worst:.1e}"
    );
    assert!(worst < 1e-6, "{worst}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The grand mobility above the wall is positive definite (f64 and f32), spheres
    /// touching, damped or overlapping as in the translational test.
    #[test]
    fn grand_wall_mobility_is_positive_definite(n in 1usize..8, seed in 0u64..1_000_000, lifts in any::<bool>(), overlap in any::<bool>()) {
        let s = configuration(n, seed, 0.0, lifts && !overlap, overlap);
        for level in [Hydro::Rpy, Hydro::FreeDraining] {
            for single in [false, true] {
                let m = 2 * s.len();
                let ok = if single {
                    grand_cholesky::<f32>(level, &s, m)
                } else {
                    grand_cholesky::<f64>(level, &s, m)
                };
                prop_assert!(ok, "{level:?} f32 {single} {s:?}");
            }
        }
    }
}

fn grand_cholesky<T: Real>(level: Hydro, s: &[([f64; 3], f64)], m: usize) -> bool {
    let pos: Vec<T::V3> = s.iter().map(|c| T::v3_from(c.0)).collect();
    let rad: Vec<T> = s.iter().map(|c| T::from_f64(c.1)).collect();
    let mut out = vec![T::M3_ZERO; m * (m + 1) / 2];
    wall::assemble_grand(level, T::ONE, T::ZERO, &pos, &rad, &mut out).unwrap();
    linalg::cholesky::<T>(&mut out, m).is_ok()
}

/// Spins of a lone sphere pushed along the wall (gravity tilted): one overdamped step
/// with `rotation` reports `W = c z x F`, the coupling `c` of `lone_sphere_rotation`.
fn spin_along_wall<T: Real>() {
    let (a, h, rho) = (1.0, 1.8, 2.0);
    let mut p = params::<T>(1e-3, Method::Overdamped, SolverKind::Auto);
    p.wall = Some(Wall::new(T::ZERO));
    p.rotation = true;
    p.gravity = v3::<T>(1.0, 0.0, -1.0);
    let ps = lone_step::<T>(&p, [0.0, 0.0, h], a, rho);
    let fx = 4.0 / 3.0 * PI * a.powi(3) * rho;
    let c = 3.0 / 32.0 * (a / h).powi(4) / (6.0 * PI * a * a);
    let w = f64s::<T>(ps.omega[0]);
    eprintln!(
        "spin along the wall: {w:?}, expected (0, {}, 0) to first order in dt",
        c * fx
    );
    assert!((w[1] / (c * fx) - 1.0).abs() < 1e-2, "{w:?}");
    assert!(w[0].abs() < 1e-12 && w[2].abs() < 1e-12);
}

#[test]
fn spin_along_the_wall_f64() {
    spin_along_wall::<f64>();
}

#[test]
fn spin_along_the_wall_f32() {
    spin_along_wall::<f32>();
}

/// The wall is held as a one-sided constraint in the overdamped projection only: the
/// inertial methods refuse it with a typed error (the grand mobility above the wall is
/// checked on its own, and through the spins of the overdamped step above), and the
/// state is left as it was.
fn stable_grand<T: Real>() {
    let mut p = params::<T>(0.1, Method::RattleStable, SolverKind::Auto);
    p.wall = Some(Wall::new(T::ZERO));
    p.rotation = true;
    let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
        pos: [0.0, 0.0, 2.0],
        radius: 1.0,
        density: 3.0,
    }]);
    let before = ps.clone();
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
    let mut ws = buf.workspace();
    let e = hydrorattle::step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap_err();
    assert!(matches!(e, hydrorattle::StepError::Unsupported(_)), "{e}");
    assert_eq!(ps.pos[0], before.pos[0]);
}

#[test]
fn stable_method_with_a_wall_is_refused_f64() {
    stable_grand::<f64>();
}

#[test]
fn stable_method_with_a_wall_is_refused_f32() {
    stable_grand::<f32>();
}

/// One step of a lone sphere (centre `pos`, radius `a`, density `rho`) with `p`.
fn lone_step<T: Real>(
    p: &hydrorattle::Params<T>,
    pos: [f64; 3],
    a: f64,
    rho: f64,
) -> ParticleSet<T, 1> {
    let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
        pos,
        radius: a,
        density: rho,
    }]);
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(p, 1, 0));
    let mut ws = buf.workspace();
    hydrorattle::step(&mut ps, &bonds, p, &mut ws, &mut NoForce).unwrap();
    ps
}
