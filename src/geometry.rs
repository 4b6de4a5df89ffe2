//! The geometry as a step sees it, above the mobility's geometries (`mobility`: free
//! space, wall, periodic box, PSE) and the noise, below the constraint solvers and the
//! integrators that read it: the periodic sums a step holds (`sums`, with the `periodic` feature). The step's own
//! error ([`StepError`](crate::StepError)) is in reach here, not in `mobility`, whose
//! geometries raise only their own errors.

#[cfg(feature = "periodic")]
pub mod sums;
