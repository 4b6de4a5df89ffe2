//! The paper's claims about Figure 1, one by one, each with a verdict computed from the
//! runs' observables (never written by hand).
//!
//! Windows of a run of duration `T` starting at `t0`: the *initial stage* is the first
//! quarter `[t0, t0 + T/4]`, the *late window* the last quarter `[t0 + 3T/4, t0 + T]`.
//! A claim about a state reads either a named state of the timeline (stretched) or
//! *twisting*: coherent rotation about the vertical
//! ([`is_rotating`](hydrorattle::observables::is_rotating)) whatever the shape, since
//! the paper's (c) twists while it stretches. A state is *seen* when it holds in at
//! least [`MIN_FRAMES`] consecutive frames; a *segment* runs from its first frame's time
//! to the next frame's (the last frame's at the end), as in the timeline.
//!
//! Verdicts, by the kind of claim:
//!
//! * a lasting state ("eventually stretched", "everlasting twisting"): **holds** when the
//!   state holds in at least [`LATE_SHARE`] of the late window's frames (window: its
//!   last segment); **transient** when it is seen but does not hold (window: its longest
//!   segment); **fails** when it is never seen;
//! * an early state ("twisting for a short period in the initial stage"): **holds**
//!   when it is seen in a segment that starts in the initial stage (window: that
//!   segment); **transient** when it is seen only later; **fails** otherwise;
//! * "settles faster than": the mean centre-of-mass settling speed (height lost over
//!   time, over the time both runs cover) over each quarter; **holds** when the ratio
//!   is at least [`FASTER`] over the whole run and in every quarter; **transient** when
//!   it is in some quarters (window: the longest run of such quarters); **fails**
//!   otherwise;
//! * the stretching front: **holds** when at least [`FRONT_SHARE`] of the bonds turned
//!   near-vertical and the correlation between bond index (from the head) and the time
//!   each first did so is at least [`FRONT_CORRELATION`] (window: first to last of those
//!   times); **fails** otherwise;
//! * "initially like (a)": **holds** when the state of most frames of the initial stage
//!   is the same in both runs; **fails** otherwise.

use hydrorattle::observables::{Rotation, State, StateThresholds, is_rotating};
use serde::Serialize;
use serde_json::{Value, json};

use crate::sim::{Front, Observables};

/// Least share of the late window's frames in a lasting state for it to hold.
pub const LATE_SHARE: f64 = 0.8;
/// Least number of consecutive frames for a state to be seen.
pub const MIN_FRAMES: usize = 3;
/// "Faster": the ratio of mean settling speeds is at least this.
pub const FASTER: f64 = 1.2;
/// Least share of bonds that must turn near-vertical for a stretching front.
pub const FRONT_SHARE: f64 = 0.75;
/// Least index-time correlation of a front from the head to the end.
pub const FRONT_CORRELATION: f64 = 0.5;

/// A claim's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Holds over the claimed window.
    Holds,
    /// Held during a window, but not over the one claimed (not to the end).
    Transient,
    /// Not seen.
    Fails,
}

impl Verdict {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Transient => "transient",
            Verdict::Fails => "fails",
        }
    }
}

/// What a claim says a chain is doing in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Doing {
    /// In this named state.
    In(State),
    /// Turning coherently about the vertical, whatever its shape.
    Twisting,
}

impl Doing {
    /// Name in evidence.
    pub fn name(self) -> &'static str {
        match self {
            Doing::In(s) => s.name(),
            Doing::Twisting => "twisting",
        }
    }

    /// `true` when frame `o` shows it.
    pub fn at(self, o: &Observables) -> bool {
        match self {
            Doing::In(s) => o.state.0 == s,
            Doing::Twisting => {
                let spin = Rotation {
                    rate: o.spin_rate,
                    coherence: o.spin_coherence,
                };
                is_rotating(&spin, &StateThresholds::default())
            }
        }
    }
}

/// What kind of statement a claim makes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// The case ends doing this and keeps doing it.
    Lasting(Doing),
    /// The case does this in its initial stage.
    Early(Doing),
    /// The case settles faster than the other case (by its letter).
    FasterThan(&'static str),
    /// Bonds turn vertical from the head to the end.
    FrontFromHead,
    /// The case's initial stage is in the same state as the other case's.
    StartsLike(&'static str),
}

/// One claim of the paper about Figure 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spec {
    /// Short identifier (tables).
    pub id: &'static str,
    /// "a", "b" or "c".
    pub case: &'static str,
    /// The paper's words.
    pub words: &'static str,
    /// What it states.
    pub kind: Kind,
}

