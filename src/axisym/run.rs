//! A scene on an axisymmetric mesh (`[mesh] generator = "axisymmetric"`), made into the
//! axisymmetric model and run: the same scene keys, effects and analyses as on a 3-D mesh, for
//! the effects the meridian implements (gas at a given over-pressure or of a fixed amount above
//! an inside fluid, fluid wetting the membrane wholly or in part, fluid spinning about z,
//! planes normal to the axis, fixed and sliding edges; the fluid-volume, gas-amount and fixed
//! constraints; the held-translation start of a sphere on a plane; the material's μ, k and H
//! as numbers or parameters, the pre-stretch a number); every other effect, constraint or key
//! is refused in one line that names it. Stability is by wave number m = 0..=`mesh.modes`
//! (docs/theory.md §15.3).

use super::{AxisymModel, AxisymProblem, Meridian, MeridianMaterial, Pressure};
use crate::analysis::modes::{self, ModePath};
use crate::continuation::{PathOptions, PathPoint, SolveError};
use crate::effects::Quantity;
use crate::results::{CriticalKind, StopReason, TurningRow};
use crate::scene::{self, Analysis, AxisymShape, Direction, Effect, MeshSpec, Scene};
use nalgebra::DVector;
use serde::Serialize;
use std::time::{Duration, Instant};

/// Why an axisymmetric scene cannot be built or run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AxisymRunError {
    /// The scene asks for something the axisymmetric model does not do (user input).
    #[error("{0}")]
    Unsupported(String),
    /// The start state did not converge.
    #[error("the start state did not converge: {0}")]
    Start(String),
}

/// A scene made into the axisymmetric model.
pub struct AxisymStudy {
    /// The scene.
    pub scene: Scene,
    /// The model.
    pub model: AxisymModel,
    /// Parameter names (scene order).
    pub parameters: Vec<String>,
    /// Start values.
    pub start: Vec<f64>,
    /// The control's index (path and linear-buckling analyses).
    pub control: Option<usize>,
    /// The largest wave number.
    pub modes: usize,
    /// The stress-free enclosed volume (closed meridians: the stretch's reference).
    stress_free_volume: Option<f64>,
    /// The fluid-volume constraint: (fluid effect, level parameter, target).
    volume: Option<(usize, usize, scene::Target)>,
    /// The gas-amount constraint (its target `f64::NAN` while "initial", set at the start).
    gas: Option<super::GasTarget>,
    /// `[start] hold-translation` along ±e_z: the sign.
    hold: Option<f64>,
}

fn unsupported(what: String) -> AxisymRunError {
    AxisymRunError::Unsupported(what)
}

