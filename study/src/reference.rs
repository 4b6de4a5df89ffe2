//! How far the main job's trajectories can be trusted: each Figure 1 case is run at the
//! main job's settings and at cheaper or older ones, and compared frame by frame with
//! a reference at a small time step (same model: hard contacts, RPY).
//!
//! Writes `reference.json` (per case and variant: RMS deviation from the reference at
//! every common frame, the horizons where it first exceeds 0.1 and 0.5 tail radii, the
//! final outcome of both; per variant: the paper's claims judged on its runs next to
//! the reference's verdicts) and `reference_{a,b,c}.png` (deviation against time).

use std::path::Path;

use anyhow::{Result, bail};
use rayon::prelude::*;
use serde::Serialize;

use crate::charts::rms;
use crate::claims::{CaseRun, Verdict, claims};
use crate::render::{LineChart, Series, Snapshot, line_chart};
use hydrorattle_host::output::write_json;
use hydrorattle_host::scene::{Method, Scene};
use hydrorattle_host::sim::{KeepFrames, RunOptions, RunResult, run};

/// Time between compared frames (every variant writes a frame this often).
const FRAME_DT: f64 = 2.0;
/// Deviation thresholds of the horizons, tail radii.
pub const THRESHOLDS: [f64; 2] = [0.1, 0.5];

/// One way of running a case.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Variant {
    /// Short name (`main`, `first-order`, ...).
    pub name: &'static str,
    /// Integrator.
    #[serde(serialize_with = "hydrorattle_host::scene::names::serialize")]
    pub method: Method,
    /// Time step.
    pub dt: f64,
}

/// The variants compared with the reference: the main job's settings first.
pub fn variants(main: &Scene) -> Vec<Variant> {
    let dt = main.integrator.dt;
    vec![
        Variant {
            name: "main",
            method: main.integrator.method,
            dt,
        },
        Variant {
            name: "first order, same dt",
            method: Method::Overdamped,
            dt,
        },
        Variant {
            name: "first order, dt / 2",
            method: Method::Overdamped,
            dt: dt / 2.0,
        },
        Variant {
            name: "main, dt / 2",
            method: main.integrator.method,
            dt: dt / 2.0,
        },
        Variant {
            name: "first order, dt = 0.005",
            method: Method::Overdamped,
            dt: 0.005,
        },
    ]
}

/// A variant's comparison with the reference.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// The variant.
    pub variant: Variant,
    /// `(time, RMS deviation of the centres from the reference, tail radii)`.
    pub deviation: Vec<(f64, f64)>,
    /// First time the deviation exceeds each of [`THRESHOLDS`]; `None`: never in the run.
    pub horizons: Vec<Option<f64>>,
    /// The variant's outcome at the end.
    pub outcome: String,
    /// CPU time of the run, seconds.
    pub wall_time_s: f64,
}

/// One case: the reference and the variants.
#[derive(Debug, Clone, Serialize)]
pub struct CaseReference {
    /// "a", "b" or "c".
    pub case: String,
    /// The reference's method and time step.
    pub reference: Variant,
    /// The reference's outcome at the end.
    pub reference_outcome: String,
    /// The comparisons, main job first.
    pub variants: Vec<Comparison>,
}

/// One claim's verdict on a variant's runs next to the reference's.
#[derive(Debug, Clone, Serialize)]
pub struct VerdictRow {
    /// The claim's id.
    pub id: String,
    /// Its case.
    pub case: String,
    /// The reference's verdict.
    pub reference: Verdict,
    /// The variant's verdict, in the order of [`variants`].
    pub variants: Vec<Verdict>,
}

/// `reference.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ReferenceReport {
    /// Per case: deviations and horizons.
    pub cases: Vec<CaseReference>,
    /// The variants' names, in order.
    pub variant_names: Vec<String>,
    /// Per claim: the reference's verdict and each variant's.
    pub verdicts: Vec<VerdictRow>,
}

/// `scene` run as `v`, with a frame every [`FRAME_DT`].
fn as_variant(scene: &Scene, v: Variant) -> Scene {
    let mut s = scene.clone();
    s.integrator.method = v.method;
    s.integrator.dt = v.dt;
    s.output.every = ((FRAME_DT / v.dt).round() as usize).max(1);
    s
}

/// Deviation at the frame times both runs share (to a millionth of a time unit).
fn deviation(reference: &[Snapshot], other: &[Snapshot]) -> Vec<(f64, f64)> {
    let key = |t: f64| (t * 1e6).round() as i64;
    let at: std::collections::BTreeMap<i64, &Snapshot> =
        other.iter().map(|f| (key(f.time), f)).collect();
    // Times are sums of time steps: report them rounded to a millionth.
    reference
        .iter()
        .filter_map(|f| {
            let t = key(f.time);
            at.get(&t)
                .map(|g| (t as f64 * 1e-6, rms(&f.positions, &g.positions)))
        })
        .collect()
}

