//! A pinned floor under a suspension: the `[floor]` table.
//!
//! ```toml
//! [floor]
//! radius = 1.0    # the floor spheres' radius (> 0); default: the suspension's mean radius
//! density = 4.5   # their density (>= 0); default: the suspension's
//! ```
//!
//! In a periodic box gravity is balanced by the mean pressure gradient and nothing
//! compresses; a floor that carries load is a layer of pinned spheres (the kernel's
//! `Bond::pin` rows, `docs/CONTACTS.md`). The floor is a square lattice of `k x k`
//! spheres across the box's cross-section, `k` the most that fit side by side
//! (`k = floor(L / 2 a_f)`, spacing `L / k >= 2 a_f`), centred at `z = a_f`. No
//! suspension sphere passes through it: the widest hole of the lattice admits a
//! sphere of radius `(sqrt 2 s - 2 a_f) / 2` (`s` the spacing), which must be below
//! the smallest suspension radius (else the table is refused at `radius`).
//!
//! The suspension's spheres (placed by `[suspension]` in its cube of edge `L`) are
//! raised above the floor by `2 a_f + a_max` (plus the generator's gap), and the box
//! grows in `z` to `L + 2 a_f + 2 a_max` (plus the gap): no sphere touches the floor
//! or the floor's image above at the start. The floor's spheres come first (indices
//! `0 .. k^2`, species `floor`), then the suspension's (`sphere`).

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::Issue;
use super::raw::{Bound, S, number};
use super::{GAP, Particle};

/// A pinned square lattice under a suspension (see the module).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Floor {
    /// The floor spheres' radius (> 0).
    pub radius: f64,
    /// Their density (>= 0).
    pub density: f64,
}

/// `[floor]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFloor {
    radius: S<f64>,
    density: S<f64>,
}

/// Resolves `[floor]`, its defaults the suspension's mean radius and density.
pub(super) fn resolve(raw: &Spanned<RawFloor>, radius: f64, density: f64) -> Result<Floor, Issue> {
    let r = raw.get_ref();
    Ok(Floor {
        radius: number(&r.radius, radius, "floor radius", Bound::Positive)?,
        density: number(&r.density, density, "floor density", Bound::NonNegative)?,
    })
}

/// The span of `radius` in `[floor]`, or of the table.
pub(super) fn radius_span(raw: &Spanned<RawFloor>) -> std::ops::Range<usize> {
    raw.get_ref()
        .radius
        .as_ref()
        .map_or(raw.span(), |r| r.span())
}

impl Floor {
    /// Lays the floor under `spheres` (a suspension in its cube of edge `edge`): the
    /// floor's spheres then the raised suspension, and the box's size; or why the
    /// floor cannot hold the suspension.
    pub fn lay(
        &self,
        spheres: &[Particle],
        edge: f64,
    ) -> Result<(Vec<Particle>, [f64; 3]), String> {
        let a = self.radius;
        let k = (edge / (2.0 * a)).floor();
        if k.is_nan() || k < 1.0 {
            return Err(format!(
                "a floor sphere of radius {a} does not fit across the box's edge {edge}"
            ));
        }
        let k = k as usize;
        let spacing = edge / k as f64;
        let (lo, hi) = spheres
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| {
                (lo.min(p.radius), hi.max(p.radius))
            });
        let hole = (std::f64::consts::SQRT_2 * spacing - 2.0 * a) / 2.0;
        if hole.is_nan() || hole >= lo {
            return Err(format!(
                "spheres of radius {lo} would fall through the floor: its lattice ({k} x {k} spheres of radius {a}, spacing {spacing}) leaves holes of radius {hole}; give the floor a larger radius"
            ));
        }
        let gap = GAP * (a + hi);
        let lift = 2.0 * a + hi + gap;
        let mut out = Vec::with_capacity(k * k + spheres.len());
        for i in 0..k {
            for j in 0..k {
                out.push(Particle {
                    position: [(i as f64 + 0.5) * spacing, (j as f64 + 0.5) * spacing, a],
                    radius: a,
                    density: self.density,
                    ..Particle::default()
                });
            }
        }
        out.extend(spheres.iter().map(|p| Particle {
            position: [p.position[0], p.position[1], p.position[2] + lift],
            ..*p
        }));
        Ok((out, [edge, edge, edge + lift + hi + gap]))
    }

    /// Spheres in the floor of a box of edge `edge` (the first indices); saturates at
    /// `usize::MAX` (a count no storage limit passes).
    pub fn count(&self, edge: f64) -> usize {
        let k = (edge / (2.0 * self.radius)).floor().max(0.0) as usize;
        k.saturating_mul(k)
    }
}

/// The solid volume fraction of spheres (centres `pos`, radii `radius`) in the slab
/// `lo < z < hi` of a periodic box of cross-section `area` (each sphere's part in the
/// slab, exactly: `pi (a^2 u - u^3 / 3)` between the slab's faces, `u = z - z_i`).
/// The bed's fraction measured in its middle layers, away from the floor's lattice
/// and the loose top.
pub fn slab_fraction(pos: &[[f64; 3]], radius: &[f64], area: f64, (lo, hi): (f64, f64)) -> f64 {
    let part = |z: f64, a: f64| {
        let (u1, u2) = ((lo - z).max(-a), (hi - z).min(a));
        let f = |u: f64| a * a * u - u * u * u / 3.0;
        if u2 > u1 {
            std::f64::consts::PI * (f(u2) - f(u1))
        } else {
            0.0
        }
    };
    let solid: f64 = pos.iter().zip(radius).map(|(p, &a)| part(p[2], a)).sum();
    solid / (area * (hi - lo))
}
