//! The engines a sweep runs on: a SLURM array job, a GNU parallel command, a row
//! workflow. Each task runs `host-demo sweep FILE --out DIR` on its shard or point,
//! so the points come out the same whichever engine ran them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::{POINTS, STATEPOINT_JSON, Sweep, run::prepare_points};
use crate::sim::SUMMARY_JSON;

/// SLURM's default largest array index is 1000 (`MaxArraySize = 1001`): an array job
/// has at most this many tasks unless asked otherwise.
pub const DEFAULT_MAX_TASKS: usize = 1000;

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

/// The array job's settings.
#[derive(Debug, Clone, Default)]
pub struct SlurmOptions {
    /// Array tasks (shards); None: one per point, at most [`DEFAULT_MAX_TASKS`].
    pub tasks: Option<usize>,
    /// At most this many tasks at once (`%M`).
    pub throttle: Option<usize>,
    /// Partition.
    pub partition: Option<String>,
    /// Time limit per task (`HH:MM:SS`, `D-HH:MM:SS` or minutes).
    pub time: Option<String>,
    /// CPUs per task (points run at once in a task).
    pub cpus: usize,
    /// The `host-demo` the tasks run (default: this program), for nodes where it is
    /// installed elsewhere.
    pub program: Option<PathBuf>,
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

/// Writes the sweep's folder (`sweep.json`, the points' state points and scenes) and the
/// engine's file in `dir`; returns the file and the command that starts it.
pub fn emit(
    engine: Engine,
    sweep: &Sweep,
    file: &Path,
    dir: &Path,
    slurm: &SlurmOptions,
) -> Result<(PathBuf, String)> {
    prepare_points(sweep, dir)?;
    let exe = match &slurm.program {
        Some(p) => p.clone(),
        None => absolute(&std::env::current_exe().context("finding this program")?)?,
    };
    let (file, dir) = (absolute(file)?, absolute(dir)?);
    let base = format!(
        "{} sweep {} --out {}",
        sh(&exe.display().to_string()),
        sh(&file.display().to_string()),
        sh(&dir.display().to_string())
    );
    let n = sweep.points.len();
    match engine {
        Engine::Slurm => {
            let tasks = slurm
                .tasks
                .unwrap_or(n.min(DEFAULT_MAX_TASKS))
                .clamp(1, n.max(1));
            let throttle = slurm.throttle.map_or(String::new(), |m| format!("%{m}"));
            let logs = dir.join("slurm");
            std::fs::create_dir_all(&logs)?;
            let mut s = String::from("#!/bin/bash\n");
            s += &format!(
                "# {n} points of {} in {tasks} array tasks: task K runs shard K/{tasks} (the points whose\n\
                 # index is K modulo {tasks}), skipping finished points and resuming unfinished ones,\n\
                 # so the job can be resubmitted as it is after a time limit or a failure.\n\
                 # Submit: sbatch {}\n",
                file.display(),
                dir.join("slurm.sh").display()
            );
            s += "#SBATCH --job-name=hydrorattle-sweep\n";
            s += &format!("#SBATCH --array=0-{}{throttle}\n", tasks - 1);
            s += "#SBATCH --ntasks=1\n";
            s += &format!("#SBATCH --cpus-per-task={}\n", slurm.cpus.max(1));
            if let Some(t) = &slurm.time {
                s += &format!("#SBATCH --time={t}\n");
            }
            if let Some(p) = &slurm.partition {
                s += &format!("#SBATCH --partition={p}\n");
            }
            s += &format!("#SBATCH --output={}/%A_%a.out\n", logs.display());
            s += "set -euo pipefail\n";
            s += &format!(
                "exec {base} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\"\n"
            );
            let path = dir.join("slurm.sh");
            write_script(&path, &s)?;
            Ok((
                path.clone(),
                format!("sbatch {}", sh(&path.display().to_string())),
            ))
        }
        Engine::Parallel => {
            let ids = dir.join("point_ids.txt");
            let list: String = sweep.points.iter().map(|p| format!("{}\n", p.id)).collect();
            std::fs::write(&ids, list).with_context(|| format!("writing {}", ids.display()))?;
            let line = format!(
                "parallel --jobs {} --joblog {} -q {base} --point {{}} --jobs 1 :::: {}",
                slurm.cpus.max(1),
                sh(&dir.join("parallel.log").display().to_string()),
                sh(&ids.display().to_string())
            );
            let path = dir.join("parallel.sh");
            write_script(
                &path,
                &format!(
                    "#!/bin/bash\n# {n} points of {}, one GNU parallel job each.\nset -euo pipefail\n{line}\n",
                    file.display()
                ),
            )?;
            Ok((path, line))
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
            let path = dir.join("workflow.toml");
            std::fs::write(&path, s).with_context(|| format!("writing {}", path.display()))?;
            Ok((
                path,
                format!("cd {} && row submit", sh(&dir.display().to_string())),
            ))
        }
    }
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
