//! Writes `memory.x` for cortex-m-rt's `link.x`: 256 KiB of flash and, unless
//! `HYDRORATTLE_FW_RAM` says otherwise (bytes, or with a `K` suffix), 64 KiB of RAM,
//! at QEMU mps2-an386's code and data SRAM. With flip-link the stack gets what the
//! statics leave of the RAM, so a smaller RAM is a smaller stack.
//!
//! Also writes `geometry.rs`: the Figure 1 (c) helix computed here, on the build
//! machine, by the same scene code the host check runs (`f64`, `libm`), as exact bit
//! patterns. The firmware starts from that constant, so it links no `f64` maths
//! (about 11 KB of soft-float trigonometry) and starts from the host's very bits.

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
    fs::write(out.join("geometry.rs"), geometry()).expect("writing geometry.rs");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-env-changed=HYDRORATTLE_FW_RAM");
    println!("cargo:rerun-if-changed=build.rs");
}

/// The helix as a `Helix` constant built from bit patterns (no decimal round trip).
fn geometry() -> String {
    let h = hydrorattle_scene::helix(hydrorattle_scene::B).expect("the scene's helix");
    let bits = |x: &f64| format!("f64::from_bits({:#018x})", x.to_bits());
    let list = |xs: &[f64]| xs.iter().map(bits).collect::<Vec<_>>().join(", ");
    let pos: Vec<String> = h.pos.iter().map(|c| format!("[{}]", list(c))).collect();
    format!(
        "/// The Figure 1 (c) helix, computed by the build script.\n\
         const GEOMETRY: hydrorattle_scene::Helix = hydrorattle_scene::Helix {{\n    \
         pos: [{}],\n    radius: [{}],\n    length: [{}],\n}};\n",
        pos.join(", "),
        list(&h.radius),
        list(&h.length)
    )
}
