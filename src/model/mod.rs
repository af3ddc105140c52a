//! The model: Π(u; Λ) = Σ_effects Π_e(x(u); Λ), x = X + u (docs/theory.md §1).
//!
//! A [`FeModel`] owns the reference mesh, the map from nodes to unknowns (fixed nodes have
//! none), the sparsity pattern of the tangent (computed once) and the effects a scene asked
//! for. [`FeModel::evaluate`] fills an [`Evaluation`]: Π, the residual F = ∂Π/∂u, the values
//! of the symmetric tangent K = ∂²Π/∂u² on the fixed pattern, and the load vectors ∂F/∂Λ_j.
//! Solvers see the [`Model`] trait, never a membrane.

mod assembly;
pub mod check;
pub mod constraint;
mod local;
pub mod newton;
pub mod validity;

pub use assembly::{
    Assembler, Evaluation, GlobalGradient, Layout, NodeTerms, Request, Subset, TriangleTerms,
};
pub use local::Local;
pub use validity::StateDefect;

use crate::linalg::SymmetricPattern;
use nalgebra::Vector3;
use symmetry::Invariant;

/// A point or vector in 3-D.
pub type Vec3 = Vector3<f64>;

/// Why an evaluation failed.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum ModelError {
    /// An element left the domain of its potential (inverted or collapsed triangle).
    #[error("effect '{effect}': {what} at triangle {triangle}")]
    Element {
        /// The effect's name.
        effect: String,
        /// The triangle.
        triangle: usize,
        /// What went wrong.
        what: String,
    },
    /// A global quantity left its domain (e.g. a non-positive gas volume).
    #[error("effect '{effect}': {what}")]
    Global {
        /// The effect's name.
        effect: String,
        /// What went wrong.
        what: String,
    },
    /// A non-finite number appeared.
    #[error("non-finite {what} in effect '{effect}'")]
    NonFinite {
        /// The effect's name.
        effect: String,
        /// Energy, residual, tangent or load.
        what: &'static str,
    },
}

/// One term of the potential: a membrane, a gas, a fluid, a plane …
///
/// An effect adds its potential, gradient, Hessian and parameter derivatives through the
/// [`Assembler`], which runs its per-triangle or per-node kernel in parallel and scatters the
/// results into precomputed slots.
pub trait Effect: Send + Sync {
    /// A short name for reports, e.g. `membrane`, `gas`.
    fn name(&self) -> &str;

    /// What this effect leaves invariant on its own (gravity: the direction −z; a plane: its
    /// normal as a direction). Unless the effect has a [`Effect::placement`], the scene's
    /// group keeps all of it (see [`scene_elements`]).
    fn keeps(&self) -> Vec<Invariant>;

    /// For an effect that a group element may map onto *another* effect of the same scene
    /// (a rigid plane goes to the plane with normal R n and the same offset and law): its
    /// placement. Such effects are kept as a set, not one by one (docs/theory.md §9.4).
    fn placement(&self) -> Option<Placement> {
        None
    }

    /// The rigid motions that leave Π_e unchanged, as vectors (t_x, t_y, t_z, ω_x, ω_y, ω_z)
    /// of translations and rotations about axes through the origin spanning them. A free body
    /// has a zero tangent eigenvalue for every motion all its effects keep.
    fn rigid_motions(&self) -> Vec<[f64; 6]>;

    /// Rigid motions this effect does not keep but that no physical support resists, which a
    /// free body's stability analysis holds (docs/theory.md §8.5): spin about z makes every
    /// translation across the axis unstable — the body would drift off the axis of the
    /// rotating frame — a trivial instability the analysis leaves out by holding the mean
    /// position. Empty by default.
    fn drifts(&self) -> Vec<[f64; 6]> {
        Vec::new()
    }

    /// Adds Π_e and its derivatives at the current node positions `x` and parameters `params`.
    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError>;

    /// The per-triangle quantities this effect can show at a state (stretches, tensions, a
    /// pressure), for the state files; none by default.
    fn cell_fields(
        &self,
        _x: &[Vec3],
        _triangles: &[[usize; 3]],
        _params: &[f64],
    ) -> Vec<CellField> {
        Vec::new()
    }

