//! The thread pool's integration tests, one binary: each file of this folder is a
//! module (`cargo test --release -p hydrorattle-parallel --test parallel pool::` runs
//! one file's). A new test file `tests/parallel/NAME.rs` is added by one line below,
//! `mod NAME;`.

// The tests' one deterministic generator, shared with the kernel's tests.
#[path = "../../../tests/kernel/common/fuzz.rs"]
mod fuzz;

mod bits;
mod block;
mod compact;
mod ewald_bits;
mod free_fast_bits;
mod pair_bits;
mod pool;
mod pse_bits;
mod wall_bits;
