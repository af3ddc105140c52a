//! A run's critical and turning points on refined meshes (`memstab run --refine`,
//! docs/theory.md §8.11): the scene runs again with the mesh's resolution doubled (once, or
//! twice), every point of the run is matched to its counterparts there as [`super::compare`]
//! matches a rung's images (by irrep or wave number, the piece of the path and value), and
//! gets its value on every level, the observed order, the Richardson value and an error
//! estimate per level. A point with no counterpart on a refined mesh is not mesh-converged
//! ([`crate::results::validity::Flag::NotMeshConverged`]). With `continuum` the scene also
//! runs on its meridian, as `compare` runs `axisymmetric`, and every point gets the
//! meridian's value and its distance from it. On a critical curve its events (cusps, folds,
//! hilltops, irrep changes) are followed the same way, each kind on its own, both
//! coordinates estimated ([`refine_events`]).

use super::matching::{match_rungs, measure_distances, Rung};
use super::meshes::{describe, resolution, variant, Common};
use super::Point;
use super::{
    floor_of, labelled, parse_meshes, point_of, range_of, refine_mesh, turning_of, CompareError,
    Job, Level, MeshRuns,
};
use crate::results::refine::{
    ContinuumRun, ContinuumValue, Estimate, EventContinuum, EventRefinement, FailedRun, NewPoint,
    PointRefinement, RefinedLevel, Refinement, Series, ASSUMED_ORDER, MERIDIAN_ORDER,
    ORDER_TOLERANCE,
};
use crate::results::{
    CriticalKind, CurveEventKind, CurveReport, Extremum, Outcome, RunResult, StopReason,
};
use crate::scene::{MeshSpec, Scene};
use crate::study::meridian::MeridianStudy;
use crate::study::mesh::MeshStudy;
use crate::text::one_line;

/// What `run --refine` (or the scene's `[refine]`) asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RefineOptions {
    /// Refinements: 1 (the resolution doubled) or 2 (doubled and quadrupled).
    pub levels: usize,
    /// Also run the scene's meridian.
    pub continuum: bool,
    /// Whether the scene's `[refine]` asked for it (messages then name its keys), not the
    /// command line.
    pub from_scene: bool,
}

impl RefineOptions {
    /// What a run of `scene` refines: the command line's `--refine N` (`levels`, with
    /// `--continuum` as `continuum`) overrides the scene's `[refine]`; without it the scene's
    /// section, `--continuum` adding the meridian to it. `None`: no refinement. A
    /// `--continuum` without either is bad input, in one line.
    pub fn resolve(
        levels: Option<usize>,
        continuum: bool,
        scene: &Scene,
    ) -> Result<Option<Self>, CompareError> {
        match (levels, scene.refine) {
            (Some(levels), _) => Ok(Some(Self {
                levels,
                continuum,
                from_scene: false,
            })),
            (None, Some(r)) => Ok(Some(Self {
                levels: r.levels,
                continuum: r.continuum || continuum,
                from_scene: true,
            })),
            (None, None) if continuum => Err(CompareError::Input(
                "--continuum: needs --refine or the scene's [refine]".into(),
            )),
            (None, None) => Ok(None),
        }
    }

    /// The option that asked for the refinement, with its value, as messages name it.
    fn named(&self, scene: &Scene) -> String {
        if self.from_scene {
            format!("{}: 'refine.levels' = {}", scene.origin, self.levels)
        } else {
            format!("--refine {}", self.levels)
        }
    }

    /// The option that asked for the meridian, as messages name it.
    fn continuum_named(&self, scene: &Scene) -> String {
        if self.from_scene && scene.refine.is_some_and(|r| r.continuum) {
            format!("{}: 'refine.continuum' = true", scene.origin)
        } else {
            "--continuum".into()
        }
    }
}

/// The refined runs of a scene, built (and checked) before its own run.
pub struct Refiner {
    control: String,
    base_mesh: String,
    base_resolution: usize,
    meridian: bool,
    label_modes: bool,
    floor: f64,
    levels: Vec<Job>,
    continuum: Option<(Job, Job)>,
}

impl std::fmt::Debug for Refiner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Refiner")
            .field("base_mesh", &self.base_mesh)
            .field("levels", &self.levels.len())
            .field("continuum", &self.continuum.is_some())
            .finish()
    }
}

/// A 3-D study or a meridian of `scene`; what cannot be built is bad input, named by `what`.
fn job(scene: Scene, what: &str) -> Result<Job, CompareError> {
    let bad = |e: String| CompareError::Input(one_line(&format!("{what}: {e}")));
    if let MeshSpec::Axisymmetric(_) = scene.mesh {
        Ok(Job::Meridian(Box::new(
            MeridianStudy::build(scene).map_err(|e| bad(e.to_string()))?,
        )))
    } else {
        Ok(Job::Solid(Box::new(
            MeshStudy::build(scene).map_err(|e| bad(e.to_string()))?,
        )))
    }
}

