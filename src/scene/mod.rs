//! Scene files: what to compute, in one TOML file.
//!
//! A scene names the mesh (a generator and its options), the membrane's material, the loads
//! (*effects*, each a potential — docs/theory.md §1), the fixed node sets, the load parameters with
//! their start values and bounds, the augmenting constraints, the analysis and how it starts.
//! The format, with every key, its default and its validation rule, is documented in
//! `docs/scenes.md`; the types below mirror it one to one (a TOML key `cut-height` is the
//! field `cut_height`).
//!
//! Loading ([`Scene::from_toml_str`], [`Scene::load`]) parses and checks everything that does
//! not need the mesh; [`Scene::build_mesh`] builds the mesh and checks the rest (boundary
//! names, closed or clamped membranes for the enclosing effects). Every failure is a
//! [`SceneError`], one line naming the key path and the value.
//!
//! After a successful load the scene is *consistent*: every parameter name used by an effect
//! or a constraint is declared, every declared parameter is used by an effect, and (for a
//! path) every parameter other than the control is governed by exactly one constraint.
//!
//! # Conventions the consumer relies on
//! - Units are consistent but otherwise free; `μ·H` (material `mu` × `thickness`) is the
//!   natural tension scale and `μH/R` the natural pressure scale (R a mesh radius).
//! - Gravity acts along −z; a plane's [`PlaneEffect::normal`] is a unit vector (normalised
//!   on loading) pointing to the side where the membrane may be (`n·x ≥ d`).
//! - Indices in key paths and in [`FluidVolumeConstraint::effect`] count from 0 in the
//!   order of the `[[effect]]` tables.
//! - The mesh is the *reference* configuration X; the stress-free state is X/λ0 with λ0 =
//!   [`Material::prestretch`]; the first Newton guess is `start.stretch · X` (see [`Start`]).

pub mod analyses;
mod error;
mod load;
mod tags;
mod validate;

pub use crate::effects::gas::{GasAmountEffect, GasEffect};
pub use crate::effects::hydrostatic::{FluidEffect, Side as FluidSide};
pub use crate::effects::plane::PlaneEffect;
pub use crate::effects::spec::{EffectSpec, Quantity, Range};
pub use crate::effects::spin::SpinEffect;
pub use analyses::{
    analysis_types, Analysis, AnalysisSpec, BranchesAnalysis, CriticalCurveAnalysis, CurveStart,
    CuspCurveAnalysis, DiagramAnalysis, EquilibriumAnalysis, LinearBucklingAnalysis, PathAnalysis,
    SurfaceAnalysis, MAX_BRANCH_DEPTH,
};
pub use error::{Problem, SceneError};
pub use tags::{ConstraintKind, Generator};

use meshes::generators::{self, DiscOptions, Down, IcosphereOptions, TruncatedSphereOptions};
use meshes::{MeshError, SymmetricMesh};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use symmetry::Group;

/// A validated scene. Build the mesh with [`Scene::build_mesh`], which checks the parts of
/// the scene that refer to it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Where the scene came from (a file name or a label); used in error messages.
    #[serde(skip)]
    pub origin: String,
    /// `[scene]`: name and description.
    #[serde(rename = "scene")]
    pub info: SceneInfo,
    /// `[mesh]`: the generator and its options.
    pub mesh: MeshSpec,
    /// `[mesh] radius = "R"`: the parameter the reference radius follows, if it is one. The
    /// mesh is generated once at the parameter's start value R0 (which `mesh`'s radius then
    /// holds) and the model scales the reference by R/R0 (docs/theory.md §2.8).
    #[serde(skip)]
    pub mesh_radius: Option<Quantity>,
    /// `[material]`: the membrane (always present; it is the first effect).
    pub material: Material,
    /// `[[effect]]`: the loads, in file order (indices count from 0).
    #[serde(rename = "effect", skip_serializing_if = "Vec::is_empty")]
    pub effects: Vec<Effect>,
    /// `[boundary]`: fixed node sets.
    pub boundary: Boundary,
    /// `[parameters.NAME]`: the load parameters Λ, by name (sorted by name).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, Parameter>,
    /// `[[constraint]]`: the augmenting equations, in file order.
    #[serde(rename = "constraint", skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<Constraint>,
    /// `[analysis]`: what to compute.
    pub analysis: Analysis,
    /// `[start]`: how the first state is found.
    pub start: Start,
    /// `[refine]`: the run again on refined meshes, as `memstab run --refine` (the flag
    /// overrides it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine: Option<Refine>,
}

/// `[refine]`: every critical and turning point of a run followed on the mesh at twice (and
/// four times) its resolution, with its error estimate (docs/theory.md §8.11); what `memstab
/// run --refine [N] [--continuum]` asks for, which overrides it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Refine {
    /// Refinements: 1 (the resolution doubled) or 2 (doubled and quadrupled). Default 1.
    #[serde(default = "one_level")]
    pub levels: usize,
    /// Also run the scene's meridian. Default false.
    #[serde(default)]
    pub continuum: bool,
}

fn one_level() -> usize {
    1
}

/// `[scene]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SceneInfo {
    /// A short name (non-empty), used in output metadata.
    pub name: String,
    /// Free text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
}

