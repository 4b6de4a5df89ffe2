//! Periodic-box configurations for the Ewald and PSE tests: a seeded generator of
//! polydisperse spheres, separated or overlapping (minimum-image distances).

use super::fuzz::Rng;
use super::{admissible, norm};
use hydrorattle::Real;

pub fn min_image(r: [f64; 3], size: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|d| r[d] - size[d] * (r[d] / size[d]).round())
}

/// `n` spheres of radii in `[0.5, a_hi]` in the box `size` ([`config_radii`]).
pub fn config(
    n: usize,
    seed: u64,
    size: [f64; 3],
    a_hi: f64,
    overlap: bool,
) -> (Vec<[f64; 3]>, Vec<f64>) {
    config_radii(n, seed, size, [0.5, a_hi], overlap)
}

/// `n` spheres of radii in `[a_lo, a_hi]` in the box `size`: with `overlap`, half of
/// them placed overlapping an earlier one (centre distance between nested-plus-a-margin
/// and contact), otherwise all apart. Distances are minimum-image distances.
pub fn config_radii(
    n: usize,
    seed: u64,
    size: [f64; 3],
    [a_lo, a_hi]: [f64; 2],
    overlap: bool,
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let mut rng = Rng(seed);
    let (mut pos, mut rad): (Vec<[f64; 3]>, Vec<f64>) = (vec![], vec![]);
    let mut tries = 0;
    while pos.len() < n && tries < 100_000 {
        tries += 1;
        let a = rng.range(a_lo, a_hi);
        let p = if overlap && !pos.is_empty() && rng.unit() < 0.5 {
            let j = (rng.unit() * pos.len() as f64) as usize;
            let lo = (a - rad[j]).abs() + 0.1 * a.min(rad[j]);
            let s = rng.range(lo, a + rad[j]);
            let (u, phi) = (rng.range(-1.0, 1.0), rng.range(0.0, core::f64::consts::TAU));
            let w = (1.0 - u * u).sqrt();
            [0, 1, 2].map(|d| pos[j][d] + s * [w * phi.cos(), w * phi.sin(), u][d])
        } else {
            [0, 1, 2].map(|d| rng.range(0.0, size[d]))
        };
        let ok = pos.iter().zip(&rad).all(|(q, &b)| {
            let s = norm(min_image([0, 1, 2].map(|d| p[d] - q[d]), size));
            admissible(s, a, b, overlap)
        });
        if ok {
            pos.push(p);
            rad.push(a);
        }
    }
    (pos, rad)
}

pub fn to_t<T: Real>(pos: &[[f64; 3]], rad: &[f64]) -> (Vec<T::V3>, Vec<T>) {
    (
        pos.iter().map(|&p| T::v3_from(p)).collect(),
        rad.iter().map(|&a| T::from_f64(a)).collect(),
    )
}
