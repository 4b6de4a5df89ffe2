//! The stored mobility's 3x3 blocks: general ([`Real::M3`], nine scalars) or symmetric
//! ([`Sym`], six), behind one trait ([`Block`]), so that the product and assembly loops
//! are written once for both.
//!
//! Why: the stored products stream the packed mobility from memory (604 MB in `f64` at
//! N = 4096), so they are bound by bandwidth, not arithmetic. The free-space
//! translational blocks are symmetric in bits (`a I + b e e^T`, `e e^T` formed as
//! `e_r e_c`, the same product either way round; the diagonal `s I`), and so are a
//! periodic box's Ewald blocks (sums of such blocks and of mirrored entries,
//! `mobility::periodic`), so their lower triangles carry all of them: 48 bytes a pair
//! in `f64` instead of 72. A wall's blocks and the rotational couplings are not
//! symmetric and keep nine scalars.
//!
//! **Same bits.** [`Block::mul`] and [`Block::tmul`] of a [`Sym`] do the arithmetic of
//! glam's `M3 * V3` (`(c0 x + c1 y) + c2 z`, column by column) and of
//! [`Real::m3_tmul`] (`(r0 x + r1 y) + r2 z` with the dots of the columns), entry by
//! entry and in the same order, on the entries the full block would hold: for a block
//! that is symmetric in bits both give the full block's bits.

// Declared beside `Real`, whose general block (`M3`) implements it.
pub use crate::real::Block;
use crate::real::Real;

/// A symmetric 3x3 block by its lower triangle in glam's column-major order:
/// `[m00, m10, m20, m11, m21, m22]` (`m_rc`, row `r`, column `c`).
pub type Sym<T> = [T; 6];

impl<T: Real> Block<T> for Sym<T> {
    const SCALARS: usize = 6;

    #[inline(always)]
    fn store(m: T::M3) -> Self {
        let e = T::m3_entries(&m);
        [e[0], e[1], e[2], e[4], e[5], e[8]]
    }

    #[inline(always)]
    fn full(self) -> T::M3 {
        let [a, b, c, d, e, f] = self;
        T::m3_cols(T::v3(a, b, c), T::v3(b, d, e), T::v3(c, e, f))
    }

    /// Row `r` is `(m_0r x + m_1r y) + m_2r z` with `m_cr = m_rc`: glam's columns times
    /// the components, summed in column order.
    #[inline(always)]
    fn mul(self, x: T::V3) -> T::V3 {
        let [a, b, c, d, e, f] = self;
        let [x, y, z] = T::xyz(x);
        T::v3(
            a * x + b * y + c * z,
            b * x + d * y + e * z,
            c * x + e * y + f * z,
        )
    }

    /// Entry `c` is the dot of column `c` with `x`, `(m_0c x + m_1c y) + m_2c z`: for a
    /// symmetric block the same products in the same order as [`Block::mul`].
    #[inline(always)]
    fn tmul(self, x: T::V3) -> T::V3 {
        self.mul(x)
    }
}

