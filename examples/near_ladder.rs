//! The model ladder's speed and accuracy on the Figure 1 chain: free draining, Oseen,
//! RPY, and RPY with Stokesian dynamics' near field (`Params::near`).
//!
//! `cargo run --release --example near_ladder [steps]` (default 20) prints CSV, and
//! appends it to `bench/results/near_ladder.csv` as records where
//! `HYDRORATTLE_BENCH_MACHINE` names the machine: for each rung, the seconds of one step of the
//! Figure 1 (c) chain (a head of radius 2 and 24 tails, bonds `D = 1.05`, settling from
//! its helix: `Overdamped2`, Newton, hard contacts, `dt = 0.1`, f64, one core; the mean
//! over `steps` steps from the start), and the error of its two-sphere mobility at the
//! chain's tail gap (`s = 2.1`) against the exact values: two equal spheres falling
//! along their line of centres at 1.53633 `U0` (Stimson and Jeffery's series, summed in
//! `tests/kernel/stokesian.rs`) and across it at 1.3917 `U0` (the published value).

use std::time::Instant;

#[path = "shared/record.rs"]
mod record;

use glam::DVec3;
use hydrorattle::helix::{HeadEnd, Helix};
use hydrorattle::linalg::tri;
use hydrorattle::stokesian::{NearField, mobility, storage};
use hydrorattle::{
    BondSet, Contacts, Hydro, Layout, Method, NoForce, Params, Particle, ParticleSet, SolverKind,
    step,
};
use hydrorattle_heap::Buffers;

/// Exact two-sphere speeds at `s = 2.1`, in units of Stokes' speed.
const ALONG: f64 = 1.53633;
const ACROSS: f64 = 1.3917;

/// `(along, across)` of the two-sphere mobility at `s = 2.1` (unit spheres, unit fluid),
/// in units of Stokes' mobility.
fn two_sphere(level: Hydro, near: bool) -> (f64, f64) {
    let u0 = 1.0 / (6.0 * std::f64::consts::PI);
    let pos = [DVec3::ZERO, DVec3::new(0.0, 0.0, 2.1)];
    let radius = [1.0, 1.0];
    if near {
        let (nb, nd) = storage(2);
        let (mut packed, mut m) = (vec![glam::DMat3::ZERO; nb], vec![0.0; nd]);
        mobility(
            1.0,
            None,
            &pos,
            &radius,
            NearField::default(),
            &mut packed,
            &mut m,
        )
        .expect("two spheres");
        return ((m[2 * 12 + 2] + m[2 * 12 + 5]) / u0, (m[0] + m[3]) / u0);
    }
    let mut mu = [glam::DMat3::ZERO; tri(2)];
    hydrorattle::mobility::assemble_tt(level, 1.0, &pos, &radius, &mut mu).expect("pair");
    let (s, c) = (mu[0], mu[1]);
    (
        (s.z_axis.z + c.z_axis.z) / u0,
        (s.x_axis.x + c.x_axis.x) / u0,
    )
}

/// Seconds per step of the Figure 1 (c) chain at `level` (with the near field if
/// `near`), over `steps` steps.
fn step_cost(level: Hydro, near: bool, steps: usize) -> f64 {
    let h = Helix {
        tails: 24,
        head_ratio: 2.0,
        dhat: 1.05,
        radius: 2.0,
        pitch: 7.0,
        head_end: HeadEnd::Bottom,
    };
    let list: Vec<Particle<f64>> = h
        .positions()
        .expect("helix")
        .enumerate()
        .map(|(k, p)| Particle::new(DVec3::from_array(p), h.bead_radius(k), 4.5))
        .collect();
    let mut ps = ParticleSet::<f64, 25>::from_slice(&list, true).expect("chain");
    let bonds = BondSet::<f64, 24>::chain(&ps.pos[..25]).expect("bonds");
    let mut p = Params::new(0.1);
    p.method = Method::Overdamped2;
    p.hydro = level;
    p.solver.kind = SolverKind::Newton;
    p.allow_overlap = true;
    p.contacts = Some(Contacts::new(4 * 25));
    p.near = near.then(NearField::default);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 25, 24));
    let mut ws = buf.workspace();
    let t = Instant::now();
    for k in 0..steps {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("{level:?} near {near}: step {k}: {e}"));
    }
    t.elapsed().as_secs_f64() / steps as f64
}

fn main() {
    let steps = std::env::args()
        .nth(1)
        .map_or(20, |s| s.parse().expect("steps"));
    println!("rung,step_s,along_U0,across_U0,along_error,across_error,max_abs_error");
    let rungs = [
        ("free-draining", Hydro::FreeDraining, false),
        ("oseen", Hydro::Oseen, false),
        ("rpy", Hydro::Rpy, false),
        ("rpy+near", Hydro::Rpy, true),
    ];
    let command = format!("target/release/examples/near_ladder {steps}");
    let mut rec = record::Recorder::new(env!("CARGO_MANIFEST_DIR"), "near_ladder", command);
    let table = "model ladder, Figure 1 (c) chain, f64, one core";
    for (name, level, near) in rungs {
        let (along, across) = two_sphere(level, near);
        let (ea, ec) = (along / ALONG - 1.0, across / ACROSS - 1.0);
        let cost = step_cost(level, near, steps);
        let worst = ea.abs().max(ec.abs());
        println!("{name},{cost:.3e},{along:.5},{across:.5},{ea:+.4},{ec:+.4},{worst:.4}");
        for (quantity, value) in [
            ("s a step", format!("{cost:.3e}")),
            ("along, U0 (s = 2.1)", format!("{along:.5}")),
            ("across, U0 (s = 2.1)", format!("{across:.5}")),
            ("along, relative error", format!("{ea:+.4}")),
            ("across, relative error", format!("{ec:+.4}")),
            ("largest relative error", format!("{worst:.4}")),
        ] {
            rec.row(table, name, quantity, &value);
        }
    }
    rec.finish().expect("appending the records");
}
