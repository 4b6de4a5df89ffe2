//! A run killed with a real SIGKILL resumes from what it left: the
//! child `host-demo run --checkpoint-every` is killed once a checkpoint is on disk, and
//! `host-demo resume DIR --until T` then writes the same bytes as one run to `T`
//! (trajectories, observables and `scene.toml`; `summary.json` differs by its wall time,
//! machine and `resumed_from`). `resume` reads the scene under the limits `run` applies.

use crate::common::{BIN, SAME, ok};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::fuzz;

/// The fuzzers' deterministic generator: the test draws the same scenes and kill times
/// on every machine.
struct Draw(fuzz::Rng);

impl Draw {
    /// An integer in `lo..=hi`.
    fn int(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.0.below((hi - lo + 1) as usize) as u64
    }

    /// A number in `[lo, hi)`.
    fn real(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.0.unit()
    }
}

/// A scene: `n` beads in a wavy line (a chain when `bonded`), `steps` steps of `dt`,
/// a frame every `every` steps, thermal noise with `seed` when given.
#[derive(Debug)]
struct Spec {
    method: &'static str,
    n: usize,
    bonded: bool,
    noise: Option<u64>,
    steps: usize,
    every: usize,
}

const DT: f64 = 0.01;

impl Spec {
    fn toml(&self, draw: &mut Draw) -> String {
        let mut t = String::new();
        let gap = if self.bonded { 2.2 } else { 3.0 };
        for i in 0..self.n {
            let (y, z) = (draw.real(-0.3, 0.3), draw.real(-0.3, 0.3));
            let r = draw.real(0.9, 1.1);
            t += &format!(
                "[[particle]]\nposition = [{}, {y}, {z}]\nradius = {r}\n\n",
                gap * i as f64
            );
        }
        if self.bonded {
            for i in 1..self.n {
                t += &format!("[[bond]]\nbetween = [{}, {i}]\n\n", i - 1);
            }
        }
        t += &format!(
            "[integrator]\nmethod = \"{}\"\ndt = {DT}\nduration = {}\n\n[output]\nevery = {}\n",
            self.method,
            self.steps as f64 * DT,
            self.every
        );
        if self.method == "springs" {
            // Soft enough for the explicit spring step at this dt.
            t = t.replace("\n\n[output]", "\nstiffness = 20.0\n\n[output]");
        }
        if let Some(seed) = self.noise {
            t += &format!("\n[brownian]\ntemperature = 0.5\nseed = {seed}\n");
        }
        t
    }
}

/// What a kill found.
#[derive(Debug, PartialEq)]
enum Kill {
    /// Killed by SIGKILL before it finished.
    Midway,
    /// It had finished (no kill was needed to resume it).
    Finished,
}

/// Runs `scene` into `dir` with a checkpoint every `k` steps and SIGKILLs it once a
/// checkpoint of step `at` or later is on disk and `linger` more has passed.
fn run_and_kill(scene: &Path, dir: &Path, k: usize, at: u64, linger: Duration) -> Kill {
    let every = format!("{}", k as f64 * DT);
    let mut child = Command::new(BIN)
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ])
        .args(["--checkpoint-every", &every])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let checkpoint = dir.join("checkpoint.json");
    let t0 = Instant::now();
    loop {
        // The checkpoint is renamed into place whole: a read finds all of one.
        let step = std::fs::read_to_string(&checkpoint)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|c| c["step"].as_u64());
        if step.is_some_and(|s| s >= at) {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "the run failed before its checkpoint");
            return Kill::Finished;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(1));
    }
    std::thread::sleep(linger);
    child.kill().unwrap(); // SIGKILL on Unix
    let status = child.wait().unwrap();
    if status.signal() == Some(9) {
        Kill::Midway
    } else {
        assert!(status.success(), "the run failed: {status}");
        Kill::Finished
    }
}

