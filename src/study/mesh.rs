//! A scene on a 3-D mesh made ready to solve: scene → mesh + group → effects → model
//! (docs/architecture.md), and the [`Study`] it is for the analyses.
//!
//! Only the effects the scene lists are built. The scene's group is the mesh group restricted
//! to what every effect keeps (computed from [`crate::model::Effect::keeps`], never typed in),
//! and the path is followed in that group's fixed-point space.

use super::block_test::BlockTest;
use super::{
    About, BranchOptions, Control, Followed, Free, Point, RunError, Study, SymmetricProblem,
};
use crate::adapted::AdaptedBasis;
use crate::adapted::SparseBasis;
use crate::continuation::crossings::{Blocks, CriticalTest};
use crate::continuation::{solve_at, solve_at_or_drift, Drift, PathOptions};
use crate::effects::gas::{GasAmount, GasAmountConstraint};
use crate::effects::hydrostatic::{Fluid, FluidSide, FluidVolumeConstraint};
use crate::effects::membrane::{self, MaterialQuantities, Membrane};
use crate::effects::spec::{Build, Measured};
use crate::effects::volume::ClosingFace;
use crate::effects::Quantity;
use crate::limits::Limits;
use crate::model::constraint::Constraint;
use crate::model::CellQuantity;
use crate::model::{Effect, FeModel, Model, Vec3};
use crate::output::{node_normals, Drawing};
use crate::results::validity::{Checks, StateCheck};
use crate::results::{
    Branches, CriticalPoint, MeshInfo, RecordedPoint, RunResult, State, StateKind,
    WrinkledCritical, WrinkledPoint, Wrinkling,
};
use crate::scene::{self, Scene};
use crate::stability::{IrrepBlocks, Stability};
use meshes::write::Fields;
use meshes::{GroupAction, SymmetricMesh};
use std::sync::Arc;
use symmetry::Invariant;

/// Why a scene could not be made into a model (the scene itself was valid).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The scene file is wrong (user input).
    #[error("{0}")]
    Scene(#[from] scene::SceneError),
    /// The scene asks for something this version cannot do (user input).
    #[error("{0}")]
    Unsupported(String),
    /// The scene would cost more than the limits allow (user input).
    #[error("{0}")]
    Limit(#[from] crate::limits::LimitError),
}

/// Measures reported along a path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// Largest nodal displacement |u_i|.
    MaxDisplacement,
    /// Lowest z of the membrane.
    MinZ,
    /// Highest z of the membrane.
    MaxZ,
    /// Enclosed volume (closed membranes).
    Volume,
    /// (V / V_stress-free)^(1/3) (closed membranes).
    Stretch,
    /// Fluid volume of the fluid effect with this index among the fluids.
    FluidVolume(usize),
    /// Over-pressure C/(V − V*) − P_atm of the gas-amount effect with this index among them.
    GasPressure(usize),
    /// The current area of the wrinkled triangles (relaxed energy).
    WrinkledArea,
    /// The current area of the slack triangles (relaxed energy).
    SlackArea,
    /// The number of nodes in contact with a penalty plane (its gap negative): the pieces of a
    /// piecewise-smooth Π ([`Model::switches`]) that are on.
    ContactNodes,
}

/// A scene on a 3-D mesh, ready to solve.
pub struct MeshStudy {
    /// The scene.
    pub scene: Scene,
    /// The mesh with its own group.
    pub mesh: SymmetricMesh,
    /// The scene's group acting on the mesh (mesh group restricted to what the effects keep).
    pub action: GroupAction,
    /// The model.
    pub model: FeModel,
    /// Parameter names (scene order).
    pub parameters: Vec<String>,
    /// Start values, in that order.
    pub start: Vec<f64>,
    /// Augmenting equations, in scene order (targets set by [`MeshStudy::set_targets`]).
    pub constraints: Vec<Box<dyn Constraint>>,
    /// Index of the control parameter (path analyses).
    pub control: Option<usize>,
    /// The free parameters: the control, then those the constraints govern.
    pub free: Vec<usize>,
    /// The fixed-point basis of the scene's group.
    pub basis: SparseBasis,
    /// Measures reported along the path, with names.
    pub measures: Vec<(String, Measure)>,
    /// Warnings about the setup that a run should report, e.g. symmetry of a mesh file beyond
    /// its declared group ([`Scene::mesh_warnings`]).
    pub warnings: Vec<String>,
    /// What every report says of the study.
    about: About,
    /// The scene's control.
    control_handle: Option<Control>,
    /// The symmetry-adapted basis of the scene's group, built at the first stability analysis
    /// (or why there is none: a group whose irreps the analysis cannot split by).
    adapted: std::sync::OnceLock<Result<crate::adapted::AdaptedBasis, String>>,
    fluids: Vec<Fluid>,
    gases: Vec<GasAmount>,
    closed: bool,
    closing: Option<Arc<ClosingFace>>,
    /// The enclosed volume of the mesh (closed membranes); the stress-free volume is this over
    /// λ0³.
    mesh_volume: f64,
    prestretch: Quantity,
    /// The reference radius R as a parameter and the radius R0 the mesh was generated at.
    radius: Option<(Quantity, f64)>,
    targets_from_start: Vec<bool>,
    /// Whether the last start solve was accepted at round-off along a near-singular
    /// direction (a motion nothing holds).
    start_drifted: bool,
}

