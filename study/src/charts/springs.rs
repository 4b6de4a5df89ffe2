//! The paper's claim that constraints beat stiff springs, quantified.

use std::path::Path;

use anyhow::{Result, anyhow};
use hydrorattle::Method;

use super::{Point, base_scene, max_stable, setup, simulate, stays_bounded, write_chart};
use crate::render::LineChart;

/// The paper's claim, quantified: at equal bond-length error (1e-6), how much more
/// springs cost than constraints on scene (a). Springs' bond error is `~ tension / k`,
/// and explicit stability needs `dt ~ 1 / (k mu)`: both scale with `k`.
pub(super) fn springs_vs_constraints(out: &Path, quick: bool) -> Result<String> {
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
    write_chart(out, quick, "springs_vs_constraints", chart, &rows)?;
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
