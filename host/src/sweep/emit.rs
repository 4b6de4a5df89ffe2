//! The engines a sweep runs on: a SLURM array job, a GNU parallel command, a row
//! workflow. Each task runs `host-demo sweep --frozen --out DIR` on its shard or point:
//! the points frozen in `DIR` when the job was emitted ([`super::frozen`]), whatever
//! happens to the sweep file and its base scenes after, so the points come out the same
//! whichever engine ran them, and as emitted.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use super::cluster::{ArrayJob, DEFAULT_JOB_NAME, SIGNAL_LEAD_S, SLURM_JSON, infinite};
pub use super::cluster::{DEFAULT_MAX_TASKS, SlurmOptions};
use super::{POINTS, STATEPOINT_JSON, Sweep, run::prepare_points};
use crate::output::write_json;
use crate::sim::SUMMARY_JSON;

/// Which engine to write for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Engine {
    /// `DIR/slurm.sh`: an `sbatch --array` job script, one shard per task.
    Slurm,
    /// `DIR/parallel.sh`: a GNU parallel command line, one point per job.
    Parallel,
    /// `DIR/workflow.toml`: a row workflow, one point per directory.
    Row,
}

impl Engine {
    /// Every engine with its name, as `--emit` spells it.
    pub const ALL: [(&'static str, Engine); 3] = [
        ("slurm", Engine::Slurm),
        ("parallel", Engine::Parallel),
        ("row", Engine::Row),
    ];

    /// The engine named `name`; the error lists the names.
    pub fn from_name(name: &str) -> Result<Engine, String> {
        Self::ALL
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(_, e)| e)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|(n, _)| *n).collect();
                format!("unknown engine {name:?} (one of: {})", names.join(", "))
            })
    }
}

/// Quotes `s` for a POSIX shell.
fn sh(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "/._-+=:,@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).with_context(|| format!("resolving {}", p.display()))
}

/// An engine's job file as [`emit`] writes it, and what else it writes beside it.
#[derive(Debug, Clone)]
pub struct JobFile {
    /// Where it goes.
    pub path: PathBuf,
    /// Its text.
    pub text: String,
    /// The command that starts it.
    pub command: String,
    /// The array job's record ([`SLURM_JSON`]), for SLURM.
    array: Option<ArrayJob>,
    /// The ids list GNU parallel reads (`DIR/point_ids.txt`), for parallel.
    ids: Option<(PathBuf, String)>,
}

/// The engine's job file for `sweep` (read from `file`) in `dir`, every setting
/// checked: nothing is written (what `--emit ENGINE --dry-run` prints).
pub fn job_file(
    engine: Engine,
    sweep: &Sweep,
    file: &Path,
    dir: &Path,
    slurm: &SlurmOptions,
) -> Result<JobFile> {
    let n = sweep.points.len();
    let tasks = slurm.check(n)?;
    if engine == Engine::Row && slurm.time.as_deref().is_some_and(infinite) {
        bail!("--time infinite: row's walltime is a finite time (HH:MM:SS or D-HH:MM:SS)");
    }
    let exe = match &slurm.program {
        Some(p) => p.clone(),
        None => absolute(&std::env::current_exe().context("finding this program")?)?,
    };
    let (file, dir) = (absolute(file)?, absolute(dir)?);
    let verbose = match slurm.verbose {
        0 => String::new(),
        v => format!(" -{}", "v".repeat(usize::from(v.min(3)))),
    };
    let every = slurm
        .checkpoint_every
        .map_or(String::new(), |t| format!(" --checkpoint-every {t}"));
    let base = format!(
        "{}{verbose} sweep --frozen --out {}{every}",
        sh(&exe.display().to_string()),
        sh(&dir.display().to_string())
    );
    let job = |path: PathBuf, text: String, command: String| JobFile {
        path,
        text,
        command,
        array: None,
        ids: None,
    };
    Ok(match engine {
        Engine::Slurm => {
            let path = dir.join("slurm.sh");
            let text = slurm_script(slurm, tasks, n, &file, &dir, &path, &base);
            let command = format!("sbatch {}", sh(&path.display().to_string()));
            JobFile {
                array: Some(ArrayJob {
                    tasks,
                    throttle: slurm.throttle,
                    script: path.clone(),
                }),
                ..job(path, text, command)
            }
        }
        Engine::Parallel => {
            let ids = dir.join("point_ids.txt");
            let list: String = sweep.points.iter().map(|p| format!("{}\n", p.id)).collect();
            let line = format!(
                "parallel --jobs {} --joblog {} -q {base} --point {{}} --jobs 1 :::: {}",
                slurm.cpus.max(1),
                sh(&dir.join("parallel.log").display().to_string()),
                sh(&ids.display().to_string())
            );
            let text = format!(
                "#!/bin/bash\n# {n} points of {}, one GNU parallel job each.\nset -euo pipefail\n{line}\n",
                file.display()
            );
            JobFile {
                ids: Some((ids, list)),
                ..job(dir.join("parallel.sh"), text, line)
            }
        }
        Engine::Row => {
            let command = format!("{base} --point {{directory}}");
            let mut s = format!(
                "# row reads this sweep's folder as a project: one directory per point, its\n\
                 # value the signac state point. Run: row submit (in {})\n",
                dir.display()
            );
            s += &format!(
                "[workspace]\npath = \"{POINTS}\"\nvalue_file = \"{STATEPOINT_JSON}\"\n\n"
            );
            s += &format!(
                "[[action]]\nname = \"run\"\ncommand = {}\nproducts = [\"{SUMMARY_JSON}\"]\n",
                toml::Value::String(command)
            );
            if let Some(t) = &slurm.time {
                s += &format!("resources.walltime.per_directory = {:?}\n", t);
            }
            let start = format!("cd {} && row submit", sh(&dir.display().to_string()));
            job(dir.join("workflow.toml"), s, start)
        }
    })
}

