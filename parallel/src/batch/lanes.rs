//! [`Lanes`]: `K` independent `f64` values, one per system, and the divergence flag.
//!
//! Every arithmetic operation is the `f64` operation lane by lane (written as a loop
//! over a fixed-size array, which LLVM packs into `addpd`/`vaddpd`, `mulpd`, `divpd`,
//! `sqrtpd`), so lane `k` of a result has the bits the scalar operation gives on lane
//! `k`'s operands. What cannot be lane-wise (a comparison that steers a branch, a
//! single `f64` taken out) is decided per lane; where the lanes disagree the answer is
//! lane 0's and the thread's divergence flag ([`diverged`]) is raised, so that the
//! caller knows the other lanes did not follow their own path and throws them away.

use core::cell::Cell;
use core::cmp::Ordering;
use core::fmt;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

thread_local! {
    /// Raised when the lanes of a decision disagreed on this thread.
    static DIVERGED: Cell<bool> = const { Cell::new(false) };
}

/// Clears this thread's divergence flag (before a lane step).
pub fn clear_divergence() {
    DIVERGED.with(|d| d.set(false));
}

/// Whether a decision's lanes disagreed on this thread since [`clear_divergence`].
pub fn diverged() -> bool {
    DIVERGED.with(|d| d.get())
}

/// Lane 0's answer; raises the flag unless every lane gave it.
#[inline(always)]
pub(super) fn agree<X: PartialEq + Copy, const K: usize>(x: [X; K]) -> X {
    let first = x[0];
    if x.iter().any(|&y| y != first) {
        if std::env::var_os("BATCH_TRACE").is_some() && !diverged() {
            eprintln!("{}", std::backtrace::Backtrace::force_capture());
        }
        DIVERGED.with(|d| d.set(true));
    }
    first
}

/// `K` `f64` values, lane `k` belonging to system `k`.
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
        let mut out = self.0;
        for x in &mut out {
            *x = f(*x);
        }
        Self(out)
    }

    /// `f` of the two operands' lanes, lane by lane.
    #[inline(always)]
    pub fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut out = self.0;
        for (x, &y) in out.iter_mut().zip(&other.0) {
            *x = f(*x, y);
        }
        Self(out)
    }

    /// A decision taken per lane ([`agree`]).
    #[inline(always)]
    pub(super) fn decide<X: PartialEq + Copy>(self, other: Self, f: impl Fn(f64, f64) -> X) -> X {
        agree(core::array::from_fn::<X, K, _>(|k| f(self.0[k], other.0[k])))
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
