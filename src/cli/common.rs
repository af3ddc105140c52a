//! Helpers shared by `memstab spectrum` and `memstab compare`: loading a scene and building its
//! study with the exit codes of `memstab run`, solving the start state as `run` does, the
//! chiral-group check, and number formatting.

use super::CliError;
use memstab::scene::Scene;
use memstab::study::{Study, StudyError};
use std::path::Path;

/// Loads and validates a scene file; any problem is bad input (exit 2).
pub(super) fn load_scene(path: &Path) -> Result<Scene, CliError> {
    Scene::load(path).map_err(|e| CliError::Input(one_line(&e.to_string())))
}

/// Builds the study (mesh, the scene's group, effects, model); a scene that cannot be built is
/// bad input (exit 2), as in `memstab run`.
pub(super) fn build_study(scene: Scene) -> Result<Study, CliError> {
    Study::build(scene).map_err(|e| match e {
        StudyError::Scene(_) | StudyError::Unsupported(_) => {
            CliError::Input(one_line(&e.to_string()))
        }
    })
}

/// Fails with bad input when the scene's group has an irrep of complex type (a chiral group
/// `C<n>`, n ≥ 3), whose blocks the adapted basis does not support yet. `what` names the scene
/// or mesh in the message.
pub(super) fn check_real_irreps(study: &Study, what: &str) -> Result<(), CliError> {
    let group = study.action.group();
    if let Some(irrep) = group
        .irreps()
        .iter()
        .find(|i| i.kind() != symmetry::IrrepKind::Real)
    {
        return Err(CliError::Input(format!(
            "{what}: the scene's group {} is chiral: its irrep {} is of complex type, whose \
             block the symmetry-adapted analysis does not support yet; use a group with mirrors \
             (C<n>v)",
            group.name(),
            irrep.name()
        )));
    }
    Ok(())
}

/// The start state as `memstab run` solves it: the reference scaled by `start.stretch`, every
/// parameter at `params`, no constraint active, Newton in the fixed-point space of the scene's
/// group (at least 50 iterations). Constraint targets declared `"initial"` are then measured
/// there, so the constraints border the tangent as on `run`'s first point. Returns the
/// displacement over the unknowns and the Newton iterations; the error is one line.
pub(super) fn solve_start(study: &mut Study, params: &[f64]) -> Result<(Vec<f64>, usize), String> {
    memstab::analysis::equilibrium::solve_start(study, params)
        .map(|(u, _, iterations)| (u, iterations))
        .map_err(|e| one_line(&e.to_string()))
}

/// Joins the lines of a message into one.
pub(super) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// `x` with `digits` significant digits, plain for moderate sizes (`1.35511`, `0.000123457`),
/// else in exponent form (`1.23457e7`).
pub(super) fn sig_digits(x: f64, digits: usize) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{x}");
    }
    let e = a.log10().floor() as i32;
    let digits = digits.max(1) as i32;
    if (-4..6).contains(&e) {
        let decimals = (digits - 1 - e).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        let decimals = (digits - 1) as usize;
        format!("{x:.decimals$e}")
    }
}

/// A short scientific form for eigenvalues and gaps: `1.234e-3`, `-5.000e0`, `0`.
pub(super) fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else {
        format!("{x:.3e}")
    }
}
