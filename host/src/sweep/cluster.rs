//! The array job's settings, checked before anything is written (a value SLURM would
//! refuse at submission, or one that makes no sense for the sweep, is refused here, by
//! name), and the array indices that rerun only the unfinished points.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// SLURM's default largest array index is 1000 (`MaxArraySize = 1001`): an array job
/// has at most this many tasks unless asked otherwise.
pub const DEFAULT_MAX_TASKS: usize = 1000;

/// Seconds before the time limit at which SLURM sends the batch shell (`host-demo`
/// itself, by `exec`) SIGTERM (`--signal=B:TERM@60`) unless asked otherwise: time for
/// the running steps to end and the points to checkpoint.
pub const SIGNAL_LEAD_S: u32 = 60;

/// The most seconds `--signal` takes (SLURM's limit).
const MAX_SIGNAL_LEAD_S: u32 = 65535;

/// The job's name unless asked otherwise.
pub const DEFAULT_JOB_NAME: &str = "hydrorattle-sweep";

/// The `sbatch` options the script writes itself, long and short: given again as an
/// extra option they would contradict it (the dedicated flag, named, sets them).
const OWN_OPTIONS: [(&str, Option<char>, &str); 12] = [
    ("job-name", Some('J'), "--job-name"),
    ("array", Some('a'), "--tasks and --throttle"),
    ("ntasks", Some('n'), "nothing: one process a task"),
    ("cpus-per-task", Some('c'), "--cpus"),
    ("time", Some('t'), "--time"),
    ("partition", Some('p'), "--partition"),
    ("mem", None, "--mem"),
    ("account", Some('A'), "--account"),
    ("qos", Some('q'), "--qos"),
    ("constraint", Some('C'), "--constraint"),
    ("signal", None, "--signal-lead"),
    ("output", Some('o'), "nothing: the logs go to DIR/slurm"),
];

/// The array job's settings.
#[derive(Debug, Clone, Default)]
pub struct SlurmOptions {
    /// Array tasks (shards); None: one per point, at most [`DEFAULT_MAX_TASKS`].
    pub tasks: Option<usize>,
    /// At most this many tasks at once (`%M`).
    pub throttle: Option<usize>,
    /// Partition.
    pub partition: Option<String>,
    /// Time limit per task (`MM`, `MM:SS`, `HH:MM:SS`, `D-HH`, `D-HH:MM`, `D-HH:MM:SS`,
    /// or `infinite`/`unlimited`).
    pub time: Option<String>,
    /// Memory per node (`--mem`: a whole number with an optional unit K, M, G or T and
    /// an optional B, in either case).
    pub mem: Option<String>,
    /// The job's name (default [`DEFAULT_JOB_NAME`]).
    pub job_name: Option<String>,
    /// Seconds before the time limit that SIGTERM comes (default [`SIGNAL_LEAD_S`]).
    pub signal_lead: Option<u32>,
    /// Further `sbatch` options, each written as an `#SBATCH` line as given
    /// (`--gres=gpu:1`, `--mail-type=END`, `--exclusive`).
    pub extra: Vec<String>,
    /// Account charged.
    pub account: Option<String>,
    /// Quality of service.
    pub qos: Option<String>,
    /// Node features required (`--constraint`).
    pub constraint: Option<String>,
    /// CPUs per task (points run at once in a task).
    pub cpus: usize,
    /// The `host-demo` the tasks run (default: this program), for nodes where it is
    /// installed elsewhere.
    pub program: Option<std::path::PathBuf>,
    /// Checkpoint interval (simulated time) the tasks pass on.
    pub checkpoint_every: Option<f64>,
    /// Log verbosity the tasks pass on (`-v` repeated).
    pub verbose: u8,
}

/// The array job's shape in the sweep's folder, for `collect` to name the tasks of the
/// unfinished points and the `sbatch --array` line that reruns them.
pub const SLURM_JSON: &str = "slurm.json";

/// What [`SLURM_JSON`] holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ArrayJob {
    /// Array tasks: task K runs the points whose index is K modulo this.
    pub tasks: usize,
    /// At most this many tasks at once, if limited.
    pub throttle: Option<usize>,
    /// The job script.
    pub script: PathBuf,
}

impl ArrayJob {
    /// The array job emitted into `dir`, if one was.
    pub fn read(dir: &Path) -> Result<Option<ArrayJob>> {
        let path = dir.join(SLURM_JSON);
        match std::fs::read_to_string(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            t => {
                let t = t.with_context(|| format!("reading {}", path.display()))?;
                let job = serde_json::from_str(&t)
                    .with_context(|| format!("{}: not an array job record", path.display()))?;
                Ok(Some(job))
            }
        }
    }

    /// The task that runs point `index`.
    pub fn task_of(&self, index: usize) -> usize {
        index % self.tasks.max(1)
    }

