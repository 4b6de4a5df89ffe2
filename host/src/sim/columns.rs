//! The columns of a run's `observables.csv` checked before a resumed run continues it:
//! a file of another version is refused with its mismatch named (no migration).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::record::COLUMNS;

/// An `observables.csv` whose columns are not the ones this program writes (a run of
/// another version: the wall's three columns came later), which a resumed run
/// cannot continue. [`check_columns`] returns it inside its `anyhow::Error`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnsMismatch {
    /// The file read.
    pub path: PathBuf,
    /// Its header's columns.
    pub found: Vec<String>,
    /// [`COLUMNS`] the file lacks.
    pub missing: Vec<String>,
    /// The file's columns that are not among [`COLUMNS`].
    pub unknown: Vec<String>,
}

impl std::fmt::Display for ColumnsMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {} columns where this program writes {}",
            self.path.display(),
            self.found.len(),
            COLUMNS.len()
        )?;
        for (what, names) in [("lacks", &self.missing), ("has unknown", &self.unknown)] {
            if !names.is_empty() {
                write!(f, "; it {what} {}", names.join(", "))?;
            }
        }
        if self.missing.is_empty() && self.unknown.is_empty() {
            write!(f, " (in another order)")?;
        }
        write!(
            f,
            ": the run was written by another version of hydrorattle-host (this is {}); resume \
             it with that version, or run its scene.toml again",
            crate::provenance::CODE_VERSION
        )
    }
}

impl std::error::Error for ColumnsMismatch {}

/// Checks that the header of the `observables.csv` at `path` is [`COLUMNS`]: a resumed
/// run appends rows of these columns. Anything else is a [`ColumnsMismatch`].
pub fn check_columns(path: &Path) -> Result<()> {
    use std::io::BufRead;
    let file = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let mut header = String::new();
    std::io::BufReader::new(file)
        .read_line(&mut header)
        .with_context(|| format!("reading {}", path.display()))?;
    let found: Vec<String> = header.trim_end().split(',').map(str::to_string).collect();
    if found.iter().map(String::as_str).eq(COLUMNS) {
        return Ok(());
    }
    let lacks = |list: &[String], name: &str| !list.iter().any(|c| c == name);
    Err(ColumnsMismatch {
        path: path.to_path_buf(),
        missing: (COLUMNS.iter())
            .filter(|c| lacks(&found, c))
            .map(|c| c.to_string())
            .collect(),
        unknown: (found.iter())
            .filter(|c| !COLUMNS.contains(&c.as_str()))
            .cloned()
            .collect(),
        found,
    }
    .into())
}
