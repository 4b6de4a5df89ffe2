//! Pinned spheres ([`Bond::pin`], `docs/CONTACTS.md`): three linear rows per sphere hold
//! it at its anchor, solved with the bonds; the multipliers are the force that holds
//! it. Checked against references the kernel does not compute:
//!
//! * a lone pinned sphere under gravity does not move (bit for bit) and its pin force
//!   is minus its buoyant weight `4/3 pi a^3 (rho - rho_f) g`, with every solver, in
//!   free space and in a periodic box (and stays put with `Overdamped2`);
//! * a free sphere beside a pinned one (free space): the free sphere's velocity is
//!   `(M11 - M12 M22^-1 M21) F` and the pin's force `-M22^-1 M21 F`, with `M` the
//!   two-sphere RPY tensors written here from the closed form (Rotne and Prager 1969;
//!   unequal radii, Zuk et al. 2014); in a periodic box the same with `M` the kernel's
//!   own Ewald mobility assembled explicitly and a dense solve here (an internal
//!   cross-check of the pin rows against the mobility, not of the mobility);
//! * a bed settled on a pinned floor in a periodic box: at rest the pins carry the
//!   total buoyant weight (1e-9 in f64), no overlap beyond the tolerance at any step;
//! * typed refusals that leave the state as it was: a pin out of range, a sphere
//!   pinned twice, a bad axis or scale, a non-finite anchor, overlapping pinned
//!   spheres, and the methods pins do not support.

#![allow(clippy::needless_range_loop)] // 3x3 matrices indexed as written.

use crate::common;

use std::f64::consts::PI;

use common::*;
use hydrorattle::linalg::tri;
use hydrorattle::{
    Bond, BondError, BondSet, Brownian, Contacts, Layout, Method, NoForce, Params, ParticleError,
    ParticleSet, Periodic, Real, SolverKind, StepError, StepReport, step,
};
use hydrorattle_heap::Buffers;

const SOLVERS: [SolverKind; 3] = [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov];
const RHO_F: f64 = 1.0;

fn buoyant(a: f64, rho: f64) -> f64 {
    4.0 / 3.0 * PI * a.powi(3) * (rho - RHO_F)
}

fn pin_params<T: Real>(kind: SolverKind, l: Option<f64>) -> Params<T> {
    let mut p = params::<T>(0.1, Method::Overdamped, kind);
    p.fluid_density = T::from_f64(RHO_F);
    p.periodic = l.map(|l| Periodic::new([T::from_f64(l); 3]).unwrap());
    p
}

fn one_step<T: Real, const N: usize, const B: usize>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    store: &mut Buffers<T>,
) -> Result<StepReport<T>, StepError> {
    step(ps, bonds, p, &mut store.workspace(), &mut NoForce)
}

/// The force the held rows put on each sphere (pin rows alone: `lambda s e`).
fn pin_forces<T: Real>(store: &mut Buffers<T>, rows: &[Bond<T>], n: usize) -> Vec<[f64; 3]> {
    let lambda: Vec<f64> = store
        .workspace()
        .multipliers(rows.len())
        .iter()
        .map(|x| x.to_f64())
        .collect();
    let mut f = vec![[0.0; 3]; n];
    for (l, b) in rows.iter().enumerate() {
        if b.is_pin() {
            f[b.i][b.axis()] += lambda[l] * b.length.to_f64();
        }
    }
    f
}

fn pinned_set<T: Real, const B: usize>(spheres: &[usize], radius: &[f64]) -> BondSet<T, B> {
    let mut bonds = BondSet::new();
    for &i in spheres {
        for b in Bond::pins(i, T::from_f64(radius[i])) {
            bonds.push(b, radius.len()).unwrap();
        }
    }
    bonds
}

