//! A run's critical and turning points (and a critical curve's events) on refined meshes
//! (docs/theory.md §8.11): each point's
//! value on every level, the observed order, the Richardson value and an error estimate per
//! level beside that level's wall time, as plain data (`memstab run --refine`, `refine.json`).

use super::{Extremum, StopReason};
use crate::text::{sci, sig_digits};
use serde::Serialize;

/// The order of convergence the error estimate assumes on a 3-D mesh: its linear triangles
/// converge at O(h²) in the critical values (docs/theory.md §13.4).
pub const ASSUMED_ORDER: f64 = 2.0;

/// The order it assumes on a meridian: its quadratic elements converge at O(h⁴) (2p for
/// degree p = 2, docs/theory.md §15.3).
pub const MERIDIAN_ORDER: f64 = 4.0;

/// How far the observed order may be from the assumed one for the values to be taken as in
/// the asymptotic range (and extrapolated).
pub const ORDER_TOLERANCE: f64 = 0.5;

/// A run and its refinements, point by point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refinement {
    /// The control parameter the values are of.
    pub control: String,
    /// The order the estimate assumes ([`ASSUMED_ORDER`] on a 3-D mesh, [`MERIDIAN_ORDER`] on
    /// a meridian).
    pub assumed_order: f64,
    /// The largest |observed − assumed| order taken as asymptotic ([`ORDER_TOLERANCE`]).
    pub order_tolerance: f64,
    /// The run's own mesh first, then each refinement (the resolution doubled each time).
    pub levels: Vec<RefinedLevel>,
    /// The meridian's run, with `--continuum`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuum: Option<ContinuumRun>,
    /// The run's critical points, one entry per rung (a point, or the split halves of a
    /// double the mesh breaks), in the order of `critical.json`.
    pub critical: Vec<PointRefinement>,
    /// The run's turning points of the control, in path order.
    pub turning: Vec<PointRefinement>,
    /// The events of a critical curve (`type = "critical-curve"`) in curve order, but its
    /// start and end: empty for another analysis.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<EventRefinement>,
    /// The curve's second parameter, with events.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub second: Option<String>,
    /// Critical points of the refined meshes with no counterpart on the run's own mesh.
    pub new_on_finer: Vec<NewPoint>,
    /// The refined runs that failed (and those not run after a failed one): `levels` and the
    /// estimates hold the runs that worked.
    pub failed: Vec<FailedRun>,
}

/// A refined run that failed, or was not run because a coarser one had failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FailedRun {
    /// Which: `level 1`, `level 2`, `continuum`.
    pub run: String,
    /// Its mesh, as one line.
    pub mesh: String,
    /// Why, in one line.
    pub reason: String,
}

/// One mesh of the refinement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RefinedLevel {
    /// The mesh options as one line, e.g. `icosphere frequency=8`.
    pub mesh: String,
    /// Its divisions (an icosphere's frequency, a meridian's elements).
    pub resolution: usize,
    /// Nodes.
    pub nodes: usize,
    /// Unknowns of the model.
    pub unknowns: usize,
    /// Wall time of its run.
    pub seconds: f64,
    /// Why its path ended.
    pub stop: StopReason,
    /// Its critical points.
    pub critical: usize,
    /// Its turning points.
    pub turning: usize,
}

/// The meridian's run (`--continuum`): the scene's axisymmetric counterpart.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContinuumRun {
    /// The meridian's options as one line.
    pub mesh: String,
    /// Its elements.
    pub resolution: usize,
    /// Wall time of its run and of its check run at twice the elements.
    pub seconds: f64,
}

