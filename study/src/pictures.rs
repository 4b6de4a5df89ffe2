//! The pictures of runs: any run's initial and final configuration, and the pictures of
//! Figure 1 (the Figure 1 layout at each case's own and at one common scale, state
//! timelines, snapshots at chosen times, one animation per case), drawn in parallel.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, anyhow};
use hydrorattle::observables::FrameState;
use plotters::style::RGBColor;
use rayon::prelude::*;

use crate::render::{
    Animation, Figure1Case, HEAD_COLOR, LAST_COLOR, SERIES_COLORS, SnapshotRow, Strip, TAIL_COLOR,
    chain_colors, draw_configuration, draw_figure1, draw_figure1_common, draw_snapshots,
    draw_timeline, draw_timelines, write_gif,
};
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::RunResult;

/// A run's initial configuration (side and top views).
pub const INITIAL_PNG: &str = "initial.png";
/// A run's final configuration (side and top views).
pub const FINAL_PNG: &str = "final.png";
/// Figure 1 at each case's own scale.
pub const FIGURE1_PNG: &str = "figure1.png";
/// Figure 1 at one common scale.
pub const FIGURE1_COMMON_PNG: &str = "figure1_common.png";
/// The three cases' timelines on one time axis.
pub const TIMELINES_PNG: &str = "timelines.png";
/// One case's timeline (in the case's folder).
pub const TIMELINE_PNG: &str = "timeline.png";
/// One case's animation (in the case's folder).
pub const ANIMATION_GIF: &str = "animation.gif";
/// Side views of the cases at the times asked (`--at`).
pub const SNAPSHOTS_PNG: &str = "snapshots.png";

/// Frames an animation aims at (the cadence is a whole number of steps).
pub const ANIMATION_FRAMES: usize = 100;
/// Size of an animation frame, pixels.
pub const ANIMATION_SIZE: (u32, u32) = (360, 480);
/// Delay between animation frames, hundredths of a second.
pub const ANIMATION_DELAY: u16 = 8;
/// Most times `--at` takes.
pub const MAX_AT: usize = 12;

/// Colours of a scene's spheres: a helix chain's head red, tails blue, last green;
/// otherwise by species (in order of first appearance), all blue for one species.
pub fn scene_colors(scene: &Scene) -> Vec<RGBColor> {
    let n = scene.particles.len();
    if scene.helix.is_some() {
        return chain_colors(n);
    }
    let palette = [TAIL_COLOR, HEAD_COLOR, LAST_COLOR];
    let mut seen: Vec<&str> = Vec::new();
    (0..n)
        .map(|i| {
            let s = scene.species.get(i).map_or("P", |s| s.as_ref());
            let k = seen.iter().position(|&t| t == s).unwrap_or_else(|| {
                seen.push(s);
                seen.len() - 1
            });
            palette
                .get(k)
                .copied()
                .unwrap_or(SERIES_COLORS[k % SERIES_COLORS.len()])
        })
        .collect()
}

/// Draws a run's [`INITIAL_PNG`] (when `initial`; a resumed run keeps its first) and
/// [`FINAL_PNG`] into `dir`.
pub fn draw_run(dir: &Path, r: &RunResult, initial: bool) -> Result<()> {
    let scene = &r.summary.resolved_scene;
    let colors = scene_colors(scene);
    let what = format!(
        "{} particles, {} bonds",
        scene.particles.len(),
        scene.bonds.len()
    );
    let name = &r.summary.scene;
    // A picture that cannot be drawn is skipped with a message: the run's data stand.
    let draw = |file: &str, snap, when: &str| {
        let title = format!("{name}: {when} configuration ({what})");
        let path = dir.join(file);
        if let Err(e) = draw_configuration(&path, snap, &colors, &title, (900, 500)) {
            match e.downcast_ref::<crate::render::Undrawable>() {
                Some(why) => log::warn!("{}: not drawn: {why}", path.display()),
                None => return Err(e),
            }
        }
        Ok(())
    };
    let (a, b) = rayon::join(
        || match initial {
            true => draw(INITIAL_PNG, &r.initial, "initial"),
            false => Ok(()),
        },
        || draw(FINAL_PNG, &r.last, "final"),
    );
    a.and(b)
}

/// The times of `--at`, checked: at most [`MAX_AT`], each finite and within the run's
/// `0..=duration`.
pub fn check_times(at: &[f64], duration: f64) -> Result<()> {
    if at.len() > MAX_AT {
        return Err(anyhow!(
            "--at takes at most {MAX_AT} times, not {}",
            at.len()
        ));
    }
    if let Some(t) = at
        .iter()
        .find(|t| !(t.is_finite() && **t >= 0.0 && **t <= duration))
    {
        return Err(anyhow!(
            "--at {t}: every time must be a number from 0 to the runs' duration {duration}"
        ));
    }
    Ok(())
}

