//! Validation of the mobility assembly, the linear algebra and the input checks.
//!
//! Every expected value is a closed form written out here (Stokes' law, the RPY
//! two-sphere settling speeds, the far-field formulas of docs/MODEL.md#far-branch, the
//! classical equal-sphere overlapping forms, rigid-body limits) or a direct check such
//! as `A x = b`; nothing is computed by the code under test and then compared with
//! itself. One generic body per check, instantiated for `f32` and `f64` by
//! `precision_tests!` with per-precision tolerances.

use crate::common;

use common::admissible;
use common::fuzz::Rng;
use std::f64::consts::PI;

use hydrorattle::bonds::{Bond, BondSet};
use hydrorattle::linalg::{cholesky, cholesky_solve, lu, lu_solve, sym_get, sym_matvec, tri};
use hydrorattle::mobility::{Hydro, assemble_grand, assemble_tt};
use hydrorattle::{BondError, LinalgError, Particle, ParticleError, ParticleSet, Real};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------
// Tolerances, random numbers, small f64 matrix helpers.
// ---------------------------------------------------------------------------------

/// Tolerances for one precision.
struct Tol {
    /// A closed form evaluated with a handful of roundings (relative).
    exact: f64,
    /// Longer computations: sums over pairs, factorisations, rotated inputs (relative).
    rel: f64,
    /// Step `h` used to approach a limit, and the relative tolerance there.
    h: f64,
    limit: f64,
}

const TOL_F64: Tol = Tol {
    exact: 1e-14,
    rel: 1e-11,
    h: 1e-8,
    limit: 1e-6,
};

const TOL_F32: Tol = Tol {
    exact: 2e-6,
    rel: 2e-4,
    h: 2e-3,
    limit: 3e-2,
};

type M = [[f64; 3]; 3]; // [row][col]

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn ident(s: f64) -> M {
    [[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
}
fn outer(a: [f64; 3], b: [f64; 3]) -> M {
    let mut m = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = a[r] * b[c];
        }
    }
    m
}
fn madd(a: M, b: M) -> M {
    let mut m = a;
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] += b[r][c];
        }
    }
    m
}
fn mscale(a: M, s: f64) -> M {
    let mut m = a;
    for row in &mut m {
        for x in row {
            *x *= s;
        }
    }
    m
}
fn mmul(a: M, b: M) -> M {
    let mut m = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = (0..3).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}
fn mt(a: M) -> M {
    let mut m = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = a[c][r];
        }
    }
    m
}
fn mvec(a: M, v: [f64; 3]) -> [f64; 3] {
    [dot(a[0], v), dot(a[1], v), dot(a[2], v)]
}
fn max_abs(a: M) -> f64 {
    a.iter().flatten().fold(0.0f64, |m, &x| m.max(x.abs()))
}
fn max_diff(a: M, b: M) -> f64 {
    let mut d = 0.0f64;
    for r in 0..3 {
        for c in 0..3 {
            d = d.max((a[r][c] - b[r][c]).abs());
        }
    }
    d
}
/// The matrix of `F -> F x e`.
fn cross_right(e: [f64; 3]) -> M {
    // Column c is (unit_c x e).
    let mut m = [[0.0; 3]; 3];
    for c in 0..3 {
        let mut u = [0.0; 3];
        u[c] = 1.0;
        let col = cross(u, e);
        for r in 0..3 {
            m[r][c] = col[r];
        }
    }
    m
}

fn to_f64<T: Real>(m: T::M3) -> M {
    let mut o = [[0.0; 3]; 3];
    for (r, row) in o.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = T::m3_get(m, r, c).to_f64();
        }
    }
    o
}
fn from_f64<T: Real>(m: M) -> T::M3 {
    let col = |c: usize| T::v3_from([m[0][c], m[1][c], m[2][c]]);
    T::m3_cols(col(0), col(1), col(2))
}

/// Block `(bi, bj)` of a packed symmetric `nb x nb` block matrix, in f64.
fn blk<T: Real>(a: &[T::M3], _nb: usize, bi: usize, bj: usize) -> M {
    to_f64::<T>(sym_get::<T>(a, bi, bj))
}

/// The full scalar matrix (`3 nb` square, row-major) of a block matrix.
fn dense<T: Real>(a: &[T::M3], nb: usize) -> Vec<f64> {
    let n3 = 3 * nb;
    let mut d = vec![0.0; n3 * n3];
    for r in 0..n3 {
        for c in 0..n3 {
            d[r * n3 + c] = T::m3_get(sym_get::<T>(a, r / 3, c / 3), r % 3, c % 3).to_f64();
        }
    }
    d
}

/// Block storage from a dense scalar matrix (`3 nb` square, row-major).
fn blocks_from<T: Real>(d: &[f64], nb: usize) -> Vec<T::M3> {
    let n3 = 3 * nb;
    let mut out = vec![T::M3_ZERO; tri(nb)];
    for bi in 0..nb {
        for bj in 0..=bi {
            let mut m = [[0.0; 3]; 3];
            for (r, row) in m.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = d[(3 * bi + r) * n3 + 3 * bj + c];
                }
            }
            out[tri(bi) + bj] = from_f64::<T>(m);
        }
    }
    out
}

fn quad_form(d: &[f64], x: &[f64]) -> f64 {
    let n = x.len();
    (0..n)
        .map(|r| x[r] * (0..n).map(|c| d[r * n + c] * x[c]).sum::<f64>())
        .sum()
}

fn flat<T: Real>(v: &[T::V3]) -> Vec<f64> {
    v.iter().flat_map(|&x| T::v3_to_f64(x)).collect()
}

fn vecs<T: Real>(x: &[f64]) -> Vec<T::V3> {
    x.chunks(3)
        .map(|c| T::v3_from([c[0], c[1], c[2]]))
        .collect()
}

fn conv<T: Real>(pos: &[[f64; 3]], radii: &[f64]) -> (Vec<T::V3>, Vec<T>) {
    (
        pos.iter().map(|&p| T::v3_from(p)).collect(),
        radii.iter().map(|&a| T::from_f64(a)).collect(),
    )
}

/// Random polydisperse configuration of `n` spheres, radii in [0.5, 2].
///
/// Half the spheres are grown next to an earlier one (dense clusters, near contact);
/// the rest land in a box. With `overlap` a grown sphere may overlap its neighbour
/// (never nested: centre distance at least `|a_i - a_j| + 0.1 min(a_i, a_j)`); without
/// it every pair satisfies `s > a_i + a_j`.
fn random_config(n: usize, seed: u64, overlap: bool) -> (Vec<[f64; 3]>, Vec<f64>) {
    let mut rng = Rng(seed);
    let mut pos: Vec<[f64; 3]> = Vec::with_capacity(n);
    let mut rad: Vec<f64> = Vec::with_capacity(n);
    let side = 4.0 * (n as f64).cbrt() + 4.0;
    while pos.len() < n {
        let a = rng.range(0.5, 2.0);
        let p = if !pos.is_empty() && rng.unit() < 0.5 {
            let j = (rng.next() % pos.len() as u64) as usize;
            let (lo, hi) = if overlap {
                ((a - rad[j]).abs() + 0.1 * a.min(rad[j]), a + rad[j])
            } else {
                (a + rad[j], 1.3 * (a + rad[j]))
            };
            add(pos[j], scale(rng.direction(), rng.range(lo, hi)))
        } else {
            [
                rng.range(0.0, side),
                rng.range(0.0, side),
                rng.range(0.0, side),
            ]
        };
        let ok = pos
            .iter()
            .zip(&rad)
            .all(|(&q, &b)| admissible(norm(sub(p, q)), a, b, overlap));
        if ok {
            pos.push(p);
            rad.push(a);
        }
    }
    (pos, rad)
}

