//! `type = "linear-buckling"`: the start state held while the control sweeps its range.

use super::super::error::Problem;
use super::super::load::key_path;
use super::super::validate::{at_least, known_parameter};
use super::super::ConstraintKind;
use super::{AnalysisSpec, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "linear-buckling"`: the critical loads of the start state. The start state is solved
/// at the start values and then held — taken as a trivial solution whose shape does not
/// depend on the control (a flat pre-stretched disc under fluid at its rim, say) — while the
/// control runs over `[min, max]` of its parameter in `samples` equal steps. Wherever a block's
/// eigenvalue changes sign between two samples, the critical value is localised to round-off
/// and classified by its irrep. Other parameters stay at their start values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct LinearBucklingAnalysis {
    /// The swept parameter (it needs `min` and `max`).
    pub control: String,
    /// Number of equal steps over `[min, max]` (≥ 1). Default 200.
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// The shared settings: Newton's tolerance and iterations for the start state.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

fn default_samples() -> usize {
    200
}

impl AnalysisSpec for LinearBucklingAnalysis {
    fn shared(&self) -> &Settings {
        &self.settings
    }
    fn shared_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    /// Newton's tolerance and iterations; the driver's defaults for the rest.
    fn settings(&self) -> Settings {
        self.settings.newton_only()
    }
    fn budget(&self) -> Option<usize> {
        Some(self.samples)
    }
    fn set_budget(&mut self, n: usize) {
        self.samples = n;
    }
    fn holds_state(&self) -> bool {
        true
    }
    fn control(&self) -> Option<&str> {
        Some(&self.control)
    }
    /// The swept parameter is held at each sample, not free.
    fn free(&self) -> Option<Vec<&str>> {
        None
    }
    fn check(&self, scene: &Scene) -> Result<(), Problem> {
        known_parameter(&scene.parameters, "analysis.control", &self.control)?;
        let p = &scene.parameters[&self.control];
        if p.min.is_none() || p.max.is_none() {
            return Err(Problem::at(
                &key_path("parameters", &self.control),
                "needs both min and max: linear-buckling sweeps the control over [min, max]",
            ));
        }
        if let Some((i, c)) = scene
            .constraints
            .iter()
            .enumerate()
            .find(|(_, c)| c.kind() != ConstraintKind::Fixed)
        {
            return Err(Problem::at(
                &format!("constraint[{i}]"),
                format!(
                    "type = \"{}\" cannot be active in a linear-buckling analysis (the state is \
                     held)",
                    c.kind()
                ),
            ));
        }
        at_least("analysis.samples", self.samples, 1)
    }
    fn stored_points(&self) -> (u64, u64) {
        ((self.samples as u64).saturating_add(1), 1)
    }
}
