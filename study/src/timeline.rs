//! The outcome timeline of a run: its named state at every output frame
//! (`observables.csv`'s `state` column), compressed into segments of one state.
//!
//! A segment runs from the time of its first frame to the time of the next segment's
//! first frame (the last one to the last frame's time), so the segments of a run tile
//! its time without gaps: a strip of `(t_start, t_end, state)` bars draws it.

use hydrorattle::observables::FrameState;
use serde::Serialize;

use hydrorattle_host::sim::Observables;

/// A stretch of frames in one state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Segment {
    /// The state ([`FrameState::name`] in files).
    #[serde(serialize_with = "state_by_name")]
    pub state: FrameState,
    /// Time of the segment's first frame.
    pub t_start: f64,
    /// Time of the next segment's first frame (the last frame's for the last segment).
    pub t_end: f64,
    /// Frames in the segment.
    pub frames: usize,
}

fn state_by_name<S: serde::Serializer>(s: &FrameState, ser: S) -> Result<S::Ok, S::Error> {
    ser.serialize_str(s.name())
}

/// `t` rounded to a nanosecond of simulated time: frame times are sums of time steps,
/// and `2.0000000000000004` reads as 2 in a file meant for people.
pub fn tidy(t: f64) -> f64 {
    (t * 1e9).round() / 1e9
}

/// The series' states as segments, in time order (times [`tidy`]).
pub fn segments(series: &[Observables]) -> Vec<Segment> {
    let mut out: Vec<Segment> = Vec::new();
    for o in series {
        match out.last_mut() {
            Some(s) if s.state == o.state.0 => {
                s.t_end = tidy(o.time);
                s.frames += 1;
            }
            last => {
                if let Some(s) = last {
                    s.t_end = tidy(o.time);
                }
                out.push(Segment {
                    state: o.state.0,
                    t_start: tidy(o.time),
                    t_end: tidy(o.time),
                    frames: 1,
                });
            }
        }
    }
    out
}

/// `(time, state name)` at every frame, for a strip picture.
pub fn states(series: &[Observables]) -> Vec<(f64, &'static str)> {
    series.iter().map(|o| (o.time, o.state.0.name())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hydrorattle_host::sim::Label;

    fn frame(time: f64, s: FrameState) -> Observables {
        Observables {
            time,
            state: Label(s),
            ..Observables::default()
        }
    }

    #[test]
    fn segments_tile_the_run() {
        let series = [
            frame(0.0, FrameState::Other),
            frame(2.0, FrameState::Rotating),
            frame(4.0, FrameState::Rotating),
            frame(6.0, FrameState::Stretched),
        ];
        let s = segments(&series);
        let got: Vec<(FrameState, f64, f64, usize)> = s
            .iter()
            .map(|g| (g.state, g.t_start, g.t_end, g.frames))
            .collect();
        assert_eq!(
            got,
            [
                (FrameState::Other, 0.0, 2.0, 1),
                (FrameState::Rotating, 2.0, 6.0, 2),
                (FrameState::Stretched, 6.0, 6.0, 1),
            ]
        );
        assert!(segments(&[]).is_empty());
        assert_eq!(states(&series)[1], (2.0, "rotating"));
    }
}
