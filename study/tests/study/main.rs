//! The study's integration tests, one binary: each file of this folder is a module
//! (`cargo test --release -p hydrorattle-study --test study claims::` runs one).
//! A new test file `tests/study/NAME.rs` is added by one line below, `mod NAME;`.

mod claims;
mod cloud;
mod render;
