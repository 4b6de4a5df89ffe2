//! Fixed-capacity bond lists: chains, rings, trees and arbitrary topologies.
//!
//! Bond `k` joins particles `(i, j)` with length `d_k`; its constraint is
//! `sigma_k = |r_i - r_j|^2 - d_k^2 = 0`. A length of zero is allowed for
//! [`Method::Springs`](crate::Method::Springs) only (a spring of rest length zero, the
//! classic Hookean dumbbell); a constrained step refuses it
//! ([`BondError::BadLength`]).
//!
//! Inside a step the constraint solve also holds **wall links** ([`Bond::wall`]), which
//! no caller's bond can be (`j == i`, refused as a self-bond): sphere `i` tied to its
//! foot on the wall, the point of the plane below its centre, which follows the sphere
//! along the wall and takes no force. The projection runs in the wall's frame (the plane
//! is `z = 0` there), so the link's relative vector is the normal component
//! `(0, 0, z_i)` ([`Bond::relative`]); its length is the sphere's radius (touching).
//!
//! A caller's list may hold **pin rows** ([`Bond::pin`], `docs/CONTACTS.md`): sphere
//! `i` held along axis `e` at its *anchor*, its position at the start of the step
//! (`x_i . e = anchor . e`), a linear equality that pushes on that sphere alone along
//! `e`. Three rows (x, y, z: [`Bond::pins`]) hold a sphere fixed; the multipliers are
//! the force that holds it. Their `j` is a tag past every particle index
//! ([`PIN`] + axis), their length a scale (the sphere's radius: the residual is the
//! anchor's error in radii). The step puts a pinned coordinate back on its anchor bit
//! for bit after the solve, so a pinned sphere never drifts.

use crate::cell::Periodic;
use crate::fault::BondError;
use crate::real::Real;
use heapless::Vec;

/// One holonomic distance constraint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bond<T: Real> {
    /// First particle.
    pub i: usize,
    /// Second particle.
    pub j: usize,
    /// Centre-to-centre length (> 0; a spring's rest length may be 0).
    pub length: T,
}

impl<T: Real> Bond<T> {
    /// The wall link of sphere `i` of radius `radius` (see the module): it holds the
    /// centre at height `radius` above the wall. Its constraint is linear,
    /// `2 a (z_i - a) = 0`: the bond's `|r|^2 - d^2` linearised at contact, so that a
    /// step carrying the sphere far through the wall has no second root to land on.
    pub const fn wall(i: usize, radius: T) -> Self {
        Self {
            i,
            j: i,
            length: radius,
        }
    }

    /// The ceiling link of sphere `i` of radius `radius`: [`Bond::wall`] upside down,
    /// the centre held a radius below the ceiling (a slit's upper plane). Its length is
    /// `-radius`, the sign naming the surface: the normal `-z`, so that the gradient
    /// `(0, 0, 2 d)` and the constraint `2 d (z_i - c - d) = 0` (`c` the ceiling's
    /// height in the floor's frame, where the projection runs) are the wall link's.
    pub fn ceiling(i: usize, radius: T) -> Self {
        Self {
            i,
            j: i,
            length: -radius,
        }
    }

    /// `true` for a ceiling link ([`Bond::ceiling`]); always `false` without the
    /// `slit` and `contacts` features (firmware: the branch compiles away).
    #[inline(always)]
    pub fn is_ceiling(&self) -> bool {
        cfg!(feature = "slit")
            && cfg!(feature = "contacts")
            && self.is_wall()
            && self.length < T::ZERO
    }

    /// Pin row of sphere `i` along `axis` (0, 1, 2: x, y, z; see the module), `scale`
    /// its length (> 0; the sphere's radius). An axis past 2 makes a row that
    /// [`validate`] refuses ([`BondError::OutOfRange`]).
    pub const fn pin(i: usize, axis: usize, scale: T) -> Self {
        Self {
            i,
            j: PIN.wrapping_add(if axis < 3 { axis } else { 3 }),
            length: scale,
        }
    }

    /// The three pin rows that hold sphere `i` fixed (x, y, z).
    pub const fn pins(i: usize, scale: T) -> [Self; 3] {
        [
            Self::pin(i, 0, scale),
            Self::pin(i, 1, scale),
            Self::pin(i, 2, scale),
        ]
    }

    /// `true` for a pin row ([`Bond::pin`]); always `false` without the `pins` feature
    /// (firmware: every pin branch compiles away).
    #[inline(always)]
    pub const fn is_pin(&self) -> bool {
        cfg!(feature = "pins") && self.j >= PIN && self.j < PIN + 3
    }

