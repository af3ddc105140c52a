//! The `critical-curve` analysis (docs/theory.md §11.7): a critical point of the path in the
//! control, followed as a second parameter varies.
//!
//! The point is found on the path in the control (the second parameter held), by the index
//! changes of the blocks ([`crate::continuation::crossings::IndexChanges`]). Its block μ is singular
//! there with a *simple* zero — also at a d-fold bifurcation point of K, whose d partner
//! blocks are identical — so the minimally augmented test function of the bordered block
//!
//! ```text
//!   [[K_μ, b], [bᵀ, 0]] [v; σ] = [0; 1]
//! ```
//!
//! vanishes exactly where K_μ is singular, and its derivatives are σ_z = −vᵀ (∂K_μ/∂z) v
//! for every unknown z (K_μ symmetric: the left and right vectors coincide). The curve is the
//! path of R = 0 (the equilibrium in the fixed-point space), g = 0 (the constraints) and
//! σ = 0 in (q, second, the constraints' parameters, control), followed by the ordinary
//! [`Continuation`] driver with σ as one more augmenting equation ([`CurveProblem`]) and
//! watched by the ordinary detectors: a turning point of the second parameter on a limit
//! curve is a cusp (two limit points merge). Unless `watch = false`, the other blocks'
//! negative counts are watched at every curve point (`OtherBlocks`): where one changes, that block is singular together
//! with the curve's — a hilltop (one of them trivial) or a change of the critical irrep —
//! localised on the curve by the path's own routine (docs/theory.md §11.9).
//!
//! The test function of the block is the study's ([`crate::study::Study::critical_test`]):
//! the 3-D irrep block's by directional differences of the tangent, the meridian's Fourier
//! block's by differences of its entries.

use super::path::{record_branch, start_driver};
use super::{Analysis, Context, Observer, RunError};
use crate::continuation::crossings::{CriticalTest, Crossings, End, IndexChanges, Spectrum};
use crate::continuation::events::{trace, Branch, Detector, Event, States};
use crate::continuation::{
    Accepted, Continuation, Linearization, PathOptions, PathPoint, Problem, Settings,
};
use crate::model::ModelError;
use crate::output::{self, Described, OutputError};
use crate::results::{
    CriticalKind, CriticalPoint, CurveEvent, CurveEventKind, CurveReport, CurveRow, Outcome,
    PhaseTimes, RunResult, StateKind, StopReason,
};
use crate::scene::AnalysisSpec as _;
use crate::scene::Scene;
use crate::scene::{CriticalCurveAnalysis, CurveStart};
use crate::study::{Followed, Free, Study};
use crate::text::sig_digits;
use nalgebra::{DMatrix, DVector};
use std::path::Path;
use std::time::Instant;

/// The curve's problem: the fixed-point problem with the second parameter free, plus σ = 0.
/// Its free parameters are (second, the constraints' parameters, control).
pub struct CurveProblem<'a> {
    inner: Box<dyn Followed + 'a>,
    test: Box<dyn CriticalTest + 'a>,
    /// The parameter index of every free parameter, in the order of λ.
    free: Vec<usize>,
    /// The last evaluated (q, λ) and its null vector v.
    last: Option<(DVector<f64>, DVector<f64>, DVector<f64>)>,
}

impl<'a> CurveProblem<'a> {
    /// The curve of `test`'s block in the problem `inner`, whose free parameters are the
    /// parameter indices `free`.
    pub fn new(
        inner: Box<dyn Followed + 'a>,
        test: Box<dyn CriticalTest + 'a>,
        free: Vec<usize>,
    ) -> Self {
        Self {
            inner,
            test,
            free,
            last: None,
        }
    }

