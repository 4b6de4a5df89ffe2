//! The model ladder's speed and accuracy: free draining, Oseen, RPY, and RPY with
//! Stokesian dynamics' near field (`Params::near`). f64, one core. Modes:
//!
//! * `near_ladder chain [steps]` (default 20): each rung's error against exact values
//!   nobody here computed, from one `Overdamped` step of the kernel (unit spheres, unit
//!   fluid, unit buoyant weight): two equal spheres at the Figure 1 chain's bead gap
//!   (`s = 2.1`, bond `D = 1.05` diameters) falling along their line of centres
//!   (Stimson and Jeffery: 1.53633 `U0`) and side by side (1.3917 `U0`, each spinning at
//!   0.137 `U0 / a`), and a sphere at `h / a = 1.1` approaching the wall (Brenner:
//!   0.087266 `U0`); and the cost of a step of the Figure 1 (c) chain (a head of radius 2
//!   and 24 tails, settling from its helix: `Overdamped2`, Newton, hard contacts,
//!   `dt = 0.1`; the mean over `steps` steps), with its counts: mobilities formed, pairs
//!   inside the near field's cutoff, dense flops.
//! * `near_ladder box N [near|iter]`: the cost of one `Overdamped` step of `N` spheres
//!   in a periodic box (volume fraction 0.25, radii 0.8 to 1.2) at each far-field rung,
//!   and with `near` the dense near-field step too (minutes at `N = 1000`), with `iter`
//!   the iterative one (`Params::matrix_free`) and its counts: close pairs, conjugate-
//!   gradient iterations, far-field products.
//! * `near_ladder work N ...`: the near field's own work in that box: the pairs inside
//!   the cutoff (found through the cell list) and the seconds to find them and form each
//!   pair's correction `R_near`.
//! * `near_ladder chart`: `docs/near_ladder.svg` from the latest records of
//!   `bench/results/near_ladder.csv`.
//!
//! Measuring modes print CSV and, where `HYDRORATTLE_BENCH_MACHINE` names the machine,
//! append records to `bench/results/near_ladder.csv`.

use std::time::Instant;

#[path = "shared/ladder_chart.rs"]
mod chart;
#[path = "shared/record.rs"]
mod record;
#[path = "shared/suspension.rs"]
mod suspension;
#[path = "shared/svg.rs"]
mod svg;

use glam::DVec3;
use hydrorattle::cell::Periodic;
use hydrorattle::helix::{HeadEnd, Helix};
use hydrorattle::mobility::periodic::Ewald;
use hydrorattle::stokesian::iterative::count_pairs;
use hydrorattle::stokesian::{Far, NearField, pair_correction};
use hydrorattle::{
    BondSet, Contacts, Hydro, Layout, Method, NoForce, Params, Particle, ParticleSet, SolverKind,
    Wall, step,
};
use hydrorattle_heap::Buffers;

/// Stokes' speed of the unit sphere of unit buoyant weight in the unit fluid.
const U0: f64 = 1.0 / (6.0 * std::f64::consts::PI);
/// Density of unit buoyant weight for a unit sphere (`g = 1`).
const RHO1: f64 = 3.0 / (4.0 * std::f64::consts::PI);
/// The rungs: name, far field, near field.
const RUNGS: [(&str, Hydro, bool); 4] = [
    ("free-draining", Hydro::FreeDraining, false),
    ("oseen", Hydro::Oseen, false),
    ("rpy", Hydro::Rpy, false),
    ("rpy+near", Hydro::Rpy, true),
];
/// The accuracy checks: record quantity, short label, exact value.
const EXACT: [(&str, &str, f64); 4] = [
    ("along, U0 (s = 2.1)", "along", 1.53633),
    ("across, U0 (s = 2.1)", "across", 1.3917),
    ("spin, U0/a (s = 2.1)", "spin", 0.137),
    ("wall approach, U0 (h/a = 1.1)", "wall", 0.087266),
];
const ACCURACY: &str = "model ladder, one step against exact values, f64";
const CHAIN: &str = "model ladder, Figure 1 (c) chain, f64, one core";
const WORK: &str = "near field's own work, box at volume fraction 0.25, f64, one core";

