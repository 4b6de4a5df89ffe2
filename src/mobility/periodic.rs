//! The Rotne-Prager-Yamakawa translational mobility in a rectangular periodic box,
//! Ewald-summed for unequal radii, the overlapping branch included: Hasimoto's
//! splitting function (as in Fiore et al., J. Chem. Phys. 146, 124116, 2017) with
//! Beenakker's polynomial sphere factors (J. Chem. Phys. 85, 1581, 1986). The exact reference path: every block is summed to a tolerance near
//! the precision's epsilon. Derivation and measured accuracy in `docs/PERIODIC.md`.
//!
//! **What is summed.** In a box of volume `V` the mobility of spheres `i`, `j` at
//! `r = r_i - r_j` is the Fourier series
//! `M_ij = 1/(eta V) sum_{k != 0} (I - k k/k^2)/k^2 sinc(k a_i) sinc(k a_j) e^{i k.r}`
//! (`k = 0`, the mean flow, excluded: the net force is balanced by the mean pressure
//! gradient). The split multiplies the Oseen kernel by
//! `H = (1 + k^2/(4 xi^2)) e^{-k^2/(4 xi^2)}` in wave space, with the sphere factors
//! `(1 - k^2 a^2/6)` (whose transform equals `sinc`'s beyond contact), and leaves
//! the rest in real space: there each image contributes the free-space RPY block
//! ([`crate::mobility::pair_tt`], both branches, so overlapping pairs need no formulas of
//! their own) minus the smooth transform `W` of the wave-space kernel. The self block
//! takes `1/(6 pi eta a) - W(0)` for the sphere itself. The sum does not depend on `xi`.
//!
//! **Positive definiteness.** `F^T M F` is the dissipation of the periodic flow driven
//! by the forces spread uniformly over the sphere surfaces (the `sinc` form is a sum of
//! Gram terms, `|sum_j sinc(k a_j) e^{-i k.r_j} (I - k k/k^2) F_j|^2 / k^2 >= 0`). It is
//! zero only when that force density is a periodic pressure gradient plus a constant;
//! a uniform vector on a patch of sphere surface is normal to it nowhere unless it is
//! zero, so every `F_j = 0`: positive definite for every configuration accepted (no
//! sphere nested in another's image, every radius below half the box's smallest edge).
//!
//! **Parameters.** [`Ewald::new`] picks `xi` to balance the cost of the two sums and
//! the cutoffs for a tolerance near epsilon; [`Ewald::with_xi`] takes them from the
//! caller. The rotation blocks (`rt`, `rr`) are summed with the same split in `rot.rs`
//! ([`pair_rot`], [`self_rr`], [`assemble_grand`], [`add_spin`]).

pub(crate) mod real;
mod rot;
mod wave;

pub use rot::{RotBlocks, add_spin, assemble_grand, pair_rot, self_rr};
#[cfg(feature = "pse")]
pub(crate) use rot::{real_grand, real_self_rr};

pub use crate::cell::{Periodic, PeriodicError};
use crate::fault::ParticleError;
use crate::linalg::{Block, tri};
use crate::parallel::{
    Blocks, Packed, Parallel, assemble_blocks, block_at, product_blocks, serial_product,
};
use crate::real::Real;

/// Largest image or wave-vector index per axis that the sums visit (a bound on their
/// cost: a box too elongated for it is [`PeriodicError::TooElongated`]).
pub const MAX_INDEX: usize = 40;

/// `xi V^{1/3}` of [`Ewald::new`]: balances the measured cost of a real-space image
/// (an RPY block, `erf`, `exp`) against that of a wave vector (`docs/PERIODIC.md`).
pub const XI_BALANCE: f64 = 2.9;

/// The largest `xi a_max` of [`Ewald::new`]: beyond it the sphere factors
/// `(1 - k^2 a^2 / 6)` make the wave-space terms cancel (a sphere of a third of the box
/// at `xi a = 2.4` loses two digits), so spheres that large lower `xi` below the balance.
pub const XI_RADIUS: f64 = 1.0;

/// The Ewald parameters for one box and one largest radius: the splitting parameter
/// `xi`, the real-space cutoff and the wave-space cutoff, with the index bounds and
/// per-axis Gaussian factors the sums read.
#[derive(Clone, Copy, Debug)]
pub struct Ewald<T: Real> {
    cell: Periodic<T>,
    a_max: T,
    xi: T,
    /// The real-space sum's box, `xi`, cutoff and image bounds.
    split: real::Split<T>,
    k_max: T,
    volume: T,
    inv_4xi2: T,
    /// Wave-space index bound per axis.
    waves: [usize; 3],
    /// `2 pi / L_d`.
    dk: [T; 3],
    /// `exp(-(n dk_d)^2 / (4 xi^2))`, `n = 0..=waves[d]`.
    gauss: [[T; MAX_INDEX + 1]; 3],
}

