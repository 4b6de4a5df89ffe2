//! The run of a scene in precision `T`, as a short list of stages ([`run_t`]):
//!
//! 1. [`Engine::new`]: the system (particles, bonds, parameters, storage), checked and
//!    sized before anything is written; a resumed run takes its checkpoint's state;
//! 2. [`Tracks::open`]: the files and the trackers (twist, stretching front, late-time
//!    window, kept frames) with the first frame, or the rows replayed from a checkpoint;
//! 3. [`Tracks::steps`]: the time loop, a step and what follows it (trackers, frames,
//!    checkpoints);
//! 4. [`Tracks::close`]: the closing row, the summary, the files under their final names
//!    with `summary.json` (and a resumed run's `scene.toml`; a run from the start writes
//!    it before its first step, so that it can be resumed however it stops).
//!
//! Stage 4, the checkpoints and the stop on request are in [`end`].

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use hydrorattle::observables::{StateThresholds, Twist, VerticalFront};
use hydrorattle::{Real, StepReport};

use super::checkpoint::{Checkpoint, ready_folder};
use super::engine::Engine;
use super::frames::Keeper;
use super::record::{NEAR_VERTICAL_COS, OBSERVABLES_CSV, Observer, Recorder, WallGauge, each_row};
use super::tail::TailSlope;
use super::{Beads, Observables, RunOptions, RunResult, snapshot};
use crate::progress::Progress;
use crate::scene::Scene;

mod end;

/// What a run records about where it came from.
pub(super) struct Origin<'a> {
    /// The scene file, when the run came from one.
    pub scene_path: Option<String>,
    /// What `level = "auto"` chose.
    pub level_choice: Option<crate::auto::Choice>,
    /// The checkpoint the run continues from.
    pub checkpoint: Option<&'a Checkpoint>,
    /// The caller holds the output folder's lock.
    pub locked: bool,
}

/// Runs `scene` (its level already applied) on `engine` (built from it) from the
/// start or from `origin`'s checkpoint, writing the run's files into `out` when given.
pub(super) fn run_t<T: Real>(
    engine: Engine<T>,
    scene: &Scene,
    name: &str,
    out: Option<&Path>,
    opts: RunOptions,
    origin: Origin,
) -> Result<RunResult> {
    let mut engine = engine.with_threads(opts.threads)?;
    if let Some(c) = origin.checkpoint {
        c.restore(&mut engine.beads)?;
        // A Brownian run continues its generator and its retry count.
        let thermal = scene.brownian.is_some_and(|b| b.temperature > 0.0);
        match c.noise()? {
            Some(g) => engine.noise = g,
            None if thermal => bail!("the checkpoint of a Brownian run has no generator state"),
            None => {}
        }
        engine.retries = c.retries;
        engine.pair_steps = c.pair_steps;
        engine.lanczos = c.lanczos.unwrap_or_default();
    }
    let mut lock = None;
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| crate::output::name_error(dir, e))?;
        // One writer per folder, held until the run ends: a second one would truncate
        // this run's files under it.
        lock = (!origin.locked)
            .then(|| crate::output::FolderLock::take(dir))
            .transpose()?;
        ready_folder(dir, scene, origin.checkpoint.is_none())?;
    }
    let mut twist_prev = vec![T::ZERO; engine.beads.len()];
    let mut front_times = vec![-T::ONE; engine.bonds.len()];
    let mut tracks = Tracks::open(
        scene,
        &engine,
        out,
        opts,
        origin.checkpoint,
        &mut twist_prev,
        &mut front_times,
    )?;
    let (done, halt, wall) = tracks.steps(&mut engine, name)?;
    let failure = match halt {
        Halt::Ended => None,
        Halt::Failed(why) => Some(why),
        Halt::Stopped(signal) => return Err(tracks.interrupt(&engine, done, signal)),
    };
    let result = tracks.close(engine, done, failure, wall, name, origin);
    drop(lock);
    result
}

/// Why the time loop ended.
enum Halt {
    /// Every step made.
    Ended,
    /// A step failed (why).
    Failed(String),
    /// A stop was requested (by this signal) before the next step.
    Stopped(usize),
}