/// A proper rotation from an axis and an angle (Rodrigues).
fn rotation(axis: [f64; 3], angle: f64) -> M {
    let k = scale(axis, 1.0 / norm(axis));
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    madd(
        madd(ident(1.0), mscale(kx, angle.sin())),
        mscale(mmul(kx, kx), 1.0 - angle.cos()),
    )
}

// ---------------------------------------------------------------------------------
// Closed forms, written out from docs/MODEL.md#far-branch and the classical RPY papers.
// ---------------------------------------------------------------------------------

/// Far-field (`s > a_i + a_j`) polydisperse RPY blocks of `docs/MODEL.md`: `(tt, rr, rt_ij)`
/// with `r = r_i - r_j`.
fn far_blocks(eta: f64, ai: f64, aj: f64, r: [f64; 3]) -> (M, M, M) {
    let s = norm(r);
    let e = scale(r, 1.0 / s);
    let ee = outer(e, e);
    let q = (ai * ai + aj * aj) / (s * s);
    let tt = mscale(
        madd(ident(1.0 + q / 3.0), mscale(ee, 1.0 - q)),
        1.0 / (8.0 * PI * eta * s),
    );
    let rr = mscale(
        madd(mscale(ee, 3.0), ident(-1.0)),
        1.0 / (16.0 * PI * eta * s * s * s),
    );
    let rt = mscale(cross_right(e), 1.0 / (8.0 * PI * eta * s * s));
    (tt, rr, rt)
}

// ---------------------------------------------------------------------------------
// Generic test bodies.
// ---------------------------------------------------------------------------------

/// A lone sphere: `U = F / (6 pi eta a)` through assembly and the symmetric product,
/// and the resistance `6 pi eta a` through the Cholesky solve.
fn lone_sphere_stokes<T: Real>(tol: &Tol) {
    let mut worst = 0.0f64;
    for &(eta, a) in &[(1.0, 1.0), (0.37, 2.5), (3.0, 0.125)] {
        let force = [0.7, -1.9, 3.25];
        let (pos, rad) = conv::<T>(&[[1.0, -2.0, 0.5]], &[a]);
        let mut mu = vec![T::M3_ZERO; 1];
        assemble_tt(Hydro::Rpy, T::from_f64(eta), &pos, &rad, &mut mu).unwrap();
        let f = [T::v3_from(force)];
        let mut u = [T::V3_ZERO];
        sym_matvec::<T>(&mu, 1, &f, &mut u);
        let want = scale(force, 1.0 / (6.0 * PI * eta * a));
        let got = T::v3_to_f64(u[0]);
        for c in 0..3 {
            let err = (got[c] - want[c]).abs() / want[c].abs();
            worst = worst.max(err);
            assert!(
                err <= tol.exact,
                "Stokes' law, component {c}: rel error {err:e}"
            );
        }
        // Resistance: F = 6 pi eta a U by the factorised mobility.
        let mut fac = mu.clone();
        cholesky::<T>(&mut fac, 1).unwrap();
        let velocity = [0.25, 0.5, -1.0];
        let mut x = [T::v3_from(velocity)];
        cholesky_solve::<T>(&fac, 1, &mut x);
        let want = scale(velocity, 6.0 * PI * eta * a);
        let got = T::v3_to_f64(x[0]);
        for c in 0..3 {
            let err = (got[c] - want[c]).abs() / want[c].abs();
            worst = worst.max(err);
            assert!(
                err <= tol.exact * 4.0,
                "resistance, component {c}: rel error {err:e}"
            );
        }
        // All three levels agree on a lone sphere.
        for level in [Hydro::FreeDraining, Hydro::Oseen] {
            let mut m2 = vec![T::M3_ZERO; 1];
            assemble_tt(level, T::from_f64(eta), &pos, &rad, &mut m2).unwrap();
            assert_eq!(m2[0], mu[0]);
        }
    }
    eprintln!("Stokes' law: worst relative error {worst:.2e}");
}

/// Two equal spheres, equal forces: settling speed along and across the line of
/// centres relative to a lone sphere's, against the RPY closed forms (far branch)
/// and the classical Rotne-Prager overlapping forms (`r < 2a`).
fn two_equal_spheres_settling<T: Real>(tol: &Tol) {
    let mut rng = Rng(7);
    let (eta, a) = (0.8, 1.3);
    let u0 = 1.0 / (6.0 * PI * eta * a);
    let mut worst = 0.0f64;
    for &x in &[0.25, 0.8, 1.5, 1.999, 2.0001, 2.2, 3.0, 5.0, 10.0, 100.0] {
        let r = x * a;
        let e = rng.direction();
        let perp = {
            let t = cross(e, rng.direction());
            scale(t, 1.0 / norm(t))
        };
        let centre = [0.3, -1.1, 2.0];
        let pos = [centre, add(centre, scale(e, r))];
        let (p, rad) = conv::<T>(&pos, &[a, a]);
        let mut mu = vec![T::M3_ZERO; 4];
        assemble_tt(Hydro::Rpy, T::from_f64(eta), &p, &rad, &mut mu).unwrap();
        let (ar, ar3) = (a / r, (a / r).powi(3));
        let (want_par, want_perp) = if r > 2.0 * a {
            (1.0 + 1.5 * ar - ar3, 1.0 + 0.75 * ar + 0.5 * ar3)
        } else {
            (2.0 - 3.0 * r / (16.0 * a), 2.0 - 9.0 * r / (32.0 * a))
        };
        for (dir, want) in [(e, want_par), (perp, want_perp)] {
            let f = [T::v3_from(scale(dir, 2.0)), T::v3_from(scale(dir, 2.0))];
            let mut u = [T::V3_ZERO; 2];
            sym_matvec::<T>(&mu, 2, &f, &mut u);
            for ui in u {
                let v = T::v3_to_f64(ui);
                let along = dot(v, dir) / (2.0 * u0);
                let off = norm(sub(v, scale(dir, dot(v, dir)))) / (2.0 * u0);
                let err = ((along - want) / want).abs();
                worst = worst.max(err);
                assert!(
                    err <= tol.exact * 8.0,
                    "r/a = {x}: speed ratio {along} vs {want}"
                );
                assert!(off <= tol.exact * 8.0, "r/a = {x}: sideways drift {off:e}");
            }
        }
    }
    eprintln!("two equal spheres: worst relative error {worst:.2e}");
}

