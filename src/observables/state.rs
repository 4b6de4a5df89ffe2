//! Named states of a settling chain, read from one frame: the vocabulary of
//! the outcome timeline. A frame's numbers ([`Shape`]) come from the motion and shape
//! observables; [`state_of`] names them with the thresholds of [`StateThresholds`].
//!
//! The states are tried in a fixed order and the first that fits names the frame:
//! stretched, column over knot, rolling ring, rotating, folded, other.

use super::motion::{Rotation, extents, poloidal_circulation, spin_about_vertical, vertical_run};
use super::{extension, verticality};
use crate::bonds::Bond;
use crate::real::Real;

/// What a chain is doing in one frame: a name read from the frame, not the particles'
/// state a step advances ([`crate::State`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FrameState {
    /// Hangs straight along the vertical ("stretched like a chopstick"): verticality
    /// and extension both high.
    Stretched,
    /// A vertical column of consecutive near-vertical bonds above or below a compact
    /// rest (a knot).
    ColumnOverKnot,
    /// Compact (ends close together) and rolling over itself: coherent poloidal
    /// circulation, a smoke ring's motion.
    RollingRing,
    /// Turning about the vertical through the centre of mass, coherently ("twisting").
    Rotating,
    /// Compact, none of the motions above.
    Folded,
    /// None of the above: an open chain, tilted or tumbling.
    Other,
}

impl FrameState {
    /// Every state, in the fixed order of the classifier (and of any legend).
    pub const ALL: [FrameState; 6] = [
        FrameState::Stretched,
        FrameState::ColumnOverKnot,
        FrameState::RollingRing,
        FrameState::Rotating,
        FrameState::Folded,
        FrameState::Other,
    ];

