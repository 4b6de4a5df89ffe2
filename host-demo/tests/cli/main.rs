//! The command line's integration tests, one binary: each file of this folder is a
//! module (`cargo test --release -p host-demo --test cli sweep::` runs one file's).
//! A new test file `tests/cli/NAME.rs` is added by one line below, `mod NAME;`, and
//! `use crate::common::...` inside it for the shared helpers.

/// The calling test file's scratch folder `name`, removed ([`common::scratch`]).
macro_rules! scratch {
    ($name:expr) => {
        $crate::common::scratch(module_path!(), $name)
    };
}

/// The calling test file's scratch folder `name`, empty ([`common::empty_dir`]).
macro_rules! empty_dir {
    ($name:expr) => {
        $crate::common::empty_dir(module_path!(), $name)
    };
}

mod common;

// The tests' one deterministic generator, shared with the kernel's tests.
#[path = "../../../tests/kernel/common/fuzz.rs"]
mod fuzz;

mod bad_input;
mod brownian_scene;
mod large;
mod library_names;
mod one_writer;
mod periodic_scene;
mod pictures;
mod record;
mod run;
mod scenes;
mod sigkill;
mod sigterm;
mod sweep;
mod sweep_owner;
