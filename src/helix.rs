//! The paper's chain: a head and tails of radius 1 on a right-handed helix about the
//! vertical axis, written once for the host scenes and the firmware.
//!
//! The geometry is computed in `f64` with `libm` (the same code, so the same bits, on
//! every target and for every run precision; callers round once to theirs). Bead 0 is
//! the head, beads `1..=tails` the tails; bond `k` joins beads `k` and `k + 1` at length
//! `dhat (a_k + a_{k+1})`. The tails lie on `(radius cos phi, radius sin phi, lift +
//! pitch phi / 2 pi)` at a constant angular step, solved so that consecutive tails are
//! exactly one bond apart; the head sits at the origin, on the axis, one head bond
//! from the first tail (below it, or above it with [`HeadEnd::Top`]).

use core::f64::consts::PI;

/// Radius of a tail bead (the unit of length).
pub const TAIL_RADIUS: f64 = 1.0;

/// Which end of the helix the head sits at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeadEnd {
    /// Below the first tail (the tails climb the helix above the head).
    #[default]
    Bottom,
    /// Above the first tail (the tails descend the helix below the head).
    Top,
}

/// Why a helix cannot be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HelixError {
    /// No tails.
    NoTails,
    /// The tail bond is longer than the chord of half a turn, the longest the helix
    /// has at an angular step in `(0, pi]`.
    TooTight {
        /// The tail bond length.
        bond: f64,
        /// The chord of half a turn.
        max_chord: f64,
    },
    /// The helix radius exceeds the head bond: the head on the axis cannot reach the
    /// first tail.
    HeadTooShort {
        /// The head bond length.
        head_bond: f64,
    },
}

/// The helix's numbers (the scene files' `[helix]` table, less what is not geometry).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Helix {
    /// Number of tail beads (>= 1).
    pub tails: usize,
    /// Head radius over tail radius (> 0).
    pub head_ratio: f64,
    /// Bond length over the sum of the two radii (> 0).
    pub dhat: f64,
    /// Distance of the tail centres from the axis (> 0).
    pub radius: f64,
    /// Rise per turn (>= 0).
    pub pitch: f64,
    /// Where the head is.
    pub head_end: HeadEnd,
}

impl Helix {
    /// Head radius.
    pub fn head_radius(&self) -> f64 {
        self.head_ratio * TAIL_RADIUS
    }

    /// Radius of bead `k` (0 the head).
    pub fn bead_radius(&self, k: usize) -> f64 {
        if k == 0 {
            self.head_radius()
        } else {
            TAIL_RADIUS
        }
    }

    /// Length of the head-to-first-tail bond.
    pub fn head_bond(&self) -> f64 {
        self.dhat * (self.head_radius() + TAIL_RADIUS)
    }

    /// Length of a tail-to-tail bond.
    pub fn tail_bond(&self) -> f64 {
        self.dhat * 2.0 * TAIL_RADIUS
    }

    /// Length of bond `k` (beads `k` and `k + 1`): `dhat (a_k + a_{k+1})`.
    pub fn bond_length(&self, k: usize) -> f64 {
        self.dhat * (self.bead_radius(k) + self.bead_radius(k + 1))
    }

    /// Squared chord between two tails `x` apart in angle.
    fn chord2(&self, x: f64) -> f64 {
        let across = 2.0 * self.radius * libm::sin(0.5 * x);
        let up = self.pitch * x / (2.0 * PI);
        across * across + up * up
    }

    /// Angular step between consecutive tails: the `x` in `(0, pi]` with
    /// `(2 R sin(x / 2))^2 + (p x / 2 pi)^2 = d^2`, by bisection down to adjacent
    /// doubles (the left side increases strictly there), then whichever of the two
    /// brackets has the smaller residual: the bond length nearest the one asked for.
    pub fn angular_step(&self) -> Result<f64, HelixError> {
        let d2 = self.tail_bond() * self.tail_bond();
        if !(self.chord2(PI) >= d2) {
            return Err(HelixError::TooTight {
                bond: self.tail_bond(),
                max_chord: libm::sqrt(self.chord2(PI)),
            });
        }
        let (mut lo, mut hi) = (0.0_f64, PI);
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.chord2(mid) < d2 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let off = |x: f64| libm::fabs(self.chord2(x) - d2);
        Ok(if off(lo) <= off(hi) { lo } else { hi })
    }

    /// The bead centres, head first: [`Helix::tails`] `+ 1` of them. Checks the
    /// geometry (not the numbers' ranges, which the callers report in their terms).
    pub fn positions(&self) -> Result<Positions, HelixError> {
        if self.tails == 0 {
            return Err(HelixError::NoTails);
        }
        if self.radius > self.head_bond() {
            return Err(HelixError::HeadTooShort {
                head_bond: self.head_bond(),
            });
        }
        let dphi = self.angular_step()?;
        let hb = self.head_bond();
        let lift = libm::sqrt(libm::fmax(hb * hb - self.radius * self.radius, 0.0));
        Ok(Positions {
            helix: *self,
            dphi,
            lift,
            next: 0,
        })
    }
}

/// The bead centres of a [`Helix`], head first ([`Helix::positions`]).
#[derive(Clone, Debug)]
pub struct Positions {
    helix: Helix,
    dphi: f64,
    lift: f64,
    next: usize,
}

impl Positions {
    /// The angular step between consecutive tails.
    pub fn angular_step(&self) -> f64 {
        self.dphi
    }
}

impl Iterator for Positions {
    type Item = [f64; 3];

    fn next(&mut self) -> Option<[f64; 3]> {
        let k = self.next;
        if k > self.helix.tails {
            return None;
        }
        self.next += 1;
        if k == 0 {
            return Some([0.0; 3]);
        }
        let sign = match self.helix.head_end {
            HeadEnd::Bottom => 1.0,
            HeadEnd::Top => -1.0,
        };
        let (r, pitch) = (self.helix.radius, self.helix.pitch);
        let phi = sign * (k - 1) as f64 * self.dphi;
        let z = sign * self.lift + pitch * phi / (2.0 * PI);
        Some([r * libm::cos(phi), r * libm::sin(phi), z])
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = (self.helix.tails + 1).saturating_sub(self.next);
        (left, Some(left))
    }
}

impl ExactSizeIterator for Positions {}