/// The trackers and files of a run, over the caller's storage.
struct Tracks<'a, 's, T: Real> {
    scene: &'s Scene,
    out: Option<&'s Path>,
    opts: RunOptions<'s>,
    rec: Recorder,
    twist: Twist<'a, T>,
    front: VerticalFront<'a, T>,
    tail: TailSlope,
    series: Vec<Observables>,
    keeper: Keeper,
    mass: Vec<T>,
    gravity: T::V3,
    bonds: Vec<hydrorattle::Bond<T>>,
    /// The wall, if any, as the observables see it.
    wall: Option<WallGauge<T>>,
    /// The end of the first step after which a sphere was held on the wall.
    landing: Option<T>,
    initial: super::Snapshot,
    /// Steps asked for (the scene's, cut by `max_steps`).
    steps: usize,
    /// The first step to make (1, or the one after a checkpoint).
    first: usize,
    /// The last frame's observables.
    last: Observables,
    total_iterations: u64,
    /// The last step's constraint iterations and largest tension (what a closing row
    /// records).
    solve: (u32, T),
}

impl<'a, 's, T: Real> Tracks<'a, 's, T> {
    /// Opens the files and starts the trackers at `engine`'s state: records the first
    /// frame, or (from a checkpoint) replays the rows written so far.
    fn open(
        scene: &'s Scene,
        engine: &Engine<T>,
        out: Option<&'s Path>,
        opts: RunOptions<'s>,
        from: Option<&Checkpoint>,
        twist_prev: &'a mut [T],
        front_times: &'a mut [T],
    ) -> Result<Self> {
        let beads = &engine.beads;
        let gravity = engine.params.gravity;
        let steps = opts.max_steps.map_or(scene.integrator.steps(), |m| {
            m.min(scene.integrator.steps())
        });
        let rec = Recorder::new(out, scene.topology(), from.map(|c| c.marks))?;
        let mut twist = Twist::new(twist_prev, T::from_f64(0.25));
        if let Some(c) = from {
            c.restore_front(front_times)?;
        }
        let mut front = VerticalFront::resume(front_times);
        if from.is_none() {
            front.update(
                &engine.bonds,
                &beads.pos,
                gravity,
                T::from_f64(NEAR_VERTICAL_COS),
                beads.time,
            );
        }
        let initial = snapshot::<T>(&beads.pos, &beads.radius, beads.time);
        // The twist tracker starts from the current positions; a resumed run carries the
        // total on.
        twist.update(&beads.pos, gravity);
        let mut tracks = Tracks {
            scene,
            out,
            opts,
            rec,
            twist,
            front,
            tail: TailSlope::new(steps as f64 * scene.integrator.dt),
            series: Vec::new(),
            keeper: Keeper::new(&opts.keep, steps, scene.integrator.dt, beads.len()),
            mass: (0..beads.len()).map(|i| beads.mass(i)).collect(),
            gravity,
            bonds: engine.bonds.clone(),
            wall: engine.params.wall.map(|w| WallGauge {
                height: w.height,
                tolerance: engine.params.solver.tolerance,
            }),
            landing: None,
            initial,
            steps,
            first: 1,
            last: Observables::default(),
            total_iterations: 0,
            solve: (0, T::ZERO),
        };
        match from {
            Some(c) => {
                tracks.twist.total = T::from_f64(f64::from_bits(c.twist));
                // The recorder has cut the rows back to the checkpoint, under the
                // temporary name: replay them into the twist-rate window (and the series).
                if let Some(dir) = out {
                    let rows = crate::output::tmp_path(&dir.join(OBSERVABLES_CSV));
                    each_row(&rows, c.marks.csv_bytes, |o| tracks.keep_row(o))?;
                }
                (tracks.first, tracks.last) = (c.step as usize + 1, c.last);
                tracks.landing = c.landing.map(|t| T::from_f64(f64::from_bits(t)));
                tracks.total_iterations = c.total_iterations;
                if let Some(s) = c.last_step {
                    tracks.solve = (s.iterations, T::from_f64(f64::from_bits(s.max_tension)));
                }
            }
            None => {
                tracks.last = tracks.frame(0, beads, T::ZERO, 0, T::ZERO)?;
            }
        }
        tracks.keeper.take(tracks.first - 1, beads);
        Ok(tracks)
    }

    /// A run at temperature (its steps draw noise).
    fn thermal(&self) -> bool {
        self.scene.brownian.is_some_and(|b| b.temperature > 0.0)
    }

