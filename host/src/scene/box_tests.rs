//! Unit tests of the `[box]` table and the `[suspension]` generator: each refusal at
//! its file line, the write-back, and the generator's volume fraction and separations
//! measured here (not read from the generator).

use super::*;

/// Two spheres 3 apart and a bond between them, in a box (line 12 is `size`).
const BOXED: &str = "\
[[particle]]
position = [0, 0, 0]
radius = 1

[[particle]]
position = [3, 0, 0]
radius = 1

[[bond]]
between = [0, 1]

[box]
size = [10, 10, 12]

[integrator]
method = \"overdamped\"
dt = 0.01
duration = 1
";

fn refused(text: &str) -> SceneError {
    Scene::parse(text, "b.toml").expect_err("the scene should be refused")
}

#[test]
fn a_box_is_read_with_its_defaults_and_written_back() {
    let s = Scene::parse(BOXED, "b.toml").unwrap();
    let b = s.periodic.unwrap();
    assert_eq!(b.size, [10.0, 10.0, 12.0]);
    assert_eq!(
        (b.method, b.tolerance),
        (BoxMethod::Auto, DEFAULT_BOX_TOLERANCE)
    );
    let back = Scene::parse(&s.to_toml(), "scene.toml").unwrap();
    assert_eq!(back, s);
    let text = BOXED.replace(
        "size = [10, 10, 12]",
        "size = [10, 10, 12]\nmethod = \"pse\"\ntolerance = 1e-4",
    );
    let s = Scene::parse(&text, "b.toml").unwrap();
    let b = s.periodic.unwrap();
    assert_eq!((b.method, b.tolerance), (BoxMethod::Pse, 1e-4));
    assert_eq!(b.method_line, Some(14));
    assert!(s.to_toml().contains("method = \"pse\""));
    assert_eq!(Scene::parse(&s.to_toml(), "scene.toml").unwrap(), s);
}

#[test]
fn pse_runs_where_products_suffice_and_is_refused_at_its_line_elsewhere() {
    let with = |m: &str, extra: &str| {
        let text = BOXED.replace(
            "size = [10, 10, 12]",
            &format!("size = [10, 10, 12]\nmethod = \"{m}\""),
        );
        Scene::parse(&format!("{text}{extra}"), "b.toml").unwrap()
    };
    let s = with("pse", "");
    let why = s.needs_matrix();
    // "pse" runs on PSE where products suffice (matrix-free, written back); "auto"
    // takes it where it is also the cheaper path, not for two spheres (the cost model).
    assert_eq!(why, None);
    let s = with("pse", "");
    assert!(s.check_box_runs(None).is_ok());
    let run = s.with_box_resolved();
    assert_eq!(run.periodic.unwrap().method, BoxMethod::Pse);
    assert!(run.integrator.matrix_free);
    assert!(run.to_toml().contains("method = \"pse\""));
    assert!(run.to_toml().contains("matrix_free = true"));
    let run = with("auto", "").with_box_resolved();
    assert_eq!(run.periodic.unwrap().method, BoxMethod::Ewald);
    assert!(!run.integrator.matrix_free);
    // A scene that needs the assembled matrix: "pse" refused at its line, "auto" is Ewald.
    let mut s = with("pse", "");
    s.integrator.method = super::Method::RattleStable;
    let e = s.check_box_runs(Some("b.toml")).unwrap_err();
    assert_eq!(e.line, Some(14));
    assert!(
        e.to_string()
            .starts_with("b.toml:14: [box] method = \"pse\" gives mobility products only"),
        "{e}"
    );
    let mut s = with("auto", "");
    s.integrator.method = super::Method::RattleStable;
    let run = s.with_box_resolved();
    assert_eq!(run.periodic.unwrap().method, BoxMethod::Ewald);
    assert!(!run.integrator.matrix_free);
    // "ewald" stays itself.
    let run = with("ewald", "").with_box_resolved();
    assert_eq!(run.periodic.unwrap().method, BoxMethod::Ewald);
    assert!(!run.integrator.matrix_free);
}

/// `compact_products` in a box: with `method = "ewald"` the kernel keeps the compact copy
/// (at the 700 beads it needs: `Params::compact_copy`); on PSE, which stores nothing,
/// the flag is ignored.
#[test]
fn compact_products_in_a_box_take_the_ewald_path_only() {
    let with = |m: &str| {
        let text = BOXED
            .replace(
                "size = [10, 10, 12]",
                &format!("size = [10, 10, 12]\nmethod = \"{m}\""),
            )
            .replace("duration = 1\n", "duration = 1\ncompact_products = true\n");
        Scene::parse(&text, "b.toml").unwrap().with_box_resolved()
    };
    let ewald = params::<f64>(&with("ewald"));
    assert!(ewald.periodic.is_some() && ewald.pse.is_none() && ewald.compact_products);
    assert!(ewald.compact_copy(700, 699));
    let pse = params::<f64>(&with("pse"));
    assert!(pse.pse.is_some() && pse.matrix_free && pse.compact_products);
    assert!(!pse.compact_copy(700, 699));
}

