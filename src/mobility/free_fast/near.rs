//! The near part: the self blocks, and for each pair closer than the cutoff the exact
//! RPY block (overlapping branch included) minus the far block ([`radial`]), for the
//! translation product and the grand one (torques in, rotations out).
//!
//! Each pair once, from the later row in the cell list's order, its blocks applied both
//! ways. The rows run in pieces ([`pieces`]): a piece adds to its own rows, and to the
//! earlier pieces' rows in its own partial sums, which a second round adds in piece
//! order; so every value is summed in the same order whatever the thread count.

use core::convert::Infallible;

use super::pieces::{self, JOBS, before, none, range, rows};
use super::{FreeError, FreeFast, SQRT_2, radial};
use crate::cell_list::CellList;
use crate::fault::ParticleError;
use crate::mobility::{Hydro, pair_blocks, pair_tt, self_rr, self_tt};
use crate::parallel::Parallel;
use crate::real::Real;

const PI: f64 = core::f64::consts::PI;

/// The spheres and what acts on them: forces, and torques for the grand product.
#[derive(Clone, Copy)]
pub(super) struct Spheres<'s, T: Real> {
    pub(super) pos: &'s [T::V3],
    pub(super) radius: &'s [T],
    pub(super) force: &'s [T::V3],
    pub(super) torque: Option<&'s [T::V3]>,
}

impl<T: Real> Spheres<'_, T> {
    /// Reals per result row: a velocity, and a rotation for the grand product.
    pub(super) fn width(&self) -> usize {
        if self.torque.is_some() { 6 } else { 3 }
    }
}

/// Reals of the near part's partial sums for `n` spheres and rows of `width`: piece `t`
/// keeps a row for each sphere of the pieces before it.
pub(super) fn partial_len(n: usize, width: usize) -> usize {
    (0..JOBS).map(|t| width * range(n, t)[0]).sum()
}

/// `s[q] += v` for rows of 3 reals.
#[inline(always)]
fn add<T: Real>(s: &mut [T], q: usize, v: T::V3) {
    for (x, c) in s[3 * q..3 * q + 3].iter_mut().zip(T::xyz(v)) {
        *x += c;
    }
}

