//! Generator of the kernel's two-sphere resistance tables (`src/near/tables.rs`).
//!
//! Jeffrey and Onishi's (1984) twin-multipole recurrences give each resistance function
//! as a power series in `1/s`; near contact the series is summed with its lubrication
//! singularity subtracted term by term, which leaves a smooth remainder. This crate
//! computes both and writes them as Rust constants: `cargo run --release -p
//! hydrorattle-near-gen` rewrites `src/near/tables.rs`, and a test checks that the
//! checked-in file equals a fresh generation. The same run writes `src/near/wall_table.rs`,
//! the exact sphere-wall functions for motion parallel to the wall ([`wall`]).

pub mod emit;
pub mod recur;
pub mod series;
pub mod wall;

/// Terms of the recurrences summed for the remainder tables.
pub const K_SUM: usize = 200;
/// Terms of the far-field series the kernel sums (from `s = 4` on).
pub const K_FAR: usize = 30;
/// Gap `xi = s - 2` where the far-field series takes over from the tables.
pub const XI_MAX: f64 = 2.0;
/// Size-ratio nodes: `log10(lambda)` from `U_MIN` in steps of `U_STEP`.
pub const N_L: usize = 41;
/// First node of `log10(lambda)`.
pub const U_MIN: f64 = -1.0;
/// Node spacing of `log10(lambda)`.
pub const U_STEP: f64 = 0.05;
/// Gap nodes, uniform in `t = sqrt(xi / XI_MAX)`.
pub const N_T: usize = 33;
/// Gap nodes of the sphere-wall table: `log10(delta)` from `W_U_MIN` in steps of `W_U_STEP`.
pub const W_N: usize = 135;
/// First node of `log10(delta)` (`delta = 1e-5`).
pub const W_U_MIN: f64 = -5.0;
/// Node spacing of `log10(delta)`.
pub const W_U_STEP: f64 = 0.05;
