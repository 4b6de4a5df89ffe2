//! The Lanczos iterations of a thermal run's noise (the kernel's
//! `StepReport::noise_iterations`), counted over every kernel step the run makes (the
//! sub-steps of a split step each count, [`retry`](super::retry)), kept in checkpoints
//! and written to `summary.json` as `noise_iterations`.

use hydrorattle::{NoiseSqrt, Params, Real, Stage, StepError, StepReport};
use serde::{Deserialize, Serialize};

/// What the run's kernel steps reported about the noise's square root so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LanczosTally {
    /// Kernel steps at temperature that succeeded.
    pub steps: u64,
    /// Their Lanczos iterations summed (0 for the Cholesky factor).
    pub iterations: u64,
    /// The most iterations one step took.
    pub max: u32,
    /// Kernel steps refused because the Lanczos iteration reached its cap without
    /// converging (`NoConvergence` at the mobility stage; the run retries them split).
    pub capped: u64,
}

impl LanczosTally {
    /// Counts one kernel step's outcome.
    pub fn add<T: Real>(&mut self, outcome: &Result<StepReport<T>, StepError>) {
        match outcome {
            Ok(r) => {
                self.steps += 1;
                self.iterations += u64::from(r.noise_iterations);
                self.max = self.max.max(r.noise_iterations);
            }
            Err(StepError::NoConvergence {
                stage: Stage::Mobility,
                ..
            }) => self.capped += 1,
            Err(_) => {}
        }
    }

    /// `summary.json`'s record of the tally, for a run of `n` beads with `p`.
    pub fn record<T: Real>(&self, p: &Params<T>, n: usize) -> NoiseIterations {
        let lanczos = p.lanczos_noise(n);
        NoiseIterations {
            sqrt: match (p.noise_sqrt, lanczos) {
                (NoiseSqrt::Auto, true) => "lanczos (auto)",
                (NoiseSqrt::Auto, false) => "cholesky (auto)",
                (_, true) => "lanczos",
                (_, false) => "cholesky",
            },
            steps: self.steps,
            mean: match self.steps {
                0 => 0.0,
                s => self.iterations as f64 / s as f64,
            },
            max: self.max,
            total: self.iterations,
            cap: p.lanczos.max_iterations,
            capped: self.capped,
        }
    }
}

/// `summary.json`'s `noise_iterations` (thermal runs only): the Lanczos iterations of
/// the noise's square root per kernel step (a split step's sub-steps count one each).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct NoiseIterations {
    /// The square root the steps took, as the scene's `sqrt` resolved at its size:
    /// "cholesky" or "lanczos", with "(auto)" when `auto` chose it. The Cholesky factor
    /// iterates not at all: every count below is then 0.
    pub sqrt: &'static str,
    /// Kernel steps at temperature that succeeded.
    pub steps: u64,
    /// Mean iterations per step.
    pub mean: f64,
    /// The most iterations one step took.
    pub max: u32,
    /// Iterations summed over the steps.
    pub total: u64,
    /// The cap (`Params::lanczos.max_iterations`): a step that needs more is refused.
    pub cap: u32,
    /// Kernel steps refused at the cap (each retried split; see `retries`).
    pub capped: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tally_counts_steps_iterations_and_refusals_at_the_cap() {
        let mut t = LanczosTally::default();
        let ok = |k| {
            Ok(StepReport::<f64> {
                noise_iterations: k,
                ..StepReport::default()
            })
        };
        for k in [7, 12, 9] {
            t.add(&ok(k));
        }
        t.add::<f64>(&Err(StepError::NoConvergence {
            stage: Stage::Mobility,
            iterations: 64,
            residual: 0.1,
        }));
        // Not the noise's: a constraint solve's cap, and other refusals.
        t.add::<f64>(&Err(StepError::NoConvergence {
            stage: Stage::Positions,
            iterations: 64,
            residual: 0.1,
        }));
        t.add::<f64>(&Err(StepError::BadTimeStep));
        assert_eq!(
            t,
            LanczosTally {
                steps: 3,
                iterations: 28,
                max: 12,
                capped: 1,
            }
        );
        let mut p = Params::<f64>::new(0.01);
        p.noise_sqrt = NoiseSqrt::Lanczos;
        let r = t.record(&p, 25);
        assert_eq!(
            (r.sqrt, r.steps, r.max, r.total, r.cap),
            ("lanczos", 3, 12, 28, 64)
        );
        assert!((r.mean - 28.0 / 3.0).abs() < 1e-15);
        p.noise_sqrt = NoiseSqrt::Auto;
        assert_eq!(t.record(&p, 25).sqrt, "cholesky (auto)");
        assert_eq!(LanczosTally::default().record(&p, 25).mean, 0.0);
    }
}