/// Why [`MeshStudy::spectrum_at`] gave no spectrum.
#[derive(Debug, Clone, thiserror::Error)]
pub enum SpectrumError {
    /// The symmetry-adapted basis could not be built.
    #[error("{0}")]
    Basis(String),
    /// The tangent could not be evaluated at the state.
    #[error("the tangent could not be evaluated: {0}")]
    Tangent(crate::model::ModelError),
}

impl MeshStudy {
    /// Builds mesh, effects, model, constraints and basis from a validated scene.
    pub fn build(scene: Scene) -> Result<Self, StudyError> {
        let limits = Limits::from_env()?;
        Self::build_within(scene, &limits)
    }

    /// As [`MeshStudy::build`], refusing a scene whose group or estimated memory
    /// ([`Scene::estimated_bytes`]) exceeds `limits` before anything is allocated.
    pub fn build_within(scene: Scene, limits: &Limits) -> Result<Self, StudyError> {
        limits.check_group(&scene.mesh.group_name())?;
        limits.check_memory(
            format!("scene '{}' ({})", scene.info.name, scene.mesh.describe()),
            scene.estimated_bytes(),
        )?;
        let mut mesh = scene.build_mesh()?;
        let mut warnings = scene.mesh_warnings(&mesh);
        let unusable =
            |e: meshes::MeshError| StudyError::Unsupported(format!("{}: {e}", mesh_key(&scene)));
        let mut topology = mesh.mesh.topology().map_err(unusable)?;
        if orient_up(&mut mesh.mesh, topology.closed) {
            warnings.push(format!(
                "{}: the triangles' normals pointed down (−z); they were turned to point up, so that fluid 'below' is under the membrane and 'above' on it",
                mesh_key(&scene)
            ));
            // Its boundary loops now run the other way round.
            topology = mesh.mesh.topology().map_err(unusable)?;
        }
        let m = &mesh.mesh;
        let parameters: Vec<String> = scene.parameters.keys().cloned().collect();
        let closed = topology.closed;
        let fixed = scene.fixed_nodes(&mesh);
        let sliding: Vec<(usize, Vec3)> = scene
            .sliding_nodes(&mesh)
            .into_iter()
            .map(|(i, n)| (i, Vec3::from(n)))
            .collect();
        let closing = if closed {
            None
        } else {
            closing_face(m, &topology.boundary_loops, &fixed, &sliding)?.map(Arc::new)
        };
        let index = |name: &str| {
            parameters
                .iter()
                .position(|p| p == name)
                .expect("validated parameter")
        };
        let quantity = |q: &scene::Quantity| match q {
            scene::Quantity::Value(v) => Quantity::Value(*v),
            scene::Quantity::Parameter(name) => Quantity::Parameter(index(name)),
        };
        // The fluid held by a fluid-volume constraint with a known target, by effect index:
        // what a gas amount in the same enclosure leaves out of its volume.
        let fluid_amount = |effect: usize| {
            scene.constraints.iter().find_map(|c| match c {
                scene::Constraint::FluidVolume(v) if v.effect == effect => match &v.value {
                    scene::Target::Value(x) => Some(Quantity::Value(*x)),
                    scene::Target::Parameter(n) => Some(Quantity::Parameter(index(n))),
                    scene::Target::Initial => None,
                },
                _ => None,
            })
        };
        // The fluid inside the enclosure, whose amount a gas of fixed amount leaves out.
        let inside_fluid = scene.effects.iter().position(|e| {
            e.get::<scene::FluidEffect>()
                .is_some_and(|f| f.side == scene::FluidSide::Inside)
        });
        let build = Build {
            quantity: &quantity,
            closing: closing.clone(),
            fluid_amount: inside_fluid.and_then(fluid_amount),
        };
        let mat = &scene.material;
        let membrane = Membrane::parametric(
            &m.nodes,
            &m.triangles,
            MaterialQuantities {
                mu: quantity(&mat.mu),
                k: quantity(&mat.k),
                thickness: quantity(&mat.thickness),
                prestretch: quantity(&mat.prestretch),
            },
        )
        .map_err(|e| StudyError::Unsupported(format!("{}: {e}", mesh_key(&scene))))?
        .with_wrinkling(match mat.relaxed_stiffness() {
            Some(stiffness) => membrane::Wrinkling::Relaxed {
                stiffness,
                width: mat.relaxed_width().unwrap_or(0.0),
            },
            None => membrane::Wrinkling::None,
        });
        // The mesh was generated at the radius parameter's start value R0.
        let radius = scene
            .mesh_radius
            .as_ref()
            .map(|q| (quantity(q), scene.start_value(q)));
        // A plate closing the rim off the origin's plane would have to move with the radius.
        let encloses = scene.effects.iter().any(|e| e.spec().measures_enclosure());
        if let (Some(c), Some((Quantity::Parameter(_), _)), true) = (&closing, &radius, encloses) {
            if c.z.abs() > 1e-12 * m.size().max(1e-300) {
                return Err(StudyError::Unsupported(format!(
                    "mesh.radius = \"{}\": the plate closing the rim at z = {} would move with \
                     the radius; give a number, or a rim in the plane z = 0",
                    scene
                        .mesh_radius
                        .as_ref()
                        .and_then(|q| q.parameter())
                        .unwrap_or_default(),
                    c.z
                )));
            }
        }
        let membrane = match radius {
            Some((r, r0)) => membrane.with_reference_radius(r, r0),
            None => membrane,
        };
        let mut effects: Vec<Box<dyn Effect>> = vec![Box::new(membrane)];
        let mut fluids = Vec::new();
        let mut gases = Vec::new();
        for e in &scene.effects {
            let built = e.spec().build(&build);
            match built.measured {
                Some(Measured::FluidVolume(f)) => fluids.push(f),
                Some(Measured::GasPressure(g)) => gases.push(g),
                None => {}
            }
            effects.push(built.effect);
        }
        let held: Vec<Invariant> =
            sliding
                .iter()
                .map(|(_, n)| Invariant::Axis(*n))
                .fold(Vec::new(), |mut acc, k| {
                    if !acc.contains(&k) {
                        acc.push(k);
                    }
                    acc
                });
        let action = scene_action(&mesh, &effects, &held)?;
        let mut constraints: Vec<Box<dyn Constraint>> = Vec::new();
        let mut targets_from_start = Vec::new();
        for c in &scene.constraints {
            let (con, initial): (Box<dyn Constraint>, bool) = match c {
                scene::Constraint::FluidVolume(fv) => {
                    if !closed && closing.is_none() {
                        return Err(StudyError::Unsupported(
                            "a fluid-volume constraint needs a closed membrane, or an open one whose rim is fixed in a horizontal plane (closed by a flat plate)".into(),
                        ));
                    }
                    let fluid = scene.effects[fv.effect]
                        .get::<scene::FluidEffect>()
                        .expect("validated: the constraint names a fluid effect")
                        .fluid(&build);
                    let (target, initial, target_parameter) = target(&fv.value, &index);
                    (
                        Box::new(FluidVolumeConstraint {
                            fluid,
                            level: index(&fv.level),
                            target,
                            target_parameter,
                            closing: closing.clone(),
                        }),
                        initial,
                    )
                }
                scene::Constraint::GasAmount(ga) => {
                    let (target, initial, target_parameter) = target(&ga.value, &index);
                    (
                        Box::new(GasAmountConstraint {
                            pressure: index(&ga.pressure),
                            ambient: ga.ambient_pressure,
                            target,
                            target_parameter,
                            closing: closing.clone(),
                            fluid: build.fluid_amount,
                        }),
                        initial,
                    )
                }
                scene::Constraint::Fixed(_) => continue,
            };
            constraints.push(con);
            targets_from_start.push(initial);
        }
        let control = scene.control().map(index);
        let free: Vec<usize> = control
            .into_iter()
            .chain(constraints.iter().map(|c| c.frees()))
            .collect();
        let start: Vec<f64> = parameters
            .iter()
            .map(|p| scene.parameters[p].start)
            .collect();
        let mesh_volume = if closed { m.volume() } else { 0.0 };
        let prestretch = quantity(&mat.prestretch);
        let mut measures = vec![
            ("max_displacement".to_string(), Measure::MaxDisplacement),
            ("min_z".to_string(), Measure::MinZ),
            ("max_z".to_string(), Measure::MaxZ),
        ];
        if closed {
            measures.push(("volume".into(), Measure::Volume));
            measures.push(("stretch".into(), Measure::Stretch));
        } else if closing.is_some()
            && (inside_fluid.is_some()
                || !gases.is_empty()
                || scene
                    .constraints
                    .iter()
                    .any(|c| matches!(c, scene::Constraint::GasAmount(_))))
        {
            measures.push(("volume".into(), Measure::Volume));
        }
        for i in 0..fluids.len() {
            let name = if fluids.len() == 1 {
                "fluid_volume".to_string()
            } else {
                format!("fluid_volume_{i}")
            };
            measures.push((name, Measure::FluidVolume(i)));
        }
        for i in 0..gases.len() {
            let name = if gases.len() == 1 {
                "gas_pressure".to_string()
            } else {
                format!("gas_pressure_{i}")
            };
            measures.push((name, Measure::GasPressure(i)));
        }
        if mat.relaxed_stiffness().is_some() {
            measures.push(("wrinkled_area".into(), Measure::WrinkledArea));
            measures.push(("slack_area".into(), Measure::SlackArea));
        }
        let model = FeModel::new(
            m.nodes.clone(),
            m.triangles.clone(),
            &fixed,
            effects,
            parameters.clone(),
        )
        .with_sliding(&sliding);
        if model
            .switches(&vec![0.0; model.layout().unknowns()], &start)
            .is_some()
        {
            measures.push(("contact_nodes".into(), Measure::ContactNodes));
        }
        let names: Vec<String> = measures.iter().map(|(n, _)| n.clone()).collect();
        super::check_measure(&scene, &names)
            .map_err(|e| StudyError::Unsupported(format!("{}: {e}", scene.origin)))?;
        // Held nodes scale with the reference radius (docs/theory.md §2.8).
        let model = match radius {
            Some((Quantity::Parameter(p), r0)) if !fixed.is_empty() || !sliding.is_empty() => {
                model.with_scaled_holding(p, r0)
            }
            _ => model,
        };
        let basis = SparseBasis::fixed_point(&action, model.layout());
        if let Some(d) = scene.start.hold_translation {
            // The held translation must be a symmetric displacement.
            let keeps = action.group().elements().iter().all(|r| {
                let v = Vec3::from(d);
                (r * v - v).amax() < 1e-9
            });
            if !keeps {
                return Err(StudyError::Unsupported(format!(
                    "{}: 'start.hold-translation' = [{}, {}, {}]: the scene's group {} moves \
                     that direction, so its symmetric states cannot translate along it",
                    scene.origin,
                    d[0],
                    d[1],
                    d[2],
                    action.group().name()
                )));
            }
        }
        let about = About {
            scene: scene.info.name.clone(),
            origin: scene.origin.clone(),
            mesh: MeshInfo {
                generator: scene.mesh.generator().to_string(),
                nodes: mesh.mesh.nodes.len(),
                elements: mesh.mesh.triangles.len(),
                group: mesh.group().name().to_string(),
                order: mesh.group().order(),
                radius: MeshInfo::radius_of(
                    &mesh
                        .mesh
                        .nodes
                        .iter()
                        .map(|p| [p[0], p[1], p[2]])
                        .collect::<Vec<_>>(),
                    &mesh.mesh.triangles,
                ),
            },
            group: action.group().name().to_string(),
            group_order: action.group().order(),
            unknowns: basis.unknowns(),
            symmetric_unknowns: basis.dim(),
            parameters: parameters.clone(),
            measures: measures.iter().map(|(n, _)| n.clone()).collect(),
        };
        let control_handle = control.map(|c| Control::of(&scene, &parameters, c));
        Ok(Self {
            about,
            control_handle,
            adapted: std::sync::OnceLock::new(),
            scene,
            mesh,
            action,
            model,
            parameters,
            start,
            constraints,
            control,
            free,
            basis,
            measures,
            warnings,
            fluids,
            gases,
            closed,
            closing,
            mesh_volume,
            prestretch,
            radius,
            targets_from_start,
            start_drifted: false,
        })
    }

