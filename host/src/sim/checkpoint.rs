//! Checkpoints: the exact state of a run at a time step, written atomically to
//! `checkpoint.json` in the output folder, and what `host-demo resume` continues from.
//!
//! Every number of the state is stored as the bits of its `f64` value (the kernel's
//! `f32` values widen exactly), so a resumed run continues bit for bit. The files of
//! the run are cut back to the marks the checkpoint names and continued: a run to `T`
//! resumed to `2 T` writes the same bytes as one run to `2 T`.
//!
//! A run can be killed at any moment (SIGKILL included) and resumed from its last
//! checkpoint: [`ready_folder`] writes `scene.toml` before the first step, and every
//! file is written aside and renamed, so the folder never holds half a checkpoint.

use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use hydrorattle::Real;
use serde::{Deserialize, Serialize};

use super::record::{Marks, Observables};
use super::{SCENE_TOML, SUMMARY_JSON};
use crate::output::{tmp_path, write_atomic, write_json};
use crate::scene::Beads;
use crate::scene::{Precision, Scene};

/// The checkpoint file's name in the output folder.
pub const CHECKPOINT: &str = "checkpoint.json";

/// Format version of the checkpoint file.
const VERSION: u32 = 2;

/// The state of a run after time step `step`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Format version.
    pub version: u32,
    /// Time steps done.
    pub step: u64,
    /// Precision of the state.
    pub precision: Precision,
    /// Simulated time, `f64` bits.
    pub time: u64,
    /// Centres, `f64` bits, x y z per particle.
    pub pos: Vec<u64>,
    /// Velocities, likewise.
    pub vel: Vec<u64>,
    /// Angular velocities, likewise.
    pub omega: Vec<u64>,
    /// Twist accumulated so far, `f64` bits.
    pub twist: u64,
    /// Per bond, the first time it was near-vertical (`f64` bits; negative: not yet).
    pub front: Vec<u64>,
    /// Constraint iterations summed over the steps done.
    pub total_iterations: u64,
    /// Where the run's files stand.
    pub marks: Marks,
    /// The last row written.
    pub last: Observables,
    /// The thermal-noise generator after `step` ([`hydrorattle::Noise::save`]); absent
    /// for a deterministic run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<[u64; 6]>,
    /// Steps retried split so far (Brownian runs).
    #[serde(default)]
    pub retries: super::retry::Retries,
    /// With `[free_space] reweigh`: the steps taken on the pair sums so far.
    #[serde(default)]
    pub pair_steps: u64,
    /// With a wall: the landing time so far (`f64` bits; absent: not landed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub landing: Option<u64>,
    /// At temperature: the noise's Lanczos iterations so far (absent for a
    /// deterministic run, and in checkpoints written before it was kept: a run resumed
    /// from one counts from the checkpoint on).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lanczos: Option<super::LanczosTally>,
    /// The solve of step `step` itself. A run that ends there between frames closes
    /// with a row after the checkpoint; a run resumed there writes that row again from
    /// these (absent in checkpoints written before they were kept: such a checkpoint
    /// is not resumed at the last step of its run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_step: Option<StepSolve>,
}

/// The constraint solve of one step, as its row in `observables.csv` records it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepSolve {
    /// Constraint iterations.
    pub iterations: u32,
    /// The largest bond tension, `f64` bits.
    pub max_tension: u64,
}

fn bits<T: Real>(v: &[T::V3]) -> Vec<u64> {
    v.iter()
        .flat_map(|&x| T::v3_to_f64(x))
        .map(f64::to_bits)
        .collect()
}

fn restore<T: Real>(bits: &[u64], out: &mut [T::V3], what: &str) -> Result<()> {
    if bits.len() != 3 * out.len() {
        bail!(
            "the checkpoint has {} {what} values for {} particles",
            bits.len(),
            out.len()
        );
    }
    for (o, b) in out.iter_mut().zip(bits.chunks(3)) {
        *o = T::v3_from([b[0], b[1], b[2]].map(f64::from_bits));
    }
    Ok(())
}

