//! Where a point's folder stands, from whatever files it holds: any mix of present and
//! missing files (a run killed, stopped, cut, or files deleted by hand) leads to a
//! finished point, a resume that ends as an uninterrupted run, or a clean restart.
//!
//! * *Foreign*: a `scene.toml` that is not the point's (another sweep's, or a run
//!   resumed by hand to another time): never touched.
//! * *Finished*: the point's `scene.toml` and a `summary.json` whose data files are
//!   those it records (size and digest).
//! * *Damaged*: a `summary.json` whose data files are not those it records (a byte
//!   changed, a file cut or copied over since the run finished), or one that cannot be
//!   read: run from the start. A checkpoint marks how many bytes of each file it
//!   continues, not what they hold, so resuming would keep the damaged bytes and vouch
//!   for them in a new summary.
//! * *Resumable*: the point's `scene.toml`, a readable `checkpoint.json` before the last
//!   step or at it (one that records its step's solve, for the closing row), and each
//!   data file (its `.tmp` or final name) holding at least the bytes the checkpoint
//!   marks.
//! * *New*: anything else (no `scene.toml`, no usable checkpoint, a data file short
//!   or missing): the run files are removed and the point runs from the start.

use std::collections::BTreeMap;
use std::path::Path;

use crate::output::{FileCheck, continued_source, mismatch};
use crate::scene::Scene;
use crate::sim::{
    CHECKPOINT, Checkpoint, OBSERVABLES_CSV, SCENE_TOML, SUMMARY_JSON, TRAJECTORY_GSD,
    TRAJECTORY_XYZ,
};

/// Where a point stands.
pub(super) enum State {
    /// Another scene is in the folder (why).
    Foreign(String),
    /// Done: nothing to run.
    Finished,
    /// Continue from this checkpoint.
    Resumable(Box<Checkpoint>),
    /// Run from the start.
    New,
}

/// The state of the folder `pdir` of a point whose `scene.toml` is `scene_text`
/// (`scene` is that scene, its level applied).
pub(super) fn state(pdir: &Path, scene_text: &str, scene: &Scene) -> State {
    match std::fs::read(pdir.join(SCENE_TOML)) {
        Ok(t) if t == scene_text.as_bytes() => {}
        Ok(_) => {
            return State::Foreign(format!(
                "{} is not this point's scene (another sweep, or a resume to another time, wrote it): the folder is left as it is; remove it to run the point here",
                pdir.join(SCENE_TOML).display()
            ));
        }
        Err(_) => return State::New,
    }
    match summary(pdir) {
        Summary::Vouches => return State::Finished,
        Summary::Damaged => return State::New,
        Summary::None => {}
    }
    match Checkpoint::load(pdir) {
        Ok(c) if resumable(pdir, &c, scene) => State::Resumable(Box::new(c)),
        _ => State::New,
    }
}

/// What a point's `summary.json` says of its data files.
enum Summary {
    /// They are those it records: the point is finished.
    Vouches,
    /// They are not (or the summary cannot be read): changed since the run finished.
    Damaged,
    /// No summary, or one without a files record (an older one vouches for nothing).
    None,
}

fn summary(pdir: &Path) -> Summary {
    let text = match std::fs::read(pdir.join(SUMMARY_JSON)) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Summary::None,
        Err(_) => return Summary::Damaged,
    };
    let Ok(summary) = serde_json::from_slice::<serde_json::Value>(&text) else {
        return Summary::Damaged;
    };
    let Some(files) = summary.get("files") else {
        return Summary::None;
    };
    match serde_json::from_value::<BTreeMap<String, FileCheck>>(files.clone()) {
        Ok(f) if !f.is_empty() && mismatch(pdir, &f).is_none() => Summary::Vouches,
        _ => Summary::Damaged,
    }
}

/// A checkpoint of this scene before its last step, whose files hold what it marks.
fn resumable(pdir: &Path, c: &Checkpoint, scene: &Scene) -> bool {
    // At the last step: resumed to write the closing row, from the step's solve that
    // the checkpoint records (an older one does not: run again).
    let steps = scene.integrator.steps() as u64;
    if c.precision != scene.integrator.precision
        || c.step > steps
        || (c.step == steps && c.last_step.is_none())
    {
        return false;
    }
    let gsd = crate::output::gsd::data_end(&scene.topology(), c.marks.frames);
    [
        (TRAJECTORY_XYZ, c.marks.xyz_bytes),
        (OBSERVABLES_CSV, c.marks.csv_bytes),
        (TRAJECTORY_GSD, gsd),
    ]
    .iter()
    .all(|&(name, keep)| {
        let source = continued_source(&pdir.join(name), keep);
        std::fs::metadata(source).is_ok_and(|m| m.is_file() && m.len() >= keep)
    })
}

/// Whether `name` is one of the files a run leaves in a point's folder (removed before
/// a run from the start).
pub(super) const RUN_FILES: [&str; 6] = [
    SUMMARY_JSON,
    CHECKPOINT,
    OBSERVABLES_CSV,
    TRAJECTORY_XYZ,
    TRAJECTORY_GSD,
    super::run::ERROR_TXT,
];