/// `[mesh]`, tagged by `generator`. Options not given take the generators' defaults (the
/// same as `memstab mesh`); `generator = "file"` reads the mesh from a file instead.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "generator", rename_all = "kebab-case")]
pub enum MeshSpec {
    /// `generator = "disc"`: a flat disc in z = 0, normal +z, node set `rim`.
    Disc(DiscMesh),
    /// `generator = "icosphere"`: a closed sphere, outward normals, no node sets.
    Icosphere(IcosphereMesh),
    /// `generator = "truncated-sphere"`: the cap z ≥ cut-height, outward normals, node set
    /// `cut`.
    TruncatedSphere(TruncatedSphereMesh),
    /// `generator = "file"`: a mesh file (`.msh`, `.vtu`, as `memstab mesh --out` writes
    /// them) with its node sets, declared to have the symmetry `group`.
    File(FileMesh),
    /// `generator = "axisymmetric"`: a meridian of quadratic elements, the surface of
    /// revolution `shape` (disc: node set `rim`; truncated sphere: `cut`; sphere: none), run
    /// by the axisymmetric model with stability by wave number (docs/theory.md §15).
    Axisymmetric(AxisymmetricMesh),
}

/// The surface of revolution of an axisymmetric mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AxisymShape {
    /// The disc of radius `radius` in z = 0, normal +z, node set `rim` at its edge.
    Disc,
    /// The cap z ≥ `cut-height` of the sphere of radius `radius`, outward normal, node set
    /// `cut`.
    TruncatedSphere,
    /// The sphere of radius `radius`, outward normal, no node sets.
    Sphere,
}

/// Options of the axisymmetric generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct AxisymmetricMesh {
    /// The surface. Default `disc`.
    #[serde(default = "default_axisym_shape")]
    pub shape: AxisymShape,
    /// Radius of the disc or the sphere. Default 1.
    #[serde(default = "one")]
    pub radius: f64,
    /// Height c of a truncated sphere's cut, −R < c < R. Default −0.5.
    #[serde(default = "default_cut_height")]
    pub cut_height: f64,
    /// Quadratic elements along the meridian, 1..=4096. Default 64.
    #[serde(default = "default_axisym_elements")]
    pub elements: usize,
    /// The largest wave number M of the stability analysis (blocks m = 0..=M), ≤ 200.
    /// Default 20.
    #[serde(default = "default_axisym_modes")]
    pub modes: usize,
}

/// Options of the disc generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct DiscMesh {
    /// Radius of the mesh (the clamped radius λ0·a of a pre-stretched disc). Default 1.
    #[serde(default = "one")]
    pub radius: f64,
    /// Number of sectors N ≥ 3. Default 7.
    #[serde(default = "default_sectors")]
    pub sectors: usize,
    /// Rings per sector d ≥ 1 (N d² triangles). Default 16.
    #[serde(default = "default_disc_divisions")]
    pub divisions: usize,
    /// Declared group `C<M>v` or `C<M>` with M | N; default `C<N>v`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
}

/// Options of the icosphere generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct IcosphereMesh {
    /// Radius R. Default 1.
    #[serde(default = "one")]
    pub radius: f64,
    /// Frequency f ≥ 1 (20 f² triangles). Default 4.
    #[serde(default = "default_frequency")]
    pub frequency: usize,
    /// What points down (−z); default: the standard orientation (group Ih, coordinate axes
    /// 2-fold).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub down: Option<DownSpec>,
}

/// `mesh.down` of an icosphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DownSpec {
    /// A vertex points down (a scene that keeps −z keeps C5v).
    Vertex,
    /// A face centre points down (C3v).
    Face,
    /// An edge midpoint points down (C2v).
    Edge,
}

/// Options of the truncated-sphere generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct TruncatedSphereMesh {
    /// Radius R. Default 1.
    #[serde(default = "one")]
    pub radius: f64,
    /// Height c of the cut plane, −R < c < R. Default −0.5.
    #[serde(default = "default_cut_height")]
    pub cut_height: f64,
    /// Declared group about z (`C8v`, `C2v`, `C1v`, …). Default `C8v`.
    #[serde(default = "default_pattern")]
    pub pattern: String,
    /// Rings between pole and cut (8 d² triangles); default: about the reference element
    /// count of the pattern (d = 29 for C8v, 26 for C2v and C1v).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub divisions: Option<usize>,
}

/// Options of a mesh read from a file ([`meshes::read::read_mesh`]).
///
/// A file carries no group, so the scene declares one; building the mesh computes the group's
/// action on the nodes and verifies it (a group that does not map the mesh onto itself is an
/// error naming `mesh.group`), and symmetry the mesh has beyond it is reported by
/// [`Scene::mesh_warnings`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FileMesh {
    /// The mesh file; the extension chooses the reader (`.msh` Gmsh 4.1 ascii, `.vtu`).
    /// [`Scene::load`] resolves a relative path against the scene file's directory (so after
    /// loading it is the path to open); [`Scene::from_toml_str`] keeps it as written, relative
    /// to the current directory.
    pub path: PathBuf,
    /// The declared symmetry group, a name [`Group::by_name`] accepts (`C8v`, `C4`, `Ih`, …),
    /// acting in the mesh's own coordinates. Default `C1`, the trivial group.
    #[serde(default = "default_file_group")]
    pub group: String,
}

