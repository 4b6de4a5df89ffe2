//! Steps on the fast free-space product ([`Params::pse`](crate::Params::pse) without a
//! box or a wall; kernel feature `fast-free`): the parameters of [`FreeFast`] derived for each step
//! from the cloud it starts from, the caller's storage, and the products and the
//! Lanczos noise the step's stages read through [`FastProduct`] (as on PSE's path).
//!
//! **A cloud that moves.** [`FreeFast`] is sized for a bounding box. A step derives its
//! parameters afresh from the cloud's bounding box at its start, each edge widened by
//! [`FAST_MARGIN`] largest radii (a midpoint's or a contact round's positions stay
//! within it), so a cloud may grow, shrink and travel without a limit set in advance.
//! A product whose spheres pass that box (the predictor-corrector's predicted point
//! after a step that stretches the cloud further) derives parameters over the larger
//! box, which the rest of the step keeps.
//! The grid follows the cloud: with the rule's `sigma ~ (V / n)^{1/3}` its points stay
//! near `n` times a constant whatever the cloud's volume, so storage sized once by
//! `integrate::fast_storage` usually keeps fitting. Where it does not (a cloud that has grown
//! dense, or storage sized below the rule), the step widens the spreading Gaussian
//! until the grid fits the caller's arrays: a coarser grid and more near pairs, the
//! same tolerance; only where no grid within the bounds fits is the step refused. The
//! storage's lengths are therefore inputs of the step's bits.
//!
//! **The kernel's transform kept.** The edges are rounded up to a coarse step
//! ([`round_extent`]) before the parameters are derived, so a cloud that travels, or
//! deforms by less than a step, keeps them; the transform, a function of them alone,
//! stays in the caller's reals between steps and is used again where they match bit for
//! bit ([`FreeStorage`]). Whether it is kept never changes a step's bits.

use core::cell::{Cell, RefCell};

use crate::error::StepError;
use crate::geometry::fast::{FastProduct, Slices};
use crate::mobility::free_fast::{FreeError, FreeFast, FreeSize, FreeStorage, round_extent};
use crate::noise::{Noise, lanczos};
use crate::parallel::Parallel;
use crate::real::Real;

/// Largest radii added to each edge of the cloud's bounding box when a step sizes its
/// fast free-space product: room for the products the step takes away from its start
/// (the Brownian midpoint, a contact round's trial positions).
pub const FAST_MARGIN: f64 = 4.0;

/// Why a step with rotation on the fast free-space product is refused without its vectors.
const SPARE: &str = "the workspace's fast free-space vectors with rotation \
     (Workspace::with_fast_vectors, at least integrate::fast_vectors)";

/// How many times the spreading width grows by [`WIDEN`] before the caller's storage
/// is declared too small (`1.25^24`, about 200 times the rule's width).
const TRIES: u32 = 24;
/// The spreading width's growth factor while fitting the caller's storage.
const WIDEN: f64 = 1.25;

/// The step's fast free-space parameters for these spheres ([`FreeFast::new`]'s rule
/// over the bounding box widened by [`FAST_MARGIN`], each edge then rounded up by
/// [`round_extent`]), the spreading widened until
/// the grid fits `have` complex values and reals (and its bounds). With `grand` (a step
/// with rotation) the grand product's ([`FreeFast::new_grand`], sized by
/// [`FreeFast::storage_grand`]).
pub(crate) fn params<T: Real>(
    rule: (f64, bool),
    pos: &[T::V3],
    radius: &[T],
    have: [usize; 2],
) -> Result<FreeFast<T>, FreeError> {
    let a_max = radius.iter().fold(T::ZERO, |m, &a| m.max(a));
    fitted(rule, a_max, edges::<T>(pos), pos.len(), have)
}

