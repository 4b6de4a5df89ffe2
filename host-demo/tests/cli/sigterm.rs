//! SIGTERM during a long step, with a real process. The first signal is said at once
//! and honoured after the step under way (a checkpoint there); a second one ends the
//! process mid-step, at once, and says so. Nothing is lost or mixed: the last
//! checkpoint stays valid and `resume` from it ends with the bytes of one run; a run
//! ended so before its first checkpoint is refused by `resume`, by name.

use crate::common::{BIN, SAME, text};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Beads in the chain: enough for a step of about a second (the dense solve of the
/// bonds through the RPY mobility).
const BEADS: usize = 1600;
/// Time step.
const DT: f64 = 0.01;
/// Steps of the run.
const STEPS: usize = 3;

/// A chain of [`BEADS`] beads in a zig-zag, bonded, settling overdamped: a slow step.
fn scene(dir: &Path) -> PathBuf {
    let mut t = String::from(
        "[model]\nhydrodynamics = \"rpy\"\ninertia = false\nrotation = false\n\n\
         [gravity]\nacceleration = [0.0, 0.0, -1.0]\n\n",
    );
    for i in 0..BEADS {
        let y = if i % 2 == 0 { 0.0 } else { 0.5 };
        t += &format!(
            "[[particle]]\nposition = [{}, {y}, 0.0]\nradius = 1.0\n\n",
            2.2 * i as f64
        );
    }
    for i in 1..BEADS {
        t += &format!("[[bond]]\nbetween = [{}, {i}]\n\n", i - 1);
    }
    t += &format!(
        "[integrator]\nmethod = \"overdamped\"\ndt = {DT}\nduration = {}\nsolver = \"newton\"\n\n\
         [output]\nevery = 1\n",
        STEPS as f64 * DT
    );
    let path = dir.join("chain.toml");
    std::fs::write(&path, t).unwrap();
    path
}

fn run(scene: &Path, out: &Path) -> Child {
    Command::new(BIN)
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--checkpoint-every", &DT.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn sigterm(child: &Child) {
    let s = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(s.success());
}

/// Waits (at most a few minutes) for `path` to exist.
fn wait_for(path: &Path) {
    let t0 = Instant::now();
    while !path.exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "{} never came",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Two SIGTERMs 50 ms apart: the run ends at once with both said. `None` when the
/// run stopped cleanly on the first one instead: it landed between two steps (the
/// process was between writing `ready` and starting the next step), which is not the
/// case under test.
fn stop_twice(child: Child) -> Option<String> {
    sigterm(&child);
    std::thread::sleep(Duration::from_millis(50));
    sigterm(&child);
    let o = child.wait_with_output().unwrap();
    let said = text(&o);
    assert_eq!(o.status.code(), Some(143), "{said}");
    assert!(
        said.contains("signal 15: stopping after the step under way"),
        "{said}"
    );
    if !said.contains("signal 15 again: ending at once") {
        assert!(said.contains("stopped by signal 15 after step"), "{said}");
        return None;
    }
    Some(said)
}

/// Runs the scene into `dir/{name}-{k}` and stops it twice inside a step: after
/// `ready` (a path relative to the run's folder) exists, and `pause` (a fraction of a
/// step). A loaded machine can hold the process between `ready` and the step long
/// enough for the first signal to land between steps; then the attempt is made again
/// (a few times at most). Returns the run's folder.
fn stopped_inside_a_step(
    scene: &Path,
    dir: &Path,
    name: &str,
    ready: &str,
    pause: Duration,
) -> PathBuf {
    for k in 0..4 {
        let out = dir.join(format!("{name}-{k}"));
        let child = run(scene, &out);
        wait_for(&out.join(ready));
        std::thread::sleep(pause);
        let t = Instant::now();
        if stop_twice(child).is_some() {
            eprintln!(
                "ended {:.2} s after the first signal",
                t.elapsed().as_secs_f64()
            );
            return out;
        }
        eprintln!("attempt {k}: the first signal landed between steps; again");
    }
    panic!("no attempt stopped inside a step");
}

/// The step of `dir`'s checkpoint.
fn checkpoint_step(dir: &Path) -> u64 {
    let c = std::fs::read_to_string(dir.join("checkpoint.json")).unwrap();
    let c: serde_json::Value = serde_json::from_str(&c).unwrap();
    c["step"].as_u64().unwrap()
}

#[test]
fn a_second_sigterm_ends_a_long_step_at_once_and_nothing_is_lost() {
    let dir = empty_dir!("twice");
    let scene = scene(&dir);
    let one = dir.join("one");
    let t = Instant::now();
    let o = run(&scene, &one).wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    // A quarter of a step (the run's time over its steps and its start): into the
    // step, well before its end.
    let pause = t.elapsed() / (4 * (STEPS as u32 + 1));

    // Stopped twice inside step 2, after the checkpoint of step 1.
    let cut = stopped_inside_a_step(&scene, &dir, "cut", "checkpoint.json", pause);
    // Ended inside the step: no checkpoint after it, nothing finished.
    assert_eq!(checkpoint_step(&cut), 1);
    assert!(!cut.join("summary.json").exists());
    let until = (STEPS as f64 * DT).to_string();
    let o = Command::new(BIN)
        .args(["resume", cut.to_str().unwrap(), "--until", &until])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    for name in SAME {
        let (a, b) = (
            std::fs::read(one.join(name)).unwrap(),
            std::fs::read(cut.join(name)).unwrap(),
        );
        assert!(a == b, "{name} differs from one run's");
    }

    // Stopped twice inside step 1, past the first frame: no checkpoint, and resume
    // says so.
    let early = stopped_inside_a_step(&scene, &dir, "early", "trajectory.xyz.tmp", pause);
    assert!(!early.join("checkpoint.json").exists());
    let o = Command::new(BIN)
        .args(["resume", early.to_str().unwrap(), "--until", &until])
        .output()
        .unwrap();
    let said = text(&o);
    assert_eq!(o.status.code(), Some(1), "{said}");
    assert!(said.contains("no checkpoint to resume from"), "{said}");
    let _ = std::fs::remove_dir_all(&dir);
}