/// `[material]`: an incompressible Mooney–Rivlin membrane,
/// W = c1(I1 − 3) + c2(I2 − 3), μ/2 = c1 + c2, k = c2/c1 (docs/theory.md §2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Material {
    /// The constitutive model; default and only choice `mooney-rivlin`.
    #[serde(default)]
    pub model: MaterialModel,
    /// Shear modulus μ > 0 (a number or a parameter).
    pub mu: Quantity,
    /// Mooney–Rivlin ratio k = c2/c1 ≥ 0 (0: neo-Hookean; a number or a parameter).
    pub k: Quantity,
    /// Thickness H > 0 of the stress-free membrane (a number or a parameter).
    pub thickness: Quantity,
    /// Isotropic pre-stretch λ0 > 0 of the mesh relative to the stress-free state (the
    /// stress-free state is the mesh shrunk by 1/λ0; a number or a parameter). Default 1.
    #[serde(default = "one_quantity")]
    pub prestretch: Quantity,
    /// How compression is carried: `none` (the plain energy, the default) or `relaxed` (the
    /// tension-field energy: taut, wrinkled or slack per triangle; docs/theory.md §2.9).
    #[serde(default, skip_serializing_if = "Wrinkling::is_none")]
    pub wrinkling: Wrinkling,
    /// The residual stiffness ε of the relaxed energy, 0 ≤ ε ≤ 1 (default
    /// [`DEFAULT_WRINKLING_STIFFNESS`]); only with `wrinkling = "relaxed"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrinkling_stiffness: Option<f64>,
    /// The switching width δ of the relaxed energy, 0 ≤ δ ≤ 0.1 (default 0: the relaxed
    /// energy exactly); only with `wrinkling = "relaxed"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrinkling_width: Option<f64>,
    /// The largest principal stretch (from the stress-free state) the material is stated
    /// for, above 1; a state stretched beyond it is flagged `stretch` (docs/theory.md §8.10).
    /// None: no range stated, no flag.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_stretch: Option<f64>,
}

/// The residual stiffness ε of the relaxed energy when the scene gives none.
pub const DEFAULT_WRINKLING_STIFFNESS: f64 = 1e-4;

/// `material.wrinkling`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Wrinkling {
    /// The plain energy everywhere.
    #[default]
    None,
    /// The relaxed (tension-field) energy.
    Relaxed,
}

impl Wrinkling {
    /// True for the plain energy (the default, left out when a scene is written back).
    pub fn is_none(&self) -> bool {
        *self == Self::None
    }
}

impl Material {
    /// The residual stiffness ε when the relaxed energy is selected, `None` for the plain one.
    pub fn relaxed_stiffness(&self) -> Option<f64> {
        (self.wrinkling == Wrinkling::Relaxed).then(|| {
            self.wrinkling_stiffness
                .unwrap_or(DEFAULT_WRINKLING_STIFFNESS)
        })
    }

    /// The switching width δ when the relaxed energy is selected (0 unless the scene gives
    /// one), `None` for the plain one.
    pub fn relaxed_width(&self) -> Option<f64> {
        (self.wrinkling == Wrinkling::Relaxed).then(|| self.wrinkling_width.unwrap_or(0.0))
    }

    /// The quantities with their keys and the range a value must lie in.
    pub fn ruled_quantities(&self) -> Vec<(&'static str, &Quantity, Range)> {
        vec![
            ("mu", &self.mu, Range::Positive),
            ("k", &self.k, Range::NonNegative),
            ("thickness", &self.thickness, Range::Positive),
            ("prestretch", &self.prestretch, Range::Positive),
        ]
    }
}

/// `material.model`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialModel {
    /// Incompressible Mooney–Rivlin (plane stress).
    #[default]
    MooneyRivlin,
}

/// `[[effect]]`: one load, with its potential (docs/theory.md §1). Its keys are the struct of
/// its `type` in `src/effects/` ([`EffectSpec`]), read through [`crate::effects::REGISTRY`].
#[derive(Debug)]
pub struct Effect {
    kind: &'static str,
    spec: Box<dyn EffectSpec>,
}

impl Effect {
    /// The effect of `type` `kind` with the keys `spec`.
    pub fn new(kind: &'static str, spec: Box<dyn EffectSpec>) -> Self {
        Effect { kind, spec }
    }

    /// The `type` of this effect.
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// Its keys.
    pub fn spec(&self) -> &dyn EffectSpec {
        self.spec.as_ref()
    }

    /// Its keys, to normalise while checking them.
    pub(crate) fn spec_mut(&mut self) -> &mut dyn EffectSpec {
        self.spec.as_mut()
    }

