//! The wall as a one-sided constraint (`Params::wall`), checked against what holds for
//! any mobility (these do not depend on the wall's image system):
//!
//! * a sphere settling onto the wall stops at contact: the gap never goes negative (to
//!   the solver's tolerance), the step that would cross ends exactly at contact, and
//!   from then on it rests there, the wall pushing with the sphere's buoyant weight
//!   `W = 4/3 pi a^3 rho g` (its multiplier times `a`); at `dt` = 0.01, 0.1 and 1, both
//!   overdamped methods, every solver, with and without hard contacts;
//! * pulled up, a resting sphere leaves the wall (the wall never pulls);
//! * two stacked spheres land: the wall carries both weights, the contact the upper one;
//! * chains land: a tilted dimer pivots onto the wall and a flat 5-bead chain lands
//!   flat; bonds hold and no gap goes negative;
//! * refusals: a sphere below or crossing the wall (with its index), methods without
//!   the wall, a non-finite height, too little storage, an active set that cannot
//!   settle; each leaves the state bit for bit.

use crate::common;

use std::f64::consts::PI;

use common::*;
use hydrorattle::{
    BondSet, Contacts, Layout, Method, NoForce, Params, ParticleError, ParticleSet, Real,
    SolverKind, Stage, StepError, StepReport, Wall, step,
};
use hydrorattle_heap::Buffers;

/// The wall's height in these tests: not zero, so that the projection's frame moves.
const H: f64 = -1.25;

fn wall_params<T: Real>(dt: f64, method: Method, kind: SolverKind) -> Params<T> {
    let mut p = params::<T>(dt, method, kind);
    p.wall = Some(Wall::new(T::from_f64(H)));
    p
}

/// Buoyant weight of a sphere of radius `a` and density `rho` at `g = 1`, `rho_f = 0`.
fn weight(a: f64, rho: f64) -> f64 {
    4.0 / 3.0 * PI * a * a * a * rho
}

/// Gap between sphere `i` and the wall, relative to its radius.
fn gap<T: Real, const N: usize>(ps: &ParticleSet<T, N>, i: usize) -> f64 {
    let a = ps.radius[i].to_f64();
    (f64s::<T>(ps.pos[i])[2] - H - a) / a
}

fn one_step<T: Real, const N: usize, const B: usize>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    store: &mut Buffers<T>,
) -> Result<StepReport<T>, StepError> {
    step(ps, bonds, p, &mut store.workspace(), &mut NoForce)
}

/// Tolerance on a gap: the solver's, plus the rounding of the wall's frame (`|H|`).
fn gap_tolerance<T: Real>(p: &Params<T>) -> f64 {
    2.0 * p.solver.tolerance.to_f64() + 4.0 * T::EPSILON.to_f64() * (1.0 + H.abs())
}

fn sphere_settles_onto_the_wall<T: Real>() {
    let (a, rho, start_gap) = (1.0, RHO, 3.3);
    let w = weight(a, rho);
    for dt in [0.01, 0.1, 1.0] {
        for method in [Method::Overdamped, Method::Overdamped2] {
            for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
                for contacts in [None, Some(Contacts::new(2))] {
                    let mut p = wall_params::<T>(dt, method, kind);
                    p.contacts = contacts;
                    let what = format!("dt {dt} {method:?} {kind:?} contacts {contacts:?}");
                    let tol = gap_tolerance(&p);
                    let mut ps = particles::<T, 1>(&[Sphere {
                        pos: [0.3, -0.7, H + a + start_gap],
                        radius: a,
                        density: rho,
                    }]);
                    let bonds = BondSet::<T, 1>::new();
                    let mut store = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
                    let start_xy = [f64s::<T>(ps.pos[0])[0], f64s::<T>(ps.pos[0])[1]];
                    let mut landed = None;
                    // Long enough for the slowest mobility near a wall (a quarter of
                    // Stokes' at contact, far field): 3.3 / 0.25 < 16.
                    let steps = (16.0 / dt).ceil() as usize;
                    for k in 0..steps {
                        let before = gap(&ps, 0);
                        let r = one_step(&mut ps, &bonds, &p, &mut store)
                            .unwrap_or_else(|e| panic!("{what} step {k}: {e}"));
                        let after = gap(&ps, 0);
                        assert!(after >= -tol, "{what} step {k}: gap {after} < 0");
                        assert!(after <= before + tol, "{what} step {k}: rises");
                        let xy = f64s::<T>(ps.pos[0]);
                        assert_eq!([xy[0], xy[1]], start_xy, "{what}: no sideways drift");
                        match (landed, r.wall_contacts) {
                            (None, 1) => {
                                landed = Some(k);
                                assert!(
                                    after.abs() <= tol,
                                    "{what} step {k}: lands at contact ({after})"
                                );
                            }
                            (None, 0) => {}
                            (Some(_), 1) => {
                                assert!(after.abs() <= tol, "{what} step {k}: rests ({after})");
                                let u = f64s::<T>(ps.vel[0])[2];
                                assert!(u.abs() * dt <= tol * a, "{what} step {k}: moves {u}");
                                if method == Method::Overdamped {
                                    // The wall's force: multiplier times |g| = a.
                                    let lambda = store.workspace().multipliers(1)[0].to_f64();
                                    let f = lambda * a;
                                    assert!(
                                        (f - w).abs() <= pick::<T>(1e-4, 1e-9) * w,
                                        "{what}: wall force {f} vs weight {w}"
                                    );
                                }
                            }
                            (_, c) => panic!("{what} step {k}: {c} wall contacts after {landed:?}"),
                        }
                        assert_eq!(r.contacts, 0, "{what}: no pair contacts");
                    }
                    assert!(
                        landed.is_some(),
                        "{what}: never landed (gap {})",
                        gap(&ps, 0)
                    );
                }
            }
        }
    }
}