/// Asserts that `dir` holds the bytes of `one` and no temporary file.
fn same_as(one: &Path, dir: &Path, what: &str) {
    for f in SAME {
        let (a, b) = (std::fs::read(one.join(f)), std::fs::read(dir.join(f)));
        let (a, b) = (a.unwrap(), b.unwrap_or_else(|e| panic!("{what}: {f}: {e}")));
        assert!(a == b, "{what}: {f} differs from one run's");
    }
    for e in std::fs::read_dir(dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "{what}: {name} left");
    }
    assert!(dir.join("summary.json").is_file(), "{what}: no summary");
}

/// Runs `spec` once whole and once killed (checkpoints every `k` steps, killed after
/// the checkpoint of step `at` and `linger`), resumes the killed one and compares.
fn kill_and_resume(dir: &Path, spec: &Spec, draw: &mut Draw, k: usize, at: u64) -> Kill {
    let scene = dir.join("scene-in.toml");
    std::fs::write(&scene, spec.toml(draw)).unwrap();
    let (one, killed) = (dir.join("one"), dir.join("killed"));
    let scene_s = scene.to_str().unwrap();
    ok(&["run", scene_s, "--out", one.to_str().unwrap()]);
    let linger = Duration::from_micros(draw.int(0, 20_000));
    let kill = run_and_kill(&scene, &killed, k, at, linger);
    if kill == Kill::Midway {
        assert!(!killed.join("summary.json").exists());
        // What a run killed while saving a checkpoint leaves: resume removes it.
        std::fs::write(killed.join("checkpoint.json.tmp"), b"{\"step\": 1").unwrap();
        let until = format!("{}", spec.steps as f64 * DT);
        ok(&["resume", killed.to_str().unwrap(), "--until", &until]);
    }
    same_as(&one, &killed, &format!("{} {kill:?}", dir.display()));
    kill
}

