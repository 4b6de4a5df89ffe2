//! f32 against f64: can the constraint solve reach a tolerance, and how far the two
//! precisions drift apart over a long run.

use anyhow::{Result, anyhow};
use hydrorattle::bonds::max_residual;
use hydrorattle::{ExternalForce, Method, Real, SoftContact, glam, step_slices};

use super::{Point, build, rms, setup, simulate, storage};
use hydrorattle_host::scene::Scene;

pub(super) fn tolerance_ok<T: Real>(scene: &Scene, tol: f64) -> bool {
    let mut s = setup::<T>(scene, Method::Overdamped, 0.01, 1.0);
    s.p.solver.tolerance = T::from_f64(tol);
    s.p.solver.max_iterations = 50;
    simulate(scene, s, 0.2, 1).is_ok()
}

pub(super) fn precision_drift(scene: &Scene, t_end: f64) -> Result<Vec<Point>> {
    let mut p64 = setup::<f64>(scene, Method::Overdamped, 0.005, 1.0);
    p64.p.solver.tolerance = 1e-12;
    let mut p32 = setup::<f32>(scene, Method::Overdamped, 0.005, 1.0);
    // 1e-5 is at f32's floor: it stalls at 1.02e-5 near t = 44 on this scene.
    p32.p.solver.tolerance = 1e-4;
    let (mut a, bonds_a) = build::<f64>(scene, 1.0).map_err(|e| anyhow!("{e}"))?;
    let (mut b, bonds_b) = build::<f32>(scene, 1.0).map_err(|e| anyhow!("{e}"))?;
    let mut wa_store = storage(&p64.p, &a, &bonds_a);
    let mut wa = wa_store.workspace();
    let mut wb_store = storage(&p32.p, &b, &bonds_b);
    let mut wb = wb_store.workspace();
    let ka = scene
        .contact
        .and_then(|c| c.soft())
        .map(|k| SoftContact { stiffness: k });
    let kb = scene.contact.and_then(|c| c.soft()).map(|k| SoftContact {
        stiffness: k as f32,
    });
    let steps = (t_end / 0.005) as usize;
    let every = (steps / 100).max(1);
    let mut pts = Vec::new();
    for s in 1..=steps {
        let ra = step_slices(
            a.state(),
            &bonds_a,
            &p64.p,
            &mut wa,
            &mut |x: &[glam::DVec3], r: &[f64], f: &mut [glam::DVec3]| {
                if let Some(mut c) = ka {
                    c.add(x, r, f)
                }
            },
        );
        let rb = step_slices(
            b.state(),
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
            let pa: Vec<[f64; 3]> = a.pos.iter().map(|v| v.to_array()).collect();
            let pb: Vec<[f64; 3]> = b.pos.iter().map(|v| v.as_dvec3().to_array()).collect();
            let t = a.time;
            pts.push(Point {
                series: "f32 bond error".into(),
                x: t,
                y: max_residual(&bonds_b, &b.pos).1 as f64,
                extra: vec![],
            });
            pts.push(Point {
                series: "f64 bond error".into(),
                x: t,
                y: max_residual(&bonds_a, &a.pos).1.max(1e-17),
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
