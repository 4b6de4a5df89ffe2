//! Steps on the fast free-space product (`Params::pse` without a box or a wall,
//! `mobility::free_fast`): the matrix-free product, the Krylov metric's products and
//! the Lanczos noise read `FreeFast::apply`. Checked against values not from the fast
//! code:
//!
//! * deterministic steps against the same steps on the dense stored mobility (the
//!   pair blocks, `mobility::assemble_tt`) within the requested tolerance: a
//!   polydisperse cloud with overlapping pairs, a bonded chain by Krylov, hard contacts;
//! * the thermal step's displacement covariance against `2 kT dt M`, `M` the dense
//!   free-space mobility, and a lone sphere's diffusion against Stokes-Einstein
//!   `D0 = kT / (6 pi eta a)`;
//! * the same bits twice; the refusals typed, the state untouched; storage below the
//!   rule's served by a coarser grid within the tolerance; the workspace `O(N)`.
//!
//! `cargo test --release --test kernel fast_step:: -- --nocapture`.

use crate::common;

use common::boxes::config_radii;
use common::thermal::*;
use common::*;
use hydrorattle::integrate::fast_storage;
use hydrorattle::linalg::{sym_get, tri};
use hydrorattle::mobility::assemble_tt;
use hydrorattle::{
    Bond, BondSet, Brownian, Contacts, Drift, ExternalForce, Hydro, Layout, Method, NoForce, Noise,
    Params, Particle, ParticleSet, Real, SolverKind, StepError, Wall, step,
};
use hydrorattle_heap::{Buffers, FreeBuffers};
use std::f64::consts::PI;

/// The fast product's arrays for steps of `p` from the spheres `s` (complex values,
/// reals, indices), each scaled by `shrink` (1: what `fast_storage` asks).
pub(super) fn arrays(p: &Params<f64>, s: &[Sphere], shrink: [f64; 3]) -> FreeBuffers<f64> {
    let pos: Vec<_> = s.iter().map(|x| f64::v3_from(x.pos)).collect();
    let rad: Vec<f64> = s.iter().map(|x| x.radius).collect();
    let z = fast_storage(p, &pos, &rad).unwrap().expect("a fast step");
    let len = |k: usize, n: usize| (n as f64 * shrink[k]) as usize;
    let mut a = FreeBuffers::new(z);
    a.complex.truncate(len(0, z.complex));
    a.reals.truncate(len(1, z.reals));
    a.index.truncate(len(2, z.index));
    a
}

/// A particle set that may hold overlapping spheres.
pub(super) fn set<const M: usize>(s: &[Sphere]) -> ParticleSet<f64, M> {
    let list: Vec<Particle<f64>> = s
        .iter()
        .map(|x| Particle::new(f64::v3_from(x.pos), x.radius, x.density))
        .collect();
    ParticleSet::from_slice(&list, true).expect("valid scene")
}

/// `steps` steps of `p` (the fast product's arrays sized from `s`, scaled by
/// `shrink`, where `p` takes it); the positions after each.
fn run_fast<const M: usize, const B: usize, E: ExternalForce<f64>>(
    s: &[Sphere],
    bonds: &BondSet<f64, B>,
    p: &Params<f64>,
    ext: &mut E,
    steps: usize,
    shrink: [f64; 3],
) -> Result<Vec<Vec<[f64; 3]>>, StepError> {
    let mut ps = set::<M>(s);
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, s.len(), bonds.len()));
    let mut a = match p.pse {
        Some(_) => arrays(p, s, shrink),
        None => FreeBuffers::default(),
    };
    let mut ws = a.attach(buf.workspace());
    let mut out = vec![];
    for _ in 0..steps {
        step(&mut ps, bonds, p, &mut ws, ext)?;
        out.push(ps.pos[..s.len()].iter().map(|&r| f64s::<f64>(r)).collect());
    }
    Ok(out)
}

/// `p` on the fast product at `tol` (matrix-free), or on the dense stored mobility.
pub(super) fn on(mut p: Params<f64>, tol: Option<f64>) -> Params<f64> {
    p.matrix_free = tol.is_some();
    p.pse = tol;
    p.allow_overlap = true;
    p
}

/// Largest displacement difference over the largest displacement.
pub(super) fn relative(start: &[Sphere], a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let big = start
        .iter()
        .zip(a)
        .map(|(s, r)| norm(sub(*r, s.pos)))
        .fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| norm(sub(*x, *y)))
        .fold(0.0, f64::max);
    diff / big
}