/// A resting sphere pulled up by more than its weight leaves the wall at once.
fn pulled_sphere_leaves_the_wall<T: Real>() {
    let a = 1.0;
    let w = weight(a, RHO);
    let mut ps = particles::<T, 1>(&[Sphere {
        pos: [0.0, 0.0, H + a],
        radius: a,
        density: RHO,
    }]);
    let p = wall_params::<T>(0.1, Method::Overdamped, SolverKind::Newton);
    let bonds = BondSet::<T, 1>::new();
    let mut store = Buffers::<T>::new(Layout::for_params(&p, 1, 0));
    let mut lift = |_: &[T::V3], _: &[T], f: &mut [T::V3]| f[0] += v3::<T>(0.0, 0.0, 2.0 * w);
    let r = step(&mut ps, &bonds, &p, &mut store.workspace(), &mut lift).unwrap();
    assert_eq!(r.wall_contacts, 0, "released");
    // Held at the start; let go inside the solve (an inequality), in one round.
    assert_eq!(
        r.contact_rounds, 1,
        "held at the start, released in the solve"
    );
    assert!(gap(&ps, 0) > 0.0, "rises: {}", gap(&ps, 0));
    // Pushed down instead, it stays.
    let mut ps2 = particles::<T, 1>(&[Sphere {
        pos: [0.0, 0.0, H + a],
        radius: a,
        density: RHO,
    }]);
    let r = one_step(&mut ps2, &bonds, &p, &mut store).unwrap();
    assert_eq!(
        (r.wall_contacts, r.contact_rounds),
        (1, 1),
        "held from the start"
    );
    assert!(gap(&ps2, 0).abs() <= gap_tolerance(&p));
}

