//! `type = "diagram"`: the global bifurcation diagram — the path, the branches of its
//! bifurcation points to a depth, and the second pieces beside its folds.

use super::super::error::Problem;
use super::super::validate::{at_least, free_parameter, positive};
use super::path::{check_stops, check_stretch_needs_closed, MAX_BRANCH_DEPTH};
use super::{AnalysisSpec, BranchesAnalysis, PathAnalysis, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "diagram"`: the path in `control` (as `type = "path"` follows it, with
/// `stop-stretch` and `stop-displacement`), the branches of every bifurcation point to
/// `depth` levels (each branch once: a branch that is a group image of a known one, or reaches
/// a known critical point, is merged or ends there as a connection), and beside every fold of
/// the path the second piece of an imperfect bifurcation, if there is one, followed for
/// `partner-steps` steps beyond the fold (docs/theory.md §14, §16.4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct DiagramAnalysis {
    /// The parameter that is free on the path.
    pub control: String,
    /// Stop the path where the volume stretch reaches this value (closed membranes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_stretch: Option<f64>,
    /// Stop the path where the largest displacement reaches this value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_displacement: Option<f64>,
    /// Levels of branches: 1, the path's; 2, also the branches' own; 3 at most. Default 2.
    #[serde(default = "default_depth")]
    pub depth: usize,
    /// Points of each branch after the point it leaves. Default 40.
    #[serde(default = "default_branch_steps")]
    pub branch_steps: usize,
    /// Largest arclength step along a branch. Default: the path's `max-step`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch_max_step: Option<f64>,
    /// Seek the second piece beside every fold of the path. Default true.
    #[serde(default = "default_partners")]
    pub partners: bool,
    /// Seek the second piece also beside every dip of the path: a minimum of the |eigenvalue|
    /// of its own block with no change of index, whose mode has a wave number m ≥ 1 (a
    /// double broken without a fold, docs/theory.md §16.7). Default true.
    #[serde(default = "default_partners")]
    pub near_misses: bool,
    /// Points of each second piece beyond its fold. Default 60.
    #[serde(default = "default_partner_steps")]
    pub partner_steps: usize,
    /// The shared settings of the path: steps, step sizes, direction, save-every, Newton's.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

fn default_depth() -> usize {
    2
}
fn default_branch_steps() -> usize {
    40
}
fn default_partners() -> bool {
    true
}
fn default_partner_steps() -> usize {
    60
}

impl DiagramAnalysis {
    /// The diagram of the path `p`: its control, stops and settings, the depth, steps and
    /// largest step of its `[analysis.branches]` where it has them (at least the default
    /// depth), the defaults elsewhere.
    pub fn of_path(p: &PathAnalysis) -> Self {
        let b = p.branches.as_ref();
        Self {
            control: p.control.clone(),
            stop_stretch: p.stop_stretch,
            stop_displacement: p.stop_displacement,
            depth: b.map_or(default_depth(), |b| b.depth.max(default_depth())),
            branch_steps: b.map_or(default_branch_steps(), |b| b.steps),
            branch_max_step: b.and_then(|b| b.max_step),
            partners: default_partners(),
            near_misses: default_partners(),
            partner_steps: default_partner_steps(),
            settings: p.settings.clone(),
        }
    }

    /// The path with its branches that the diagram runs first.
    pub fn path(&self) -> PathAnalysis {
        PathAnalysis {
            control: self.control.clone(),
            stop_stretch: self.stop_stretch,
            stop_displacement: self.stop_displacement,
            branches: Some(BranchesAnalysis {
                depth: self.depth,
                steps: self.branch_steps,
                max_step: self.branch_max_step,
                points: None,
            }),
            settings: self.settings.clone(),
        }
    }
}

impl AnalysisSpec for DiagramAnalysis {
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
        check_stops(self.stop_stretch, self.stop_displacement)?;
        if self.depth < 1 || self.depth > MAX_BRANCH_DEPTH {
            return Err(Problem::at(
                "analysis.depth",
                format!(
                    "must lie within [1, {MAX_BRANCH_DEPTH}], got {}",
                    self.depth
                ),
            ));
        }
        at_least("analysis.branch-steps", self.branch_steps, 1)?;
        at_least("analysis.partner-steps", self.partner_steps, 1)?;
        if let Some(m) = self.branch_max_step {
            positive("analysis.branch-max-step", m)?;
        }
        Ok(())
    }
    fn check_mesh(&self, closed: bool, the_mesh: &str) -> Result<(), Problem> {
        check_stretch_needs_closed(self.stop_stretch, closed, the_mesh)
    }
    /// The path, then each second piece (a branch keeps only its own points).
    fn stored_points(&self) -> (u64, u64) {
        let points = (self.settings.steps as u64).saturating_add(1);
        let pieces = (self.partner_steps as u64).saturating_add(1);
        (
            points.saturating_add(pieces),
            (points + pieces) / (self.settings.save_every.max(1) as u64) + 4,
        )
    }
}