pub(super) const C: usize = 60;

/// `C` polydisperse spheres (radii 0.5 to 1, half placed overlapping an earlier one)
/// in a cube of edge 14, densities 2 to 6 (so the forces differ).
pub(super) fn cloud() -> Vec<Sphere> {
    let (pos, rad) = config_radii(C, 7, [14.0; 3], [0.5, 1.0], true);
    assert_eq!(pos.len(), C);
    let s: Vec<Sphere> = (0..C)
        .map(|i| Sphere {
            pos: pos[i],
            radius: rad[i],
            density: 2.0 + (i % 5) as f64,
        })
        .collect();
    let overlapping = (0..C)
        .flat_map(|i| (0..i).map(move |j| (i, j)))
        .filter(|&(i, j)| norm(sub(s[i].pos, s[j].pos)) < s[i].radius + s[j].radius)
        .count();
    assert!(overlapping >= 10, "{overlapping} overlapping pairs");
    s
}

/// Sedimentation of the cloud (`Overdamped`, `Springs` without bonds): one step on the
/// fast product within its tolerance of the dense step, at `1e-3`, `1e-4` and `1e-6`.
#[test]
fn cloud_matches_dense() {
    let s = cloud();
    let none = BondSet::<f64, 0>::new();
    for method in [Method::Overdamped, Method::Springs] {
        let p = params::<f64>(0.05, method, SolverKind::Auto);
        let dense = run_fast::<C, 0, _>(&s, &none, &on(p, None), &mut NoForce, 1, [1.0; 3]);
        let dense = dense.unwrap();
        for tol in [1e-3, 1e-4, 1e-6] {
            let fast = run_fast::<C, 0, _>(&s, &none, &on(p, Some(tol)), &mut NoForce, 1, [1.0; 3]);
            let err = relative(&s, &dense[0], &fast.unwrap()[0]);
            println!("{method:?} tol {tol:e}: fast vs dense {err:.2e}");
            assert!(err < tol, "{method:?} tol {tol}: {err}");
            assert!(err > 0.0, "the fast product did not run");
        }
    }
}

/// Storage below what `fast_storage` asks (60 % of the complex values and reals)
/// is served by a coarser grid: the step still within the tolerance of the dense one.
/// Indices below `3 n + 1` are refused, typed, the state untouched.
#[test]
fn small_storage_coarser_grid_or_refused() {
    let s = cloud();
    let none = BondSet::<f64, 0>::new();
    let p = params::<f64>(0.05, Method::Overdamped, SolverKind::Auto);
    let dense = run_fast::<C, 0, _>(&s, &none, &on(p, None), &mut NoForce, 1, [1.0; 3]);
    let fast = on(p, Some(1e-4));
    let coarse = run_fast::<C, 0, _>(&s, &none, &fast, &mut NoForce, 1, [0.6, 0.6, 1.0]);
    let err = relative(&s, &dense.unwrap()[0], &coarse.unwrap()[0]);
    println!("60 % of the storage, tol 1e-4: fast vs dense {err:.2e}");
    assert!(err < 1e-4, "{err}");
    for shrink in [[1.0, 1.0, 0.5], [1e-6, 1e-6, 1.0]] {
        let mut ps = set::<C>(&s);
        let before = snapshot(&ps);
        let mut buf = Buffers::<f64>::new(Layout::for_params(&fast, C, 0));
        let mut a = arrays(&fast, &s, shrink);
        let mut ws = a.attach(buf.workspace());
        let r = step(&mut ps, &none, &fast, &mut ws, &mut NoForce);
        let storage = |e: &StepError| matches!(e, StepError::BadParameter(w) if w.contains("fast free-space storage"));
        assert_failed_unchanged(&before, &ps, &r, storage, "small storage");
    }
}

/// A push along `x` on the first half, against `-x` on the rest.
pub(super) struct Push;

impl<T: Real> ExternalForce<T> for Push {
    fn add(&mut self, _pos: &[T::V3], _radius: &[T], force: &mut [T::V3]) {
        let n = force.len();
        for (i, f) in force.iter_mut().enumerate() {
            let s = if i < n / 2 { 30.0 } else { -30.0 };
            *f += v3::<T>(s, 0.0, 0.0);
        }
    }
}

