//! Observables that name what a settling chain does over time: rotation
//! about the vertical, poloidal circulation of a ring rolling over itself, vertical
//! runs of bonds and the order in which bonds turn vertical, extents and the
//! centre-of-mass settling speed.
//!
//! "Up" is minus gravity. Masses weight every average; all functions take slices and
//! return plain numbers, so a host records them at any cadence.

use crate::bonds::Bond;
use crate::real::Real;

/// Unit vector along "up" (minus gravity); `None` for zero or non-finite gravity.
fn up<T: Real>(gravity: T::V3) -> Option<T::V3> {
    let g = T::norm(gravity);
    (g > T::ZERO && g.is_finite()).then(|| -gravity / g)
}

/// Component of `v` perpendicular to the unit vector `n`.
fn perp<T: Real>(v: T::V3, n: T::V3) -> T::V3 {
    v - n * T::dot(v, n)
}

/// Mass-weighted means of positions and velocities, and the total mass.
fn means<T: Real>(pos: &[T::V3], vel: &[T::V3], mass: &[T]) -> (T::V3, T::V3, T) {
    let (mut r, mut v, mut m) = (T::V3_ZERO, T::V3_ZERO, T::ZERO);
    for ((&p, &u), &w) in pos.iter().zip(vel).zip(mass) {
        r += p * w;
        v += u * w;
        m += w;
    }
    if m > T::ZERO {
        (r / m, v / m, m)
    } else {
        (r, v, m)
    }
}

/// A least-squares rotation rate and how much of the motion it explains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotation<T> {
    /// Rate in radians per time unit (the sense is given by each function).
    pub rate: T,
    /// Fraction of the relative motion (mass-weighted kinetic energy) this rotation
    /// explains, in `[0, 1]`: 1 for a pure rotation of that kind, 0 when the beads move
    /// without a common sense of turning. Zero when nothing moves. Tracked over time,
    /// a steady state keeps both the rate and the coherence.
    pub coherence: T,
}

impl<T: Real> Rotation<T> {
    /// The least-squares rate `L / I` from an angular momentum `L` and moment `I`, and
    /// its share `(L^2 / I) / E` of the relative kinetic energy `E`; zero without a
    /// moment.
    fn fit(l: T, inertia: T, energy: T) -> Self {
        if !(inertia > T::ZERO) {
            return Self {
                rate: T::ZERO,
                coherence: T::ZERO,
            };
        }
        let rate = l / inertia;
        let coherence = if energy > T::ZERO {
            (rate * l / energy).min(T::ONE)
        } else {
            T::ZERO
        };
        Self { rate, coherence }
    }
}

/// Rotation about the vertical through the centre of mass: the rate `L_up / I_up`
/// (right-handed about "up") of the rigid rotation that best fits the horizontal
/// velocities relative to the centre of mass, and the share of the horizontal relative
/// motion it explains.
pub fn spin_about_vertical<T: Real>(
    pos: &[T::V3],
    vel: &[T::V3],
    mass: &[T],
    gravity: T::V3,
) -> Rotation<T> {
    let Some(n) = up::<T>(gravity) else {
        return Rotation::fit(T::ZERO, T::ZERO, T::ZERO);
    };
    let (c, vc, _) = means::<T>(pos, vel, mass);
    let (mut l, mut inertia, mut energy) = (T::ZERO, T::ZERO, T::ZERO);
    for ((&p, &u), &w) in pos.iter().zip(vel).zip(mass) {
        let (r, v) = (perp::<T>(p - c, n), perp::<T>(u - vc, n));
        l += w * T::dot(T::cross(r, v), n);
        inertia += w * T::norm2(r);
        energy += w * T::norm2(v);
    }
    Rotation::fit(l, inertia, energy)
}

