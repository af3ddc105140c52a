//! A scene on an axisymmetric mesh (`[mesh] generator = "axisymmetric"`) made into the
//! meridian's model (docs/theory.md §15), and the [`Study`] it is for the analyses: the same
//! scene keys, effects and analyses as on a 3-D mesh, for the effects the meridian implements
//! (gas at a given over-pressure or of a fixed amount above an inside fluid, fluid wetting the
//! membrane wholly or in part, fluid spinning about z, planes normal to the axis, fixed and
//! sliding edges; the fluid-volume, gas-amount and fixed constraints; the held-translation
//! start of a sphere on a plane); every other effect, constraint or key is refused in one line
//! that names it. Stability is by wave number m = 0..=`mesh.modes` (docs/theory.md §15.3).

use super::{About, BranchOptions, Control, Followed, Free, Point, RunError, Study};
use crate::axisym::blocks::{wave_number, MeridianBlocks, MERIDIAN_GROUP};
use crate::axisym::critical_test::MeridianTest;
use crate::axisym::{default_segments, revolved_mesh, revolved_mode, revolved_positions};
use crate::axisym::{
    AxisymModel, AxisymProblem, GasAmountBorder, GasTarget, Meridian, MeridianMaterial, Pressure,
    VolumeTarget,
};
use crate::continuation::crossings::{Blocks, CriticalTest};
use crate::continuation::{solve_at, PathOptions, SolveError};
use crate::effects::membrane::Wrinkling;
use crate::effects::spec::{Build, MeridianLoad};
use crate::effects::Quantity;
use crate::output::{node_normals, Drawing};
use crate::results::{
    Branches, CriticalPoint, MeshInfo, RecordedPoint, RunResult, State, StateKind,
};
use crate::scene::{self, AxisymShape, FluidEffect, MeshSpec, Scene, SpinEffect};
use meshes::write::Fields;
use nalgebra::DVector;

/// Why an axisymmetric scene cannot be built (user input: the scene asks for something the
/// meridian does not do).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct Unsupported(pub String);

/// A scene made into the meridian's model.
pub struct MeridianStudy {
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
    /// What every report says of the study.
    about: About,
    /// The scene's control.
    control_handle: Option<Control>,
    /// The constraints' targets, once the start state has set them.
    targets: (Option<VolumeTarget>, Option<GasTarget>),
    /// The meridian revolved into a surface, what its states are drawn on.
    revolved: meshes::Mesh,
    /// The stress-free enclosed volume (closed meridians: the stretch's reference).
    stress_free_volume: Option<f64>,
    /// The fluid-volume constraint: (fluid effect, level parameter, target).
    volume: Option<(usize, usize, scene::Target)>,
    /// The gas-amount constraint (its target `f64::NAN` while "initial", set at the start).
    gas: Option<GasTarget>,
    /// `[start] hold-translation` along ±e_z: the sign.
    hold: Option<f64>,
}

fn unsupported(what: String) -> Unsupported {
    Unsupported(what)
}