pub(super) const K: usize = 6;

/// A chain of `K` beads of unequal radii and its bonds at their lengths.
pub(super) fn chain() -> (Vec<Sphere>, BondSet<f64, { K - 1 }>) {
    let s: Vec<Sphere> = (0..K)
        .map(|k| Sphere {
            pos: [1.7 * k as f64, 0.3 * (k % 2) as f64, 0.2 * k as f64],
            radius: 0.6 + 0.03 * k as f64,
            density: 3.0,
        })
        .collect();
    let mut bonds = BondSet::<f64, { K - 1 }>::new();
    for k in 0..K - 1 {
        let length = norm(sub(s[k + 1].pos, s[k].pos));
        bonds
            .push(
                Bond {
                    i: k,
                    j: k + 1,
                    length,
                },
                K,
            )
            .unwrap();
    }
    (s, bonds)
}

/// The bonded chain under gravity and a push, constrained by Krylov (what `Auto`
/// resolves to on the fast product): positions after 3 steps within the tolerance of
/// the dense Krylov step's, bonds held to the solver's tolerance.
#[test]
fn chain_krylov_matches_dense() {
    let (s, bonds) = chain();
    let mut p = params::<f64>(0.05, Method::Overdamped, SolverKind::Krylov);
    let dense = run_fast::<K, { K - 1 }, _>(&s, &bonds, &on(p, None), &mut Push, 3, [1.0; 3]);
    let dense = dense.unwrap();
    p.solver.kind = SolverKind::Auto;
    for tol in [1e-4, 1e-6] {
        let fast = on(p, Some(tol));
        assert_eq!(fast.solver_kind(K, K - 1), SolverKind::Krylov);
        let got = run_fast::<K, { K - 1 }, _>(&s, &bonds, &fast, &mut Push, 3, [1.0; 3]).unwrap();
        let err = relative(&s, &dense[2], &got[2]);
        println!("chain tol {tol:e}: fast vs dense after 3 steps {err:.2e}");
        assert!(err < tol, "tol {tol}: {err}");
        for b in bonds.as_slice() {
            let r = norm(sub(got[2][b.i], got[2][b.j]));
            assert!((r - b.length).abs() < 1e-8 * b.length, "bond {r}");
        }
    }
}

/// Four spheres in a row pushed together with hard contacts by Krylov: no overlap, a
/// contact held, the positions within the tolerance of the dense path's after 4 steps
/// (`Overdamped`, and `Overdamped2` against the stored `Overdamped2`).
#[test]
fn contacts_match_dense() {
    for method in [Method::Overdamped, Method::Overdamped2] {
        contacts_match_dense_with(method);
    }
}

fn contacts_match_dense_with(method: Method) {
    let s: Vec<Sphere> = (0..4)
        .map(|k| Sphere {
            pos: [[-1.6, -0.3, 1.2, 2.5][k], 0.0, 0.1 * k as f64],
            radius: 0.5,
            density: 1.0,
        })
        .collect();
    let none = BondSet::<f64, 0>::new();
    let with = |tol| {
        let mut p = on(params::<f64>(0.05, method, SolverKind::Krylov), tol);
        p.allow_overlap = false;
        p.contacts = Some(Contacts::new(8));
        p
    };
    let dense = run_fast::<4, 0, _>(&s, &none, &with(None), &mut Push, 4, [1.0; 3]).unwrap();
    let fast = run_fast::<4, 0, _>(&s, &none, &with(Some(1e-5)), &mut Push, 4, [1.0; 3]).unwrap();
    let closest = |x: &[[f64; 3]]| {
        let r = |i: usize, j: usize| norm(sub(x[i], x[j]));
        (0..4)
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| r(i, j))
            .fold(f64::MAX, f64::min)
    };
    for x in &fast {
        assert!(closest(x) > 1.0 - 1e-8, "overlap {}", closest(x));
    }
    assert!(closest(&fast[3]) < 1.0 + 1e-8, "no contact held");
    let err = relative(&s, &dense[3], &fast[3]);
    println!("{method:?} contacts tol 1e-5: fast vs dense after 4 steps {err:.2e}");
    assert!(err < 1e-5, "{method:?}: {err}");
}

