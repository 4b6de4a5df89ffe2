//! One precision trait, implemented for `f32` and `f64`.
//!
//! Every algorithm in the kernel is written once against [`Real`]. The vector and
//! 3x3 matrix types are glam's (`Vec3`/`Mat3` or `DVec3`/`DMat3`); transcendental
//! functions go through `libm`, so results do not depend on the platform's maths
//! library.

use core::fmt::{Debug, Display};
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A stored block of a packed mobility: [`Real::M3`] itself (nine scalars) or the
/// symmetric [`Sym`](crate::linalg::Sym) (six), in `linalg/block.rs`. Declared here,
/// below `linalg`, because [`Real::M3`] is one.
pub trait Block<T: Real>: Copy + Send + Sync + core::fmt::Debug + 'static {
    /// Scalars a block takes in memory (9 general, 6 symmetric).
    const SCALARS: usize;
    /// The block to store for `m` (for [`Sym`](crate::linalg::Sym), its lower triangle: `m` must be
    /// symmetric in bits, as every free-space translational block is).
    fn store(m: T::M3) -> Self;
    /// The full block.
    fn full(self) -> T::M3;
    /// `b x`, with the bits of glam's `M3 * V3` on [`Block::full`].
    fn mul(self, x: T::V3) -> T::V3;
    /// `b^T x`, with the bits of [`Real::m3_tmul`] on [`Block::full`].
    fn tmul(self, x: T::V3) -> T::V3;
}

