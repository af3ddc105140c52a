//! Helpers shared by the commands: loading a scene and building its study with the exit
//! codes of `memstab run`, the `--at NAME=VALUE` overrides, the chiral-group check, and
//! number formatting.

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

/// Parses the `--at` list against the parameter names: (index, value) pairs.
pub(super) fn parse_at(at: &[String], names: &[String]) -> Result<Vec<(usize, f64)>, CliError> {
    let mut out = Vec::new();
    for item in at {
        let Some((name, value)) = item.split_once('=') else {
            return Err(CliError::Input(format!(
                "--at '{item}': expected NAME=VALUE, e.g. --at p=1.3"
            )));
        };
        let (name, value) = (name.trim(), value.trim());
        let Some(i) = names.iter().position(|n| n == name) else {
            let known = if names.is_empty() {
                "the scene has no parameters".to_string()
            } else {
                format!("the scene's parameters: {}", names.join(", "))
            };
            return Err(CliError::Input(format!(
                "--at '{item}': unknown parameter '{name}' ({known})"
            )));
        };
        let v: f64 = match value.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                return Err(CliError::Input(format!(
                    "--at '{item}': the value '{value}' of '{name}' is not a finite number"
                )))
            }
        };
        out.push((i, v));
    }
    Ok(out)
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
