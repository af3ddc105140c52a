//! `[analysis]`: what a scene computes. Each analysis type is one file here — its keys with
//! their defaults and its checks, implementing [`AnalysisSpec`] — and one line of
//! [`REGISTRY`]; the analysis that runs it is one file of `src/analysis/` and one line of its
//! registry (docs/architecture.md).
//!
//! The keys every path-following analysis shares (`steps`, `initial-step`, `min-step`,
//! `max-step`, `tolerance`, `max-iterations`, `direction`, `save-every`) are one table,
//! parsed straight into the driver's [`Settings`] and checked once ([`check_settings`]); an
//! analysis takes the subset it names in its registry line, and the rest of its table is its
//! own.

mod buckling;
mod curve;
mod cusps;
pub mod deflation;
mod diagram;
mod equilibrium;
mod path;
mod surface;

pub use buckling::LinearBucklingAnalysis;
pub use curve::{CriticalCurveAnalysis, CurveStart};
pub use cusps::CuspCurveAnalysis;
pub use diagram::DiagramAnalysis;
pub use equilibrium::EquilibriumAnalysis;
pub use path::{BranchesAnalysis, PathAnalysis, MAX_BRANCH_DEPTH};
pub use surface::SurfaceAnalysis;

use super::error::{num, Problem};
use super::load::de;
use super::Scene;
use crate::continuation::Settings;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::any::Any;
use std::fmt;
use std::path::Path;
use toml::{Table, Value};

/// The analysis types of `[analysis] type = "…"`, each with the shared keys it takes: one
/// line per analysis.
const REGISTRY: &[Entry] = &[
    Entry::of::<PathAnalysis>("path", &ALL),
    Entry::of::<EquilibriumAnalysis>("equilibrium", &NEWTON),
    Entry::of::<LinearBucklingAnalysis>("linear-buckling", &NEWTON),
    Entry::of::<CriticalCurveAnalysis>("critical-curve", &PATHS),
    Entry::of::<CuspCurveAnalysis>("cusp-curve", &PATHS),
    Entry::of::<SurfaceAnalysis>("surface", &PATHS),
    Entry::of::<deflation::DeflationAnalysis>("deflation", &ALL),
    Entry::of::<DiagramAnalysis>("diagram", &ALL),
];

/// Every shared key.
const ALL: [&str; 8] = [
    "direction",
    "steps",
    "initial-step",
    "min-step",
    "max-step",
    "save-every",
    "tolerance",
    "max-iterations",
];
/// The shared keys of an analysis whose paths write no states along the way.
const PATHS: [&str; 7] = [
    "direction",
    "steps",
    "initial-step",
    "min-step",
    "max-step",
    "tolerance",
    "max-iterations",
];
/// The shared keys of an analysis with one Newton solve and no path.
const NEWTON: [&str; 2] = ["tolerance", "max-iterations"];

/// One `[analysis]` type: its keys (a serde struct, its shared [`Settings`] held beside them)
/// and what the scene and its checks need to know of it.
pub trait AnalysisSpec: fmt::Debug + Send + Sync + Erased {
    /// The shared settings as parsed (defaults where a key was left out).
    fn shared(&self) -> &Settings;
    /// The shared settings, to set after parsing.
    fn shared_mut(&mut self) -> &mut Settings;
    /// The continuation settings of its paths (by default the shared ones).
    fn settings(&self) -> Settings {
        self.shared().clone()
    }
    /// The step budget of its paths (the steps of a path, of a surface's paths, of the path
    /// to a critical curve's point, the samples of a sweep); none for an equilibrium.
    fn budget(&self) -> Option<usize> {
        Some(self.shared().steps)
    }
    /// Sets the step budget of its paths ([`AnalysisSpec::budget`]).
    fn set_budget(&mut self, n: usize) {
        self.shared_mut().steps = n;
    }
    /// Whether the start state is held while the control sweeps (linear buckling).
    fn holds_state(&self) -> bool {
        false
    }
    /// The measure it names (a surface's third coordinate), if it names one.
    fn measure(&self) -> Option<&str> {
        None
    }
    /// The parameter its paths follow first (the control), if it has one.
    fn control(&self) -> Option<&str>;
    /// The parameters free on its paths; every other parameter must be governed by a
    /// constraint. `None`: it follows no path in a free parameter (every parameter is held).
    fn free(&self) -> Option<Vec<&str>> {
        self.control().map(|c| vec![c])
    }
    /// Checks its keys against the scene (the shared settings are checked before).
    fn check(&self, scene: &Scene) -> Result<(), Problem>;
    /// Checks what needs the mesh: whether the membrane is `closed`; `the_mesh` names it.
    fn check_mesh(&self, _closed: bool, _the_mesh: &str) -> Result<(), Problem> {
        Ok(())
    }
    /// Resolves a relative path it names against the scene file's directory.
    fn resolve(&mut self, _dir: &Path) {}
    /// The points it keeps in memory (each with a state and a tangent) and the states it
    /// saves, for the estimate of a run's memory.
    fn stored_points(&self) -> (u64, u64);
}

