//! The thermal step's share of the free-space cost model ([`free_cost`](super::free_cost)):
//! how many mobility products a Brownian step's Lanczos noise takes, by path.
//!
//! The paths draw differently. In free space the stored and matrix-free paths keep the
//! midpoint drift: the Lanczos run gives `M^(1/2) z` and `M^(-1/2) z` together, and
//! stops when both are converged, so it runs longer; then a second mobility (an
//! assembly and a product, or one more matrix-free product) at the midpoint. The fast
//! path, like PSE's, takes the uncorrected draw without bonds (free space's RPY
//! mobility is divergence-free): `M^(1/2) z` alone, no midpoint. Measured
//! (`cargo run --release --example free_brownian`, rows in `bench/results/free_cost.csv`):
//! 26 iterations with the inverse against 15 without on a cloud of 1000 spheres at
//! volume fraction 0.01.
//!
//! The iterations grow with the mobility's spread of eigenvalues: the collective mode
//! (the whole cloud falling, `1 + 6 N a / (5 R)` times a lone sphere's mobility for a
//! ball of radius `R`) at the top, the overlapping pairs at the bottom. The model is
//! `c0 + c1 ln N + c2 sqrt(S)`, `S = 1 + 6 N a_max / (5 R)` with `R` half the longest
//! edge of the spheres' bounding box plus a radius: a cloud's collective mobility, a
//! chain's (a line: `S` near 2, its iterations grow as `ln N`). Fitted to the recorded
//! iterations of every shape and count by `python3 bench/free_fit.py --brownian COMMIT`.

use super::free_cost::Spheres;

/// Lanczos iterations with the inverse root (the midpoint drift), fixed part.
pub const MIDPOINT_FIXED: f64 = 0.0;
/// Lanczos iterations with the inverse root per `ln N`.
pub const MIDPOINT_LOG_N: f64 = 0.0;
/// Lanczos iterations with the inverse root per `sqrt(S)`.
pub const MIDPOINT_SPREAD: f64 = 0.0;
/// Lanczos iterations of the root alone (the uncorrected draw), fixed part.
pub const ROOT_FIXED: f64 = 0.0;
/// Lanczos iterations of the root alone per `ln N`.
pub const ROOT_LOG_N: f64 = 0.0;
/// Lanczos iterations of the root alone per `sqrt(S)`.
pub const ROOT_SPREAD: f64 = 0.0;

/// The iteration model's terms for `s`: `[1, ln N, sqrt(S)]`.
pub fn terms(s: &Spheres) -> [f64; 3] {
    let n = s.n.max(1) as f64;
    let longest = s.extent.iter().fold(0.0f64, |m, &e| m.max(e));
    let r = 0.5 * longest + s.a_max.max(f64::MIN_POSITIVE);
    let spread = 1.0 + 1.2 * n * s.a_max / r;
    [1.0, n.ln(), spread.sqrt()]
}

/// The modelled Lanczos iterations of a thermal step of `s`: with the inverse root
/// (`midpoint`) or the root alone; at least one.
pub fn iterations(s: &Spheres, midpoint: bool) -> f64 {
    let c = match midpoint {
        true => [MIDPOINT_FIXED, MIDPOINT_LOG_N, MIDPOINT_SPREAD],
        false => [ROOT_FIXED, ROOT_LOG_N, ROOT_SPREAD],
    };
    let x = terms(s);
    (c[0] * x[0] + c[1] * x[1] + c[2] * x[2]).max(1.0)
}