    /// Its keys as their concrete type `T`, if it is one of that type.
    pub fn get<T: 'static>(&self) -> Option<&T> {
        self.spec.as_any().downcast_ref::<T>()
    }

    /// The quantities of this effect with their keys, in declaration order.
    pub fn quantities(&self) -> Vec<(&'static str, &Quantity)> {
        self.ruled_quantities()
            .into_iter()
            .map(|(k, q, _)| (k, q))
            .collect()
    }

    /// The quantities with their keys and the range a literal value must lie in.
    pub fn ruled_quantities(&self) -> Vec<(&'static str, &Quantity, Range)> {
        self.spec.quantities()
    }

    /// The parameters this effect depends on.
    pub fn parameters(&self) -> Vec<&str> {
        self.quantities()
            .into_iter()
            .filter_map(|(_, q)| q.parameter())
            .collect()
    }

    /// True for the effects that load the enclosed region (gas, fluid, spin): they need a
    /// closed membrane or an open one whose whole rim is fixed.
    pub fn encloses(&self) -> bool {
        self.spec.needs_enclosure()
    }
}

impl Clone for Effect {
    fn clone(&self) -> Self {
        Effect {
            kind: self.kind,
            spec: self.spec.clone_box(),
        }
    }
}

impl PartialEq for Effect {
    fn eq(&self, other: &Self) -> bool {
        self.kind == other.kind && self.spec.eq_dyn(other.spec.as_ref())
    }
}

impl Serialize for Effect {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let table = self.spec.table();
        let mut map = s.serialize_map(Some(table.len() + 1))?;
        map.serialize_entry("type", self.kind)?;
        for (k, v) in &table {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// `[boundary]`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Boundary {
    /// Node sets of the mesh whose nodes are held at their reference positions. Default none.
    #[serde(default)]
    pub fixed: Vec<String>,
    /// `[[boundary.slide]]`: node sets whose nodes move in planes. Default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slide: Vec<Slide>,
}

/// `[[boundary.slide]]`: every node of `set` moves in the plane through its reference
/// position with normal `normal` (frictionless: an edge resting on a plane).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Slide {
    /// The node set.
    pub set: String,
    /// The plane's normal (normalised on loading).
    pub normal: [f64; 3],
}

/// `[parameters.NAME]`: a load parameter Λ_j.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Parameter {
    /// Value at the start state.
    pub start: f64,
    /// Lower bound: the path stops when the parameter falls below it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// Upper bound: the path stops when the parameter exceeds it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
}

/// `[[constraint]]`, tagged by `type`: one augmenting equation, which governs (frees) one
/// parameter (docs/theory.md §7.1).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum Constraint {
    /// `type = "fluid-volume"`: the fluid volume of a fluid effect is held fixed; its level
    /// (a parameter) is the unknown that adjusts.
    FluidVolume(FluidVolumeConstraint),
    /// `type = "gas-amount"`: the amount of gas (P_atm + p)·V of a `gas` effect is held
    /// fixed; its pressure (a parameter) adjusts.
    GasAmount(GasAmountConstraint),
    /// `type = "fixed"`: a parameter is held at its start value.
    Fixed(FixedConstraint),
}

impl Constraint {
    /// The parameter this constraint governs.
    pub fn parameter(&self) -> &str {
        match self {
            Constraint::FluidVolume(c) => &c.level,
            Constraint::GasAmount(c) => &c.pressure,
            Constraint::Fixed(c) => &c.parameter,
        }
    }

    /// The `type` of this constraint.
    pub fn kind(&self) -> ConstraintKind {
        match self {
            Constraint::FluidVolume(_) => ConstraintKind::FluidVolume,
            Constraint::GasAmount(_) => ConstraintKind::GasAmount,
            Constraint::Fixed(_) => ConstraintKind::Fixed,
        }
    }
}

/// A held value: a number, `"initial"` — the value at the start state — or the name of a
/// declared parameter (which may then be the path's control).
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// The value measured at the start state (after the start solve).
    Initial,
    /// A given number.
    Value(f64),
    /// The value of this parameter.
    Parameter(String),
}

impl Target {
    /// The parameter this target follows, if any.
    pub fn parameter(&self) -> Option<&str> {
        match self {
            Target::Parameter(name) => Some(name),
            Target::Initial | Target::Value(_) => None,
        }
    }
}

/// `type = "fluid-volume"`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub struct FluidVolumeConstraint {
    /// Index of the fluid effect (in the file `effect = N`, optional when there is one fluid
    /// effect; always resolved after loading).
    pub effect: usize,
    /// The fluid volume V_f = ∮ min(z, h) n_z dA to hold, or its initial value.
    pub value: Target,
    /// The level parameter of that effect, which this constraint governs.
    #[serde(skip)]
    pub level: String,
}

/// `type = "gas-amount"`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub struct GasAmountConstraint {
    /// Index of the `gas` effect (optional in the file when there is one; resolved).
    pub effect: usize,
    /// The amount C = (P_atm + p)·V to hold, or its initial value.
    pub value: Target,
    /// Ambient (absolute) pressure P_atm ≥ 0.
    pub ambient_pressure: f64,
    /// The pressure parameter of that effect, which this constraint governs.
    #[serde(skip)]
    pub pressure: String,
}

/// `type = "fixed"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct FixedConstraint {
    /// The parameter held at its start value.
    pub parameter: String,
}