    /// For a contact effect (a rigid plane): every node's penetration ⟨−δ_i⟩ ≥ 0 at the
    /// positions `x` (0 off contact), which says which nodes are in contact; `None` for an
    /// effect that makes no contact (the default).
    fn penetrations(&self, _x: &[Vec3], _params: &[f64]) -> Option<Vec<f64>> {
        None
    }

    /// The per-triangle vectors this effect can show at a state (a direction), for the state
    /// files; none by default.
    fn cell_vectors(
        &self,
        _x: &[Vec3],
        _triangles: &[[usize; 3]],
        _params: &[f64],
    ) -> Vec<CellVectorField> {
        Vec::new()
    }

    /// The per-node quantities this effect can show at a state (the pressure it applies),
    /// for the state files; none by default.
    fn node_fields(
        &self,
        _x: &[Vec3],
        _triangles: &[[usize; 3]],
        _params: &[f64],
    ) -> Vec<NodeField> {
        Vec::new()
    }
}

/// What a per-node field of a state holds (its name in the state files is
/// [`NodeQuantity::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeQuantity {
    /// The pressure across the membrane that the gas and fluid loads apply at the node,
    /// positive when it pushes along the membrane's normal (out of a closed membrane, up
    /// on a membrane whose normals point up).
    Pressure,
}

impl NodeQuantity {
    /// The field's name in the state files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Pressure => "pressure",
        }
    }
}

/// One value per node of a [`NodeQuantity`].
#[derive(Debug, Clone, PartialEq)]
pub struct NodeField {
    /// What it holds.
    pub quantity: NodeQuantity,
    /// One value per node, in the mesh's order.
    pub values: Vec<f64>,
}

/// What a per-triangle field of a state holds (its name in the state files is
/// [`CellQuantity::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellQuantity {
    /// The larger principal stretch λ₁ from the stress-free state.
    Stretch1,
    /// The smaller principal stretch λ₂.
    Stretch2,
    /// The current thickness h = H λ₃ = H/(λ₁λ₂).
    Thickness,
    /// The larger principal Cauchy tension (force per current length).
    Tension1,
    /// The smaller principal Cauchy tension.
    Tension2,
    /// 1 where the smaller principal tension is negative (the membrane would wrinkle), else 0.
    Wrinkled,
    /// With the relaxed energy: 0 where the triangle is taut, 1 wrinkled, 2 slack.
    MembraneState,
    /// The fluid pressure ρ g (h − z)₊ at the triangle's centroid (unclipped in a filled
    /// enclosure), whichever side the fluid is on.
    FluidPressure,
    /// The contact pressure of a plane: the nodes' penalty forces over their tributary
    /// areas (a third of the adjacent triangles' areas), averaged over the triangle.
    ContactPressure,
}

impl CellQuantity {
    /// The field's name in the state files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Stretch1 => "stretch_1",
            Self::Stretch2 => "stretch_2",
            Self::Thickness => "thickness",
            Self::Tension1 => "tension_1",
            Self::Tension2 => "tension_2",
            Self::Wrinkled => "wrinkled",
            Self::MembraneState => "membrane_state",
            Self::FluidPressure => "fluid_pressure",
            Self::ContactPressure => "contact_pressure",
        }
    }
}

/// One value per triangle of a [`CellQuantity`].
#[derive(Debug, Clone, PartialEq)]
pub struct CellField {
    /// What it holds.
    pub quantity: CellQuantity,
    /// One value per triangle, in the mesh's order.
    pub values: Vec<f64>,
}

/// One 3-vector per triangle, with its name in the state files.
#[derive(Debug, Clone, PartialEq)]
pub struct CellVectorField {
    /// The field's name (`wrinkle_direction`).
    pub name: &'static str,
    /// One vector per triangle, in the mesh's order.
    pub values: Vec<Vec3>,
}

/// How a group element moves an effect that can be mapped onto another one: the element R
/// takes it to an effect of the same `kind` and `key` with normal R·`normal`.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// What the effect is (`plane`): only effects of the same kind map onto each other.
    pub kind: &'static str,
    /// The unit direction the element turns (a plane's normal).
    pub normal: Vec3,
    /// Everything else that must agree exactly (offset, penalty, law …), as numbers.
    pub key: Vec<f64>,
}

