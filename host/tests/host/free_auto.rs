//! `[free_space] method = "auto"` through the run's resolution (`sim::resolve_level`,
//! which also applies `level = "auto"`): the shipped free-space scenes keep the stored
//! mobility, and `"auto"` resolves to the path the measured model picks.

use hydrorattle_host::scene::free_cost::{FreeChoice, choose_for};
use std::collections::BTreeMap;

use hydrorattle_host::scene::{FreeMethod, Scene, params, sizing};

/// `auto` keeps the stored mobility for every shipped free-space scene (2 to 25
/// spheres): their constraint solves (Newton at their size) read a stored metric, and
/// where another path could run, one assembly of a few hundred blocks costs less than
/// the products it serves (`bench/free_scenes.py` times them: docs/FREE.md).
#[test]
fn auto_picks_dense_for_the_shipped_scenes() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut seen = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let scene = Scene::parse(&text, &path.to_string_lossy()).unwrap();
        // A scene that names its free-space path (the clouds) keeps it.
        if scene.periodic.is_some() || scene.wall.is_some() || scene.free_space.is_some() {
            continue;
        }
        let scene = hydrorattle_host::sim::resolve_level(&scene, "shipped").0;
        let (c, t) = choose_for(&scene, 1e-4, sizing::DEFAULT_LIMIT).unwrap();
        assert_eq!(c, FreeChoice::Dense, "{}: {t:e} s a step", path.display());
        seen += 1;
    }
    assert!(seen >= 8, "{seen}");
}

/// `[free_space] method = "auto"`: resolved when the run starts to the path the model
/// picks (a four-bead chain keeps the stored mobility; a cloud of 20,000 spheres, whose
/// stored mobility would need 9.6 GB, is read without that estimate and takes the fast
/// product), written back as what ran; with a wall it is `"dense"` at once.
#[test]
fn free_space_auto_resolves_by_the_model() {
    let chain = "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n\
                 [[particle]]\nposition = [2.1, 0, 0]\nradius = 1\n\n\
                 [[bond]]\nbetween = [0, 1]\n\n\
                 [free_space]\nmethod = \"auto\"\n\n\
                 [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 0.1\n";
    let s = Scene::parse(chain, "c.toml").unwrap();
    assert_eq!(s.free_space.unwrap().method, FreeMethod::Auto);
    let run = hydrorattle_host::sim::resolve_level(&s, "c").0;
    assert_eq!(run.free_space.unwrap().method, FreeMethod::Dense);
    assert!(!run.integrator.matrix_free);
    assert!(run.to_toml().contains("method = \"dense\""));
    let walled = format!("{chain}\n[wall]\nheight = -5\n");
    let s = Scene::parse(&walled, "w.toml").unwrap();
    assert_eq!(s.free_space.unwrap().method, FreeMethod::Dense);
    let cloud = "[cloud]\ncount = 20000\ncloud_radius = 126\nseed = 3\n\n\
                 [free_space]\nmethod = \"auto\"\n\n\
                 [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 0.1\n";
    let s = Scene::parse(cloud, "cloud.toml").unwrap();
    let run = hydrorattle_host::sim::resolve_level(&s, "cloud").0;
    assert_eq!(run.free_space.unwrap().method, FreeMethod::Fast);
    assert!(run.integrator.matrix_free);
    assert_eq!(params::<f64>(&run).pse, Some(1e-4));
}

/// `text` with `method = "method"` in its `[table]` (the table added where missing).
fn with_method(text: &str, table: &str, method: &str) -> String {
    let head = format!("[{table}]");
    let line = format!("method = \"{method}\"");
    let Some(at) = text.lines().position(|l| l.trim() == head) else {
        return format!("{text}\n{head}\n{line}\n");
    };
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let end = (at + 1..lines.len())
        .find(|&k| lines[k].starts_with('['))
        .unwrap_or(lines.len());
    match (at + 1..end).find(|&k| lines[k].trim_start().starts_with("method")) {
        Some(k) => lines[k] = line,
        None => lines.insert(at + 1, line),
    }
    lines.join("\n")
}

/// The path a run of `text` under `auto` takes, named as `bench/free_scenes.py` names
/// its explicit paths.
fn auto_path(text: &str, name: &str) -> String {
    use hydrorattle_host::scene::BoxMethod;
    let boxed = text.lines().any(|l| l.trim() == "[box]");
    let table = if boxed { "box" } else { "free_space" };
    let scene = Scene::parse(&with_method(text, table, "auto"), name).unwrap();
    let run = hydrorattle_host::sim::resolve_level(&scene, name).0;
    if let Some(b) = run.periodic {
        return match b.method {
            BoxMethod::Pse => "pse",
            _ => "ewald",
        }
        .into();
    }
    let fast = run.free_space.is_some_and(|f| f.method == FreeMethod::Fast);
    match (
        fast,
        run.integrator.matrix_free,
        run.integrator.compact_products,
    ) {
        (true, ..) => "fast",
        (false, true, _) => "matrix-free",
        (false, false, true) => "compact",
        _ => "dense",
    }
    .into()
}

/// Whether the kernel keeps the compact copy for the scene `text` with
/// `compact_products = true` (`Params::compact_copy`).
fn compact_kept(text: &str, name: &str) -> bool {
    let on = text.replacen("[integrator]", "[integrator]\ncompact_products = true", 1);
    let Ok(scene) = Scene::parse(&on, name) else {
        return false;
    };
    let run = hydrorattle_host::sim::resolve_level(&scene, name).0;
    let s = hydrorattle_host::scene::free_cost::Spheres::of(&run);
    params::<f64>(&run).compact_copy(s.n, s.bonds)
}