#[test]
fn bad_boxes_are_refused_at_their_line() {
    let cases: [(&str, &str, usize, &str); 10] = [
        (
            "size = [10, 10, 12]",
            "size = [10, 0, 12]",
            13,
            "every edge must be finite and > 0, not Ly = 0",
        ),
        (
            "size = [10, 10, 12]",
            "size = [10, 10, -1]",
            13,
            "not Lz = -1",
        ),
        (
            "size = [10, 10, 12]",
            "size = [nan, 10, 12]",
            13,
            "not Lx = NaN",
        ),
        (
            "size = [10, 10, 12]",
            "size = [inf, 10, 12]",
            13,
            "not Lx = inf",
        ),
        (
            "size = [10, 10, 12]",
            "size = [10, 10, 12]\ntolerance = 0",
            14,
            "box tolerance must be > 0",
        ),
        (
            "size = [10, 10, 12]",
            "size = [10, 10, 12]\ntolerance = 1.5",
            14,
            "box tolerance must be between 1e-12 and 0.1 (PSE's relative error), not 1.5",
        ),
        (
            "size = [10, 10, 12]",
            "size = [10, 10, 12]\ntolerance = 0.5",
            14,
            "between 1e-12 and 0.1 (PSE's relative error), not 0.5",
        ),
        (
            "size = [10, 10, 12]",
            "size = [10, 10, 12]\nmethod = \"ewald\"\ntolerance = 1e-13",
            15,
            "box tolerance must be between 1e-12 and 0.1",
        ),
        (
            "size = [10, 10, 12]",
            "size = [10, 10, 12]\nmethod = \"fast\"",
            14,
            "unknown variant `fast`",
        ),
        (
            "size = [10, 10, 12]",
            "",
            12,
            "missing field `size` in [box]",
        ),
    ];
    for (from, to, line, message) in cases {
        let e = refused(&BOXED.replace(from, to));
        assert_eq!(e.line(), Some(line), "{to}: {e}");
        assert!(e.message.contains(message), "{to}: {e}");
    }
}

#[test]
fn spheres_and_bonds_too_large_for_the_box_are_refused_at_their_line() {
    // A radius of half the smallest edge: at the sphere's position.
    let e = refused(&BOXED.replace("size = [10, 10, 12]", "size = [10, 2, 12]"));
    assert_eq!(e.line(), Some(2), "{e}");
    assert!(
        e.message.contains("not below half the box's smallest edge"),
        "{e}"
    );
    // A bond of 3 in a box of smallest edge 6: half of it, refused (the kernel's
    // predicate) at the bond.
    let e = refused(&BOXED.replace("size = [10, 10, 12]", "size = [10, 6, 12]"));
    assert_eq!(e.line(), Some(10), "{e}");
    assert!(e.message.contains("bond 0"), "{e}");
    // Spheres that overlap through a face: at the later sphere.
    let text = BOXED.replace("position = [3, 0, 0]", "position = [9.5, 0, 0]");
    let text = text.replace("[[bond]]\nbetween = [0, 1]\n", "");
    let e = refused(&text);
    assert_eq!(e.line(), Some(6), "{e}");
    assert!(e.message.contains("overlaps particle 0"), "{e}");
}

#[test]
fn a_box_with_a_wall_or_oseen_is_refused_at_the_box() {
    let wall = BOXED.replace("[integrator]", "[wall]\nheight = -5\n\n[integrator]");
    let e = refused(&wall);
    assert_eq!(e.line(), Some(13), "{e}");
    assert!(e.message.contains("with a [wall] is not supported"), "{e}");
    let model = "hydrodynamics = \"oseen\"";
    let text = BOXED.replace("[integrator]", &format!("[model]\n{model}\n\n[integrator]"));
    let e = refused(&text);
    assert_eq!(e.line(), Some(13), "{model}: {e}");
    assert!(e.message.contains("a periodic box with"), "{model}: {e}");
}

/// Rotation in a box is accepted (the kernel sums the box's `rt` and `rr` blocks), for
/// the overdamped method and the stable RATTLE that assembles the grand mobility.
#[test]
fn a_box_with_rotation_is_accepted() {
    for method in ["overdamped", "rattle-stable"] {
        let text = BOXED
            .replace("[integrator]", "[model]\nrotation = true\n\n[integrator]")
            .replace("method = \"overdamped\"", &format!("method = \"{method}\""));
        let s = Scene::parse(&text, "b.toml").unwrap_or_else(|e| panic!("{method}: {e}"));
        assert!(s.periodic.is_some());
        assert_eq!(Scene::parse(&s.to_toml(), "scene.toml").unwrap(), s);
    }
}

const SUSPENSION: &str = "\
[suspension]
count = 200
fraction = 0.2
polydispersity = 0.3
seed = 11

[integrator]
method = \"overdamped\"
dt = 0.01
duration = 1
";