/// The elements of `group` that map the set of effects onto itself (docs/theory.md §9.4):
/// they keep every invariant of the effects without a placement, and they permute the
/// effects with one — element R maps each onto an effect of the same kind and key whose
/// normal is R n (to 1e-9). A mirror between two planes x = ±a with one offset swaps them, so
/// it belongs to the scene's group although it keeps neither plane alone.
pub fn scene_elements(group: &symmetry::Group, effects: &[Box<dyn Effect>]) -> Vec<usize> {
    let keep: Vec<Invariant> = effects
        .iter()
        .filter(|e| e.placement().is_none())
        .flat_map(|e| e.keeps())
        .collect();
    let placed: Vec<Placement> = effects.iter().filter_map(|e| e.placement()).collect();
    (0..group.order())
        .filter(|&g| {
            let r = group.element(g);
            keep.iter().all(|k| k.kept_by(r)) && permutes(&placed, r)
        })
        .collect()
}

/// True if `r` maps the multiset of placements onto itself.
fn permutes(placed: &[Placement], r: &nalgebra::Matrix3<f64>) -> bool {
    let mut used = vec![false; placed.len()];
    placed.iter().all(|p| {
        let image = r * p.normal;
        let hit = placed.iter().enumerate().position(|(j, q)| {
            !used[j] && q.kind == p.kind && q.key == p.key && (q.normal - image).amax() < 1e-9
        });
        match hit {
            Some(j) => {
                used[j] = true;
                true
            }
            None => false,
        }
    })
}

/// The rigid motions that keep every point in its plane with unit normal `n`: the two
/// translations within it and the rotation about `n`.
pub fn in_plane_motions(n: Vec3) -> Vec<[f64; 6]> {
    let a = if n.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let t1 = n.cross(&a).normalize();
    let t2 = n.cross(&t1);
    vec![
        [t1.x, t1.y, t1.z, 0.0, 0.0, 0.0],
        [t2.x, t2.y, t2.z, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, n.x, n.y, n.z],
    ]
}

/// True if the motion `v` lies in the span of the orthonormal or not `basis` (to 1e-9).
fn in_span(v: &[f64; 6], basis: &[[f64; 6]]) -> bool {
    let v = nalgebra::DVector::from_row_slice(v);
    if basis.is_empty() {
        return v.norm() <= 1e-9;
    }
    let b = nalgebra::DMatrix::from_fn(6, basis.len(), |i, j| basis[j][i]);
    let svd = b.svd(true, false);
    let u = svd.u.expect("U requested");
    let rank = svd.singular_values.iter().filter(|&&x| x > 1e-12).count();
    let u = u.columns(0, rank);
    (&v - u * (u.transpose() * &v)).norm() <= 1e-9 * v.norm().max(1.0)
}

/// The centre and radius of the sphere through the points `x` (least squares, then checked:
/// every point within 1e-9 of the radius), if they lie on one.
fn sphere_through(x: &[Vec3]) -> Option<(Vec3, f64)> {
    // |x|² = 2 x·c + (r² − |c|²): linear in (c, r² − |c|²).
    let a = nalgebra::DMatrix::from_fn(x.len(), 4, |i, j| if j < 3 { 2.0 * x[i][j] } else { 1.0 });
    let b = nalgebra::DVector::from_iterator(x.len(), x.iter().map(|p| p.norm_squared()));
    let sol = a.svd(true, true).solve(&b, 1e-12).ok()?;
    let c = Vec3::new(sol[0], sol[1], sol[2]);
    let r = (sol[3] + c.norm_squared()).max(0.0).sqrt();
    (r > 0.0 && x.iter().all(|p| ((p - c).norm() - r).abs() <= 1e-9 * r)).then_some((c, r))
}

