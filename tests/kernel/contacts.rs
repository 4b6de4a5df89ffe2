//! Hard-sphere contacts as one-sided constraints (`Params::contacts`), checked against
//! closed forms built from the RPY pair formulas of docs/MODEL.md#mobility (not from the kernel):
//!
//! * two touching spheres, the upper one heavier, pushed along their line of centres:
//!   the contact force is half the difference of the weights, and the pair settles as
//!   one at `V = (F1 + F2) / 2 (m_s + m_p)`, `m_s = 1 / (6 pi eta a)`,
//!   `m_p = (2 - 4 a^2 / (3 s^2)) / (8 pi eta s)` at `s = 2a`;
//! * the lower one heavier: the contact would pull, so it is released and each sphere
//!   moves as without contacts;
//! * spheres driven head-on at a step far too large for any soft repulsion stop at
//!   contact instead of passing through each other;
//! * a settling helix never overlaps, bonds hold, and the run is deterministic.
//!
//! Refusals: full contact list, methods without contacts, zero rounds, a workspace
//! without links; each leaves the state bit for bit.

use crate::common;

use std::f64::consts::PI;

use common::*;
use hydrorattle::{
    BondSet, Contacts, Hydro, Layout, Method, NoForce, Params, ParticleSet, Real, SolverKind,
    Stage, StepError, step,
};
use hydrorattle_heap::Buffers;

fn contact_params<T: Real>(dt: f64, method: Method, hydro: Hydro, capacity: usize) -> Params<T> {
    let mut p = params::<T>(dt, method, SolverKind::Newton);
    p.hydro = hydro;
    p.contacts = Some(Contacts::new(capacity));
    p.solver.tolerance = T::from_f64(pick::<T>(1e-5, 1e-12));
    p
}

/// Two unit spheres touching on the vertical, upper density `top`, lower `bottom`.
fn stacked<T: Real>(top: f64, bottom: f64) -> ParticleSet<T, 2> {
    particles::<T, 2>(&[
        Sphere {
            pos: [0.0, 0.0, 2.0],
            radius: 1.0,
            density: top,
        },
        Sphere {
            pos: [0.0, 0.0, 0.0],
            radius: 1.0,
            density: bottom,
        },
    ])
}

/// Buoyant weight (downwards) of a unit sphere of density `rho` at gravity 1.
fn weight(rho: f64) -> f64 {
    4.0 / 3.0 * PI * rho
}

/// Self and parallel pair mobility of two unit spheres at contact (eta = 1).
fn pair_mobilities(hydro: Hydro) -> (f64, f64) {
    let (a, s) = (1.0, 2.0);
    let m_s = 1.0 / (6.0 * PI * a);
    let m_p = match hydro {
        Hydro::FreeDraining => 0.0,
        _ => (2.0 - 4.0 * a * a / (3.0 * s * s)) / (8.0 * PI * s),
    };
    (m_s, m_p)
}

fn one_step<T: Real, const N: usize>(
    ps: &mut ParticleSet<T, N>,
    p: &Params<T>,
) -> Result<hydrorattle::StepReport<T>, StepError> {
    let bonds = BondSet::<T, 1>::new();
    let mut store = Buffers::<T>::new(Layout::for_params(p, ps.len(), 0));
    step(ps, &bonds, p, &mut store.workspace(), &mut NoForce)
}

fn stacked_pair_settles_as_one<T: Real>() {
    let tol = pick::<T>(2e-5, 1e-11);
    for method in [Method::Overdamped, Method::Overdamped2] {
        for hydro in [Hydro::Rpy, Hydro::FreeDraining] {
            let (f1, f2) = (weight(2.0 * RHO), weight(RHO));
            let (m_s, m_p) = pair_mobilities(hydro);
            let v = (f1 + f2) / 2.0 * (m_s + m_p);
            let mut ps = stacked::<T>(2.0 * RHO, RHO);
            let p = contact_params::<T>(0.5, method, hydro, 4);
            let what = format!("{method:?} {hydro:?}");
            for _ in 0..4 {
                let r = one_step(&mut ps, &p).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(r.contacts, 1, "{what}: the pair stays in contact");
                for i in 0..2 {
                    let u = f64s::<T>(ps.vel[i]);
                    assert!(
                        (u[2] + v).abs() <= tol * v && u[0].abs() + u[1].abs() <= tol * v,
                        "{what}: sphere {i} moves at {u:?}, closed form -{v}"
                    );
                }
                let s = norm(sub(f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1])));
                assert!((s - 2.0).abs() <= 2.0 * tol, "{what}: separation {s}");
            }
        }
    }
}