impl Refiner {
    /// Builds the refined scenes' studies (and, with `continuum`, the meridian's at N and 2N
    /// elements). Bad input, naming the option and its value: `levels` not 1 or 2, a scene
    /// without a control, a mesh file, a saved or restarted start (whose state does not fit
    /// another mesh), a scene without an axisymmetric counterpart, a refined mesh over a limit.
    pub fn new(scene: &Scene, options: &RefineOptions) -> Result<Self, CompareError> {
        let flag = options.named(scene);
        let input = |what: String| CompareError::Input(format!("{flag}: {what}"));
        if !(1..=2).contains(&options.levels) {
            return Err(input(
                "must be 1 (the mesh at twice the divisions) or 2 (at twice and four times)".into(),
            ));
        }
        let Some(control) = scene.control().map(str::to_string) else {
            return Err(input(format!(
                "a {} analysis has no control to follow critical points in",
                scene.analysis.kind()
            )));
        };
        if let MeshSpec::File(f) = &scene.mesh {
            return Err(input(format!(
                "the scene's mesh is the file '{}', which cannot be refined; only a generated \
                 mesh can (docs/scenes.md)",
                f.path.display()
            )));
        }
        if scene.start.from.is_some() {
            return Err(input(
                "the scene starts from a saved state ([start] from), which does not fit a \
                 refined mesh; remove [start] from"
                    .into(),
            ));
        }
        if super::super::analysis_of(&scene.analysis)
            .restarts_from()
            .is_some()
        {
            return Err(input(
                "the scene's analysis starts from a finished run's critical point (from-run), \
                 whose state does not fit a refined mesh"
                    .into(),
            ));
        }
        let mut levels = Vec::new();
        for l in 1..=options.levels {
            let mut s = scene.clone();
            refine_mesh(&mut s.mesh, 1 << l);
            let what = format!("{flag}: mesh '{}'", describe(&s.mesh));
            levels.push(job(s, &what)?);
        }
        let continuum = if options.continuum {
            if let MeshSpec::Axisymmetric(_) = scene.mesh {
                return Err(CompareError::Input(format!(
                    "{}: the scene is on a meridian already; it is its own axisymmetric \
                     counterpart",
                    options.continuum_named(scene)
                )));
            }
            let choice = parse_meshes(&["axisymmetric".into()])?;
            let common = Common {
                control: control.clone(),
                max: None,
                samples: None,
                divisions: None,
                sectors: 0,
            };
            let named = options.continuum_named(scene);
            let coarse = variant(scene, &choice[0], &common).map_err(|e| {
                CompareError::Input(format!(
                    "{named}: the scene has no axisymmetric counterpart: {e}"
                ))
            })?;
            let mut fine = coarse.clone();
            refine_mesh(&mut fine.mesh, 2);
            let what = format!("{named}: the scene's meridian");
            Some((job(coarse, &what)?, job(fine, &what)?))
        } else {
            None
        };
        Ok(Refiner {
            floor: floor_of(range_of(scene, &control)),
            control,
            base_mesh: describe(&scene.mesh),
            base_resolution: resolution(&scene.mesh),
            meridian: matches!(scene.mesh, MeshSpec::Axisymmetric(_)),
            label_modes: labelled(scene),
            levels,
            continuum,
        })
    }