impl<T: Real> FreeFast<T> {
    /// `rows[k] = M^near (F, T)` for sphere `order[k]` (`order` the cell list's, else
    /// index order; [`Spheres::width`] reals each: velocity, then rotation), `rank` the
    /// inverse of `order`. The first error in row order.
    pub(super) fn near(
        &self,
        eta: T,
        s: Spheres<'_, T>,
        (list, rank): (Option<&CellList<'_>>, &[usize]),
        (rows_buf, partial): (&mut [T], &mut [T]),
        par: &dyn Parallel,
    ) -> Result<(), FreeError> {
        let Spheres {
            pos,
            radius,
            force,
            torque,
        } = s;
        let (n, w) = (pos.len(), s.width());
        let rad = radial::Radial::new(
            1.0 / (2.0 * SQRT_2 * self.sigma),
            2.0 * self.sigma * self.sigma,
        );
        let cut2 = self.r_cut * self.r_cut;
        let inv_eta = 1.0 / eta.to_f64();
        let sc = |c: f64| T::from_f64(c * inv_eta);
        let at = |k: usize| list.map_or(k, |l| l.order()[k]);
        // Row `q`'s velocity and rotation in a slice of rows of `w`.
        let put = |s: &mut [T], q: usize, v: T::V3, o: Option<T::V3>| {
            add(s, q * w / 3, v);
            if let Some(o) = o {
                add(s, q * 2 + 1, o);
            }
        };
        let cuts = (
            (&mut rows_buf[..w * n], &rows(w) as _),
            (&mut partial[..partial_len(n, w)], &before(w) as _),
            none(),
        );
        pieces::pieces(par, n, cuts, |[a, b], r, part, _| {
            part.fill(T::ZERO);
            r.fill(T::ZERO);
            for k in a..b {
                let i = at(k);
                let alpha = radius[i].to_f64() * radius[i].to_f64() / 6.0;
                let (c_self, _) = rad.far((alpha, alpha), 0.0);
                let v = force[i] * (self_tt(eta, radius[i]) - sc(c_self));
                let o = torque.map(|t| {
                    let c = rad.rotation((alpha, alpha), 0.0)[2];
                    t[i] * (self_rr(eta, radius[i]) - sc(c))
                });
                put(r, k - a, v, o);
            }
            for k in a..b {
                let i = at(k);
                let ai = radius[i];
                let alpha_i = ai.to_f64() * ai.to_f64() / 6.0;
                let (mut acc, mut acc_o) = (T::V3_ZERO, T::V3_ZERO);
                let mut err = None;
                let mut pair = |j: usize| {
                    let q = rank[j];
                    if q >= k || err.is_some() {
                        return;
                    }
                    let d = pos[i] - pos[j];
                    let u = T::norm2(d).to_f64();
                    if u >= cut2 {
                        return;
                    }
                    let nested = FreeError::Particle(ParticleError::Nested { i: j, j: i });
                    let aj = radius[j].to_f64();
                    let alpha = (alpha_i, aj * aj / 6.0);
                    let (fi, fj) = (force[i], force[j]);
                    // One evaluation of the radial functions for every block.
                    let ((ci, crr), rot) = match torque {
                        Some(_) => rad.grand(alpha, u),
                        None => (rad.far(alpha, u), [0.0; 4]),
                    };
                    let far = |f: T::V3| f * sc(ci) + d * (T::dot(d, f) * sc(crr));
                    let Some(tq) = torque else {
                        if u > (ai.to_f64() + aj) * (ai.to_f64() + aj) {
                            // Apart: RPY's far branch, `((1 + A / (3 r^2)) I + (1 - A /
                            // r^2) e e) / (8 pi r)`, less the far block as two scalars in
                            // f64 (no block formed, no cancellation in `T`).
                            let a2 = alpha_i * 6.0 + aj * aj;
                            let c = 1.0 / (8.0 * PI * libm::sqrt(u));
                            let (ri, rr) = (c * (1.0 + a2 / (3.0 * u)), c * (1.0 - a2 / u) / u);
                            let (ni, nrr) = (sc(ri - ci), sc(rr - crr));
                            let near = |f: T::V3| f * ni + d * (T::dot(d, f) * nrr);
                            acc += near(fj);
                            match q >= a {
                                true => put(r, q - a, near(fi), None),
                                false => put(part, q, near(fi), None),
                            }
                            return;
                        }
                        let Some(rpy) = pair_tt(Hydro::Rpy, eta, ai, radius[j], d) else {
                            err = Some(nested);
                            return;
                        };
                        acc += rpy * fj - far(fj);
                        match q >= a {
                            true => put(r, q - a, rpy * fi - far(fi), None),
                            false => put(part, q, rpy * fi - far(fi), None),
                        }
                        return;
                    };
                    let Some(e) = pair_blocks(Hydro::Rpy, eta, ai, radius[j], d) else {
                        err = Some(nested);
                        return;
                    };
                    let [hi, hj, ri, rrr] = rot.map(sc);
                    let rr = |t: T::V3| e.rr * t - (t * ri + d * (T::dot(d, t) * rrr));
                    let (ti, tj) = (tq[i], tq[j]);
                    // `tr_ij = rt_ji^T`: the translation of `i` from the torque on `j`.
                    let (tr_ij, tr_ji) = (T::transpose(e.rt_ji), T::transpose(e.rt_ij));
                    acc += e.tt * fj - far(fj) + tr_ij * tj - T::cross(d, tj) * hi;
                    acc_o += e.rt_ij * fj - T::cross(d, fj) * hj + rr(tj);
                    let v = e.tt * fi - far(fi) + tr_ji * ti + T::cross(d, ti) * hj;
                    let o = e.rt_ji * fi + T::cross(d, fi) * hi + rr(ti);
                    match q >= a {
                        true => put(r, q - a, v, Some(o)),
                        false => put(part, q, v, Some(o)),
                    }
                };
                match list {
                    Some(l) => l.near::<T>(pos[i], &mut pair),
                    None => (0..i).for_each(&mut pair),
                }
                if let Some(e) = err {
                    return Err(e);
                }
                put(r, k - a, acc, torque.map(|_| acc_o));
            }
            Ok(())
        })?;
        // Each piece's rows gain the later pieces' partial sums, in piece order.
        let partial = &*partial;
        let cuts = ((&mut rows_buf[..w * n], &rows(w) as _), none(), none());
        pieces::pieces(par, n, cuts, |[a, b], r, _, _| {
            let mut offset = 0;
            for t in 0..JOBS {
                let [at, _] = range(n, t);
                if at >= b && b > a {
                    let src = &partial[offset + w * a..offset + w * b];
                    r.iter_mut().zip(src).for_each(|(x, s)| *x += *s);
                }
                offset += w * at;
            }
            Ok::<(), Infallible>(())
        })
        .map_err(|e| match e {})
    }
}
