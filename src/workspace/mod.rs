//! Caller-owned scratch storage for [`step`](crate::integrate::step), sized to what the
//! chosen method needs ([`Layout`]) and never allocated by the kernel.
//!
//! A [`Workspace`] borrows four slices (blocks, vectors, scalars, indices). Who owns
//! them is the caller's choice:
//! * firmware: a [`Storage`] sized at compile time from a `const` [`Layout`], which can
//!   live in a `static` (its constructor is `const`);
//! * a host: `Buffers` (crate `hydrorattle-heap`), built directly on the heap, never on the
//!   stack, so thousands of beads fit;
//! * anything else: four slices from wherever (an arena, a C caller).
//!
//! ```
//! use hydrorattle::{Layout, Method, Storage};
//! const L: Layout = Layout::new(Method::Overdamped, false, 25, 24);
//! static STORE: Storage<f32, { L.blocks }, { L.vectors }, { L.scalars }, { L.indices }> =
//!     Storage::new();
//! # let _ = &STORE;
//! ```

mod layout;
mod views;

pub use crate::error::Layout;
#[cfg(feature = "near")]
pub(crate) use layout::near_noise_sizes;
pub(crate) use layout::{block_rows, symmetric};
pub(crate) use views::{Links, Views};

use crate::bonds::Bond;
use crate::parallel::{Parallel, Serial};
use crate::real::Real;

/// Scratch for one step, borrowed from caller-owned slices. Any sizes work; a step
/// whose [`Layout`] does not fit returns [`StepError::Storage`](crate::StepError::Storage)
/// before touching anything.
#[derive(Debug)]
pub struct Workspace<'a, T: Real> {
    pub(crate) blocks: &'a mut [T::M3],
    pub(crate) vectors: &'a mut [T::V3],
    pub(crate) scalars: &'a mut [T],
    pub(crate) indices: &'a mut [usize],
    pub(crate) links: &'a mut [Bond<T>],
    pub(crate) parallel: &'a dyn Parallel,
    /// The fast products' arrays (complex, index, vectors, reals) for a step with
    /// [`Params::pse`](crate::Params::pse): PSE's in a box, the fast free-space
    /// product's (complex, index, reals) in free space.
    #[cfg(feature = "pse")]
    pub(crate) pse: PseSlices<'a, T>,
}

/// The caller's fast products' arrays (complex values, indices, vectors, reals).
#[cfg(feature = "pse")]
pub(crate) use crate::geometry::fast::Slices as PseSlices;

impl<'a, T: Real> Workspace<'a, T> {
    /// A workspace over four caller-owned slices (contents are overwritten by steps).
    pub fn new(
        blocks: &'a mut [T::M3],
        vectors: &'a mut [T::V3],
        scalars: &'a mut [T],
        indices: &'a mut [usize],
    ) -> Self {
        Self {
            blocks,
            vectors,
            scalars,
            indices,
            links: &mut [],
            parallel: &Serial,
            #[cfg(feature = "pse")]
            pse: (&mut [], &mut [], &mut [], &mut []),
        }
    }

    /// This workspace with a host's way of running the mobility's bands on several
    /// threads ([`crate::parallel`]; [`Serial`] by default). The bits do not depend on it.
    pub fn with_parallel(self, parallel: &'a dyn Parallel) -> Self {
        Self { parallel, ..self }
    }

    /// This workspace with a constraint list for steps with contacts
    /// ([`Layout::links`] entries: the bonds are copied in, the contacts follow).
    pub fn with_links(self, links: &'a mut [Bond<T>]) -> Self {
        Self { links, ..self }
    }

    /// This workspace with the arrays of the PSE products of a step with
    /// [`Params::pse`](crate::Params::pse): at least
    /// [`pse_storage`](crate::integrate::pse_storage) (complex values, indices,
    /// vectors), else the step is refused with
    /// [`StepError::BadParameter`](crate::StepError::BadParameter) before anything is
    /// touched. Not counted by [`Layout`]: the grid depends on the box and the
    /// tolerance at run time.
    #[cfg(feature = "pse")]
    pub fn with_pse(
        self,
        complex: &'a mut [crate::mobility::fft::Cx<T>],
        index: &'a mut [usize],
        vectors: &'a mut [T::V3],
    ) -> Self {
        Self {
            pse: (complex, index, vectors, &mut []),
            ..self
        }
    }

