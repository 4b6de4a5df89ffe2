//! External forces: buoyant weight, and a hook for anything else (DLVO, walls, traps)
//! that needs no allocation.

use crate::error::StepError;
use crate::params::Params;
use crate::particles::sphere_volume;
use crate::real::Real;

/// Adds user forces on top of gravity. Called with candidate positions (possibly
/// more than once per step, e.g. at a predictor), so it must not keep state that
/// assumes one call per step.
pub trait ExternalForce<T: Real> {
    /// Adds forces into `force` (which already holds the buoyant weight).
    fn add(&mut self, pos: &[T::V3], radius: &[T], force: &mut [T::V3]);
}

/// No forces besides gravity.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoForce;

impl<T: Real> ExternalForce<T> for NoForce {
    fn add(&mut self, _: &[T::V3], _: &[T], _: &mut [T::V3]) {}
}

impl<T: Real, F: FnMut(&[T::V3], &[T], &mut [T::V3])> ExternalForce<T> for F {
    fn add(&mut self, pos: &[T::V3], radius: &[T], force: &mut [T::V3]) {
        self(pos, radius, force)
    }
}

/// Buoyant weight `(rho_p - rho_f) V g` plus the hook, into `out`; NaN is reported.
pub fn external<T: Real, E: ExternalForce<T>>(
    p: &Params<T>,
    pos: &[T::V3],
    radius: &[T],
    density: &[T],
    ext: &mut E,
    out: &mut [T::V3],
) -> Result<(), StepError> {
    for ((f, &a), &rho) in out.iter_mut().zip(radius).zip(density) {
        *f = p.gravity * ((rho - p.fluid_density) * sphere_volume(a));
    }
    ext.add(pos, radius, out);
    match out.iter().position(|&f| !T::v3_is_finite(f)) {
        Some(particle) => Err(StepError::NonFiniteForce { particle }),
        None => Ok(()),
    }
}

/// Hookean bond forces `-k (|b| - d) b / |b|` (`-k b` for rest length `d = 0`), or with `fene = Some(Q0)` the FENE
/// forces `-k b / (1 - |b|^2 / Q0^2)`, added into `out`. A FENE bond at or past `Q0`
/// is refused ([`BondError::Overstretched`](crate::BondError::Overstretched)).
pub fn springs<T: Real>(
    bonds: &[crate::bonds::Bond<T>],
    stiffness: T,
    fene: Option<T>,
    pos: &[T::V3],
    out: &mut [T::V3],
) -> Result<(), crate::BondError> {
    springs_in(bonds, stiffness, fene, pos, None, out)
}

/// [`springs`] in a periodic box `cell`: each bond vector is its minimum image.
pub fn springs_in<T: Real>(
    bonds: &[crate::bonds::Bond<T>],
    stiffness: T,
    fene: Option<T>,
    pos: &[T::V3],
    cell: Option<crate::cell::Periodic<T>>,
    out: &mut [T::V3],
) -> Result<(), crate::BondError> {
    for (k, b) in bonds.iter().enumerate() {
        let r = crate::cell::image(cell.as_ref(), pos[b.i] - pos[b.j]);
        let f = match fene {
            // Rest length zero: -k r, defined at r = 0 too.
            None if b.length == T::ZERO => r * -stiffness,
            None => {
                let s = T::norm(r);
                r * (-stiffness * (s - b.length) / s)
            }
            Some(q0) => {
                let x = T::norm2(r) / (q0 * q0);
                overstretched(k, x)?;
                r * (-stiffness / (T::ONE - x))
            }
        };
        out[b.i] += f;
        out[b.j] -= f;
    }
    Ok(())
}

/// Refuses a FENE bond `k` at `x = Q^2 / Q0^2 >= 1` (or NaN).
pub(crate) fn overstretched<T: Real>(k: usize, x: T) -> Result<(), crate::BondError> {
    if x < T::ONE {
        Ok(())
    } else {
        Err(crate::BondError::Overstretched {
            bond: k,
            ratio: x.to_f64().sqrt(),
        })
    }
}

/// Soft excluded volume: overlapping spheres (`s < a_i + a_j`) repel with
/// `k (a_i + a_j - s)` along their line of centres. The paper's chains have no
/// excluded volume, so without it beads of a settling chain can pass through each
/// other; with an explicit integrator keep `dt k / (3 pi eta a) < 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftContact<T> {
    /// Contact stiffness `k` (force per overlap length).
    pub stiffness: T,
}

impl<T: Real> ExternalForce<T> for SoftContact<T> {
    fn add(&mut self, pos: &[T::V3], radius: &[T], force: &mut [T::V3]) {
        for (i, (&pi, &ai)) in pos.iter().zip(radius).enumerate() {
            let (before, fi) = force[..=i].split_at_mut(i);
            let others = before.iter_mut().zip(pos).zip(radius);
            for ((fj, &pj), &aj) in others {
                let r = pi - pj;
                let reach = ai + aj;
                let s2 = T::norm2(r);
                if s2 < reach * reach && s2 > T::ZERO {
                    let s = s2.sqrt();
                    let f = r * (self.stiffness * (reach - s) / s);
                    fi[0] += f;
                    *fj -= f;
                }
            }
        }
    }
}
