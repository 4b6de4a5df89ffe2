//! Figure 1 (c) under thermal noise: a Peclet-number sweep.
//!
//! `Pe = F a / kT` with `F` a tail's buoyant weight (`6 pi` in the demo units, so
//! `Pe = 6 pi / kT`). Each Peclet number runs several seeds; the chart shows the mean
//! final verticality, extension, fraction classified "stretched" and settling speed
//! (relative to the deterministic run), against the deterministic values.

use std::f64::consts::PI;
use std::path::Path;

use anyhow::{Result, anyhow};

use super::{Point, write_chart};
use crate::render::LineChart;
use hydrorattle_host::scene::{Drift, Method, Scene, Sqrt, Thermal};
use hydrorattle_host::sim::{RunOptions, RunResult, run};

/// `(verticality, extension, stretched, settling speed)` at the end of a run.
fn outcome(r: &RunResult) -> Result<[f64; 4]> {
    if let Some(f) = &r.summary.failure {
        return Err(anyhow!("{f}"));
    }
    let (first, last) = (r.series[0], r.summary.final_observables);
    let speed = (first.com[2] - last.com[2]) / (last.time - first.time);
    let stretched = f64::from(u8::from(r.summary.outcome == "stretched"));
    Ok([last.verticality, last.extension, stretched, speed])
}

fn at(scene: &Scene, kt: f64, seed: u64) -> Result<[f64; 4]> {
    let mut s = scene.clone();
    s.brownian = (kt > 0.0).then_some(Thermal {
        temperature: kt,
        seed,
        drift: Drift::Midpoint,
        sqrt: Sqrt::Auto,
    });
    outcome(&run(&s, "peclet", None, RunOptions::default())?)
}

/// The sweep; `quick`: one seed, a short run.
pub(super) fn peclet(out: &Path, quick: bool) -> Result<String> {
    let mut scene = Scene::figure1()?
        .into_iter()
        .find(|(case, _)| *case == "c")
        .ok_or_else(|| anyhow!("no Figure 1 (c)"))?
        .1;
    let (duration, seeds) = if quick { (5.0, 1) } else { (100.0, 6) };
    // Thermal noise runs in the first-order overdamped step without hard contacts: the
    // soft contact at the step it allows.
    scene.with_soft_contact();
    scene.integrator.method = Method::Overdamped;
    scene.integrator.duration = duration;
    scene.output.every = scene.integrator.steps();
    let base = at(&scene, 0.0, 0)?;
    let pes = [1000.0, 300.0, 100.0, 30.0, 10.0, 3.0];
    let jobs: Vec<(f64, u64)> = pes
        .iter()
        .flat_map(|&pe| (1..=seeds).map(move |s| (pe, s)))
        .collect();
    let results: Vec<Result<[f64; 4]>> = std::thread::scope(|s| {
        let half = jobs.len().div_ceil(2);
        let workers: Vec<_> = jobs
            .chunks(half)
            .map(|chunk| {
                let scene = &scene;
                s.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(pe, seed)| at(scene, 6.0 * PI / pe, seed))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_default())
            .collect()
    });
    let names = [
        "final verticality",
        "final extension",
        "fraction stretched",
        "settling speed / deterministic",
    ];
    let mut rows = Vec::new();
    for (k, &pe) in pes.iter().enumerate() {
        let runs: Vec<[f64; 4]> = results[k * seeds as usize..(k + 1) * seeds as usize]
            .iter()
            .map(|r| r.as_ref().map(|o| *o).map_err(|e| anyhow!("Pe {pe}: {e}")))
            .collect::<Result<_>>()?;
        for (m, name) in names.iter().enumerate() {
            let scale = if m == 3 { base[3] } else { 1.0 };
            let values: Vec<f64> = runs.iter().map(|o| o[m] / scale).collect();
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            let spread = values.iter().fold(0.0f64, |s, v| s.max((v - mean).abs()));
            rows.push(Point {
                series: (*name).into(),
                x: pe,
                y: mean,
                extra: vec![("largest deviation from the mean".into(), spread)],
            });
        }
        for (m, name) in [
            (0, "deterministic verticality"),
            (1, "deterministic extension"),
        ] {
            rows.push(Point {
                series: name.into(),
                x: pe,
                y: base[m],
                extra: vec![("largest deviation from the mean".into(), 0.0)],
            });
        }
    }
    let chart = LineChart {
        title: format!(
            "Figure 1 (c) with thermal noise: outcome at t = {duration} ({seeds} seeds per Pe)"
        ),
        x_label: "Peclet number Pe = F a / kT".into(),
        y_label: "value (mean over seeds)".into(),
        log_x: true,
        ..Default::default()
    };
    write_chart(out, quick, "brownian_peclet", chart, &rows)?;
    Ok(format!(
        "Peclet sweep (Figure 1 (c), t = {duration}): deterministic verticality {:.3}, extension {:.3}, settling speed {:.3}",
        base[0], base[1], base[3]
    ))
}
