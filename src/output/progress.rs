//! The terminal progress bar of a run.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// Positions of the bar across the control's range.
const TICKS: u64 = 1000;

/// A progress bar on stderr that shows what a run can know as it goes: the points converged
/// so far and where the control stands in its range, e.g.
/// `[00:00:03] ########-------- p = 1.35510 in [0, 2], 120 points`. The bar is the control's
/// place between the bounds of its range (a path may turn back, so it may move back too); a
/// control without two finite bounds gets a spinner instead. The step budget is not shown: a
/// path usually stops long before it (a stop condition, a bound).
///
/// Completely silent — nothing is printed, not even a final line — when built `quiet` or when
/// stderr is not a terminal (a pipe, a file, CI), so logs and redirected output stay clean.
#[derive(Debug, Clone)]
pub struct Progress {
    bar: ProgressBar,
    control: String,
    range: Option<(f64, f64)>,
}

impl Progress {
    /// A bar for the control `control` over `range` (its bounds, when both are finite and
    /// distinct), hidden when `quiet` or when stderr is not a terminal.
    pub fn new(control: &str, range: Option<(f64, f64)>, quiet: bool) -> Self {
        let range = range.filter(|(a, b)| a.is_finite() && b.is_finite() && b > a);
        let visible = !quiet && std::io::stderr().is_terminal();
        let bar = if visible {
            let (template, len) = match range {
                Some(_) => ("[{elapsed_precise}] {bar:30.cyan/blue} {msg}", Some(TICKS)),
                None => ("[{elapsed_precise}] {spinner} {msg}", None),
            };
            let style = ProgressStyle::with_template(template)
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("#>-");
            ProgressBar::with_draw_target(len, ProgressDrawTarget::stderr()).with_style(style)
        } else {
            ProgressBar::hidden()
        };
        Self {
            bar,
            control: control.to_string(),
            range,
        }
    }

    /// True if the bar is drawn (not quiet, stderr a terminal).
    pub fn is_visible(&self) -> bool {
        !self.bar.is_hidden()
    }

    /// Shows that `points` points have converged, the last at control value `value`.
    pub fn set(&self, points: usize, value: f64) {
        if let Some(f) = fraction(value, self.range) {
            self.bar.set_position((f * TICKS as f64).round() as u64);
        } else {
            self.bar.tick();
        }
        self.bar
            .set_message(message(&self.control, value, self.range, points));
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

/// Where `value` lies in `range`, clamped to [0, 1] (`None` without a range or for a
/// non-finite value).
pub fn fraction(value: f64, range: Option<(f64, f64)>) -> Option<f64> {
    let (a, b) = range?;
    let f = (value - a) / (b - a);
    f.is_finite().then(|| f.clamp(0.0, 1.0))
}

/// The bar's message: `p = 1.35510 in [0, 2], 120 points` (the value to six significant
/// digits; without a range: `p = 1.35510, 120 points`).
pub fn message(control: &str, value: f64, range: Option<(f64, f64)>, points: usize) -> String {
    let v = crate::text::sig_digits(value, 6);
    // The bounds as the scene gives them (shortest round trip).
    let range = range.map_or_else(String::new, |(a, b)| format!(" in [{a}, {b}]"));
    let points = if points == 1 {
        "1 point".to_string()
    } else {
        format!("{points} points")
    };
    format!("{control} = {v}{range}, {points}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_shows_the_control_in_its_range_and_the_points() {
        let r = Some((0.0, 2.0));
        assert_eq!(fraction(0.5, r), Some(0.25));
        assert_eq!(fraction(-1.0, r), Some(0.0));
        assert_eq!(fraction(3.0, r), Some(1.0));
        assert_eq!(fraction(1.0, None), None);
        assert_eq!(fraction(f64::NAN, r), None);
        assert_eq!(
            message("p", 1.25, r, 120),
            "p = 1.25000 in [0, 2], 120 points"
        );
        assert_eq!(message("h", 0.5, None, 1), "h = 0.500000, 1 point");
        // A quiet bar takes every call and prints nothing.
        let bar = Progress::new("p", Some((2.0, 1.0)), true);
        assert!(!bar.is_visible());
        bar.set(3, 1.5);
        bar.finish("done");
    }
}
