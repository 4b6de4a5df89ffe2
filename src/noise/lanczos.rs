//! The Krylov (Lanczos) square root of the mobility (Fixman 1986; Ando, Chow, Saad and
//! Skolnick 2012, J. Chem. Phys. 137, 064106): `y ~= M^(1/2) z` from products `M v`
//! only.
//!
//! Lanczos started at `v_1 = z / |z|` builds an orthonormal basis `V_m` of the Krylov
//! space of `M` and `z` and the tridiagonal `T_m = V_m^T M V_m`; then
//! `y_m = |z| V_m T_m^(1/2) e_1`, with `T_m^(1/2)` from the eigen-decomposition of the
//! small tridiagonal `T_m` (implicit QL, fixed order). The basis is reorthogonalised in full
//! against every earlier vector (it is stored anyway), so the error is Lanczos's, not
//! round-off's. The iteration stops when the estimated relative error of `y_m` is
//! below half the tolerance (a safety factor: the error falls irregularly): the change `|y_m - y_(m-1)| / |y_m|` (read off the
//! coefficients, `V_m` being orthonormal) times `max(1, rho / (1 - rho))`, `rho` the
//! ratio of successive changes (capped at 0.9), or when the Krylov space is exhausted
//! (`beta_(m+1)` at round-off: `y_m` is then exact). The same run optionally gives
//! `M^(-1/2) z` (the Fixman midpoint's `L^-T xi`), converged to the same tolerance.
//!
//! Storage: `(cap + 1) n` vectors for the basis and one product, and
//! [`scalars`]`(cap)` scalars for `T_m`, its eigenvectors and the coefficients. A
//! step's products read a large stored mobility through its reduced copy
//! ([`super::reduced`], `f32` entries and sums): the noise is then `M~^(1/2) z`, each
//! product `M~ v` within about `1e-7` of `M v`.

use crate::real::Real;
use core::fmt;

/// Settings of the Lanczos square root.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanczos<T> {
    /// Relative error of the noise at which the iteration stops, estimated from the
    /// change between successive iterations and the rate it falls at (the geometric
    /// tail of the remaining error; `tests/kernel/lanczos_chain.rs` checks the actual error
    /// against roots from a dense eigen-decomposition, below this tolerance). Default
    /// `1e-3` (f64 and f32): the covariance of the noise is then right to about
    /// `1e-3`, below the statistical error of any run's averages, at about half the
    /// iterations `1e-6` takes (14 against 25 on a 1024-bead RPY chain).
    pub tolerance: T,
    /// Most iterations (Krylov dimension; storage grows with it: `(cap + 1) n`
    /// vectors). A step needing more is refused. Default 64.
    pub max_iterations: u32,
}

impl<T: Real> Default for Lanczos<T> {
    fn default() -> Self {
        Self {
            tolerance: T::from_f64(1e-3),
            max_iterations: 64,
        }
    }
}

/// Why a Lanczos square root failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LanczosError {
    /// The estimated error was still above the tolerance after `iterations`.
    NoConvergence {
        /// Iterations done (the cap).
        iterations: u32,
        /// Estimated relative error at the last iteration.
        change: f64,
    },
    /// `T_m` has an eigenvalue that is not positive: the mobility is not positive
    /// definite (or `z` is zero or not finite).
    NotPositiveDefinite {
        /// The iteration.
        iterations: u32,
    },
    /// The storage given is smaller than `cap` needs.
    Storage,
}

impl fmt::Display for LanczosError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NoConvergence { iterations, change } => write!(
                f,
                "Lanczos square root not converged after {iterations} iterations (error {change:.3e})"
            ),
            Self::NotPositiveDefinite { iterations } => write!(
                f,
                "Lanczos square root: mobility not positive definite (iteration {iterations})"
            ),
            Self::Storage => write!(f, "Lanczos square root: storage too small"),
        }
    }
}

/// Scalars the Lanczos square root needs for `cap` iterations.
pub const fn scalars(cap: usize) -> usize {
    2 * cap * cap + 8 * cap + 1
}

/// Vectors (3-vectors) the basis of `cap` iterations takes for `n` beads.
pub const fn vectors(cap: usize, n: usize) -> usize {
    (cap + 1) * n
}