/// Polydisperse pair: every block of the 12 x 12 grand mobility against the far-field
/// formulas of `docs/MODEL.md`, both orderings of big and small.
fn polydisperse_pair_far<T: Real>(tol: &Tol) {
    let mut worst = 0.0f64;
    let mut rng = Rng(11);
    let eta = 1.7;
    for &(a0, a1, gap) in &[
        (2.0, 0.5, 1.001),
        (0.6, 1.9, 1.3),
        (1.0, 1.26, 4.0),
        (1.5, 0.7, 20.0),
    ] {
        let e = rng.direction();
        let r0 = [0.5, 0.25, -0.75];
        let r1 = add(r0, scale(e, gap * (a0 + a1)));
        let (pos, rad) = conv::<T>(&[r0, r1], &[a0, a1]);
        let mut g = vec![T::M3_ZERO; 16];
        assemble_grand(Hydro::Rpy, T::from_f64(eta), &pos, &rad, &mut g).unwrap();
        // The test's own positions are those seen by the kernel (exact conversion).
        let p: Vec<[f64; 3]> = pos.iter().map(|&v| T::v3_to_f64(v)).collect();
        let a = [rad[0].to_f64(), rad[1].to_f64()];
        let (tt01, rr01, rt01) = far_blocks(eta, a[0], a[1], sub(p[0], p[1]));
        let (tt10, rr10, rt10) = far_blocks(eta, a[1], a[0], sub(p[1], p[0]));
        let zero = [[0.0; 3]; 3];
        let mut want = [[zero; 4]; 4];
        for i in 0..2 {
            want[i][i] = ident(1.0 / (6.0 * PI * eta * a[i]));
            want[2 + i][2 + i] = ident(1.0 / (8.0 * PI * eta * a[i].powi(3)));
        }
        want[0][1] = tt01;
        want[1][0] = tt10;
        want[2][3] = rr01;
        want[3][2] = rr10;
        want[2][1] = rt01; // rotation of 0 from force on 1
        want[3][0] = rt10; // rotation of 1 from force on 0
        want[0][3] = mt(rt10); // tr_01 = rt_10^T
        want[1][2] = mt(rt01);
        let scale_all = want
            .iter()
            .flatten()
            .fold(0.0f64, |m, &b| m.max(max_abs(b)));
        for (bi, row) in want.iter().enumerate() {
            for (bj, &w) in row.iter().enumerate() {
                let got = blk::<T>(&g, 4, bi, bj);
                let err = max_diff(got, w) / max_abs(w).max(1e-3 * scale_all);
                worst = worst.max(err);
                assert!(
                    err <= tol.exact * 16.0,
                    "radii ({a0}, {a1}), gap {gap}: block ({bi},{bj}) rel error {err:e}\n got {got:?}\nwant {w:?}"
                );
            }
        }
        // The translation-only path gives the same tt blocks.
        let mut t = vec![T::M3_ZERO; 4];
        assemble_tt(Hydro::Rpy, T::from_f64(eta), &pos, &rad, &mut t).unwrap();
        for bi in 0..2 {
            for bj in 0..2 {
                assert_eq!(sym_get::<T>(&t, bi, bj), sym_get::<T>(&g, bi, bj));
            }
        }
    }
    eprintln!("polydisperse far blocks: worst relative error {worst:.2e}");
}

/// Equal overlapping spheres: the classical Rotne-Prager regularised blocks
/// (`r < 2a`): `tt = [(1 - 9r/32a) I + (3r/32a) ee] / (6 pi eta a)`,
/// `rr = [(1 - 27r/32a + 5r^3/64a^3) I + (9r/32a - 3r^3/64a^3) ee] / (8 pi eta a^3)`,
/// `rt F = (r/a)(1 - 3r/8a) (F x e) / (16 pi eta a^2)`.
fn equal_overlapping_blocks<T: Real>(tol: &Tol) {
    let mut worst = 0.0f64;
    let mut rng = Rng(3);
    let (eta, a) = (1.2, 0.9);
    for &x in &[0.2, 0.7, 1.0, 1.6, 1.99] {
        let r = x * a;
        let e = rng.direction();
        let r0 = [1.0, 2.0, 3.0];
        let (pos, rad) = conv::<T>(&[add(r0, scale(e, r)), r0], &[a, a]);
        let p: Vec<[f64; 3]> = pos.iter().map(|&v| T::v3_to_f64(v)).collect();
        let d = sub(p[0], p[1]);
        let (s, e) = (norm(d), scale(d, 1.0 / norm(d)));
        let ee = outer(e, e);
        let tt = mscale(
            madd(
                ident(1.0 - 9.0 * s / (32.0 * a)),
                mscale(ee, 3.0 * s / (32.0 * a)),
            ),
            1.0 / (6.0 * PI * eta * a),
        );
        let q3 = (s / a).powi(3);
        let rr = mscale(
            madd(
                ident(1.0 - 27.0 * s / (32.0 * a) + 5.0 * q3 / 64.0),
                mscale(ee, 9.0 * s / (32.0 * a) - 3.0 * q3 / 64.0),
            ),
            1.0 / (8.0 * PI * eta * a.powi(3)),
        );
        let rt = mscale(
            cross_right(e),
            (s / a) * (1.0 - 3.0 * s / (8.0 * a)) / (16.0 * PI * eta * a * a),
        );
        let mut g = vec![T::M3_ZERO; 16];
        assemble_grand(Hydro::Rpy, T::from_f64(eta), &pos, &rad, &mut g).unwrap();
        for (name, got, want) in [
            ("tt", blk::<T>(&g, 4, 0, 1), tt),
            ("rr", blk::<T>(&g, 4, 2, 3), rr),
            ("rt_01", blk::<T>(&g, 4, 2, 1), rt),
            // rt_10 uses -e: the same magnitude, opposite sign.
            ("rt_10", blk::<T>(&g, 4, 3, 0), mscale(rt, -1.0)),
        ] {
            let err = max_diff(got, want) / max_abs(want);
            worst = worst.max(err);
            assert!(
                err <= tol.exact * 64.0,
                "r/a = {x}: {name} rel error {err:e}"
            );
        }
    }
    eprintln!("equal overlapping blocks: worst relative error {worst:.2e}");
}

