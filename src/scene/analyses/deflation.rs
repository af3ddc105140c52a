//! `type = "deflation"`: the solutions at given control values other than the known ones.

use super::super::error::{num, Problem};
use super::super::validate::{at_least, free_parameter, positive};
use super::{AnalysisSpec, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "deflation"`: the path through the start state in `control` (as `type = "path"`
/// follows it), then, at every value of `at` (default the start's control value), from a
/// solution known there (the start state, the path's state at the value, or the start state
/// carried to it), deflated Newton (docs/theory.md §16) for up to `solutions` other
/// solutions, from first guesses that scale each known solution's state by 1 + a for every a
/// in `offsets` and move it along the path's tangent by a times its size, with every known
/// solution deflated. Each solution found says whether the path through the start reaches
/// it; with `follow`, the piece of path through it is followed in the control for `steps`
/// steps — the pieces the start's path does not reach (disconnected paths, isolas).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct DeflationAnalysis {
    /// The parameter of the paths.
    pub control: String,
    /// The control values where solutions are sought. Default: the start value alone.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub at: Vec<f64>,
    /// At most this many solutions besides the start state (1 to 20). Default 4.
    #[serde(default = "default_solutions")]
    pub solutions: usize,
    /// The first guesses' offsets: each known solution's state scaled by 1 + a, then moved
    /// along the path's tangent there by a times its size. Default [0.5, 2, -0.5].
    #[serde(default = "default_offsets")]
    pub offsets: Vec<f64>,
    /// Follow the piece of path through every solution found. Default true.
    #[serde(default = "default_follow")]
    pub follow: bool,
    /// The deflation's power p (> 0). Default 2.
    #[serde(default = "default_power")]
    pub power: f64,
    /// The deflation's shift σ (> 0). Default 1.
    #[serde(default = "default_shift")]
    pub shift: f64,
    /// The shared settings: the paths' steps, step sizes and direction, Newton's tolerance
    /// and iterations (a deflated step is at most `max-step` long).
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

fn default_solutions() -> usize {
    4
}
fn default_offsets() -> Vec<f64> {
    vec![0.5, 2.0, -0.5]
}
fn default_follow() -> bool {
    true
}
fn default_power() -> f64 {
    2.0
}
fn default_shift() -> f64 {
    1.0
}

impl AnalysisSpec for DeflationAnalysis {
    fn shared(&self) -> &Settings {
        &self.settings
    }
    fn shared_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    fn control(&self) -> Option<&str> {
        Some(&self.control)
    }
    fn check(&self, scene: &Scene) -> Result<(), Problem> {
        free_parameter(scene, "analysis.control", &self.control)?;
        at_least("analysis.solutions", self.solutions, 1)?;
        if self.solutions > 20 {
            return Err(Problem::at(
                "analysis.solutions",
                format!("must be <= 20, got {}", self.solutions),
            ));
        }
        if self.offsets.is_empty() {
            return Err(Problem::at(
                "analysis.offsets",
                "= []: needs at least one offset (the first guesses scale a solution's displacement by 1 + a)",
            ));
        }
        for (i, &a) in self.offsets.iter().enumerate() {
            let key = format!("analysis.offsets[{i}]");
            if !a.is_finite() || a == 0.0 || a <= -1.0 {
                return Err(Problem::at(
                    &key,
                    format!(
                        "must be a finite number > -1 and not 0 (1 + a scales the displacement), got {}",
                        num(a)
                    ),
                ));
            }
        }
        let bounds = scene.parameters.get(&self.control);
        for (i, &v) in self.at.iter().enumerate() {
            let key = format!("analysis.at[{i}]");
            let outside = bounds
                .is_some_and(|p| p.min.is_some_and(|m| v < m) || p.max.is_some_and(|m| v > m));
            if !v.is_finite() || outside {
                return Err(Problem::at(
                    &key,
                    format!(
                        "= {}: must be a finite value of {} within its [min, max]",
                        num(v),
                        self.control
                    ),
                ));
            }
        }
        positive("analysis.power", self.power)?;
        positive("analysis.shift", self.shift)
    }
    /// The path through the start and every piece.
    fn stored_points(&self) -> (u64, u64) {
        let points = (self.settings.steps as u64).saturating_add(1);
        let searches = self.at.len().max(1) as u64;
        (
            points.saturating_mul((self.solutions as u64 + 1).saturating_mul(searches)),
            points / (self.settings.save_every.max(1) as u64) + 2,
        )
    }
}
