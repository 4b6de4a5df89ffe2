//! The pictures of runs, through the real `host-demo`: `figure1 --quick --at` writes
//! every picture (valid PNGs and GIFs of the expected sizes and frame counts), a bad
//! `--at` list is refused before anything runs, `run` draws its initial and final
//! configuration, and drawing is deterministic.

use crate::common::{cli, manifest};
use std::path::Path;

use hydrorattle::observables::FrameState;
use hydrorattle_host::scene::Scene;
use hydrorattle_study::pictures::{ANIMATION_FRAMES, ANIMATION_SIZE};
use hydrorattle_study::render::{Animation, Snapshot, chain_colors, draw_timeline, write_gif};

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

/// Size and frame count of a GIF, every frame decoded.
fn gif_frames(path: &Path) -> ((u16, u16), usize) {
    let file = std::fs::File::open(path).unwrap();
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::Indexed);
    let mut d = options.read_info(file).unwrap();
    let size = (d.width(), d.height());
    let mut frames = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        assert!(u32::from(f.left) + u32::from(f.width) <= u32::from(size.0));
        assert!(u32::from(f.top) + u32::from(f.height) <= u32::from(size.1));
        frames += 1;
    }
    (size, frames)
}

#[test]
fn figure1_quick_writes_every_picture() {
    let out = scratch!("figure1");
    let o = cli(&[
        "figure1",
        "--quick",
        "--out",
        out.to_str().unwrap(),
        "--at",
        "0,5,10,300",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("pictures in"), "{stdout}");
    for f in ["figure1.png", "figure1_common.png", "timelines.png"] {
        let (w, h) = png_size(&out.join(f));
        assert!(w > 900 && h > 150, "{f}: {w} x {h}");
    }
    // Three rows of four panels.
    let (w, h) = png_size(&out.join("snapshots.png"));
    assert!(w > 900 && h > 1200, "{w} x {h}");
    // 2000 steps at every 20: frames at steps 0, 20, ..., 2000.
    for case in ["a", "b", "c"] {
        let dir = out.join(case);
        let (w, h) = png_size(&dir.join("timeline.png"));
        assert!(w > 900 && h > 100, "{w} x {h}");
        let gif = dir.join("animation.gif");
        let (size, frames) = gif_frames(&gif);
        assert_eq!(
            (u32::from(size.0), u32::from(size.1)),
            ANIMATION_SIZE,
            "{case}"
        );
        assert_eq!(frames, ANIMATION_FRAMES + 1, "{case}");
        let bytes = gif.metadata().unwrap().len();
        assert!(bytes < 600_000, "{case}: {bytes} bytes");
    }
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("figure1.json")).unwrap()).unwrap();
    assert!(j["drawing_wall_time_s"].as_f64().unwrap() > 0.0);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn a_bad_at_list_is_refused_before_anything_runs() {
    for bad in ["-1", "nan", "inf", "400.5", "1,2,x", "", "1,,2"] {
        let out = scratch!("bad-at");
        let o = cli(&[
            "figure1",
            "--quick",
            "--out",
            out.to_str().unwrap(),
            "--at",
            bad,
        ]);
        assert!(!o.status.success(), "--at {bad:?} accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("--at"), "--at {bad:?}: {err}");
        assert!(!out.exists(), "--at {bad:?}: output written");
    }
}

#[test]
fn run_draws_the_initial_and_final_configuration() {
    let out = scratch!("run");
    let scene = manifest().join("../host/scenes").join("tree.toml");
    let o = cli(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["initial.png", "final.png"] {
        assert_eq!(png_size(&out.join(f)), (900, 500), "{f}");
    }
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn drawing_is_deterministic() {
    let dir = scratch!("deterministic");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = &Scene::figure1().unwrap()[2].1;
    let frames: Vec<Snapshot> = (0..12)
        .map(|k| Snapshot {
            time: f64::from(k),
            positions: scene
                .positions()
                .iter()
                .map(|p| [p[0] + 0.3 * f64::from(k), p[1], p[2] - 2.0 * f64::from(k)])
                .collect(),
            radii: scene.radii(),
            wall: None,
        })
        .collect();
    let colors = chain_colors(frames[0].positions.len());
    let names = FrameState::ALL.map(FrameState::name);
    let rows: Vec<(f64, &str)> = (0..12u32)
        .map(|k| (f64::from(k), names[k as usize % names.len()]))
        .chain([(12.0, "unknown state")])
        .collect();
    let mut bytes = Vec::new();
    for n in 0..2 {
        let gif = dir.join(format!("{n}.gif"));
        let a = Animation {
            title: "(c)",
            frames: &frames,
            colors: &colors,
            size: (200, 300),
            delay: 8,
        };
        let info = write_gif(&gif, &a).unwrap();
        assert_eq!(info.frames, 12);
        assert_eq!(gif_frames(&gif), ((200, 300), 12));
        let png = dir.join(format!("{n}.png"));
        draw_timeline(&png, "timeline", &rows, &names, 20.0).unwrap();
        bytes.push((std::fs::read(&gif).unwrap(), std::fs::read(&png).unwrap()));
    }
    assert!(bytes[0] == bytes[1], "drawing twice gave different bytes");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A sphere 1.5 radii above a wall at `z = -2.5`, free draining: it lands.
const WALL_SCENE: &str = "[wall]\nheight = -2.5\n\n\
    [[particle]]\nposition = [0.0, 0.0, 0.0]\nradius = 1.0\n\n\
    [model]\nhydrodynamics = \"free-draining\"\n\n\
    [integrator]\nmethod = \"overdamped\"\ndt = 0.1\nduration = 6.0\n";

/// A wall scene's pictures draw the wall: `run` writes them, its configurations carry
/// the wall's height, and a configuration drawn with its wall is not the one drawn
/// without (the geometry is `render::panel`'s unit test).
#[test]
fn a_wall_scene_s_pictures_draw_the_wall() {
    let out = scratch!("wall");
    std::fs::create_dir_all(&out).unwrap();
    let path = out.join("landing.toml");
    std::fs::write(&path, WALL_SCENE).unwrap();
    let dir = out.join("run");
    let o = cli(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["initial.png", "final.png"] {
        assert_eq!(png_size(&dir.join(f)), (900, 500), "{f}");
    }
    let scene = Scene::from_path(&path).unwrap();
    let r = hydrorattle_host::sim::run(&scene, "landing", None, Default::default()).unwrap();
    assert!(r.summary.landing_time.is_some());
    assert_eq!((r.initial.wall, r.last.wall), (Some(-2.5), Some(-2.5)));
    let draw = |s: &Snapshot, name: &str| {
        let p = out.join(name);
        let colors = chain_colors(1);
        hydrorattle_study::render::draw_configuration(&p, s, &colors, "landed", (600, 300))
            .unwrap();
        std::fs::read(p).unwrap()
    };
    let without = Snapshot {
        wall: None,
        ..r.last.clone()
    };
    assert!(draw(&r.last, "with.png") != draw(&without, "without.png"));
    std::fs::remove_dir_all(&out).unwrap();
}

/// A sphere at 1e16: its spread is lost in the rounding of its coordinates, so its
/// pictures are skipped with a message, promptly, and the run's data stand (it used to
/// hang while drawing). The step is long enough for the settling to move it by more
/// than its coordinates' spacing (about 2 there): a shorter one is refused.
#[test]
fn a_sphere_far_from_the_origin_is_skipped_not_drawn_forever() {
    let dir = scratch!("far-sphere");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("far.toml");
    let text = "[[particle]]\nposition = [1e16, 1e16, 1e16]\nradius = 1.0\n\n\
                [integrator]\nmethod = \"overdamped\"\ndt = 1000.0\nduration = 10000.0\n";
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let t = std::time::Instant::now();
    let o = cli(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(t.elapsed() < std::time::Duration::from_secs(10));
    assert!(err.contains("not drawn"), "{err}");
    assert!(out.join("summary.json").exists() && out.join("observables.csv").exists());
    assert!(!out.join("final.png").exists());
}