/// Polydisperse overlapping branch at its two ends: continuous with the far form at
/// contact, and at the nesting boundary `s -> |a_i - a_j|` the rigid-body limits (the
/// small sphere moves with the big one): `tt -> I/(6 pi eta A)`, `rr -> I/(8 pi eta A^3)`,
/// rotation of the big sphere from a force on the small one `= (r_small - r_big) x F /
/// (8 pi eta A^3)`, rotation of the small one from a force on the big one `-> 0`.
fn polydisperse_overlap_limits<T: Real>(tol: &Tol) {
    let mut worst = 0.0f64;
    let mut rng = Rng(5);
    let eta = 0.9;
    for &(big_first, ab, asm) in &[(true, 2.0, 0.5), (false, 1.7, 1.1), (true, 1.26, 1.0)] {
        let e = rng.direction();
        let c = [-0.5, 1.5, 0.25];
        let build = |s: f64| -> (Vec<[f64; 3]>, Vec<f64>, Vec<T::M3>) {
            let other = add(c, scale(e, s));
            let (p, a) = if big_first {
                (vec![c, other], vec![ab, asm])
            } else {
                (vec![other, c], vec![asm, ab])
            };
            let (pos, rad) = conv::<T>(&p, &a);
            let mut g = vec![T::M3_ZERO; 16];
            assemble_grand(Hydro::Rpy, T::from_f64(eta), &pos, &rad, &mut g).unwrap();
            let p: Vec<[f64; 3]> = pos.iter().map(|&v| T::v3_to_f64(v)).collect();
            let a: Vec<f64> = rad.iter().map(|&x| x.to_f64()).collect();
            (p, a, g)
        };
        let (big, small) = if big_first { (0, 1) } else { (1, 0) };
        // Contact: just inside against the far formula at the same distance.
        let (p, a, g) = build((ab + asm) * (1.0 - tol.h));
        let (tt, rr, rt01) = far_blocks(eta, a[0], a[1], sub(p[0], p[1]));
        let (_, _, rt10) = far_blocks(eta, a[1], a[0], sub(p[1], p[0]));
        for (name, got, want) in [
            ("tt", blk::<T>(&g, 4, 0, 1), tt),
            ("rr", blk::<T>(&g, 4, 2, 3), rr),
            ("rt_01", blk::<T>(&g, 4, 2, 1), rt01),
            ("rt_10", blk::<T>(&g, 4, 3, 0), rt10),
        ] {
            let err = max_diff(got, want) / max_abs(want);
            worst = worst.max(err);
            assert!(
                err <= tol.limit,
                "contact ({ab}, {asm}): {name} rel error {err:e}"
            );
        }
        // Nesting boundary.
        let (p, _, g) = build((ab - asm) * (1.0 + tol.h));
        let big_tt = 1.0 / (6.0 * PI * eta * ab);
        let big_rr = 1.0 / (8.0 * PI * eta * ab.powi(3));
        let arm = sub(p[small], p[big]);
        let lever = mscale(cross_right(arm), -big_rr); // F -> arm x F
        let zero = [[0.0; 3]; 3];
        for (name, got, want, scale_ref) in [
            ("tt", blk::<T>(&g, 4, 0, 1), ident(big_tt), big_tt),
            ("rr", blk::<T>(&g, 4, 2, 3), ident(big_rr), big_rr),
            (
                "rt_big,small",
                blk::<T>(&g, 4, 2 + big, small),
                lever,
                max_abs(lever),
            ),
            (
                "rt_small,big",
                blk::<T>(&g, 4, 2 + small, big),
                zero,
                max_abs(lever),
            ),
        ] {
            let err = max_diff(got, want) / scale_ref;
            worst = worst.max(err);
            assert!(
                err <= tol.limit,
                "nesting limit ({ab}, {asm}): {name} rel error {err:e}"
            );
        }
    }
    eprintln!("overlap branch limits: worst relative error {worst:.2e}");
}

/// Oseen and free-draining off-diagonal blocks against their closed forms.
fn cheaper_levels<T: Real>(tol: &Tol) {
    let (eta, a0, a1) = (1.1, 0.8, 1.7);
    let r0 = [0.0, 0.0, 0.0];
    let r1 = [1.5, -2.0, 2.5];
    let (pos, rad) = conv::<T>(&[r0, r1], &[a0, a1]);
    let d = sub(r0, r1);
    let s = norm(d);
    let e = scale(d, 1.0 / s);
    let oseen = mscale(madd(ident(1.0), outer(e, e)), 1.0 / (8.0 * PI * eta * s));
    let mut m = vec![T::M3_ZERO; 4];
    assemble_tt(Hydro::Oseen, T::from_f64(eta), &pos, &rad, &mut m).unwrap();
    let err = max_diff(blk::<T>(&m, 2, 0, 1), oseen) / max_abs(oseen);
    assert!(err <= tol.exact * 16.0, "Oseen block rel error {err:e}");
    assemble_tt(Hydro::FreeDraining, T::from_f64(eta), &pos, &rad, &mut m).unwrap();
    assert_eq!(blk::<T>(&m, 2, 0, 1), [[0.0; 3]; 3]);
    assert_eq!(blk::<T>(&m, 2, 1, 0), [[0.0; 3]; 3]);
    let want = 1.0 / (6.0 * PI * eta * a1);
    let got = blk::<T>(&m, 2, 1, 1);
    assert!((got[1][1] - want).abs() <= tol.exact * want);
}

/// Largest `|A_rc - A_cr|` relative to the largest entry, over the assembled tt and
/// grand matrices of every level, for configurations with and without overlapping
/// pairs. Storage is packed (one triangle), so what can break symmetry is a stored
/// block that should be symmetric and is not: every tt and rr block (diagonal and
/// off-diagonal) is compared with its own transpose. The kernel's hydrodynamic metric
/// reads tt blocks from either triangle without transposing, relying on this.
fn worst_asymmetry<T: Real>() -> f64 {
    let mut worst = 0.0f64;
    for (seed, overlap) in [(1, false), (2, true), (3, true)] {
        let (p, r) = random_config(12, seed, overlap);
        let (pos, rad) = conv::<T>(&p, &r);
        let n = pos.len();
        for level in [Hydro::Rpy, Hydro::Oseen, Hydro::FreeDraining] {
            let mut t = vec![T::M3_ZERO; tri(n)];
            assemble_tt(level, T::ONE, &pos, &rad, &mut t).unwrap();
            let mut g = vec![T::M3_ZERO; tri(2 * n)];
            assemble_grand(level, T::ONE, &pos, &rad, &mut g).unwrap();
            for (a, nb) in [(&t, n), (&g, 2 * n)] {
                let big = dense::<T>(a, nb)
                    .iter()
                    .fold(0.0f64, |m, &v| m.max(v.abs()));
                for bi in 0..nb {
                    for bj in 0..=bi {
                        if (bi < n) != (bj < n) {
                            continue; // rt blocks: not symmetric by nature
                        }
                        let m = to_f64::<T>(a[tri(bi) + bj]);
                        for (r, c) in [(1, 0), (2, 0), (2, 1)] {
                            worst = worst.max((m[r][c] - m[c][r]).abs() / big);
                        }
                    }
                }
            }
        }
    }
    worst
}

/// The assembled tt and grand matrices are symmetric (to rounding).
fn symmetry<T: Real>(tol: &Tol) {
    let w = worst_asymmetry::<T>();
    eprintln!("worst asymmetry {w:.2e}");
    assert!(w <= tol.exact, "assembled mobility asymmetric by {w:e}");
}

/// "Symmetric by construction": every entry equals its mirror bit for bit.
fn exact_symmetry<T: Real>(_tol: &Tol) {
    let w = worst_asymmetry::<T>();
    assert!(
        w == 0.0,
        "assembled mobility not exactly symmetric: worst |A_rc - A_cr| / max|A| = {w:e}"
    );
}

