//! The Figure 1 study of hydrorattle and its pictures, over the host library
//! (`hydrorattle-host`): runs in, tables and pictures out.
//!
//! * [`figure1`]: the paper's Figure 1 (three helices settling), its claims and pictures;
//! * [`mod@reference`]: the Figure 1 runs against a small-dt reference (agreement horizons);
//! * [`phase`]: the outcome map over the bond gap and head ratio, and the sensitivity table;
//! * [`cloud`]: a falling cloud's core, tail and density about its axis (the torus);
//! * [`claims`]: the paper's claims judged on a run's observables;
//! * [`charts`]: accuracy and speed charts of the integrators and solvers;
//! * [`render`]: sphere pictures (side and top views, the Figure 1 layout, snapshots,
//!   GIF animations), state timelines and charts, with an embedded font ([`fonts`]);
//! * [`pictures`]: the pictures of a run, drawn after it from its record;
//! * [`timeline`]: a run's states over time;
//! * [`collect`]: a sweep's collected table with each Figure 1 point's claims, and its chart.

pub mod charts;
pub mod claims;
pub mod cloud;
pub mod collect;
pub mod figure1;
pub mod fonts;
pub mod phase;
pub mod pictures;
pub mod reference;
pub mod render;
pub mod timeline;
