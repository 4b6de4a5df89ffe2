//! A sweep folder belongs to one sweep: a second sweep into
//! it is refused and the first one's files stay byte for byte; the points run from the
//! copy frozen when the job was emitted, whatever happens to the base scene after, and a
//! frozen scene changed since is refused; nonsense job settings are refused before
//! anything is written; SIGTERM checkpoints a sweep, which then ends equal to a clean
//! run; bad sweep files are said at their line.

use crate::common::{BIN, cli, ok, text};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../host/scenes")
        .join(name)
}

/// A sweep file `name` in `dir` over `base` with `body` after `[sweep]`.
fn sweep_file(dir: &Path, name: &str, base: &Path, body: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!("[sweep]\nbase = {:?}\n{body}", base.display().to_string());
    std::fs::write(&path, text).unwrap();
    path
}

/// Every file under `dir` (recursively, links not followed) with its bytes.
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let m = std::fs::symlink_metadata(&p).unwrap();
            if m.is_dir() {
                todo.push(p);
            } else if m.is_file() {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

/// The files of the points under `a` and `b` equal (summary.json apart from its
/// execution fields); the number compared.
fn same_points(a: &Path, b: &Path) -> usize {
    let (fa, fb) = (files(&a.join("points")), files(&b.join("points")));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "different files"
    );
    for (name, x) in &fa {
        let y = &fb[name];
        if name.ends_with("summary.json") {
            let strip = |bytes: &[u8]| {
                let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
                for k in ["wall_time_s", "steps_per_second", "machine", "resumed_from"] {
                    v.as_object_mut().unwrap().remove(k);
                }
                v
            };
            assert_eq!(strip(x), strip(y), "{name:?}");
        } else {
            assert!(x == y, "{name:?} differs");
        }
    }
    fa.len()
}