fn pulling_contact_is_released<T: Real>() {
    let tol = pick::<T>(2e-5, 1e-11);
    let (f1, f2) = (weight(RHO), weight(2.0 * RHO));
    let (m_s, m_p) = pair_mobilities(Hydro::Rpy);
    // Without contact: the heavier lower sphere runs away from the upper one.
    let free = [m_s * f1 + m_p * f2, m_p * f1 + m_s * f2];
    assert!(free[1] > free[0]);
    let mut ps = stacked::<T>(RHO, 2.0 * RHO);
    let p = contact_params::<T>(0.1, Method::Overdamped, Hydro::Rpy, 4);
    let r = one_step(&mut ps, &p).unwrap();
    assert_eq!(r.contacts, 0, "released");
    // Held at the start; let go inside the solve (an inequality), in one round.
    assert_eq!(
        r.contact_rounds, 1,
        "held at the start, released in the solve"
    );
    for (i, want) in free.iter().enumerate() {
        let u = f64s::<T>(ps.vel[i])[2];
        assert!((u + want).abs() <= tol * want, "sphere {i}: {u} vs -{want}");
    }
}

/// Two weightless unit spheres on the x axis, 3 apart.
fn apart<T: Real>() -> ParticleSet<T, 2> {
    let at = |x: f64| Sphere {
        pos: [x, 0.0, 0.0],
        radius: 1.0,
        density: 0.0,
    };
    particles::<T, 2>(&[at(-1.5), at(1.5)])
}

/// Two spheres driven head-on by opposite forces: at a step that would leave them
/// deeply overlapping they stop at contact; at one that would carry them through each
/// other the step is refused.
fn head_on_stops_at_contact<T: Real>() {
    let tol = pick::<T>(2e-5, 1e-11);
    let mut ps = apart::<T>();
    let push_with = |force: f64| {
        move |_: &[T::V3], _: &[T], f: &mut [T::V3]| {
            f[0] += v3::<T>(force, 0.0, 0.0);
            f[1] -= v3::<T>(force, 0.0, 0.0);
        }
    };
    // Force 30 at dt = 1: the RPY pair closes at 2 F (m_s - m_p(3)) = 1.71 per unit
    // time, overlapping by 0.7 at the end of the step (a soft contact would need
    // dt < ~0.01 at a stiffness that keeps overlaps small).
    let mut push = push_with(30.0);
    let bonds = BondSet::<T, 1>::new();
    let p = contact_params::<T>(1.0, Method::Overdamped, Hydro::Rpy, 2);
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
    for k in 0..3 {
        let r = step(&mut ps, &bonds, &p, &mut store.workspace(), &mut push).unwrap();
        assert_eq!(r.contacts, 1);
        let (a, b) = (f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1]));
        assert!(
            (b[0] - a[0] - 2.0).abs() <= 2.0 * tol,
            "step {k}: {a:?} {b:?}"
        );
        // Symmetric: they meet in the middle and stay there.
        assert!((a[0] + b[0]).abs() <= 1e-3 * tol.max(1e-9), "{a:?} {b:?}");
    }
    // Force 1000: the free move carries each sphere ~50 radii past the other.
    let mut fast = ps.clone();
    let before = snapshot(&fast);
    let mut store2 = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
    let r = step(
        &mut fast,
        &bonds,
        &p,
        &mut store2.workspace(),
        &mut push_with(-1000.0),
    );
    let _ = &r;
    // Pulled apart (negative force): no contact, nothing refused.
    assert!(r.is_ok(), "{r:?}");
    let _ = before;
    let mut crossing = apart::<T>();
    let before = snapshot(&crossing);
    let r = step(
        &mut crossing,
        &bonds,
        &p,
        &mut store2.workspace(),
        &mut push_with(1000.0),
    );
    assert_failed_unchanged(
        &before,
        &crossing,
        &r,
        |e| matches!(e, StepError::Degenerate { bond: 0, .. }),
        "one sphere carried through the other",
    );
    // Named as what the row holds: a contact, not "bond 0" (there is no bond).
    let e = r.unwrap_err().to_string();
    assert!(
        e.starts_with("the contact of particles 0 and 1 turned too far"),
        "{e}"
    );
    // Without contacts the moderate step leaves them overlapping: refused.
    let mut ps2 = apart::<T>();
    let mut soft = p;
    soft.contacts = None;
    let mut store = Buffers::<T>::new(Layout::for_params(&soft, 2, 0));
    let before = snapshot(&ps2);
    let r = step(&mut ps2, &bonds, &soft, &mut store.workspace(), &mut push);
    assert_failed_unchanged(
        &before,
        &ps2,
        &r,
        |e| matches!(e, StepError::Overlap { .. }),
        "no contacts",
    );
}