    /// `sbatch --array=...` that reruns the tasks of the points `indices` only (the
    /// script's throttle kept); None without points.
    pub fn rerun(&self, indices: &[usize]) -> Option<String> {
        let mut tasks: Vec<usize> = indices.iter().map(|&i| self.task_of(i)).collect();
        tasks.sort_unstable();
        tasks.dedup();
        if tasks.is_empty() {
            return None;
        }
        let throttle = self.throttle.map_or(String::new(), |m| format!("%{m}"));
        Some(format!(
            "sbatch --array={}{throttle} {}",
            array_ranges(&tasks),
            self.script.display()
        ))
    }
}

/// Whether `t` is SLURM's time limit without limit (`infinite` or `unlimited`, in any
/// case).
pub fn infinite(t: &str) -> bool {
    t.eq_ignore_ascii_case("infinite") || t.eq_ignore_ascii_case("unlimited")
}

/// A SLURM time limit: minutes, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S` (whole
/// numbers), or [`infinite`].
fn time_ok(t: &str) -> bool {
    let num = |s: &str| !s.is_empty() && s.len() <= 9 && s.bytes().all(|b| b.is_ascii_digit());
    if infinite(t) {
        return true;
    }
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    if days.is_some_and(|d| !num(d)) {
        return false;
    }
    let parts: Vec<&str> = rest.split(':').collect();
    // With days: hours, then at most minutes and seconds.
    parts.len() <= 3 && parts.iter().all(|p| num(p))
}

/// A `--mem` size: a whole number, an optional unit K, M, G or T, then an optional B
/// (either case).
fn mem_ok(m: &str) -> bool {
    let m = m
        .strip_suffix(['B', 'b'])
        .filter(|r| r.ends_with(|c: char| "KMGTkmgt".contains(c)))
        .unwrap_or(m);
    let digits = m.trim_end_matches(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't']);
    m.len() - digits.len() <= 1 && !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
}

/// Why an extra `sbatch` option is refused, or None.
fn extra_refused(x: &str) -> Option<String> {
    if !x.starts_with('-') || x == "-" || x == "--" {
        return Some("an sbatch option starts with - or -- (--gres=gpu:1)".into());
    }
    if x.chars().any(|c| c.is_control() || c == '#') {
        return Some("one option on one line, without #".into());
    }
    let (long, short) = match x.strip_prefix("--") {
        Some(rest) => (rest.split(['=', ' ']).next(), None),
        None => (None, x[1..].chars().next()),
    };
    OWN_OPTIONS
        .iter()
        .find(|(l, s, _)| long == Some(*l) || (short.is_some() && short == *s))
        .map(|(l, _, flag)| format!("the script sets --{l} itself (set by {flag})"))
}

impl SlurmOptions {
    /// The number of array tasks for `points` points, every setting checked first.
    pub fn check(&self, points: usize) -> Result<usize> {
        if self.cpus == 0 {
            bail!("--cpus 0: a task needs at least one CPU");
        }
        if self.throttle == Some(0) {
            bail!("--throttle 0 would run no task: give at least 1");
        }
        let tasks = match self.tasks {
            Some(0) => bail!("--tasks 0: an array job has at least one task"),
            Some(t) if t > points => bail!(
                "--tasks {t} is more than the sweep's {points} points: a task would have no point (give at most {points})"
            ),
            Some(t) => t,
            None => points.clamp(1, DEFAULT_MAX_TASKS),
        };
        if let Some(t) = &self.time
            && !time_ok(t)
        {
            bail!(
                "--time {t:?} is not a SLURM time limit: minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS or infinite"
            );
        }
        if let Some(m) = &self.mem
            && !mem_ok(m)
        {
            bail!(
                "--mem {m:?} is not a size: a whole number with an optional unit K, M, G or T and an optional B (4G, 4GB, 500M)"
            );
        }
        if let Some(s) = self.signal_lead
            && !(1..=MAX_SIGNAL_LEAD_S).contains(&s)
        {
            bail!("--signal-lead {s}: seconds from 1 to {MAX_SIGNAL_LEAD_S}");
        }
        for x in &self.extra {
            if let Some(why) = extra_refused(x) {
                bail!("--sbatch-arg {x:?}: {why}");
            }
        }
        for (flag, v) in [
            ("--partition", &self.partition),
            ("--account", &self.account),
            ("--qos", &self.qos),
            ("--constraint", &self.constraint),
            ("--job-name", &self.job_name),
        ] {
            if let Some(v) = v
                && (v.is_empty()
                    || v.chars()
                        .any(|c| c.is_whitespace() || c.is_control() || "'\"#\\".contains(c)))
            {
                bail!("{flag} {v:?}: a SLURM name without spaces, quotes or #");
            }
        }
        if let Some(c) = self.checkpoint_every
            && !(c.is_finite() && c > 0.0)
        {
            bail!("--checkpoint-every {c}: a positive time");
        }
        Ok(tasks)
    }
}