impl<T: Real> Ewald<T> {
    /// Parameters by the documented rule: `xi = XI_BALANCE / V^{1/3}` and a tolerance of
    /// an eighth of the precision's epsilon.
    pub fn new(cell: Periodic<T>, a_max: T) -> Result<Self, PeriodicError> {
        let xi = (XI_BALANCE / libm::cbrt(cell.volume().to_f64())).min(XI_RADIUS / a_max.to_f64());
        Self::with_xi(cell, a_max, T::from_f64(xi), T::EPSILON / T::from_f64(8.0))
    }

    /// Parameters for a given splitting parameter `xi` and relative tolerance `tol`
    /// (`0 < tol < 1`). With `p^2 = ln(1/tol) + 2 ln(1 + (a_max xi p)^2 / 2)` (the
    /// second term covers the sphere factors' growth, iterated to a fixed point from
    /// `p^2 = ln(1/tol)`), the cutoffs are `r_cut = max(p / xi, 2 a_max)` and
    /// `k_max = 2 p xi`: the neglected terms fall like `exp(-p^2)` on both sides.
    pub fn with_xi(cell: Periodic<T>, a_max: T, xi: T, tol: T) -> Result<Self, PeriodicError> {
        if !(xi > T::ZERO && xi.is_finite()) {
            return Err(PeriodicError::BadParameter("xi"));
        }
        if !(tol > T::ZERO && tol < T::ONE) {
            return Err(PeriodicError::BadParameter("tolerance"));
        }
        if !(a_max > T::ZERO && a_max.is_finite()) {
            return Err(PeriodicError::BadParameter("largest radius"));
        }
        let size = cell.size();
        if !(a_max + a_max < size[0].min(size[1]).min(size[2])) {
            return Err(PeriodicError::SphereTooLarge);
        }
        // The rule in f64 whatever T: the parameters are not part of the sums' rounding.
        let (x, a, base) = (xi.to_f64(), a_max.to_f64(), -libm::log(tol.to_f64()));
        let mut p2 = base;
        for _ in 0..4 {
            let t = a * x * libm::sqrt(p2);
            p2 = base + 2.0 * libm::log(1.0 + 0.5 * t * t);
        }
        let p = libm::sqrt(p2);
        let r_cut = (p / x).max(2.0 * a);
        let k_max = 2.0 * p * x;
        let split = real::Split::new(cell, xi, r_cut)?;
        let mut waves = [0; 3];
        let mut dk = [T::ZERO; 3];
        let mut gauss = [[T::ZERO; MAX_INDEX + 1]; 3];
        for d in 0..3 {
            let l = size[d].to_f64();
            let w = libm::floor(k_max * l / (2.0 * core::f64::consts::PI));
            if !(w <= MAX_INDEX as f64) {
                return Err(PeriodicError::TooElongated);
            }
            waves[d] = w as usize;
            dk[d] = T::TWO * T::PI / size[d];
            for n in 0..=waves[d] {
                let k = T::from_f64(n as f64) * dk[d];
                gauss[d][n] = (-(k * k) / (T::from_f64(4.0) * xi * xi)).exp();
            }
        }
        Ok(Self {
            cell,
            a_max,
            xi,
            split,
            k_max: T::from_f64(k_max),
            volume: cell.volume(),
            inv_4xi2: T::ONE / (T::from_f64(4.0) * xi * xi),
            waves,
            dk,
            gauss,
        })
    }

    /// The box.
    pub fn cell(&self) -> Periodic<T> {
        self.cell
    }
    /// The splitting parameter `xi`.
    pub fn xi(&self) -> T {
        self.xi
    }
    /// The real-space cutoff.
    pub fn r_cut(&self) -> T {
        self.split.r_cut
    }
    /// The wave-space cutoff.
    pub fn k_max(&self) -> T {
        self.k_max
    }
    /// The largest radius the cutoffs were chosen for.
    pub fn a_max(&self) -> T {
        self.a_max
    }
}