    /// Lower-case name, as written to files.
    pub fn name(self) -> &'static str {
        match self {
            FrameState::Stretched => "stretched",
            FrameState::ColumnOverKnot => "column_over_knot",
            FrameState::RollingRing => "rolling_ring",
            FrameState::Rotating => "rotating",
            FrameState::Folded => "folded",
            FrameState::Other => "other",
        }
    }

    /// The state of a name written by [`FrameState::name`].
    pub fn from_name(name: &str) -> Option<FrameState> {
        FrameState::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Position in [`FrameState::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// [`FrameState::name`], as a free function (for plotting code that maps states to names).
pub fn state_name(s: FrameState) -> &'static str {
    s.name()
}

/// One frame's numbers, from which [`state_of`] names the state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape<T> {
    /// End-to-end distance over contour length.
    pub extension: T,
    /// `|cos|` of the head-to-end vector with gravity.
    pub verticality: T,
    /// Rotation about the vertical through the centre of mass.
    pub spin: Rotation<T>,
    /// Poloidal circulation (rolling over itself).
    pub poloidal: Rotation<T>,
    /// Longest run of consecutive near-vertical bonds.
    pub vertical_run: usize,
    /// Number of bonds.
    pub bonds: usize,
    /// Sum of the bond lengths.
    pub contour: T,
    /// Largest horizontal distance between two centres.
    pub horizontal: T,
    /// Spread of the centres' heights.
    pub vertical: T,
}

impl<T: Real> Shape<T> {
    /// Measures a chain (bonds in chain order, bead 0 the head): positions, velocities,
    /// masses, gravity, and the cosine above which a bond counts as near-vertical.
    /// `O(N^2)` (the horizontal extent) plus one gyration-tensor eigenvector.
    pub fn measure(
        pos: &[T::V3],
        vel: &[T::V3],
        mass: &[T],
        bonds: &[Bond<T>],
        gravity: T::V3,
        cos_min: T,
    ) -> Self {
        let (horizontal, vertical) = extents::<T>(pos, gravity);
        Shape {
            extension: extension::<T>(pos, bonds),
            verticality: verticality::<T>(pos, gravity),
            spin: spin_about_vertical::<T>(pos, vel, mass, gravity),
            poloidal: poloidal_circulation::<T>(pos, vel, mass),
            vertical_run: vertical_run::<T>(bonds, pos, gravity, cos_min).1,
            bonds: bonds.len(),
            contour: bonds.iter().fold(T::ZERO, |a, b| a + b.length),
            horizontal,
            vertical,
        }
    }
}

/// Thresholds of [`state_of`]. Defaults (see [`Default`]):
///
/// * stretched: verticality >= 0.95 and extension >= 0.85;
/// * column over knot: a run of at least 6 near-vertical bonds (a quarter of the
///   paper's 24) whose rest is compact: horizontal extent at most 0.5 of the rest's
///   contour length (the bonds outside the run);
/// * compact (rolling ring, folded): extension at most 0.35;
/// * rolling ring: compact, poloidal coherence >= 0.5 and `|poloidal rate|` >= 0.01
///   rad per time unit;
/// * rotating: spin coherence >= 0.5 and `|spin rate|` >= 0.002 rad per time unit
///   (a turn per ~3000 time units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateThresholds<T> {
    /// Minimum verticality of a stretched chain.
    pub stretched_verticality: T,
    /// Minimum extension of a stretched chain.
    pub stretched_extension: T,
    /// Minimum run of near-vertical bonds of a column.
    pub column_bonds: usize,
    /// Largest horizontal extent of a column's knot, over the knot's contour length.
    pub knot_spread: T,
    /// Largest extension of a compact chain.
    pub compact_extension: T,
    /// Minimum poloidal coherence of a rolling ring.
    pub rolling_coherence: T,
    /// Minimum `|poloidal rate|` of a rolling ring.
    pub rolling_rate: T,
    /// Minimum spin coherence of a rotating chain.
    pub spin_coherence: T,
    /// Minimum `|spin rate|` of a rotating chain.
    pub spin_rate: T,
}

impl<T: Real> Default for StateThresholds<T> {
    fn default() -> Self {
        Self {
            stretched_verticality: T::from_f64(0.95),
            stretched_extension: T::from_f64(0.85),
            column_bonds: 6,
            knot_spread: T::HALF,
            compact_extension: T::from_f64(0.35),
            rolling_coherence: T::HALF,
            rolling_rate: T::from_f64(0.01),
            spin_coherence: T::HALF,
            spin_rate: T::from_f64(0.002),
        }
    }
}

fn turning<T: Real>(r: &Rotation<T>, coherence: T, rate: T) -> bool {
    r.coherence >= coherence && r.rate.abs() >= rate
}

/// `true` when a rotation about the vertical is coherent and fast enough to count as
/// turning ([`StateThresholds::spin_coherence`], [`StateThresholds::spin_rate`]),
/// whatever the shape: the "twisting" of a chain that also stretches or folds (the
/// state [`FrameState::Rotating`] is this motion when no shape state applies first).
pub fn is_rotating<T: Real>(spin: &Rotation<T>, th: &StateThresholds<T>) -> bool {
    turning(spin, th.spin_coherence, th.spin_rate)
}

/// Names a frame: the first of [`FrameState::ALL`] whose definition fits (see
/// [`StateThresholds`]); [`FrameState::Other`] when none does.
pub fn state_of<T: Real>(s: &Shape<T>, th: &StateThresholds<T>) -> FrameState {
    let compact = s.extension <= th.compact_extension;
    if s.verticality >= th.stretched_verticality && s.extension >= th.stretched_extension {
        return FrameState::Stretched;
    }
    if s.vertical_run >= th.column_bonds && s.vertical_run < s.bonds && s.bonds > 0 {
        let rest = T::from_f64((s.bonds - s.vertical_run) as f64) / T::from_f64(s.bonds as f64);
        if s.horizontal <= th.knot_spread * rest * s.contour {
            return FrameState::ColumnOverKnot;
        }
    }
    if compact && turning(&s.poloidal, th.rolling_coherence, th.rolling_rate) {
        FrameState::RollingRing
    } else if is_rotating(&s.spin, th) {
        FrameState::Rotating
    } else if compact {
        FrameState::Folded
    } else {
        FrameState::Other
    }
}
