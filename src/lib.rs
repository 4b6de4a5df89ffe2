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
//!
//! ## Layers
//!
//! The modules stand in layers, each building only on the layers below it (and on
//! modules of its own layer, without a circle); `host/tests/host/layers.rs` checks this
//! against the same table, and prints the import graph with
//! `cargo test --release -p hydrorattle-host --test host import_graph -- --nocapture`.
//! From the bottom:
//!
//! 1. **Foundation**: [`real`] (the precision, and the stored-block trait
//!    [`linalg::Block`] its 3x3 matrix implements), the low layers' errors
//!    ([`ParticleError`], [`BondError`], [`LinalgError`], re-exported from [`error`]),
//!    and [`helix`] (the paper's chain, in `f64`). Builds on nothing in the crate.
//! 2. **Linear algebra**: [`linalg`] (packed symmetric storage, the banded product
//!    kernel, Cholesky, LU). Builds on the foundation.
//! 3. **Free-space pairs, the periodic cell, the near field's pair functions**: [`rpy`]
//!    (the self and pair blocks of free space), [`cell`] (a periodic box, minimum
//!    images) and `near` (feature `near`: the two-sphere and sphere-wall resistance
//!    functions). Build on linear algebra.
//! 4. **Bonds, cell lists and bands**: [`bonds`], [`cell_list`] (pair searches over
//!    cells) and [`parallel`] (the mobility's work in bands, the [`Parallel`] trait).
//!    Build on the pairs and the cell.
//! 5. **Noise**: [`noise`] (Cholesky, Lanczos and reduced square roots). Builds on the
//!    bands.
//! 6. **The geometries' mobility, particles**: [`mobility`] (free space, wall, periodic
//!    box, PSE: assembly and products), [`particles`] and [`observables`]. Build on the
//!    noise and the bands.
//! 7. **The step's error**: [`error`] ([`StepError`], which wraps every error below and
//!    reports a [`Layout`]). Builds on the geometries.
//! 8. **The geometry a step sees**: [`geometry`] (each geometry's step, what a step
//!    holds for its products: the periodic sums, the fast free-space product), and
//!    `stokesian` (feature `near`: the dense Stokesian dynamics mobility, far field plus
//!    the near field's pair and wall corrections, in free space, above the wall or in
//!    the box, and `stokesian::iterative`, its product for many spheres by conjugate
//!    gradients over the close pairs). Build on the step's error and the geometries.
//! 9. **Constraints**: [`constraints`] (SHAKE sweep, Newton, Krylov, the metric).
//!    Builds on the geometry a step sees.
//! 10. **Configuration**: [`params`], [`forces`], [`names`]. Build on the constraints'
//!     and geometries' choices they name.
//! 11. **Workspace**: [`workspace`] (what a step needs, sized from its parameters).
//! 12. **Integrators**: [`integrate`] ([`step`] and its stages). Build on everything.
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
mod fault;
pub mod forces;
pub mod geometry;
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
pub mod rpy;
#[cfg(feature = "near")]
pub mod stokesian;
pub mod workspace;

pub use bonds::{Bond, BondSet};
pub use cell::{Periodic, PeriodicError};
pub use constraints::{DENSE_BONDS_MAX, PILE_NEWTON_MAX, PILE_NEWTON_ROWS_MAX, Solver, SolverKind};
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
pub use params::{
    Brownian, Contacts, Drift, LANCZOS_CROSSOVER, Method, NEAR_PAIRS_PER_SPHERE, NoiseSqrt, Params,
    Slit, Wall,
};
pub use particles::{Particle, ParticleSet, State};
pub use real::Real;
pub use workspace::{Layout, Storage, Workspace};
