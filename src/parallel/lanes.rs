//! The fused assembly and first product of a small free-space RPY mobility (at most
//! [`MAX`] beads: the paper's 25-bead chain) with its
//! pairs side by side, in structure-of-arrays form: the same bits as the row-by-row
//! [`band_fused`](super::assembly::band_fused).
//!
//! Why: glam's `DVec3`/`DMat3` are scalar code, so a pair at a time leaves all but one
//! lane of every vector register empty. Here row `i` is evaluated column-wise over all
//! its pairs `(i, j)`, `j < i`: the positions, radii and the vectors `x` and `y` are
//! copied into arrays of `x`, `y` and `z` components, and each stage of [`pair_tt`]'s far
//! branch is a loop over `j` with no dependence between iterations, which the compiler
//! vectorises (two `f64` lanes with SSE2, four with AVX2). Each pair's block comes from
//! the same operations in the same order as [`pair_tt`]'s; only independent pairs share
//! an instruction. Row `i`'s own sum still adds its columns' products in column order,
//! and `y_j` still receives the rows' transposed products in row order.
//!
//! A block is symmetric bit for bit (`e_r e_c = e_c e_r`, the diagonal added on its
//! own), so six entries per pair are computed, and `B^T x` takes the same products as
//! `B x`. A row with a pair outside the far branch (overlapping spheres, NaN) is taken
//! pair by pair by [`pair_tt`]; nested spheres are the same first error.

use super::Pairs;
use crate::fault::ParticleError;
use crate::linalg::{Block, tri};
use crate::real::Real;
use crate::rpy::{Hydro, pair_tt, self_tt};

/// Beads the lanes take at most (the arrays live on the stack, and are zeroed once per
/// assembly: 32 covers the paper's chain at half the bytes of `RUNS_MIN`).
pub(super) const MAX: usize = 32;

/// One value per column of a row.
type Col<T> = [T; MAX];

/// The components of a run of vectors, one array each.
struct Soa<T: Real> {
    x: Col<T>,
    y: Col<T>,
    z: Col<T>,
}

impl<T: Real> Soa<T> {
    #[inline(always)]
    fn new(v: &[T::V3]) -> Self {
        let mut s = Self {
            x: [T::ZERO; MAX],
            y: [T::ZERO; MAX],
            z: [T::ZERO; MAX],
        };
        for (k, &vk) in v.iter().enumerate() {
            [s.x[k], s.y[k], s.z[k]] = T::xyz(vk);
        }
        s
    }
}

/// Per-column work arrays of one row.
struct Work<T: Real> {
    r: Soa<T>,
    s2: Col<T>,
    s: Col<T>,
    inv: Col<T>,
    /// The blocks' six distinct entries `b00, b10, b20, b11, b21, b22`.
    b: [Col<T>; 6],
    /// `B x_j`, summed into the row in column order afterwards.
    u: Soa<T>,
}

/// [`band_fused`](super::assembly::band_fused) of all `y.len()` rows (`b0 = 0`, at most
/// [`MAX`] rows, `Hydro::Rpy`) column-wise: the same blocks into `rows`, the same
/// product bits in `y`, the same first error.
#[inline(always)]
pub(super) fn band_lanes<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    rows: &mut [B],
    x: &[T::V3],
    y: &mut [T::V3],
) -> Result<(), ParticleError> {
    let n = y.len();
    let (eta, pos, radius) = (src.eta, &src.pos[..n], &src.radius[..n]);
    let (p, xs) = (Soa::<T>::new(pos), Soa::<T>::new(&x[..n]));
    // `y` starts from the diagonal terms, as in `Pairs::start`.
    let mut ys = Soa::<T>::new(&[]);
    for i in 0..n {
        let diag = T::m3_diag(self_tt(eta, radius[i]));
        rows[tri(i) + i] = B::store(diag);
        [ys.x[i], ys.y[i], ys.z[i]] = T::xyz(diag * x[i]);
    }
    let z = [T::ZERO; MAX];
    let mut w = Work {
        r: Soa::new(&[]),
        s2: z,
        s: z,
        inv: z,
        b: [z; 6],
        u: Soa::new(&[]),
    };
    for i in 0..n {
        let (row, _) = rows[tri(i)..].split_at_mut(i);
        let acc = row_lanes(src, i, &p, &xs, &mut ys, &mut w, row)?;
        ys.x[i] += acc[0];
        ys.y[i] += acc[1];
        ys.z[i] += acc[2];
    }
    for (k, yk) in y.iter_mut().enumerate() {
        *yk = T::v3(ys.x[k], ys.y[k], ys.z[k]);
    }
    Ok(())
}

