//! Brownian steps on the PSE path (`Params::pse`): the step's noise is PSE's own (`Pse::noise_in`: the real part by Lanczos
//! on the near field, the wave part from white noise on the grid; the Fixman midpoint's
//! `M^-1 L w` by conjugate gradients with PSE products). Checked against values not
//! from the PSE code:
//!
//! * the step's displacement covariance against the Ewald path's assembled mobility
//!   (`2 kT dt M`, dense sums to rounding, themselves checked against Hasimoto in
//!   `tests/kernel/periodic.rs`), entry by entry and in its trace, with both drifts;
//! * a lone sphere's diffusion coefficient in cubic boxes against Hasimoto's
//!   `1 - 2.8372974794806 a/L + (4 pi/3)(a/L)^3` (the constant written here).
//!
//! `cargo test --release --test kernel pse_brownian:: -- --nocapture` (about 20 s of CPU, 45 s
//! on the loaded 2 cores);
//! the longer Hasimoto run with `-- --ignored`.

use crate::common;

use common::boxes::{config_radii, to_t};
use common::thermal::*;
use common::*;
use hydrorattle::integrate::pse_storage;
use hydrorattle::linalg::{sym_get, tri};
use hydrorattle::mobility::periodic::{Ewald, assemble_tt};
use hydrorattle::{
    BondSet, Drift, Hydro, Layout, NoForce, Noise, Params, ParticleSet, Periodic, Real, StepError,
};
use hydrorattle_heap::{Buffers, PseBuffers};
use std::f64::consts::PI;

/// Hasimoto (1959): `D(L) / D0` of a sphere in a simple cubic array at `x = a/L`.
fn hasimoto(x: f64) -> f64 {
    1.0 - 2.8372974794806 * x + 4.0 * PI / 3.0 * x.powi(3)
}

/// PSE's arrays for steps of `p` over `radius`.
fn arrays(p: &Params<f64>, radius: &[f64]) -> PseBuffers<f64> {
    PseBuffers::new(pse_storage(p, radius).unwrap().expect("a PSE step"))
}

/// `draws` steps of `p` from the same configuration `s` (reset before each), the
/// generator carried on: each step's displacement, flattened.
fn displacements<const M: usize>(
    s: &[Sphere],
    p: &Params<f64>,
    seed: u64,
    draws: usize,
) -> Vec<Vec<f64>> {
    let mut ps: ParticleSet<f64, M> = particles_overlapping(s);
    let radius: Vec<f64> = s.iter().map(|x| x.radius).collect();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, s.len(), 0));
    let mut arrays = arrays(p, &radius);
    let mut ws = arrays.attach(buf.workspace());
    let bonds = BondSet::<f64, 0>::new();
    let mut noise = Noise::new(seed);
    let start = ps.pos;
    (0..draws)
        .map(|k| {
            ps.pos = start;
            step_thermal(&mut ps, &bonds, p, &mut ws, &mut NoForce, &mut noise)
                .unwrap_or_else(|e| panic!("draw {k}: {e}"));
            (0..s.len())
                .flat_map(|i| sub(f64s::<f64>(ps.pos[i]), f64s::<f64>(start[i])))
                .collect()
        })
        .collect()
}

/// A particle set that may hold overlapping spheres (the configurations below have an
/// overlapping pair; `Params::allow_overlap` lets the step take them).
fn particles_overlapping<const M: usize>(s: &[Sphere]) -> ParticleSet<f64, M> {
    let list: Vec<hydrorattle::Particle<f64>> = s
        .iter()
        .map(|x| hydrorattle::Particle::new(f64::v3_from(x.pos), x.radius, x.density))
        .collect();
    ParticleSet::from_slice(&list, true).expect("valid scene")
}

