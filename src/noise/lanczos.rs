//! The Krylov (Lanczos) square root of the mobility (Fixman 1986; Ando, Chow, Saad and
//! Skolnick 2012, J. Chem. Phys. 137, 064106): `y ~= M^(1/2) z` from products `M v`
//! only.
//!
//! Lanczos started at `v_1 = z / |z|` builds an orthonormal basis `V_m` of the Krylov
//! space of `M` and `z` and the tridiagonal `T_m = V_m^T M V_m`; then
//! `y_m = |z| V_m T_m^(1/2) e_1`, with `T_m^(1/2)` from the eigen-decomposition of the
//! small `T_m` (cyclic Jacobi, fixed order). The basis is reorthogonalised in full
//! against every earlier vector (it is stored anyway), so the error is Lanczos's, not
//! round-off's. The iteration stops when the relative change of `y` from `m - 1` to
//! `m`, `|y_m - y_(m-1)| / |y_m|` (read off the coefficients, `V_m` being
//! orthonormal), is below the tolerance, or when the Krylov space is exhausted
//! (`beta_(m+1)` at round-off: `y_m` is then exact). The same run optionally gives
//! `M^(-1/2) z` (the Fixman midpoint's `L^-T xi`), converged to the same tolerance.
//!
//! Storage: `(cap + 1) n` vectors for the basis and one product, and
//! [`scalars`]`(cap)` scalars for `T_m`, its eigenvectors and the coefficients.

use crate::real::Real;
use core::fmt;

/// Settings of the Lanczos square root.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanczos<T> {
    /// Relative change of the noise between successive iterations at which the
    /// iteration stops. Default `1e-6` (f64) / `1e-4` (f32).
    pub tolerance: T,
    /// Most iterations (Krylov dimension; storage grows with it: `(cap + 1) n`
    /// vectors). A step needing more is refused. Default 64.
    pub max_iterations: u32,
}

impl<T: Real> Default for Lanczos<T> {
    fn default() -> Self {
        let tolerance = if T::EPSILON.to_f64() < 1e-10 {
            1e-6
        } else {
            1e-4
        };
        Self {
            tolerance: T::from_f64(tolerance),
            max_iterations: 64,
        }
    }
}

/// Why a Lanczos square root failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LanczosError {
    /// The relative change was still above the tolerance after `iterations`.
    NoConvergence {
        /// Iterations done (the cap).
        iterations: u32,
        /// Relative change at the last iteration.
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
                "Lanczos square root not converged after {iterations} iterations (change {change:.3e})"
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
        // Eigen-decomposition of T_m, then c = T^(1/2) e_1 and d = T^(-1/2) e_1.
        for r in 0..m {
            for k in 0..m {
                tm[r * m + k] = if r == k {
                    alpha[r]
                } else if k == r + 1 || r == k + 1 {
                    beta[r.max(k)]
                } else {
                    T::ZERO
                };
            }
        }
        jacobi(&mut tm[..m * m], &mut q[..m * m], m);
        for r in 0..m {
            c[r] = T::ZERO;
            d[r] = T::ZERO;
        }
        for k in 0..m {
            let lam = tm[k * m + k];
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
        change = rel_change(&c[..m], &c_old[..m]);
        if want_inv {
            change = change.max(rel_change(&d[..m], &d_old[..m]));
        }
        let exhausted = b.to_f64() <= T::EPSILON.to_f64() * 64.0 * a.abs().to_f64();
        if (m > 1 && change < s.tolerance.to_f64()) || exhausted {
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

/// Cyclic Jacobi on the symmetric `m x m` matrix `a` (row-major): on return its
/// diagonal holds the eigenvalues and the columns of `q` the eigenvectors. Rotations
/// in fixed row-by-row order until the off-diagonal part is at round-off (at most
/// 50 sweeps).
fn jacobi<T: Real>(a: &mut [T], q: &mut [T], m: usize) {
    for r in 0..m {
        for k in 0..m {
            q[r * m + k] = if r == k { T::ONE } else { T::ZERO };
        }
    }
    for _ in 0..50 {
        let (mut off, mut diag) = (T::ZERO, T::ZERO);
        for r in 0..m {
            diag += a[r * m + r] * a[r * m + r];
            for k in r + 1..m {
                off += a[r * m + k] * a[r * m + k];
            }
        }
        if off <= diag * T::EPSILON * T::EPSILON {
            return;
        }
        for p in 0..m {
            for r in p + 1..m {
                let apr = a[p * m + r];
                if apr == T::ZERO {
                    continue;
                }
                // Rotation zeroing a[p][r] (Rutishauser's stable form).
                let theta = (a[r * m + r] - a[p * m + p]) / (T::TWO * apr);
                let sign = if theta >= T::ZERO { T::ONE } else { -T::ONE };
                let t = sign / (theta.abs() + (theta * theta + T::ONE).sqrt());
                let cs = T::ONE / (t * t + T::ONE).sqrt();
                let sn = t * cs;
                for k in 0..m {
                    let (akp, akr) = (a[k * m + p], a[k * m + r]);
                    a[k * m + p] = cs * akp - sn * akr;
                    a[k * m + r] = sn * akp + cs * akr;
                }
                for k in 0..m {
                    let (apk, ark) = (a[p * m + k], a[r * m + k]);
                    a[p * m + k] = cs * apk - sn * ark;
                    a[r * m + k] = sn * apk + cs * ark;
                }
                for k in 0..m {
                    let (qkp, qkr) = (q[k * m + p], q[k * m + r]);
                    q[k * m + p] = cs * qkp - sn * qkr;
                    q[k * m + r] = sn * qkp + cs * qkr;
                }
            }
        }
    }
}
