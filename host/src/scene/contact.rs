//! Excluded volume between spheres: the `[contact]` table.
//!
//! ```toml
//! [contact]
//! model = "hard"      # one-sided constraints in the kernel's position solve
//! capacity = 75       # most contacts at once (default: 3 per particle)
//!
//! [contact]
//! model = "soft"      # the default model: repulsion stiffness x overlap, explicit
//! stiffness = 1000.0  # required for "soft"; keep dt stiffness / (3 pi eta a) < 1
//! ```

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S, number};

/// Contacts per particle a hard contact model holds by default: a bead in a compact
/// chain touches at most a few unbonded neighbours at once (12 in the closest
/// packing, shared by two: 6 per bead; 3 leaves room for every folded state seen).
pub const DEFAULT_CONTACTS_PER_PARTICLE: usize = 3;

/// How spheres keep out of each other.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "model", rename_all = "lowercase")]
pub enum Contact {
    /// Overlapping spheres repel with `stiffness x overlap` (the kernel's
    /// `SoftContact`, an external force). Explicit: the time step must stay below
    /// about `3 pi eta a / stiffness`.
    Soft {
        /// Force per overlap length.
        stiffness: f64,
    },
    /// Hard spheres: every pair that would overlap is held at contact by a one-sided
    /// constraint in the same solve as the bonds (the kernel's `Params::contacts`).
    /// No stiffness, so no limit on the time step. Overdamped methods only.
    Hard {
        /// Most contacts at once; `None`: [`DEFAULT_CONTACTS_PER_PARTICLE`] per particle.
        capacity: Option<usize>,
    },
}

impl Contact {
    /// The soft stiffness (0 for hard contacts).
    pub fn stiffness(&self) -> f64 {
        match *self {
            Contact::Soft { stiffness } => stiffness,
            Contact::Hard { .. } => 0.0,
        }
    }

    /// The stiffness of a soft model (`None` for hard contacts).
    pub fn soft(&self) -> Option<f64> {
        match *self {
            Contact::Soft { stiffness } => Some(stiffness),
            Contact::Hard { .. } => None,
        }
    }

    /// The contact capacity of a hard model for `n` particles (`None` for soft).
    pub fn hard_capacity(&self, n: usize) -> Option<usize> {
        match *self {
            Contact::Soft { .. } => None,
            Contact::Hard { capacity } => {
                Some(capacity.unwrap_or(n.saturating_mul(DEFAULT_CONTACTS_PER_PARTICLE)))
            }
        }
    }

    /// The model's name in a scene file.
    pub fn name(&self) -> &'static str {
        match self {
            Contact::Soft { .. } => "soft",
            Contact::Hard { .. } => "hard",
        }
    }
}

/// Hard contacts run in the overdamped methods only (the kernel's `Params::contacts`;
/// with thermal noise `"overdamped"`, which the `[brownian]` table's own check asks):
/// any other method is refused at the `[contact]` table.
pub(super) fn check_method(
    c: Contact,
    raw: &Spanned<RawContact>,
    integrator: &super::Integrator,
) -> Result<(), Issue> {
    if !matches!(c, Contact::Hard { .. }) {
        return Ok(());
    }
    let span = raw
        .get_ref()
        .model
        .as_ref()
        .map_or(raw.span(), |m| m.span());
    if !matches!(
        integrator.method,
        super::Method::Overdamped | super::Method::Overdamped2
    ) {
        return Err(issue(
            span,
            format!(
                "hard contacts need method \"overdamped\" or \"overdamped2\" (the scene's is {:?}); use model = \"soft\" with a stiffness",
                integrator.method
            ),
        ));
    }
    Ok(())
}

/// Stiffness of the soft contact the project used before hard contacts (overlaps below
/// ~0.05 a) and still uses where hard contacts do not run (inertial methods, the charts that compare every method under one model).
pub const SOFT_STIFFNESS: f64 = 1000.0;
/// The largest step that soft contact allows: `dt k / (3 pi eta a) = 0.53`.
pub const SOFT_DT: f64 = 0.005;

impl super::Scene {
    /// Switches to the soft contact ([`SOFT_STIFFNESS`]) at the step it allows
    /// ([`SOFT_DT`], or the scene's if smaller), with frames as often in time.
    pub fn with_soft_contact(&mut self) {
        let every_time = self.output.every as f64 * self.integrator.dt;
        self.contact = Some(Contact::Soft {
            stiffness: SOFT_STIFFNESS,
        });
        self.integrator.dt = self.integrator.dt.min(SOFT_DT);
        self.output.every = ((every_time / self.integrator.dt).round() as usize).max(1);
    }
}

/// `[contact]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawContact {
    model: S<String>,
    stiffness: S<f64>,
    capacity: S<i64>,
}

/// Resolves `[contact]` (its span places a missing key).
pub(super) fn resolve(raw: &Spanned<RawContact>) -> Result<Contact, Issue> {
    let c = raw.get_ref();
    let model = c.model.as_ref().map(|m| (m.get_ref().as_str(), m.span()));
    match model {
        None | Some(("soft", _)) => {
            if let Some(k) = &c.capacity {
                return Err(issue(k.span(), "capacity is for model = \"hard\" only"));
            }
            if c.stiffness.is_none() {
                return Err(issue(
                    raw.span(),
                    "missing field `stiffness` (a soft contact needs it; or set model = \"hard\")",
                ));
            }
            let stiffness = number(&c.stiffness, 0.0, "contact stiffness", Bound::Positive)?;
            Ok(Contact::Soft { stiffness })
        }
        Some(("hard", _)) => {
            if let Some(k) = &c.stiffness {
                return Err(issue(
                    k.span(),
                    "a hard contact has no stiffness (remove it, or set model = \"soft\")",
                ));
            }
            let capacity = match &c.capacity {
                None => None,
                Some(k) if *k.get_ref() >= 1 && *k.get_ref() <= 1 << 32 => {
                    Some(*k.get_ref() as usize)
                }
                Some(k) => {
                    return Err(issue(
                        k.span(),
                        "capacity must be a whole number from 1 to 2^32 (contacts at once)",
                    ));
                }
            };
            Ok(Contact::Hard { capacity })
        }
        Some((other, span)) => Err(issue(
            span,
            format!("unknown contact model {other:?} (expected \"soft\" or \"hard\")"),
        )),
    }
}
