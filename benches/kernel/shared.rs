//! The chain every group but `contacts` runs on.

/// Centres and radii of an `n`-bead chain: a head of radius 2^(1/3), then tails of
/// radius 1, bonds 1.5 (a_i + a_j), along a gently winding climbing path (no overlaps).
pub(crate) fn chain_geometry(n: usize) -> (Vec<[f64; 3]>, Vec<f64>) {
    let mut pos = Vec::with_capacity(n);
    let mut rad = Vec::with_capacity(n);
    let mut at = [0.0f64; 3];
    let mut prev = 0.0;
    for k in 0..n {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if k > 0 {
            let t = 0.6 * k as f64;
            let dir = [t.cos(), t.sin(), 0.8];
            let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            for c in 0..3 {
                at[c] += dir[c] / len * 1.5 * (a + prev);
            }
        }
        pos.push(at);
        rad.push(a);
        prev = a;
    }
    (pos, rad)
}
