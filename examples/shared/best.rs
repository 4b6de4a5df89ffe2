//! Best-of timing for the examples (shared by `#[path]`, with `shared/cpu.rs` as the
//! including crate's `cpu` module).

use std::time::Instant;

use crate::cpu::cpu;

/// Best of `reps` measurements of `f`, seconds per call: this thread's CPU time where
/// the machine tells it (each measurement repeats `f` until at least 0.3 s of it, for
/// the 10 ms ticks), else the wall clock.
pub fn best(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let (t, c) = (Instant::now(), cpu());
            let mut calls = 0;
            loop {
                f();
                calls += 1;
                let used = match (c, cpu()) {
                    (Some(a), Some(b)) => b - a,
                    _ => t.elapsed().as_secs_f64(),
                };
                if used >= 0.3 {
                    return used / calls as f64;
                }
            }
        })
        .fold(f64::INFINITY, f64::min)
}
