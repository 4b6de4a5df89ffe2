//! A falling cloud's run turned into its measures and pictures: for each frame of the
//! run's `trajectory.xyz` (or of the `trajectory.xyz.tmp` of a run still going, resumed
//! or stopped, where it is the newer: its last whole frame), the core's fall speed, the
//! fraction of spheres leaked into the tail, the torus criterion (the density on the
//! axis in the core's mid-plane over the densest ring's: about 1 for a ball, 0 for a
//! torus), that criterion with the rings of the nine frames about it pooled, and the
//! core's flatness (1 for a ball, about 0.3 for a thin torus); and, for the
//! times asked, a picture with one row per time: a thin slice through the axis and the
//! density averaged about the axis in `(r, z)` with the mean velocity in the cloud's
//! frame (`hydrorattle_study::cloud`, `render::cloud`).
//!
//! ```text
//! cargo run --release -p hydrorattle-study --example cloud_torus -- RUN_DIR OUT.png T1,T2,..
//! ```
//!
//! The cloud's initial radius is that of the first frame's centres, as a uniform ball's
//! (`cloud::ball_radius`). With `HYDRORATTLE_BENCH_MACHINE` set, the measures of every frame go
//! to `bench/results/cloud_torus.csv` (`CLOUD_TORUS_CASE` names the run there).

#[path = "../../examples/shared/record.rs"]
mod record;

use std::io::Cursor;
use std::path::Path;

use anyhow::{Context, Result, anyhow};
use hydrorattle_host::output::{Frame, read_xyz};
use hydrorattle_study::cloud::{
    CORE_REACH, axis_map, axis_rings, axis_slice, ball_radius, core, flatness, ring_ratio,
};
use hydrorattle_study::render::{CloudRow, draw_cloud};

/// Frames on each side of a frame whose axis rings are pooled.
const POOL: usize = 4;
/// The pooled criterion below which a cloud counts as a torus (a ball's is about 0.9,
/// a torus's with a hole wider than the axis ring 0).
const ONSET: f64 = 0.5;
/// Frames a run recorded at most (evenly spaced; the onset is recorded besides).
const RECORDED: usize = 50;
/// The pooled criterion's name in the records.
const POOLED: &str = "on-axis density over peak, 9 frames pooled";

/// The whole frames of an XYZ text (a file still being written may end mid-frame).
fn whole_frames(text: &str) -> Result<Vec<Frame>> {
    let lines: Vec<&str> = text.lines().collect();
    let mut end = 0;
    while let Some(n) = lines.get(end).and_then(|l| l.trim().parse::<usize>().ok()) {
        if end + n + 2 > lines.len() {
            break;
        }
        end += n + 2;
    }
    read_xyz(Cursor::new(lines[..end].join("\n"))).map_err(|e| anyhow!("{e}"))
}

