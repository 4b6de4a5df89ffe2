//! `[brownian]`: thermal noise at `temperature` (kT) from a seeded generator.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::model::{Integrator, Level, Method, Model, Precision};
use super::names::Name;
use super::raw::{Bound, S, number};

/// Drift scheme of a Brownian run: the kernel's [`hydrorattle::Drift`], by its names.
pub use hydrorattle::Drift;

/// Square root of the mobility for the noise, `sqrt = "auto" | "cholesky" | "lanczos"`:
/// the kernel's [`hydrorattle::NoiseSqrt`], by its names.
pub use hydrorattle::NoiseSqrt as Sqrt;

/// Thermal noise settings (`[brownian]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Thermal {
    /// Thermal energy kT (>= 0; 0 is the deterministic run).
    pub temperature: f64,
    /// Generator seed: the same seed gives the same run, bit for bit.
    pub seed: u64,
    /// Drift scheme.
    #[serde(serialize_with = "super::names::serialize")]
    pub drift: Drift,
    /// Square root of the mobility.
    #[serde(serialize_with = "super::names::serialize")]
    pub sqrt: Sqrt,
}

/// Default seed when `[brownian]` gives none.
pub const DEFAULT_SEED: u64 = 1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBrownian {
    temperature: S<f64>,
    seed: Option<Spanned<i64>>,
    drift: Option<Name<Drift>>,
    sqrt: Option<Spanned<Name<Sqrt>>>,
}

impl RawBrownian {
    /// Where `sqrt` is written, or else `temperature`.
    pub(super) fn sqrt_span(&self) -> Option<std::ops::Range<usize>> {
        self.sqrt
            .as_ref()
            .map(|s| s.span())
            .or_else(|| self.temperature_span())
    }

    /// Where `temperature` is written.
    pub(super) fn temperature_span(&self) -> Option<std::ops::Range<usize>> {
        self.temperature.as_ref().map(|t| t.span())
    }

    /// Checks the keys; a positive temperature needs the overdamped, spring or
    /// rattle-stable method chosen by hand (the kernel has noise for those methods
    /// only).
    pub(super) fn resolve(&self, model: &Model, integrator: &Integrator) -> Result<Thermal, Issue> {
        let temperature = number(&self.temperature, 0.0, "temperature", Bound::NonNegative)?;
        let seed = match &self.seed {
            None => DEFAULT_SEED,
            Some(s) => u64::try_from(*s.get_ref())
                .map_err(|_| issue(s.span(), format!("seed must be >= 0, not {}", s.get_ref())))?,
        };
        let manual = matches!(
            integrator.method,
            Method::Overdamped | Method::Springs | Method::RattleStable
        ) && model.level == Level::Manual;
        if temperature > 0.0 && !manual {
            let at = self.temperature.as_ref().map(|t| t.span());
            let message = "temperature > 0 needs method = \"overdamped\", \"springs\" or \
                           \"rattle-stable\" and level = \"manual\" (thermal noise is implemented \
                           for those steps only)";
            return Err(match at {
                Some(span) => issue(span, message),
                None => Issue::unplaced(message),
            });
        }
        Ok(Thermal {
            temperature,
            seed,
            drift: self.drift.map_or_else(Drift::default, |d| d.0),
            sqrt: self
                .sqrt
                .as_ref()
                .map_or_else(Sqrt::default, |s| s.get_ref().0),
        })
    }

    /// Checks a positive temperature against the run's precision, at its line: it must
    /// not round to zero or to a subnormal (the run would silently be deterministic or
    /// lose digits), and the largest per-step displacement variance
    /// `2 kT dt / (6 pi eta a_min)` must be a normal number at most the square root of
    /// the precision's largest value (1.8e19 in f32, 1.3e154 in f64), so that squared
    /// distances between kicked beads stay finite.
    pub(super) fn check_precision(
        &self,
        thermal: &Thermal,
        integrator: &Integrator,
        viscosity: f64,
        min_radius: f64,
    ) -> Result<(), Issue> {
        let kt = thermal.temperature;
        if kt == 0.0 {
            return Ok(());
        }
        let (name, tiny, huge, rounded) = match integrator.precision {
            Precision::F32 => (
                "f32",
                f64::from(f32::MIN_POSITIVE),
                f64::from(f32::MAX),
                f64::from(kt as f32),
            ),
            Precision::F64 => ("f64", f64::MIN_POSITIVE, f64::MAX, kt),
        };
        let variance =
            2.0 * kt * integrator.dt / (6.0 * std::f64::consts::PI * viscosity * min_radius);
        let show = crate::output::format_f64;
        let message = if rounded < tiny {
            format!(
                "temperature {} vanishes in {name} (it rounds to {}; the smallest normal {name} is {tiny:.2e})",
                show(kt),
                show(rounded),
            )
        } else if !(tiny..=huge.sqrt()).contains(&variance) {
            format!(
                "temperature {} gives a per-step displacement variance 2 kT dt / (6 pi eta a) = {variance:.3e} \
                 for the smallest sphere, outside what {name} can hold and square ({tiny:.2e} to {:.2e})",
                show(kt),
                huge.sqrt()
            )
        } else {
            return Ok(());
        };
        Err(match self.temperature.as_ref().map(|t| t.span()) {
            Some(span) => issue(span, message),
            None => Issue::unplaced(message),
        })
    }
}
