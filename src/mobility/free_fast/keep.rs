//! The kernel's transform kept in the caller's reals between products and between
//! steps: a header of [`HEADER`] reals before the transform records the parameters it
//! was computed for, and a product whose parameters match them bit for bit uses it as it
//! is. The transform is a function of those parameters alone (the padded and the
//! cloud's grid, the spacing and the spreading width; never the spheres' positions), so
//! a kept transform gives the bits a fresh one would.
//!
//! Each header word is written as four 16-bit digits, one per real (exact in `f32` and
//! `f64`), after a fixed tag: arrays the caller zeroed, or that hold anything but a
//! header written here, hold no transform. The header also counts the products that
//! kept the transform and those that computed it ([`TransformCounts`]).

use crate::real::Real;

/// Words: the tag, the parameters' key ([`KEY`] words), the two counts.
const WORDS: usize = 1 + KEY + 2;
/// Words of the key: padded grid (3), cloud grid (3), spacing and width as bits.
pub(super) const KEY: usize = 8;
/// Digits of 16 bits per word.
const DIGITS: usize = 4;
/// Reals of the header, at the start of the caller's reals.
pub const HEADER: usize = WORDS * DIGITS;
/// The tag that marks a header written here.
const TAG: u64 = 0x6b65_7074_6b65_726e;

/// How often the transform in a storage was kept and computed, over every product that
/// used it since the caller's reals were zeroed ([`transform_counts`](super::transform_counts)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TransformCounts {
    /// Products that found the transform for their parameters and used it.
    pub kept: u64,
    /// Products that computed it (none there, or one for other parameters).
    pub computed: u64,
}

/// Word `w` of the header, `None` where a digit is not one.
fn word<T: Real>(header: &[T], w: usize) -> Option<u64> {
    let mut v = 0u64;
    for d in 0..DIGITS {
        let x = header.get(w * DIGITS + d)?.to_f64();
        if !(0.0..65536.0).contains(&x) || x != libm::floor(x) {
            return None;
        }
        v = (v << 16) | x as u64;
    }
    Some(v)
}

fn put<T: Real>(header: &mut [T], w: usize, v: u64) {
    for d in 0..DIGITS {
        let digit = (v >> (16 * (DIGITS - 1 - d))) & 0xffff;
        header[w * DIGITS + d] = T::from_f64(digit as f64);
    }
}

/// The counts of a header written here; `None` for any other content.
pub(super) fn counts<T: Real>(header: &[T]) -> Option<TransformCounts> {
    (word(header, 0)? == TAG).then_some(())?;
    Some(TransformCounts {
        kept: word(header, 1 + KEY)?,
        computed: word(header, 2 + KEY)?,
    })
}

/// Whether the header records the transform of `key`; if so, counts a kept transform.
pub(super) fn keep<T: Real>(header: &mut [T], key: &[u64; KEY]) -> bool {
    let Some(c) = counts(header) else {
        return false;
    };
    if !(0..KEY).all(|w| word(header, 1 + w) == Some(key[w])) {
        return false;
    }
    put(header, 1 + KEY, c.kept.saturating_add(1));
    true
}

/// Marks the transform being computed: no transform until [`done`] (the counts kept).
pub(super) fn forget<T: Real>(header: &mut [T]) -> TransformCounts {
    let c = counts(header).unwrap_or_default();
    put(header, 0, 0);
    c
}

/// Records the transform of `key` as computed, after `before`'s counts.
pub(super) fn done<T: Real>(header: &mut [T], key: &[u64; KEY], before: TransformCounts) {
    for (w, &k) in key.iter().enumerate() {
        put(header, 1 + w, k);
    }
    put(header, 1 + KEY, before.kept);
    put(header, 2 + KEY, before.computed.saturating_add(1));
    put(header, 0, TAG);
}