/// `out = M^(1/2) z` (and, with `inv`, `inv = M^(-1/2) z`) to the relative tolerance
/// of `s`, with `product(v, w)` computing `w = M v`. `basis` holds at least
/// [`vectors`]`(cap, n)` vectors and `work` [`scalars`]`(cap)` scalars. Returns the
/// iterations done. `out` and `inv` are written only on success.
pub fn sqrt<T: Real, P: FnMut(&[T::V3], &mut [T::V3])>(
    s: Lanczos<T>,
    mut product: P,
    z: &[T::V3],
    basis: &mut [T::V3],
    work: &mut [T],
    out: &mut [T::V3],
    mut inv: Option<&mut [T::V3]>,
) -> Result<u32, LanczosError> {
    let n = z.len();
    let cap = s.max_iterations as usize;
    if cap == 0 || basis.len() < vectors(cap, n) || work.len() < scalars(cap) {
        return Err(LanczosError::Storage);
    }
    let (alpha, rest) = work.split_at_mut(cap);
    let (beta, rest) = rest.split_at_mut(cap + 1);
    let (tm, rest) = rest.split_at_mut(cap * cap);
    let (q, rest) = rest.split_at_mut(cap * cap);
    let (c, rest) = rest.split_at_mut(cap);
    let (c_old, rest) = rest.split_at_mut(cap);
    let (d, rest) = rest.split_at_mut(cap);
    let d_old = &mut rest[..cap];
    let want_inv = inv.is_some();
    let norm = dot::<T>(z, z).sqrt();
    if !(norm > T::ZERO && norm.is_finite()) {
        return Err(LanczosError::NotPositiveDefinite { iterations: 0 });
    }
    for (v, &x) in basis[..n].iter_mut().zip(z) {
        *v = x / norm;
    }
    c_old.fill(T::ZERO);
    d_old.fill(T::ZERO);
    let mut change = f64::INFINITY;
    let mut last = [f64::INFINITY; 2];
    for m in 1..=cap {
        let j = m - 1;
        // w = M v_j - beta_j v_(j-1), alpha_j = v_j . w, w -= alpha_j v_j.
        let (done, next) = basis.split_at_mut(m * n);
        let w = &mut next[..n];
        let vj = &done[j * n..];
        product(vj, w);
        let a = dot::<T>(vj, w);
        alpha[j] = a;
        // Full reorthogonalisation (twice is enough), fixed order.
        for _ in 0..2 {
            for k in 0..m {
                let vk = &done[k * n..(k + 1) * n];
                let h = dot::<T>(vk, w);
                for (x, &v) in w.iter_mut().zip(vk) {
                    *x -= v * h;
                }
            }
        }
        let b = dot::<T>(w, w).sqrt();
        beta[m] = b;
        // Eigen-decomposition of the tridiagonal T_m (diagonal into `tm[..m]`,
        // off-diagonal into `tm[m..2m]`), then c = T^(1/2) e_1 and d = T^(-1/2) e_1.
        // (`T_1` is its own decomposition; from m = 2 on `2 m <= cap^2`.)
        let solved = if m == 1 {
            tm[0] = alpha[0];
            q[0] = T::ONE;
            true
        } else {
            let (diag, off) = tm[..2 * m].split_at_mut(m);
            diag.copy_from_slice(&alpha[..m]);
            off[..m - 1].copy_from_slice(&beta[1..m]);
            tridiagonal_eigen(diag, off, &mut q[..m * m], m)
        };
        if !solved {
            return Err(LanczosError::NoConvergence {
                iterations: m as u32,
                change,
            });
        }
        for r in 0..m {
            c[r] = T::ZERO;
            d[r] = T::ZERO;
        }
        for k in 0..m {
            let lam = tm[k];
            if !(lam > T::ZERO) {
                return Err(LanczosError::NotPositiveDefinite {
                    iterations: m as u32,
                });
            }
            let root = lam.sqrt();
            let w0 = q[k];
            for r in 0..m {
                c[r] += q[r * m + k] * w0 * root;
                d[r] += q[r * m + k] * w0 / root;
            }
        }
        // The error of y_m from the change since m - 1 and the rate it falls at.
        let (root, inverse) = (
            rel_change(&c[..m], &c_old[..m]),
            rel_change(&d[..m], &d_old[..m]),
        );
        let now = [root, if want_inv { inverse } else { 0.0 }];
        change = estimate(now[0], last[0]).max(estimate(now[1], last[1]));
        last = now;
        let exhausted = b.to_f64() <= T::EPSILON.to_f64() * 64.0 * a.abs().to_f64();
        // A safety factor of two on the estimate: the error falls irregularly.
        if (m > 1 && change < 0.5 * s.tolerance.to_f64()) || exhausted {
            combine(&basis[..m * n], &c[..m], norm, out);
            if let Some(y) = inv.as_deref_mut() {
                combine(&basis[..m * n], &d[..m], norm, y);
            }
            return Ok(m as u32);
        }
        c_old[..m].copy_from_slice(&c[..m]);
        d_old[..m].copy_from_slice(&d[..m]);
        if m < cap {
            let inv_b = T::ONE / b;
            for x in basis[m * n..(m + 1) * n].iter_mut() {
                *x *= inv_b;
            }
        }
    }
    Err(LanczosError::NoConvergence {
        iterations: cap as u32,
        change,
    })
}

