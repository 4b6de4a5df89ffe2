//! Typed errors: one small `Copy` enum per operation, each with `Display`.
//!
//! Payloads name the particle, bond or matrix row at fault; residuals are carried as
//! `f64` so the enums stay independent of the precision.

use core::fmt;

// The low layers' errors are defined below them (`fault.rs`) and wrapped here.
pub use crate::fault::{BondError, LinalgError, ParticleError};

/// Element counts of the storage arrays one step uses (counted in `workspace/layout.rs`;
/// declared here because [`StepError::Storage`] reports it): four numeric arrays, and the
/// constraint list of a step with contacts or a wall (`links`, zero otherwise).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Layout {
    /// 3x3 blocks (factors; the packed mobility above a wall and of the inertial
    /// methods).
    pub blocks: usize,
    /// 3-vectors (forces, velocities, candidate state, bond vectors, solver vectors).
    pub vectors: usize,
    /// Scalars (multipliers, masses, solver matrices; the overdamped methods' packed
    /// mobility in free space, six scalars a symmetric block).
    pub scalars: usize,
    /// Indices (LU pivots).
    pub indices: usize,
    /// Constraint links (bonds followed by contacts and wall links) of a step with
    /// [`Params::contacts`](crate::Params::contacts) or [`Params::wall`](crate::Params::wall); zero otherwise.
    pub links: usize,
}

/// Where in a step a linear-algebra failure happened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Factorising the mobility (resistance through Cholesky).
    Mobility,
    /// Factorising the implicit drag operator.
    Drag,
    /// Solving for position multipliers.
    Positions,
    /// Solving for velocity multipliers.
    Velocities,
    /// Estimating the explicit-drag stability limit.
    Stability,
    /// The active set of hard-sphere contacts (which pairs touch).
    Contacts,
}

/// What a constraint row of a step holds, by the caller's numbering: the rows are the
/// caller's bond list (bonds and pin rows, [`Bond::pin`](crate::Bond::pin)), then the
/// step's one-sided rows (contacts and wall links).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// Bond `k` of the caller's list.
    Bond(usize),
    /// The pin row of a sphere along an axis (0, 1, 2: x, y, z).
    Pin {
        /// The sphere.
        particle: usize,
        /// The axis.
        axis: usize,
    },
    /// A hard-sphere contact between two spheres.
    Contact {
        /// First sphere (the smaller index).
        i: usize,
        /// Second sphere.
        j: usize,
    },
    /// A sphere's link to the wall.
    Wall {
        /// The sphere.
        particle: usize,
    },
}

impl Row {
    /// Row `k` of a step whose rows are `rows`, the one-sided ones (contacts, wall
    /// links) from `one_sided` on; a `k` past `rows` is named as bond `k`.
    pub fn of<T: crate::Real>(rows: &[crate::Bond<T>], k: usize, one_sided: usize) -> Self {
        // A row past the list (no caller names one) is read as a bond: no panic path.
        let Some(b) = rows.get(k) else {
            return Self::Bond(k);
        };
        match () {
            _ if b.is_pin() => Self::Pin {
                particle: b.i,
                axis: b.axis(),
            },
            _ if b.is_wall() => Self::Wall { particle: b.i },
            _ if k >= one_sided => Self::Contact {
                i: b.i.min(b.j),
                j: b.i.max(b.j),
            },
            _ => Self::Bond(k),
        }
    }
}

impl fmt::Display for Row {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Bond(k) => write!(f, "bond {k}"),
            Self::Pin { particle, axis } => {
                let name = ["x", "y", "z"].get(axis).copied().unwrap_or("?");
                write!(f, "the pin of particle {particle} along {name}")
            }
            Self::Contact { i, j } => write!(f, "the contact of particles {i} and {j}"),
            Self::Wall { particle } => write!(f, "the wall contact of particle {particle}"),
        }
    }
}

/// Most constraints a [`StepError::Infeasible`] lists.
pub const INFEASIBLE_SHOWN: usize = 4;

