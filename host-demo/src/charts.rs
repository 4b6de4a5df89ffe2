//! Speed against accuracy: work-precision, model levels, and where each method fails.
//! Every chart is a PNG with a CSV of the same name beside it.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, anyhow};
use hydrorattle::glam;
use hydrorattle::linalg;
use hydrorattle::mobility::{Hydro, assemble_tt};
use hydrorattle::{
    Bond, BondSet, Buffers, ExternalForce, Layout, Method, Params, Particle, ParticleSet, Real,
    SoftContact, SolverKind, StepError, step,
};
use rayon::prelude::*;

use crate::output::{AtomicFile, CsvWriter};
use crate::render::{LineChart, Series, line_chart};
use crate::scene::Scene;
use crate::sim::params;

/// Capacity for the 25-bead charts scene.
const N: usize = 32;

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

fn build<T: Real>(scene: &Scene, st: f64) -> Result<(ParticleSet<T, N>, BondSet<T, N>)> {
    let mut ps = ParticleSet::new();
    for q in &scene.particles {
        let p = Particle::new(
            T::v3_from(q.position),
            T::from_f64(q.radius),
            T::from_f64(q.density * st),
        );
        ps.push(p).map_err(|(_, e)| anyhow!("{e}"))?;
    }
    let mut bonds = BondSet::new();
    for b in &scene.bonds {
        let bond = Bond {
            i: b.i,
            j: b.j,
            length: T::from_f64(b.length),
        };
        bonds
            .push(bond, ps.len())
            .map_err(|(_, e)| anyhow!("{e}"))?;
    }
    Ok((ps, bonds))
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
    let contact = scene.contact.map(|k| SoftContact {
        stiffness: T::from_f64(k),
    });
    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..repeats.max(1) {
        let (mut ps, bonds) =
            build::<T>(scene, s.st).map_err(|_| StepError::BadParameter("scene"))?;
        let mut ws_store = Buffers::<T>::new(Layout::all(N, N));
        let mut ws = ws_store.workspace();
        let mut ext = |pos: &[T::V3], r: &[T], f: &mut [T::V3]| {
            if let Some(mut c) = contact {
                c.add(pos, r, f);
            }
        };
        let (mut its, mut worst) = (0u64, 0.0f64);
        let start = Instant::now();
        for _ in 0..steps {
            let rep = step(&mut ps, &bonds, &p, &mut ws, &mut ext)?;
            its += u64::from(rep.iterations);
            worst = worst.max(rep.residual.to_f64());
        }
        best = best.min(start.elapsed().as_secs_f64());
        let n = ps.len();
        result = Some(Outcome {
            pos: ps.pos[..n].iter().map(|&v| T::v3_to_f64(v)).collect(),
            cost: 0.0,
            bond_error: worst,
            iterations: its as f64 / steps as f64,
        });
    }
    let mut o = result.ok_or(StepError::BadParameter("repeats"))?;
    o.cost = best / t_end;
    Ok(o)
}

fn rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f64>())
        .sum();
    (s / a.len() as f64).sqrt()
}

fn base_scene() -> Result<Scene> {
    Ok(Scene::figure1()?.remove(0).1)
}

fn setup<T: Real>(scene: &Scene, method: Method, dt: f64, st: f64) -> Setup<T> {
    let mut p = params::<T>(scene);
    p.method = method;
    p.dt = T::from_f64(dt);
    Setup { p, st }
}

/// A curve of the work-precision chart: name, run at a given dt, inertial physics?
type Curve = (
    String,
    Box<dyn Fn(f64) -> Result<Outcome, StepError> + Sync>,
    bool,
);

/// One curve point of a chart and its CSV row.
#[derive(Clone)]
struct Point {
    series: String,
    x: f64,
    y: f64,
    extra: Vec<(String, f64)>,
}

