//! A progress bar that shows the rate and the time left, and stays out of the way.
//!
//! The bar draws on standard error only when that is a terminal, and only once the job
//! has run for [`SHOW_AFTER`]: a job shorter than that, a piped run or a CI log never
//! sees it. It may be shared between threads (`&Progress` is enough to advance it).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long a job runs before its bar appears.
pub const SHOW_AFTER: Duration = Duration::from_secs(1);

const TEMPLATE: &str =
    "{msg:>12} [{wide_bar:.cyan/blue}] {pos}/{len} {per_sec:>12} elapsed {elapsed} ETA {eta}";

/// A progress bar over `total` units of work (steps, runs, ...).
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    delay: Duration,
    enabled: bool,
    shown: AtomicBool,
}

impl Progress {
    /// A bar labelled `label`, shown on standard error when it is a terminal and the
    /// job has lasted [`SHOW_AFTER`].
    pub fn new(total: u64, label: &str) -> Progress {
        Progress::with_options(total, label, std::io::stderr().is_terminal(), SHOW_AFTER)
    }

    /// A bar that never draws (it still counts).
    pub fn hidden(total: u64) -> Progress {
        Progress::with_options(total, "", false, SHOW_AFTER)
    }

    /// A bar that draws only if `enabled`, and then only after `delay`.
    pub fn with_options(total: u64, label: &str, enabled: bool, delay: Duration) -> Progress {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        if let Ok(style) = ProgressStyle::with_template(TEMPLATE) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(label.to_string());
        Progress {
            bar,
            start: Instant::now(),
            delay,
            enabled,
            shown: AtomicBool::new(false),
        }
    }

    /// Advances by `n` units.
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.maybe_show();
    }

    /// Sets the number of units done.
    pub fn set_position(&self, pos: u64) {
        self.bar.set_position(pos);
        self.maybe_show();
    }

    /// Units done so far.
    pub fn position(&self) -> u64 {
        self.bar.position()
    }

    /// Whether the bar has started drawing.
    pub fn is_visible(&self) -> bool {
        self.shown.load(Ordering::Relaxed)
    }

    /// Runs `f` with the bar hidden (for printing a line without tearing it).
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.bar.suspend(f)
    }

    /// Ends the bar and clears it from the terminal.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }

    fn maybe_show(&self) {
        if self.enabled
            && !self.shown.load(Ordering::Relaxed)
            && self.start.elapsed() >= self.delay
            && !self.shown.swap(true, Ordering::Relaxed)
        {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.bar.enable_steady_tick(Duration::from_millis(250));
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_bar_counts_but_never_shows() {
        let p = Progress::hidden(10);
        for _ in 0..10 {
            p.inc(1);
        }
        assert_eq!(p.position(), 10);
        assert!(!p.is_visible());
        p.finish();
    }

    #[test]
    fn short_jobs_stay_hidden() {
        let p = Progress::with_options(5, "short", true, Duration::from_secs(3600));
        p.inc(5);
        assert!(!p.is_visible());
    }

    #[test]
    fn long_jobs_show_after_the_delay() {
        let p = Progress::with_options(5, "long", true, Duration::ZERO);
        p.set_position(2);
        assert!(p.is_visible());
        assert_eq!(p.suspend(|| 7), 7);
        p.finish();
    }

    #[test]
    fn bar_is_shared_between_threads() {
        let p = Progress::hidden(400);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| (0..100).for_each(|_| p.inc(1)));
            }
        });
        assert_eq!(p.position(), 400);
    }
}
