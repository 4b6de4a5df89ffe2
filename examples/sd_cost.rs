//! The cost of the dense Stokesian dynamics mobility (`hydrorattle::stokesian`): one
//! pair's near-field correction, and the whole mobility of `N` spheres against the plain
//! RPY grand assembly, in `f64` on one core.
//!
//! `cargo run --release --example sd_cost [N ...]` (default 100): prints the
//! microseconds of a pair correction and, for each `N`, the seconds of the RPY grand
//! assembly and of the SD mobility, and how many pairs are inside the cutoff.
//! The spheres (radius 1) sit on a cubic lattice of spacing 2.6 (volume fraction 0.24),
//! each moved by up to 0.25 along each axis (a fixed generator: the same spheres every run).

use std::hint::black_box;
use std::time::Instant;

use hydrorattle::Hydro;
use hydrorattle::linalg::tri;
use hydrorattle::mobility::assemble_grand;
use hydrorattle::near::near_correction;
use hydrorattle::real::Real;
use hydrorattle::stokesian::{NearField, mobility, pair_far, storage};

/// A fixed xorshift generator in `[0, 1)`.
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn lattice(n: usize) -> Vec<glam::DVec3> {
    let side = (n as f64).cbrt().ceil() as usize;
    let mut s = 0x9e37_79b9_7f4a_7c15;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        let mut jitter = || 0.5 * (uniform(&mut s) - 0.5);
        let p = [i, j, l].map(|c| c as f64 * 2.6);
        out.push(glam::DVec3::new(
            p[0] + jitter(),
            p[1] + jitter(),
            p[2] + jitter(),
        ));
    }
    out
}

fn main() {
    // One pair: gaps 0.01 to 4 mean radii (s = 2.01 to 6), size ratios 1 to 4.
    let pairs: Vec<(f64, glam::DVec3)> = (0..2000)
        .map(|k| {
            let s = 2.01 + 3.99 * (k % 100) as f64 / 100.0;
            let a2 = 1.0 + 3.0 * (k / 100) as f64 / 20.0;
            (
                a2,
                glam::DVec3::new(0.3, -0.4, 0.866).normalize() * s * (1.0 + a2) / 2.0,
            )
        })
        .collect();
    // Best of 10 rounds (the machine is shared), near (s < 4: lubrication and tables)
    // and far (s >= 4: the series) apart.
    for (name, near) in [("s < 4", true), ("4 <= s < 6", false)] {
        let mut best = f64::INFINITY;
        for _ in 0..10 {
            let t = Instant::now();
            let mut count = 0;
            for &(a2, r) in &pairs {
                if (r.length() * 2.0 / (1.0 + a2) < 4.0) == near {
                    let far = pair_far(1.0, 1.0, a2, r);
                    black_box(near_correction(1.0, 1.0, a2, r, &far).unwrap());
                    count += 1;
                }
            }
            best = best.min(t.elapsed().as_secs_f64() / count as f64);
        }
        println!(
            "pair correction (with its RPY 12x12), {name}: {:.2} us",
            best * 1e6
        );
    }
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    for n in if sizes.is_empty() { vec![100] } else { sizes } {
        let pos = lattice(n);
        let a = vec![1.0; n];
        let mut packed = vec![glam::DMat3::ZERO; tri(2 * n)];
        let t = Instant::now();
        assemble_grand(Hydro::Rpy, 1.0, &pos, &a, &mut packed).unwrap();
        let rpy = t.elapsed().as_secs_f64();
        let near = NearField::<f64>::default();
        let close = (0..n)
            .map(|i| (0..i).filter(|&j| pos[i].distance(pos[j]) < 6.0).count())
            .sum::<usize>();
        let (nb, nd) = storage(n);
        let mut packed = vec![f64::M3_ZERO; nb];
        let mut out = vec![0.0; nd];
        let t = Instant::now();
        mobility(1.0, None, &pos, &a, near, &mut packed, &mut out).unwrap();
        let sd = t.elapsed().as_secs_f64();
        println!(
            "N = {n}: RPY grand assembly {rpy:.3e} s, SD mobility {sd:.3e} s ({close} pairs inside the cutoff), ratio {:.0}",
            sd / rpy
        );
    }
}
