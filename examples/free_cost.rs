//! The constants of the cost model that chooses a free-space product
//! (`host/src/scene/free_cost.rs`): each way of giving a step its products `u = M F`,
//! timed over sphere counts and shapes, with the work each does counted, then fitted.
//!
//! * dense: the stored mobility's assembly (`parallel::assemble`, one pair evaluation
//!   per packed block) and a product from it (`parallel::product`); its block Cholesky
//!   factor (the noise's square root at small N); with rotation and inertia the grand
//!   mobility's assembly (`mobility::assemble_grand`, `tri(2N)` blocks);
//! * compact: the `f32` copy written on the way (`noise::reduced::copy_apply`) and a
//!   product from it (`reduced::apply`), from `REDUCED_MIN` spheres;
//! * matrix-free: every pair evaluated again in each product (`mobility::tt_product`);
//! * the spins of a step with rotation on the pair paths: one pass over the pairs'
//!   rotation-from-force blocks (`Geometry::add_spin`);
//! * fast: `FreeFast::apply` at tolerances 1e-4 and 1e-6 in the steady state (the
//!   kernel's transform computed by a first product and kept, as a step keeps it), its
//!   padded grid points `M`, window points `P^3` and near pairs (within the cutoff,
//!   counted) recorded; with rotation the same product under the grand parameters
//!   (`FreeFast::new_grand`) and the grand product `FreeFast::apply_grand` (a step's
//!   spins). Where the rule's grid passes its bounds (the chain from 3000 beads) the
//!   parameters a step takes instead (`integrate::fast_parameters`: the spreading
//!   widened until a grid fits).
//!
//! Shapes: unit spheres uniformly in a ball at volume fractions 0.01, 0.1 and 0.3
//! (overlaps allowed: equal radii never nest) and the helical chain of
//! `benches/kernel/shared.rs`. Counts MIN_N (10) to MAX_N (1e4 by default); the fast products
//! of the cloud at 0.1 also at 2e4, 5e4 and 1e5 when MAX_N allows, the matrix-free one
//! at 2e4 (a call takes some 4 s there and grows as `N^2`; the stored paths' storage is
//! past any bound). A path is not timed above the count where its storage passes
//! BYTES (`--max-bytes`, 400 MB by default; the fast product at 1e-4 needs some 600 MB
//! at 1e5), or where one call took more than 2 s (the `N^2` paths; the next count would
//! take 20 s) or 8 s (the fast products); the Cholesky factor up to N = 300.
//!
//! Fits, minimising relative residuals with non-negative constants (`shared/fit.rs`):
//! each dense, compact, spin and matrix-free time against `c0 + c1 tri(N)`
//! (`tri(N) = N (N + 1) / 2` blocks), the grand assembly against `c0 + c1 tri(2N)`, the
//! Cholesky against `c0 + c1 N^3`, the fast product (both tolerances, both parameter
//! rules, all shapes) and the grand product each against
//! `c0 + cG M log2 M + cN (N + 2 pairs) + cS N P^3`.
//!
//! ```text
//! HYDRORATTLE_BENCH_MACHINE=<id> cargo run --release --example free_cost [-- [MIN_N:]MAX_N [--max-bytes BYTES] [SHAPE...]]
//! ```
//!
//! `SHAPE`s (`"cloud 0.01"`, `"cloud 0.1"`, `"cloud 0.3"`, `chain`) limit the run to
//! those; all four by default. A path's constants are fitted where the run timed it
//! at least as often as they number.
//!
//! Times are this thread's CPU seconds, best of two (`shared/best.rs`). With
//! `HYDRORATTLE_BENCH_MACHINE` set the rows go to `bench/results/free_cost.csv`
//! (measurements, then the constants); the chart `docs/free_crossover.png` is drawn from
//! them by `cargo run --release -p hydrorattle-study --example free_crossover`.

use hydrorattle::Real;
use hydrorattle::geometry::Geometry;
use hydrorattle::geometry::free::Free;
use hydrorattle::integrate::fast_parameters;
use hydrorattle::linalg::{cholesky, tri};
use hydrorattle::mobility::free_fast::{FreeError, FreeFast, transform_counts};
use hydrorattle::mobility::{Hydro, assemble_grand, tt_product};
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{Serial, assemble, band_scratch, product};
use hydrorattle_heap::FreeBuffers;

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
#[path = "shared/free_shapes.rs"]
mod free_shapes;
use free_shapes::{SHAPES, chain, cloud, extent, near_pairs};

