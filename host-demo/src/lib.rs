//! Host-side driver for the hydrorattle kernel: scene files, output writers, pictures
//! and charts, and progress reporting.
//!
//! * [`scene`]: TOML scene files parsed and validated into a plain [`scene::Scene`];
//! * [`output`]: atomic file writes, extended XYZ trajectories (writer and reader),
//!   CSV and JSON;
//! * [`crate::reference`]: the Figure 1 runs against a small-dt reference (agreement horizons);
//! * [`render`]: sphere pictures (side and top views, the Figure 1 layout, snapshots,
//!   GIF animations), state timelines and charts;
//! * [`pictures`]: the pictures of a run and of Figure 1;
//! * [`progress`]: a progress bar that stays out of the way of short or piped runs;
//! * [`sweep`]: parameter sweeps (sweep files, point folders with signac ids, SLURM and
//!   GNU parallel engines, the collected table).

pub mod auto;
pub mod charts;
pub mod claims;
pub mod figure1;
pub mod fonts;
pub mod output;
pub mod phase;
pub mod pictures;
pub mod progress;
pub mod provenance;
pub mod reference;
pub mod render;
pub mod scene;
pub mod sim;
pub mod sizing;
pub mod sweep;
pub mod timeline;
