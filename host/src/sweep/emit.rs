//! The engines a sweep runs on: a SLURM array job, a GNU parallel command, a row
//! workflow. Each task runs `host-demo sweep --frozen --out DIR` on its shard or point:
//! the points frozen in `DIR` when the job was emitted ([`super::frozen`]), whatever
//! happens to the sweep file and its base scenes after, so the points come out the same
//! whichever engine ran them, and as emitted.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::cluster::{ArrayJob, SIGNAL_LEAD_S, SLURM_JSON};
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

/// Writes the sweep's folder (`sweep.json`, the points' state points and scenes) and the
/// engine's file in `dir`; returns the file and the command that starts it.
pub fn emit(
    engine: Engine,
    sweep: &Sweep,
    file: &Path,
    dir: &Path,
    slurm: &SlurmOptions,
) -> Result<(PathBuf, String)> {
    let n = sweep.points.len();
    // Every setting checked before anything is written.
    let tasks = slurm.check(n)?;
    prepare_points(sweep, dir)?;
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
    match engine {
        Engine::Slurm => {
            let throttle = slurm.throttle.map_or(String::new(), |m| format!("%{m}"));
            let logs = dir.join("slurm");
            std::fs::create_dir_all(&logs)?;
            let path = dir.join("slurm.sh");
            let mut s = String::from("#!/bin/bash\n");
            s += &format!(
                "# {n} points of {} (frozen in {} when emitted) in {tasks} array tasks: task K runs\n\
                 # shard K/{tasks} (the points whose index is K modulo {tasks}), skipping finished points\n\
                 # and resuming unfinished ones. SIGTERM (the time limit, {SIGNAL_LEAD_S} s ahead, or scancel)\n\
                 # checkpoints the running points; `host-demo collect {}` prints the sbatch line\n\
                 # that reruns the tasks left unfinished.\n\
                 # Submit: sbatch {}\n",
                file.display(),
                dir.display(),
                dir.display(),
                path.display()
            );
            s += "#SBATCH --job-name=hydrorattle-sweep\n";
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
            s += &format!("#SBATCH --signal=B:TERM@{SIGNAL_LEAD_S}\n");
            s += &format!("#SBATCH --output={}/%A_%a.out\n", logs.display());
            s += "set -euo pipefail\n";
            // exec: host-demo is the batch shell, which the B: signal reaches.
            s += &format!(
                "exec {base} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\"\n"
            );
            write_script(&path, &s)?;
            let job = ArrayJob {
                tasks,
                throttle: slurm.throttle,
                script: path.clone(),
            };
            write_json(&dir.join(SLURM_JSON), &job)?;
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
