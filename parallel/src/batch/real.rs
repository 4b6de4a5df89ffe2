//! [`Real`] for [`Lanes`]: the kernel's `f64` implementation, lane by lane.
//!
//! Each method does on every lane what `impl Real for f64` (the kernel's `real.rs`)
//! does: the same libm functions, the same order of operations (`dot` as
//! `(x x' + y y') + z z'`, `abs` as `if x < 0 { -x } else { x }`, `m3_add_diag` on the
//! diagonal only). Square roots are `f64::sqrt` per lane, which packs into `sqrtpd`:
//! IEEE square roots are correctly rounded, so they equal libm's `sqrt` (whose x86-64
//! code is `sqrtsd` itself) bit for bit. What returns one `bool` or one `f64`
//! (`is_finite`, `is_nan`, `to_f64`) is decided per lane ([`agree`]).

use hydrorattle::Real;
use hydrorattle::linalg::Block;

use super::lanes::{Lanes, agree};
use super::vec::{LM3, LV3};

impl<const K: usize> Real for Lanes<K> {
    type V3 = LV3<K>;
    type M3 = LM3<K>;
    const ZERO: Self = Lanes::splat(0.0);
    const ONE: Self = Lanes::splat(1.0);
    const TWO: Self = Lanes::splat(2.0);
    const HALF: Self = Lanes::splat(0.5);
    const PI: Self = Lanes::splat(core::f64::consts::PI);
    const EPSILON: Self = Lanes::splat(f64::EPSILON);
    const MIN_POSITIVE: Self = Lanes::splat(f64::MIN_POSITIVE);
    const V3_ZERO: LV3<K> = LV3::splat([0.0; 3]);
    const M3_ZERO: LM3<K> = LM3([Lanes::splat(0.0); 9]);
    const M3_IDENTITY: LM3<K> = {
        let (o, i) = (Lanes::splat(0.0), Lanes::splat(1.0));
        LM3([i, o, o, o, i, o, o, o, i])
    };

    const LANES: usize = K;

    #[inline(always)]
    fn broadcast(self, k: usize) -> Self {
        Lanes::splat(self.0[k])
    }
    #[inline(always)]
    fn with_lane(mut self, k: usize, from: Self) -> Self {
        self.0[k] = from.0[k];
        self
    }
    #[inline(always)]
    fn if_gt<const M: usize>(
        a: Self,
        b: Self,
        then: impl FnOnce() -> [Self; M],
        otherwise: impl FnOnce() -> [Self; M],
    ) -> [Self; M] {
        let m: [bool; K] = core::array::from_fn(|k| a.0[k] > b.0[k]);
        if m.iter().all(|&x| x) {
            return then();
        }
        if !m.iter().any(|&x| x) {
            return otherwise();
        }
        let (t, o) = (then(), otherwise());
        core::array::from_fn(|i| {
            Lanes(core::array::from_fn(|k| {
                if m[k] { t[i].0[k] } else { o[i].0[k] }
            }))
        })
    }
    #[inline(always)]
    fn all_gt(a: Self, b: Self) -> bool {
        a.0.iter().zip(&b.0).all(|(x, y)| x > y)
    }
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        Lanes::splat(x)
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from_bits(agree(self.0.map(f64::to_bits)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
    #[inline(always)]
    fn root_and_inverse(self) -> (Self, Self) {
        let s = self.sqrt();
        (s, Self::ONE / s)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(<f64 as Real>::abs)
    }
    #[inline]
    fn sin(self) -> Self {
        self.map(libm::sin)
    }
    #[inline]
    fn cos(self) -> Self {
        self.map(libm::cos)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        self.zip(x, libm::atan2)
    }
    #[inline]
    fn acos(self) -> Self {
        self.map(libm::acos)
    }
    #[inline]
    fn exp(self) -> Self {
        self.map(libm::exp)
    }
    #[inline]
    fn erf(self) -> Self {
        self.map(libm::erf)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        agree(self.0.map(f64::is_finite))
    }
    #[inline(always)]
    fn is_nan(self) -> bool {
        agree(self.0.map(f64::is_nan))
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        self.zip(other, f64::max)
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        self.zip(other, f64::min)
    }
    /// The kernel's `max_sticky` lane by lane: no decision, so no divergence where one
    /// lane's residual is the larger and another's the smaller.
    #[inline(always)]
    fn max_sticky(self, other: Self) -> Self {
        self.zip(other, <f64 as Real>::max_sticky)
    }
    #[inline(always)]
    fn v3_is_finite(v: LV3<K>) -> bool {
        agree(core::array::from_fn::<bool, K, _>(|k| {
            v.lane(k).iter().all(|c| c.is_finite())
        }))
    }
    #[inline(always)]
    fn v3(x: Self, y: Self, z: Self) -> LV3<K> {
        LV3::new(x, y, z)
    }
    #[inline(always)]
    fn xyz(v: LV3<K>) -> [Self; 3] {
        [v.x, v.y, v.z]
    }
    #[inline(always)]
    fn dot(a: LV3<K>, b: LV3<K>) -> Self {
        a.x * b.x + a.y * b.y + a.z * b.z
    }
    #[inline(always)]
    fn cross(a: LV3<K>, b: LV3<K>) -> LV3<K> {
        LV3::new(
            a.y * b.z - a.z * b.y,
            a.z * b.x - a.x * b.z,
            a.x * b.y - a.y * b.x,
        )
    }
    #[inline(always)]
    fn m3_cols(c0: LV3<K>, c1: LV3<K>, c2: LV3<K>) -> LM3<K> {
        LM3::from_cols(c0, c1, c2)
    }
    #[inline(always)]
    fn m3_col(m: LM3<K>, i: usize) -> LV3<K> {
        m.col(i)
    }
    #[inline(always)]
    fn transpose(m: LM3<K>) -> LM3<K> {
        m.transpose()
    }
    #[inline(always)]
    fn m3_entries(m: &LM3<K>) -> &[Self; 9] {
        &m.0
    }
    #[inline(always)]
    fn m3_entries_mut(m: &mut LM3<K>) -> &mut [Self; 9] {
        &mut m.0
    }
    #[inline(always)]
    fn m3_add_diag(mut m: LM3<K>, s: Self) -> LM3<K> {
        m.0[0] += s;
        m.0[4] += s;
        m.0[8] += s;
        m
    }
}

/// The general block, as the kernel's for `DMat3`: the matrix itself, glam's product,
/// the kernel's transposed product.
impl<const K: usize> Block<Lanes<K>> for LM3<K> {
    const SCALARS: usize = 9;
    #[inline(always)]
    fn store(m: LM3<K>) -> Self {
        m
    }
    #[inline(always)]
    fn full(self) -> LM3<K> {
        self
    }
    #[inline(always)]
    fn mul(self, x: LV3<K>) -> LV3<K> {
        self * x
    }
    #[inline(always)]
    fn tmul(self, x: LV3<K>) -> LV3<K> {
        Lanes::<K>::m3_tmul(self, x)
    }
}
