//! The examples' measurements as rows of `bench/results/*.csv`, appended by the example
//! that measured them (shared by `#[path]`). The columns are docs/BENCHMARKS.md's
//! "Records": date, commit, machine, load, command, measurement, case, quantity, value.
//!
//! Rows are appended only where `HYDRORATTLE_BENCH_MACHINE` names the machine (an id of
//! the page's "Machines" table, which the docs test checks every row against); without
//! it the example prints its numbers and records nothing, so a trial run leaves the
//! records alone. `bench/record.py` writes the same rows for the Python scripts.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The variable that names the machine and turns recording on.
pub const MACHINE: &str = "HYDRORATTLE_BENCH_MACHINE";
/// The columns, in order.
pub const HEADER: &str = "date,commit,machine,load,command,measurement,case,quantity,value";

/// The rows of one run of an example, appended to its file by [`Recorder::finish`].
pub struct Recorder {
    file: PathBuf,
    command: String,
    machine: Option<String>,
    load_at_start: Option<f64>,
    rows: Vec<[String; 4]>,
    written: usize,
}

impl Recorder {
    /// A recorder for `bench/results/{name}.csv` of the repository that holds
    /// `manifest_dir` (the including crate's `CARGO_MANIFEST_DIR`), for rows measured by
    /// `command` (with the arguments it ran with).
    pub fn new(manifest_dir: &str, name: &str, command: String) -> Recorder {
        let root = git(manifest_dir, &["rev-parse", "--show-toplevel"])
            .map_or_else(|| PathBuf::from(manifest_dir), PathBuf::from);
        // A debug build's times are not the release build's the command names.
        let command = match cfg!(debug_assertions) {
            true => format!("{command} (debug build)"),
            false => command,
        };
        Recorder {
            file: root.join("bench/results").join(format!("{name}.csv")),
            command,
            machine: std::env::var(MACHINE).ok().filter(|m| !m.is_empty()),
            load_at_start: load(),
            rows: Vec::new(),
            written: 0,
        }
    }

    /// One cell of a measured table: the table (`measurement`), its row (`case`), its
    /// column (`quantity`) and the value with its unit.
    pub fn row(&mut self, measurement: &str, case: &str, quantity: &str, value: &str) {
        self.rows
            .push([measurement, case, quantity, value].map(str::to_string));
    }

    /// Appends the rows so far and starts a new batch, so that a long run keeps what it
    /// measured if it is stopped (each batch's load is the one-minute load average at
    /// its start and its end). Without a machine it keeps the rows for
    /// [`Recorder::finish`] to report.
    #[allow(dead_code)] // Most examples record once, at their end.
    pub fn flush(&mut self) -> std::io::Result<()> {
        let Some(machine) = self.machine.as_deref() else {
            return Ok(());
        };
        if self.rows.is_empty() {
            return Ok(());
        }
        let dir = self.file.parent().unwrap_or(Path::new("."));
        let commit =
            git(&dir.to_string_lossy(), &["rev-parse", "--short=7", "HEAD"]).unwrap_or_default();
        let end = load();
        let load = match (self.load_at_start, end) {
            (Some(a), Some(b)) if format!("{a:.1}") != format!("{b:.1}") => {
                format!("{:.1}-{:.1}", a.min(b), a.max(b))
            }
            (Some(a), _) => format!("{a:.1}"),
            _ => String::new(),
        };
        let mut text = String::new();
        if !self.file.exists() {
            text.push_str(HEADER);
            text.push('\n');
        }
        for r in &self.rows {
            let fields = [
                today(),
                commit.clone(),
                machine.to_string(),
                load.clone(),
                self.command.clone(),
            ]
            .into_iter()
            .chain(r.iter().cloned())
            .map(|f| quoted(&f))
            .collect::<Vec<_>>();
            text.push_str(&fields.join(","));
            text.push('\n');
        }
        // One write of whole lines: a row is never left half written.
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&self.file)?
            .write_all(text.as_bytes())?;
        self.written += self.rows.len();
        self.rows.clear();
        self.load_at_start = end;
        Ok(())
    }

    /// Appends the rows not yet appended (the load is the one-minute load average at
    /// the start and the end of the run, or of the batch since the last
    /// [`Recorder::flush`]); says where, or why nothing was recorded.
    pub fn finish(mut self) -> std::io::Result<()> {
        if self.machine.is_none() {
            eprintln!(
                "not recorded: set {MACHINE} to this machine's id in docs/BENCHMARKS.md to append these rows to {}",
                self.file.display()
            );
            return Ok(());
        }
        self.flush()?;
        eprintln!("recorded {} rows in {}", self.written, self.file.display());
        Ok(())
    }
}

/// A CSV field, quoted when it holds a comma, a quote or a line break (RFC 4180).
fn quoted(field: &str) -> String {
    if field.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_string()
    }
}

/// The one-minute load average (Linux `/proc/loadavg`), `None` elsewhere.
fn load() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Today's date (UTC), `YYYY-MM-DD`: the civil date of the days since 1970-01-01.
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// The trimmed output of a successful `git -C dir ARGS`.
fn git(dir: &str, args: &[&str]) -> Option<String> {
    let o = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .ok()?;
    let s = String::from_utf8(o.stdout).ok()?;
    (o.status.success() && !s.trim().is_empty()).then(|| s.trim().to_string())
}
