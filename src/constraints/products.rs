//! Who makes the Krylov solver's products `sum_l c_l D_l`, apart from the metric that
//! gives its entries.
//!
//! The solver reads a metric two ways: entries `D_l(p)` (its band preconditioner and
//! its curvature test) and whole products (one a conjugate-gradient iteration). Every
//! [`Metric`] makes both from the same mobility ([`Exact`]: the products are
//! [`Metric::apply_all`], infallible, in the caller's scratch). A mobility known only
//! through an iterative product (Stokesian dynamics' near field by conjugate gradients,
//! `integrate/near_iter`) has no cheap entries and a product that needs storage of its
//! own and can fail to converge: it brings a [`Products`] of its own, and a metric of
//! an approximate mobility (its far field) for the entries. The entries only shape the
//! preconditioner and the curvature bound; the moves are the products', so the
//! constraints are held to the solver's tolerance along the iterative mobility.

use super::Metric;
use crate::bonds::Bond;
use crate::error::StepError;
use crate::real::Real;

/// The Krylov solver's product over all multipliers at once.
pub trait Products<T: Real> {
    /// `out = sum_l c_l D_l` for the multipliers `c` of `bonds`; `metric` is the
    /// solver's (its gradients and scale), `tmp` the solver's scratch
    /// ([`Metric::apply_all`]). An error ends the solve, the caller's state unchanged.
    fn apply(
        &mut self,
        metric: &Metric<'_, T>,
        bonds: &[Bond<T>],
        c: &[T],
        out: &mut [T::V3],
        tmp: &mut [T::V3],
    ) -> Result<(), StepError>;

    /// `z += P r`: a share of the preconditioner beside the band's solve (none by
    /// default: the band alone, the same bits).
    #[inline(always)]
    fn precondition(&self, _r: &[T], _z: &mut [T]) {}
}

/// The metric's own products ([`Metric::apply_all`]): every stored, matrix-free and
/// mass metric. Inlined to the call it replaces, the same operations, the same bits.
pub struct Exact;

impl<T: Real> Products<T> for Exact {
    #[inline(always)]
    fn apply(
        &mut self,
        metric: &Metric<'_, T>,
        bonds: &[Bond<T>],
        c: &[T],
        out: &mut [T::V3],
        tmp: &mut [T::V3],
    ) -> Result<(), StepError> {
        metric.apply_all(bonds, c, out, tmp);
        Ok(())
    }
}
