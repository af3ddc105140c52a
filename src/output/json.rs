//! `path.json`: the whole report with its metadata.

use super::{check_finite, write_whole, OutputError};
use crate::results::PathReport;
use std::io;
use std::path::{Path, PathBuf};

/// Writes `dir/path.json` — the whole [`PathReport`] as pretty-printed JSON (scene, origin,
/// version, mesh, group, unknowns, control, parameter and measure names, rows, turning points,
/// stop reason, saved states) — and returns its path. The rows hold their parameters and
/// measures as lists in the order of the names; the turning and critical points as objects by
/// name, as `critical.json` does, each with the `step` before it. Numbers are written with the fewest
/// digits that parse back to the same `f64`.
///
/// # Errors
/// [`OutputError::NoDirectory`] if `dir` does not exist, [`OutputError::Invalid`] if a value is
/// not finite (JSON has no NaN; nothing is written), [`OutputError::Io`] if the file cannot be
/// written.
pub fn write_json(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    let path = dir.join("path.json");
    check_finite(&path, report)?;
    let mut value =
        serde_json::to_value(report).map_err(|e| OutputError::invalid(&path, e.to_string()))?;
    named_points(&mut value, &report.parameters, &report.measures);
    if let Some(points) = value
        .get_mut("turning_points")
        .and_then(|v| v.as_array_mut())
    {
        for (k, p) in points.iter_mut().enumerate() {
            let flags = report.turning_flags(k);
            p["valid"] = serde_json::json!(flags.is_empty());
            p["flags"] = serde_json::to_value(flags)
                .map_err(|e| OutputError::invalid(&path, e.to_string()))?;
        }
    }
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &value).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}

/// The `turning_points` and `critical` of a report's JSON `value` with their `parameters`
/// and `measures` as objects by name.
pub(super) fn named_points(
    value: &mut serde_json::Value,
    parameters: &[String],
    measures: &[String],
) {
    for list in ["turning_points", "critical"] {
        if let Some(points) = value.get_mut(list).and_then(|v| v.as_array_mut()) {
            for p in points {
                for (key, names) in [("parameters", parameters), ("measures", measures)] {
                    if let Some(v) = p.get_mut(key) {
                        *v = by_name(names, v);
                    }
                }
            }
        }
    }
}

/// A list of values as an object `{name: value}` in the order of `names` (a list that does
/// not match the names is kept as it is).
fn by_name(names: &[String], values: &serde_json::Value) -> serde_json::Value {
    match values.as_array() {
        Some(list) if list.len() == names.len() => {
            serde_json::Value::Object(names.iter().cloned().zip(list.iter().cloned()).collect())
        }
        _ => values.clone(),
    }
}

/// One critical point as written to `critical.json`.
#[derive(serde::Serialize)]
struct CriticalJson<'a> {
    kind: crate::results::CriticalKind,
    irrep: &'a str,
    multiplicity: usize,
    parameters: std::collections::BTreeMap<&'a str, f64>,
    measures: std::collections::BTreeMap<&'a str, f64>,
    step: usize,
    residual_eigenvalue: f64,
    isotropy: &'a str,
    isotropy_order: usize,
    /// The mode's wave number about z, where the mesh has an axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    m: Option<usize>,
    /// No flag raised: a result of the model as it stands.
    valid: bool,
    /// Why it may not be ([`crate::results::validity::Flag`]).
    flags: Vec<crate::results::validity::Flag>,
}

/// Writes `dir/critical.json`: a list of the critical points (kind, irrep, multiplicity,
/// parameters and measures by name, the path step before the point, the relative size of the
/// localised eigenvalue, and the isotropy subgroup of the critical mode).
///
/// # Errors
/// As [`write_json`]; a non-finite value is refused and nothing is written.
pub fn write_critical(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    write_critical_with(dir, report, &[])
}

/// As [`write_critical`], with the `events` of a critical curve after the path's critical
/// points: each `{"kind": "start" | "cusp" | "fold" | "hilltop" | "irrep change" | "end",
/// "curve": true, "extremum", "irrep", "residual_eigenvalue", "parameters", "measures",
/// "step", "valid", "flags"}` with parameters and measures by name, `step` the curve step before the event
/// (`extremum` for a cusp or fold; `irrep`, the other singular block, and its eigenvalue for
/// a hilltop or irrep change).
///
/// # Errors
/// As [`write_critical`].
pub fn write_critical_with(
    dir: &Path,
    report: &PathReport,
    events: &[crate::results::CurveEvent],
) -> Result<PathBuf, OutputError> {
    let path = dir.join("critical.json");
    let list: Vec<CriticalJson> = report
        .critical
        .iter()
        .enumerate()
        .map(|(k, c)| CriticalJson {
            kind: c.kind,
            irrep: &c.irrep,
            multiplicity: c.multiplicity,
            parameters: report
                .parameters
                .iter()
                .map(String::as_str)
                .zip(c.parameters.iter().copied())
                .collect(),
            measures: report
                .measures
                .iter()
                .map(String::as_str)
                .zip(c.measures.iter().copied())
                .collect(),
            step: c.after_step,
            residual_eigenvalue: c.residual_eigenvalue,
            isotropy: &c.isotropy.name,
            isotropy_order: c.isotropy.order,
            m: report.wave_numbers.get(k).copied(),
            valid: report.flags(k).is_empty(),
            flags: report.flags(k),
        })
        .collect();
    for c in &list {
        if let Some((name, v)) = c
            .parameters
            .iter()
            .chain(&c.measures)
            .find(|(_, v)| !v.is_finite())
        {
            return Err(OutputError::invalid(
                &path,
                format!(
                    "critical point ({} in {}): {name} is {v} (not finite)",
                    c.kind, c.irrep
                ),
            ));
        }
    }
    let named = |names: &[String], values: &[f64]| -> serde_json::Map<String, serde_json::Value> {
        names
            .iter()
            .zip(values)
            .map(|(n, v)| (n.clone(), serde_json::json!(v)))
            .collect()
    };
    let mut all: Vec<serde_json::Value> = list
        .iter()
        .map(|c| serde_json::to_value(c).map_err(io::Error::other))
        .collect::<Result<_, _>>()
        .map_err(|e| OutputError::invalid(&path, e.to_string()))?;
    for e in events {
        if let Some(v) = e
            .parameters
            .iter()
            .chain(&e.measures)
            .find(|v| !v.is_finite())
        {
            return Err(OutputError::invalid(
                &path,
                format!("curve event {}: a value is {v} (not finite)", e.kind),
            ));
        }
        let mut event = serde_json::json!({
            "kind": e.kind.to_string(),
            "curve": true,
            "parameters": named(&report.parameters, &e.parameters),
            "measures": named(&report.measures, &e.measures),
            "step": e.after_step,
            "valid": e.flags.is_empty(),
            "flags": e.flags,
        });
        if let Some(x) = e.extremum {
            event["extremum"] = serde_json::json!(x.to_string());
        }
        if let Some(irrep) = &e.irrep {
            event["irrep"] = serde_json::json!(irrep);
        }
        if let Some(r) = e.residual_eigenvalue.filter(|r| r.is_finite()) {
            event["residual_eigenvalue"] = serde_json::json!(r);
        }
        all.push(event);
    }
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &all).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}