impl MeridianStudy {
    /// Builds the model of an axisymmetric scene, refusing what the model does not do.
    pub fn build(scene: Scene) -> Result<Self, Unsupported> {
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
        let input = |e: crate::axisym::AxisymError| unsupported(format!("mesh: {e}"));
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
        if let Some(width) = m.relaxed_width().filter(|w| *w > 0.0) {
            return Err(unsupported(format!(
                "material.wrinkling-width = {width}: the axisymmetric model takes the relaxed energy exactly (no switching width); leave the key out, or run the scene on a 3-D mesh"
            )));
        }
        meridian.wrinkling = match m.relaxed_stiffness() {
            Some(stiffness) => Wrinkling::Relaxed {
                stiffness,
                width: 0.0,
            },
            None => Wrinkling::None,
        };
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
            match scene.effects.get(v.effect).and_then(|e| e.get::<FluidEffect>()) {
                Some(f) if f.side == scene::FluidSide::Inside => {}
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
        // The fluid's amount a fluid-volume constraint holds is what a gas of fixed amount
        // leaves out of the enclosure (a number or a parameter: validated).
        let build = Build {
            quantity: &index,
            closing: None,
            fluid_amount: volume.as_ref().and_then(|v| match &v.2 {
                scene::Target::Value(x) => Some(Quantity::Value(*x)),
                scene::Target::Parameter(n) => Some(index(&scene::Quantity::Parameter(n.clone()))),
                scene::Target::Initial => None,
            }),
        };
        for (i, e) in scene.effects.iter().enumerate() {
            match e.spec().meridian(&build) {
                Ok(MeridianLoad::Pressure(p)) => pressures.push(p),
                Ok(MeridianLoad::Plane(p)) => planes.push(p),
                Err(r) => return Err(unsupported(format!("effect[{i}].{} {}", r.key, r.what))),
            }
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
        let control = scene.control().map(|c| {
            parameters
                .iter()
                .position(|p| p == c)
                .expect("validated control")
        });
        let mut model = AxisymModel::new(meridian, pressures);
        model.set_planes(planes);
        model.volume_level = volume.as_ref().map(|v| v.1);
        // A fluid volume needs a fluid, which the gas-amount constraint refuses: never both.
        model.gas_amount = gas.as_ref().map(|g: &GasTarget| g.gas);
        let stress_free_volume = model
            .meridian
            .closed()
            .then(|| model.volume(&model.meridian.nodes) / prestretch.powi(3));
        let modes = mesh.modes;
        // The enclosed volume of a closed meridian, or of an open one holding gas or fluid
        // inside (closed by the plate across its edge), as a 3-D run measures it.
        let encloses = model.meridian.closed()
            || !scene.constraints.is_empty()
            || scene.effects.iter().any(|e| e.spec().measures_enclosure());
        let mut measures = measure_names(
            encloses,
            stress_free_volume.is_some(),
            has_gas_amount(&model),
        );
        // Under the relaxed energy, the areas of its states, as on a 3-D mesh.
        if model.meridian.wrinkling != Wrinkling::None {
            measures.extend(["wrinkled_area".into(), "slack_area".into()]);
        }
        super::check_measure(&scene, &measures).map_err(Unsupported)?;
        let about = About {
            scene: scene.info.name.clone(),
            origin: scene.origin.clone(),
            mesh: MeshInfo {
                generator: scene.mesh.generator().to_string(),
                nodes: model.meridian.nodes.len(),
                elements: model.meridian.elements(),
                group: MERIDIAN_GROUP.into(),
                order: 0,
                radius: None,
            },
            group: MERIDIAN_GROUP.into(),
            group_order: 0,
            unknowns: model.dim(),
            symmetric_unknowns: model.dim(),
            parameters: parameters.clone(),
            measures,
        };
        let control_handle = control.map(|c| Control::of(&scene, &parameters, c));
        let revolved = revolved_mesh(&model.meridian, default_segments(modes))
            .map_err(|e| unsupported(format!("mesh: {e}")))?;
        Ok(Self {
            about,
            control_handle,
            targets: (None, None),
            revolved,
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

    /// The fluid-volume constraint at the state q with every parameter at `params`: its
    /// target measured there, given, or a parameter, and whether q does not meet it yet.
    fn volume_target(&self, q: &[f64], params: &[f64]) -> Option<(VolumeTarget, bool)> {
        let (effect, level, target) = self.volume.as_ref()?;
        let v0 = self
            .model
            .held_fluid(&self.model.positions(q), params)
            .expect("a fluid-volume constraint has its fluid")
            .volume;
        let f = self
            .scene
            .effects
            .get(*effect)
            .and_then(|e| e.get::<FluidEffect>())
            .expect("a validated fluid-volume constraint");
        let position = |n: &str| {
            self.parameters
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
            VolumeTarget {
                level: *level,
                target,
                scale: if scale == 0.0 { -1.0 } else { scale },
                target_parameter,
            },
            target != v0,
        ))
    }

    /// The problem at `params` with the control `control` (a dummy slot past the parameters
    /// without one) and the constraints' targets `targets`.
    fn problem_with(
        &self,
        params: &[f64],
        control: Option<usize>,
        targets: (Option<VolumeTarget>, Option<GasTarget>),
    ) -> AxisymProblem {
        let mut params = params.to_vec();
        let named = params.len();
        let control = control.unwrap_or_else(|| {
            // Without a control the problem still needs a (fixed) control slot.
            params.push(0.0);
            named
        });
        let mut problem = AxisymProblem::new(self.model.clone(), params, control);
        problem.named = named;
        problem.volume = targets.0;
        problem.gas = targets.1;
        problem
    }
}

/// The names of the measures of a meridian (those of a 3-D run: the largest displacement,
/// the lowest and highest z; the enclosed volume of one that encloses, the stretch of a
/// closed one and the gas pressure of a gas amount).
fn measure_names(encloses: bool, closed: bool, gas_amount: bool) -> Vec<String> {
    let mut n = vec![
        "max_displacement".to_string(),
        "min_z".to_string(),
        "max_z".to_string(),
    ];
    if encloses {
        n.push("volume".into());
    }
    if closed {
        n.push("stretch".into());
    }
    if gas_amount {
        n.push("gas_pressure".into());
    }
    n
}

fn has_gas_amount(model: &AxisymModel) -> bool {
    model
        .pressures
        .iter()
        .any(|p| matches!(p, Pressure::GasAmount { .. }))
}

/// The start state with a constraint just added to `problem`: solved again when the state
/// `q` does not meet it (`unmet`), else `q` with the free values as they are (no iteration).
fn meet(
    problem: &mut AxisymProblem,
    q: &DVector<f64>,
    params: &[f64],
    unmet: bool,
    opts: &PathOptions,
) -> Result<(DVector<f64>, DVector<f64>, usize), SolveError> {
    let l0 = problem.free_values(params);
    if unmet {
        solve_at(problem, q, &l0, opts)
    } else {
        Ok((q.clone(), l0, 0))
    }
}

impl Drawing for MeridianStudy {
    /// The meridian revolved about z (docs/theory.md §15.17), with enough segments for the
    /// highest wave number analysed.
    fn mesh(&self) -> &meshes::Mesh {
        &self.revolved
    }

    /// The state revolved, with its normals, and a critical state's mode drawn as its field
    /// δx of wave number m on the revolved nodes.
    fn draw(&self, s: &State) -> (Vec<meshes::Vec3>, Fields) {
        let segments = default_segments(self.modes);
        let x = revolved_positions(&self.model, &s.u, segments)
            .unwrap_or_else(|_| self.revolved.nodes.clone());
        let normals = node_normals(&x, &self.revolved.triangles);
        let mut fields = Fields::new().point_vector("normal", normals);
        if let (StateKind::Critical { irrep, .. }, Some(mode)) = (&s.kind, &s.mode) {
            let m = wave_number(irrep).unwrap_or(0);
            if let Ok(field) = revolved_mode(&self.model, m, mode, segments) {
                let field = field
                    .into_iter()
                    .map(|v| v.map(|c| if c.is_finite() { c } else { 0.0 }))
                    .collect::<Vec<[f64; 3]>>();
                fields = fields.point_vector("critical_mode", field);
            }
        }
        (x, fields)
    }

    fn unknowns(&self) -> usize {
        self.model.dim()
    }

    fn expand(&self, q: &[f64]) -> Vec<f64> {
        q.to_vec()
    }
}

impl Study for MeridianStudy {
    fn about(&self) -> &About {
        &self.about
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn control(&self) -> Option<&Control> {
        self.control_handle.as_ref()
    }

    fn parameter(&self, index: usize) -> Control {
        Control::of(&self.scene, &self.parameters, index)
    }

    fn start_values(&self) -> &[f64] {
        &self.start
    }

    fn warnings(&self) -> &[String] {
        &[]
    }

    /// The measures at displacement q, parameters `params` (the gas-amount effect's
    /// over-pressure C/(V − V*) − P_atm depends on them).
    fn measure(&self, q: &[f64], params: &[f64]) -> Vec<f64> {
        let x = self.model.positions(q);
        let nodes = &self.model.meridian.nodes;
        let max = x
            .iter()
            .zip(nodes)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max);
        let (low, high) = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p[1]), b.max(p[1]))
            });
        let v = self.model.volume(&x);
        let mut out = vec![max, low, high];
        if self.about.measures.iter().any(|m| m == "volume") {
            out.push(v);
        }
        if let Some(v0) = self.stress_free_volume {
            out.push((v / v0).cbrt());
        }
        if has_gas_amount(&self.model) {
            out.push(self.model.gas_pressure(&x, params));
        }
        if self.model.meridian.wrinkling != Wrinkling::None {
            out.extend(self.model.tension_areas(q));
        }
        out
    }