    /// The null vector v at (q, λ): from the last evaluation when it was there.
    fn null_vector(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<DVector<f64>, ModelError> {
        if let Some((lq, ll, v)) = &self.last {
            if lq == q && ll == lambda {
                return Ok(v.clone());
            }
        }
        let (u, params) = (self.inner.displacement(q), self.inner.parameters(lambda));
        Ok(self.test.value(&u, &params)?.1)
    }

    /// The test function, to refresh its border or evaluate it at a point.
    pub fn test_mut(&mut self) -> &mut (dyn CriticalTest + 'a) {
        &mut *self.test
    }
}

impl Problem for CurveProblem<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn free_parameters(&self) -> usize {
        self.inner.free_parameters()
    }

    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        let mut lin = self.inner.evaluate(q, lambda)?;
        let u = self.inner.displacement(q);
        let params = self.inner.parameters(lambda);
        let t = self.test.evaluate(&u, &params)?;
        let (m, c, nf) = (q.len(), lin.constraints.len(), lambda.len());
        let sigma_q = &t.grad_q;
        self.last = Some((q.clone(), lambda.clone(), t.vector.clone()));
        let mut constraints = DVector::zeros(c + 1);
        constraints.rows_mut(0, c).copy_from(&lin.constraints);
        constraints[c] = t.sigma;
        lin.constraints = constraints;
        let mut gq = DMatrix::zeros(c + 1, m);
        gq.view_mut((0, 0), (c, m)).copy_from(&lin.constraint_q);
        gq.row_mut(c).copy_from(&sigma_q.transpose());
        let mut gl = DMatrix::zeros(c + 1, nf);
        gl.view_mut((0, 0), (c, nf))
            .copy_from(&lin.constraint_lambda);
        for (j, &i) in self.free.iter().enumerate() {
            gl[(c, j)] = t.grad_params[i];
        }
        lin.constraint_q = gq;
        lin.constraint_lambda = gl;
        Ok(lin)
    }

    fn phase_times(&self) -> PhaseTimes {
        self.inner.phase_times()
    }
}

impl States for CurveProblem<'_> {
    fn displacement(&self, q: &DVector<f64>) -> Vec<f64> {
        self.inner.displacement(q)
    }

    fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        self.inner.parameters(lambda)
    }
}

/// Refreshes the border of the test function to the null vector at every accepted point, so
/// that the bordered block stays well conditioned along the curve.
struct RefreshBorder;

impl Detector<CurveProblem<'_>> for RefreshBorder {
    fn check(
        &mut self,
        driver: &mut Continuation<CurveProblem<'_>>,
        _: &Accepted,
        _: usize,
    ) -> Vec<Event> {
        let p = driver.point().clone();
        let problem = driver.problem_mut();
        let (u, params) = (problem.displacement(&p.q), problem.parameters(&p.lambda));
        match problem.null_vector(&p.q, &p.lambda).and_then(|v| {
            let test = problem.test_mut();
            test.set_border(&v);
            test.rescale(&u, &params)
        }) {
            Ok(()) => Vec::new(),
            Err(e) => vec![Event::Warning(format!(
                "the critical block could not be evaluated to refresh its border: {e}"
            ))],
        }
    }
}

/// The blocks other than `own` whose negative count differs between two curve points
/// (`before`, `after`: the count of every block, the trivial first). The curve's own block is
/// singular all along the curve, so its count is noise and never an event.
pub fn changed_blocks(own: usize, before: &[usize], after: &[usize]) -> Vec<usize> {
    before
        .iter()
        .zip(after)
        .enumerate()
        .filter(|&(nu, (a, b))| nu != own && a != b)
        .map(|(nu, _)| nu)
        .collect()
}

/// What it is where block `other` becomes singular on the curve of block `own` (block 0 the
/// trivial one): a hilltop when either is trivial — a limit point meets a bifurcation point —
/// else a change of the critical irrep, two bifurcation curves crossing.
pub fn crossing_kind(own: usize, other: usize) -> CurveEventKind {
    if own == 0 || other == 0 {
        CurveEventKind::Hilltop
    } else {
        CurveEventKind::IrrepChange
    }
}

/// Watches the other irrep blocks along a curve: where the negative count of a block other
/// than the curve's own changes between two curve points, that block is singular together
/// with the curve's somewhere in between — a hilltop when one of the two is the trivial block,
/// a change of the critical irrep otherwise. The crossing is localised on the curve's
/// arclength by [`Crossings::localise`], the same routine as on a path, with the curve's own
/// block left out (its eigenvalue is zero all along, its count noise).
struct OtherBlocks<'a> {
    crossings: Crossings<'a>,
    /// The curve's block.
    own: usize,
    previous: Option<(Spectrum, Vec<f64>, Vec<f64>)>,
}

