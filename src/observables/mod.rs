//! Outcome metrics of a settling chain, defined once here. Motion and shape measures over
//! time (rotation about the vertical, poloidal circulation, vertical runs and fronts,
//! extents, settling speed) are in `motion.rs`; the named states they add up to (the
//! vocabulary of an outcome timeline) in `state.rs`.
//!
//! Conventions: particle 0 is the head, the last particle the chain's end; "down" is
//! the direction of gravity.

mod motion;
mod state;

pub use motion::{
    FrontOrder, Rotation, VerticalFront, bond_is_vertical, com_settling_speed, extents,
    poloidal_circulation, spin_about_vertical, vertical_run,
};
pub use state::{FrameState, Shape, StateThresholds, is_rotating, state_name, state_of};

use crate::bonds::Bond;
use crate::real::Real;

/// End-to-end distance (head to last particle) over the contour length (sum of bond
/// lengths): 1 for a straight chain.
pub fn extension<T: Real>(pos: &[T::V3], bonds: &[Bond<T>]) -> T {
    let contour = bonds.iter().fold(T::ZERO, |a, b| a + b.length);
    match (pos.first(), pos.last()) {
        (Some(&h), Some(&e)) if contour > T::ZERO => T::norm(e - h) / contour,
        _ => T::ZERO,
    }
}

/// `|cos|` of the angle between the head-to-end vector and gravity: 1 when the chain
/// hangs vertically ("like a chopstick"), 0 when it lies horizontally.
pub fn verticality<T: Real>(pos: &[T::V3], gravity: T::V3) -> T {
    let (g, len) = (T::norm(gravity), pos.len());
    if len < 2 || g == T::ZERO {
        return T::ZERO;
    }
    let d = pos[len - 1] - pos[0];
    let l = T::norm(d);
    if l == T::ZERO {
        T::ZERO
    } else {
        (T::dot(d, gravity) / (l * g)).abs()
    }
}

/// Mass-weighted centre.
pub fn centre_of_mass<T: Real>(pos: &[T::V3], mass: impl Fn(usize) -> T) -> T::V3 {
    let mut c = T::V3_ZERO;
    let mut m = T::ZERO;
    for (i, &r) in pos.iter().enumerate() {
        c += r * mass(i);
        m += mass(i);
    }
    if m > T::ZERO { c / m } else { c }
}

/// Settling speed of particle `i` along gravity (positive when moving down).
pub fn settling_speed<T: Real>(vel: &[T::V3], i: usize, gravity: T::V3) -> T {
    let g = T::norm(gravity);
    match vel.get(i) {
        Some(&v) if g > T::ZERO => T::dot(v, gravity) / g,
        _ => T::ZERO,
    }
}

/// Accumulated azimuth of the chain about the vertical through the head.
///
/// Each update measures every other particle's azimuth about the axis through the head
/// along gravity, unwraps its change since the last update, and adds the mean change
/// weighted by the squared distance from the axis (so particles on the axis, whose
/// azimuth is meaningless, do not count). Call it often enough that no particle turns
/// by more than half a turn between calls. A chain whose root-mean-square distance from
/// the axis is below `min_radius` (a straight vertical chain) has no meaningful azimuth:
/// such updates add nothing.
/// `prev` is caller storage, one entry per particle (any length: a fixed array in
/// firmware, a `Vec` on a host); more particles than that are ignored by `update`.
#[derive(Debug)]
pub struct Twist<'a, T: Real> {
    prev: &'a mut [T],
    started: bool,
    min_radius: T,
    /// Accumulated twist angle (radians, right-handed about "up").
    pub total: T,
}

impl<'a, T: Real> Twist<'a, T> {
    /// No twist accumulated yet, over caller storage `prev`; `min_radius` as described
    /// on the type.
    pub fn new(prev: &'a mut [T], min_radius: T) -> Self {
        Self {
            prev,
            started: false,
            min_radius,
            total: T::ZERO,
        }
    }

    /// Adds the twist since the last call and returns the accumulated total.
    pub fn update(&mut self, pos: &[T::V3], gravity: T::V3) -> T {
        let g = T::norm(gravity);
        if pos.is_empty() || pos.len() > self.prev.len() || g == T::ZERO {
            return self.total;
        }
        let up = -gravity / g;
        // An orthonormal frame (ex, ey) of the horizontal plane.
        let seed = if T::xyz(up)[0].abs() < T::HALF {
            T::v3(T::ONE, T::ZERO, T::ZERO)
        } else {
            T::v3(T::ZERO, T::ONE, T::ZERO)
        };
        let ex = {
            let v = seed - up * T::dot(seed, up);
            v / T::norm(v)
        };
        let ey = T::cross(up, ex);
        let (mut num, mut den) = (T::ZERO, T::ZERO);
        let two_pi = T::TWO * T::PI;
        for k in 1..pos.len() {
            let d = pos[k] - pos[0];
            let (x, y) = (T::dot(d, ex), T::dot(d, ey));
            let phi = y.atan2(x);
            if self.started {
                let mut dphi = phi - self.prev[k];
                while dphi > T::PI {
                    dphi -= two_pi;
                }
                while dphi < -T::PI {
                    dphi += two_pi;
                }
                let w = x * x + y * y;
                num += w * dphi;
                den += w;
            }
            self.prev[k] = phi;
        }
        let count = T::from_f64((pos.len() - 1) as f64);
        if self.started && den > self.min_radius * self.min_radius * count {
            self.total += num / den;
        }
        self.started = true;
        self.total
    }
}
