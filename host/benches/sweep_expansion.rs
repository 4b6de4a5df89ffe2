//! Sweep expansion (issue 29 item 6): 10^5 points of the Figure 1 (a) chain resolved
//! (every scene parsed and validated, duplicates checked, ids computed), and what one
//! task of an emitted 20 000-point job pays to find its point (`--frozen --point ID`:
//! `sweep.json` and one frozen scene, no expansion).
//!
//!     cargo bench -p hydrorattle-host --bench sweep_expansion
//!
//! Measured on the shared 2-core development machine under a load of about 14 (so
//! the wall times are several times an idle machine's; the CPU times of
//! `host-demo sweep FILE --dry-run`, measured beside them, are the steadier figure):
//!
//! | what | wall time | CPU time (dry-run) |
//! |---|---|---|
//! | expand 99 856 points | 8.5 s | 3.5 s (35 µs a point) |
//! | expand 20 164 points | 1.74 s | |
//! | expand 40 000 points, before (quadratic duplicate check) | 20.5 s | 8.0 s |
//! | expand 40 000 points, now | 5.5 s | 1.4 s |
//! | `--frozen --point ID` of 20 164: find and read the point | 109 ms | |
//! | run that point (4000 steps of the 25-bead chain) | 855 ms | |
//!
//! So a task of an emitted 20 000-point job spends about an eighth of its point's
//! run finding it, where expanding the sweep cost twice the run.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use hydrorattle_host::sweep::run::{Options, Selection};
use hydrorattle_host::sweep::{Sweep, frozen};

/// A sweep of `n` x `n` points over the Figure 1 (a) scene.
fn grid(n: usize) -> String {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-demo/scenes/figure1a.toml");
    format!(
        "[sweep]\nbase = {:?}\n\"helix.dhat\" = {{ linspace = [1.05, 2.0, {n}] }}\n\"helix.head_ratio\" = {{ linspace = [1.0, 2.5, {n}] }}\n",
        base.display().to_string()
    )
}

fn expansion(c: &mut Criterion) {
    let mut g = c.benchmark_group("sweep");
    g.sample_size(10);
    let big = grid(316); // 99 856 points (the limit is 100 000)
    g.bench_function("expand 99856 points", |b| {
        b.iter(|| {
            Sweep::parse(&big, "bench.toml", Path::new("."))
                .unwrap()
                .points
                .len()
        })
    });
    let dir = std::env::temp_dir().join(format!("sweep-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let big_file = dir.join("big.toml");
    std::fs::write(&big_file, &big).unwrap();
    g.bench_function("check 99856 points (dry-run: each scene let go)", |b| {
        b.iter(|| Sweep::check_path(&big_file).unwrap().len())
    });
    let middle = Sweep::check_path(&big_file).unwrap()[99856 / 2].0.clone();
    g.bench_function("find one point of 99856 (sweep file)", |b| {
        b.iter(|| {
            Sweep::point_from_path(&big_file, &middle)
                .unwrap()
                .unwrap()
                .count
        })
    });
    let sweep = Sweep::parse(&grid(142), "bench.toml", Path::new(".")).unwrap(); // 20 164
    hydrorattle_host::sweep::claim::claim(&sweep, &dir).unwrap();
    let id = sweep.points[sweep.points.len() / 2].id.clone();
    let one = Selection::Point(id.clone());
    g.bench_function("find one point of 20164 (frozen)", |b| {
        b.iter(|| frozen::load(&dir, &one).unwrap().1.len())
    });
    let file = dir.join("grid.toml");
    std::fs::write(&file, grid(142)).unwrap();
    g.bench_function("find one point of 20164 (sweep file)", |b| {
        b.iter(|| Sweep::point_from_path(&file, &id).unwrap().unwrap().count)
    });
    g.bench_function("expand 20164 points (sweep file)", |b| {
        b.iter(|| {
            Sweep::parse(&grid(142), "bench.toml", Path::new("."))
                .unwrap()
                .points
                .len()
        })
    });
    // The point itself: its 4000 steps from the start.
    let opts = Options {
        jobs: 1,
        checkpoint_every: None,
        wait: false,
        stop: Default::default(),
    };
    let point = dir.join("points").join(&id);
    g.bench_function("run that point", |b| {
        b.iter(|| {
            let _ = std::fs::remove_dir_all(&point);
            hydrorattle_host::sweep::run_frozen(&dir, &one, opts)
                .unwrap()
                .ran
        })
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, expansion);
criterion_main!(benches);
