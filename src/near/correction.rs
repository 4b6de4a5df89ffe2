//! The near-field correction of one pair for Stokesian dynamics:
//! `R_near = R_2B,exact - R_2B,far`, where `R_2B,far` is the inverse of the pair's
//! far-field (RPY) 12x12 grand mobility. Summed over close pairs and added to the inverse
//! of the N-body far-field mobility it gives the Stokesian dynamics resistance
//! `R = M_far^-1 + R_near` (Durlofsky, Brady and Bossis 1987), which counts each pair's
//! two-body interactions once.
//!
//! The far-field mobility is the caller's (the kernel's RPY blocks, `crate::mobility`):
//! this module stays below the mobility in the kernel's layers and takes it as input.

use super::NearError;
use super::pair::{M, resistance_f64, to_m3};
use crate::linalg::spd_inverse;
use crate::real::Real;

/// 12x12 in `f64`, rows and columns `(U1, U2, W1, W2)`.
type Big = [[f64; 12]; 12];

fn flatten(b: &[[M; 4]; 4]) -> Big {
    let mut m = [[0.0; 12]; 12];
    for (bi, row) in b.iter().enumerate() {
        for (bj, blk) in row.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    m[3 * bi + i][3 * bj + j] = blk[i][j];
                }
            }
        }
    }
    m
}

/// `R_near` of spheres of radii `a1`, `a2`, sphere 2 at `d` from sphere 1, given the
/// pair's far-field grand mobility `far` (3x3 blocks, rows `(U1, U2, W1, W2)`, columns
/// `(F1, F2, T1, T2)`). Blocks ordered as [`super::PairResistance`].
pub fn near_correction<T: Real>(
    eta: T,
    a1: T,
    a2: T,
    d: T::V3,
    far: &[[T::M3; 4]; 4],
) -> Result<[[T::M3; 4]; 4], NearError> {
    let exact = flatten(&resistance_f64(
        eta.to_f64(),
        a1.to_f64(),
        a2.to_f64(),
        T::xyz(d).map(T::to_f64),
    )?);
    let far: [[M; 4]; 4] = far.map(|row| {
        row.map(|b| {
            let e = T::m3_entries(&b);
            core::array::from_fn(|i| core::array::from_fn(|j| e[j * 3 + i].to_f64()))
        })
    });
    // The pair's RPY grand mobility is symmetric positive definite (also overlapping).
    let mut far_r = flatten(&far);
    spd_inverse(far_r.as_flattened_mut(), 12).map_err(|_| NearError::Singular)?;
    let mut out = [[[[0.0; 3]; 3]; 4]; 4];
    for (bi, row) in out.iter_mut().enumerate() {
        for (bj, blk) in row.iter_mut().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    let (r, c) = (3 * bi + i, 3 * bj + j);
                    let v = exact[r][c] - far_r[r][c];
                    if !v.is_finite() {
                        return Err(NearError::Singular);
                    }
                    blk[i][j] = v;
                }
            }
        }
    }
    Ok(out.map(|row| row.map(to_m3::<T>)))
}