fn lone_pin<T: Real>(tol: f64) {
    for (l, method) in [None, Some(8.0)]
        .into_iter()
        .zip([Method::Overdamped2; 2])
        .chain([(None, Method::Overdamped), (Some(8.0), Method::Overdamped)])
    {
        for kind in SOLVERS {
            let p = Params {
                method,
                ..pin_params::<T>(kind, l)
            };
            let s = Sphere {
                pos: [0.3, -0.2, 1.7],
                radius: 1.3,
                density: RHO,
            };
            let mut ps = particles::<T, 1>(&[s]);
            let bonds = pinned_set::<T, 3>(&[0], &[s.radius]);
            let mut store = Buffers::<T>::new(Layout::for_params(&p, 1, 3));
            let before = snapshot(&ps);
            for _ in 0..3 {
                one_step(&mut ps, &bonds, &p, &mut store).unwrap();
            }
            let after = snapshot(&ps);
            // Positions bit for bit (the state's positions follow n and time).
            assert_eq!(
                before[2..5],
                after[2..5],
                "{method:?} {kind:?} {l:?}: moved"
            );
            // Overdamped2's last projection's multipliers are a correction to the
            // predictor's (`Engine::tensions`): its force is not the holding force.
            if method == Method::Overdamped2 {
                continue;
            }
            let f = pin_forces(&mut store, bonds.as_slice(), 1)[0];
            let w = buoyant(s.radius, RHO);
            let err = norm(sub(f, [0.0, 0.0, w])) / w;
            assert!(
                err < tol,
                "{kind:?} {l:?}: pin force {f:?}, weight {w} ({err:e})"
            );
        }
    }
}

#[test]
fn lone_pinned_sphere_carries_its_weight_f64() {
    lone_pin::<f64>(1e-12);
}

#[test]
fn lone_pinned_sphere_carries_its_weight_f32() {
    lone_pin::<f32>(1e-5);
}

type M = [[f64; 3]; 3];

fn mv(m: &M, v: [f64; 3]) -> [f64; 3] {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// `m^-1` of a 3x3 matrix (cofactors).
fn inverse(m: &M) -> M {
    let c = |r: usize, k: usize| {
        let (r1, r2, k1, k2) = ((r + 1) % 3, (r + 2) % 3, (k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let mut out = [[0.0; 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            out[r][k] = c(k, r) / det;
        }
    }
    out
}

/// The closed-form RPY pair tensor of spheres `a`, `b` at separation `r` (apart):
/// `1 / (8 pi eta |r|) [(1 + (a^2 + b^2) / 3r^2) I + (1 - (a^2 + b^2) / r^2) r r / r^2]`.
fn rpy_pair(a: f64, b: f64, r: [f64; 3], eta: f64) -> M {
    let d = norm(r);
    let s = (a * a + b * b) / (d * d);
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 + s / 3.0 } else { 0.0 };
            m[i][j] = (id + (1.0 - s) * r[i] * r[j] / (d * d)) / (8.0 * PI * eta * d);
        }
    }
    m
}

fn scaled(s: f64) -> M {
    [[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
}

fn sub_m(a: &M, b: &M) -> M {
    let mut o = *a;
    for r in 0..3 {
        for k in 0..3 {
            o[r][k] -= b[r][k];
        }
    }
    o
}

fn mm(a: &M, b: &M) -> M {
    let mut o = [[0.0; 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            o[r][k] = (0..3).map(|q| a[r][q] * b[q][k]).sum();
        }
    }
    o
}

/// Sphere 0 free (weight `F`), sphere 1 pinned and neutrally buoyant, gravity oblique.
/// Returns the step's velocity of sphere 0 and the pin force, with the blocks `M11`,
/// `M12 = M21^T`, `M22` the reference is built from (`blocks`).
fn beside<T: Real>(
    kind: SolverKind,
    l: Option<f64>,
    blocks: impl Fn(&Params<T>, &ParticleSet<T, 2>) -> (M, M, M),
) -> (f64, f64) {
    let mut p = pin_params::<T>(kind, l);
    p.gravity = T::v3_from([0.3, -0.5, -1.0]);
    let spheres = [
        Sphere {
            pos: [0.2, 0.1, 0.3],
            radius: 1.0,
            density: RHO,
        },
        Sphere {
            pos: [3.1, 0.8, -0.6],
            radius: 1.5,
            density: RHO_F,
        },
    ];
    let mut ps = particles::<T, 2>(&spheres);
    let radius = [1.0, 1.5];
    let bonds = pinned_set::<T, 3>(&[1], &radius);
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 2, 3));
    let (m11, m12, m22) = blocks(&p, &ps);
    let start = f64s::<T>(ps.pos[0]);
    one_step(&mut ps, &bonds, &p, &mut store).unwrap();
    let u = scale(sub(f64s::<T>(ps.pos[0]), start), 1.0 / p.dt.to_f64());
    let f = pin_forces(&mut store, bonds.as_slice(), 2)[1];
    let weight = scale([0.3, -0.5, -1.0], buoyant(1.0, RHO));
    let m21 = transpose(&m12);
    let m22i = inverse(&m22);
    let u_ref = mv(&sub_m(&m11, &mm(&m12, &mm(&m22i, &m21))), weight);
    let f_ref = scale(mv(&mm(&m22i, &m21), weight), -1.0);
    let du = norm(sub(u, u_ref)) / norm(u_ref);
    let df = norm(sub(f, f_ref)) / norm(f_ref);
    (du, df)
}

fn transpose(m: &M) -> M {
    let mut o = [[0.0; 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            o[r][k] = m[k][r];
        }
    }
    o
}

/// The closed-form blocks in free space.
fn closed_form<T: Real>(p: &Params<T>, ps: &ParticleSet<T, 2>) -> (M, M, M) {
    let eta = p.viscosity.to_f64();
    let r = sub(f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1]));
    (
        scaled(1.0 / (6.0 * PI * eta * 1.0)),
        rpy_pair(1.0, 1.5, r, eta),
        scaled(1.0 / (6.0 * PI * eta * 1.5)),
    )
}

