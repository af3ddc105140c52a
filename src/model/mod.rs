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
pub mod validity;

pub use assembly::{Assembler, Evaluation, Layout, NodeTerms, Request, Subset, TriangleTerms};
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

    /// What this effect leaves invariant (gravity: the direction −z; a plane: itself). The
    /// scene's group is the mesh group restricted to what every effect keeps.
    fn keeps(&self) -> Vec<Invariant>;

    /// The rigid motions that leave Π_e unchanged, as vectors (t_x, t_y, t_z, ω_x, ω_y, ω_z)
    /// of translations and rotations about axes through the origin spanning them. A free body
    /// has a zero tangent eigenvalue for every motion all its effects keep.
    fn rigid_motions(&self) -> Vec<[f64; 6]>;

    /// Adds Π_e and its derivatives at the current node positions `x` and parameters `params`.
    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError>;
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
    /// Current node positions x = X + u (fixed nodes at X).
    fn positions(&self, u: &[f64]) -> Vec<Vec3> {
        let mut x = self.reference().to_vec();
        self.layout().add_displacements(u, &mut x);
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
    /// Why the displacement `u` is not a membrane state (collapsed, torn, inside out or not
    /// finite; [`validity`]), or `None`.
    fn state_defect(&self, u: &[f64]) -> Option<StateDefect> {
        validity::state_defect(
            self.reference(),
            self.layout().triangles(),
            &self.positions(u),
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

    fn reference(&self) -> &[Vec3] {
        &self.reference
    }

    /// The rigid motions (t, ω) that every effect keeps, as an orthonormal basis of that
    /// subspace of ℝ⁶: the intersection of the effects' subspaces, computed as the null space
    /// of Σ_e (I − P_e). Empty when any node is fixed.
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        if self.layout.unknowns() < 3 * self.reference.len() {
            return Vec::new();
        }
        let mut sum = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        for e in &self.effects {
            let kept = e.rigid_motions();
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
        out.reset(request);
        let mut x = std::mem::take(&mut out.positions);
        x.clear();
        x.extend_from_slice(&self.reference);
        self.layout.add_displacements(u, &mut x);
        let result = (|| {
            for effect in &self.effects {
                let mut asm = Assembler::new(&self.layout, out, request, effect.name());
                effect.assemble(&x, params, &mut asm)?;
            }
            out.check_finite()
        })();
        out.positions = x;
        result
    }
}