/// One critical point (or turning point) of the run, followed through the refinements.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointRefinement {
    /// The points of the run it stands for, numbered from 1 as in `critical.json` (turning
    /// points in path order).
    pub points: Vec<usize>,
    /// Its kind (`limit point`, `double bifurcation`, …, or `maximum`, `minimum`).
    pub kind: String,
    /// Its irreps on the run's mesh.
    pub irreps: Vec<String>,
    /// The wave number of its mode about z, where the mesh has an axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// Its value on every level, the observed order, the Richardson value and the errors.
    #[serde(flatten)]
    pub series: Series,
    /// The meridian's value, with `--continuum`, when it has a counterpart.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuum: Option<f64>,
    /// The meridian value's own error: |value(2N) − value(N)| of its runs at N and 2N
    /// elements.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuum_error: Option<f64>,
    /// Each level's distance from the meridian's value (value − continuum).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub distances: Vec<Option<f64>>,
}

impl PointRefinement {
    /// True when every refined mesh has a counterpart.
    pub fn converged(&self) -> bool {
        self.series.converged()
    }
}

/// One number followed through the levels: its value on each, the observed order, the
/// Richardson value and each level's error.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Series {
    /// Its value on every level (the mean of a split pair's halves); `null` where the level
    /// has no counterpart.
    pub values: Vec<Option<f64>>,
    /// The observed order log2(|v₀ − v₁| / |v₁ − v₂|), with three levels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observed_order: Option<f64>,
    /// The Richardson value v_f + (v_f − v_c)/(2^p − 1) of the two finest levels, p the
    /// assumed order; only in the asymptotic range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub richardson: Option<f64>,
    /// Each level's error estimate |v − Richardson|; `null` where there is none.
    pub errors: Vec<Option<f64>>,
    /// What the estimate rests on.
    pub estimate: Estimate,
}

impl Series {
    /// True when every refined mesh has a counterpart.
    pub fn converged(&self) -> bool {
        !matches!(self.estimate, Estimate::NotMeshConverged { .. })
    }

    /// Its finite numbers' check: every number it holds.
    pub fn numbers(&self) -> impl Iterator<Item = &f64> {
        self.values
            .iter()
            .chain(&self.errors)
            .flatten()
            .chain(&self.observed_order)
            .chain(&self.richardson)
    }
}

/// An event of a critical curve (a cusp, a fold, a hilltop, a change of the critical irrep)
/// followed through the refinements: both its coordinates, each with its estimate. The curve's
/// start is the path's critical point (in `critical`), its end where the curve left its range
/// or budget: neither is an event of the mesh's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventRefinement {
    /// Its number among the curve's events, from 1 (the start), as in `curve.json`.
    pub event: usize,
    /// Its kind: `cusp`, `fold`, `hilltop`, `irrep change`.
    pub kind: String,
    /// For a cusp or fold: whether the second parameter has a maximum or a minimum there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extremum: Option<Extremum>,
    /// For a hilltop or an irrep change: the other irrep singular there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub irrep: Option<String>,
    /// That irrep's wave number about z, where the model has an axis: what matches it on
    /// the meridian.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// The control's value through the levels.
    pub control: Series,
    /// The second parameter's value through the levels.
    pub second: Series,
    /// Its counterpart on the meridian, with `--continuum`, when it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuum: Option<EventContinuum>,
}

/// A curve event's counterpart on the meridian (`--continuum`): both its coordinates there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventContinuum {
    /// The control's value.
    pub control: ContinuumValue,
    /// The second parameter's value.
    pub second: ContinuumValue,
}

/// One coordinate of a point on the meridian, as a reference for the 3-D levels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContinuumValue {
    /// Its value at N elements.
    pub value: f64,
    /// Its own error: |value(2N) − value(N)| of the meridian's runs at N and 2N elements.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<f64>,
    /// Each level's distance from it (value − continuum); `null` where a level has no
    /// counterpart.
    pub distances: Vec<Option<f64>>,
}

impl EventRefinement {
    /// True when every refined mesh has a counterpart.
    pub fn converged(&self) -> bool {
        self.control.converged()
    }
}

