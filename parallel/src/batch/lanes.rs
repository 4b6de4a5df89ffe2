//! [`Lanes`]: `K` independent `f64` values, one per system, and the divergence flag.
//!
//! Every arithmetic operation is the `f64` operation lane by lane (written as a loop
//! over a fixed-size array, which LLVM packs into `addpd`/`vaddpd`, `mulpd`, `divpd`,
//! `sqrtpd`), so lane `k` of a result has the bits the scalar operation gives on lane
//! `k`'s operands. What cannot be lane-wise (a comparison that steers a branch, a
//! single `f64` taken out) is decided per lane; where the lanes disagree the answer is
//! lane 0's and the lanes that answered otherwise are marked in the thread's
//! divergence mask ([`diverged`]), so that the caller throws those lanes' values away.

use core::cell::Cell;
use core::cmp::Ordering;
use core::fmt;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

thread_local! {
    /// The lanes (bit `k` for lane `k`) whose answer to a decision differed from lane
    /// 0's on this thread.
    static DIVERGED: Cell<u64> = const { Cell::new(0) };
}

/// Most lanes a [`Lanes`] may have: one bit each in the divergence mask.
pub const MAX_LANES: usize = 64;

/// Clears this thread's divergence mask (before a lane step).
pub fn clear_divergence() {
    DIVERGED.with(|d| d.set(0));
}

/// The lanes whose answer to some decision differed from lane 0's on this thread
/// since [`clear_divergence`] (bit `k` for lane `k`; 0 when every lane followed its own
/// path). A lane whose bit is clear took, at every decision, the side it would have
/// taken alone, so its values are its own step's.
pub fn diverged() -> u64 {
    DIVERGED.with(|d| d.get())
}

/// Lane 0's answer; marks every lane that gave another.
#[inline(always)]
pub(super) fn agree<X: PartialEq + Copy, const K: usize>(x: [X; K]) -> X {
    const { assert!(K <= MAX_LANES, "at most 64 lanes") };
    let first = x[0];
    let mut mask = 0u64;
    for (k, y) in x.iter().enumerate() {
        mask |= u64::from(*y != first) << k;
    }
    if mask != 0 {
        DIVERGED.with(|d| d.set(d.get() | mask));
    }
    first
}

/// `K` `f64` values, lane `k` belonging to system `k` (`K` at most [`MAX_LANES`]).
#[derive(Clone, Copy)]
#[repr(transparent)]
pub struct Lanes<const K: usize>(pub [f64; K]);

impl<const K: usize> Lanes<K> {
    /// Every lane `x`.
    #[inline(always)]
    pub const fn splat(x: f64) -> Self {
        Self([x; K])
    }

    /// `f` lane by lane.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self(core::array::from_fn(|k| f(self.0[k])))
    }

    /// `f` of the two operands' lanes, lane by lane.
    #[inline(always)]
    pub fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Self(core::array::from_fn(|k| f(self.0[k], other.0[k])))
    }

    /// A decision taken per lane ([`agree`]).
    #[inline(always)]
    pub(super) fn decide<X: PartialEq + Copy>(self, other: Self, f: impl Fn(f64, f64) -> X) -> X {
        agree(core::array::from_fn::<X, K, _>(|k| {
            f(self.0[k], other.0[k])
        }))
    }
}

impl<const K: usize> Default for Lanes<K> {
    fn default() -> Self {
        Self::splat(0.0)
    }
}

impl<const K: usize> fmt::Debug for Lanes<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.0.iter()).finish()
    }
}

impl<const K: usize> fmt::Display for Lanes<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[")?;
        for (k, x) in self.0.iter().enumerate() {
            if k > 0 {
                write!(f, ", ")?;
            }
            fmt::Display::fmt(x, f)?;
        }
        write!(f, "]")
    }
}

/// Equality is a decision: per lane, lane 0's answer where they disagree.
impl<const K: usize> PartialEq for Lanes<K> {
    #[inline(always)]
    fn eq(&self, other: &Self) -> bool {
        self.decide(*other, |a, b| a == b)
    }
}

/// Every comparison is a decision, each written out (not derived from `partial_cmp`,
/// which would raise the flag where lanes order differently but agree on `<`).
impl<const K: usize> PartialOrd for Lanes<K> {
    #[inline(always)]
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        self.decide(*other, |a, b| a.partial_cmp(&b))
    }
    #[inline(always)]
    fn lt(&self, other: &Self) -> bool {
        self.decide(*other, |a, b| a < b)
    }
    #[inline(always)]
    fn le(&self, other: &Self) -> bool {
        self.decide(*other, |a, b| a <= b)
    }
    #[inline(always)]
    fn gt(&self, other: &Self) -> bool {
        self.decide(*other, |a, b| a > b)
    }
    #[inline(always)]
    fn ge(&self, other: &Self) -> bool {
        self.decide(*other, |a, b| a >= b)
    }
}

macro_rules! binary {
    ($tr:ident, $f:ident, $atr:ident, $af:ident, $op:tt) => {
        impl<const K: usize> $tr for Lanes<K> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                self.zip(o, |a, b| a $op b)
            }
        }
        impl<const K: usize> $atr for Lanes<K> {
            #[inline(always)]
            fn $af(&mut self, o: Self) {
                *self = self.zip(o, |a, b| a $op b);
            }
        }
    };
}
binary!(Add, add, AddAssign, add_assign, +);
binary!(Sub, sub, SubAssign, sub_assign, -);
binary!(Mul, mul, MulAssign, mul_assign, *);
binary!(Div, div, DivAssign, div_assign, /);

impl<const K: usize> Neg for Lanes<K> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
}
