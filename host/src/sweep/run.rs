//! Running a sweep's points: each in its own folder, skipped when finished, resumed
//! from its checkpoint when unfinished, and otherwise run from the start (what a
//! folder's files say: `state.rs`). A resumed point's files come out byte for
//! byte as those of an uninterrupted run; thermal-noise runs resume the same way (their
//! checkpoints hold the noise generator's state).
//!
//! One writer per point: a process locks the point's folder ([`FolderLock`]) before it
//! looks at its files and holds the lock until the run ends. A second process on the
//! same point (`sbatch` twice, two `--point ID`) skips it and says so, or with
//! [`Options::wait`] waits for the first and then finds the point finished. The OS
//! releases the lock of a killed process.
//!
//! A stop request ([`Stop`]: SIGTERM, Ctrl-C) checkpoints the points running, starts
//! no other, and the report says so ([`RunReport::signal`]).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;

pub use super::report::{Outcome, RunReport};
use super::state::{RUN_FILES, State, state};
use super::{POINTS, Point, STATEPOINT_JSON, Sweep, claim, frozen, id::canonical_json};
use crate::output::{FolderLock, tmp_path};
use crate::scene::{Level, Scene};
use crate::sim::{Interrupted, SCENE_TOML, Start, Stop};

/// A failed start, written in the point's folder (removed when the point runs again).
pub const ERROR_TXT: &str = "error.txt";

/// Which points a process runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Selection {
    /// Every point.
    All,
    /// Shard `k` of `n` (`k` from 0, as SLURM array task ids): the points whose index
    /// is `k` modulo `n`.
    Shard {
        /// This shard.
        k: usize,
        /// Number of shards.
        n: usize,
    },
    /// One point, by id (or a unique prefix of at least 4 characters).
    Point(String),
}

impl Selection {
    /// Parses `K/N`.
    pub fn shard(text: &str) -> Result<Selection> {
        let parsed = text
            .split_once('/')
            .and_then(|(k, n)| Some((k.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((k, n)) if n >= 1 && k < n => Ok(Selection::Shard { k, n }),
            _ => bail!("--shard takes K/N with 0 <= K < N (K counted from 0), not {text:?}"),
        }
    }

    /// The selected points of `sweep`.
    pub fn points<'a>(&self, sweep: &'a Sweep) -> Result<Vec<&'a Point>> {
        Ok(match self {
            Selection::All => sweep.points.iter().collect(),
            Selection::Shard { k, n } => {
                sweep.points.iter().filter(|p| p.index % n == *k).collect()
            }
            Selection::Point(id) => match sweep.find(id) {
                Some(p) => vec![p],
                None => bail!("the sweep has no point {id:?} (see sweep.json)"),
            },
        })
    }
}

/// How a process runs its points.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Points run at once (threads).
    pub jobs: usize,
    /// Checkpoint every this much simulated time; None: about ten per run, on frames.
    pub checkpoint_every: Option<f64>,
    /// Wait for a point another process is running, rather than skip it.
    pub wait: bool,
    /// Stop on request: running points checkpoint, no other starts.
    pub stop: Stop,
}

/// The folder of point `id` under the sweep folder `dir`.
pub fn point_dir(dir: &Path, id: &str) -> PathBuf {
    dir.join(POINTS).join(id)
}

/// The scene as a run records it in `scene.toml`: `level = "auto"` applied (as the run
/// applies it), level manual.
pub fn as_run(scene: &Scene, name: &str) -> Scene {
    let mut s = crate::sim::resolve_level(scene, name).0;
    s.model.level = Level::Manual;
    s
}

