//! Far-field hydrodynamics: the polydisperse Rotne-Prager-Yamakawa grand mobility
//! (Zuk, Wajnryb, Mizerski & Szymczak, J. Fluid Mech. 741 R5, 2014) and two cheaper
//! levels (Oseen, free-draining).
//!
//! Blocks follow `U_i = sum_j (tt_ij F_j + tr_ij T_j)`, `W_i = sum_j (rt_ij F_j + rr_ij T_j)`
//! with `r = r_i - r_j`, `s = |r|`, `e = r / s`. Storage is caller-owned: the packed
//! lower triangle of 3x3 blocks ([`crate::linalg`]), `n x n` for `tt` alone or `2n x 2n`
//! for the grand mobility (block rows `0..n` translations, `n..2n` rotations, matching
//! the ordering of the reference data). `out` must hold at least `tri(n)` (or
//! `tri(2n)`) blocks: its length is the caller's contract, as for any slice API.
//!
//! The self and pair blocks themselves are in [`crate::rpy`] (re-exported here), below
//! the bands of `crate::parallel` that evaluate them; this module and its geometries
//! (wall, periodic box, PSE) build on both.

use crate::fault::ParticleError;
use crate::real::Real;

#[cfg(feature = "pse")]
pub(crate) mod fft;
#[cfg(feature = "fast-free")]
pub mod free_fast;
mod grand;
#[cfg(feature = "periodic")]
pub mod periodic;
#[cfg(feature = "pse")]
pub mod pse;
#[cfg(feature = "slit")]
pub mod slit;
pub mod wall;

// The pair formulas sit below the band machinery (`parallel`), which evaluates them.
pub use crate::rpy::{Hydro, PairBlocks, pair_blocks, pair_tt, self_rr, self_tt};
pub(crate) use grand::{Grand, add_spin_of, assemble_grand_of};

/// `y = mu_tt x` without storing `mu_tt`: each pair block is evaluated where it is
/// used, in the orientation and summation order of [`assemble_tt`] followed by
/// [`sym_matvec`](crate::linalg::sym_matvec), so the result is bit-identical to the
/// stored path below [`BANDED_MIN`](crate::parallel::BANDED_MIN) rows (from there on the
/// stored path sums in bands, [`crate::parallel`]; this one does not, so the two agree to
/// rounding), at the cost of re-evaluating the pairs (storage `O(N)` instead of
/// `O(N^2)`). Nested spheres are an error, as in assembly.
pub fn tt_product<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), ParticleError> {
    let src = crate::parallel::Pairs::new(level, eta, pos, radius);
    crate::parallel::serial_product(&src, &x[..pos.len()], y)
}

/// Block `(p, q)` of `mu_tt` as [`assemble_tt`] stores it (the pair evaluated from the
/// higher index), `None` for nested spheres.
#[inline]
pub fn tt_block_at<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    p: usize,
    q: usize,
) -> Option<T::M3> {
    let (i, j) = if p >= q { (p, q) } else { (q, p) };
    if i == j {
        return Some(T::m3_diag(self_tt(eta, radius[i])));
    }
    pair_tt(level, eta, radius[i], radius[j], pos[i] - pos[j])
}

/// Assembles the `n x n` translational mobility `mu_tt`, packed lower triangle
/// ([`tri`](crate::linalg::tri)`(n)` blocks into `out`; symmetric by construction: each pair is evaluated once).
pub fn assemble_tt<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [impl crate::linalg::Block<T>],
) -> Result<(), ParticleError> {
    crate::parallel::assemble(&crate::parallel::Serial, level, eta, pos, radius, out)
}

/// Assembles the `2n x 2n` grand mobility `[[tt, tr], [rt, rr]]`, packed lower triangle
/// (`tri(2n)` blocks; the upper blocks `tr_ij = rt_ji^T` follow by symmetry).
pub fn assemble_grand<T: Real>(
    level: Hydro,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [T::M3],
) -> Result<(), ParticleError> {
    let src = crate::parallel::Pairs::new(level, eta, pos, radius);
    grand::assemble_grand_of(&src, pos.len(), out)
}
