//! Accuracy against cost: work-precision of every method and solver, and the error of
//! each cheaper model level against the richest.

use std::path::Path;

use anyhow::{Result, anyhow};
use hydrorattle::mobility::Hydro;
use hydrorattle::{Method, SolverKind, StepError};

use super::{Outcome, Point, base_scene, rms, setup, simulate, write_chart};
use crate::render::LineChart;

/// A curve of the work-precision chart: name, run at a given dt, inertial physics?
type Curve = (
    String,
    Box<dyn Fn(f64) -> Result<Outcome, StepError> + Sync>,
    bool,
);

/// Work-precision: error at `t_end` against a converged reference, versus cost.
pub(super) fn work_precision(out: &Path, quick: bool) -> Result<String> {
    let scene = base_scene()?;
    let t_end = 2.0;
    let dts: &[f64] = if quick {
        &[0.02, 0.01]
    } else {
        &[0.04, 0.02, 0.01, 0.005, 0.0025]
    };
    let repeats = if quick { 1 } else { 3 };
    // Overdamped reference: second order at a small step, f64, tight tolerance.
    let mut r = setup::<f64>(&scene, Method::Overdamped2, 0.0005, 1.0);
    r.p.solver.tolerance = 1e-13;
    let reference = simulate(&scene, r, t_end, 1).map_err(|e| anyhow!("reference: {e}"))?;
    let mut r2 = r;
    r2.p.dt *= 2.0;
    let check = simulate(&scene, r2, t_end, 1).map_err(|e| anyhow!("reference: {e}"))?;
    let ref_err = rms(&reference.pos, &check.pos) / 3.0; // Richardson: error of the finer one.
    // Inertial reference (St = 0.1): the paper's scheme, well inside its stability limit.
    let st = 0.1;
    // Both inertial schemes are first order: Richardson-extrapolate the paper's scheme
    // from dt = 5e-4 and 2.5e-4 so the reference is second-order accurate.
    let mut ri = setup::<f64>(&scene, Method::Rattle, 0.0005, st);
    ri.p.solver.tolerance = 1e-13;
    let coarse = simulate(&scene, ri, t_end, 1).map_err(|e| anyhow!("inertial reference: {e}"))?;
    ri.p.dt *= 0.5;
    let mut inertial_ref =
        simulate(&scene, ri, t_end, 1).map_err(|e| anyhow!("inertial reference: {e}"))?;
    let inertial_ref_err = rms(&coarse.pos, &inertial_ref.pos);
    for (f, c) in inertial_ref.pos.iter_mut().zip(&coarse.pos) {
        for k in 0..3 {
            f[k] = 2.0 * f[k] - c[k];
        }
    }
    let mut jobs: Vec<Curve> = Vec::new();
    let od = |m: Method, kind: SolverKind| {
        let sc = scene.clone();
        move |dt: f64| {
            let mut s = setup::<f64>(&sc, m, dt, 1.0);
            s.p.solver.kind = kind;
            simulate(&sc, s, t_end, repeats)
        }
    };
    jobs.push((
        "overdamped newton f64".into(),
        Box::new(od(Method::Overdamped, SolverKind::Newton)),
        false,
    ));
    jobs.push((
        "overdamped sweep f64".into(),
        Box::new(od(Method::Overdamped, SolverKind::Sweep)),
        false,
    ));
    jobs.push((
        "overdamped2 newton f64".into(),
        Box::new(od(Method::Overdamped2, SolverKind::Newton)),
        false,
    ));
    {
        let sc = scene.clone();
        jobs.push((
            "overdamped newton f32".into(),
            Box::new(move |dt| {
                simulate(
                    &sc,
                    setup::<f32>(&sc, Method::Overdamped, dt, 1.0),
                    t_end,
                    repeats,
                )
            }),
            false,
        ));
    }
    for k in [1e2, 1e3] {
        let sc = scene.clone();
        jobs.push((
            format!("springs k={k:e}"),
            Box::new(move |dt| {
                let mut s = setup::<f64>(&sc, Method::Springs, dt, 1.0);
                s.p.spring_stiffness = k;
                simulate(&sc, s, t_end, repeats)
            }),
            false,
        ));
    }
    for (name, m) in [
        ("rattle (paper) St=0.1", Method::Rattle),
        ("rattle-stable St=0.1", Method::RattleStable),
    ] {
        let sc = scene.clone();
        jobs.push((
            name.into(),
            Box::new(move |dt| simulate(&sc, setup::<f64>(&sc, m, dt, st), t_end, repeats)),
            true,
        ));
    }
    let mut points = Vec::new();
    for (name, f, inertial) in &jobs {
        // Runs of one curve one after the other: timings are not disturbed by siblings.
        for &dt in dts {
            match f(dt) {
                Ok(o) => {
                    let reference = if *inertial {
                        &inertial_ref.pos
                    } else {
                        &reference.pos
                    };
                    points.push(Point {
                        series: name.clone(),
                        x: o.cost,
                        y: rms(&o.pos, reference),
                        extra: vec![
                            ("dt".into(), dt),
                            ("bond_error".into(), o.bond_error),
                            ("iterations".into(), o.iterations),
                        ],
                    });
                }
                Err(e) => log::info!("{name} dt={dt}: {e}"),
            }
        }
    }
    let chart = LineChart {
        title: format!("Work-precision, 1+24 bead helix (a), error at t = {t_end}"),
        x_label: "wall seconds per simulated time unit".into(),
        y_label: "RMS position error (tail radii)".into(),
        log_x: true,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, quick, "work_precision", chart, &points)?;
    Ok(format!(
        "work_precision: overdamped reference dt=5e-4 (Heun), estimated error {ref_err:.1e}; inertial reference (St=0.1): paper RATTLE Richardson-extrapolated from dt=5e-4 and 2.5e-4 (first-order error of the finer run {inertial_ref_err:.1e}, removed to leading order)"
    ))
}

