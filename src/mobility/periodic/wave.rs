//! The wave-space half of the Ewald split: the lattice sum over `k != 0`, `|k| <= k_max`,
//! of `(I - k k / k^2) h(k) cos(k . r) / (eta V)` with
//! `h = (1 + k^2/(4 xi^2)) exp(-k^2/(4 xi^2)) / k^2 (1 - k^2 a_i^2/6)(1 - k^2 a_j^2/6)`
//! (`docs/PERIODIC.md`, eq. K). The terms of `k` and `-k` are equal, so only the half
//! space `n_x > 0`, or `n_x = 0, n_y > 0`, or `n_x = n_y = 0, n_z > 0` is visited, twice
//! weighted, in a fixed order.

use super::{Ewald, MAX_INDEX};
use crate::real::Real;

/// The wave vector of index `n`, `1/k^2`, and the radius-free factor
/// `(1 + k^2/(4 xi^2)) exp(-k^2/(4 xi^2)) / k^2`.
#[inline(always)]
pub(super) fn mode<T: Real>(ew: &Ewald<T>, n: [i32; 3]) -> (T::V3, T, T, T) {
    let [nx, ny, nz] = n;
    let [kx, ky, kz] = ew.dk;
    let k = T::v3(
        T::from_f64(nx as f64) * kx,
        T::from_f64(ny as f64) * ky,
        T::from_f64(nz as f64) * kz,
    );
    let k2 = T::norm2(k);
    let inv_k2 = T::ONE / k2;
    let g = ew.gauss[0][nx.unsigned_abs() as usize]
        * ew.gauss[1][ny.unsigned_abs() as usize]
        * ew.gauss[2][nz.unsigned_abs() as usize];
    (k, k2, inv_k2, (T::ONE + k2 * ew.inv_4xi2) * g * inv_k2)
}

/// Visits the half space of wave vectors within `k_max` in a fixed order (`n_x`
/// ascending from 0, then `n_y`, then `n_z`, each ascending), the `n_z` range cut to the
/// sphere `|k| <= k_max` for each `(n_x, n_y)` so that no index outside it is visited.
#[inline(always)]
pub(super) fn for_each_mode<T: Real>(ew: &Ewald<T>, mut f: impl FnMut([i32; 3])) {
    let [mx, my, mz] = ew.waves.map(|m| m as i32);
    let [kx, ky, kz] = ew.dk;
    let km2 = ew.k_max * ew.k_max;
    for nx in 0..=mx {
        let ax = T::from_f64(nx as f64) * kx;
        let lo_y = if nx == 0 { 0 } else { -my };
        for ny in lo_y..=my {
            let ay = T::from_f64(ny as f64) * ky;
            let rest = km2 - ax * ax - ay * ay;
            if !(rest >= T::ZERO) {
                continue;
            }
            // floor(sqrt(rest) / dk_z), clamped to the precomputed bound.
            let top = libm::floor((rest.sqrt() / kz).to_f64()).min(mz as f64) as i32;
            let lo_z = if nx == 0 && ny == 0 { 1 } else { -top };
            for nz in lo_z..=top {
                f([nx, ny, nz]);
            }
        }
    }
}

/// `1 - k^2 a^2 / 6`: the sphere's factor of the wave-space kernel.
#[inline(always)]
pub(super) fn radius_factor<T: Real>(k2: T, a: T) -> T {
    T::ONE - k2 * a * a / T::from_f64(6.0)
}

