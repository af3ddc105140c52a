//! The `cusp-curve` analysis (docs/theory.md §11.12): the cusps of a limit-point curve in
//! (control, second), followed slice by slice in a third parameter, and where a pair of them
//! ends.
//!
//! Each slice is a critical curve ([`Curve`]) at one value of the third parameter: the start
//! state carried there at fixed control, the path in the control to the point, the curve
//! with its cusps (turning points of the second parameter, localised). Where the number of
//! cusps of neighbouring slices differs by two, a pair of neighbouring cusps — a maximum and
//! a minimum of the second parameter — ends between them. The interval is halved
//! `bisections` times, each added slice's curve stepping finely enough to resolve the pair
//! (an eighth of the pair's arclength on the slice that still holds it). The end is then
//! measured from the slices that hold the pair: the pair's arclength separation Δs vanishes
//! as the square root of the distance to the end (the cusp curve turns there in the third
//! parameter), so Δs² is linear in it, and two slices give its zero; the next two give it
//! again, which is its error. What the pair ends in is read from two independent signs: the
//! order of the pair's distance in the parameters against Δs² (3/2 at a swallowtail, 1/2 at
//! lips or beaks) and whether the fold line crosses itself beside the pair.

use super::curve::Curve;
use super::path::record_branch;
use super::surface::{carry, carry_outwards, Carried};
use super::{Analysis, Context, RunError};
use crate::continuation::PathOptions;
use crate::output::{self, Described, OutputError};
use crate::results::{
    CurveEventKind, CurveReport, CuspCurveReport, CuspSlice, Extremum, Outcome, PairEnd,
    PairEndKind, RunResult, StopReason,
};
use crate::scene::{CuspCurveAnalysis, Scene};
use crate::study::{Point, Study};
use crate::text::{num, sig_digits};
use std::path::Path;
use std::time::Instant;

/// `type = "cusp-curve"`.
pub struct Cusps(pub CuspCurveAnalysis);

impl Cusps {
    /// The curve of one slice with the scene's steps and largest step.
    fn curve(&self) -> Curve {
        Curve(
            self.0
                .curve(self.0.settings.max_step, self.0.settings.steps),
        )
    }

    /// The slice at the third parameter `value` from the carried state `start`, its curve
    /// stepping at most `max_step` for `steps` steps (its path to the point as the scene
    /// says); the path of the first slice that finds
    /// its point is recorded as the run's.
    #[allow(clippy::too_many_arguments)]
    fn slice(
        &self,
        study: &dyn Study,
        cx: &mut Context<'_>,
        start: &Carried,
        value: f64,
        (max_step, steps): (f64, usize),
        refined: bool,
        recorded: &mut Option<StopReason>,
    ) -> CuspSlice {
        let curve = Curve(self.0.curve(max_step, steps));
        let failed = |why: String| CuspSlice {
            third: value,
            refined,
            cusps: Vec::new(),
            arclengths: Vec::new(),
            line: Vec::new(),
            max_step,
            stop: None,
            failure: Some(why),
        };
        let point = Point {
            u: start.0.clone(),
            params: start.1.clone(),
            iterations: 0,
            times: Default::default(),
        };
        let t = Instant::now();
        let observer = &mut AtThird {
            inner: &mut *cx.observer,
            third: value,
        };
        // The path to the point steps as the scene says: a refined slice's finer step is
        // for its curve, near the cusps, not for the path's way up to the fold.
        let located = match self
            .curve()
            .locate(study, &mut cx.crossings, &point, &mut *observer)
        {
            Ok(l) => l,
            Err(e) => return failed(e.to_string()),
        };
        cx.times.steps.steps += located.branch.times.steps;
        cx.times.index += located.index_time;
        // The first path that found its point is the run's; so is one a signal cut short
        // before any did (the run then ends interrupted with it).
        let cut = located.branch.stop == StopReason::Interrupted;
        if recorded.is_none() && (located.branch.stop == StopReason::CriticalPoint || cut) {
            record_branch(
                study,
                &mut cx.record,
                &*located.problem,
                &located.branch,
                &located.indices,
                usize::MAX,
            );
            *recorded = Some(located.branch.stop.clone());
        }
        cx.times.path += t.elapsed();
        let cp = match located.point(&self.0.control, &self.0.from) {
            Ok(cp) => cp,
            Err(e) => return failed(e.to_string()),
        };
        let report = match curve.follow(study, &mut cx.crossings, &cp, observer) {
            Ok(r) => r,
            Err(e) => return failed(e.to_string()),
        };
        slice_of(&report, value, max_step, refined)
    }
}

