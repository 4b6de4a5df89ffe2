//! Configurations kept in memory for pictures: at a step cadence (animations) and at
//! chosen times (snapshots), in bounded memory.

use hydrorattle::Real;

use super::{Beads, snapshot};

/// Most configurations kept at a cadence: a wider cadence is used past this.
pub const MAX_FRAMES: usize = 1000;
/// Most bead positions kept at a cadence over all frames (about 32 bytes each): a big
/// scene keeps fewer frames.
pub const MAX_FRAME_BEADS: usize = 4_000_000;

/// Which configurations a run keeps in memory ([`RunResult::frames`](super::RunResult::frames),
/// [`RunResult::at`](super::RunResult::at)).
#[derive(Debug, Clone, Copy, Default)]
pub struct KeepFrames<'a> {
    /// Keep the configuration every this many steps, counted from step 0, and the last
    /// one; None: none at a cadence. Widened when needed so that at most
    /// [`MAX_FRAMES`] frames and [`MAX_FRAME_BEADS`] bead positions are kept.
    pub every: Option<usize>,
    /// Keep the configuration at each of these simulated times, snapped to the first
    /// step at or after it (step `ceil(t / dt)`, up to rounding by `1e-9` of a step).
    pub at: &'a [f64],
}

/// The step whose time is the first at or after `t`.
pub fn step_at_or_after(t: f64, dt: f64) -> usize {
    ((t / dt) - 1e-9).ceil().max(0.0) as usize
}

/// Takes the configurations asked for as the steps go by.
pub(super) struct Keeper {
    every: Option<usize>,
    /// `(step, request index)`, by step.
    at: Vec<(usize, usize)>,
    next_at: usize,
    frames: Vec<Snapshot>,
    at_snapshots: Vec<Option<Snapshot>>,
    last_step: Option<usize>,
}

impl Keeper {
    /// For a run of `steps` steps of `dt` with `particles` beads.
    pub(super) fn new(keep: &KeepFrames<'_>, steps: usize, dt: f64, particles: usize) -> Self {
        let most = MAX_FRAMES.min(MAX_FRAME_BEADS / particles.max(1)).max(2);
        let every = keep
            .every
            .map(|e| e.max(1).max(steps.div_ceil(most - 1).max(1)));
        let mut at: Vec<(usize, usize)> = keep
            .at
            .iter()
            .enumerate()
            .map(|(k, &t)| (step_at_or_after(t, dt), k))
            .collect();
        at.sort_unstable();
        Keeper {
            every,
            at,
            next_at: 0,
            frames: Vec::new(),
            at_snapshots: vec![None; keep.at.len()],
            last_step: None,
        }
    }

    /// Takes the configuration of step `step` if asked for (steps in increasing order).
    pub(super) fn take<T: Real>(&mut self, step: usize, beads: &Beads<T>) {
        let take = || snapshot::<T>(&beads.pos, &beads.radius, beads.time);
        if self.every.is_some_and(|e| step.is_multiple_of(e)) {
            self.frames.push(take());
            self.last_step = Some(step);
        }
        while let Some(&(s, k)) = self.at.get(self.next_at) {
            if s > step {
                break;
            }
            if s == step {
                self.at_snapshots[k] = Some(take());
            }
            self.next_at += 1;
        }
    }

    /// The frames (the last step `done` added when off the cadence) and the snapshots
    /// at the chosen times (None for a time past the run's last step).
    pub(super) fn finish<T: Real>(
        mut self,
        done: usize,
        beads: &Beads<T>,
    ) -> (Vec<Snapshot>, Vec<Option<Snapshot>>) {
        if self.every.is_some() && self.last_step != Some(done) {
            self.frames
                .push(snapshot::<T>(&beads.pos, &beads.radius, beads.time));
        }
        (self.frames, self.at_snapshots)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_snap_to_the_first_step_at_or_after() {
        assert_eq!(step_at_or_after(0.0, 0.005), 0);
        assert_eq!(step_at_or_after(1.0, 0.005), 200);
        assert_eq!(step_at_or_after(1.001, 0.005), 201);
        assert_eq!(step_at_or_after(0.1 + 0.2, 0.1), 3);
    }

    #[test]
    fn the_cadence_is_widened_to_bound_memory() {
        let keep = KeepFrames {
            every: Some(1),
            at: &[],
        };
        let k = Keeper::new(&keep, 1_000_000, 0.01, 25);
        assert!(1_000_000 / k.every.unwrap() < MAX_FRAMES);
        // Room for 4 frames of a million beads: steps 0, 334, 668 and the last.
        let k = Keeper::new(&keep, 1000, 0.01, 1_000_000);
        assert_eq!(k.every, Some(334));
    }
}

/// Sphere centres and radii at one moment: a frame of a run, as the pictures draw it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Snapshot {
    /// Simulated time.
    pub time: f64,
    /// Centres.
    pub positions: Vec<[f64; 3]>,
    /// Radii.
    pub radii: Vec<f64>,
    /// The height of the scene's wall, the plane `z = wall` below the spheres (side
    /// views draw it).
    pub wall: Option<f64>,
}