    /// The measures at displacement `u` and parameters `params`, in the order of
    /// [`MeshStudy::measures`].
    pub fn measure(&self, u: &[f64], params: &[f64]) -> Vec<f64> {
        let x = self.model.positions(u, params);
        let tris = self.model.layout().triangles();
        // The reference is the mesh scaled by R/R0 when the radius is a parameter.
        let scale = self
            .radius
            .as_ref()
            .map_or(1.0, |(r, r0)| r.value(params) / r0);
        let volume = || {
            tris.iter()
                .map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c])))
                .sum::<f64>()
                / 6.0
                + self.closing.as_ref().map_or(0.0, |c| c.volume(tris, &x))
        };
        self.measures
            .iter()
            .map(|(_, m)| match *m {
                Measure::MaxDisplacement => x
                    .iter()
                    .zip(self.model.reference())
                    .map(|(a, b)| (a - b * scale).norm())
                    .fold(0.0, f64::max),
                Measure::MinZ => x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min),
                Measure::MaxZ => x.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max),
                Measure::Volume => volume(),
                Measure::Stretch => {
                    let l0 = self.prestretch.value(params);
                    (volume() * l0.powi(3) / (self.mesh_volume * scale.powi(3))).cbrt()
                }
                Measure::FluidVolume(i) => {
                    let f = &self.fluids[i];
                    let sign = if f.side == FluidSide::Behind {
                        1.0
                    } else {
                        -1.0
                    };
                    let plate = self.closing.as_ref().map_or(0.0, |c| {
                        sign * c.fluid_volume(tris, &x, f.level.value(params), f.filled).0
                    });
                    f.fluid_volume(tris, &x, params) + plate
                }
                Measure::GasPressure(i) => self.gases[i].over_pressure(tris, &x, params),
                Measure::WrinkledArea => self.area_in_state(u, params, &x, 1.0),
                Measure::SlackArea => self.area_in_state(u, params, &x, 2.0),
                Measure::ContactNodes => self
                    .model
                    .switches(u, params)
                    .map_or(0, |on| on.iter().filter(|&&s| s).count())
                    as f64,
            })
            .collect()
    }

    /// The current area of the triangles whose `membrane_state` is `code` (1 wrinkled,
    /// 2 slack), at the positions `x` of (u, Λ); 0 without that field.
    fn area_in_state(&self, u: &[f64], params: &[f64], x: &[Vec3], code: f64) -> f64 {
        let tris = self.model.layout().triangles();
        self.model
            .cell_fields(u, params)
            .into_iter()
            .find(|f| f.quantity == CellQuantity::MembraneState)
            .map_or(0.0, |f| {
                tris.iter()
                    .zip(&f.values)
                    .filter(|(_, &v)| v == code)
                    .map(|(&[a, b, c], _)| 0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])).norm())
                    .fold(0.0, |sum, area| sum + area)
            })
    }

    /// True if the mesh is closed.
    pub fn closed(&self) -> bool {
        self.closed
    }

    /// The warning of a start state accepted at round-off ([`Drift`]): the near-singular
    /// direction (a rigid translation, by the share of the correction a uniform translation
    /// of the nodes carries, or another neutral mode) and what holds it.
    fn drift_warning(&self, drift: &Drift) -> String {
        let mut u = vec![0.0; self.basis.unknowns()];
        self.basis.expand(&drift.correction, &mut u);
        let norm2: f64 = u.iter().map(|v| v * v).sum();
        let nodes = self.model.reference().len();
        let mut t = [0.0; 3];
        for i in 0..nodes {
            for (c, tc) in t.iter_mut().enumerate() {
                if let Some(k) = self.model.layout().dof(i, c) {
                    *tc += u[k] / nodes as f64;
                }
            }
        }
        let t2: f64 = t.iter().map(|v| v * v).sum();
        let direction = if norm2 > 0.0 && t2 * nodes as f64 >= 0.9 * norm2 {
            let n = t2.sqrt();
            let a: Vec<String> = t
                .iter()
                .map(|v| {
                    let r = (v / n * 100.0).round() / 100.0;
                    format!("{}", if r == 0.0 { 0.0 } else { r })
                })
                .collect();
            format!(
                "a rigid translation along [{}], which nothing holds (a free body, or a support it does not touch yet); hold it with [start] hold-translation = [{}] or a support it rests on (a plane it touches, fixed nodes)",
                a.join(", "),
                a.join(", ")
            )
        } else {
            "a neutral mode that is not a rigid translation (a rotation, or a motion no effect stiffens), which nothing holds; hold it with a support (fixed nodes, a plane it touches) or a group that excludes it".to_string()
        };
        format!(
            "the start state was accepted at round-off: its residual is {:.1e} of the force scale, but Newton's correction does not vanish: the tangent is near-singular in {direction}",
            drift.residual
        )
    }

    /// Sets the targets of constraints declared `"initial"` from the state (u, params).
    pub fn set_targets(&mut self, u: &[f64], params: &[f64]) {
        let x = self.model.positions(u, params);
        for (c, &initial) in self.constraints.iter_mut().zip(&self.targets_from_start) {
            if initial {
                c.set_target(c.measure(self.model.layout(), &x, params));
            }
        }
    }

    /// The start displacement: the reference scaled by `start.stretch` about the origin.
    pub fn start_displacement(&self) -> Vec<f64> {
        let s = self.scene.start.stretch - 1.0;
        let mut u = vec![0.0; self.model.layout().unknowns()];
        for (i, x) in self.model.reference().iter().enumerate() {
            for c in 0..3 {
                if let Some(d) = self.model.layout().dof(i, c) {
                    u[d] = s * x[c];
                }
            }
        }
        u
    }
}