/// The step's displacement covariance over 4000 draws against `2 kT dt M`, `M` the
/// Ewald path's assembled mobility: 3 polydisperse spheres (an overlapping pair) in a
/// `8 x 9 x 10` box with `Drift::Uncorrected`, 4 spheres in `7^3` with the default
/// `Drift::Midpoint` (without bonds the step takes the uncorrected draw: the box's
/// mobility is divergence-free; `dt = 1e-4`). PSE at `1e-4`, Lanczos at `1e-6`. The
/// midpoint's solve `M^-1 L w` (bonds only) is run by `chain_end_to_end` and
/// `host-demo/tests/cli/periodic_scene.rs`.
/// Standard error of the second moment `C_ab` of a zero-mean normal: `sqrt((M_aa M_bb +
/// M_ab^2) / n)`; asserted within 5 of them entry by entry (the largest of 45 to 78
/// entries), and the trace within 4 (`var = 2 sum M_ab^2 / n`). Power: a real part or
/// a wave part missing moves the diagonal by 10 to 50 % (`tests/kernel/pse.rs`,
/// `noise_covariance`), many standard errors (about 2 % each here).
#[test]
fn step_covariance_matches_ewald() {
    let draws = 4000;
    for (size, n, seed, drift) in [
        ([8.0, 9.0, 10.0], 3, 21u64, Drift::Uncorrected),
        ([7.0; 3], 4, 4, Drift::Midpoint),
    ] {
        let (pos, rad) = config_radii(n, seed, size, [0.6, 1.4], n == 3);
        let s: Vec<Sphere> = pos
            .iter()
            .zip(&rad)
            .map(|(&pos, &radius)| Sphere {
                pos,
                radius,
                density: 0.0,
            })
            .collect();
        let dt = 1e-4;
        let mut p = thermal::<f64>(dt, 1.0, Hydro::Rpy, drift);
        p.periodic = Some(Periodic::new(size).unwrap());
        p.matrix_free = true;
        p.allow_overlap = true;
        p.pse = Some(1e-4);
        p.lanczos.tolerance = 1e-6;
        let x = match n {
            3 => displacements::<3>(&s, &p, seed, draws),
            _ => displacements::<4>(&s, &p, seed, draws),
        };
        let a_max = rad.iter().cloned().fold(0.0, f64::max);
        let ew = Ewald::new(Periodic::new(size).unwrap(), a_max).unwrap();
        let mut m = vec![f64::M3_ZERO; tri(n)];
        let (pt, rt) = to_t::<f64>(&pos, &rad);
        assemble_tt(&ew, 1.0, &pt, &rt, &mut m).unwrap();
        let get = |a: usize, b: usize| f64::m3_get(sym_get::<f64>(&m, a / 3, b / 3), a % 3, b % 3);
        let dim = 3 * n;
        let scale = 2.0 * dt; // 2 kT dt
        let mut c = vec![0.0; dim * dim];
        for d in &x {
            for a in 0..dim {
                for b in 0..dim {
                    c[a * dim + b] += d[a] * d[b] / (scale * draws as f64);
                }
            }
        }
        let mut worst = 0.0f64;
        for a in 0..dim {
            for b in 0..dim {
                let want = get(a, b);
                let se = ((get(a, a) * get(b, b) + want * want) / draws as f64).sqrt();
                worst = worst.max(((c[a * dim + b] - want) / se).abs());
            }
        }
        let (tc, tm) = (0..dim).fold((0.0, 0.0), |(x, y), a| (x + c[a * dim + a], y + get(a, a)));
        let m2: f64 = (0..dim * dim).map(|k| get(k / dim, k % dim).powi(2)).sum();
        let zt = (tc - tm) / (2.0 * m2 / draws as f64).sqrt();
        println!(
            "n {n} {drift:?}: worst |C - M| / se {worst:.2}, trace {:.5} vs {tm:.5} ({zt:+.2} se)",
            tc
        );
        assert!(worst < 5.0, "covariance off by {worst:.2} standard errors");
        assert!(zt.abs() < 4.0, "trace off by {zt:.2} standard errors");
    }
}

/// `D/D0` of a lone unit sphere (`eta = 1/(6 pi)`, `D0 = 1`, `dt = 0.5`,
/// `Drift::Midpoint`, PSE at `1e-4`) in a cubic box of edge `l` over `steps` steps:
/// `<|dx|^2> / (6 dt)` (no image: a step moves about 1.7, and the positions are not
/// wrapped), its chi-squared standard error `D sqrt(2 / (3 n))` (a lone sphere's
/// steps are independent), and the 50-block one.
fn lone_sphere(l: f64, steps: usize, seed: u64) -> (f64, f64, f64) {
    let dt = 0.5;
    let s = [Sphere {
        pos: [0.3, -1.2, 2.0],
        radius: 1.0,
        density: 0.0,
    }];
    let mut p = thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
    p.periodic = Some(Periodic::new([l; 3]).unwrap());
    p.matrix_free = true;
    p.pse = Some(1e-4);
    let mut ps: ParticleSet<f64, 1> = particles(&s);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 1, 0));
    let mut arrays = arrays(&p, &[1.0]);
    let mut ws = arrays.attach(buf.workspace());
    let bonds = BondSet::<f64, 0>::new();
    let mut noise = Noise::new(seed);
    let mut sq = Vec::with_capacity(steps);
    for _ in 0..steps {
        let before = ps.pos[0];
        step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise).unwrap();
        let d = sub(f64s::<f64>(ps.pos[0]), f64s::<f64>(before));
        sq.push(dot(d, d) / (6.0 * dt));
    }
    let (d, se_blocks) = block_mean(&sq, 50);
    (d, d * (2.0 / (3.0 * steps as f64)).sqrt(), se_blocks)
}