fn read_frames(dir: &Path) -> Result<Vec<Frame>> {
    // A run resumed past its end writes `.tmp` again beside the finished file: the
    // newer of the two is the run as it stands.
    let (done, going) = (dir.join("trajectory.xyz"), dir.join("trajectory.xyz.tmp"));
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let path = match (modified(&done), modified(&going)) {
        (Some(d), Some(g)) if g > d => going,
        (Some(_), _) => done,
        _ => going,
    };
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    whole_frames(&text).with_context(|| path.display().to_string())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dir, out, times] = args.as_slice() else {
        return Err(anyhow!("usage: cloud_torus RUN_DIR OUT.png T1,T2,.."));
    };
    let times: Vec<f64> = times
        .split(',')
        .map(|t| t.trim().parse().context("a time"))
        .collect::<Result<_>>()?;
    let frames = read_frames(Path::new(dir))?;
    let first = frames.first().ok_or_else(|| anyhow!("{dir}: no frame"))?;
    let n = first.positions.len();
    let radius = ball_radius(&first.positions);
    let predicted = 1.0 + 6.0 * n as f64 / (5.0 * radius);
    println!("{n} spheres, initial radius {radius:.2}: 1 + 6 N a / (5 R) = {predicted:.2}");
    println!("time,core_z,fall_speed,fallen_radii,tail_fraction,axis_ratio,pooled_ratio,flatness");
    let case = std::env::var("CLOUD_TORUS_CASE").unwrap_or_else(|_| dir.clone());
    let mut rec = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "cloud_torus",
        format!(
            "cargo run --release -p hydrorattle-study --example cloud_torus -- {dir} {out} ..."
        ),
    );
    let what = format!("falling cloud of {n} unit spheres, initial radius {radius:.1}");
    rec.row(
        &what,
        "t = 0",
        "continuum speed 1 + 6 N a / (5 R), U0",
        &format!("{predicted:.2}"),
    );
    let z0 = core(&first.positions, &[], radius).centre[2];
    // Rings as wide as a fifth of the radius, in a slab of half the radius.
    let (width, slab) = (0.2 * radius, 0.5 * radius);
    let cores: Vec<_> = frames
        .iter()
        .map(|f| core(&f.positions, &f.velocities, radius))
        .collect();
    let rings: Vec<Vec<usize>> = frames
        .iter()
        .zip(&cores)
        .map(|(f, c)| axis_rings(&f.positions, c, width, slab, 2.0 * radius))
        .collect();
    let show = |r: Option<f64>| r.map_or("".into(), |r| format!("{r:.3}"));
    // The last frame whose pooled criterion is still a ball's (at least ONSET).
    let mut ball_until = None;
    for (k, (f, c)) in frames.iter().zip(&cores).enumerate() {
        let tail = c.tail as f64 / n as f64;
        let ratio = show(ring_ratio(&rings[k]));
        // One frame's ring on the axis holds some fifteen spheres at 1000: the rings
        // of the frames within POOL of this one, summed, divide that noise.
        let near = k.saturating_sub(POOL)..(k + POOL + 1).min(frames.len());
        let mut pooled = vec![0; rings[k].len()];
        for r in &rings[near] {
            pooled.iter_mut().zip(r).for_each(|(p, c)| *p += c);
        }
        let pooled = ring_ratio(&pooled);
        if pooled.is_none_or(|p| p >= ONSET) {
            ball_until = Some(k);
        }
        let pooled = show(pooled);
        let flat = show(flatness(&f.positions, c, CORE_REACH * radius));
        let fallen = (z0 - c.centre[2]) / radius;
        let speed = -c.velocity[2];
        let time = format!("{:.3}", f.time);
        let time = time.trim_end_matches('0').trim_end_matches('.');
        println!(
            "{time},{:.2},{speed:.3},{fallen:.2},{tail:.4},{ratio},{pooled},{flat}",
            c.centre[2]
        );
        // The records keep about RECORDED frames a run (every frame is printed).
        if k % frames.len().div_ceil(RECORDED) != 0 {
            continue;
        }
        let at = format!("{case}, t = {time}");
        if f.time > 0.0 {
            rec.row(&what, &at, "core fall speed, U0", &format!("{speed:.3}"));
        }
        rec.row(&what, &at, "fallen, initial radii", &format!("{fallen:.2}"));
        rec.row(&what, &at, "fraction in the tail", &format!("{tail:.4}"));
        rec.row(&what, &at, "on-axis density over peak", &ratio);
        rec.row(&what, &at, POOLED, &pooled);
        rec.row(&what, &at, "flatness sqrt(2) z_rms / r_rms", &flat);
    }
    let onset = ball_until.map_or(Some(0), |k| (k + 1 < frames.len()).then_some(k + 1));
    match onset {
        Some(k) => {
            let t = format!("{:.1}", frames[k].time);
            let fallen = (z0 - cores[k].centre[2]) / radius;
            println!(
                "torus from t = {t} ({fallen:.1} radii fallen): pooled criterion below {ONSET} to the last frame"
            );
            let at = format!("{case}, t = {t}");
            rec.row(
                &what,
                &at,
                "torus onset, fallen initial radii",
                &format!("{fallen:.1}"),
            );
        }
        None => println!("no torus: the pooled criterion is {ONSET} or more at the last frame"),
    }
    // About 8 cells across the radius at 1000 spheres, 16 from 8000: a cell on the
    // axis then holds some ten spheres or more.
    let cells = (0.8 * (n as f64).cbrt()).round().clamp(8.0, 16.0) as usize;
    let rows: Vec<CloudRow> = times
        .iter()
        .map(|&t| {
            let k = (0..frames.len())
                .min_by(|&a, &b| {
                    (frames[a].time - t)
                        .abs()
                        .total_cmp(&(frames[b].time - t).abs())
                })
                .expect("frames");
            let (f, c) = (&frames[k], cores[k]);
            let half_width = 0.1 * radius;
            CloudRow {
                time: f.time,
                slice: axis_slice(&f.positions, &c, half_width),
                half_width,
                map: axis_map(
                    &f.positions,
                    &f.velocities,
                    &c,
                    (2.0 * radius, 1.25 * radius),
                    (cells, cells * 5 / 4),
                ),
                x_half: 2.0 * radius,
                z_range: (-1.5 * radius, 2.5 * radius),
            }
        })
        .collect();
    draw_cloud(Path::new(out), &what, &rows, 900, 380)?;
    eprintln!("wrote {out}");
    rec.finish()?;
    Ok(())
}
