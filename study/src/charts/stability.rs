//! Where each method fails: the explicit drag's stability limit against the Stokes
//! number, springs against their stiffness, the sweep and Newton solvers as dt grows,
//! Oseen on a close-packed cube, and the f32 tolerance floor and drift.

use std::path::Path;

use anyhow::{Result, anyhow};
use hydrorattle::mobility::Hydro;
use hydrorattle::{Method, NoForce, SolverKind, StepError, step_slices};
use rayon::prelude::*;

use super::cube::{cube_cholesky_ok, cube_min_eigen};
use super::precision::{precision_drift, tolerance_ok};
use super::{
    Point, base_scene, build, max_stable, setup, stays_bounded, storage, write_chart,
    write_chart_clipped,
};
use crate::render::LineChart;
use hydrorattle_host::scene::Scene;

/// The guard's estimate `2 lambda_min(M^1/2 mu M^1/2)` at the start configuration.
fn guard_limit(scene: &Scene, st: f64) -> f64 {
    let mut s = setup::<f64>(scene, Method::Rattle, 1e6, st);
    s.p.stability_guard = true;
    s.p.gravity *= 1.0 / st;
    let Ok((mut beads, bonds)) = build::<f64>(scene, st) else {
        return f64::NAN;
    };
    let mut store = storage(&s.p, &beads, &bonds);
    let mut ws = store.workspace();
    match step_slices(beads.state(), &bonds, &s.p, &mut ws, &mut NoForce) {
        Err(StepError::Unstable { limit, .. }) => limit,
        _ => f64::NAN,
    }
}

