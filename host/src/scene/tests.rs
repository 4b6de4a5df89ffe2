//! Unit tests of scene parsing and the helix generator.

use super::raw::distance;
use super::*;
use crate::sizing::Plan;

const MINIMAL: &str = "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n[integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 1\n";

#[test]
fn line_col_counts_lines_and_characters() {
    let t = "ab\nçd\nx";
    assert_eq!(line_col(t, 0), (1, 1));
    assert_eq!(line_col(t, 3), (2, 1));
    assert_eq!(line_col(t, 5), (2, 2)); // after the two-byte 'ç'
    assert_eq!(line_col(t, 100), (3, 2));
}

#[test]
fn minimal_scene_gets_defaults() {
    let s = Scene::parse(MINIMAL, "m.toml").unwrap();
    assert_eq!(s.fluid.viscosity, 1.0);
    assert_eq!(s.fluid.density, 0.0);
    assert_eq!(s.gravity, [0.0, 0.0, -1.0]);
    assert_eq!(s.particles[0].density, DEFAULT_DENSITY);
    assert_eq!(s.model, Model::default());
    assert_eq!(s.integrator.solver, Solver::Auto);
    assert_eq!(s.integrator.tolerance, 1e-10);
    assert_eq!(s.integrator.max_iterations, 500);
    assert_eq!(s.integrator.precision, Precision::F64);
    assert_eq!(s.integrator.stiffness, 1e4);
    assert_eq!(s.integrator.steps(), 100);
    assert_eq!(s.output.every, 1);
    assert_eq!(s.species(), vec!["A"]);
}

#[test]
fn default_density_settles_a_lone_tail_at_unit_speed() {
    let weight = 4.0 / 3.0 * std::f64::consts::PI * DEFAULT_DENSITY;
    assert!((weight - 6.0 * std::f64::consts::PI).abs() < 1e-12);
}

#[test]
fn default_every_aims_at_200_frames() {
    let text = MINIMAL.replace("duration = 1", "duration = 400");
    let s = Scene::parse(&text, "m.toml").unwrap();
    assert_eq!(s.integrator.steps(), 40_000);
    assert_eq!(s.output.every, 200);
}

#[test]
fn semantic_error_points_at_the_key() {
    let text = MINIMAL.replace("radius = 1", "radius = -1");
    let e = Scene::parse(&text, "m.toml").unwrap_err();
    assert_eq!(e.location, Some((3, 10)));
    assert!(e.to_string().starts_with("m.toml:3:10: radius must be > 0"));
}

#[test]
fn unknown_key_is_an_error_with_its_line() {
    let text = MINIMAL.replace("radius = 1", "radius = 1\ncolour = 2");
    let e = Scene::parse(&text, "m.toml").unwrap_err();
    assert_eq!(e.line(), Some(4), "{e}");
    assert!(e.message.contains("colour"), "{e}");
}

#[test]
fn helix_default_geometry_is_exact() {
    let h = Helix::default();
    let c = h.generate().unwrap();
    assert_eq!(c.positions.len(), 25);
    for &(i, j, d) in &c.bonds {
        let s = distance(c.positions[i], c.positions[j]);
        assert!((s - d).abs() < 1e-12, "bond {i}-{j}: {s} vs {d}");
    }
    // Head at the bottom, on the axis.
    assert_eq!(c.positions[0], [0.0, 0.0, 0.0]);
    assert!(c.positions[1..].iter().all(|p| p[2] > 0.0));
}

#[test]
fn helix_head_at_top_is_above_every_tail() {
    let h = Helix {
        head_end: HeadEnd::Top,
        ..Helix::default()
    };
    let c = h.generate().unwrap();
    assert!(c.positions[1..].iter().all(|p| p[2] < 0.0));
    let s = distance(c.positions[0], c.positions[1]);
    assert!((s - h.head_bond()).abs() < 1e-12);
}

#[test]
fn helix_too_wide_for_the_head_bond_is_refused() {
    let h = Helix {
        radius: 3.0,
        dhat: 1.05,
        ..Helix::default()
    };
    assert!(h.generate().unwrap_err().contains("head bond"));
}

#[test]
fn helix_too_tight_is_refused() {
    let h = Helix {
        radius: 1.0,
        pitch: 0.5,
        dhat: 1.5,
        head_ratio: 2.0,
        ..Helix::default()
    };
    assert!(h.generate().unwrap_err().contains("too tight"));
}