/// A floating-point precision the kernel runs in.
pub trait Real:
    Copy
    + Debug
    + Display
    + Default
    + PartialEq
    + PartialOrd
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
{
    /// 3-vector of this precision (glam).
    type V3: Copy
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::V3>
        + Sub<Output = Self::V3>
        + Mul<Self, Output = Self::V3>
        + Div<Self, Output = Self::V3>
        + Neg<Output = Self::V3>
        + AddAssign
        + SubAssign
        + MulAssign<Self>;
    /// 3x3 matrix of this precision (glam, column-major).
    type M3: Copy
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::M3>
        + Sub<Output = Self::M3>
        + Mul<Output = Self::M3>
        + Mul<Self::V3, Output = Self::V3>
        + Mul<Self, Output = Self::M3>
        + AddAssign
        + SubAssign
        + Block<Self>;

    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 2.
    const TWO: Self;
    /// 1/2.
    const HALF: Self;
    /// pi.
    const PI: Self;
    /// Machine epsilon.
    const EPSILON: Self;
    /// The smallest positive normal number: a radius below it is refused (subnormal
    /// radii lose their digits, and `1 / (6 pi eta a)` overflows).
    const MIN_POSITIVE: Self;
    /// The zero vector.
    const V3_ZERO: Self::V3;
    /// The zero matrix.
    const M3_ZERO: Self::M3;
    /// The identity matrix.
    const M3_IDENTITY: Self::M3;

    /// Converts from `f64` (rounding for `f32`).
    fn from_f64(x: f64) -> Self;
    /// Converts to `f64` (exact).
    fn to_f64(self) -> f64;
    /// Square root (libm).
    fn sqrt(self) -> Self;
    /// `(sqrt(x), 1 / sqrt(x))` for a positive normal `x`, the pair distance and its
    /// inverse the mobility needs per pair: through libm's correctly rounded square root
    /// and one division in f64; in f32 from three Newton steps on the inverse square root
    /// (within a few units in the last place, plain IEEE multiplies and adds, so the same
    /// bits on every core). A Cortex-M4F has no square root reachable from safe stable
    /// Rust (libm 0.2.16 has no Arm path, `core::f32::math::sqrt` is unstable in Rust
    /// 1.95): libm's software `sqrtf` and the division cost ~58 instructions per pair
    /// there, these steps ~15. Other inputs (zero, subnormal, infinite, NaN) go through
    /// libm.
    fn root_and_inverse(self) -> (Self, Self);
    /// [`Real::root_and_inverse`] of each `x[k]` into `s[k]` and `inv[k]` (the same
    /// bits), as loops the compiler may vectorise (the `f64` divisions).
    #[inline(always)]
    fn roots_and_inverses(x: &[Self], s: &mut [Self], inv: &mut [Self]) {
        for ((&x, s), inv) in x.iter().zip(s).zip(inv) {
            (*s, *inv) = x.root_and_inverse();
        }
    }
    /// Absolute value.
    fn abs(self) -> Self;
    /// Sine (libm).
    fn sin(self) -> Self;
    /// Cosine (libm).
    fn cos(self) -> Self;
    /// Four-quadrant arctangent of `self / x` (libm).
    fn atan2(self, x: Self) -> Self;
    /// Arccosine (libm).
    fn acos(self) -> Self;
    /// Exponential (libm).
    fn exp(self) -> Self;
    /// Error function (libm; the periodic mobility's Ewald split).
    fn erf(self) -> Self;
    /// `true` unless NaN or infinite.
    fn is_finite(self) -> bool;
    /// `true` for NaN.
    fn is_nan(self) -> bool;
    /// The larger of two values (NaN-ignoring as `f64::max`).
    fn max(self, other: Self) -> Self;
    /// The smaller of two values.
    fn min(self, other: Self) -> Self;

    /// Builds a vector.
    fn v3(x: Self, y: Self, z: Self) -> Self::V3;
    /// The components of a vector.
    fn xyz(v: Self::V3) -> [Self; 3];
    /// Dot product.
    fn dot(a: Self::V3, b: Self::V3) -> Self;
    /// Cross product.
    fn cross(a: Self::V3, b: Self::V3) -> Self::V3;
    /// Builds a matrix from its columns.
    fn m3_cols(c0: Self::V3, c1: Self::V3, c2: Self::V3) -> Self::M3;
    /// Column `i` of a matrix.
    fn m3_col(m: Self::M3, i: usize) -> Self::V3;
    /// Transpose.
    fn transpose(m: Self::M3) -> Self::M3;
    /// The nine entries of a matrix in memory, column by column.
    fn m3_entries(m: &Self::M3) -> &[Self; 9];
    /// The nine entries of a matrix in memory, column by column, to write.
    fn m3_entries_mut(m: &mut Self::M3) -> &mut [Self; 9];

    /// Converts from an `f64` triple.
    fn v3_from(a: [f64; 3]) -> Self::V3 {
        Self::v3(
            Self::from_f64(a[0]),
            Self::from_f64(a[1]),
            Self::from_f64(a[2]),
        )
    }
    /// Converts to an `f64` triple.
    fn v3_to_f64(v: Self::V3) -> [f64; 3] {
        let [x, y, z] = Self::xyz(v);
        [x.to_f64(), y.to_f64(), z.to_f64()]
    }
    /// Squared length (plain multiply-add, no fma: same bits everywhere).
    fn norm2(v: Self::V3) -> Self {
        Self::dot(v, v)
    }
    /// Length, through libm's square root.
    fn norm(v: Self::V3) -> Self {
        Self::dot(v, v).sqrt()
    }
    /// `true` when all three components are finite.
    fn v3_is_finite(v: Self::V3) -> bool {
        let [x, y, z] = Self::xyz(v);
        x.is_finite() && y.is_finite() && z.is_finite()
    }
    /// The larger of two residuals, NaN-sticky: once either is NaN the result is NaN,
    /// so a bad bond can never be hidden by a later good one.
    fn max_sticky(self, other: Self) -> Self {
        if self.is_nan() {
            self
        } else if other.is_nan() || other > self {
            other
        } else {
            self
        }
    }
    /// Outer product `a b^T`.
    fn outer(a: Self::V3, b: Self::V3) -> Self::M3 {
        let [x, y, z] = Self::xyz(b);
        Self::m3_cols(a * x, a * y, a * z)
    }
    /// `m^T v` without forming the transpose.
    fn m3_tmul(m: Self::M3, v: Self::V3) -> Self::V3 {
        Self::v3(
            Self::dot(Self::m3_col(m, 0), v),
            Self::dot(Self::m3_col(m, 1), v),
            Self::dot(Self::m3_col(m, 2), v),
        )
    }
    /// `s I`.
    fn m3_diag(s: Self) -> Self::M3 {
        Self::M3_IDENTITY * s
    }
    /// `m + s I`, touching only the diagonal (the same values as `m + m3_diag(s)`
    /// wherever an off-diagonal entry is nonzero, for 3 additions instead of 18 flops).
    fn m3_add_diag(m: Self::M3, s: Self) -> Self::M3;
    /// Element at row `r`, column `c`.
    fn m3_get(m: Self::M3, r: usize, c: usize) -> Self {
        Self::xyz(Self::m3_col(m, c))[r]
    }
    /// The matrix of `x -> v x x` (cross-product matrix `[v]x`).
    fn m3_cross(v: Self::V3) -> Self::M3 {
        let [x, y, z] = Self::xyz(v);
        let o = Self::ZERO;
        Self::m3_cols(Self::v3(o, z, -y), Self::v3(-z, o, x), Self::v3(y, -x, o))
    }
}