impl AxisymStudy {
    /// Builds the model of an axisymmetric scene, refusing what the model does not do.
    pub fn build(scene: Scene) -> Result<Self, AxisymRunError> {
        let MeshSpec::Axisymmetric(mesh) = &scene.mesh else {
            return Err(unsupported(
                "mesh.generator: the axisymmetric model needs generator = \"axisymmetric\"".into(),
            ));
        };
        let parameters: Vec<String> = scene.parameters.keys().cloned().collect();
        let start: Vec<f64> = scene.parameters.values().map(|p| p.start).collect();
        let index = |q: &scene::Quantity| match q {
            scene::Quantity::Value(v) => Quantity::Value(*v),
            scene::Quantity::Parameter(n) => Quantity::Parameter(
                parameters
                    .iter()
                    .position(|p| p == n)
                    .expect("validated parameter"),
            ),
        };
        // μ, k and H numbers or parameters (docs/theory.md §15.18); the pre-stretch a number.
        let m = &scene.material;
        let material = MeridianMaterial {
            mu: index(&m.mu),
            k: index(&m.k),
            thickness: index(&m.thickness),
        };
        let prestretch = match &m.prestretch {
            scene::Quantity::Value(v) => *v,
            scene::Quantity::Parameter(n) => {
                return Err(unsupported(format!(
                    "material.prestretch = \"{n}\": the axisymmetric model takes the pre-stretch as a number, not a parameter"
                )))
            }
        };
        let input = |e: super::AxisymError| unsupported(format!("mesh: {e}"));
        let (mut meridian, edge) = match mesh.shape {
            AxisymShape::Disc => (
                Meridian::disc(mesh.radius, mesh.elements, prestretch, material).map_err(input)?,
                Some("rim"),
            ),
            AxisymShape::TruncatedSphere => (
                Meridian::truncated_sphere(
                    mesh.radius,
                    mesh.cut_height,
                    mesh.elements,
                    prestretch,
                    material,
                )
                .map_err(input)?,
                Some("cut"),
            ),
            AxisymShape::Sphere => (
                Meridian::sphere(mesh.radius, mesh.elements, prestretch, material)
                    .map_err(input)?,
                None,
            ),
        };
        meridian.clamped = (false, false);
        for (i, name) in scene.boundary.fixed.iter().enumerate() {
            if Some(name.as_str()) == edge {
                meridian.clamped.1 = true;
            } else {
                return Err(unsupported(format!(
                    "boundary.fixed[{i}]: unknown node set \"{name}\" (the axisymmetric {} has: {})",
                    shape_name(mesh.shape),
                    edge.unwrap_or("no node sets")
                )));
            }
        }
        for (i, s) in scene.boundary.slide.iter().enumerate() {
            if Some(s.set.as_str()) != edge {
                return Err(unsupported(format!(
                    "boundary.slide[{i}].set: unknown node set \"{}\" (the axisymmetric {} has: {})",
                    s.set,
                    shape_name(mesh.shape),
                    edge.unwrap_or("no node sets")
                )));
            }
            if s.normal[0].hypot(s.normal[1]) > 1e-12 {
                return Err(unsupported(format!(
                    "boundary.slide[{i}].normal = {:?}: the axisymmetric model slides an edge on a plane normal to the axis only (normal = [0, 0, ±1])",
                    s.normal
                )));
            }
            if meridian.clamped.1 {
                return Err(unsupported(format!(
                    "boundary.slide[{i}]: the set \"{}\" is also fixed",
                    s.set
                )));
            }
            meridian.sliding.1 = true;
        }
        let mut volume = None;
        let mut gas = None;
        for (i, c) in scene.constraints.iter().enumerate() {
            let v = match c {
                scene::Constraint::FluidVolume(v) => v,
                scene::Constraint::GasAmount(g) => {
                    gas = Some(gas_amount_constraint(&scene, &parameters, i, g)?);
                    continue;
                }
                // Every parameter but the control and the one a constraint frees stays at its
                // start value.
                scene::Constraint::Fixed(_) => continue,
            };
            match scene.effects.get(v.effect) {
                Some(Effect::Fluid(f)) if f.side == scene::FluidSide::Inside => {}
                _ => {
                    return Err(unsupported(format!(
                        "constraint[{i}].effect = {}: the axisymmetric model holds the volume of a fluid inside the membrane only",
                        v.effect
                    )))
                }
            }
            let level = parameters
                .iter()
                .position(|p| *p == v.level)
                .expect("validated level");
            volume = Some((v.effect, level, v.value.clone()));
        }
        let mut pressures = Vec::new();
        let mut planes = Vec::new();
        for (i, e) in scene.effects.iter().enumerate() {
            match e {
                Effect::Gas(g) => pressures.push(Pressure::Gas {
                    pressure: index(&g.pressure),
                }),
                Effect::Fluid(f) => pressures.push(Pressure::Fluid {
                    filled: f.filled,
                    density: index(&f.density),
                    gravity: index(&f.gravity),
                    level: index(&f.level),
                    front: match f.side {
                        scene::FluidSide::Above => true,
                        scene::FluidSide::Below | scene::FluidSide::Inside => false,
                    },
                }),
                // The fluid spinning behind the membrane, as the 3-D effect takes it.
                Effect::Spin(s) => pressures.push(Pressure::Spin {
                    density: index(&s.density),
                    omega2: index(&s.omega2),
                }),
                Effect::Plane(p) => {
                    if p.normal[0].hypot(p.normal[1]) > 1e-12 {
                        return Err(unsupported(format!(
                            "effect[{i}].normal = {:?}: the axisymmetric model takes a plane normal to the axis only (normal = [0, 0, ±1])",
                            p.normal
                        )));
                    }
                    planes.push(super::FloorPlane {
                        normal_z: p.normal[2].signum(),
                        offset: index(&p.offset),
                        penalty: index(&p.penalty),
                        exponent: p.exponent,
                    });
                }
                // The fluid's amount a fluid-volume constraint holds is what the gas leaves
                // out of the enclosure (a number or a parameter: validated).
                Effect::GasAmount(g) => pressures.push(Pressure::GasAmount {
                    amount: index(&g.amount),
                    ambient: g.ambient_pressure,
                    fluid: volume.as_ref().and_then(|v| match &v.2 {
                        scene::Target::Value(x) => Some(Quantity::Value(*x)),
                        scene::Target::Parameter(n) => {
                            Some(index(&scene::Quantity::Parameter(n.clone())))
                        }
                        scene::Target::Initial => None,
                    }),
                }),
            }
        }
        if scene.start.from.is_some() {
            return Err(unsupported(
                "start.from: not implemented by the axisymmetric model".into(),
            ));
        }
        let hold = match scene.start.hold_translation {
            None => None,
            Some(d) if d[0].hypot(d[1]) > 1e-12 => {
                return Err(unsupported(format!(
                    "start.hold-translation = {d:?}: the axisymmetric model holds the translation along the axis only ([0, 0, ±1])"
                )))
            }
            Some(_) if !meridian.closed() || planes.is_empty() => {
                return Err(unsupported(
                    "start.hold-translation: the axisymmetric model lowers a closed meridian (shape = \"sphere\") onto a plane effect only".into(),
                ))
            }
            Some(d) => Some(d[2].signum()),
        };
        let control_name = match &scene.analysis {
            Analysis::Path(p) => {
                if p.branches.is_some() {
                    return Err(unsupported(
                        "analysis.branches: branch switching is not implemented by the axisymmetric model; use a 3-D mesh".into(),
                    ));
                }
                Some(p.control.clone())
            }
            Analysis::LinearBuckling(b) => Some(b.control.clone()),
            Analysis::Equilibrium(_) => None,
            Analysis::CriticalCurve(_) => {
                return Err(unsupported(
                    "analysis.type = \"critical-curve\": not implemented by the axisymmetric model; use a 3-D mesh".into(),
                ))
            }
            Analysis::Surface(_) => {
                return Err(unsupported(
                    "analysis.type = \"surface\": not implemented by the axisymmetric model; use a 3-D mesh".into(),
                ))
            }
        };
        let control = control_name.map(|c| {
            parameters
                .iter()
                .position(|p| *p == c)
                .expect("validated control")
        });
        let mut model = AxisymModel::new(meridian, pressures);
        model.set_planes(planes);
        model.volume_level = volume.as_ref().map(|v| v.1);
        // A fluid volume needs a fluid, which the gas-amount constraint refuses: never both.
        model.gas_amount = gas.as_ref().map(|g: &super::GasTarget| g.gas);
        let stress_free_volume = model
            .meridian
            .closed()
            .then(|| model.volume(&model.meridian.nodes) / prestretch.powi(3));
        let modes = mesh.modes;
        Ok(Self {
            scene,
            model,
            parameters,
            start,
            control,
            modes,
            stress_free_volume,
            volume,
            gas,
            hold,
        })
    }

