//! A scene made ready to solve: scene → mesh + group → effects → model (docs/architecture.md).
//!
//! Only the effects the scene lists are built. The scene's group is the mesh group restricted
//! to what every effect keeps (computed from [`crate::model::Effect::keeps`], never typed in),
//! and the path is followed in that group's fixed-point space.

use crate::adapted::SparseBasis;
use crate::effects::gas::{GasAmount, GasAmountConstraint, GasPressure};
use crate::effects::hydrostatic::{Fluid, FluidSide, FluidVolumeConstraint};
use crate::effects::membrane::{MaterialQuantities, Membrane};
use crate::effects::plane::{PenaltyLaw, Plane};
use crate::effects::spin::Spin;
use crate::effects::volume::ClosingFace;
use crate::effects::Quantity;
use crate::limits::Limits;
use crate::model::constraint::Constraint;
use crate::model::{Effect, FeModel, Model, Vec3};
use crate::scene::{self, Scene};
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

/// A critical point of a finished run, read back: where a critical curve starts with
/// `analysis.from-run`.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedCritical {
    /// Its number in the run (1-based: `critical_NN.vtu`).
    pub number: usize,
    /// The irrep of its singular block.
    pub irrep: String,
    /// Every parameter there.
    pub parameters: Vec<f64>,
    /// Every measure there, as the run recorded them.
    pub measures: Vec<f64>,
    /// Its localised eigenvalue relative to ‖K‖, as the run recorded it.
    pub residual_eigenvalue: f64,
    /// The state over the unknowns.
    pub state: Vec<f64>,
    /// The critical mode over the unknowns (unit norm).
    pub mode: Vec<f64>,
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
}

/// A scene ready to solve.
pub struct Study {
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
    /// Augmenting equations, in scene order (targets set by [`Study::set_targets`]).
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
    /// The critical point of a finished run a critical curve starts from (`analysis.from-run`),
    /// once loaded (`output::reopen::load_curve_start`).
    pub saved_critical: Option<SavedCritical>,
    /// The saved state of `[start] from`, once loaded (`output::store::load_start`): the first
    /// guess of the start solve instead of `start.stretch · X`.
    pub saved_start: Option<Vec<f64>>,
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
}

fn side(s: scene::FluidSide) -> FluidSide {
    match s {
        // Open meshes are oriented with their normals up (`orient_up`): fluid below is
        // behind them.
        scene::FluidSide::Inside | scene::FluidSide::Below => FluidSide::Behind,
        scene::FluidSide::Above => FluidSide::Front,
    }
}

impl Study {
    /// Builds mesh, effects, model, constraints and basis from a validated scene.
    pub fn build(scene: Scene) -> Result<Self, StudyError> {
        let limits = Limits::from_env()?;
        Self::build_within(scene, &limits)
    }