/// Storage past which a path is not timed (bytes), unless `--max-bytes` says otherwise.
const MAX_BYTES: f64 = 4e8;
/// The largest count the matrix-free product is timed at.
const MAX_FREE: usize = 20_000;
/// The paths timed, in the order of their rows.
const NAMES: [&str; 14] = [
    "dense assembly",
    "dense product",
    "dense Cholesky",
    "compact copy",
    "compact product",
    "matrix-free product",
    "spin pass",
    "grand assembly",
    "fast product 1e-4",
    "fast product 1e-6",
    "fast grand-parameter product 1e-4",
    "fast grand-parameter product 1e-6",
    "fast grand product 1e-4",
    "fast grand product 1e-6",
];
/// The first fast path's index.
const FAST: usize = 8;
/// A call this long (CPU seconds) ends a path's counts for its shape: the `N^2` paths
/// (the next count, three times larger, takes nine times as long), then the fast ones.
fn max_call(k: usize) -> f64 {
    if k < FAST { 2.0 } else { 8.0 }
}

/// The timings of one path: its fit's rows of terms and times.
#[derive(Default, Clone)]
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

/// One timing of path `k`, kept unless it is past the bounds (its storage, or an
/// earlier call that took too long).
fn time(k: usize, bytes: f64, stopped: &mut [bool], f: &mut dyn FnMut()) -> Option<f64> {
    if stopped[k] || bytes > max_bytes() {
        stopped[k] = true;
        return None;
    }
    let t = best(2, &mut *f);
    stopped[k] = t > max_call(k);
    Some(t)
}

/// The storage bound of this run: `--max-bytes`, else [`MAX_BYTES`].
fn max_bytes() -> f64 {
    let args: Vec<String> = std::env::args().collect();
    let at = args.iter().position(|a| a == "--max-bytes");
    at.and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(MAX_BYTES)
}