    /// The names of the measures reported along a path.
    pub fn measure_names(&self) -> Vec<String> {
        let mut n = vec![
            "max-displacement".to_string(),
            "apex-z".to_string(),
            "volume".to_string(),
        ];
        if self.stress_free_volume.is_some() {
            n.push("stretch".into());
        }
        if self.has_gas_amount() {
            n.push("gas_pressure".into());
        }
        n
    }

    fn has_gas_amount(&self) -> bool {
        self.model
            .pressures
            .iter()
            .any(|p| matches!(p, Pressure::GasAmount { .. }))
    }

    /// The measures at displacement q, parameters `params` (the gas-amount effect's
    /// over-pressure C/(V − V*) − P_atm depends on them).
    pub fn measure(&self, q: &[f64], params: &[f64]) -> Vec<f64> {
        let x = self.model.positions(q);
        let nodes = &self.model.meridian.nodes;
        let max = x
            .iter()
            .zip(nodes)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max);
        let v = self.model.volume(&x);
        let mut out = vec![max, x[0][1], v];
        if let Some(v0) = self.stress_free_volume {
            out.push((v / v0).cbrt());
        }
        if self.has_gas_amount() {
            out.push(self.model.gas_pressure(&x, params));
        }
        out
    }

    fn options(&self) -> PathOptions {
        let nodes = &self.model.meridian.nodes;
        let r = nodes
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0, f64::max)
            .max(1e-300);
        let scale = r * (nodes.len() as f64).sqrt();
        let bounds = self
            .control
            .map(|c| &self.scene.parameters[&self.parameters[c]])
            .map_or((f64::NEG_INFINITY, f64::INFINITY), |b| {
                (
                    b.min.unwrap_or(f64::NEG_INFINITY),
                    b.max.unwrap_or(f64::INFINITY),
                )
            });
        match &self.scene.analysis {
            Analysis::Path(p) => PathOptions {
                initial_step: p.initial_step,
                min_step: p.min_step,
                max_step: p.max_step,
                max_steps: p.steps,
                max_iterations: p.max_iterations,
                tolerance: p.tolerance,
                bounds,
                parameter_scales: vec![1.0],
                state_scale: scale,
                direction: match p.direction {
                    Direction::Decrease => -1.0,
                    Direction::Increase => 1.0,
                },
            },
            Analysis::Equilibrium(e) => PathOptions {
                tolerance: e.tolerance,
                max_iterations: e.max_iterations,
                state_scale: scale,
                ..PathOptions::default()
            },
            Analysis::LinearBuckling(b) => PathOptions {
                tolerance: b.tolerance,
                max_iterations: b.max_iterations,
                state_scale: scale,
                ..PathOptions::default()
            },
            Analysis::CriticalCurve(_) | Analysis::Surface(_) => PathOptions::default(),
        }
    }
}

