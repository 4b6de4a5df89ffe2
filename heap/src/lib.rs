//! Heap storage for the `hydrorattle` kernel on hosts, sized at run time from a
//! [`Layout`]. The kernel is `no_std` and never allocates; this crate is where a host
//! gets its workspace when the size is only known at run time (thousands of beads, a
//! scene file). Firmware uses the kernel's `Storage` instead.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod fast;

use std::collections::TryReserveError;

pub use fast::{FreeBuffers, PseBuffers};

use hydrorattle::particles::sphere_volume;
use hydrorattle::{Bond, Layout, Noise, ParticleError, Real, State, Workspace};

/// Heap storage holding a [`Layout`]: built element by element on the heap, so no
/// size ever passes through the stack.
#[derive(Clone, Debug, Default)]
pub struct Buffers<T: Real> {
    blocks: Vec<T::M3>,
    vectors: Vec<T::V3>,
    scalars: Vec<T>,
    indices: Vec<usize>,
    links: Vec<Bond<T>>,
}

impl<T: Real> Buffers<T> {
    /// A placeholder link (overwritten by every step that reads it).
    const EMPTY_LINK: Bond<T> = Bond {
        i: 0,
        j: 0,
        length: T::ZERO,
    };

    /// Zeroed buffers holding `layout`.
    pub fn new(layout: Layout) -> Self {
        Self {
            blocks: vec![T::M3_ZERO; layout.blocks],
            vectors: vec![T::V3_ZERO; layout.vectors],
            scalars: vec![T::ZERO; layout.scalars],
            indices: vec![0; layout.indices],
            links: vec![Self::EMPTY_LINK; layout.links],
        }
    }

    /// Like [`Buffers::new`], but an allocation the system refuses is an error instead
    /// of an abort (hosts sizing storage from user input).
    pub fn try_new(layout: Layout) -> Result<Self, TryReserveError> {
        fn zeroed<X: Clone>(len: usize, x: X) -> Result<Vec<X>, TryReserveError> {
            let mut v = Vec::new();
            v.try_reserve_exact(len)?;
            v.resize(len, x);
            Ok(v)
        }
        Ok(Self {
            blocks: zeroed(layout.blocks, T::M3_ZERO)?,
            vectors: zeroed(layout.vectors, T::V3_ZERO)?,
            scalars: zeroed(layout.scalars, T::ZERO)?,
            indices: zeroed(layout.indices, 0)?,
            links: zeroed(layout.links, Self::EMPTY_LINK)?,
        })
    }

    /// The constraint list of the last step with contacts or a wall: the bonds, then
    /// the one-sided constraints held ([`StepReport`](hydrorattle::StepReport)'s
    /// `contacts + wall_contacts` of them), in the order of the multipliers.
    pub fn links(&self) -> &[Bond<T>] {
        &self.links
    }

    /// A workspace over these buffers.
    pub fn workspace(&mut self) -> Workspace<'_, T> {
        Workspace::new(
            &mut self.blocks,
            &mut self.vectors,
            &mut self.scalars,
            &mut self.indices,
        )
        .with_links(&mut self.links)
    }
}

/// A particle state on the heap: the arrays a [`State`] borrows, owned, for hosts,
/// tests and examples that size their systems at run time (the host library's
/// `Beads`, whose engine keeps the generator itself and leaves `noise` empty).
#[derive(Clone, Debug)]
pub struct Spheres<T: Real> {
    /// Centres.
    pub pos: Vec<T::V3>,
    /// Translational velocities.
    pub vel: Vec<T::V3>,
    /// Angular velocities.
    pub omega: Vec<T::V3>,
    /// Radii.
    pub radius: Vec<T>,
    /// Material densities.
    pub density: Vec<T>,
    /// Simulated time.
    pub time: T,
    /// The thermal noise's generator, when the steps draw noise.
    pub noise: Option<Noise>,
}

impl<T: Real> Spheres<T> {
    /// Spheres at `pos` with radii `radius` and densities `density`, at rest at time
    /// zero, without a noise generator.
    pub fn at_rest(pos: Vec<T::V3>, radius: Vec<T>, density: Vec<T>) -> Self {
        let n = pos.len();
        Self {
            pos,
            vel: vec![T::V3_ZERO; n],
            omega: vec![T::V3_ZERO; n],
            radius,
            density,
            time: T::ZERO,
            noise: None,
        }
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// `true` when there are none.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Mass of sphere `i`.
    pub fn mass(&self, i: usize) -> T {
        sphere_volume(self.radius[i]) * self.density[i]
    }

    /// Nested spheres are refused; overlapping ones unless `allow_overlap` (in the
    /// periodic box `cell`, through the minimum image): the kernel's `check_pairs` over
    /// its cell list (`O(N)` pairs, the same error).
    pub fn check_pairs(
        &self,
        allow_overlap: bool,
        cell: Option<&hydrorattle::cell::Periodic<T>>,
    ) -> Result<(), ParticleError> {
        let mut store = vec![0; hydrorattle::cell_list::indices(self.len())];
        let (pos, radius) = (&self.pos, &self.radius);
        hydrorattle::cell_list::check_pairs_periodic(pos, radius, allow_overlap, cell, &mut store)
    }

    /// The state a step takes, every array borrowed.
    pub fn state(&mut self) -> State<'_, T> {
        State {
            pos: &mut self.pos,
            vel: &mut self.vel,
            omega: &mut self.omega,
            radius: &self.radius,
            density: &self.density,
            time: &mut self.time,
            noise: self.noise.as_mut(),
        }
    }
}
