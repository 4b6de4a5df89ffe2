//! The 3-vector and 3x3 matrix of [`Lanes`]: glam's `DVec3` and `DMat3` lane by lane.
//!
//! **Same bits.** Each operation does, on every lane, the `f64` operations glam 0.34
//! does for `DVec3`/`DMat3`, in glam's order: vectors component by component;
//! `M * v` as `(c0 x + c1 y) + c2 z` (glam's `mul_vec3`); `M * N` as `M` times each
//! column of `N`; `M * s`, `M + N`, `M - N` column by column. A matrix is its nine
//! entries in glam's column-major order, so that the kernel's `m3_entries` reads them
//! as it reads a `DMat3`'s.

use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

use super::lanes::{Lanes, agree};

/// A 3-vector of lanes (`DVec3` on each lane).
#[derive(Clone, Copy, Debug, Default)]
pub struct LV3<const K: usize> {
    /// `x` on each lane.
    pub x: Lanes<K>,
    /// `y` on each lane.
    pub y: Lanes<K>,
    /// `z` on each lane.
    pub z: Lanes<K>,
}

impl<const K: usize> LV3<K> {
    /// The vector of the three components.
    #[inline(always)]
    pub const fn new(x: Lanes<K>, y: Lanes<K>, z: Lanes<K>) -> Self {
        Self { x, y, z }
    }

    /// Every lane `v`.
    pub const fn splat(v: [f64; 3]) -> Self {
        Self::new(Lanes::splat(v[0]), Lanes::splat(v[1]), Lanes::splat(v[2]))
    }

    /// Lane `k`'s vector.
    #[inline(always)]
    pub fn lane(self, k: usize) -> [f64; 3] {
        [self.x.0[k], self.y.0[k], self.z.0[k]]
    }

    /// Lane `k` set to `v`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, v: [f64; 3]) {
        [self.x.0[k], self.y.0[k], self.z.0[k]] = v;
    }

    /// `f` component by component.
    #[inline(always)]
    fn each(self, f: impl Fn(Lanes<K>) -> Lanes<K>) -> Self {
        Self::new(f(self.x), f(self.y), f(self.z))
    }

    /// `f` of the two vectors' components.
    #[inline(always)]
    fn each2(self, o: Self, f: impl Fn(Lanes<K>, Lanes<K>) -> Lanes<K>) -> Self {
        Self::new(f(self.x, o.x), f(self.y, o.y), f(self.z, o.z))
    }
}

/// glam's `DVec3 == DVec3` (`x == x && y == y && z == z`) per lane, a decision.
impl<const K: usize> PartialEq for LV3<K> {
    fn eq(&self, o: &Self) -> bool {
        agree(core::array::from_fn::<bool, K, _>(|k| {
            self.lane(k) == o.lane(k)
        }))
    }
}

impl<const K: usize> Add for LV3<K> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.each2(o, |a, b| a + b)
    }
}

impl<const K: usize> Sub for LV3<K> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.each2(o, |a, b| a - b)
    }
}

impl<const K: usize> Mul<Lanes<K>> for LV3<K> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: Lanes<K>) -> Self {
        self.each(|a| a * s)
    }
}

impl<const K: usize> Div<Lanes<K>> for LV3<K> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: Lanes<K>) -> Self {
        self.each(|a| a / s)
    }
}

impl<const K: usize> Neg for LV3<K> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.each(|a| -a)
    }
}

impl<const K: usize> AddAssign for LV3<K> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<const K: usize> SubAssign for LV3<K> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

impl<const K: usize> MulAssign<Lanes<K>> for LV3<K> {
    #[inline(always)]
    fn mul_assign(&mut self, s: Lanes<K>) {
        *self = *self * s;
    }
}

/// A 3x3 matrix of lanes (`DMat3` on each lane): the nine entries column by column.
#[derive(Clone, Copy, Debug, Default)]
pub struct LM3<const K: usize>(pub [Lanes<K>; 9]);

impl<const K: usize> LM3<K> {
    /// The matrix of three columns.
    #[inline(always)]
    pub const fn from_cols(a: LV3<K>, b: LV3<K>, c: LV3<K>) -> Self {
        Self([a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z])
    }

    /// Column `i` (0, 1 or 2; beyond, an index out of bounds, as glam's).
    #[inline(always)]
    pub fn col(&self, i: usize) -> LV3<K> {
        let c = &self.0[3 * i..3 * i + 3];
        LV3::new(c[0], c[1], c[2])
    }

    /// glam's `transpose`.
    #[inline(always)]
    pub fn transpose(&self) -> Self {
        let e = &self.0;
        Self([e[0], e[3], e[6], e[1], e[4], e[7], e[2], e[5], e[8]])
    }

    /// `f` of the two matrices' columns.
    #[inline(always)]
    fn cols2(self, o: Self, f: impl Fn(LV3<K>, LV3<K>) -> LV3<K>) -> Self {
        Self::from_cols(
            f(self.col(0), o.col(0)),
            f(self.col(1), o.col(1)),
            f(self.col(2), o.col(2)),
        )
    }
}

/// glam's `DMat3 == DMat3` (every column equal) per lane, a decision.
impl<const K: usize> PartialEq for LM3<K> {
    fn eq(&self, o: &Self) -> bool {
        agree(core::array::from_fn::<bool, K, _>(|k| {
            (0..9).all(|i| self.0[i].0[k] == o.0[i].0[k])
        }))
    }
}

impl<const K: usize> Add for LM3<K> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.cols2(o, |a, b| a + b)
    }
}

impl<const K: usize> Sub for LM3<K> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.cols2(o, |a, b| a - b)
    }
}

impl<const K: usize> AddAssign for LM3<K> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<const K: usize> SubAssign for LM3<K> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

/// glam's `mul_vec3`: `(c0 x + c1 y) + c2 z`.
impl<const K: usize> Mul<LV3<K>> for LM3<K> {
    type Output = LV3<K>;
    #[inline(always)]
    fn mul(self, v: LV3<K>) -> LV3<K> {
        let mut r = self.col(0) * v.x;
        r += self.col(1) * v.y;
        r + self.col(2) * v.z
    }
}

/// glam's `M * N`: `M` times each column of `N`.
impl<const K: usize> Mul for LM3<K> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self::from_cols(self * o.col(0), self * o.col(1), self * o.col(2))
    }
}

/// glam's `mul_scalar`: each column times `s`.
impl<const K: usize> Mul<Lanes<K>> for LM3<K> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: Lanes<K>) -> Self {
        Self::from_cols(self.col(0) * s, self.col(1) * s, self.col(2) * s)
    }
}
