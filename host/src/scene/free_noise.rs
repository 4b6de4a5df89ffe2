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
//! ball of radius `R`) at the top, the overlapping pairs of a dense cloud at the
//! bottom. The model is `c0 + c1 sqrt(S) + c2 sqrt(f)`: `S = 1 + 6 N a_max / (5 R)`,
//! `R` half the longest edge of the spheres' bounding box plus a radius (a cloud's
//! collective mobility; a chain's `S` stays near 2), and the box's fill
//! `f = N a_max^3 / V`, `V` the box with a radius added each side (the overlaps). Fitted
//! to the recorded iterations of every shape and count by `python3 bench/free_fit.py
//! --brownian COMMIT...`; worst misfit in [`MIDPOINT_MISFIT`] and [`ROOT_MISFIT`].

use super::free_cost::Spheres;

/// Lanczos iterations with the inverse root (the midpoint drift), fixed part.
pub const MIDPOINT_FIXED: f64 = 0.0000e0;
/// Lanczos iterations with the inverse root per `sqrt(S)`.
pub const MIDPOINT_SPREAD: f64 = 5.1868e0;
/// Lanczos iterations with the inverse root per `sqrt(f)`.
pub const MIDPOINT_FILL: f64 = 4.1480e1;
/// The fit's worst factor between modelled and measured iterations, inverse root.
pub const MIDPOINT_MISFIT: f64 = 1.36;
/// Lanczos iterations of the root alone (the uncorrected draw), fixed part.
pub const ROOT_FIXED: f64 = 2.3443e0;
/// Lanczos iterations of the root alone per `sqrt(S)`.
pub const ROOT_SPREAD: f64 = 1.7118e0;
/// Lanczos iterations of the root alone per `sqrt(f)`.
pub const ROOT_FILL: f64 = 5.0863e1;
/// The fit's worst factor between modelled and measured iterations, root alone.
pub const ROOT_MISFIT: f64 = 1.28;

/// The iteration model's terms for `s`: `[1, sqrt(S), sqrt(f)]`.
pub fn terms(s: &Spheres) -> [f64; 3] {
    let n = s.n as f64;
    let a = s.a_max.max(f64::MIN_POSITIVE);
    let longest = s.extent.iter().fold(0.0f64, |m, &e| m.max(e));
    let spread = 1.0 + 1.2 * n * a / (0.5 * longest + a);
    let volume: f64 = s.extent.iter().map(|e| e + 2.0 * a).product();
    [1.0, spread.sqrt(), (n * a * a * a / volume).sqrt()]
}

/// The modelled Lanczos iterations of a thermal step of `s`: with the inverse root
/// (`midpoint`) or the root alone; at least one.
pub fn iterations(s: &Spheres, midpoint: bool) -> f64 {
    let c = match midpoint {
        true => [MIDPOINT_FIXED, MIDPOINT_SPREAD, MIDPOINT_FILL],
        false => [ROOT_FIXED, ROOT_SPREAD, ROOT_FILL],
    };
    let x = terms(s);
    (c[0] * x[0] + c[1] * x[1] + c[2] * x[2]).max(1.0)
}
