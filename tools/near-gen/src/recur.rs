//! Jeffrey and Onishi's (1984) twin-multipole recurrences.
//!
//! The coefficients `P_npq`, `V_npq`, `Q_npq` do not depend on the size ratio: the
//! far-field series of a resistance function is `f_k(lambda) = 2^k sum_q c_q lambda^q`
//! with `c_q` read off these arrays (`n = 1`, `p = k - q`). They are computed level by
//! level in `p + q`: every term of the recurrences refers to a lower level.

/// One family's arrays, indexed `[n][p][q]` for `n <= K + 1`, `p, q <= K`.
pub struct Arrays {
    k: usize,
    binom: Vec<Vec<f64>>,
    p: Vec<f64>,
    v: Vec<f64>,
    q: Vec<f64>,
}

/// Which recurrence and which start.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Family {
    /// Axisymmetric translation (`X^A`): `P_n00 = V_n00 = delta_n1`.
    Xa,
    /// Transverse translation (`Y^A`, and `Y^B` from `Q`): `P_n00 = V_n00 = delta_n1`.
    Ya,
    /// Transverse rotation (`Y^C`): `Q_n00 = delta_n1`.
    Yc,
}

/// Pascal's triangle up to row `rows - 1`, `[n][k]`.
fn pascal(rows: usize) -> Vec<Vec<f64>> {
    let mut t: Vec<Vec<f64>> = Vec::with_capacity(rows);
    for n in 0..rows {
        let mut row = vec![1.0; n + 1];
        for k in 1..n {
            row[k] = t[n - 1][k - 1] + t[n - 1][k];
        }
        t.push(row);
    }
    t
}

impl Arrays {
    fn at(&self, a: &[f64], n: i64, p: i64, q: i64) -> f64 {
        let k = self.k as i64;
        if n < 1 || p < 0 || q < 0 {
            return 0.0;
        }
        assert!(
            n <= k + 1 && p <= k && q <= k,
            "index beyond the computed range"
        );
        a[((n as usize) * (self.k + 1) + p as usize) * (self.k + 1) + q as usize]
    }
    fn idx(&self, n: usize, p: usize, q: usize) -> usize {
        (n * (self.k + 1) + p) * (self.k + 1) + q
    }
    /// `P_npq`.
    pub fn p(&self, n: i64, p: i64, q: i64) -> f64 {
        self.at(&self.p, n, p, q)
    }
    /// `Q_npq`.
    pub fn q(&self, n: i64, p: i64, q: i64) -> f64 {
        self.at(&self.q, n, p, q)
    }
    fn v(&self, n: i64, p: i64, q: i64) -> f64 {
        self.at(&self.v, n, p, q)
    }

    /// The arrays of `family` up to level `p + q <= k`.
    pub fn new(family: Family, k: usize) -> Self {
        let size = (k + 2) * (k + 1) * (k + 1);
        let mut a = Arrays {
            k,
            binom: pascal(2 * k + 4),
            p: vec![0.0; size],
            v: vec![0.0; size],
            q: vec![0.0; size],
        };
        let start = a.idx(1, 0, 0);
        match family {
            Family::Xa | Family::Ya => {
                a.p[start] = 1.0;
                a.v[start] = 1.0;
            }
            Family::Yc => a.q[start] = 1.0,
        }
        for level in 1..=k {
            for p in 0..=level {
                let q = level - p;
                // An entry (n, level) feeds the root (1, k) only when n + level <= k + 1.
                for n in 1..=k + 1 - level {
                    let (pv, qv) = match family {
                        Family::Xa => (a.xa_p(n, p, q), 0.0),
                        Family::Ya | Family::Yc => (a.ya_p(n, p, q), a.ya_q(n, p, q)),
                    };
                    let i = a.idx(n, p, q);
                    a.p[i] = pv;
                    a.q[i] = qv;
                    let vv = match family {
                        Family::Xa => a.xa_v(n, p, q),
                        Family::Ya | Family::Yc => a.ya_v(n, p, q),
                    };
                    a.v[i] = vv;
                }
            }
        }
        a
    }