/// The spheres of the covariance test: 4, polydisperse (radii 0.6 to 1.4), an
/// overlapping pair among them.
fn four() -> Vec<Sphere> {
    let (pos, rad) = config_radii(4, 4, [6.0; 3], [0.6, 1.4], true);
    assert_eq!(pos.len(), 4);
    pos.iter()
        .zip(&rad)
        .map(|(&pos, &radius)| Sphere {
            pos,
            radius,
            density: 0.0,
        })
        .collect()
}

/// The thermal step's displacement covariance over 2000 draws from one configuration
/// against `2 kT dt M`, `M` the dense free-space RPY mobility (`assemble_tt`): fast
/// product at `1e-3`, Lanczos at `1e-4` (both far below the standard errors, 2 to 3 %), `Drift::Midpoint` asked (without bonds the
/// step takes the uncorrected draw, free space's RPY mobility being divergence-free,
/// as on PSE's path). Standard error of the second moment `C_ab` of a zero-mean normal:
/// `sqrt((M_aa M_bb + M_ab^2) / n)`; asserted within 5 of them entry by entry (the
/// largest of 78 entries) and the trace within 4 (`var = 2 sum M_ab^2 / n`). Power:
/// the free-draining covariance (no interactions) must fail.
#[test]
fn noise_covariance_matches_dense() {
    let draws = 2000;
    let s = four();
    let n = s.len();
    let dt = 1e-4;
    let mut p = thermal::<f64>(dt, 1.0, Hydro::Rpy, Drift::Midpoint);
    p = on(p, Some(1e-3));
    p.lanczos.tolerance = 1e-4;
    let mut ps = set::<4>(&s);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, n, 0));
    let mut a = arrays(&p, &s, [1.0; 3]);
    let mut ws = a.attach(buf.workspace());
    let bonds = BondSet::<f64, 0>::new();
    let mut noise = Noise::new(17);
    let start = ps.pos;
    let x: Vec<Vec<f64>> = (0..draws)
        .map(|_| {
            ps.pos = start;
            step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise).unwrap();
            (0..n)
                .flat_map(|i| sub(f64s::<f64>(ps.pos[i]), f64s::<f64>(start[i])))
                .collect()
        })
        .collect();
    let mut m = vec![f64::M3_ZERO; tri(n)];
    let pos: Vec<_> = s.iter().map(|x| f64::v3_from(x.pos)).collect();
    let rad: Vec<f64> = s.iter().map(|x| x.radius).collect();
    assemble_tt(Hydro::Rpy, 1.0, &pos, &rad, &mut m).unwrap();
    let rpy = |a: usize, b: usize| f64::m3_get(sym_get::<f64>(&m, a / 3, b / 3), a % 3, b % 3);
    let dim = 3 * n;
    let mut c = vec![0.0; dim * dim];
    for d in &x {
        for a in 0..dim {
            for b in 0..dim {
                c[a * dim + b] += d[a] * d[b] / (2.0 * dt * draws as f64);
            }
        }
    }
    let worst = |get: &dyn Fn(usize, usize) -> f64| {
        let mut worst = 0.0f64;
        for a in 0..dim {
            for b in 0..dim {
                let want = get(a, b);
                let se = ((get(a, a) * get(b, b) + want * want) / draws as f64).sqrt();
                worst = worst.max(((c[a * dim + b] - want) / se).abs());
            }
        }
        worst
    };
    let (tc, tm) = (0..dim).fold((0.0, 0.0), |(x, y), a| (x + c[a * dim + a], y + rpy(a, a)));
    let m2: f64 = (0..dim * dim).map(|k| rpy(k / dim, k % dim).powi(2)).sum();
    let zt = (tc - tm) / (2.0 * m2 / draws as f64).sqrt();
    let against_rpy = worst(&rpy);
    let alone = |a: usize, b: usize| match a == b {
        true => 1.0 / (6.0 * PI * rad[a / 3]),
        false => 0.0,
    };
    let against_alone = worst(&alone);
    println!(
        "worst |C - M| / se {against_rpy:.2} (free draining {against_alone:.1}), trace {tc:.5} vs {tm:.5} ({zt:+.2} se)"
    );
    assert!(against_rpy < 5.0, "covariance off by {against_rpy:.2} se");
    assert!(zt.abs() < 4.0, "trace off by {zt:.2} se");
    assert!(against_alone > 10.0, "no power: {against_alone:.2}");
}