impl OtherBlocks<'_> {
    /// The index spectrum at `point` with the curve's own block's count zeroed, remembered;
    /// returns the earlier one.
    fn observe(
        &mut self,
        problem: &CurveProblem<'_>,
        point: &PathPoint,
    ) -> Option<(Spectrum, Vec<f64>, Vec<f64>)> {
        let u = problem.displacement(&point.q);
        let params = problem.parameters(&point.lambda);
        let spectrum = self.crossings.index(&u, &params).map(|mut s| {
            s.blocks[self.own].negative = 0;
            s
        });
        std::mem::replace(&mut self.previous, spectrum.map(|s| (s, u, params)))
    }
}

impl<'b> Detector<CurveProblem<'b>> for OtherBlocks<'_> {
    fn start(&mut self, driver: &mut Continuation<CurveProblem<'b>>) -> Vec<Event> {
        let point = driver.point().clone();
        self.observe(driver.problem(), &point);
        Vec::new()
    }

    fn check(
        &mut self,
        driver: &mut Continuation<CurveProblem<'b>>,
        step: &Accepted,
        after: usize,
    ) -> Vec<Event> {
        let point = driver.point().clone();
        let previous = self.observe(driver.problem(), &point);
        let (Some((a, u0, p0)), Some((b, u1, p1))) = (&previous, &self.previous) else {
            return Vec::new();
        };
        if changed_blocks(self.own, &a.negatives(), &b.negatives()).is_empty() {
            return Vec::new();
        }
        let s1 = point.arclength - step.from.arclength;
        let ends = (
            End {
                spectrum: a,
                u: u0,
                params: p0,
            },
            End {
                spectrum: b,
                u: u1,
                params: p1,
            },
        );
        self.crossings
            .localise(ends.0, ends.1, after, s1, false, |s| {
                let q = driver.corrected_from(&step.from, s).ok()?;
                let problem = driver.problem();
                Some((problem.displacement(&q.q), problem.parameters(&q.lambda)))
            })
    }
}

/// Watches the path for critical points and stops it at the one `from` asks for.
struct FirstCritical<'a> {
    index: IndexChanges<'a>,
    from: CurveStart,
    seen: usize,
}

impl FirstCritical<'_> {
    fn wanted(&mut self, cp: &CriticalPoint) -> bool {
        let hit = asks_for(&self.from, cp, self.seen);
        self.seen += 1;
        hit
    }
}

/// Whether `from` asks for `cp`, the path's critical point number `seen` (0 the first).
fn asks_for(from: &CurveStart, cp: &CriticalPoint, seen: usize) -> bool {
    match from {
        CurveStart::Limit => cp.kind == CriticalKind::LimitPoint,
        CurveStart::Irrep(name) => cp.irrep == *name,
        CurveStart::Index(i) => seen == *i,
    }
}

impl<'b> Detector<Box<dyn Followed + 'b>> for FirstCritical<'_> {
    fn start(&mut self, driver: &mut Continuation<Box<dyn Followed + 'b>>) -> Vec<Event> {
        self.index.start(driver)
    }

    fn check(
        &mut self,
        driver: &mut Continuation<Box<dyn Followed + 'b>>,
        step: &Accepted,
        after: usize,
    ) -> Vec<Event> {
        let mut events = self.index.check(driver, step, after);
        let found = events.iter().any(|e| match e {
            Event::Critical(cp) => self.wanted(cp),
            _ => false,
        });
        if found {
            events.push(Event::Stop(StopReason::CriticalPoint));
        }
        events
    }
}

/// The point the curve starts from, in words, for messages.
fn describe(from: &CurveStart) -> String {
    match from {
        CurveStart::Limit => "limit point".into(),
        CurveStart::Irrep(name) => format!("critical point in {name}"),
        CurveStart::Index(i) => format!("critical point number {i}"),
    }
}

/// `type = "critical-curve"`.
pub struct Curve(pub CriticalCurveAnalysis);

impl Curve {
    /// The settings of the curve.
    fn settings(&self) -> Settings {
        self.0.settings()
    }
}