/// The unit normal of the plane the points lie in (within 1e-9 of `size`), if they do.
fn plane_normal(points: impl Iterator<Item = Vec3>, size: f64) -> Option<Vec3> {
    let pts: Vec<Vec3> = points.collect();
    let mean = pts.iter().sum::<Vec3>() / pts.len().max(1) as f64;
    let m = pts.iter().fold(nalgebra::Matrix3::zeros(), |acc, p| {
        let d = p - mean;
        acc + d * d.transpose()
    });
    let eig = nalgebra::SymmetricEigen::new(m);
    let k = eig.eigenvalues.imin();
    let a: Vec3 = eig.eigenvectors.column(k).into();
    pts.iter()
        .all(|p| (p - mean).dot(&a).abs() <= 1e-9 * size)
        .then_some(a)
}

/// All six rigid motions.
pub const ALL_RIGID_MOTIONS: [[f64; 6]; 6] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
];

/// What the solvers and the analysis need from a model: nodes with their unknowns (the
/// group acts on nodes), Π and its derivatives at a state, and the rigid motions it keeps.
/// Nothing here names a particular effect.
pub trait Model: Sync {
    /// The nodes, their unknowns, the triangles and the tangent's pattern.
    fn layout(&self) -> &Layout;
    /// Reference node positions X.
    fn reference(&self) -> &[Vec3];
    /// The rigid motions (t, ω) under which Π is invariant, as an orthonormal basis of that
    /// subspace of ℝ⁶ (empty when a node is fixed).
    fn rigid_motions(&self) -> Vec<[f64; 6]>;
    /// Mean motions the stability analysis holds (docs/theory.md §8.5), as fields
    /// t + ω × X_i at the *reference* positions: the rolling of a spherical reference about
    /// the axes its rigid motions leave out. Empty by default.
    fn held_motions(&self) -> Vec<[f64; 6]> {
        Vec::new()
    }
    /// The held motions that are exact invariances of Π in the continuum (the relabellings of
    /// a spherical reference, docs/theory.md §8.5), as fields t + ω × X_i at the reference
    /// positions: a path holds them in every fixed-point space that contains them, as it holds
    /// the rigid motions (§7.9), since the mesh alone gives them their tiny stiffness. Empty
    /// by default.
    fn gauge_motions(&self) -> Vec<[f64; 6]> {
        Vec::new()
    }
    /// Number of unknowns N.
    fn unknowns(&self) -> usize {
        self.layout().unknowns()
    }
    /// Names of the parameters Λ, in order.
    fn parameters(&self) -> &[String];
    /// The fixed sparsity pattern of the tangent.
    fn pattern(&self) -> &SymmetricPattern {
        self.layout().pattern()
    }
    /// Current node positions x = X + u at the parameters `params` (fixed nodes at X, or
    /// where a held motion moves them: [`Layout::with_held_motion`]).
    fn positions(&self, u: &[f64], params: &[f64]) -> Vec<Vec3> {
        let mut x = self.reference().to_vec();
        self.layout().add_displacements(u, &mut x);
        self.layout().add_held_motion(params, &mut x);
        x
    }
    /// Evaluates what `request` asks for at (u, Λ) into `out` (buffers are reused).
    fn evaluate(
        &self,
        u: &[f64],
        params: &[f64],
        request: Request,
        out: &mut Evaluation,
    ) -> Result<(), ModelError>;
    /// A fresh evaluation buffer sized for this model.
    fn new_evaluation(&self) -> Evaluation;
    /// Where Π is only piecewise smooth (a penalty that acts on one side of a plane): which
    /// piece each of its switches is on at (u, Λ), one flag per switch (a node in contact or
    /// not). The tangent may jump where a switch changes; `None` (the default) for a smooth Π.
    fn switches(&self, _u: &[f64], _params: &[f64]) -> Option<Vec<bool>> {
        None
    }
    /// Why the displacement `u` is not a membrane state (collapsed, torn, inside out or not
    /// finite; [`validity`]), or `None`.
    fn state_defect(&self, u: &[f64], params: &[f64]) -> Option<StateDefect> {
        validity::state_defect_of(
            self.reference(),
            self.layout().triangles(),
            &self.positions(u, params),
            self.layout().is_closed(),
        )
    }
}