/// Two spheres stacked at contact land: the wall carries both weights, the contact
/// between them the upper one's.
fn stacked_pair_lands<T: Real>() {
    let (a, drop) = (1.0, 0.7);
    let (w_top, w_bottom) = (weight(a, 2.0 * RHO), weight(a, RHO));
    for method in [Method::Overdamped, Method::Overdamped2] {
        let mut ps = particles::<T, 2>(&[
            Sphere {
                pos: [0.0, 0.0, H + 3.0 * a + drop],
                radius: a,
                density: 2.0 * RHO,
            },
            Sphere {
                pos: [0.0, 0.0, H + a + drop],
                radius: a,
                density: RHO,
            },
        ]);
        let mut p = wall_params::<T>(0.5, method, SolverKind::Newton);
        p.contacts = Some(Contacts::new(2));
        let tol = gap_tolerance(&p);
        let bonds = BondSet::<T, 1>::new();
        let mut store = Buffers::<T>::new(Layout::for_params(&p, 2, 0));
        let mut last = StepReport::default();
        for k in 0..40 {
            last = one_step(&mut ps, &bonds, &p, &mut store)
                .unwrap_or_else(|e| panic!("{method:?} step {k}: {e}"));
            assert!(gap(&ps, 1) >= -tol, "{method:?} step {k}");
        }
        assert_eq!((last.contacts, last.wall_contacts), (1, 1), "{method:?}");
        assert!(gap(&ps, 1).abs() <= tol, "{method:?}: bottom on the wall");
        let s = norm(sub(f64s::<T>(ps.pos[0]), f64s::<T>(ps.pos[1])));
        assert!(
            (s - 2.0 * a).abs() <= 2.0 * a * tol,
            "{method:?}: touching ({s})"
        );
        if method == Method::Overdamped {
            // Links: a pair's g is r_i - r_j (|g| = 2a), the wall's (0, 0, a).
            let l = store.workspace().multipliers(2).to_vec();
            let forces = [l[0].to_f64(), l[1].to_f64()];
            let want = (w_top, w_bottom + w_top);
            let ok = |pair: f64, wall: f64| {
                let close = |x: f64, y: f64| (x - y).abs() <= pick::<T>(1e-4, 1e-9) * y;
                close(pair.abs() * 2.0 * a, want.0) && close(wall * a, want.1)
            };
            assert!(
                ok(forces[0], forces[1]) || ok(forces[1], forces[0]),
                "multipliers {forces:?}: contact {}, wall {}",
                want.0,
                want.1
            );
        }
    }
}

/// A dimer tilted at 45 degrees lands on its lower bead, pivots, and ends flat on the
/// wall; a flat 5-bead chain lands flat. Bonds hold, no gap goes negative.
fn chains_land<T: Real>() {
    let a = 1.0;
    let s = 2.2 * a;
    let c = s / 2f64.sqrt();
    let dimer = [[0.0, 0.0, H + a + 1.0], [c, 0.0, H + a + 1.0 + c]];
    let flat: Vec<[f64; 3]> = (0..5).map(|k| [k as f64 * s, 0.5, H + a + 2.0]).collect();
    for (name, centres) in [("dimer", dimer.to_vec()), ("flat chain", flat)] {
        for method in [Method::Overdamped, Method::Overdamped2] {
            let spheres: Vec<Sphere> = centres
                .iter()
                .map(|&pos| Sphere {
                    pos,
                    radius: a,
                    density: RHO,
                })
                .collect();
            let n = spheres.len();
            let mut ps = particles::<T, 5>(&spheres);
            let bonds = BondSet::<T, 4>::chain(&ps.pos[..n]).unwrap();
            let p = wall_params::<T>(0.2, method, SolverKind::Newton);
            let tol = gap_tolerance(&p);
            let mut store = Buffers::<T>::new(Layout::for_params(&p, n, n - 1));
            let mut last = StepReport::default();
            let what = format!("{name} {method:?}");
            for k in 0..150 {
                last = one_step(&mut ps, &bonds, &p, &mut store)
                    .unwrap_or_else(|e| panic!("{what} step {k}: {e}"));
                assert!(
                    last.residual.to_f64() <= p.solver.tolerance.to_f64(),
                    "{what}: bonds"
                );
                for i in 0..n {
                    assert!(
                        gap(&ps, i) >= -tol,
                        "{what} step {k}: sphere {i} {}",
                        gap(&ps, i)
                    );
                }
            }
            assert_eq!(
                last.wall_contacts as usize, n,
                "{what}: every sphere on the wall"
            );
            for i in 0..n {
                assert!(
                    gap(&ps, i).abs() <= tol,
                    "{what}: sphere {i} at {}",
                    gap(&ps, i)
                );
            }
            if method == Method::Overdamped {
                // At rest the wall carries the whole weight (the bonds' multipliers
                // follow them in the list).
                let l = store.workspace().multipliers(2 * n - 1).to_vec();
                let wall: f64 = l[n - 1..].iter().map(|x| x.to_f64() * a).sum();
                let want = n as f64 * weight(a, RHO);
                assert!(
                    (wall - want).abs() <= pick::<T>(1e-3, 1e-8) * want,
                    "{what}: wall force {wall} vs weight {want}"
                );
            }
        }
    }
}

