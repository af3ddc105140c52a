//! The minimally augmented test function of one irrep's block of a 3-D model (docs/theory.md
//! §11.7, §11.11): σ from the bordered block K_μ = B_μᵀ K B_μ, its derivatives
//! σ_z = −vᵀ (∂K_μ/∂z) v by directional differences of the tangent and the loads along the
//! critical vector a = B_μ v, and the trivial block bordered by the active constraints — the
//! [`CriticalTest`] a critical curve of a mesh study follows.
//!
//! With a = B_μ v the critical vector in the full space, vᵀ (∂K_μ/∂u · e) v = D³Π[a, a, e]
//! = eᵀ (d/dε) K(u + εa) a, and vᵀ (∂K_μ/∂Λ_j) v = (d/dε) aᵀ ∂F/∂Λ_j(u + εa): both come
//! from one pair of evaluations at u ± εa, by central differences of the tangent and of the
//! loads ([`BlockTest::evaluate`]; the step is [`DIFFERENCE_STEP`], tested for accuracy). On
//! a limit curve a is symmetric, and every evaluation assembles only the triangles around the
//! orbit representatives; for another block u ± εa is not symmetric, and those two assemble
//! the whole mesh.

use crate::adapted::SparseBasis;
use crate::continuation::crossings::{CriticalTest, TestValue};
use crate::model::check::tangent_times;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Model, ModelError, Request, Subset};
use nalgebra::{DMatrix, DVector};

/// The step of the directional differences along the critical vector a, relative to the
/// mesh size L: |ε a|∞ = `DIFFERENCE_STEP` · L. Central differences of the tangent err by
/// O(ε²) from truncation and O(u_round/ε) from round-off; the balance is near u_round^(1/3)
/// ≈ 6e-6 (the accuracy is checked against Richardson extrapolation in the tests).
pub const DIFFERENCE_STEP: f64 = 1e-5;

/// The minimally augmented test function of one irrep's block at states of a model.
pub struct BlockTest<'a> {
    model: &'a dyn Model,
    block: &'a SparseBasis,
    fixed: &'a SparseBasis,
    trivial: bool,
    border: DVector<f64>,
    length: f64,
    /// Around the block's orbit representatives: all its restriction reads.
    eval: Evaluation,
    plus: Evaluation,
    minus: Evaluation,
    work: Vec<f64>,
    /// The active constraints bordering the trivial block (docs/theory.md §11.11), empty for
    /// any other block.
    constraints: &'a [Box<dyn Constraint>],
    /// The row scaling s_k of every constraint, held between refreshes.
    scales: Vec<f64>,
}

/// An evaluation of `model` around the orbit representatives of `basis` (the whole mesh
/// for a basis without orbit-local form).
fn local_evaluation(model: &dyn Model, basis: &SparseBasis) -> Evaluation {
    match basis.representatives() {
        Some(reps) => model
            .new_evaluation()
            .restricted_to(std::sync::Arc::new(Subset::around(model.layout(), &reps))),
        None => model.new_evaluation(),
    }
}

impl<'a> BlockTest<'a> {
    /// The test function of the block with basis `block` (the first partner of an irrep;
    /// `trivial` for the trivial irrep, whose block is the fixed-point space `fixed`),
    /// bordered by `border` (block coordinates, normalised here); `length` is the mesh size
    /// that scales the difference step.
    pub fn new(
        model: &'a dyn Model,
        block: &'a SparseBasis,
        fixed: &'a SparseBasis,
        trivial: bool,
        border: &DVector<f64>,
        length: f64,
    ) -> Self {
        // A critical vector of the trivial block is symmetric, and so are the states u ± εa:
        // the orbit representatives carry everything. Any other needs the whole mesh there.
        let shifted = || {
            if trivial {
                local_evaluation(model, fixed)
            } else {
                model.new_evaluation()
            }
        };
        Self {
            model,
            block,
            fixed,
            trivial,
            border: border / border.norm().max(1e-300),
            length,
            eval: local_evaluation(model, block),
            plus: shifted(),
            minus: shifted(),
            work: Vec::new(),
            constraints: &[],
            scales: Vec::new(),
        }
    }