/// The caller's observer during one slice: every point reported at the slice's value of the
/// third parameter, so that a progress display moves along the slices, not back and forth in
/// each slice's control.
struct AtThird<'o> {
    inner: &'o mut dyn super::Observer,
    third: f64,
}

impl super::Observer for AtThird<'_> {
    fn progress(&mut self, point: usize, _control: f64) {
        self.inner.progress(point, self.third);
    }

    fn state(&mut self, u: &[f64], params: &[f64]) {
        self.inner.state(u, params);
    }
}

/// The slice's cusps, their arclengths and its fold line, from its curve.
fn slice_of(curve: &CurveReport, third: f64, max_step: f64, refined: bool) -> CuspSlice {
    let column = |name: &str| {
        curve
            .parameters
            .iter()
            .position(|p| p == name)
            .expect("the curve's parameters")
    };
    let (c, s) = (column(&curve.control), column(&curve.second));
    let cusps: Vec<_> = curve
        .events
        .iter()
        .filter(|e| e.kind == CurveEventKind::Cusp)
        .cloned()
        .collect();
    CuspSlice {
        third,
        refined,
        arclengths: cusps.iter().map(|e| e.arclength).collect(),
        cusps,
        line: curve
            .rows
            .iter()
            .map(|r| [r.parameters[c], r.parameters[s]])
            .collect(),
        max_step,
        stop: Some(curve.stop.clone()),
        failure: None,
    }
}

/// The pairs of neighbouring cusps of opposite extremum, as indices into the slice's cusps.
pub fn pairs(slice: &CuspSlice) -> Vec<(usize, usize)> {
    (1..slice.cusps.len())
        .filter(|&i| {
            let (a, b) = (slice.cusps[i - 1].extremum, slice.cusps[i].extremum);
            matches!(
                (a, b),
                (Some(Extremum::Maximum), Some(Extremum::Minimum))
                    | (Some(Extremum::Minimum), Some(Extremum::Maximum))
            )
        })
        .map(|i| (i - 1, i))
        .collect()
}

/// The slice's closest pair of cusps (by arclength between them) and that arclength.
fn closest_pair(slice: &CuspSlice) -> Option<((usize, usize), f64)> {
    pairs(slice)
        .into_iter()
        .map(|(a, b)| ((a, b), (slice.arclengths[b] - slice.arclengths[a]).abs()))
        .min_by(|x, y| x.1.total_cmp(&y.1))
}

