//! An abstract invariant potential with branches known in closed form (docs/theory.md §14.6):
//! not a load, but a test problem for branch switching on a mesh with a large group.
//!
//! A node's radial displacement is w_i = n_i · u_i (n_i the unit vector from the origin to
//! the reference node X_i). The group acts on such fields by permuting the nodes, and
//! `z = P w` is the part of w in one irrep μ (P = (d/|G|) Σ_g χ_μ(g) Π_g, the isotypic
//! projector of the node permutation representation). With the parameter λ,
//!
//! ```text
//!   Π(u; λ) = ½ |u|² − ½ f(λ) |z|² + c₃ I₃(z) + c₃' J₃(z) + c₄ |z|⁴,      z = P w,
//!   I₃(z) = Σ_i z_i³,   J₃(z) = tr Q(z)³,   Q(z) = Σ_i z_i (n_i n_iᵀ − I/3).
//! ```
//!
//! Every term is invariant: P commutes with every Π_g; I₃ and |z|² are sums over the nodes;
//! Q(Π_g z) = R_g Q(z) R_gᵀ because R_g n_i = n_{π_g(i)}, and the trace of its cube is
//! invariant under any rotation. (Two cubics, because one alone may vanish on some axial
//! line: I₃ does on the D3d lines of the icosahedron's Hg.) u = 0 is an equilibrium for
//! every λ; with f(λ) = λ (the default) its tangent is I − λ N P Nᵀ (N: w ↦ u, u_i = w_i n_i,
//! an isometry), so the eigenvalue 1 − λ of the fields in range(P) crosses zero at λ = 1 in
//! irrep μ, d-fold. On an axial line z = a v (v ∈ Fix(Σ) ∩ range(P), |v| = 1) the
//! equilibrium equations reduce to the closed form f(λ) = 1 + 3 (c₃ I₃(v) + c₃' J₃(v)) a +
//! 4 c₄ a² (docs/theory.md §14.6). With f(λ) = λ − μ λ² ([`IrrepPotential::with_curvature`])
//! the eigenvalue 1 − f(λ) vanishes at two values of λ and each axial branch joins them.
//!
//! The Hessian of the z-terms has rank d: it is handed over as d rank-one terms c a aᵀ, from
//! the eigen-decomposition of its d × d restriction to an orthonormal basis of range(P).

use crate::model::{Assembler, Effect, ModelError, Vec3};
use meshes::GroupAction;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use symmetry::Invariant;

/// Π = ½|u|² − ½ λ |z|² + c₃ Σ z_i³ + c₃' tr Q(z)³ + c₄ |z|⁴, z = P w, on the radial
/// fields' part in one irrep (module docs).
#[derive(Debug, Clone)]
pub struct IrrepPotential {
    reference: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// An orthonormal basis of range(P), nodes × d.
    range: DMatrix<f64>,
    parameter: usize,
    /// c₃, c₃', c₄.
    coefficients: [f64; 3],
    /// μ in f(λ) = λ − μ λ² (0: f = λ).
    curvature: f64,
}

impl IrrepPotential {
    /// The potential of the radial fields' part in `irrep` of the action's group, with λ the
    /// parameter of index `parameter` and `coefficients` = [c₃, c₃', c₄]. Every reference
    /// node must be away from the origin.
    /// Errors name the irrep when the group has none of that name or the radial fields have
    /// no part in it.
    pub fn new(
        action: &GroupAction,
        reference: &[Vec3],
        irrep: &str,
        parameter: usize,
        coefficients: [f64; 3],
    ) -> Result<Self, String> {
        let group = action.group();
        let mu = group
            .irrep(irrep)
            .ok_or_else(|| format!("{} has no irrep {irrep}", group.name()))?;
        let n = reference.len();
        if reference.iter().any(|x| x.norm() == 0.0) {
            return Err("a node at the origin has no radial direction".into());
        }
        // P = (d/|G|) Σ_g χ(g) Π_g with (Π_g)_{π_g(i), i} = 1.
        let mut p = DMatrix::<f64>::zeros(n, n);
        for g in 0..group.order() {
            let chi = mu.character(g);
            for (i, &j) in action.node_perm(g).iter().enumerate() {
                p[(j, i)] += chi;
            }
        }
        p *= mu.dim() as f64 / group.order() as f64;
        let eig = SymmetricEigen::new(p);
        let columns: Vec<DVector<f64>> = (0..n)
            .filter(|&k| eig.eigenvalues[k] > 0.5)
            .map(|k| eig.eigenvectors.column(k).into_owned())
            .collect();
        if columns.is_empty() {
            return Err(format!(
                "the radial fields of the mesh have no part in {irrep} of {}",
                group.name()
            ));
        }
        Ok(Self {
            reference: reference.to_vec(),
            normals: reference.iter().map(|x| x.normalize()).collect(),
            range: DMatrix::from_columns(&columns),
            parameter,
            coefficients,
            curvature: 0.0,
        })
    }

    /// The same potential with −½ f(λ) |z|², f(λ) = λ − μ λ², in place of −½ λ |z|²: the
    /// trivial path's eigenvalue 1 − f(λ) in the irrep then vanishes twice (at the roots of
    /// μ λ² − λ + 1 for 0 < μ < ¼), and every axial branch joins the two points (§14.6).
    pub fn with_curvature(mut self, mu: f64) -> Self {
        self.curvature = mu;
        self
    }