/// What a point's error estimate rests on.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "basis", rename_all = "kebab-case")]
pub enum Estimate {
    /// Richardson extrapolation of the two finest levels with the assumed order: confirmed by
    /// the observed order of three levels (`observed`), or assumed with two.
    Richardson {
        /// Whether three levels confirmed the order.
        observed: bool,
    },
    /// The observed order is far from the assumed one: the values are not in the asymptotic
    /// range, and are not extrapolated.
    NotAsymptotic {
        /// The observed order (`null` when it is not defined: one difference is zero, or the
        /// differences change sign and size at once).
        order: Option<f64>,
    },
    /// The values do not change on refinement (a value the symmetry or the load fixes).
    Unchanged,
    /// No refined level ran (each failed; `failed` says why): no estimate.
    NotRefined,
    /// A refined mesh has no counterpart: the point is not mesh-converged.
    NotMeshConverged {
        /// That mesh, as one line.
        finer: String,
    },
}

/// A critical point of a refined mesh with no counterpart on the run's mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NewPoint {
    /// The level (1 for the first refinement).
    pub level: usize,
    /// Its irrep.
    pub irrep: String,
    /// Its value.
    pub value: f64,
    /// Its wave number about z.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
}

/// The lines of one number through the levels (`name` is what it is the value of): each
/// level's value, error and wall time, then the observed order and the Richardson value, or
/// why there is none.
fn series_lines(r: &Refinement, name: &str, p: &Series, indent: &str) -> Vec<String> {
    let mut lines = Vec::new();
    for (l, (v, e)) in p.values.iter().zip(&p.errors).enumerate() {
        let value = v.map_or_else(|| "-".to_string(), |v| sig_digits(v, 8));
        let error = e.map_or_else(String::new, |e| format!("  error {}", sci(e)));
        lines.push(format!(
            "{indent}level {l}: {name} = {value}{error}  ({:.2} s)",
            r.levels[l].seconds
        ));
    }
    let changes = || {
        let v: Vec<f64> = p.values.iter().flatten().copied().collect();
        v.windows(2)
            .map(|w| sci(w[1] - w[0]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let tail = match (&p.estimate, p.richardson) {
        (Estimate::Richardson { observed: true }, Some(x)) => format!(
            "observed order {:.2}; Richardson {}",
            p.observed_order.unwrap_or(f64::NAN),
            sig_digits(x, 8)
        ),
        (Estimate::Richardson { .. }, Some(x)) => format!(
            "order {} assumed (two levels do not observe it); Richardson {}",
            r.assumed_order,
            sig_digits(x, 8)
        ),
        (Estimate::Unchanged, _) => "the value does not change on refinement".to_string(),
        (Estimate::NotRefined, _) => "no refined level ran: no error estimated".to_string(),
        (Estimate::NotAsymptotic { order }, _) => format!(
            "observed order {}, far from {}: not in the asymptotic range, not \
             extrapolated and no error estimated (the value changes by {})",
            order.map_or_else(|| "undefined".to_string(), |p| format!("{p:.2}")),
            r.assumed_order,
            changes()
        ),
        _ => String::new(),
    };
    if !tail.is_empty() {
        lines.push(format!("{indent}{tail}"));
    }
    lines
}

/// `: not mesh-converged, …` for a series without a counterpart on a refined mesh.
fn status(p: &Series) -> String {
    match &p.estimate {
        Estimate::NotMeshConverged { finer } => {
            format!(": not mesh-converged, no counterpart on {finer}")
        }
        _ => String::new(),
    }
}

/// A continuum value's own error (` +-e`, or nothing) and the finest level's distance from
/// it, printed.
fn continuum_parts(error: Option<f64>, distances: &[Option<f64>]) -> (String, Option<String>) {
    let e = error.map_or_else(String::new, |e| format!(" +-{}", sci(e)));
    let d = distances.iter().rev().flatten().next().map(|d| sci(*d));
    (e, d)
}

/// The critical and turning points (and a critical curve's events) on the refined meshes:
/// each level's value, error estimate and wall time, the observed order and the Richardson
/// value (or why there is none), the continuum's value and distance.
pub fn summary(r: &Refinement) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(format!(
        "mesh refinement (errors estimated by Richardson extrapolation, which assumes the \
         asymptotic range at order {}; docs/theory.md §8.11):",
        r.assumed_order
    ));
    for (l, level) in r.levels.iter().enumerate() {
        lines.push(format!(
            "  level {l}: {}, {} unknowns, {:.2} s, stopped: {}",
            level.mesh, level.unknowns, level.seconds, level.stop
        ));
    }
    if let Some(c) = &r.continuum {
        lines.push(format!(
            "  continuum: {} (and twice its elements), {:.2} s",
            c.mesh, c.seconds
        ));
    }
    for f in &r.failed {
        lines.push(format!("  {} ({}) failed: {}", f.run, f.mesh, f.reason));
    }
    let block = |lines: &mut Vec<String>, title: String, p: &PointRefinement| {
        let m = p.m.map_or_else(String::new, |m| format!(", m = {m}"));
        lines.push(format!("  {title}{m}{}", status(&p.series)));
        let mut series = series_lines(r, &r.control, &p.series, "    ");
        if let Some(c) = p.continuum {
            let (e, d) = continuum_parts(p.continuum_error, &p.distances);
            let d = d.map_or_else(String::new, |d| format!(", distance of the finest {d}"));
            let text = format!("continuum {}{e}{d}", sig_digits(c, 8));
            // After the estimate's line, or alone.
            match series.last_mut() {
                Some(last) if !last.trim_start().starts_with("level ") => {
                    last.push_str(&format!("; {text}"));
                }
                _ => series.push(format!("    {text}")),
            }
        }
        lines.extend(series);
    };
    for p in &r.critical {
        let numbers: Vec<String> = p.points.iter().map(ToString::to_string).collect();
        block(
            &mut lines,
            format!(
                "critical {}: {} in {}",
                numbers.join(" + "),
                p.kind,
                p.irreps.join(" + ")
            ),
            p,
        );
    }
    for (k, p) in r.turning.iter().enumerate() {
        block(&mut lines, format!("turning {}: {}", k + 1, p.kind), p);
    }
    let second = r.second.as_deref().unwrap_or("second");
    for e in &r.events {
        let what = match (&e.extremum, &e.irrep) {
            (Some(x), _) => format!(" ({x} of {second})"),
            (None, Some(irrep)) => match e.m {
                Some(m) => format!(" with {irrep} (m = {m})"),
                None => format!(" with {irrep}"),
            },
            (None, None) => String::new(),
        };
        lines.push(format!(
            "  curve event {}: {}{what}{}",
            e.event,
            e.kind,
            status(&e.control)
        ));
        lines.extend(series_lines(r, &r.control, &e.control, "    "));
        if e.control.converged() {
            lines.extend(series_lines(r, second, &e.second, "    "));
        }
        if let Some(c) = &e.continuum {
            let text = |name: &str, v: &ContinuumValue| {
                let (err, d) = continuum_parts(v.error, &v.distances);
                let d = d.map_or_else(String::new, |d| format!(" (finest level {d})"));
                format!("{name} = {}{err}{d}", sig_digits(v.value, 8))
            };
            lines.push(format!(
                "    continuum: {}, {}",
                text(&r.control, &c.control),
                text(second, &c.second)
            ));
        }
    }
    for n in &r.new_on_finer {
        let m = n.m.map_or_else(String::new, |m| format!(", m = {m}"));
        lines.push(format!(
            "  new on level {}: a critical point in {} at {} = {}{m}, with no counterpart on \
             this run's mesh",
            n.level,
            n.irrep,
            r.control,
            sig_digits(n.value, 8)
        ));
    }
    lines
}
