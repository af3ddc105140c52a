//! `type = "critical-curve"`: a critical point followed in two parameters.

use super::super::error::Problem;
use super::super::validate::{at_least, free_parameter};
use super::{AnalysisSpec, Scene};
use crate::continuation::Settings;
use serde::de::{self, Deserializer, Unexpected, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;
use std::path::{Path, PathBuf};

/// `type = "critical-curve"`: the path in `control` from the start state (second parameter
/// held at its start value) up to the critical point `from`; then that point followed as
/// `second` varies — the equilibrium in the fixed-point space and a singular block of its
/// irrep, in (u, control, second), with the constraints active (docs/theory.md §11.7). The
/// curve stops when `second` or `control` leaves its `[min, max]`, or after `steps` steps
/// (the shared settings, which are those of the curve; its `direction` is the sense of its
/// first step in `second`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct CriticalCurveAnalysis {
    /// The parameter of the path that finds the point.
    pub control: String,
    /// The other free parameter of the curve.
    pub second: String,
    /// Which critical point of the path: `"limit"` (the first limit point), an irrep name
    /// (the first critical point in that irrep's block) or an index (0: the first critical
    /// point of any kind). Default `"limit"`. With `from-run`, the index of a critical point
    /// of that run.
    #[serde(default)]
    pub from: CurveStart,
    /// The output directory of a finished run of the same model: the curve starts from its
    /// critical point `from` (its saved state and mode), without a path. Loading a scene file
    /// resolves a relative directory against the scene file's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from_run: Option<PathBuf>,
    /// Step budget of the path that finds the point (≥ 1). Default 200.
    #[serde(default = "default_path_steps")]
    pub path_steps: usize,
    /// Watch the other irrep blocks at every curve point for hilltops and changes of the
    /// critical irrep (docs/theory.md §11.9). Default true; false saves their index at every
    /// point.
    #[serde(default = "default_watch")]
    pub watch: bool,
    /// The shared settings of the curve: steps, step sizes, direction, Newton's.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

fn default_path_steps() -> usize {
    200
}
fn default_watch() -> bool {
    true
}

/// `analysis.from` of a critical curve.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum CurveStart {
    /// The first limit point (the trivial block).
    #[default]
    Limit,
    /// The first critical point in this irrep's block.
    Irrep(String),
    /// The critical point with this index along the path (0 the first).
    Index(usize),
}

impl AnalysisSpec for CriticalCurveAnalysis {
    fn shared(&self) -> &Settings {
        &self.settings
    }
    fn shared_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    /// The curve's settings; it saves no states along the way.
    fn settings(&self) -> Settings {
        self.settings.saving_no_states()
    }
    /// The steps of the path that finds the point.
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
        Some(vec![&self.control, &self.second])
    }
    fn check(&self, scene: &Scene) -> Result<(), Problem> {
        free_parameter(scene, "analysis.control", &self.control)?;
        free_parameter(scene, "analysis.second", &self.second)?;
        if self.second == self.control {
            return Err(Problem::at(
                "analysis.second",
                format!(
                    "= \"{}\" is the control; the curve needs a second parameter",
                    self.second
                ),
            ));
        }
        if self.from_run.is_some() && !matches!(self.from, CurveStart::Index(_)) {
            let from = match &self.from {
                CurveStart::Limit => "\"limit\"".to_string(),
                CurveStart::Irrep(name) => format!("\"{name}\""),
                CurveStart::Index(i) => i.to_string(),
            };
            return Err(Problem::at(
                "analysis.from",
                format!(
                    "= {from}: with analysis.from-run it must be the index of a critical \
                     point of that run (0 the first, as in its critical.json)"
                ),
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
    fn resolve(&mut self, dir: &Path) {
        if let Some(run) = &mut self.from_run {
            if run.is_relative() {
                *run = dir.join(&*run);
            }
        }
    }
    fn stored_points(&self) -> (u64, u64) {
        let points = (self.settings.steps as u64).saturating_add(self.path_steps as u64);
        (points.saturating_add(2), 2)
    }
}

impl<'de> Deserialize<'de> for CurveStart {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = CurveStart;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("\"limit\", an irrep name or a critical-point index")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<CurveStart, E> {
                usize::try_from(v)
                    .map(CurveStart::Index)
                    .map_err(|_| E::invalid_value(Unexpected::Signed(v), &self))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<CurveStart, E> {
                usize::try_from(v)
                    .map(CurveStart::Index)
                    .map_err(|_| E::invalid_value(Unexpected::Unsigned(v), &self))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<CurveStart, E> {
                Ok(match v {
                    "limit" => CurveStart::Limit,
                    name => CurveStart::Irrep(name.to_string()),
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for CurveStart {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            CurveStart::Limit => s.serialize_str("limit"),
            CurveStart::Irrep(name) => s.serialize_str(name),
            CurveStart::Index(i) => s.serialize_u64(*i as u64),
        }
    }
}
