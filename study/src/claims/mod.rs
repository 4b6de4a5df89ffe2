//! The paper's claims about Figure 1, one by one, each with a verdict computed from the
//! runs' observables (never written by hand).
//!
//! Windows of a run of duration `T` starting at `t0`: the *initial stage* is the first
//! quarter `[t0, t0 + T/4]`, the *late window* the last quarter `[t0 + 3T/4, t0 + T]`.
//! A claim about a state reads either a named state of the timeline (stretched) or
//! *twisting*: coherent rotation about the vertical
//! ([`is_rotating`]) whatever the shape, since
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

mod judge;
mod sensitivity;

pub use sensitivity::claim_tables;

use hydrorattle::observables::{FrameState, Rotation, StateThresholds, is_rotating};
use serde::Serialize;
use serde_json::Value;

use hydrorattle_host::sim::{Front, Observables};
use judge::{early, faster, front, lasting, starts_like};

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
    In(FrameState),
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
        kind: Kind::Lasting(Doing::In(FrameState::Stretched)),
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
        kind: Kind::Lasting(Doing::In(FrameState::Stretched)),
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
                window: window.map(|w| w.map(crate::timeline::tidy)),
                evidence,
            })
        })
        .collect()
}
