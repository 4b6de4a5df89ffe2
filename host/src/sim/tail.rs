//! The late-time twist rate and late state, accumulated as the frames go by: the
//! least-squares slope of twist against time over the frames in the last quarter of the
//! run's time, and how many of those frames are in each named state, in constant memory
//! (running means and co-moments, updated in frame order, so a resumed run that replays
//! the same rows gets the same bits).

use hydrorattle::observables::FrameState;

use super::record::Observables;

/// Running least-squares slope of twist against time, for frames at or after `from`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TailSlope {
    from: f64,
    n: f64,
    mean_t: f64,
    mean_w: f64,
    /// Sum of (t - mean_t)^2.
    stt: f64,
    /// Sum of (t - mean_t)(w - mean_w).
    stw: f64,
    /// Frames in each state of [`FrameState::ALL`].
    states: [u64; FrameState::ALL.len()],
}

impl TailSlope {
    /// Collects the frames of a run that ends at `end` (the last quarter: from `3 end /
    /// 4`).
    pub(super) fn new(end: f64) -> Self {
        TailSlope {
            from: 0.75 * end,
            n: 0.0,
            mean_t: 0.0,
            mean_w: 0.0,
            stt: 0.0,
            stw: 0.0,
            states: [0; FrameState::ALL.len()],
        }
    }

    /// Takes a frame (ignored before the window).
    pub(super) fn add(&mut self, o: &Observables) {
        if o.time < self.from {
            return;
        }
        self.n += 1.0;
        self.states[o.state.0.index()] += 1;
        let dt = o.time - self.mean_t;
        self.mean_t += dt / self.n;
        self.mean_w += (o.twist - self.mean_w) / self.n;
        self.stt += dt * (o.time - self.mean_t);
        self.stw += dt * (o.twist - self.mean_w);
    }

    /// The state of most frames in the window (the first in [`FrameState::ALL`] on a tie);
    /// None without frames.
    pub(super) fn late_state(&self) -> Option<FrameState> {
        let mut best: Option<(FrameState, u64)> = None;
        for s in FrameState::ALL {
            let n = self.states[s.index()];
            if n > 0 && best.is_none_or(|b| n > b.1) {
                best = Some((s, n));
            }
        }
        best.map(|b| b.0)
    }

    /// The slope (0 with fewer than two frames or no spread in time).
    pub(super) fn slope(&self) -> f64 {
        if self.n >= 2.0 && self.stt > 0.0 {
            self.stw / self.stt
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_of_a_line_over_the_last_quarter() {
        let mut s = TailSlope::new(10.0);
        for k in 0..=100 {
            let t = k as f64 * 0.1;
            // Flat, then a slope of 3 over the last quarter.
            let w = if t < 7.5 { 1.0 } else { 1.0 + 3.0 * (t - 7.5) };
            s.add(&Observables {
                time: t,
                twist: w,
                ..Observables::default()
            });
        }
        assert!((s.slope() - 3.0).abs() < 1e-12, "{}", s.slope());
        assert_eq!(TailSlope::new(1.0).slope(), 0.0);
    }

    #[test]
    fn the_late_state_is_the_most_frequent_in_the_last_quarter() {
        use super::super::record::Label;
        let mut s = TailSlope::new(10.0);
        assert_eq!(s.late_state(), None);
        // Stretched early (outside the window), rotating in 3 late frames, folded in 2.
        let states = [
            (1.0, FrameState::Stretched),
            (2.0, FrameState::Stretched),
            (3.0, FrameState::Stretched),
            (7.6, FrameState::Folded),
            (8.0, FrameState::Rotating),
            (8.5, FrameState::Folded),
            (9.0, FrameState::Rotating),
            (10.0, FrameState::Rotating),
        ];
        for (time, st) in states {
            s.add(&Observables {
                time,
                state: Label(st),
                ..Observables::default()
            });
        }
        assert_eq!(s.late_state(), Some(FrameState::Rotating));
    }
}
