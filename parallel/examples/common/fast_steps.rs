//! `free_fast_threads`'s step mode (`STEP=1`): steps of a sedimenting cloud on the fast
//! free-space product (`Params::pse` without a box, `Method::Overdamped`, densities 1 to
//! 3, dt 0.01, f64) on one thread and on more, each thread count over its own zeroed
//! arrays: the first step computes the kernel's transform, the second (from the first's
//! end) keeps it, and the second again on zeroed arrays computes it afresh and must give
//! the same bits. Wall and process CPU seconds of each.

use std::time::Instant;

use hydrorattle::glam::DVec3;
use hydrorattle::integrate::{fast_storage, step_slices};
use hydrorattle::mobility::free_fast::transform_counts;
use hydrorattle::{Layout, Method, NoForce, Parallel, Params, Serial, State};
use hydrorattle_heap::{Buffers, FreeBuffers};
use hydrorattle_parallel::Threads;

use crate::common::cpu_ns;

/// The arrays of the fast product for steps of `p` from `pos`.
fn arrays(p: &Params<f64>, pos: &[DVec3]) -> FreeBuffers<f64> {
    let z = fast_storage(p, pos, &vec![1.0; pos.len()])
        .unwrap()
        .unwrap();
    FreeBuffers::new(z)
}

/// One step of `p` from `pos` over `a` on `par`: the positions after, wall and CPU
/// seconds.
fn step(
    p: &Params<f64>,
    pos: &[DVec3],
    a: &mut FreeBuffers<f64>,
    par: &dyn Parallel,
) -> (Vec<DVec3>, f64, f64) {
    let n = pos.len();
    let rad = vec![1.0; n];
    let density: Vec<f64> = (0..n).map(|i| 1.0 + (i % 3) as f64).collect();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, n, 0));
    let ws = buf.workspace().with_parallel(par);
    let mut ws = a.attach(ws);
    let (mut pos, mut vel, mut omega) = (pos.to_vec(), vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let mut time = 0.0;
    let state = State {
        pos: &mut pos,
        vel: &mut vel,
        omega: &mut omega,
        radius: &rad,
        density: &density,
        time: &mut time,
        noise: None,
    };
    let (c0, t0) = (cpu_ns(), Instant::now());
    step_slices(state, &[], p, &mut ws, &mut NoForce).unwrap();
    let wall = t0.elapsed().as_secs_f64();
    (pos, wall, (cpu_ns() - c0) as f64 * 1e-9)
}

/// The step mode for the cloud `pos` at tolerance `tol`: printed, and rows of `table`
/// for `case` through `row(case, quantity, value)`.
pub fn steps(tol: f64, threads: usize, pos: &[DVec3], mut row: impl FnMut(&str, &str)) {
    let mut p = Params::<f64>::new(0.01);
    p.method = Method::Overdamped;
    p.allow_overlap = true;
    p.matrix_free = true;
    p.pse = Some(tol);
    let pool = Threads::new(threads).unwrap();
    let seconds = |row: &mut dyn FnMut(&str, &str), what: &str, t: usize, (wall, cpu)| {
        println!("  {what}, {t} thread(s): {wall:.3} s wall, {cpu:.3} s CPU");
        row(
            &format!("seconds, {what}, {t} thread(s), wall"),
            &format!("{wall:.3}"),
        );
        row(
            &format!("seconds, {what}, {t} thread(s), CPU"),
            &format!("{cpu:.3}"),
        );
    };
    let mut after = vec![];
    for (t, par) in [
        (1, &Serial as &dyn Parallel),
        (threads, &pool as &dyn Parallel),
    ] {
        let mut a = arrays(&p, pos);
        let (p1, w1, c1) = step(&p, pos, &mut a, par);
        seconds(&mut row, "first step, transform computed", t, (w1, c1));
        let (p2, w2, c2) = step(&p, &p1, &mut a, par);
        seconds(&mut row, "second step, transform kept", t, (w2, c2));
        let counts = transform_counts(&a.reals).unwrap_or_default();
        let (p3, w3, c3) = step(&p, &p1, &mut arrays(&p, pos), par);
        seconds(
            &mut row,
            "second step on zeroed arrays, transform computed",
            t,
            (w3, c3),
        );
        println!(
            "  transform counts {counts:?}, kept and fresh same bits: {}",
            p2 == p3
        );
        row(
            &format!("products that kept the transform, two steps, {t} thread(s)"),
            &counts.kept.to_string(),
        );
        row(
            &format!("products that computed the transform, two steps, {t} thread(s)"),
            &counts.computed.to_string(),
        );
        row(
            &format!("second step's bits, kept against zeroed arrays, {t} thread(s)"),
            &(p2 == p3).to_string(),
        );
        after.push(p2);
    }
    let same = after[0] == after[1];
    println!("  same bits on 1 and {threads} threads: {same}");
    row("same bits on 1 and more threads", &same.to_string());
}
