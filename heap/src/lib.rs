//! Heap storage for the `hydrorattle` kernel on hosts, sized at run time from a
//! [`Layout`]. The kernel is `no_std` and never allocates; this crate is where a host
//! gets its workspace when the size is only known at run time (thousands of beads, a
//! scene file). Firmware uses the kernel's `Storage` instead.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

use std::collections::TryReserveError;

use hydrorattle::{Bond, Layout, Real, Workspace};

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
