//! A random close packing compressed under gravity in a periodic box: a
//! polydisperse suspension settles onto a pinned floor (`[floor]`, the kernel's pin
//! rows) and jams. Checked: no overlap beyond the tolerance at any step, the run comes
//! to rest, the floor has not moved, at rest the pins carry the buoyant weight of every
//! sphere (1e-9 in f64: the references are the spheres' weights, `4/3 pi a^3 rho g`),
//! and the bed's packing fraction in its middle layers lies between random loose
//! (0.55) and the densest random packing of frictionless polydisperse spheres (0.66).
//!
//! CI: 30 spheres on a 3 x 3 floor (`cargo test --release -p hydrorattle-host --test
//! packing`). The full scene `host/scenes/packing.toml` (160 spheres on 5 x 5)
//! is `#[ignore]`d: `cargo test --release -p hydrorattle-host --test host packing:: --
//! --ignored --nocapture` (the same run as `cargo run --release -p host-demo -- run
//! host/scenes/packing.toml --out out/packing`).

use std::f64::consts::PI;

use hydrorattle_host::scene::{Scene, slab_fraction};
use hydrorattle_host::sim::Engine;

/// What a run to rest measured.
struct Rest {
    steps: usize,
    time: f64,
    worst_overlap: f64,
    load_error: f64,
    fraction: f64,
    height: f64,
}

fn settle(scene: &Scene, max_steps: usize) -> Rest {
    let mut e = Engine::<f64>::new(scene, usize::MAX).expect("the scene builds");
    let n = e.beads.len();
    let size = scene.periodic.expect("a box").size;
    let floor: Vec<[f64; 3]> = scene
        .pinned
        .iter()
        .map(|&k| e.beads.pos[k].to_array())
        .collect();
    let tol = e.params.solver.tolerance;
    let (mut still, mut steps, mut worst) = (0, 0, f64::MIN);
    while still < 3 {
        assert!(steps < max_steps, "not at rest after {steps} steps");
        let before = e.beads.pos.clone();
        e.step()
            .unwrap_or_else(|err| panic!("step {}: {err}", steps + 1));
        steps += 1;
        let pos = &e.beads.pos;
        let moved = (0..n)
            .map(|i| (pos[i] - before[i]).length())
            .fold(0.0, f64::max);
        still = if moved < 1e-9 { still + 1 } else { 0 };
        if steps % 100 == 0 {
            eprintln!("step {steps}: largest move {moved:.1e}");
        }
        let r = &e.beads.radius;
        for i in 0..n {
            for j in 0..i {
                let d = (pos[i] - pos[j]).to_array();
                let d: [f64; 3] =
                    std::array::from_fn(|k| d[k] - size[k] * (d[k] / size[k]).round());
                let s = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                worst = worst.max(1.0 - s / (r[i] + r[j]));
            }
        }
        assert!(worst < 2.0 * tol, "overlap {worst:e} at step {steps}");
    }
    for (k, &i) in scene.pinned.iter().enumerate() {
        assert_eq!(
            e.beads.pos[i].to_array(),
            floor[k],
            "floor sphere {i} moved"
        );
    }
    let g = scene.gravity[2].abs();
    let weight: f64 = scene
        .particles
        .iter()
        .map(|p| 4.0 / 3.0 * PI * p.radius.powi(3) * (p.density - scene.fluid.density) * g)
        .sum();
    let load = e.pin_load().expect("pins loaded")[2];
    // The bed: from one mean diameter above the floor's top to one below the bed's top.
    let pos: Vec<[f64; 3]> = e.beads.pos.iter().map(|p| p.to_array()).collect();
    let free = |k: &usize| !scene.pinned.contains(k);
    let top = (0..n)
        .filter(free)
        .map(|k| pos[k][2] + e.beads.radius[k])
        .fold(0.0, f64::max);
    let floor_top = 2.0 * scene.floor.expect("a floor").radius;
    let d = 2.0 * scene.suspension.expect("a suspension").radius;
    let slab = (floor_top + d, top - d);
    let fraction = slab_fraction(&pos, &e.beads.radius, size[0] * size[1], slab);
    Rest {
        steps,
        time: e.beads.time,
        worst_overlap: worst,
        load_error: (load - weight).abs() / weight,
        fraction,
        height: top - floor_top,
    }
}

fn report(what: &str, r: &Rest) {
    eprintln!(
        "{what}: at rest after {} steps (t = {:.1}), worst overlap {:.1e}, pins carry the weight to {:.1e}, bed height {:.2}, packing fraction {:.4} (middle layers)",
        r.steps, r.time, r.worst_overlap, r.load_error, r.height, r.fraction
    );
}

#[test]
fn small_packing_rests_on_its_pinned_floor() {
    let text = r#"
[suspension]
count = 30
fraction = 0.3
polydispersity = 0.2
seed = 3

[floor]
radius = 1.1

[box]
method = "ewald"

[contact]
model = "hard"

[integrator]
method = "overdamped"
solver = "newton"
dt = 0.2
duration = 100.0
"#;
    let scene = Scene::parse(text, "small_packing").expect("a scene");
    assert_eq!(scene.pinned.len(), 9, "a 3 x 3 floor");
    let r = settle(&scene, 500);
    report("30 spheres", &r);
    assert!(r.load_error < 1e-9);
    // Two layers: the middle slab is thin, so only a loose bound.
    assert!(
        r.fraction > 0.3 && r.fraction < 0.74,
        "fraction {}",
        r.fraction
    );
}

#[test]
#[ignore]
fn packing_scene_rests_on_its_pinned_floor() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/packing.toml");
    // `PACKING_SCENE` names the file where the binary runs from another tree.
    let path = std::env::var("PACKING_SCENE").unwrap_or(path.to_string());
    let scene = Scene::from_path(std::path::Path::new(&path)).expect("the scene");
    let r = settle(&scene, 5000);
    report("packing.toml", &r);
    assert!(r.load_error < 1e-9);
    assert!(
        r.fraction > 0.55 && r.fraction < 0.66,
        "fraction {}",
        r.fraction
    );
}