/// Largest wave number tried when labelling a critical mode.
const MAX_WAVE_NUMBER: usize = 24;

impl MeshStudy {
    /// The symmetry-adapted basis of the scene's group, built once.
    pub fn adapted(&self) -> Result<&AdaptedBasis, String> {
        self.adapted
            .get_or_init(|| {
                AdaptedBasis::new(&self.action, self.model.layout()).map_err(|e| e.to_string())
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The tangent's spectrum by irrep block at the state (u, Λ): the `lowest` eigenvalues of
    /// every block, stopping between blocks on a signal (`memstab spectrum`, and Python's).
    ///
    /// # Errors
    /// [`SpectrumError::Basis`] when the symmetry-adapted basis cannot be built (bad input);
    /// [`SpectrumError::Tangent`] when the tangent cannot be evaluated there.
    pub fn spectrum_at(
        &self,
        u: &[f64],
        params: &[f64],
        lowest: usize,
    ) -> Result<crate::continuation::crossings::Spectrum, SpectrumError> {
        let adapted = self.adapted().map_err(SpectrumError::Basis)?;
        let stability = Stability::new(&self.model, adapted).interruptible();
        let mut eval = self.model.new_evaluation();
        stability
            .analyse(
                u,
                params,
                &self.constraints,
                &mut eval,
                None,
                crate::stability::Detail::Eigenvalues { lowest },
            )
            .map_err(SpectrumError::Tangent)
    }

    /// The number of wrinkled triangles of the state (u, Λ), or `None` when the model shows
    /// no `wrinkled` field.
    fn wrinkled_triangles(&self, u: &[f64], params: &[f64]) -> Option<usize> {
        self.model
            .cell_fields(u, params)
            .into_iter()
            .find(|f| f.quantity == CellQuantity::Wrinkled)
            .map(|f| f.values.iter().filter(|&&w| w > 0.5).count())
    }

    /// The share of `cp`'s mode (Σ |φ_n|² over nodes) on the nodes of its state's wrinkled
    /// triangles (0 for a point without a mode over the model's unknowns).
    fn mode_in_wrinkled(&self, cp: &CriticalPoint) -> f64 {
        if cp.mode.len() != self.model.layout().unknowns() {
            return 0.0;
        }
        let Some(field) = self
            .model
            .cell_fields(&cp.state, &cp.parameters)
            .into_iter()
            .find(|f| f.quantity == CellQuantity::Wrinkled)
        else {
            return 0.0;
        };
        let mut phi = vec![Vec3::zeros(); self.model.reference().len()];
        self.model.layout().add_displacements(&cp.mode, &mut phi);
        let mut inside = vec![false; phi.len()];
        for (t, &w) in self.mesh().triangles.iter().zip(&field.values) {
            if w > 0.5 {
                for &n in t {
                    inside[n] = true;
                }
            }
        }
        let total: f64 = phi.iter().map(|v| v.norm_squared()).sum();
        let wrinkled: f64 = phi
            .iter()
            .zip(&inside)
            .filter(|(_, &i)| i)
            .map(|(v, _)| v.norm_squared())
            .sum();
        if total > 0.0 {
            wrinkled / total
        } else {
            0.0
        }
    }

    /// The critical points (numbered from 1, as `critical_NN.vtu`) whose state has wrinkled
    /// triangles, with how many; empty when the model shows no `wrinkled` field.
    pub fn wrinkled_critical(&self, critical: &[CriticalPoint]) -> Vec<WrinkledCritical> {
        critical
            .iter()
            .enumerate()
            .filter_map(|(k, cp)| {
                let n = self.wrinkled_triangles(&cp.state, &cp.parameters)?;
                (n > 0).then(|| WrinkledCritical {
                    critical: k + 1,
                    wrinkled: n,
                    mode: self.mode_in_wrinkled(cp),
                })
            })
            .collect()
    }

    /// Where the membrane wrinkles along the path: the first point with wrinkled triangles
    /// (`checks`, from every point's kept state) and the critical points in a wrinkled state;
    /// `None` when the model shows no `wrinkled` field or no point's state was kept (a
    /// branch).
    fn wrinkling(&self, result: &RunResult, checks: &Checks) -> Option<Wrinkling> {
        if checks.rows.is_empty() || checks.rows.len() != result.report.rows.len() {
            return None;
        }
        let mut first = None;
        for (row, check) in result.report.rows.iter().zip(&checks.rows) {
            let n = check.wrinkled?;
            if n > 0 {
                first = Some(WrinkledPoint {
                    step: row.step,
                    wrinkled: n,
                });
                break;
            }
        }
        let critical = self.wrinkled_critical(&result.report.critical);
        Some(Wrinkling {
            triangles: self.mesh.mesh.triangles.len(),
            first,
            critical,
            relaxed: self.scene.material.relaxed_stiffness().is_some(),
            width: self.scene.material.relaxed_width().unwrap_or(0.0),
        })
    }

    /// The wave number m about z of every critical mode, when the mesh has an axis (a disc or
    /// a truncated sphere, as `compare` labels them); empty otherwise.
    pub fn wave_numbers(&self, critical: &[CriticalPoint]) -> Vec<usize> {
        critical
            .iter()
            .map_while(|cp| self.wave_number_of(cp))
            .collect()
    }

    /// The wave number m about z of a critical mode, when the mesh has an axis.
    fn wave_number_of(&self, cp: &CriticalPoint) -> Option<usize> {
        match self.scene.mesh {
            scene::MeshSpec::Disc(_) | scene::MeshSpec::TruncatedSphere(_) => {
                Some(crate::adapted::labels::wave_number(
                    self.model.reference(),
                    self.model.layout(),
                    &cp.mode,
                    MAX_WAVE_NUMBER,
                ))
            }
            _ => None,
        }
    }
}

impl Drawing for MeshStudy {
    fn mesh(&self) -> &meshes::Mesh {
        &self.mesh.mesh
    }

    /// The state's positions and fields: per node the unit normal and what the model's effects
    /// show (the pressure), per triangle what they show (stretches, thickness, tensions, where
    /// the membrane would wrinkle, fluid and contact pressure), and a critical state's mode.
    fn draw(&self, s: &State) -> (Vec<Vec3>, Fields) {
        let finite = |v: &f64| if v.is_finite() { *v } else { 0.0 };
        let x = self.model.positions(&s.u, &s.params);
        let normals = node_normals(&x, &self.mesh.mesh.triangles);
        let fields = self
            .model
            .node_fields(&s.u, &s.params)
            .into_iter()
            .fold(Fields::new().point_vector("normal", normals), |f, n| {
                f.point_scalar(n.quantity.name(), n.values.iter().map(finite))
            });
        let mut fields = self
            .model
            .cell_fields(&s.u, &s.params)
            .into_iter()
            .fold(fields, |f, c| {
                f.cell_scalar(c.quantity.name(), c.values.iter().map(finite))
            });
        for v in self.model.cell_vectors(&s.u, &s.params) {
            let finite3 = |p: &Vec3| -> [f64; 3] {
                if p.iter().all(|c| c.is_finite()) {
                    (*p).into()
                } else {
                    [0.0; 3]
                }
            };
            fields = fields.cell_vector(v.name, v.values.iter().map(finite3));
        }
        if let (StateKind::Critical { .. }, Some(mode)) = (&s.kind, &s.mode) {
            let mut moved = vec![Vec3::zeros(); self.model.reference().len()];
            self.model.layout().add_displacements(mode, &mut moved);
            let field: Vec<[f64; 3]> = moved.iter().map(|&v| v.into()).collect();
            fields = fields.point_vector("critical_mode", field);
        }
        (x, fields)
    }

    fn unknowns(&self) -> usize {
        self.basis.unknowns()
    }

    fn expand(&self, q: &[f64]) -> Vec<f64> {
        let mut u = vec![0.0; self.basis.unknowns()];
        self.basis
            .expand(&nalgebra::DVector::from_column_slice(q), &mut u);
        u
    }
}

impl Study for MeshStudy {
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
        &self.warnings
    }

    fn start_drifted(&self) -> bool {
        self.start_drifted
    }

    fn measure(&self, u: &[f64], params: &[f64]) -> Vec<f64> {
        MeshStudy::measure(self, u, params)
    }

    /// The mesh radius times √nodes, so that a step is an RMS displacement relative to the
    /// mesh size.
    fn state_scale(&self) -> f64 {
        let r = self
            .model
            .reference()
            .iter()
            .map(|x| x.norm())
            .fold(0.0, f64::max)
            .max(1e-300);
        r * (self.model.reference().len() as f64).sqrt()
    }

    fn coordinates(&self, u: &[f64]) -> Vec<f64> {
        self.basis.restrict(u).iter().copied().collect()
    }

    /// The start state, solved in the fixed-point space of the scene's group with every
    /// parameter at `params` and no constraint active, from the reference scaled by
    /// `start.stretch` (or `guess`), with the start homotopy of `[start] hold-translation`;
    /// an inside-out or inadmissible solution is refused.
    fn solve_start(
        &mut self,
        guess: Option<&[f64]>,
        params: &[f64],
        opts: &PathOptions,
    ) -> Result<Point, RunError> {
        let u0 = guess.map_or_else(|| self.start_displacement(), <[f64]>::to_vec);
        let q0 = self.basis.restrict(&u0);
        let study: &Self = self;
        let mut problem = SymmetricProblem::new(
            &study.model,
            &study.basis,
            &[],
            params.to_vec(),
            study.control,
        )
        .holding_neutral();
        let lambda = problem.free_values(params);
        let start_opts = PathOptions {
            max_iterations: opts.max_iterations.max(50),
            ..opts.clone()
        };
        let q0 = match study.scene.start.hold_translation {
            Some(d) => {
                let mut e = vec![0.0; study.basis.unknowns()];
                for i in 0..study.model.reference().len() {
                    for (c, dc) in d.iter().enumerate() {
                        if let Some(k) = study.model.layout().dof(i, c) {
                            e[k] = *dc;
                        }
                    }
                }
                let w = study.basis.restrict(&e);
                crate::continuation::release::released(&mut problem, &q0, &lambda, w, &start_opts)
                    .map_err(|e| RunError::start(study, e))?
                    .0
            }
            None => q0,
        };
        // A state at round-off along a free motion is accepted only when it is the state the
        // path starts from: constraints are added after this solve, and a state they move
        // must converge in the strict sense.
        let (q, lambda, iterations, drift) = if study.constraints.is_empty() {
            solve_at_or_drift(&mut problem, &q0, &lambda, &start_opts)
        } else {
            solve_at(&mut problem, &q0, &lambda, &start_opts).map(|(q, l, i)| (q, l, i, None))
        }
        .map_err(|e| RunError::start(study, e))?;
        let drifted = drift.map(|d| study.drift_warning(&d));
        let params = problem.parameters(&lambda);
        let times = problem.times;
        let mut u = vec![0.0; study.basis.unknowns()];
        study.basis.expand(&q, &mut u);
        // A closed membrane with a negative enclosed volume is inside out (an open one closed
        // by its plate may enclose a negative volume: a disc sagging below its rim).
        if let Some(k) = study
            .measures
            .iter()
            .position(|(_, m)| *m == Measure::Volume)
            .filter(|_| study.closed())
        {
            let volume = study.measure(&u, &params)[k];
            if volume <= 0.0 {
                return Err(RunError::InsideOut { volume });
            }
        }
        if let Some(defect) = study.model.state_defect(&u, &params) {
            return Err(RunError::Degenerate(defect));
        }
        self.start_drifted = drifted.is_some();
        if let Some(w) = drifted {
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
        }
        self.set_targets(&u, &params);
        Ok(Point {
            u,
            params,
            iterations,
            times,
        })
    }

    fn problem(&self, params: &[f64], free: &Free) -> Box<dyn Followed + '_> {
        let constraints: &[Box<dyn crate::model::constraint::Constraint>] = if free.constraints {
            &self.constraints
        } else {
            &[]
        };
        let mut problem = SymmetricProblem::new(
            &self.model,
            &self.basis,
            constraints,
            params.to_vec(),
            free.control,
        );
        for &p in &free.also {
            problem = problem.with_free_parameter(p);
        }
        if free.hold_neutral {
            problem = problem.holding_neutral();
        }
        Box::new(problem)
    }

    fn blocks(&self) -> Result<Box<dyn Blocks + '_>, String> {
        let adapted = self.adapted()?;
        Ok(Box::new(IrrepBlocks::new(
            Stability::new(&self.model, adapted),
            &self.model,
            &self.constraints,
            &self.action,
        )))
    }