/// The rows of `bench/results/NAME.csv` whose case names a scene and a path
/// (`"scene, path"`), with them.
fn scene_rows(name: &str) -> Vec<(String, String, Vec<String>)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let csv = std::fs::read_to_string(root.join(format!("bench/results/{name}.csv"))).unwrap();
    csv.lines()
        .skip(1)
        .map(hydrorattle_host::output::csv_fields)
        .filter_map(|row| {
            let (scene, path) = row[6].split_once(", ")?;
            Some((scene.to_string(), path.to_string(), row.clone()))
        })
        .collect()
}

/// Every shipped scene that can run more than one way runs under `auto` within a fifth
/// of its fastest explicit path, as measured (`bench/results/free_scenes.csv`, written
/// by `bench/free_scenes.py`: CPU seconds a step of short `host-demo run`s under each
/// path; a path whose run passed the script's time limit counts as slower than every
/// path that finished, a refused path is left out). The path `auto` takes is resolved
/// here by the run's own resolution; its time and the others' are the measured ones, so
/// the check does not read the cost model's constants.
#[test]
fn auto_is_within_a_fifth_of_the_best() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    // The last recorded seconds a step of each (scene, path).
    let mut times = BTreeMap::<String, BTreeMap<String, f64>>::new();
    for (scene, path, row) in scene_rows("free_scenes") {
        if row[7] != "seconds a step" || path == "auto" {
            continue;
        }
        let paths = times.entry(scene).or_default();
        // A run stopped at the script's limit is slower than every one that finished.
        let t = match row[8].parse::<f64>() {
            Ok(t) => Some(t),
            Err(_) if row[8].starts_with("over ") => Some(f64::INFINITY),
            Err(_) => None,
        };
        match t {
            Some(t) => paths.insert(path.clone(), t),
            None => paths.remove(&path),
        };
    }
    let mut checked = Vec::new();
    for (scene, paths) in &mut times {
        let file = root.join("host/scenes").join(format!("{scene}.toml"));
        let text = std::fs::read_to_string(&file).unwrap();
        // Where the kernel keeps no compact copy, `compact_products` changes nothing:
        // its rows time the dense path again, and the faster of the two is that path's.
        if !compact_kept(&text, scene)
            && let Some(c) = paths.remove("compact")
            && let Some(d) = paths.get_mut("dense")
        {
            *d = d.min(c);
        }
        if paths.len() < 2 {
            continue;
        }
        let path = auto_path(&text, scene);
        let (best, t_best) = paths
            .iter()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, v)| (k.clone(), *v))
            .unwrap();
        let t = *paths
            .get(&path)
            .unwrap_or_else(|| panic!("{scene}: auto takes {path}, not measured: {paths:?}"));
        assert!(
            t <= 1.2 * t_best,
            "{scene}: auto takes {path} ({t:.3e} s a step), {:.2} times {best} ({t_best:.3e})",
            t / t_best
        );
        println!(
            "{scene}: auto takes {path}, {:.2} times the best ({best})",
            t / t_best
        );
        checked.push(scene.clone());
    }
    // The Figure 1 scenes run one way only (their method stores the mobility, and 25
    // beads are too few for the compact copy): nothing to choose.
    for want in [
        "brownian_chain",
        "cloud",
        "cloud_small",
        "dimer",
        "fene_dumbbell",
        "periodic_chain",
        "periodic_suspension",
        "ring",
        "tree",
    ] {
        assert!(
            checked.iter().any(|s| s == want),
            "{want} not measured: {checked:?}"
        );
    }
}

/// The same over whole runs (`bench/results/whole_runs.csv`, written by
/// `bench/whole_runs.py`: CPU seconds of each shipped cloud's whole run on the pair
/// sums, on the fast product weighed once, and under `auto`, which weighs the fast
/// product again before every step). A falling cloud's tail stretches the box the fast
/// product is sized from, so a path chosen at the start alone can lose over the run.
/// The rows of each scene's last recorded commit are read; `auto`'s time must be within
/// a fifth of the fastest explicit path's.
#[test]
fn auto_is_within_a_fifth_of_the_best_over_whole_runs() {
    // Per scene: the last commit's CPU seconds by path.
    let mut runs = BTreeMap::<String, (String, BTreeMap<String, f64>)>::new();
    for (scene, path, row) in scene_rows("whole_runs") {
        if !row[7].starts_with("CPU seconds") {
            continue;
        }
        let (commit, times) = runs.entry(scene).or_default();
        if *commit != row[1] {
            *commit = row[1].clone();
            times.clear();
        }
        times.insert(path, row[8].parse().unwrap());
    }
    assert!(runs.contains_key("cloud"), "{runs:?}");
    for (scene, (commit, times)) in &runs {
        let auto = *times
            .get("auto")
            .unwrap_or_else(|| panic!("{scene} at {commit}: no auto row: {times:?}"));
        let (best, t_best) = times
            .iter()
            .filter(|(p, _)| *p != "auto")
            .min_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        assert!(
            times.len() >= 3 && auto <= 1.2 * t_best,
            "{scene} at {commit}: auto {auto} CPU s, {:.2} times {best} ({t_best})",
            auto / t_best
        );
        println!("{scene}: auto {:.2} times the best ({best})", auto / t_best);
    }
}