/// Rotating the configuration by `Q` rotates every 3x3 block: `mu' = Q mu Q^T`
/// (tt, rr and the pseudo-tensor rt alike, `Q` proper). Translating it changes nothing.
fn rotation_covariance<T: Real>(tol: &Tol) {
    for (seed, overlap) in [(21, false), (22, true)] {
        let (p, r) = random_config(9, seed, overlap);
        let mut rng = Rng(seed + 100);
        let q = rotation(rng.direction(), rng.range(0.3, 3.0));
        // Rotate about a point inside the cluster, then shift.
        let rotated: Vec<[f64; 3]> = p
            .iter()
            .map(|&x| add(mvec(q, sub(x, p[0])), [3.0, -1.0, 0.5]))
            .collect();
        let (pos, rad) = conv::<T>(&p, &r);
        let (pos_q, _) = conv::<T>(&rotated, &r);
        let n = pos.len();
        let mut g = vec![T::M3_ZERO; 4 * n * n];
        let mut gq = vec![T::M3_ZERO; 4 * n * n];
        assemble_grand(Hydro::Rpy, T::ONE, &pos, &rad, &mut g).unwrap();
        assemble_grand(Hydro::Rpy, T::ONE, &pos_q, &rad, &mut gq).unwrap();
        let m = 2 * n;
        let global = (0..m * m).fold(0.0f64, |a, k| a.max(max_abs(to_f64::<T>(g[k]))));
        let mut worst = 0.0f64;
        for bi in 0..m {
            for bj in 0..m {
                let want = mmul(mmul(q, blk::<T>(&g, m, bi, bj)), mt(q));
                let got = blk::<T>(&gq, m, bi, bj);
                let err = max_diff(got, want) / max_abs(want).max(1e-2 * global);
                worst = worst.max(err);
            }
        }
        eprintln!("rotation covariance (overlap {overlap}): worst block rel error {worst:.2e}");
        assert!(worst <= tol.rel, "rotation covariance: {worst:e}");
    }
}

/// Positive definiteness of RPY (tt and grand): the Cholesky factorisation succeeds,
/// `x^T mu x > 0` for random `x`, and the factor solves `mu x = b`.
fn rpy_positive_definite<T: Real>(n: usize, seed: u64, overlap: bool, tol: &Tol) {
    let (p, r) = random_config(n, seed, overlap);
    let (pos, rad) = conv::<T>(&p, &r);
    let mut rng = Rng(seed ^ 0xA5A5);
    let mut t = vec![T::M3_ZERO; n * n];
    assemble_tt(Hydro::Rpy, T::ONE, &pos, &rad, &mut t).unwrap();
    let mut g = vec![T::M3_ZERO; 4 * n * n];
    assemble_grand(Hydro::Rpy, T::ONE, &pos, &rad, &mut g).unwrap();
    for (name, a, nb) in [("tt", t, n), ("grand", g, 2 * n)] {
        let d = dense::<T>(&a, nb);
        let n3 = 3 * nb;
        for _ in 0..4 {
            let x: Vec<f64> = (0..n3).map(|_| rng.range(-1.0, 1.0)).collect();
            let q = quad_form(&d, &x);
            assert!(q > 0.0, "{name}, n = {n}, seed {seed}: x^T mu x = {q:e}");
        }
        let mut fac = a.clone();
        let res = cholesky::<T>(&mut fac, nb);
        assert!(
            res.is_ok(),
            "{name}, n = {n}, seed {seed}, overlap {overlap}: {res:?}"
        );
        let b: Vec<f64> = (0..n3).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut x = vecs::<T>(&b);
        cholesky_solve::<T>(&fac, nb, &mut x);
        let xf = flat::<T>(&x);
        let dmax = d.iter().fold(0.0f64, |m, &v| m.max(v.abs()));
        let xmax = xf.iter().fold(0.0f64, |m, &v| m.max(v.abs()));
        for row in 0..n3 {
            let ax: f64 = (0..n3).map(|c| d[row * n3 + c] * xf[c]).sum();
            let err = (ax - b[row]).abs() / (dmax * xmax * n3 as f64);
            assert!(
                err <= tol.rel,
                "{name}: residual of mu x = b at row {row}: {err:e}"
            );
        }
    }
}

/// The Oseen level at close range is not positive definite: a 2x2x2 cube of touching
/// unit spheres. The outward radial force pattern has a negative quadratic form, and
/// `cholesky` reports it as a typed error (RPY on the same spheres factorises).
fn oseen_close_range_fails<T: Real>(_tol: &Tol) {
    let mut p = Vec::new();
    for x in 0..2 {
        for y in 0..2 {
            for z in 0..2 {
                p.push([2.0 * x as f64, 2.0 * y as f64, 2.0 * z as f64]);
            }
        }
    }
    let r = vec![1.0; 8];
    let (pos, rad) = conv::<T>(&p, &r);
    let radial: Vec<f64> = p.iter().flat_map(|&q| sub(q, [1.0, 1.0, 1.0])).collect();
    let mut oseen = vec![T::M3_ZERO; 64];
    assemble_tt(Hydro::Oseen, T::ONE, &pos, &rad, &mut oseen).unwrap();
    let q = quad_form(&dense::<T>(&oseen, 8), &radial);
    assert!(
        q < 0.0,
        "Oseen radial quadratic form {q:e} should be negative"
    );
    match cholesky::<T>(&mut oseen, 8) {
        Err(LinalgError::NotPositiveDefinite { row }) => assert!(row < 24),
        other => panic!("Oseen cube: expected NotPositiveDefinite, got {other:?}"),
    }
    let mut rpy = vec![T::M3_ZERO; 64];
    assemble_tt(Hydro::Rpy, T::ONE, &pos, &rad, &mut rpy).unwrap();
    assert!(quad_form(&dense::<T>(&rpy, 8), &radial) > 0.0);
    cholesky::<T>(&mut rpy, 8).expect("RPY on touching spheres is positive definite");
    // The grand Oseen mobility fails the same way.
    let mut grand = vec![T::M3_ZERO; 256];
    assemble_grand(Hydro::Oseen, T::ONE, &pos, &rad, &mut grand).unwrap();
    assert!(matches!(
        cholesky::<T>(&mut grand, 16),
        Err(LinalgError::NotPositiveDefinite { .. })
    ));
    // Two overlapping equal spheres closer than 1.5 a: the antisymmetric mode along the
    // line of centres has eigenvalue 1/(6 pi a) - 1/(4 pi s) < 0.
    let (pos, rad) = conv::<T>(&[[0.0, 0.0, 0.0], [0.0, 1.2, 0.0]], &[1.0, 1.0]);
    let mut m = vec![T::M3_ZERO; 4];
    assemble_tt(Hydro::Oseen, T::ONE, &pos, &rad, &mut m).unwrap();
    assert!(matches!(
        cholesky::<T>(&mut m, 2),
        Err(LinalgError::NotPositiveDefinite { .. })
    ));
}

