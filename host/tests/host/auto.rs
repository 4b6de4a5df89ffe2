//! `level = "auto"` picks the cheapest adequate model from the scene's numbers.

use hydrorattle_host::auto::{choose, interaction, stokes_number};
use hydrorattle_host::scene::{Hydrodynamics, Method, Scene};

fn dimer(density: f64, gravity: f64, separation: f64, vorticity: f64) -> Scene {
    let text = format!(
        r#"
[gravity]
acceleration = [0.0, 0.0, {g}]
[flow]
vorticity = [0.0, 0.0, {vorticity}]
[[particle]]
position = [0.0, 0.0, 0.0]
radius = 1.0
density = {density}
[[particle]]
position = [{separation}, 0.0, 0.0]
radius = 1.0
density = {density}
[[bond]]
between = [0, 1]
[model]
level = "auto"
[integrator]
method = "rattle"
dt = 0.01
duration = 1.0
"#,
        g = -gravity
    );
    Scene::parse(&text, "inline").unwrap()
}

#[test]
fn stokes_number_matches_design_units() {
    // Density 4.5, gravity 1: lone sphere settles at 1, St = (2/9) 4.5 = 1.
    assert!((stokes_number(&dimer(4.5, 1.0, 3.0, 0.0)) - 1.0).abs() < 1e-12);
    // Density 0.045, gravity 100: same weight, St = 0.01.
    assert!((stokes_number(&dimer(0.045, 100.0, 3.0, 0.0)) - 0.01).abs() < 1e-12);
}

#[test]
fn colloids_close_together_get_overdamped_rpy() {
    let c = choose(&dimer(0.0045, 1000.0, 3.0, 0.0)); // St = 0.001
    assert!(!c.inertia);
    assert_eq!(c.method, Method::Overdamped);
    assert_eq!(c.hydrodynamics, Hydrodynamics::Rpy);
    assert!(!c.rotation);
}

#[test]
fn heavy_particles_keep_inertia_with_the_stable_drag() {
    let c = choose(&dimer(4.5, 1.0, 3.0, 0.0)); // St = 1
    assert!(c.inertia);
    assert_eq!(c.method, Method::RattleStable);
    let spun = choose(&dimer(4.5, 1.0, 3.0, 0.5));
    assert!(
        spun.rotation,
        "inertial spheres in a rotating fluid resolve rotation"
    );
}

#[test]
fn far_apart_spheres_are_free_draining() {
    // 3 a / (4 r) <= 0.01 needs r >= 75 a.
    let far = dimer(0.0045, 1000.0, 100.0, 0.0);
    assert!((interaction(&far) - 0.0075).abs() < 1e-12);
    assert_eq!(choose(&far).hydrodynamics, Hydrodynamics::FreeDraining);
    assert_eq!(
        choose(&dimer(0.0045, 1000.0, 50.0, 0.0)).hydrodynamics,
        Hydrodynamics::Rpy
    );
}

#[test]
fn the_run_records_the_choice() {
    let scene = dimer(0.0045, 1000.0, 3.0, 0.0);
    let opts = hydrorattle_host::sim::RunOptions {
        progress: false,
        max_steps: Some(5),
        ..Default::default()
    };
    let r = hydrorattle_host::sim::run(&scene, "auto", None, opts).unwrap();
    let c = r
        .summary
        .level_choice
        .expect("auto level records its choice");
    assert_eq!(c.method, Method::Overdamped);
    assert_eq!(r.summary.integrator.method, Method::Overdamped);
    assert!(c.reason.contains("overdamped"));
}