/// Where each method fails.
pub(super) fn stability(out: &Path, quick: bool) -> Result<String> {
    let scene = base_scene()?;
    let mut notes = Vec::new();
    // (1) Explicit drag over (dt, St): empirical limit versus 2 m / zeta = 2 St.
    let sts: Vec<f64> = if quick {
        vec![0.1]
    } else {
        vec![0.01, 0.03, 0.1, 0.3, 1.0]
    };
    let steps = if quick { 50 } else { 400 };
    let limits: Vec<(f64, f64, f64, f64)> = sts
        .par_iter()
        .map(|&st| {
            let chain = max_stable(1e-4, 10.0, |dt| {
                stays_bounded::<f64>(&scene, setup(&scene, Method::Rattle, dt, st), steps)
            });
            let single = {
                let mut one = scene.clone();
                one.particles.truncate(2);
                one.particles.remove(0);
                one.bonds.clear();
                max_stable(1e-4, 10.0, |dt| {
                    stays_bounded::<f64>(&one, setup(&one, Method::Rattle, dt, st), steps)
                })
            };
            (st, chain, single, guard_limit(&scene, st))
        })
        .collect();
    let mut pts = Vec::new();
    for &(st, chain, single, guard) in &limits {
        let theory = 2.0 * st;
        pts.push(Point {
            series: "25-bead helix, guard estimate 2 lambda_min(M^1/2 mu M^1/2)".into(),
            x: st,
            y: guard,
            extra: vec![
                ("theory_2m_over_zeta".into(), theory),
                ("lone_tail".into(), single),
            ],
        });
        pts.push(Point {
            series: "25-bead helix, paper RATTLE".into(),
            x: st,
            y: chain,
            extra: vec![
                ("theory_2m_over_zeta".into(), theory),
                ("lone_tail".into(), single),
            ],
        });
        pts.push(Point {
            series: "lone tail, paper RATTLE".into(),
            x: st,
            y: single,
            extra: vec![
                ("theory_2m_over_zeta".into(), theory),
                ("lone_tail".into(), single),
            ],
        });
        pts.push(Point {
            series: "theory dt = 2 m / zeta (tail)".into(),
            x: st,
            y: theory,
            extra: vec![
                ("theory_2m_over_zeta".into(), theory),
                ("lone_tail".into(), single),
            ],
        });
        notes.push(format!(
            "St={st}: chain {chain:.4} (guard estimate {guard:.4}), lone tail {single:.4}, 2m/zeta {theory:.4}"
        ));
    }
    let chart = LineChart {
        title: "Explicit-drag RATTLE: largest stable dt vs Stokes number".into(),
        x_label: "Stokes number St = m U0 / (6 pi eta a^2)".into(),
        y_label: "largest stable dt (a / U0)".into(),
        log_x: true,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, quick, "stability", chart, &pts)?;
    // (2) Springs over (dt, stiffness).
    let ks: Vec<f64> = if quick {
        vec![1e2]
    } else {
        vec![1e1, 1e2, 1e3, 1e4]
    };
    let spring: Vec<Point> = ks
        .par_iter()
        .map(|&k| {
            let dt = max_stable(1e-6, 1.0, |dt| {
                let mut s = setup::<f64>(&scene, Method::Springs, dt, 1.0);
                s.p.spring_stiffness = k;
                stays_bounded(&scene, s, steps)
            });
            Point {
                series: "springs, explicit overdamped".into(),
                x: k,
                y: dt,
                extra: vec![("k_dt".into(), k * dt)],
            }
        })
        .collect();
    let chart = LineChart {
        title: "Hookean springs: largest stable dt vs stiffness".into(),
        x_label: "spring stiffness k".into(),
        y_label: "largest stable dt".into(),
        log_x: true,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, quick, "stability_springs", chart, &spring)?;
    // (3) Sweep versus Newton as dt grows (one step from the helix).
    let dts: Vec<f64> = if quick {
        vec![0.01, 0.1]
    } else {
        vec![0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0]
    };
    let mut solver_pts = Vec::new();
    for kind in [SolverKind::Sweep, SolverKind::Newton] {
        for &dt in &dts {
            let mut s = setup::<f64>(&scene, Method::Overdamped, dt, 1.0);
            s.p.solver.kind = kind;
            s.p.solver.max_iterations = 2000;
            let name = format!("{kind:?}");
            let (mut beads, bonds) = build::<f64>(&scene, 1.0).map_err(|e| anyhow!("{e}"))?;
            let before = beads.pos.clone();
            let mut store = storage(&s.p, &beads, &bonds);
            let mut ws = store.workspace();
            let res = step_slices(beads.state(), &bonds, &s.p, &mut ws, &mut NoForce);
            // Largest bond rotation in the step, degrees.
            let rot = bonds
                .iter()
                .map(|b| {
                    let (u, v) = (before[b.i] - before[b.j], beads.pos[b.i] - beads.pos[b.j]);
                    (u.dot(v) / (u.length() * v.length()))
                        .clamp(-1.0, 1.0)
                        .acos()
                        .to_degrees()
                })
                .fold(0.0, f64::max);
            let (its, failed) = match res {
                Ok(r) => (f64::from(r.iterations), 0.0),
                Err(e) => {
                    notes.push(format!("{name} dt={dt}: {e}"));
                    (2000.0, 1.0)
                }
            };
            // Failures get their own series, drawn at the cap, so that they show.
            let series = if failed > 0.0 {
                format!("{name}: failed (drawn at the cap)")
            } else {
                name
            };
            solver_pts.push(Point {
                series,
                x: dt,
                y: its.max(0.5),
                extra: vec![("failed".into(), failed), ("bond_rotation_deg".into(), rot)],
            });
        }
    }
    let chart = LineChart {
        title: "Constraint solve: iterations per step vs dt (failures plotted at the cap, 2000)"
            .into(),
        x_label: "dt".into(),
        y_label: "iterations".into(),
        log_x: true,
        log_y: true,
        series: Vec::new(),
    };
    // The failures sit at the cap (2000), above the usual clip for diverged errors.
    write_chart_clipped(out, quick, "stability_solvers", chart, &solver_pts, None)?;
    // (4) Oseen losing positive definiteness as the gap closes (3x3x3 cube of spheres).
    let mut oseen_pts = Vec::new();
    let mut first_fail = None;
    for k in 0..40 {
        let gap = 0.02 + 0.05 * k as f64;
        for (name, level) in [("Oseen", Hydro::Oseen), ("RPY", Hydro::Rpy)] {
            let lmin = cube_min_eigen(level, gap);
            oseen_pts.push(Point {
                series: name.into(),
                x: gap,
                y: lmin,
                extra: vec![(
                    "cholesky_ok".into(),
                    f64::from(u8::from(cube_cholesky_ok(level, gap))),
                )],
            });
            if level == Hydro::Oseen && !cube_cholesky_ok(level, gap) {
                first_fail = Some(first_fail.map_or(gap, |g: f64| g.max(gap)));
            }
        }
    }
    notes.push(format!(
        "Oseen Cholesky fails on the 27-sphere cube up to gap {:?}",
        first_fail
    ));
    let chart = LineChart {
        title: "27 spheres on a cube: smallest mobility eigenvalue vs gap (negative: not PD)"
            .into(),
        x_label: "gap between neighbours (radii)".into(),
        y_label: "smallest eigenvalue of mu_tt x 6 pi eta a".into(),
        log_x: false,
        log_y: false,
        series: Vec::new(),
    };
    write_chart(out, quick, "stability_oseen", chart, &oseen_pts)?;
    // (5) f32 against f64: the tolerance floor and the drift of a long run.
    let mut floor_pts = Vec::new();
    for e in 2..=13 {
        let tol = 10f64.powi(-e);
        for (name, ok) in [
            ("f32", tolerance_ok::<f32>(&scene, tol)),
            ("f64", tolerance_ok::<f64>(&scene, tol)),
        ] {
            floor_pts.push(Point {
                series: name.into(),
                x: tol,
                y: f64::from(u8::from(ok)),
                extra: vec![],
            });
        }
    }
    let chart = LineChart {
        title: "Can the constraint solve reach the tolerance? (1 = yes)".into(),
        x_label: "tolerance".into(),
        y_label: "reached".into(),
        log_x: true,
        log_y: false,
        series: Vec::new(),
    };
    write_chart(out, quick, "stability_precision", chart, &floor_pts)?;
    let drift = precision_drift(&scene, if quick { 2.0 } else { 100.0 })?;
    let chart = LineChart {
        title: "f32 vs f64 over a long run: bond error and distance between trajectories".into(),
        x_label: "time".into(),
        y_label: "value".into(),
        log_x: false,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, quick, "stability_drift", chart, &drift)?;
    Ok(notes.join("\n"))
}