fn horizons(dev: &[(f64, f64)]) -> Vec<Option<f64>> {
    THRESHOLDS
        .iter()
        .map(|&h| dev.iter().find(|(_, d)| *d > h).map(|(t, _)| *t))
        .collect()
}

/// Runs every case at every variant and at `reference_dt`, into `out/{case}/...`, and
/// writes `reference.json` and `reference_{a,b,c}.png`. `max_steps` caps each run (smoke runs).
pub fn reference(
    out: &Path,
    reference_dt: f64,
    max_steps: Option<usize>,
) -> Result<ReferenceReport> {
    if !(reference_dt.is_finite() && reference_dt > 0.0) {
        bail!("--dt {reference_dt}: the reference time step must be positive");
    }
    std::fs::create_dir_all(out)?;
    let scenes = Scene::figure1()?;
    // Every run of every case, in parallel: per case the reference first, then the
    // variants. Each keeps its frames (every FRAME_DT) in memory.
    let mut jobs = Vec::new();
    for (case, scene) in &scenes {
        let refv = Variant {
            name: "reference",
            method: scene.integrator.method,
            dt: reference_dt,
        };
        for v in std::iter::once(refv).chain(variants(scene)) {
            jobs.push((*case, v, as_variant(scene, v)));
        }
    }
    let done: Vec<(&str, Variant, RunResult)> = jobs
        .par_iter()
        .map(|(case, v, s)| {
            let opts = RunOptions {
                max_steps,
                keep: KeepFrames {
                    every: Some(s.output.every),
                    at: &[],
                },
                ..RunOptions::default()
            };
            run(s, case, None, opts).map(|r| (*case, *v, r))
        })
        .collect::<Result<_>>()?;
    let mut cases = Vec::new();
    for (case, _) in &scenes {
        let mut runs = done.iter().filter(|(c, ..)| c == case);
        let (_, refv, reference) = runs.next().expect("the reference runs first");
        let variants = runs
            .map(|(_, variant, r)| {
                let dev = deviation(&reference.frames, &r.frames);
                Comparison {
                    variant: *variant,
                    horizons: horizons(&dev),
                    deviation: dev,
                    outcome: r.summary.outcome.clone(),
                    wall_time_s: r.summary.wall_time_s,
                }
            })
            .collect();
        cases.push(CaseReference {
            case: case.to_string(),
            reference: *refv,
            reference_outcome: reference.summary.outcome.clone(),
            variants,
        });
    }
    let report = ReferenceReport {
        variant_names: variants(&scenes[0].1)
            .iter()
            .map(|v| v.name.to_string())
            .collect(),
        verdicts: verdicts(&done),
        cases,
    };
    write_json(&out.join("reference.json"), &report)?;
    draw(out, &report.cases, max_steps.is_some())?;
    Ok(report)
}

/// The claims judged on each variant's three runs (and the reference's), side by side.
fn verdicts(done: &[(&str, Variant, RunResult)]) -> Vec<VerdictRow> {
    let judged = |name: &str| {
        let runs: Vec<CaseRun<'_>> = done
            .iter()
            .filter(|(_, v, _)| v.name == name)
            .map(|(case, _, r)| CaseRun {
                case,
                series: &r.series,
                front: &r.summary.front,
            })
            .collect();
        claims(&runs)
    };
    let names: Vec<&str> = done
        .iter()
        .filter(|(case, ..)| *case == done[0].0)
        .map(|(_, v, _)| v.name)
        .filter(|n| *n != "reference")
        .collect();
    let others: Vec<_> = names.iter().map(|n| judged(n)).collect();
    judged("reference")
        .into_iter()
        .map(|c| VerdictRow {
            variants: others
                .iter()
                .map(|o| {
                    o.iter()
                        .find(|x| x.id == c.id)
                        .map_or(Verdict::Fails, |x| x.verdict)
                })
                .collect(),
            id: c.id,
            case: c.case,
            reference: c.verdict,
        })
        .collect()
}

fn draw(out: &Path, cases: &[CaseReference], quick: bool) -> Result<()> {
    for c in cases {
        let series = c
            .variants
            .iter()
            .map(|v| Series {
                name: format!(
                    "{} ({:?}, dt {})",
                    v.variant.name, v.variant.method, v.variant.dt
                ),
                points: v.deviation.iter().copied().filter(|p| p.1 > 0.0).collect(),
            })
            .collect();
        let chart = LineChart {
            title: format!(
                "Figure 1 ({}): RMS deviation from the {:?} dt = {} reference{}",
                c.case,
                c.reference.method,
                c.reference.dt,
                if quick { " [QUICK]" } else { "" }
            ),
            x_label: "time (a / U0)".into(),
            y_label: "RMS deviation of the centres (tail radii)".into(),
            log_x: false,
            log_y: true,
            series,
        };
        line_chart(
            &out.join(format!("reference_{}.png", c.case)),
            &chart,
            (1100, 700),
        )?;
    }
    Ok(())
}