    /// The test function of the trivial block bordered by the active `constraints`:
    /// K̃ = [[K_A, L], [s Gᵀ, s ∂g/∂μ]], the Jacobian of the augmented system in (q, the
    /// freed parameters) with each constraint row scaled by s_k as the stability analysis
    /// scales it, the scales taken at (u, params). The border is padded with zeros to the
    /// bordered size.
    pub fn with_constraints(
        mut self,
        constraints: &'a [Box<dyn Constraint>],
        u: &[f64],
        params: &[f64],
    ) -> Result<Self, ModelError> {
        if !self.trivial || constraints.is_empty() {
            return Ok(self);
        }
        self.constraints = constraints;
        let m = self.block.dim();
        if self.border.len() == m {
            let mut b = DVector::zeros(m + constraints.len());
            b.rows_mut(0, m).copy_from(&self.border);
            self.border = b;
        }
        self.rescale(u, params)?;
        Ok(self)
    }

    /// Takes the constraints' row scales at (u, params): s_k = G_k·L_k / |G_k|² (1 for a
    /// constraint without gradient), so that s_k G_k and L_k agree (docs/theory.md §8.3).
    pub fn rescale(&mut self, u: &[f64], params: &[f64]) -> Result<(), ModelError> {
        if self.constraints.is_empty() {
            return Ok(());
        }
        self.model
            .evaluate(u, params, Request::ALL, &mut self.eval)?;
        let x = self.model.positions(u, params);
        let layout = self.model.layout();
        self.scales = self
            .constraints
            .iter()
            .map(|con| {
                let g = self
                    .block
                    .restrict(&con.evaluate(layout, &x, params).grad_u);
                let l = self.block.restrict_invariant(&self.eval.loads[con.frees()]);
                if g.norm_squared() > 0.0 {
                    g.dot(&l) / g.norm_squared()
                } else {
                    1.0
                }
            })
            .collect();
        Ok(())
    }

    /// The bordered rows and columns at a state whose evaluation is `eval`:
    /// (L, s G, s ∂g/∂μ) in block coordinates.
    fn constraint_rows(
        &self,
        eval: &Evaluation,
        x: &[crate::model::Vec3],
        params: &[f64],
    ) -> (Vec<DVector<f64>>, Vec<DVector<f64>>, DMatrix<f64>) {
        let layout = self.model.layout();
        let c = self.constraints.len();
        let mut cc = DMatrix::zeros(c, c);
        let mut ls = Vec::with_capacity(c);
        let mut gs = Vec::with_capacity(c);
        for (k, con) in self.constraints.iter().enumerate() {
            let v = con.evaluate(layout, x, params);
            ls.push(self.block.restrict_invariant(&eval.loads[con.frees()]));
            gs.push(self.block.restrict(&v.grad_u) * self.scales[k]);
            for (j, other) in self.constraints.iter().enumerate() {
                cc[(k, j)] = self.scales[k] * v.grad_params[other.frees()];
            }
        }
        (ls, gs, cc)
    }

    /// The matrix whose singularity σ detects: K_μ, or K̃ with the constraints' border.
    fn test_matrix(&self, k: DMatrix<f64>, u: &[f64], params: &[f64]) -> DMatrix<f64> {
        if self.constraints.is_empty() {
            return k;
        }
        let (m, c) = (k.nrows(), self.constraints.len());
        let x = self.model.positions(u, params);
        let (ls, gs, cc) = self.constraint_rows(&self.eval, &x, params);
        let mut j = DMatrix::zeros(m + c, m + c);
        j.view_mut((0, 0), (m, m)).copy_from(&k);
        for kk in 0..c {
            j.view_mut((0, m + kk), (m, 1)).copy_from(&ls[kk]);
            j.view_mut((m + kk, 0), (1, m))
                .copy_from(&gs[kk].transpose());
        }
        j.view_mut((m, m), (c, c)).copy_from(&cc);
        j
    }