impl Analysis for Curve {
    fn events<'r>(&self, result: &'r RunResult) -> &'r [CurveEvent] {
        result
            .outcome::<CurveReport>()
            .map_or(&[], |c| c.events.as_slice())
    }

    /// `curve.csv`, `curve.json`, `curve.svg`.
    fn write(
        &self,
        result: &RunResult,
        _drawing: &dyn crate::output::Drawing,
        scene: &Scene,
        out: &Path,
    ) -> Result<Vec<Described>, OutputError> {
        let Some(curve) = result.outcome::<CurveReport>() else {
            return Ok(Vec::new());
        };
        let files = output::write_curve_with(
            out,
            curve,
            Some(&result.report),
            &output::Scales::of_scene(scene, result.report.mesh.radius),
            &output::caption_of(&result.report),
        )?;
        let what = [
            format!(
                "{} rows: both parameters, the measures, the block's eigenvalues",
                curve.rows.len()
            ),
            "the curve: its points and events".to_string(),
            format!("{} against {}, events marked", curve.second, curve.control),
            "the same figure as an image".to_string(),
        ];
        Ok(Described::each(files, what))
    }

    /// What was followed, its extent and its events.
    fn summary(&self, result: &RunResult) -> Vec<String> {
        let Some(curve) = result.outcome::<CurveReport>() else {
            return Vec::new();
        };
        let mut lines = vec![format!(
            "critical curve of the {} in {} x{} in ({}, {}): {} points",
            curve.kind,
            curve.irrep,
            curve.multiplicity,
            curve.control,
            curve.second,
            curve.rows.len()
        )];
        let column = |name: &str| curve.parameters.iter().position(|p| p == name);
        let (Some(c), Some(s)) = (column(&curve.control), column(&curve.second)) else {
            return lines;
        };
        for e in &curve.events {
            let extremum = e
                .extremum
                .map_or_else(String::new, |x| format!(" ({x} of {})", curve.second));
            let why: Vec<String> = e.flags.iter().map(ToString::to_string).collect();
            let flagged = if why.is_empty() {
                String::new()
            } else {
                format!(" — flagged: {}", why.join("; "))
            };
            lines.push(format!(
                "  {:<9} {} = {}, {} = {}{extremum} (after curve step {}){flagged}",
                e.kind.to_string(),
                curve.control,
                sig_digits(e.parameters[c], 6),
                curve.second,
                sig_digits(e.parameters[s], 6),
                e.after_step
            ));
        }
        lines.push(format!("curve stopped: {}", curve.stop));
        lines.extend(curve.warnings.iter().map(|w| format!("warning: {w}")));
        lines
    }

    fn restarts_from(&self) -> Option<(std::path::PathBuf, usize)> {
        match (&self.0.from_run, &self.0.from) {
            (Some(dir), CurveStart::Index(i)) => Some((dir.clone(), *i)),
            _ => None,
        }
    }

    /// The options of the path that finds the curve's first point: the control increasing
    /// from the start for `path-steps` steps.
    fn options(&self, study: &dyn Study) -> PathOptions {
        let settings = Settings {
            steps: self.0.path_steps,
            direction: 1.0,
            ..self.settings()
        };
        super::equilibrium::path_options(study, &settings, None)
    }

    /// Finds the critical point on the path in the control (or takes the finished run's,
    /// `from-run`), then follows it in (control, second); the path is recorded, the curve
    /// put into the record.
    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let analysis = &self.0;
        let t0 = Instant::now();
        if cx.crossings.is_none() {
            return Err(RunError::Curve(
                "the critical curve needs the stability analysis by blocks, which this \
                 scene's group does not allow"
                    .into(),
            ));
        }
        if analysis.from_run.is_some() {
            let Some(cp) = cx.from.clone() else {
                return Err(RunError::Curve(
                    "analysis.from-run is set but no critical point of that run was given".into(),
                ));
            };
            // The run's point is this run's one path row and critical point.
            let record = &mut cx.record;
            record.row(study, 0, 0.0, &cp.state, cp.parameters.clone(), 0, None);
            record.state(0, StateKind::Step, cp.state.clone(), &cp.parameters);
            record.add_critical(cp.clone());
            cx.times.path = t0.elapsed();
            let curve = self.follow(study, &mut cx.crossings, &cp, &mut *cx.observer)?;
            cx.record.outcome = Some(Outcome::new(curve));
            return Ok(StopReason::CriticalPoint);
        }
        // The path in the control up to the point.
        let located = self.locate(study, &mut cx.crossings, &cx.start, &mut *cx.observer)?;
        cx.times.steps = located.branch.times;
        cx.times.index = located.index_time;
        record_branch(
            study,
            &mut cx.record,
            &*located.problem,
            &located.branch,
            &located.indices,
            usize::MAX,
        );
        cx.times.path = t0.elapsed();
        // A signal in the path phase: the path so far is the result (no curve).
        if located.branch.stop == StopReason::Interrupted {
            return Ok(StopReason::Interrupted);
        }
        let cp = located.point(&analysis.control, &analysis.from)?;
        let stop = located.branch.stop.clone();
        let curve = self.follow(study, &mut cx.crossings, &cp, &mut *cx.observer)?;
        cx.record.outcome = Some(Outcome::new(curve));
        Ok(stop)
    }
}

