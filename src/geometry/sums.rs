//! The periodic mobility a step sums with: the exact Ewald sums
//! ([`crate::mobility::periodic`], the default) or the PSE fast path
//! ([`crate::mobility::pse`], [`Params::pse`](crate::Params::pse)). Held once per step
//! (parameters derived in the step's checks) and read by every product of the step:
//! the mobility product, the Krylov metric's product and the Lanczos noise's.
//!
//! PSE gives products only. Everything that needs a block of the matrix (assembly,
//! Cholesky noise, the tabulating solvers Sweep and Newton) reads the Ewald sums, and
//! the step's checks refuse those with PSE ([`BoxSums::ewald`] is `None` then).
//! PSE's storage is the caller's ([`Workspace::with_pse`](crate::Workspace::with_pse)),
//! held in a `RefCell` ([`PseStep`]) so that the step's products, which share the
//! metric and product closures by shared reference, can each borrow it in turn (they
//! never nest, so a borrow never fails; if one did, the product reports it). The
//! step's stages see it as a [`FastProduct`] trait object (`geometry/fast.rs`, shared
//! with the fast free-space product): the storage's own lifetime
//! stays out of their signatures.

#[cfg(feature = "pse")]
use core::cell::RefCell;
use core::fmt;

#[cfg(feature = "pse")]
use super::fast::FastProduct;
use crate::error::StepError;
use crate::mobility::periodic::{self, Ewald};
#[cfg(feature = "pse")]
use crate::mobility::pse::{Part, Pse, PseStorage};
#[cfg(feature = "pse")]
use crate::noise::{Noise, lanczos::Lanczos};
use crate::parallel::Parallel;
use crate::real::Real;

/// The step's periodic sums: Ewald's parameters, or PSE's with the caller's storage.
pub enum BoxSums<'a, T: Real> {
    /// The exact Ewald sums (dense pair blocks; assembly and products).
    Ewald(&'a Ewald<T>),
    /// The PSE product (`docs/PERIODIC.md`, section PSE) with its storage ([`PseStep`]).
    #[cfg(feature = "pse")]
    Pse(&'a dyn FastProduct<T>),
}

/// PSE's parameters and the caller's storage for one step's products.
#[cfg(feature = "pse")]
pub struct PseStep<'s, T: Real> {
    pse: &'s Pse<T>,
    store: RefCell<PseStorage<'s, T>>,
}

#[cfg(feature = "pse")]
impl<'s, T: Real> PseStep<'s, T> {
    /// The products of `pse` over `store` (checked by each product).
    pub fn new(pse: &'s Pse<T>, store: PseStorage<'s, T>) -> Self {
        Self {
            pse,
            store: RefCell::new(store),
        }
    }
}

#[cfg(feature = "pse")]
impl<T: Real> FastProduct<T> for PseStep<'_, T> {
    fn product(
        &self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        u: &mut [T::V3],
    ) -> Result<(), StepError> {
        let mut store = self
            .store
            .try_borrow_mut()
            .map_err(|_| StepError::Unsupported("a PSE product inside another (storage in use)"))?;
        Ok(self
            .pse
            .apply(Part::Both, eta, pos, radius, f, u, &mut store)?)
    }

    /// `(U, W) = M (F, T)` over the `2n` vectors: PSE's grand product
    /// ([`Pse::apply_grand`]), the iterative near field's far field in the box (its
    /// storage at least [`Pse::storage_grand`], which `integrate::pse_storage` sizes when
    /// the near field is on).
    fn grand(
        &self,
        eta: T,
        spheres: (&[T::V3], &[T]),
        ft: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let mut store = self
            .store
            .try_borrow_mut()
            .map_err(|_| StepError::Unsupported("a PSE product inside another (storage in use)"))?;
        let ((f, t), (u, w)) = super::fast::grand_halves::<T>(spheres.0.len(), ft, out)?;
        Ok(self.pse.apply_grand(eta, spheres, f, t, u, w, &mut store)?)
    }

    fn noise(
        &self,
        eta: T,
        spheres: (&[T::V3], &[T]),
        rng: &mut Noise,
        s: Lanczos<T>,
        z: &mut [T::V3],
        out: &mut [T::V3],
        scratch: (&mut [T::V3], &mut [T]),
    ) -> Result<u32, StepError> {
        let mut store = self
            .store
            .try_borrow_mut()
            .map_err(|_| StepError::Unsupported("a PSE draw inside a product (storage in use)"))?;
        let pse = self.pse;
        Ok(pse.noise_in(eta, spheres, rng, s, z, out, &mut store, scratch)?)
    }
}

/// The sums a far field holds ([`BlockSums`](super::BlockSums)): the Ewald sums'
/// blocks alone, `Send` and `Sync`, unlike a PSE step's storage.
pub type Blocks<'a, T> = &'a Ewald<T>;

/// The Ewald sums as the step's.
impl<'a, T: Real> From<&'a Ewald<T>> for BoxSums<'a, T> {
    fn from(e: &'a Ewald<T>) -> Self {
        Self::Ewald(e)
    }
}

/// The Ewald sums of the step's, where it sums by Ewald (the sums back on PSE's path,
/// which has no blocks).
impl<'a, T: Real> TryFrom<BoxSums<'a, T>> for &'a Ewald<T> {
    type Error = BoxSums<'a, T>;

    fn try_from(sums: BoxSums<'a, T>) -> Result<Self, Self::Error> {
        sums.ewald().ok_or(sums)
    }
}

impl<T: Real> Clone for BoxSums<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T: Real> Copy for BoxSums<'_, T> {}

impl<T: Real> fmt::Debug for BoxSums<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Ewald(e) => f.debug_tuple("Ewald").field(e).finish(),
            #[cfg(feature = "pse")]
            Self::Pse(_) => f.write_str("Pse"),
        }
    }
}

impl<'a, T: Real> BoxSums<'a, T> {
    /// The PSE sums' own products and noise, where the step sums by PSE.
    #[cfg(feature = "pse")]
    pub fn pse(self) -> Option<&'a dyn FastProduct<T>> {
        match self {
            Self::Ewald(_) => None,
            Self::Pse(p) => Some(p),
        }
    }

    /// The Ewald parameters, where the step sums by Ewald (`None` on the PSE path,
    /// which has no pair blocks).
    pub fn ewald(self) -> Option<&'a Ewald<T>> {
        match self {
            Self::Ewald(e) => Some(e),
            #[cfg(feature = "pse")]
            Self::Pse(..) => None,
        }
    }

    /// `u = M f`, the box's translational mobility (viscosity `eta`) by the step's sums:
    /// Ewald's real-space half in bands through `par` (`bands`: their scratch,
    /// [`periodic::free_product`]), PSE's through its storage's own.
    #[allow(clippy::too_many_arguments)]
    pub fn product(
        self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        u: &mut [T::V3],
        (par, bands): (&dyn Parallel, &mut [T::V3]),
    ) -> Result<(), StepError> {
        match self {
            Self::Ewald(e) => Ok(periodic::free_product(
                par, e, eta, pos, radius, f, u, bands,
            )?),
            #[cfg(feature = "pse")]
            Self::Pse(p) => p.product(eta, pos, radius, f, u),
        }
    }
}
