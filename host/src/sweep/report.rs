//! What a process did with its points: each point's outcome, a line printed for it,
//! and the counts ([`RunReport`]).

use super::Point;
use super::file::describe;
use crate::sim::Summary;

/// What happened to one point.
#[derive(Debug, Clone)]
pub enum Outcome {
    /// Already finished: not run.
    Skipped,
    /// Another process holds the point's lock (it is running it): not run.
    Locked,
    /// Run, from the start or from its checkpoint (`resumed_from`).
    Ran(Box<Summary>),
    /// Could not be run (the message is also in the folder's `error.txt`, unless the
    /// folder is another sweep's).
    Failed(String),
    /// Stopped on request (by this signal) and checkpointed.
    Interrupted(usize),
    /// Not started: a stop was requested before its turn.
    NotStarted,
}

/// What a process did.
#[derive(Debug, Clone, Default)]
pub struct RunReport {
    /// Points selected.
    pub selected: usize,
    /// Already finished.
    pub skipped: usize,
    /// Skipped: another process was running them.
    pub locked: usize,
    /// Run from the start.
    pub ran: usize,
    /// Continued from a checkpoint.
    pub resumed: usize,
    /// Runs that stopped early (a step failed): finished, with their failure recorded.
    pub stopped_early: Vec<String>,
    /// Points that could not be run, with why.
    pub failed: Vec<(String, String)>,
    /// Points stopped on request and checkpointed (they resume when run again).
    pub interrupted: usize,
    /// Points not started because a stop was requested.
    pub not_started: usize,
    /// The signal that asked this process to stop, if one did.
    pub signal: Option<usize>,
}

impl std::fmt::Display for RunReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "ran {} of {} points ({} from the start, {} resumed from their checkpoints), {} already finished, {} stopped early, {} failed",
            self.ran + self.resumed,
            self.selected,
            self.ran,
            self.resumed,
            self.skipped,
            self.stopped_early.len(),
            self.failed.len()
        )?;
        if self.locked > 0 {
            write!(f, ", {} skipped: locked by another process", self.locked)?;
        }
        if let Some(sig) = self.signal {
            write!(
                f,
                "; stopped by signal {sig}: {} checkpointed, {} not started (run again to go on)",
                self.interrupted, self.not_started
            )?;
        }
        Ok(())
    }
}

impl RunReport {
    /// Counts the outcome of point `p` and prints its line.
    pub(super) fn tally(&mut self, p: &Point, outcome: Outcome) {
        let what = describe(&p.params);
        match outcome {
            Outcome::Skipped => self.skipped += 1,
            Outcome::Locked => {
                self.locked += 1;
                println!("{} {what}: skipped: locked by another process", p.id);
            }
            Outcome::Ran(s) => {
                let how = match s.resumed_from {
                    Some(t) => {
                        self.resumed += 1;
                        format!("resumed from t = {t}")
                    }
                    None => {
                        self.ran += 1;
                        "ran".to_string()
                    }
                };
                if let Some(f) = &s.failure {
                    self.stopped_early.push(p.id.clone());
                    println!("{} {what}: {how}, stopped early: {f}", p.id);
                } else {
                    println!(
                        "{} {what}: {how}, {} steps at {:.0} steps/s, outcome {}",
                        p.id, s.steps_done, s.steps_per_second, s.outcome
                    );
                }
            }
            Outcome::Failed(why) => {
                println!("{} {what}: FAILED: {why}", p.id);
                self.failed.push((p.id.clone(), why));
            }
            Outcome::Interrupted(sig) => {
                self.interrupted += 1;
                println!("{} {what}: stopped by signal {sig}, checkpointed", p.id);
            }
            Outcome::NotStarted => self.not_started += 1,
        }
    }
}