fn refusals_keep_the_state<T: Real>() {
    let a = 1.0;
    let at = |gap: f64| Sphere {
        pos: [0.0, 0.0, H + a + gap],
        radius: a,
        density: RHO,
    };
    let trio = |third: f64| {
        let mut s = [at(0.5), at(0.5), at(third)];
        s[1].pos[0] = 3.0;
        s[2].pos[0] = 6.0;
        particles::<T, 3>(&s)
    };
    let bonds = BondSet::<T, 1>::new();
    let p = wall_params::<T>(0.1, Method::Overdamped, SolverKind::Newton);
    let layout = Layout::for_params(&p, 3, 0);
    // Below the wall, and crossing it: refused with the sphere's index.
    for (third, what) in [(-3.0, "below"), (-0.5, "crossing")] {
        let mut ps = trio(third);
        let before = snapshot(&ps);
        let r = one_step(&mut ps, &bonds, &p, &mut Buffers::<T>::new(layout));
        assert_failed_unchanged(
            &before,
            &ps,
            &r,
            |e| {
                matches!(
                    e,
                    StepError::Particle(ParticleError::BelowWall { particle: 2 })
                )
            },
            what,
        );
        let text = r.unwrap_err().to_string();
        assert!(
            text.contains("particle 2") && text.contains("wall"),
            "{text}"
        );
    }
    // Touching is fine.
    let mut ps = trio(0.0);
    one_step(&mut ps, &bonds, &p, &mut Buffers::<T>::new(layout)).unwrap();
    // Methods without the wall, a bad height, too little storage, one round.
    let mut bad_height = p;
    bad_height.wall = Some(Wall::new(T::from_f64(f64::NAN)));
    let mut one_round = p;
    one_round.contacts = Some(Contacts {
        capacity: 2,
        max_rounds: 1,
    });
    type Case<'a, T> = (Params<T>, Layout, &'a dyn Fn(&StepError) -> bool, &'a str);
    let mut cases: Vec<Case<'_, T>> = Vec::new();
    for method in [Method::Rattle, Method::RattleStable, Method::Springs] {
        cases.push((
            Params { method, ..p },
            Layout::all(3, 3),
            &|e| matches!(e, StepError::Unsupported(m) if m.contains("wall")),
            "method",
        ));
    }
    cases.push((
        bad_height,
        layout,
        &|e| matches!(e, StepError::BadParameter(_)),
        "height",
    ));
    cases.push((
        p,
        Layout::for_params(&Params { wall: None, ..p }, 3, 0),
        &|e| matches!(e, StepError::Storage { .. }),
        "storage without the wall's links",
    ));
    cases.push((
        one_round,
        Layout::for_params(&one_round, 3, 0),
        &|e| {
            matches!(
                e,
                StepError::NoConvergence {
                    stage: Stage::Contacts,
                    ..
                }
            )
        },
        "a landing needs a second round",
    ));
    for (p, layout, pred, what) in cases {
        // A step of 10 lands every sphere (gap 0.5; near a wall a sphere settles at
        // a quarter of Stokes' speed or more, 1 here).
        let p = Params {
            dt: T::from_f64(10.0),
            ..p
        };
        let mut ps = trio(0.5);
        let before = snapshot(&ps);
        let r = one_step(&mut ps, &bonds, &p, &mut Buffers::<T>::new(layout));
        assert_failed_unchanged(&before, &ps, &r, pred, what);
    }
}

/// The wall's storage: one link and one constraint per sphere.
#[test]
fn layout_counts_one_link_per_sphere() {
    let mut p = Params::<f64>::new(0.1);
    let none = Layout::for_params(&p, 10, 9);
    p.wall = Some(Wall::new(0.0));
    assert_eq!(p.constraints(10, 9), 19);
    let wall = Layout::for_params(&p, 10, 9);
    assert_eq!(wall.links, 19);
    // More constraints: more bond vectors; and above the wall the mobility keeps
    // general blocks (`tri(10)`) where free space stores symmetric ones in scalars.
    assert!(wall.vectors > none.vectors);
    assert_eq!(wall.blocks, none.blocks + 55);
    p.contacts = Some(Contacts::new(30));
    assert_eq!(Layout::for_params(&p, 10, 9).links, 49);
}

both_precisions! {
    settles => sphere_settles_onto_the_wall;
    leaves => pulled_sphere_leaves_the_wall;
    stacked => stacked_pair_lands;
    chains => chains_land;
    refusals => refusals_keep_the_state;
}
