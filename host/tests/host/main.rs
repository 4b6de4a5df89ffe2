//! The host library's integration tests, one binary: each file of this folder is a
//! module (`cargo test --release -p hydrorattle-host --test host packing::` runs one).
//! A new test file `tests/host/NAME.rs` is added by one line below, `mod NAME;`.

// The tests' one deterministic generator, shared with the kernel's tests.
#[path = "../../../tests/kernel/common/fuzz.rs"]
mod fuzz;

mod auto;
mod box_sweep;
mod cloud;
mod falling_cloud;
mod free_auto;
mod free_reweigh;
mod free_space_scene;
mod fuzz_scene;
mod geometries;
mod jam_retry;
mod layers;
mod near_field_scene;
mod packing;
mod recovery;
mod slit_scene;
mod wall_scene;
mod xyz_roundtrip;
