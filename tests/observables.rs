//! Outcome metrics and the classifier on synthetic shapes whose answers are known.

use hydrorattle::Bond;
use hydrorattle::glam::DVec3;
use hydrorattle::observables::{
    Outcome, Thresholds, Twist, centre_of_mass, classify, extension, settling_speed, verticality,
};

const DOWN: DVec3 = DVec3::new(0.0, 0.0, -1.0);

fn chain_bonds(pos: &[DVec3]) -> Vec<Bond<f64>> {
    (1..pos.len())
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: (pos[i] - pos[i - 1]).length(),
        })
        .collect()
}

#[test]
fn a_straight_vertical_chain_is_stretched() {
    let pos: Vec<DVec3> = (0..25)
        .map(|k| DVec3::new(0.0, 0.0, 2.1 * k as f64))
        .collect();
    let b = chain_bonds(&pos);
    assert!((extension(&pos, &b) - 1.0).abs() < 1e-12);
    assert!((verticality::<f64>(&pos, DOWN) - 1.0).abs() < 1e-12);
    let th = Thresholds::default();
    assert_eq!(classify(1.0, 1.0, 0.0, &th), Outcome::Stretched);
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
    let mut tw: Twist<f64, 16> = Twist::new(0.1);
    let dt = 0.5;
    for s in 0..=200 {
        tw.update(&shape(s as f64 * dt), DOWN);
    }
    // Gravity down: "up" is +z, and the tails turn counter-clockwise seen from above.
    assert!((tw.total - w * 200.0 * dt).abs() < 1e-9, "{}", tw.total);
    let th = Thresholds::default();
    assert_eq!(classify(0.5, 0.3, w, &th), Outcome::Twisting);
    assert_eq!(classify(0.5, 0.3, 0.0001, &th), Outcome::Other);
}

#[test]
fn a_chain_on_the_axis_accumulates_no_twist() {
    let mut tw: Twist<f64, 8> = Twist::new(0.1);
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
