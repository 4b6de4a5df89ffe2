//! The CLI's display of progress ([`hydrorattle_host::progress`]): a bar that shows the
//! rate and the time left, and stays out of the way.
//!
//! The bar draws on standard error only when that is a terminal, and only once the job
//! has run for [`SHOW_AFTER`]: a job shorter than that, a piped run or a CI log never
//! sees it. It may be shared between threads (`&Bar` is enough to advance it).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long a job runs before its bar appears.
pub const SHOW_AFTER: Duration = Duration::from_secs(1);

const TEMPLATE: &str =
    "{msg:>12} [{wide_bar:.cyan/blue}] {pos}/{len} {per_sec:>12} elapsed {elapsed} ETA {eta}";

/// A progress bar over `total` units of work (steps, runs, ...).
pub struct Bar {
    bar: ProgressBar,
    start: Instant,
    delay: Duration,
    enabled: bool,
    shown: AtomicBool,
}

impl Bar {
    /// A bar labelled `label`, shown on standard error when it is a terminal and the
    /// job has lasted [`SHOW_AFTER`].
    pub fn new(total: u64, label: &str) -> Bar {
        Bar::with_options(total, label, std::io::stderr().is_terminal(), SHOW_AFTER)
    }

    /// A bar that draws only if `enabled`, and then only after `delay`.
    pub fn with_options(total: u64, label: &str, enabled: bool, delay: Duration) -> Bar {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        if let Ok(style) = ProgressStyle::with_template(TEMPLATE) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(label.to_string());
        Bar {
            bar,
            start: Instant::now(),
            delay,
            enabled,
            shown: AtomicBool::new(false),
        }
    }

    /// Sets the number of units done.
    pub fn set_position(&self, pos: u64) {
        self.bar.set_position(pos);
        self.maybe_show();
    }

    /// Whether the bar has started drawing.
    #[cfg(test)]
    fn is_visible(&self) -> bool {
        self.shown.load(Ordering::Relaxed)
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

impl Drop for Bar {
    fn drop(&mut self) {
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
        }
    }
}

impl hydrorattle_host::progress::Display for Bar {
    fn set_position(&self, done: u64) {
        Bar::set_position(self, done);
    }

    fn finish(&self) {
        Bar::finish(self);
    }
}

/// Shows every later job's progress of the host library as a bar on standard error.
pub fn install() {
    hydrorattle_host::progress::install(|total, label| Box::new(Bar::new(total, label)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_jobs_stay_hidden() {
        let p = Bar::with_options(5, "short", true, Duration::from_secs(3600));
        p.set_position(5);
        assert!(!p.is_visible());
    }

    #[test]
    fn long_jobs_show_after_the_delay() {
        let p = Bar::with_options(5, "long", true, Duration::ZERO);
        p.set_position(2);
        assert!(p.is_visible());
        p.finish();
    }

    #[test]
    fn a_disabled_bar_never_shows() {
        let p = Bar::with_options(5, "piped", false, Duration::ZERO);
        p.set_position(5);
        assert!(!p.is_visible());
    }
}