/// Model levels: error of each cheaper model against the richest one, versus cost.
/// One series per model, one point per Stokes number.
pub(super) fn models(out: &Path, quick: bool) -> Result<String> {
    let scene = base_scene()?;
    let t_end = if quick { 1.0 } else { 5.0 };
    let dt = 0.005;
    let repeats = if quick { 1 } else { 2 };
    let sts: &[f64] = if quick { &[0.1] } else { &[0.01, 0.1, 1.0] };
    let mut points = Vec::new();
    let mut notes = Vec::new();
    for &st in sts {
        // Richest: RPY, rotation resolved, inertia at this Stokes number.
        let mut rich = setup::<f64>(&scene, Method::RattleStable, dt, st);
        rich.p.rotation = true;
        let r =
            simulate(&scene, rich, t_end, repeats).map_err(|e| anyhow!("richest model: {e}"))?;
        notes.push(format!(
            "St={st}: richest model costs {:.3} s per time unit",
            r.cost
        ));
        let mut fd = setup::<f64>(&scene, Method::Overdamped, dt, 1.0);
        fd.p.hydro = Hydro::FreeDraining;
        let mut os = setup::<f64>(&scene, Method::Overdamped, dt, 1.0);
        os.p.hydro = Hydro::Oseen;
        let candidates = [
            ("free-draining (overdamped)", fd),
            ("Oseen (overdamped)", os),
            (
                "RPY overdamped",
                setup::<f64>(&scene, Method::Overdamped, dt, 1.0),
            ),
            (
                "RPY inertial, no rotation",
                setup::<f64>(&scene, Method::RattleStable, dt, st),
            ),
        ];
        for (name, s) in candidates {
            match simulate(&scene, s, t_end, repeats) {
                Ok(o) => points.push(Point {
                    series: name.to_string(),
                    x: o.cost,
                    y: rms(&o.pos, &r.pos).max(1e-16),
                    extra: vec![
                        ("stokes_number".into(), st),
                        ("richest_cost".into(), r.cost),
                    ],
                }),
                Err(e) => notes.push(format!("{name} St={st}: {e}")),
            }
        }
    }
    mean_cost_per_model(&mut points);
    let chart = LineChart {
        title: format!(
            "Model error at t = {t_end} vs cost (reference: RPY + rotation + inertia; points: St = {sts:?})"
        ),
        x_label: "wall seconds per simulated time unit".into(),
        y_label: "RMS position error (tail radii)".into(),
        log_x: true,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, quick, "models", chart, &points)?;
    Ok(notes.join("\n"))
}

/// One cost per model (mean over its runs): timing noise would otherwise zig-zag the
/// lines; the points of a model then stack vertically, one per Stokes number. Each
/// point keeps its own run's cost as `measured_cost` (one column).
fn mean_cost_per_model(points: &mut [Point]) {
    let mut names: Vec<String> = Vec::new();
    for p in points.iter() {
        if !names.contains(&p.series) {
            names.push(p.series.clone());
        }
    }
    for name in names {
        let costs: Vec<f64> = points
            .iter()
            .filter(|p| p.series == name)
            .map(|p| p.x)
            .collect();
        let mean = costs.iter().sum::<f64>() / costs.len() as f64;
        for p in points.iter_mut().filter(|p| p.series == name) {
            p.extra.push(("measured_cost".into(), p.x));
            p.x = mean;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_point_keeps_one_measured_cost_and_the_model_mean() {
        let mut pts: Vec<Point> = [("rpy", 1.0), ("rpy", 3.0), ("fd", 5.0)]
            .iter()
            .map(|&(s, x)| Point {
                series: s.into(),
                x,
                y: 0.1,
                extra: Vec::new(),
            })
            .collect();
        mean_cost_per_model(&mut pts);
        for p in &pts {
            assert_eq!(p.extra.len(), 1, "{:?}", p.extra);
        }
        assert_eq!((pts[0].x, pts[1].x, pts[2].x), (2.0, 2.0, 5.0));
        assert_eq!(pts[1].extra[0].1, 3.0);
    }
}