/// The spheres' volume over the box's, and the smallest gap between two surfaces
/// through the minimum image, relative to the radii's sum (the test's own image).
fn fraction_and_gap(s: &Scene) -> (f64, f64) {
    let l = s.periodic.unwrap().size;
    let volume: f64 = s
        .radii()
        .iter()
        .map(|a| 4.0 / 3.0 * std::f64::consts::PI * a.powi(3))
        .sum();
    let mut gap = f64::INFINITY;
    for (j, q) in s.particles.iter().enumerate() {
        for p in &s.particles[..j] {
            let d: f64 = (0..3)
                .map(|k| {
                    let x = q.position[k] - p.position[k];
                    (x - l[k] * (x / l[k]).round()).powi(2)
                })
                .sum::<f64>()
                .sqrt();
            gap = gap.min(d / (p.radius + q.radius) - 1.0);
        }
    }
    (volume / (l[0] * l[1] * l[2]), gap)
}

#[test]
fn a_suspension_fills_its_fraction_without_overlap_and_repeats() {
    let s = Scene::parse(SUSPENSION, "s.toml").unwrap();
    assert_eq!(s.particles.len(), 200);
    let (phi, gap) = fraction_and_gap(&s);
    assert!((phi - 0.2).abs() < 1e-12, "fraction {phi}");
    assert!(gap >= GAP * 0.999, "smallest gap {gap}");
    let l = s.periodic.unwrap().size;
    assert!(l[0] == l[1] && l[1] == l[2]);
    for p in &s.particles {
        assert!(p.position.iter().all(|&x| (0.0..l[0]).contains(&x)));
        assert!((0.7..=1.3).contains(&p.radius));
    }
    // Polydisperse: the radii spread over most of [0.7, 1.3].
    let (lo, hi) = s
        .radii()
        .iter()
        .fold((2.0, 0.0), |(a, b), &r| (r.min(a), r.max(b)));
    assert!(lo < 0.75 && hi > 1.25, "radii {lo} .. {hi}");
    // The same table, the same spheres; another seed, others; written back, the same.
    assert_eq!(Scene::parse(SUSPENSION, "s.toml").unwrap(), s);
    let other = Scene::parse(&SUSPENSION.replace("seed = 11", "seed = 12"), "s.toml").unwrap();
    assert_ne!(other.particles, s.particles);
    let back = Scene::parse(&s.to_toml(), "scene.toml").unwrap();
    assert_eq!(back, s);
    // Monodisperse at a higher fraction.
    let mono = SUSPENSION
        .replace("polydispersity = 0.3\n", "")
        .replace("0.2", "0.3");
    let m = Scene::parse(&mono, "s.toml").unwrap();
    let (phi, gap) = fraction_and_gap(&m);
    assert!(
        (phi - 0.3).abs() < 1e-12 && gap >= GAP * 0.999,
        "{phi} {gap}"
    );
    assert!(m.radii().iter().all(|&a| a == 1.0));
}

#[test]
fn bad_suspensions_are_refused_at_their_line() {
    let cases: [(&str, &str, usize, &str); 6] = [
        ("count = 200", "count = 0", 2, "count must be >= 1"),
        ("fraction = 0.2", "fraction = 0.5", 3, "above 0.35"),
        (
            "fraction = 0.2",
            "fraction = -0.1",
            3,
            "fraction must be > 0",
        ),
        ("polydispersity = 0.3", "polydispersity = 1", 4, "below 1"),
        ("seed = 11", "seed = -1", 5, "seed must be >= 0"),
        ("fraction = 0.2\n", "", 1, "missing field `fraction`"),
    ];
    for (from, to, line, message) in cases {
        let e = refused(&SUSPENSION.replace(from, to));
        assert_eq!(e.line(), Some(line), "{to}: {e}");
        assert!(e.message.contains(message), "{to}: {e}");
    }
    // With its own spheres, or a box size of its own.
    let both = format!("{SUSPENSION}\n[[particle]]\nposition = [0, 0, 0]\nradius = 1\n");
    let e = refused(&both);
    assert_eq!(e.line(), Some(12), "{e}");
    let sized = format!("{SUSPENSION}\n[box]\nsize = [10, 10, 10]\n");
    let e = refused(&sized);
    assert_eq!(e.line(), Some(13), "{e}");
    assert!(e.message.contains("leave [box] size out"), "{e}");
}

/// The near field forms its mobility from the assembled far-field blocks, which PSE
/// never builds: `"pse"` with `[near_field]` is refused at the method's line and
/// `"auto"` stays on the Ewald sum (the kernel refuses PSE with the near field).
#[test]
fn the_near_field_in_a_box_needs_the_ewald_sum() {
    let text = |m: &str| {
        BOXED.replace(
            "size = [10, 10, 12]",
            &format!("size = [10, 10, 12]\nmethod = \"{m}\""),
        ) + "\n[near_field]\n"
    };
    let e = Scene::parse(&text("pse"), "b.toml").unwrap_err();
    assert_eq!(e.line(), Some(14));
    assert!(e.message.contains("[near_field]"), "{}", e.message);
    let run = Scene::parse(&text("auto"), "b.toml")
        .unwrap()
        .with_box_resolved();
    assert_eq!(run.periodic.unwrap().method, BoxMethod::Ewald);
    assert!(!run.integrator.matrix_free);
}