/// Calls `f(k, k^2, 1/k^2, h, cos(k . r0), sin(k . r0))` for every mode of
/// [`for_each_mode`] (`h` the radius-free factor of [`mode`]). The phases come from the
/// axis phases `exp(i n_d k_d r_d)`, raised to the `n`-th power by repeated
/// multiplication (exact to a few ulp for the `n <= MAX_INDEX` used).
#[inline(always)]
pub(super) fn for_each_phase<T: Real>(
    ew: &Ewald<T>,
    r0: T::V3,
    mut f: impl FnMut(T::V3, T, T, T, T, T),
) {
    let r = T::xyz(r0);
    let mut pw = [[(T::ONE, T::ZERO); MAX_INDEX + 1]; 3];
    for d in 0..3 {
        let t = ew.dk[d] * r[d];
        let (c, s) = (t.cos(), t.sin());
        for n in 1..=ew.waves[d] {
            let (pc, ps) = pw[d][n - 1];
            pw[d][n] = (pc * c - ps * s, pc * s + ps * c);
        }
    }
    // exp(i n t) for a signed index: the conjugate for n < 0.
    let phase = |d: usize, n: i32| {
        let (c, s) = pw[d][n.unsigned_abs() as usize];
        if n < 0 { (c, -s) } else { (c, s) }
    };
    for_each_mode(ew, |[nx, ny, nz]| {
        let (k, k2, inv_k2, base) = mode(ew, [nx, ny, nz]);
        let (c1, s1) = phase(0, nx);
        let (c2, s2) = phase(1, ny);
        let (c3, s3) = phase(2, nz);
        let (c12, s12) = (c1 * c2 - s1 * s2, c1 * s2 + s1 * c2);
        f(
            k,
            k2,
            inv_k2,
            base,
            c12 * c3 - s12 * s3,
            c12 * s3 + s12 * c3,
        );
    });
}

/// `sum c k k^T` as the six entries `xx, xy, xz, yy, yz, zz` added to `kk`.
#[inline(always)]
pub(super) fn add_kk<T: Real>(kk: &mut [T; 6], k: T::V3, c: T) {
    let [x, y, z] = T::xyz(k);
    let (gx, gy) = (c * x, c * y);
    kk[0] += gx * x;
    kk[1] += gx * y;
    kk[2] += gx * z;
    kk[3] += gy * y;
    kk[4] += gy * z;
    kk[5] += c * z * z;
}

/// `w (d I - kk)`, `kk` as [`add_kk`] sums it: the symmetric block of a projected sum.
#[inline(always)]
pub(super) fn projected<T: Real>(d: T, kk: [T; 6], w: T) -> T::M3 {
    let [xx, xy, xz, yy, yz, zz] = kk.map(|v| -(v * w));
    let d = d * w;
    T::m3_cols(
        T::v3(xx + d, xy, xz),
        T::v3(xy, yy + d, yz),
        T::v3(xz, yz, zz + d),
    )
}

/// The wave-space block for radii `a_i`, `a_j` at separation `r0` (minimum image).
pub(super) fn wave_sum<T: Real>(ew: &Ewald<T>, eta: T, ai: T, aj: T, r0: T::V3) -> T::M3 {
    let (mut diag, mut kk) = (T::ZERO, [T::ZERO; 6]);
    for_each_phase(ew, r0, |k, k2, inv_k2, base, cos, _| {
        let f = base * radius_factor(k2, ai) * radius_factor(k2, aj) * cos;
        diag += f;
        add_kk(&mut kk, k, f * inv_k2);
    });
    projected(diag, kk, T::TWO / (eta * ew.volume))
}

/// `y += M_wave x` for all spheres through structure factors: for each wave vector,
/// `C = sum_j (1 - k^2 a_j^2/6) cos(k . r_j) x_j` and the same with `sin`, projected
/// across `k`, then `y_i += 2 h (1 - k^2 a_i^2/6) (cos(k . r_i) P C + sin(k . r_i) P S)
/// / (eta V)`: `O(N K)` instead of `O(N^2 K)`. `pos` are wrapped into the box.
pub(super) fn wave_product<T: Real>(
    ew: &Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    x: &[T::V3],
    y: &mut [T::V3],
) {
    let w = T::TWO / (eta * ew.volume);
    for_each_mode(ew, |n| {
        let (k, k2, inv_k2, base) = mode(ew, n);
        let (mut c, mut s) = (T::V3_ZERO, T::V3_ZERO);
        for j in 0..pos.len() {
            let t = T::dot(k, ew.cell.wrap_into(pos[j]));
            let f = radius_factor(k2, radius[j]);
            c += x[j] * (f * t.cos());
            s += x[j] * (f * t.sin());
        }
        // Project across k: P v = v - k (k . v) / k^2.
        let c = c - k * (T::dot(k, c) * inv_k2);
        let s = s - k * (T::dot(k, s) * inv_k2);
        let h = base * w;
        for i in 0..pos.len() {
            let t = T::dot(k, ew.cell.wrap_into(pos[i]));
            let f = h * radius_factor(k2, radius[i]);
            y[i] += (c * t.cos() + s * t.sin()) * f;
        }
    });
}
