//! Sweep files: expansion order, zip groups, replicas, linspace, state points, and the
//! place of errors.

use std::path::Path;

use serde_json::json;

use super::Sweep;
use crate::scene::Scene;

/// The dimer scene with a `[sweep]` table added.
fn dimer_with(sweep: &str) -> String {
    let dimer = include_str!("../../scenes/dimer.toml");
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
    let base = Scene::parse(include_str!("../../scenes/dimer.toml"), "dimer").unwrap();
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
        include_str!("../../scenes/dimer.toml")
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
    let base_lines = include_str!("../../scenes/dimer.toml").lines().count();
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
    let e = parse(include_str!("../../scenes/dimer.toml")).unwrap_err();
    assert!(e.to_string().contains("no [sweep] table"), "{e}");
}

/// Sets `value` at a dotted path of a TOML table (numbers index lists), making tables on
/// the way: how a point's scene was written before it was resolved from the parsed
/// base, kept here as the reference.
fn set_in_table(table: &mut toml::Table, key: &str, value: toml::Value) {
    let parts: Vec<&str> = key.split('.').collect();
    let mut node = table
        .entry(parts[0].to_string())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    for p in &parts[1..] {
        node = match node {
            toml::Value::Array(a) => &mut a[p.parse::<usize>().unwrap()],
            toml::Value::Table(t) => t
                .entry(p.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new())),
            other => panic!("{key}: {other} is not a table"),
        };
    }
    *node = value;
}

#[test]
fn each_point_is_the_scene_its_text_would_give() {
    // The base's parsed document with each point's values set, resolved, against the
    // scene of the text written from the base's table with the values set.
    let scenes = [
        ("dimer", include_str!("../../scenes/dimer.toml")),
        ("figure1a", include_str!("../../scenes/figure1a.toml")),
        ("chain", include_str!("../../scenes/periodic_chain.toml")),
        ("brownian", include_str!("../../scenes/brownian_chain.toml")),
    ];
    let sweeps = [
        (
            "dimer",
            "\"integrator.dt\" = [0.01, 0.02]\n\"particle.1.radius\" = [1, 1.1]\n\"fluid.density\" = [0, 0.5]\n",
        ),
        (
            "figure1a",
            "\"helix.dhat\" = { linspace = [1.05, 2.0, 3] }\n[[sweep.zip]]\n\"helix.head_end\" = [\"top\", \"bottom\"]\n\"model.hydrodynamics\" = [\"oseen\", \"free-draining\"]\n",
        ),
        (
            "chain",
            "\"box.size\" = [[16.0, 16.0, 24.0], [20, 20, 20]]\n\"box.method\" = [\"ewald\", \"auto\"]\n",
        ),
        (
            "brownian",
            "replicas = 3\n\"brownian.temperature\" = [0.5, 2]\n\"brownian.drift\" = [\"midpoint\", \"uncorrected\"]\n",
        ),
    ];
    for (name, sweep) in sweeps {
        let base = scenes.iter().find(|s| s.0 == name).unwrap().1;
        let s = parse(&format!("{base}\n[sweep]\n{sweep}")).unwrap();
        assert!(s.points.len() >= 4, "{name}");
        let table: toml::Table = toml::from_str(base).unwrap();
        for p in &s.points {
            let mut t = table.clone();
            for (k, v) in &p.params {
                set_in_table(&mut t, k, v.clone());
            }
            let want = Scene::parse(&toml::to_string(&t).unwrap(), name).unwrap();
            assert_eq!(p.scene, want, "{name}: {}", p.id);
            let json = |s: &Scene| serde_json::to_string(s).unwrap();
            assert_eq!(json(&p.scene), json(&want), "{name}: {}", p.id);
        }
    }
}