    /// Runs the refined meshes one after the other (so that each wall time is its own), and
    /// the meridian with `continuum`, and follows the points of `base`, the scene's own run
    /// that took `seconds`, through them. `progress` hears of each run as it ends. `None`
    /// when a signal interrupted a run: its points would be missing for that reason alone.
    pub fn run(
        self,
        result: &RunResult,
        seconds: f64,
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<Option<Refinement>, CompareError> {
        let base = &result.report;
        let interrupted = crate::continuation::interrupt::requested;
        let control = base.parameters.iter().position(|p| *p == base.control);
        let critical = (0..base.critical.len())
            .map(|k| {
                let m = base.wave_numbers.get(k).copied();
                let irrep = match (self.meridian, m) {
                    (true, Some(m)) => format!("m={m}"),
                    _ => base.critical[k].irrep.clone(),
                };
                point_of(
                    base,
                    control,
                    k,
                    irrep,
                    m.filter(|_| self.label_modes),
                    None,
                )
            })
            .collect();
        let own = Level {
            mesh: self.base_mesh.clone(),
            resolution: self.base_resolution,
            nodes: base.mesh.nodes,
            triangles: base.mesh.elements,
            group: base.group.clone(),
            order: base.group_order,
            unknowns: base.unknowns,
            symmetric_unknowns: base.symmetric_unknowns,
            stop: base.stop.clone(),
            note: base.stability_note.clone(),
            warnings: Vec::new(),
            seconds,
            critical,
            flagged: Vec::new(),
            turning: turning_of(base, control),
            events: events_of(result),
            pieces: Vec::new(),
        };
        let mut levels = vec![own];
        let mut failed: Vec<FailedRun> = Vec::new();
        for (l, job) in self.levels.into_iter().enumerate() {
            let run = format!("level {}", l + 1);
            let mesh = job.mesh();
            if !failed.is_empty() {
                failed.push(FailedRun {
                    run,
                    mesh,
                    reason: format!("not run: {} failed", failed[0].run),
                });
                continue;
            }
            let label = format!("refinement {}", l + 1);
            match execute_or_fail(job, &label, self.label_modes, progress)? {
                Ok(level) => levels.push(level),
                Err(reason) => failed.push(FailedRun { run, mesh, reason }),
            }
            if interrupted() {
                return Ok(None);
            }
        }
        let continuum = match self.continuum {
            Some((coarse, fine)) => {
                let mesh = coarse.mesh();
                let coarse = execute_or_fail(coarse, "meridian", self.label_modes, progress)?;
                let fine = execute_or_fail(fine, "meridian check", self.label_modes, progress)?;
                if interrupted() {
                    return Ok(None);
                }
                match (coarse, fine) {
                    (Ok(coarse), Ok(fine)) => Some((coarse, fine)),
                    (Err(reason), _) | (_, Err(reason)) => {
                        failed.push(FailedRun {
                            run: "continuum".into(),
                            mesh,
                            reason,
                        });
                        None
                    }
                }
            }
            None => None,
        };
        let finer: Vec<String> = levels.iter().map(|l| l.mesh.clone()).collect();
        let order = if self.meridian {
            MERIDIAN_ORDER
        } else {
            ASSUMED_ORDER
        };
        // The critical points, with the meridian as a second mesh.
        let mut meshes = vec![MeshRuns {
            label: "run".into(),
            generator: String::new(),
            levels: levels.clone(),
            check: None,
        }];
        if let Some((coarse, fine)) = &continuum {
            meshes.push(MeshRuns {
                label: "axisymmetric".into(),
                generator: "axisymmetric".into(),
                levels: vec![coarse.clone()],
                check: Some(fine.clone()),
            });
        }
        let (mut rungs, _) = match_rungs(&meshes, self.floor);
        if continuum.is_some() {
            measure_distances(&meshes, &mut rungs, 1);
        }
        let base_resolution = self.base_resolution;
        let (own, new): (Vec<Rung>, Vec<Rung>) = rungs
            .into_iter()
            .partition(|r| r.found_at == base_resolution);
        let critical = own
            .iter()
            .map(|r| refined(r, false, &finer, order))
            .collect();
        let new_on_finer = new
            .iter()
            .map(|r| NewPoint {
                level: levels
                    .iter()
                    .position(|l| l.resolution == r.found_at)
                    .unwrap_or(0),
                irrep: r.irreps.join("+"),
                value: r.values.iter().sum::<f64>() / r.values.len().max(1) as f64,
                m: r.m,
            })
            .collect();
        // The turning points, on their own.

        let as_turning = |l: &Level| Level {
            critical: l.turning.clone(),
            ..l.clone()
        };
        let mut turning_runs = vec![MeshRuns {
            label: "run".into(),
            generator: String::new(),
            levels: levels.iter().map(as_turning).collect(),
            check: None,
        }];
        // The meridian's turning points, as its critical points are matched.
        if let Some((coarse, fine)) = &continuum {
            turning_runs.push(MeshRuns {
                label: "axisymmetric".into(),
                generator: "axisymmetric".into(),
                levels: vec![as_turning(coarse)],
                check: Some(as_turning(fine)),
            });
        }
        let (mut turning_rungs, _) = match_rungs(&turning_runs, self.floor);
        if continuum.is_some() {
            measure_distances(&turning_runs, &mut turning_rungs, 1);
        }
        let turning = turning_rungs
            .iter()
            .filter(|r| r.found_at == base_resolution)
            .map(|r| refined(r, true, &finer, order))
            .collect();
        // A critical curve's events, each kind on its own.
        let on_levels: Vec<(usize, Vec<EventPoint>)> = levels
            .iter()
            .map(|l| (l.resolution, l.events.clone()))
            .collect();
        let on_meridian = continuum.as_ref().map(|(c, f)| {
            (
                (c.resolution, c.events.clone()),
                (f.resolution, f.events.clone()),
            )
        });
        let events = refine_events(
            &on_levels,
            on_meridian.as_ref().map(|(c, f)| (c, f)),
            &finer,
            order,
            self.floor,
        );
        Ok(Some(Refinement {
            second: result.outcome::<CurveReport>().map(|c| c.second.clone()),
            events,
            control: self.control,
            assumed_order: order,
            order_tolerance: ORDER_TOLERANCE,
            levels: levels
                .iter()
                .map(|l| RefinedLevel {
                    mesh: l.mesh.clone(),
                    resolution: l.resolution,
                    nodes: l.nodes,
                    unknowns: l.unknowns,
                    seconds: l.seconds,
                    stop: l.stop.clone(),
                    critical: l.critical.len(),
                    turning: l.turning.len(),
                })
                .collect(),
            continuum: continuum.map(|(coarse, fine)| ContinuumRun {
                mesh: coarse.mesh.clone(),
                resolution: coarse.resolution,
                seconds: coarse.seconds + fine.seconds,
            }),
            critical,
            turning,
            new_on_finer,
            failed,
        }))
    }
}

/// Runs `job`: its level, or why it failed (the run's failure in one line, without the
/// label and mesh that [`FailedRun`] gives); bad input and a signal are errors.
fn execute_or_fail(
    job: Job,
    label: &str,
    label_modes: bool,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Result<Level, String>, CompareError> {
    let prefix = format!("mesh '{label}' ({}): ", job.mesh());
    // A refined level is one run of the scene's own mesh: no second pieces sought.
    match job.execute(label, (label_modes, false), progress) {
        Ok(level) => Ok(Ok(level)),
        Err(CompareError::Failure(m)) => {
            progress(&format!("{label}: failed"));
            Ok(Err(m.strip_prefix(&prefix).unwrap_or(&m).to_string()))
        }
        Err(e) => Err(e),
    }
}

/// A rung of the run's own level, followed through the levels (its images on the first
/// mesh), with its estimate; a turning point's kind is its irrep (`maximum`, `minimum`).
fn refined(rung: &Rung, turning: bool, finer: &[String], order: f64) -> PointRefinement {
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    let values: Vec<Option<f64>> = rung.images[0]
        .levels
        .iter()
        .map(|l| mean(&l.values))
        .collect();
    let points = rung.images[0].levels[0]
        .points
        .iter()
        .map(|i| i + 1)
        .collect();
    let series = series(values, finer, order);
    PointRefinement {
        points,
        kind: if turning {
            rung.irreps.first().cloned().unwrap_or_default()
        } else {
            rung.kind.to_string()
        },
        irreps: if turning {
            Vec::new()
        } else {
            rung.irreps.clone()
        },
        m: rung.m,
        distances: match rung.continuum {
            Some(c) => series.values.iter().map(|v| v.map(|v| v - c)).collect(),
            None => Vec::new(),
        },
        series,
        continuum: rung.continuum,
        continuum_error: rung.continuum_error,
    }
}

/// Values on levels of halved h with their estimate ([`estimate`]).
fn series(values: Vec<Option<f64>>, finer: &[String], order: f64) -> Series {
    let (observed_order, richardson, errors, estimate) = estimate(&values, finer, order);
    Series {
        values,
        observed_order,
        richardson,
        errors,
        estimate,
    }
}

/// An event of a critical curve on one level, as `run --refine` follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct EventPoint {
    /// Its number among the curve's events, from 1 (the start).
    pub number: usize,
    /// Its kind.
    pub kind: CurveEventKind,
    /// A cusp's or fold's extremum of the second parameter.
    pub extremum: Option<Extremum>,
    /// A hilltop's or an irrep change's other irrep.
    pub irrep: Option<String>,
    /// That irrep's wave number about z, where the model has an axis.
    pub m: Option<usize>,
    /// The control's value there.
    pub control: f64,
    /// The second parameter's value there.
    pub second: f64,
}

impl EventPoint {
    /// What its images on other levels and on the meridian share with it: the kind, the
    /// extremum, the other irrep's wave number where the model has an axis (the meridian's
    /// blocks are named by it, the mesh's by their irreps), else its name.
    fn key(&self) -> String {
        let other = match (self.m, &self.irrep) {
            (Some(m), Some(_)) => format!("m={m}"),
            (_, irrep) => irrep.clone().unwrap_or_default(),
        };
        format!(
            "{} {} {other}",
            self.kind,
            self.extremum.map_or_else(String::new, |x| x.to_string()),
        )
    }
}

/// One level's resolution and its curve's events.
pub type EventLevel = (usize, Vec<EventPoint>);

/// The events of a run's critical curve (none for another analysis), but its start and end.
pub(super) fn events_of(result: &RunResult) -> Vec<EventPoint> {
    let Some(curve) = result.outcome::<CurveReport>() else {
        return Vec::new();
    };
    let column = |name: &str| curve.parameters.iter().position(|p| p == name);
    let (Some(c), Some(s)) = (column(&curve.control), column(&curve.second)) else {
        return Vec::new();
    };
    curve
        .events
        .iter()
        .enumerate()
        .filter(|(_, e)| !matches!(e.kind, CurveEventKind::Start | CurveEventKind::End))
        .map(|(k, e)| EventPoint {
            number: k + 1,
            kind: e.kind,
            extremum: e.extremum,
            irrep: e.irrep.clone(),
            m: e.m,
            control: e.parameters[c],
            second: e.parameters[s],
        })
        .collect()
}

/// The events of the first level followed through the others (each level's resolution and
/// events, the first level the run's own): the events of one kind (with one extremum or
/// other irrep) are matched as critical points are, by the control's value
/// ([`match_rungs`]); each gets both coordinates on every level with their estimates, and an
/// event without a counterpart on a refined level is not mesh-converged. With `continuum`
/// (the meridian's events at N and 2N elements) each event's counterpart there is matched
/// the same way, as a second mesh ([`measure_distances`]), and gives both coordinates'
/// continuum values, their own errors and each level's distances. In the first level's
/// order.
pub fn refine_events(
    levels: &[EventLevel],
    continuum: Option<(&EventLevel, &EventLevel)>,
    finer: &[String],
    order: f64,
    floor: f64,
) -> Vec<EventRefinement> {
    let Some((base_resolution, base)) = levels.first() else {
        return Vec::new();
    };
    let mut keys: Vec<String> = Vec::new();
    for key in base.iter().map(EventPoint::key) {
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    let mut out = Vec::new();
    for key in &keys {
        let of_key: Vec<Vec<&EventPoint>> = levels
            .iter()
            .map(|(_, events)| events.iter().filter(|e| e.key() == *key).collect())
            .collect();
        let mut runs = vec![MeshRuns {
            label: "run".into(),
            generator: String::new(),
            levels: levels
                .iter()
                .zip(&of_key)
                .map(|((resolution, _), events)| bare(*resolution, events))
                .collect(),
            check: None,
        }];
        let meridian = continuum.map(|(coarse, fine)| (of_kind(coarse, key), of_kind(fine, key)));
        if let Some(((coarse, _), (fine, _))) = &meridian {
            runs.push(MeshRuns {
                label: "axisymmetric".into(),
                generator: "axisymmetric".into(),
                levels: vec![coarse.clone()],
                check: Some(fine.clone()),
            });
        }
        let (mut rungs, _) = match_rungs(&runs, floor);
        if meridian.is_some() {
            measure_distances(&runs, &mut rungs, 1);
        }
        for rung in rungs.iter().filter(|r| r.found_at == *base_resolution) {
            let images = &rung.images[0].levels;
            let at = |l: usize| images[l].points.first().map(|&i| of_key[l][i]);
            let Some(event) = at(0) else { continue };
            let along = |f: fn(&EventPoint) -> f64| {
                (0..images.len()).map(|l| at(l).map(f)).collect::<Vec<_>>()
            };
            let continuum = meridian.as_ref().and_then(|((_, coarse), (_, fine))| {
                let on = rung.images[1].levels[0]
                    .points
                    .first()
                    .map(|&i| coarse[i])?;
                // Its image at 2N elements: the nearest of its kind in the control.
                let check = fine.iter().min_by(|a, b| {
                    (a.control - on.control)
                        .abs()
                        .total_cmp(&(b.control - on.control).abs())
                });
                let value = |f: fn(&EventPoint) -> f64| ContinuumValue {
                    value: f(on),
                    error: check.map(|c| (f(c) - f(on)).abs()),
                    distances: along(f).iter().map(|v| v.map(|v| v - f(on))).collect(),
                };
                Some(EventContinuum {
                    control: value(|e| e.control),
                    second: value(|e| e.second),
                })
            });
            out.push(EventRefinement {
                event: event.number,
                kind: event.kind.to_string(),
                extremum: event.extremum,
                irrep: event.irrep.clone(),
                m: event.m,
                control: series(along(|e| e.control), finer, order),
                second: series(along(|e| e.second), finer, order),
                continuum,
            });
        }
    }
    out.sort_by_key(|e| e.event);
    out
}

/// The events of the kind `key` on one level (its resolution and events), and that level
/// holding them ([`bare`]).
fn of_kind<'a>((resolution, events): &'a EventLevel, key: &str) -> (Level, Vec<&'a EventPoint>) {
    let events: Vec<&EventPoint> = events.iter().filter(|e| e.key() == key).collect();
    (bare(*resolution, &events), events)
}

/// A level that holds `events` as its critical points (limit points, met as the control
/// rises, unlabelled: matched by the control's value alone) and nothing else.
fn bare(resolution: usize, events: &[&EventPoint]) -> Level {
    Level {
        mesh: String::new(),
        resolution,
        nodes: 0,
        triangles: 0,
        group: String::new(),
        order: 1,
        unknowns: 0,
        symmetric_unknowns: 0,
        stop: StopReason::Condition,
        note: None,
        warnings: Vec::new(),
        seconds: 0.0,
        critical: events
            .iter()
            .map(|e| Point {
                kind: CriticalKind::LimitPoint,
                irrep: e.key(),
                multiplicity: 1,
                value: e.control,
                m: None,
                residual_eigenvalue: 0.0,
                precision: None,
                isotropy: String::new(),
                rising: true,
                flags: Vec::new(),
                piece: None,
            })
            .collect(),
        flagged: Vec::new(),
        turning: Vec::new(),
        events: Vec::new(),
        pieces: Vec::new(),
    }
}

/// Puts `refinement` into `result`'s report, and the flags it raises on a critical curve's
/// events (`not-mesh-converged`) on them.
pub fn attach(result: &mut RunResult, refinement: Refinement) {
    if let Some(curve) = result.outcome::<CurveReport>() {
        let mut curve = curve.clone();
        curve.flag_refined(&refinement);
        result.outcome = Some(Outcome::new(curve));
    }
    result.report.refinement = Some(refinement);
}

/// The observed order of three values on meshes halved each time: log2(|v₀ − v₁| / |v₁ − v₂|),
/// `None` when a difference is zero or not finite.
pub fn observed_order(v0: f64, v1: f64, v2: f64) -> Option<f64> {
    let (a, b) = ((v0 - v1).abs(), (v1 - v2).abs());
    let p = (a / b).log2();
    (a > 0.0 && b > 0.0 && p.is_finite()).then_some(p)
}

/// Richardson extrapolation of the values on a mesh and on the mesh with h halved, assuming
/// order `order`: v_f + (v_f − v_c) / (2^order − 1).
pub fn richardson(coarse: f64, fine: f64, order: f64) -> f64 {
    fine + (fine - coarse) / (2f64.powf(order) - 1.0)
}

/// The estimate of values on levels of halved h (the first level's value present), assuming
/// the order `assumed`: the observed order with three levels, the Richardson value and each
/// level's error, unless a refined level has no value (`finer` names each level's mesh) or
/// the observed order is more than [`ORDER_TOLERANCE`] from `assumed`.
pub fn estimate(
    values: &[Option<f64>],
    finer: &[String],
    assumed: f64,
) -> (Option<f64>, Option<f64>, Vec<Option<f64>>, Estimate) {
    let none = vec![None; values.len()];
    if values.len() < 2 {
        return (None, None, none, Estimate::NotRefined);
    }
    if let Some(l) = values.iter().position(Option::is_none) {
        let finer = finer.get(l).cloned().unwrap_or_default();
        return (None, None, none, Estimate::NotMeshConverged { finer });
    }
    let v: Vec<f64> = values.iter().map(|v| v.unwrap_or(f64::NAN)).collect();
    if v.windows(2).all(|w| w[0] == w[1]) {
        return (
            None,
            Some(v[0]),
            vec![Some(0.0); v.len()],
            Estimate::Unchanged,
        );
    }
    let order = match v.as_slice() {
        [.., a, b, c] => Some(observed_order(*a, *b, *c)),
        _ => None,
    };
    // Three levels must agree in sign of the change and in order with the assumed one.
    let asymptotic = match (order, v.as_slice()) {
        (None, _) => true,
        (Some(Some(p)), [.., a, b, c]) => {
            (a - b) * (b - c) > 0.0 && (p - assumed).abs() <= ORDER_TOLERANCE
        }
        (Some(_), _) => false,
    };
    let observed = order.flatten();
    if !asymptotic {
        return (
            observed,
            None,
            none,
            Estimate::NotAsymptotic { order: observed },
        );
    }
    let n = v.len();
    let r = richardson(v[n - 2], v[n - 1], assumed);
    let errors = v.iter().map(|x| Some((x - r).abs())).collect();
    (
        observed,
        Some(r),
        errors,
        Estimate::Richardson {
            observed: order.is_some(),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::validity::Flag;

    #[test]
    fn second_order_values_are_extrapolated_and_their_errors_estimated() {
        // v(h) = 1 + h² at h = 1, 1/2, 1/4.
        let values = [Some(2.0), Some(1.25), Some(1.0625)];
        let (order, r, errors, basis) = estimate(&values, &[], 2.0);
        assert!((order.unwrap() - 2.0).abs() < 1e-12);
        assert!((r.unwrap() - 1.0).abs() < 1e-12);
        assert!((errors[0].unwrap() - 1.0).abs() < 1e-12);
        assert!((errors[2].unwrap() - 0.0625).abs() < 1e-12);
        assert_eq!(basis, Estimate::Richardson { observed: true });
        // Two levels: the order is assumed.
        let (order, r, _, basis) = estimate(&values[..2], &[], 2.0);
        assert_eq!(order, None);
        assert!((r.unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(basis, Estimate::Richardson { observed: false });
    }

    #[test]
    fn an_order_far_from_two_is_said_not_extrapolated() {
        // v(h) = 1 + h^0.7.
        let v = |h: f64| Some(1.0 + h.powf(0.7));
        let (order, r, errors, basis) = estimate(&[v(1.0), v(0.5), v(0.25)], &[], 2.0);
        assert!((order.unwrap() - 0.7).abs() < 1e-9);
        assert_eq!(r, None);
        assert!(errors.iter().all(Option::is_none));
        assert!(
            matches!(basis, Estimate::NotAsymptotic { order: Some(p) } if (p - 0.7).abs() < 1e-9)
        );
        // A fourth-order sequence is asymptotic for elements of that order only.
        let w = |h: f64| Some(1.0 + h.powi(4));
        let quartic = [w(1.0), w(0.5), w(0.25)];
        assert!(matches!(
            estimate(&quartic, &[], 2.0).3,
            Estimate::NotAsymptotic { .. }
        ));
        let (_, r, errors, basis) = estimate(&quartic, &[], 4.0);
        assert!((r.unwrap() - 1.0).abs() < 1e-12);
        assert!((errors[0].unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(basis, Estimate::Richardson { observed: true });
        // Changes of alternating sign are not in the asymptotic range either.
        let (_, r, _, basis) = estimate(&[Some(1.0), Some(1.4), Some(1.3)], &[], 2.0);
        assert_eq!(r, None);
        assert!(matches!(basis, Estimate::NotAsymptotic { .. }));
    }

    #[test]
    fn a_point_without_a_counterpart_is_not_mesh_converged() {
        let finer = ["a".to_string(), "b".to_string(), "c".to_string()];
        let (_, r, _, basis) = estimate(&[Some(1.0), Some(1.1), None], &finer, 2.0);
        assert_eq!(r, None);
        assert_eq!(basis, Estimate::NotMeshConverged { finer: "c".into() });
        let (_, _, _, basis) = estimate(&[Some(1.0), Some(1.0)], &finer, 2.0);
        assert_eq!(basis, Estimate::Unchanged);
    }

    fn event(
        number: usize,
        kind: CurveEventKind,
        irrep: Option<&str>,
        at: (f64, f64),
    ) -> EventPoint {
        EventPoint {
            number,
            kind,
            extremum: (kind == CurveEventKind::Cusp).then_some(Extremum::Maximum),
            irrep: irrep.map(str::to_string),
            m: None,
            control: at.0,
            second: at.1,
        }
    }

    /// On the meridian the blocks are named by their wave number: a hilltop with the mesh's
    /// E2 (m = 2) is the meridian's hilltop with m2, not the one with m3 beside it, and gets
    /// its coordinates there; a cusp is matched by its kind alone; an event the meridian does
    /// not have gets no continuum.
    #[test]
    fn a_curves_events_are_matched_on_the_meridian_by_wave_number() {
        use CurveEventKind::{Cusp, Hilltop};
        let with_m = |mut e: EventPoint, m| {
            e.m = Some(m);
            e
        };
        let mesh = vec![
            (
                8,
                vec![
                    event(2, Cusp, None, (1.5, 0.21)),
                    with_m(event(3, Hilltop, Some("E2"), (2.0, 0.3)), 2),
                    with_m(event(4, Hilltop, Some("E4"), (2.5, 0.3)), 4),
                ],
            ),
            (
                16,
                vec![
                    event(2, Cusp, None, (1.49, 0.2101)),
                    with_m(event(3, Hilltop, Some("E2"), (1.99, 0.3)), 2),
                    with_m(event(4, Hilltop, Some("E4"), (2.49, 0.3)), 4),
                ],
            ),
        ];
        let meridian = |shift: f64| {
            (
                64,
                vec![
                    event(2, Cusp, None, (1.48 + shift, 0.2102)),
                    with_m(event(3, Hilltop, Some("m3"), (1.985, 0.3)), 3),
                    with_m(event(4, Hilltop, Some("m2"), (1.98 + shift, 0.31)), 2),
                ],
            )
        };
        let (coarse, fine) = (meridian(0.0), meridian(1e-4));
        let finer = ["f8".to_string(), "f16".to_string()];
        let events = refine_events(&mesh, Some((&coarse, &fine)), &finer, 2.0, 1e-3);
        assert_eq!(events.len(), 3, "{events:?}");
        let cusp = events[0].continuum.as_ref().expect("the cusp's continuum");
        assert_eq!(cusp.control.value, 1.48);
        assert!((cusp.control.error.unwrap() - 1e-4).abs() < 1e-12);
        assert!((cusp.control.distances[1].unwrap() - 0.01).abs() < 1e-12);
        let hilltop = events[1].continuum.as_ref().expect("E2's continuum");
        assert_eq!((hilltop.control.value, hilltop.second.value), (1.98, 0.31));
        assert_eq!(events[1].m, Some(2));
        assert!(events[2].continuum.is_none(), "{:?}", events[2]);
    }

    /// A cusp whose coordinates converge at O(h²) on three levels is extrapolated in both; a
    /// hilltop whose finest level has only a hilltop with another irrep (and a cusp nearby)
    /// has no counterpart there: not mesh-converged, and its event flagged so in the curve.
    #[test]
    fn a_curves_events_are_followed_through_the_levels_by_kind() {
        use CurveEventKind::{Cusp, Hilltop};
        // Coordinates (1 + h²/10, 0.2 − h²/100) at h = 1, 1/2, 1/4.
        let cusp = |number, h: f64| {
            event(
                number,
                Cusp,
                None,
                (1.0 + h * h / 10.0, 0.2 - h * h / 100.0),
            )
        };
        let levels = vec![
            (
                4,
                vec![cusp(2, 1.0), event(3, Hilltop, Some("B1"), (3.0, 0.1))],
            ),
            (
                8,
                vec![event(2, Hilltop, Some("B1"), (3.01, 0.1)), cusp(3, 0.5)],
            ),
            (
                16,
                vec![cusp(2, 0.25), event(3, Hilltop, Some("B2"), (3.0, 0.1))],
            ),
        ];
        let finer = ["f4".to_string(), "f8".to_string(), "f16".to_string()];
        let events = refine_events(&levels, None, &finer, 2.0, 1e-3);
        assert_eq!(events.len(), 2, "{events:?}");
        let (c, h) = (&events[0], &events[1]);
        assert_eq!((c.event, c.kind.as_str()), (2, "cusp"));
        assert_eq!(c.extremum, Some(Extremum::Maximum));
        assert!((c.control.observed_order.unwrap() - 2.0).abs() < 1e-9);
        assert!((c.control.richardson.unwrap() - 1.0).abs() < 1e-12);
        assert!((c.second.richardson.unwrap() - 0.2).abs() < 1e-12);
        assert!((c.control.errors[0].unwrap() - 0.1).abs() < 1e-12);
        assert!((c.second.errors[2].unwrap() - 0.000625).abs() < 1e-12);
        assert_eq!((h.event, h.irrep.as_deref()), (3, Some("B1")));
        assert_eq!(h.control.values, [Some(3.0), Some(3.01), None]);
        assert_eq!(
            h.control.estimate,
            Estimate::NotMeshConverged {
                finer: "f16".into()
            }
        );
        assert!(!h.converged() && c.converged());
        // On the run's curve: the hilltop is flagged, the cusp is not.
        let curve_event = |kind, irrep: Option<&str>| crate::results::CurveEvent {
            kind,
            extremum: None,
            irrep: irrep.map(str::to_string),
            m: None,
            residual_eigenvalue: None,
            after_step: 0,
            arclength: 0.0,
            parameters: vec![0.0, 0.0],
            measures: Vec::new(),
            flags: Vec::new(),
        };
        let curve = CurveReport {
            control: "p".into(),
            second: "k".into(),
            irrep: "Ag".into(),
            kind: CriticalKind::LimitPoint,
            multiplicity: 1,
            parameters: vec!["k".into(), "p".into()],
            measures: Vec::new(),
            rows: Vec::new(),
            events: vec![
                curve_event(CurveEventKind::Start, None),
                curve_event(Cusp, None),
                curve_event(Hilltop, Some("B1")),
                curve_event(CurveEventKind::End, None),
            ],
            stop: StopReason::Bounds,
            warnings: Vec::new(),
        };
        let mut curve = curve;
        curve.flag_refined(&Refinement {
            control: "p".into(),
            assumed_order: 2.0,
            order_tolerance: ORDER_TOLERANCE,
            levels: Vec::new(),
            continuum: None,
            critical: Vec::new(),
            turning: Vec::new(),
            events,
            second: Some("k".into()),
            new_on_finer: Vec::new(),
            failed: Vec::new(),
        });
        let flags: Vec<Vec<&str>> = curve
            .events
            .iter()
            .map(|e| e.flags.iter().map(Flag::name).collect())
            .collect();
        assert_eq!(flags, [vec![], vec![], vec!["not-mesh-converged"], vec![]]);
    }
}