/// `[start]`: how the first equilibrium is found. The first Newton guess is the mesh scaled
/// by `stretch` about the origin, x⁰ = stretch · X, with every parameter at its start value;
/// Newton from there gives the start state. A free closed membrane (a balloon) needs
/// `stretch > 1` with a start pressure that holds it (a membrane without tension has a
/// singular tangent); a clamped membrane starts taut from `material.prestretch > 1` and
/// must keep `stretch = 1` (the fixed nodes stay at X).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct Start {
    /// Isotropic scale of the first guess about the origin (> 0). Default 1.
    #[serde(default = "one")]
    pub stretch: f64,
    /// The `path.json` of an earlier run of a scene with the same mesh and parameters: the
    /// start is its saved path point `point` (state and parameters as saved), refined by
    /// Newton. A relative path is relative to the scene file's directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<PathBuf>,
    /// The path point (row `step`) of `from` to start from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<usize>,
    /// A start homotopy for a free body resting on a plane: the mean translation along this
    /// direction is held first (by a uniform force, an extra unknown), then released along an
    /// auxiliary path in the held position until that force vanishes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_translation: Option<[f64; 3]>,
}

impl Default for Start {
    fn default() -> Self {
        Start {
            stretch: 1.0,
            from: None,
            point: None,
            hold_translation: None,
        }
    }
}

fn one() -> f64 {
    1.0
}
fn one_quantity() -> Quantity {
    Quantity::Value(1.0)
}
fn default_sectors() -> usize {
    DiscOptions::default().sectors
}
fn default_disc_divisions() -> usize {
    DiscOptions::default().divisions
}
fn default_frequency() -> usize {
    IcosphereOptions::default().frequency
}
fn default_cut_height() -> f64 {
    TruncatedSphereOptions::default().cut_height
}
fn default_pattern() -> String {
    TruncatedSphereOptions::default().pattern
}
fn default_axisym_shape() -> AxisymShape {
    AxisymShape::Disc
}
fn default_axisym_elements() -> usize {
    64
}
fn default_axisym_modes() -> usize {
    20
}
fn default_file_group() -> String {
    "C1".to_string()
}

/// Why a command that needs a 3-D mesh refuses an axisymmetric one.
pub const AXISYMMETRIC_ONLY: &str =
    "generator \"axisymmetric\" is a meridian, not a 3-D mesh: `memstab run`, `branch` and `compare` take it, `spectrum` and `export-matrix` do not";

impl MeshSpec {
    /// A `[mesh]` table on its own, as TOML text (`generator = "disc"`, `sectors = 8`, …),
    /// read and checked as a scene's `[mesh]` is (the messages name `mesh.<key>`); a radius
    /// must be a number here. The file generator's path is taken as given.
    pub fn parse(text: &str, origin: &str) -> Result<Self, SceneError> {
        load::parse_mesh(text, origin)
    }

    /// The generator.
    pub fn generator(&self) -> Generator {
        match self {
            MeshSpec::Disc(_) => Generator::Disc,
            MeshSpec::Icosphere(_) => Generator::Icosphere,
            MeshSpec::TruncatedSphere(_) => Generator::TruncatedSphere,
            MeshSpec::File(_) => Generator::File,
            MeshSpec::Axisymmetric(_) => Generator::Axisymmetric,
        }
    }

    /// How messages name the mesh: `the disc mesh`, `the mesh in 'disc.msh'`.
    pub fn describe(&self) -> String {
        match self {
            MeshSpec::File(f) => format!("the mesh in '{}'", f.path.display()),
            other => format!("the {} mesh", other.generator()),
        }
    }

    /// The number of triangles the generator will build (saturating; a cheap guard before
    /// building). A file is not read here: its count is 0 (reading costs what the file's size
    /// is, so there is nothing to guard against).
    pub fn triangle_count(&self) -> usize {
        match self {
            MeshSpec::Disc(d) => d
                .sectors
                .saturating_mul(d.divisions)
                .saturating_mul(d.divisions),
            MeshSpec::Icosphere(i) => 20usize
                .saturating_mul(i.frequency)
                .saturating_mul(i.frequency),
            MeshSpec::TruncatedSphere(t) => {
                let d = t.divisions_or_default();
                8usize.saturating_mul(d).saturating_mul(d)
            }
            MeshSpec::File(_) | MeshSpec::Axisymmetric(_) => 0,
        }
    }

    /// Builds the mesh with its symmetry group. A generator's complaint becomes a
    /// [`SceneError::Invalid`] naming `mesh.<option>`; a mesh file that cannot be read or is
    /// not a sound surface names `mesh.path`, a group that does not map it onto itself
    /// `mesh.group`.
    pub fn build(&self) -> Result<SymmetricMesh, SceneError> {
        match self {
            MeshSpec::File(f) => f.build().map_err(SceneError::from),
            generated => generated.generate().map_err(|e| self.mesh_error(e).into()),
        }
    }