    fn critical_test(&self, cp: &CriticalPoint) -> Result<Box<dyn CriticalTest + '_>, String> {
        let adapted = self.adapted()?;
        let mu = adapted
            .irreps
            .iter()
            .position(|ib| ib.name == cp.irrep)
            .ok_or_else(|| format!("{} has no irrep {}", self.about.group, cp.irrep))?;
        let block = adapted.irreps[mu].first();
        let x = self.model.positions(&cp.state, &cp.parameters);
        let rigid = self
            .model
            .rigid_motions()
            .iter()
            .any(|m| block.restrict_rigid(m, &x, self.model.layout()).amax() > 1e-9);
        if rigid {
            return Err(format!(
                "the block of {} holds rigid-body modes; following its critical points is not \
                 supported yet",
                cp.irrep
            ));
        }
        let length = self
            .model
            .reference()
            .iter()
            .map(|x| x.norm())
            .fold(0.0, f64::max)
            .max(1e-300);
        let border = block.restrict(&cp.mode);
        let test = BlockTest::new(&self.model, block, &self.basis, mu == 0, &border, length)
            .with_constraints(&self.constraints, &cp.state, &cp.parameters)
            .map_err(|e| format!("the critical point's constraints: {e}"))?;
        Ok(Box::new(test))
    }

    fn branches(
        &self,
        critical: &[CriticalPoint],
        options: BranchOptions,
    ) -> Result<Branches, String> {
        Ok(super::switching::run(self, critical, options))
    }

    fn recorded(
        &self,
        recorded: &[RecordedPoint],
        n: usize,
        state: Vec<f64>,
        mode: Vec<f64>,
    ) -> Result<Vec<CriticalPoint>, String> {
        super::switching::recorded_points(self, recorded, n, state, mode)
    }

    fn wrinkled(&self, u: &[f64], params: &[f64]) -> Option<usize> {
        self.wrinkled_triangles(u, params)
    }

    /// Its wrinkled triangles and largest principal stretch, from its cell fields.
    fn state_check(&self, u: &[f64], params: &[f64]) -> StateCheck {
        if u.len() != self.model.layout().unknowns() {
            return StateCheck::default();
        }
        let fields = self.model.cell_fields(u, params);
        let field = |q: CellQuantity| fields.iter().find(|f| f.quantity == q);
        StateCheck {
            wrinkled: field(CellQuantity::Wrinkled)
                .map(|f| f.values.iter().filter(|&&w| w > 0.5).count()),
            stretch: field(CellQuantity::Stretch1)
                .map(|f| f.values.iter().copied().fold(f64::NEG_INFINITY, f64::max))
                .filter(|s| s.is_finite()),
            contact: None,
        }
    }

    /// Each node's deepest penetration of the contact effects, and the mean edge length of
    /// the deformed triangles.
    fn penetrations(&self, u: &[f64], params: &[f64]) -> Option<(Vec<f64>, f64)> {
        if u.len() != self.model.layout().unknowns() {
            return None;
        }
        let (at, x) = self.model.penetrations(u, params)?;
        let triangles = &self.mesh().triangles;
        let edges: f64 = triangles
            .iter()
            .map(|&[a, b, c]| (x[b] - x[a]).norm() + (x[c] - x[b]).norm() + (x[a] - x[c]).norm())
            .sum();
        Some((at, edges / (3 * triangles.len().max(1)) as f64))
    }

    fn wave_number(&self, cp: &CriticalPoint) -> Option<usize> {
        self.wave_number_of(cp)
    }

    fn annotate(&self, result: &mut RunResult) {
        let checks = super::checks::checks(self, result);
        result.report.wrinkling = self.wrinkling(result, &checks);
        result.report.wave_numbers = self.wave_numbers(&result.report.critical);
        result.report.checks = Some(checks);
    }
}

