//! The helix generator: the paper's head-and-tails chain, exact to the last bit.

use hydrorattle::helix::HelixError;
use serde::{Deserialize, Serialize};

use super::{DEFAULT_DENSITY, DEFAULT_HEAD_RATIO, DEFAULT_HELIX_PITCH, DEFAULT_HELIX_RADIUS};

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

impl Chain {
    /// The chain's spheres as scene particles (at rest).
    pub fn particles(&self) -> Vec<super::Particle> {
        (0..self.positions.len())
            .map(|k| super::Particle {
                position: self.positions[k],
                radius: self.radii[k],
                density: self.densities[k],
                ..super::Particle::default()
            })
            .collect()
    }

    /// The chain's bonds as scene bonds.
    pub fn scene_bonds(&self) -> Vec<super::Bond> {
        self.bonds
            .iter()
            .map(|&(i, j, length)| super::Bond { i, j, length })
            .collect()
    }
}

impl Helix {
    /// The kernel's helix ([`hydrorattle::helix`]): the one geometry the scenes and the
    /// firmware build.
    pub fn geometry(&self) -> hydrorattle::helix::Helix {
        hydrorattle::helix::Helix {
            tails: self.tails,
            head_ratio: self.head_ratio,
            dhat: self.dhat,
            radius: self.radius,
            pitch: self.pitch,
            head_end: match self.head_end {
                HeadEnd::Bottom => hydrorattle::helix::HeadEnd::Bottom,
                HeadEnd::Top => hydrorattle::helix::HeadEnd::Top,
            },
        }
    }

    /// Head radius (tail radius is [`TAIL_RADIUS`](super::TAIL_RADIUS)).
    pub fn head_radius(&self) -> f64 {
        self.geometry().head_radius()
    }

    /// Length of the head-to-first-tail bond.
    pub fn head_bond(&self) -> f64 {
        self.geometry().head_bond()
    }

    /// Length of a tail-to-tail bond.
    pub fn tail_bond(&self) -> f64 {
        self.geometry().tail_bond()
    }

    /// Angular step between consecutive tails
    /// ([`hydrorattle::helix::Helix::angular_step`]).
    pub fn angular_step(&self) -> Result<f64, String> {
        self.geometry().angular_step().map_err(|e| self.describe(e))
    }

    /// A kernel refusal in the scene's terms.
    fn describe(&self, e: HelixError) -> String {
        let (r, p) = (self.radius, self.pitch);
        match e {
            HelixError::NoTails => "helix needs at least one tail".into(),
            HelixError::TooTight { bond, max_chord } => format!(
                "helix too tight: tail bond length {bond} exceeds the largest chord \
                 {max_chord:.6} of a half turn (radius {r}, pitch {p}); increase radius or pitch"
            ),
            HelixError::HeadTooShort { head_bond } => format!(
                "helix radius {r} exceeds the head bond length {head_bond} = dhat (head_ratio + 1): \
                 the head on the axis cannot reach the first tail; choose radius <= {head_bond}"
            ),
        }
    }

    /// Checks the numbers (ranges, finiteness) and the geometry.
    pub fn check(&self) -> Result<(), String> {
        self.check_numbers()?;
        self.geometry()
            .positions()
            .map(|_| ())
            .map_err(|e| self.describe(e))
    }

    /// Checks the numbers (ranges, finiteness); the geometry is checked where the
    /// positions are made (once: its angular step is a bisection, a sweep's helices
    /// each make one).
    fn check_numbers(&self) -> Result<(), String> {
        if self.tails < 1 {
            return Err(self.describe(HelixError::NoTails));
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
        Ok(())
    }

    /// Generates the chain: bead 0 is the head, beads `1..=tails` the tails, bonds
    /// `(k, k + 1, dhat (a_k + a_{k+1}))`.
    pub fn generate(&self) -> Result<Chain, String> {
        self.check_numbers()?;
        let h = self.geometry();
        let n = self.tails + 1;
        Ok(Chain {
            positions: h.positions().map_err(|e| self.describe(e))?.collect(),
            radii: (0..n).map(|k| h.bead_radius(k)).collect(),
            densities: vec![self.density; n],
            bonds: (0..self.tails)
                .map(|k| (k, k + 1, h.bond_length(k)))
                .collect(),
        })
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
