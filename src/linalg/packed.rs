//! The packed symmetric product's band kernel: rows of `y = A x` with the transposed
//! blocks' products summed beside them. [`sym_matvec`](super::sym_matvec) is its
//! one-band case; `parallel` runs it band by band on a host's threads.

use super::{Block, tri};
use crate::real::Real;

/// One band of the product: rows `b0..b0 + y.len()` of `y = A x` from the packed `a`,
/// with the transposed blocks left of the band summed into `z` (the `b0` rows above, from
/// zero), those inside it into `y`. Row `i` starts `y_i` from its diagonal term and adds
/// its lower blocks' products in order; the transposed products reach `y_j` from the rows
/// below in row order. With `b0 = 0` this is the one-pass
/// [`sym_matvec`](crate::linalg::sym_matvec).
#[inline(always)]
pub(crate) fn band<T: Real, B: Block<T>>(
    a: &[B],
    b0: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    z.fill(T::V3_ZERO);
    for (k, yk) in y.iter_mut().enumerate() {
        let i = b0 + k;
        *yk = a[tri(i) + i].mul(x[i]);
    }
    for k in 0..y.len() {
        row::<T, B>(a, b0, k, x, y, z);
    }
}

/// Row `b0 + k` of a [`band`]: its lower blocks' products summed in order into `y_k`,
/// their transposed products added to `z` (left of the band) and `y` (inside it).
#[inline(always)]
fn row<T: Real, B: Block<T>>(
    a: &[B],
    b0: usize,
    k: usize,
    x: &[T::V3],
    y: &mut [T::V3],
    z: &mut [T::V3],
) {
    let i = b0 + k;
    let (left, inside) = a[tri(i)..tri(i) + i].split_at(b0);
    let xi = x[i];
    let mut acc = T::V3_ZERO;
    for ((&b, zj), &xj) in left.iter().zip(z.iter_mut()).zip(x) {
        acc += b.mul(xj);
        *zj += b.tmul(xi);
    }
    let (ys, yi) = y[..=k].split_at_mut(k);
    for ((&b, yj), &xj) in inside.iter().zip(ys).zip(&x[b0..]) {
        acc += b.mul(xj);
        *yj += b.tmul(xi);
    }
    yi[0] += acc;
}