/// The rows of one shape at one count: every path's time into `fits`, the cells to
/// `cell`. `all`: the stored paths too (else the matrix-free and fast ones alone).
fn measure(
    pos: &[V],
    all: bool,
    stopped: &mut [bool],
    fits: &mut [Fit],
    cell: &mut dyn FnMut(&str, String),
) {
    let n = pos.len();
    let rad = vec![1.0; n];
    let mut rng = Rng(5);
    let f: Vec<V> = (0..n)
        .map(|_| f64::v3_from([0, 1, 2].map(|_| 2.0 * rng.unit() - 1.0)))
        .collect();
    let mut y = vec![V::ZERO; n];
    let blocks = tri(n) as f64;
    // Path `k`'s time, where it was taken, as a cell and a row of its fit.
    let put = |k: usize,
               t: Option<f64>,
               x: Vec<f64>,
               fits: &mut [Fit],
               cell: &mut dyn FnMut(&str, String)| {
        if let Some(t) = t {
            cell(NAMES[k], format!("{t:.4e}"));
            fits[k].add(x, t);
        }
    };
    cell("packed blocks tri(N)", format!("{}", tri(n)));
    // The matrix-free product stores nothing: it runs past 1e4 too, to `MAX_FREE`.
    let bytes = if n <= MAX_FREE { 0.0 } else { f64::INFINITY };
    let t = time(5, bytes, stopped, &mut || {
        tt_product(Hydro::Rpy, 1.0, pos, &rad, &f, &mut y).unwrap();
    });
    put(5, t, vec![1.0, blocks], fits, cell);
    if all {
        let par = Serial;
        let stored = blocks * 72.0;
        let mut mu = vec![M::ZERO; if stored <= max_bytes() { tri(n) } else { 0 }];
        let mut z = vec![V::ZERO; band_scratch(n).max(1)];
        let t = time(0, stored, stopped, &mut || {
            assemble::<f64>(&par, Hydro::Rpy, 1.0, pos, &rad, &mut mu).unwrap();
        });
        put(0, t, vec![1.0, blocks], fits, cell);
        if t.is_some() {
            let t = time(1, stored, stopped, &mut || {
                product::<f64>(&par, &mu, n, &f, &mut y, &mut z);
            });
            put(1, t, vec![1.0, blocks], fits, cell);
            let mut l = if n <= 300 { mu.clone() } else { vec![] };
            let bytes = if n <= 300 { stored } else { f64::INFINITY };
            let t = time(2, bytes, stopped, &mut || {
                l.copy_from_slice(&mu);
                cholesky::<f64>(&mut l, n).unwrap();
            });
            put(2, t, vec![1.0, (n as f64).powi(3)], fits, cell);
            if reduced::usable::<f64>(n) {
                let mut copy = vec![M::ZERO; reduced::slots(n)];
                let t = time(3, stored, stopped, &mut || {
                    reduced::copy_apply::<f64>(&par, &mu, n, &mut copy, &f, &mut y, &mut z);
                });
                put(3, t, vec![1.0, blocks], fits, cell);
                let t = time(4, stored, stopped, &mut || {
                    reduced::apply::<f64>(&par, &copy, n, &f, &mut y, &mut z);
                });
                put(4, t, vec![1.0, blocks], fits, cell);
            }
        }
        drop(mu);
        let free = Free::new(Hydro::Rpy, 1.0);
        let t = time(6, 0.0, stopped, &mut || {
            free.add_spin(pos, &rad, &f, &mut y).unwrap();
        });
        put(6, t, vec![1.0, blocks], fits, cell);
        let grand = tri(2 * n) as f64;
        let mut g = vec![
            M::ZERO;
            if grand * 72.0 <= max_bytes() {
                tri(2 * n)
            } else {
                0
            }
        ];
        let t = time(7, grand * 72.0, stopped, &mut || {
            assemble_grand::<f64>(Hydro::Rpy, 1.0, pos, &rad, &mut g).unwrap();
        });
        put(7, t, vec![1.0, grand], fits, cell);
    }
    let torque = vec![V::ZERO; n];
    let mut spin = vec![V::ZERO; n];
    // Translation under each parameter rule; the grand rule's grand product beside it.
    for (k, tol, grand) in [
        (FAST, 1e-4, false),
        (FAST + 1, 1e-6, false),
        (FAST + 2, 1e-4, true),
        (FAST + 3, 1e-6, true),
    ] {
        let ext = extent(pos);
        let made = match grand {
            false => FreeFast::<f64>::new(1.0, tol, ext, n),
            true => FreeFast::<f64>::new_grand(1.0, tol, ext, n),
        };
        // Where the rule's grid passes its bounds (a long chain) a step widens the
        // spreading until one fits: time those parameters, as a run takes them.
        let made = match made {
            Err(FreeError::GridTooLarge) => fast_parameters(tol, grand, 1.0, ext, n),
            made => made,
        };
        let Ok(ff) = made else {
            cell(NAMES[k], "refused (grid past its bound)".into());
            continue;
        };
        let size = match grand {
            false => ff.storage(n),
            true => ff.storage_grand(n),
        };
        let bytes = FreeBuffers::<f64>::bytes_of(size) as f64;
        if stopped[k] || bytes > max_bytes() {
            stopped[k] = true;
            continue;
        }
        let mut arrays = FreeBuffers::<f64>::new(size);
        let mut store = arrays.storage();
        // The first product transforms the kernel; the step keeps it (steady state).
        ff.apply(1.0, pos, &rad, &f, &mut y, &mut store).unwrap();
        let Some(t) = time(k, bytes, stopped, &mut || {
            ff.apply(1.0, pos, &rad, &f, &mut y, &mut store).unwrap();
        }) else {
            continue;
        };
        let tg = grand
            .then(|| {
                time(k + 2, bytes, stopped, &mut || {
                    let fs = (pos, &rad[..]);
                    ff.apply_grand(1.0, fs, &f, &torque, &mut y, &mut spin, &mut store)
                        .unwrap();
                })
            })
            .flatten();
        let counts = transform_counts(&arrays.reals).expect("a transform is held");
        let g = ff.grid();
        let m = (g[0] * g[1] * g[2]) as f64;
        let p3 = ff.support().pow(3) as f64;
        let pairs = near_pairs(pos, ff.r_cut()) as f64;
        let terms = vec![1.0, m * m.log2(), n as f64 + 2.0 * pairs, n as f64 * p3];
        cell(NAMES[k], format!("{t:.4e}"));
        fits[k].add(terms.clone(), t);
        if let Some(tg) = tg {
            cell(NAMES[k + 2], format!("{tg:.4e}"));
            fits[k + 2].add(terms, tg);
        }
        let tag = NAMES[k].replace("product ", "");
        for (q, v) in [
            ("padded grid points M", format!("{m}")),
            ("window points P^3", format!("{p3}")),
            ("near pairs", format!("{pairs}")),
            ("cutoff r_c", format!("{:.4}", ff.r_cut())),
            ("storage bytes", format!("{bytes}")),
            ("transforms computed", format!("{}", counts.computed)),
        ] {
            cell(&format!("{tag}: {q}"), v);
        }
    }
}

