//! `[brownian]`: thermal noise at `temperature` (kT) from a seeded generator.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::model::{Integrator, Level, Method, Model};
use super::raw::{Bound, S, number};

/// Drift scheme of a Brownian run (the kernel's [`hydrorattle::Drift`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Drift {
    /// Fixman-type midpoint: the stiff-bond (flexible chain) equilibrium.
    #[default]
    Midpoint,
    /// Noise then projection, no correction (rigid-constraint bias).
    Uncorrected,
}

impl Drift {
    /// The kernel's drift.
    pub fn kernel(self) -> hydrorattle::Drift {
        match self {
            Drift::Midpoint => hydrorattle::Drift::Midpoint,
            Drift::Uncorrected => hydrorattle::Drift::Uncorrected,
        }
    }
}

/// Thermal noise settings (`[brownian]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Thermal {
    /// Thermal energy kT (>= 0; 0 is the deterministic run).
    pub temperature: f64,
    /// Generator seed: the same seed gives the same run, bit for bit.
    pub seed: u64,
    /// Drift scheme.
    pub drift: Drift,
}

/// Default seed when `[brownian]` gives none.
pub const DEFAULT_SEED: u64 = 1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBrownian {
    temperature: S<f64>,
    seed: Option<Spanned<i64>>,
    drift: Option<Drift>,
}

impl RawBrownian {
    /// Checks the keys; a positive temperature needs the overdamped method chosen by
    /// hand (the kernel has noise for that method only).
    pub(super) fn resolve(&self, model: &Model, integrator: &Integrator) -> Result<Thermal, Issue> {
        let temperature = number(&self.temperature, 0.0, "temperature", Bound::NonNegative)?;
        let seed = match &self.seed {
            None => DEFAULT_SEED,
            Some(s) => u64::try_from(*s.get_ref())
                .map_err(|_| issue(s.span(), format!("seed must be >= 0, not {}", s.get_ref())))?,
        };
        let manual = integrator.method == Method::Overdamped && model.level == Level::Manual;
        if temperature > 0.0 && !manual {
            let at = self.temperature.as_ref().map(|t| t.span());
            let message = "temperature > 0 needs method = \"overdamped\" and level = \"manual\" \
                           (thermal noise is implemented for the overdamped step only)";
            return Err(match at {
                Some(span) => issue(span, message),
                None => Issue::unplaced(message),
            });
        }
        Ok(Thermal {
            temperature,
            seed,
            drift: self.drift.unwrap_or_default(),
        })
    }
}