    /// This workspace with the arrays of the fast free-space product of a step with
    /// [`Params::pse`](crate::Params::pse) and no box: at least
    /// [`fast_storage`](crate::integrate::fast_storage) (complex values, reals,
    /// indices, as [`FreeSize`](crate::mobility::free_fast::FreeSize) counts them). Less
    /// complex values or reals than that is served by a coarser grid (a wider
    /// spreading, more near pairs, the same tolerance: `docs/FREE.md`); storage that
    /// no grid within the bounds fits, or indices below `3 n + 1`, is refused with
    /// [`StepError::BadParameter`](crate::StepError::BadParameter) before anything is
    /// touched. Not counted by [`Layout`]: the grid depends on the cloud and the
    /// tolerance at run time.
    #[cfg(feature = "fast-free")]
    pub fn with_fast(
        self,
        complex: &'a mut [crate::mobility::fft::Cx<T>],
        reals: &'a mut [T],
        index: &'a mut [usize],
    ) -> Self {
        Self {
            pse: (complex, index, &mut [], reals),
            ..self
        }
    }

    /// This workspace with the vectors a fast free-space step with
    /// [`Params::rotation`](crate::Params::rotation) needs for its spins (at least
    /// [`fast_vectors`](crate::integrate::fast_vectors), else the step is refused with
    /// [`StepError::BadParameter`](crate::StepError::BadParameter) before anything is
    /// touched). Call it after [`Workspace::with_fast`].
    #[cfg(feature = "fast-free")]
    pub fn with_fast_vectors(self, vectors: &'a mut [T::V3]) -> Self {
        let (complex, index, _, reals) = self.pse;
        Self {
            pse: (complex, index, vectors, reals),
            ..self
        }
    }

    /// The element counts this workspace holds.
    pub fn capacity(&self) -> Layout {
        Layout {
            blocks: self.blocks.len(),
            vectors: self.vectors.len(),
            scalars: self.scalars.len(),
            indices: self.indices.len(),
            links: self.links.len(),
        }
    }

    /// The position multipliers of the last constrained step with `bonds` bonds (force
    /// per unit length along each bond). The inertial methods solve them again from
    /// the step's displacements, which f32 resolves where it cannot resolve the
    /// positions' change. After `Springs` or a failed step they are
    /// stale or partial; after `Overdamped2` they hold only the final projection's
    /// small correction.
    pub fn multipliers(&self, bonds: usize) -> &[T] {
        &self.scalars[..bonds.min(self.scalars.len())]
    }
}

/// Fixed-size storage: `BL` blocks, `VE` vectors, `SC` scalars, `IX` indices, sized
/// from a `const` [`Layout`]. `const fn new`, so it can initialise a `static`.
#[derive(Clone, Debug)]
pub struct Storage<T: Real, const BL: usize, const VE: usize, const SC: usize, const IX: usize> {
    blocks: [T::M3; BL],
    vectors: [T::V3; VE],
    scalars: [T; SC],
    indices: [usize; IX],
}

impl<T: Real, const BL: usize, const VE: usize, const SC: usize, const IX: usize> Default
    for Storage<T, BL, VE, SC, IX>
{
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const BL: usize, const VE: usize, const SC: usize, const IX: usize>
    Storage<T, BL, VE, SC, IX>
{
    /// Zeroed storage.
    pub const fn new() -> Self {
        Self {
            blocks: [T::M3_ZERO; BL],
            vectors: [T::V3_ZERO; VE],
            scalars: [T::ZERO; SC],
            indices: [0; IX],
        }
    }

    /// A workspace over this storage.
    pub fn workspace(&mut self) -> Workspace<'_, T> {
        Workspace::new(
            &mut self.blocks,
            &mut self.vectors,
            &mut self.scalars,
            &mut self.indices,
        )
    }
}
