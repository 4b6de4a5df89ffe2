//! Sweep expansion: 10^5 points of the Figure 1 (a) chain resolved
//! (every scene resolved and validated, duplicates checked, ids computed), held
//! (`Sweep::parse`) or let go as checked (`Sweep::check_path`, `--dry-run`); and what
//! finding one point costs: from an emitted folder (`--frozen --point ID`: `sweep.json`
//! and one frozen scene) or from the sweep file (`sweep FILE --point ID`: every id, one
//! scene).
//!
//!     cargo bench -p hydrorattle-host --bench sweep_expansion
//!
//! Criterion medians on the shared 2-core development machine under load (2 threads;
//! "before" is the commit before each point's scene was resolved from the parsed base,
//! run just before "after" on the same machine). The CPU time of `host-demo sweep FILE
//! --out o --dry-run` on one thread (`RAYON_NUM_THREADS=1`, `perf stat` task-clock,
//! best of 3) is the steadier figure:
//!
//! | what | before | after |
//! |---|---|---|
//! | expand 99 856 points (held) | 2.87 s | 0.91 s |
//! | check 99 856 points (dry-run: each scene let go) | | 0.52 s |
//! | expand 20 164 points (held) | 564 ms | 225 ms |
//! | find one point of 99 856 (sweep file) | (the whole expansion) | 81 ms |
//! | find one point of 20 164 (sweep file) | (the whole expansion) | 28 ms |
//! | find one point of 20 164 (frozen) | 41 ms | 34 ms |
//! | run that point (4000 steps of the 25-bead chain) | 419 ms | 282 ms |
//! | dry-run of 10^4 points, CPU on one thread | 0.36 s | 0.093 s |
//! | dry-run of 99 856 points, CPU on one thread | 3.68 s | 0.92 s (9 µs a point) |
//!
//! (The point's run is the same code before and after: its two figures show the
//! load's noise.) Per point, the expansion was: the base's TOML table cloned, the
//! point's values set, the table written as text and the text parsed (60 % of it); an
//! id from a JSON tree and an MD5 that allocated per block and per hex digit; a
//! duplicate check over every point. It is now: a copy of the base's parsed document
//! with the values set, resolved; one canonical JSON text and an allocation-free MD5;
//! duplicates found in each list's own rows. And the scene no longer allocates a
//! species name per bead: 26 small strings freed between larger blocks sent glibc's
//! allocator down its slow path, which was half of what remained.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use hydrorattle_host::sweep::run::{Options, Selection};
use hydrorattle_host::sweep::{Sweep, frozen};

/// A sweep of `n` x `n` points over the Figure 1 (a) scene.
fn grid(n: usize) -> String {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/figure1a.toml");
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
