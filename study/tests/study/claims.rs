//! The claims' verdicts on made-up series whose verdicts are known, and the same
//! verdicts from two runs of the Figure 1 cases.

use hydrorattle::observables::FrameState;
use hydrorattle_host::scene::Scene;
use hydrorattle_host::sim::{Front, Label, Observables, RunOptions, run};
use hydrorattle_study::claims::{CaseRun, Claim, Verdict, claims};
use hydrorattle_study::figure1::claims_of;

/// 41 frames at t = 0, 10, ..., 400: state `state(t)`, spin `(rate, coherence)` from
/// `spin(t)`, centre of mass falling at `speed(t)`.
fn series(
    state: impl Fn(f64) -> FrameState,
    spin: impl Fn(f64) -> (f64, f64),
    speed: impl Fn(f64) -> f64,
) -> Vec<Observables> {
    let mut z = 0.0;
    (0..=40)
        .map(|k| {
            let t = 10.0 * k as f64;
            if k > 0 {
                z -= 10.0 * speed(t - 5.0);
            }
            let (spin_rate, spin_coherence) = spin(t);
            Observables {
                time: t,
                com: [0.0, 0.0, z],
                spin_rate,
                spin_coherence,
                state: Label(state(t)),
                ..Observables::default()
            }
        })
        .collect()
}

fn front(correlation: f64, count: usize) -> Front {
    Front {
        cos_min: 0.9,
        count,
        correlation,
        first_vertical: (0..24).map(|k| (k < count).then_some(k as f64)).collect(),
    }
}

fn verdict(cs: &[Claim], id: &str) -> (Verdict, Option<[f64; 2]>) {
    let c = cs.iter().find(|c| c.id == id).expect(id);
    (c.verdict, c.window)
}

fn judge(a: &[Observables], b: &[Observables], c: &[Observables], f: &Front) -> Vec<Claim> {
    let none = Front::default();
    claims(&[
        CaseRun {
            case: "a",
            series: a,
            front: &none,
        },
        CaseRun {
            case: "b",
            series: b,
            front: &none,
        },
        CaseRun {
            case: "c",
            series: c,
            front: f,
        },
    ])
}

#[test]
fn lasting_states_hold_pass_or_fail() {
    let still = |_| (0.0, 0.0);
    let one = |_| 1.0;
    // (a) stretched from t = 100 on: holds, window [100, 400].
    let a = series(
        |t| {
            if t >= 100.0 {
                FrameState::Stretched
            } else {
                FrameState::Other
            }
        },
        still,
        one,
    );
    // (b) twisting from t = 50 to 150 only: transient, window [50, 160) as [50, 160].
    let b = series(
        |_| FrameState::Folded,
        |t| {
            if (50.0..=150.0).contains(&t) {
                (0.1, 0.8)
            } else {
                (0.0, 0.0)
            }
        },
        one,
    );
    // (c) stretched in two frames only (too short to be seen): fails.
    let c = series(
        |t| {
            if t == 200.0 || t == 210.0 {
                FrameState::Stretched
            } else {
                FrameState::Folded
            }
        },
        still,
        one,
    );
    let cs = judge(&a, &b, &c, &front(0.0, 0));
    assert_eq!(
        verdict(&cs, "a_stretched"),
        (Verdict::Holds, Some([100.0, 400.0]))
    );
    assert_eq!(
        verdict(&cs, "b_lasting_twisting"),
        (Verdict::Transient, Some([50.0, 160.0]))
    );
    assert_eq!(verdict(&cs, "c_stretched"), (Verdict::Fails, None));
    // Stretched in 80 % of the last quarter (t = 300..400: 11 frames, 9 of them) holds;
    // in 7 of 11 it does not.
    let late = |gap: f64| {
        series(
            move |t| {
                if t >= 300.0 && t < 300.0 + gap {
                    FrameState::Other
                } else {
                    FrameState::Stretched
                }
            },
            still,
            one,
        )
    };
    let cs = judge(&late(20.0), &b, &c, &front(0.0, 0));
    assert_eq!(verdict(&cs, "a_stretched").0, Verdict::Holds);
    let cs = judge(&late(40.0), &b, &c, &front(0.0, 0));
    assert_eq!(verdict(&cs, "a_stretched").0, Verdict::Transient);
}