    /// Replaces the border (normalised here); σ's zero set does not change.
    pub fn set_border(&mut self, border: &DVector<f64>) {
        self.border = border / border.norm().max(1e-300);
    }

    /// K_μ = B_μᵀ K B_μ at (u, params) (the state symmetric under the scene's group), and
    /// max|K_ij| (of the assembled part) as its scale.
    pub fn block_tangent(
        &mut self,
        u: &[f64],
        params: &[f64],
    ) -> Result<(DMatrix<f64>, f64), ModelError> {
        self.model
            .evaluate(u, params, Request::ALL, &mut self.eval)?;
        let k = self
            .block
            .restrict_tangent(self.model.layout(), &self.eval, &mut self.work);
        let scale = self
            .eval
            .tangent
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300);
        if self.constraints.is_empty() {
            return Ok((k, scale));
        }
        let j = self.test_matrix(k, u, params);
        Ok(((&j + j.transpose()) * 0.5, scale))
    }

    /// σ and v from the bordered block `k` (the left null vector: from kᵀ).
    fn solve(&self, k: &DMatrix<f64>) -> Result<(f64, DVector<f64>), ModelError> {
        crate::linalg::bordered::test_function(k, &self.border).ok_or_else(|| ModelError::Global {
            effect: "critical block".into(),
            what: "the bordered block is singular (its border is orthogonal to the kernel)".into(),
        })
    }

    /// σ and v at (u, params); with constraints v = (v, w) over the block and the freed
    /// parameters.
    pub fn value(&mut self, u: &[f64], params: &[f64]) -> Result<(f64, DVector<f64>), ModelError> {
        self.matrix_value(u, params).map(|(s, v, _)| (s, v))
    }

    /// σ, the right null vector and the test matrix at (u, params).
    fn matrix_value(
        &mut self,
        u: &[f64],
        params: &[f64],
    ) -> Result<(f64, DVector<f64>, DMatrix<f64>), ModelError> {
        self.model
            .evaluate(u, params, Request::ALL, &mut self.eval)?;
        let k = self
            .block
            .restrict_tangent(self.model.layout(), &self.eval, &mut self.work);
        let j = self.test_matrix(k, u, params);
        let (sigma, v) = self.solve(&j)?;
        Ok((sigma, v, j))
    }

    /// The critical vector a = B_μ v over the model's unknowns, and the difference step ε
    /// along it ([`DIFFERENCE_STEP`] · L / |a|∞).
    pub fn critical_vector(&self, v: &DVector<f64>) -> (Vec<f64>, f64) {
        let mut a = vec![0.0; self.model.unknowns()];
        let v = v.rows(0, self.block.dim()).into_owned();
        self.block.expand(&v, &mut a);
        let amax = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
        (a, DIFFERENCE_STEP * self.length / amax)
    }

    /// σ, v and the derivatives of σ at (u, params), the directional differences along
    /// a = B_μ v with the step of [`BlockTest::critical_vector`].
    pub fn evaluate(&mut self, u: &[f64], params: &[f64]) -> Result<TestValue, ModelError> {
        if !self.constraints.is_empty() {
            return self.evaluate_constrained(u, params);
        }
        let (sigma, vector) = self.value(u, params)?;
        let (a, eps) = self.critical_vector(&vector);
        let (grad_q, grad_params) = self.third_derivatives(u, params, &a, eps)?;
        Ok(TestValue {
            sigma,
            vector,
            grad_q,
            grad_params,
        })
    }

    /// σ, φ and the derivatives of σ = −ψᵀ (∂K̃/∂z) φ for the trivial block bordered by the
    /// constraints (docs/theory.md §11.11), φ = (v, w) and ψ = (v', w') the right and left
    /// null vectors of K̃, a = B v and a' = B v'. With
    /// ψᵀ K̃ φ = v'ᵀ K v + Σ_k w_k a'ᵀ ∂F/∂μ_k + Σ_k w'_k s_k (aᵀ ∇g_k + Σ_j ∂g_k/∂μ_j w_j):
    /// the first term by the mixed directional differences along a'; the loads' term in q by
    /// its symmetry ∂(a'ᵀ ∂F/∂μ_k)/∂u = ∂(K a')/∂μ_k; the constraints' terms in q by
    /// differences of ∇g_k along a and in μ_j; every term in the parameters by central
    /// differences in each parameter. The scales s_k are held (set by [`BlockTest::rescale`]).
    fn evaluate_constrained(&mut self, u: &[f64], params: &[f64]) -> Result<TestValue, ModelError> {
        let (sigma, phi, j) = self.matrix_value(u, params)?;
        let (_, psi) = self.solve(&j.transpose())?;
        let (m, c) = (self.block.dim(), self.constraints.len());
        let (w, wl) = (phi.rows(m, c).into_owned(), psi.rows(m, c).into_owned());
        let (a, eps) = self.critical_vector(&phi);
        let (al, epsl) = self.critical_vector(&psi);
        let (mut grad_q, mut grad_params) =
            self.mixed_third_derivatives(u, params, &al, &a, epsl)?;
        let layout = self.model.layout();
        let x = self.model.positions(u, params);
        let v = phi.rows(0, m).into_owned();
        let vl = psi.rows(0, m).into_owned();
        // aᵀ ∇g_k along ±ε a: Hess g_k a.
        let shifted = |s: f64| -> Vec<f64> { u.iter().zip(&a).map(|(x, d)| x + s * d).collect() };
        let (xp, xm) = (
            self.model.positions(&shifted(eps), params),
            self.model.positions(&shifted(-eps), params),
        );
        for (k, con) in self.constraints.iter().enumerate() {
            let gp = con.evaluate(layout, &xp, params).grad_u;
            let gm = con.evaluate(layout, &xm, params).grad_u;
            let hess_a: Vec<f64> = gp
                .iter()
                .zip(&gm)
                .map(|(p, q)| (p - q) / (2.0 * eps))
                .collect();
            grad_q -= self.fixed.restrict(&hess_a) * (wl[k] * self.scales[k]);
        }
        // The border's part of ψᵀ K̃ φ at (u, Λ) from an evaluation there.
        let border_part = |test: &Self, e: &Evaluation, p: &[f64]| -> f64 {
            let (ls, gs, cc) = test.constraint_rows(e, &x, p);
            (0..c)
                .map(|k| {
                    w[k] * vl.dot(&ls[k]) + wl[k] * (gs[k].dot(&v) + cc.row(k).dot(&w.transpose()))
                })
                .sum()
        };
        for l in 0..params.len() {
            let h = DIFFERENCE_STEP * params[l].abs().max(1.0);
            let mut pp = params.to_vec();
            pp[l] += h;
            let mut pm = params.to_vec();
            pm[l] -= h;
            self.model.evaluate(u, &pp, Request::ALL, &mut self.plus)?;
            self.model.evaluate(u, &pm, Request::ALL, &mut self.minus)?;
            let d = (border_part(self, &self.plus, &pp) - border_part(self, &self.minus, &pm))
                / (2.0 * h);
            grad_params[l] -= d;
            for (k, con) in self.constraints.iter().enumerate() {
                if con.frees() != l {
                    continue;
                }
                // ∂(a'ᵀ ∂F/∂μ_k)/∂u = ∂(K a')/∂μ_k.
                let kp = tangent_times(self.model, &self.plus, &al);
                let km = tangent_times(self.model, &self.minus, &al);
                let dk: Vec<f64> = kp
                    .iter()
                    .zip(&km)
                    .map(|(p, q)| (p - q) / (2.0 * h))
                    .collect();
                grad_q -= self.fixed.restrict_invariant(&dk) * w[k];
                // Σ_i w'_i s_i w_k ∂∇g_i/∂μ_k.
                for (i, other) in self.constraints.iter().enumerate() {
                    let gp = other.evaluate(layout, &x, &pp).grad_u;
                    let gm = other.evaluate(layout, &x, &pm).grad_u;
                    let dg: Vec<f64> = gp
                        .iter()
                        .zip(&gm)
                        .map(|(p, q)| (p - q) / (2.0 * h))
                        .collect();
                    grad_q -= self.fixed.restrict(&dg) * (wl[i] * self.scales[i] * w[k]);
                }
            }
        }
        Ok(TestValue {
            sigma,
            vector: phi,
            grad_q,
            grad_params,
        })
    }

    /// −B₀ᵀ D³Π[a, a, ·] (fixed-point coordinates) and −aᵀ ∂K/∂Λ_j a for every parameter,
    /// by central differences of the tangent and the loads with step `eps` along `a`.
    pub fn third_derivatives(
        &mut self,
        u: &[f64],
        params: &[f64],
        a: &[f64],
        eps: f64,
    ) -> Result<(DVector<f64>, Vec<f64>), ModelError> {
        self.mixed_third_derivatives(u, params, a, a, eps)
    }

    /// −B₀ᵀ D³Π[s, a, ·] and −sᵀ ∂K/∂Λ_j a, by central differences with step `eps` along
    /// `shift` of the tangent times `a` and of aᵀ ∂F/∂Λ_j.
    fn mixed_third_derivatives(
        &mut self,
        u: &[f64],
        params: &[f64],
        shift: &[f64],
        a: &[f64],
        eps: f64,
    ) -> Result<(DVector<f64>, Vec<f64>), ModelError> {
        let shifted =
            |s: f64| -> Vec<f64> { u.iter().zip(shift).map(|(x, d)| x + s * d).collect() };
        self.model
            .evaluate(&shifted(eps), params, Request::ALL, &mut self.plus)?;
        self.model
            .evaluate(&shifted(-eps), params, Request::ALL, &mut self.minus)?;
        let kp = tangent_times(self.model, &self.plus, a);
        let km = tangent_times(self.model, &self.minus, a);
        let d3: Vec<f64> = kp
            .iter()
            .zip(&km)
            .map(|(p, m)| -(p - m) / (2.0 * eps))
            .collect();
        let (grad_q, grad_params) = if self.trivial {
            // Everything is G-invariant: exact at the orbit representatives, where the
            // restriction reads it; aᵀ L = αᵀ B₀ᵀ L with α = B₀ᵀ a.
            let alpha = self.fixed.restrict(a);
            let dot =
                |e: &Evaluation, j: usize| alpha.dot(&self.fixed.restrict_invariant(&e.loads[j]));
            let grad_params = (0..params.len())
                .map(|j| -(dot(&self.plus, j) - dot(&self.minus, j)) / (2.0 * eps))
                .collect();
            (self.fixed.restrict_invariant(&d3), grad_params)
        } else {
            let dot = |x: &[f64]| x.iter().zip(a).map(|(x, y)| x * y).sum::<f64>();
            let grad_params = (0..params.len())
                .map(|j| -(dot(&self.plus.loads[j]) - dot(&self.minus.loads[j])) / (2.0 * eps))
                .collect();
            (self.fixed.restrict(&d3), grad_params)
        };
        Ok((grad_q, grad_params))
    }
}

impl CriticalTest for BlockTest<'_> {
    fn evaluate(&mut self, u: &[f64], params: &[f64]) -> Result<TestValue, ModelError> {
        BlockTest::evaluate(self, u, params)
    }

    fn value(&mut self, u: &[f64], params: &[f64]) -> Result<(f64, DVector<f64>), ModelError> {
        BlockTest::value(self, u, params)
    }

    fn set_border(&mut self, border: &DVector<f64>) {
        BlockTest::set_border(self, border)
    }

    fn rescale(&mut self, u: &[f64], params: &[f64]) -> Result<(), ModelError> {
        BlockTest::rescale(self, u, params)
    }

    fn block_tangent(
        &mut self,
        u: &[f64],
        params: &[f64],
    ) -> Result<(DMatrix<f64>, f64), ModelError> {
        BlockTest::block_tangent(self, u, params)
    }
}