    /// As [`Study::build`], refusing a scene whose group or estimated memory
    /// ([`Scene::estimated_bytes`]) exceeds `limits` before anything is allocated.
    pub fn build_within(scene: Scene, limits: &Limits) -> Result<Self, StudyError> {
        limits.check_group(&scene.mesh.group_name())?;
        limits.check_memory(
            format!("scene '{}' ({})", scene.info.name, scene.mesh.describe()),
            scene.estimated_bytes(),
        )?;
        let mut mesh = scene.build_mesh()?;
        let mut warnings = scene.mesh_warnings(&mesh);
        if orient_up(&mut mesh.mesh) {
            warnings.push(format!(
                "{}: the triangles' normals pointed down (−z); they were turned to point up, so that fluid 'below' is under the membrane and 'above' on it",
                mesh_key(&scene)
            ));
        }
        let m = &mesh.mesh;
        let parameters: Vec<String> = scene.parameters.keys().cloned().collect();
        let topology = m
            .topology()
            .map_err(|e| StudyError::Unsupported(format!("{}: {e}", mesh_key(&scene))))?;
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
        let inside_fluid = scene.effects.iter().position(
            |e| matches!(e, scene::Effect::Fluid(f) if f.side == scene::FluidSide::Inside),
        );
        let gas_fluid = inside_fluid.and_then(fluid_amount);
        let fluid_of = |f: &scene::FluidEffect| {
            let side = side(f.side);
            Fluid {
                density: quantity(&f.density),
                gravity: quantity(&f.gravity),
                level: quantity(&f.level),
                side,
                filled: f.filled,
                closing: closing
                    .clone()
                    .filter(|_| f.side == scene::FluidSide::Inside),
            }
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
        .map_err(|e| StudyError::Unsupported(format!("{}: {e}", mesh_key(&scene))))?;
        // The mesh was generated at the radius parameter's start value R0.
        let radius = scene
            .mesh_radius
            .as_ref()
            .map(|q| (quantity(q), scene.start_value(q)));
        // A plate closing the rim off the origin's plane would have to move with the radius.
        let encloses = scene.effects.iter().any(|e| match e {
            scene::Effect::Gas(_) | scene::Effect::GasAmount(_) | scene::Effect::Fluid(_) => true,
            scene::Effect::Spin(_) | scene::Effect::Plane(_) => false,
        });
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
            effects.push(match e {
                scene::Effect::Gas(g) => Box::new(GasPressure {
                    pressure: quantity(&g.pressure),
                    closing: closing.clone(),
                }),
                scene::Effect::GasAmount(g) => {
                    let gas = GasAmount {
                        amount: quantity(&g.amount),
                        ambient: g.ambient_pressure,
                        closing: closing.clone(),
                        fluid: gas_fluid,
                    };
                    gases.push(gas.clone());
                    Box::new(gas)
                }
                scene::Effect::Fluid(f) => {
                    let fluid = fluid_of(f);
                    fluids.push(fluid.clone());
                    Box::new(fluid)
                }
                scene::Effect::Spin(s) => Box::new(Spin {
                    density: quantity(&s.density),
                    omega2: quantity(&s.omega2),
                    side: FluidSide::Behind,
                }),
                scene::Effect::Plane(p) => Box::new(Plane {
                    normal: Vec3::from(p.normal),
                    offset: quantity(&p.offset),
                    penalty: quantity(&p.penalty),
                    law: if p.exponent == 3 {
                        PenaltyLaw::Cubic
                    } else {
                        PenaltyLaw::Linear
                    },
                }),
            });
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
                    let fluid = match &scene.effects[fv.effect] {
                        scene::Effect::Fluid(f) => fluid_of(f),
                        _ => unreachable!("validated: the constraint names a fluid effect"),
                    };
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
                            fluid: gas_fluid,
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
        if let scene::Analysis::Surface(a) = &scene.analysis {
            if let Some(name) = &a.measure {
                if !measures.iter().any(|(n, _)| n == name) {
                    let names: Vec<&str> = measures.iter().map(|(n, _)| n.as_str()).collect();
                    return Err(StudyError::Unsupported(format!(
                        "{}: 'analysis.measure' = \"{name}\": not a measure of this scene \
                         (it has {})",
                        scene.origin,
                        names.join(", ")
                    )));
                }
            }
        }
        let model = FeModel::new(
            m.nodes.clone(),
            m.triangles.clone(),
            &fixed,
            effects,
            parameters.clone(),
        )
        .with_sliding(&sliding);
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
        Ok(Self {
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
            saved_start: None,
            saved_critical: None,
            fluids,
            gases,
            closed,
            closing,
            mesh_volume,
            prestretch,
            radius,
            targets_from_start,
        })
    }

    /// The measures at displacement `u` and parameters `params`, in the order of
    /// [`Study::measures`].
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
            })
            .collect()
    }

    /// True if the mesh is closed.
    pub fn closed(&self) -> bool {
        self.closed
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

    /// The start displacement: a loaded saved state ([`Study::saved_start`]), else the
    /// reference scaled by `start.stretch` about the origin.
    pub fn start_displacement(&self) -> Vec<f64> {
        if let Some(u) = &self.saved_start {
            return u.clone();
        }
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

/// Turns an open mesh whose normals point down on the whole (a negative projected area
/// Σ_T A_T·ẑ, which only its boundary determines) to point up — the orientation in which
/// fluid "below" and "above" and the closing plate are defined; true if it did. A closed mesh
/// (outward by construction) and one whose boundary projects to no area are left as they are.
fn orient_up(m: &mut meshes::Mesh) -> bool {
    if m.topology().is_ok_and(|t| t.closed) {
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
