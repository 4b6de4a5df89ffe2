//! Outcome metrics and the named states on synthetic shapes whose answers are known.

use crate::common;

use common::chain_bonds;
use hydrorattle::glam::DVec3;
use hydrorattle::observables::{Twist, centre_of_mass, extension, settling_speed, verticality};

const DOWN: DVec3 = DVec3::new(0.0, 0.0, -1.0);

#[test]
fn a_straight_vertical_chain_has_full_extension_and_verticality() {
    let pos: Vec<DVec3> = (0..25)
        .map(|k| DVec3::new(0.0, 0.0, 2.1 * k as f64))
        .collect();
    let b = chain_bonds(&pos);
    assert!((extension(&pos, &b) - 1.0).abs() < 1e-12);
    assert!((verticality::<f64>(&pos, DOWN) - 1.0).abs() < 1e-12);
}

#[test]
fn a_horizontal_chain_is_not_vertical_and_a_folded_one_is_short() {
    let flat: Vec<DVec3> = (0..10)
        .map(|k| DVec3::new(2.0 * k as f64, 0.0, 0.0))
        .collect();
    assert!(verticality::<f64>(&flat, DOWN).abs() < 1e-12);
    // A hairpin: out along x and back, ends side by side 2 apart.
    let mut hairpin: Vec<DVec3> = (0..5)
        .map(|k| DVec3::new(2.0 * k as f64, 0.0, 0.0))
        .collect();
    hairpin.extend((0..5).rev().map(|k| DVec3::new(2.0 * k as f64, 2.0, 0.0)));
    let b = chain_bonds(&hairpin);
    assert!((extension(&hairpin, &b) - 2.0 / 18.0).abs() < 1e-12);
}

#[test]
fn a_rigidly_rotating_helix_twists_at_its_angular_speed() {
    // Tails on a circle of radius 2 around the head's vertical axis, turning at w.
    let w = 0.05;
    let shape = |t: f64| -> Vec<DVec3> {
        let mut v = vec![DVec3::ZERO];
        v.extend((0..12).map(|k| {
            let phi = 0.6 * k as f64 + w * t;
            DVec3::new(2.0 * phi.cos(), 2.0 * phi.sin(), 0.5 * k as f64 + 1.0)
        }));
        v
    };
    let mut prev = [0.0; 16];
    let mut tw = Twist::new(&mut prev, 0.1);
    let dt = 0.5;
    for s in 0..=200 {
        tw.update(&shape(s as f64 * dt), DOWN);
    }
    // Gravity down: "up" is +z, and the tails turn counter-clockwise seen from above.
    assert!((tw.total - w * 200.0 * dt).abs() < 1e-9, "{}", tw.total);
}

#[test]
fn a_chain_on_the_axis_accumulates_no_twist() {
    let mut prev = [0.0; 8];
    let mut tw = Twist::new(&mut prev, 0.1);
    for s in 0..50 {
        // Straight down the axis, with sub-threshold jitter that has no meaningful azimuth.
        let jitter = 1e-3 * ((s % 7) as f64 - 3.0);
        let pos: Vec<DVec3> = (0..6)
            .map(|k| DVec3::new(jitter, -jitter, 2.0 * k as f64))
            .collect();
        tw.update(&pos, DOWN);
    }
    assert_eq!(tw.total, 0.0);
}

#[test]
fn centre_of_mass_and_settling_speed() {
    let pos = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(3.0, 0.0, 0.0)];
    let com = centre_of_mass::<f64>(&pos, |i| if i == 0 { 2.0 } else { 1.0 });
    assert!((com - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-15);
    let vel = [DVec3::new(0.3, 0.0, -1.5)];
    assert!((settling_speed::<f64>(&vel, 0, DVec3::new(0.0, 0.0, -9.0)) - 1.5).abs() < 1e-15);
}

// --- Motion and shape over time ----------------------------------------------------

use hydrorattle::observables::{
    VerticalFront, com_settling_speed, extents, poloidal_circulation, spin_about_vertical,
    vertical_run,
};

/// Beads on a torus: core radius 5 about `normal` through `centre`, tube radius 1.5;
/// bead k at toroidal angle 2 pi k / 24 and poloidal angle 2 pi 5k / 24 (covers the
/// tube evenly). Returns positions, the core tangent and the tube offset of each bead.
fn torus(normal: DVec3, centre: DVec3) -> Vec<(DVec3, DVec3, DVec3)> {
    let n = normal.normalize();
    let ex = n.any_orthonormal_vector();
    let ey = n.cross(ex);
    (0..24)
        .map(|k| {
            let th = std::f64::consts::TAU * k as f64 / 24.0;
            let ps = std::f64::consts::TAU * (5 * k) as f64 / 24.0;
            let radial = ex * th.cos() + ey * th.sin();
            let tangent = n.cross(radial);
            let rho = (radial * ps.cos() + n * ps.sin()) * 1.5;
            (centre + radial * 5.0 + rho, tangent, rho)
        })
        .collect()
}