fn main() -> std::io::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    // `--max-bytes BYTES` anywhere (read by `max_bytes`), named in the command.
    let bound = match args.iter().position(|a| a == "--max-bytes") {
        Some(i) => {
            let b = args.drain(i..(i + 2).min(args.len())).collect::<Vec<_>>();
            format!(" {}", b.join(" "))
        }
        None => String::new(),
    };
    let pick = free_shapes::Selection::new(&args);
    let (range, named) = (&pick.range, &pick.named);
    let mut rows = record::Recorder::new(
        env!("CARGO_MANIFEST_DIR"),
        "free_cost",
        format!("cargo run --release --example free_cost -- {range}{bound}{named}"),
    );
    let table = "free-space product paths, unit spheres, f64, one thread, CPU seconds a call \
                 (best of two; fast products with the kernel's transform kept)";
    let mut fits: Vec<Fit> = NAMES.iter().map(|_| Fit::default()).collect();
    for (shape, phi) in SHAPES {
        if !pick.shape(shape) {
            continue;
        }
        let mut stopped = [false; NAMES.len()];
        for n in pick.counts() {
            // Past 1e4 only the paths that store no mobility, on the cloud at 0.1.
            let all = n <= 10_000;
            if !all && shape != "cloud 0.1" {
                continue;
            }
            let pos = match phi {
                Some(phi) => cloud(n, phi, 11 + n as u64),
                None => chain(n),
            };
            let case = format!("{shape}, N = {n}");
            let mut cell = |q: &str, v: String| {
                println!("{case}: {q} {v}");
                rows.row(table, &case, q, &v);
            };
            measure(&pos, all, &mut stopped, &mut fits, &mut cell);
        }
    }
    // Translation shares one fast model over both tolerances and both parameter rules
    // (their terms carry them); the grand product its own over both tolerances.
    let join = |a: &Fit, b: &Fit| Fit {
        x: [&a.x[..], &b.x[..]].concat(),
        t: [&a.t[..], &b.t[..]].concat(),
    };
    let fast = join(
        &join(&fits[FAST], &fits[FAST + 1]),
        &join(&fits[FAST + 2], &fits[FAST + 3]),
    );
    let grand = join(&fits[FAST + 4], &fits[FAST + 5]);
    let fitted: [(&str, &Fit, &[&str]); 10] = [
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
        ("spin pass", &fits[6], &["SPIN_FIXED", "SPIN_BLOCK"]),
        (
            "grand assembly",
            &fits[7],
            &["GRAND_ASSEMBLY_FIXED", "GRAND_ASSEMBLY_BLOCK"],
        ),
        (
            "fast product",
            &fast,
            &["FAST_FIXED", "FAST_GRID", "FAST_NEAR", "FAST_SPREAD"],
        ),
        (
            "fast grand product",
            &grand,
            &["GRAND_FIXED", "GRAND_GRID", "GRAND_NEAR", "GRAND_SPREAD"],
        ),
    ];
    let model =
        "free-space cost model constants (seconds a call per term), fitted to this run's rows";
    for (path, data, consts) in fitted {
        // Fewer rows than constants (a run over a few counts) fix no fit.
        if data.t.len() < consts.len() {
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
