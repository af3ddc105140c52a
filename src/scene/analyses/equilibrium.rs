//! `type = "equilibrium"`: the start state alone, with its stability.

use super::super::error::Problem;
use super::{AnalysisSpec, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "equilibrium"`: one Newton solve at the start values (its tolerance and iterations
/// are the shared `tolerance` and `max-iterations`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct EquilibriumAnalysis {
    /// The shared settings: Newton's tolerance and iterations.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

impl AnalysisSpec for EquilibriumAnalysis {
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
        None
    }
    fn set_budget(&mut self, _n: usize) {}
    fn control(&self) -> Option<&str> {
        None
    }
    fn check(&self, _scene: &Scene) -> Result<(), Problem> {
        Ok(())
    }
    fn stored_points(&self) -> (u64, u64) {
        (1, 1)
    }
}
