//! A scene made ready to solve: scene → mesh + group → effects → model (docs/architecture.md).
//!
//! Only the effects the scene lists are built. The scene's group is the mesh group restricted
//! to what every effect keeps (computed from [`crate::model::Effect::keeps`], never typed in),
//! and the path is followed in that group's fixed-point space.

use crate::adapted::SparseBasis;
use crate::effects::gas::{GasAmount, GasAmountConstraint, GasPressure};
use crate::effects::hydrostatic::{Fluid, FluidSide, FluidVolumeConstraint};
use crate::effects::membrane::{Membrane, MooneyRivlin};
use crate::effects::plane::{PenaltyLaw, Plane};
use crate::effects::spin::Spin;
use crate::effects::volume::ClosingFace;
use crate::effects::Quantity;
use crate::limits::Limits;
use crate::model::constraint::Constraint;
use crate::model::{Effect, FeModel, Model, Vec3};
use crate::scene::{self, Scene};
use meshes::{GroupAction, SymmetricMesh};

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
    fluids: Vec<Fluid>,
    closed: bool,
    closing: Option<ClosingFace>,
    stress_free_volume: f64,
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
        let closing = if closed {
            None
        } else {
            closing_face(m, &topology.boundary_loops, &fixed)
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
        let mat = &scene.material;
        let membrane = Membrane::new(
            &m.nodes,
            &m.triangles,
            MooneyRivlin::new(mat.mu, mat.k, mat.thickness),
            mat.prestretch,
        )
        .map_err(|e| StudyError::Unsupported(format!("{}: {e}", mesh_key(&scene))))?;
        let mut effects: Vec<Box<dyn Effect>> = vec![Box::new(membrane)];
        let mut fluids = Vec::new();
        for e in &scene.effects {
            effects.push(match e {
                scene::Effect::Gas(g) => Box::new(GasPressure {
                    pressure: quantity(&g.pressure),
                }),
                scene::Effect::GasAmount(g) => Box::new(GasAmount {
                    amount: quantity(&g.amount),
                    ambient: g.ambient_pressure,
                    closing_volume: closing.map_or(0.0, |c| c.volume()),
                }),
                scene::Effect::Fluid(f) => {
                    let fluid = Fluid {
                        density: quantity(&f.density),
                        gravity: f.gravity,
                        level: quantity(&f.level),
                        side: side(f.side),
                    };
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
                    penalty: p.penalty,
                    law: if p.exponent == 3 {
                        PenaltyLaw::Cubic
                    } else {
                        PenaltyLaw::Linear
                    },
                }),
            });
        }
        let keep: Vec<_> = effects.iter().flat_map(|e| e.keeps()).collect();
        let action = mesh
            .action
            .restrict(&keep)
            .map_err(|e| StudyError::Unsupported(format!("the scene's symmetry group: {e}")))?;
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
                        scene::Effect::Fluid(f) => Fluid {
                            density: quantity(&f.density),
                            gravity: f.gravity,
                            level: quantity(&f.level),
                            side: side(f.side),
                        },
                        _ => unreachable!("validated: the constraint names a fluid effect"),
                    };
                    let (target, initial) = target(&fv.value);
                    (
                        Box::new(FluidVolumeConstraint {
                            fluid,
                            level: index(&fv.level),
                            target,
                            closing,
                        }),
                        initial,
                    )
                }
                scene::Constraint::GasAmount(ga) => {
                    let (target, initial) = target(&ga.value);
                    (
                        Box::new(GasAmountConstraint {
                            pressure: index(&ga.pressure),
                            ambient: ga.ambient_pressure,
                            target,
                            closing_volume: closing.map_or(0.0, |c| c.volume()),
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
        let stress_free_volume = if closed {
            m.volume() / mat.prestretch.powi(3)
        } else {
            0.0
        };
        let mut measures = vec![
            ("max_displacement".to_string(), Measure::MaxDisplacement),
            ("min_z".to_string(), Measure::MinZ),
            ("max_z".to_string(), Measure::MaxZ),
        ];
        if closed {
            measures.push(("volume".into(), Measure::Volume));
            measures.push(("stretch".into(), Measure::Stretch));
        }
        for i in 0..fluids.len() {
            let name = if fluids.len() == 1 {
                "fluid_volume".to_string()
            } else {
                format!("fluid_volume_{i}")
            };
            measures.push((name, Measure::FluidVolume(i)));
        }
        let model = FeModel::new(
            m.nodes.clone(),
            m.triangles.clone(),
            &fixed,
            effects,
            parameters.clone(),
        );
        let basis = SparseBasis::fixed_point(&action, model.layout());
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
            fluids,
            closed,
            closing,
            stress_free_volume,
            targets_from_start,
        })
    }

    /// The measures at displacement `u` and parameters `params`, in the order of
    /// [`Study::measures`].
    pub fn measure(&self, u: &[f64], params: &[f64]) -> Vec<f64> {
        let x = self.model.positions(u);
        let tris = self.model.layout().triangles();
        let volume = || {
            tris.iter()
                .map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c])))
                .sum::<f64>()
                / 6.0
        };
        self.measures
            .iter()
            .map(|(_, m)| match *m {
                Measure::MaxDisplacement => x
                    .iter()
                    .zip(self.model.reference())
                    .map(|(a, b)| (a - b).norm())
                    .fold(0.0, f64::max),
                Measure::MinZ => x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min),
                Measure::MaxZ => x.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max),
                Measure::Volume => volume(),
                Measure::Stretch => (volume() / self.stress_free_volume).cbrt(),
                Measure::FluidVolume(i) => {
                    let f = &self.fluids[i];
                    let sign = if f.side == FluidSide::Behind {
                        1.0
                    } else {
                        -1.0
                    };
                    let plate = self
                        .closing
                        .map_or(0.0, |c| sign * c.fluid_volume(f.level.value(params)).0);
                    f.fluid_volume(tris, &x, params) + plate
                }
            })
            .collect()
    }

    /// True if the mesh is closed.
    pub fn closed(&self) -> bool {
        self.closed
    }

    /// Sets the targets of constraints declared `"initial"` from the state (u, params).
    pub fn set_targets(&mut self, u: &[f64], params: &[f64]) {
        let x = self.model.positions(u);
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

/// The flat plate closing an open membrane: every boundary loop fixed and in one horizontal
/// plane. Its area vector is minus that of the loops as they run in the triangles, so that it
/// is oriented like the membrane (outward for the closed body).
fn closing_face(m: &meshes::Mesh, loops: &[Vec<usize>], fixed: &[usize]) -> Option<ClosingFace> {
    let first = *loops.first()?.first()?;
    let z = m.nodes[first].z;
    let tol = 1e-12 * m.size().max(1e-300);
    let mut area_z = 0.0;
    for lp in loops {
        for (k, &i) in lp.iter().enumerate() {
            if fixed.binary_search(&i).is_err() || (m.nodes[i].z - z).abs() > tol {
                return None;
            }
            let j = lp[(k + 1) % lp.len()];
            let (a, b) = (m.nodes[i], m.nodes[j]);
            area_z -= 0.5 * (a.x * b.y - a.y * b.x);
        }
    }
    Some(ClosingFace { z, area_z })
}

fn target(t: &scene::Target) -> (f64, bool) {
    match *t {
        scene::Target::Initial => (0.0, true),
        scene::Target::Value(v) => (v, false),
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