/// A finite-element model: reference mesh, fixed nodes, effects, parameters.
pub struct FeModel {
    reference: Vec<Vec3>,
    layout: Layout,
    effects: Vec<Box<dyn Effect>>,
    parameters: Vec<String>,
}

impl FeModel {
    /// Every node's deepest penetration into the contact effects (the rigid planes) at
    /// (u, Λ), with the positions: `None` when no effect makes contact.
    pub fn penetrations(&self, u: &[f64], params: &[f64]) -> Option<(Vec<f64>, Vec<Vec3>)> {
        let x = self.positions(u, params);
        let mut deepest: Option<Vec<f64>> = None;
        for p in self
            .effects
            .iter()
            .filter_map(|e| e.penetrations(&x, params))
        {
            match &mut deepest {
                Some(d) => d.iter_mut().zip(&p).for_each(|(d, p)| *d = d.max(*p)),
                None => deepest = Some(p),
            }
        }
        deepest.map(|d| (d, x))
    }

    /// Every effect's per-triangle fields at (u, Λ), in effect order (a quantity that two
    /// effects show, such as two fluids' pressures, is summed).
    pub fn cell_fields(&self, u: &[f64], params: &[f64]) -> Vec<CellField> {
        let x = self.positions(u, params);
        let mut fields: Vec<CellField> = Vec::new();
        for f in self
            .effects
            .iter()
            .flat_map(|e| e.cell_fields(&x, self.layout.triangles(), params))
        {
            match fields.iter_mut().find(|g| g.quantity == f.quantity) {
                Some(g) => g
                    .values
                    .iter_mut()
                    .zip(&f.values)
                    .for_each(|(a, b)| *a += b),
                None => fields.push(f),
            }
        }
        fields
    }

    /// Every effect's per-triangle vectors at (u, Λ), in effect order.
    pub fn cell_vectors(&self, u: &[f64], params: &[f64]) -> Vec<CellVectorField> {
        let x = self.positions(u, params);
        self.effects
            .iter()
            .flat_map(|e| e.cell_vectors(&x, self.layout.triangles(), params))
            .collect()
    }

    /// Every effect's per-node fields at (u, Λ), in effect order (a quantity that several
    /// effects show, such as gas and fluid pressure, is summed).
    pub fn node_fields(&self, u: &[f64], params: &[f64]) -> Vec<NodeField> {
        let x = self.positions(u, params);
        let mut fields: Vec<NodeField> = Vec::new();
        for f in self
            .effects
            .iter()
            .flat_map(|e| e.node_fields(&x, self.layout.triangles(), params))
        {
            match fields.iter_mut().find(|g| g.quantity == f.quantity) {
                Some(g) => g
                    .values
                    .iter_mut()
                    .zip(&f.values)
                    .for_each(|(a, b)| *a += b),
                None => fields.push(f),
            }
        }
        fields
    }

    /// A model of the mesh (reference positions and triangles) with the nodes in `fixed`
    /// held in place, the given effects, and parameter names.
    pub fn new(
        reference: Vec<Vec3>,
        triangles: Vec<[usize; 3]>,
        fixed: &[usize],
        effects: Vec<Box<dyn Effect>>,
        parameters: Vec<String>,
    ) -> Self {
        let layout = Layout::new(reference.len(), triangles, fixed);
        Self {
            reference,
            layout,
            effects,
            parameters,
        }
    }

    /// Lets the nodes `sliding` move in the planes through their reference positions with the
    /// given normals ([`Layout::with_sliding`]).
    pub fn with_sliding(mut self, sliding: &[(usize, Vec3)]) -> Self {
        self.layout = self.layout.with_sliding(sliding);
        self
    }

    /// Moves the held coordinates with the reference radius R = Λ_`parameter`, the mesh
    /// having been built at R0 = `built_at`: a fixed node to (R/R0) X_i, a sliding one to the
    /// plane through (R/R0) X_i with its normal (docs/theory.md §2.8). Call after
    /// [`FeModel::with_sliding`].
    pub fn with_scaled_holding(mut self, parameter: usize, built_at: f64) -> Self {
        let rates = (0..self.reference.len())
            .map(|i| {
                let x = self.reference[i] / built_at;
                match (self.layout.dof(i, 0), self.layout.slide_normal(i)) {
                    (None, _) => x,
                    (Some(_), Some(n)) => n * n.dot(&x),
                    (Some(_), None) => Vec3::zeros(),
                }
            })
            .collect();
        self.layout = self.layout.with_held_motion(parameter, built_at, rates);
        self
    }