/// A step failed; the caller's state is exactly as it was before the call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepError {
    /// `dt` is zero, negative or not finite.
    BadTimeStep,
    /// A parameter other than `dt` is invalid (named).
    BadParameter(&'static str),
    /// The particle set is invalid (checked at the start of the step).
    Particle(ParticleError),
    /// The bond set is invalid for these particles.
    Bond(BondError),
    /// A factorisation failed.
    Linalg {
        /// The stage.
        stage: Stage,
        /// The failure.
        error: LinalgError,
    },
    /// A constraint solve hit its iteration cap.
    NoConvergence {
        /// Which solve.
        stage: Stage,
        /// Iterations done.
        iterations: u32,
        /// Largest residual left.
        residual: f64,
    },
    /// A bond turned so far in one step that the linearised update has no root
    /// (the SHAKE denominator vanished or changed sign), or a hard contact would end
    /// on the far side of where its pair started (the step carried one sphere past the
    /// other).
    Degenerate {
        /// The bond; past the bonds, contact `bond - bonds` of the step.
        bond: usize,
        /// What that row holds (a bond, a pin, a contact or a wall link), named as
        /// the message prints it.
        row: Row,
    },
    /// The constraints cannot all hold at once: the geometry is infeasible (a sphere
    /// squeezed between two that cannot move apart: a bond shorter than the spheres
    /// between its ends, walls of spheres pinned by bonds). Found where the
    /// constraints are linearly dependent and the solve stops converging on them
    /// (`docs/CONTACTS.md`).
    Infeasible {
        /// The constraints of the dependent set, in increasing index (a bond; past the
        /// bonds, one-sided constraint `k - bonds` of the step: a contact or a wall
        /// link); the first `shown` are valid.
        constraints: [usize; INFEASIBLE_SHOWN],
        /// How many of `constraints` are valid.
        shown: usize,
        /// How many constraints the dependent set holds (`shown` of them listed: the
        /// ones carrying the largest forces).
        count: usize,
    },
    /// A velocity or position became NaN or infinite.
    NonFinite {
        /// The particle.
        particle: usize,
    },
    /// The force on a particle (buoyant weight plus the caller's
    /// [`ExternalForce`](crate::ExternalForce)) is NaN or infinite: bad input, not a
    /// failure of the step (nothing was integrated).
    NonFiniteForce {
        /// The particle.
        particle: usize,
    },
    /// Two spheres overlap or nest after the step, and the policy rejects it.
    Overlap {
        /// First particle.
        i: usize,
        /// Second particle.
        j: usize,
    },
    /// The workspace is smaller than this step's [`Layout`]; nothing was touched.
    Storage {
        /// What the step needs.
        need: Layout,
        /// What the workspace holds.
        have: Layout,
    },
    /// The state's slices disagree in length.
    StateLength,
    /// The explicit-drag step is beyond its linear stability limit.
    Unstable {
        /// The step asked for.
        dt: f64,
        /// The largest stable step for this configuration.
        limit: f64,
    },
    /// More spheres would touch at once than [`Contacts::capacity`](crate::Contacts)
    /// holds (with a wall, plus one wall link per sphere: the pool of one-sided
    /// constraints, [`Params::constraints`](crate::Params::constraints)).
    ContactsFull {
        /// The capacity.
        capacity: usize,
    },
    /// The combination asked for is not implemented (named): for example thermal noise
    /// with a method other than `Overdamped`, or without a stored mobility.
    Unsupported(&'static str),
}

impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::BadTimeStep => write!(f, "time step must be finite and > 0"),
            Self::BadParameter(name) => write!(f, "invalid parameter: {name}"),
            Self::Particle(e) => write!(f, "{e}"),
            Self::Bond(e) => write!(f, "{e}"),
            Self::Linalg { stage, error } => write!(f, "{stage:?}: {error}"),
            Self::NoConvergence {
                stage,
                iterations,
                residual,
            } => write!(
                f,
                "{stage:?} constraint solve did not converge in {iterations} iterations (residual {residual:e})"
            ),
            Self::Degenerate { row, .. } => {
                write!(
                    f,
                    "{row} turned too far in one step (degenerate SHAKE update)"
                )
            }
            Self::Infeasible {
                constraints,
                shown,
                count,
            } => {
                write!(f, "constraints")?;
                for (k, c) in constraints.iter().take(shown).enumerate() {
                    write!(f, "{}{c}", if k == 0 { " " } else { ", " })?;
                }
                if count > shown {
                    write!(f, " (of {count} dependent)")?;
                }
                write!(
                    f,
                    " cannot all hold: infeasible geometry (spheres squeezed by constraints that cannot give way)"
                )
            }
            Self::NonFinite { particle } => {
                write!(f, "particle {particle}: state became non-finite")
            }
            Self::NonFiniteForce { particle } => write!(
                f,
                "particle {particle}: the force on it is NaN or infinite (weight plus external force)"
            ),
            Self::Overlap { i, j } => write!(f, "particles {i} and {j} overlap after the step"),
            Self::Storage { need, have } => write!(
                f,
                "workspace too small: need {} blocks, {} vectors, {} scalars, {} indices, {} links; have {}, {}, {}, {}, {}",
                need.blocks,
                need.vectors,
                need.scalars,
                need.indices,
                need.links,
                have.blocks,
                have.vectors,
                have.scalars,
                have.indices,
                have.links
            ),
            Self::StateLength => write!(f, "state slices differ in length"),
            Self::Unstable { dt, limit } => write!(
                f,
                "explicit drag unstable: dt = {dt:e} exceeds the stability limit {limit:e}"
            ),
            Self::ContactsFull { capacity } => write!(
                f,
                "more than {capacity} contacts at once (raise the contact capacity)"
            ),
            Self::Unsupported(what) => write!(f, "not supported: {what}"),
        }
    }
}

