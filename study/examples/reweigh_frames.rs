//! The weighing before each step (`[free_space] reweigh`) against the clock, frame by
//! frame of a falling cloud's run: at each frame the cost model's seconds a step on
//! the fast product (its near pairs counted) and on the pair sums, the path the
//! weighing takes, and the measured seconds of one step on each path from that frame
//! (the second of two steps: the first may compute the fast product's kernel
//! transform again, which a run pays only when its rounded box changes), and the
//! seconds of the weighing itself.
//!
//! ```text
//! cargo run --release -p hydrorattle-study --example reweigh_frames -- RUN_DIR SCENE.toml [EVERY]
//! ```
//!
//! `RUN_DIR` holds the run's `trajectory.xyz` (every `EVERY`-th frame is read, default
//! 2), `SCENE.toml` the scene it ran (its `[free_space]` is replaced by each path's).
//! One thread. With `HYDRORATTLE_BENCH_MACHINE` set, rows go to
//! `bench/results/reweigh_frames.csv`.

use anyhow::{Context, Result, anyhow};
use hydrorattle::Real;
use hydrorattle_host::output::read_xyz_file;
use hydrorattle_host::scene::Scene;
use hydrorattle_host::scene::free_reweigh::Reweigh;
use hydrorattle_host::sim::{Engine, resolve_level};
use hydrorattle_host::sizing::DEFAULT_LIMIT;
use std::time::Instant;

#[path = "../../examples/shared/record.rs"]
mod record;

/// The scene text with its `[free_space]` table replaced by `table`.
fn with_free(text: &str, table: &str) -> String {
    let mut out = String::new();
    let mut skip = false;
    for line in text.lines() {
        if line.trim_start().starts_with('[') {
            skip = line.trim() == "[free_space]";
        }
        if !skip {
            out.push_str(line);
            out.push('\n');
        }
    }
    format!("{out}\n{table}\n")
}

fn engine(text: &str, name: &str) -> Result<Engine<f64>> {
    let scene = Scene::parse(text, name).map_err(|e| anyhow!("{e}"))?;
    let scene = resolve_level(&scene, name).0;
    Engine::new(&scene, DEFAULT_LIMIT).map_err(|e| anyhow!("{e}"))
}

/// Seconds of the second of two steps of `e` from `pos`.
fn timed(e: &mut Engine<f64>, pos: &[[f64; 3]]) -> Result<f64> {
    e.beads.pos = pos.iter().map(|&p| f64::v3_from(p)).collect();
    e.step().map_err(|k| anyhow!("{k}"))?;
    let t = Instant::now();
    e.step().map_err(|k| anyhow!("{k}"))?;
    Ok(t.elapsed().as_secs_f64())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (dir, scene) = match args.as_slice() {
        [d, s, ..] => (d, s),
        _ => return Err(anyhow!("usage: reweigh_frames RUN_DIR SCENE.toml [EVERY]")),
    };
    let every: usize = args.get(2).map_or(Ok(2), |e| e.parse())?;
    let text = std::fs::read_to_string(scene).with_context(|| scene.clone())?;
    let frames = read_xyz_file(&std::path::Path::new(dir).join("trajectory.xyz"))?;
    let mut fast = engine(&with_free(&text, "[free_space]\nmethod = \"fast\""), scene)?;
    let sums = "[free_space]\nmethod = \"dense\"";
    let sums =
        with_free(&text, sums).replacen("[integrator]", "[integrator]\nmatrix_free = true", 1);
    let mut sums = engine(&sums, scene)?;
    let weigh = Reweigh::new(&fast.params, 0).ok_or_else(|| anyhow!("{scene}: no weighing"))?;
    let mut rec = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "reweigh_frames",
        format!(
            "cargo run --release -p hydrorattle-study --example reweigh_frames -- RUN_DIR {scene} {every}"
        ),
    );
    let n = fast.beads.len();
    let what =
        format!("frames of a falling cloud of {n} spheres ({scene}), seconds a step, one thread");
    println!(
        "time,box_height,modelled_fast,modelled_sums,choice,weighing,measured_fast,measured_sums"
    );
    for f in frames.iter().step_by(every.max(1)) {
        let pos = &f.positions;
        let radius = vec![1.0; pos.len()];
        let v: Vec<_> = pos.iter().map(|&p| f64::v3_from(p)).collect();
        let [mf, ms] = weigh
            .modelled::<f64>(&v, &radius)
            .ok_or_else(|| anyhow!("not weighed"))?;
        let clock = Instant::now();
        let choice = format!("{:?}", weigh.choose::<f64>(&v, &radius));
        let weighing = clock.elapsed().as_secs_f64();
        let height = pos.iter().map(|p| p[2]).fold(f64::MIN, f64::max)
            - pos.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
        let (tf, ts) = (timed(&mut fast, pos)?, timed(&mut sums, pos)?);
        let t = f.time;
        println!("{t:.1},{height:.0},{mf:.3},{ms:.3},{choice},{weighing:.4},{tf:.3},{ts:.3}");
        let case = format!("t = {t:.1}, box height {height:.0}");
        rec.row(&what, &case, "modelled fast", &format!("{mf:.3}"));
        rec.row(&what, &case, "modelled pair sums", &format!("{ms:.3}"));
        rec.row(&what, &case, "weighing takes", &choice);
        rec.row(
            &what,
            &case,
            "seconds of the weighing",
            &format!("{weighing:.4}"),
        );
        rec.row(&what, &case, "measured fast", &format!("{tf:.3}"));
        rec.row(&what, &case, "measured pair sums", &format!("{ts:.3}"));
    }
    rec.finish()?;
    Ok(())
}
