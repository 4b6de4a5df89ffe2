//! The cost of a Brownian step with the iterative near field (`Params::near` with
//! `Params::matrix_free` and `Params::brownian`) against the deterministic one, and the
//! noise's two ways counted: the far field's Lanczos root with the close pairs' factors
//! and one solve (what the kernel does), and a Lanczos root of `M_SD,tt` itself, each
//! of whose iterations is one conjugate-gradient solve. f64, one core.
//!
//! `near_brownian N ...`: `N` spheres in a periodic box at volume fraction 0.25 (radii
//! 0.8 to 1.2, `examples/shared/suspension.rs`), one `Overdamped` step each way (kT = 1,
//! the midpoint drift, `dt = 1e-4`), then the root of `M_SD,tt` on the same
//! configuration (Lanczos at the kernel's default tolerance, `1e-3`, and with the
//! inverse root the midpoint needs). Prints CSV; with `HYDRORATTLE_BENCH_MACHINE` set,
//! appends records to `bench/results/near_brownian.csv`.

use std::time::Instant;

#[path = "shared/record.rs"]
mod record;
#[path = "shared/suspension.rs"]
mod suspension;

use glam::{DMat3, DVec3};
use hydrorattle::cell::Periodic;
use hydrorattle::mobility::periodic::Ewald;
use hydrorattle::noise::lanczos::{self, Lanczos};
use hydrorattle::stokesian::iterative::{Solver, Storage, count_pairs, packed_product, sizes};
use hydrorattle::stokesian::{Far, NearField};
use hydrorattle::{
    BondSet, Brownian, Layout, Method, NoForce, Noise, Params, Particle, ParticleSet, step,
};
use hydrorattle_heap::Buffers;

fn table(n: usize) -> String {
    format!("iterative near field, {n} spheres in a box at volume fraction 0.25, f64, one core")
}

/// One step of the suspension, deterministic or at `kT = 1`: seconds and the report.
fn one_step(
    n: usize,
    (pos, rad, l): (&[DVec3], &[f64], f64),
    thermal: bool,
) -> (f64, hydrorattle::StepReport<f64>) {
    let mut p = Params::new(1e-4);
    p.method = Method::Overdamped;
    p.near = Some(NearField::default());
    p.matrix_free = true;
    p.rotation = true;
    p.allow_overlap = true;
    p.periodic = Some(Periodic::new([l; 3]).expect("box"));
    if thermal {
        p.gravity = DVec3::ZERO;
        p.brownian = Some(Brownian::new(1.0));
    }
    let list: Vec<Particle<f64>> = (0..n).map(|i| Particle::new(pos[i], rad[i], 1.0)).collect();
    let mut ps = ParticleSet::<f64, 2000>::from_slice(&list, false).expect("spheres");
    ps.noise = Some(Noise::new(1));
    let bonds = BondSet::<f64, 1>::new();
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
    let mut ws = buf.workspace();
    let t = Instant::now();
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).expect("step");
    (t.elapsed().as_secs_f64(), r)
}

/// A Lanczos root (and inverse root) of `M_SD,tt` on the suspension: its iterations,
/// the conjugate-gradient iterations of all its solves, and the seconds after the
/// far field's assembly (its error where it does not converge within the default 64
/// iterations).
fn root_of_msd(
    n: usize,
    (pos, rad, l): (&[DVec3], &[f64], f64),
) -> (Result<u32, String>, u32, f64) {
    let ew = Ewald::new(Periodic::new([l; 3]).expect("box"), 1.2).expect("sums");
    let far = Far::periodic(&ew);
    let nf = NearField::default();
    let mut packed = vec![DMat3::ZERO; 2 * n * (2 * n + 1) / 2];
    far.assemble_grand(1.0, pos, rad, &mut packed)
        .expect("grand mobility");
    let mut cells = vec![0; 3 * n + 1];
    let np = count_pairs(far, pos, rad, nf, &mut cells).expect("pairs");
    let (k, reals, vectors, indices) = sizes(n, np);
    let (mut pairs, mut reals) = (vec![[0; 2]; k], vec![0.0; reals]);
    let (mut field, mut cells) = (vec![DVec3::ZERO; vectors], vec![0; indices]);
    let storage = Storage {
        pairs: &mut pairs,
        reals: &mut reals,
        field: &mut field,
        cells: &mut cells,
    };
    let mut solver = Solver::new(1.0, far, pos, rad, nf, storage).expect("factors");
    let t = Instant::now();
    let (mut fin, mut out) = (vec![DVec3::ZERO; 2 * n], vec![DVec3::ZERO; 2 * n]);
    let mut cg = 0;
    let product = |v: &[DVec3], w: &mut [DVec3]| {
        fin[..n].copy_from_slice(v);
        let mut grand = |x: &[DVec3], y: &mut [DVec3]| {
            packed_product::<f64>(&packed, n, x, y);
            Ok(())
        };
        let r = solver
            .product(&mut grand, &fin, &mut out, 1e-10, 1000)
            .expect("solve");
        cg += r.iterations;
        w.copy_from_slice(&out[..n]);
    };
    let s = Lanczos::<f64>::default();
    let cap = s.max_iterations as usize;
    let mut z = vec![DVec3::ZERO; n];
    Noise::new(2).fill::<f64>(&mut z);
    let mut basis = vec![DVec3::ZERO; lanczos::vectors(cap, n)];
    let mut work = vec![0.0; lanczos::scalars(cap)];
    let (mut root, mut inv) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let it = lanczos::sqrt(
        s,
        product,
        &z,
        &mut basis,
        &mut work,
        &mut root,
        Some(&mut inv),
    )
    .map_err(|e| e.to_string());
    (it, cg, t.elapsed().as_secs_f64())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let command = format!("target/release/examples/near_brownian {}", args.join(" "));
    let mut rec = record::Recorder::new(env!("CARGO_MANIFEST_DIR"), "near_brownian", command);
    println!("N,case,quantity,value");
    for a in &args {
        let n: usize = a.parse().expect("N");
        let (pos, rad, l) = suspension::suspension(n, 0.25);
        let t = table(n);
        let mut out = |case: &str, quantity: &str, value: String| {
            println!("{n},{case},{quantity},{value}");
            rec.row(&t, case, quantity, &value);
        };
        for (case, thermal) in [("deterministic", false), ("Brownian", true)] {
            let (secs, r) = one_step(n, (&pos, &rad, l), thermal);
            out(case, "s a step", format!("{secs:.3e}"));
            out(case, "close pairs", r.near_pairs.to_string());
            out(case, "products", r.near_products.to_string());
            out(
                case,
                "conjugate-gradient iterations",
                r.near_iterations.to_string(),
            );
            out(
                case,
                "far-field Lanczos iterations",
                r.noise_iterations.to_string(),
            );
        }
        let (it, cg, secs) = root_of_msd(n, (&pos, &rad, l));
        let case = "Lanczos root of M_SD,tt (not run by the kernel)";
        let it = it.map_or_else(|e| format!("not converged: {e}"), |k| k.to_string());
        out(case, "Lanczos iterations (products)", it);
        out(case, "conjugate-gradient iterations", cg.to_string());
        out(
            case,
            "s after the far field's assembly",
            format!("{secs:.3e}"),
        );
    }
    rec.finish().expect("appending the records");
}
