//! Regressions from review: residuals that could hide a bad bond, bond lengths whose
//! square overflows, a stability guard blind to modes along z, and the spin of the
//! second-order overdamped scheme.

use hydrorattle::glam::DVec3;
use hydrorattle::{
    Bond, BondError, BondSet, Method, NoForce, Params, Particle, ParticleSet, StepError,
    bonds::max_residual, step,
};

#[test]
fn a_length_whose_square_overflows_is_refused() {
    let mut b64: BondSet<f64, 4> = BondSet::new();
    let err = b64
        .push(
            Bond {
                i: 0,
                j: 1,
                length: 1e300,
            },
            2,
        )
        .unwrap_err()
        .1;
    assert_eq!(err, BondError::BadLength { bond: 0 });
    let mut b32: BondSet<f32, 4> = BondSet::new();
    let err = b32
        .push(
            Bond {
                i: 0,
                j: 1,
                length: 1e20,
            },
            2,
        )
        .unwrap_err()
        .1;
    assert_eq!(err, BondError::BadLength { bond: 0 });
}

#[test]
fn max_residual_never_hides_nan_or_a_missing_particle() {
    let pos = [
        DVec3::ZERO,
        DVec3::new(f64::NAN, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 2.0),
    ];
    let bonds = [
        Bond {
            i: 0,
            j: 1,
            length: 1.0,
        }, // NaN residual
        Bond {
            i: 0,
            j: 2,
            length: 1.0,
        }, // residual 1, later: must not hide the NaN
    ];
    let (k, r) = max_residual::<f64>(&bonds, &pos);
    assert_eq!(k, 0);
    assert!(r.is_nan());
    let (k, r) = max_residual(
        &[
            bonds[1],
            Bond {
                i: 0,
                j: 7,
                length: 1.0,
            },
        ],
        &pos,
    );
    assert_eq!((k, r), (1, f64::INFINITY));
}

/// The guard's limit for two unbonded equal spheres 3 apart is set by their relative
/// motion along the line of centres: `2 m mu0 (1 - 3a/(2r) + a^3/r^3)` (RPY), whatever
/// the line's direction.
#[test]
fn the_guard_sees_the_stiffest_mode_in_every_direction() {
    let (a, r, rho) = (1.0f64, 3.0f64, 4.5f64);
    let m = 4.0 / 3.0 * std::f64::consts::PI * a.powi(3) * rho;
    let mu0 = 1.0 / (6.0 * std::f64::consts::PI * a);
    let theory = 2.0 * m * mu0 * (1.0 - 1.5 * a / r + a.powi(3) / r.powi(3));
    for dir in [DVec3::X, DVec3::Z, DVec3::new(1.0, 2.0, -2.0) / 3.0] {
        let mut ps: ParticleSet<f64, 2> = ParticleSet::new();
        ps.push(Particle::new(DVec3::ZERO, a, rho)).unwrap();
        ps.push(Particle::new(dir * r, a, rho)).unwrap();
        let bonds: BondSet<f64, 1> = BondSet::new();
        let mut p = Params::new(1e6);
        p.method = Method::Rattle;
        p.stability_guard = true;
        let mut ws_store = hydrorattle_heap::Buffers::<f64>::new(hydrorattle::Layout::all(2, 1));
        let mut ws = ws_store.workspace();
        match step(&mut ps, &bonds, &p, &mut ws, &mut NoForce) {
            Err(StepError::Unstable { limit, .. }) => {
                assert!(
                    (limit - theory).abs() < 1e-3 * theory,
                    "{dir}: {limit} vs {theory}"
                );
            }
            other => panic!("expected Unstable, got {other:?}"),
        }
    }
}

/// With rotation reported, the second-order scheme's angular velocities agree with the
/// first-order ones to O(dt): both include the constraint forces.
#[test]
fn overdamped2_spin_includes_the_constraint_forces() {
    let run = |method| {
        let mut ps: ParticleSet<f64, 3> = ParticleSet::new();
        for (k, a) in [2.0, 1.0, 1.0].into_iter().enumerate() {
            let x = DVec3::new(3.2 * k as f64, 0.0, 0.8 * (k % 2) as f64);
            ps.push(Particle::new(x, a, 4.5)).unwrap();
        }
        let bonds: BondSet<f64, 2> = BondSet::chain(&ps.pos[..3]).unwrap();
        let mut p = Params::new(1e-3);
        p.method = method;
        p.rotation = true;
        p.gravity = DVec3::new(0.3, 0.0, -1.0);
        let mut ws_store = hydrorattle_heap::Buffers::<f64>::new(hydrorattle::Layout::all(3, 2));
        let mut ws = ws_store.workspace();
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
        ps.omega
    };
    let (w1, w2) = (run(Method::Overdamped), run(Method::Overdamped2));
    for i in 0..3 {
        assert!(w1[i].length() > 1e-3);
        assert!(
            (w1[i] - w2[i]).length() < 1e-2 * w1[i].length(),
            "{i}: {} vs {}",
            w1[i],
            w2[i]
        );
    }
}