/// `sum_i a_i . b_i`, in index order.
fn dot<T: Real>(a: &[T::V3], b: &[T::V3]) -> T {
    a.iter()
        .zip(b)
        .fold(T::ZERO, |s, (&x, &y)| s + T::dot(x, y))
}

/// The relative error of the latest iterate, extrapolated from its change `now` since
/// the one before and the change `last` before that: with a contraction `rho = now /
/// last` per iteration the remaining error is `now rho / (1 - rho)` (the geometric
/// tail), taken no smaller than `now` (convergence is not regular enough to trust a
/// fast rate: on a 10-bead cluster it once stopped at an error 1.8 times the
/// tolerance), with `rho` capped at 0.9 so a plateau never stops the iteration early.
fn estimate(now: f64, last: f64) -> f64 {
    if !(last > 0.0 && last.is_finite()) {
        return now;
    }
    let rho = (now / last).min(0.9);
    now * (rho / (1.0 - rho)).max(1.0)
}

/// `|c - c_old| / |c|` (`c_old` zero-padded: its last entry is the new one's slot).
fn rel_change<T: Real>(c: &[T], c_old: &[T]) -> f64 {
    let (mut diff, mut size) = (0.0, 0.0);
    for (&a, &b) in c.iter().zip(c_old) {
        let (a, b) = (a.to_f64(), b.to_f64());
        diff += (a - b) * (a - b);
        size += a * a;
    }
    libm::sqrt(diff / size)
}

/// `out = norm sum_k coef_k v_k`.
fn combine<T: Real>(basis: &[T::V3], coef: &[T], norm: T, out: &mut [T::V3]) {
    let n = out.len();
    out.fill(T::V3_ZERO);
    for (k, &ck) in coef.iter().enumerate() {
        let a = ck * norm;
        for (o, &v) in out.iter_mut().zip(&basis[k * n..(k + 1) * n]) {
            *o += v * a;
        }
    }
}

/// Eigen-decomposition of the symmetric tridiagonal `m x m` matrix with diagonal `d` and
/// off-diagonal `e` (`e[k]` couples `k` and `k + 1`; `e[m - 1]` is ignored) by the
/// implicit QL iteration with Wilkinson shifts: on return `d` holds the eigenvalues and
/// the columns of `q` (row-major) the eigenvectors; `e` is destroyed. `O(m^2)` work
/// for the eigenvalues and `O(m^3)` with a small constant for the vectors (a cyclic
/// Jacobi on the dense `T_m`, used before, cost about ten times more: at `N = 256` it
/// outweighed the mobility products). Fixed order; `false` if an eigenvalue needs more
/// than 60 iterations (not seen: the iteration converges cubically).
fn tridiagonal_eigen<T: Real>(d: &mut [T], e: &mut [T], q: &mut [T], m: usize) -> bool {
    for r in 0..m {
        for k in 0..m {
            q[r * m + k] = if r == k { T::ONE } else { T::ZERO };
        }
    }
    e[m - 1] = T::ZERO;
    for l in 0..m {
        let mut iterations = 0;
        loop {
            // The first negligible off-diagonal element at or after l.
            let mut j = l;
            while j + 1 < m {
                let dd = d[j].abs() + d[j + 1].abs();
                if e[j].abs() <= T::EPSILON * dd {
                    break;
                }
                j += 1;
            }
            if j == l {
                break;
            }
            iterations += 1;
            if iterations > 60 {
                return false;
            }
            // Wilkinson shift from the leading 2 x 2 block, then QL sweeps j-1 .. l.
            let mut g = (d[l + 1] - d[l]) / (T::TWO * e[l]);
            let mut r = (g * g + T::ONE).sqrt();
            let signed = if g >= T::ZERO { r } else { -r };
            g = d[j] - d[l] + e[l] / (g + signed);
            let (mut s, mut c, mut p) = (T::ONE, T::ONE, T::ZERO);
            let mut deflated = false;
            for i in (l..j).rev() {
                let f = s * e[i];
                let b = c * e[i];
                r = (f * f + g * g).sqrt();
                e[i + 1] = r;
                if r == T::ZERO {
                    d[i + 1] -= p;
                    e[j] = T::ZERO;
                    deflated = true;
                    break;
                }
                s = f / r;
                c = g / r;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + T::TWO * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
                for k in 0..m {
                    let (a, h) = (q[k * m + i], q[k * m + i + 1]);
                    q[k * m + i + 1] = s * a + c * h;
                    q[k * m + i] = c * a - s * h;
                }
            }
            if deflated {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[j] = T::ZERO;
        }
    }
    true
}
