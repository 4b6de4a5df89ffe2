//! Where a run's numbers came from: the code version (from `git describe` at build
//! time) and the machine.

use serde::Serialize;

/// The code version: the crate version and `git describe` of the build's checkout
/// (`no git` when built outside one).
pub const CODE_VERSION: &str = env!("HYDRORATTLE_HOST_VERSION");

/// The library that writes the records and trajectories, and its crate version: the
/// application a trajectory file names (GSD's `application` field).
pub const APPLICATION: &str = concat!("hydrorattle-host ", env!("CARGO_PKG_VERSION"));

/// The machine a run ran on.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Machine {
    /// Operating system (`linux`, `macos`, ...).
    pub os: String,
    /// CPU architecture (`x86_64`, `aarch64`, ...).
    pub arch: String,
    /// Processor model, where the system tells it (Linux `/proc/cpuinfo`).
    pub cpu: Option<String>,
    /// Logical CPUs available to the process.
    pub cpus: usize,
}

impl Machine {
    /// This machine.
    pub fn this() -> Machine {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|text| {
                text.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            });
        Machine {
            os: std::env::consts::OS.to_string(),
            arch: std::env::consts::ARCH.to_string(),
            cpu,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}