/// Poloidal circulation: beads turning about the chain's own centreline, a ring
/// rolling over itself (a smoke ring's motion).
///
/// The centreline is the core circle of the bead cloud: centred on the centre of mass,
/// in the plane normal to the cloud's thinnest axis (the gyration tensor's smallest
/// principal axis), of the mass-weighted mean distance from that axis. Each bead at
/// `rho` from its nearest core point, moving at `v` relative to the centre of mass,
/// turns about the local core tangent `t` (toroidal direction, right-handed about the
/// normal) at `(rho x v) . t / |rho|^2`; the rate is the mass-weighted least-squares
/// fit, positive right-handed about `t`. Applies to closed chains and to folded ones
/// whose beads wind around a core.
pub fn poloidal_circulation<T: Real>(pos: &[T::V3], vel: &[T::V3], mass: &[T]) -> Rotation<T> {
    let (c, vc, m) = means::<T>(pos, vel, mass);
    if !(m > T::ZERO) || pos.len() < 3 {
        return Rotation::fit(T::ZERO, T::ZERO, T::ZERO);
    }
    let n = thinnest_axis::<T>(pos, mass, c);
    let mut radius = T::ZERO;
    for (&p, &w) in pos.iter().zip(mass) {
        radius += w * T::norm(perp::<T>(p - c, n));
    }
    radius /= m;
    let (mut l, mut inertia, mut energy) = (T::ZERO, T::ZERO, T::ZERO);
    for ((&p, &u), &w) in pos.iter().zip(vel).zip(mass) {
        let v = u - vc;
        energy += w * T::norm2(v);
        let q = perp::<T>(p - c, n);
        let ql = T::norm(q);
        if !(ql > T::ZERO) {
            continue; // on the axis: no toroidal direction
        }
        let t = T::cross(n, q) / ql;
        let rho = p - c - q * (radius / ql);
        l += w * T::dot(T::cross(rho, v), t);
        inertia += w * T::norm2(rho);
    }
    Rotation::fit(l, inertia, energy)
}

/// Unit eigenvector of the smallest eigenvalue of the gyration tensor
/// `S = sum m (r - c)(r - c)^T`: power iteration on `tr(S) I - S` (positive
/// semidefinite, same eigenvectors, order reversed), from its largest column so the
/// start is never orthogonal to the answer; 64 fixed iterations (deterministic).
fn thinnest_axis<T: Real>(pos: &[T::V3], mass: &[T], c: T::V3) -> T::V3 {
    let mut s = T::M3_ZERO;
    for (&p, &w) in pos.iter().zip(mass) {
        let d = p - c;
        s += T::outer(d, d) * w;
    }
    let trace = T::m3_get(s, 0, 0) + T::m3_get(s, 1, 1) + T::m3_get(s, 2, 2);
    let a = T::m3_diag(trace) - s;
    let mut x = T::m3_col(a, 0);
    for k in 1..3 {
        if T::norm2(T::m3_col(a, k)) > T::norm2(x) {
            x = T::m3_col(a, k);
        }
    }
    for _ in 0..64 {
        let l = T::norm(x);
        if !(l > T::ZERO) {
            return T::v3(T::ZERO, T::ZERO, T::ONE);
        }
        x = a * (x / l);
    }
    let l = T::norm(x);
    if l > T::ZERO {
        x / l
    } else {
        T::v3(T::ZERO, T::ZERO, T::ONE)
    }
}

/// Mass-weighted speed of the centre of mass along gravity (positive downwards).
pub fn com_settling_speed<T: Real>(vel: &[T::V3], mass: &[T], gravity: T::V3) -> T {
    match up::<T>(gravity) {
        Some(n) => {
            let (mut s, mut m) = (T::ZERO, T::ZERO);
            for (&u, &w) in vel.iter().zip(mass) {
                s -= w * T::dot(u, n);
                m += w;
            }
            if m > T::ZERO { s / m } else { T::ZERO }
        }
        None => T::ZERO,
    }
}

/// Extents of the centres: `(horizontal, vertical)`. Vertical: the spread of heights;
/// horizontal: the largest horizontal distance between two centres (the diameter of
/// the top view; `O(N^2)`).
pub fn extents<T: Real>(pos: &[T::V3], gravity: T::V3) -> (T, T) {
    let Some(n) = up::<T>(gravity) else {
        return (T::ZERO, T::ZERO);
    };
    let (mut lo, mut hi) = (T::ZERO, T::ZERO);
    let mut wide = T::ZERO;
    for (i, &p) in pos.iter().enumerate() {
        let h = T::dot(p, n);
        if i == 0 || h < lo {
            lo = h;
        }
        if i == 0 || h > hi {
            hi = h;
        }
        for &q in &pos[..i] {
            wide = wide.max(T::norm2(perp::<T>(p - q, n)));
        }
    }
    (wide.sqrt(), hi - lo)
}