/// The block `(i, j)`, `i != j`, for radii `a_i`, `a_j` (at most [`Ewald::a_max`]) and
/// separation `r = r_i - r_j` (any image: it is reduced to the minimum image first).
/// Exactly symmetric; `None` when a sphere lies inside an image of the other.
pub fn pair_tt<T: Real>(ew: &Ewald<T>, eta: T, ai: T, aj: T, r: T::V3) -> Option<T::M3> {
    let r0 = ew.cell.minimum_image(r);
    let real = real::real_sum(&ew.split, eta, ai, aj, r0, false)?;
    Some(real + wave::wave_sum(ew, eta, ai, aj, r0))
}

/// The self block of a sphere of radius `a` (at most [`Ewald::a_max`]): its Stokes
/// mobility corrected for its periodic images (for a cubic box, Hasimoto's
/// `(1 - 2.837297 a/L + 4 pi/3 (a/L)^3) / (6 pi eta a)`).
pub fn self_tt<T: Real>(ew: &Ewald<T>, eta: T, a: T) -> T::M3 {
    // No image of a sphere lies inside it (a < L/2), so the real sum is never `None`.
    let real = real::real_sum(&ew.split, eta, a, a, T::V3_ZERO, true).unwrap_or(T::M3_ZERO);
    real + wave::wave_sum(ew, eta, a, a, T::V3_ZERO)
}

/// Positions finite, radii in `(0, a_max]`.
fn check<T: Real>(ew: &Ewald<T>, pos: &[T::V3], radius: &[T]) -> Result<(), PeriodicError> {
    for (i, (&p, &a)) in pos.iter().zip(radius).enumerate() {
        if !T::v3_is_finite(p) {
            return Err(PeriodicError::Particle(ParticleError::NonFinite {
                particle: i,
            }));
        }
        if !(a > T::ZERO && a <= ew.a_max) {
            return Err(PeriodicError::Radius { particle: i });
        }
    }
    Ok(())
}

/// Assembles the `n x n` periodic `mu_tt`, packed lower triangle ([`tri`]`(n)` blocks
/// into `out`), in the layout of [`crate::mobility::assemble_tt`]: general blocks or
/// symmetric ones ([`Sym`](crate::linalg::Sym)), the same bits, since every Ewald
/// block is symmetric in bits (the real-space images' free-space blocks and
/// `A I + B e e^T` with `e e^T` formed as `e_r e_c` either way round; the wave-space
/// sum's six mirrored entries; tested below).
pub fn assemble_tt<T: Real>(
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [impl Block<T>],
) -> Result<(), PeriodicError> {
    assemble(&crate::parallel::Serial, ew, eta, pos, radius, out)
}

/// [`assemble_tt`] in the bands of [`crate::parallel`] through `par`: the same blocks
/// (each pair is summed on its own) and the same first error, on any number of threads.
pub fn assemble<T: Real>(
    par: &dyn Parallel,
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [impl Block<T>],
) -> Result<(), PeriodicError> {
    let none = (&mut [][..], tri as fn(usize) -> usize);
    assemble_then(par, ew, eta, pos, radius, out, none, |_, _, _, _| {})
}

/// `u = mu_tt f`: [`assemble`] into `mu` (also into the compact copy `copy` of
/// [`Params::compact_products`](crate::Params::compact_products) when given, in the same
/// pass, [`assemble_then`]) and applied in the bands of [`crate::parallel`] through `par`
/// (`bands`: their scratch).
pub(crate) fn assemble_apply<T: Real>(
    ew: &Ewald<T>,
    eta: T,
    (pos, radius): (&[T::V3], &[T]),
    mu: crate::linalg::MobMut<'_, T>,
    (f, u): (&[T::V3], &mut [T::V3]),
    (par, bands): (&dyn Parallel, &mut [T::V3]),
    copy: Option<&mut [T::M3]>,
) -> Result<(), PeriodicError> {
    use crate::noise::reduced;
    crate::linalg::with_blocks!(mut mu, mu => {
        match copy {
            None => assemble(par, ew, eta, pos, radius, mu)?,
            Some(copy) => {
                let side = (copy, reduced::copy_start as fn(usize) -> usize);
                let pack = reduced::pack_rows::<T, _>;
                assemble_then(par, ew, eta, pos, radius, mu, side, pack)?
            }
        }
        crate::parallel::product::<T>(par, mu, pos.len(), f, u, bands);
        Ok(())
    })
}

