//! What `[box] method = "auto"` weighs: the time of one mobility product by the Ewald
//! sum and by PSE, from a cost model in the sphere count, the box and the tolerance
//! whose constants were measured (`cargo run --release --example auto_box`, which
//! writes each timing, the fitted constants, the commit, the machine and the command
//! to `bench/results/auto_box.csv`).
//!
//! * Ewald: `t = EWALD_FIXED + EWALD_SPHERE N + EWALD_PAIR N^2`. Its splitting
//!   parameter scales with the box, so the work per pair does not depend on the box's
//!   size or the tolerance (it sums to rounding).
//! * PSE: `t = PSE_FIXED + PSE_GRID M log2 M + PSE_NEAR N (1 + n_near) + PSE_SPREAD N P^3`,
//!   with `M` the grid's points (which grow with the box's volume and with
//!   `ln(1/tolerance)^(3/2)`), `n_near` the spheres within the real-space cutoff of
//!   each (from the number density) and `P^3` the Gaussian support's points, all from
//!   the kernel's own parameters (`Pse::new`).
//!
//! A step takes one product, or dozens with a constraint solve and Lanczos noise
//! ([`Work`]); the Ewald path assembles its mobility once (twice with the midpoint) and
//! serves them from it, PSE pays every one.
//!
//! A dilute box is where the grid dominates: a lone unit sphere in a box of 50 needs a
//! grid of 72^3 points at tolerance 1e-6 for one pair's worth of Ewald work.

use hydrorattle::Periodic;
use hydrorattle::mobility::pse::Pse;

/// Seconds per Ewald product, fixed part.
pub const EWALD_FIXED: f64 = 0.000e0;
/// Seconds per Ewald product per sphere.
pub const EWALD_SPHERE: f64 = 3.484e-5;
/// Seconds per Ewald product per pair (`N^2`, the self blocks included).
pub const EWALD_PAIR: f64 = 2.148e-6;
/// Seconds per PSE product, fixed part.
pub const PSE_FIXED: f64 = 7.286e-6;
/// Seconds per PSE product per `M log2 M` of the grid (three FFTs each way).
pub const PSE_GRID: f64 = 1.199e-8;
/// Seconds per PSE product per near-field pair (and per sphere).
pub const PSE_NEAR: f64 = 2.132e-7;
/// Seconds per PSE product per support point of a sphere (spread and interpolation).
pub const PSE_SPREAD: f64 = 1.296e-8;

/// Mobility products a step takes beyond its first, for a constraint solve (the Krylov
/// iterations), measured: the shipped 13-bead periodic chain on PSE
/// (`host/scenes/periodic_chain.toml` with `method = "pse"`, 10 steps:
/// `mean_iterations` 21.6 in its `summary.json`).
pub const PRODUCTS_SOLVE: f64 = 21.6;
/// Products a step takes for Lanczos noise, measured on the same run (its
/// `noise_iterations.mean`, 16.4).
pub const PRODUCTS_NOISE: f64 = 16.4;
/// Products of the midpoint's solve with bonds on PSE (`integrate::brownian`: "some
/// 30 to 50 products"), and the Ewald path's second assembly there.
pub const PRODUCTS_MIDPOINT: f64 = 40.0;

/// What a step asks of the mobility: how many products, and how many assemblies the
/// Ewald path makes for them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Work {
    /// Constraints (bonds, pins, hard contacts): a Krylov solve a step.
    pub constraints: bool,
    /// Thermal noise (drawn by Lanczos from products on PSE).
    pub thermal: bool,
    /// The midpoint drift with constraints (a second solve).
    pub midpoint: bool,
    /// The Ewald path without the stored mobility (every product summed on the fly).
    pub matrix_free: bool,
}

impl Work {
    /// Products a step takes.
    pub fn products(&self) -> f64 {
        let mut k = 1.0;
        k += if self.constraints {
            PRODUCTS_SOLVE
        } else {
            0.0
        };
        k += if self.thermal { PRODUCTS_NOISE } else { 0.0 };
        k += if self.midpoint {
            PRODUCTS_MIDPOINT
        } else {
            0.0
        };
        k
    }

    /// The Ewald path's assemblies a step (the stored mobility then serves the
    /// products at a few nanoseconds a pair, left out), or every product when
    /// matrix-free.
    pub fn assemblies(&self) -> f64 {
        match (self.matrix_free, self.midpoint) {
            (true, _) => self.products(),
            (false, true) => 2.0,
            (false, false) => 1.0,
        }
    }
}

/// The modelled time of one product by each path, seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxCost {
    /// The Ewald sum.
    pub ewald: f64,
    /// PSE; `None` where the kernel refuses its parameters (a grid or support past its
    /// bounds, a sphere too large for the box, a tolerance out of range).
    pub pse: Option<f64>,
}

