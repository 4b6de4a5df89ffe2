//! The end of a run and its pauses: a checkpoint after a step, a run stopped on
//! request (a checkpoint there, the files kept aside), and the close (the closing row,
//! the summary, the files renamed, the record).

use std::path::Path;

use anyhow::Result;
use hydrorattle::Real;

use super::super::checkpoint::{Checkpoint, StepSolve};
use super::super::engine::Engine;
use super::super::record::{NEAR_VERTICAL_COS, OBSERVABLES_CSV, TRAJECTORY_GSD, TRAJECTORY_XYZ};
use super::super::stop::Interrupted;
use super::super::{Front, RunResult, SCENE_TOML, SUMMARY_JSON, Summary, snapshot};
use super::{Origin, Tracks};
use crate::output::{write_atomic, write_json};
use crate::scene::Level;

impl<T: Real> Tracks<'_, '_, T> {
    /// Writes `DIR/checkpoint.json` after step `s` (twist so far `tw`).
    pub(super) fn checkpoint(
        &mut self,
        s: usize,
        engine: &Engine<T>,
        tw: T,
        dir: &Path,
    ) -> Result<()> {
        let marks = self.rec.marks()?;
        let precision = self.scene.integrator.precision;
        let trackers = (tw, self.front.times());
        let its = self.total_iterations;
        let beads = &engine.beads;
        let mut c = Checkpoint::of(s as u64, precision, beads, trackers, its, marks, self.last);
        if self.thermal() {
            c.noise = Some(engine.noise.save());
            c.retries = engine.retries;
            c.lanczos = Some(engine.lanczos);
        }
        c.pair_steps = engine.pair_steps;
        c.landing = self.landing.map(|t| t.to_f64().to_bits());
        c.last_step = Some(StepSolve {
            iterations: self.solve.0,
            max_tension: self.solve.1.to_f64().to_bits(),
        });
        c.save(dir)
    }

    /// Ends a run stopped on request after step `done`: a checkpoint there, the files
    /// left under their temporary names (what it marks), and [`Interrupted`].
    pub(super) fn interrupt(
        mut self,
        engine: &Engine<T>,
        done: usize,
        signal: usize,
    ) -> anyhow::Error {
        let tw = self.twist.total;
        let checkpoint = self.out.map(|dir| {
            self.checkpoint(done, engine, tw, dir)
                .map(|()| dir.join(super::super::CHECKPOINT))
        });
        let checkpoint = match checkpoint.transpose() {
            Ok(c) => c,
            Err(e) => return e.context("checkpointing a run stopped on request"),
        };
        if let Err(e) = self.rec.suspend() {
            return e.context("keeping the files of a run stopped on request");
        }
        Interrupted {
            signal,
            step: done as u64,
            time: engine.beads.time.to_f64(),
            checkpoint,
        }
        .into()
    }

    /// Closes the run after step `done`: a final row when it stopped between frames,
    /// the summary, the files renamed, and the record (`scene.toml`, `summary.json`).
    pub(super) fn close(
        mut self,
        engine: Engine<T>,
        done: usize,
        failure: Option<String>,
        wall: f64,
        name: &str,
        origin: Origin,
    ) -> Result<RunResult> {
        let beads = &engine.beads;
        if self.last.time != beads.time.to_f64() {
            // A run that ended between frames without a closing row: one resumed at
            // its last step (the row its step wrote, from the checkpoint's solve), or
            // one whose step failed (no solve to record).
            let (iterations, tension) = match failure {
                None => self.solve,
                Some(_) => (0, T::ZERO),
            };
            let total = self.twist.total;
            self.last = self.frame(done, beads, total, iterations, tension)?;
        }
        let outcome = match (&failure, self.tail.late_state()) {
            (None, Some(s)) => s.name().to_string(),
            _ => "failed".to_string(),
        };
        let order = self.front.order();
        let front = Front {
            cos_min: NEAR_VERTICAL_COS,
            count: order.count,
            correlation: order.correlation.to_f64(),
            first_vertical: self
                .front
                .times()
                .iter()
                .map(|t| (*t >= T::ZERO).then(|| t.to_f64()))
                .collect(),
        };
        let stepped = done + 1 - self.first;
        let mut summary = Summary {
            scene_path: origin.scene_path,
            particles: beads.len(),
            bonds: self.bonds.len(),
            tolerance_used: engine.params.solver.tolerance.to_f64(),
            steps: self.steps,
            steps_done: done,
            resumed_from: origin.checkpoint.map(Checkpoint::time),
            wall_time_s: wall,
            steps_per_second: stepped as f64 / wall.max(1e-12),
            mean_iterations: self.total_iterations as f64 / (done.max(1) as f64),
            final_observables: self.last,
            twist_rate: self.tail.slope(),
            outcome,
            front,
            failure,
            retries: engine.retries,
            pair_sum_steps: engine.reweighs().then_some(engine.pair_steps),
            noise_iterations: self
                .thermal()
                .then(|| engine.lanczos.record(&engine.params, beads.len())),
            landing_time: self.landing.map(T::to_f64),
            level_choice: origin.level_choice,
            ..Summary::for_scene(self.scene, name)
        };
        summary.resolved_scene.model.level = Level::Manual;
        self.rec.commit()?;
        if let Some(dir) = self.out {
            // A resumed run's duration is new; a run from the start wrote its scene
            // before the first step.
            if origin.checkpoint.is_some() {
                let resolved = &summary.resolved_scene;
                write_atomic(&dir.join(SCENE_TOML), resolved.to_toml().as_bytes())?;
            }
            // Read back after the rename: what a reader of the folder will find.
            let data = [OBSERVABLES_CSV, TRAJECTORY_XYZ, TRAJECTORY_GSD];
            summary.files = crate::output::check_files(dir, &data)?;
            write_json(&dir.join(SUMMARY_JSON), &summary)?;
        }
        let (mut frames, mut at) = self.keeper.finish(done, beads);
        let (mut initial, mut last) = (
            self.initial,
            snapshot::<T>(&beads.pos, &beads.radius, beads.time),
        );
        // The pictures draw the wall.
        let wall = self.wall.map(|w| w.height.to_f64());
        let kept = frames.iter_mut().chain(at.iter_mut().flatten());
        for s in kept.chain([&mut initial, &mut last]) {
            s.wall = wall;
        }
        Ok(RunResult {
            summary,
            initial,
            last,
            series: self.series,
            frames,
            at,
        })
    }
}