    /// The observables of `beads` with the twist so far and a step's solve figures.
    fn observe(&self, beads: &Beads<T>, twist: T, iterations: u32, tension: T) -> Observables {
        let observer = Observer {
            bonds: &self.bonds,
            mass: &self.mass,
            gravity: self.gravity,
            thresholds: StateThresholds::default(),
            wall: self.wall,
        };
        Observables::of(beads, &observer, twist, iterations, tension)
    }

    /// A row into the late-time window and the series.
    fn keep_row(&mut self, o: Observables) {
        self.tail.add(&o);
        if self.opts.keep_series {
            self.series.push(o);
        }
    }

    /// Records a frame reached at step `step` and its row.
    fn frame(
        &mut self,
        step: usize,
        beads: &Beads<T>,
        twist: T,
        iterations: u32,
        tension: T,
    ) -> Result<Observables> {
        let o = self.observe(beads, twist, iterations, tension);
        self.rec.record(step as u64, beads, &o)?;
        self.keep_row(o);
        Ok(o)
    }

    /// The time loop: steps `first..=steps`, each followed by [`Tracks::after_step`];
    /// stops at the first failed step, or before a step once a stop is requested.
    /// Returns the last step done, why the loop ended and the wall time.
    fn steps(&mut self, engine: &mut Engine<T>, name: &str) -> Result<(usize, Halt, f64)> {
        let bar = if self.opts.progress {
            Progress::new(self.steps as u64, name)
        } else {
            Progress::hidden(self.steps as u64)
        };
        let start = Instant::now();
        let (mut done, mut failure) = (self.first - 1, None);
        for s in self.first..=self.steps {
            // Between steps only: the state is whole, and a checkpoint can hold it.
            if let Some(signal) = self.opts.stop.requested_after(done as u64) {
                bar.finish();
                return Ok((done, Halt::Stopped(signal), start.elapsed().as_secs_f64()));
            }
            match engine.step() {
                Ok(rep) => {
                    done = s;
                    self.after_step(s, engine, &rep)?;
                    // A row the precision could not compute ends the run as a failed
                    // step does: its rows so far are kept, and the run exits non-zero.
                    if let Some((column, x)) = self.last.non_finite() {
                        let t = engine.beads.time.to_f64();
                        let message = format!(
                            "step {s} (t = {t}): observable {column} is {x}: the state is beyond what the run's precision can measure"
                        );
                        log::warn!("{name}: {message}");
                        failure = Some(message);
                        break;
                    }
                }
                Err(e) => {
                    let t = engine.beads.time;
                    log::warn!("{name}: step {s} failed at t = {t}: {e}");
                    failure = Some(format!("step {s} (t = {}): {e}", t.to_f64()));
                    break;
                }
            }
            if s % 256 == 0 {
                bar.set_position(s as u64);
            }
        }
        bar.finish();
        let halt = failure.map_or(Halt::Ended, Halt::Failed);
        Ok((done, halt, start.elapsed().as_secs_f64()))
    }

    /// What follows step `s`: the trackers, the scheduled frame, a checkpoint, and the
    /// closing frame of a run that ends between frames.
    fn after_step(&mut self, s: usize, engine: &Engine<T>, rep: &StepReport<T>) -> Result<()> {
        let beads = &engine.beads;
        let gravity = self.gravity;
        self.keeper.take(s, beads);
        self.total_iterations += u64::from(rep.iterations);
        self.solve = (rep.iterations, rep.max_tension);
        if self.landing.is_none() && rep.wall_contacts > 0 {
            self.landing = Some(beads.time);
        }
        let tw = self.twist.update(&beads.pos, gravity);
        let cos_vertical = T::from_f64(NEAR_VERTICAL_COS);
        self.front
            .update(&self.bonds, &beads.pos, gravity, cos_vertical, beads.time);
        let scheduled = s.is_multiple_of(self.scene.output.every.max(1));
        if scheduled {
            self.last = self.frame(s, beads, tw, rep.iterations, rep.max_tension)?;
        }
        // A checkpoint marks the files after the scheduled frames only: the closing
        // frame of a run that ends between frames is not part of a longer run.
        if let (Some(t), Some(dir)) = (self.opts.checkpoint_every, self.out) {
            let k = ((t / self.scene.integrator.dt).round() as usize).max(1);
            if s.is_multiple_of(k) {
                self.checkpoint(s, engine, tw, dir)?;
            }
        }
        if s == self.steps && !scheduled {
            self.last = self.frame(s, beads, tw, rep.iterations, rep.max_tension)?;
        }
        Ok(())
    }
}