#[test]
fn a_second_sweep_into_one_folder_is_refused_and_the_first_stays_byte_for_byte() {
    let dir = empty_dir!("two");
    let body = "\"integrator.duration\" = [2.0]\n\"integrator.dt\" = [0.1, 0.05]\n";
    let chain = sweep_file(&dir, "chain.toml", &scene("figure1a.toml"), body);
    // The same parameters over a dimer: the same ids, other scenes.
    let dimer = sweep_file(&dir, "dimer.toml", &scene("dimer.toml"), body);
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    ok(&["sweep", chain.to_str().unwrap(), "--out", out_s]);
    let before = files(&out);
    for other in [&dimer, &chain] {
        // The second: refused; the first again (a rerun of the same sweep): finished.
        let o = cli(&["sweep", other.to_str().unwrap(), "--out", out_s]);
        if other == &dimer {
            assert_eq!(o.status.code(), Some(1), "{}", text(&o));
            let said = text(&o);
            assert!(
                said.contains("holds another sweep")
                    && said.contains("the same parameters over other scenes")
                    && said.contains("nothing was written"),
                "{said}"
            );
            // --emit and --point are refused alike.
            for extra in [&["--emit", "slurm"][..], &["--shard", "0/2"][..]] {
                let o = cli(&[
                    &["sweep", other.to_str().unwrap(), "--out", out_s][..],
                    extra,
                ]
                .concat());
                assert!(
                    !o.status.success() && text(&o).contains("holds another sweep"),
                    "{extra:?}: {}",
                    text(&o)
                );
            }
        } else {
            assert!(
                o.status.success() && text(&o).contains("2 already finished"),
                "{}",
                text(&o)
            );
        }
        let after = files(&out);
        assert_eq!(
            before.keys().collect::<Vec<_>>(),
            after.keys().collect::<Vec<_>>()
        );
        for (name, bytes) in &before {
            assert!(after[name] == *bytes, "{name:?} changed");
        }
    }
    // The dimer sweep in a folder of its own runs.
    let own = dir.join("own");
    ok(&[
        "sweep",
        dimer.to_str().unwrap(),
        "--out",
        own.to_str().unwrap(),
    ]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn points_run_with_the_values_emitted_whatever_the_base_becomes() {
    let dir = empty_dir!("frozen");
    let base = dir.join("base.toml");
    std::fs::copy(scene("figure1a.toml"), &base).unwrap();
    let body = "\"integrator.duration\" = [2.0]\n\"helix.dhat\" = [1.05, 1.5]\n\"integrator.dt\" = [0.1, 0.05]\n";
    let file = sweep_file(&dir, "sweep.toml", &base, body);
    let (clean, out) = (dir.join("clean"), dir.join("out"));
    ok(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        clean.to_str().unwrap(),
    ]);
    ok(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--emit",
        "parallel",
    ]);
    // Edited after emitting: another viscosity; then the sweep file removed.
    let edited = std::fs::read_to_string(&base)
        .unwrap()
        .replace("viscosity = 1.0", "viscosity = 3.0");
    assert!(edited.contains("viscosity = 3.0"));
    std::fs::write(&base, edited).unwrap();
    // The sweep file now gives other scenes: refused in the emitted folder.
    let o = cli(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && text(&o).contains("holds another sweep"),
        "{}",
        text(&o)
    );
    std::fs::remove_file(&file).unwrap();
    // What the emitted GNU parallel line runs, one point at a time.
    let script = std::fs::read_to_string(out.join("parallel.sh")).unwrap();
    assert!(script.contains("sweep --frozen --out"), "{script}");
    let ids = std::fs::read_to_string(out.join("point_ids.txt")).unwrap();
    for id in ids.lines() {
        ok(&[
            "sweep",
            "--frozen",
            "--out",
            out.to_str().unwrap(),
            "--point",
            id,
            "--jobs",
            "1",
        ]);
    }
    assert!(same_points(&clean, &out) >= 4 * 6);
    for id in ids.lines() {
        let s = std::fs::read_to_string(out.join("points").join(id).join("scene.toml")).unwrap();
        assert!(s.contains("viscosity = 1.0"), "{id}: {s}");
    }
    // A frozen scene changed since: refused, the others run (finished here).
    let first = ids.lines().next().unwrap();
    let frozen = out.join("frozen").join(format!("{first}.toml"));
    let f = std::fs::read_to_string(&frozen)
        .unwrap()
        .replace("viscosity = 1.0", "viscosity = 2.0");
    std::fs::write(&frozen, f).unwrap();
    let o = cli(&["sweep", "--frozen", "--out", out.to_str().unwrap()]);
    let said = text(&o);
    assert_eq!(o.status.code(), Some(1), "{said}");
    assert!(
        said.contains(&format!("{first}: REFUSED: {}", frozen.display()))
            && said.contains("changed after the sweep was emitted"),
        "{said}"
    );
    assert!(
        said.contains("3 already finished, 0 stopped early, 1 failed"),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nonsense_job_settings_are_refused_before_anything_is_written() {
    let dir = empty_dir!("nonsense");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/sweeps/small.toml");
    let out = dir.join("out");
    for (args, says) in [
        (&["--tasks", "0"][..], "--tasks 0"),
        (&["--tasks", "9"][..], "more than the sweep's 8 points"),
        (&["--time", "banana"][..], "not a SLURM time limit"),
        (&["--mem", "lots"][..], "not a size"),
        (&["--qos", "a b"][..], "--qos"),
        (&["--throttle", "0"][..], "--throttle 0"),
    ] {
        let o = cli(&[
            &[
                "sweep",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--emit",
                "slurm",
            ][..],
            args,
        ]
        .concat());
        assert!(
            !o.status.success() && text(&o).contains(says),
            "{args:?}: {}",
            text(&o)
        );
        assert!(!out.exists(), "{args:?}: something was written");
    }
    // --dry-run lists the 8 points and writes nothing.
    let said = ok(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--dry-run",
    ]);
    assert!(
        said.contains("8 points, all valid; nothing run or written"),
        "{said}"
    );
    assert!(!out.exists());
    // The settings reach the script, with the signal ahead of the time limit.
    ok(&[
        "-vv",
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--emit",
        "slurm",
        "--tasks",
        "3",
        "--time",
        "1-00:30:00",
        "--mem",
        "2G",
        "--account",
        "acct",
        "--qos",
        "short",
        "--constraint",
        "avx512",
        "--checkpoint-every",
        "2.5",
    ]);
    let script = std::fs::read_to_string(out.join("slurm.sh")).unwrap();
    for line in [
        "#SBATCH --array=0-2\n",
        "#SBATCH --time=1-00:30:00\n",
        "#SBATCH --mem=2G\n",
        "#SBATCH --account=acct\n",
        "#SBATCH --qos=short\n",
        "#SBATCH --constraint=avx512\n",
        "#SBATCH --signal=B:TERM@60\n",
        " -vv sweep --frozen --out ",
        " --checkpoint-every 2.5 --shard \"$SLURM_ARRAY_TASK_ID/3\"",
    ] {
        assert!(script.contains(line), "{line:?} not in {script}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--emit ENGINE --dry-run` prints the job file and writes nothing; the job name,
/// the signal's lead and further sbatch options are set, and the time and memory forms
/// SLURM accepts (`infinite`, `4GB`) are taken.
#[test]
fn emit_dry_run_previews_the_script_with_the_options_given() {
    let dir = empty_dir!("preview");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/sweeps/small.toml");
    let out = dir.join("out");
    let args = [
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--emit",
        "slurm",
        "--time",
        "infinite",
        "--mem",
        "4GB",
        "--job-name",
        "helices",
        "--signal-lead",
        "600",
        "--sbatch-arg",
        "--gres=gpu:1",
        "--sbatch-arg=--mail-type=END,FAIL",
        "--sbatch-arg",
        "--exclusive",
    ];
    let o = cli(&[&args[..], &["--dry-run"]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let printed = String::from_utf8(o.stdout.clone()).unwrap();
    assert!(!out.exists(), "--dry-run wrote something");
    assert!(
        text(&o).contains("nothing written") && printed.starts_with("#!/bin/bash\n"),
        "{}",
        text(&o)
    );
    for line in [
        "#SBATCH --job-name=helices\n",
        "#SBATCH --time=infinite\n",
        "#SBATCH --mem=4GB\n",
        "#SBATCH --gres=gpu:1\n",
        "#SBATCH --mail-type=END,FAIL\n",
        "#SBATCH --exclusive\n",
        "#SBATCH --signal=B:TERM@600\n",
    ] {
        assert!(printed.contains(line), "{line:?} not in {printed}");
    }
    // The preview is the script emitting writes.
    ok(&args);
    assert_eq!(
        std::fs::read_to_string(out.join("slurm.sh")).unwrap(),
        printed
    );
    // An option the script sets itself is refused, naming the flag that sets it.
    let o = cli(&[&args[..], &["--sbatch-arg=--time=10", "--dry-run"]].concat());
    assert!(
        !o.status.success() && text(&o).contains("set by --time"),
        "{}",
        text(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sweep stopped by SIGTERM once two points have checkpoints: exit status 143, the
/// running points checkpointed, `collect` names each point's array task and the
/// `sbatch --array` line, and the rerun ends equal to a clean run.
#[test]
fn sigterm_checkpoints_a_sweep_that_then_ends_as_a_clean_run() {
    let dir = empty_dir!("sigterm");
    let body = "\"integrator.duration\" = [300.0]\n\"helix.dhat\" = [1.05, 1.2, 1.35]\n";
    let file = sweep_file(&dir, "long.toml", &scene("figure1a.toml"), body);
    let (clean, out) = (dir.join("clean"), dir.join("out"));
    let f = file.to_str().unwrap();
    ok(&[
        "sweep",
        f,
        "--out",
        clean.to_str().unwrap(),
        "--checkpoint-every",
        "10",
    ]);
    ok(&[
        "sweep",
        f,
        "--out",
        out.to_str().unwrap(),
        "--emit",
        "slurm",
        "--tasks",
        "2",
        "--checkpoint-every",
        "10",
    ]);
    let mut child = Command::new(BIN)
        .args([
            "sweep",
            "--frozen",
            "--out",
            out.to_str().unwrap(),
            "--jobs",
            "2",
            "--checkpoint-every",
            "10",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        let checkpoints = std::fs::read_dir(out.join("points"))
            .unwrap()
            .filter(|e| e.as_ref().unwrap().path().join("checkpoint.json").exists())
            .count();
        if checkpoints >= 2 || child.try_wait().unwrap().is_some() {
            break;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&o.stdout).into_owned();
    if o.status.success() {
        eprintln!("the sweep ended before the signal: {said}");
    } else {
        assert_eq!(o.status.code(), Some(143), "{said}");
        assert!(
            said.contains("stopped by signal 15, checkpointed")
                && said.contains("not started (run again to go on)"),
            "{said}"
        );
        let c = cli(&["collect", out.to_str().unwrap()]);
        let listed = text(&c);
        assert!(!c.status.success());
        assert!(
            listed.contains(" unfinished [array task ")
                && listed.contains("to run again: sbatch --array="),
            "{listed}"
        );
    }
    ok(&[
        "sweep",
        "--frozen",
        "--out",
        out.to_str().unwrap(),
        "--checkpoint-every",
        "10",
    ]);
    assert_eq!(same_points(&clean, &out), 3 * 7);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bad sweep file, said at `FILE:LINE:` with `says`, nothing written.
fn refused_at(file: &Path, line: usize, says: &str) {
    let out = file.with_extension("out");
    let o = cli(&[
        "sweep",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let said = text(&o);
    assert!(!o.status.success(), "{said}");
    let at = format!("{}:{line}:", file.display());
    assert!(
        said.contains(&at) && said.contains(says),
        "expected {at} ... {says:?}: {said}"
    );
    assert!(!out.exists());
}

#[test]
fn circular_bases_misspellings_and_equal_numbers_are_said_at_their_line() {
    let dir = empty_dir!("messages");
    let dimer = scene("dimer.toml");
    let w = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let self_base = w(
        "self.toml",
        "[sweep]\nbase = \"self.toml\"\n\"integrator.dt\" = [0.1]\n".into(),
    );
    refused_at(&self_base, 2, "base names this sweep file itself");
    let a = w(
        "a.toml",
        "[sweep]\nbase = \"b.toml\"\n\"integrator.dt\" = [0.1]\n".into(),
    );
    w(
        "b.toml",
        "# b\n[sweep]\nbase = \"a.toml\"\n\"integrator.dt\" = [0.2]\n".to_string(),
    );
    refused_at(
        &a,
        2,
        "is itself a sweep ([sweep] at its line 2, whose base is this file: a circular base)",
    );
    let on_sweep = w(
        "c.toml",
        "[sweep]\nbase = \"small.toml\"\n\"integrator.dt\" = [0.1]\n".into(),
    );
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/sweeps/small.toml"),
        dir.join("small.toml"),
    )
    .unwrap();
    refused_at(&on_sweep, 2, "is itself a sweep");
    let base = format!("base = {:?}\n", dimer.display().to_string());
    let typo = w(
        "typo.toml",
        format!("# a typo\n[sweeep]\n{base}\"integrator.dt\" = [0.1]\n"),
    );
    refused_at(&typo, 2, "did you mean [sweep]?");
    let zipp = w(
        "zipp.toml",
        format!("[sweep]\n{base}\n[[sweep.zipp]]\n\"integrator.dt\" = [0.1]\n"),
    );
    refused_at(&zipp, 4, "did you mean [[sweep.zip]]");
    let replica = w(
        "replica.toml",
        format!("[sweep]\n{base}replica = 3\n\"integrator.dt\" = [0.1]\n"),
    );
    refused_at(&replica, 3, "did you mean replicas?");
    let equal = w(
        "equal.toml",
        format!("[sweep]\n{base}\"output.every\" = [2,\n  2.0]\n"),
    );
    refused_at(&equal, 4, "values equal as numbers are one value");
    let _ = std::fs::remove_dir_all(&dir);
}
