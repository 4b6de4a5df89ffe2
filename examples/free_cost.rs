//! The constants of the cost model that chooses a free-space product
//! (`host/src/scene/free_cost.rs`): each way of giving a step its products `u = M F`,
//! timed over sphere counts and shapes, with the work each does counted, then fitted.
//!
//! * dense: the stored mobility's assembly (`parallel::assemble`, one pair evaluation
//!   per packed block) and a product from it (`parallel::product`); its block Cholesky
//!   factor (the noise's square root at small N);
//! * compact: the `f32` copy written on the way (`noise::reduced::copy_apply`) and a
//!   product from it (`reduced::apply`), from `REDUCED_MIN` spheres;
//! * matrix-free: every pair evaluated again in each product (`mobility::tt_product`);
//! * fast: `FreeFast::apply` at tolerances 1e-4 and 1e-6, its padded grid points `M`,
//!   window points `P^3` and near pairs (within the cutoff, counted) recorded.
//!
//! Shapes: unit spheres uniformly in a ball at volume fractions 0.01, 0.1 and 0.3
//! (overlaps allowed: equal radii never nest) and the helical chain of
//! `benches/kernel.rs`. Counts 10 to 1e5; a path is not timed above the count where
//! its storage passes 400 MB, or where one call took more than 2 s (the `N^2` paths;
//! the next count would take 20 s) or 5 s (the fast product); the Cholesky factor up to
//! N = 300.
//!
//! Fits, minimising relative residuals with non-negative constants (`shared/fit.rs`):
//! each dense and compact time against `c0 + c1 tri(N)` (`tri(N) = N (N + 1) / 2`
//! blocks), the Cholesky against `c0 + c1 N^3`, the matrix-free product against
//! `c0 + c1 tri(N)`, the fast product against
//! `c0 + cG M log2 M + cN (N + 2 pairs) + cS N P^3` (both tolerances, all shapes).
//!
//! ```text
//! HYDRORATTLE_BENCH_MACHINE=<id> cargo run --release --example free_cost [-- MAX_N]
//! ```
//!
//! Times are this thread's CPU seconds, best of two (`shared/best.rs`). With
//! `HYDRORATTLE_BENCH_MACHINE` set the rows go to `bench/results/free_cost.csv`
//! (measurements, then the constants); the chart `docs/free_crossover.png` is drawn from
//! them by `cargo run --release -p hydrorattle-study --example free_crossover`.

use hydrorattle::Real;
use hydrorattle::linalg::{cholesky, tri};
use hydrorattle::mobility::free_fast::{FreeFast, FreeStorage};
use hydrorattle::mobility::{Hydro, tt_product};
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{Serial, assemble, band_scratch, product};

type V = <f64 as Real>::V3;
type M = <f64 as Real>::M3;

#[path = "shared/best.rs"]
mod best;
#[path = "shared/cpu.rs"]
mod cpu;
use best::best;
#[path = "shared/fit.rs"]
mod fit;
use fit::{fit, misfit};
#[path = "shared/record.rs"]
mod record;
#[path = "shared/splitmix.rs"]
mod splitmix;
use splitmix::Rng;

/// Storage past which a path is not timed (bytes).
const MAX_BYTES: f64 = 4e8;
/// A call this long (CPU seconds) ends a path's counts for its shape: the `N^2` paths
/// (the next count, three times larger, takes nine times as long), then the fast ones.
const MAX_CALL: [f64; 8] = [2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 5.0, 5.0];

/// `n` unit spheres uniformly in a ball at volume fraction `phi`.
fn cloud(n: usize, phi: f64, seed: u64) -> Vec<V> {
    let radius = (n as f64 / phi).cbrt();
    let mut rng = Rng(seed);
    let mut pos = Vec::with_capacity(n);
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| radius * (2.0 * rng.unit() - 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= radius * radius {
            pos.push(f64::v3_from(p));
        }
    }
    pos
}

/// The chain of `benches/kernel.rs`: turning 0.6 rad per bead, rising 0.8, bonds 3
/// (unit beads touching at 1.5 times contact).
fn chain(n: usize) -> Vec<V> {
    let mut at = [0.0f64; 3];
    (0..n)
        .map(|k| {
            let t = 0.6 * k as f64;
            let d = [t.cos(), t.sin(), 0.8];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if k > 0 {
                (0..3).for_each(|c| at[c] += 3.0 * d[c] / l);
            }
            f64::v3_from(at)
        })
        .collect()
}

/// The bounding box's edges of `pos`.
fn extent(pos: &[V]) -> [f64; 3] {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pos {
        let a = f64::v3_to_f64(*p);
        for c in 0..3 {
            lo[c] = lo[c].min(a[c]);
            hi[c] = hi[c].max(a[c]);
        }
    }
    [0, 1, 2].map(|c| hi[c] - lo[c])
}