    /// The relabellings of a spherical reference (docs/theory.md §8.5), as motions
    /// (c × ω, ω) at the reference positions: when the reference nodes lie on a sphere about c
    /// (to 1e-9 of its radius), relabelling the material points by a rotation about c that
    /// maps the reference surface onto itself keeps Π in the continuum (every effect sees only
    /// the current shape; the membrane is isotropic with a spherical stress-free state), and
    /// nearly so on a mesh. A closed sphere is mapped onto itself by every rotation about c, a
    /// cap whose rim lies in one plane with normal a only by those about a — and a rim that
    /// slides must slide in planes normal to a. Empty otherwise.
    pub fn relabellings(&self) -> Vec<[f64; 6]> {
        let Some((c, r)) = sphere_through(&self.reference) else {
            return Vec::new();
        };
        let rim = self.layout.rim();
        let axes: Vec<Vec3> = if rim.is_empty() {
            (0..3).map(|k| Vec3::ith(k, 1.0)).collect()
        } else {
            let Some(a) = plane_normal(rim.iter().map(|&i| self.reference[i]), r) else {
                return Vec::new();
            };
            let slides_across = (0..self.reference.len()).any(|i| {
                self.layout
                    .slide_normal(i)
                    .is_some_and(|m| m.cross(&a).norm() > 1e-9)
            });
            if slides_across {
                return Vec::new();
            }
            vec![a]
        };
        axes.iter()
            .map(|w| {
                let t = c.cross(w);
                [t.x, t.y, t.z, w.x, w.y, w.z]
            })
            .collect()
    }

    /// The effects, in assembly order.
    pub fn effects(&self) -> &[Box<dyn Effect>] {
        &self.effects
    }

    /// The displacement fields of rigid motions at positions `x`: u_i = t + ω × x_i.
    pub fn rigid_modes(&self, motions: &[[f64; 6]], x: &[Vec3]) -> Vec<Vec<f64>> {
        motions
            .iter()
            .map(|m| {
                let (t, w) = (Vec3::new(m[0], m[1], m[2]), Vec3::new(m[3], m[4], m[5]));
                let mut u = vec![0.0; self.layout.unknowns()];
                for (i, xi) in x.iter().enumerate() {
                    let v = t + w.cross(xi);
                    for k in 0..3 {
                        if let Some(d) = self.layout.dof(i, k) {
                            u[d] = v[k];
                        }
                    }
                }
                u
            })
            .collect()
    }
}

impl Model for FeModel {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Every node in contact with a penalty plane or not.
    fn switches(&self, u: &[f64], params: &[f64]) -> Option<Vec<bool>> {
        let (depth, _) = self.penetrations(u, params)?;
        Some(depth.iter().map(|&d| d > 0.0).collect())
    }

    fn reference(&self) -> &[Vec3] {
        &self.reference
    }

