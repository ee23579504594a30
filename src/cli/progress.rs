//! The progress bar of `ricochet run` (indicatif), drawn only when stderr is a terminal:
//! simulated time against the end time, steps, rate and ETA.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

/// The bar, or nothing when stderr is not a terminal.
pub struct Bar(Option<ProgressBar>);

impl Bar {
    /// A bar on stderr if it is a terminal.
    pub fn on_stderr() -> Self {
        if !std::io::stderr().is_terminal() {
            return Self(None);
        }
        let bar = ProgressBar::new(10_000);
        let Ok(style) =
            ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} [{per_sec}, ETA {eta}]")
        else {
            return Self(None);
        };
        bar.set_style(style);
        Self(Some(bar))
    }

    /// Shows simulated time `t` of `end` after `steps` steps.
    pub fn tick(&self, t: f64, end: f64, steps: u64) {
        if let Some(b) = &self.0 {
            b.set_position((t / end * 10_000.0).min(10_000.0) as u64);
            b.set_message(format!("t = {t:.4e} s, {steps} steps"));
        }
    }

    /// Clears the bar.
    pub fn finish(self) {
        if let Some(b) = self.0 {
            b.finish_and_clear();
        }
    }
}