fn check_lone(l: f64, steps: usize, seed: u64) {
    let (d, se, se_blocks) = lone_sphere(l, steps, seed);
    let want = hasimoto(1.0 / l);
    println!(
        "L/a = {l}: D/D0 = {d:.5} +- {se:.5} (blocks {se_blocks:.5}), Hasimoto {want:.5}, {:+.2} se",
        (d - want) / se
    );
    assert!(
        (se_blocks / se - 1.0).abs() < 0.3,
        "block se {se_blocks} vs {se}"
    );
    assert!((d - want).abs() < 3.0 * se, "L = {l}: D {d} vs {want}");
    // Power: the free value, and Hasimoto without its (a/L)^3 term, are far off.
    assert!(1.0 - want > 20.0 * se, "cannot tell the box");
    if l == 5.0 {
        assert!(4.0 * PI / 3.0 / 125.0 > 7.0 * se, "cannot tell a^3/L^3");
    }
}

/// A lone sphere's `D` in boxes `L/a = 5, 10` against Hasimoto within 3 standard
/// errors, 15 000 steps each (CI).
#[test]
fn lone_sphere_diffusion_follows_hasimoto() {
    for (k, l) in [5.0, 10.0].into_iter().enumerate() {
        let steps = std::env::var("STEPS").map_or(15_000, |s| s.parse().unwrap());
        check_lone(l, steps, 300 + k as u64);
    }
}

/// The same at `L/a = 5, 10, 20` with 100 000 steps each (`-- --ignored`).
#[test]
#[ignore]
fn lone_sphere_diffusion_long() {
    for (k, l) in [5.0, 10.0, 20.0].into_iter().enumerate() {
        check_lone(l, 100_000, 400 + k as u64);
    }
}

/// A step whose noise cannot converge (Lanczos capped at one iteration, tolerance
/// `1e-12`) is refused with `StepError::NoConvergence`, the positions and the
/// generator as they were; the same seed gives the same bits on a repeat.
#[test]
fn refusal_keeps_state_and_repeats_bits() {
    let (pos, rad) = config_radii(12, 7, [9.0; 3], [0.5, 1.0], false);
    let s: Vec<Sphere> = pos
        .iter()
        .zip(&rad)
        .map(|(&pos, &radius)| Sphere {
            pos,
            radius,
            density: 3.0,
        })
        .collect();
    let mut p = thermal::<f64>(0.05, 1.0, Hydro::Rpy, Drift::Midpoint);
    p.periodic = Some(Periodic::new([9.0; 3]).unwrap());
    p.matrix_free = true;
    p.pse = Some(1e-4);
    let run = |p: &Params<f64>, steps: usize| -> Result<Vec<u64>, StepError> {
        let mut ps: ParticleSet<f64, 12> = particles(&s);
        let mut buf = Buffers::<f64>::new(Layout::for_params(p, 12, 0));
        let mut arrays = arrays(p, &rad);
        let mut ws = arrays.attach(buf.workspace());
        let mut noise = Noise::new(9);
        let bonds = BondSet::<f64, 0>::new();
        for _ in 0..steps {
            let (before, g) = (ps.pos, noise.clone());
            if let Err(e) = step_thermal(&mut ps, &bonds, p, &mut ws, &mut NoForce, &mut noise) {
                assert_eq!(ps.pos, before, "state changed by a refused step");
                assert_eq!(noise, g, "generator changed by a refused step");
                return Err(e);
            }
        }
        Ok(ps.pos[..12]
            .iter()
            .flat_map(|&r| f64s::<f64>(r))
            .map(|x| x.to_bits())
            .collect())
    };
    let a = run(&p, 3).unwrap();
    assert_eq!(a, run(&p, 3).unwrap(), "same seed, different bits");
    let mut capped = p;
    capped.lanczos.max_iterations = 1;
    capped.lanczos.tolerance = 1e-12;
    match run(&capped, 1) {
        Err(StepError::NoConvergence { .. }) => {}
        other => panic!("{other:?}"),
    }
}

