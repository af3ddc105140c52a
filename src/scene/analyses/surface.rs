//! `type = "surface"`: the equilibrium manifold in two parameters.

use super::super::error::{num, Problem};
use super::super::validate::{at_least, free_parameter};
use super::{AnalysisSpec, Scene};
use crate::continuation::Settings;
use serde::{Deserialize, Serialize};

/// `type = "surface"`: the two-parameter equilibrium manifold in the fixed-point space
/// (docs/theory.md §11.10). With `parameters = [a, b]`, the start state is carried at fixed
/// `a` to each of `paths` equally spaced values of `b` over `ranges[1]`; from each, the path
/// in `a` is followed through its folds until `a` leaves `ranges[0]` or after `steps` steps
/// (the shared settings, those of every path; `direction` is the sense of every path's first
/// step in `a`). Neighbouring paths are stitched into triangles; every vertex carries the
/// index by irrep blocks, and the critical points of the paths are joined across `b` into
/// critical lines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SurfaceAnalysis {
    /// `[a, b]`: the parameter of the paths and the parameter of the grid.
    pub parameters: Vec<String>,
    /// `[[a_min, a_max], [b_min, b_max]]`: where the paths stop, and the grid's extent.
    pub ranges: Vec<Vec<f64>>,
    /// Number of paths, the values of `b` (>= 2). Default 5.
    #[serde(default = "default_paths")]
    pub paths: usize,
    /// The measure of the surface's third coordinate. Default the scene's first measure.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measure: Option<String>,
    /// The shared settings of every path: steps, step sizes, direction, Newton's.
    #[serde(skip, default = "Settings::of_scene")]
    pub settings: Settings,
}

fn default_paths() -> usize {
    5
}

impl SurfaceAnalysis {
    /// The parameter of the paths.
    pub fn a(&self) -> &str {
        &self.parameters[0]
    }

    /// The parameter of the grid.
    pub fn b(&self) -> &str {
        &self.parameters[1]
    }

    /// The grid's values of `b`, ascending.
    pub fn b_values(&self) -> Vec<f64> {
        let [lo, hi] = [self.ranges[1][0], self.ranges[1][1]];
        let n = self.paths.max(2);
        (0..n)
            .map(|j| lo + (hi - lo) * j as f64 / (n - 1) as f64)
            .collect()
    }
}

impl AnalysisSpec for SurfaceAnalysis {
    fn shared(&self) -> &Settings {
        &self.settings
    }
    fn shared_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    /// Every path's settings; the paths save no states along the way.
    fn settings(&self) -> Settings {
        self.settings.saving_no_states()
    }
    fn measure(&self) -> Option<&str> {
        self.measure.as_deref()
    }
    fn control(&self) -> Option<&str> {
        self.parameters.first().map(String::as_str)
    }
    fn free(&self) -> Option<Vec<&str>> {
        Some(self.parameters.iter().map(String::as_str).collect())
    }
    fn check(&self, scene: &Scene) -> Result<(), Problem> {
        check_surface(scene, self)
    }
    /// The paths' points are kept (as rows) but only the first path's states.
    fn stored_points(&self) -> (u64, u64) {
        ((self.settings.steps as u64).saturating_add(1), 2)
    }
}

/// `[analysis] type = "surface"`: two free parameters, a finite range of each (the first
/// holding its start value), at least two paths.
fn check_surface(scene: &Scene, a: &SurfaceAnalysis) -> Result<(), Problem> {
    let names = |v: &[String]| {
        let quoted: Vec<String> = v.iter().map(|n| format!("\"{n}\"")).collect();
        format!("[{}]", quoted.join(", "))
    };
    let [first, second] = a.parameters.as_slice() else {
        return Err(Problem::at(
            "analysis.parameters",
            format!(
                "= {}: needs two parameter names [a, b] (the paths' parameter, the grid's)",
                names(&a.parameters)
            ),
        ));
    };
    free_parameter(scene, "analysis.parameters[0]", first)?;
    free_parameter(scene, "analysis.parameters[1]", second)?;
    if first == second {
        return Err(Problem::at(
            "analysis.parameters",
            format!("= {}: the two parameters must differ", names(&a.parameters)),
        ));
    }
    let show = |r: &[f64]| {
        let v: Vec<String> = r.iter().map(|x| num(*x)).collect();
        format!("[{}]", v.join(", "))
    };
    if a.ranges.len() != 2 {
        let all: Vec<String> = a.ranges.iter().map(|r| show(r)).collect();
        return Err(Problem::at(
            "analysis.ranges",
            format!(
                "= [{}]: needs two ranges [[a_min, a_max], [b_min, b_max]]",
                all.join(", ")
            ),
        ));
    }
    for (i, r) in a.ranges.iter().enumerate() {
        let key = format!("analysis.ranges[{i}]");
        let ok = r.len() == 2 && r.iter().all(|x| x.is_finite()) && r[0] < r[1];
        if !ok {
            return Err(Problem::at(
                &key,
                format!("= {}: needs [min, max] with finite min < max", show(r)),
            ));
        }
    }
    let start = scene.parameters[first].start;
    if !(a.ranges[0][0]..=a.ranges[0][1]).contains(&start) {
        return Err(Problem::at(
            "analysis.ranges[0]",
            format!(
                "= {}: the paths start at {first} = {} (parameters.{first}.start), outside it",
                show(&a.ranges[0]),
                num(start)
            ),
        ));
    }
    // The grid of b inside b's own bounds, where it declares them.
    let declared = &scene.parameters[second];
    let (lo, hi) = (a.ranges[1][0], a.ranges[1][1]);
    let outside = declared.min.is_some_and(|m| lo < m) || declared.max.is_some_and(|m| hi > m);
    if outside {
        let bound = |b: Option<f64>| b.map_or_else(|| "none".to_string(), num);
        return Err(Problem::at(
            "analysis.ranges[1]",
            format!(
                "= {}: outside [min, max] = [{}, {}] of parameters.{second}",
                show(&a.ranges[1]),
                bound(declared.min),
                bound(declared.max)
            ),
        ));
    }
    at_least("analysis.paths", a.paths, 2)?;
    if a.paths > 1000 {
        return Err(Problem::at(
            "analysis.paths",
            format!("must be <= 1000, got {}", a.paths),
        ));
    }
    if let Some(m) = &a.measure {
        if m.trim().is_empty() {
            return Err(Problem::at(
                "analysis.measure",
                "= \"\": needs the name of a measure (stretch, volume, max_displacement, ...)",
            ));
        }
    }
    Ok(())
}