fn box_table(n: usize) -> String {
    format!("model ladder, {n} spheres in a box at volume fraction 0.25, f64, one core")
}

/// Parameters of a rung.
fn params(level: Hydro, near: bool, dt: f64) -> Params<f64> {
    let mut p = Params::new(dt);
    p.method = Method::Overdamped;
    p.hydro = level;
    p.near = near.then(NearField::default);
    p
}

/// One step of `spheres` (centre, radius; unit buoyant weight each at radius 1) under
/// `p`: velocities and spins, in `U0` and `U0 / a`.
fn one_step<const N: usize>(
    p: &Params<f64>,
    spheres: &[(DVec3, f64)],
) -> Result<(Vec<DVec3>, Vec<DVec3>), String> {
    let list: Vec<Particle<f64>> = spheres
        .iter()
        .map(|&(c, a)| Particle::new(c, a, RHO1))
        .collect();
    let mut ps = ParticleSet::<f64, N>::from_slice(&list, false).map_err(|e| e.to_string())?;
    let bonds = BondSet::<f64, N>::new();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, list.len(), 0));
    let mut ws = buf.workspace();
    step(&mut ps, &bonds, p, &mut ws, &mut NoForce).map_err(|e| e.to_string())?;
    let n = list.len();
    let v = ps.vel[..n].iter().map(|&v| v / U0).collect();
    let w = ps.omega[..n].iter().map(|&w| w / U0).collect();
    Ok((v, w))
}

/// The rung's values of [`EXACT`] (`Err` where the kernel refuses the case).
fn accuracy(level: Hydro, near: bool) -> [Result<f64, String>; 4] {
    let mut p = params(level, near, 1e-3);
    p.rotation = true;
    let pair = |e: DVec3| [(-1.05 * e, 1.0), (1.05 * e, 1.0)];
    let along = one_step::<2>(&p, &pair(DVec3::Z)).map(|(v, _)| -v[0].z);
    let side = one_step::<2>(&p, &pair(DVec3::X));
    let across = side.clone().map(|(v, _)| -v[0].z);
    let spin = side.map(|(_, w)| w[0].length());
    p.wall = Some(Wall::new(0.0));
    let wall = one_step::<1>(&p, &[(DVec3::new(0.0, 0.0, 1.1), 1.0)]).map(|(v, _)| -v[0].z);
    [along, across, spin, wall]
}

/// Seconds per step of the Figure 1 (c) chain at `level` (with the near field if
/// `near`), over `steps` steps, and the `M_SD` formed a step.
fn chain_cost(level: Hydro, near: bool, steps: usize) -> (f64, f64, Vec<DVec3>, Vec<f64>) {
    let h = Helix {
        tails: 24,
        head_ratio: 2.0,
        dhat: 1.05,
        radius: 2.0,
        pitch: 7.0,
        head_end: HeadEnd::Bottom,
    };
    let list: Vec<Particle<f64>> = h
        .positions()
        .expect("helix")
        .enumerate()
        .map(|(k, p)| Particle::new(DVec3::from_array(p), h.bead_radius(k), 4.5))
        .collect();
    let start: Vec<DVec3> = list.iter().map(|q| q.position).collect();
    let radii: Vec<f64> = list.iter().map(|q| q.radius).collect();
    let mut ps = ParticleSet::<f64, 25>::from_slice(&list, true).expect("chain");
    let bonds = BondSet::<f64, 24>::chain(&ps.pos[..25]).expect("bonds");
    let mut p = params(level, near, 0.1);
    p.method = Method::Overdamped2;
    p.solver.kind = SolverKind::Newton;
    p.allow_overlap = true;
    p.contacts = Some(Contacts::new(4 * 25));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 25, 24));
    let mut ws = buf.workspace();
    let (t, mut formed) = (Instant::now(), 0);
    for k in 0..steps {
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("{level:?} near {near}: step {k}: {e}"));
        formed += r.near_formations;
    }
    let per = steps as f64;
    (
        t.elapsed().as_secs_f64() / per,
        formed as f64 / per,
        start,
        radii,
    )
}