    /// The meridian's largest radius times √nodes.
    fn state_scale(&self) -> f64 {
        let nodes = &self.model.meridian.nodes;
        let r = nodes
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0, f64::max)
            .max(1e-300);
        r * (nodes.len() as f64).sqrt()
    }

    fn coordinates(&self, u: &[f64]) -> Vec<f64> {
        u.to_vec()
    }

    /// The start state: Newton from the meridian scaled by `start.stretch` (or `guess`),
    /// after the start homotopy of `[start] hold-translation`; then the constraints' targets
    /// measured there (or given), and the state solved again where it does not meet them.
    fn solve_start(
        &mut self,
        guess: Option<&[f64]>,
        params: &[f64],
        opts: &PathOptions,
    ) -> Result<Point, RunError> {
        let study: &Self = self;
        let control = study.control_handle.as_ref().map(|c| c.index);
        let mut problem = study.problem_with(params, control, (None, None));
        let q0 = match guess {
            Some(u) => DVector::from_column_slice(u),
            None => {
                let stretch = study.scene.start.stretch;
                let guess: Vec<[f64; 2]> = study
                    .model
                    .meridian
                    .nodes
                    .iter()
                    .map(|p| [p[0] * stretch, p[1] * stretch])
                    .collect();
                DVector::from_vec(study.model.displacement_of(&guess))
            }
        };
        let lambda0 = problem.free_values(&problem.params.clone());
        let start_opts = PathOptions {
            max_iterations: opts.max_iterations.max(50),
            ..opts.clone()
        };
        let failed = |e: SolveError| RunError::start(study, e);
        // A sphere not yet resting on its plane: its mean height held, lowered until the
        // holding force vanishes, with the fluid's volume (so its weight) held throughout
        // (docs/theory.md §7.8, §15.16).
        let (q0, lambda0) = match study.hold {
            Some(sign) => {
                problem.volume = study.volume_target(q0.as_slice(), params).map(|t| t.0);
                let w = study.model.held_translation(sign);
                let l0 = problem.free_values(&problem.params.clone());
                crate::continuation::release::released(&mut problem, &q0, &l0, w, &start_opts)
                    .map_err(failed)?
            }
            None => (q0, lambda0),
        };
        let (mut q, mut lambda, mut iterations) =
            solve_at(&mut problem, &q0, &lambda0, &start_opts).map_err(failed)?;
        if problem.volume.is_none() {
            if let Some((target, unmet)) = study.volume_target(q.as_slice(), params) {
                problem.volume = Some(target);
                let all = problem.params.clone();
                let (q1, l1, it) =
                    meet(&mut problem, &q, &all, unmet, &start_opts).map_err(failed)?;
                (q, lambda, iterations) = (q1, l1, iterations + it);
            }
        }
        // The gas-amount constraint: its amount measured at the start, given, or a
        // parameter; the gas's pressure free from here on.
        if let Some(mut g) = study.gas {
            if g.target.is_nan() && g.target_parameter.is_none() {
                g.target = study.model.gas_amount(&g.gas, q.as_slice(), params);
            }
            problem.gas = Some(g);
            let unmet = g.amount(params) != study.model.gas_amount(&g.gas, q.as_slice(), params);
            let all = problem.params.clone();
            let (q1, l1, it) = meet(&mut problem, &q, &all, unmet, &start_opts).map_err(failed)?;
            (q, lambda, iterations) = (q1, l1, iterations + it);
        }
        let params = problem.parameters(&lambda);
        let times = crate::continuation::Problem::phase_times(&problem);
        self.targets = (problem.volume, problem.gas);
        Ok(Point {
            u: q.iter().copied().collect(),
            params,
            iterations,
            times,
        })
    }

    fn problem(&self, params: &[f64], free: &Free) -> Box<dyn Followed + '_> {
        let targets = if free.constraints {
            self.targets
        } else {
            (None, None)
        };
        let mut problem = self.problem_with(params, free.control, targets);
        problem.also = free.also.clone();
        Box::new(problem)
    }

    fn blocks(&self) -> Result<Box<dyn Blocks + '_>, String> {
        Ok(Box::new(MeridianBlocks::new(
            self.model.clone(),
            self.modes,
        )))
    }

    fn critical_test(&self, cp: &CriticalPoint) -> Result<Box<dyn CriticalTest + '_>, String> {
        let m = wave_number(&cp.irrep)
            .filter(|&m| m <= self.modes)
            .ok_or_else(|| format!("the meridian has no block {}", cp.irrep))?;
        Ok(Box::new(MeridianTest::new(self.model.clone(), m, &cp.mode)))
    }

    fn branches(
        &self,
        critical: &[CriticalPoint],
        options: BranchOptions,
    ) -> Result<Branches, String> {
        super::meridian_branches::switch(self, critical, options)
    }

    fn recorded(
        &self,
        recorded: &[RecordedPoint],
        n: usize,
        state: Vec<f64>,
        mode: Vec<f64>,
    ) -> Result<Vec<CriticalPoint>, String> {
        let (mut state, mut mode) = (Some(state), Some(mode));
        recorded
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let m = wave_number(&c.irrep)
                    .filter(|&m| m <= self.modes)
                    .ok_or_else(|| {
                        format!(
                            "critical point {}: the meridian has no block {} (modes 0..{})",
                            k + 1,
                            c.irrep,
                            self.modes
                        )
                    })?;
                let (u, v) = if k + 1 == n {
                    (
                        state.take().unwrap_or_default(),
                        mode.take().unwrap_or_default(),
                    )
                } else {
                    (Vec::new(), Vec::new())
                };
                let multiplicity = if m == 0 { 1 } else { 2 };
                Ok(CriticalPoint {
                    kind: crate::results::CriticalKind::of(m == 0, multiplicity, c.held()),
                    irrep: c.irrep.clone(),
                    multiplicity,
                    parameters: c.parameters.clone(),
                    measures: c.measures.clone(),
                    after_step: c.after_step,
                    residual_eigenvalue: c.residual_eigenvalue,
                    isotropy: crate::axisym::blocks::isotropy(m),
                    mode: v,
                    state: u,
                    bracket: None,
                })
            })
            .collect()
    }

    /// Its largest principal stretch (the meridian's elements do not say where it would
    /// wrinkle: no count).
    fn wrinkled(&self, u: &[f64], _params: &[f64]) -> Option<usize> {
        (u.len() == self.model.dim()).then(|| self.model.wrinkled_elements(u))
    }

    fn state_check(&self, u: &[f64], _params: &[f64]) -> crate::results::validity::StateCheck {
        if u.len() != self.model.dim() {
            return crate::results::validity::StateCheck::default();
        }
        crate::results::validity::StateCheck {
            wrinkled: Some(self.model.wrinkled_elements(u)),
            stretch: Some(self.model.largest_stretch(u)).filter(|s| s.is_finite()),
            contact: None,
        }
    }

    fn penetrations(&self, u: &[f64], params: &[f64]) -> Option<(Vec<f64>, f64)> {
        if u.len() != self.model.dim() {
            return None;
        }
        self.model.penetrations(u, params)
    }

    fn wave_number(&self, cp: &CriticalPoint) -> Option<usize> {
        wave_number(&cp.irrep)
    }

    fn annotate(&self, result: &mut RunResult) {
        result.report.wave_numbers = result
            .report
            .critical
            .iter()
            .map(|cp| wave_number(&cp.irrep).unwrap_or(0))
            .collect();
        result.report.checks = Some(super::checks::checks(self, result));
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
) -> Result<GasTarget, Unsupported> {
    if let Some(k) = scene
        .effects
        .iter()
        .position(|e| e.get::<FluidEffect>().is_some() || e.get::<SpinEffect>().is_some())
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
    Ok(GasTarget {
        gas: GasAmountBorder {
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
