//! `[slit]` in scene files: parsed, written back in `scene.toml` to the same scene, and
//! run: the shipped `slit.toml` settles onto the floor, and a lone sphere at the
//! midplane falls at superposition's speed across the walls. Bad `[slit]` tables are
//! in the CLI's `tests/data/bad/slit_*.toml` (file:line).

use hydrorattle_host::scene::{Scene, Slit};
use hydrorattle_host::sim::{RunOptions, run};

const SHIPPED: &str = include_str!("../../scenes/slit.toml");

/// One unit sphere of density 4.5 (Stokes' speed 1: `2/9 (4.5) g a^2 / eta`) at height
/// `z` in the slit `[0, 2 l]`, one step of `dt`.
fn lone(l: f64, z: f64, dt: f64) -> String {
    format!(
        "[slit]\nfloor = 0.0\nceiling = {}\n\n\
         [[particle]]\nposition = [0.0, 0.0, {z}]\nradius = 1.0\ndensity = 4.5\n\n\
         [integrator]\nmethod = \"overdamped\"\ndt = {dt}\nduration = {dt}\n",
        2.0 * l
    )
}

#[test]
fn the_slit_reads_and_writes_back() {
    let s = Scene::parse(SHIPPED, "slit.toml").unwrap();
    let want = Slit {
        floor: 0.0,
        ceiling: 20.0,
    };
    assert_eq!(s.slit, Some(want));
    let text = s.to_toml();
    assert!(
        text.contains("[slit]\nceiling = 20.0\nfloor = 0.0"),
        "{text}"
    );
    assert_eq!(Scene::parse(&text, "scene.toml").unwrap(), s);
    let plain = Scene::parse(&lone(10.0, 10.0, 0.01), "lone").unwrap();
    let plain = Scene {
        slit: None,
        ..plain
    };
    assert!(!plain.to_toml().contains("[slit]"));
}

/// Across the walls superposition's midplane mobility is `1 - 9/4 x + x^3 - 1/4 x^5`
/// of Stokes' (`x = a / l`, each wall's perpendicular self term summed; derived in
/// `docs/GEOMETRY.md`, "The slit"). This is superposition's own closed form, not the
/// exact slit's: the first step's speed is checked against it.
#[test]
fn a_sphere_at_the_midplane_falls_at_superpositions_speed() {
    for l in [5.0, 10.0] {
        let dt = 1e-3;
        let s = Scene::parse(&lone(l, l, dt), "lone").unwrap();
        let r = run(&s, "lone", None, RunOptions::default()).unwrap();
        assert_eq!(r.summary.failure, None);
        let speed = (l - r.last.positions[0][2]) / dt;
        let x = 1.0 / l;
        let want = 1.0 - 2.25 * x + x.powi(3) - 0.25 * x.powi(5);
        assert!((speed - want).abs() < 1e-9, "l = {l}: {speed} vs {want}");
    }
}

/// The shipped scene settles: the chain ends on the floor (held there, not past it),
/// below the ceiling, its bonds kept.
#[test]
fn the_shipped_slit_scene_settles_onto_the_floor() {
    let s = Scene::parse(SHIPPED, "slit.toml").unwrap();
    let r = run(&s, "slit", None, RunOptions::default()).unwrap();
    assert_eq!(r.summary.failure, None);
    let low = r
        .last
        .positions
        .iter()
        .map(|p| p[2])
        .fold(f64::INFINITY, f64::min);
    assert!((low - 1.0).abs() < 1e-6, "lowest centre at {low}");
    assert!(r.last.positions.iter().all(|p| p[2] <= 19.0));
}