/// A stored mobility, read-only: symmetric blocks or general ones (packed lower
/// triangle, [`tri`](super::tri)`(n)` blocks; empty when nothing is stored).
#[derive(Clone, Copy, Debug)]
pub enum Mob<'a, T: Real> {
    /// Six scalars a block (free space, a periodic box).
    Sym(&'a [Sym<T>]),
    /// Nine scalars a block (above a wall, the rotational mobility).
    Full(&'a [T::M3]),
}

/// A stored mobility to write ([`Mob`]).
#[derive(Debug)]
pub enum MobMut<'a, T: Real> {
    /// Six scalars a block (free space, a periodic box).
    Sym(&'a mut [Sym<T>]),
    /// Nine scalars a block.
    Full(&'a mut [T::M3]),
}

impl<'a, T: Real> Mob<'a, T> {
    /// Block `k` of the packed storage, in full.
    #[inline(always)]
    pub fn get(self, k: usize) -> T::M3 {
        match self {
            Mob::Sym(a) => a[k].full(),
            Mob::Full(a) => a[k],
        }
    }

    /// Blocks stored.
    pub fn len(self) -> usize {
        match self {
            Mob::Sym(a) => a.len(),
            Mob::Full(a) => a.len(),
        }
    }

    /// `true` when nothing is stored (matrix-free).
    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// Block `(i, j)` of the packed symmetric matrix, either triangle (`A_ji = A_ij^T`).
    #[inline(always)]
    pub fn sym_get(self, i: usize, j: usize) -> T::M3 {
        use super::tri;
        if j <= i {
            self.get(tri(i) + j)
        } else {
            T::transpose(self.get(tri(j) + i))
        }
    }
}

impl<'a, T: Real> MobMut<'a, T> {
    /// The same storage, borrowed for a shorter time.
    pub fn reborrow(&mut self) -> MobMut<'_, T> {
        match self {
            MobMut::Sym(a) => MobMut::Sym(a),
            MobMut::Full(a) => MobMut::Full(a),
        }
    }

    /// The same storage, read-only.
    pub fn as_ref(&self) -> Mob<'_, T> {
        match self {
            MobMut::Sym(a) => Mob::Sym(a),
            MobMut::Full(a) => Mob::Full(a),
        }
    }

    /// The same storage, read-only, for as long as it is borrowed.
    pub fn into_ref(self) -> Mob<'a, T> {
        match self {
            MobMut::Sym(a) => Mob::Sym(a),
            MobMut::Full(a) => Mob::Full(a),
        }
    }

    /// The general blocks (empty for symmetric ones: the steps that need general
    /// blocks, the inertial ones and those above a wall, are given them,
    /// [`Layout::for_params`](crate::Layout::for_params)).
    pub fn general(self) -> &'a mut [T::M3] {
        match self {
            MobMut::Sym(_) => &mut [],
            MobMut::Full(a) => a,
        }
    }
}

/// `match` on a [`Mob`] or [`MobMut`] with one expression for both block types: `$a`
/// is the slice, of [`Sym`] or of [`Real::M3`] blocks (each arm its own monomorph).
macro_rules! with_blocks {
    ($mob:expr, $a:ident => $body:expr) => {
        match $mob {
            $crate::linalg::Mob::Sym($a) => $body,
            $crate::linalg::Mob::Full($a) => $body,
        }
    };
    (mut $mob:expr, $a:ident => $body:expr) => {
        match $mob {
            $crate::linalg::MobMut::Sym($a) => $body,
            $crate::linalg::MobMut::Full($a) => $body,
        }
    };
}
pub(crate) use with_blocks;

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::{DMat3, DVec3, Vec3};

    /// Deterministic values in [-0.5, 0.5) (a linear congruential sequence) and the
    /// state each came from.
    pub(crate) fn lcg(seed: u64) -> impl FnMut() -> (f64, u64) {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5, s)
        }
    }

    /// [`lcg`]'s values with zeros, huge and tiny values mixed in.
    pub(crate) fn values(seed: u64) -> impl FnMut() -> f64 {
        let mut next = lcg(seed);
        move || {
            let (v, s) = next();
            match s % 17 {
                0 => 0.0,
                1 => v * 1e300,
                2 => v * 1e-300,
                _ => v,
            }
        }
    }

    /// A symmetric block and a vector: the symmetric block's products give glam's bits
    /// for `M3 * V3` and the kernel's `m3_tmul`, in both precisions.
    #[test]
    fn symmetric_products_give_the_bits_of_the_full_block() {
        let mut v = values(3);
        for _ in 0..100_000 {
            let e: [f64; 6] = core::array::from_fn(|_| v());
            let x = DVec3::new(v(), v(), v());
            let m = DMat3::from_cols(
                DVec3::new(e[0], e[1], e[2]),
                DVec3::new(e[1], e[3], e[4]),
                DVec3::new(e[2], e[4], e[5]),
            );
            let s = <Sym<f64> as Block<f64>>::store(m);
            assert_eq!(s, e);
            assert_eq!(Block::<f64>::full(s), m);
            let bits = |u: DVec3| u.to_array().map(f64::to_bits);
            assert_eq!(bits(s.mul(x)), bits(m * x));
            assert_eq!(bits(s.tmul(x)), bits(<f64 as Real>::m3_tmul(m, x)));
            let (m, x) = (m.as_mat3(), x.as_vec3());
            let s = <Sym<f32> as Block<f32>>::store(m);
            let bits = |u: Vec3| u.to_array().map(f32::to_bits);
            assert_eq!(bits(s.mul(x)), bits(m * x));
            assert_eq!(bits(s.tmul(x)), bits(<f32 as Real>::m3_tmul(m, x)));
            assert_eq!(Block::<f32>::full(s), m);
        }
    }
}