#[test]
fn early_twisting_must_start_in_the_first_quarter() {
    let one = |_| 1.0;
    let twist_between = |lo: f64, hi: f64| {
        move |t: f64| {
            if t >= lo && t <= hi {
                (-0.1, 0.6)
            } else {
                (0.1, 0.2)
            }
        }
    };
    let a = series(|_| FrameState::Other, twist_between(10.0, 30.0), one);
    let b = series(|_| FrameState::Other, twist_between(200.0, 300.0), one);
    // Coherent but too slow to count.
    let c = series(|_| FrameState::Other, |_| (0.001, 0.9), one);
    let cs = judge(&a, &b, &c, &front(0.0, 0));
    assert_eq!(
        verdict(&cs, "a_group_rotation"),
        (Verdict::Holds, Some([10.0, 40.0]))
    );
    assert_eq!(verdict(&cs, "c_early_twisting"), (Verdict::Fails, None));
    // (b) has no early claim of its own: reuse its series as (a).
    let cs = judge(&b, &b, &c, &front(0.0, 0));
    assert_eq!(
        verdict(&cs, "a_group_rotation"),
        (Verdict::Transient, Some([200.0, 310.0]))
    );
}

#[test]
fn faster_settling_over_every_quarter_or_some() {
    let still = |_| (0.0, 0.0);
    let other = |_| FrameState::Other;
    let a = series(other, still, |_| 1.0);
    // (b) fast in the second quarter only.
    let b = series(other, still, |t| {
        if (100.0..200.0).contains(&t) {
            3.0
        } else {
            1.0
        }
    });
    // (c) 1.5 times (a) throughout; 1.5 times (b) outside (b)'s fast quarter, half
    // of it inside (the same overall).
    let c = series(other, still, |_| 1.5);
    let cs = judge(&a, &b, &c, &front(0.0, 0));
    assert_eq!(
        verdict(&cs, "c_faster_than_a"),
        (Verdict::Holds, Some([0.0, 400.0]))
    );
    let (v, w) = verdict(&cs, "c_faster_than_b");
    assert_eq!((v, w), (Verdict::Transient, Some([200.0, 400.0])));
    // 1.15 times is not "much faster".
    let c = series(other, still, |_| 1.15);
    let cs = judge(&a, &b, &c, &front(0.0, 0));
    assert_eq!(verdict(&cs, "c_faster_than_a"), (Verdict::Fails, None));
}

#[test]
fn a_front_runs_from_the_head_when_most_bonds_turn_in_index_order() {
    let s = series(|_| FrameState::Stretched, |_| (0.0, 0.0), |_| 1.0);
    let cs = judge(&s, &s, &s, &front(0.9, 24));
    assert_eq!(
        verdict(&cs, "c_front_from_head"),
        (Verdict::Holds, Some([0.0, 23.0]))
    );
    let cs = judge(&s, &s, &s, &front(-0.7, 24));
    assert_eq!(verdict(&cs, "c_front_from_head").0, Verdict::Fails);
    // 17 of 24 bonds (below three quarters): no front, whatever the order.
    let cs = judge(&s, &s, &s, &front(1.0, 17));
    assert_eq!(verdict(&cs, "c_front_from_head").0, Verdict::Fails);
    let cs = judge(&s, &s, &s, &front(1.0, 18));
    assert_eq!(verdict(&cs, "c_front_from_head").0, Verdict::Holds);
}

#[test]
fn the_figure1_verdicts_are_the_same_in_two_runs() {
    let scenes = Scene::figure1().unwrap();
    let opts = RunOptions {
        max_steps: Some(1200),
        ..RunOptions::default()
    };
    let verdicts = || {
        let results: Vec<_> = scenes
            .iter()
            .map(|(case, s)| run(s, case, None, opts).unwrap())
            .collect();
        claims_of(&scenes, &results)
    };
    let (one, two) = (verdicts(), verdicts());
    assert_eq!(one.len(), 9);
    assert_eq!(one, two);
    assert_eq!(
        serde_json::to_string(&one).unwrap(),
        serde_json::to_string(&two).unwrap()
    );
}