/// `n` unit spheres in a row, 3 apart, and a chain of `b` bonds along them.
fn row(n: usize, b: usize, level: &str) -> String {
    let mut t = format!(
        "[model]\nlevel = \"{level}\"\n\n[integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 1\n"
    );
    for k in 0..n {
        t += &format!("\n[[particle]]\nposition = [{}, 0, 0]\nradius = 1\n", 3 * k);
    }
    for k in 0..b {
        t += &format!("\n[[bond]]\nbetween = [{k}, {}]\n", k + 1);
    }
    t
}

fn line_of(text: &str, needle: &str) -> usize {
    1 + text.lines().position(|l| l == needle).unwrap()
}

fn overdamped() -> Plan {
    Plan::free(Method::Overdamped, Solver::Auto)
}

#[test]
fn too_many_particles_are_refused_at_the_first_that_does_not_fit() {
    let text = row(12, 0, "manual");
    let limit = overdamped().bytes(9, 0).unwrap();
    let e = Scene::parse_within(&text, "row.toml", limit).unwrap_err();
    // Nine particles fit; the tenth (index 9) does not.
    assert_eq!(
        e.line(),
        Some(line_of(&text, "position = [27, 0, 0]")),
        "{e}"
    );
    let big = e.too_large.expect("a storage refusal");
    assert_eq!((big.particles, big.bonds, big.limit), (12, 0, limit));
    assert_eq!(big.bytes, overdamped().bytes(12, 0));
    assert!(e.message.contains("over the limit"), "{e}");
    assert!(Scene::parse_within(&text, "row.toml", big.bytes.unwrap()).is_ok());
}

#[test]
fn too_many_bonds_are_refused_at_the_first_that_does_not_fit() {
    let text = row(8, 7, "manual");
    let limit = overdamped().bytes(8, 4).unwrap();
    let e = Scene::parse_within(&text, "row.toml", limit).unwrap_err();
    assert_eq!(e.line(), Some(line_of(&text, "between = [4, 5]")), "{e}");
    assert_eq!(e.too_large.map(|t| t.bonds), Some(7));
}

#[test]
fn an_auto_level_scene_is_sized_for_every_method_it_may_get() {
    // The stable inertial method stores two mobilities: twice the overdamped's.
    let text = row(20, 19, "auto");
    let limit = overdamped().bytes(20, 19).unwrap();
    let e = Scene::parse_within(&text, "row.toml", limit).unwrap_err();
    assert!(e.too_large.is_some(), "{e}");
    let manual = row(20, 19, "manual");
    assert!(Scene::parse_within(&manual, "row.toml", limit).is_ok());
}

#[test]
fn solvers_are_named_as_in_the_kernel() {
    for (name, solver) in [
        ("auto", Solver::Auto),
        ("sweep", Solver::Sweep),
        ("newton", Solver::Newton),
        ("krylov", Solver::Krylov),
    ] {
        let text = MINIMAL.replace(
            "duration = 1",
            &format!("duration = 1\nsolver = \"{name}\""),
        );
        assert_eq!(
            Scene::parse(&text, "m.toml").unwrap().integrator.solver,
            solver
        );
    }
}

/// `[integrator] compact_products`: off by default and then not written; on, it reaches
/// the kernel's parameters and the storage plan (the copy is half the stored symmetric
/// mobility where the kernel takes it) and is written back.
#[test]
fn compact_products_reaches_the_kernel_and_is_written_back_only_when_set() {
    let plain = Scene::parse(&row(700, 699, "manual"), "row.toml").unwrap();
    assert!(!plain.integrator.compact_products);
    assert!(!plain.to_toml().contains("compact_products"));
    assert!(!params::<f64>(&plain).compact_products);
    let text = row(700, 699, "manual")
        .replace("duration = 1\n", "duration = 1\ncompact_products = true\n");
    let s = Scene::parse(&text, "row.toml").unwrap();
    assert!(s.integrator.compact_products);
    assert!(params::<f64>(&s).compact_products);
    let written = s.to_toml();
    assert!(written.contains("compact_products = true"));
    let again = Scene::parse(&written, "scene.toml").unwrap();
    assert!(again.integrator.compact_products);
    // Storage: the plan keeps the copy where the kernel takes it (700 beads, Krylov).
    let (with, without) = (Plan::of(&s), Plan::of(&plain));
    let (a, b) = (
        with.bytes(700, 699).unwrap(),
        without.bytes(700, 699).unwrap(),
    );
    // The copy: 24 bytes a pair and a little padding, half the 48 of the stored blocks.
    let pairs = 700 * 701 / 2;
    assert!(a >= b + 24 * pairs && a < b + 25 * pairs, "{a} against {b}");
}
