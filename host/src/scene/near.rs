//! Stokesian dynamics' near field: the `[near_field]` table, the top rung of the model
//! ladder (free draining, Oseen, RPY, RPY with the near field).
//!
//! ```toml
//! [near_field]        # every key optional; an empty table takes the defaults
//! cutoff = 4.0        # pairs whose surface gap is below 4 mean radii get lubrication
//! wall_cutoff = 4.0   # spheres nearer the wall than 4 radii get its lubrication
//! min_gap = 1e-3      # the smallest gap the near field sees (surface roughness)
//! ```
//!
//! It is the kernel's `Params::near` (`docs/NEAR.md`): the step's mobility becomes the
//! dense Stokesian dynamics mobility `(M_far^-1 + R_near)^-1`, the far field RPY
//! (`hydrodynamics = "rpy"`), in free space, above a `[wall]` or in a periodic box (its
//! Ewald sums), with methods
//! `"overdamped"` and `"overdamped2"` (level manual), and thermal noise by Cholesky.
//! Dense: a few hundred spheres at most. With `[integrator] matrix_free = true` the
//! kernel applies the same mobility by its iterative product instead (no dense matrix;
//! free space, the Ewald box or above a `[wall]` with `"overdamped"`; bonds, pins and
//! hard contacts with `"overdamped"` and `"overdamped2"`, any solver (`"auto"` is Krylov
//! there); thermal noise by Lanczos with `"overdamped"`: `docs/NEAR.md`,
//! "Iterative steps"). The kernel's first-step check refuses the rest (the box's PSE
//! sums, Lanczos noise) at this table.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S, number};
use super::{Hydrodynamics, Level, Model};

/// The near field's parameters, in radii (the kernel's `NearField`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NearField {
    /// Pairs whose surface gap is below `cutoff` mean radii are corrected.
    pub cutoff: f64,
    /// Spheres whose gap to the wall is below `wall_cutoff` radii are corrected.
    pub wall_cutoff: f64,
    /// The smallest gap the near field sees (closer pairs get this gap's correction).
    pub min_gap: f64,
}

impl Default for NearField {
    fn default() -> Self {
        let k = hydrorattle::stokesian::NearField::<f64>::default();
        Self {
            cutoff: k.cutoff,
            wall_cutoff: k.wall_cutoff,
            min_gap: k.min_gap,
        }
    }
}

impl NearField {
    /// The kernel's parameters in precision `T`.
    pub fn kernel<T: hydrorattle::Real>(self) -> hydrorattle::stokesian::NearField<T> {
        hydrorattle::stokesian::NearField {
            cutoff: T::from_f64(self.cutoff),
            wall_cutoff: T::from_f64(self.wall_cutoff),
            min_gap: T::from_f64(self.min_gap),
        }
    }
}

/// `[near_field]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawNearField {
    cutoff: S<f64>,
    wall_cutoff: S<f64>,
    min_gap: S<f64>,
}

/// Resolves `[near_field]`: the numbers in range, the far field RPY and the level manual
/// (the automatic level picks its own hydrodynamics).
pub(super) fn resolve(raw: &Spanned<RawNearField>, model: &Model) -> Result<NearField, Issue> {
    let r = raw.get_ref();
    let d = NearField::default();
    let near = NearField {
        cutoff: number(&r.cutoff, d.cutoff, "cutoff", Bound::NonNegative)?,
        wall_cutoff: number(
            &r.wall_cutoff,
            d.wall_cutoff,
            "wall_cutoff",
            Bound::NonNegative,
        )?,
        min_gap: number(&r.min_gap, d.min_gap, "min_gap", Bound::Positive)?,
    };
    if model.hydrodynamics != Hydrodynamics::Rpy {
        return Err(issue(
            raw.span(),
            "[near_field] corrects the RPY far field: it needs hydrodynamics = \"rpy\"",
        ));
    }
    if model.level == Level::Auto {
        return Err(issue(
            raw.span(),
            "[near_field] needs level = \"manual\" (the automatic level picks its own hydrodynamics)",
        ));
    }
    Ok(near)
}

impl super::Scene {
    /// This scene with the near field `near` (as a `[near_field]` table would put it):
    /// the numbers in range, the far field RPY, the level manual and the method
    /// overdamped (the kernel refuses the rest at the first step).
    pub fn with_near_field(mut self, near: NearField) -> Result<super::Scene, String> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !(ok(near.cutoff) && ok(near.wall_cutoff) && ok(near.min_gap) && near.min_gap > 0.0) {
            return Err(format!(
                "the near field's cutoff and wall_cutoff must be finite and >= 0, its min_gap finite and > 0 ({near:?})"
            ));
        }
        if self.model.hydrodynamics != Hydrodynamics::Rpy || self.model.level == Level::Auto {
            return Err(
                "the near field needs hydrodynamics = \"rpy\" and level = \"manual\"".into(),
            );
        }
        if !matches!(
            self.integrator.method,
            super::Method::Overdamped | super::Method::Overdamped2
        ) {
            return Err(format!(
                "the near field needs method \"overdamped\" or \"overdamped2\" (the scene's is {:?})",
                self.integrator.method
            ));
        }
        self.near_field = Some(near);
        Ok(self)
    }
}