/// A lone sphere's diffusion on the fast path (at `1e-3`): `<|dx|^2> / (6 dt)` over 2000 steps
/// against `D0 = kT / (6 pi eta a)` (`kT = 1`, `eta = 1 / (6 pi)`, `a = 1`: `D0 = 1`;
/// `dt = 0.5`, the sphere carried about 1.7 a step, the cloud's grid following it).
/// A lone sphere's steps are independent: the mean's standard error is `D0 sqrt(2 /
/// (3 n))` (chi-squared with 3 degrees of freedom, 1.8 % here); asserted within 4.
#[test]
fn lone_sphere_diffuses_as_stokes_einstein() {
    let steps = 2000;
    let dt = 0.5;
    let s = [Sphere {
        pos: [0.3, -1.2, 2.0],
        radius: 1.0,
        density: 0.0,
    }];
    let p = on(
        thermal::<f64>(dt, 1.0 / (6.0 * PI), Hydro::Rpy, Drift::Midpoint),
        Some(1e-3),
    );
    let mut ps = set::<1>(&s);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 1, 0));
    let mut a = arrays(&p, &s, [1.0; 3]);
    let mut ws = a.attach(buf.workspace());
    let bonds = BondSet::<f64, 0>::new();
    let mut noise = Noise::new(0x9E37_79B9);
    let mut sq = Vec::with_capacity(steps);
    for _ in 0..steps {
        let before = ps.pos[0];
        step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise).unwrap();
        let d = sub(f64s::<f64>(ps.pos[0]), f64s::<f64>(before));
        sq.push(dot(d, d) / (6.0 * dt));
    }
    let d = sq.iter().sum::<f64>() / steps as f64;
    let se = (2.0 / (3.0 * steps as f64)).sqrt();
    println!(
        "lone sphere: D/D0 = {d:.4} +- {se:.4} ({:+.2} se)",
        (d - 1.0) / se
    );
    assert!(((d - 1.0) / se).abs() < 4.0, "D/D0 = {d} +- {se}");
}

/// The same inputs give the same bits: a thermal bonded chain (the Krylov
/// constraints, the Lanczos draw and the midpoint's solve on the fast product) run
/// twice, 3 steps each.
#[test]
fn same_bits_twice() {
    let (s, bonds) = chain();
    let mut p = on(
        thermal::<f64>(1e-3, 1.0, Hydro::Rpy, Drift::Midpoint),
        Some(1e-4),
    );
    p.gravity = f64::v3_from([0.0, 0.0, -9.81]);
    let run = || {
        let mut ps = set::<K>(&s);
        let mut buf = Buffers::<f64>::new(Layout::for_params(&p, K, K - 1));
        let mut a = arrays(&p, &s, [1.0; 3]);
        let mut ws = a.attach(buf.workspace());
        let mut noise = Noise::new(3);
        for _ in 0..3 {
            step_thermal(&mut ps, &bonds, &p, &mut ws, &mut Push, &mut noise).unwrap();
        }
        snapshot(&ps)
    };
    let (first, second) = (run(), run());
    assert_eq!(first, second);
    assert_ne!(first, snapshot(&set::<K>(&s)), "the steps did not move");
}

/// A step of `p` on the chain `(s, bonds)` (with a noise generator, without fast
/// storage) refused with `StepError::Unsupported` naming `why`, the state untouched.
pub(super) fn assert_unsupported(
    (s, bonds): (&[Sphere], &BondSet<f64, { K - 1 }>),
    p: &Params<f64>,
    why: &str,
    name: &str,
) {
    let mut ps = set::<K>(s);
    ps.noise = Some(Noise::new(1));
    let before = snapshot(&ps);
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, K, K - 1));
    let mut ws = buf.workspace();
    let r = step(&mut ps, bonds, p, &mut ws, &mut NoForce);
    let typed = |e: &StepError| matches!(e, StepError::Unsupported(w) if w.contains(why));
    assert_failed_unchanged(&before, &ps, &r, typed, name);
}