    /// `true` for a link that pushes on sphere `i` alone: a wall link or a pin row (`j`
    /// names no sphere).
    #[inline(always)]
    pub const fn one_sphere(&self) -> bool {
        self.is_wall() || self.is_pin()
    }

    /// The axis a one-sphere link holds: `z` for a wall link, the pin row's axis.
    #[inline(always)]
    pub const fn axis(&self) -> usize {
        if self.is_pin() { self.j - PIN } else { 2 }
    }

    /// `true` for a wall link ([`Bond::wall`]).
    #[inline(always)]
    pub const fn is_wall(&self) -> bool {
        // Without the `wall` feature no wall link is ever made (a step with a wall is
        // refused, a user's bond to itself too), so every wall branch compiles away.
        cfg!(feature = "wall") && self.i == self.j
    }

    /// `v_i - v_j` over per-particle vectors `v` (positions, displacements): for a
    /// wall link, the normal component `(0, 0, v_i.z)` (its other end, the foot on the
    /// wall, moves with the sphere along the wall); for a pin row, the component of
    /// `v_i` along its axis (a displacement or a velocity; a position's error is
    /// measured from the anchor by the solve).
    #[inline(always)]
    pub fn relative(&self, v: &[T::V3]) -> T::V3 {
        if self.one_sphere() {
            component::<T>(v[self.i], self.axis())
        } else {
            v[self.i] - v[self.j]
        }
    }
}

impl<T: Real> Bond<T> {
    /// The link's relative position `x_i - x_j` ([`Bond::relative`]), in a periodic box
    /// its minimum image ([`crate::cell::image`]; a wall link or a pin row has none to
    /// take: a pin's anchor is the unwrapped start position).
    #[inline(always)]
    pub fn separation(&self, pos: &[T::V3], cell: Option<&Periodic<T>>) -> T::V3 {
        match self.one_sphere() {
            true => self.relative(pos),
            false => crate::cell::image(cell, pos[self.i] - pos[self.j]),
        }
    }
}

/// The first of the `j` tags of pin rows ([`Bond::pin`]): `PIN + axis`. Past any
/// particle index a step can hold.
pub const PIN: usize = usize::MAX - 3;

/// The component of `v` along coordinate axis `axis` (a vector along it).
#[inline(always)]
pub(crate) fn component<T: Real>(v: T::V3, axis: usize) -> T::V3 {
    let c = T::xyz(v);
    let mut e = [T::ZERO; 3];
    e[axis] = c[axis];
    T::v3(e[0], e[1], e[2])
}

/// The unit vector of coordinate axis `axis` times `s`.
#[inline(always)]
pub(crate) fn along<T: Real>(axis: usize, s: T) -> T::V3 {
    let mut e = [T::ZERO; 3];
    e[axis] = s;
    T::v3(e[0], e[1], e[2])
}

/// Relative length error of link `b` whose relative vector is `r`:
/// `| |r| - d | / d`, or `|z - d| / d` for a wall link (signed: a centre below the
/// wall's plane is not near its length).
#[inline]
fn link_error<T: Real>(b: &Bond<T>, r: T::V3) -> T {
    if b.is_wall() {
        ((T::xyz(r)[2] - b.length) / b.length).abs()
    } else {
        ((T::norm(r) - b.length) / b.length).abs()
    }
}

/// Up to `B` bonds (heapless storage).
#[derive(Clone, Debug, Default)]
pub struct BondSet<T: Real, const B: usize> {
    bonds: Vec<Bond<T>, B>,
}

impl<T: Real, const B: usize> BondSet<T, B> {
    /// No bonds.
    pub const fn new() -> Self {
        Self { bonds: Vec::new() }
    }

    /// The bonds, in insertion order (which is the SHAKE sweep order).
    pub fn as_slice(&self) -> &[Bond<T>] {
        &self.bonds
    }

    /// Number of bonds.
    pub fn len(&self) -> usize {
        self.bonds.len()
    }

    /// `true` when there are no bonds.
    pub fn is_empty(&self) -> bool {
        self.bonds.is_empty()
    }

    /// Adds a bond after checking it against the `n` particles and the bonds already
    /// present. Hands the bond back with the reason when it is rejected.
    pub fn push(&mut self, b: Bond<T>, n: usize) -> Result<usize, (Bond<T>, BondError)> {
        let k = self.bonds.len();
        if let Err(e) = check_bond(k, &b, n, &self.bonds) {
            return Err((b, e));
        }
        self.bonds.push(b).map_err(|b| (b, BondError::Full))?;
        Ok(k)
    }

