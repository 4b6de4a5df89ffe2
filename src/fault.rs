//! The errors the low layers raise: a particle set's or a geometry's input
//! ([`ParticleError`]), a bond set's ([`BondError`]), a factorisation's
//! ([`LinalgError`]). Defined below everything that raises them; the step's own error,
//! which wraps them, is in `error.rs` (re-exported from there, the public path).

use core::fmt;

/// A particle set rejected an input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParticleError {
    /// The set is full (capacity `N`).
    Full,
    /// A position, velocity, radius or density is NaN or infinite.
    NonFinite {
        /// Index of the particle.
        particle: usize,
    },
    /// Radius is zero, negative or subnormal (below the precision's smallest normal
    /// number, where `1 / (6 pi eta a)` loses its digits or overflows).
    BadRadius {
        /// Index of the particle.
        particle: usize,
    },
    /// Density is negative.
    BadDensity {
        /// Index of the particle.
        particle: usize,
    },
    /// One sphere lies inside the other (`|r_i - r_j| <= |a_i - a_j|`).
    Nested {
        /// First particle.
        i: usize,
        /// Second particle.
        j: usize,
    },
    /// Two centres coincide (`r_i = r_j`): no overlap policy allows it (the pair has
    /// no direction; with equal radii the spheres are one).
    Coincident {
        /// First particle.
        i: usize,
        /// Second particle.
        j: usize,
    },
    /// Two spheres overlap (`|r_i - r_j| < a_i + a_j`) and the policy rejects it.
    Overlap {
        /// First particle.
        i: usize,
        /// Second particle.
        j: usize,
    },
    /// An inertial method needs every particle to have positive mass.
    Massless {
        /// Index of the particle.
        particle: usize,
    },
    /// The sphere crosses the wall or lies below it: its centre is below
    /// `height + radius` ([`Wall`](crate::Wall)).
    BelowWall {
        /// Index of the particle.
        particle: usize,
    },
    /// In a periodic box, a coordinate so far from the origin that its spacing in the
    /// precision (`eps |x|`) reaches half the sphere's radius: the minimum image of a
    /// separation is lost in the rounding, so no pair geometry can be computed (a
    /// position given there, or a step that would carry a sphere there).
    Unresolved {
        /// Index of the particle.
        particle: usize,
    },
}

/// A bond set rejected an input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BondError {
    /// The bond list is full (capacity `B`).
    Full,
    /// A bond joins a particle to itself.
    SelfBond {
        /// Index of the bond.
        bond: usize,
        /// The particle.
        particle: usize,
    },
    /// A bond names a particle that does not exist.
    OutOfRange {
        /// Index of the bond.
        bond: usize,
        /// The index given.
        particle: usize,
    },
    /// The same pair is bonded twice.
    Duplicate {
        /// Index of the later bond.
        bond: usize,
        /// Index of the earlier bond.
        other: usize,
    },
    /// Length is negative, not finite, or so large that its square overflows; or zero
    /// in a step of a method other than [`Method::Springs`](crate::Method::Springs)
    /// (only a spring may have rest length zero); or, in a periodic box
    /// ([`Params::periodic`](crate::Params::periodic)), not below half the box's
    /// smallest edge (its minimum image would be ambiguous).
    BadLength {
        /// Index of the bond.
        bond: usize,
    },
    /// The configuration is off the constraint by more than the tolerance.
    Violated {
        /// Index of the bond.
        bond: usize,
        /// Relative length error `| |r_ij| - d | / d`.
        residual: f64,
    },
    /// A FENE spring at or past its maximum extension (at the start of a step, or in
    /// the step's candidate: the step is refused; a shorter step may pass).
    Overstretched {
        /// Index of the bond.
        bond: usize,
        /// Length over the maximum extension (>= 1, or NaN).
        ratio: f64,
    },
    /// A tree needs `parents.len() == particles` and each parent index below its child.
    BadTree {
        /// The child whose parent is invalid.
        particle: usize,
    },
}

/// A factorisation or solve failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinalgError {
    /// The matrix is not (numerically) positive definite; the pivot at `row` was not positive.
    NotPositiveDefinite {
        /// Scalar row where the pivot failed.
        row: usize,
    },
    /// The matrix is (numerically) singular at `row`.
    Singular {
        /// Scalar row where the pivot vanished.
        row: usize,
    },
}

impl fmt::Display for ParticleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Full => write!(f, "particle set is full"),
            Self::NonFinite { particle } => write!(f, "particle {particle}: non-finite value"),
            Self::BadRadius { particle } => write!(
                f,
                "particle {particle}: radius must be > 0 and normal (not subnormal)"
            ),
            Self::BadDensity { particle } => write!(f, "particle {particle}: density must be >= 0"),
            Self::Nested { i, j } => {
                write!(f, "particles {i} and {j}: one sphere inside the other")
            }
            Self::Coincident { i, j } => write!(
                f,
                "particles {i} and {j}: coincident centres (refused even where overlaps are allowed)"
            ),
            Self::Overlap { i, j } => write!(f, "particles {i} and {j} overlap"),
            Self::Massless { particle } => {
                write!(f, "particle {particle}: inertial method needs mass > 0")
            }
            Self::BelowWall { particle } => write!(
                f,
                "particle {particle}: sphere below or crossing the wall (centre below height + radius)"
            ),
            Self::Unresolved { particle } => write!(
                f,
                "particle {particle}: a coordinate too far from the origin for the periodic box (its spacing in the precision reaches half the radius; the minimum image is lost in the rounding)"
            ),
        }
    }
}

impl fmt::Display for BondError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Full => write!(f, "bond list is full"),
            Self::SelfBond { bond, particle } => {
                write!(f, "bond {bond}: particle {particle} bonded to itself")
            }
            Self::OutOfRange { bond, particle } => {
                write!(f, "bond {bond}: particle index {particle} out of range")
            }
            Self::Duplicate { bond, other } => write!(f, "bond {bond} duplicates bond {other}"),
            Self::BadLength { bond } => write!(
                f,
                "bond {bond}: length must be finite and > 0 (0 only for springs; below half the smallest edge of a periodic box)"
            ),
            Self::Violated { bond, residual } => {
                write!(f, "bond {bond}: configuration off by relative {residual:e}")
            }
            Self::Overstretched { bond, ratio } => write!(
                f,
                "bond {bond}: FENE spring at {ratio:.6} of its maximum extension (must stay below 1)"
            ),
            Self::BadTree { particle } => {
                write!(
                    f,
                    "tree: particle {particle} needs a parent with a smaller index"
                )
            }
        }
    }
}

impl fmt::Display for LinalgError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NotPositiveDefinite { row } => {
                write!(f, "matrix not positive definite (pivot at row {row})")
            }
            Self::Singular { row } => write!(f, "matrix singular (pivot at row {row})"),
        }
    }
}

impl core::error::Error for ParticleError {}
impl core::error::Error for BondError {}
impl core::error::Error for LinalgError {}