/// The path in the control from a start state up to the critical point a curve starts from.
pub(super) struct Located<'s> {
    /// The path.
    pub branch: Branch,
    /// Its problem (the path's coordinates).
    pub problem: Box<dyn Followed + 's>,
    /// The index at every point of the path.
    pub indices: Vec<Option<usize>>,
    /// The time spent on the index.
    pub index_time: std::time::Duration,
}

impl Located<'_> {
    /// The critical point the path stopped at, or an error saying what it found instead.
    pub fn point(&self, control: &str, from: &CurveStart) -> Result<CriticalPoint, RunError> {
        match self.branch.stop {
            // The first point `from` asks for: one step may cross several blocks at once
            // (a pair split by the mesh), and the one asked for need not be the last.
            StopReason::CriticalPoint => self
                .branch
                .critical_points()
                .enumerate()
                .find(|(seen, cp)| asks_for(from, cp, *seen))
                .map(|(_, cp)| cp.clone()),
            _ => None,
        }
        .ok_or_else(|| {
            RunError::Curve(format!(
                "the path in '{control}' found no {} (analysis.from) in {} steps: {}",
                describe(from),
                self.branch.points.len() - 1,
                self.branch.stop
            ))
        })
    }
}

impl Curve {
    /// The path in the control from `start` (the second parameter held) up to the critical
    /// point `from`, with the index by blocks at every point (`crossings`, taken and put
    /// back; it must be there).
    pub(super) fn locate<'s>(
        &self,
        study: &'s dyn Study,
        crossings: &mut Option<Crossings<'_>>,
        start: &crate::study::Point,
        observer: &mut dyn Observer,
    ) -> Result<Located<'s>, RunError> {
        let opts = self.options(study);
        let max_steps = opts.max_steps;
        let mut driver = start_driver(study, start, opts)?;
        let mut first = FirstCritical {
            index: IndexChanges::new(crossings.take().expect("the index by blocks")),
            from: self.0.from.clone(),
            seen: 0,
        };
        let mut count = 0usize;
        let branch = {
            let mut extra: Vec<&mut dyn Detector<Box<dyn Followed>>> = vec![&mut first];
            trace(
                &mut driver,
                max_steps,
                |_, _| None,
                &mut extra,
                |problem, p| {
                    observer.progress(count, p.lambda[0]);
                    observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                    count += 1;
                },
            )
        };
        let index_time = first.index.index_time;
        let indices = first.index.indices.clone();
        *crossings = Some(first.index.into_crossings());
        Ok(Located {
            branch,
            problem: driver.into_problem(),
            indices,
            index_time,
        })
    }

    /// Follows the critical point `cp` in (control, second), with the index by blocks
    /// (`crossings`, taken and put back; it must be there).
    pub(super) fn follow(
        &self,
        study: &dyn Study,
        crossings: &mut Option<Crossings<'_>>,
        cp: &CriticalPoint,
        observer: &mut dyn Observer,
    ) -> Result<CurveReport, RunError> {
        let analysis = &self.0;
        let index = |name: &str| {
            study
                .about()
                .parameters
                .iter()
                .position(|p| p == name)
                .expect("validated parameter")
        };
        let (control, second) = (index(&analysis.control), index(&analysis.second));
        let mu = crossings
            .as_ref()
            .and_then(|c| c.block(&cp.irrep))
            .expect("the critical point's block is one of the study's");
        let test = study.critical_test(cp).map_err(RunError::Curve)?;
        let inner = study.problem(
            &cp.parameters,
            &Free {
                control: Some(second),
                constraints: true,
                also: vec![control],
                hold_neutral: false,
            },
        );
        let free = inner.free_indices();
        let lambda0 = inner.free_values(&cp.parameters);
        let q0 = inner.coordinates(&cp.state);
        let second_handle = study.parameter(second);
        let opts = PathOptions::new(
            &self.settings(),
            second_handle.bounds(),
            study.state_scale(),
            free.len(),
        );
        let last = free.len() - 1;
        let problem = CurveProblem::new(inner, test, free);
        let mut driver = Continuation::start(problem, &q0, &lambda0, opts).map_err(|e| {
            RunError::Curve(format!(
                "the critical point did not converge as the first point of the curve: {e}"
            ))
        })?;
        let control_bounds = study.parameter(control).bounds();
        // `trace` watches the turning points of λ_0, the second parameter: cusps and folds.
        let mut refresh = RefreshBorder;
        let mut others = OtherBlocks {
            crossings: crossings.take().expect("the index by blocks"),
            own: mu,
            previous: None,
        };
        let mut count = 0usize;
        let branch = {
            let mut extra: Vec<&mut dyn Detector<CurveProblem>> = vec![&mut refresh];
            if analysis.watch {
                extra.push(&mut others);
            }
            trace(
                &mut driver,
                analysis.settings.steps,
                |_, p: &PathPoint| {
                    let c = p.lambda[last];
                    (c < control_bounds.0 || c > control_bounds.1).then_some(StopReason::Bounds)
                },
                &mut extra,
                |problem: &CurveProblem, p| {
                    observer.progress(count, p.lambda[0]);
                    observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                    count += 1;
                },
            )
        };
        let crossings = crossings.insert(others.crossings);
        let mut problem = driver.into_problem();
        let mut report = CurveReport {
            control: analysis.control.clone(),
            second: analysis.second.clone(),
            irrep: cp.irrep.clone(),
            kind: cp.kind,
            multiplicity: cp.multiplicity,
            parameters: study.about().parameters.clone(),
            measures: study.about().measures.clone(),
            rows: Vec::new(),
            events: Vec::new(),
            stop: branch.stop.clone(),
            warnings: branch
                .events
                .iter()
                .filter_map(|e| match e {
                    Event::Warning(w) => Some(w.clone()),
                    _ => None,
                })
                .collect(),
        };
        if let (StopReason::Stalled(_), [.., before, last]) = (&branch.stop, &branch.points[..]) {
            // A stall where the model is only piecewise smooth: ahead of the last point, along
            // the last step, the switches (nodes in contact) change within one longest step.
            // K jumps there and σ with it (its derivatives, by differences over states a
            // small step apart, already see the jump before it), so σ = 0 may have no
            // solution past it: the curve continues pinned to the switch (docs/theory.md
            // §11.13), which this follower does not follow. Probed at doubling distances.
            let length = last.arclength - before.arclength;
            let max_step = self.settings().max_step;
            let at = |t: f64| {
                let ahead = |x: &DVector<f64>, y: &DVector<f64>| y + (y - x) * (t / length);
                (
                    problem.displacement(&ahead(&before.q, &last.q)),
                    problem.parameters(&ahead(&before.lambda, &last.lambda)),
                )
            };
            let (u0, p0) = at(0.0);
            let probes = std::iter::successors(Some(length), |t| Some(2.0 * t))
                .take_while(|&t| length > 0.0 && t <= max_step);
            let change = probes.into_iter().find_map(|t| {
                let (u1, p1) = at(t);
                crossings
                    .switched((&u0, &p0), (&u1, &p1))
                    .filter(|&n| n > 0)
                    .map(|n| (n, t))
            });
            if let Some((n, t)) = change {
                report.warnings.push(format!(
                    "the curve stalls where the tangent jumps: {n} of the model's switches \
                     (nodes in contact) change within {t:.1e} ahead of point {} along the \
                     curve; its test function jumps there, and the critical curve may \
                     continue pinned to that change, which σ = 0 does not follow \
                     (docs/theory.md §11.13)",
                    branch.points.len() - 1
                ));
            }
        }
        for (i, p) in branch.points.iter().enumerate() {
            let u = problem.displacement(&p.q);
            let params = problem.parameters(&p.lambda);
            let test = problem.test_mut();
            let (critical, second_eigenvalue) = test
                .rescale(&u, &params)
                .and_then(|()| test.block_tangent(&u, &params))
                .map(|(k, scale)| nearest_eigenvalues(&k, scale))
                .unwrap_or((f64::NAN, f64::NAN));
            report.rows.push(CurveRow {
                step: i,
                arclength: p.arclength,
                measures: study.measure(&u, &params),
                parameters: params,
                iterations: p.iterations,
                critical_eigenvalue: critical,
                second_eigenvalue,
            });
        }
        let event = |kind, extremum, after_step: usize, point: &PathPoint| {
            let u = problem.displacement(&point.q);
            let params = problem.parameters(&point.lambda);
            CurveEvent {
                kind,
                extremum,
                irrep: None,
                m: None,
                residual_eigenvalue: None,
                after_step,
                arclength: point.arclength,
                measures: study.measure(&u, &params),
                flags: study.state_flags(&u, &params),
                parameters: params,
            }
        };
        report
            .events
            .push(event(CurveEventKind::Start, None, 0, &branch.points[0]));
        for t in branch.turning_points() {
            let kind = if mu == 0 {
                CurveEventKind::Cusp
            } else {
                CurveEventKind::Fold
            };
            report
                .events
                .push(event(kind, Some(t.kind), t.after_step, &t.point));
        }
        for other in branch.critical_points() {
            // The other block singular together with the curve's.
            let nu = crossings
                .block(&other.irrep)
                .expect("the crossing's block is one of the study's");
            let kind = crossing_kind(mu, nu);
            let mut flags = study.state_flags(&other.state, &other.parameters);
            if other.residual_eigenvalue > crate::results::validity::LOCALISED {
                flags.push(crate::results::validity::Flag::NotLocalised {
                    residual: other.residual_eigenvalue,
                    bracket: other.bracket.as_ref().map(|b| b.width),
                });
            }
            report.events.push(CurveEvent {
                flags,
                kind,
                extremum: None,
                irrep: Some(other.irrep.clone()),
                m: study.wave_number(other),
                residual_eigenvalue: Some(other.residual_eigenvalue),
                after_step: other.after_step,
                arclength: branch.points[other.after_step].arclength,
                parameters: other.parameters.clone(),
                measures: other.measures.clone(),
            });
        }
        // In curve order (stable: a turning point and a crossing in one step keep their order).
        report.events[1..].sort_by_key(|e| e.after_step);
        let n = branch.points.len() - 1;
        report
            .events
            .push(event(CurveEventKind::End, None, n, &branch.points[n]));
        Ok(report)
    }
}

