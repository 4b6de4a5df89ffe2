//! Sweep files: expansion order, zip groups, replicas, linspace, state points, and the
//! place of errors.

use std::path::Path;

use serde_json::json;

use super::Sweep;
use crate::scene::Scene;

/// The dimer scene with a `[sweep]` table added.
fn dimer_with(sweep: &str) -> String {
    let dimer = include_str!("../../../host-demo/scenes/dimer.toml");
    format!("{dimer}\n[sweep]\n{sweep}")
}

fn parse(text: &str) -> Result<Sweep, crate::scene::SceneError> {
    Sweep::parse(text, "s.toml", Path::new("."))
}

#[test]
fn lists_combine_as_a_product_in_file_order_the_last_fastest() {
    let s = parse(&dimer_with(
        "\"integrator.dt\" = [0.01, 0.02]\n\"particle.1.radius\" = [1.0, 1.1, 0.5]\n",
    ))
    .unwrap();
    assert_eq!(s.keys, ["integrator.dt", "particle.1.radius"]);
    let got: Vec<(f64, f64)> = s
        .points
        .iter()
        .map(|p| (p.scene.integrator.dt, p.scene.particles[1].radius))
        .collect();
    let want = [
        (0.01, 1.0),
        (0.01, 1.1),
        (0.01, 0.5),
        (0.02, 1.0),
        (0.02, 1.1),
        (0.02, 0.5),
    ];
    assert_eq!(got, want);
    // The rest of the scene is the base's.
    let base = Scene::parse(
        include_str!("../../../host-demo/scenes/dimer.toml"),
        "dimer",
    )
    .unwrap();
    let mut p = s.points[4].scene.clone();
    (p.integrator.dt, p.particles[1].radius) = (base.integrator.dt, base.particles[1].radius);
    p.output = base.output;
    assert_eq!(p.particles, base.particles);
    assert_eq!(p.bonds.len(), 1);
    assert_eq!(
        s.points[4].statepoint,
        json!({"integrator": {"dt": 0.02}, "particle": {"1": {"radius": 1.1}}})
    );
}

#[test]
fn zip_groups_vary_together_and_replicas_count_seeds() {
    let text = format!(
        "{}\n[brownian]\ntemperature = 0.5\nseed = 40\n\n[sweep]\nreplicas = 3\n\"model.hydrodynamics\" = [\"rpy\", \"free-draining\"]\n\n[[sweep.zip]]\n\"integrator.dt\" = [0.01, 0.02]\n\"integrator.duration\" = [1.0, 2.0]\n",
        include_str!("../../../host-demo/scenes/dimer.toml")
    );
    let s = parse(&text).unwrap();
    assert_eq!(s.points.len(), 2 * 2 * 3);
    assert_eq!(s.replicas, 3);
    for p in &s.points {
        let i = &p.scene.integrator;
        assert_eq!(i.duration / i.dt, 100.0, "dt and duration go together");
        let seed = p.scene.brownian.unwrap().seed;
        assert_eq!(seed, 40 + p.replica.unwrap() as u64);
        assert_eq!(p.statepoint["brownian"]["seed"], json!(seed));
    }
    let ids: std::collections::BTreeSet<&str> = s.points.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids.len(), 12, "every point has its own id");
}

#[test]
fn linspace_is_the_phase_grid_and_ints_stay_ints() {
    let s = parse(&dimer_with(
        "\"integrator.dt\" = { linspace = [0.01, 0.02, 3] }\n\"output.every\" = [5]\n",
    ))
    .unwrap();
    let dts: Vec<f64> = s.points.iter().map(|p| p.scene.integrator.dt).collect();
    assert_eq!(dts, crate::sweep::linspace(0.01, 0.02, 3));
    assert_eq!(s.points[0].statepoint["output"]["every"], json!(5));
    assert!(s.points[0].statepoint["output"]["every"].is_i64());
}

fn error(text: &str) -> (usize, String) {
    let e = parse(text).unwrap_err();
    (e.line().unwrap_or(0), e.to_string())
}

#[test]
fn errors_name_the_line_of_the_value_at_fault() {
    let base_lines = include_str!("../../../host-demo/scenes/dimer.toml")
        .lines()
        .count();
    // The [sweep] header is two lines after the base; its first key the next.
    let first = base_lines + 3;
    let (line, msg) = error(&dimer_with("\"integrator.dt\" = [0.01, 30.0]\n"));
    assert_eq!(line, first, "{msg}");
    assert!(
        msg.contains("dt (30) is longer than the duration (20)"),
        "{msg}"
    );
    let (line, msg) = error(&dimer_with(
        "\"integrator.dt\" = [0.01]\n\"fluid.viscosity\" = [1,\n -1]\n",
    ));
    assert_eq!(line, first + 2, "{msg}");
    assert!(msg.contains("viscosity must be > 0"), "{msg}");
    let (line, msg) = error(&dimer_with("\"particle.5.radius\" = [1.0]\n"));
    assert_eq!(line, first, "{msg}");
    assert!(msg.contains("particle has 2 entries"), "{msg}");
    let (line, msg) = error(&dimer_with("\"integrator.dt.x\" = [1.0]\n"));
    assert_eq!(line, first, "{msg}");
    assert!(msg.contains("integrator.dt is a value"), "{msg}");
    let (line, msg) = error(&dimer_with("helix.dhat = [1.0]\n"));
    assert_eq!(line, first, "{msg}");
    assert!(msg.contains("quoted"), "{msg}");
    let (line, msg) = error(&dimer_with("\"integrator.dt\" = 0.01\n"));
    assert_eq!(line, first, "{msg}");
    assert!(msg.contains("must be a list"), "{msg}");
    // An error of the base scene itself is at its own line.
    let broken =
        dimer_with("\"integrator.dt\" = [0.01]\n").replace("radius = 1.0", "radius = -1.0");
    let (line, msg) = error(&broken);
    let radius_line = broken
        .lines()
        .position(|l| l.contains("radius = -1.0"))
        .unwrap()
        + 1;
    assert_eq!(line, radius_line, "{msg}");
    // No [sweep] at all.
    let e = parse(include_str!("../../../host-demo/scenes/dimer.toml")).unwrap_err();
    assert!(e.to_string().contains("no [sweep] table"), "{e}");
}
