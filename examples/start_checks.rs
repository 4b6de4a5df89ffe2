//! The start-up pair checks (nested, coincident or overlapping spheres) over every pair
//! (`particles::check_pairs`) against the cell list (`cell_list::check_pairs_in`, what
//! the host's `Engine::new` and the scene's geometry check use): unit spheres at random
//! without overlap at volume fraction 0.1, this thread's CPU time, and the verdicts
//! compared.
//!
//! ```text
//! cargo run --release --example start_checks [-- N...]   # default 10000 100000
//! ```

use hydrorattle::Real;
use hydrorattle::cell_list::{check_pairs_in, indices};
use hydrorattle::particles::check_pairs;

type V = <f64 as Real>::V3;

#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

#[path = "shared/cpu.rs"]
mod cpu;
use cpu::cpu;

/// `n` unit spheres on a jittered cubic lattice at volume fraction 0.1 (apart: the
/// check visits everything and finds nothing).
fn lattice(n: usize) -> Vec<V> {
    let side = (n as f64).cbrt().ceil() as usize;
    let spacing = (4.0 / 3.0 * std::f64::consts::PI / 0.1f64).cbrt();
    let mut rng = Rng(3);
    (0..n)
        .map(|k| {
            let c = [k % side, k / side % side, k / (side * side)];
            let j = |i: usize, r: &mut Rng| (i as f64 + 0.2 * (r.unit() - 0.5)) * spacing;
            f64::v3(j(c[0], &mut rng), j(c[1], &mut rng), j(c[2], &mut rng))
        })
        .collect()
}

fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let (t, c) = (std::time::Instant::now(), cpu());
    let r = f();
    let s = match (c, cpu()) {
        (Some(a), Some(b)) => b - a,
        _ => t.elapsed().as_secs_f64(),
    };
    (r, s)
}

fn main() {
    let ns: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    for n in if ns.is_empty() {
        vec![10_000, 100_000]
    } else {
        ns
    } {
        let pos = lattice(n);
        let radius = vec![1.0; n];
        let mut store = vec![0; indices(n)];
        let (fast, t_fast) = timed(|| check_pairs_in(&pos, &radius, false, &mut store));
        let (all, t_all) = timed(|| check_pairs(&pos, &radius, false));
        assert_eq!(fast, all);
        println!(
            "N {n:>6}: every pair {t_all:.3} s, cell list {t_fast:.4} s ({:.0} times), verdict {fast:?}",
            t_all / t_fast.max(1e-4)
        );
    }
}