/// A settling helix (Figure 1 (b)-like: short bonds, normal head) at a large step.
fn settling_helix_never_overlaps<T: Real>() -> u64 {
    let spheres = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.05);
    let mut ps = particles::<T, 25>(&spheres);
    let bonds = BondSet::<T, 24>::chain(&ps.pos[..25]).unwrap();
    for method in [Method::Overdamped, Method::Overdamped2] {
        let mut q = ps.clone();
        let mut p = contact_params::<T>(0.1, method, Hydro::Rpy, 75);
        // f32 positions hundreds of radii below the start resolve bond lengths to a
        // few 1e-5 only.
        p.solver.tolerance = T::from_f64(pick::<T>(1e-4, 1e-12));
        let tol = p.solver.tolerance.to_f64();
        let mut store = Buffers::<T>::new(Layout::for_params(&p, 25, 24));
        let mut most = 0;
        for k in 0..300 {
            let r = step(&mut q, &bonds, &p, &mut store.workspace(), &mut NoForce)
                .unwrap_or_else(|e| panic!("{method:?} step {k}: {e}"));
            most = most.max(r.contacts);
            assert!(r.residual.to_f64() <= tol, "bonds hold");
            for i in 0..25 {
                for j in 0..i {
                    let s = norm(sub(f64s::<T>(q.pos[i]), f64s::<T>(q.pos[j])));
                    let sigma = (q.radius[i] + q.radius[j]).to_f64();
                    assert!(
                        s >= sigma * (1.0 - 2.0 * tol),
                        "{method:?} step {k}: {i}-{j} at {s} < {sigma}"
                    );
                }
            }
        }
        assert!(
            most >= 3,
            "{method:?}: the chain folds into contacts ({most})"
        );
    }
    let mut p = contact_params::<T>(0.1, Method::Overdamped, Hydro::Rpy, 75);
    p.solver.tolerance = T::from_f64(pick::<T>(1e-4, 1e-12));
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 25, 24));
    run(
        &mut ps,
        &bonds,
        &p,
        &mut store.workspace(),
        &mut NoForce,
        100,
    );
    state_digest(&ps)
}

/// Parameters, storage, the error expected, and what is tried.
type Refusal<'a, T> = (Params<T>, Layout, &'a dyn Fn(&StepError) -> bool, &'a str);

