//! `[free_space] method = "auto"` through the run's resolution (`sim::resolve_level`,
//! which also applies `level = "auto"`): the shipped free-space scenes keep the stored
//! mobility, and `"auto"` resolves to the path the measured model picks.

use hydrorattle_host::scene::free_cost::{FreeChoice, choose_for};
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