    /// Adds a bond whose length is the current distance between its particles.
    pub fn push_current(
        &mut self,
        i: usize,
        j: usize,
        pos: &[T::V3],
    ) -> Result<usize, (Bond<T>, BondError)> {
        let length = match (pos.get(i), pos.get(j)) {
            (Some(&a), Some(&b)) => T::norm(a - b),
            _ => T::ZERO,
        };
        self.push(Bond { i, j, length }, pos.len())
    }

    /// A chain `0-1-...-(n-1)` with lengths taken from `pos` (`n = pos.len()`).
    pub fn chain(pos: &[T::V3]) -> Result<Self, BondError> {
        let mut s = Self::new();
        for i in 1..pos.len() {
            s.push_current(i - 1, i, pos).map_err(|(_, e)| e)?;
        }
        Ok(s)
    }

    /// A ring: the chain plus the bond closing it (needs at least 3 particles).
    pub fn ring(pos: &[T::V3]) -> Result<Self, BondError> {
        let mut s = Self::chain(pos)?;
        // n < 3 fails naturally: a self-bond (n = 1), a duplicate (n = 2), out of range (n = 0).
        let last = pos.len().saturating_sub(1);
        s.push_current(last, 0, pos).map_err(|(_, e)| e)?;
        Ok(s)
    }

    /// A tree from a parent list: `parents[c] = Some(p)` bonds `c` to `p < c`;
    /// `None` marks a root. Lengths are taken from `pos`.
    pub fn tree(pos: &[T::V3], parents: &[Option<usize>]) -> Result<Self, BondError> {
        if parents.len() != pos.len() {
            return Err(BondError::BadTree {
                particle: parents.len().min(pos.len()),
            });
        }
        let mut s = Self::new();
        for (c, p) in parents.iter().enumerate() {
            if let Some(p) = *p {
                if p >= c {
                    return Err(BondError::BadTree { particle: c });
                }
                s.push_current(p, c, pos).map_err(|(_, e)| e)?;
            }
        }
        Ok(s)
    }

    /// Checks every bond against `n` particles and against each other.
    pub fn validate(&self, n: usize) -> Result<(), BondError> {
        validate(&self.bonds, n)
    }

    /// Largest relative length error `| |r_ij| - d | / d` and its bond (0 if none;
    /// bonds of length zero have none and are skipped).
    pub fn max_residual(&self, pos: &[T::V3]) -> (usize, T) {
        max_residual(&self.bonds, pos)
    }

    /// Validates, then checks that `pos` satisfies every bond to relative `tolerance`.
    pub fn check_satisfied(&self, pos: &[T::V3], tolerance: T) -> Result<(), BondError> {
        self.validate(pos.len())?;
        let (bond, r) = self.max_residual(pos);
        if r.is_finite() && r <= tolerance {
            Ok(())
        } else {
            Err(BondError::Violated {
                bond,
                residual: r.to_f64(),
            })
        }
    }
}

/// Checks a bond list of any length against `n` particles: range, self-bonds, lengths
/// and duplicates (the checks [`BondSet::push`] makes, for runtime-sized hosts; the
/// duplicate check is `O(B^2)`, once per list, not per step).
pub fn validate<T: Real>(bonds: &[Bond<T>], n: usize) -> Result<(), BondError> {
    for (k, b) in bonds.iter().enumerate() {
        check_bond(k, b, n, &bonds[..k])?;
    }
    Ok(())
}

/// Largest relative length error `| |r_ij| - d | / d` over `bonds` and the bond where it
/// occurs. NaN is sticky (a NaN residual is never hidden), and a bond naming a particle
/// beyond `pos` counts as infinitely violated. A bond of length zero (a spring's rest
/// length) has no relative error and is skipped, as is a pin row (its error is
/// measured from the anchor by the solve, [`Bond::pin`]). A wall link ([`Bond::wall`]) counts its
/// height error `|z_i - a| / a` (positions in the wall's frame).
///
/// Two square roots, not one per bond: the error grows with `|r_ij|^2 / d^2` away from 1
/// on either side, so it is largest at the largest or the smallest of these ratios
/// (exactly so in exact arithmetic; where two bonds' errors agree to rounding, either
/// may be named).
pub fn max_residual<T: Real>(bonds: &[Bond<T>], pos: &[T::V3]) -> (usize, T) {
    max_residual_in(bonds, pos, None)
}

