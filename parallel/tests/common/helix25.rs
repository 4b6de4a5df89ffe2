//! The paper's 25-bead helix as `bench/peer/helix25.toml` builds it (the kernel's
//! `helix` module with the scene's defaults: radius 2, pitch 7; density 4.5; the f64
//! overdamped step, Newton to 1e-12), tilted about the `x` axis: the reorientation
//! under gravity a user sweeps over starting angles. Shared by the batch tests and
//! `examples/batch.rs`.

#![allow(dead_code)] // Each user takes a part.

use hydrorattle::constraints::{Solver, SolverKind};
use hydrorattle::glam::DVec3;
use hydrorattle::helix::{HeadEnd, Helix};
use hydrorattle::{Bond, Params, Particle, ParticleSet};

/// Beads of the helix.
pub const N: usize = 25;

/// The scene's helix.
pub const HELIX: Helix = Helix {
    tails: 24,
    head_ratio: 1.259_921_049_894_873_2,
    dhat: 1.5,
    radius: 2.0,
    pitch: 7.0,
    head_end: HeadEnd::Bottom,
};

/// The helix's beads, rotated by `tilt` (radians) about the `x` axis, every bead of
/// density `density` (the scene's is 4.5) and the head's radius times `head_scale`
/// (1 for the scene; the bonds keep the scene's lengths, so a head scaled a little
/// leaves the chain valid).
pub fn beads(tilt: f64, density: f64, head_scale: f64) -> ParticleSet<f64, N> {
    let (s, c) = (libm::sin(tilt), libm::cos(tilt));
    let mut set = ParticleSet::new();
    for (k, [x, y, z]) in HELIX.positions().expect("helix").enumerate() {
        let at = DVec3::new(x, c * y - s * z, s * y + c * z);
        let radius = HELIX.bead_radius(k) * if k == 0 { head_scale } else { 1.0 };
        set.push(Particle::new(at, radius, density)).expect("bead");
    }
    set
}

/// The scene's bonds: bead `k` to `k + 1` at `dhat (a_k + a_{k+1})`.
pub fn bonds() -> Vec<Bond<f64>> {
    (0..HELIX.tails)
        .map(|k| Bond {
            i: k,
            j: k + 1,
            length: HELIX.bond_length(k),
        })
        .collect()
}

/// The scene's parameters (as `hydrorattle_host::scene::params` makes them).
pub fn params() -> Params<f64> {
    let mut p = Params::new(0.01);
    p.solver = Solver {
        kind: SolverKind::Newton,
        tolerance: 1e-12,
        max_iterations: 50,
    };
    p.allow_overlap = true;
    p.stability_guard = true;
    p
}

/// FNV-1a of the positions' bits (`host/examples/step_windows.rs`'s digest).
pub fn digest(pos: &[DVec3]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in pos {
        for x in v.to_array() {
            h = (h ^ x.to_bits()).wrapping_mul(0x100_0000_01b3);
        }
    }
    h
}