/// Whether the segments p0–p1 and q0–q1 cross (properly, not at a shared end).
fn segments_cross(p0: [f64; 2], p1: [f64; 2], q0: [f64; 2], q1: [f64; 2]) -> bool {
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let (d1, d2) = (orient(q0, q1, p0), orient(q0, q1, p1));
    let (d3, d4) = (orient(p0, p1, q0), orient(p0, p1, q1));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// The number of times the polyline `line` crosses itself between the points `from` and
/// `to` (segments that share a point are not compared).
pub fn self_crossings(line: &[[f64; 2]], from: usize, to: usize) -> usize {
    let to = to.min(line.len().saturating_sub(1));
    let mut count = 0;
    for i in from..to {
        for j in i + 2..to {
            if segments_cross(line[i], line[i + 1], line[j], line[j + 1]) {
                count += 1;
            }
        }
    }
    count
}

/// Whether the slice's fold line crosses itself beside its closest pair: between the pair's
/// steps widened on each side by twice the steps between them.
fn crosses_beside_pair(slice: &CuspSlice) -> bool {
    let Some(((a, b), _)) = closest_pair(slice) else {
        return false;
    };
    let (i, j) = (slice.cusps[a].after_step, slice.cusps[b].after_step);
    let wide = 2 * (j - i) + 2;
    self_crossings(&slice.line, i.saturating_sub(wide), j + wide + 1) > 0
}

/// Where Δs² = α (t_end − t) through the two points (t1, Δs1), (t2, Δs2) vanishes.
pub fn square_root_end((t1, s1): (f64, f64), (t2, s2): (f64, f64)) -> Option<f64> {
    let slope = (s2 * s2 - s1 * s1) / (t2 - t1);
    let end = t1 - s1 * s1 / slope;
    (slope != 0.0 && end.is_finite()).then_some(end)
}

/// The observed order of a distance d against Δs²: ln(d1/d2) / ln(Δs1²/Δs2²).
pub fn order((d1, s1): (f64, f64), (d2, s2): (f64, f64)) -> Option<f64> {
    let p = (d1 / d2).ln() / (s1 * s1 / (s2 * s2)).ln();
    p.is_finite().then_some(p)
}

/// What the order of the pair's distance in the second parameter and the self-crossing say
/// together: 3/2 and a crossing a swallowtail, 1/2 and none lips or beaks.
pub fn classify(order: Option<f64>, self_crossing: bool) -> PairEndKind {
    match order {
        Some(p) if (p - 1.5).abs() < (p - 0.5).abs() && self_crossing => PairEndKind::Swallowtail,
        Some(p) if (p - 0.5).abs() < (p - 1.5).abs() && !self_crossing => PairEndKind::LipsOrBeaks,
        _ => PairEndKind::Undecided,
    }
}

/// The end of a pair from the slices that hold it (`with`, nearest the end first) and the
/// bracket; `c`, `s` the columns of the control and the second parameter.
fn measure_end(with: &[&CuspSlice], bracket: [f64; 2], (c, s): (usize, usize)) -> PairEnd {
    let data: Vec<(f64, f64, f64, f64)> = with
        .iter()
        .filter_map(|sl| {
            let ((a, b), ds) = closest_pair(sl)?;
            let (pa, pb) = (&sl.cusps[a].parameters, &sl.cusps[b].parameters);
            Some((sl.third, ds, (pa[c] - pb[c]).abs(), (pa[s] - pb[s]).abs()))
        })
        .collect();
    let end_of = |i: usize| square_root_end((data[i].0, data[i].1), (data[i + 1].0, data[i + 1].1));
    let estimate = (data.len() >= 2).then(|| end_of(0)).flatten();
    let error = match (estimate, (data.len() >= 3).then(|| end_of(1)).flatten()) {
        (Some(a), Some(b)) => Some((a - b).abs()),
        _ => None,
    };
    let orders = (data.len() >= 2)
        .then(|| {
            let (x, y) = (data[0], data[1]);
            Some([
                order((x.2, x.1), (y.2, y.1))?,
                order((x.3, x.1), (y.3, y.1))?,
            ])
        })
        .flatten();
    let self_crossing = with.first().is_some_and(|sl| crosses_beside_pair(sl));
    let nearest = with
        .first()
        .and_then(|sl| {
            let ((a, b), _) = closest_pair(sl)?;
            Some([
                sl.cusps[a].parameters.clone(),
                sl.cusps[b].parameters.clone(),
            ])
        })
        .unwrap_or_default();
    PairEnd {
        kind: classify(orders.map(|o| o[1]), self_crossing),
        bracket,
        estimate,
        error,
        orders,
        self_crossing,
        nearest,
        slices: data.iter().map(|d| d.0).collect(),
    }
}

impl Analysis for Cusps {
    /// The path that finds each slice's point, as for `critical-curve`.
    fn options(&self, study: &dyn Study) -> PathOptions {
        self.curve().options(study)
    }

    /// The third parameter over the slices' range.
    fn progress_axis(&self) -> Option<(String, Option<(f64, f64)>)> {
        let range = match self.0.range[..] {
            [a, b] if a.is_finite() && b.is_finite() => Some((a.min(b), a.max(b))),
            _ => None,
        };
        Some((self.0.third.clone(), range))
    }

    /// Every slice of the grid, the slices added where a pair of cusps ends, and the ends;
    /// the first slice's path is the run's path.
    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let a = &self.0;
        if cx.crossings.is_none() {
            return Err(RunError::Curve(
                "the cusp curve needs the stability analysis by blocks, which this scene's \
                 group does not allow"
                    .into(),
            ));
        }
        let index = |name: &str| {
            study
                .about()
                .parameters
                .iter()
                .position(|p| p == name)
                .expect("validated parameter")
        };
        let (c, s, t) = (index(&a.control), index(&a.second), index(&a.third));
        let opts = self.options(study);
        let values = a.values();
        // The start state at every value of the grid, carried outwards from the start's.
        let (starts, mut warnings) = carry_outwards(study, &opts, &cx.start, t, &values);
        let scene_step = (a.settings.max_step, a.settings.steps);
        let mut recorded = None;
        // (slice, its start) in grid order.
        let mut slices: Vec<(CuspSlice, Carried)> = Vec::new();
        for (j, start) in starts.into_iter().enumerate() {
            let Some(start) = start else { continue };
            let slice = self.slice(
                study,
                cx,
                &start,
                values[j],
                scene_step,
                false,
                &mut recorded,
            );
            slices.push((slice, start));
            if crate::continuation::interrupt::requested() {
                break;
            }
        }
        // Where the number of cusps of neighbouring good slices differs by two, halve.
        let good: Vec<usize> = (0..slices.len())
            .filter(|&i| slices[i].0.failure.is_none())
            .collect();
        let mut ends = Vec::new();
        for w in good.windows(2) {
            let (n0, n1) = (slices[w[0]].0.cusps.len(), slices[w[1]].0.cusps.len());
            if n0.abs_diff(n1) != 2 {
                continue;
            }
            let (n_with, n_without) = (n0.max(n1), n0.min(n1));
            let (mut with, mut without) = if n0 > n1 { (w[0], w[1]) } else { (w[1], w[0]) };
            let mut added = vec![with];
            for _ in 0..a.bisections {
                if crate::continuation::interrupt::requested() {
                    break;
                }
                let value = 0.5 * (slices[with].0.third + slices[without].0.third);
                let Some((_, ds)) = closest_pair(&slices[with].0) else {
                    break;
                };
                let reach = slices[with].0.arclengths.last().copied().unwrap_or(0.0) + 2.0 * ds;
                let max_step = a.settings.max_step.min(ds / 8.0);
                let steps = ((1.5 * reach / max_step).ceil() as usize + 20).max(a.settings.steps);
                let start = slices[with].1.clone();
                let carried = match carry(study, &opts, &start.0, &start.1, t, value) {
                    Ok(state) => state,
                    Err(why) => {
                        warnings.push(format!("no slice at {} = {}: {why}", a.third, num(value)));
                        break;
                    }
                };
                let slice = self.slice(
                    study,
                    cx,
                    &carried,
                    value,
                    (max_step, steps),
                    true,
                    &mut recorded,
                );
                let n = slice.cusps.len();
                let failure = slice.failure.clone();
                slices.push((slice, carried));
                let new = slices.len() - 1;
                match failure {
                    Some(why) => {
                        warnings.push(format!("slice at {} = {}: {why}", a.third, num(value)));
                        break;
                    }
                    None if n == n_with => {
                        with = new;
                        added.push(new);
                    }
                    None if n == n_without => without = new,
                    None => {
                        warnings.push(format!(
                            "the slice at {} = {} has {n} cusps, neither {n_with} nor \
                             {n_without}: the interval is not halved further",
                            a.third,
                            num(value)
                        ));
                        break;
                    }
                }
            }
            // Every good slice on the pair's side holding n_with cusps, nearest the end first.
            let edge = slices[with].0.third;
            let side = (slices[without].0.third - edge).signum();
            let mut holding: Vec<&CuspSlice> = slices
                .iter()
                .map(|(sl, _)| sl)
                .filter(|sl| {
                    sl.failure.is_none()
                        && sl.cusps.len() == n_with
                        && (sl.third - edge) * side <= 0.0
                })
                .collect();
            holding.sort_by(|x, y| (edge - x.third).abs().total_cmp(&(edge - y.third).abs()));
            ends.push(measure_end(
                &holding,
                [edge, slices[without].0.third],
                (c, s),
            ));
        }
        let mut slices: Vec<CuspSlice> = slices.into_iter().map(|(sl, _)| sl).collect();
        slices.sort_by(|x, y| x.third.total_cmp(&y.third));
        for sl in &slices {
            if let Some(why) = &sl.failure {
                warnings.push(format!(
                    "no curve at {} = {}: {why}",
                    a.third,
                    num(sl.third)
                ));
            }
        }
        let Some(stop) = recorded else {
            return Err(RunError::Curve(format!(
                "no slice found its point: {}",
                warnings.join("; ")
            )));
        };
        let irrep = cx
            .record
            .critical
            .first()
            .map(|cp| cp.irrep.clone())
            .unwrap_or_default();
        cx.record.outcome = Some(Outcome::new(CuspCurveReport {
            control: a.control.clone(),
            second: a.second.clone(),
            third: a.third.clone(),
            irrep,
            parameters: study.about().parameters.clone(),
            measures: study.about().measures.clone(),
            slices,
            ends,
            warnings,
        }));
        Ok(stop)
    }

    /// `cusps.csv`, `cusp_curve.json`, `cusp_curve.svg` and `.png`.
    fn write(
        &self,
        result: &RunResult,
        _drawing: &dyn crate::output::Drawing,
        scene: &Scene,
        out: &Path,
    ) -> Result<Vec<Described>, OutputError> {
        let Some(report) = result.outcome::<CuspCurveReport>() else {
            return Ok(Vec::new());
        };
        let files = output::write_cusp_curve(
            out,
            report,
            &output::Scales::of_scene(scene, result.report.mesh.radius),
            &output::caption_of(&result.report),
        )?;
        let what = [
            format!(
                "a row per cusp of each of the {} slices: {}, both parameters, extremum, arclength",
                report.slices.len(),
                report.third
            ),
            "the slices, their cusps and fold lines, and where pairs of cusps end".to_string(),
            format!(
                "the fold lines in ({}, {}), one per slice, cusps marked",
                report.second, report.control
            ),
            "the same figure as an image".to_string(),
        ];
        Ok(Described::each(files, what))
    }

    /// The slices' cusp counts and each pair's end.
    fn summary(&self, result: &RunResult) -> Vec<String> {
        let Some(r) = result.outcome::<CuspCurveReport>() else {
            return Vec::new();
        };
        summary_lines(r)
    }
}

