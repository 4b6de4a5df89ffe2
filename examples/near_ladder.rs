//! The model ladder's speed and accuracy: free draining, Oseen, RPY, and RPY with
//! Stokesian dynamics' near field (`Params::near`), dense and iterative
//! (`Params::matrix_free`). f64, one core. Modes:
//!
//! * `near_ladder chain [steps]` (default 20): each rung's error against exact values
//!   nobody here computed, from one `Overdamped` step of the kernel (unit spheres, unit
//!   fluid, unit buoyant weight): two equal spheres at the Figure 1 chain's bead gap
//!   (`s = 2.1`, bond `D = 1.05` diameters) falling along their line of centres
//!   (Stimson and Jeffery: 1.53633 `U0`) and side by side (1.3917 `U0`, each spinning at
//!   0.137 `U0 / a`), and a sphere at `h / a = 1.1` approaching the wall (Brenner:
//!   0.087266 `U0`); and the cost of a step of the Figure 1 (c) chain (a head of radius 2
//!   and 24 tails, settling from its helix, `dt = 0.1`; the mean over `steps` steps)
//!   twice: as the paper steps it (`Overdamped2`, Newton, hard contacts), and as
//!   every rung steps it (`Overdamped`, Krylov, rotation,
//!   no contacts), with the iterative rung's distance from the dense one's positions;
//!   with their counts: mobilities formed, pairs inside the near field's cutoff, dense
//!   flops.
//! * `near_ladder box N [near|iter|both]`: the cost of one `Overdamped` step of `N`
//!   spheres in a periodic box (volume fraction 0.25, radii 0.8 to 1.2) at each
//!   far-field rung, and with `near` the dense near-field step too (minutes at
//!   `N = 1000`), with `iter` the iterative one and its counts: close pairs,
//!   conjugate-gradient iterations, far-field products; `both` runs the two and records
//!   the iterative step's velocities against the dense step's.
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
/// The near field of a rung.
#[derive(Clone, Copy, PartialEq)]
enum Near {
    Off,
    /// `M_SD` formed and inverted (`Params::near`).
    Dense,
    /// Products of `M_SD` by conjugate gradients (`Params::near` and `matrix_free`).
    Iterative,
}

