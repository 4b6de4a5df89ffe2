//! `[free_space] reweigh`: a run on the fast product weighs it against the pair sums
//! before each step and steps on the cheaper, bit for bit as a run on that path alone;
//! the weighing survives a saved and restored system.

use hydrorattle::Real;
use hydrorattle_host::scene::{FreeMethod, Scene};
use hydrorattle_host::sim::{Engine, resolve_level};
use hydrorattle_host::sizing::DEFAULT_LIMIT;

/// The shipped falling cloud's spheres (10^4 at volume fraction 0.01) with the
/// `[free_space] method = "method"` and one first-order step (`matrix_free` where
/// `pairs`).
fn cloud(method: &str, pairs: bool) -> Engine<f64> {
    let text = format!(
        "[cloud]\ncount = 10000\ncloud_radius = 101.0\nseed = 1\n\n\
         [free_space]\nmethod = \"{method}\"\n\n\
         [integrator]\nmethod = \"overdamped\"\ndt = 0.05\nduration = 0.05\n\
         matrix_free = {pairs}\n"
    );
    let scene = Scene::parse(&text, "cloud.toml").unwrap();
    let scene = resolve_level(&scene, "cloud").0;
    Engine::new(&scene, DEFAULT_LIMIT).unwrap()
}

/// One sphere in twenty strung out below the cloud, down to `depth` (a falling
/// cloud's tail, which stretches the box the fast product is sized from).
fn stretch(e: &mut Engine<f64>, depth: f64) {
    let k = e.beads.len() / 20;
    for (i, p) in e.beads.pos.iter_mut().take(k).enumerate() {
        *p = f64::v3_from([0.0, 0.0, -110.0 - depth * (i + 1) as f64 / k as f64]);
    }
}

#[test]
fn each_step_runs_the_path_it_weighs() {
    let mut auto = cloud("auto", false);
    let mut fast = cloud("fast", false);
    let mut sums = cloud("dense", true);
    assert!(auto.reweighs());
    assert!(!fast.reweighs() && !sums.reweighs());
    // The ball as it starts: the fast product.
    for e in [&mut auto, &mut fast, &mut sums] {
        e.step().unwrap();
    }
    assert_eq!(auto.beads.pos, fast.beads.pos);
    assert_ne!(
        auto.beads.pos, sums.beads.pos,
        "the two paths differ in their bits"
    );
    assert_eq!(auto.pair_steps, 0);
    // With a tail 10^4 radii long: the pair sums.
    stretch(&mut auto, 1e4);
    // A system saved and restored goes on weighing.
    let saved = auto.save(hydrorattle_host::scene::Precision::F64);
    let mut back = Engine::<f64>::restore(&saved).unwrap();
    assert!(back.reweighs());
    sums.beads.pos.clone_from(&auto.beads.pos);
    for e in [&mut auto, &mut sums, &mut back] {
        e.step().unwrap();
    }
    assert_eq!(auto.beads.pos, sums.beads.pos);
    assert_eq!(back.beads.pos, sums.beads.pos);
    assert_eq!((auto.pair_steps, back.pair_steps), (1, 1));
}

/// `reweigh` is read, written back and refused where there is no fast product to weigh.
#[test]
fn the_key_is_read_written_and_refused_on_dense() {
    let base = "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n\
                [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 0.1\n\n";
    let fs = |t: &str| Scene::parse(&format!("{base}[free_space]\n{t}\n"), "s.toml");
    // Defaults: on under "auto", off under "fast".
    assert!(fs("method = \"auto\"").unwrap().free_space.unwrap().reweigh);
    let fast = fs("method = \"fast\"").unwrap();
    assert!(!fast.free_space.unwrap().reweigh);
    assert!(!fast.to_toml().contains("reweigh"));
    let on = fs("method = \"fast\"\nreweigh = true").unwrap();
    let f = on.free_space.unwrap();
    assert!(f.reweigh && f.method == FreeMethod::Fast && f.reweighs());
    let again = Scene::parse(&on.to_toml(), "again.toml").unwrap();
    assert_eq!(again.free_space, on.free_space);
    let err = fs("method = \"dense\"\nreweigh = true")
        .unwrap_err()
        .to_string();
    assert!(err.contains("s.toml:") && err.contains("reweigh"), "{err}");
    // "auto" that resolves to a dense path does not weigh.
    let two = fs("method = \"auto\"").unwrap();
    let run = resolve_level(&two, "s").0;
    assert!(!run.free_space.unwrap().reweigh);
}