/// The kernel's Ewald blocks (`geometry::mobility_tt`), block `(i, j)` at `tri(i) + j`.
fn ewald_blocks<T: Real>(p: &Params<T>, ps: &ParticleSet<T, 2>) -> (M, M, M) {
    let mut mu = vec![T::M3_ZERO; tri(2)];
    hydrorattle::integrate::geometry::mobility_tt(p, &ps.pos[..2], &ps.radius[..2], &mut mu)
        .unwrap();
    let get = |k: usize| {
        let mut m = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                m[r][c] = T::m3_get(mu[k], r, c).to_f64();
            }
        }
        m
    };
    // mu[tri(1) + 0] is block (1, 0) = M21; M12 is its transpose.
    (get(tri(0)), transpose(&get(tri(1))), get(tri(1) + 1))
}

#[test]
fn free_sphere_beside_a_pinned_one_free_space() {
    for kind in SOLVERS {
        let (du, df) = beside::<f64>(kind, None, closed_form::<f64>);
        eprintln!("free space {kind:?}: velocity {du:.1e}, pin force {df:.1e} (relative)");
        assert!(
            du < 1e-9 && df < 1e-9,
            "{kind:?}: velocity {du:e}, pin force {df:e}"
        );
        let (du, df) = beside::<f32>(kind, None, closed_form::<f32>);
        assert!(du < 1e-4 && df < 1e-4, "{kind:?} f32: {du:e}, {df:e}");
    }
}

#[test]
fn free_sphere_beside_a_pinned_one_periodic() {
    for kind in SOLVERS {
        let (du, df) = beside::<f64>(kind, Some(9.0), ewald_blocks::<f64>);
        eprintln!("box {kind:?}: velocity {du:.1e}, pin force {df:.1e} (relative)");
        assert!(
            du < 1e-9 && df < 1e-9,
            "{kind:?}: velocity {du:e}, pin force {df:e}"
        );
    }
}