impl core::error::Error for StepError {}

impl From<ParticleError> for StepError {
    fn from(e: ParticleError) -> Self {
        Self::Particle(e)
    }
}

/// A fast free-space product's error as the step's own
/// ([`crate::mobility::free_fast::FreeError`]): particles as the pair blocks', the rest
/// named (no new variant reaches callers' matches).
#[cfg(feature = "fast-free")]
impl From<crate::mobility::free_fast::FreeError> for StepError {
    fn from(e: crate::mobility::free_fast::FreeError) -> Self {
        use crate::mobility::free_fast::FreeError as E;
        match e {
            E::BadParameter("tolerance") => Self::BadParameter(
                "pse (the fast free-space product's tolerance, mobility::free_fast::MIN_TOLERANCE to MAX_TOLERANCE)",
            ),
            E::BadParameter("viscosity") => Self::BadParameter("viscosity"),
            E::BadParameter(_) => Self::BadParameter(
                "the fast free-space product's parameters (a largest radius and a cloud's extent finite and > 0)",
            ),
            E::Precision { .. } => Self::BadParameter(
                "a fast free-space tolerance below what the precision can reach (mobility::free_fast::min_tolerance)",
            ),
            E::GridTooLarge => Self::Unsupported(
                "a fast free-space tolerance and cloud whose grid exceeds the bounds (mobility::free_fast::MAX_GRID, MAX_SUPPORT)",
            ),
            E::Length => Self::StateLength,
            E::Particle(e) => Self::Particle(e),
            E::Radius { particle } => Self::Particle(ParticleError::BadRadius { particle }),
            E::Extent => Self::Unsupported(
                "a fast free-space product beyond the cloud's extent widened by integrate::FAST_MARGIN radii (a step's trial positions that far from its start)",
            ),
            E::Storage { .. } => Self::BadParameter(
                "the workspace's fast free-space storage (Workspace::with_fast, at least integrate::fast_storage)",
            ),
        }
    }
}

/// A failed Lanczos square root (the noise's, or PSE's real part's) as the step's error,
/// at the mobility stage.
impl From<crate::noise::lanczos::LanczosError> for StepError {
    fn from(e: crate::noise::lanczos::LanczosError) -> Self {
        use crate::noise::lanczos::LanczosError as E;
        match e {
            E::NoConvergence { iterations, change } => Self::NoConvergence {
                stage: Stage::Mobility,
                iterations,
                residual: change,
            },
            E::NotPositiveDefinite { .. } => Self::Linalg {
                stage: Stage::Mobility,
                error: LinalgError::NotPositiveDefinite { row: 0 },
            },
            E::Storage => Self::BadParameter("lanczos.max_iterations (> 0)"),
        }
    }
}

impl From<BondError> for StepError {
    fn from(e: BondError) -> Self {
        Self::Bond(e)
    }
}
