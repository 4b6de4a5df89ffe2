//! What a step's checks derive once and hold for its products ([`Held`]): the box's
//! Ewald parameters, PSE's ([`Params::pse`](crate::Params::pse)), or the fast
//! free-space product's, which gives products only as PSE does and reaches the stages
//! through the same sums; and the storage of a step's fast products over the caller's
//! arrays (`Store`).
//!
//! `xi` and the cutoffs come from the box and the step's largest radius by
//! [`Ewald::new`], once, in the step's checks (`integrate/checks/periodic_box.rs`), and
//! every product, assembly and matrix-free metric block of the step reads that one copy
//! ([`Sums`]): they depend on the box and the radii only, which a step does not change.
//! Not held in the parameters: the largest radius is the state's (a radius above a
//! stored one would be refused) and `Params` stays small and `Copy`. The assembly and
//! the products run in the bands of [`crate::parallel`] (each block summed on its own,
//! so the same bits on any number of threads); so does the matrix-free product's
//! real-space half ([`periodic::free_product`](crate::mobility::periodic::free_product)).

use crate::cell::Periodic;
use crate::error::StepError;
use crate::geometry::{HeldSums, Sums, sums::BoxSums};
use crate::mobility::periodic::Ewald;
use crate::real::Real;

#[cfg(feature = "pse")]
pub(crate) use fast::{PseSize, fast_store, pse_size, step_sums};

/// What a step holds for its products ([`Sums`] borrows it): the Ewald parameters,
/// PSE's ([`Params::pse`](crate::Params::pse)), or the fast free-space product's.
#[derive(Debug)]
pub(crate) enum Held<T: Real> {
    /// The exact Ewald sums.
    Ewald(Ewald<T>),
    /// The PSE fast path.
    #[cfg(feature = "pse")]
    Pse(crate::mobility::pse::Pse<T>),
    /// Free space's fast product ([`Params::pse`](crate::Params::pse) without a box):
    /// the parameters derived for the cloud at the step's start (`geometry/free/fast.rs`).
    #[cfg(feature = "fast-free")]
    Fast(crate::mobility::free_fast::FreeFast<T>),
}

/// The largest radius of the step (the sums accept every radius up to it).
fn a_max<T: Real>(radius: &[T]) -> T {
    radius.iter().fold(T::ZERO, |m, &a| m.max(a))
}

impl<T: Real> Held<T> {
    /// The Ewald parameters for this box and these spheres (every radius at most the
    /// largest, so the sums accept each one).
    pub(crate) fn ewald(cell: Periodic<T>, radius: &[T]) -> Result<Self, StepError> {
        Ok(Self::Ewald(ewald(cell, radius)?))
    }
}

/// The Ewald parameters for this box and these spheres.
fn ewald<T: Real>(cell: Periodic<T>, radius: &[T]) -> Result<Ewald<T>, StepError> {
    Ok(Ewald::new(cell, a_max(radius))?)
}

/// The Ewald sums of what the step's checks hold, as [`Sums`] (none for PSE's or the
/// fast free-space product's, which need their storage: `step_sums`).
pub(crate) fn held_ewald<T: Real>(held: &HeldSums<T>) -> Sums<'_, T> {
    match held.as_ref()? {
        Held::Ewald(e) => Some(BoxSums::Ewald(e)),
        // PSE's and the fast product's, where the kernel has them.
        #[allow(unreachable_patterns)]
        _ => None,
    }
}

/// The step's sums ([`Sums`]): Ewald's (no `pse` feature).
#[cfg(not(feature = "pse"))]
pub(crate) fn step_sums<T: Real>(held: Option<&Held<T>>) -> Sums<'_, T> {
    match held? {
        Held::Ewald(e) => Some(BoxSums::Ewald(e)),
    }
}

/// The fast products' part (feature `pse`): PSE's parameters, and the storage of a
/// step's fast products over the caller's arrays ([`Store`]).
#[cfg(feature = "pse")]
mod fast {
    use super::{Held, a_max};
    use crate::cell::Periodic;
    use crate::error::StepError;
    use crate::geometry::fast::Slices;
    #[cfg(feature = "fast-free")]
    use crate::geometry::free::fast::FastStep;
    use crate::geometry::{Sums, sums::BoxSums, sums::PseStep};
    pub use crate::mobility::pse::PseSize;
    use crate::mobility::pse::{Pse, PseError, PseStorage};
    use crate::parallel::Parallel;
    use crate::real::Real;