/// The claims checked, in a fixed order.
pub const SPECS: [Spec; 9] = [
    Spec {
        id: "a_group_rotation",
        case: "a",
        words: "the long chain underwent reptile-like group-angular motion",
        kind: Kind::Early(Doing::Twisting),
    },
    Spec {
        id: "a_stretched",
        case: "a",
        words: "eventually stretched like a chopstick in the vertical direction",
        kind: Kind::Lasting(Doing::In(State::Stretched)),
    },
    Spec {
        id: "b_starts_like_a",
        case: "b",
        words: "the initial dynamics of the short colloidal chain was similar to that of case (a)",
        kind: Kind::StartsLike("a"),
    },
    Spec {
        id: "b_lasting_twisting",
        case: "b",
        words: "in the later state, everlasting twisting was observed instead of linear stretching",
        kind: Kind::Lasting(Doing::Twisting),
    },
    Spec {
        id: "c_faster_than_a",
        case: "c",
        words: "the big head leads to much faster settling motion in comparison to that in case (a)",
        kind: Kind::FasterThan("a"),
    },
    Spec {
        id: "c_faster_than_b",
        case: "c",
        words: "the big head leads to much faster settling motion in comparison to that in case (b)",
        kind: Kind::FasterThan("b"),
    },
    Spec {
        id: "c_early_twisting",
        case: "c",
        words: "the twisting motion was observed for a short period in the initial stage",
        kind: Kind::Early(Doing::Twisting),
    },
    Spec {
        id: "c_stretched",
        case: "c",
        words: "later, the chain primarily underwent full stretching",
        kind: Kind::Lasting(Doing::In(State::Stretched)),
    },
    Spec {
        id: "c_front_from_head",
        case: "c",
        words: "this local stretching propagated from the head to the end of the chain",
        kind: Kind::FrontFromHead,
    },
];

/// One claim's entry in `figure1.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Claim {
    /// [`Spec::id`].
    pub id: String,
    /// "a", "b" or "c".
    pub case: String,
    /// The paper's words.
    pub claim: String,
    /// The verdict.
    pub verdict: Verdict,
    /// When it holds (or held), `[t_start, t_end]`.
    pub window: Option<[f64; 2]>,
    /// The numbers the verdict rests on.
    pub evidence: Value,
}

/// One case's run, as the claims read it.
#[derive(Debug, Clone, Copy)]
pub struct CaseRun<'a> {
    /// "a", "b" or "c".
    pub case: &'a str,
    /// Observables at every frame.
    pub series: &'a [Observables],
    /// The stretching front.
    pub front: &'a Front,
}

/// The claims of [`SPECS`] whose cases are all among `runs` (with at least two frames).
pub fn claims(runs: &[CaseRun<'_>]) -> Vec<Claim> {
    let find = |c: &str| runs.iter().find(|r| r.case == c && r.series.len() >= 2);
    SPECS
        .iter()
        .filter_map(|spec| {
            let run = find(spec.case)?;
            let (verdict, window, evidence) = match spec.kind {
                Kind::Lasting(s) => lasting(run, s),
                Kind::Early(s) => early(run, s),
                Kind::FasterThan(o) => faster(run, find(o)?),
                Kind::FrontFromHead => front(run),
                Kind::StartsLike(o) => starts_like(run, find(o)?),
            };
            Some(Claim {
                id: spec.id.to_string(),
                case: spec.case.to_string(),
                claim: spec.words.to_string(),
                verdict,
                window,
                evidence,
            })
        })
        .collect()
}

type Judged = (Verdict, Option<[f64; 2]>, Value);

/// Start and end time of a run.
fn span(r: &CaseRun<'_>) -> (f64, f64) {
    (r.series[0].time, r.series[r.series.len() - 1].time)
}

/// Share of the frames in `[t0, t1]` that show `d`.
fn share(r: &CaseRun<'_>, d: Doing, t0: f64, t1: f64) -> f64 {
    let (mut n, mut yes) = (0usize, 0usize);
    for o in r.series.iter().filter(|o| o.time >= t0 && o.time <= t1) {
        n += 1;
        yes += usize::from(d.at(o));
    }
    if n > 0 { yes as f64 / n as f64 } else { 0.0 }
}

/// The named state of most frames in `[t0, t1]` (first in `State::ALL` on a tie).
fn most(r: &CaseRun<'_>, t0: f64, t1: f64) -> Option<State> {
    let mut counts = [0usize; State::ALL.len()];
    for o in r.series.iter().filter(|o| o.time >= t0 && o.time <= t1) {
        counts[o.state.0.index()] += 1;
    }
    State::ALL
        .into_iter()
        .filter(|k| counts[k.index()] > 0)
        .fold(None, |b: Option<State>, k| match b {
            Some(b) if counts[b.index()] >= counts[k.index()] => Some(b),
            _ => Some(k),
        })
}

/// A stretch of consecutive frames showing something: `[t_start, t_end]` as in the
/// timeline, and its number of frames.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Run {
    window: [f64; 2],
    frames: usize,
}