/// What the fast product cannot serve is refused, typed, the state untouched: a wall,
/// the stored path, the Oseen level, a tabulating solver with bonds,
/// Cholesky noise; and a step with no fast storage in its workspace.
#[test]
fn refusals() {
    let (s, bonds) = chain();
    let fast = on(
        params::<f64>(0.05, Method::Overdamped, SolverKind::Auto),
        Some(1e-4),
    );
    let with = |f: &dyn Fn(&mut Params<f64>)| {
        let mut p = fast;
        f(&mut p);
        p
    };
    let cases: Vec<(&str, Params<f64>, &str)> = vec![
        ("wall", with(&|p| p.wall = Some(Wall::new(-5.0))), "wall"),
        ("stored", with(&|p| p.matrix_free = false), "products only"),
        ("Oseen", with(&|p| p.hydro = Hydro::Oseen), "Oseen"),
        (
            "Sweep",
            with(&|p| p.solver.kind = SolverKind::Sweep),
            "products only",
        ),
        (
            "Newton",
            with(&|p| p.solver.kind = SolverKind::Newton),
            "products only",
        ),
        (
            "Cholesky",
            with(&|p| {
                p.brownian = Some(Brownian::new(1.0));
                p.noise_sqrt = hydrorattle::NoiseSqrt::Cholesky;
            }),
            "Cholesky",
        ),
    ];
    for (name, p, why) in cases {
        assert!(fast_storage(&p, &[f64::V3_ZERO], &[1.0]).is_ok());
        assert_unsupported((&s, &bonds), &p, why, name);
    }
    // No fast storage at all.
    let mut ps = set::<K>(&s);
    let before = snapshot(&ps);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&fast, K, K - 1));
    let mut ws = buf.workspace();
    let r = step(&mut ps, &bonds, &fast, &mut ws, &mut NoForce);
    let typed = |e: &StepError| matches!(e, StepError::BadParameter(w) if w.contains("fast free-space storage"));
    assert_failed_unchanged(&before, &ps, &r, typed, "no storage");
    // A tolerance out of range, before any storage is sized.
    let bad = Params {
        pse: Some(0.5),
        ..fast
    };
    assert!(matches!(
        fast_storage(&bad, &[f64::V3_ZERO], &[1.0]),
        Err(StepError::BadParameter(_))
    ));
    // None where the step takes no fast product: a box (PSE's), free draining, no pse.
    let none = [
        with(&|p| p.pse = None),
        with(&|p| p.hydro = Hydro::FreeDraining),
        with(&|p| p.periodic = hydrorattle::Periodic::new([20.0; 3]).ok()),
    ];
    for p in none {
        assert_eq!(fast_storage(&p, &[f64::V3_ZERO], &[1.0]), Ok(None));
    }
}

/// The workspace of a fast step grows as `N` (no `N^2` object): its layout at 2000
/// beads at most 2.01 times its layout at 1000, deterministic and thermal; the fast
/// product's storage for a dilute cloud likewise within a small factor of linear.
#[test]
fn storage_is_linear() {
    let total = |l: Layout| l.blocks * 9 + l.vectors * 3 + l.scalars + l.indices;
    for thermal_on in [false, true] {
        let mut p = on(
            params::<f64>(0.05, Method::Overdamped, SolverKind::Auto),
            Some(1e-4),
        );
        if thermal_on {
            p.brownian = Some(Brownian::new(1.0));
        }
        let (l1, l2) = (
            Layout::for_params(&p, 1000, 999),
            Layout::for_params(&p, 2000, 1999),
        );
        println!("thermal {thermal_on}: {l1:?} -> {l2:?}");
        assert!(
            total(l2) as f64 <= 2.01 * total(l1) as f64,
            "{l1:?} -> {l2:?}"
        );
        assert_eq!(l1.blocks, 0, "{l1:?}");
    }
    let p = on(
        params::<f64>(0.05, Method::Overdamped, SolverKind::Auto),
        Some(1e-4),
    );
    let size = |n: usize| {
        // A jittered lattice of spacing 4 (volume fraction about 0.05 at radius 1).
        let edge = (n as f64).cbrt().ceil() as usize;
        let pos: Vec<_> = (0..n)
            .map(|k| {
                let c = [k % edge, (k / edge) % edge, k / (edge * edge)].map(|c| 4.0 * c as f64);
                f64::v3_from(add(c, [0.3 * (k as f64).sin(), 0.0, 0.0]))
            })
            .collect();
        let z = fast_storage(&p, &pos, &vec![1.0; n]).unwrap().unwrap();
        (z.complex * 2 + z.reals + z.index) as f64
    };
    let (s1, s8) = (size(1000), size(8000));
    println!("fast storage: {s1:.3e} values at 1000, {s8:.3e} at 8000");
    assert!(s8 < 12.0 * s1, "{s1} -> {s8}");
}