/// `true` when the bond's direction is within the angle whose cosine is `cos_min` of
/// the vertical (either sense).
pub fn bond_is_vertical<T: Real>(b: &Bond<T>, pos: &[T::V3], gravity: T::V3, cos_min: T) -> bool {
    let (Some(n), Some(&a), Some(&c)) = (up::<T>(gravity), pos.get(b.i), pos.get(b.j)) else {
        return false;
    };
    let d = a - c;
    let l = T::norm(d);
    l > T::ZERO && T::dot(d, n).abs() >= cos_min * l
}

/// The longest run of consecutive near-vertical bonds in bond order, counting only
/// neighbours that share a particle (a chain's bonds in order): `(first bond, count)`,
/// `(0, 0)` when no bond is vertical.
pub fn vertical_run<T: Real>(
    bonds: &[Bond<T>],
    pos: &[T::V3],
    gravity: T::V3,
    cos_min: T,
) -> (usize, usize) {
    let (mut best, mut start, mut len) = ((0, 0), 0, 0);
    for (k, b) in bonds.iter().enumerate() {
        let linked = k > 0 && {
            let a = bonds[k - 1];
            a.i == b.i || a.i == b.j || a.j == b.i || a.j == b.j
        };
        if bond_is_vertical(b, pos, gravity, cos_min) {
            if len == 0 || !linked {
                (start, len) = (k, 0);
            }
            len += 1;
            if len > best.1 {
                best = (start, len);
            }
        } else {
            len = 0;
        }
    }
    best
}

/// Records, per bond, the first time it was near-vertical: the order in which a
/// stretching front runs along the chain. `first` is caller storage, one entry per
/// bond, filled with a negative value ("not yet") by [`VerticalFront::new`].
#[derive(Debug)]
pub struct VerticalFront<'a, T: Real> {
    first: &'a mut [T],
}

/// Which way the stretching front ran.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontOrder<T> {
    /// Bonds that have turned vertical so far.
    pub count: usize,
    /// Pearson correlation between bond index and the time it turned vertical, in
    /// `[-1, 1]`: near +1 when the front runs from the head (bond 0) to the end, near
    /// -1 from the end to the head, near 0 without order. Zero for fewer than 3 bonds.
    pub correlation: T,
}

impl<'a, T: Real> VerticalFront<'a, T> {
    /// A tracker over `first` (one entry per bond; all are reset).
    pub fn new(first: &'a mut [T]) -> Self {
        first.fill(-T::ONE);
        Self { first }
    }

    /// Marks the bonds that are near-vertical at `time` (>= 0) and were not before.
    pub fn update(
        &mut self,
        bonds: &[Bond<T>],
        pos: &[T::V3],
        gravity: T::V3,
        cos_min: T,
        time: T,
    ) {
        for (f, b) in self.first.iter_mut().zip(bonds) {
            if *f < T::ZERO && bond_is_vertical(b, pos, gravity, cos_min) {
                *f = time;
            }
        }
    }

    /// A tracker that carries on over `first` as it stands (times recorded before,
    /// negative for "not yet"): a run resumed from a saved state.
    pub fn resume(first: &'a mut [T]) -> Self {
        Self { first }
    }

    /// First-vertical times (negative: not yet).
    pub fn times(&self) -> &[T] {
        self.first
    }

    /// Correlation between bond index and first-vertical time over the marked bonds.
    pub fn order(&self) -> FrontOrder<T> {
        let marked = || {
            self.first
                .iter()
                .enumerate()
                .filter(|(_, t)| **t >= T::ZERO)
        };
        let count = marked().count();
        let zero = FrontOrder {
            count,
            correlation: T::ZERO,
        };
        if count < 3 {
            return zero;
        }
        let k = T::from_f64(count as f64);
        let (mut mi, mut mt) = (T::ZERO, T::ZERO);
        for (i, &t) in marked() {
            mi += T::from_f64(i as f64);
            mt += t;
        }
        let (mi, mt) = (mi / k, mt / k);
        let (mut sit, mut sii, mut stt) = (T::ZERO, T::ZERO, T::ZERO);
        for (i, &t) in marked() {
            let (di, dt) = (T::from_f64(i as f64) - mi, t - mt);
            sit += di * dt;
            sii += di * di;
            stt += dt * dt;
        }
        if sii > T::ZERO && stt > T::ZERO {
            FrontOrder {
                count,
                correlation: sit / (sii * stt).sqrt(),
            }
        } else {
            zero
        }
    }
}