/// PSE's deviates are one draw over both parts (`Noise::fill_parts`): unsplit, the
/// real part's vectors and then the grid's values in stream order (as `fill` and
/// `normal` give them); split into `2^2` sub-steps along the bridge, the four leaves of
/// both parts add up to twice the unsplit draw (so a retried PSE step's sub-steps add
/// up to the refused step's noise), to rounding.
#[test]
fn deviates_bridge_over_both_parts() {
    let (n, m) = (5, 7);
    let g = Noise::new(42);
    let mut head = vec![f64::V3_ZERO; n];
    let mut tail = vec![[1.0f64, 1.0]; 3 * m];
    g.clone().fill_parts::<f64>(&mut head, &mut tail);
    let mut plain = g.clone();
    let mut want = vec![f64::V3_ZERO; n];
    plain.fill::<f64>(&mut want);
    assert_eq!(head, want);
    for v in &tail {
        assert_eq!(v[0].to_bits(), plain.normal().to_bits());
        assert_eq!(v[1], 0.0);
    }
    let (mut sh, mut st) = (vec![[0.0; 3]; n], vec![0.0; 3 * m]);
    for index in 0..4 {
        let (mut h, mut t) = (vec![f64::V3_ZERO; n], vec![[0.0f64; 2]; 3 * m]);
        g.split(2, index).fill_parts::<f64>(&mut h, &mut t);
        for (s, &x) in sh.iter_mut().zip(&h) {
            *s = add(*s, f64s::<f64>(x));
        }
        for (s, x) in st.iter_mut().zip(&t) {
            *s += x[0];
        }
    }
    for (s, &x) in sh.iter().zip(&head) {
        let d = sub(*s, f64s::<f64>(x).map(|c| 2.0 * c));
        assert!(norm(d) < 1e-14, "{d:?}");
    }
    for (s, x) in st.iter().zip(&tail) {
        assert!((s - 2.0 * x[0]).abs() < 1e-14);
    }
}

/// One freely jointed chain's `R^2` samples on the PSE path: 5 unit beads, rigid bonds
/// 3, phantom, `Drift::Midpoint` (whose `M^-1 L w` the conjugate gradients give: the
/// only place a PSE step solves with `M`), `dt = 0.1`, box of edge 10, sampled every
/// 0.5 time units after 20 (as `tests/kernel/periodic_brownian.rs` does on the Ewald path).
fn chain_r2(seed: u64, steps: usize) -> f64 {
    const C: usize = 5;
    let (l, dt) = (10.0, 0.1);
    let (mut ps, bonds) = zigzag_chain::<C, { C - 1 }>(C, 3.0);
    let mut p = thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint);
    p.allow_overlap = true;
    p.periodic = Some(Periodic::new([l; 3]).unwrap());
    p.matrix_free = true;
    p.pse = Some(1e-4);
    ps.noise = Some(Noise::new(seed));
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, C, C - 1));
    let mut arrays = arrays(&p, &[1.0; C]);
    let mut ws = arrays.attach(buf.workspace());
    let (burn, every) = ((20.0 / dt) as usize, (0.5 / dt) as usize);
    let mut out = Vec::new();
    for k in 0..steps {
        step_retrying(&mut ps, &bonds, &p, &mut ws);
        if k >= burn && (k - burn) % every == 0 {
            let r = (1..C).fold([0.0; 3], |acc, j| {
                let d = sub(f64s::<f64>(ps.pos[j]), f64s::<f64>(ps.pos[j - 1]));
                add(acc, d.map(|x| x - l * (x / l).round()))
            });
            out.push(dot(r, r));
        }
    }
    mean_se(&out).0
}

/// `<R^2>` of the chain above against `B b^2 = 36` within 3 standard errors (each
/// chain's time average one sample, the spread over chains): `CHAINS` chains (default
/// 8) of `STEPS` steps (default 8 000). `-- --ignored` (minutes).
#[test]
#[ignore = "minutes: cargo test --release --test kernel pse_brownian::chain -- --ignored"]
fn chain_end_to_end() {
    let env = |k: &str, d: usize| std::env::var(k).map_or(d, |s| s.parse().unwrap());
    let (chains, steps) = (env("CHAINS", 8) as u64, env("STEPS", 8_000));
    let t = std::time::Instant::now();
    let (m, se) = over_seeds(chains, |seed| chain_r2(500 + seed, steps));
    println!(
        "PSE chain in a box: <R^2> = {m:.3} +- {se:.3} (36, {:+.2} se), {chains} x {steps} steps, {:.1} s",
        (m - 36.0) / se,
        t.elapsed().as_secs_f64()
    );
    assert!((m - 36.0).abs() < 3.0 * se, "<R^2> {m} vs 36");
}
