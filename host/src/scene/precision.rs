//! The scene in the kernel's precision: a value valid in f64 may overflow or vanish in
//! f32 (a position past 3.4e38, a radius that rounds to zero), and a bond length whose
//! square overflows is refused by the kernel in either. Checked here with the kernel's
//! own rules, so that the error points at the value's line.

use hydrorattle::{Bond as KBond, Real};

use super::error::{Issue, issue};
use super::model::{Bond, Particle, Precision};
use super::resolve::BodySpans;

/// Checks every particle and bond as the kernel will see them in `precision`.
pub(super) fn check(
    particles: &[Particle],
    bonds: &[Bond],
    precision: Precision,
    spans: &BodySpans,
) -> Result<(), Issue> {
    match precision {
        Precision::F32 => check_t::<f32>(particles, bonds, spans, "f32", f32::MIN_POSITIVE.into()),
        Precision::F64 => check_t::<f64>(particles, bonds, spans, "f64", f64::MIN_POSITIVE),
    }
}

fn check_t<T: Real>(
    particles: &[Particle],
    bonds: &[Bond],
    spans: &BodySpans,
    name: &str,
    min_normal: f64,
) -> Result<(), Issue> {
    for (k, p) in particles.iter().enumerate() {
        let mut kp = hydrorattle::Particle::new(
            T::v3_from(p.position),
            T::from_f64(p.radius),
            T::from_f64(p.density),
        );
        kp.velocity = T::v3_from(p.velocity);
        if let Err(e) = hydrorattle::particles::check_one(k, &kp) {
            return Err(issue(spans.position(k), format!("{e} in {name}")));
        }
        let mass = hydrorattle::particles::sphere_volume(kp.radius) * kp.density;
        if !T::v3_is_finite(T::v3_from(p.angular_velocity)) || !mass.is_finite() {
            return Err(issue(
                spans.position(k),
                format!("particle {k}: its mass or angular velocity overflows in {name}"),
            ));
        }
    }
    for (l, b) in bonds.iter().enumerate() {
        let kb = KBond {
            i: 0,
            j: 1,
            length: T::from_f64(b.length),
        };
        // A rest length whose square is subnormal or zero has no relative error to
        // measure (the residual divides by it): zero (a spring's) or normal only.
        let tiny = kb.length > T::ZERO && (kb.length * kb.length).to_f64() < min_normal;
        if tiny || hydrorattle::bonds::validate(&[kb], 2).is_err() {
            return Err(issue(
                spans.bond(l),
                format!(
                    "bond {l} between [{}, {}]: length {} is not usable in {name} (it must be 0 or > 0 with a normal, finite square)",
                    b.i,
                    b.j,
                    crate::output::format_f64(b.length)
                ),
            ));
        }
    }
    Ok(())
}
