//! Newton's factor of the active rows with one-sided rows (`docs/CONTACTS.md`, "Large
//! piles"): the chord matrix does not change within a solve, only the active set does,
//! so the factor is built once per solve and then follows the set row by row
//! ([`ordered_append`](crate::linalg::ordered_append) for a row taken in,
//! [`ordered_remove`](crate::linalg::ordered_remove) for one released: `O(rows^2)`
//! each instead of a factorisation's `O(rows^3)`). Its rows are the bonds and the
//! active one-sided rows, in the order they entered (list order at the build); an
//! inactive row is not in it (its update is `-lambda_k`, the release of its
//! multiplier, the active rows' right-hand side corrected by `A_jk lambda_k`).

use super::{Metric, onesided};
use crate::bonds::Bond;
use crate::fault::LinalgError;
use crate::linalg::{ordered_append, ordered_build, ordered_remove, ordered_solve};
use crate::real::Real;

/// The chord matrix `A = c G D` and the factor of its active rows.
pub(super) struct Rows<'s, 'm, T: Real> {
    pub metric: &'s Metric<'m, T>,
    pub bonds: &'s [Bond<T>],
    /// The chord factor `c`.
    pub c: T,
    /// The first one-sided row.
    pub from: usize,
    /// The rank tolerance.
    pub floor: T,
}

impl<T: Real> Rows<'_, '_, T> {
    /// `A_kl`, as the lower triangle is formed: along row `max(k, l)`'s gradient.
    fn entry(&self, k: usize, l: usize) -> T {
        let (r, s) = if l <= k { (k, l) } else { (l, k) };
        T::dot(
            self.metric.grad(r) * self.c,
            self.metric.relative(self.bonds, r, s),
        )
    }

    /// Whether row `k` is an equality of the current set.
    fn on(&self, state: &[usize], k: usize) -> bool {
        k < self.from || onesided::active(state[k])
    }

    /// The factor of the current set from scratch (rows in list order) into `jac`
    /// (stride `bonds`), `order` holding the rows by position. Returns the rows in it
    /// and the dependent rows counted.
    pub fn build(
        &self,
        state: &[usize],
        order: &mut [usize],
        jac: &mut [T],
    ) -> Result<(usize, usize), LinalgError> {
        let nb = self.bonds.len();
        let mut m = 0;
        for k in (0..nb).filter(|&k| self.on(state, k)) {
            order[m] = k;
            m += 1;
        }
        let order = &*order;
        let d = ordered_build(jac, nb, m, self.floor, |i, j| {
            self.entry(order[i], order[j])
        })?;
        Ok((m, d))
    }

    /// The factor of `m` rows brought to the current set: released rows removed (from
    /// the last position up), rows taken in appended in list order. Returns the
    /// dependent rows counted.
    pub fn sync(
        &self,
        state: &[usize],
        order: &mut [usize],
        m: &mut usize,
        jac: &mut [T],
    ) -> Result<usize, LinalgError> {
        let nb = self.bonds.len();
        for p in (0..*m).rev() {
            if !self.on(state, order[p]) {
                order.copy_within(p + 1..*m, p);
                let order = &*order;
                ordered_remove(jac, nb, *m, p, self.floor, |j| {
                    self.entry(order[j], order[j])
                });
                *m -= 1;
            }
        }
        for k in self.from..nb {
            if self.on(state, k) && !order[..*m].contains(&k) {
                let pos = &order[..*m];
                ordered_append(jac, nb, *m, self.floor, self.entry(k, k), |j| {
                    self.entry(k, pos[j])
                })
                .map_err(|_| LinalgError::NotPositiveDefinite { row: k })?;
                order[*m] = k;
                *m += 1;
            }
        }
        Ok((0..*m).filter(|&i| jac[i * nb + i] == T::ZERO).count())
    }

    /// The factor the last solve left (`m` rows at stride `stride`, `order` holding
    /// them by position, in that solve's indices) brought to this solve's list: the
    /// `released` row taken out of it (and the rows after it one index down, as the
    /// list moved them), the factor restrided to this solve's rows. Returns the rows
    /// left in it.
    pub fn carried(
        &self,
        (m, stride): (usize, usize),
        released: Option<usize>,
        order: &mut [usize],
        jac: &mut [T],
    ) -> usize {
        let nb = self.bonds.len();
        let mut m = m;
        if let Some(r) = released {
            let at = order[..m].iter().position(|&k| k == r);
            for k in order[..m].iter_mut().filter(|k| **k > r) {
                *k -= 1;
            }
            if let Some(p) = at {
                order.copy_within(p + 1..m, p);
                let order = &*order;
                ordered_remove(jac, stride, m, p, self.floor, |j| {
                    self.entry(order[j], order[j])
                });
                m -= 1;
            }
        }
        // Rows from the last up where the stride grows, from the first down where it
        // shrinks: a row's new place never overwrites a row not yet moved.
        let row = |i: usize| (i * stride..i * stride + i + 1, i * nb);
        match nb > stride {
            true => (0..m).rev().for_each(|i| {
                let (from, to) = row(i);
                jac.copy_within(from, to);
            }),
            false => (0..m).for_each(|i| {
                let (from, to) = row(i);
                jac.copy_within(from, to);
            }),
        }
        m
    }

    /// Whether bringing the factor of `m` rows (`order`) to the current set row by row
    /// would cost more than building it: a removal at position `p` costs about `3 (m -
    /// p)^2` (the rotations of the block below it), an append `m^2` (the forward
    /// substitution), the factorisation `m^3 / 3`. A carried factor that the first
    /// iteration's set shrinks to its first rows (the rows appended last go first) is
    /// cheap to bring; one that has to change all through is not.
    pub fn rebuild_cheaper(&self, state: &[usize], order: &[usize], m: usize) -> bool {
        let mut rows = m;
        let mut cost = 0;
        for p in (0..m).rev().filter(|&p| !self.on(state, order[p])) {
            cost += 3 * (rows - p) * (rows - p);
            rows -= 1;
        }
        for k in (self.from..self.bonds.len()).filter(|&k| self.on(state, k)) {
            if !order[..m].contains(&k) {
                cost += rows * rows;
                rows += 1;
            }
        }
        cost > rows * rows * rows / 3
    }

    /// The update for the right-hand side `rhs` (all rows): the inactive rows'
    /// `-lambda_k`, the active rows' solve with their right-hand side corrected by
    /// `A_jk lambda_k`.
    pub fn solve(
        &self,
        state: &[usize],
        (order, m): (&[usize], usize),
        jac: &[T],
        mult: &[T],
        rhs: &mut [T],
    ) {
        let nb = self.bonds.len();
        for k in self.from..nb {
            if self.on(state, k) {
                continue;
            }
            let l = mult[k];
            if l != T::ZERO {
                for &j in &order[..m] {
                    rhs[j] += self.entry(j, k) * l;
                }
            }
            rhs[k] = -l;
        }
        ordered_solve(jac, nb, m, order, rhs);
    }
}