/// The eigenvalue of the symmetric `k` nearest zero and the next nearest, relative to
/// `scale`.
fn nearest_eigenvalues(k: &DMatrix<f64>, scale: f64) -> (f64, f64) {
    let n = k.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (k[(i, j)] + k[(j, i)]));
    let Ok(mut values) = m.self_adjoint_eigenvalues(faer::Side::Lower) else {
        return (f64::NAN, f64::NAN);
    };
    values.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    let at = |i: usize| values.get(i).map_or(f64::NAN, |v| v / scale);
    (at(0), at(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The events a curve's watch reports along a constructed sequence of negative counts
    /// (blocks A1, A2, E1, E2): on the E1 curve a change of E2 is a change of the critical
    /// irrep, a change of A1 a hilltop, and E1's own count never an event; on the limit curve
    /// (A1) every other block's change is a hilltop.
    #[test]
    fn the_watch_names_irrep_changes_and_hilltops_along_a_sequence() {
        let names = ["A1", "A2", "E1", "E2"];
        let sequence: [[usize; 4]; 5] = [
            [0, 0, 0, 0],
            [0, 0, 1, 0], // E1's own count: noise on its own curve
            [0, 0, 0, 1], // E2 becomes unstable: the E1 and E2 curves cross
            [1, 0, 1, 1], // A1: the E1 curve meets the limit curve
            [1, 1, 0, 1], // A2
        ];
        let events = |own: usize| -> Vec<(usize, &str, CurveEventKind)> {
            sequence
                .windows(2)
                .enumerate()
                .flat_map(|(step, w)| {
                    changed_blocks(own, &w[0], &w[1])
                        .into_iter()
                        .map(move |nu| (step, names[nu], crossing_kind(own, nu)))
                })
                .collect()
        };
        assert_eq!(
            events(2),
            vec![
                (1, "E2", CurveEventKind::IrrepChange),
                (2, "A1", CurveEventKind::Hilltop),
                (3, "A2", CurveEventKind::IrrepChange),
            ]
        );
        assert_eq!(
            events(0),
            vec![
                (0, "E1", CurveEventKind::Hilltop),
                (1, "E1", CurveEventKind::Hilltop),
                (1, "E2", CurveEventKind::Hilltop),
                (2, "E1", CurveEventKind::Hilltop),
                (3, "A2", CurveEventKind::Hilltop),
                (3, "E1", CurveEventKind::Hilltop),
            ]
        );
    }
}
