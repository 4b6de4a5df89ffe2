//! # hydrorattle
//!
//! A `#![no_std]`, allocation-free kernel for HydroRATTLE (A. S. Kim, 2012):
//! RATTLE/SHAKE constraint dynamics of bonded rigid spheres in Stokesian dynamics with
//! the far-field Rotne-Prager-Yamakawa grand mobility.
//!
//! Everything is generic over the precision ([`Real`]: `f32`, `f64`) and over the
//! particle capacity `N` (and bond capacity `B`); all storage is caller-owned.
//!
//! Where to look:
//! * RPY formulas: [`mobility`];
//! * Cholesky and solves: [`linalg`]; the mobility's work in bands for hosts' threads:
//!   [`parallel`];
//! * the SHAKE sweep, Newton solve and RATTLE velocity sweep: [`constraints`];
//! * [`step`] and its stages: [`integrate`] (one file per integrator; the paper's
//!   velocity-Verlet HydroRATTLE step is `src/integrate/rattle.rs`).
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// `!(x <= tol)` is deliberate throughout: NaN must fail the test, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Index loops over several parallel arrays read like the paper's formulas.
#![allow(clippy::needless_range_loop)]

pub mod bonds;
pub mod cell;
pub mod cell_list;
pub mod constraints;
pub mod error;
mod error_info;
pub mod forces;
pub mod helix;
pub mod integrate;
pub mod linalg;
pub mod mobility;
pub mod names;
#[cfg(feature = "near")]
pub mod near;
pub mod noise;
pub mod observables;
pub mod parallel;
pub mod params;
pub mod particles;
pub mod real;
#[cfg(feature = "near")]
pub mod stokesian;
pub mod workspace;

pub use bonds::{Bond, BondSet};
pub use cell::{Periodic, PeriodicError};
pub use constraints::{DENSE_BONDS_MAX, Solver, SolverKind};
pub use error::{BondError, INFEASIBLE_SHOWN, LinalgError, ParticleError, Row, Stage, StepError};
pub use forces::{ExternalForce, NoForce, SoftContact};
/// The vector crate the kernel is written against (re-exported so callers match versions).
pub use glam;
pub use integrate::{StepReport, check_step, step, step_slices};
pub use mobility::Hydro;
pub use names::{Named, UnknownName};
pub use noise::Noise;
pub use noise::lanczos::{Lanczos, LanczosError};
pub use parallel::{Parallel, Serial};
pub use params::{Brownian, Contacts, Drift, LANCZOS_CROSSOVER, Method, NoiseSqrt, Params, Wall};
pub use particles::{Particle, ParticleSet, State};
pub use real::Real;
pub use workspace::{Layout, Storage, Workspace};