    /// Runs the generator with these options (a file is read as `build` reads it); the
    /// generator's own error.
    pub fn generate(&self) -> Result<SymmetricMesh, MeshError> {
        match self {
            MeshSpec::Disc(d) => generators::disc(&DiscOptions {
                radius: d.radius,
                sectors: d.sectors,
                divisions: d.divisions,
                group: d.group.clone(),
            }),
            MeshSpec::Icosphere(i) => {
                let opts = IcosphereOptions {
                    radius: i.radius,
                    frequency: i.frequency,
                };
                match i.down {
                    None => generators::icosphere(&opts),
                    Some(down) => generators::icosphere_oriented(
                        &opts,
                        match down {
                            DownSpec::Vertex => Down::Vertex,
                            DownSpec::Face => Down::Face,
                            DownSpec::Edge => Down::Edge,
                        },
                    ),
                }
            }
            MeshSpec::TruncatedSphere(t) => {
                let mut opts = TruncatedSphereOptions::for_pattern(&t.pattern);
                opts.radius = t.radius;
                opts.cut_height = t.cut_height;
                opts.divisions = t.divisions_or_default();
                generators::truncated_sphere(&opts)
            }
            MeshSpec::File(f) => f.build().map_err(|p| MeshError::Invalid(p.message.clone())),
            MeshSpec::Axisymmetric(_) => Err(MeshError::Invalid(AXISYMMETRIC_ONLY.into())),
        }
    }

    /// The name of the group the mesh is built with (before a scene restricts it).
    pub fn group_name(&self) -> String {
        match self {
            MeshSpec::Disc(d) => d
                .group
                .clone()
                .unwrap_or_else(|| format!("C{}v", d.sectors)),
            MeshSpec::Icosphere(_) => "Ih".into(),
            MeshSpec::TruncatedSphere(t) => t.pattern.clone(),
            MeshSpec::File(f) => f.group.clone(),
            // A meridian carries no finite group; it builds no group action.
            MeshSpec::Axisymmetric(_) => "C1".into(),
        }
    }

    /// An estimate of the memory that building the mesh and its group action takes, bytes:
    /// ~200 B a triangle for the mesh, and 8 B per node and triangle for each group element's
    /// permutations. A mesh file's triangles are bounded by its size (≥ 20 bytes each).
    pub fn estimated_bytes(&self) -> u64 {
        let triangles = self.estimated_triangles();
        let order = symmetry::Group::order_of(&self.group_name()).unwrap_or(1) as u64;
        triangles
            .saturating_mul(200)
            .saturating_add(order.saturating_mul(triangles.saturating_mul(12)))
    }

    /// The triangles of the mesh: [`MeshSpec::triangle_count`], and for a file the most its
    /// size allows.
    pub fn estimated_triangles(&self) -> u64 {
        match self {
            MeshSpec::File(f) => std::fs::metadata(&f.path).map_or(0, |m| m.len() / 20),
            other => other.triangle_count() as u64,
        }
    }

    /// A generator error as a problem naming `mesh.<option>` when the generator names one
    /// of this generator's options.
    fn mesh_error(&self, e: MeshError) -> error::Problem {
        let options = self.generator().options();
        match e {
            MeshError::Option { option, message }
                if options.contains(&option.replace('_', "-").as_str()) =>
            {
                let key = format!("mesh.{}", option.replace('_', "-"));
                if message.starts_with("must") {
                    error::Problem::at(&key, message)
                } else {
                    error::Problem::new(&key, format!("'{key}': {option} {message}"))
                }
            }
            other => error::Problem::new("mesh", format!("'mesh' ({}): {other}", self.generator())),
        }
    }
}

impl FileMesh {
    /// Reads the file, pairs the mesh with the declared group and verifies the action.
    fn build(&self) -> Result<SymmetricMesh, error::Problem> {
        let shown = self.path.display();
        let bad_file = |why: String| {
            error::Problem::new("mesh.path", format!("'mesh.path' = \"{shown}\": {why}"))
        };
        let not_symmetric = |why: String| {
            error::Problem::new(
                "mesh.group",
                format!(
                    "'mesh.group' = \"{}\": the group does not map the mesh in '{shown}' to \
                     itself ({why})",
                    self.group
                ),
            )
        };
        let group = Group::by_name(&self.group).map_err(|e| {
            error::Problem::new(
                "mesh.group",
                format!("'mesh.group' = \"{}\": {e}", self.group),
            )
        })?;
        let mesh = meshes::read::read_mesh(&self.path).map_err(|e| {
            bad_file(match e {
                MeshError::Io { source, .. } => format!("cannot read the mesh file: {source}"),
                MeshError::Read { message, .. } => message,
                other => other.to_string(),
            })
        })?;
        if let Some((a, b)) = meshes::coincident_nodes(&mesh) {
            let x = mesh.nodes[b];
            return Err(bad_file(format!(
                "nodes {a} and {b} coincide at ({}, {}, {}); a membrane's nodes are distinct \
                 points (merge them and renumber the triangles)",
                error::num(x.x),
                error::num(x.y),
                error::num(x.z)
            )));
        }
        let sym = SymmetricMesh::new(mesh, group).map_err(|e| not_symmetric(inner(e)))?;
        sym.verify().map_err(|e| match e {
            MeshError::Topology(m) => bad_file(format!("not a usable membrane: {m}")),
            other => not_symmetric(inner(other)),
        })?;
        Ok(sym)
    }
}

/// The text of a symmetry or topology error without its `symmetry:` / `topology:` label.
fn inner(e: MeshError) -> String {
    match e {
        MeshError::Symmetry(m) | MeshError::Topology(m) | MeshError::Invalid(m) => m,
        other => other.to_string(),
    }
}