/// Asserts that a step with `rows` is refused as `want` says and keeps the state.
fn refused<T: Real, const N: usize>(
    ps: &mut ParticleSet<T, N>,
    rows: &[Bond<T>],
    p: &Params<T>,
    want: impl Fn(&StepError) -> bool,
    what: &str,
) {
    let mut store = Buffers::<T>::new(Layout::for_params(p, ps.len(), rows.len()).max(
        Layout::for_params(
            &params::<T>(0.1, Method::Overdamped, SolverKind::Auto),
            ps.len(),
            rows.len(),
        ),
    ));
    let before = snapshot(ps);
    let r = hydrorattle::step_slices(ps.state(), rows, p, &mut store.workspace(), &mut NoForce);
    assert_failed_unchanged(&before, ps, &r, want, what);
}

#[test]
fn bad_pins_are_refused_and_the_state_kept() {
    let spheres = [
        Sphere {
            pos: [0.0, 0.0, 0.0],
            radius: 1.0,
            density: RHO,
        },
        Sphere {
            pos: [2.5, 0.0, 0.0],
            radius: 1.0,
            density: RHO,
        },
    ];
    let p = pin_params::<f64>(SolverKind::Newton, None);
    let mut ps = particles::<f64, 2>(&spheres);
    let pins0 = Bond::pins(0, 1.0);
    let range = |e: &StepError| {
        matches!(
            e,
            StepError::Bond(BondError::OutOfRange {
                bond: 1,
                particle: 5
            })
        )
    };
    refused(
        &mut ps,
        &[pins0[0], Bond::pin(5, 1, 1.0)],
        &p,
        range,
        "out of range",
    );
    let axis = |e: &StepError| matches!(e, StepError::Bond(BondError::OutOfRange { bond: 0, .. }));
    refused(&mut ps, &[Bond::pin(0, 3, 1.0)], &p, axis, "axis 3");
    let twice = |e: &StepError| {
        matches!(
            e,
            StepError::Bond(BondError::Duplicate { bond: 3, other: 0 })
        )
    };
    let mut rows = pins0.to_vec();
    rows.push(Bond::pin(0, 0, 1.5));
    refused(&mut ps, &rows, &p, twice, "pinned twice");
    for scale in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let bad = |e: &StepError| matches!(e, StepError::Bond(BondError::BadLength { bond: 0 }));
        refused(&mut ps, &[Bond::pin(0, 2, scale)], &p, bad, "scale");
    }
    // The anchor is the sphere's position: a non-finite one is refused as such.
    let mut nan = ps.clone();
    nan.pos[0] = v3::<f64>(f64::NAN, 0.0, 0.0);
    let nonfinite = |e: &StepError| {
        matches!(
            e,
            StepError::Particle(ParticleError::NonFinite { particle: 0 })
        )
    };
    refused(&mut nan, &pins0, &p, nonfinite, "non-finite anchor");
    // Two pinned spheres that overlap (the second moved into the first).
    let mut close = ps.clone();
    close.pos[1] = v3::<f64>(1.5, 0.0, 0.0);
    let mut rows = pins0.to_vec();
    rows.extend(Bond::pins(1, 1.0));
    let overlap = |e: &StepError| {
        matches!(
            e,
            StepError::Particle(ParticleError::Overlap { i: 0, j: 1 })
        )
    };
    refused(&mut close, &rows, &p, overlap, "pinned overlap");
    // Methods without pins.
    for method in [Method::Rattle, Method::RattleStable, Method::Springs] {
        let q = Params { method, ..p };
        let unsupported = |e: &StepError| matches!(e, StepError::Unsupported(_));
        refused(&mut ps, &pins0, &q, unsupported, "method");
    }
    let mut q = p;
    q.brownian = Some(Brownian {
        temperature: 1.0,
        drift: Default::default(),
    });
    ps.noise = Some(hydrorattle::Noise::new(1));
    let unsupported = |e: &StepError| matches!(e, StepError::Unsupported(_));
    refused(&mut ps, &pins0, &q, unsupported, "thermal");
}