/// Writes `bytes` to `path` unless it already holds them, under a temporary name of
/// this process.
fn write_same(path: &Path, bytes: &[u8]) -> Result<()> {
    if std::fs::read(path).is_ok_and(|b| b == bytes) {
        return Ok(());
    }
    let tmp = path.with_extension(format!("tmp.{}", std::process::id()));
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// The point's state point in its folder (rewritten only when missing or changed).
fn write_statepoint(point: &Point, pdir: &Path) -> Result<()> {
    let mut sp = canonical_json(&point.statepoint).into_bytes();
    sp.push(b'\n');
    write_same(&pdir.join(STATEPOINT_JSON), &sp)
}

/// Clears a point's folder of run files and writes its state point and scene.
fn prepare(point: &Point, pdir: &Path, scene_text: &str) -> Result<()> {
    std::fs::create_dir_all(pdir).with_context(|| format!("creating {}", pdir.display()))?;
    for name in RUN_FILES {
        let path = pdir.join(name);
        for p in [tmp_path(&path), path] {
            if p.exists() {
                std::fs::remove_file(&p).with_context(|| format!("removing {}", p.display()))?;
            }
        }
    }
    write_statepoint(point, pdir)?;
    write_same(&pdir.join(SCENE_TOML), scene_text.as_bytes())
}

/// Writes the folders of the points that are not finished or resumable (state point
/// and scene), without running them: what `--emit` leaves for the engines (row finds
/// its directories by them). A point folder another sweep wrote is left alone.
pub fn prepare_points(sweep: &Sweep, dir: &Path) -> Result<usize> {
    claim::claim(sweep, dir)?;
    let mut prepared = 0;
    for p in &sweep.points {
        let pdir = point_dir(dir, &p.id);
        let text = frozen::run_text(p).0;
        std::fs::create_dir_all(&pdir).with_context(|| format!("creating {}", pdir.display()))?;
        // A point another process is running is left to it.
        let Some(_lock) = FolderLock::try_take(&pdir)? else {
            continue;
        };
        if let State::New = state(&pdir, &text, &as_run(&p.scene, &p.id)) {
            prepare(p, &pdir, &text)?;
            prepared += 1;
        }
    }
    Ok(prepared)
}

/// The checkpoint interval of a point: `every` if given, else about a tenth of the run
/// on a frame step.
fn checkpoint_every(scene: &Scene, every: Option<f64>) -> Option<f64> {
    every.or_else(|| {
        let (steps, frame) = (scene.integrator.steps(), scene.output.every.max(1));
        let k = steps.div_ceil(10).div_ceil(frame) * frame;
        (k < steps).then_some(k as f64 * scene.integrator.dt)
    })
}

/// Locks the folder of point `id` (creating it), waiting with `wait`; None when
/// another process holds it and `wait` is off.
fn lock_point(pdir: &Path, id: &str, wait: bool) -> Result<Option<FolderLock>> {
    std::fs::create_dir_all(pdir).with_context(|| format!("creating {}", pdir.display()))?;
    let lock = FolderLock::try_take(pdir)?;
    if lock.is_some() || !wait {
        return Ok(lock);
    }
    println!("{id}: locked by another process: waiting for it");
    Ok(Some(FolderLock::wait(pdir)?))
}

/// Runs one point (the one place a sweep calls the run), under the point's lock.
pub fn run_point(point: &Point, dir: &Path, opts: Options) -> Outcome {
    let pdir = point_dir(dir, &point.id);
    // Held until the run ends: the state read below stays true while it runs.
    let _lock = match lock_point(&pdir, &point.id, opts.wait) {
        Ok(Some(lock)) => lock,
        Ok(None) => return Outcome::Locked,
        Err(e) => return Outcome::Failed(format!("{e:#}")),
    };
    let (text, _) = frozen::run_text(point);
    let checkpoint = match state(&pdir, &text, &as_run(&point.scene, &point.id)) {
        State::Foreign(why) => return Outcome::Failed(why),
        State::Finished => {
            return match write_statepoint(point, &pdir) {
                Ok(()) => Outcome::Skipped,
                Err(e) => Outcome::Failed(format!("{e:#}")),
            };
        }
        State::Resumable(c) => {
            if let Err(e) = write_statepoint(point, &pdir) {
                return Outcome::Failed(format!("{e:#}"));
            }
            Some(*c)
        }
        State::New => {
            if let Err(e) = prepare(point, &pdir, &text) {
                return Outcome::Failed(format!("{e:#}"));
            }
            None
        }
    };
    let run_opts = crate::sim::RunOptions {
        progress: false,
        keep_series: false,
        checkpoint_every: checkpoint_every(&point.scene, opts.checkpoint_every),
        stop: opts.stop,
        ..crate::sim::RunOptions::default()
    };
    let start = Start {
        scene_path: None,
        checkpoint,
        locked: true,
    };
    match crate::sim::run_from(&point.scene, &point.id, Some(&pdir), run_opts, start) {
        Ok(r) => Outcome::Ran(Box::new(r.summary)),
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => {
            Outcome::Interrupted(e.downcast_ref::<Interrupted>().map_or(0, |i| i.signal))
        }
        Err(e) => {
            let why = format!("{e:#}");
            let _ = std::fs::write(pdir.join(ERROR_TXT), format!("{why}\n"));
            Outcome::Failed(why)
        }
    }
}

/// Runs the `selection` of `sweep` in `dir` with `opts.jobs` points at a time, printing
/// a line per point as it ends. The folder is claimed first ([`claim::claim`]): a
/// folder holding another sweep is refused before anything is written.
pub fn run_points(
    sweep: &Sweep,
    dir: &Path,
    selection: &Selection,
    opts: Options,
) -> Result<RunReport> {
    let points = selection.points(sweep)?;
    claim::claim(sweep, dir)?;
    run_selected(&points, dir, opts, Vec::new())
}

/// Runs point `id` (or a unique prefix of it) of the sweep file `file` in `dir`. When
/// `dir` holds this sweep already (its `sweep.json` has the sweep's digest: every point
/// was checked when the sweep claimed the folder), only that point's scene is resolved
/// ([`Sweep::point_from_path`]: the cost of the ids, an MD5 a point); otherwise the
/// sweep is expanded whole and claims the folder first ([`run_points`]).
pub fn run_point_of_file(file: &Path, dir: &Path, id: &str, opts: Options) -> Result<RunReport> {
    let Some(found) = Sweep::point_from_path(file, id)? else {
        bail!("the sweep has no point {id:?} (see sweep.json)");
    };
    if super::record::SweepRecord::read_digest(dir)?.as_ref() == Some(&found.digest) {
        return run_selected(&[&found.point], dir, opts, Vec::new());
    }
    let sweep = Sweep::from_path(file)?;
    run_points(&sweep, dir, &Selection::Point(id.to_string()), opts)
}

/// Runs the `selection` of the sweep frozen in `dir` ([`frozen::load`]): neither the
/// sweep file nor its base scenes are read. A point whose frozen scene was changed is
/// refused (counted failed) and the others run.
pub fn run_frozen(dir: &Path, selection: &Selection, opts: Options) -> Result<RunReport> {
    let (_, points, refused) = frozen::load(dir, selection)?;
    for (id, why) in &refused {
        println!("{id}: REFUSED: {why}");
    }
    let points: Vec<&Point> = points.iter().collect();
    run_selected(&points, dir, opts, refused)
}

/// Runs `points` in `dir`; `refused` are counted failed.
fn run_selected(
    points: &[&Point],
    dir: &Path,
    opts: Options,
    refused: Vec<(String, String)>,
) -> Result<RunReport> {
    let report = Mutex::new(RunReport {
        selected: points.len() + refused.len(),
        failed: refused,
        ..RunReport::default()
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs.max(1))
        .build()?;
    pool.install(|| {
        points.par_iter().for_each(|p| {
            let outcome = match opts.stop.requested() {
                Some(_) => Outcome::NotStarted,
                None => run_point(p, dir, opts),
            };
            let mut r = report.lock().unwrap_or_else(|e| e.into_inner());
            r.tally(p, outcome);
        });
    });
    let mut report = report.into_inner().unwrap_or_else(|e| e.into_inner());
    report.signal = opts.stop.requested();
    Ok(report)
}

/// [`run_points`] of a sweep file.
pub fn run_sweep(
    file: &Path,
    dir: &Path,
    selection: &Selection,
    opts: Options,
) -> Result<RunReport> {
    let sweep = Sweep::from_path(file)?;
    run_points(&sweep, dir, selection, opts)
}
