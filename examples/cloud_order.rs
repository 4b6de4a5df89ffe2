//! What the second-order step buys on a falling cloud on the fast free-space product
//! (`Params::pse` without a box, matrix-free): `Overdamped` and `Overdamped2` at
//! `dt = 0.2, 0.1, 0.05` to `t = T`, against `Overdamped2`'s Richardson extrapolation
//! from `dt = 0.05` and `0.025` (`(4 x(0.025) - x(0.05)) / 3`). Unit spheres placed at
//! random without overlap in a ball at volume fraction 0.01 (as
//! `host/scenes/cloud_small.toml`), density 4.5 in a fluid at rest, gravity 1: each
//! alone settles at `U0 = 1`. f64, one thread.
//!
//! ```text
//! cargo run --release --example cloud_order                   # N = 1000, T = 10, tolerance 1e-5
//! cargo run --release --example cloud_order -- 1000 10 1e-5
//! ```
//!
//! Prints, per method and step: this thread's CPU seconds, the centroid's fall speed
//! at `T` (every sphere's velocity at the final configuration, one probe step of
//! `Overdamped` at `dt = 1e-3`, averaged) and its error against the reference's, and
//! the spheres' rms position error at `T` over the distance the centroid fell.

use hydrorattle::integrate::{fast_storage, step_slices};
use hydrorattle::{Layout, Method, NoForce, Params, Real, State};
use hydrorattle_heap::FreeBuffers;

type V = <f64 as Real>::V3;

#[path = "shared/cpu.rs"]
mod cpu;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

/// `n` unit spheres at random in a ball at volume fraction `phi`, none overlapping.
fn cloud(n: usize, phi: f64, seed: u64) -> Vec<V> {
    let radius = (n as f64 / phi).cbrt();
    let mut rng = Rng(seed);
    let mut pos: Vec<[f64; 3]> = Vec::with_capacity(n);
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| (radius - 1.0) * (2.0 * rng.unit() - 1.0));
        let inside = p.iter().map(|x| x * x).sum::<f64>() <= (radius - 1.0).powi(2);
        let apart = pos
            .iter()
            .all(|q| (0..3).map(|d| (p[d] - q[d]).powi(2)).sum::<f64>() > 4.0 * 1.000_001);
        if inside && apart {
            pos.push(p);
        }
    }
    pos.into_iter().map(f64::v3_from).collect()
}

/// `steps` steps of `p` from `pos0`: the positions after, the velocities of the last
/// step, and this thread's CPU seconds.
fn run(p: &Params<f64>, pos0: &[V], steps: usize) -> (Vec<V>, Vec<V>, f64) {
    let n = pos0.len();
    let rad = vec![1.0; n];
    let density = vec![4.5; n];
    let mut arrays = FreeBuffers::<f64>::for_step(fast_storage(p, pos0, &rad).unwrap());
    let mut buf = hydrorattle_heap::Buffers::<f64>::new(Layout::for_params(p, n, 0));
    let mut ws = arrays.attach(buf.workspace());
    let (mut pos, mut vel, mut omega) = (pos0.to_vec(), vec![V::ZERO; n], vec![V::ZERO; n]);
    let mut time = 0.0;
    let c0 = cpu::cpu().unwrap_or(0.0);
    for k in 0..steps {
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &rad,
            density: &density,
            time: &mut time,
            noise: None,
        };
        step_slices(state, &[], p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("{:?} dt {} step {k}: {e}", p.method, p.dt));
    }
    let c = cpu::cpu().unwrap_or(0.0) - c0;
    (pos, vel, c)
}

fn params(method: Method, dt: f64, tol: f64) -> Params<f64> {
    let mut p = Params::new(dt);
    p.method = method;
    p.matrix_free = true;
    p.pse = Some(tol);
    // Point-like spheres under RPY pass through each other, as the cloud scenes' do.
    p.allow_overlap = true;
    p
}

/// The centroid's fall speed at the configuration `pos`: one probe step of
/// `Overdamped`, whose velocities are the mobility's at its start.
fn fall_speed(pos: &[V], tol: f64) -> f64 {
    let (_, vel, _) = run(&params(Method::Overdamped, 1e-3, tol), pos, 1);
    -vel.iter().map(|v| v.z).sum::<f64>() / pos.len() as f64
}

fn centroid_z(pos: &[V]) -> f64 {
    pos.iter().map(|v| v.z).sum::<f64>() / pos.len() as f64
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().map_or(1000, |s| s.parse().unwrap());
    let t_end: f64 = args.get(1).map_or(10.0, |s| s.parse().unwrap());
    let tol: f64 = args.get(2).map_or(1e-5, |s| s.parse().unwrap());
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "cloud_order",
        format!("cargo run --release --example cloud_order -- {n} {t_end} {tol:e}"),
    );
    let pos0 = cloud(n, 0.01, 1);
    let steps = |dt: f64| (t_end / dt).round() as usize;
    // The reference: Overdamped2's Richardson extrapolation.
    let (a, _, ca) = run(&params(Method::Overdamped2, 0.05, tol), &pos0, steps(0.05));
    let (b, _, cb) = run(
        &params(Method::Overdamped2, 0.025, tol),
        &pos0,
        steps(0.025),
    );
    let reference: Vec<V> = a
        .iter()
        .zip(&b)
        .map(|(a, b)| (*b * 4.0 - *a) / 3.0)
        .collect();
    let v_ref = fall_speed(&reference, tol);
    let fallen = centroid_z(&pos0) - centroid_z(&reference);
    let table = format!(
        "falling cloud of {n} unit spheres at volume fraction 0.01 (U0 = 1), fast free-space product tolerance {tol:e}, f64, one thread, to t = {t_end}"
    );
    println!("{table}");
    println!(
        "reference: centroid fall speed {v_ref:.4} U0 at t = {t_end}, fallen {fallen:.2} (Overdamped2 at dt 0.05 and 0.025: {ca:.1} + {cb:.1} CPU s)"
    );
    rows.row(
        &table,
        "reference (Overdamped2, Richardson from dt 0.05 and 0.025)",
        "centroid fall speed at t end, U0",
        &format!("{v_ref:.5}"),
    );
    println!("method,dt,cpu_s,fall_speed,speed_error_pct,rms_position_error_over_fallen");
    for method in [Method::Overdamped, Method::Overdamped2] {
        for dt in [0.2, 0.1, 0.05] {
            let (pos, _, cpu) = match (method, dt) {
                (Method::Overdamped2, 0.05) => (a.clone(), vec![], ca),
                _ => run(&params(method, dt, tol), &pos0, steps(dt)),
            };
            let v = fall_speed(&pos, tol);
            let err = 100.0 * (v - v_ref) / v_ref;
            let rms = (pos
                .iter()
                .zip(&reference)
                .map(|(x, r)| (*x - *r).length_squared())
                .sum::<f64>()
                / n as f64)
                .sqrt()
                / fallen;
            println!("{method:?},{dt},{cpu:.1},{v:.5},{err:.2e},{rms:.2e}");
            let case = format!("{method:?} dt {dt}");
            rows.row(&table, &case, "CPU s", &format!("{cpu:.1}"));
            rows.row(
                &table,
                &case,
                "centroid fall speed at t end, U0",
                &format!("{v:.5}"),
            );
            rows.row(
                &table,
                &case,
                "fall speed error against the reference, %",
                &format!("{err:.2e}"),
            );
            rows.row(
                &table,
                &case,
                "rms position error over distance fallen",
                &format!("{rms:.2e}"),
            );
        }
    }
    rows.finish().unwrap();
}
