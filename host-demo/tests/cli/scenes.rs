//! Scene files: every shipped scene parses; the helix generator is exact; every bad
//! file under `tests/data/bad/` is refused with the line its `# expect-line:` names.

use crate::common::{BIN, manifest};
use hydrorattle_host::scene::{FIGURE1_SCENES, HeadEnd, Helix, Scene};
use std::path::{Path, PathBuf};
use std::process::Command;

fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Winding number of the closed top-view polygon through `points` around `centre`.
fn winding_number(points: &[[f64; 3]], centre: [f64; 3]) -> f64 {
    let angle = |p: &[f64; 3]| (p[1] - centre[1]).atan2(p[0] - centre[0]);
    let mut total = 0.0;
    for k in 0..points.len() {
        let a = angle(&points[k]);
        let b = angle(&points[(k + 1) % points.len()]);
        let mut d = b - a;
        while d > std::f64::consts::PI {
            d -= 2.0 * std::f64::consts::PI;
        }
        while d < -std::f64::consts::PI {
            d += 2.0 * std::f64::consts::PI;
        }
        total += d;
    }
    total / (2.0 * std::f64::consts::PI)
}

#[test]
fn every_shipped_scene_parses() {
    let files = toml_files(&manifest().join("../host/scenes"));
    let names: Vec<_> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for expected in [
        "dimer.toml",
        "figure1a.toml",
        "figure1b.toml",
        "figure1c.toml",
        "ring.toml",
        "tree.toml",
    ] {
        assert!(names.iter().any(|n| n == expected), "missing {expected}");
    }
    for path in files {
        let scene = Scene::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!scene.particles.is_empty(), "{}", path.display());
        // Constrained bonds start at their length (a spring may start stretched).
        let springs = scene.integrator.method == hydrorattle_host::scene::Method::Springs;
        for b in scene.bonds.iter().filter(|_| !springs) {
            let s = distance(scene.particles[b.i].position, scene.particles[b.j].position);
            assert!(
                (s - b.length).abs() < 1e-12,
                "{}: bond {}-{} is {s}, should be {}",
                path.display(),
                b.i,
                b.j,
                b.length
            );
        }
    }
}

#[test]
fn small_scenes_have_the_described_shapes() {
    let dir = manifest().join("../host/scenes");
    let dimer = Scene::from_path(&dir.join("dimer.toml")).unwrap();
    assert_eq!((dimer.particles.len(), dimer.bonds.len()), (2, 1));
    assert!((dimer.bonds[0].length - 3.15).abs() < 1e-12);
    let ring = Scene::from_path(&dir.join("ring.toml")).unwrap();
    assert_eq!((ring.particles.len(), ring.bonds.len()), (6, 6));
    let tree = Scene::from_path(&dir.join("tree.toml")).unwrap();
    assert_eq!((tree.particles.len(), tree.bonds.len()), (7, 6));
    let hub_degree = tree.bonds.iter().filter(|b| b.i == 0 || b.j == 0).count();
    assert_eq!(hub_degree, 3);
}

#[test]
fn figure1_scenes_are_the_papers_cases() {
    let cases = Scene::figure1().unwrap();
    let expected = [
        ("a", 1.50, 2f64.cbrt()),
        ("b", 1.05, 2f64.cbrt()),
        ("c", 1.05, 2.0),
    ];
    for ((case, scene), (want_case, dhat, ratio)) in cases.iter().zip(expected) {
        assert_eq!(*case, want_case);
        let h = scene.helix.expect("figure 1 scenes use the helix");
        assert_eq!(h.tails, 24);
        assert_eq!(h.dhat, dhat);
        assert!((h.head_ratio - ratio).abs() < 1e-15);
        assert_eq!(scene.particles.len(), 25);
        assert_eq!(scene.species()[0], "head");
        assert!(scene.species()[1..].iter().all(|s| *s == "tail"));
        // Hard contacts (no stiffness, so no explicit-stability limit on dt), with the
        // second-order method at dt = 0.1 (docs/FIGURE1.md#figure-1-at-dt--01).
        assert_eq!(
            scene.contact,
            Some(hydrorattle_host::scene::Contact::Hard { capacity: None })
        );
        assert_eq!(
            scene.integrator.method,
            hydrorattle_host::scene::Method::Overdamped2
        );
        assert_eq!(scene.integrator.dt, 0.1);
        assert!(scene.integrator.duration >= 400.0);
    }
    // The embedded copies are the files on disk.
    for (_, name, text) in FIGURE1_SCENES {
        let on_disk = std::fs::read_to_string(manifest().join("../host").join(name)).unwrap();
        assert_eq!(on_disk, text);
    }
}

fn check_helix(h: &Helix) {
    let c = h.generate().unwrap_or_else(|e| panic!("{h:?}: {e}"));
    assert_eq!(c.positions.len(), h.tails + 1);
    assert_eq!(c.radii[0], h.head_ratio);
    assert!(c.radii[1..].iter().all(|&r| r == 1.0));
    for (k, &(i, j, d)) in c.bonds.iter().enumerate() {
        assert_eq!((i, j), (k, k + 1));
        assert_eq!(d, h.dhat * (c.radii[i] + c.radii[j]));
        let s = distance(c.positions[i], c.positions[j]);
        assert!((s - d).abs() < 1e-12, "{h:?} bond {k}: {s} vs {d}");
    }
    // The head is on the axis and inside the ring the tails draw in top view.
    let head = c.positions[0];
    assert_eq!((head[0], head[1]), (0.0, 0.0));
    for p in &c.positions[1..] {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        assert!((r - h.radius).abs() < 1e-12);
    }
    if h.tails >= 8 {
        assert!(winding_number(&c.positions[1..], head).abs() >= 1.0 - 1e-9);
    }
    // The head is at the requested end.
    match h.head_end {
        HeadEnd::Bottom => assert!(c.positions[1..].iter().all(|p| p[2] > head[2])),
        HeadEnd::Top => assert!(c.positions[1..].iter().all(|p| p[2] < head[2])),
    }
}