/// Every stretch of frames that show `d`, in time order.
fn runs(r: &CaseRun<'_>, d: Doing) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    let mut open = false;
    for o in r.series {
        let yes = d.at(o);
        match (yes, open, out.last_mut()) {
            (true, true, Some(g)) => {
                g.window[1] = o.time;
                g.frames += 1;
            }
            (true, _, _) => out.push(Run {
                window: [o.time, o.time],
                frames: 1,
            }),
            (false, true, Some(g)) => g.window[1] = o.time,
            (false, _, _) => {}
        }
        open = yes;
    }
    out
}

/// The runs of `d` that are seen (at least `MIN_FRAMES` frames).
fn seen(r: &CaseRun<'_>, d: Doing) -> Vec<Run> {
    runs(r, d)
        .into_iter()
        .filter(|g| g.frames >= MIN_FRAMES)
        .collect()
}

fn longest(gs: &[Run]) -> Option<&Run> {
    gs.iter().fold(None, |b: Option<&Run>, g| match b {
        Some(b) if b.window[1] - b.window[0] >= g.window[1] - g.window[0] => Some(b),
        _ => Some(g),
    })
}

/// Mean of `f` over the frames of `r` in `[t0, t1]`.
fn mean(r: &CaseRun<'_>, t0: f64, t1: f64, f: impl Fn(&Observables) -> f64) -> f64 {
    let v: Vec<f64> = r
        .series
        .iter()
        .filter(|o| o.time >= t0 && o.time <= t1)
        .map(f)
        .collect();
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn lasting(r: &CaseRun<'_>, d: Doing) -> Judged {
    let (t0, t1) = span(r);
    let late = t0 + 0.75 * (t1 - t0);
    let late_share = share(r, d, late, t1);
    let segs = seen(r, d);
    let last = r.series[r.series.len() - 1];
    let (verdict, win) = if late_share >= LATE_SHARE {
        (Verdict::Holds, runs(r, d).last().map(|g| g.window))
    } else if let Some(g) = longest(&segs) {
        (Verdict::Transient, Some(g.window))
    } else {
        (Verdict::Fails, None)
    };
    let widest = r.series.iter().fold(
        &r.series[0],
        |b, o| if o.extension > b.extension { o } else { b },
    );
    let evidence = json!({
        "state": d.name(),
        "late_window": [late, t1],
        "late_share": late_share,
        "late_state": most(r, late, t1).map(State::name),
        "final_state": last.state.0.name(),
        "overall_share": share(r, d, t0, t1),
        "final_extension": last.extension,
        "final_verticality": last.verticality,
        "max_extension": widest.extension,
        "max_extension_time": widest.time,
        "late_mean_spin_rate": mean(r, late, t1, |o| o.spin_rate),
        "late_mean_spin_coherence": mean(r, late, t1, |o| o.spin_coherence),
        "late_mean_poloidal_rate": mean(r, late, t1, |o| o.poloidal_rate),
        "late_mean_poloidal_coherence": mean(r, late, t1, |o| o.poloidal_coherence),
        "late_mean_vertical_run": mean(r, late, t1, |o| f64::from(o.vertical_run)),
    });
    (verdict, win, evidence)
}

fn early(r: &CaseRun<'_>, d: Doing) -> Judged {
    let (t0, t1) = span(r);
    let initial = t0 + 0.25 * (t1 - t0);
    let segs = seen(r, d);
    let first = segs.iter().find(|g| g.window[0] <= initial);
    let (verdict, win) = match (first, segs.first()) {
        (Some(g), _) => (Verdict::Holds, Some(g.window)),
        (None, Some(g)) => (Verdict::Transient, Some(g.window)),
        (None, None) => (Verdict::Fails, None),
    };
    let longest_any = runs(r, d).iter().map(|g| g.frames).max().unwrap_or(0);
    let evidence = json!({
        "state": d.name(),
        "initial_stage": [t0, initial],
        "initial_share": share(r, d, t0, initial),
        "initial_state": most(r, t0, initial).map(State::name),
        "longest_run_frames": longest_any,
        "min_frames": MIN_FRAMES,
        "initial_mean_spin_rate": mean(r, t0, initial, |o| o.spin_rate),
        "initial_mean_spin_coherence": mean(r, t0, initial, |o| o.spin_coherence),
        "late_share": share(r, d, t0 + 0.75 * (t1 - t0), t1),
    });
    (verdict, win, evidence)
}

/// Height of the centre of mass at time `t`, linear between frames (clamped).
fn com_z(r: &CaseRun<'_>, t: f64) -> f64 {
    let s = r.series;
    let k = s.partition_point(|o| o.time < t);
    if k == 0 {
        return s[0].com[2];
    }
    if k == s.len() {
        return s[k - 1].com[2];
    }
    let (a, b) = (&s[k - 1], &s[k]);
    let w = if b.time > a.time {
        (t - a.time) / (b.time - a.time)
    } else {
        1.0
    };
    a.com[2] + w * (b.com[2] - a.com[2])
}

/// Mean settling speed (height lost per time) over `[t0, t1]`; gravity is along -z in
/// the Figure 1 scenes.
fn settling(r: &CaseRun<'_>, t0: f64, t1: f64) -> f64 {
    if t1 > t0 {
        (com_z(r, t0) - com_z(r, t1)) / (t1 - t0)
    } else {
        0.0
    }
}

fn faster(r: &CaseRun<'_>, other: &CaseRun<'_>) -> Judged {
    let (t0, t1) = (span(r).0.max(span(other).0), span(r).1.min(span(other).1));
    let q = (t1 - t0) / 4.0;
    let ratio = |a: f64, b: f64| {
        let (u, v) = (settling(r, a, b), settling(other, a, b));
        if v > 0.0 { u / v } else { f64::INFINITY }
    };
    let quarters: Vec<[f64; 2]> = (0..4)
        .map(|k| [t0 + k as f64 * q, t0 + (k + 1) as f64 * q])
        .collect();
    let ratios: Vec<f64> = quarters.iter().map(|w| ratio(w[0], w[1])).collect();
    let overall = ratio(t0, t1);
    // The longest run of consecutive quarters where it holds (earliest on a tie).
    let (mut best, mut run): (Option<(usize, usize)>, Option<(usize, usize)>) = (None, None);
    for (k, &x) in ratios.iter().enumerate() {
        run = match (x >= FASTER, run) {
            (true, Some((a, _))) => Some((a, k)),
            (true, None) => Some((k, k)),
            (false, _) => None,
        };
        if let Some((a, b)) = run {
            if best.is_none_or(|(c, d)| b - a > d - c) {
                best = Some((a, b));
            }
        }
    }
    let all = ratios.iter().all(|&x| x >= FASTER) && overall >= FASTER;
    let (verdict, win) = match best {
        _ if all => (Verdict::Holds, Some([t0, t1])),
        Some((a, b)) => (Verdict::Transient, Some([quarters[a][0], quarters[b][1]])),
        None => (Verdict::Fails, None),
    };
    let finite = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
    let evidence = json!({
        "measure": "mean centre-of-mass settling speed (height lost / time)",
        "margin": FASTER,
        "span": [t0, t1],
        "speed": settling(r, t0, t1),
        "speed_other": settling(other, t0, t1),
        "other": other.case,
        "ratio": finite(overall),
        "quarter_ratios": ratios.iter().map(|&x| finite(x)).collect::<Vec<_>>(),
        "late_mean_com_speed": mean(r, t0 + 3.0 * q, t1, |o| o.com_speed),
        "late_mean_com_speed_other": mean(other, t0 + 3.0 * q, t1, |o| o.com_speed),
    });
    (verdict, win, evidence)
}

fn front(r: &CaseRun<'_>) -> Judged {
    let f = r.front;
    let bonds = f.first_vertical.len();
    let times: Vec<f64> = f.first_vertical.iter().flatten().copied().collect();
    let (lo, hi) = times
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    let enough = bonds > 0 && f.count as f64 >= FRONT_SHARE * bonds as f64;
    let (verdict, win) = if enough && f.correlation >= FRONT_CORRELATION {
        (Verdict::Holds, Some([lo, hi]))
    } else {
        (Verdict::Fails, None)
    };
    let evidence = json!({
        "near_vertical_cos": f.cos_min,
        "bonds": bonds,
        "bonds_turned_vertical": f.count,
        "index_time_correlation": f.correlation,
        "first_bond_time": f.first_vertical.first().copied().flatten(),
        "last_bond_time": f.first_vertical.last().copied().flatten(),
        "first_vertical": f.first_vertical,
    });
    (verdict, win, evidence)
}

fn starts_like(r: &CaseRun<'_>, other: &CaseRun<'_>) -> Judged {
    let stage = |x: &CaseRun<'_>| {
        let (t0, t1) = span(x);
        let end = t0 + 0.25 * (t1 - t0);
        let m = most(x, t0, end);
        let frac = m.map_or(0.0, |m| share(x, Doing::In(m), t0, end));
        (m, frac, [t0, end])
    };
    let (mine, theirs) = (stage(r), stage(other));
    let same = mine.0.is_some() && mine.0 == theirs.0;
    let verdict = if same { Verdict::Holds } else { Verdict::Fails };
    let evidence = json!({
        "initial_stage": mine.2,
        "initial_state": mine.0.map(State::name),
        "initial_state_share": mine.1,
        "other": other.case,
        "other_initial_state": theirs.0.map(State::name),
        "other_initial_state_share": theirs.1,
    });
    (verdict, same.then_some(mine.2), evidence)
}