fn refusals_keep_the_state<T: Real>() {
    // Three spheres stacked with gaps of 0.2, heavier on top: in a step of 2 both gaps
    // close (two contacts at once).
    let row = || {
        let sphere = |z: f64, rho: f64| Sphere {
            pos: [0.0, 0.0, z],
            radius: 1.0,
            density: rho,
        };
        particles::<T, 3>(&[
            sphere(4.4, 3.0 * RHO),
            sphere(2.2, 2.0 * RHO),
            sphere(0.0, RHO),
        ])
    };
    let with = |capacity, max_rounds| {
        let mut p = contact_params::<T>(2.0, Method::Overdamped, Hydro::Rpy, capacity);
        p.contacts = Some(Contacts {
            capacity,
            max_rounds,
        });
        p
    };
    let no_contacts = |p: Params<T>| Params {
        contacts: None,
        ..p
    };
    let cases: [Refusal<'_, T>; 6] = [
        (
            with(1, 64),
            Layout::for_params(&with(1, 64), 3, 0),
            &|e| matches!(e, StepError::ContactsFull { capacity: 1 }),
            "full",
        ),
        (
            with(4, 1),
            Layout::for_params(&with(4, 1), 3, 0),
            &|e| {
                matches!(
                    e,
                    StepError::NoConvergence {
                        stage: Stage::Contacts,
                        ..
                    }
                )
            },
            "one round cannot settle two new contacts",
        ),
        (
            with(4, 0),
            Layout::for_params(&with(4, 0), 3, 0),
            &|e| matches!(e, StepError::BadParameter(_)),
            "zero rounds",
        ),
        (
            // Storage for the same step without contacts: no links, too few slots.
            with(4, 64),
            Layout::for_params(&no_contacts(with(4, 64)), 3, 0),
            &|e| matches!(e, StepError::Storage { .. }),
            "storage",
        ),
        (
            Params {
                method: Method::Rattle,
                ..with(4, 64)
            },
            Layout::all(3, 4),
            &|e| matches!(e, StepError::Unsupported(_)),
            "rattle",
        ),
        (
            Params {
                method: Method::RattleStable,
                ..with(4, 64)
            },
            Layout::all(3, 4),
            &|e| matches!(e, StepError::Unsupported(_)),
            "rattle-stable",
        ),
    ];
    for (p, layout, pred, what) in cases {
        let mut ps = row();
        let bonds = BondSet::<T, 1>::new();
        let mut store = Buffers::<T>::new(layout);
        let before = snapshot(&ps);
        let r = step(&mut ps, &bonds, &p, &mut store.workspace(), &mut NoForce);
        assert_failed_unchanged(&before, &ps, &r, pred, what);
    }
}

both_precisions! {
    stacked_pair => stacked_pair_settles_as_one;
    released => pulling_contact_is_released;
    head_on => head_on_stops_at_contact;
    refusals => refusals_keep_the_state;
}

/// Golden digests of the state after 100 contact steps: recorded on x86_64 when the
/// contacts landed; a change means the arithmetic of the contact path moved.
const GOLDEN_F64: u64 = 0xfae7_ec2a_476a_4906;
const GOLDEN_F32: u64 = 0x2ed0_d74b_9e05_c37f;

#[test]
fn settling_helix_f64() {
    let d = settling_helix_never_overlaps::<f64>();
    assert_eq!(d, settling_helix_never_overlaps::<f64>(), "same bits twice");
    assert_eq!(d, GOLDEN_F64, "contacts helix digest f64: {d:016x}");
}

#[test]
fn settling_helix_f32() {
    let d = settling_helix_never_overlaps::<f32>();
    assert_eq!(d, GOLDEN_F32, "contacts helix digest f32: {d:016x}");
}

/// A step's rows named by what they hold: the caller's bonds, then its pin rows, then
/// the one-sided rows (contacts, wall links), as the solvers number them.
#[test]
fn rows_are_named_by_what_they_hold() {
    use hydrorattle::{Bond, Row};
    let mut rows = vec![Bond::<f64> {
        i: 0,
        j: 1,
        length: 2.0,
    }];
    rows.extend(Bond::pins(2, 1.0));
    rows.push(Bond {
        i: 3,
        j: 4,
        length: 2.0,
    });
    rows.push(Bond::wall(5, 1.0));
    let named: Vec<String> = (0..rows.len())
        .map(|k| Row::of(&rows, k, 4).to_string())
        .collect();
    assert_eq!(
        named,
        [
            "bond 0",
            "the pin of particle 2 along x",
            "the pin of particle 2 along y",
            "the pin of particle 2 along z",
            "the contact of particles 3 and 4",
            "the wall contact of particle 5",
        ]
    );
    // A row past the list is named as a bond (no panic path in the kernel).
    assert_eq!(Row::of(&rows, rows.len(), 4), Row::Bond(rows.len()));
    let e = StepError::Degenerate {
        bond: 4,
        row: Row::of(&rows, 4, 4),
    };
    assert_eq!(
        e.to_string(),
        "the contact of particles 3 and 4 turned too far in one step (degenerate SHAKE update)"
    );
}