/// What makes an [`AnalysisSpec`] a value: cloned, compared, written back as TOML and read
/// as its concrete type. Implemented for every serde struct that is one.
pub trait Erased {
    /// A copy.
    fn clone_box(&self) -> Box<dyn AnalysisSpec>;
    /// Whether `other` is the same type with equal keys.
    fn eq_dyn(&self, other: &dyn AnalysisSpec) -> bool;
    /// Its own keys (not the shared ones) as a TOML table.
    fn own_table(&self) -> Table;
    /// As its concrete type.
    fn as_any(&self) -> &dyn Any;
    /// As its concrete type, mutably.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: AnalysisSpec + Clone + PartialEq + Serialize + 'static> Erased for T {
    fn clone_box(&self) -> Box<dyn AnalysisSpec> {
        Box::new(self.clone())
    }
    fn eq_dyn(&self, other: &dyn AnalysisSpec) -> bool {
        other.as_any().downcast_ref::<T>() == Some(self)
    }
    fn own_table(&self) -> Table {
        Table::try_from(self).expect("an analysis' keys serialise to a TOML table")
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// One line of [`REGISTRY`].
struct Entry {
    kind: &'static str,
    shared: &'static [&'static str],
    parse: fn(Table) -> Result<Box<dyn AnalysisSpec>, Problem>,
}

impl Entry {
    const fn of<T: AnalysisSpec + DeserializeOwned + 'static>(
        kind: &'static str,
        shared: &'static [&'static str],
    ) -> Entry {
        Entry {
            kind,
            shared,
            parse: parse::<T>,
        }
    }
}

fn parse<T: AnalysisSpec + DeserializeOwned + 'static>(
    own: Table,
) -> Result<Box<dyn AnalysisSpec>, Problem> {
    de::<T>(&Value::Table(own), "analysis").map(|t| Box::new(t) as Box<dyn AnalysisSpec>)
}

/// `[analysis]` as parsed: its type, the shared settings it takes and its own keys.
#[derive(Debug)]
pub struct Analysis {
    kind: &'static str,
    shared: &'static [&'static str],
    spec: Box<dyn AnalysisSpec>,
}

/// The analysis types, by their `type`.
pub fn analysis_types() -> Vec<&'static str> {
    REGISTRY.iter().map(|e| e.kind).collect()
}

impl Analysis {
    /// Reads `[analysis]` of type `kind` from `table` (without its `type`): the shared keys
    /// the type takes into its [`Settings`], the others into its own keys.
    pub(super) fn read(kind: &str, table: &Table) -> Result<Analysis, Problem> {
        let entry = REGISTRY
            .iter()
            .find(|e| e.kind == kind)
            .expect("the tag was checked against analysis_types()");
        let (shared, own): (Table, Table) = table
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .partition(|(k, _)| entry.shared.contains(&k.as_str()));
        let settings: Settings = de(&Value::Table(shared), "analysis")?;
        let mut spec = (entry.parse)(own).map_err(|p| with_shared(p, entry.shared))?;
        *spec.shared_mut() = settings;
        Ok(Analysis {
            kind: entry.kind,
            shared: entry.shared,
            spec,
        })
    }