/// Pairs inside the default cutoff (the minimum image in the box).
fn close_pairs(far: Far<'_, f64>, pos: &[DVec3], rad: &[f64]) -> usize {
    let mut cells = vec![0; 3 * pos.len() + 1];
    count_pairs(far, pos, rad, NearField::default(), &mut cells).expect("pairs")
}

fn chain(steps: usize, rec: &mut record::Recorder) {
    println!("rung,quantity,value,exact,relative_error");
    for (name, level, near) in RUNGS {
        for ((quantity, _, exact), got) in EXACT.iter().zip(accuracy(level, near)) {
            match got {
                Ok(v) => {
                    let e = v / exact - 1.0;
                    println!("{name},{quantity},{v:.6},{exact},{e:+.3e}");
                    rec.row(ACCURACY, name, quantity, &format!("{v:.6}"));
                    let q = format!("{quantity}, relative error");
                    rec.row(ACCURACY, name, &q, &format!("{e:+.3e}"));
                }
                Err(e) => {
                    println!("{name},{quantity},refused,{exact},");
                    rec.row(ACCURACY, name, quantity, &format!("refused: {e}"));
                }
            }
        }
    }
    println!("rung,step_s,formed_a_step,pairs_in_cutoff,dense_flops_a_step");
    for (name, level, near) in RUNGS {
        let (cost, formed, pos, rad) = chain_cost(level, near, steps);
        let pairs = if near {
            close_pairs(Far::FREE, &pos, &rad)
        } else {
            0
        };
        // Each formation: two `spd_inverse` of `6N x 6N`, about `2/3 m^3` flops each.
        let m = 6.0 * pos.len() as f64;
        let flops = formed * 2.0 * (2.0 / 3.0) * m * m * m;
        println!("{name},{cost:.3e},{formed},{pairs},{flops:.3e}");
        rec.row(CHAIN, name, "s a step", &format!("{cost:.3e}"));
        if near {
            rec.row(CHAIN, name, "M_SD formed a step", &format!("{formed}"));
            rec.row(
                CHAIN,
                name,
                "pairs inside the cutoff (start)",
                &pairs.to_string(),
            );
            rec.row(
                CHAIN,
                name,
                "dense inversion flops a step",
                &format!("{flops:.3e}"),
            );
        }
    }
}

/// One `Overdamped` step of the suspension of `n` spheres in its box at each rung; the
/// near field's rung dense (`near = "near"`), iterative (`"iter"`) or left out.
fn box_cost(n: usize, near_mode: &str, rec: &mut record::Recorder) {
    let (with_near, iterative) = (near_mode == "near", near_mode == "iter");
    let (pos, rad, l) = suspension::suspension(n, 0.25);
    let table = box_table(n);
    let cell = Periodic::new([l; 3]).expect("box");
    let ew = Ewald::new(cell, 1.2).expect("sums");
    let pairs = close_pairs(Far::periodic(&ew), &pos, &rad);
    println!("N = {n}, edge {l:.3}, {pairs} pairs inside the cutoff");
    println!("rung,step_s");
    for (name, level, near) in RUNGS {
        if near && !(with_near || iterative) {
            continue;
        }
        let mut p = params(level, near, 1e-4);
        p.periodic = Some(cell);
        p.matrix_free = near && iterative;
        let name = match p.matrix_free {
            true => "rpy+near iterative",
            false => name,
        };
        let list: Vec<Particle<f64>> = (0..n)
            .map(|i| Particle::new(pos[i], rad[i], RHO1))
            .collect();
        let mut ps = ParticleSet::<f64, 2000>::from_slice(&list, false).expect("spheres");
        let bonds = BondSet::<f64, 1>::new();
        let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
        let mut ws = buf.workspace();
        let t = Instant::now();
        let value = match step(&mut ps, &bonds, &p, &mut ws, &mut NoForce) {
            Ok(r) if p.matrix_free => {
                let counts = [
                    ("close pairs corrected", r.near_pairs),
                    ("conjugate-gradient iterations", r.near_iterations),
                    (
                        "far-field products",
                        r.near_iterations + 2 * r.near_products,
                    ),
                ];
                let t = format!("{:.3e}", t.elapsed().as_secs_f64());
                for (quantity, k) in counts {
                    println!("{name},{quantity},{k}");
                    rec.row(&table, name, quantity, &k.to_string());
                }
                t
            }
            Ok(_) => format!("{:.3e}", t.elapsed().as_secs_f64()),
            Err(e) => format!("refused: {e}"),
        };
        println!("{name},{value}");
        rec.row(&table, name, "s a step", &value);
    }
    rec.row(&table, "all", "pairs inside the cutoff", &pairs.to_string());
    if iterative {
        // The iterative step's far field alone: the Ewald grand mobility's assembly.
        let mut packed = vec![glam::DMat3::ZERO; 2 * n * (2 * n + 1) / 2];
        let t = Instant::now();
        Far::periodic(&ew)
            .assemble_grand(1.0, &pos, &rad, &mut packed)
            .expect("grand mobility");
        let value = format!("{:.3e}", t.elapsed().as_secs_f64());
        println!("grand mobility assembly,{value}");
        rec.row(
            &table,
            "rpy+near iterative",
            "s to assemble the grand mobility",
            &value,
        );
    }
}

