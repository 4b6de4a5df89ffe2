//! The helix generator: the paper's head-and-tails chain, exact to the last bit.

use serde::{Deserialize, Serialize};

use super::{
    DEFAULT_DENSITY, DEFAULT_HEAD_RATIO, DEFAULT_HELIX_PITCH, DEFAULT_HELIX_RADIUS, TAIL_RADIUS,
};

/// Which end of the helix the head sits at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum HeadEnd {
    /// Below the first tail (the tails climb the helix above the head).
    #[default]
    Bottom,
    /// Above the first tail (the tails descend the helix below the head).
    Top,
}

/// The helix generator: one head and `tails` tails of radius 1 on a right-handed helix
/// about the vertical `z` axis.
///
/// Bond `k` joins beads `k` and `k + 1` at length `dhat (a_k + a_{k+1})`. The tail
/// centres lie on the helix `(radius cos phi, radius sin phi, pitch phi / 2 pi)` with a
/// constant angular step, solved so that consecutive tails are exactly one bond length
/// apart. The head (bead 0) sits on the axis (`x = y = 0`), inside the ring the tails
/// draw in top view, below the first tail (`head_end = "bottom"`) or above it (`"top"`),
/// at the height that makes its distance to the first tail exactly the head bond length;
/// the head is at the origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Helix {
    /// Number of tail beads (>= 1). Default 24.
    pub tails: usize,
    /// Head radius over tail radius (> 0). Default `2^(1/3)`.
    pub head_ratio: f64,
    /// Bond length over the sum of the two radii (> 0). Default 1.5.
    pub dhat: f64,
    /// Where the head is. Default bottom.
    pub head_end: HeadEnd,
    /// Distance of the tail centres from the axis (> 0). Default
    /// [`DEFAULT_HELIX_RADIUS`].
    pub radius: f64,
    /// Rise per turn (>= 0). Default [`DEFAULT_HELIX_PITCH`].
    pub pitch: f64,
    /// Density of every bead (head and tails alike, as in the paper). Default
    /// [`DEFAULT_DENSITY`].
    pub density: f64,
}

impl Default for Helix {
    fn default() -> Self {
        Helix {
            tails: 24,
            head_ratio: DEFAULT_HEAD_RATIO,
            dhat: 1.5,
            head_end: HeadEnd::Bottom,
            radius: DEFAULT_HELIX_RADIUS,
            pitch: DEFAULT_HELIX_PITCH,
            density: DEFAULT_DENSITY,
        }
    }
}

/// The beads and bonds a generator produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chain {
    /// Centres.
    pub positions: Vec<[f64; 3]>,
    /// Radii.
    pub radii: Vec<f64>,
    /// Densities.
    pub densities: Vec<f64>,
    /// Bonds `(i, j, length)`.
    pub bonds: Vec<(usize, usize, f64)>,
}

impl Helix {
    /// Head radius (tail radius is [`TAIL_RADIUS`]).
    pub fn head_radius(&self) -> f64 {
        self.head_ratio * TAIL_RADIUS
    }

    /// Length of the head-to-first-tail bond.
    pub fn head_bond(&self) -> f64 {
        self.dhat * (self.head_radius() + TAIL_RADIUS)
    }

    /// Length of a tail-to-tail bond.
    pub fn tail_bond(&self) -> f64 {
        self.dhat * 2.0 * TAIL_RADIUS
    }

    /// Angular step between consecutive tails: the `dphi` in `(0, pi]` with
    /// `(2 R sin(dphi/2))^2 + (p dphi / 2 pi)^2 = d^2`, found by bisection to the last
    /// bit (the left side increases strictly on that interval).
    pub fn angular_step(&self) -> Result<f64, String> {
        let (r, p, d) = (self.radius, self.pitch, self.tail_bond());
        let chord2 = |x: f64| {
            let h = 2.0 * r * (0.5 * x).sin();
            let v = p * x / (2.0 * std::f64::consts::PI);
            h * h + v * v
        };
        let pi = std::f64::consts::PI;
        if chord2(pi) < d * d {
            return Err(format!(
                "helix too tight: tail bond length {d} exceeds the largest chord \
                 {:.6} of a half turn (radius {r}, pitch {p}); increase radius or pitch",
                chord2(pi).sqrt()
            ));
        }
        let (mut lo, mut hi) = (0.0_f64, pi);
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if chord2(mid) < d * d {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let best = if (chord2(lo) - d * d).abs() <= (chord2(hi) - d * d).abs() {
            lo
        } else {
            hi
        };
        Ok(best)
    }

    /// Checks the numbers (ranges, finiteness) and the geometry.
    pub fn check(&self) -> Result<(), String> {
        if self.tails < 1 {
            return Err("helix needs at least one tail".into());
        }
        for (name, value, min, strict) in [
            ("head_ratio", self.head_ratio, 0.0, true),
            ("dhat", self.dhat, 0.0, true),
            ("radius", self.radius, 0.0, true),
            ("pitch", self.pitch, 0.0, false),
            ("density", self.density, 0.0, false),
        ] {
            check_number(name, value, min, strict)?;
        }
        if self.radius > self.head_bond() {
            return Err(format!(
                "helix radius {} exceeds the head bond length {} = dhat (head_ratio + 1): \
                 the head on the axis cannot reach the first tail; choose radius <= {}",
                self.radius,
                self.head_bond(),
                self.head_bond()
            ));
        }
        self.angular_step().map(|_| ())
    }

    /// Generates the chain: bead 0 is the head, beads `1..=tails` the tails, bonds
    /// `(k, k + 1, dhat (a_k + a_{k+1}))`.
    pub fn generate(&self) -> Result<Chain, String> {
        self.check()?;
        let dphi = self.angular_step()?;
        let sign = match self.head_end {
            HeadEnd::Bottom => 1.0,
            HeadEnd::Top => -1.0,
        };
        let r = self.radius;
        let lift = (self.head_bond().powi(2) - r * r).max(0.0).sqrt();
        let n = self.tails + 1;
        let mut chain = Chain {
            positions: Vec::with_capacity(n),
            radii: Vec::with_capacity(n),
            densities: vec![self.density; n],
            bonds: Vec::with_capacity(self.tails),
        };
        chain.positions.push([0.0, 0.0, 0.0]);
        chain.radii.push(self.head_radius());
        for k in 0..self.tails {
            let phi = sign * (k as f64) * dphi;
            let z = sign * lift + self.pitch * phi / (2.0 * std::f64::consts::PI);
            chain.positions.push([r * phi.cos(), r * phi.sin(), z]);
            chain.radii.push(TAIL_RADIUS);
        }
        for k in 0..self.tails {
            let length = self.dhat * (chain.radii[k] + chain.radii[k + 1]);
            chain.bonds.push((k, k + 1, length));
        }
        Ok(chain)
    }
}

fn check_number(name: &str, value: f64, min: f64, strict: bool) -> Result<(), String> {
    if !value.is_finite() {
        return Err(format!(
            "{name} must be a finite number, not {}",
            crate::output::format_f64(value)
        ));
    }
    if strict && value <= min {
        return Err(format!(
            "{name} must be > {min}, not {}",
            crate::output::format_f64(value)
        ));
    }
    if !strict && value < min {
        return Err(format!(
            "{name} must be >= {min}, not {}",
            crate::output::format_f64(value)
        ));
    }
    Ok(())
}