/// A bed on a pinned floor in a periodic box: a 3 x 3 floor of touching unit spheres
/// (holes of radius 0.41: no sphere falls through) under 8 spheres of radii 0.9 to
/// 1.1 dropped from above, with hard contacts, settles to rest; no overlap beyond the
/// tolerance at any step; at rest the pins carry the buoyant weight of all 17 spheres
/// (the floor's own included) to 1e-9, and the floor has not moved by a bit.
fn bed_settles(kind: SolverKind) {
    let mut p = pin_params::<f64>(kind, None);
    p.periodic = Some(Periodic::new([6.0, 6.0, 14.0]).unwrap());
    p.contacts = Some(Contacts::new(96));
    p.dt = 0.2;
    let mut spheres = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            spheres.push(Sphere {
                pos: [1.0 + 2.0 * i as f64, 1.0 + 2.0 * j as f64, 1.0],
                radius: 1.0,
                density: RHO,
            });
        }
    }
    let free = [
        ([1.4, 1.6, 4.2], 1.0),
        ([4.5, 1.3, 4.6], 0.9),
        ([1.7, 4.4, 5.0], 1.1),
        ([4.3, 4.6, 5.4], 1.0),
        ([3.1, 2.9, 7.8], 0.95),
        ([0.3, 3.2, 8.3], 1.05),
        ([3.2, 0.2, 10.6], 0.9),
        ([5.2, 5.1, 11.0], 1.1),
    ];
    for (pos, radius) in free {
        spheres.push(Sphere {
            pos,
            radius,
            density: RHO,
        });
    }
    let n = spheres.len();
    let radius: Vec<f64> = spheres.iter().map(|s| s.radius).collect();
    let mut ps = particles::<f64, 17>(&spheres);
    let bonds = pinned_set::<f64, 27>(&(0..9).collect::<Vec<_>>(), &radius);
    let mut store = Buffers::<f64>::new(Layout::for_params(&p, n, 27));
    let floor = snapshot(&ps)[2..2 + 27].to_vec();
    let total: f64 = radius.iter().map(|&a| buoyant(a, RHO)).sum();
    let tol = p.solver.tolerance;
    let (mut still, mut steps, mut contacts) = (0, 0, 0);
    while still < 3 {
        assert!(steps < 400, "{kind:?}: not at rest after {steps} steps");
        let before = ps.pos;
        let r = one_step(&mut ps, &bonds, &p, &mut store);
        steps += 1;
        let r = r.unwrap_or_else(|e| panic!("{kind:?}: step {steps}: {e}"));
        contacts = r.contacts;
        let moved = (0..n)
            .map(|i| (ps.pos[i] - before[i]).length())
            .fold(0.0, f64::max);
        still = if moved < 1e-9 { still + 1 } else { 0 };
        for i in 0..n {
            for j in 0..i {
                let d = (ps.pos[i] - ps.pos[j]).to_array();
                let d: [f64; 3] = std::array::from_fn(|k| {
                    let l = [6.0, 6.0, 14.0][k];
                    d[k] - l * (d[k] / l).round()
                });
                let gap = norm(d) / (radius[i] + radius[j]) - 1.0;
                assert!(
                    gap > -2.0 * tol,
                    "{kind:?}: {i}, {j} overlap {gap:e} at step {steps}"
                );
            }
        }
    }
    assert_eq!(
        snapshot(&ps)[2..2 + 27],
        floor[..],
        "{kind:?}: the floor moved"
    );
    let load: f64 = pin_forces(&mut store, bonds.as_slice(), n)
        .iter()
        .map(|f| f[2])
        .sum();
    let err = (load - total).abs() / total;
    assert!(
        err < 1e-9,
        "{kind:?}: pins carry {load}, weight {total} ({err:e})"
    );
    eprintln!(
        "{kind:?}: at rest after {steps} steps, {contacts} contacts, pins carry the weight to {err:.1e}"
    );
}

#[test]
fn bed_on_a_pinned_floor_rests_on_it() {
    bed_settles(SolverKind::Newton);
}

/// Krylov: the band of the floor's pin rows is indefinite, so its preconditioner is
/// Jacobi (`docs/CONTACTS.md`, pins).
#[test]
fn bed_on_a_pinned_floor_rests_on_it_krylov() {
    bed_settles(SolverKind::Krylov);
}