#[test]
fn a_run_killed_with_sigkill_resumes_to_the_bytes_of_one_run() {
    let dir = empty_dir!("chain");
    let spec = Spec {
        method: "rattle-stable",
        n: 6,
        bonded: true,
        noise: None,
        steps: 60_000,
        every: 37,
    };
    // Checkpoints every 999 steps (not on the last one), killed after the sixth.
    let kill = kill_and_resume(&dir, &spec, &mut Draw(fuzz::Rng(33)), 999, 6 * 999);
    assert_eq!(kill, Kill::Midway, "the run ended before it was killed");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Random small scenes (method, bead count, bonds, thermal noise and its seed, frame
/// and checkpoint intervals) killed at random times resume to the bytes of one run.
#[test]
fn killed_runs_of_random_scenes_resume_to_the_bytes_of_one_run() {
    const METHODS: [&str; 5] = [
        "overdamped",
        "overdamped2",
        "rattle",
        "rattle-stable",
        "springs",
    ];
    let mut draw = Draw(fuzz::Rng(0x33));
    let mut midway = 0;
    let cases = 8;
    for case in 0..cases {
        let method = METHODS[draw.int(0, 4) as usize];
        let thermal = matches!(method, "overdamped" | "springs" | "rattle-stable");
        let steps = draw.int(15_000, 30_000) as usize;
        let spec = Spec {
            method,
            n: draw.int(2, 6) as usize,
            bonded: draw.int(0, 3) > 0,
            noise: (thermal && draw.int(0, 1) == 1).then(|| draw.int(0, 1 << 40)),
            steps,
            every: draw.int(1, 60) as usize,
        };
        // Not a divisor of the step count: the last checkpoint is before the end.
        let k = (draw.int(steps as u64 / 40, steps as u64 / 8) as usize) | 1;
        let k = if steps.is_multiple_of(k) { k + 2 } else { k };
        let at = (draw.int(1, 5) * k as u64).min((steps / k * k) as u64);
        eprintln!("case {case}: {spec:?}, checkpoints every {k} steps, killed after {at}");
        let dir = empty_dir!(&format!("random-{case}"));
        if kill_and_resume(&dir, &spec, &mut draw, k, at) == Kill::Midway {
            midway += 1;
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    eprintln!("{midway} of {cases} runs killed midway, the others had finished");
    assert!(midway > 0, "no run was killed midway");
}

/// A scene of a chain of `n` overdamped beads, `steps` steps, a frame every 10.
fn small_scene(dir: &Path, n: usize, steps: usize) -> PathBuf {
    let spec = Spec {
        method: "overdamped",
        n,
        bonded: true,
        noise: None,
        steps,
        every: 10,
    };
    let scene = dir.join(format!("scene-{steps}.toml"));
    std::fs::write(&scene, spec.toml(&mut Draw(fuzz::Rng(1)))).unwrap();
    scene
}

/// [`small_scene`] run into `dir/run` with `extra` arguments: the folder.
fn small_run(dir: &Path, n: usize, steps: usize, extra: &[&str]) -> PathBuf {
    let (scene, out) = (small_scene(dir, n, steps), dir.join("run"));
    let args = [
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    ok(&[&args[..], extra].concat());
    out
}

/// Runs `args`, which must be refused (stopped after 30 s otherwise: were a limit not
/// applied, the run would go on, writing gigabytes); returns what it said.
fn refused(args: &[&str]) -> String {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap();
            panic!("{args:?} ran instead of being refused");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let o = child.wait_with_output().unwrap();
    assert!(!o.status.success(), "{args:?} ran");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `resume` reads the scene to `--until` under the output and step limits of `run`,
/// and says so at `scene.toml`, before any file is touched.
#[test]
fn resume_applies_the_output_limits_of_run() {
    let dir = empty_dir!("limits");
    let out = small_run(&dir, 3, 400, &["--checkpoint-every", "2"]);
    let out_s = out.to_str().unwrap();
    let before = std::fs::read(out.join("observables.csv")).unwrap();
    // 1e11 steps, a frame every 10: far past the default 64 GiB. Then 4000 steps, 402
    // frames of 3 particles: about 690 KiB, over 0.0001 GiB.
    let small = ["--until", "40", "--max-output", "0.0001"];
    for (args, limit) in [
        (&["--until", "1e9"][..], "64.0 GiB"),
        (&small[..], "104.9 KiB"),
    ] {
        let said = refused(&[&["resume", out_s][..], args].concat());
        let at = format!("{}:", out.join("scene.toml").display());
        assert!(said.contains(&at), "{args:?}: {said}");
        assert!(
            said.contains(&format!("over the limit of {limit}")),
            "{said}"
        );
        assert_eq!(std::fs::read(out.join("observables.csv")).unwrap(), before);
    }
    // `run` refuses that scene to 40 under the same limit, with the same words.
    let long = small_scene(&dir, 3, 4000);
    let x = dir.join("x");
    let said = refused(&[
        "run",
        long.to_str().unwrap(),
        "--out",
        x.to_str().unwrap(),
        "--max-output",
        "0.0001",
    ]);
    assert!(said.contains("over the limit of 104.9 KiB"), "{said}");
    ok(&["resume", out_s, "--until", "40"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run killed before its first checkpoint has nothing to resume from: `resume` says
/// so, naming the checkpoint.
#[test]
fn a_run_without_a_checkpoint_is_refused_by_name() {
    let dir = empty_dir!("none");
    let out = small_run(&dir, 2, 100, &[]);
    let e = hydrorattle_host::sim::resume(&out, 2.0, Default::default(), Default::default())
        .unwrap_err();
    let none = e.downcast_ref::<hydrorattle_host::sim::NoCheckpoint>();
    assert_eq!(
        none.map(|n| n.path.clone()),
        Some(out.join("checkpoint.json"))
    );
    let said = refused(&["resume", out.to_str().unwrap(), "--until", "2"]);
    assert!(said.contains("no checkpoint to resume from"), "{said}");
    let _ = std::fs::remove_dir_all(&dir);
}
