//! The grand mobility's loops, written once over a geometry's rotation blocks
//! ([`Grand`]): the packed `2n x 2n` assembly ([`assemble_grand_of`]) and the spins of
//! torque-free spheres ([`add_spin_of`]), for free space, the wall and the box alike.

use crate::linalg::tri;
use crate::parallel::{Blocks, Pairs};
use crate::real::Real;
use crate::rpy::{PairBlocks, pair_blocks, self_rr};

/// A geometry's grand mobility, block by block: its translational blocks
/// ([`Blocks`]) and its rotation blocks.
pub(crate) trait Grand<T: Real>: Blocks<T> {
    /// The `rr` self block of sphere `i`.
    fn self_rr(&self, i: usize, si: Self::Site) -> T::M3;
    /// The `rt` self block of sphere `i`; `None` where it vanishes (free space, the box),
    /// so that a spin adds nothing for it.
    fn self_rt(&self, i: usize, si: Self::Site) -> Option<T::M3>;
    /// Every block of the pair `(i, j)`, `j < i`.
    fn pair_grand(
        &self,
        i: usize,
        si: Self::Site,
        j: usize,
        sj: Self::Site,
    ) -> Result<PairBlocks<T>, Self::Error>;
    /// `(rt_ij, rt_ji)` as the spins sum them (by default the grand mobility's).
    #[inline(always)]
    fn pair_spin(
        &self,
        i: usize,
        si: Self::Site,
        j: usize,
        sj: Self::Site,
    ) -> Result<(T::M3, T::M3), Self::Error> {
        let b = self.pair_grand(i, si, j, sj)?;
        Ok((b.rt_ij, b.rt_ji))
    }
}

/// The `2n x 2n` grand mobility of `src` (translations then rotations), packed lower
/// triangle into `out` ([`tri`]`(2n)` blocks). The first error in row order.
pub(crate) fn assemble_grand_of<T: Real, S: Grand<T>>(
    src: &S,
    n: usize,
    out: &mut [T::M3],
) -> Result<(), S::Error> {
    for i in 0..n {
        let si = src.site(i)?;
        let (ti, ri) = (tri(i), tri(n + i));
        out[ti + i] = src.diag(i, si);
        out[ri + n + i] = src.self_rr(i, si);
        out[ri + i] = src.self_rt(i, si).unwrap_or(T::M3_ZERO);
        for j in 0..i {
            let b = src.pair_grand(i, si, j, src.site(j)?)?;
            let rj = tri(n + j);
            out[ti + j] = b.tt;
            out[ri + n + j] = b.rr;
            out[ri + j] = b.rt_ij;
            out[rj + i] = b.rt_ji;
        }
    }
    Ok(())
}

/// `out_i += sum_j rt_ij f_j` over the `n` spheres of `src` (self terms where they do
/// not vanish): the spins of torque-free spheres under the forces `f` they exert on the
/// fluid. The first error in row order.
pub(crate) fn add_spin_of<T: Real, S: Grand<T>>(
    src: &S,
    n: usize,
    f: &[T::V3],
    out: &mut [T::V3],
) -> Result<(), S::Error> {
    for i in 0..n {
        let si = src.site(i)?;
        if let Some(rt) = src.self_rt(i, si) {
            out[i] += rt * f[i];
        }
        for j in 0..i {
            let (rt_ij, rt_ji) = src.pair_spin(i, si, j, src.site(j)?)?;
            out[i] += rt_ij * f[j];
            out[j] += rt_ji * f[i];
        }
    }
    Ok(())
}

/// Free space.
impl<T: Real> Grand<T> for Pairs<'_, T> {
    #[inline(always)]
    fn self_rr(&self, i: usize, _: ()) -> T::M3 {
        T::m3_diag(self_rr(self.eta, self.radius[i]))
    }
    #[inline(always)]
    fn self_rt(&self, _: usize, _: ()) -> Option<T::M3> {
        None
    }
    #[inline(always)]
    fn pair_grand(
        &self,
        i: usize,
        _: (),
        j: usize,
        _: (),
    ) -> Result<PairBlocks<T>, crate::fault::ParticleError> {
        let (pos, radius) = (self.pos, self.radius);
        pair_blocks(self.level, self.eta, radius[i], radius[j], pos[i] - pos[j])
            .ok_or(crate::fault::ParticleError::Nested { i: j, j: i })
    }
}
