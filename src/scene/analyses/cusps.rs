//! `type = "cusp-curve"`: the cusps of a limit-point curve followed in a third parameter.

use super::super::error::{num, Problem};
use super::super::validate::{at_least, free_parameter};
use super::{AnalysisSpec, CriticalCurveAnalysis, CurveStart, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "cusp-curve"`: at each of `slices` equally spaced values of `third` over `range`
/// (and at values added between two of them, `bisections` times, where a pair of cusps
/// appears or vanishes) the critical curve of `type = "critical-curve"` in (`control`,
/// `second`): its path in the control from the start state carried to that value, the
/// point `from`, and the curve with its cusps. Where two neighbouring cusps merge and vanish
/// between slices, the end is located, measured and classified: a swallowtail, or lips or
/// beaks (docs/theory.md §11.12). The shared settings are those of every slice's curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct CuspCurveAnalysis {
    /// The parameter of the paths that find each slice's point.
    pub control: String,
    /// The other parameter of each slice's curve.
    pub second: String,
    /// The parameter of the slices.
    pub third: String,
    /// `[min, max]` of the third parameter over the slices.
    pub range: Vec<f64>,
    /// Number of slices of the grid (>= 2). Default 6.
    #[serde(default = "default_slices")]
    pub slices: usize,
    /// Slices added by halving the interval where a pair of cusps ends. Default 4.
    #[serde(default = "default_bisections")]
    pub bisections: usize,
    /// Which critical point of each path, as for `critical-curve`. Default `"limit"`.
    #[serde(default)]
    pub from: CurveStart,
    /// Step budget of each path that finds the point (>= 1). Default 200.
    #[serde(default = "default_path_steps")]
    pub path_steps: usize,
    /// The shared settings of every slice's curve.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

fn default_slices() -> usize {
    6
}
fn default_bisections() -> usize {
    4
}
fn default_path_steps() -> usize {
    200
}

impl CuspCurveAnalysis {
    /// The grid of the third parameter, ascending.
    pub fn values(&self) -> Vec<f64> {
        let [lo, hi] = [self.range[0], self.range[1]];
        let n = self.slices.max(2);
        (0..n)
            .map(|j| lo + (hi - lo) * j as f64 / (n - 1) as f64)
            .collect()
    }

    /// The critical curve of one slice, its curve's largest step `max_step` and its step
    /// budget `steps`; the other blocks are not watched (the slices need only the cusps).
    pub fn curve(&self, max_step: f64, steps: usize) -> CriticalCurveAnalysis {
        CriticalCurveAnalysis {
            control: self.control.clone(),
            second: self.second.clone(),
            from: self.from.clone(),
            from_run: None,
            path_steps: self.path_steps,
            watch: false,
            settings: Settings {
                max_step,
                steps,
                ..self.settings.clone()
            },
        }
    }
}

impl AnalysisSpec for CuspCurveAnalysis {
    fn shared(&self) -> &Settings {
        &self.settings
    }
    fn shared_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    /// Every curve's settings; the curves save no states along the way.
    fn settings(&self) -> Settings {
        self.settings.saving_no_states()
    }
    /// The steps of each path that finds the point.
    fn budget(&self) -> Option<usize> {
        Some(self.path_steps)
    }
    fn set_budget(&mut self, n: usize) {
        self.path_steps = n;
    }
    fn control(&self) -> Option<&str> {
        Some(&self.control)
    }
    fn free(&self) -> Option<Vec<&str>> {
        Some(vec![&self.control, &self.second, &self.third])
    }
    fn check(&self, scene: &Scene) -> Result<(), Problem> {
        free_parameter(scene, "analysis.control", &self.control)?;
        free_parameter(scene, "analysis.second", &self.second)?;
        free_parameter(scene, "analysis.third", &self.third)?;
        for (key, name) in [
            ("analysis.second", &self.second),
            ("analysis.third", &self.third),
        ] {
            if *name == self.control {
                return Err(Problem::at(
                    key,
                    format!("= \"{name}\" is the control; the three parameters must differ"),
                ));
            }
        }
        if self.third == self.second {
            return Err(Problem::at(
                "analysis.third",
                format!(
                    "= \"{}\" is the second parameter; the three parameters must differ",
                    self.third
                ),
            ));
        }
        let show: Vec<String> = self.range.iter().map(|x| num(*x)).collect();
        let ok = self.range.len() == 2
            && self.range.iter().all(|x| x.is_finite())
            && self.range[0] < self.range[1];
        if !ok {
            return Err(Problem::at(
                "analysis.range",
                format!(
                    "= [{}]: needs [min, max] with finite min < max",
                    show.join(", ")
                ),
            ));
        }
        let declared = &scene.parameters[&self.third];
        let outside = declared.min.is_some_and(|m| self.range[0] < m)
            || declared.max.is_some_and(|m| self.range[1] > m);
        if outside {
            let bound = |b: Option<f64>| b.map_or_else(|| "none".to_string(), num);
            return Err(Problem::at(
                "analysis.range",
                format!(
                    "= [{}]: outside [min, max] = [{}, {}] of parameters.{}",
                    show.join(", "),
                    bound(declared.min),
                    bound(declared.max),
                    self.third
                ),
            ));
        }
        at_least("analysis.slices", self.slices, 2)?;
        if self.slices > 200 {
            return Err(Problem::at(
                "analysis.slices",
                format!("must be <= 200, got {}", self.slices),
            ));
        }
        if self.bisections > 30 {
            return Err(Problem::at(
                "analysis.bisections",
                format!("must be <= 30, got {}", self.bisections),
            ));
        }
        if let CurveStart::Irrep(name) = &self.from {
            if name.trim().is_empty() {
                return Err(Problem::at(
                    "analysis.from",
                    "must be \"limit\", an irrep name or an index, got \"\"",
                ));
            }
        }
        at_least("analysis.path-steps", self.path_steps, 1)
    }
    /// The first slice's path and curve are kept as rows.
    fn stored_points(&self) -> (u64, u64) {
        let points = (self.settings.steps as u64).saturating_add(self.path_steps as u64);
        (points.saturating_add(2), 2)
    }
}