/// Turns an open mesh whose normals point down on the whole (a negative projected area
/// Σ_T A_T·ẑ, which only its boundary determines) to point up — the orientation in which
/// fluid "below" and "above" and the closing plate are defined; true if it did. A closed mesh
/// (outward by construction; `closed`, from its topology) and one whose boundary projects to
/// no area are left as they are.
fn orient_up(m: &mut meshes::Mesh, closed: bool) -> bool {
    if closed {
        return false;
    }
    let projected: f64 = (0..m.triangles.len()).map(|t| m.area_vector(t).z).sum();
    if projected < -1e-9 * m.area() {
        m.reverse_orientation();
        return true;
    }
    false
}

/// The mesh's action restricted to the elements that map the set of effects onto itself
/// ([`crate::model::scene_elements`]). When those are exactly the elements keeping every
/// effect's own invariants, the stabiliser of those invariants names and orders the subgroup
/// (as it always has); otherwise (two planes a mirror swaps) the subgroup is built from its
/// elements, its axis oriented along the first invariant of an effect without a placement
/// (gravity's −z), else with a positive z component.
fn scene_action(
    mesh: &SymmetricMesh,
    effects: &[Box<dyn Effect>],
    held: &[Invariant],
) -> Result<GroupAction, StudyError> {
    let unsupported =
        |e: String| StudyError::Unsupported(format!("the scene's symmetry group: {e}"));
    let group = mesh.action.group();
    let keep: Vec<_> = effects
        .iter()
        .flat_map(|e| e.keeps())
        .chain(held.iter().copied())
        .collect();
    let members: Vec<usize> = crate::model::scene_elements(group, effects)
        .into_iter()
        .filter(|&g| held.iter().all(|k| k.kept_by(group.element(g))))
        .collect();
    let alone: Vec<usize> = (0..group.order())
        .filter(|&g| keep.iter().all(|k| k.kept_by(group.element(g))))
        .collect();
    if members == alone {
        return mesh
            .action
            .restrict(&keep)
            .map_err(|e| unsupported(e.to_string()));
    }
    let hint = effects
        .iter()
        .filter(|e| e.placement().is_none())
        .flat_map(|e| e.keeps())
        .chain(held.iter().copied())
        .next();
    let sub = match hint {
        Some(k) => group.subgroup_along(&members, k.direction()),
        None => group.subgroup(&members),
    }
    .map_err(|e| unsupported(e.to_string()))?;
    mesh.action
        .restrict_to(&sub)
        .map_err(|e| unsupported(e.to_string()))
}