#[test]
fn a_rigidly_spinning_body_has_its_rate_and_full_coherence() {
    let w = 0.3;
    let drift = DVec3::new(0.2, -0.1, -1.0); // any translation changes nothing
    let pos: Vec<DVec3> = (0..12)
        .map(|k| {
            DVec3::new(
                (k as f64).cos() * 3.0 + 1.0,
                (k as f64 * 1.3).sin() * 2.0,
                k as f64,
            )
        })
        .collect();
    let mass: Vec<f64> = (0..12).map(|k| 1.0 + 0.1 * k as f64).collect();
    let c = pos
        .iter()
        .zip(&mass)
        .fold(DVec3::ZERO, |a, (&p, &m)| a + p * m)
        / mass.iter().sum::<f64>();
    let vel: Vec<DVec3> = pos
        .iter()
        .map(|&p| DVec3::Z.cross(p - c) * w + drift)
        .collect();
    let s = spin_about_vertical::<f64>(&pos, &vel, &mass, DOWN);
    assert!((s.rate - w).abs() < 1e-12, "{s:?}");
    assert!((s.coherence - 1.0).abs() < 1e-12, "{s:?}");
    // Beads moving straight out from the centre: no turning, no coherence.
    let out: Vec<DVec3> = pos
        .iter()
        .map(|&p| (p - c) * DVec3::new(1.0, 1.0, 0.0))
        .collect();
    let s = spin_about_vertical::<f64>(&pos, &out, &mass, DOWN);
    assert!(s.rate.abs() < 1e-12 && s.coherence.abs() < 1e-12, "{s:?}");
    assert!((com_settling_speed::<f64>(&vel, &mass, DOWN) - 1.0).abs() < 1e-12);
}

#[test]
fn a_rolling_ring_circulates_poloidally_at_its_rate() {
    let w = 0.7;
    for normal in [DVec3::Z, DVec3::new(0.3, 0.0, 1.0), DVec3::X] {
        let ring = torus(normal, DVec3::new(2.0, -1.0, 4.0));
        let pos: Vec<DVec3> = ring.iter().map(|r| r.0).collect();
        let mass = vec![1.0; pos.len()];
        // Rolling: each bead turns about its core tangent; plus a settling drift.
        let roll: Vec<DVec3> = ring
            .iter()
            .map(|&(_, t, rho)| t.cross(rho) * w + DVec3::new(0.0, 0.0, -0.5))
            .collect();
        let p = poloidal_circulation::<f64>(&pos, &roll, &mass);
        assert!((p.rate - w).abs() < 1e-9, "{normal}: {p:?}");
        assert!(p.coherence > 0.999, "{normal}: {p:?}");
        // Spinning about its own axis is not rolling.
        let n = normal.normalize();
        let spin: Vec<DVec3> = pos
            .iter()
            .map(|&x| n.cross(x - DVec3::new(2.0, -1.0, 4.0)) * w)
            .collect();
        let p = poloidal_circulation::<f64>(&pos, &spin, &mass);
        assert!(
            p.rate.abs() < 1e-9 && p.coherence < 1e-9,
            "{normal}: spin read as {p:?}"
        );
    }
    // A horizontal ring spinning about the vertical: spin, not circulation.
    let ring = torus(DVec3::Z, DVec3::ZERO);
    let pos: Vec<DVec3> = ring.iter().map(|r| r.0).collect();
    let vel: Vec<DVec3> = pos.iter().map(|&x| DVec3::Z.cross(x) * w).collect();
    let s = spin_about_vertical::<f64>(&pos, &vel, &[1.0; 24], DOWN);
    assert!((s.rate - w).abs() < 1e-12);
}

#[test]
fn extents_of_known_shapes() {
    let column: Vec<DVec3> = (0..5)
        .map(|k| DVec3::new(0.0, 0.0, -2.0 * k as f64))
        .collect();
    let (h, v) = extents::<f64>(&column, DOWN);
    assert!(h.abs() < 1e-12 && (v - 8.0).abs() < 1e-12);
    let square = [
        DVec3::ZERO,
        DVec3::X * 3.0,
        DVec3::new(3.0, 4.0, 1.0),
        DVec3::Y * 4.0,
    ];
    let (h, v) = extents::<f64>(&square, DOWN);
    assert!((h - 5.0).abs() < 1e-12 && (v - 1.0).abs() < 1e-12);
}

#[test]
fn vertical_runs_and_the_direction_of_a_stretching_front() {
    // Bonds: 0, 1 vertical; 2 horizontal; 3, 4, 5 vertical (within 10 degrees).
    let steps = [
        DVec3::new(0.0, 0.0, -2.0),
        DVec3::new(0.1, 0.0, -2.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.3, -2.0),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(-0.2, 0.0, -2.0),
    ];
    let mut pos = vec![DVec3::ZERO];
    for s in steps {
        pos.push(*pos.last().unwrap() + s);
    }
    let bonds = chain_bonds(&pos);
    let cos10 = 10f64.to_radians().cos();
    assert_eq!(vertical_run::<f64>(&bonds, &pos, DOWN, cos10), (3, 3));
    // A chain of 10 horizontal bonds straightening one bond per time unit.
    let straighten = |order: &dyn Fn(usize) -> usize| {
        let mut first = vec![0.0; 10];
        let mut front = VerticalFront::new(&mut first);
        let flat: Vec<DVec3> = (0..11).map(|k| DVec3::X * 2.0 * k as f64).collect();
        let bonds = chain_bonds(&flat);
        for t in 0..10 {
            // Bonds turned so far hang down; the rest stay horizontal.
            let mut p = vec![DVec3::ZERO];
            for k in 0..10 {
                let down = order(k) <= t;
                let step = if down {
                    DVec3::new(0.0, 0.0, -2.0)
                } else {
                    DVec3::X * 2.0
                };
                p.push(*p.last().unwrap() + step);
            }
            front.update(&bonds, &p, DOWN, cos10, t as f64);
        }
        front.order()
    };
    let head_first = straighten(&|k| k);
    assert_eq!(head_first.count, 10);
    assert!(
        (head_first.correlation - 1.0).abs() < 1e-12,
        "{head_first:?}"
    );
    let end_first = straighten(&|k| 9 - k);
    assert!((end_first.correlation + 1.0).abs() < 1e-12, "{end_first:?}");
}
