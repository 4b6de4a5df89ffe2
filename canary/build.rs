//! Linker arguments for the host (x86_64 Linux) no_std build: no C runtime start
//! files (the binary brings its own `_start`), and the C library linked only for the
//! `memcpy`/`memset` family that `core` expects the platform to provide (on bare-metal
//! targets `compiler_builtins` supplies them). The thumbv7em build needs nothing extra.

fn main() {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if os == "linux" {
        println!("cargo:rustc-link-arg-bins=-nostartfiles");
        println!("cargo:rustc-link-arg-bins=-lc");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