/// The summary of a cusp curve: a line per slice, then each end.
pub fn summary_lines(r: &CuspCurveReport) -> Vec<String> {
    let column = |name: &str| r.parameters.iter().position(|p| p == name);
    let (Some(c), Some(s)) = (column(&r.control), column(&r.second)) else {
        return Vec::new();
    };
    let mut lines = vec![format!(
        "cusps of the limit curve in ({}, {}) at {} values of {}:",
        r.control,
        r.second,
        r.slices.len(),
        r.third
    )];
    for sl in &r.slices {
        let what = match &sl.failure {
            Some(why) => format!("no curve ({why})"),
            None if sl.cusps.is_empty() => "no cusp".to_string(),
            None => sl
                .cusps
                .iter()
                .map(|e| {
                    format!(
                        "{} = {}, {} = {}",
                        r.control,
                        sig_digits(e.parameters[c], 6),
                        r.second,
                        sig_digits(e.parameters[s], 6)
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
        };
        let added = if sl.refined { " (added)" } else { "" };
        lines.push(format!(
            "  {} = {}{added}: {what}",
            r.third,
            sig_digits(sl.third, 6)
        ));
    }
    for e in &r.ends {
        let at = match (e.estimate, e.error) {
            (Some(x), Some(err)) => format!(
                "{} = {} ± {}",
                r.third,
                sig_digits(x, 6),
                sig_digits(err, 2)
            ),
            (Some(x), None) => format!("{} = {} (error not measured)", r.third, sig_digits(x, 6)),
            _ => "not estimated".to_string(),
        };
        let orders = e.orders.map_or_else(
            || "orders not measured".to_string(),
            |o| {
                format!(
                    "orders {:.2} in {}, {:.2} in {}",
                    o[0], r.control, o[1], r.second
                )
            },
        );
        lines.push(format!(
            "pair of cusps ends between {} = {} and {}: {}, at {at}; {orders}; fold line {}",
            r.third,
            sig_digits(e.bracket[0], 6),
            sig_digits(e.bracket[1], 6),
            e.kind,
            if e.self_crossing {
                "crosses itself beside the pair"
            } else {
                "does not cross itself"
            }
        ));
    }
    lines.extend(r.warnings.iter().map(|w| format!("warning: {w}")));
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The swallowtail's unfolding V = x⁵ + a x³ + b x² + c x: its fold set V' = V'' = 0 in
    /// (b, c) at fixed a, parametrised by x, and its cusps (V''' = 0 too) at x = ±√(−a/10).
    fn swallowtail_slice(a: f64, n: usize) -> Vec<[f64; 2]> {
        (0..=n)
            .map(|i| {
                let x = -1.0 + 2.0 * i as f64 / n as f64;
                let b = -10.0 * x * x * x - 3.0 * a * x;
                let c = -5.0 * x.powi(4) - 3.0 * a * x * x - 2.0 * b * x;
                [c, b]
            })
            .collect()
    }

    #[test]
    fn a_swallowtail_slice_crosses_itself_once_and_a_smooth_one_never() {
        let inside = swallowtail_slice(-0.3, 400);
        assert_eq!(self_crossings(&inside, 0, inside.len()), 1);
        let outside = swallowtail_slice(0.3, 400);
        assert_eq!(self_crossings(&outside, 0, outside.len()), 0);
    }

    #[test]
    fn the_swallowtails_pair_ends_by_the_square_root_law_with_order_three_halves() {
        // The pair's cusps at x = ±√(−a/10): Δs ∝ √(−a) to leading order (the state's
        // separation), Δb = 2·|b(x)| ∝ (−a)^{3/2}.
        let pair = |a: f64| {
            let x = (-a / 10.0).sqrt();
            let b = -10.0 * x * x * x - 3.0 * a * x;
            (2.0 * x, 2.0 * b.abs())
        };
        let (t1, t2) = (-0.02, -0.01);
        let ((s1, b1), (s2, b2)) = (pair(t1), pair(t2));
        let end = square_root_end((t1, s1), (t2, s2)).unwrap();
        assert!(end.abs() < 1e-15, "{end}");
        let p = order((b1, s1), (b2, s2)).unwrap();
        assert!((p - 1.5).abs() < 1e-12, "{p}");
        assert_eq!(classify(Some(p), true), PairEndKind::Swallowtail);
        assert_eq!(classify(Some(0.5), false), PairEndKind::LipsOrBeaks);
        assert_eq!(classify(Some(1.5), false), PairEndKind::Undecided);
        assert_eq!(classify(None, true), PairEndKind::Undecided);
    }
}
