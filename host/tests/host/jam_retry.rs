//! A jammed pile at long steps: 100 spheres dropped in a column onto the wall inside a
//! container of 36 pinned spheres (two rings of 18, radius 1.5), the dense Newton solve
//! with contacts and wall links as inequalities. At dt 0.2 and 0.3 the drop runs to
//! rest; from the rest state, steps of 5, 10 and 100 keep it at rest. Each step
//! either passes in the kernel or is retried by the host as split steps
//! (`sim::retry`; from rest the kernel refuses steps from about 3 on).
//! Checked against invariants only: no overlap and no wall crossing beyond the
//! tolerance after any step, the pins' spheres never move, and the pile comes to rest
//! (no sphere moving by 1e-9 in three consecutive steps).
//!
//! `cargo test --release -p hydrorattle-host --test host jam_retry::`

use std::f64::consts::PI;

use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::Engine;

/// The container scene at `dt` (two rings of pinned spheres on the wall at 0, the
/// column of 100 jittered by a fixed pattern).
fn container(dt: f64) -> Scene {
    let mut text = format!(
        "[fluid]\nviscosity = 1.0\ndensity = 0.0\n[gravity]\nacceleration = [0.0, 0.0, -1.0]\n\
         [model]\nhydrodynamics = \"rpy\"\ninertia = false\nrotation = false\n\
         [wall]\nheight = 0.0\n[contact]\nmodel = \"hard\"\ncapacity = 700\n\
         [integrator]\nmethod = \"overdamped\"\ndt = {dt}\nduration = 1000.0\n\
         solver = \"newton\"\ntolerance = 1e-10\nmax_iterations = 500\nprecision = \"f64\"\n"
    );
    let ring = 1.501 / (PI / 18.0).sin();
    for layer in 0..2 {
        for k in 0..18 {
            let a = 2.0 * PI * (k as f64 + 0.5 * layer as f64) / 18.0;
            let (x, y, z) = (ring * a.cos(), ring * a.sin(), 1.5 + 3.0 * layer as f64);
            text += &format!(
                "[[particle]]\nposition = [{x}, {y}, {z}]\nradius = 1.5\ndensity = 10.0\nfixed = true\n"
            );
        }
    }
    // A fixed jitter pattern (an LCG), so that the column is not a lattice.
    let mut seed = 7u64;
    let mut jitter = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        0.1 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    };
    for n in 0..100 {
        let (l, i, j) = (n / 9, (n % 9) / 3, n % 3);
        let x = 2.3 * (i as f64 - 1.0) + jitter();
        let y = 2.3 * (j as f64 - 1.0) + jitter();
        let z = 2.6 + 2.3 * l as f64 + jitter();
        text += &format!("[[particle]]\nposition = [{x}, {y}, {z}]\nradius = 1.0\ndensity = 4.5\n");
    }
    Scene::parse(&text, "container.toml").expect("the container scene parses")
}

/// Largest relative overlap of two spheres and of a sphere with the wall.
fn worst_violation(e: &Engine<f64>) -> f64 {
    let (pos, r) = (&e.beads.pos, &e.beads.radius);
    let mut worst = f64::MIN;
    for i in 0..pos.len() {
        worst = worst.max(1.0 - pos[i].z / r[i]);
        for j in 0..i {
            worst = worst.max(1.0 - (pos[i] - pos[j]).length() / (r[i] + r[j]));
        }
    }
    worst
}

/// Steps `e` until no sphere moves by 1e-9 in three steps running (at most `cap`
/// steps), checking every step; returns the steps taken.
fn to_rest(e: &mut Engine<f64>, scene: &Scene, cap: usize, what: &str) -> usize {
    let pinned: Vec<_> = scene.pinned.iter().map(|&k| e.beads.pos[k]).collect();
    let tol = e.params.solver.tolerance;
    let (mut still, mut steps) = (0, 0);
    while still < 3 {
        assert!(steps < cap, "{what}: not at rest after {steps} steps");
        let before = e.beads.pos.clone();
        e.step()
            .unwrap_or_else(|err| panic!("{what}: step {}: {err}", steps + 1));
        steps += 1;
        let v = worst_violation(e);
        assert!(v <= 2.0 * tol, "{what}: step {steps}: violation {v:e}");
        let moved = (0..before.len())
            .map(|i| (e.beads.pos[i] - before[i]).length())
            .fold(0.0, f64::max);
        still = if moved < 1e-9 { still + 1 } else { 0 };
    }
    for (k, &i) in scene.pinned.iter().enumerate() {
        assert_eq!(e.beads.pos[i], pinned[k], "{what}: pinned sphere {i} moved");
    }
    steps
}

#[test]
fn a_jammed_pile_runs_to_rest_at_long_steps() {
    for dt in [0.2, 0.3] {
        let scene = container(dt);
        let mut e = Engine::<f64>::new(&scene, usize::MAX).expect("the scene builds");
        let steps = to_rest(&mut e, &scene, 2000, &format!("drop at dt {dt}"));
        eprintln!(
            "dt {dt}: at rest after {steps} steps, {} steps retried split",
            e.retries.steps
        );
        if dt != 0.2 {
            continue;
        }
        // From rest, steps far longer than the settling time: still at rest.
        for long in [5.0, 10.0, 100.0] {
            e.params.dt = long;
            to_rest(&mut e, &scene, 20, &format!("at rest, dt {long}"));
            eprintln!(
                "dt {long} from rest: {} steps retried split",
                e.retries.steps
            );
        }
    }
}
