//! Recovery from every partial state of a point: a point finished,
//! or stopped as SIGTERM stops it after a random step (its checkpoint there, its files
//! under their temporary names), loses a random subset of its files; run again, it
//! ends with the bytes of a clean run, whether it is found finished, resumed or
//! restarted. 200 cases of a 60-step dimer (a frame every 7 steps, so the last one is a
//! closing frame; a checkpoint every 5), about a second in all.
//!
//! `checkpoint.json` is the run's restart state, not a result: it is compared where
//! both runs wrote their last one at the same step, and otherwise only its presence is
//! not required (a finished point is not rerun for it; a point stopped after its last
//! periodic checkpoint keeps the stop's).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use hydrorattle_host::sim::Stop;
use hydrorattle_host::sweep::run::{Options, point_dir};
use hydrorattle_host::sweep::{RunReport, Selection, Sweep, run_points};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// The execution fields of `summary.json`, which differ between runs.
const EXECUTION: [&str; 4] = ["wall_time_s", "steps_per_second", "machine", "resumed_from"];

fn sweep(dir: &Path) -> Sweep {
    let dimer = include_str!("../../scenes/dimer.toml");
    let text =
        format!("{dimer}\n[sweep]\n\"integrator.duration\" = [0.6]\n\"output.every\" = [7]\n");
    Sweep::parse(&text, "recovery.toml", dir).unwrap()
}

fn run(sweep: &Sweep, dir: &Path, stop: Stop) -> RunReport {
    let opts = Options {
        jobs: 1,
        checkpoint_every: Some(0.05),
        wait: false,
        stop,
    };
    run_points(sweep, dir, &Selection::All, opts).unwrap()
}

/// The files of a folder by name.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let name = e.file_name().to_string_lossy().into_owned();
            (name, std::fs::read(e.path()).unwrap())
        })
        .collect()
}

fn summary(bytes: &[u8]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    for k in EXECUTION {
        v.as_object_mut().unwrap().remove(k);
    }
    v
}

/// Why `got` is not the clean folder `want`, if it is not.
fn differs(want: &BTreeMap<String, Vec<u8>>, got: &BTreeMap<String, Vec<u8>>) -> Option<String> {
    for name in got.keys() {
        if !want.contains_key(name) {
            return Some(format!("{name} left"));
        }
    }
    for (name, bytes) in want {
        let Some(g) = got.get(name) else {
            if name == "checkpoint.json" {
                continue;
            }
            return Some(format!("{name} missing"));
        };
        let same = match name.as_str() {
            "summary.json" => summary(bytes) == summary(g),
            "checkpoint.json" => {
                let step = |b: &[u8]| {
                    serde_json::from_slice::<serde_json::Value>(b).unwrap()["step"].clone()
                };
                step(bytes) != step(g) || bytes == g
            }
            _ => bytes == g,
        };
        if !same {
            return Some(format!("{name} differs"));
        }
    }
    None
}

#[test]
fn any_subset_of_a_points_files_deleted_reruns_to_a_clean_run() {
    // On tmpfs where there is one: each run syncs a dozen files to disk (a checkpoint
    // survives a crash), which is most of a case's time on a disk and none on tmpfs.
    let shm = Path::new("/dev/shm");
    let tmp = if shm.is_dir() {
        shm.to_path_buf()
    } else {
        PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
    };
    let root = tmp.join(format!("hydrorattle-recovery-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let sweep = sweep(&root);
    let id = sweep.points[0].id.clone();
    let clean = root.join("clean");
    let r = run(&sweep, &clean, Stop::default());
    assert_eq!(r.ran, 1, "{r}");
    let want = files(&point_dir(&clean, &id));
    assert_eq!(want.len(), 7, "{:?}", want.keys());
    let config = Config {
        cases: 200,
        failure_persistence: None,
        ..Config::default()
    };
    let rng = TestRng::deterministic_rng(RngAlgorithm::ChaCha);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let tally = std::cell::RefCell::new(BTreeMap::<&str, usize>::new());
    let dir = root.join("case");
    runner
        .run(
            &(
                any::<bool>(),
                0u64..60,
                prop::collection::vec(any::<prop::sample::Index>(), 0..5),
            ),
            |(finished, after, picks)| {
                // The sweep folder is claimed once; each case starts its point afresh.
                let _ = std::fs::remove_dir_all(point_dir(&dir, &id));
                let stop = if finished {
                    Stop::default()
                } else {
                    Stop::after_step(after)
                };
                let first = run(&sweep, &dir, stop);
                prop_assert!(first.failed.is_empty(), "{first}");
                let pdir = point_dir(&dir, &id);
                let present: Vec<String> = files(&pdir).into_keys().collect();
                let mut gone: Vec<String> = picks.iter().map(|i| i.get(&present).clone()).collect();
                gone.sort();
                gone.dedup();
                for name in &gone {
                    std::fs::remove_file(pdir.join(name)).unwrap();
                }
                let again = run(&sweep, &dir, Stop::default());
                prop_assert!(again.failed.is_empty(), "{again}");
                let how = match (again.skipped, again.resumed, again.ran) {
                    (1, 0, 0) => "finished",
                    (0, 1, 0) => "resumed",
                    (0, 0, 1) => "restarted",
                    _ => "?",
                };
                *tally.borrow_mut().entry(how).or_default() += 1;
                let got = files(&pdir);
                let why = differs(&want, &got);
                prop_assert!(
                    why.is_none(),
                    "{} (stopped after {after}: {}), deleted {gone:?}, then {how}: {}",
                    if finished { "finished" } else { "stopped" },
                    !finished,
                    why.unwrap_or_default()
                );
                Ok(())
            },
        )
        .unwrap();
    let seen = tally.into_inner();
    eprintln!("200 cases: {seen:?}");
    for how in ["finished", "resumed", "restarted"] {
        assert!(
            seen.get(how).is_some_and(|&n| n > 0),
            "no case {how}: {seen:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&root);
}