#[test]
fn helix_generator_is_exact_over_the_phase_grid() {
    for (_, scene) in Scene::figure1().unwrap() {
        check_helix(&scene.helix.unwrap());
    }
    for i in 0..6 {
        for j in 0..6 {
            for head_end in [HeadEnd::Bottom, HeadEnd::Top] {
                check_helix(&Helix {
                    dhat: 1.05 + (2.0 - 1.05) * i as f64 / 5.0,
                    head_ratio: 1.0 + 1.5 * j as f64 / 5.0,
                    head_end,
                    ..Helix::default()
                });
            }
        }
    }
}

struct Expectation {
    line: usize,
    message: String,
}

fn expectation(path: &Path) -> Expectation {
    let text = std::fs::read_to_string(path).unwrap();
    let field = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(key))
            .unwrap_or_else(|| panic!("{} has no `{key}` line", path.display()))
            .trim()
            .to_string()
    };
    Expectation {
        line: field("# expect-line:").parse().unwrap(),
        message: field("# expect-message:"),
    }
}

#[test]
fn bad_scenes_report_file_line_and_reason() {
    let files = toml_files(&manifest().join("tests/data/bad"));
    assert!(files.len() >= 20);
    let mut failures = Vec::new();
    for path in files {
        let want = expectation(&path);
        let Err(err) = Scene::from_path(&path) else {
            failures.push(format!("{}: accepted", path.display()));
            continue;
        };
        let shown = err.to_string();
        let prefix = format!("{}:{}:", path.display(), want.line);
        if err.line() != Some(want.line)
            || !shown.starts_with(&prefix)
            || !err.message.contains(&want.message)
            || err.message.contains('\n')
        {
            failures.push(format!(
                "{shown}\n    expected line {} and a one-line message containing {:?}",
                want.line, want.message
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn unreadable_file_is_an_error_without_a_line() {
    let err = Scene::from_path(Path::new("no/such/scene.toml")).unwrap_err();
    assert_eq!(err.line(), None);
    assert!(
        err.to_string()
            .starts_with("no/such/scene.toml: cannot read")
    );
}

#[test]
fn the_binary_exits_non_zero_on_a_bad_scene_before_writing() {
    let bad = manifest().join("tests/data/bad/negative_radius.toml");
    let out = std::env::temp_dir().join(format!("host-demo-bad-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let result = Command::new(BIN)
        .arg("run")
        .arg(&bad)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(
        stderr.contains(&format!("{}:9:", bad.display())),
        "stderr: {stderr}"
    );
    assert!(!out.exists(), "no output may be written for a bad scene");
}

/// The number after `before` in `text` (up to the next space).
fn number_after(text: &str, before: &str) -> f64 {
    let at = text
        .find(before)
        .unwrap_or_else(|| panic!("pile.toml does not say {before:?}"));
    let rest = &text[at + before.len()..];
    let word = rest.split_whitespace().next().unwrap_or_default();
    word.parse()
        .unwrap_or_else(|_| panic!("pile.toml: {before:?} then {word:?}"))
}

/// `pile.toml` run to its end is the pile its header describes: the spheres inside the
/// fence and spilled over it, the pile's depth in layers, the spilled ones a monolayer
/// on the wall.
#[test]
fn the_shipped_pile_is_what_its_header_says() {
    let scene = manifest().join("../host/scenes/pile.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    let header: String = text
        .lines()
        .take_while(|l| l.starts_with('#'))
        .map(|l| format!("{} ", l.trim_start_matches('#').trim()))
        .collect();
    let inside_said = number_after(&header, "at rest");
    let depth_said = number_after(&header, "in a pile");
    let spilled_said = number_after(&header, "), and");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("shipped-pile");
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(BIN)
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frames = hydrorattle_host::output::read_xyz_file(&out.join("trajectory.xyz")).unwrap();
    let last = frames.last().unwrap();
    // The fence: the spheres of radius 1.5, in a ring about the vertical axis.
    let fence: Vec<usize> = (0..last.radii.len())
        .filter(|&i| last.radii[i] > 1.2)
        .collect();
    assert_eq!(fence.len(), 15);
    let ring = fence
        .iter()
        .map(|&i| last.positions[i][0].hypot(last.positions[i][1]))
        .fold(0.0_f64, f64::max);
    let (mut inside, mut spilled, mut top) = (0, 0, 0.0_f64);
    for i in (0..last.radii.len()).filter(|i| !fence.contains(i)) {
        let [x, y, z] = last.positions[i];
        let r = last.radii[i];
        if x.hypot(y) < ring {
            inside += 1;
            top = top.max(z + r);
        } else {
            spilled += 1;
            // A monolayer: every spilled sphere on the wall (z = 0), none on another.
            assert!(
                (z - r).abs() < 1e-6,
                "sphere {i} outside the fence at z = {z}"
            );
        }
    }
    let depth = top / 2.0;
    eprintln!("inside {inside}, spilled {spilled}, pile {depth:.2} layers deep (top at {top:.2})");
    assert_eq!(inside + spilled, 100);
    assert!(
        (inside as f64 - inside_said).abs() <= 3.0,
        "{inside} inside, said {inside_said}"
    );
    assert!(
        (spilled as f64 - spilled_said).abs() <= 3.0,
        "{spilled} spilled, said {spilled_said}"
    );
    assert!(
        (depth - depth_said).abs() <= 0.25,
        "{depth} layers, said {depth_said}"
    );
    let _ = std::fs::remove_dir_all(&out);
}
