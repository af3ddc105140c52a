//! `type = "path"`: the equilibrium path in the control, with its branches.

use super::super::error::{num, Problem};
use super::super::validate::{at_least, free_parameter, positive};
use super::{AnalysisSpec, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "path"`: pseudo-arclength continuation from the start state. The path stops at
/// the first of: the control leaving `[min, max]` of its parameter, the stretch reaching
/// `stop-stretch`, the largest displacement reaching `stop-displacement`, or `steps` steps
/// (the shared settings, [`Settings`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct PathAnalysis {
    /// The parameter that is free on the path.
    pub control: String,
    /// Stop when the volume stretch λ = (V/V_sf)^(1/3) reaches this value (closed membranes
    /// only; V_sf = V(mesh)/λ0³ is the stress-free enclosed volume).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_stretch: Option<f64>,
    /// Stop when the largest nodal displacement |u_i| reaches this value (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_displacement: Option<f64>,
    /// `[analysis.branches]`: switch at the path's bifurcation points and follow the
    /// branches that leave them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branches: Option<BranchesAnalysis>,
    /// The shared settings: steps, step sizes, direction, save-every, Newton's.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

/// `[analysis.branches]` of a path: at every bifurcation point of the path (or those listed
/// in `points`), one branch per conjugacy class of axial isotropy subgroups of its irrep
/// (both halves where they are not conjugate), each followed for `steps` points in its own
/// fixed-point space; with `depth = 2` also the branches of the branches' bifurcation points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct BranchesAnalysis {
    /// 1: the branches of the path's critical points; 2: also those of their critical
    /// points; at most [`MAX_BRANCH_DEPTH`]. Default 1.
    #[serde(default = "default_depth")]
    pub depth: usize,
    /// Points of each branch after the point it leaves (≥ 1). Default 40.
    #[serde(default = "default_branch_steps")]
    pub steps: usize,
    /// Largest arclength step along a branch. Default: the path's `max-step`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step: Option<f64>,
    /// The path's critical points to switch at, numbered from 1 in the order of
    /// `critical.json` (the `NN` of `critical_NN.vtu`). Default: every one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<Vec<usize>>,
}

/// The largest `analysis.branches.depth`.
pub const MAX_BRANCH_DEPTH: usize = 3;

fn default_depth() -> usize {
    1
}
fn default_branch_steps() -> usize {
    40
}

impl AnalysisSpec for PathAnalysis {
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
        if let Some(b) = &self.branches {
            check_branches(b)?;
        }
        Ok(())
    }
    fn check_mesh(&self, closed: bool, the_mesh: &str) -> Result<(), Problem> {
        check_stretch_needs_closed(self.stop_stretch, closed, the_mesh)
    }
    fn stored_points(&self) -> (u64, u64) {
        let points = (self.settings.steps as u64).saturating_add(1);
        (
            points,
            points / (self.settings.save_every.max(1) as u64) + 2,
        )
    }
}

/// A path's stops: `stop-stretch` and `stop-displacement` positive where given.
pub(super) fn check_stops(stretch: Option<f64>, displacement: Option<f64>) -> Result<(), Problem> {
    if let Some(s) = stretch {
        positive("analysis.stop-stretch", s)?;
    }
    if let Some(s) = displacement {
        positive("analysis.stop-displacement", s)?;
    }
    Ok(())
}

/// `stop-stretch` needs a closed membrane (the stretch is (V/V0)^(1/3)).
pub(super) fn check_stretch_needs_closed(
    stretch: Option<f64>,
    closed: bool,
    the_mesh: &str,
) -> Result<(), Problem> {
    match stretch {
        Some(s) if !closed => Err(Problem::at(
            "analysis.stop-stretch",
            format!(
                "= {} needs a closed membrane (the stretch is (V/V0)^(1/3)); {the_mesh} is open",
                num(s)
            ),
        )),
        _ => Ok(()),
    }
}

/// `[analysis.branches]`: depth within [1, MAX_BRANCH_DEPTH], steps ≥ 1, a positive
/// max-step, points numbered from 1 without repeats.
fn check_branches(b: &BranchesAnalysis) -> Result<(), Problem> {
    if b.depth < 1 || b.depth > MAX_BRANCH_DEPTH {
        return Err(Problem::at(
            "analysis.branches.depth",
            format!("must lie within [1, {MAX_BRANCH_DEPTH}], got {}", b.depth),
        ));
    }
    at_least("analysis.branches.steps", b.steps, 1)?;
    if let Some(m) = b.max_step {
        positive("analysis.branches.max-step", m)?;
    }
    if let Some(points) = &b.points {
        for (i, &p) in points.iter().enumerate() {
            let key = format!("analysis.branches.points[{i}]");
            at_least(&key, p, 1)?;
            if points[..i].contains(&p) {
                return Err(Problem::at(&key, format!("= {p} is listed twice")));
            }
        }
    }
    Ok(())
}
