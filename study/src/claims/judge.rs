//! The verdict of each kind of claim (the definitions are in the parent module's
//! documentation), with the numbers it rests on.

use hydrorattle::observables::FrameState;
use serde_json::{Value, json};

use super::{
    CaseRun, Doing, FASTER, FRONT_CORRELATION, FRONT_SHARE, LATE_SHARE, MIN_FRAMES, Verdict,
};
use hydrorattle_host::sim::Observables;

pub(super) type Judged = (Verdict, Option<[f64; 2]>, Value);

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

/// The named state of most frames in `[t0, t1]` (first in `FrameState::ALL` on a tie).
fn most(r: &CaseRun<'_>, t0: f64, t1: f64) -> Option<FrameState> {
    let mut counts = [0usize; FrameState::ALL.len()];
    for o in r.series.iter().filter(|o| o.time >= t0 && o.time <= t1) {
        counts[o.state.0.index()] += 1;
    }
    FrameState::ALL
        .into_iter()
        .filter(|k| counts[k.index()] > 0)
        .fold(None, |b: Option<FrameState>, k| match b {
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

pub(super) fn lasting(r: &CaseRun<'_>, d: Doing) -> Judged {
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
        "late_state": most(r, late, t1).map(FrameState::name),
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

pub(super) fn early(r: &CaseRun<'_>, d: Doing) -> Judged {
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
        "initial_state": most(r, t0, initial).map(FrameState::name),
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

pub(super) fn faster(r: &CaseRun<'_>, other: &CaseRun<'_>) -> Judged {
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
    let mut best: Option<(usize, usize)> = None;
    let mut run: Option<(usize, usize)> = None;
    for (k, &x) in ratios.iter().enumerate() {
        run = match (x >= FASTER, run) {
            (true, Some((a, _))) => Some((a, k)),
            (true, None) => Some((k, k)),
            (false, _) => None,
        };
        if let Some((a, b)) = run
            && best.is_none_or(|(c, d)| b - a > d - c)
        {
            best = Some((a, b));
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

pub(super) fn front(r: &CaseRun<'_>) -> Judged {
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

pub(super) fn starts_like(r: &CaseRun<'_>, other: &CaseRun<'_>) -> Judged {
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
        "initial_state": mine.0.map(FrameState::name),
        "initial_state_share": mine.1,
        "other": other.case,
        "other_initial_state": theirs.0.map(FrameState::name),
        "other_initial_state_share": theirs.1,
    });
    (verdict, same.then_some(mine.2), evidence)
}