/// Array indices as SLURM writes them: runs of consecutive indices as `a-b`, joined by
/// commas (`0-3,7,9-10`); `indices` sorted.
pub fn array_ranges(indices: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut k = 0;
    while k < indices.len() {
        let start = indices[k];
        while k + 1 < indices.len() && indices[k + 1] == indices[k] + 1 {
            k += 1;
        }
        out.push(match indices[k] {
            end if end == start => start.to_string(),
            end => format!("{start}-{end}"),
        });
        k += 1;
    }
    out.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nonsense_is_refused_by_name() {
        let ok = SlurmOptions {
            cpus: 1,
            ..SlurmOptions::default()
        };
        assert_eq!(ok.check(8).unwrap(), 8);
        assert_eq!(ok.check(5000).unwrap(), DEFAULT_MAX_TASKS);
        let bad = |o: SlurmOptions, says: &str| {
            let e = o.check(8).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        };
        bad(
            SlurmOptions {
                tasks: Some(0),
                ..ok.clone()
            },
            "--tasks 0",
        );
        bad(
            SlurmOptions {
                tasks: Some(9),
                ..ok.clone()
            },
            "more than the sweep's 8 points",
        );
        bad(
            SlurmOptions {
                time: Some("banana".into()),
                ..ok.clone()
            },
            "not a SLURM time limit",
        );
        bad(
            SlurmOptions {
                mem: Some("4 GB".into()),
                ..ok.clone()
            },
            "not a size",
        );
        bad(
            SlurmOptions {
                account: Some("a b".into()),
                ..ok.clone()
            },
            "--account",
        );
        bad(
            SlurmOptions {
                throttle: Some(0),
                ..ok.clone()
            },
            "--throttle 0",
        );
        bad(
            SlurmOptions {
                cpus: 0,
                ..ok.clone()
            },
            "--cpus 0",
        );
        bad(
            SlurmOptions {
                signal_lead: Some(0),
                ..ok.clone()
            },
            "--signal-lead 0",
        );
        bad(
            SlurmOptions {
                job_name: Some("my job".into()),
                ..ok.clone()
            },
            "--job-name",
        );
        for (x, says) in [
            ("gres=gpu:1", "starts with -"),
            ("--mail-type=END\n#SBATCH --x", "one option on one line"),
            ("--array=0-3", "set by --tasks"),
            ("-J x", "set by --job-name"),
            ("--time=10", "set by --time"),
            ("--signal=USR1@30", "set by --signal-lead"),
        ] {
            bad(
                SlurmOptions {
                    extra: vec![x.into()],
                    ..ok.clone()
                },
                says,
            );
        }
        let extras = [
            "--gres=gpu:1",
            "--exclusive",
            "--mail-type=END,FAIL",
            "-x node3",
        ];
        let fine = SlurmOptions {
            extra: extras.map(String::from).to_vec(),
            signal_lead: Some(300),
            job_name: Some("mine".into()),
            ..ok.clone()
        };
        assert_eq!(fine.check(8).unwrap(), 8);
        for t in [
            "30",
            "30:00",
            "1:00:00",
            "2-0",
            "2-12:00",
            "1-00:00:00",
            "UNLIMITED",
            "infinite",
            "Infinite",
            "unlimited",
        ] {
            assert!(time_ok(t), "{t}");
        }
        for t in ["", "1:2:3:4", "1h", "-1", "1-", "a-1"] {
            assert!(!time_ok(t), "{t}");
        }
        for m in [
            "4G", "500", "500M", "1t", "4GB", "4gb", "500Mb", "2TB", "16k",
        ] {
            assert!(mem_ok(m), "{m}");
        }
        for m in ["", "G", "GB", "4B", "4GBB", "4.5G", "-4G", "4 GB"] {
            assert!(!mem_ok(m), "{m}");
        }
    }

    #[test]
    fn array_ranges_join_runs() {
        assert_eq!(array_ranges(&[0, 1, 2, 3, 7, 9, 10]), "0-3,7,9-10");
        assert_eq!(array_ranges(&[5]), "5");
        assert_eq!(array_ranges(&[]), "");
        let job = ArrayJob {
            tasks: 4,
            throttle: Some(2),
            script: "/d/slurm.sh".into(),
        };
        assert_eq!(job.task_of(13), 1);
        assert_eq!(
            job.rerun(&[13, 1, 2, 7, 3]).unwrap(),
            "sbatch --array=1-3%2 /d/slurm.sh"
        );
        assert_eq!(job.rerun(&[]), None);
    }
}