/// Pairs closer than `cut`, counted in cells of edge `cut` (the fast product's near
/// work).
fn near_pairs(pos: &[V], cut: f64) -> usize {
    use std::collections::HashMap;
    let key = |p: &V| f64::v3_to_f64(*p).map(|x| (x / cut).floor() as i64);
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in pos.iter().enumerate() {
        cells.entry(key(p)).or_default().push(i);
    }
    let mut count = 0;
    for (i, p) in pos.iter().enumerate() {
        let k = key(p);
        for d in 0..27i64 {
            let c = [k[0] + d % 3 - 1, k[1] + d / 3 % 3 - 1, k[2] + d / 9 - 1];
            for &j in cells.get(&c).map_or(&[][..], Vec::as_slice) {
                count += usize::from(j > i && f64::norm2(pos[j] - *p) < cut * cut);
            }
        }
    }
    count
}

/// The timings of one path: its fit's rows of terms and times.
#[derive(Default)]
struct Fit {
    x: Vec<Vec<f64>>,
    t: Vec<f64>,
}

impl Fit {
    fn add(&mut self, terms: Vec<f64>, t: f64) {
        self.x.push(terms);
        self.t.push(t);
    }
}

fn main() -> std::io::Result<()> {
    let max_n: usize = std::env::args()
        .nth(1)
        .map_or(100_000, |s| s.parse::<f64>().unwrap() as usize);
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "free_cost",
        format!("cargo run --release --example free_cost -- {max_n}"),
    );
    let table =
        "free-space product paths, unit spheres, f64, one thread, CPU seconds a call (best of two)";
    let shapes: [(&str, Option<f64>); 4] = [
        ("cloud 0.01", Some(0.01)),
        ("cloud 0.1", Some(0.1)),
        ("cloud 0.3", Some(0.3)),
        ("chain", None),
    ];
    let counts = [10, 30, 100, 300, 1000, 3000, 10_000, 30_000, 100_000];
    let names = [
        "dense assembly",
        "dense product",
        "dense Cholesky",
        "compact copy",
        "compact product",
        "matrix-free product",
        "fast product 1e-4",
        "fast product 1e-6",
    ];
    let mut fits: Vec<Fit> = names.iter().map(|_| Fit::default()).collect();
    let par = Serial;
    for (shape, phi) in shapes {
        let mut stopped = [false; 8];
        for &n in counts.iter().filter(|&&n| n <= max_n) {
            let pos = match phi {
                Some(phi) => cloud(n, phi, 11 + n as u64),
                None => chain(n),
            };
            let rad = vec![1.0; n];
            let mut rng = Rng(5);
            let f: Vec<V> = (0..n)
                .map(|_| f64::v3_from([0, 1, 2].map(|_| 2.0 * rng.unit() - 1.0)))
                .collect();
            let mut y = vec![V::ZERO; n];
            let case = format!("{shape}, N = {n}");
            let blocks = tri(n) as f64;
            let cell = |rows: &mut record::Recorder, q: &str, v: String| {
                println!("{case}: {q} {v}");
                rows.row(table, &case, q, &v);
            };
            cell(&mut rows, "packed blocks tri(N)", format!("{}", tri(n)));
            // One timing of path `k`, kept unless it is past the bounds.
            let time = |k: usize, bytes: f64, stopped: &mut [bool; 8], f: &mut dyn FnMut()| {
                if stopped[k] || bytes > MAX_BYTES {
                    stopped[k] = true;
                    return None;
                }
                let t = best(2, &mut *f);
                stopped[k] = t > MAX_CALL[k];
                Some(t)
            };
            let stored = blocks * 72.0;
            let mut mu = vec![M::ZERO; if stored <= MAX_BYTES { tri(n) } else { 0 }];
            let mut z = vec![V::ZERO; band_scratch(n).max(1)];
            let t = time(0, stored, &mut stopped, &mut || {
                assemble::<f64>(&par, Hydro::Rpy, 1.0, &pos, &rad, &mut mu).unwrap();
            });
            if let Some(t) = t {
                cell(&mut rows, names[0], format!("{t:.4e}"));
                fits[0].add(vec![1.0, blocks], t);
                let t = time(1, stored, &mut stopped, &mut || {
                    product::<f64>(&par, &mu, n, &f, &mut y, &mut z);
                });
                if let Some(t) = t {
                    cell(&mut rows, names[1], format!("{t:.4e}"));
                    fits[1].add(vec![1.0, blocks], t);
                }
                let cube = (n as f64).powi(3);
                let mut l = if n <= 300 { mu.clone() } else { vec![] };
                let t = time(
                    2,
                    if n <= 300 { stored } else { f64::INFINITY },
                    &mut stopped,
                    &mut || {
                        l.copy_from_slice(&mu);
                        cholesky::<f64>(&mut l, n).unwrap();
                    },
                );
                if let Some(t) = t {
                    cell(&mut rows, names[2], format!("{t:.4e}"));
                    fits[2].add(vec![1.0, cube], t);
                }
                if reduced::usable::<f64>(n) {
                    let mut copy = vec![M::ZERO; reduced::slots(n)];
                    let t = time(3, stored, &mut stopped, &mut || {
                        reduced::copy_apply::<f64>(&par, &mu, n, &mut copy, &f, &mut y, &mut z);
                    });
                    if let Some(t) = t {
                        cell(&mut rows, names[3], format!("{t:.4e}"));
                        fits[3].add(vec![1.0, blocks], t);
                    }
                    let t = time(4, stored, &mut stopped, &mut || {
                        reduced::apply::<f64>(&par, &copy, n, &f, &mut y, &mut z);
                    });
                    if let Some(t) = t {
                        cell(&mut rows, names[4], format!("{t:.4e}"));
                        fits[4].add(vec![1.0, blocks], t);
                    }
                }
            }
            drop(mu);
            let t = time(5, 0.0, &mut stopped, &mut || {
                tt_product(Hydro::Rpy, 1.0, &pos, &rad, &f, &mut y).unwrap();
            });
            if let Some(t) = t {
                cell(&mut rows, names[5], format!("{t:.4e}"));
                fits[5].add(vec![1.0, blocks], t);
            }
            for (k, tol) in [(6, 1e-4), (7, 1e-6)] {
                let ext = extent(&pos);
                let Ok(ff) = FreeFast::<f64>::new(1.0, tol, ext, n) else {
                    cell(&mut rows, names[k], "refused (grid past its bound)".into());
                    continue;
                };
                let size = ff.storage(n);
                let bytes = (size.complex * 16 + size.reals * 8 + size.index * 8) as f64;
                if stopped[k] || bytes > MAX_BYTES {
                    stopped[k] = true;
                    continue;
                }
                let mut cx = vec![[0.0; 2]; size.complex];
                let mut re = vec![0.0; size.reals];
                let mut ix = vec![0usize; size.index];
                let mut store = FreeStorage::new(&mut cx, &mut re, &mut ix);
                // The first product transforms the kernel; the step keeps it.
                ff.apply(1.0, &pos, &rad, &f, &mut y, &mut store).unwrap();
                let Some(t) = time(k, bytes, &mut stopped, &mut || {
                    ff.apply(1.0, &pos, &rad, &f, &mut y, &mut store).unwrap();
                }) else {
                    continue;
                };
                let g = ff.grid();
                let m = (g[0] * g[1] * g[2]) as f64;
                let p3 = ff.support().pow(3) as f64;
                let pairs = near_pairs(&pos, ff.r_cut()) as f64;
                cell(&mut rows, names[k], format!("{t:.4e}"));
                let tag = names[k].replace("product ", "");
                cell(
                    &mut rows,
                    &format!("{tag}: padded grid points M"),
                    format!("{m}"),
                );
                cell(
                    &mut rows,
                    &format!("{tag}: window points P^3"),
                    format!("{p3}"),
                );
                cell(&mut rows, &format!("{tag}: near pairs"), format!("{pairs}"));
                cell(
                    &mut rows,
                    &format!("{tag}: cutoff r_c"),
                    format!("{:.4}", ff.r_cut()),
                );
                cell(
                    &mut rows,
                    &format!("{tag}: storage bytes"),
                    format!("{bytes}"),
                );
                fits[k].add(
                    vec![1.0, m * m.log2(), n as f64 + 2.0 * pairs, n as f64 * p3],
                    t,
                );
            }
        }
    }
    // The two tolerances share one fast model: their terms carry the tolerance.
    let fast = Fit {
        x: [&fits[6].x[..], &fits[7].x[..]].concat(),
        t: [&fits[6].t[..], &fits[7].t[..]].concat(),
    };
    let fitted: [(&str, &Fit, &[&str]); 7] = [
        (
            "dense assembly",
            &fits[0],
            &["DENSE_ASSEMBLY_FIXED", "DENSE_ASSEMBLY_BLOCK"],
        ),
        (
            "dense product",
            &fits[1],
            &["DENSE_PRODUCT_FIXED", "DENSE_PRODUCT_BLOCK"],
        ),
        (
            "dense Cholesky",
            &fits[2],
            &["CHOLESKY_FIXED", "CHOLESKY_CUBE"],
        ),
        (
            "compact copy",
            &fits[3],
            &["COMPACT_COPY_FIXED", "COMPACT_COPY_BLOCK"],
        ),
        (
            "compact product",
            &fits[4],
            &["COMPACT_PRODUCT_FIXED", "COMPACT_PRODUCT_BLOCK"],
        ),
        (
            "matrix-free product",
            &fits[5],
            &["FREE_FIXED", "FREE_BLOCK"],
        ),
        (
            "fast product",
            &fast,
            &["FAST_FIXED", "FAST_GRID", "FAST_NEAR", "FAST_SPREAD"],
        ),
    ];
    let model =
        "free-space cost model constants (seconds a call per term), fitted to this run's rows";
    for (path, data, consts) in fitted {
        if data.t.is_empty() {
            continue;
        }
        let c = fit(&data.x, &data.t);
        for (name, v) in consts.iter().zip(&c) {
            println!("{name} = {v:.4e}");
            rows.row(model, path, name, &format!("{v:.4e}"));
        }
        let worst = misfit(&data.x, &data.t, &c);
        println!(
            "{path}: worst misfit x{worst:.2} over {} rows",
            data.t.len()
        );
        rows.row(model, path, "worst misfit (factor)", &format!("{worst:.2}"));
    }
    rows.finish()
}
