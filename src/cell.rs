//! The periodic box's geometry: its edges and the minimum image of a separation.
//!
//! Always compiled, so that [`Params::periodic`](crate::Params::periodic) can name the
//! box in every build; the Ewald sums that use it are the `periodic` feature's
//! (`mobility::periodic`), and without that feature a step with a box is refused
//! (`StepError::Unsupported`) before anything here is called, so the firmware links
//! none of it.

use core::fmt;

use crate::fault::ParticleError;
use crate::real::Real;

/// A rejected periodic box, Ewald parameter or sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PeriodicError {
    /// A box edge is zero, negative or not finite (axis 0, 1, 2).
    BadEdge {
        /// The axis.
        axis: usize,
    },
    /// The splitting parameter, tolerance or largest radius is out of range (named).
    BadParameter(&'static str),
    /// The largest radius is not below half the smallest edge: a sphere would overlap
    /// its own image.
    SphereTooLarge,
    /// The cutoffs need more than `mobility::periodic::MAX_INDEX` images or wave vectors
    /// along an axis.
    TooElongated,
    /// A radius is not finite, not positive, or above the parameters' largest radius.
    Radius {
        /// Index of the particle.
        particle: usize,
    },
    /// A position is not finite, or a sphere lies inside another's image.
    Particle(ParticleError),
}

impl fmt::Display for PeriodicError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadEdge { axis } => write!(f, "periodic box edge {axis} must be finite and > 0"),
            Self::BadParameter(name) => write!(f, "invalid Ewald parameter: {name}"),
            Self::SphereTooLarge => write!(f, "a sphere is not smaller than half the box"),
            Self::TooElongated => write!(f, "the box is too elongated for the Ewald sums' bounds"),
            Self::Radius { particle } => {
                write!(f, "particle {particle}: radius not in (0, largest radius]")
            }
            Self::Particle(e) => write!(f, "{e}"),
        }
    }
}

/// A rectangular periodic box, edges `size` (validated: finite and positive).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periodic<T: Real> {
    size: [T; 3],
}

impl<T: Real> Periodic<T> {
    /// The box `L_x x L_y x L_z`.
    pub fn new(size: [T; 3]) -> Result<Self, PeriodicError> {
        for (axis, l) in size.iter().enumerate() {
            if !(*l > T::ZERO && l.is_finite()) {
                return Err(PeriodicError::BadEdge { axis });
            }
        }
        Ok(Self { size })
    }

    /// The edges.
    pub fn size(&self) -> [T; 3] {
        self.size
    }

    /// `L_x L_y L_z`.
    pub fn volume(&self) -> T {
        self.size[0] * self.size[1] * self.size[2]
    }

    /// The minimum image of a separation: each component reduced by a whole number of
    /// edges into `[-L/2, L/2]`. A function of `r` alone, so separations that differ by
    /// exactly a box vector give the same bits.
    pub fn minimum_image(&self, r: T::V3) -> T::V3 {
        let v = T::xyz(r);
        let f = |d: usize| {
            let (l, q) = (self.size[d], v[d] / self.size[d]);
            // Below half an edge `round` gives a signed zero and `v - 0 l` is `v + 0`
            // bit for bit (-0 included): skips libm's `round`, the hot spot of the
            // contacts' all-pairs search in a large box.
            match q.abs() < T::HALF {
                true => v[d] + T::ZERO,
                false => v[d] - T::from_f64(libm::round(q.to_f64())) * l,
            }
        };
        T::v3(f(0), f(1), f(2))
    }

    /// A position moved by whole edges into `[0, L)` (for the phases of the wave sums).
    pub fn wrap_into(&self, p: T::V3) -> T::V3 {
        let v = T::xyz(p);
        let f = |d: usize| {
            let l = self.size[d];
            v[d] - T::from_f64(libm::floor((v[d] / l).to_f64())) * l
        };
        T::v3(f(0), f(1), f(2))
    }
}

/// `r` itself without a box, its minimum image in one ([`Periodic::minimum_image`]).
/// Without the `periodic` feature no step runs with a box (it is refused), and this
/// is `r` whatever `cell` says, so the image code compiles away.
#[inline(always)]
pub fn image<T: Real>(cell: Option<&Periodic<T>>, r: T::V3) -> T::V3 {
    match cell {
        Some(c) if cfg!(feature = "periodic") => c.minimum_image(r),
        _ => r,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shortcut below half an edge gives the bits of `v - round(v / L) L` (signed
    /// zeros, half-edge ties and far images included), in f64 and f32.
    #[test]
    fn minimum_image_has_the_bits_of_the_rounded_form() -> Result<(), PeriodicError> {
        fn check<T: Real>(l: f64, x: f64) -> Result<(), PeriodicError> {
            let c = Periodic::<T>::new([T::from_f64(l); 3])?;
            let (lt, v) = (T::from_f64(l), T::from_f64(x));
            let want = v - T::from_f64(libm::round((v / lt).to_f64())) * lt;
            let got = T::xyz(c.minimum_image(T::v3(v, v, v)))[0];
            assert_eq!(
                got.to_f64().to_bits(),
                want.to_f64().to_bits(),
                "{x} in {l}"
            );
            Ok(())
        }
        let special = [0.0, -0.0, 5.0, -5.0, 4.999999, -5.000001, 1e-300, -1e-300];
        let spread = (0..2000).map(|k| (k as f64 - 1000.0) * 0.0137 * 3.1);
        for x in special.into_iter().chain(spread) {
            for l in [10.0, 7.3, 0.9] {
                check::<f64>(l, x)?;
                check::<f32>(l, x)?;
            }
        }
        Ok(())
    }
}
