//! Writes `memory.x` for cortex-m-rt's `link.x`: 256 KiB of flash and, unless
//! `HYDRORATTLE_FW_RAM` says otherwise (bytes, or with a `K` suffix), 64 KiB of RAM,
//! at QEMU mps2-an386's code and data SRAM. With flip-link the stack gets what the
//! statics leave of the RAM, so a smaller RAM is a smaller stack.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let ram = env::var("HYDRORATTLE_FW_RAM").unwrap_or_else(|_| "64K".into());
    let ok = ram.trim_end_matches('K').parse::<u32>().is_ok();
    assert!(
        ok,
        "HYDRORATTLE_FW_RAM must be a byte count or NNK, not {ram:?}"
    );
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory = format!(
        "MEMORY\n{{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 256K\n  \
         RAM : ORIGIN = 0x20000000, LENGTH = {ram}\n}}\n"
    );
    fs::write(out.join("memory.x"), memory).expect("writing memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-env-changed=HYDRORATTLE_FW_RAM");
    println!("cargo:rerun-if-changed=build.rs");
}