/// One sphere inside another: assembly reports `Nested` naming both (RPY).
fn nested_assembly_error<T: Real>(_tol: &Tol) {
    let p = [
        [0.0, 0.0, 0.0],
        [5.0, 0.0, 0.0],
        [0.5, 0.2, 0.0],
        [10.0, 0.0, 0.0],
    ];
    let r = [2.0, 1.0, 1.0, 1.0]; // sphere 2 lies inside sphere 0
    let (pos, rad) = conv::<T>(&p, &r);
    let mut t = vec![T::M3_ZERO; 16];
    assert_eq!(
        assemble_tt(Hydro::Rpy, T::ONE, &pos, &rad, &mut t),
        Err(ParticleError::Nested { i: 0, j: 2 })
    );
    let mut g = vec![T::M3_ZERO; 64];
    assert_eq!(
        assemble_grand(Hydro::Rpy, T::ONE, &pos, &rad, &mut g),
        Err(ParticleError::Nested { i: 0, j: 2 })
    );
    // Internally tangent (s = |a_i - a_j|) counts as nested; coincident equal spheres too.
    let (pos, rad) = conv::<T>(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], &[2.0, 1.0]);
    let mut t = vec![T::M3_ZERO; 4];
    assert_eq!(
        assemble_tt(Hydro::Rpy, T::ONE, &pos, &rad, &mut t),
        Err(ParticleError::Nested { i: 0, j: 1 })
    );
    let (pos, rad) = conv::<T>(&[[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]], &[1.0, 1.0]);
    assert_eq!(
        assemble_tt(Hydro::Rpy, T::ONE, &pos, &rad, &mut t),
        Err(ParticleError::Nested { i: 0, j: 1 })
    );
}

/// docs/MODEL.md#nested-spheres: nesting is invalid, whatever the hydrodynamic level.
/// (Today Oseen and free-draining assemble it; with coincident centres the Oseen
/// blocks come out NaN while assembly returns `Ok`.)
fn nested_assembly_error_cheaper_levels<T: Real>(_tol: &Tol) {
    for (p1, a1) in [([0.0, 0.0, 0.0], 2.0), ([0.5, 0.0, 0.0], 1.0)] {
        let (pos, rad) = conv::<T>(&[[0.0, 0.0, 0.0], p1], &[2.0, a1]);
        for level in [Hydro::Oseen, Hydro::FreeDraining] {
            let mut t = vec![T::M3_ZERO; 4];
            let res = assemble_tt(level, T::ONE, &pos, &rad, &mut t);
            let finite = dense::<T>(&t, 2).iter().all(|x| x.is_finite());
            assert_eq!(
                res,
                Err(ParticleError::Nested { i: 0, j: 1 }),
                "{level:?}, second centre {p1:?}: blocks finite: {finite}"
            );
        }
    }
}

/// Each invalid particle input gives its own typed error naming the particle(s).
fn particle_validation<T: Real>(_tol: &Tol) {
    let f = T::from_f64;
    let ok = |x: f64| Particle::<T>::new(T::v3_from([x, 0.0, 0.0]), f(1.0), f(2.0));
    let mut set = ParticleSet::<T, 4>::new();
    set.push(ok(0.0)).unwrap();
    set.push(ok(3.0)).unwrap();
    // NaN position: rejected at push, handed back, set unchanged.
    let bad = Particle::<T>::new(T::v3(f(1.0), f(f64::NAN), f(0.0)), f(1.0), f(1.0));
    let (back, err) = set.push(bad).unwrap_err();
    assert_eq!(err, ParticleError::NonFinite { particle: 2 });
    assert!(
        T::xyz(back.position)[1].to_f64().is_nan(),
        "the rejected particle is handed back"
    );
    assert_eq!(set.len(), 2);
    // Infinite velocity, infinite radius.
    let mut v = ok(6.0);
    v.velocity = T::v3(f(0.0), f(f64::INFINITY), f(0.0));
    assert_eq!(
        set.push(v).unwrap_err().1,
        ParticleError::NonFinite { particle: 2 }
    );
    let r = Particle::<T>::new(T::v3_from([6.0, 0.0, 0.0]), f(f64::INFINITY), f(1.0));
    assert_eq!(
        set.push(r).unwrap_err().1,
        ParticleError::NonFinite { particle: 2 }
    );
    // Radius zero and negative.
    for a in [0.0, -1.0] {
        let p = Particle::<T>::new(T::v3_from([6.0, 0.0, 0.0]), f(a), f(1.0));
        assert_eq!(
            set.push(p).unwrap_err().1,
            ParticleError::BadRadius { particle: 2 }
        );
    }
    // Negative density (zero is allowed: a massless bead for the overdamped methods).
    let p = Particle::<T>::new(T::v3_from([6.0, 0.0, 0.0]), f(1.0), f(-0.5));
    assert_eq!(
        set.push(p).unwrap_err().1,
        ParticleError::BadDensity { particle: 2 }
    );
    set.push(Particle::new(T::v3_from([6.0, 0.0, 0.0]), f(1.0), f(0.0)))
        .unwrap();
    set.push(ok(9.0)).unwrap();
    assert_eq!(set.push(ok(12.0)).unwrap_err().1, ParticleError::Full);
    assert_eq!(set.validate(false), Ok(()));
    // The same checks through from_slice, at the right index.
    let mk = |list: &[(f64, f64, f64)]| -> Vec<Particle<T>> {
        list.iter()
            .map(|&(x, a, rho)| Particle::new(T::v3_from([x, 0.0, 0.0]), f(a), f(rho)))
            .collect()
    };
    let base = [(0.0, 1.0, 1.0), (3.0, 1.0, 1.0), (6.0, 1.0, 1.0)];
    let mut l = base;
    l[1].1 = 0.0;
    assert_eq!(
        ParticleSet::<T, 4>::from_slice(&mk(&l), false).unwrap_err(),
        ParticleError::BadRadius { particle: 1 }
    );
    let mut l = base;
    l[2].2 = -1.0;
    assert_eq!(
        ParticleSet::<T, 4>::from_slice(&mk(&l), false).unwrap_err(),
        ParticleError::BadDensity { particle: 2 }
    );
    let mut l = base;
    l[2].0 = f64::NAN;
    assert_eq!(
        ParticleSet::<T, 4>::from_slice(&mk(&l), false).unwrap_err(),
        ParticleError::NonFinite { particle: 2 }
    );
    // Nested: always an error, overlap allowed or not; overlap only when not allowed.
    let nested = [(0.0, 2.0, 1.0), (5.0, 1.0, 1.0), (0.8, 1.0, 1.0)];
    for allow in [false, true] {
        assert_eq!(
            ParticleSet::<T, 4>::from_slice(&mk(&nested), allow).unwrap_err(),
            ParticleError::Nested { i: 0, j: 2 }
        );
    }
    let overlapping = [(0.0, 1.0, 1.0), (5.0, 1.0, 1.0), (6.5, 1.0, 1.0)];
    assert_eq!(
        ParticleSet::<T, 4>::from_slice(&mk(&overlapping), false).unwrap_err(),
        ParticleError::Overlap { i: 1, j: 2 }
    );
    assert!(ParticleSet::<T, 4>::from_slice(&mk(&overlapping), true).is_ok());
    // validate() catches a state corrupted after construction.
    let mut s = ParticleSet::<T, 4>::from_slice(&mk(&base), false).unwrap();
    s.pos[1] = T::v3(f(f64::NAN), f(0.0), f(0.0));
    assert_eq!(
        s.validate(false),
        Err(ParticleError::NonFinite { particle: 1 })
    );
    let mut s = ParticleSet::<T, 4>::from_slice(&mk(&base), false).unwrap();
    s.omega[2] = T::v3(f(0.0), f(0.0), f(f64::INFINITY));
    assert_eq!(
        s.validate(false),
        Err(ParticleError::NonFinite { particle: 2 })
    );
    // Mass = 4/3 pi a^3 rho.
    let s = ParticleSet::<T, 4>::from_slice(&mk(&[(0.0, 1.5, 2.0)]), false).unwrap();
    let want = 4.0 / 3.0 * PI * 1.5f64.powi(3) * 2.0;
    assert!((s.mass(0).to_f64() - want).abs() <= 1e-5 * want);
}