macro_rules! impl_real {
    ($t:ty, $v:ty, $m:ty, $sqrt:path, $rootinv:path, $rootsinv:path, $sin:path, $cos:path, $atan2:path, $acos:path, $exp:path, $erf:path) => {
        impl Real for $t {
            type V3 = $v;
            type M3 = $m;
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const TWO: Self = 2.0;
            const HALF: Self = 0.5;
            const PI: Self = core::f64::consts::PI as $t;
            const EPSILON: Self = <$t>::EPSILON;
            const MIN_POSITIVE: Self = <$t>::MIN_POSITIVE;
            const V3_ZERO: $v = <$v>::ZERO;
            const M3_ZERO: $m = <$m>::ZERO;
            const M3_IDENTITY: $m = <$m>::IDENTITY;

            #[inline]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn sqrt(self) -> Self {
                $sqrt(self)
            }
            #[inline]
            fn root_and_inverse(self) -> (Self, Self) {
                $rootinv(self)
            }
            #[inline(always)]
            fn roots_and_inverses(x: &[Self], s: &mut [Self], inv: &mut [Self]) {
                $rootsinv(x, s, inv)
            }
            #[inline]
            fn abs(self) -> Self {
                if self < 0.0 { -self } else { self }
            }
            #[inline]
            fn sin(self) -> Self {
                $sin(self)
            }
            #[inline]
            fn cos(self) -> Self {
                $cos(self)
            }
            #[inline]
            fn atan2(self, x: Self) -> Self {
                $atan2(self, x)
            }
            #[inline]
            fn acos(self) -> Self {
                $acos(self)
            }
            #[inline]
            fn exp(self) -> Self {
                $exp(self)
            }
            #[inline]
            fn erf(self) -> Self {
                $erf(self)
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline]
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
            #[inline]
            fn v3(x: Self, y: Self, z: Self) -> $v {
                <$v>::new(x, y, z)
            }
            #[inline]
            fn xyz(v: $v) -> [Self; 3] {
                v.to_array()
            }
            #[inline]
            fn dot(a: $v, b: $v) -> Self {
                a.x * b.x + a.y * b.y + a.z * b.z
            }
            #[inline]
            fn cross(a: $v, b: $v) -> $v {
                <$v>::new(
                    a.y * b.z - a.z * b.y,
                    a.z * b.x - a.x * b.z,
                    a.x * b.y - a.y * b.x,
                )
            }
            #[inline]
            fn m3_cols(c0: $v, c1: $v, c2: $v) -> $m {
                <$m>::from_cols(c0, c1, c2)
            }
            #[inline]
            fn m3_col(m: $m, i: usize) -> $v {
                m.col(i)
            }
            #[inline]
            fn transpose(m: $m) -> $m {
                m.transpose()
            }
            #[inline(always)]
            fn m3_entries(m: &$m) -> &[Self; 9] {
                m.as_ref()
            }
            #[inline(always)]
            fn m3_entries_mut(m: &mut $m) -> &mut [Self; 9] {
                m.as_mut()
            }
            #[inline]
            fn m3_add_diag(mut m: $m, s: Self) -> $m {
                m.x_axis.x += s;
                m.y_axis.y += s;
                m.z_axis.z += s;
                m
            }
        }

        /// The general block: glam's product, the kernel's transposed product.
        impl Block<$t> for $m {
            const SCALARS: usize = 9;
            #[inline(always)]
            fn store(m: $m) -> Self {
                m
            }
            #[inline(always)]
            fn full(self) -> $m {
                self
            }
            #[inline(always)]
            fn mul(self, x: $v) -> $v {
                self * x
            }
            #[inline(always)]
            fn tmul(self, x: $v) -> $v {
                <$t as Real>::m3_tmul(self, x)
            }
        }
    };
}