/// [`max_residual`] in a periodic box: each bond's length is that of its minimum image
/// ([`Bond::separation`]).
pub fn max_residual_in<T: Real>(
    bonds: &[Bond<T>],
    pos: &[T::V3],
    cell: Option<&Periodic<T>>,
) -> (usize, T) {
    let (mut hi, mut lo) = ((0, T::ZERO), (0, T::ZERO));
    let mut first = true;
    for (k, b) in bonds.iter().enumerate() {
        // A pin row's error is its anchor's, which the solve measures (the step puts
        // the coordinate back on it after the solve): none here.
        if b.is_pin() && b.i < pos.len() {
            continue;
        }
        if b.i >= pos.len() || b.j >= pos.len() {
            return max_residual_each(bonds, pos, cell);
        }
        if b.length == T::ZERO {
            continue;
        }
        let r = b.separation(pos, cell);
        let mut ratio = T::norm2(r) / (b.length * b.length);
        // A wall link's centre at or below the plane has the error of a bond stretched
        // to `(2 - z/a) d`: the ratio that orders it with the others.
        let h = T::xyz(r)[2] / b.length;
        if b.is_wall() && !(h > T::ZERO) {
            ratio = (T::TWO - h) * (T::TWO - h);
        }
        if ratio.is_nan() {
            return max_residual_each(bonds, pos, cell);
        }
        if first || ratio > hi.1 {
            hi = (k, ratio);
        }
        if first || ratio < lo.1 {
            lo = (k, ratio);
        }
        first = false;
    }
    let at = |k: usize| {
        let b = &bonds[k];
        (k, link_error(b, b.separation(pos, cell)))
    };
    if first {
        return (0, T::ZERO);
    }
    let (h, l) = (at(hi.0), at(lo.0));
    if l.1 > h.1 || (l.1 == h.1 && l.0 < h.0) {
        l
    } else {
        h
    }
}

/// [`max_residual`] bond by bond, for the rare lists with a NaN or a bond out of range.
fn max_residual_each<T: Real>(
    bonds: &[Bond<T>],
    pos: &[T::V3],
    cell: Option<&Periodic<T>>,
) -> (usize, T) {
    let mut worst = (0, T::ZERO);
    for (k, b) in bonds.iter().enumerate() {
        let r = match b.i < pos.len() && (b.j < pos.len() || b.is_pin()) {
            true if b.length == T::ZERO || b.is_pin() => continue,
            true => link_error(b, b.separation(pos, cell)),
            false => T::ONE / T::ZERO,
        };
        if !worst.1.is_nan() && (r.is_nan() || r > worst.1) {
            worst = (k, r);
        }
    }
    worst
}

fn check_bond<T: Real>(
    k: usize,
    b: &Bond<T>,
    n: usize,
    earlier: &[Bond<T>],
) -> Result<(), BondError> {
    check_one(k, b, n)?;
    let same = |o: &Bond<T>| (o.i == b.i && o.j == b.j) || (o.i == b.j && o.j == b.i);
    if let Some(other) = earlier.iter().position(same) {
        return Err(BondError::Duplicate { bond: k, other });
    }
    Ok(())
}

/// Bond `k` on its own against `n` particles: range, self-bond, length (finite, >= 0;
/// `O(1)`).
pub(crate) fn check_one<T: Real>(k: usize, b: &Bond<T>, n: usize) -> Result<(), BondError> {
    // A pin row's `j` is its axis tag (no particle); its scale must be > 0.
    if b.is_pin() {
        if b.i >= n {
            return Err(BondError::OutOfRange {
                bond: k,
                particle: b.i,
            });
        }
        if !(b.length > T::ZERO && (b.length * b.length).is_finite()) {
            return Err(BondError::BadLength { bond: k });
        }
        return Ok(());
    }
    for p in [b.i, b.j] {
        if p >= n {
            return Err(BondError::OutOfRange {
                bond: k,
                particle: p,
            });
        }
    }
    if b.i == b.j {
        return Err(BondError::SelfBond {
            bond: k,
            particle: b.i,
        });
    }
    // The constraint squares the length: d^2 must be finite too. Zero is a spring's
    // rest length; a constrained step refuses it (`integrate::checks`).
    if !(b.length >= T::ZERO && (b.length * b.length).is_finite()) {
        return Err(BondError::BadLength { bond: k });
    }
    Ok(())
}