/// One case of Figure 1, run, for its pictures.
#[derive(Debug, Clone, Copy)]
pub struct CaseRun<'a> {
    /// "a", "b" or "c": the case's folder.
    pub case: &'a str,
    /// Title of the case's pictures.
    pub title: &'a str,
    /// The run, with its series and frames kept.
    pub result: &'a RunResult,
}

/// A picture job: draws one file and says what it wrote.
type Job<'a> = Box<dyn Fn() -> Result<String> + Send + Sync + 'a>;

/// Draws every picture of Figure 1 into `out` (the cases' own ones into `out/<case>`),
/// in parallel; `at`: the times of `snapshots.png` (none: no such file). Returns a line
/// per file written (GIFs with frames and bytes) and the wall time, seconds.
pub fn figure1_pictures(
    out: &Path,
    cases: &[CaseRun<'_>],
    at: &[f64],
) -> Result<(Vec<String>, f64)> {
    let start = Instant::now();
    let panels: Vec<Figure1Case> = cases
        .iter()
        .map(|c| Figure1Case {
            title: c.title.to_string(),
            initial: c.result.initial.clone(),
            last: c.result.last.clone(),
        })
        .collect();
    let names = FrameState::ALL.map(FrameState::name);
    let states: Vec<Vec<(f64, &str)>> = cases
        .iter()
        .map(|c| crate::timeline::states(&c.result.series))
        .collect();
    let duration = cases.iter().map(|c| planned(c.result)).fold(0.0, f64::max);
    let written = |p: &Path| format!("wrote {}", p.display());
    let mut jobs: Vec<Job<'_>> = vec![
        Box::new(|| {
            let p = out.join(FIGURE1_PNG);
            draw_figure1(&p, &panels).map(|()| written(&p))
        }),
        Box::new(|| {
            let p = out.join(FIGURE1_COMMON_PNG);
            draw_figure1_common(&p, &panels).map(|()| written(&p))
        }),
        Box::new(|| {
            let strips: Vec<Strip<'_>> = cases
                .iter()
                .zip(&states)
                .map(|(c, rows)| Strip {
                    label: format!("({})", c.case),
                    rows: rows.clone(),
                })
                .collect();
            let p = out.join(TIMELINES_PNG);
            let title = "State against time, the three cases";
            draw_timelines(&p, title, &strips, &names, duration).map(|()| written(&p))
        }),
    ];
    for (c, rows) in cases.iter().zip(&states) {
        let dir = out.join(c.case);
        let (d1, d2) = (dir.clone(), dir);
        jobs.push(Box::new(move || {
            let p = d1.join(TIMELINE_PNG);
            let title = format!("{}: state against time", c.title);
            let d = planned(c.result);
            draw_timeline(&p, &title, rows, &names, d).map(|()| written(&p))
        }));
        jobs.push(Box::new(move || {
            let p = d2.join(ANIMATION_GIF);
            let colors = chain_colors(c.result.initial.positions.len());
            let title = format!("({})", c.case);
            let a = Animation {
                title: &title,
                frames: &c.result.frames,
                colors: &colors,
                size: ANIMATION_SIZE,
                delay: ANIMATION_DELAY,
            };
            let info = write_gif(&p, &a)?;
            Ok(format!(
                "wrote {} ({} frames, {} bytes)",
                p.display(),
                info.frames,
                info.bytes
            ))
        }));
    }
    if !at.is_empty() {
        jobs.push(Box::new(|| {
            let rows: Vec<SnapshotRow> = cases
                .iter()
                .map(|c| SnapshotRow {
                    title: c.title.to_string(),
                    snapshots: c.result.at.clone(),
                })
                .collect();
            let p = out.join(SNAPSHOTS_PNG);
            draw_snapshots(&p, &rows, at).map(|()| written(&p))
        }));
    }
    let notes = jobs
        .par_iter()
        .map(|job| job())
        .collect::<Result<Vec<_>>>()?;
    Ok((notes, start.elapsed().as_secs_f64()))
}

/// The simulated time a run was asked to cover (its steps, capped, times `dt`).
fn planned(r: &RunResult) -> f64 {
    r.summary.steps as f64 * r.summary.integrator.dt
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_are_checked() {
        assert!(check_times(&[0.0, 10.0, 400.0], 400.0).is_ok());
        for bad in [-1.0, 400.5, f64::NAN, f64::INFINITY] {
            let e = check_times(&[1.0, bad], 400.0).unwrap_err().to_string();
            assert!(e.contains("--at"), "{e}");
        }
        assert!(check_times(&[1.0; 13], 400.0).is_err());
    }
}
