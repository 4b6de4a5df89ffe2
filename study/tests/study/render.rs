//! Pictures: each drawing function writes a valid PNG of the expected size. The files
//! stay in the target's temporary directory (`render/`) for a look by eye.

use hydrorattle_host::scene::{Helix, Scene};
use hydrorattle_study::render::{
    CategoryMap, Figure1Case, LineChart, Mark, Series, Snapshot, category_map, chain_colors,
    draw_configuration, draw_figure1, line_chart, line_charts,
};
use plotters::style::RGBColor;
use std::path::{Path, PathBuf};

fn out_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("render");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

fn snapshot(scene: &Scene, time: f64) -> Snapshot {
    Snapshot {
        time,
        positions: scene.positions(),
        radii: scene.radii(),
        wall: None,
    }
}

/// A synthetic late state: the chain hanging straight down from its head, with a small
/// sideways wiggle of the given amplitude, moved `drop` down.
fn stretched(helix: &Helix, wiggle: f64, drop: f64) -> Snapshot {
    let chain = helix.generate().unwrap();
    let mut z = -drop;
    let mut positions = vec![[0.0, 0.0, z]];
    for (k, &(_, _, d)) in chain.bonds.iter().enumerate() {
        let phase = k as f64 * 0.9;
        let (dx, dy) = (wiggle * phase.cos(), wiggle * phase.sin());
        z += (d * d - dx * dx - dy * dy).sqrt();
        positions.push([dx, dy, z]);
    }
    Snapshot {
        time: 400.0,
        positions,
        radii: chain.radii,
        wall: None,
    }
}

#[test]
fn figure1_layout() {
    let cases = Scene::figure1().unwrap();
    let titles = [
        "(a) D=1.50, head 2^(1/3)",
        "(b) D=1.05, head 2^(1/3)",
        "(c) D=1.05, head 2",
    ];
    let wiggles = [0.2, 1.8, 0.5];
    let figure: Vec<Figure1Case> = cases
        .iter()
        .zip(titles)
        .zip(wiggles)
        .map(|(((_, scene), title), wiggle)| Figure1Case {
            title: title.to_string(),
            initial: snapshot(scene, 0.0),
            last: stretched(&scene.helix.unwrap(), wiggle, 380.0),
        })
        .collect();
    let path = out_dir().join("figure1.png");
    draw_figure1(&path, &figure).unwrap();
    let (w, h) = png_size(&path);
    assert!(w > 1000 && h > 600, "{w} x {h}");
}

#[test]
fn single_configurations() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/scenes");
    for name in ["dimer", "ring", "tree", "figure1c"] {
        let scene = Scene::from_path(&dir.join(format!("{name}.toml"))).unwrap();
        let path = out_dir().join(format!("{name}.png"));
        draw_configuration(
            &path,
            &snapshot(&scene, 0.0),
            &chain_colors(scene.particles.len()),
            name,
            (800, 450),
        )
        .unwrap();
        assert_eq!(png_size(&path), (800, 450));
    }
}

#[test]
fn line_charts_linear_and_log() {
    let series = |name: &str, p: f64| Series {
        name: name.to_string(),
        points: (0..8)
            .map(|k| {
                let dt = 1e-3 * 2f64.powi(k);
                (dt, dt.powf(p))
            })
            .collect(),
    };
    for (log, file) in [(false, "line.png"), (true, "line_loglog.png")] {
        let chart = LineChart {
            title: "error against time step".into(),
            x_label: "dt".into(),
            y_label: "error".into(),
            log_x: log,
            log_y: log,
            series: vec![series("first order", 1.0), series("second order", 2.0)],
        };
        let path = out_dir().join(file);
        line_chart(&path, &chart, (800, 500)).unwrap();
        assert_eq!(png_size(&path), (800, 500));
    }
    let empty = LineChart {
        log_x: true,
        series: vec![Series {
            name: "negative".into(),
            points: vec![(-1.0, 1.0)],
        }],
        ..LineChart::default()
    };
    assert!(line_chart(&out_dir().join("empty.png"), &empty, (100, 100)).is_err());
    // Stacked: one picture of the given size, and no picture where a panel has no point.
    let panel = |name: &str| LineChart {
        title: name.into(),
        log_x: true,
        log_y: true,
        series: vec![series("first order", 1.0)],
        ..LineChart::default()
    };
    let path = out_dir().join("stacked.png");
    line_charts(&path, &[panel("top"), panel("bottom")], (600, 800)).unwrap();
    assert_eq!(png_size(&path), (600, 800));
    let path = out_dir().join("stacked_empty.png");
    let _ = std::fs::remove_file(&path);
    assert!(line_charts(&path, &[panel("top"), empty], (600, 800)).is_err());
    assert!(!path.exists());
}

#[test]
fn category_map_with_marks() {
    let x: Vec<f64> = (0..6).map(|i| 1.05 + 0.19 * i as f64).collect();
    let y: Vec<f64> = (0..6).map(|j| 1.0 + 0.3 * j as f64).collect();
    let cells = (0..36)
        .map(|k| match k {
            7 => None,
            _ if (k % 6) as f64 * 0.5 > (k / 6) as f64 * 0.4 => Some(0),
            _ => Some(1),
        })
        .collect();
    let map = CategoryMap {
        title: "outcome".into(),
        x_label: "D".into(),
        y_label: "head ratio".into(),
        x,
        y,
        cells,
        categories: vec![
            ("stretched".into(), RGBColor(120, 170, 220)),
            ("twisting".into(), RGBColor(240, 170, 90)),
        ],
        marks: vec![
            Mark {
                x: 1.5,
                y: 2f64.cbrt(),
                label: "a".into(),
            },
            Mark {
                x: 1.05,
                y: 2f64.cbrt(),
                label: "b".into(),
            },
            Mark {
                x: 1.05,
                y: 2.0,
                label: "c".into(),
            },
        ],
    };
    let path = out_dir().join("phase.png");
    category_map(&path, &map, (900, 650)).unwrap();
    assert_eq!(png_size(&path), (900, 650));
    let bad = CategoryMap {
        cells: vec![Some(5); 36],
        ..map
    };
    assert!(category_map(&out_dir().join("bad.png"), &bad, (300, 300)).is_err());
}