/// Each invalid bond gives its own typed error naming the bond and the particle.
fn bond_validation<T: Real>(_tol: &Tol) {
    let f = T::from_f64;
    let bond = |i, j, d: f64| Bond { i, j, length: f(d) };
    let mut b = BondSet::<T, 4>::new();
    b.push(bond(0, 1, 2.0), 4).unwrap();
    b.push(bond(1, 2, 2.0), 4).unwrap();
    let (back, e) = b.push(bond(2, 2, 2.0), 4).unwrap_err();
    assert_eq!(
        e,
        BondError::SelfBond {
            bond: 2,
            particle: 2
        }
    );
    assert_eq!(back, bond(2, 2, 2.0));
    assert_eq!(
        b.push(bond(1, 7, 2.0), 4).unwrap_err().1,
        BondError::OutOfRange {
            bond: 2,
            particle: 7
        }
    );
    assert_eq!(
        b.push(bond(2, 1, 2.0), 4).unwrap_err().1,
        BondError::Duplicate { bond: 2, other: 1 }
    );
    assert_eq!(
        b.push(bond(0, 1, 3.0), 4).unwrap_err().1,
        BondError::Duplicate { bond: 2, other: 0 }
    );
    // Zero is a spring's rest length: the list takes it, a constrained step refuses it
    // (tests/kernel/springs_thermal.rs).
    for d in [-1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(
            b.push(bond(2, 3, d), 4).unwrap_err().1,
            BondError::BadLength { bond: 2 }
        );
    }
    assert_eq!(b.len(), 2, "rejected bonds are not stored");
    b.push(bond(2, 3, 2.0), 4).unwrap();
    b.push(bond(3, 0, 2.0), 4).unwrap();
    assert_eq!(b.push(bond(0, 2, 2.0), 4).unwrap_err().1, BondError::Full);
    assert_eq!(b.validate(4), Ok(()));
    assert_eq!(
        b.validate(3),
        Err(BondError::OutOfRange {
            bond: 2,
            particle: 3
        })
    );
    // Violated: a chain built from positions, then its last bead pulled outward by
    // delta along the last bond: residual delta / d on that bond only.
    let p = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 3.0, 0.0],
        [2.0, 3.0, 2.5],
    ];
    let mut pos: Vec<T::V3> = p.iter().map(|&x| T::v3_from(x)).collect();
    let chain = BondSet::<T, 3>::chain(&pos).unwrap();
    assert_eq!(chain.check_satisfied(&pos, f(1e-6)), Ok(()));
    let delta = 0.125;
    pos[3] = T::v3_from([2.0, 3.0, 2.5 + delta]);
    match chain.check_satisfied(&pos, f(1e-3)) {
        Err(BondError::Violated { bond, residual }) => {
            assert_eq!(bond, 2);
            assert!(
                (residual - delta / 2.5).abs() <= 1e-6,
                "residual {residual}"
            );
        }
        other => panic!("expected Violated, got {other:?}"),
    }
    assert_eq!(chain.check_satisfied(&pos, f(0.06)), Ok(()));
    // A ring needs three particles; a tree needs parents below children.
    assert!(BondSet::<T, 3>::ring(&pos[..2]).is_err());
    assert_eq!(
        BondSet::<T, 3>::tree(&pos, &[None, Some(0), Some(3), Some(1)]).unwrap_err(),
        BondError::BadTree { particle: 2 }
    );
}

/// Block Cholesky: `A x = b` checked directly on a random SPD matrix; `sym_matvec`
/// against the dense product; an indefinite and a NaN matrix give typed errors.
fn cholesky_direct_check<T: Real>(tol: &Tol) {
    let mut rng = Rng(99);
    let nb = 7;
    let n3 = 3 * nb;
    let g: Vec<f64> = (0..n3 * n3).map(|_| rng.range(-1.0, 1.0)).collect();
    let mut a = vec![0.0; n3 * n3];
    for r in 0..n3 {
        for c in 0..n3 {
            a[r * n3 + c] = (0..n3).map(|k| g[r * n3 + k] * g[c * n3 + k]).sum::<f64>()
                + if r == c { 0.5 } else { 0.0 };
        }
    }
    let blocks = blocks_from::<T>(&a, nb);
    let a = dense::<T>(&blocks, nb); // exactly the matrix the kernel sees
    // Packed storage holds only the lower triangle.
    let lower_only = blocks.clone();
    let x: Vec<f64> = (0..n3).map(|_| rng.range(-1.0, 1.0)).collect();
    let mut y = vec![T::V3_ZERO; nb];
    sym_matvec::<T>(&lower_only, nb, &vecs::<T>(&x), &mut y);
    let yf = flat::<T>(&y);
    for r in 0..n3 {
        let want: f64 = (0..n3).map(|c| a[r * n3 + c] * x[c]).sum();
        assert!((yf[r] - want).abs() <= tol.rel * 10.0, "sym_matvec row {r}");
    }
    // Factorise (lower triangle only) and solve.
    let mut fac = lower_only;
    cholesky::<T>(&mut fac, nb).unwrap();
    let b: Vec<f64> = (0..n3).map(|_| rng.range(-1.0, 1.0)).collect();
    let mut sol = vecs::<T>(&b);
    cholesky_solve::<T>(&fac, nb, &mut sol);
    let s = flat::<T>(&sol);
    let mut worst = 0.0f64;
    for r in 0..n3 {
        let ax: f64 = (0..n3).map(|c| a[r * n3 + c] * s[c]).sum();
        worst = worst.max((ax - b[r]).abs());
    }
    assert!(
        worst <= tol.rel * 100.0,
        "Cholesky solve residual {worst:e}"
    );
    // Indefinite: diag(1, 1, 1, 1, 1, -1) fails at scalar row 5.
    let mut d = vec![0.0; 36];
    for k in 0..6 {
        d[k * 6 + k] = if k == 5 { -1.0 } else { 1.0 };
    }
    let mut m = blocks_from::<T>(&d, 2);
    assert_eq!(
        cholesky::<T>(&mut m, 2),
        Err(LinalgError::NotPositiveDefinite { row: 5 })
    );
    // NaN gives the typed error too, not a NaN factor.
    d[3 * 6 + 3] = f64::NAN;
    let mut m = blocks_from::<T>(&d, 2);
    assert_eq!(
        cholesky::<T>(&mut m, 2),
        Err(LinalgError::NotPositiveDefinite { row: 3 })
    );
}

