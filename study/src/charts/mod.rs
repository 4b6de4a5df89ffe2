//! Speed against accuracy: work-precision, model levels, and where each method fails.
//! Every chart is a PNG with a CSV of the same name beside it.
//!
//! * `accuracy`: work-precision and model levels;
//! * `stability`: where each method fails (explicit drag, springs, solvers), with
//!   `cube` (Oseen's lost positive definiteness) and `precision` (f32 against f64);
//! * `springs`: the paper's claim, springs against constraints at equal bond error;
//! * `brownian`, `peclet`: thermal noise checked against exact results, and what it
//!   does to Figure 1 (c).

mod accuracy;
mod brownian;
mod cube;
mod peclet;
mod precision;
mod springs;
mod stability;

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use hydrorattle::{
    Bond, ExternalForce, Layout, Method, Params, Real, SoftContact, StepError, step_slices,
};
use hydrorattle_heap::Buffers;

use crate::render::{LineChart, Series, line_chart};
use hydrorattle_host::output::{AtomicFile, CsvWriter};
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::{Beads, beads, bonds, params};

/// How a chart run is set up: the kernel parameters and the density scale (Stokes number).
#[derive(Clone, Copy)]
struct Setup<T: Real> {
    p: Params<T>,
    /// Particle density = 4.5 * st and gravity / st: same weights, Stokes number st.
    st: f64,
}

/// Outcome of a timed run to `t_end`.
struct Outcome {
    pos: Vec<[f64; 3]>,
    /// Wall seconds per simulated time unit (best of `repeats`).
    cost: f64,
    bond_error: f64,
    iterations: f64,
}

/// The scene's beads (densities scaled by `st`) and bonds.
fn build<T: Real>(scene: &Scene, st: f64) -> Result<(Beads<T>, Vec<Bond<T>>), StepError> {
    let beads = beads(&scene.particles, st)?;
    let bonds = bonds(&scene.bonds, beads.len())?;
    Ok((beads, bonds))
}

/// Storage for steps of `p` on `beads` and `bonds`: what that method and solver need.
fn storage<T: Real>(p: &Params<T>, beads: &Beads<T>, bonds: &[Bond<T>]) -> Buffers<T> {
    Buffers::new(Layout::for_params(p, beads.len(), bonds.len()))
}

fn simulate<T: Real>(
    scene: &Scene,
    s: Setup<T>,
    t_end: f64,
    repeats: usize,
) -> Result<Outcome, StepError> {
    let steps = (t_end / s.p.dt.to_f64()).round().max(1.0) as usize;
    let mut p = s.p;
    p.gravity *= T::from_f64(1.0 / s.st);
    let contact = scene.contact.and_then(|c| c.soft()).map(|k| SoftContact {
        stiffness: T::from_f64(k),
    });
    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..repeats.max(1) {
        let (mut beads, bonds) = build::<T>(scene, s.st)?;
        let mut store = storage(&p, &beads, &bonds);
        let mut ws = store.workspace();
        let mut ext = |pos: &[T::V3], r: &[T], f: &mut [T::V3]| {
            if let Some(mut c) = contact {
                c.add(pos, r, f);
            }
        };
        let (mut its, mut worst) = (0u64, 0.0f64);
        let start = Instant::now();
        for _ in 0..steps {
            let rep = step_slices(beads.state(), &bonds, &p, &mut ws, &mut ext)?;
            its += u64::from(rep.iterations);
            worst = worst.max(rep.residual.to_f64());
        }
        best = best.min(start.elapsed().as_secs_f64());
        result = Some(Outcome {
            pos: beads.pos.iter().map(|&v| T::v3_to_f64(v)).collect(),
            cost: 0.0,
            bond_error: worst,
            iterations: its as f64 / steps as f64,
        });
    }
    let mut o = result.ok_or(StepError::BadParameter("repeats"))?;
    o.cost = best / t_end;
    Ok(o)
}

/// RMS distance between matching centres of two configurations.
pub(crate) fn rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f64>())
        .sum();
    (s / a.len() as f64).sqrt()
}

/// Figure 1 (a) with the soft contact (stiffness 1000) the charts compare every method
/// under: hard contacts are for the overdamped methods only, and each chart sets its
/// own method and step.
fn base_scene() -> Result<Scene> {
    let mut s = Scene::figure1()?.remove(0).1;
    s.with_soft_contact();
    s.integrator.method = hydrorattle_host::scene::Method::Overdamped;
    Ok(s)
}

fn setup<T: Real>(scene: &Scene, method: Method, dt: f64, st: f64) -> Setup<T> {
    let mut p = params::<T>(scene);
    p.method = method;
    p.dt = T::from_f64(dt);
    Setup { p, st }
}

/// One curve point of a chart and its CSV row.
#[derive(Clone)]
struct Point {
    series: String,
    x: f64,
    y: f64,
    extra: Vec<(String, f64)>,
}

/// Writes `FILE.png` and `FILE.csv`; a `quick` (smoke) run says so in the title.
/// Points of `|y| >= 1e3` (diverged runs) stay in the CSV but are left off the plot.
fn write_chart(
    out: &Path,
    quick: bool,
    file: &str,
    chart: LineChart,
    points: &[Point],
) -> Result<()> {
    write_chart_clipped(out, quick, file, chart, points, Some(1e3))
}

/// One plotted series per series name, in order of first appearance, with the points
/// of `|y| < clip` (every point for `None`).
fn series_of(points: &[Point], clip: Option<f64>) -> Vec<Series> {
    let mut names: Vec<String> = Vec::new();
    for p in points {
        if !names.contains(&p.series) {
            names.push(p.series.clone());
        }
    }
    names
        .iter()
        .map(|n| Series {
            name: n.clone(),
            points: points
                .iter()
                .filter(|p| &p.series == n && clip.is_none_or(|c| p.y.abs() < c))
                .map(|p| (p.x, p.y))
                .collect(),
        })
        .collect()
}

