//! Periodic boxes through the CLI: the shipped periodic
//! scenes run and write both trajectory formats with the box, the GSD file's wrapped
//! positions plus image flags give back the extended XYZ's unwrapped ones, the bonds
//! measured straight from the unwrapped positions keep their lengths; a box on the PSE
//! path runs within its tolerance of the Ewald run, and asks for `method = "pse"` with
//! a solver that needs the assembled mobility stop the run at its file and line before
//! any output.

use crate::common::{BIN, manifest};
use std::path::Path;
use std::process::Command;

use hydrorattle_host::output::read_xyz_file;
use hydrorattle_host::scene::Scene;

fn demo_run(scene: &Path, out: &Path) -> std::process::Output {
    Command::new(BIN)
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// The test's own reading of a GSD file (file layer 2.0): the chunk `name` of frame
/// `frame` as raw bytes, and the name list.
fn gsd_chunk(bytes: &[u8], frame: u64, name: &str) -> Option<Vec<u8>> {
    let (index, entries, names_at) = (
        u64_at(bytes, 8) as usize,
        u64_at(bytes, 16) as usize,
        u64_at(bytes, 24) as usize,
    );
    let names: Vec<&str> = bytes[names_at..]
        .split(|&c| c == 0)
        .take_while(|s| !s.is_empty())
        .map(|s| std::str::from_utf8(s).unwrap())
        .collect();
    let id = names.iter().position(|&n| n == name)? as u16;
    (0..entries).find_map(|k| {
        let e = &bytes[index + 32 * k..index + 32 * (k + 1)];
        let (f, n, at) = (u64_at(e, 0), u64_at(e, 8), u64_at(e, 16) as usize);
        let m = u32::from_le_bytes(e[24..28].try_into().unwrap()) as usize;
        let this = u16::from_le_bytes(e[28..30].try_into().unwrap());
        (f == frame && this == id).then(|| bytes[at..at + 4 * n as usize * m].to_vec())
    })
}

fn f32s(b: &[u8]) -> Vec<f32> {
    b.chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn i32s(b: &[u8]) -> Vec<i32> {
    b.chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn periodic_scenes_run_and_give_the_box_in_both_formats() {
    let mut crossed = 0;
    // The chain names "ewald"; the suspension's "auto" needs products only
    // (overdamped, hard contacts, solver auto), and at 32 spheres the cost model picks
    // the Ewald sum (measured 69 against 31 steps/s on PSE).
    for (name, method) in [
        ("periodic_chain", "ewald"),
        ("periodic_suspension", "ewald"),
    ] {
        let path = manifest()
            .join("../host/scenes")
            .join(format!("{name}.toml"));
        let scene = Scene::from_path(&path).unwrap();
        let cell = scene.periodic.unwrap().size;
        let out = scratch!(name);
        let r = demo_run(&path, &out);
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let written = std::fs::read_to_string(out.join("scene.toml")).unwrap();
        let named = format!("[box]\nmethod = \"{method}\"");
        assert!(written.contains(&named), "{written}");
        assert_eq!(written.contains("matrix_free = true"), method == "pse");
        let frames = read_xyz_file(&out.join("trajectory.xyz")).unwrap();
        let xyz = std::fs::read_to_string(out.join("trajectory.xyz")).unwrap();
        let lattice = format!(
            "Lattice=\"{} 0 0 0 {} 0 0 0 {}\"",
            cell[0], cell[1], cell[2]
        );
        assert!(xyz.lines().nth(1).unwrap().starts_with(&lattice), "{name}");
        assert!(
            xyz.lines().nth(1).unwrap().ends_with("pbc=\"T T T\""),
            "{name}"
        );
        let gsd = std::fs::read(out.join("trajectory.gsd")).unwrap();
        for (k, f) in frames.iter().enumerate() {
            assert_eq!(f.cell, Some(cell), "{name} frame {k}");
            // Bonds measured without any image: the positions are unwrapped.
            for b in &scene.bonds {
                let (p, q) = (f.positions[b.i], f.positions[b.j]);
                let d = (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt();
                assert!(
                    (d / b.length - 1.0).abs() < 1e-8,
                    "{name} frame {k}: bond {d}"
                );
            }
            let chunk = |what| gsd_chunk(&gsd, k as u64, what).unwrap();
            let box_ = f32s(&chunk("configuration/box"));
            assert_eq!(
                box_,
                [cell[0], cell[1], cell[2], 0.0, 0.0, 0.0].map(|x| x as f32)
            );
            let (pos, img) = (
                f32s(&chunk("particles/position")),
                i32s(&chunk("particles/image")),
            );
            for (i, p) in f.positions.iter().enumerate() {
                for c in 0..3 {
                    let (w, n, l) = (pos[3 * i + c], img[3 * i + c], cell[c]);
                    assert!(
                        -l / 2.0 <= f64::from(w) && f64::from(w) < l / 2.0,
                        "{w} outside"
                    );
                    let back = f64::from(w) + f64::from(n) * l;
                    let tol = 2.0 * f64::from(f32::EPSILON) * (p[c].abs() + l);
                    assert!(
                        (back - p[c]).abs() <= tol,
                        "{name} frame {k}: {back} != {}",
                        p[c]
                    );
                    crossed += usize::from(n != 0);
                }
            }
        }
    }
    // Some sphere was wrapped: the image flags were exercised.
    assert!(crossed > 0);
}

#[test]
fn a_run_without_a_box_writes_no_box() {
    let out = scratch!("dimer");
    let r = demo_run(&manifest().join("../host/scenes/dimer.toml"), &out);
    assert!(r.status.success());
    let xyz = std::fs::read_to_string(out.join("trajectory.xyz")).unwrap();
    assert!(!xyz.contains("Lattice") && xyz.contains("pbc=\"F F F\""));
    let gsd = std::fs::read(out.join("trajectory.gsd")).unwrap();
    assert!(gsd_chunk(&gsd, 0, "particles/position").is_some());
    assert!(gsd_chunk(&gsd, 0, "particles/image").is_none());
    assert!(!gsd.windows(15).any(|w| w == b"particles/image"));
}

/// The chain on PSE (`method = "pse"`, tolerance 1e-6) runs; without noise (the two
/// paths draw theirs differently: Cholesky and Lanczos) it ends within 1e-5 of the
/// Ewald run (relative to the largest displacement); with the Newton solver (which
/// reads single blocks of the assembled mobility) "pse" stops the run at its line
/// before any output.
#[test]
fn pse_runs_and_matches_ewald_or_stops_at_its_line() {
    let dir = scratch!("pse");
    std::fs::create_dir_all(&dir).unwrap();
    let chain = manifest().join("../host/scenes/periodic_chain.toml");
    let text = std::fs::read_to_string(&chain).unwrap();
    let text = text.replace("method = \"ewald\"", "method = \"pse\"");
    let path = dir.join("pse.toml");
    std::fs::write(&path, &text).unwrap();
    let r = demo_run(&path, &dir.join("thermal"));
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let written = std::fs::read_to_string(dir.join("thermal/scene.toml")).unwrap();
    assert!(written.contains("[box]\nmethod = \"pse\""), "{written}");
    let cold = |t: &str, name: &str| {
        let p = dir.join(name);
        std::fs::write(&p, t.replace("temperature = 0.5", "temperature = 0.0")).unwrap();
        p
    };
    let ewald = std::fs::read_to_string(&chain).unwrap();
    let (out, ewald_out) = (dir.join("out"), dir.join("ewald"));
    assert!(
        demo_run(&cold(&text, "cold_pse.toml"), &out)
            .status
            .success()
    );
    assert!(
        demo_run(&cold(&ewald, "cold_ewald.toml"), &ewald_out)
            .status
            .success()
    );
    let (a, b) = (
        read_xyz_file(&out.join("trajectory.xyz")).unwrap(),
        read_xyz_file(&ewald_out.join("trajectory.xyz")).unwrap(),
    );
    let (first, last, other) = (&b[0], b.last().unwrap(), a.last().unwrap());
    let dist = |p: [f64; 3], q: [f64; 3]| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt();
    let moved = (0..first.positions.len())
        .map(|i| dist(first.positions[i], last.positions[i]))
        .fold(0.0, f64::max);
    let diff = (0..first.positions.len())
        .map(|i| dist(other.positions[i], last.positions[i]))
        .fold(0.0, f64::max);
    assert!(
        moved > 0.1 && diff < 1e-5 * moved,
        "moved {moved}, PSE vs Ewald {diff}"
    );
    let text = text.replace("[integrator]", "[integrator]\nsolver = \"newton\"");
    let line = text.lines().position(|l| l == "method = \"pse\"").unwrap() + 1;
    std::fs::write(&path, &text).unwrap();
    let out = dir.join("refused");
    let r = demo_run(&path, &out);
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    let at = format!("{}:{line}:", path.display());
    assert!(err.contains(&at), "{err}");
    assert!(
        err.contains(
            "[box] method = \"pse\" gives mobility products only, and the sweep or newton solver"
        ),
        "{err}"
    );
    assert!(!out.exists());
}