/// The gas-amount constraint `constraint[i]` on the meridian: a gas effect whose pressure is
/// a parameter other than the control, alone in the membrane (no fluid, whose volume the gas
/// would share).
fn gas_amount_constraint(
    scene: &Scene,
    parameters: &[String],
    i: usize,
    g: &scene::GasAmountConstraint,
) -> Result<super::GasTarget, AxisymRunError> {
    if let Some(k) = scene
        .effects
        .iter()
        .position(|e| matches!(e, Effect::Fluid(_) | Effect::Spin(_)))
    {
        return Err(unsupported(format!(
            "constraint[{i}].effect = {}: the axisymmetric model holds the amount of a gas alone in the membrane (effect[{k}] is a {}); use a 3-D mesh",
            g.effect,
            scene.effects[k].kind()
        )));
    }
    let position = |n: &str| parameters.iter().position(|p| p == n);
    let pressure = position(&g.pressure).expect("validated pressure");
    let (target, target_parameter) = match &g.value {
        scene::Target::Value(v) => (*v, None),
        scene::Target::Initial => (f64::NAN, None),
        scene::Target::Parameter(n) => (f64::NAN, Some(position(n).expect("validated amount"))),
    };
    Ok(super::GasTarget {
        gas: super::GasAmountBorder {
            pressure,
            ambient: g.ambient_pressure,
        },
        target,
        target_parameter,
    })
}

fn shape_name(s: AxisymShape) -> &'static str {
    match s {
        AxisymShape::Disc => "disc",
        AxisymShape::TruncatedSphere => "truncated-sphere",
        AxisymShape::Sphere => "sphere",
    }
}

