//! Brownian dynamics: the charts that show the noise is right and what it
//! does to the paper's chain.
//!
//! * `brownian_trimer`: a freely jointed trimer's bond-angle density, with and without
//!   the midpoint drift, against the flexible `sin(theta)/2` and rigid
//!   `sin(theta) sqrt(1 - cos^2/4) / Z` laws;
//! * `brownian_dimer_orientation`, `brownian_dimer_msd`: a rigid dimer's axis
//!   autocorrelation and midpoint mean-square displacement against `exp(-2 D_r t)` and
//!   `6 D_t t` from the two-sphere RPY mobility;
//! * `brownian_peclet`: Figure 1 (c) at Peclet numbers from 1000 down to 3, several
//!   seeds each: how thermal noise changes its verticality, extension and settling.

use std::f64::consts::PI;
use std::path::Path;

use anyhow::{Result, anyhow};
use hydrorattle::glam::DVec3;
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, NoForce, Noise, Params, Particle, ParticleSet, step,
};
use hydrorattle_heap::Buffers;

use super::{Point, write_chart};
use crate::render::LineChart;

/// `steps` thermal steps of `N` unit spheres at `pos` joined in a chain, `kT = 1`;
/// `observe` sees the centres after each step.
fn sample<const N: usize, const B: usize>(
    pos: [[f64; 3]; N],
    p: &Params<f64>,
    seed: u64,
    steps: usize,
    mut observe: impl FnMut(&[DVec3]),
) -> Result<()> {
    let mut ps = ParticleSet::<f64, N>::new();
    for r in pos {
        ps.push(Particle::new(r.into(), 1.0, 0.0))
            .map_err(|(_, e)| anyhow!("{e}"))?;
    }
    let bonds = BondSet::<f64, B>::chain(&ps.pos[..N]).map_err(|e| anyhow!("{e}"))?;
    let mut store = Buffers::<f64>::new(Layout::for_params(p, N, bonds.len()));
    let mut ws = store.workspace();
    ps.noise = Some(Noise::new(seed));
    for _ in 0..steps {
        step(&mut ps, &bonds, p, &mut ws, &mut NoForce)?;
        observe(&ps.pos[..N]);
    }
    Ok(())
}

/// Overdamped, no gravity, `kT = 1`.
fn thermal(dt: f64, eta: f64, hydro: Hydro, drift: Drift) -> Params<f64> {
    let mut p = Params::new(dt);
    p.viscosity = eta;
    p.gravity = DVec3::ZERO;
    p.hydro = hydro;
    p.allow_overlap = true;
    p.brownian = Some(Brownian {
        temperature: 1.0,
        drift,
    });
    p
}

/// Bond-angle histograms of the trimer (unit beads, bonds 3, bead mobility 1).
pub(super) fn trimer(out: &Path, quick: bool) -> Result<String> {
    const BINS: usize = 36;
    let steps = if quick { 100_000 } else { 1_200_000 };
    let cases = [
        (
            "free draining, uncorrected",
            Hydro::FreeDraining,
            Drift::Uncorrected,
        ),
        (
            "free draining, midpoint",
            Hydro::FreeDraining,
            Drift::Midpoint,
        ),
        ("RPY, uncorrected", Hydro::Rpy, Drift::Uncorrected),
        ("RPY, midpoint", Hydro::Rpy, Drift::Midpoint),
    ];
    let results: Vec<Result<(Vec<f64>, f64)>> = std::thread::scope(|s| {
        let runs: Vec<_> = cases
            .iter()
            .enumerate()
            .map(|(k, &(_, hydro, drift))| {
                s.spawn(move || {
                    let p = thermal(0.045, 1.0 / (6.0 * PI), hydro, drift);
                    let mut hist = vec![0.0; BINS];
                    let mut c2 = 0.0;
                    let start = [[0.0; 3], [3.0, 0.0, 0.0], [3.0, 3.0, 0.0]];
                    sample::<3, 2>(start, &p, 20 + k as u64, steps, |x| {
                        let (b1, b2) = (x[0] - x[1], x[1] - x[2]);
                        let c = (b1.dot(b2) / (b1.length() * b2.length())).clamp(-1.0, 1.0);
                        let bin = ((c.acos() / PI * BINS as f64) as usize).min(BINS - 1);
                        hist[bin] += 1.0;
                        c2 += c * c;
                    })?;
                    Ok((hist, c2 / steps as f64))
                })
            })
            .collect();
        runs.into_iter()
            .map(|r| r.join().unwrap_or_else(|_| Err(anyhow!("thread panicked"))))
            .collect()
    });
    let width = PI / BINS as f64;
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    for ((name, ..), r) in cases.iter().zip(results) {
        let (hist, c2) = r?;
        notes.push(format!("{name} <cos^2> = {c2:.4}"));
        for (k, h) in hist.iter().enumerate() {
            rows.push(Point {
                series: (*name).into(),
                x: (k as f64 + 0.5) * width,
                y: h / (steps as f64 * width),
                extra: vec![("mean cos^2".into(), c2)],
            });
        }
    }
    let z = PI / 3.0 + 3f64.sqrt() / 2.0;
    for k in 0..=90 {
        let t = PI * k as f64 / 90.0;
        let (s, c) = t.sin_cos();
        for (series, y, m) in [
            ("flexible (stiff bonds): sin / 2", s / 2.0, 1.0 / 3.0),
            (
                "rigid: sin sqrt(1 - cos^2/4) / Z",
                s * (1.0 - c * c / 4.0).sqrt() / z,
                0.32102,
            ),
        ] {
            rows.push(Point {
                series: series.into(),
                x: t,
                y,
                extra: vec![("mean cos^2".into(), m)],
            });
        }
    }
    let chart = LineChart {
        title: "Freely jointed trimer: angle between the bonds".into(),
        x_label: "angle between bond vectors (rad)".into(),
        y_label: "probability density".into(),
        ..Default::default()
    };
    write_chart(out, quick, "brownian_trimer", chart, &rows)?;
    Ok(format!(
        "trimer ({steps} steps each; flexible 0.3333, rigid 0.3210): {}",
        notes.join(", ")
    ))
}