/// [`assemble`], handing each row `i` of the mobility, just written and still in the
/// core's cache, to `then(i, i + 1, row, side_rows)` with `side` from its row `i` on
/// (empty where `side` is): a second use of the blocks without a second pass over
/// memory (the compact copy of
/// [`Params::compact_products`](crate::Params::compact_products) in a box, as
/// [`assemble_apply_then`](crate::parallel::assemble_apply_then) writes it in free
/// space). The same blocks and the same first error.
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble_then<T: Real, B: Block<T>, F>(
    par: &dyn Parallel,
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    out: &mut [B],
    side: Packed<'_, T::M3>,
    then: F,
) -> Result<(), PeriodicError>
where
    F: Fn(usize, usize, &[B], &mut [T::M3]) + Sync,
{
    check(ew, pos, radius)?;
    let src = Sums::new(ew, eta, (pos, radius), true);
    assemble_blocks(par, pos.len(), &src, out, side, then)
}

/// `y = mu_tt x` without storing `mu_tt`: the real-space blocks pair by pair (each
/// evaluated once, used for both rows), the wave-space part through structure factors
/// (`O(N K)` for `K` wave vectors). Agrees with [`assemble_tt`] followed by
/// [`sym_matvec`](crate::linalg::sym_matvec) to rounding, not bit for bit. One thread
/// and one band: [`free_product`] gives its bits below
/// [`BANDED_MIN`](crate::parallel::BANDED_MIN) rows.
pub fn tt_product<T: Real>(
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), PeriodicError> {
    check(ew, pos, radius)?;
    let src = Sums::new(ew, eta, (pos, radius), false);
    serial_product(&src, &x[..pos.len()], y)?;
    wave::wave_product(ew, eta, pos, radius, x, y);
    Ok(())
}

/// [`tt_product`] with its real-space half in the bands of
/// [`crate::parallel::product`] through `par` (`z`: at least
/// [`band_scratch`](crate::parallel::band_scratch)`(n)` vectors), the same bits on any
/// number of threads (and [`tt_product`]'s below
/// [`BANDED_MIN`](crate::parallel::BANDED_MIN) rows); the same first error. The
/// wave-space half, `O(N K)` against the real half's `O(N^2)` image sums, stays on the
/// calling thread (its structure factors are sums over every sphere, in order).
#[allow(clippy::too_many_arguments)]
pub fn free_product<T: Real>(
    par: &dyn Parallel,
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) -> Result<(), PeriodicError> {
    check(ew, pos, radius)?;
    let src = Sums::new(ew, eta, (pos, radius), false);
    product_blocks(par, &src, &x[..pos.len()], y, z)?;
    wave::wave_product(ew, eta, pos, radius, x, y);
    Ok(())
}

/// The box's blocks as the band loops of [`crate::parallel`] read them: whole (real
/// and wave space, as [`assemble_tt`] stores them), or the real-space half alone (the
/// matrix-free products add the wave-space half through structure factors). Nested
/// spheres the error of [`assemble_tt`].
#[derive(Clone, Copy)]
struct Sums<'a, T: Real> {
    ew: &'a Ewald<T>,
    eta: T,
    pos: &'a [T::V3],
    radius: &'a [T],
    whole: bool,
}

impl<'a, T: Real> Sums<'a, T> {
    #[inline(always)]
    fn new(ew: &'a Ewald<T>, eta: T, (pos, radius): (&'a [T::V3], &'a [T]), whole: bool) -> Self {
        Self {
            ew,
            eta,
            pos,
            radius,
            whole,
        }
    }
}

impl<T: Real> Blocks<T> for Sums<'_, T> {
    type Site = ();
    type Error = PeriodicError;
    #[inline(always)]
    fn site(&self, _: usize) -> Result<(), PeriodicError> {
        Ok(())
    }
    #[inline(always)]
    fn diag(&self, i: usize, _: ()) -> T::M3 {
        let a = self.radius[i];
        match self.whole {
            true => self_tt(self.ew, self.eta, a),
            // a < L/2: no image of a sphere lies inside it, so the self sum is never `None`.
            false => real::real_sum(&self.ew.split, self.eta, a, a, T::V3_ZERO, true)
                .unwrap_or(T::M3_ZERO),
        }
    }
    #[inline(always)]
    fn pair(&self, i: usize, _: (), j: usize, _: ()) -> Result<T::M3, PeriodicError> {
        let (ew, eta, pos, radius) = (self.ew, self.eta, self.pos, self.radius);
        let block = match self.whole {
            true => pair_tt(ew, eta, radius[i], radius[j], pos[i] - pos[j]),
            false => {
                let r0 = ew.cell.minimum_image(pos[i] - pos[j]);
                real::real_sum(&ew.split, eta, radius[i], radius[j], r0, false)
            }
        };
        block.ok_or(PeriodicError::Particle(ParticleError::Nested {
            i: j,
            j: i,
        }))
    }
}

