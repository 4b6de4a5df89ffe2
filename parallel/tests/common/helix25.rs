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

/// The scene's head radius over the tails'.
pub const HEAD_RATIO: f64 = HELIX.head_ratio;

/// The helix with head ratio `head_ratio`.
fn helix(head_ratio: f64) -> Helix {
    Helix {
        head_ratio,
        ..HELIX
    }
}

/// The beads of the helix of head ratio `head_ratio` (the scene's: [`HEAD_RATIO`]),
/// rotated by `tilt` (radians) about the `x` axis, every bead of density `density`
/// (the scene's is 4.5).
pub fn beads(tilt: f64, density: f64, head_ratio: f64) -> ParticleSet<f64, N> {
    let h = helix(head_ratio);
    let (s, c) = (libm::sin(tilt), libm::cos(tilt));
    let mut set = ParticleSet::new();
    for (k, [x, y, z]) in h.positions().expect("helix").enumerate() {
        let at = DVec3::new(x, c * y - s * z, s * y + c * z);
        set.push(Particle::new(at, h.bead_radius(k), density))
            .expect("bead");
    }
    set
}

/// The bonds of the helix of head ratio `head_ratio`: bead `k` to `k + 1` at
/// `dhat (a_k + a_{k+1})`.
pub fn bonds(head_ratio: f64) -> Vec<Bond<f64>> {
    let h = helix(head_ratio);
    (0..h.tails)
        .map(|k| Bond {
            i: k,
            j: k + 1,
            length: h.bond_length(k),
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