/// The flat plate closing an open membrane: every boundary loop in one horizontal plane, its
/// nodes fixed or sliding in that plane (normal ±z). A sliding rim in another plane cannot be
/// closed by a horizontal plate: with an enclosure that is an error.
fn closing_face(
    m: &meshes::Mesh,
    loops: &[Vec<usize>],
    fixed: &[usize],
    sliding: &[(usize, Vec3)],
) -> Result<Option<ClosingFace>, StudyError> {
    let Some(&first) = loops.first().and_then(|l| l.first()) else {
        return Ok(None);
    };
    let z = m.nodes[first].z;
    let tol = 1e-12 * m.size().max(1e-300);
    for &i in loops.iter().flatten() {
        let slides = sliding.iter().find(|(j, _)| *j == i).map(|(_, n)| *n);
        if let Some(n) = slides {
            if n.x.abs() > 1e-12 || n.y.abs() > 1e-12 {
                return Ok(None);
            }
        } else if fixed.binary_search(&i).is_err() {
            return Ok(None);
        }
        if (m.nodes[i].z - z).abs() > tol {
            return Ok(None);
        }
    }
    Ok(Some(ClosingFace::new(z, &m.triangles)))
}

/// The held value of a constraint: (number, measured at the start, parameter index).
fn target(t: &scene::Target, index: &dyn Fn(&str) -> usize) -> (f64, bool, Option<usize>) {
    match t {
        scene::Target::Initial => (0.0, true, None),
        scene::Target::Value(v) => (*v, false, None),
        scene::Target::Parameter(name) => (0.0, false, Some(index(name))),
    }
}

/// How a message about the mesh names it: the file and its key for a mesh file, else the
/// generator.
fn mesh_key(scene: &Scene) -> String {
    match &scene.mesh {
        scene::MeshSpec::File(f) => format!("'mesh.path' = \"{}\"", f.path.display()),
        other => format!("mesh ({})", other.generator()),
    }
}
