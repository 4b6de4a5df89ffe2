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
    // "auto" without the weighing keeps it off when written and read back (a sweep's
    // frozen point is checked by its written scene).
    let off = fs("method = \"auto\"\nreweigh = false").unwrap();
    let again = Scene::parse(&off.to_toml(), "again.toml").unwrap();
    assert_eq!(again.free_space, off.free_space);
    assert!(!again.free_space.unwrap().reweigh);
    let err = fs("method = \"dense\"\nreweigh = true")
        .unwrap_err()
        .to_string();
    assert!(err.contains("s.toml:") && err.contains("reweigh"), "{err}");
    // "auto" that resolves to a dense path does not weigh.
    let two = fs("method = \"auto\"").unwrap();
    let run = resolve_level(&two, "s").0;
    assert!(!run.free_space.unwrap().reweigh);
}

/// A Brownian step the pair sums cannot take (their Lanczos run, with the midpoint's
/// inverse root, past the cap) is taken on the fast product instead, bit for bit as a
/// system on the fast product alone takes it; where both run, the pair sums.
#[test]
fn a_step_the_pair_sums_cannot_take_falls_back_to_the_fast_product() {
    let text = |reweigh: bool| {
        format!(
            "[cloud]\ncount = 500\ncloud_radius = 23.2\nseed = 2\n\n\
             [free_space]\nmethod = \"fast\"\nreweigh = {reweigh}\n\n\
             [brownian]\ntemperature = 1.0\nseed = 5\n\n\
             [integrator]\nmethod = \"overdamped\"\ndt = 0.05\nduration = 0.05\n"
        )
    };
    let build = |reweigh: bool| {
        let scene = Scene::parse(&text(reweigh), "b.toml").unwrap();
        let scene = resolve_level(&scene, "b").0;
        Engine::<f64>::new(&scene, DEFAULT_LIMIT).unwrap()
    };
    let (mut weighed, mut fast) = (build(true), build(false));
    assert!(weighed.reweighs());
    // 500 spheres: the pair sums are the cheaper, and run.
    let mut first = weighed.clone();
    first.step().unwrap();
    let mut alone = fast.clone();
    alone.step().unwrap();
    let (sums, root) = (first.lanczos.max, alone.lanczos.max);
    assert_eq!((first.pair_steps, first.lanczos.capped), (1, 0));
    assert_ne!(first.beads.pos, alone.beads.pos);
    // A cap the fast product's root passes and the midpoint's inverse root does not.
    assert!(sums > root, "{sums} against {root}");
    for e in [&mut weighed, &mut fast] {
        e.params.lanczos.max_iterations = root;
    }
    weighed.step().unwrap();
    fast.step().unwrap();
    assert_eq!(weighed.pair_steps, 0);
    assert!(weighed.lanczos.capped > 0);
    assert_eq!(weighed.beads.pos, fast.beads.pos);
    assert_eq!(weighed.noise.save(), fast.noise.save());
}