/// A row of an axisymmetric path.
#[derive(Debug, Clone, Serialize)]
pub struct AxisymRow {
    /// The point's index.
    pub step: usize,
    /// Arclength from the start.
    pub arclength: f64,
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// The measures.
    pub measures: Vec<f64>,
    /// Newton iterations.
    pub iterations: usize,
    /// The index of every block m = 0..=M (None where a block could not be evaluated).
    pub index: Option<Vec<usize>>,
}

/// A critical point, labelled by its wave number and multiplicity.
#[derive(Debug, Clone, Serialize)]
pub struct AxisymCritical {
    /// The wave number m.
    pub m: usize,
    /// 1 for m = 0, 2 for m ≥ 1.
    pub multiplicity: usize,
    /// The kind.
    #[serde(serialize_with = "display")]
    pub kind: CriticalKind,
    /// After this row (`step` in `path.json`).
    #[serde(rename = "step")]
    pub after_step: usize,
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// The measures.
    pub measures: Vec<f64>,
    /// Whether the crossing was localised.
    pub localised: bool,
    /// The block's eigenvalue nearest zero there, relative to its largest entry (NaN where
    /// the crossing was not localised).
    pub eigenvalue: f64,
}

fn display<S: serde::Serializer>(k: &CriticalKind, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(k)
}

/// A finished axisymmetric run.
#[derive(Debug, Clone, Serialize)]
pub struct AxisymReport {
    /// The scene's name.
    pub scene: String,
    /// The mesh: `axisymmetric shape=… elements=… modes=…`.
    pub mesh: String,
    /// Unknowns of the axisymmetric problem.
    pub unknowns: usize,
    /// The largest wave number analysed.
    pub modes: usize,
    /// The control's name (empty without one).
    pub control: String,
    /// Parameter names.
    pub parameters: Vec<String>,
    /// Measure names.
    pub measures: Vec<String>,
    /// The path.
    pub rows: Vec<AxisymRow>,
    /// Turning points of the control.
    pub turning_points: Vec<TurningRow>,
    /// Critical points in path order.
    pub critical: Vec<AxisymCritical>,
    /// Why it ended.
    pub stop: StopReason,
    /// What could not be settled.
    pub warnings: Vec<String>,
    /// Wall time of the run.
    #[serde(skip)]
    pub time: Duration,
    /// Of it, the blocks (assembly, inertia, localisation).
    #[serde(skip)]
    pub block_time: Duration,
}

/// The start with a constraint just added to `problem`: solved again when the state `q`
/// does not meet it (`unmet`), else `q` with the free values as they are (no iteration).
fn meet(
    problem: &mut AxisymProblem,
    q: &DVector<f64>,
    params: &[f64],
    unmet: bool,
    opts: &PathOptions,
) -> Result<(DVector<f64>, DVector<f64>, usize), SolveError> {
    let l0 = problem.free_values(params);
    if unmet {
        crate::continuation::solve_at(problem, q, &l0, opts)
    } else {
        Ok((q.clone(), l0, 0))
    }
}