#[test]
fn one_point_found_alone_is_the_point_of_the_whole_sweep() {
    let dir = std::env::temp_dir().join(format!("sweep-one-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("s.toml");
    let text = format!(
        "{}\n[brownian]\ntemperature = 0.5\n\n[sweep]\nreplicas = 2\n\"integrator.dt\" = [0.01, 0.02, 0.04]\n\"particle.1.radius\" = [1, 0.5]\n",
        include_str!("../../scenes/dimer.toml")
    );
    std::fs::write(&file, text).unwrap();
    let all = Sweep::from_path(&file).unwrap();
    for p in &all.points {
        for id in [p.id.as_str(), &p.id[..8]] {
            let found = Sweep::point_from_path(&file, id).unwrap().unwrap();
            assert_eq!(found.digest, all.digest);
            assert_eq!(found.count, all.points.len());
            let q = found.point;
            assert_eq!((q.index, &q.id, &q.params), (p.index, &p.id, &p.params));
            assert_eq!((q.replica, &q.statepoint), (p.replica, &p.statepoint));
            assert_eq!(q.scene, p.scene);
        }
    }
    assert!(
        Sweep::point_from_path(&file, "0123456789abcdef")
            .unwrap()
            .is_none()
    );
    let listed = Sweep::check_path(&file).unwrap();
    let ids: Vec<&str> = listed.iter().map(|(id, _)| id.as_str()).collect();
    let want: Vec<&str> = all.points.iter().map(|p| p.id.as_str()).collect();
    assert_eq!(ids, want);
    for ((_, json), p) in listed.iter().zip(&all.points) {
        assert_eq!(*json, super::id::canonical_json(&p.statepoint));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Equal as numbers (integers and floats alike), element by element.
fn same(a: &toml::Value, b: &toml::Value) -> bool {
    let num = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    match (num(a), num(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

#[test]
fn the_first_repeated_point_is_named_as_a_search_of_all_points_names_it() {
    // Lists with repeats in several factors (and a zip group): the error names the
    // first point, in sweep order, equal to an earlier one, and that earlier one, as a
    // comparison of every pair of points finds them.
    let cases: [&[&[&str]]; 5] = [
        &[&["1", "2", "1.0"], &["3", "3.0", "4"]],
        &[&["1", "2", "3"], &["4", "5", "4.0"]],
        &[&["1", "2"], &["7", "8", "9"], &["4", "5", "5"]],
        &[&["2", "1", "2.0", "1"], &["7", "8"]],
        &[&["1", "2"], &["3", "4"]],
    ];
    for lists in cases {
        let keys = ["fluid.viscosity", "fluid.density", "integrator.tolerance"];
        let body: String = lists
            .iter()
            .zip(keys)
            .map(|(l, k)| format!("\"{k}\" = [{}]\n", l.join(", ")))
            .collect();
        let value =
            |v: &str| toml::from_str::<toml::Table>(&format!("v = {v}")).unwrap()["v"].clone();
        let values: Vec<Vec<toml::Value>> = lists
            .iter()
            .map(|l| l.iter().map(|v| value(v)).collect())
            .collect();
        // Every point in sweep order (the last list fastest).
        let mut points: Vec<Vec<&toml::Value>> = vec![vec![]];
        for l in &values {
            points = points
                .into_iter()
                .flat_map(|p| l.iter().map(move |v| [p.clone(), vec![v]].concat()))
                .collect();
        }
        let first = (0..points.len()).find_map(|k| {
            (0..k)
                .find(|&j| points[j].iter().zip(&points[k]).all(|(a, b)| same(a, b)))
                .map(|j| (k, j))
        });
        let text = dimer_with(&body);
        match first {
            None => assert!(parse(&text).is_ok(), "{lists:?}"),
            Some((later, earlier)) => {
                let e = parse(&text).unwrap_err().to_string();
                assert!(
                    e.contains(&format!("it is point {earlier} already")),
                    "{lists:?}: {e}"
                );
                let said: Vec<String> = keys
                    .iter()
                    .zip(&points[later])
                    .map(|(k, v)| format!("{k} = {v}"))
                    .collect();
                let said = format!("the point ({}) is given twice", said.join(", "));
                assert!(e.contains(&said), "{lists:?}: {e} (want {said})");
            }
        }
    }
}

#[test]
fn zero_and_negative_zero_are_one_value() {
    // Every parameter treats -0.0 as 0.0 (the same trajectory), so a sweep that lists
    // both lists one point twice.
    let e = parse(&dimer_with("\"fluid.density\" = [0.0, -0.0]\n"))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("given twice (it is point 0 already)"), "{e}");
}