/// LU with partial pivoting on a random nonsymmetric matrix: `A x = b` directly; a
/// zero leading pivot needs the row swap; singular matrices give `Singular`.
fn lu_direct_check<T: Real>(tol: &Tol) {
    let mut rng = Rng(1234);
    for n in [1usize, 2, 5, 12, 30] {
        let a: Vec<f64> = (0..n * n).map(|_| rng.range(-1.0, 1.0)).collect();
        let at: Vec<T> = a.iter().map(|&v| T::from_f64(v)).collect();
        let a: Vec<f64> = at.iter().map(|v| v.to_f64()).collect();
        let b: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut fac = at.clone();
        let mut piv = vec![0usize; n];
        lu::<T>(&mut fac, n, &mut piv).unwrap();
        let mut x: Vec<T> = b.iter().map(|&v| T::from_f64(v)).collect();
        lu_solve::<T>(&fac, n, &piv, &mut x);
        let xf: Vec<f64> = x.iter().map(|v| v.to_f64()).collect();
        let xmax = xf.iter().fold(1.0f64, |m, &v| m.max(v.abs()));
        for r in 0..n {
            let ax: f64 = (0..n).map(|c| a[r * n + c] * xf[c]).sum();
            let err = (ax - b[r]).abs() / xmax;
            assert!(
                err <= tol.rel * 10.0,
                "LU n = {n}: residual {err:e} at row {r}"
            );
        }
    }
    // [[0, 2], [3, 1]] x = [4, 5] -> x = [1, 2]; needs pivoting.
    let mut a: Vec<T> = [0.0, 2.0, 3.0, 1.0]
        .iter()
        .map(|&v| T::from_f64(v))
        .collect();
    let mut piv = [0usize; 2];
    lu::<T>(&mut a, 2, &mut piv).unwrap();
    let mut x = [T::from_f64(4.0), T::from_f64(5.0)];
    lu_solve::<T>(&a, 2, &piv, &mut x);
    assert!((x[0].to_f64() - 1.0).abs() <= tol.exact * 4.0);
    assert!((x[1].to_f64() - 2.0).abs() <= tol.exact * 4.0);
    // Singular: row 1 = 2 row 0 (elimination is exact in these small integers).
    let mut a: Vec<T> = [1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 1.0, 1.0, 1.0]
        .iter()
        .map(|&v| T::from_f64(v))
        .collect();
    let mut piv = [0usize; 3];
    assert_eq!(
        lu::<T>(&mut a, 3, &mut piv),
        Err(LinalgError::Singular { row: 2 })
    );
    let mut z = vec![T::ZERO; 4];
    assert_eq!(
        lu::<T>(&mut z, 2, &mut piv),
        Err(LinalgError::Singular { row: 0 })
    );
    let mut nan = vec![T::from_f64(f64::NAN); 4];
    assert!(matches!(
        lu::<T>(&mut nan, 2, &mut piv),
        Err(LinalgError::Singular { .. })
    ));
}

// ---------------------------------------------------------------------------------
// Instantiation for both precisions.
// ---------------------------------------------------------------------------------

macro_rules! precision_tests {
    ($m:ident, $t:ty, $tol:expr) => {
        mod $m {
            use super::*;
            const TOL: Tol = $tol;

            #[test]
            fn lone_sphere_obeys_stokes_law() {
                lone_sphere_stokes::<$t>(&TOL);
            }
            #[test]
            fn two_equal_spheres_match_rpy_closed_forms() {
                two_equal_spheres_settling::<$t>(&TOL);
            }
            #[test]
            fn polydisperse_pair_matches_far_formulas() {
                polydisperse_pair_far::<$t>(&TOL);
            }
            #[test]
            fn equal_overlapping_pair_matches_rotne_prager() {
                equal_overlapping_blocks::<$t>(&TOL);
            }
            #[test]
            fn polydisperse_overlap_branch_limits() {
                polydisperse_overlap_limits::<$t>(&TOL);
            }
            #[test]
            fn oseen_and_free_draining_blocks() {
                cheaper_levels::<$t>(&TOL);
            }
            #[test]
            fn assembled_matrices_are_symmetric() {
                symmetry::<$t>(&TOL);
            }
            #[test]
            fn assembled_matrices_are_exactly_symmetric() {
                exact_symmetry::<$t>(&TOL);
            }
            #[test]
            fn mobility_rotates_with_the_configuration() {
                rotation_covariance::<$t>(&TOL);
            }
            #[test]
            fn oseen_close_range_is_not_positive_definite() {
                oseen_close_range_fails::<$t>(&TOL);
            }
            #[test]
            fn nested_spheres_are_an_assembly_error() {
                nested_assembly_error::<$t>(&TOL);
            }
            #[test]
            fn nested_spheres_are_an_error_at_every_level() {
                nested_assembly_error_cheaper_levels::<$t>(&TOL);
            }
            #[test]
            fn particle_set_validation_errors() {
                particle_validation::<$t>(&TOL);
            }
            #[test]
            fn bond_set_validation_errors() {
                bond_validation::<$t>(&TOL);
            }
            #[test]
            fn cholesky_solves_spd_systems() {
                cholesky_direct_check::<$t>(&TOL);
            }
            #[test]
            fn lu_solves_nonsymmetric_systems() {
                lu_direct_check::<$t>(&TOL);
            }

            proptest! {
                #![proptest_config(ProptestConfig::with_cases(64))]
                #[test]
                fn rpy_is_positive_definite(n in 2usize..=32, seed in any::<u64>()) {
                    rpy_positive_definite::<$t>(n, seed, false, &TOL);
                }
                #[test]
                fn rpy_overlapping_is_positive_definite(n in 2usize..=32, seed in any::<u64>()) {
                    rpy_positive_definite::<$t>(n, seed, true, &TOL);
                }
                #[test]
                fn rpy_overlapping_pair_is_positive_definite(
                    a0 in 0.5f64..2.0,
                    a1 in 0.5f64..2.0,
                    t in 0.05f64..1.0,
                    seed in any::<u64>(),
                ) {
                    // Centre distance between |a0 - a1| (nested) and a0 + a1 (contact).
                    let lo = (a0 - a1).abs();
                    let s = lo + t * (a0 + a1 - lo);
                    let mut rng = Rng(seed);
                    let p = [[0.0, 0.0, 0.0], scale(rng.direction(), s)];
                    let (pos, rad) = conv::<$t>(&p, &[a0, a1]);
                    let mut g = vec![<$t as Real>::M3_ZERO; 16];
                    assemble_grand(Hydro::Rpy, 1.0, &pos, &rad, &mut g).unwrap();
                    let d = dense::<$t>(&g, 4);
                    for _ in 0..4 {
                        let x: Vec<f64> = (0..12).map(|_| rng.range(-1.0, 1.0)).collect();
                        prop_assert!(quad_form(&d, &x) > 0.0);
                    }
                    prop_assert!(cholesky::<$t>(&mut g, 4).is_ok());
                }
            }
        }
    };
}

precision_tests!(f64_tests, f64, TOL_F64);
precision_tests!(f32_tests, f32, TOL_F32);
