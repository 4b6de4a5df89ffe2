//! One file per subcommand: its arguments (clap) and the library calls it makes.

pub mod args;
pub mod chart;
pub mod collect;
pub mod figure1;
pub mod phase;
pub mod reference;
pub mod resume;
pub mod run;
pub mod sweep;