    /// The rigid motions (t, ω) that every effect keeps, as an orthonormal basis of that
    /// subspace of ℝ⁶: the intersection of the effects' subspaces, computed as the null space
    /// of Σ_e (I − P_e). Empty when any node is fixed; nodes that slide in a plane keep only
    /// the translations within it and the rotations about its normal.
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        if self.layout.unknowns() < 3 * self.reference.len() {
            return Vec::new();
        }
        let mut normals: Vec<Vec3> = Vec::new();
        for n in (0..self.reference.len()).filter_map(|i| self.layout.slide_normal(i)) {
            if !normals.iter().any(|m| m.cross(&n).norm() < 1e-9) {
                normals.push(n);
            }
        }
        let sliding = normals.iter().map(|&n| in_plane_motions(n));
        let mut sum = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        for kept in self
            .effects
            .iter()
            .map(|e| e.rigid_motions())
            .chain(sliding)
        {
            let basis = nalgebra::DMatrix::from_fn(6, kept.len(), |i, j| kept[j][i]);
            let projector = if kept.is_empty() {
                nalgebra::DMatrix::zeros(6, 6)
            } else {
                let svd = basis.svd(true, false);
                let u = svd.u.expect("U requested");
                let rank = svd.singular_values.iter().filter(|&&v| v > 1e-12).count();
                let u = u.columns(0, rank);
                u * u.transpose()
            };
            sum += nalgebra::SMatrix::<f64, 6, 6>::identity()
                - nalgebra::SMatrix::<f64, 6, 6>::from_fn(|i, j| projector[(i, j)]);
        }
        let eig = nalgebra::SymmetricEigen::new(sum);
        (0..6)
            .filter(|&k| eig.eigenvalues[k].abs() < 1e-10)
            .map(|k| std::array::from_fn(|i| eig.eigenvectors[(i, k)]))
            .collect()
    }

    /// The mean motions a stability analysis holds (docs/theory.md §8.5), for a free body
    /// (no node fixed): the relabellings of a spherical reference ([`FeModel::relabellings`])
    /// and the drifts of its effects ([`Effect::drifts`]) that every other effect keeps, less
    /// the rigid motions, as an orthonormal basis of what is left.
    fn held_motions(&self) -> Vec<[f64; 6]> {
        let n = self.reference.len();
        if n < 4 || self.layout.unknowns() < 3 * n {
            return Vec::new();
        }
        let mut candidates = self.relabellings();
        for (k, e) in self.effects.iter().enumerate() {
            for d in e.drifts() {
                let kept_by_others = self
                    .effects
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != k)
                    .all(|(_, o)| in_span(&d, &o.rigid_motions()));
                let normals = (0..n).filter_map(|i| self.layout.slide_normal(i));
                let kept_by_slides = normals
                    .into_iter()
                    .all(|m| in_span(&d, &in_plane_motions(m)));
                if kept_by_others && kept_by_slides {
                    candidates.push(d);
                }
            }
        }
        let kept = self.rigid_motions();
        let mut cand = nalgebra::DMatrix::<f64>::zeros(6, candidates.len());
        for (k, v) in candidates.iter().enumerate() {
            let mut v = nalgebra::DVector::from_row_slice(v);
            for m in &kept {
                let m = nalgebra::DVector::from_row_slice(m);
                v -= &m * m.dot(&v);
            }
            cand.set_column(k, &v);
        }
        if candidates.is_empty() {
            return Vec::new();
        }
        let svd = cand.svd(true, false);
        let u = svd.u.expect("U requested");
        (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > 1e-9)
            .map(|k| std::array::from_fn(|i| u[(i, k)]))
            .collect()
    }

    fn gauge_motions(&self) -> Vec<[f64; 6]> {
        let n = self.reference.len();
        if n < 4 || self.layout.unknowns() < 3 * n {
            return Vec::new();
        }
        self.relabellings()
    }

    fn parameters(&self) -> &[String] {
        &self.parameters
    }

    fn new_evaluation(&self) -> Evaluation {
        Evaluation::new(&self.layout, self.parameters.len())
    }

    fn evaluate(
        &self,
        u: &[f64],
        params: &[f64],
        request: Request,
        out: &mut Evaluation,
    ) -> Result<(), ModelError> {
        assert_eq!(u.len(), self.unknowns(), "state length");
        assert_eq!(params.len(), self.parameters.len(), "parameter count");
        // The implicit load of a held motion comes from the local Hessians.
        let request = Request {
            tangent: request.tangent || (request.loads && self.layout.held_parameter().is_some()),
            ..request
        };
        out.reset(request);
        let mut x = std::mem::take(&mut out.positions);
        x.clear();
        x.extend_from_slice(&self.reference);
        self.layout.add_displacements(u, &mut x);
        self.layout.add_held_motion(params, &mut x);
        let result = (|| {
            for effect in &self.effects {
                let mut asm = Assembler::new(&self.layout, out, request, effect.name());
                effect.assemble(&x, params, &mut asm)?;
            }
            out.finish(&self.layout);
            out.check_finite()
        })();
        out.positions = x;
        result
    }
}