/// Row `i`: its blocks into `row`, their transposed products with `x_i` added to `y_j`,
/// and the sum of their products with `x_j` in column order (returned).
#[inline(always)]
fn row_lanes<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    i: usize,
    p: &Soa<T>,
    xs: &Soa<T>,
    ys: &mut Soa<T>,
    w: &mut Work<T>,
    row: &mut [B],
) -> Result<[T; 3], ParticleError> {
    let (eta, a) = (src.eta, &src.radius[..i]);
    let [pix, piy, piz] = T::xyz(src.pos[i]);
    let [xix, xiy, xiz] = T::xyz(xs_at(xs, i));
    let ai = src.radius[i];
    // `r = r_i - r_j`, `s^2 = |r|^2`; whether any pair is nested (`s^2 <= (a_i - a_j)^2`),
    // found as one flag so that the loop stays a vector loop.
    let mut nested = false;
    {
        let (px, py, pz) = (&p.x[..i], &p.y[..i], &p.z[..i]);
        let (rx, ry, rz) = (&mut w.r.x[..i], &mut w.r.y[..i], &mut w.r.z[..i]);
        let s2 = &mut w.s2[..i];
        for j in 0..i {
            let (x, y, z) = (pix - px[j], piy - py[j], piz - pz[j]);
            (rx[j], ry[j], rz[j]) = (x, y, z);
            let d2 = x * x + y * y + z * z;
            s2[j] = d2;
            let dif = ai - a[j];
            nested |= d2 <= dif * dif;
        }
    }
    if nested {
        return row_pairs(src, i, xs, ys, row);
    }
    T::roots_and_inverses(&w.s2[..i], &mut w.s[..i], &mut w.inv[..i]);
    let mut near = false;
    for (&s, &aj) in w.s[..i].iter().zip(a) {
        near |= !(s > ai + aj);
    }
    if near {
        return row_pairs(src, i, xs, ys, row);
    }
    // `tt_block`'s far branch, its constants formed as it forms them: `e = r / s`,
    // `c = 1 / (8 pi eta s)`, `q = (a_i^2 + a_j^2) / s^2`,
    // `B = c (1 - q) e e^T + c (1 + q / 3) I`; then `B x_j` and `B^T x_i` (glam's
    // order: columns times components, summed in order).
    let k8 = T::ONE / (T::from_f64(8.0) * T::PI * eta);
    let third = T::ONE / T::from_f64(3.0);
    {
        let (rx, ry, rz, inv) = (&w.r.x[..i], &w.r.y[..i], &w.r.z[..i], &w.inv[..i]);
        let (xjx, xjy, xjz) = (&xs.x[..i], &xs.y[..i], &xs.z[..i]);
        let [b00, b10, b20, b11, b21, b22] = &mut w.b;
        let (b00, b10, b20) = (&mut b00[..i], &mut b10[..i], &mut b20[..i]);
        let (b11, b21, b22) = (&mut b11[..i], &mut b21[..i], &mut b22[..i]);
        let (ux, uy, uz) = (&mut w.u.x[..i], &mut w.u.y[..i], &mut w.u.z[..i]);
        let (yx, yy, yz) = (&mut ys.x[..i], &mut ys.y[..i], &mut ys.z[..i]);
        for j in 0..i {
            let v = inv[j];
            let (ex, ey, ez) = (rx[j] * v, ry[j] * v, rz[j] * v);
            let c = v * k8;
            let q = (ai * ai + a[j] * a[j]) * (v * v);
            let (f, d) = (c * (T::ONE - q), c * (T::ONE + q * third));
            let (m00, m10, m20) = (ex * ex * f + d, ey * ex * f, ez * ex * f);
            let (m11, m21, m22) = (ey * ey * f + d, ez * ey * f, ez * ez * f + d);
            (b00[j], b10[j], b20[j], b11[j], b21[j], b22[j]) = (m00, m10, m20, m11, m21, m22);
            let (x, y, z) = (xjx[j], xjy[j], xjz[j]);
            ux[j] = m00 * x + m10 * y + m20 * z;
            uy[j] = m10 * x + m11 * y + m21 * z;
            uz[j] = m20 * x + m21 * y + m22 * z;
            yx[j] += m00 * xix + m10 * xiy + m20 * xiz;
            yy[j] += m10 * xix + m11 * xiy + m21 * xiz;
            yz[j] += m20 * xix + m21 * xiy + m22 * xiz;
        }
    }
    let [b00, b10, b20, b11, b21, b22] = &w.b;
    for (j, o) in row.iter_mut().enumerate() {
        *o = B::store(T::m3_cols(
            T::v3(b00[j], b10[j], b20[j]),
            T::v3(b10[j], b11[j], b21[j]),
            T::v3(b20[j], b21[j], b22[j]),
        ));
    }
    let mut acc = [T::ZERO; 3];
    for j in 0..i {
        acc[0] += w.u.x[j];
        acc[1] += w.u.y[j];
        acc[2] += w.u.z[j];
    }
    Ok(acc)
}

/// Vector `i` of a [`Soa`].
#[inline(always)]
fn xs_at<T: Real>(s: &Soa<T>, i: usize) -> T::V3 {
    T::v3(s.x[i], s.y[i], s.z[i])
}

