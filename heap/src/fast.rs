//! Heap arrays of the kernel's grid products, sized from the kernel's own counts: the
//! fast free-space product ([`FreeBuffers`], from a [`FreeSize`]) and the periodic box's
//! PSE product ([`PseBuffers`], from a [`PseSize`]). The kernel takes them as slices
//! (`FreeStorage`, `PseStorage`, `Workspace::with_fast`, `Workspace::with_pse`); a host
//! sizes them at run time, once, here.

use hydrorattle::mobility::free_fast::{FreeSize, FreeStorage};
use hydrorattle::mobility::pse::{Cx, PseSize, PseStorage};
use hydrorattle::{Real, Workspace};

/// The arrays of the fast free-space product, zeroed (no kept transform): complex
/// values, reals, indices. Empty by default (a step that takes no fast product).
#[derive(Clone, Debug, Default)]
pub struct FreeBuffers<T: Real> {
    /// Complex values ([`FreeSize::complex`]).
    pub complex: Vec<Cx<T>>,
    /// Reals ([`FreeSize::reals`]); they keep the kernel's transform between products.
    pub reals: Vec<T>,
    /// Indices ([`FreeSize::index`]).
    pub index: Vec<usize>,
}

impl<T: Real> FreeBuffers<T> {
    /// Zeroed arrays of `size` (`FreeFast::storage`, `integrate::fast_storage`).
    pub fn new(size: FreeSize) -> Self {
        let mut a = Self::default();
        a.grow(size);
        a
    }

    /// Arrays of `size` where a step takes the fast product, else empty (as
    /// `integrate::fast_storage` answers).
    pub fn for_step(size: Option<FreeSize>) -> Self {
        size.map(Self::new).unwrap_or_default()
    }

    /// Grows each array to at least `size`'s, zeros appended (arrays for several
    /// clouds: the largest of each count).
    pub fn grow(&mut self, size: FreeSize) {
        let len = |have: usize, need: usize| have.max(need);
        self.complex
            .resize(len(self.complex.len(), size.complex), [T::ZERO; 2]);
        self.reals
            .resize(len(self.reals.len(), size.reals), T::ZERO);
        self.index.resize(len(self.index.len(), size.index), 0);
    }

    /// Bytes the arrays hold.
    pub fn bytes(&self) -> usize {
        size_of_val(&self.complex[..]) + size_of_val(&self.reals[..]) + size_of_val(&self.index[..])
    }

    /// Bytes arrays of `size` would hold (to bound a run before allocating them).
    pub fn bytes_of(size: FreeSize) -> usize {
        size.complex * size_of::<Cx<T>>()
            + size.reals * size_of::<T>()
            + size.index * size_of::<usize>()
    }

    /// The product's storage over these arrays (serial; add a pool with
    /// `FreeStorage::with_parallel`).
    pub fn storage(&mut self) -> FreeStorage<'_, T> {
        FreeStorage::new(&mut self.complex, &mut self.reals, &mut self.index)
    }

    /// `ws` with these arrays for a fast free-space step (`Workspace::with_fast`).
    pub fn attach<'a>(&'a mut self, ws: Workspace<'a, T>) -> Workspace<'a, T> {
        ws.with_fast(&mut self.complex, &mut self.reals, &mut self.index)
    }
}

/// The arrays of the periodic box's PSE product, zeroed: complex values, indices,
/// vectors. Empty by default (a step that takes no PSE product).
#[derive(Clone, Debug)]
pub struct PseBuffers<T: Real> {
    /// Complex values ([`PseSize::complex`]).
    pub complex: Vec<Cx<T>>,
    /// Indices ([`PseSize::index`]).
    pub index: Vec<usize>,
    /// Vectors ([`PseSize::vectors`]).
    pub vectors: Vec<T::V3>,
}

impl<T: Real> Default for PseBuffers<T> {
    fn default() -> Self {
        Self {
            complex: Vec::new(),
            index: Vec::new(),
            vectors: Vec::new(),
        }
    }
}

impl<T: Real> PseBuffers<T> {
    /// Zeroed arrays of `size` (`Pse::storage`, `integrate::pse_storage`).
    pub fn new(size: PseSize) -> Self {
        Self {
            complex: vec![[T::ZERO; 2]; size.complex],
            index: vec![0; size.index],
            vectors: vec![T::V3_ZERO; size.vectors],
        }
    }

    /// Arrays of `size` where a step takes the PSE product, else empty (as
    /// `integrate::pse_storage` answers).
    pub fn for_step(size: Option<PseSize>) -> Self {
        size.map(Self::new).unwrap_or_default()
    }

    /// The product's storage over these arrays (serial; add a pool with
    /// `PseStorage::with_parallel`).
    pub fn storage(&mut self) -> PseStorage<'_, T> {
        PseStorage::new(&mut self.complex, &mut self.index, &mut self.vectors)
    }

    /// `ws` with these arrays for a PSE step (`Workspace::with_pse`).
    pub fn attach<'a>(&'a mut self, ws: Workspace<'a, T>) -> Workspace<'a, T> {
        ws.with_pse(&mut self.complex, &mut self.index, &mut self.vectors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydrorattle::mobility::free_fast::FreeFast;
    use hydrorattle::mobility::pse::Pse;
    use hydrorattle::{Periodic, Real};

    #[test]
    fn free_buffers_hold_the_sizes_asked_and_run_the_product() {
        let n = 8;
        let ff = FreeFast::<f64>::new(1.0, 1e-4, [24.0; 3], n).unwrap();
        let z = ff.storage(n);
        let mut a = FreeBuffers::<f64>::new(z);
        let lens = |a: &FreeBuffers<f64>| (a.complex.len(), a.reals.len(), a.index.len());
        assert_eq!(lens(&a), (z.complex, z.reals, z.index));
        assert_eq!(a.bytes(), FreeBuffers::<f64>::bytes_of(z));
        let pos: Vec<_> = (0..n).map(|i| f64::v3(3.0 * i as f64, 0.0, 0.0)).collect();
        let f = vec![f64::v3(0.0, 0.0, -1.0); n];
        let mut u = vec![f64::V3_ZERO; n];
        ff.apply(1.0, &pos, &vec![1.0; n], &f, &mut u, &mut a.storage())
            .unwrap();
        assert!(u.iter().all(|v| f64::xyz(*v)[2] < 0.0));
        // Growing keeps the larger of each count.
        a.grow(FreeSize {
            complex: 1,
            reals: z.reals + 5,
            index: 0,
        });
        assert_eq!(lens(&a), (z.complex, z.reals + 5, z.index));
        assert_eq!(lens(&FreeBuffers::for_step(None)), (0, 0, 0));
    }

    #[test]
    fn pse_buffers_hold_the_sizes_asked() {
        let pse = Pse::<f64>::new(Periodic::new([10.0; 3]).unwrap(), 1.0, 1e-4).unwrap();
        let z = pse.storage(4);
        let a = PseBuffers::<f64>::new(z);
        let got = (a.complex.len(), a.index.len(), a.vectors.len());
        assert_eq!(got, (z.complex, z.index, z.vectors));
        assert!(PseBuffers::<f64>::for_step(None).complex.is_empty());
    }
}
