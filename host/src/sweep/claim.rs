//! One sweep per folder. A sweep claims its folder before it writes anything there:
//! under the folder's lock, a folder without `sweep.json` becomes this sweep's (its
//! frozen scenes, the signac project files, then `sweep.json` last), a folder whose
//! `sweep.json` has this sweep's digest is this sweep's already (as is one an older
//! host-demo wrote, without a digest, for the same point ids: each point's
//! `scene.toml` is still checked before the point is touched), and any other is
//! refused with [`AnotherSweep`], nothing written: two sweeps never mix in one folder,
//! and the first one's files stay as they were.

use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::record::SweepRecord;
use super::{POINTS, SWEEP_JSON, Sweep, frozen};
use crate::output::{FolderLock, write_atomic, write_json};

/// The folder holds another sweep.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AnotherSweep {
    /// The folder.
    pub dir: PathBuf,
    /// Points and digest of the sweep recorded there.
    pub theirs: (usize, Option<String>),
    /// Points and digest of the sweep refused.
    pub ours: (usize, String),
    /// Whether the two have the same point ids (the same parameters): then the scenes
    /// differ elsewhere (the base scene, or a value the parameters leave alone).
    pub same_ids: bool,
}

impl fmt::Display for AnotherSweep {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = self.dir.display();
        write!(
            f,
            "{d} holds another sweep ({} points, digest {} in {d}/{SWEEP_JSON}; this one has {} points, digest {}): ",
            self.theirs.0,
            self.theirs
                .1
                .as_deref()
                .unwrap_or("none: an older hydrorattle-host wrote it"),
            self.ours.0,
            self.ours.1
        )?;
        if self.same_ids {
            write!(
                f,
                "the same parameters over other scenes (the base scene changed?). "
            )?;
        }
        write!(
            f,
            "A folder holds one sweep: nothing was written. Give this one its own --out; to go on with the one in {d} as it was emitted, run its frozen points (`sweep --frozen --out {d}`)"
        )
    }
}

impl std::error::Error for AnotherSweep {}

/// Makes `dir` the folder of `sweep`, or refuses ([`AnotherSweep`]) before writing.
pub fn claim(sweep: &Sweep, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    // Held while the record is read and written: two first processes of two sweeps
    // cannot both find the folder free.
    let _lock = FolderLock::wait(dir)?;
    if let Some(r) = SweepRecord::read(dir)? {
        if r.digest.as_deref() == Some(sweep.digest.as_str()) {
            return Ok(());
        }
        let same_ids = r.points.len() == sweep.points.len()
            && r.points
                .iter()
                .zip(&sweep.points)
                .all(|(a, b)| a.id == b.id);
        // A record of an older hydrorattle-host (format 1, no digest) with the same points is
        // adopted: each point's scene.toml is still checked before it is touched.
        if !(r.digest.is_none() && same_ids) {
            return Err(AnotherSweep {
                dir: dir.to_path_buf(),
                theirs: (r.count, r.digest),
                ours: (sweep.points.len(), sweep.digest.clone()),
                same_ids,
            }
            .into());
        }
    }
    std::fs::create_dir_all(dir.join(POINTS))
        .with_context(|| format!("creating {}", dir.join(POINTS).display()))?;
    let digests = frozen::freeze(sweep, dir)?;
    signac_project(dir)?;
    // Last: its presence says the frozen copy is whole.
    write_json(&dir.join(SWEEP_JSON), &sweep.record(&digests))?;
    Ok(())
}

/// The signac project files: `.signac/config`, and `workspace` linked to `points`.
fn signac_project(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir.join(".signac"))?;
    write_atomic(&dir.join(".signac/config"), b"schema_version = 2\n")?;
    let link = dir.join("workspace");
    if std::fs::symlink_metadata(&link).is_err() {
        #[cfg(unix)]
        if let Err(e) = std::os::unix::fs::symlink(POINTS, &link)
            && std::fs::symlink_metadata(&link).is_err()
        {
            log::warn!("{}: cannot link to {POINTS}: {e}", link.display());
        }
    }
    Ok(())
}
