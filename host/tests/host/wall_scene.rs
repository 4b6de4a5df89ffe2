//! `[wall]` in scene files: parsed, written back in `scene.toml` to
//! the same scene, and run: a sphere and a dimer land, the run records when (the
//! landing time: the end of the first step after which a sphere is held on the wall)
//! and the observables gain the height above the wall and the contacts with it. Bad
//! `[wall]` tables are in `tests/data/bad/wall_*.toml` (file:line, `scenes.rs`).

use hydrorattle_host::scene::{Scene, Wall};
use hydrorattle_host::sim::{OBSERVABLES_CSV, RunOptions, SUMMARY_JSON, run};

/// A sphere `gap` above a wall at `height`, and a tilted dimer beside it, 3 radii
/// higher, free draining (each sphere falls at Stokes' speed 1 at most: the wall only
/// slows it), with hard contacts between spheres when `hard`.
fn scene(height: f64, gap: f64, method: &str, precision: &str, hard: bool) -> String {
    let z = height + 1.0 + gap;
    let contact = if hard {
        "[contact]\nmodel = \"hard\"\n"
    } else {
        ""
    };
    format!(
        "[wall]\nheight = {height}\n\n\
         [[particle]]\nposition = [0.0, 0.0, {z}]\nradius = 1.0\n\n\
         [[particle]]\nposition = [5.0, 0.0, {}]\nradius = 1.0\n\n\
         [[particle]]\nposition = [6.5, 0.0, {}]\nradius = 1.0\n\n\
         [[bond]]\nbetween = [1, 2]\n\n{contact}\
         [model]\nhydrodynamics = \"free-draining\"\n\n\
         [integrator]\nmethod = \"{method}\"\ndt = 0.1\nduration = 12.0\nprecision = \"{precision}\"\n\n\
         [output]\nevery = 10\n",
        z + 3.0,
        z + 4.5
    )
}

#[test]
fn the_wall_reads_and_writes_back() {
    let s = Scene::parse(&scene(-2.5, 2.05, "overdamped", "f64", true), "wall.toml").unwrap();
    assert_eq!(s.wall, Some(Wall { height: -2.5 }));
    let text = s.to_toml();
    assert!(text.contains("[wall]\nheight = -2.5"), "{text}");
    assert_eq!(Scene::parse(&text, "scene.toml").unwrap(), s);
    // Touching at t = 0 is allowed; a scene without the table has no wall.
    let touching = Scene::parse(&scene(-2.5, 0.0, "overdamped2", "f32", false), "t").unwrap();
    assert_eq!(touching.wall.map(|w| w.height), Some(-2.5));
    let plain = scene(-2.5, 2.0, "overdamped", "f64", false).replace("[wall]\nheight = -2.5\n", "");
    let plain = Scene::parse(&plain, "plain").unwrap();
    assert_eq!(plain.wall, None);
    assert!(!plain.to_toml().contains("[wall]"));
}

#[test]
fn spheres_land_and_the_run_records_it() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("wall-scene");
    for (k, (method, precision, hard)) in [
        ("overdamped", "f64", true),
        ("overdamped2", "f64", false),
        ("overdamped", "f32", false),
    ]
    .into_iter()
    .enumerate()
    {
        let (height, gap) = (-2.5, 2.05);
        let s = Scene::parse(&scene(height, gap, method, precision, hard), "wall").unwrap();
        let out = dir.join(format!("{k}"));
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        let r = run(&s, "wall", Some(&out), RunOptions::default()).unwrap();
        let what = format!("{method} {precision} hard {hard}");
        assert_eq!(r.summary.failure, None, "{what}");
        // Free draining, nothing falls faster than Stokes' speed (1 here) above a
        // wall: no landing before gap / 1; and within the run.
        let landing = r.summary.landing_time.expect("landed");
        assert!(landing >= gap - 1e-6 && landing < 12.0, "{what}: {landing}");
        let f = r.summary.final_observables;
        assert_eq!(f.wall_contacts, Some(3), "{what}: all three on the wall");
        let tol = if precision == "f32" { 1e-4 } else { 1e-8 };
        assert!(f.wall_gap.unwrap().abs() <= tol, "{what}: {:?}", f.wall_gap);
        // The centre of mass of three unit spheres on the wall is one radius above it.
        let h = f.wall_height.unwrap();
        assert!((h - 1.0).abs() <= tol, "{what}: {h}");
        for p in &r.last.positions {
            assert!((p[2] - height - 1.0).abs() <= tol, "{what}: {p:?}");
        }
        // The records: the columns in observables.csv, the landing in summary.json.
        let csv = std::fs::read_to_string(out.join(OBSERVABLES_CSV)).unwrap();
        let header = csv.lines().next().unwrap();
        assert!(
            header.contains("wall_height,wall_gap,wall_contacts"),
            "{header}"
        );
        let cells = |row: &str| -> Vec<String> { row.split(',').map(String::from).collect() };
        let (first, last) = (
            cells(csv.lines().nth(1).unwrap()),
            cells(csv.lines().last().unwrap()),
        );
        let n = first.len();
        assert_eq!(
            (first[n - 2].as_str(), last[n - 2].as_str()),
            ("0", "3"),
            "{what}"
        );
        let gap0: f64 = first[n - 3].parse().unwrap();
        // (the sphere's gap: the dimer starts higher)
        assert!((gap0 - gap).abs() <= 1e-6, "{what}: {gap0}");
        let json = std::fs::read_to_string(out.join(SUMMARY_JSON)).unwrap();
        assert!(json.contains("\"landing_time\""), "{what}");
        let again = Scene::parse(
            &std::fs::read_to_string(out.join("scene.toml")).unwrap(),
            "s",
        );
        assert_eq!(again.unwrap().wall, s.wall, "{what}");
    }
}

/// A sphere touching a wall far from the origin: in f32 the coordinates' spacing
/// there (2 at 3e7) exceeds the radius, so its centre rounds onto the plane, and the
/// parse refuses it at its position (the step's own test in the step's precision),
/// where before the parse passed it and the run stopped at step 1. In f64 it runs.
#[test]
fn a_touching_sphere_far_from_the_origin_is_judged_in_the_run_precision() {
    let text = |precision| {
        format!(
            "[wall]\nheight = -3e7\n\n\
             [[particle]]\nposition = [0.0, 0.0, -29999999.0]\nradius = 1.0\n\n\
             [contact]\nmodel = \"hard\"\n\n\
             [integrator]\nmethod = \"overdamped\"\ndt = 0.1\nduration = 0.2\nprecision = \"{precision}\"\n"
        )
    };
    let e = Scene::parse(&text("f32"), "far.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("far.toml:5:")
            && e.contains("particle 0: sphere below or crossing the wall")
            && e.contains("in f32"),
        "{e}"
    );
    let s = Scene::parse(&text("f64"), "far.toml").unwrap();
    let r = run(&s, "far", None, RunOptions::default()).unwrap();
    assert_eq!(r.summary.failure, None);
}