    fn xa_p(&self, n: usize, p: usize, q: usize) -> f64 {
        let (nf, ni, pi) = (n as f64, n as i64, p as i64);
        let mut sum = 0.0;
        for s in 1..=q {
            let (sf, si) = (s as f64, s as i64);
            let rest = q as i64 - si;
            let c = self.binom[n + s][n];
            let t1 = nf * (2.0 * nf + 1.0) * (2.0 * nf * sf - nf - sf + 2.0)
                / (2.0 * (nf + 1.0) * (2.0 * sf - 1.0) * (nf + sf))
                * self.p(si, rest, pi - ni + 1);
            let t2 = nf * (2.0 * nf - 1.0) / (2.0 * (nf + 1.0)) * self.p(si, rest, pi - ni - 1);
            let t3 = nf * (4.0 * nf * nf - 1.0) / (2.0 * (nf + 1.0) * (2.0 * sf + 1.0))
                * self.v(si, rest - 2, pi - ni + 1);
            sum += c * (t1 - t2 - t3);
        }
        sum
    }

    fn xa_v(&self, n: usize, p: usize, q: usize) -> f64 {
        let (nf, ni, pi) = (n as f64, n as i64, p as i64);
        let mut sum = 0.0;
        for s in 1..=q {
            sum += self.binom[n + s][n] * self.p(s as i64, (q - s) as i64, pi - ni - 1);
        }
        self.p(ni, pi, q as i64) - 2.0 * nf / ((nf + 1.0) * (2.0 * nf + 3.0)) * sum
    }

    fn ya_p(&self, n: usize, p: usize, q: usize) -> f64 {
        let (nf, ni, pi) = (n as f64, n as i64, p as i64);
        let mut sum = 0.0;
        for s in 1..=q {
            let (sf, si) = (s as f64, s as i64);
            let rest = q as i64 - si;
            let c = self.binom[n + s][n + 1];
            let t1 = (2.0 * nf + 1.0) / (2.0 * (nf + 1.0))
                * (3.0 * (nf + sf) - (nf * sf + 1.0) * (2.0 * nf * sf - sf - nf + 2.0))
                / (sf * (nf + sf) * (2.0 * sf - 1.0))
                * self.p(si, rest, pi - ni + 1);
            let t2 = nf * (2.0 * nf - 1.0) / (2.0 * (nf + 1.0)) * self.p(si, rest, pi - ni - 1);
            let t3 = nf * (4.0 * nf * nf - 1.0) / (2.0 * (nf + 1.0) * (2.0 * sf + 1.0))
                * self.v(si, rest - 2, pi - ni + 1);
            let t4 = 2.0 * (4.0 * nf * nf - 1.0) / (3.0 * (nf + 1.0))
                * self.q(si, rest - 1, pi - ni + 1);
            sum += c * (t1 + t2 + t3 - t4);
        }
        sum
    }

    fn ya_q(&self, n: usize, p: usize, q: usize) -> f64 {
        let (nf, ni, pi) = (n as f64, n as i64, p as i64);
        let mut sum = 0.0;
        for s in 1..=q {
            let (sf, si) = (s as f64, s as i64);
            let rest = q as i64 - si;
            let c = self.binom[n + s][n + 1];
            sum += c
                * (sf / (nf + 1.0) * self.q(si, rest - 1, pi - ni)
                    - 3.0 / (2.0 * nf * sf * (nf + 1.0)) * self.p(si, rest, pi - ni));
        }
        sum
    }

    fn ya_v(&self, n: usize, p: usize, q: usize) -> f64 {
        let (nf, ni, pi) = (n as f64, n as i64, p as i64);
        let mut sum = 0.0;
        for s in 1..=q {
            sum += self.binom[n + s][n + 1] * self.p(s as i64, (q - s) as i64, pi - ni - 1);
        }
        self.p(ni, pi, q as i64) + 2.0 * nf / ((nf + 1.0) * (2.0 * nf + 3.0)) * sum
    }
}