impl_real!(
    f32,
    glam::Vec3,
    glam::Mat3,
    sqrt_f32,
    root_and_inverse_f32,
    roots_and_inverses_f32,
    libm::sinf,
    libm::cosf,
    libm::atan2f,
    libm::acosf,
    libm::expf,
    libm::erff
);
impl_real!(
    f64,
    glam::DVec3,
    glam::DMat3,
    libm::sqrt,
    root_and_inverse_f64,
    roots_and_inverses_f64,
    libm::sin,
    libm::cos,
    libm::atan2,
    libm::acos,
    libm::exp,
    libm::erf
);

#[inline]
fn root_and_inverse_f64(x: f64) -> (f64, f64) {
    let s = libm::sqrt(x);
    (s, 1.0 / s)
}

/// [`root_and_inverse_f64`] of each entry: the roots first, then the divisions, which
/// (unlike the roots, an instruction libm emits itself) the compiler packs.
#[inline(always)]
fn roots_and_inverses_f64(x: &[f64], s: &mut [f64], inv: &mut [f64]) {
    let (s, inv) = (&mut s[..x.len()], &mut inv[..x.len()]);
    for (s, &x) in s.iter_mut().zip(x) {
        *s = libm::sqrt(x);
    }
    for (inv, &s) in inv.iter_mut().zip(&*s) {
        *inv = 1.0 / s;
    }
}

/// [`root_and_inverse_f32`] of each entry.
#[inline(always)]
fn roots_and_inverses_f32(x: &[f32], s: &mut [f32], inv: &mut [f32]) {
    for ((&x, s), inv) in x.iter().zip(s).zip(inv) {
        (*s, *inv) = root_and_inverse_f32(x);
    }
}

/// libm's `sqrtf`, called rather than inlined on 32-bit Arm: there it is ~220 bytes of
/// software (no hardware path from safe stable Rust, see `root_and_inverse`) that
/// inlining copied into every call site (~1 kB of flash); elsewhere it is one instruction.
#[cfg_attr(target_arch = "arm", inline(never))]
#[cfg_attr(not(target_arch = "arm"), inline)]
fn sqrt_f32(x: f32) -> f32 {
    libm::sqrtf(x)
}

#[inline]
fn root_and_inverse_f32(x: f32) -> (f32, f32) {
    let bits = x.to_bits();
    // Positive normal numbers only: [2^-126, f32::MAX].
    if bits.wrapping_sub(0x0080_0000) >= 0x7f00_0000 {
        let s = sqrt_f32(x);
        return (s, 1.0 / s);
    }
    // A 3.4 % estimate from the bits, then y <- y (3/2 - x y^2 / 2): 1.8e-3, 4.6e-6,
    // 3e-11 (rounding bound).
    let h = 0.5 * x;
    let mut y = f32::from_bits(0x5f37_59df - (bits >> 1));
    for _ in 0..3 {
        y = y * (1.5 - h * y * y);
    }
    (x * y, y)
}

#[cfg(test)]
mod tests {
    use super::Real;

    /// Every input of two whole binades (both exponent parities) and random bit patterns
    /// over the normal range: within 4 units in the last place of the correctly rounded
    /// root and inverse root (from f64).
    #[test]
    fn f32_root_and_inverse_are_within_a_few_ulp() {
        let ulps = |got: f32, exact: f64| ((f64::from(got) - exact) / exact).abs() / 2f64.powi(-23);
        let check = |bits: u32| {
            let x = f32::from_bits(bits);
            let (s, inv) = x.root_and_inverse();
            let exact = f64::from(x).sqrt();
            assert!(ulps(s, exact) <= 4.0, "sqrt({x:e}) = {s:e}");
            assert!(ulps(inv, 1.0 / exact) <= 4.0, "1/sqrt({x:e}) = {inv:e}");
        };
        let one = 1.0f32.to_bits();
        (one..one + (2 << 23)).for_each(check);
        let mut r = 0x9e37_79b9u32;
        for _ in 0..1_000_000 {
            r ^= r << 13;
            r ^= r >> 17;
            r ^= r << 5;
            let bits = 0x0080_0000 + r % (0x7f80_0000 - 0x0080_0000);
            check(bits);
        }
        for x in [0.0f32, f32::INFINITY, f32::NAN, f32::from_bits(1)] {
            let (s, inv) = x.root_and_inverse();
            let want = libm::sqrtf(x);
            assert!(s.to_bits() == want.to_bits() || s.is_nan() && want.is_nan());
            assert!(inv.to_bits() == (1.0 / want).to_bits() || inv.is_nan());
        }
    }
}