fn write_chart(out: &Path, file: &str, mut chart: LineChart, points: &[Point]) -> Result<()> {
    let mut names: Vec<String> = Vec::new();
    for p in points {
        if !names.contains(&p.series) {
            names.push(p.series.clone());
        }
    }
    chart.series = names
        .iter()
        .map(|n| Series {
            name: n.clone(),
            points: points
                .iter()
                // Diverged runs (error above 1e3) stay in the CSV but would flatten the plot.
                .filter(|p| &p.series == n && p.y.abs() < 1e3)
                .map(|p| (p.x, p.y))
                .collect(),
        })
        .collect();
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

/// Work-precision: error at `t_end` against a converged reference, versus cost.
fn work_precision(out: &Path, quick: bool) -> Result<String> {
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
    write_chart(out, "work_precision", chart, &points)?;
    Ok(format!(
        "work_precision: overdamped reference dt=5e-4 (Heun), estimated error {ref_err:.1e}; inertial reference (St=0.1): paper RATTLE Richardson-extrapolated from dt=5e-4 and 2.5e-4 (first-order error of the finer run {inertial_ref_err:.1e}, removed to leading order)"
    ))
}

/// Model levels: error of each cheaper model against the richest one, versus cost.
/// One series per model, one point per Stokes number.
fn models(out: &Path, quick: bool) -> Result<String> {
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
    // One cost per model (mean over its runs): timing noise would otherwise zig-zag the
    // lines; the points of a model then stack vertically, one per Stokes number.
    let names: Vec<String> = points.iter().map(|p| p.series.clone()).collect();
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
    write_chart(out, "models", chart, &points)?;
    Ok(notes.join("\n"))
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
    let Ok((mut ps, bonds)) = build::<T>(scene, s.st) else {
        return false;
    };
    let n = ps.len();
    let mut p = s.p;
    p.stability_guard = false;
    p.gravity *= T::from_f64(1.0 / s.st);
    let mut ws_store = Buffers::<T>::new(Layout::all(N, N));
    let mut ws = ws_store.workspace();
    let mut ext = hydrorattle::NoForce;
    let mut prev_v: Vec<T::V3> = ps.vel[..n].to_vec();
    let mut prev_dv: Vec<T::V3> = vec![T::V3_ZERO; n];
    let mut flips = 0;
    for _ in 0..steps {
        match step(&mut ps, &bonds, &p, &mut ws, &mut ext) {
            // Beads meeting (no excluded volume here) ends the test, not an instability.
            Err(StepError::Overlap { .. }) => return true,
            Err(e) => {
                log::debug!("dt {}: {e}", p.dt);
                return false;
            }
            Ok(_) => {}
        }
        if ps.vel[..n].iter().any(|&v| T::norm(v).to_f64() > 100.0) {
            return false;
        }
        let (mut dot, mut a2, mut b2) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let dv = ps.vel[i] - prev_v[i];
            dot += T::dot(dv, prev_dv[i]).to_f64();
            a2 += T::norm2(dv).to_f64();
            b2 += T::norm2(prev_dv[i]).to_f64();
            prev_dv[i] = dv;
            prev_v[i] = ps.vel[i];
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

/// The guard's estimate `2 lambda_min(M^1/2 mu M^1/2)` at the start configuration.
fn guard_limit(scene: &Scene, st: f64) -> f64 {
    let mut s = setup::<f64>(scene, Method::Rattle, 1e6, st);
    s.p.stability_guard = true;
    s.p.gravity *= 1.0 / st;
    let Ok((mut ps, bonds)) = build::<f64>(scene, st) else {
        return f64::NAN;
    };
    let mut ws_store = Buffers::<f64>::new(Layout::all(N, N));
    let mut ws = ws_store.workspace();
    match step(&mut ps, &bonds, &s.p, &mut ws, &mut hydrorattle::NoForce) {
        Err(StepError::Unstable { limit, .. }) => limit,
        _ => f64::NAN,
    }
}

/// Where each method fails.
fn stability(out: &Path, quick: bool) -> Result<String> {
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
    write_chart(out, "stability", chart, &pts)?;
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
    write_chart(out, "stability_springs", chart, &spring)?;
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
            let (mut ps, bonds) = build::<f64>(&scene, 1.0)?;
            let before = ps.pos;
            let mut ws_store = Buffers::<f64>::new(Layout::all(N, N));
            let mut ws = ws_store.workspace();
            let res = step(&mut ps, &bonds, &s.p, &mut ws, &mut hydrorattle::NoForce);
            // Largest bond rotation in the step, degrees.
            let rot = bonds
                .as_slice()
                .iter()
                .map(|b| {
                    let (u, v) = (before[b.i] - before[b.j], ps.pos[b.i] - ps.pos[b.j]);
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
            solver_pts.push(Point {
                series: name,
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
    write_chart(out, "stability_solvers", chart, &solver_pts)?;
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
    write_chart(out, "stability_oseen", chart, &oseen_pts)?;
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
    write_chart(out, "stability_precision", chart, &floor_pts)?;
    let drift = precision_drift(&scene, if quick { 2.0 } else { 100.0 })?;
    let chart = LineChart {
        title: "f32 vs f64 over a long run: bond error and distance between trajectories".into(),
        x_label: "time".into(),
        y_label: "value".into(),
        log_x: false,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, "stability_drift", chart, &drift)?;
    Ok(notes.join("\n"))
}

/// `x` spacing `2 + gap` cube of 27 unit spheres.
fn cube(gap: f64) -> Vec<glam::DVec3> {
    let s = 2.0 + gap;
    let mut v = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                v.push(glam::DVec3::new(i as f64 * s, j as f64 * s, k as f64 * s));
            }
        }
    }
    v
}

fn cube_mobility(level: Hydro, gap: f64) -> (Vec<glam::DMat3>, usize) {
    let pos = cube(gap);
    let n = pos.len();
    let rad = vec![1.0; n];
    let mut mu = vec![glam::DMat3::ZERO; n * n];
    // Nested spheres cannot occur on the cube: spacing > 2.
    let _ = assemble_tt::<f64>(level, 1.0, &pos, &rad, &mut mu);
    (mu, n)
}

fn cube_cholesky_ok(level: Hydro, gap: f64) -> bool {
    let (mut mu, n) = cube_mobility(level, gap);
    linalg::cholesky::<f64>(&mut mu, n).is_ok()
}

/// Smallest eigenvalue (scaled by 6 pi eta a) by power iteration on `c I - mu`.
fn cube_min_eigen(level: Hydro, gap: f64) -> f64 {
    let (mu, n) = cube_mobility(level, gap);
    let c = 2.0 / (6.0 * std::f64::consts::PI) * n as f64;
    let mut x: Vec<glam::DVec3> = (0..n)
        .map(|i| glam::DVec3::new(1.0, 0.3 + i as f64 * 0.01, -0.7))
        .collect();
    let mut y = vec![glam::DVec3::ZERO; n];
    let mut lambda = 0.0;
    for _ in 0..3000 {
        linalg::sym_matvec::<f64>(&mu, n, &x, &mut y);
        let mut norm = 0.0;
        for i in 0..n {
            y[i] = x[i] * c - y[i];
            norm += y[i].length_squared();
        }
        let norm = norm.sqrt();
        lambda = x.iter().zip(&y).map(|(a, b)| a.dot(*b)).sum::<f64>()
            / x.iter().map(|a| a.length_squared()).sum::<f64>();
        for i in 0..n {
            x[i] = y[i] / norm;
        }
    }
    (c - lambda) * 6.0 * std::f64::consts::PI
}

fn tolerance_ok<T: Real>(scene: &Scene, tol: f64) -> bool {
    let mut s = setup::<T>(scene, Method::Overdamped, 0.01, 1.0);
    s.p.solver.tolerance = T::from_f64(tol);
    s.p.solver.max_iterations = 50;
    simulate(scene, s, 0.2, 1).is_ok()
}

fn precision_drift(scene: &Scene, t_end: f64) -> Result<Vec<Point>> {
    let mut p64 = setup::<f64>(scene, Method::Overdamped, 0.005, 1.0);
    p64.p.solver.tolerance = 1e-12;
    let mut p32 = setup::<f32>(scene, Method::Overdamped, 0.005, 1.0);
    // 1e-5 is at f32's floor: it stalls at 1.02e-5 near t = 44 on this scene.
    p32.p.solver.tolerance = 1e-4;
    let (mut a, bonds_a) = build::<f64>(scene, 1.0)?;
    let (mut b, bonds_b) = build::<f32>(scene, 1.0)?;
    let mut wa_store = Buffers::<f64>::new(Layout::all(N, N));
    let mut wa = wa_store.workspace();
    let mut wb_store = Buffers::<f32>::new(Layout::all(N, N));
    let mut wb = wb_store.workspace();
    let ka = scene.contact.map(|k| SoftContact { stiffness: k });
    let kb = scene.contact.map(|k| SoftContact {
        stiffness: k as f32,
    });
    let steps = (t_end / 0.005) as usize;
    let every = (steps / 100).max(1);
    let mut pts = Vec::new();
    for s in 1..=steps {
        let ra = step(
            &mut a,
            &bonds_a,
            &p64.p,
            &mut wa,
            &mut |x: &[glam::DVec3], r: &[f64], f: &mut [glam::DVec3]| {
                if let Some(mut c) = ka {
                    c.add(x, r, f)
                }
            },
        );
        let rb = step(
            &mut b,
            &bonds_b,
            &p32.p,
            &mut wb,
            &mut |x: &[glam::Vec3], r: &[f32], f: &mut [glam::Vec3]| {
                if let Some(mut c) = kb {
                    c.add(x, r, f)
                }
            },
        );
        if let Err(e) = ra.and(rb.map(|_| ())).map(|_| ()) {
            log::warn!("f32/f64 drift run stopped at t = {}: {e}", a.time);
            break;
        }
        if s % every == 0 {
            let n = a.len();
            let pa: Vec<[f64; 3]> = a.pos[..n].iter().map(|v| v.to_array()).collect();
            let pb: Vec<[f64; 3]> = b.pos[..n].iter().map(|v| v.as_dvec3().to_array()).collect();
            let t = a.time;
            pts.push(Point {
                series: "f32 bond error".into(),
                x: t,
                y: bonds_b.max_residual(&b.pos[..n]).1 as f64,
                extra: vec![],
            });
            pts.push(Point {
                series: "f64 bond error".into(),
                x: t,
                y: bonds_a.max_residual(&a.pos[..n]).1.max(1e-17),
                extra: vec![],
            });
            pts.push(Point {
                series: "RMS distance f32-f64".into(),
                x: t,
                y: rms(&pa, &pb).max(1e-17),
                extra: vec![],
            });
        }
    }
    Ok(pts)
}

/// The paper's claim, quantified: at equal bond-length error (1e-6), how much more
/// springs cost than constraints on scene (a). Springs' bond error is `~ tension / k`,
/// and explicit stability needs `dt ~ 1 / (k mu)`: both scale with `k`.
fn springs_vs_constraints(out: &Path, quick: bool) -> Result<String> {
    let scene = base_scene()?;
    let target = 1e-6;
    let horizon = 0.02;
    let mut rows = Vec::new();
    let ks: Vec<f64> = if quick {
        vec![1e4]
    } else {
        vec![1e4, 1e5, 1e6, 1e7, 1e8]
    };
    for &k in &ks {
        let stable = max_stable(1e-9, 0.1, |dt| {
            let mut s = setup::<f64>(&scene, Method::Springs, dt, 1.0);
            s.p.spring_stiffness = k;
            stays_bounded(&scene, s, 200)
        });
        let dt = 0.5 * stable; // a margin below the edge
        let mut s = setup::<f64>(&scene, Method::Springs, dt, 1.0);
        s.p.spring_stiffness = k;
        if let Ok(o) = simulate(&scene, s, horizon, 1) {
            rows.push(Point {
                series: "springs".into(),
                x: o.bond_error,
                y: o.cost,
                extra: vec![("stiffness".into(), k), ("dt".into(), dt)],
            });
        }
    }
    let mut c = setup::<f64>(&scene, Method::Overdamped, 0.005, 1.0);
    c.p.solver.tolerance = target;
    let cons = simulate(&scene, c, 1.0, 3).map_err(|e| anyhow!("constraints: {e}"))?;
    rows.push(Point {
        series: "constraints (overdamped, Newton, tol 1e-6, dt 0.005)".into(),
        x: cons.bond_error.max(1e-17),
        y: cons.cost,
        extra: vec![("stiffness".into(), 0.0), ("dt".into(), 0.005)],
    });
    // Springs' cost at bond error 1e-6, by log-log interpolation (cost ~ error^-1).
    let sp: Vec<&Point> = rows.iter().filter(|p| p.series == "springs").collect();
    let at_target = sp.windows(2).find_map(|w| {
        let (a, b) = (w[0], w[1]);
        ((a.x - target) * (b.x - target) <= 0.0).then(|| {
            let f = (target.ln() - a.x.ln()) / (b.x.ln() - a.x.ln());
            (a.y.ln() + f * (b.y.ln() - a.y.ln())).exp()
        })
    });
    let chart = LineChart {
        title: "Springs vs constraints on scene (a): cost vs bond-length error".into(),
        x_label: "largest relative bond-length error".into(),
        y_label: "wall seconds per simulated time unit".into(),
        log_x: true,
        log_y: true,
        series: Vec::new(),
    };
    write_chart(out, "springs_vs_constraints", chart, &rows)?;
    Ok(match at_target {
        Some(cost) => format!(
            "springs at bond error 1e-6 cost {cost:.3e} s per time unit; constraints {:.3e}: ratio {:.0}",
            cons.cost,
            cost / cons.cost
        ),
        None => format!(
            "springs: bond error 1e-6 not bracketed by k = {ks:?}; constraints cost {:.3e} s per time unit",
            cons.cost
        ),
    })
}

/// Writes all charts into `out`; returns notes for the terminal.
pub fn charts(out: &Path, quick: bool) -> Result<Vec<String>> {
    std::fs::create_dir_all(out)?;
    let t = Instant::now();
    let mut notes = vec![work_precision(out, quick)?];
    log::info!("work-precision done in {:.1} s", t.elapsed().as_secs_f64());
    notes.push(models(out, quick)?);
    log::info!("models done in {:.1} s", t.elapsed().as_secs_f64());
    notes.push(stability(out, quick)?);
    notes.push(springs_vs_constraints(out, quick)?);
    Ok(notes)
}