/// The rungs: name, far field, near field.
const RUNGS: [(&str, Hydro, Near); 5] = [
    ("free-draining", Hydro::FreeDraining, Near::Off),
    ("oseen", Hydro::Oseen, Near::Off),
    ("rpy", Hydro::Rpy, Near::Off),
    ("rpy+near", Hydro::Rpy, Near::Dense),
    ("rpy+near iterative", Hydro::Rpy, Near::Iterative),
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
/// The chain as every rung steps it (the chart's chain panel).
const CHAIN_KRYLOV: &str =
    "model ladder, Figure 1 (c) chain, Overdamped, Krylov, rotation, no contacts, f64, one core";
const WORK: &str = "near field's own work, box at volume fraction 0.25, f64, one core";

fn box_table(n: usize) -> String {
    format!("model ladder, {n} spheres in a box at volume fraction 0.25, f64, one core")
}

/// Parameters of a rung.
fn params(level: Hydro, near: Near, dt: f64) -> Params<f64> {
    let mut p = Params::new(dt);
    p.method = Method::Overdamped;
    p.hydro = level;
    p.near = (near != Near::Off).then(NearField::default);
    p.matrix_free = near == Near::Iterative;
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
fn accuracy(level: Hydro, near: Near) -> [Result<f64, String>; 4] {
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

/// A chain step's cost: seconds a step, `M_SD` formed a step, the start's positions and
/// radii, the end's positions.
struct ChainCost {
    per_step: f64,
    formed: f64,
    start: Vec<DVec3>,
    radii: Vec<f64>,
    end: Vec<DVec3>,
}

/// `steps` steps of the Figure 1 (c) chain at a rung: as the paper steps it (`paper`:
/// `Overdamped2`, Newton, hard contacts) or as every rung can (`Overdamped`, Krylov,
/// rotation, no contacts). `Err` where the kernel refuses it.
fn chain_cost(level: Hydro, near: Near, steps: usize, paper: bool) -> Result<ChainCost, String> {
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
    p.allow_overlap = true;
    if paper {
        p.method = Method::Overdamped2;
        p.solver.kind = SolverKind::Newton;
        p.contacts = Some(Contacts::new(4 * 25));
    } else {
        p.solver.kind = SolverKind::Krylov;
        p.solver.tolerance = 1e-10;
        p.rotation = true;
    }
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 25, 24));
    let mut ws = buf.workspace();
    let (t, mut formed) = (Instant::now(), 0);
    for k in 0..steps {
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .map_err(|e| format!("refused: {e} (step {k})"))?;
        formed += r.near_formations;
    }
    let per = steps as f64;
    Ok(ChainCost {
        per_step: t.elapsed().as_secs_f64() / per,
        formed: formed as f64 / per,
        start,
        radii,
        end: ps.pos[..25].to_vec(),
    })
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
    println!("chain,rung,step_s,formed_a_step,pairs_in_cutoff,dense_flops_a_step");
    for (table, paper) in [(CHAIN, true), (CHAIN_KRYLOV, false)] {
        let mut dense_end = None;
        for (name, level, near) in RUNGS {
            let c = match chain_cost(level, near, steps, paper) {
                Ok(c) => c,
                Err(e) => {
                    println!("{paper},{name},{e}");
                    rec.row(table, name, "s a step", &e);
                    continue;
                }
            };
            let pairs = match near {
                Near::Off => 0,
                _ => close_pairs(Far::FREE, &c.start, &c.radii),
            };
            // Each formation: two `spd_inverse` of `6N x 6N`, about `2/3 m^3` flops each.
            let m = 6.0 * c.start.len() as f64;
            let flops = c.formed * 2.0 * (2.0 / 3.0) * m * m * m;
            println!(
                "{paper},{name},{:.3e},{},{pairs},{flops:.3e}",
                c.per_step, c.formed
            );
            rec.row(table, name, "s a step", &format!("{:.3e}", c.per_step));
            if near == Near::Off {
                continue;
            }
            let counts = [
                ("M_SD formed a step", c.formed.to_string()),
                ("pairs inside the cutoff (start)", pairs.to_string()),
                ("dense inversion flops a step", format!("{flops:.3e}")),
            ];
            for (quantity, value) in counts {
                rec.row(table, name, quantity, &value);
            }
            match (near, &dense_end) {
                (Near::Dense, _) => dense_end = Some((c.start, c.end)),
                (Near::Iterative, Some((start, end))) => {
                    // How far the iterative chain ends from the dense one, against the
                    // distance the dense chain's head fell.
                    let apart = (0..25).map(|i| (c.end[i] - end[i]).length());
                    let apart = apart.fold(0.0, f64::max) / (start[0] - end[0]).length();
                    println!("{paper},{name},apart from the dense step,{apart:.3e}");
                    let q = "largest distance from the dense step's beads, over the head's fall";
                    rec.row(table, name, q, &format!("{apart:.3e}"));
                }
                _ => {}
            }
        }
    }
}

/// One `Overdamped` step of the suspension of `n` spheres in its box at each rung; the
/// near field's rungs as `near_mode` says: `near` (dense), `iter` (iterative), `both`.
fn box_cost(n: usize, near_mode: &str, rec: &mut record::Recorder) {
    let both = near_mode == "both";
    let (with_dense, with_iter) = (both || near_mode == "near", both || near_mode == "iter");
    let (pos, rad, l) = suspension::suspension(n, 0.25);
    let table = box_table(n);
    let cell = Periodic::new([l; 3]).expect("box");
    let ew = Ewald::new(cell, 1.2).expect("sums");
    let pairs = close_pairs(Far::periodic(&ew), &pos, &rad);
    println!("N = {n}, edge {l:.3}, {pairs} pairs inside the cutoff");
    println!("rung,step_s");
    let mut dense_vel: Option<Vec<DVec3>> = None;
    for (name, level, near) in RUNGS {
        if (near == Near::Dense && !with_dense) || (near == Near::Iterative && !with_iter) {
            continue;
        }
        let mut p = params(level, near, 1e-4);
        p.periodic = Some(cell);
        let list: Vec<Particle<f64>> = (0..n)
            .map(|i| Particle::new(pos[i], rad[i], RHO1))
            .collect();
        let mut ps = ParticleSet::<f64, 2000>::from_slice(&list, false).expect("spheres");
        let bonds = BondSet::<f64, 1>::new();
        let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
        let mut ws = buf.workspace();
        let t = Instant::now();
        let value = match step(&mut ps, &bonds, &p, &mut ws, &mut NoForce) {
            Ok(r) if near == Near::Iterative => {
                let t = format!("{:.3e}", t.elapsed().as_secs_f64());
                let counts = [
                    ("close pairs corrected", r.near_pairs),
                    ("conjugate-gradient iterations", r.near_iterations),
                    (
                        "far-field products",
                        r.near_iterations + 2 * r.near_products,
                    ),
                ];
                for (quantity, k) in counts {
                    println!("{name},{quantity},{k}");
                    rec.row(&table, name, quantity, &k.to_string());
                }
                if let Some(dense) = &dense_vel {
                    // The iterative step's velocities against the dense step's.
                    let big = dense.iter().map(|v| v.length()).fold(0.0, f64::max);
                    let diff = (0..n).map(|i| (ps.vel[i] - dense[i]).length());
                    let rel = diff.fold(0.0, f64::max) / big;
                    println!("{name},velocities against the dense step,{rel:.3e}");
                    let q = "largest velocity difference from the dense step, over the largest velocity";
                    rec.row(&table, name, q, &format!("{rel:.3e}"));
                }
                t
            }
            Ok(_) => {
                if near == Near::Dense {
                    dense_vel = Some(ps.vel[..n].to_vec());
                }
                format!("{:.3e}", t.elapsed().as_secs_f64())
            }
            Err(e) => format!("refused: {e}"),
        };
        println!("{name},{value}");
        rec.row(&table, name, "s a step", &value);
    }
    rec.row(&table, "all", "pairs inside the cutoff", &pairs.to_string());
    if with_iter {
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