impl TruncatedSphereMesh {
    /// `divisions`, or the generator's default for the pattern.
    pub fn divisions_or_default(&self) -> usize {
        self.divisions
            .unwrap_or_else(|| TruncatedSphereOptions::for_pattern(&self.pattern).divisions)
    }
}

/// What `path` is when it exists and is not a regular file (`a FIFO`, `a directory` …),
/// by its metadata, without opening it (opening a FIFO waits for a writer); `None` for a
/// regular file (a symbolic link to one included) and for a path that does not exist (its
/// read says so).
pub fn not_regular(path: &Path) -> Option<&'static str> {
    let t = std::fs::metadata(path).ok()?.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("a special file")
}

impl Scene {
    /// Parses and validates a scene from TOML text; `origin` (a file name or a label) prefixes
    /// error messages. Checks everything that does not need the mesh; call
    /// [`Scene::build_mesh`] for the rest.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
        load::parse(text, origin)
    }

    /// Reads, parses and validates a scene file (see [`Scene::from_toml_str`]). A relative
    /// `mesh.path` of a `generator = "file"` mesh is resolved against the directory of the
    /// scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let limit = crate::limits::Limits::from_env()?.scene_bytes;
        let read = |source| SceneError::Read {
            path: path.to_path_buf(),
            source,
        };
        // Only a regular file is opened: opening a FIFO waits for a writer, and a signal does
        // not end that wait.
        if let Some(what) = not_regular(path) {
            return Err(SceneError::NotRegular {
                path: path.to_path_buf(),
                what,
            });
        }
        // A bounded read: a file that grows while it is read must not fill the memory.
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(
            &mut std::io::Read::take(std::fs::File::open(path).map_err(read)?, limit + 1),
            &mut bytes,
        )
        .map_err(read)?;
        if bytes.len() as u64 > limit {
            return Err(SceneError::TooLarge {
                path: path.to_path_buf(),
                limit,
            });
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            read(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("not UTF-8 text (at byte {})", e.utf8_error().valid_up_to()),
            ))
        })?;
        let origin = path.display().to_string();
        let mut scene = Self::from_toml_str(&text, &origin)?;
        if let MeshSpec::File(f) = &mut scene.mesh {
            if f.path.is_relative() {
                let resolved = path.parent().unwrap_or(Path::new("")).join(&f.path);
                // The scene must stay writable as TOML (`to_toml`), which needs UTF-8.
                if resolved.to_str().is_none() {
                    return Err(error::Problem::at(
                        "mesh.path",
                        format!(
                            "resolved against the scene's directory is not valid UTF-8: {}",
                            resolved.display()
                        ),
                    )
                    .into_error(&origin));
                }
                f.path = resolved;
            }
        }
        if let Some(from) = &mut scene.start.from {
            if from.is_relative() {
                *from = path.parent().unwrap_or(Path::new("")).join(&*from);
            }
        }
        // The files the scene names, checked as the scene file is, before anything opens them.
        let named = [
            match &scene.mesh {
                MeshSpec::File(f) => Some(("mesh.path", f.path.as_path())),
                _ => None,
            },
            scene.start.from.as_deref().map(|p| ("start.from", p)),
        ];
        for (key, file) in named.into_iter().flatten() {
            if let Some(what) = not_regular(file) {
                return Err(error::Problem::at(
                    key,
                    format!(
                        "= '{}' is {what}, not a regular file; give the path of a file",
                        file.display()
                    ),
                )
                .into_error(&origin));
            }
        }
        scene
            .analysis
            .resolve(path.parent().unwrap_or(Path::new("")));
        Ok(scene)
    }

    /// Builds the mesh and checks the parts of the scene that refer to it
    /// An estimate of a run's peak memory, bytes: the mesh and its group action
    /// ([`MeshSpec::estimated_bytes`]), the model and its stability analysis (~16 KB a
    /// triangle, measured on icospheres up to 330 000 triangles), the path's points (a state
    /// and a tangent of up to 3 unknowns a node each, every point) and saved states, and the
    /// rows of the path or sweep.
    pub fn estimated_bytes(&self) -> u64 {
        let triangles = self.mesh.estimated_triangles();
        // Nodes ≈ triangles / 2; 3 unknowns a node; 8 bytes a number.
        let state = triangles.saturating_mul(12);
        let (points, saved) = self.analysis.spec().stored_points();
        let row = 256 + 16 * (self.parameters.len() as u64 + 8);
        self.mesh
            .estimated_bytes()
            .saturating_add(triangles.saturating_mul(16_384))
            .saturating_add(points.saturating_mul(state.saturating_mul(2).saturating_add(row)))
            .saturating_add(saved.saturating_mul(state))
    }

    /// ([`Scene::check_mesh`]).
    pub fn build_mesh(&self) -> Result<SymmetricMesh, SceneError> {
        let mesh = self.mesh.build().map_err(|e| e.with_origin(&self.origin))?;
        self.check_mesh(&mesh)?;
        Ok(mesh)
    }

    /// Warnings about the built mesh for the run's report: for a mesh read from a file, the
    /// symmetry it has beyond the declared `mesh.group` ([`SymmetricMesh::hidden_symmetries`]),
    /// which the analysis does not use. Generated meshes have exactly their group by
    /// construction, so they get none.
    pub fn mesh_warnings(&self, mesh: &SymmetricMesh) -> Vec<String> {
        let MeshSpec::File(f) = &self.mesh else {
            return Vec::new();
        };
        let hidden = mesh.hidden_symmetries();
        if hidden.is_empty() {
            return Vec::new();
        }
        const SHOWN: usize = 3;
        let mut list = hidden
            .iter()
            .take(SHOWN)
            .cloned()
            .collect::<Vec<_>>()
            .join("; ");
        if hidden.len() > SHOWN {
            list.push_str(&format!(" and {} more", hidden.len() - SHOWN));
        }
        vec![format!(
            "the mesh in '{}' has symmetry beyond mesh.group = \"{}\" ({list}); the analysis \
             uses only {}: declare the larger group to split the tangent by it",
            f.path.display(),
            f.group,
            mesh.group().name()
        )]
    }

    /// Checks the scene against its mesh: every `boundary.fixed` name is a node set of the
    /// mesh; gas, fluid and spin need a closed membrane or one whose whole rim is fixed;
    /// fluid `below`/`above` needs an open membrane; `start.stretch ≠ 1` and
    /// `analysis.stop-stretch` need a closed one.
    pub fn check_mesh(&self, mesh: &SymmetricMesh) -> Result<(), SceneError> {
        validate::check_mesh(self, mesh).map_err(|p| p.into_error(&self.origin))
    }

    /// The sorted, de-duplicated nodes of all `boundary.fixed` sets (names must have been
    /// checked with [`Scene::check_mesh`]; unknown names contribute nothing).
    pub fn fixed_nodes(&self, mesh: &SymmetricMesh) -> Vec<usize> {
        let mut nodes: Vec<usize> = self
            .boundary
            .fixed
            .iter()
            .filter_map(|name| mesh.mesh.boundaries.get(name))
            .flatten()
            .copied()
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// The nodes of the `[[boundary.slide]]` sets with their planes' unit normals, sorted by
    /// node (a node in two sets takes the first set's normal; unknown names contribute
    /// nothing).
    pub fn sliding_nodes(&self, mesh: &SymmetricMesh) -> Vec<(usize, [f64; 3])> {
        let mut nodes: Vec<(usize, [f64; 3])> = Vec::new();
        for slide in &self.boundary.slide {
            for &i in mesh.mesh.boundaries.get(&slide.set).into_iter().flatten() {
                if !nodes.iter().any(|(j, _)| *j == i) {
                    nodes.push((i, slide.normal));
                }
            }
        }
        nodes.sort_by_key(|(i, _)| *i);
        nodes
    }

    /// Parameter values at the start state.
    pub fn start_values(&self) -> BTreeMap<String, f64> {
        self.parameters
            .iter()
            .map(|(name, p)| (name.clone(), p.start))
            .collect()
    }

    /// The control parameter of a path analysis.
    pub fn control(&self) -> Option<&str> {
        self.analysis.control()
    }

    /// Every quantity of the scene that may be a parameter (the mesh's radius, the
    /// material's, then each effect's), with its key path (`material.k`, `effect[0].gravity`)
    /// and its range.
    pub fn quantities(&self) -> Vec<(String, &Quantity, Range)> {
        let radius = self
            .mesh_radius
            .iter()
            .map(|q| ("mesh.radius".to_string(), q, Range::Positive));
        let material = self
            .material
            .ruled_quantities()
            .into_iter()
            .map(|(k, q, r)| (format!("material.{k}"), q, r));
        let effects = self.effects.iter().enumerate().flat_map(|(i, e)| {
            e.ruled_quantities()
                .into_iter()
                .map(move |(k, q, r)| (format!("effect[{i}].{k}"), q, r))
        });
        radius.chain(material).chain(effects).collect()
    }

    /// The value of `q` at the start state (a parameter at its start value).
    pub fn start_value(&self, q: &Quantity) -> f64 {
        match q {
            Quantity::Value(v) => *v,
            Quantity::Parameter(name) => self.parameters.get(name).map_or(f64::NAN, |p| p.start),
        }
    }

    /// The constraint that governs `parameter`, if any.
    pub fn governing(&self, parameter: &str) -> Option<&Constraint> {
        self.constraints.iter().find(|c| c.parameter() == parameter)
    }

    /// The scene as TOML (loading it again gives an equal scene).
    pub fn to_toml(&self) -> String {
        let text = toml::to_string(self).expect("a scene serialises to TOML");
        let Some(Quantity::Parameter(name)) = &self.mesh_radius else {
            return text;
        };
        // The radius parameter is kept beside the mesh options: put its name back in [mesh].
        let mut doc: toml::Table = text.parse().expect("the scene's own TOML parses");
        if let Some(toml::Value::Table(mesh)) = doc.get_mut("mesh") {
            mesh.insert("radius".into(), toml::Value::String(name.clone()));
        }
        toml::to_string(&doc).expect("a scene serialises to TOML")
    }
}
