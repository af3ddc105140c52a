//! Branches switched from a finished run (`memstab branch RUN_DIR --critical N`): the run read
//! back and checked against the study, its critical point N with its state and mode, the start
//! solved again (it sets the targets of `"initial"` constraints), and the branches of that point
//! followed with the scene's `[analysis.branches]`, as a path run follows them.

use super::{path_of, restart, RunError};
use crate::output::FinishedRun;
use crate::results::StopReason;
use crate::results::{Branches, Node, Skip};
use crate::scene::BranchesAnalysis;
use crate::study::Study;

/// What `memstab branch` changes of the scene's `[analysis.branches]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// The depth.
    pub depth: Option<usize>,
    /// Points of each branch.
    pub steps: Option<usize>,
    /// The largest arclength step along a branch.
    pub max_step: Option<f64>,
}

impl Overrides {
    /// Refuses a value no scene could hold, in one line naming its flag: a depth outside
    /// [1, [`crate::scene::MAX_BRANCH_DEPTH`]], no steps, a step that is not a positive
    /// number.
    ///
    /// # Errors
    /// The line naming the flag and its value.
    pub fn check(&self) -> Result<(), String> {
        if let Some(d) = self.depth {
            if !(1..=crate::scene::MAX_BRANCH_DEPTH).contains(&d) {
                return Err(format!(
                    "--depth {d}: must lie within [1, {}]",
                    crate::scene::MAX_BRANCH_DEPTH
                ));
            }
        }
        if self.steps == Some(0) {
            return Err("--steps 0: must be >= 1".into());
        }
        if let Some(m) = self.max_step {
            if !(m.is_finite() && m > 0.0) {
                return Err(format!("--max-step {m}: must be > 0"));
            }
        }
        Ok(())
    }
}

/// Why branches could not be switched from a finished run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BranchError {
    /// The run or the scene does not fit (bad input).
    #[error("{0}")]
    Input(String),
    /// The start state did not converge again.
    #[error("{0}")]
    Start(RunError),
}

/// Whether a signal stopped the following of `branches` (one of them stopped interrupted, or a
/// stop was requested after the last).
pub fn interrupted(branches: &Branches) -> bool {
    crate::continuation::interrupt::requested()
        || branches
            .runs
            .iter()
            .any(|r| r.report.stop == StopReason::Interrupted)
}

/// The branches of critical point `n` (1-based) of the finished `run` of `study`.
pub fn from_run(
    study: &mut dyn Study,
    run: &FinishedRun,
    n: usize,
    overrides: &Overrides,
) -> Result<Branches, BranchError> {
    let input = |e: crate::output::ReopenError| BranchError::Input(e.to_string());
    restart::check(run, study).map_err(input)?;
    let Some(path) = path_of(&study.scene().analysis) else {
        unreachable!("checked: the run's analysis is a path")
    };
    let (state, mode) = restart::critical_state(run, study, n).map_err(input)?;
    let critical = study
        .recorded(&run.critical, n, state, mode)
        .map_err(BranchError::Input)?;
    let opts = path.options_of(study);
    let params = study.start_values().to_vec();
    study
        .solve_start(None, &params, &opts)
        .map_err(BranchError::Start)?;
    let scene = path.0.branches.clone().unwrap_or(BranchesAnalysis {
        depth: 1,
        steps: 40,
        max_step: None,
        points: None,
    });
    let b = BranchesAnalysis {
        depth: overrides.depth.unwrap_or(scene.depth),
        steps: overrides.steps.unwrap_or(scene.steps),
        max_step: overrides.max_step.or(scene.max_step),
        points: Some(vec![n]),
    };
    let options = path.branch_options(study, Some(&b));
    let branches = study
        .branches(&critical, options)
        .map_err(BranchError::Input)?;
    // A point whose branches leave the study's states is refused, with the model to use.
    let refused = branches
        .graph
        .graph
        .node_weights()
        .find_map(|node| match node {
            Node::Critical {
                on: None,
                number,
                skipped: Some(Skip::Elsewhere(why)),
                ..
            } if *number == n => Some(why.clone()),
            _ => None,
        });
    match refused {
        Some(why) => Err(BranchError::Input(why)),
        None => Ok(branches),
    }
}