impl Checkpoint {
    /// The state of `beads` after `step` steps, with the trackers' state (twist and
    /// stretching-front times).
    pub(super) fn of<T: Real>(
        step: u64,
        precision: Precision,
        beads: &Beads<T>,
        trackers: (T, &[T]),
        total_iterations: u64,
        marks: Marks,
        last: Observables,
    ) -> Self {
        let (twist, front) = trackers;
        Checkpoint {
            version: VERSION,
            step,
            precision,
            time: beads.time.to_f64().to_bits(),
            pos: bits::<T>(&beads.pos),
            vel: bits::<T>(&beads.vel),
            omega: bits::<T>(&beads.omega),
            twist: twist.to_f64().to_bits(),
            front: front.iter().map(|t| t.to_f64().to_bits()).collect(),
            total_iterations,
            marks,
            last,
            noise: None,
            retries: super::retry::Retries::default(),
            pair_steps: 0,
            landing: None,
            lanczos: None,
            last_step: None,
        }
    }

    /// The generator saved with the state, checked (a Brownian run's checkpoint has one).
    pub(super) fn noise(&self) -> Result<Option<hydrorattle::Noise>> {
        match self.noise {
            None => Ok(None),
            Some(words) => hydrorattle::Noise::restore(words)
                .map(Some)
                .context("the checkpoint's noise generator state is not one a generator has"),
        }
    }

    /// Puts the state back into `beads` (built from the same scene).
    pub(super) fn restore<T: Real>(&self, beads: &mut Beads<T>) -> Result<()> {
        restore::<T>(&self.pos, &mut beads.pos, "position")?;
        restore::<T>(&self.vel, &mut beads.vel, "velocity")?;
        restore::<T>(&self.omega, &mut beads.omega, "angular velocity")?;
        beads.time = T::from_f64(f64::from_bits(self.time));
        Ok(())
    }

    /// Puts the stretching-front times back into `front` (one per bond).
    pub(super) fn restore_front<T: Real>(&self, front: &mut [T]) -> Result<()> {
        if self.front.len() != front.len() {
            bail!(
                "the checkpoint has {} front times for {} bonds",
                self.front.len(),
                front.len()
            );
        }
        for (f, &b) in front.iter_mut().zip(&self.front) {
            *f = T::from_f64(f64::from_bits(b));
        }
        Ok(())
    }

    /// Simulated time.
    pub fn time(&self) -> f64 {
        f64::from_bits(self.time)
    }

    /// Writes `DIR/checkpoint.json` atomically.
    pub fn save(&self, dir: &Path) -> Result<()> {
        Ok(write_json(&dir.join(CHECKPOINT), self)?)
    }

    /// Reads `DIR/checkpoint.json`; [`NoCheckpoint`] when there is none.
    pub fn load(dir: &Path) -> Result<Self> {
        let path = dir.join(CHECKPOINT);
        let text = match std::fs::read_to_string(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(NoCheckpoint { path }),
            read => read.with_context(|| format!("reading {}", path.display()))?,
        };
        let c: Checkpoint = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a checkpoint", path.display()))?;
        if c.version != VERSION {
            bail!(
                "{}: checkpoint format {} (this program reads {VERSION})",
                path.display(),
                c.version
            );
        }
        Ok(c)
    }
}

/// `resume` of a folder without `checkpoint.json`: a run killed before its first
/// checkpoint, or one run without `--checkpoint-every`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NoCheckpoint {
    /// The checkpoint's path.
    pub path: PathBuf,
}

impl fmt::Display for NoCheckpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: no checkpoint to resume from (the run stopped before its first one, or ran \
             without --checkpoint-every); run its scene.toml again",
            self.path.display()
        )
    }
}

impl std::error::Error for NoCheckpoint {}

/// Readies the output folder `dir` for a run of `scene` (its level applied) that can be
/// killed at any moment and resumed: the `checkpoint.json.tmp` of a run killed while
/// saving goes (never read, it would otherwise outlive the run). A run from the start
/// (`fresh`) writes `scene.toml` before its first step, as `resume` reads it, and
/// removes the checkpoint and summary a previous run left in the folder: beside the new
/// `scene.toml` they would describe another run, and resuming from that checkpoint would
/// mix the two. A resumed run keeps `scene.toml` until it ends, so that a resume that
/// fails leaves the folder as it was.
pub(super) fn ready_folder(dir: &Path, scene: &Scene, fresh: bool) -> Result<()> {
    let checkpoint = dir.join(CHECKPOINT);
    let mut stale = vec![tmp_path(&checkpoint)];
    if fresh {
        stale.extend([checkpoint, dir.join(SUMMARY_JSON)]);
    }
    for path in stale {
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(crate::output::name_error(&path, e).into());
            }
            _ => {}
        }
    }
    if fresh {
        write_atomic(&dir.join(SCENE_TOML), scene.to_toml().as_bytes())?;
    }
    Ok(())
}
