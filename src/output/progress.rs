//! The terminal progress bar of a run.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar on stderr over the path steps, e.g.
/// `[00:00:03] ########-------- 120/400 steps  p = 1.3551`.
///
/// Completely silent — nothing is printed, not even a final line — when built `quiet` or when
/// stderr is not a terminal (a pipe, a file, CI), so logs and redirected output stay clean.
#[derive(Debug, Clone)]
pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// A bar over `total_steps` steps (the step budget; the run may stop earlier), hidden when
    /// `quiet` or when stderr is not a terminal.
    pub fn new(total_steps: usize, quiet: bool) -> Self {
        let visible = !quiet && std::io::stderr().is_terminal();
        let bar = if visible {
            let style = ProgressStyle::with_template(
                "[{elapsed_precise}] {bar:30.cyan/blue} {pos}/{len} steps  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("#>-");
            ProgressBar::with_draw_target(Some(total_steps as u64), ProgressDrawTarget::stderr())
                .with_style(style)
        } else {
            ProgressBar::hidden()
        };
        Self { bar }
    }

    /// True if the bar is drawn (not quiet, stderr a terminal).
    pub fn is_visible(&self) -> bool {
        !self.bar.is_hidden()
    }

    /// Shows step `step` with `message`, typically the control's value (`p = 1.3551`).
    pub fn set(&self, step: usize, message: impl Into<String>) {
        self.bar.set_position(step as u64);
        self.bar.set_message(message.into());
    }

    /// Stops the bar where it is and leaves it on screen with `message` (e.g. why the path
    /// stopped), followed by a line break so later output starts on a line of its own
    /// (indicatif leaves the cursor at the end of the bar). A second call does nothing.
    pub fn finish(&self, message: impl Into<String>) {
        if self.bar.is_hidden() || self.bar.is_finished() {
            return;
        }
        self.bar.abandon_with_message(message.into());
        eprintln!();
    }
}
