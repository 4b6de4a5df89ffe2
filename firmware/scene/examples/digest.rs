//! The host side of the host-versus-Cortex-M check: runs every firmware binary's case
//! on this machine and prints the same summary lines the firmware prints over
//! semihosting. `cargo run --release --example digest [NAME ...]`.

use hydrorattle::{Buffers, Layout, ParticleSet};
use hydrorattle_scene::{N, RUNS, STEPS, chain, params, run, summary};

fn main() {
    let only: Vec<String> = std::env::args().skip(1).collect();
    let mut out = String::new();
    for (name, method, rotation) in RUNS {
        if !only.is_empty() && !only.iter().any(|o| o == name) {
            continue;
        }
        let mut ps = ParticleSet::<f32, N>::new();
        let bonds = chain(&mut ps).expect("the scene builds");
        let p = params::<f32>(method, rotation);
        let mut store = Buffers::<f32>::new(Layout::for_params(&p, N, bonds.len()));
        let outcome = run(&mut ps, &bonds, &p, &mut store.workspace(), STEPS, |_| {});
        summary(&mut out, method, rotation, &outcome).expect("writing to a String");
    }
    print!("{out}");
}