/// [`write_chart`] with the plot clipped at `|y| < clip` (`None`: every point drawn).
fn write_chart_clipped(
    out: &Path,
    quick: bool,
    file: &str,
    mut chart: LineChart,
    points: &[Point],
    clip: Option<f64>,
) -> Result<()> {
    if quick {
        chart
            .title
            .push_str(" [QUICK smoke run: fewer, shorter runs]");
    }
    chart.series = series_of(points, clip);
    line_chart(&out.join(format!("{file}.png")), &chart, (1100, 750))?;
    let extra: Vec<String> = points
        .first()
        .map(|p| p.extra.iter().map(|e| e.0.clone()).collect())
        .unwrap_or_default();
    let mut cols = vec![
        "series".to_string(),
        chart.x_label.clone(),
        chart.y_label.clone(),
    ];
    cols.extend(extra);
    let mut csv = CsvWriter::new(AtomicFile::create(&out.join(format!("{file}.csv")))?, &cols)?;
    for p in points {
        let mut rec = vec![p.series.clone(), format!("{:e}", p.x), format!("{:e}", p.y)];
        rec.extend(p.extra.iter().map(|e| format!("{:e}", e.1)));
        csv.write_record(&rec)?;
    }
    csv.into_inner().commit()?;
    Ok(())
}

/// Largest dt (bisection over a geometric bracket) for which `ok(dt)` holds.
fn max_stable(lo: f64, hi: f64, ok: impl Fn(f64) -> bool) -> f64 {
    let (mut lo, mut hi) = (lo, hi);
    for _ in 0..12 {
        let mid = (lo * hi).sqrt();
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Runs `steps` steps with the stability guard off. Unstable when a step fails, a
/// speed exceeds 100 settling speeds, or the velocity increments keep flipping sign
/// (the explicit drag's period-2 "shiver": bounded, silent, and wrong).
fn stays_bounded<T: Real>(scene: &Scene, s: Setup<T>, steps: usize) -> bool {
    let Ok((mut beads, bonds)) = build::<T>(scene, s.st) else {
        return false;
    };
    let n = beads.len();
    let mut p = s.p;
    p.stability_guard = false;
    p.gravity *= T::from_f64(1.0 / s.st);
    let mut store = storage(&p, &beads, &bonds);
    let mut ws = store.workspace();
    let mut ext = hydrorattle::NoForce;
    let mut prev_v: Vec<T::V3> = beads.vel.clone();
    let mut prev_dv: Vec<T::V3> = vec![T::V3_ZERO; n];
    let mut flips = 0;
    for _ in 0..steps {
        match step_slices(beads.state(), &bonds, &p, &mut ws, &mut ext) {
            // Beads meeting (no excluded volume here) ends the test, not an instability.
            Err(StepError::Overlap { .. }) => return true,
            Err(e) => {
                log::debug!("dt {}: {e}", p.dt);
                return false;
            }
            Ok(_) => {}
        }
        if beads.vel.iter().any(|&v| T::norm(v).to_f64() > 100.0) {
            return false;
        }
        let (mut dot, mut a2, mut b2) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let dv = beads.vel[i] - prev_v[i];
            dot += T::dot(dv, prev_dv[i]).to_f64();
            a2 += T::norm2(dv).to_f64();
            b2 += T::norm2(prev_dv[i]).to_f64();
            prev_dv[i] = dv;
            prev_v[i] = beads.vel[i];
        }
        // Alternating and not decaying (a damped oscillation, dt in (tau, 2 tau), is fine).
        let alternating = dot < -0.5 * (a2 * b2).sqrt() && a2.sqrt() > 1e-3 && a2 >= 0.98 * b2;
        flips = if alternating { flips + 1 } else { 0 };
        if flips >= 20 {
            log::debug!("dt {}: persistent period-2 velocity oscillation", p.dt);
            return false;
        }
    }
    true
}

/// Writes all charts into `out`; returns notes for the terminal.
pub fn charts(out: &Path, quick: bool) -> Result<Vec<String>> {
    std::fs::create_dir_all(out)?;
    let t = Instant::now();
    let mut notes = vec![accuracy::work_precision(out, quick)?];
    log::info!("work-precision done in {:.1} s", t.elapsed().as_secs_f64());
    notes.push(accuracy::models(out, quick)?);
    log::info!("models done in {:.1} s", t.elapsed().as_secs_f64());
    notes.push(stability::stability(out, quick)?);
    notes.push(springs::springs_vs_constraints(out, quick)?);
    notes.push(brownian::trimer(out, quick)?);
    notes.push(brownian::dimer(out, quick)?);
    notes.push(peclet::peclet(out, quick)?);
    log::info!("Brownian charts done in {:.1} s", t.elapsed().as_secs_f64());
    Ok(notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(series: &str, y: f64) -> Point {
        Point {
            series: series.into(),
            x: 1.0,
            y,
            extra: Vec::new(),
        }
    }

    #[test]
    fn failures_at_the_cap_are_drawn_when_not_clipped() {
        let pts = [point("Sweep", 12.0), point("Sweep: failed", 2000.0)];
        let drawn = series_of(&pts, None);
        assert_eq!(drawn.len(), 2);
        assert_eq!(drawn[1].points, vec![(1.0, 2000.0)]);
        assert!(series_of(&pts, Some(1e3))[1].points.is_empty());
    }
}
