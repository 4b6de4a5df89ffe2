//! `hydrorattle._hydrorattle`: the Python extension module of the hydrorattle kernel
//! (PyO3). The Python package `hydrorattle` (in `pysrc/`) wraps it:
//!
//! * [`mobility`]: the dense RPY / Oseen / free-draining mobility and its product
//!   (in a box by PSE where it fits: [`pse`]; in free space by the fast product on
//!   request: [`free`]);
//! * [`system`]: a system stepped by the kernel through the host library's
//!   [`Engine`](hydrorattle_host::sim::Engine);
//! * [`runs`]: scene files and runs, through the CLI's own library code;
//! * [`errors`]: the exception hierarchy mirroring the kernel's typed errors.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

use pyo3::prelude::*;

mod alloc;
mod dense;
mod errors;
mod free;
mod input;
mod mobility;
mod near;
mod params;
mod pse;
mod runs;
mod shared;
mod stepping;
mod system;

/// The extension module.
#[pymodule]
fn _hydrorattle(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    m.add_function(wrap_pyfunction!(mobility::mobility, m)?)?;
    m.add_function(wrap_pyfunction!(mobility::mobility_dot, m)?)?;
    m.add_function(wrap_pyfunction!(runs::run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(runs::resume_run, m)?)?;
    m.add_function(wrap_pyfunction!(runs::read_trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(runs::load_scene_json, m)?)?;
    m.add_class::<system::Core>()?;
    m.add_class::<system::Report>()?;
    Ok(())
}
