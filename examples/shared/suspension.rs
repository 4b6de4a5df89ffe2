//! Random suspensions of spheres in a cubic periodic box for the examples (shared by
//! `#[path]`): radii uniform in 0.8..1.2, placed by random sequential addition with gaps
//! of at least 1e-3 mean radii at their minimum image, from a fixed generator.

use glam::DVec3;

/// A fixed xorshift generator in `[0, 1)`.
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// `n` spheres at volume fraction `phi` in a cubic box: positions, radii, edge.
pub fn suspension(n: usize, phi: f64) -> (Vec<DVec3>, Vec<f64>, f64) {
    let mut s = 0x9e37_79b9_7f4a_7c15u64 ^ n as u64;
    let rad: Vec<f64> = (0..n).map(|_| 0.8 + 0.4 * uniform(&mut s)).collect();
    let vol: f64 = rad
        .iter()
        .map(|a| 4.0 / 3.0 * std::f64::consts::PI * a * a * a)
        .sum();
    let l = (vol / phi).cbrt();
    let mut pos: Vec<DVec3> = Vec::with_capacity(n);
    for &a in &rad {
        loop {
            let p = DVec3::new(uniform(&mut s), uniform(&mut s), uniform(&mut s)) * l;
            let clear = pos.iter().zip(&rad).all(|(q, &b)| {
                let d = p - *q;
                let d = d - (d / l).round() * l;
                d.length() >= (a + b) * 0.5 * 2.001
            });
            if clear {
                pos.push(p);
                break;
            }
        }
    }
    (pos, rad, l)
}