/// `DIR/slurm.sh`: `tasks` array tasks over the `n` points of `file` in `dir`, each
/// running `base` on its shard.
fn slurm_script(
    slurm: &SlurmOptions,
    tasks: usize,
    n: usize,
    file: &Path,
    dir: &Path,
    path: &Path,
    base: &str,
) -> String {
    let throttle = slurm.throttle.map_or(String::new(), |m| format!("%{m}"));
    let lead = slurm.signal_lead.unwrap_or(SIGNAL_LEAD_S);
    let mut s = String::from("#!/bin/bash\n");
    s += &format!(
        "# {n} points of {} (frozen in {} when emitted) in {tasks} array tasks: task K runs\n\
         # shard K/{tasks} (the points whose index is K modulo {tasks}), skipping finished points\n\
         # and resuming unfinished ones. SIGTERM (the time limit, {lead} s ahead, or scancel)\n\
         # checkpoints the running points; `host-demo collect {}` prints the sbatch line\n\
         # that reruns the tasks left unfinished.\n\
         # Submit: sbatch {}\n",
        file.display(),
        dir.display(),
        dir.display(),
        path.display()
    );
    let name = slurm.job_name.as_deref().unwrap_or(DEFAULT_JOB_NAME);
    s += &format!("#SBATCH --job-name={name}\n");
    s += &format!("#SBATCH --array=0-{}{throttle}\n", tasks - 1);
    s += "#SBATCH --ntasks=1\n";
    s += &format!("#SBATCH --cpus-per-task={}\n", slurm.cpus.max(1));
    for (name, v) in [
        ("time", &slurm.time),
        ("partition", &slurm.partition),
        ("mem", &slurm.mem),
        ("account", &slurm.account),
        ("qos", &slurm.qos),
        ("constraint", &slurm.constraint),
    ] {
        if let Some(v) = v {
            s += &format!("#SBATCH --{name}={v}\n");
        }
    }
    for extra in &slurm.extra {
        s += &format!("#SBATCH {extra}\n");
    }
    s += &format!("#SBATCH --signal=B:TERM@{lead}\n");
    s += &format!(
        "#SBATCH --output={}/%A_%a.out\n",
        dir.join("slurm").display()
    );
    s += "set -euo pipefail\n";
    // exec: host-demo is the batch shell, which the B: signal reaches.
    s += &format!(
        "exec {base} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\"\n"
    );
    s
}

/// Writes the sweep's folder (`sweep.json`, the points' state points and scenes) and the
/// engine's file in `dir` ([`job_file`]); returns the file and the command that starts it.
pub fn emit(
    engine: Engine,
    sweep: &Sweep,
    file: &Path,
    dir: &Path,
    slurm: &SlurmOptions,
) -> Result<(PathBuf, String)> {
    // Every setting checked before anything is written.
    let job = job_file(engine, sweep, file, dir, slurm)?;
    prepare_points(sweep, dir)?;
    let dir = absolute(dir)?;
    if let Some((ids, list)) = &job.ids {
        std::fs::write(ids, list).with_context(|| format!("writing {}", ids.display()))?;
    }
    match engine {
        Engine::Row => std::fs::write(&job.path, &job.text)
            .with_context(|| format!("writing {}", job.path.display()))?,
        _ => write_script(&job.path, &job.text)?,
    }
    if let Some(array) = &job.array {
        std::fs::create_dir_all(dir.join("slurm"))?;
        write_json(&dir.join(SLURM_JSON), array)?;
    }
    Ok((job.path, job.command))
}

fn write_script(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))?;
    }
    Ok(())
}
