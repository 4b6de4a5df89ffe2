//! Accumulated twist for any number of beads.
//!
//! The kernel's `observables::Twist<T, N>` keeps the last azimuths in an array of
//! compile-time capacity `N`; this is the same measure over a vector, with the same
//! arithmetic in the same order (so the same bits as the kernel's for the same input).
//! It goes once the kernel's twist takes caller-owned storage.

use hydrorattle::Real;

/// Accumulated azimuth of the chain about the vertical through the head (bead 0): the
/// squared-distance-weighted mean change of every other bead's unwrapped azimuth,
/// added up over updates. Updates where the beads' root-mean-square distance from the
/// axis is below `min_radius` add nothing (a straight vertical chain has no azimuth).
#[derive(Clone, Debug)]
pub struct Twist<T: Real> {
    prev: Vec<T>,
    min_radius: T,
    /// Accumulated twist (radians, right-handed about "up").
    pub total: T,
}

impl<T: Real> Twist<T> {
    /// Nothing accumulated yet.
    pub fn new(min_radius: T) -> Self {
        Self {
            prev: Vec::new(),
            min_radius,
            total: T::ZERO,
        }
    }

    /// Adds the twist since the last call (none on the first) and returns the total.
    /// Call it often enough that no bead turns by half a turn between calls.
    pub fn update(&mut self, pos: &[T::V3], gravity: T::V3) -> T {
        let g = T::norm(gravity);
        if pos.is_empty() || g == T::ZERO {
            return self.total;
        }
        let up = -gravity / g;
        // A horizontal orthonormal frame, seeded away from `up`.
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
        let started = self.prev.len() == pos.len();
        self.prev.resize(pos.len(), T::ZERO);
        let (mut num, mut den) = (T::ZERO, T::ZERO);
        for (r, prev) in pos.iter().zip(self.prev.iter_mut()).skip(1) {
            let d = *r - pos[0];
            let (x, y) = (T::dot(d, ex), T::dot(d, ey));
            let phi = y.atan2(x);
            if started {
                let w = x * x + y * y;
                num += w * unwrap(phi - *prev);
                den += w;
            }
            *prev = phi;
        }
        let count = T::from_f64((pos.len() - 1) as f64);
        if started && den > self.min_radius * self.min_radius * count {
            self.total += num / den;
        }
        self.total
    }
}

/// An angle change brought into `[-pi, pi]`.
fn unwrap<T: Real>(mut a: T) -> T {
    let turn = T::TWO * T::PI;
    while a > T::PI {
        a -= turn;
    }
    while a < -T::PI {
        a += turn;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydrorattle::glam::DVec3;
    use hydrorattle::observables;

    /// A bent chain turned about the vertical through its head in steps.
    fn frames() -> Vec<Vec<DVec3>> {
        let base: Vec<DVec3> = (0..40)
            .map(|k| {
                let k = k as f64;
                DVec3::new(0.3 * k, 0.1 * k * k / 40.0, -1.1 * k)
            })
            .collect();
        (0..60)
            .map(|s| {
                let a = 0.07 * s as f64 + 0.01 * (s as f64).sin();
                let (c, si) = (a.cos(), a.sin());
                base.iter()
                    .map(|p| DVec3::new(c * p.x - si * p.y, si * p.x + c * p.y, p.z))
                    .collect()
            })
            .collect()
    }

    #[test]
    fn same_bits_as_the_kernels_twist() {
        let g = DVec3::new(0.0, 0.0, -1.0);
        let mut ours = Twist::<f64>::new(0.25);
        let mut kernel = observables::Twist::<f64, 64>::new(0.25);
        for f in frames() {
            assert_eq!(ours.update(&f, g).to_bits(), kernel.update(&f, g).to_bits());
        }
        assert!((ours.total - (59.0 * 0.07 + 0.01 * 59f64.sin())).abs() < 1e-9);
    }

    #[test]
    fn a_vertical_chain_adds_nothing() {
        let chain: Vec<DVec3> = (0..5).map(|k| DVec3::new(0.0, 0.0, -(k as f64))).collect();
        let mut t = Twist::<f64>::new(0.25);
        t.update(&chain, DVec3::new(0.0, 0.0, -1.0));
        assert_eq!(t.update(&chain, DVec3::new(0.0, 0.0, -1.0)), 0.0);
    }
}