/// The edges of the centres' bounding box (zero for no spheres).
fn edges<T: Real>(pos: &[T::V3]) -> [f64; 3] {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &p in pos {
        let p = T::v3_to_f64(p);
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    core::array::from_fn(|d| (hi[d] - lo[d]).max(0.0))
}

/// [`params`] for `n` spheres of radius up to `a_max` whose centres' bounding box has
/// edges `box_edges`: the same parameters a step of such spheres derives, from the box
/// alone (a host's cost model weighs them before any step).
pub(crate) fn fitted<T: Real>(
    (tol, grand): (f64, bool),
    a_max: T,
    box_edges: [f64; 3],
    n: usize,
    have: [usize; 2],
) -> Result<FreeFast<T>, FreeError> {
    let fits = |s: FreeSize| s.complex <= have[0] && s.reals <= have[1];
    let size = |f: &FreeFast<T>, n| {
        if grand {
            f.storage_grand(n)
        } else {
            f.storage(n)
        }
    };
    let pad = FAST_MARGIN * a_max.to_f64();
    // Edges rounded up to a coarse step: a cloud that travels, or deforms within the
    // step, keeps its parameters and so the kernel's transform in the caller's reals.
    let edge = |d: usize| round_extent(box_edges[d] + pad, a_max.to_f64());
    let extent: [T; 3] = core::array::from_fn(|d| T::from_f64(edge(d)));
    let rule = match grand {
        true => FreeFast::new_grand(a_max, tol, extent, n),
        false => FreeFast::new(a_max, tol, extent, n),
    };
    let mut sigma = match rule {
        Ok(f) if fits(size(&f, n)) => return Ok(f),
        Ok(f) => f.sigma(),
        // Too fine a grid for the bounds: a wider spreading may fit.
        Err(FreeError::GridTooLarge) => 0.75 * a_max.to_f64(),
        Err(e) => return Err(e),
    };
    for _ in 0..TRIES {
        sigma *= WIDEN;
        let wide = T::from_f64(sigma);
        let tried = match grand {
            true => FreeFast::with_sigma_grand(a_max, tol, extent, wide),
            false => FreeFast::with_sigma(a_max, tol, extent, wide),
        };
        match tried {
            Ok(f) if fits(size(&f, n)) => return Ok(f),
            Ok(_) | Err(FreeError::GridTooLarge) => {}
            Err(e) => return Err(e),
        }
    }
    Err(match rule {
        Ok(f) => {
            let need = size(&f, n);
            FreeError::Storage {
                need: [need.complex, need.reals, need.index],
                have: [have[0], have[1], 0],
            }
        }
        Err(e) => e,
    })
}

/// The fast free-space parameters and the caller's storage for one step's products,
/// borrowed in turn by each product (they never nest) as PSE's storage is
/// ([`PseStep`](crate::geometry::sums::PseStep)).
pub(crate) struct FastStep<'s, T: Real> {
    /// The parameters, re-derived where a product's spheres pass their extent
    /// ([`FastStep::covering`]).
    fast: Cell<FreeFast<T>>,
    /// The caller's complex values and reals, which any parameters must fit.
    have: [usize; 2],
    store: RefCell<FreeStorage<'s, T>>,
    /// The spins' zero torques and discarded velocities (`integrate::fast_vectors`; empty
    /// without rotation).
    spare: RefCell<&'s mut [T::V3]>,
}

impl<'s, T: Real> FastStep<'s, T> {
    /// The step's products over the caller's arrays (complex values, indices, vectors,
    /// reals): the parameters `held` derived in the checks where they fit the arrays,
    /// else the spreading widened until they do ([`params`]); the products run on the
    /// step's threads `par` (the same bits on any number). Parameters for the grand
    /// product (a step with rotation) need `integrate::fast_vectors` vectors.
    pub(crate) fn new(
        held: &FreeFast<T>,
        spheres: (&[T::V3], &[T]),
        (complex, index, vectors, reals): Slices<'s, T>,
        par: &'s dyn Parallel,
    ) -> Result<Self, StepError> {
        let n = spheres.0.len();
        let grand = held.is_grand();
        let size = match grand {
            true => held.storage_grand(n),
            false => held.storage(n),
        };
        let have = [complex.len(), reals.len()];
        let fast = match size.complex <= have[0] && size.reals <= have[1] {
            true => *held,
            false => params((held.tolerance(), grand), spheres.0, spheres.1, have)?,
        };
        if index.len() < size.index {
            let need = [size.complex, size.reals, size.index];
            let have = [have[0], have[1], index.len()];
            return Err(FreeError::Storage { need, have }.into());
        }
        let spare = match grand {
            true => vectors
                .get_mut(..2 * n)
                .ok_or(StepError::BadParameter(SPARE))?,
            false => &mut [],
        };
        Ok(Self {
            fast: Cell::new(fast),
            have,
            store: RefCell::new(FreeStorage::new(complex, reals, index).with_parallel(par)),
            spare: RefCell::new(spare),
        })
    }
}