/// Row `i` pair by pair ([`pair_tt`]; a pair outside the far branch, or nested: the
/// first error in column order): what [`row_lanes`] does, as
/// [`band_fused`](super::assembly::band_fused)'s row does it.
#[cold]
fn row_pairs<T: Real, B: Block<T>>(
    src: Pairs<'_, T>,
    i: usize,
    xs: &Soa<T>,
    ys: &mut Soa<T>,
    row: &mut [B],
) -> Result<[T; 3], ParticleError> {
    let (eta, pos, radius) = (src.eta, src.pos, src.radius);
    let xi = xs_at(xs, i);
    let mut acc = T::V3_ZERO;
    for (j, o) in row.iter_mut().enumerate() {
        let b = pair_tt(Hydro::Rpy, eta, radius[i], radius[j], pos[i] - pos[j])
            .ok_or(ParticleError::Nested { i: j, j: i })?;
        *o = B::store(b);
        acc += b * xs_at(xs, j);
        let [tx, ty, tz] = T::xyz(T::m3_tmul(b, xi));
        ys.x[j] += tx;
        ys.y[j] += ty;
        ys.z[j] += tz;
    }
    Ok(T::xyz(acc))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec3};

    /// Deterministic values in [-0.5, 0.5) (a Weyl sequence of the golden ratio).
    fn values(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed as f64 * 0.1;
        move || {
            x = (x + 0.618_033_988_749_895) % 1.0;
            x - 0.5
        }
    }

    /// The lanes against the row-by-row fused band on `pos.len()` beads: the same first
    /// error, or the same blocks and product, bit for bit.
    fn check<T: Real>(pos: &[T::V3], radius: &[T], x: &[T::V3]) {
        let n = pos.len();
        let src = Pairs {
            level: Hydro::Rpy,
            eta: T::from_f64(0.7),
            pos,
            radius,
        };
        let (mut o0, mut o1) = ([T::M3_ZERO; tri(MAX)], [T::M3_ZERO; tri(MAX)]);
        let (mut y0, mut y1) = ([T::V3_ZERO; MAX], [T::V3_ZERO; MAX]);
        let (y0, y1) = (&mut y0[..n], &mut y1[..n]);
        let r0 = super::super::assembly::band_fused::<T, T::M3>(src, &mut o0, 0, x, y0, &mut []);
        let r1 = band_lanes::<T, T::M3>(src, &mut o1, x, y1);
        assert_eq!(r0, r1, "n = {n}");
        if r0.is_ok() {
            let m = |b: &T::M3| T::m3_entries(b).map(|e| e.to_f64().to_bits());
            let same = o0[..tri(n)].iter().zip(&o1).all(|(a, b)| m(a) == m(b));
            assert!(same, "blocks, n = {n}");
            let v = |v: &T::V3| T::v3_to_f64(*v).map(f64::to_bits);
            assert!(
                y0.iter().zip(&*y1).all(|(a, b)| v(a) == v(b)),
                "product, n = {n}"
            );
        }
    }

    /// Every bead count the lanes serve: far pairs only, a few overlapping ones (the
    /// scalar branch within a run), a nested pair after an overlapping one (the first
    /// error), a NaN; in both precisions.
    #[test]
    fn lanes_give_the_bits_and_first_error_of_the_fused_band() {
        for n in 0..=MAX {
            for case in 0..4 {
                let mut v = values(n as u64 * 4 + case);
                let mut pos = [DVec3::ZERO; MAX];
                let (mut radius, mut x) = ([0.0; MAX], [DVec3::ZERO; MAX]);
                for k in 0..n {
                    pos[k] = DVec3::new(4.0 * v(), 4.0 * v(), 2.1 * k as f64 + 0.3 * v());
                    radius[k] = 0.4 + 0.5 * (v() + 0.5);
                    x[k] = DVec3::new(v(), v(), -v());
                }
                if n > 9 {
                    match case {
                        1 => {
                            pos[n - 2] = pos[n - 5] + DVec3::new(0.3, 0.4, 0.2);
                            pos[7] = pos[2] + DVec3::new(0.0, 0.5, 0.1);
                        }
                        2 => {
                            pos[n - 3] = pos[n - 7] + DVec3::new(0.2, 0.4, 0.0);
                            pos[n - 1] = pos[5];
                        }
                        3 => pos[n / 2].x = f64::NAN,
                        _ => {}
                    }
                }
                check::<f64>(&pos[..n], &radius[..n], &x[..n]);
                let p32 = pos.map(|p| p.as_vec3());
                let (r32, x32) = (radius.map(|r| r as f32), x.map(|p| p.as_vec3()));
                let _: &[Vec3] = &x32;
                check::<f32>(&p32[..n], &r32[..n], &x32[..n]);
            }
        }
    }
}