/// Runs an axisymmetric study's analysis; `progress(point, control)` at every converged point
/// (the start is point 0, as in [`crate::analysis::run`]).
pub fn run(
    study: &AxisymStudy,
    mut progress: impl FnMut(usize, f64),
) -> Result<AxisymReport, AxisymRunError> {
    let t0 = Instant::now();
    let opts = study.options();
    let control = study.control.unwrap_or(0);
    let mut params = study.start.clone();
    if params.is_empty() {
        // Without parameters the problem still needs a (fixed) control slot.
        params.push(0.0);
    }
    let mut problem = AxisymProblem::new(study.model.clone(), params.clone(), control, study.modes);
    let stretch = study.scene.start.stretch;
    let guess: Vec<[f64; 2]> = study
        .model
        .meridian
        .nodes
        .iter()
        .map(|p| [p[0] * stretch, p[1] * stretch])
        .collect();
    let q0 = DVector::from_vec(study.model.displacement_of(&guess));
    let lambda0 = DVector::from_vec(vec![params[control]]);
    let start_opts = PathOptions {
        max_iterations: opts.max_iterations.max(50),
        ..opts.clone()
    };
    let describe = |e: SolveError| AxisymRunError::Start(e.to_string());
    // The fluid-volume constraint at the state q: its target measured there, given, or a
    // parameter; its level free from then on.
    let volume_target = |q: &DVector<f64>| {
        let (effect, level, target) = study.volume.as_ref()?;
        let v0 = study
            .model
            .held_fluid(&study.model.positions(q.as_slice()), &params)
            .expect("a fluid-volume constraint has its fluid")
            .volume;
        let Some(Effect::Fluid(f)) = study.scene.effects.get(*effect) else {
            unreachable!("a validated fluid-volume constraint")
        };
        let position = |n: &str| {
            study
                .parameters
                .iter()
                .position(|p| p == n)
                .expect("validated parameter")
        };
        let value = |x: &scene::Quantity| match x {
            scene::Quantity::Value(v) => *v,
            scene::Quantity::Parameter(n) => params[position(n)],
        };
        let scale = -value(&f.density) * value(&f.gravity);
        let (target, target_parameter) = match target {
            scene::Target::Value(v) => (*v, None),
            scene::Target::Initial => (v0, None),
            scene::Target::Parameter(n) => (params[position(n)], Some(position(n))),
        };
        Some((
            super::VolumeTarget {
                level: *level,
                target,
                scale: if scale == 0.0 { -1.0 } else { scale },
                target_parameter,
            },
            target != v0,
        ))
    };
    // A sphere not yet resting on its plane: its mean height held, lowered until the holding
    // force vanishes, with the fluid's volume (so its weight) held throughout
    // (docs/theory.md §7.8, §15.16).
    let (q0, lambda0) = match study.hold {
        Some(sign) => {
            problem.volume = volume_target(&q0).map(|t| t.0);
            let w = study.model.held_translation(sign);
            let l0 = problem.free_values(&params);
            crate::continuation::release::released(&mut problem, &q0, &l0, w, &start_opts)
                .map_err(describe)?
        }
        None => (q0, lambda0),
    };
    let (mut q, mut lambda, mut iterations) =
        crate::continuation::solve_at(&mut problem, &q0, &lambda0, &start_opts)
            .map_err(describe)?;
    if problem.volume.is_none() {
        if let Some((target, unmet)) = volume_target(&q) {
            problem.volume = Some(target);
            let (q1, l1, it) =
                meet(&mut problem, &q, &params, unmet, &start_opts).map_err(describe)?;
            (q, lambda, iterations) = (q1, l1, iterations + it);
        }
    }
    // The gas-amount constraint: its amount measured at the start, given, or a parameter;
    // the gas's pressure free from here on.
    if let Some(g) = study.gas {
        let mut g = g;
        if g.target.is_nan() && g.target_parameter.is_none() {
            g.target = study.model.gas_amount(&g.gas, q.as_slice(), &params);
        }
        problem.gas = Some(g);
        let unmet = g.amount(&params) != study.model.gas_amount(&g.gas, q.as_slice(), &params);
        let (q1, l1, it) = meet(&mut problem, &q, &params, unmet, &start_opts).map_err(describe)?;
        (q, lambda, iterations) = (q1, l1, iterations + it);
    }
    let (stop_stretch, stop_displacement) = match &study.scene.analysis {
        Analysis::Path(p) => (p.stop_stretch, p.stop_displacement),
        _ => (None, None),
    };
    let names = study.measure_names();
    let k_stretch = names.iter().position(|n| n == "stretch");
    let k_displacement = names.iter().position(|n| n == "max-displacement");
    // A stop is reached where its measure passes the target from the start's side.
    let start_measures = study.measure(q.as_slice(), &problem.parameters(&lambda));
    let side = |k: usize, target: f64| (k, target, (start_measures[k] - target).signum());
    let stretch_side = k_stretch.zip(stop_stretch).map(|(k, t)| side(k, t));
    let displacement_side = k_displacement
        .zip(stop_displacement)
        .map(|(k, t)| side(k, t));
    let mut count = 0usize;
    let path: ModePath = match &study.scene.analysis {
        Analysis::Path(_) => {
            let stop = |problem: &AxisymProblem, p: &PathPoint| {
                if stretch_side.is_none() && displacement_side.is_none() {
                    return None;
                }
                let now = study.measure(p.q.as_slice(), &problem.parameters(&p.lambda));
                let passed = |s: Option<(usize, f64, f64)>| {
                    s.and_then(|(k, t, side)| ((now[k] - t) * side <= 0.0).then_some(t))
                };
                passed(stretch_side)
                    .map(|target| StopReason::Stretch { target })
                    .or_else(|| {
                        passed(displacement_side).map(|target| StopReason::Displacement { target })
                    })
            };
            modes::follow(problem, &q, &lambda, opts, stop, |_, p| {
                progress(count, p.lambda[0]);
                count += 1;
            })
            .map_err(describe)?
            .0
        }
        Analysis::LinearBuckling(b) => {
            let range = study
                .control
                .map(|c| &study.scene.parameters[&study.parameters[c]])
                .map_or((0.0, 0.0), |p| {
                    (p.min.unwrap_or(p.start), p.max.unwrap_or(p.start))
                });
            progress(0, lambda[0]);
            modes::sweep(&mut problem, &q, &lambda, range, b.samples)
        }
        Analysis::Equilibrium(_) | Analysis::CriticalCurve(_) | Analysis::Surface(_) => {
            progress(0, lambda[0]);
            let mut path = modes::sweep(&mut problem, &q, &lambda, (lambda[0], lambda[0]), 1);
            path.points.truncate(1);
            path.index.truncate(1);
            path.stop = StopReason::Equilibrium;
            path
        }
    };
    let level = study
        .volume
        .as_ref()
        .map(|v| v.1)
        .or(study.gas.map(|g| g.gas.pressure));
    let full_params = |l: &[f64]| {
        let mut p = params.clone();
        p[control] = l[0];
        if let (Some(k), Some(h)) = (level, l.get(1)) {
            p[k] = *h;
        }
        p
    };
    let param_at = |l: &[f64]| {
        let mut p = full_params(l);
        p.truncate(study.parameters.len());
        p
    };
    let rows = path
        .points
        .iter()
        .zip(&path.index)
        .enumerate()
        .map(|(i, (p, ix))| AxisymRow {
            step: i,
            arclength: p.arclength,
            parameters: param_at(p.lambda.as_slice()),
            measures: study.measure(p.q.as_slice(), &full_params(p.lambda.as_slice())),
            iterations: if i == 0 { iterations } else { p.iterations },
            index: ix.clone(),
        })
        .collect();
    let turning_points = path
        .turning
        .iter()
        .map(|t| TurningRow {
            kind: t.kind,
            after_step: t.after_step,
            parameters: param_at(&t.lambda),
            measures: study.measure(&t.q, &full_params(&t.lambda)),
        })
        .collect();
    let critical = path
        .critical
        .iter()
        .map(|c| AxisymCritical {
            m: c.m,
            multiplicity: c.multiplicity,
            kind: c.kind,
            after_step: c.after_step,
            parameters: param_at(&c.lambda),
            measures: study.measure(&c.q, &full_params(&c.lambda)),
            localised: c.localised,
            eigenvalue: c.eigenvalue,
        })
        .collect();
    let MeshSpec::Axisymmetric(mesh) = &study.scene.mesh else {
        unreachable!("built from an axisymmetric mesh")
    };
    Ok(AxisymReport {
        scene: study.scene.info.name.clone(),
        mesh: format!(
            "axisymmetric shape={} elements={} modes={}",
            shape_name(mesh.shape),
            mesh.elements,
            mesh.modes
        ),
        unknowns: study.model.dim(),
        modes: study.modes,
        control: study
            .control
            .map_or_else(String::new, |c| study.parameters[c].clone()),
        parameters: study.parameters.clone(),
        measures: study.measure_names(),
        rows,
        turning_points,
        critical,
        stop: path.stop,
        warnings: path.warnings,
        time: t0.elapsed(),
        block_time: path.block_time,
    })
}
