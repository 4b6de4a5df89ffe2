//! The host library of hydrorattle, shared by the CLI (`host-demo`), the Python package
//! and the sweeps. It draws nothing and links no CLI, terminal or plotting crate.
//!
//! * [`scene`]: TOML scene files parsed and validated into a plain [`scene::Scene`]
//!   (errors at file and line), and written back;
//! * [`sim`]: the run: the [`sim::Engine`] (the host's one call of the kernel step),
//!   the run's stages, records, checkpoints and resume;
//! * [`output`]: atomic file writes, trajectories (extended XYZ, GSD), CSV and JSON;
//! * [`sweep`]: parameter sweeps (sweep files, point folders with signac ids, SLURM and
//!   GNU parallel engines, the collected table);
//! * [`auto`], [`sizing`] (in [`scene`]): the level a scene models and the storage it
//!   needs;
//! * [`progress`]: progress of long jobs, shown by whatever display a front end installs;
//! * [`provenance`]: the code version and machine a record names.

pub mod output;
pub mod progress;
pub mod provenance;
pub mod scene;
pub mod sim;
pub mod sweep;

// A scene's level and its storage are the scene's concern (its reader refuses a scene
// too large at the line that makes it so); their paths stay at the top for callers.
pub use scene::{auto, sizing};