/// Block `(p, q)` of the matrix [`assemble_tt`] stores (the pair evaluated from the
/// higher index, as there), `None` for a sphere inside another's image: the
/// matrix-free constraint metric's block.
pub fn tt_block_at<T: Real>(
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    p: usize,
    q: usize,
) -> Option<T::M3> {
    let src = Sums::new(ew, eta, (pos, radius), true);
    block_at(&src, false, p, q).ok()
}

#[cfg(test)]
mod tests {
    use super::{Ewald, Periodic, pair_tt, self_tt};
    use crate::linalg::block::tests::lcg;
    use crate::real::Real;

    /// Whether `m` equals its transpose bit for bit.
    fn symmetric_in_bits<T: Real>(m: T::M3) -> bool {
        let e = T::m3_entries(&m);
        (0..3).all(|r| {
            (0..3).all(|c| e[3 * c + r].to_f64().to_bits() == e[3 * r + c].to_f64().to_bits())
        })
    }

    /// Every stored Ewald block, self and pair, is symmetric in bits, so a box's
    /// mobility may be stored as six-scalar blocks (`linalg::Sym`) with the same bits:
    /// the real-space images add free-space RPY blocks (symmetric in bits, tested in
    /// `linalg::block`) minus `A I + B e e^T` with `e e^T` formed as `e_r e_c` either
    /// way round; the wave-space sum accumulates six entries and mirrors them. Random
    /// boxes (elongated too), radii, positions (overlapping pairs included), splitting
    /// parameters and tolerances, in both precisions.
    #[test]
    fn ewald_blocks_are_symmetric_in_bits() -> Result<(), crate::PeriodicError> {
        fn check<T: Real>(seed: u64) -> Result<usize, crate::PeriodicError> {
            let mut v = lcg(seed);
            let mut u = move || v().0 + 0.5;
            let mut checked = 0;
            for case in 0..12 {
                let size = [0; 3].map(|_| 6.0 + 8.0 * u());
                let cell = Periodic::new(size.map(T::from_f64))?;
                let a_max = 0.3 + 1.2 * u();
                let a = T::from_f64(a_max);
                let vol = size[0] * size[1] * size[2];
                let ew = match case % 3 {
                    0 => Ewald::new(cell, a),
                    // xi V^(1/3) from 1 to 4, tolerances from 1e-4 down to eps/8.
                    k => {
                        let xi = (1.0 + 3.0 * u()) / libm::cbrt(vol);
                        let tol = if k == 1 {
                            1e-4
                        } else {
                            T::EPSILON.to_f64() / 8.0
                        };
                        Ewald::with_xi(cell, a, T::from_f64(xi), T::from_f64(tol))
                    }
                };
                let Ok(ew) = ew else { continue };
                let eta = T::from_f64(0.5 + u());
                for _ in 0..40 {
                    let ai = T::from_f64(a_max * (0.2 + 0.8 * u()));
                    let aj = T::from_f64(a_max * (0.2 + 0.8 * u()));
                    // Separations across the box and beyond (any image), some close.
                    let scale = if u() < 0.3 {
                        2.0 * a_max
                    } else {
                        2.0 * size[0]
                    };
                    let r = T::v3(
                        T::from_f64(scale * (u() - 0.5)),
                        T::from_f64(scale * (u() - 0.5)),
                        T::from_f64(scale * (u() - 0.5)),
                    );
                    assert!(symmetric_in_bits::<T>(self_tt(&ew, eta, ai)));
                    if let Some(m) = pair_tt(&ew, eta, ai, aj, r) {
                        assert!(T::m3_entries(&m).iter().all(|x| x.is_finite()));
                        assert!(symmetric_in_bits::<T>(m), "case {case} r {r:?}");
                        checked += 1;
                    }
                }
            }
            Ok(checked)
        }
        // The check itself sees an asymmetry of one entry.
        let mut m = <f64 as Real>::m3_diag(1.0);
        <f64 as Real>::m3_entries_mut(&mut m)[1] = f64::EPSILON;
        assert!(!symmetric_in_bits::<f64>(m));
        for seed in 1..4 {
            let (d, s) = (check::<f64>(seed)?, check::<f32>(seed)?);
            // 476 of 480 pairs a seed (the rest nested through the boundary).
            assert!(d > 400 && s > 400, "seed {seed}: {d} f64, {s} f32 pairs");
        }
        Ok(())
    }
}