/// The dimer's exact `(D_t, D_r)` (equal spheres `a`, bond `d`, viscosity `eta`).
fn dimer_exact(a: f64, d: f64, eta: f64) -> (f64, f64) {
    let dt = (1.0 / a + 1.0 / d) / (12.0 * PI * eta);
    let perp = (1.0 + 2.0 * a * a / (3.0 * d * d)) / (8.0 * PI * eta * d);
    (dt, 2.0 * (1.0 / (6.0 * PI * eta * a) - perp) / (d * d))
}

/// Axis autocorrelation and midpoint MSD of the RPY dimer (a = 1, d = 3, eta = 1).
pub(super) fn dimer(out: &Path, quick: bool) -> Result<String> {
    let (dt, steps) = (0.5, if quick { 50_000 } else { 600_000 });
    let p = thermal(dt, 1.0, Hydro::Rpy, Drift::Midpoint);
    let (mut mid, mut axis) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    sample::<2, 1>([[0.0; 3], [3.0, 0.0, 0.0]], &p, 3, steps, |x| {
        mid.push((x[0] + x[1]) * 0.5);
        axis.push((x[0] - x[1]).normalize());
    })?;
    let (d_t, d_r) = dimer_exact(1.0, 3.0, 1.0);
    let (mut corr, mut msd) = (Vec::new(), Vec::new());
    for lag in (10..=300).step_by(10) {
        let t = lag as f64 * dt;
        let pairs = steps - lag;
        let c = (0..pairs).map(|k| axis[k].dot(axis[k + lag])).sum::<f64>() / pairs as f64;
        let m = (0..pairs)
            .map(|k| (mid[k + lag] - mid[k]).length_squared())
            .sum::<f64>()
            / pairs as f64;
        let point = |series: &str, y| Point {
            series: series.into(),
            x: t,
            y,
            extra: Vec::new(),
        };
        corr.push(point("measured", c));
        corr.push(point("exp(-2 D_r t), RPY", (-2.0 * d_r * t).exp()));
        msd.push(point("measured", m));
        msd.push(point("6 D_t t, RPY", 6.0 * d_t * t));
    }
    let chart = |title: &str, y: &str, log_y| LineChart {
        title: title.into(),
        x_label: "lag time t".into(),
        y_label: y.into(),
        log_y,
        ..Default::default()
    };
    write_chart(
        out,
        quick,
        "brownian_dimer_orientation",
        chart(
            "Rigid dimer (a = 1, d = 3): axis autocorrelation",
            "<u(0).u(t)>",
            true,
        ),
        &corr,
    )?;
    write_chart(
        out,
        quick,
        "brownian_dimer_msd",
        chart(
            "Rigid dimer: midpoint mean-square displacement",
            "MSD",
            false,
        ),
        &msd,
    )?;
    Ok(format!(
        "dimer ({steps} steps): D_t = {d_t:.5}, D_r = {d_r:.5} (exact, RPY); charts against them"
    ))
}