/// The near field's own work at each `n`: pairs inside the cutoff, and the seconds to
/// find them (cell list) and form each one's correction.
fn work(sizes: &[usize], rec: &mut record::Recorder) {
    println!("N,pairs,find_s,correct_s,us_a_pair");
    for &n in sizes {
        let (pos, rad, l) = suspension::suspension(n, 0.25);
        let ew = Ewald::new(Periodic::new([l; 3]).expect("box"), 1.2).expect("sums");
        let far = Far::periodic(&ew);
        let t = Instant::now();
        let pairs = close_pairs(far, &pos, &rad);
        let find = t.elapsed().as_secs_f64();
        // Every pair's correction (the all-pairs loop stands in for the cell list's
        // visit order: only pairs inside the cutoff are corrected, and timed).
        let list: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .filter(|&(i, j)| {
                let d = far.separation(pos[i], pos[j]).length() * 2.0 / (rad[i] + rad[j]);
                d - 2.0 < NearField::<f64>::default().cutoff
            })
            .collect();
        assert_eq!(list.len(), pairs);
        let t = Instant::now();
        let mut sum = 0.0;
        for &ij in &list {
            let c = pair_correction(1.0, far, &pos, &rad, NearField::default(), ij);
            sum += c.expect("pair").map_or(0.0, |c| c[0][0].x_axis.x);
        }
        let correct = t.elapsed().as_secs_f64();
        let us = correct / pairs as f64 * 1e6;
        println!("{n},{pairs},{find:.3e},{correct:.3e},{us:.2} ({sum:.3e})");
        let case = format!("N = {n}");
        rec.row(WORK, &case, "pairs inside the cutoff", &pairs.to_string());
        rec.row(
            WORK,
            &case,
            "s to find them (cell list)",
            &format!("{find:.3e}"),
        );
        rec.row(
            WORK,
            &case,
            "s to form their corrections",
            &format!("{correct:.3e}"),
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map_or("chain", |s| s.as_str());
    if mode == "chart" {
        let root = env!("CARGO_MANIFEST_DIR");
        let records = std::fs::read_to_string(format!("{root}/bench/results/near_ladder.csv"))
            .expect("bench/results/near_ladder.csv");
        let svg = chart::draw(&records);
        std::fs::write(format!("{root}/docs/near_ladder.svg"), svg).expect("docs/near_ladder.svg");
        return;
    }
    let command = format!("target/release/examples/near_ladder {}", args.join(" "));
    let mut rec = record::Recorder::new(env!("CARGO_MANIFEST_DIR"), "near_ladder", command);
    let num = |k: usize, d: usize| args.get(k).map_or(d, |s| s.parse().expect("a number"));
    match mode {
        "chain" => chain(num(1, 20), &mut rec),
        "box" => box_cost(
            num(1, 1000),
            args.get(2).map_or("", |s| s.as_str()),
            &mut rec,
        ),
        "work" => {
            let sizes: Vec<usize> = args[1..].iter().map(|s| s.parse().expect("N")).collect();
            work(&sizes, &mut rec)
        }
        _ => panic!("mode: chain, box, work or chart"),
    }
    rec.finish().expect("appending the records");
}