    /// The storage of a step's fast products, over the caller's arrays. One per step, on
    /// its stack: the fast variant's parameters are held by value (no allocation to box
    /// them).
    #[allow(clippy::large_enum_variant)]
    pub(crate) enum Store<'a, T: Real> {
        /// PSE's, in a box.
        Pse(PseStep<'a, T>),
        /// The fast free-space product's.
        #[cfg(feature = "fast-free")]
        Fast(FastStep<'a, T>),
    }

    impl<T: Real> Held<T> {
        /// The PSE parameters of this box, these spheres and the tolerance `tol`.
        pub(crate) fn pse(cell: Periodic<T>, radius: &[T], tol: f64) -> Result<Self, StepError> {
            Ok(Self::Pse(pse(cell, radius, tol)?))
        }
    }

    /// The PSE parameters of this box, these spheres and the tolerance `tol`.
    fn pse<T: Real>(cell: Periodic<T>, radius: &[T], tol: f64) -> Result<Pse<T>, StepError> {
        Ok(Pse::new(cell, a_max(radius), tol)?)
    }

    /// The PSE storage a step of these spheres in `cell` with the tolerance `tol` needs,
    /// from the same parameters the step derives (`integrate::pse_storage`): the grand
    /// product's where `grand` (the iterative near field's far field).
    pub(crate) fn pse_size<T: Real>(
        cell: Periodic<T>,
        radius: &[T],
        (tol, grand): (f64, bool),
    ) -> Result<PseSize, StepError> {
        let pse = pse(cell, radius, tol)?;
        Ok(match grand {
            true => pse.storage_grand(radius.len()),
            false => pse.storage(radius.len()),
        })
    }

    /// The caller's fast arrays as the step's storage, after checking them against the
    /// step's PSE parameters, or fitting the fast free-space product's to them
    /// (`geometry/free/fast.rs`); `None` where the step sums by Ewald or takes the pair
    /// blocks.
    pub(crate) fn fast_store<'a, T: Real>(
        held: Option<&'a Held<T>>,
        spheres: (&[T::V3], &[T]),
        slices: Slices<'a, T>,
        par: &'a dyn Parallel,
    ) -> Result<Option<Store<'a, T>>, StepError> {
        let n = spheres.0.len();
        let pse = match held {
            Some(Held::Pse(pse)) => pse,
            #[cfg(feature = "fast-free")]
            Some(Held::Fast(fast)) => {
                let step = FastStep::new(fast, spheres, slices, par)?;
                return Ok(Some(Store::Fast(step)));
            }
            _ => return Ok(None),
        };
        let (complex, index, vectors, _) = slices;
        let need = pse.storage(n);
        if complex.len() < need.complex || index.len() < need.index || vectors.len() < need.vectors
        {
            return Err(PseError::Storage {
                need: [need.complex, need.index, need.vectors],
                have: [complex.len(), index.len(), vectors.len()],
            }
            .into());
        }
        let store = PseStorage::new(complex, index, vectors).with_parallel(par);
        Ok(Some(Store::Pse(PseStep::new(pse, store))))
    }

    /// The step's sums ([`Sums`]) over what its checks hold and, for PSE, the storage
    /// [`fast_store`] made.
    pub(crate) fn step_sums<'a, T: Real>(
        held: Option<&'a Held<T>>,
        store: Option<&'a Store<'_, T>>,
    ) -> Sums<'a, T> {
        match (held?, store) {
            (Held::Ewald(e), _) => Some(BoxSums::Ewald(e)),
            (_, Some(Store::Pse(s))) => Some(BoxSums::Pse(s)),
            // The fast free-space product gives products only, as PSE does: the stages
            // read it through the same variant.
            #[cfg(feature = "fast-free")]
            (_, Some(Store::Fast(s))) => Some(BoxSums::Pse(s)),
            // `fast_store` makes the storage for every fast step.
            (_, None) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ewald;
    use crate::cell::Periodic;
    use crate::error::StepError;
    use crate::linalg::{MobMut, Sym, tri};
    use crate::mobility::periodic;
    use crate::noise::reduced;
    use crate::parallel::{self, Serial, band_scratch};
    use crate::real::Real;
    use glam::DVec3;

    /// Spheres in the box: 64, so that the test's storage fits a test thread's stack
    /// (the kernel and its tests allocate nothing). One band; the copy's products at
    /// 512 spheres in sixteen bands are `tests/kernel/box_copy.rs`.
    const N: usize = 64;

    /// The box's assembly pass with the compact copy written beside it
    /// (`Params::compact_products`) leaves the `f64` blocks and the pass's product bit
    /// for bit as the pass without it (the unconstrained move keeps its bits), and the
    /// copy it writes is the copy `reduced::copy_apply` packs from those blocks, bit for
    /// bit. A jittered 4^3 lattice of spacing 3 filling a box of edge 12 (radii 0.8 to
    /// 1, volume fraction 0.12: images at every distance).
    #[test]
    fn packing_in_the_boxs_pass_changes_neither_blocks_nor_product() -> Result<(), StepError> {
        let pos: [DVec3; N] = core::array::from_fn(|k| {
            let site = DVec3::new((k % 4) as f64, ((k / 4) % 4) as f64, (k / 16) as f64);
            let t = k as f64;
            let jitter = DVec3::new(libm::sin(1.3 * t), libm::cos(0.7 * t), libm::sin(2.1 * t));
            3.0 * site + 1.5 + 0.2 * jitter
        });
        let radius: [f64; N] = core::array::from_fn(|i| 0.8 + 0.05 * (i % 5) as f64);
        let f: [DVec3; N] = core::array::from_fn(|i| {
            DVec3::new(libm::sin(i as f64), 0.5, libm::cos(0.3 * i as f64))
        });
        let cell = Periodic::new([12.0; 3])?;
        // The parameters' default viscosity.
        let eta = 1.0;
        let ew = ewald(cell, &radius)?;
        let mut bands = [DVec3::ZERO; band_scratch(N)];
        let spheres = (&pos[..], &radius[..]);
        let mut plain: [Sym<f64>; tri(N)] = [[0.0; 6]; tri(N)];
        let mut packed: [Sym<f64>; tri(N)] = [[0.0; 6]; tri(N)];
        let (mut u_plain, mut u_packed) = ([DVec3::ZERO; N], [DVec3::ZERO; N]);
        let mut copy = [f64::M3_ZERO; reduced::slots(N)];
        let mu = MobMut::Sym(&mut plain);
        let work = (&Serial as &dyn parallel::Parallel, &mut bands[..]);
        periodic::assemble_apply(&ew, eta, spheres, mu, (&f, &mut u_plain), work, None)?;
        let mu = MobMut::Sym(&mut packed);
        let (work, side) = ((&Serial as _, &mut bands[..]), Some(&mut copy[..]));
        periodic::assemble_apply(&ew, eta, spheres, mu, (&f, &mut u_packed), work, side)?;
        let same = |a: &[DVec3], b: &[DVec3]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| x.to_array().map(f64::to_bits) == y.to_array().map(f64::to_bits))
        };
        assert!(same(&u_packed, &u_plain));
        assert!(
            packed
                .iter()
                .zip(&plain)
                .all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits))
        );
        // The copy `copy_apply` packs from the plain pass's blocks: the same bits.
        let mut again = [f64::M3_ZERO; reduced::slots(N)];
        let (mut y, mut z) = ([DVec3::ZERO; N], [DVec3::ZERO; N]);
        reduced::copy_apply::<f64>(&Serial, &plain, N, &mut again, &f, &mut y, &mut z);
        let bits = |m: &<f64 as Real>::M3| f64::m3_entries(m).map(f64::to_bits);
        assert!(copy.iter().zip(&again).all(|(a, b)| bits(a) == bits(b)));
        Ok(())
    }
}