impl<T: Real> FastStep<'_, T> {
    /// The step's parameters where they cover the spheres at `pos` (radii `radius`),
    /// else parameters over the larger of their extent and these spheres' box, kept
    /// for the rest of the step (fitted to the caller's storage as [`params`] fits
    /// them). A product away from the start can pass the margin: the predictor-corrector's
    /// predicted point, or a Krylov product there, after a step that stretches the cloud
    /// by more than [`FAST_MARGIN`] radii.
    fn covering(&self, pos: &[T::V3], radius: &[T]) -> Result<FreeFast<T>, StepError> {
        let held = self.fast.get();
        let (edge, extent) = (edges::<T>(pos), held.extent());
        if (0..3).all(|d| edge[d] <= extent[d]) {
            return Ok(held);
        }
        let wide = core::array::from_fn(|d| edge[d].max(extent[d]));
        let a_max = radius.iter().fold(T::ZERO, |m, &a| m.max(a));
        let rule = (held.tolerance(), held.is_grand());
        let fast = fitted(rule, a_max, wide, pos.len(), self.have)?;
        self.fast.set(fast);
        Ok(fast)
    }
}

impl<T: Real> FastProduct<T> for FastStep<'_, T> {
    fn product(
        &self,
        eta: T,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        u: &mut [T::V3],
    ) -> Result<(), StepError> {
        let mut store = self.store.try_borrow_mut().map_err(|_| {
            StepError::Unsupported("a fast free-space product inside another (storage in use)")
        })?;
        let fast = self.covering(pos, radius)?;
        Ok(fast.apply(eta, pos, radius, f, u, &mut store)?)
    }

    /// `out = M_rt F`: the grand product with zero torques, its velocities discarded.
    fn spin(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let in_use = StepError::Unsupported(
            "a fast free-space spin inside another product (storage in use)",
        );
        let mut store = self.store.try_borrow_mut().map_err(|_| in_use)?;
        let mut spare = self.spare.try_borrow_mut().map_err(|_| in_use)?;
        let n = pos.len();
        let (torque, vel) = spare
            .split_at_mut_checked(n)
            .ok_or(StepError::BadParameter(SPARE))?;
        let vel = vel.get_mut(..n).ok_or(StepError::BadParameter(SPARE))?;
        torque.fill(T::V3_ZERO);
        let spheres = (pos, radius);
        let fast = self.covering(pos, radius)?;
        Ok(fast.apply_grand(eta, spheres, f, torque, vel, out, &mut store)?)
    }

    /// `(U, W) = M (F, T)` over the `2n` vectors: the grand product itself (no spare
    /// vectors: the caller's `ft` and `out` hold both halves).
    fn grand(
        &self,
        eta: T,
        spheres: (&[T::V3], &[T]),
        ft: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        let mut store = self.store.try_borrow_mut().map_err(|_| {
            StepError::Unsupported("a fast free-space product inside another (storage in use)")
        })?;
        let ((f, t), (u, w)) = crate::geometry::fast::grand_halves::<T>(spheres.0.len(), ft, out)?;
        let fast = self.covering(spheres.0, spheres.1)?;
        Ok(fast.apply_grand(eta, spheres, f, t, u, w, &mut store)?)
    }

    /// Lanczos on the fast product, as the matrix-free path draws in free space: the
    /// deviates `z` from `rng`, then `out = M^(1/2) z`. Free space's RPY mobility is
    /// divergence-free, so nothing else is drawn.
    fn noise(
        &self,
        eta: T,
        (pos, radius): (&[T::V3], &[T]),
        rng: &mut Noise,
        s: lanczos::Lanczos<T>,
        z: &mut [T::V3],
        out: &mut [T::V3],
        (basis, work): (&mut [T::V3], &mut [T]),
    ) -> Result<u32, StepError> {
        let z = z.get_mut(..pos.len()).ok_or(StepError::StateLength)?;
        rng.fill::<T>(z);
        let mut failed = None;
        let product = |v: &[T::V3], w: &mut [T::V3]| {
            if failed.is_none()
                && let Err(e) = self.product(eta, pos, radius, v, w)
            {
                failed = Some(e);
            }
        };
        let result = lanczos::sqrt(s, product, z, basis, work, out, None);
        if let Some(e) = failed {
            return Err(e);
        }
        Ok(result?)
    }
}