    /// The `type`.
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// Its keys as the concrete type `T`, if it is one (`scene.analysis.get::<PathAnalysis>()`).
    pub fn get<T: 'static>(&self) -> Option<&T> {
        self.spec.as_any().downcast_ref()
    }

    /// Its keys as the concrete type `T`, mutably.
    pub fn get_mut<T: 'static>(&mut self) -> Option<&mut T> {
        self.spec.as_any_mut().downcast_mut()
    }

    /// The analysis type's view of itself.
    pub fn spec(&self) -> &dyn AnalysisSpec {
        &*self.spec
    }

    /// The continuation settings of this analysis ([`AnalysisSpec::settings`]).
    pub fn settings(&self) -> Settings {
        self.spec.settings()
    }

    /// The step budget of its paths ([`AnalysisSpec::budget`]).
    pub fn budget(&self) -> Option<usize> {
        self.spec.budget()
    }

    /// Sets the step budget of its paths.
    pub fn set_budget(&mut self, n: usize) {
        self.spec.set_budget(n)
    }

    /// Whether the start state is held while the control sweeps (linear buckling).
    pub fn holds_state(&self) -> bool {
        self.spec.holds_state()
    }

    /// The measure the analysis names (a surface's third coordinate), if it names one.
    pub fn measure(&self) -> Option<&str> {
        self.spec.measure()
    }

    /// The control parameter of its paths, if it has one.
    pub fn control(&self) -> Option<&str> {
        self.spec.control()
    }

    pub(super) fn resolve(&mut self, dir: &Path) {
        self.spec.resolve(dir)
    }

    /// The shared settings and the analysis' own checks.
    pub(super) fn check(&self, scene: &Scene) -> Result<(), Problem> {
        check_settings(self.spec.shared(), self.shared)?;
        self.spec.check(scene)
    }
}

impl Clone for Analysis {
    fn clone(&self) -> Self {
        Analysis {
            kind: self.kind,
            shared: self.shared,
            spec: self.spec.clone_box(),
        }
    }
}

impl PartialEq for Analysis {
    fn eq(&self, other: &Self) -> bool {
        self.kind == other.kind && self.spec.eq_dyn(&*other.spec)
    }
}

impl Serialize for Analysis {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut table = Table::new();
        table.insert("type".into(), Value::String(self.kind.into()));
        let shared = Table::try_from(self.spec.shared()).map_err(serde::ser::Error::custom)?;
        for (k, v) in shared {
            if self.shared.contains(&k.as_str()) {
                table.insert(k, v);
            }
        }
        table.extend(self.spec.own_table());
        table.serialize(s)
    }
}

/// An unknown key of an analysis' own table lists the shared keys it takes among the valid
/// ones.
fn with_shared(mut p: Problem, shared: &[&str]) -> Problem {
    if p.message.starts_with("unknown key ") && !shared.is_empty() {
        let list = shared.join(", ");
        p.message = match p.message.split_once("; valid keys: ") {
            Some((head, own)) => format!("{head}; valid keys: {own}, {list}"),
            None => format!("{}; valid keys: {list}", p.message),
        };
    }
    p
}

/// The shared keys an analysis takes: a step budget ≥ 1, positive step sizes with min ≤
/// initial ≤ max, save-every ≥ 1, Newton's tolerance within [1e-15, 1) and at most 1000
/// iterations.
fn check_settings(s: &Settings, shared: &[&str]) -> Result<(), Problem> {
    use super::validate::{at_least, positive};
    if shared.contains(&"steps") {
        at_least("analysis.steps", s.steps, 1)?;
    }
    if shared.contains(&"initial-step") {
        check_steps(s.initial_step, s.min_step, s.max_step)?;
    }
    if shared.contains(&"save-every") {
        at_least("analysis.save-every", s.save_every, 1)?;
    }
    positive("analysis.tolerance", s.tolerance)?;
    if !(1e-15..1.0).contains(&s.tolerance) {
        return Err(Problem::at(
            "analysis.tolerance",
            format!(
                "must lie in [1e-15, 1) (a relative residual that double precision can meet), got {}",
                num(s.tolerance)
            ),
        ));
    }
    at_least("analysis.max-iterations", s.max_iterations, 1)?;
    if s.max_iterations > 1000 {
        return Err(Problem::at(
            "analysis.max-iterations",
            format!("must be at most 1000, got {}", s.max_iterations),
        ));
    }
    Ok(())
}

/// The arclength steps: all > 0, min ≤ initial ≤ max.
fn check_steps(initial_step: f64, min_step: f64, max_step: f64) -> Result<(), Problem> {
    use super::validate::positive;
    positive("analysis.min-step", min_step)?;
    positive("analysis.max-step", max_step)?;
    positive("analysis.initial-step", initial_step)?;
    if min_step > max_step {
        return Err(Problem::at(
            "analysis.min-step",
            format!(
                "must be <= max-step = {}, got {}",
                num(max_step),
                num(min_step)
            ),
        ));
    }
    if initial_step < min_step || initial_step > max_step {
        return Err(Problem::at(
            "analysis.initial-step",
            format!(
                "must lie within [min-step, max-step] = [{}, {}], got {}",
                num(min_step),
                num(max_step),
                num(initial_step)
            ),
        ));
    }
    Ok(())
}