impl BoxCost {
    /// `n` spheres up to radius `a_max` in a box of edges `size`, PSE at `tolerance`.
    pub fn of(size: [f64; 3], n: usize, a_max: f64, tolerance: f64) -> BoxCost {
        let n = n as f64;
        let ewald = EWALD_FIXED + EWALD_SPHERE * n + EWALD_PAIR * n * n;
        let pse = Periodic::new(size)
            .ok()
            .and_then(|cell| Pse::<f64>::new(cell, a_max, tolerance).ok())
            .map(|pse| {
                let g = pse.grid();
                let m = (g[0] * g[1] * g[2]) as f64;
                let s = pse.support();
                let volume = size[0] * size[1] * size[2];
                let ball = 4.0 / 3.0 * std::f64::consts::PI * pse.r_cut().powi(3);
                let near = (n / volume * ball).min((n - 1.0).max(0.0));
                PSE_FIXED
                    + PSE_GRID * m * m.log2()
                    + PSE_NEAR * n * (1.0 + near)
                    + PSE_SPREAD * n * (s[0] * s[1] * s[2]) as f64
            });
        BoxCost { ewald, pse }
    }

    /// Whether PSE runs here and its product costs less than the Ewald sum's.
    pub fn pse_pays(&self) -> bool {
        self.pse.is_some_and(|p| p < self.ewald)
    }

    /// The modelled time of a step asking `work` of each path, seconds: the Ewald
    /// path's assemblies, PSE's products.
    pub fn per_step(&self, work: Work) -> BoxCost {
        BoxCost {
            ewald: self.ewald * work.assemblies(),
            pse: self.pse.map(|p| p * work.products()),
        }
    }
}

/// Whether `"auto"` should take PSE for one product of `n` spheres up to radius `a_max`
/// in the box `size` at `tolerance` ([`BoxCost::pse_pays`]): the rule of the Python
/// package's `mobility_dot` (a scene's steps weigh their [`Work`] too).
pub fn pse_pays(size: [f64; 3], n: usize, a_max: f64, tolerance: f64) -> bool {
    BoxCost::of(size, n, a_max, tolerance).pse_pays()
}

/// Refuses, at the `[box]` table, a box PSE cannot serve, before its grid is made: with
/// `method = "pse"`, PSE's refusal of the box (a grid edge past the kernel's bound, a
/// sphere of a third of the edge or more) or a grid and near-field lists that with the
/// step's own storage (the largest of `plans`, `O(N)` matrix-free) exceed `limit`
/// bytes; with `"pse"` or `"auto"` in `f32`, a tolerance below what that precision
/// reaches (`mobility::pse::min_tolerance`).
pub(super) fn check_pse(
    b: &super::PeriodicBox,
    raw: &toml::Spanned<super::periodic::RawBox>,
    (particles, bonds): (&[super::Particle], usize),
    plans: &[crate::sizing::Plan],
    limit: usize,
) -> Result<(), super::error::Issue> {
    use super::error::issue;
    use super::{BoxMethod, Precision};
    use crate::sizing::human;
    use hydrorattle::mobility::pse::{self, PseError};
    let r = raw.get_ref();
    let at = r.method_span().unwrap_or(raw.span());
    let f32 = plans.iter().any(|p| p.precision == Precision::F32);
    let floor = pse::min_tolerance::<f32>();
    if f32 && b.method != BoxMethod::Ewald && b.tolerance < floor {
        return Err(issue(
            r.tolerance_span().unwrap_or(at),
            format!(
                "box tolerance {:e} is below what PSE reaches in f32 ({floor:.1e}, its rounding): raise it, use precision = \"f64\" or method = \"ewald\"",
                b.tolerance
            ),
        ));
    }
    if b.method != BoxMethod::Pse {
        return Ok(());
    }
    let a_max = particles.iter().fold(0.0, |m: f64, p| m.max(p.radius));
    let size = b.size.map(|l| format!("{l}")).join(" x ");
    let made = Periodic::new(b.size)
        .map_err(PseError::from)
        .and_then(|cell| Pse::<f64>::new(cell, a_max, b.tolerance));
    let pse = match made {
        Ok(p) => p,
        Err(PseError::GridTooLarge) => {
            return Err(issue(
                at,
                format!(
                    "[box] method = \"pse\": a box of {size} at tolerance {:e} needs a PSE grid edge above {} points (the box is too large for the tolerance): use method = \"ewald\" or \"auto\", or a larger tolerance",
                    b.tolerance,
                    pse::MAX_GRID
                ),
            ));
        }
        Err(e) => return Err(issue(at, format!("[box] method = \"pse\": {e}"))),
    };
    let n = particles.len();
    let need = pse.storage(n);
    let real = if f32 { 4 } else { 8 };
    let grid = need.complex * 2 * real + need.index * 8 + need.vectors * 3 * real;
    let step = plans
        .iter()
        .filter_map(|p| p.bytes(n, bonds))
        .max()
        .unwrap_or(0);
    let total = grid.saturating_add(step);
    if total > limit {
        let g = pse.grid();
        return Err(issue(
            at,
            format!(
                "[box] method = \"pse\": a box of {size} at tolerance {:e} needs a PSE grid of {} x {} x {} points, {} with its near-field lists and the step's {}, over the limit of {}: the box is too large for the tolerance; use method = \"ewald\" or \"auto\", a larger tolerance or `run --max-storage`",
                b.tolerance,
                g[0],
                g[1],
                g[2],
                human(grid as u64),
                human(step as u64),
                human(limit as u64)
            ),
        ));
    }
    Ok(())
}
