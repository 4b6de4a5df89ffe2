//! 27 spheres on a cube: where the Oseen mobility stops being positive definite.

use hydrorattle::glam;
use hydrorattle::linalg;
use hydrorattle::mobility::{Hydro, assemble_tt};

/// `x` spacing `2 + gap` cube of 27 unit spheres.
fn cube(gap: f64) -> Vec<glam::DVec3> {
    let s = 2.0 + gap;
    let mut v = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                v.push(glam::DVec3::new(i as f64 * s, j as f64 * s, k as f64 * s));
            }
        }
    }
    v
}

fn cube_mobility(level: Hydro, gap: f64) -> (Vec<glam::DMat3>, usize) {
    let pos = cube(gap);
    let n = pos.len();
    let rad = vec![1.0; n];
    let mut mu = vec![glam::DMat3::ZERO; n * n];
    // Nested spheres cannot occur on the cube: spacing > 2.
    let _ = assemble_tt::<f64>(level, 1.0, &pos, &rad, &mut mu);
    (mu, n)
}

pub(super) fn cube_cholesky_ok(level: Hydro, gap: f64) -> bool {
    let (mut mu, n) = cube_mobility(level, gap);
    linalg::cholesky::<f64>(&mut mu, n).is_ok()
}

/// Smallest eigenvalue (scaled by 6 pi eta a) by power iteration on `c I - mu`.
pub(super) fn cube_min_eigen(level: Hydro, gap: f64) -> f64 {
    let (mu, n) = cube_mobility(level, gap);
    let c = 2.0 / (6.0 * std::f64::consts::PI) * n as f64;
    let mut x: Vec<glam::DVec3> = (0..n)
        .map(|i| glam::DVec3::new(1.0, 0.3 + i as f64 * 0.01, -0.7))
        .collect();
    let mut y = vec![glam::DVec3::ZERO; n];
    let mut lambda = 0.0;
    for _ in 0..3000 {
        linalg::sym_matvec::<f64>(&mu, n, &x, &mut y);
        let mut norm = 0.0;
        for i in 0..n {
            y[i] = x[i] * c - y[i];
            norm += y[i].length_squared();
        }
        let norm = norm.sqrt();
        lambda = x.iter().zip(&y).map(|(a, b)| a.dot(*b)).sum::<f64>()
            / x.iter().map(|a| a.length_squared()).sum::<f64>();
        for i in 0..n {
            x[i] = y[i] / norm;
        }
    }
    (c - lambda) * 6.0 * std::f64::consts::PI
}