    /// d·m: the dimension of range(P) (the irrep's dimension times its multiplicity in the
    /// node permutation representation).
    pub fn rank(&self) -> usize {
        self.range.ncols()
    }

    /// The radial field w of positions `x` (w_i = n_i · (x_i − X_i)).
    pub fn radial(&self, x: &[Vec3]) -> DVector<f64> {
        DVector::from_iterator(
            self.reference.len(),
            x.iter()
                .zip(&self.reference)
                .zip(&self.normals)
                .map(|((x, x0), n)| n.dot(&(x - x0))),
        )
    }

    /// z = P w.
    pub fn project(&self, w: &DVector<f64>) -> DVector<f64> {
        &self.range * (self.range.transpose() * w)
    }

    /// A_i = n_i n_iᵀ − I/3.
    fn tensor(&self, i: usize) -> nalgebra::Matrix3<f64> {
        let n = self.normals[i];
        n * n.transpose() - nalgebra::Matrix3::identity() / 3.0
    }

    /// Q(z) = Σ_i z_i A_i.
    pub fn quadrupole(&self, z: &DVector<f64>) -> nalgebra::Matrix3<f64> {
        (0..z.len()).map(|i| self.tensor(i) * z[i]).sum()
    }

    /// The two cubic invariants (I₃(z), J₃(z)) = (Σ z_i³, tr Q(z)³).
    pub fn cubics(&self, z: &DVector<f64>) -> (f64, f64) {
        let q = self.quadrupole(z);
        (z.iter().map(|v| v.powi(3)).sum(), (q * q * q).trace())
    }
}

impl Effect for IrrepPotential {
    fn name(&self) -> &str {
        "irrep-potential"
    }

    fn keeps(&self) -> Vec<Invariant> {
        Vec::new()
    }

    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        Vec::new()
    }

    fn assemble(
        &self,
        x: &[Vec3],
        params: &[f64],
        out: &mut Assembler<'_>,
    ) -> Result<(), ModelError> {
        // f(λ) = λ − μ λ², which multiplies |z|²/2 (§14.6).
        let l = params[self.parameter];
        let lambda = l - self.curvature * l * l;
        let rate = 1.0 - 2.0 * self.curvature * l;
        let [c3, c3t, c4] = self.coefficients;
        let z = self.project(&self.radial(x));
        let zz = z.norm_squared();
        let (i3, j3) = self.cubics(&z);
        out.add_energy(-0.5 * lambda * zz + c3 * i3 + c3t * j3 + c4 * zz * zz);
        // ∂/∂w = −λ z + P (3 c₃ z∘z + 3 c₃' (tr(Q² A_i))_i) + 4 c₄ |z|² z.
        let q = self.quadrupole(&z);
        let q2 = q * q;
        let cubic_grad = DVector::from_iterator(
            z.len(),
            (0..z.len())
                .map(|i| 3.0 * c3 * z[i] * z[i] + 3.0 * c3t * (q2 * self.tensor(i)).trace()),
        );
        let grad = -lambda * &z + self.project(&cubic_grad) + &z * (4.0 * c4 * zz);
        let reference = &self.reference;
        let normals = &self.normals;
        out.add_nodes(x, [Some(self.parameter), None], |i, xi, t| {
            let u = xi - reference[i];
            let n = normals[i];
            t.value = 0.5 * u.norm_squared();
            let g = u + n * grad[i];
            t.grad = [g.x, g.y, g.z];
            t.hess = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            t.loads[0] = [-rate * z[i] * n.x, -rate * z[i] * n.y, -rate * z[i] * n.z];
            Ok(())
        })?;
        if out.request().tangent {
            // ∂²/∂w² = −λ P + P (6 c₃ diag(z) + 6 c₃' [tr(Q A_i A_j)]) P
            //          + 4 c₄ (|z|² P + 2 z zᵀ), whose range lies in range(P) = range(Y):
            // restricted to Y it is the d × d matrix M.
            let y = &self.range;
            let n = y.nrows();
            let mut m = DMatrix::<f64>::identity(y.ncols(), y.ncols()) * (-lambda + 4.0 * c4 * zz);
            let yz = y.transpose() * &z;
            m += &yz * yz.transpose() * (8.0 * c4);
            let tensors: Vec<nalgebra::Matrix3<f64>> = (0..n).map(|i| self.tensor(i)).collect();
            let hz = DMatrix::from_fn(n, n, |i, j| {
                let diag = if i == j { 6.0 * c3 * z[i] } else { 0.0 };
                diag + 6.0 * c3t * (q * tensors[i] * tensors[j]).trace()
            });
            m += y.transpose() * hz * y;
            let eig = SymmetricEigen::new(m);
            for (k, &c) in eig.eigenvalues.iter().enumerate() {
                let w = y * eig.eigenvectors.column(k);
                let a = out.node_vector(|i| (normals[i] * w[i]).into());
                out.add_rank_one(c, a);
            }
        }
        Ok(())
    }
}
