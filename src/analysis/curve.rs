//! The `critical-curve` analysis (docs/theory.md §11.7): a critical point of the path in the
//! control, followed as a second parameter varies.
//!
//! The point is found on the path in the control (the second parameter held), by the index
//! changes of the irrep blocks ([`crate::continuation::events::IndexChanges`]). Its block μ is singular
//! there with a *simple* zero — also at a d-fold bifurcation point of K, whose d partner
//! blocks are identical — so the minimally augmented test function of the bordered block
//!
//! ```text
//!   [[K_μ, b], [bᵀ, 0]] [v; σ] = [0; 1]
//! ```
//!
//! vanishes exactly where K_μ is singular, and its derivatives are σ_z = −vᵀ (∂K_μ/∂z) v
//! for every unknown z (K_μ symmetric: the left and right vectors coincide). The curve is the
//! path of R = 0 (the equilibrium in the fixed-point space), g = 0 (the constraints) and
//! σ = 0 in (q, second, the constraints' parameters, control), followed by the ordinary
//! [`Continuation`] driver with σ as one more augmenting equation ([`CurveProblem`]) and
//! watched by the ordinary detectors: a turning point of the second parameter on a limit
//! curve is a cusp (two limit points merge). Unless `watch = false`, the other blocks'
//! negative counts are watched at every curve point (`OtherBlocks`): where one changes, that block is singular together
//! with the curve's — a hilltop (one of them trivial) or a change of the critical irrep —
//! localised on the curve by the path's own routine (docs/theory.md §11.9).
//!
//! With a = B_μ v the critical vector in the full space, vᵀ (∂K_μ/∂u · e) v = D³Π[a, a, e]
//! = eᵀ (d/dε) K(u + εa) a, and vᵀ (∂K_μ/∂Λ_j) v = (d/dε) aᵀ ∂F/∂Λ_j(u + εa): both come
//! from one pair of evaluations at u ± εa, by central differences of the tangent and of the
//! loads ([`BlockTest::evaluate`]; the step is [`DIFFERENCE_STEP`], tested for accuracy). On
//! a limit curve a is symmetric, and every evaluation assembles only the triangles around the
//! orbit representatives; for another block u ± εa is not symmetric, and those two assemble
//! the whole mesh.

use super::{Observer, Record, RunError, SymmetricProblem};
use crate::adapted::SparseBasis;
use crate::continuation::crossings::Spectrum;
use crate::continuation::crossings::{Crossings, End, IndexChanges};
use crate::continuation::events::{Detector, Event, States};
use crate::continuation::{Accepted, Continuation, Linearization, PathOptions, PathPoint, Problem};
use crate::model::check::tangent_times;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Model, ModelError, Request, Subset};
use crate::results::{
    CriticalKind, CriticalPoint, CurveEvent, CurveEventKind, CurveReport, CurveRow, PhaseTimes,
    RecordedPoint, RunTimes, StateKind, StopReason,
};
use crate::scene::{Analysis, CurveStart, Direction};
use crate::study::Study;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

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

/// σ, the null vector of the bordered block and the derivatives of σ.
#[derive(Debug, Clone)]
pub struct TestValue {
    /// σ.
    pub sigma: f64,
    /// v in the block's coordinates (bᵀ v = 1).
    pub vector: DVector<f64>,
    /// ∂σ/∂q in the fixed-point coordinates: −B₀ᵀ D³Π[a, a, ·].
    pub grad_q: DVector<f64>,
    /// ∂σ/∂Λ_j for every parameter of the model.
    pub grad_params: Vec<f64>,
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
        let m = k.nrows();
        let mut a = DMatrix::zeros(m + 1, m + 1);
        a.view_mut((0, 0), (m, m)).copy_from(k);
        a.view_mut((0, m), (m, 1)).copy_from(&self.border);
        a.view_mut((m, 0), (1, m))
            .copy_from(&self.border.transpose());
        let mut rhs = DVector::zeros(m + 1);
        rhs[m] = 1.0;
        let x = crate::linalg::bordered::solve_dense(a, &rhs)
            .filter(|x| x.iter().all(|v| v.is_finite()))
            .ok_or_else(|| ModelError::Global {
                effect: "critical block".into(),
                what: "the bordered block is singular (its border is orthogonal to the kernel)"
                    .into(),
            })?;
        Ok((x[m], x.rows(0, m).into_owned()))
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

/// The curve's problem: the fixed-point problem with the second parameter free, plus σ = 0.
/// Its free parameters are (second, the constraints' parameters, control).
pub struct CurveProblem<'a> {
    inner: SymmetricProblem<'a>,
    test: BlockTest<'a>,
    /// The parameter index of every free parameter, in the order of λ.
    free: Vec<usize>,
    /// The last evaluated (q, λ) and its null vector v.
    last: Option<(DVector<f64>, DVector<f64>, DVector<f64>)>,
}

impl<'a> CurveProblem<'a> {
    /// The curve of `test`'s block in the problem `inner`, whose free parameters are the
    /// parameter indices `free`.
    pub fn new(inner: SymmetricProblem<'a>, test: BlockTest<'a>, free: Vec<usize>) -> Self {
        Self {
            inner,
            test,
            free,
            last: None,
        }
    }

    /// The null vector v at (q, λ): from the last evaluation when it was there.
    fn null_vector(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<DVector<f64>, ModelError> {
        if let Some((lq, ll, v)) = &self.last {
            if lq == q && ll == lambda {
                return Ok(v.clone());
            }
        }
        let (u, params) = (self.inner.displacement(q), self.inner.parameters(lambda));
        Ok(self.test.value(&u, &params)?.1)
    }

    /// The test function, to refresh its border or evaluate it at a point.
    pub fn test_mut(&mut self) -> &mut BlockTest<'a> {
        &mut self.test
    }
}

impl Problem for CurveProblem<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn free_parameters(&self) -> usize {
        self.inner.free_parameters()
    }

    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        let mut lin = self.inner.evaluate(q, lambda)?;
        let u = self.inner.displacement(q);
        let params = self.inner.parameters(lambda);
        let t = self.test.evaluate(&u, &params)?;
        let (m, c, nf) = (q.len(), lin.constraints.len(), lambda.len());
        let sigma_q = &t.grad_q;
        self.last = Some((q.clone(), lambda.clone(), t.vector.clone()));
        let mut constraints = DVector::zeros(c + 1);
        constraints.rows_mut(0, c).copy_from(&lin.constraints);
        constraints[c] = t.sigma;
        lin.constraints = constraints;
        let mut gq = DMatrix::zeros(c + 1, m);
        gq.view_mut((0, 0), (c, m)).copy_from(&lin.constraint_q);
        gq.row_mut(c).copy_from(&sigma_q.transpose());
        let mut gl = DMatrix::zeros(c + 1, nf);
        gl.view_mut((0, 0), (c, nf))
            .copy_from(&lin.constraint_lambda);
        for (j, &i) in self.free.iter().enumerate() {
            gl[(c, j)] = t.grad_params[i];
        }
        lin.constraint_q = gq;
        lin.constraint_lambda = gl;
        Ok(lin)
    }

    fn phase_times(&self) -> PhaseTimes {
        self.inner.times
    }
}

impl States for CurveProblem<'_> {
    fn displacement(&self, q: &DVector<f64>) -> Vec<f64> {
        self.inner.displacement(q)
    }

    fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        self.inner.parameters(lambda)
    }
}

/// Refreshes the border of the test function to the null vector at every accepted point, so
/// that the bordered block stays well conditioned along the curve.
struct RefreshBorder;

impl Detector<CurveProblem<'_>> for RefreshBorder {
    fn check(
        &mut self,
        driver: &mut Continuation<CurveProblem<'_>>,
        _: &Accepted,
        _: usize,
    ) -> Vec<Event> {
        let p = driver.point().clone();
        let problem = driver.problem_mut();
        let (u, params) = (problem.displacement(&p.q), problem.parameters(&p.lambda));
        match problem.null_vector(&p.q, &p.lambda).and_then(|v| {
            let test = problem.test_mut();
            test.set_border(&v);
            test.rescale(&u, &params)
        }) {
            Ok(()) => Vec::new(),
            Err(e) => vec![Event::Warning(format!(
                "the critical block could not be evaluated to refresh its border: {e}"
            ))],
        }
    }
}

/// The blocks other than `own` whose negative count differs between two curve points
/// (`before`, `after`: the count of every block, the trivial first). The curve's own block is
/// singular all along the curve, so its count is noise and never an event.
pub fn changed_blocks(own: usize, before: &[usize], after: &[usize]) -> Vec<usize> {
    before
        .iter()
        .zip(after)
        .enumerate()
        .filter(|&(nu, (a, b))| nu != own && a != b)
        .map(|(nu, _)| nu)
        .collect()
}

/// What it is where block `other` becomes singular on the curve of block `own` (block 0 the
/// trivial one): a hilltop when either is trivial — a limit point meets a bifurcation point —
/// else a change of the critical irrep, two bifurcation curves crossing.
pub fn crossing_kind(own: usize, other: usize) -> CurveEventKind {
    if own == 0 || other == 0 {
        CurveEventKind::Hilltop
    } else {
        CurveEventKind::IrrepChange
    }
}

/// Watches the other irrep blocks along a curve: where the negative count of a block other
/// than the curve's own changes between two curve points, that block is singular together
/// with the curve's somewhere in between — a hilltop when one of the two is the trivial block,
/// a change of the critical irrep otherwise. The crossing is localised on the curve's
/// arclength by [`Crossings::localise`], the same routine as on a path, with the curve's own
/// block left out (its eigenvalue is zero all along, its count noise).
struct OtherBlocks<'a> {
    crossings: Crossings<'a>,
    /// The curve's block.
    own: usize,
    previous: Option<(Spectrum, Vec<f64>, Vec<f64>)>,
}

impl OtherBlocks<'_> {
    /// The index spectrum at `point` with the curve's own block's count zeroed, remembered;
    /// returns the earlier one.
    fn observe(
        &mut self,
        problem: &CurveProblem<'_>,
        point: &PathPoint,
    ) -> Option<(Spectrum, Vec<f64>, Vec<f64>)> {
        let u = problem.displacement(&point.q);
        let params = problem.parameters(&point.lambda);
        let spectrum = self.crossings.index(&u, &params).map(|mut s| {
            s.blocks[self.own].negative = 0;
            s
        });
        std::mem::replace(&mut self.previous, spectrum.map(|s| (s, u, params)))
    }
}

impl<'b> Detector<CurveProblem<'b>> for OtherBlocks<'_> {
    fn start(&mut self, driver: &mut Continuation<CurveProblem<'b>>) -> Vec<Event> {
        let point = driver.point().clone();
        self.observe(driver.problem(), &point);
        Vec::new()
    }

    fn check(
        &mut self,
        driver: &mut Continuation<CurveProblem<'b>>,
        step: &Accepted,
        after: usize,
    ) -> Vec<Event> {
        let point = driver.point().clone();
        let previous = self.observe(driver.problem(), &point);
        let (Some((a, u0, p0)), Some((b, u1, p1))) = (&previous, &self.previous) else {
            return Vec::new();
        };
        if changed_blocks(self.own, &a.negatives(), &b.negatives()).is_empty() {
            return Vec::new();
        }
        let s1 = point.arclength - step.from.arclength;
        let ends = (
            End {
                spectrum: a,
                u: u0,
                params: p0,
            },
            End {
                spectrum: b,
                u: u1,
                params: p1,
            },
        );
        self.crossings
            .localise(ends.0, ends.1, after, s1, false, |s| {
                let q = driver.corrected_from(&step.from, s).ok()?;
                let problem = driver.problem();
                Some((problem.displacement(&q.q), problem.parameters(&q.lambda)))
            })
    }
}

/// Watches the path for critical points and stops it at the one `from` asks for.
struct FirstCritical<'a> {
    index: IndexChanges<'a>,
    from: CurveStart,
    seen: usize,
}

impl FirstCritical<'_> {
    fn wanted(&mut self, cp: &CriticalPoint) -> bool {
        let hit = match &self.from {
            CurveStart::Limit => cp.kind == CriticalKind::LimitPoint,
            CurveStart::Irrep(name) => cp.irrep == *name,
            CurveStart::Index(i) => self.seen == *i,
        };
        self.seen += 1;
        hit
    }
}

impl<'b> Detector<SymmetricProblem<'b>> for FirstCritical<'_> {
    fn start(&mut self, driver: &mut Continuation<SymmetricProblem<'b>>) -> Vec<Event> {
        self.index.start(driver)
    }

    fn check(
        &mut self,
        driver: &mut Continuation<SymmetricProblem<'b>>,
        step: &Accepted,
        after: usize,
    ) -> Vec<Event> {
        let mut events = self.index.check(driver, step, after);
        let found = events.iter().any(|e| match e {
            Event::Critical(cp) => self.wanted(cp),
            _ => false,
        });
        if found {
            events.push(Event::Stop(StopReason::CriticalPoint));
        }
        events
    }
}

/// The point the curve starts from, in words, for messages.
fn describe(from: &CurveStart) -> String {
    match from {
        CurveStart::Limit => "limit point".into(),
        CurveStart::Irrep(name) => format!("critical point in {name}"),
        CurveStart::Index(i) => format!("critical point number {i}"),
    }
}

/// Finds the critical point on the path in the control, then follows it in (control,
/// second); the path is recorded in `record`, the curve returned.
#[allow(clippy::too_many_arguments)]
pub(super) fn run(
    study: &Study,
    record: &mut Record,
    crossings: Option<Crossings<'_>>,
    adapted: Option<&crate::adapted::AdaptedBasis>,
    u_start: &[f64],
    params_start: &[f64],
    observer: &mut dyn Observer,
    times: &mut RunTimes,
) -> Result<(StopReason, CurveReport), RunError> {
    let Analysis::CriticalCurve(analysis) = &study.scene.analysis else {
        unreachable!("curve::run runs critical-curve analyses")
    };
    let t0 = Instant::now();
    let (Some(crossings), Some(adapted)) = (crossings, adapted) else {
        return Err(RunError::Curve(
            "the critical curve needs the stability analysis by irrep, which this scene's \
             group does not allow"
                .into(),
        ));
    };
    if analysis.from_run.is_some() {
        let cp = saved_point(study)?;
        // The run's point is this run's one path row and critical point.
        record.row(study, 0, 0.0, &cp.state, cp.parameters.clone(), 0, None);
        record.state(0, StateKind::Step, cp.state.clone(), &cp.parameters);
        record.critical(cp.clone());
        times.path = t0.elapsed();
        let curve = follow_curve(study, crossings, adapted, &cp, observer)?;
        return Ok((StopReason::CriticalPoint, curve));
    }
    // The path in the control up to the point.
    let (mut driver, max_steps) = super::path::start_driver(study, u_start, params_start)?;
    let mut first = FirstCritical {
        index: IndexChanges::new(crossings),
        from: analysis.from.clone(),
        seen: 0,
    };
    let mut count = 0usize;
    let branch = {
        let mut extra: Vec<&mut dyn Detector<SymmetricProblem>> = vec![&mut first];
        crate::continuation::events::trace(
            &mut driver,
            max_steps,
            |_, _| None,
            &mut extra,
            |problem, p| {
                observer.progress(count, p.lambda[0]);
                observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                count += 1;
            },
        )
    };
    let path_problem = driver.into_problem();
    times.steps = branch.times;
    times.index = first.index.index_time;
    let indices = first.index.indices.clone();
    let crossings = first.index.into_crossings();
    super::path::record_branch(study, record, &path_problem, &branch, &indices, usize::MAX);
    times.path = t0.elapsed();
    let Some(cp) = (match branch.stop {
        StopReason::CriticalPoint => branch.critical_points().last().cloned(),
        _ => None,
    }) else {
        return Err(RunError::Curve(format!(
            "the path in '{}' found no {} (analysis.from) in {} steps: {}",
            analysis.control,
            describe(&analysis.from),
            branch.points.len() - 1,
            branch.stop
        )));
    };
    let curve = follow_curve(study, crossings, adapted, &cp, observer)?;
    Ok((branch.stop, curve))
}

/// The critical point of a finished run that `analysis.from-run` names, as loaded into the
/// study, with this model's measures.
fn saved_point(study: &Study) -> Result<CriticalPoint, RunError> {
    let Some(saved) = &study.saved_critical else {
        return Err(RunError::Curve(
            "analysis.from-run is set but its critical point was not loaded \
             (output::load_curve_start)"
                .into(),
        ));
    };
    let recorded = RecordedPoint {
        irrep: saved.irrep.clone(),
        parameters: saved.parameters.clone(),
        measures: study.measure(&saved.state, &saved.parameters),
        after_step: 0,
        residual_eigenvalue: saved.residual_eigenvalue,
    };
    let mut points = super::branch::recorded_points(
        study,
        &[recorded],
        1,
        saved.state.clone(),
        saved.mode.clone(),
    )
    .map_err(|e| RunError::Curve(format!("critical point {}: {e}", saved.number)))?;
    Ok(points.remove(0))
}

/// Follows the critical point `cp` in (control, second).
fn follow_curve(
    study: &Study,
    crossings: Crossings<'_>,
    adapted: &crate::adapted::AdaptedBasis,
    cp: &CriticalPoint,
    observer: &mut dyn Observer,
) -> Result<CurveReport, RunError> {
    let Analysis::CriticalCurve(analysis) = &study.scene.analysis else {
        unreachable!("curve::run runs critical-curve analyses")
    };
    let index = |name: &str| {
        study
            .parameters
            .iter()
            .position(|p| p == name)
            .expect("validated parameter")
    };
    let (control, second) = (index(&analysis.control), index(&analysis.second));
    let mu = adapted
        .irreps
        .iter()
        .position(|ib| ib.name == cp.irrep)
        .expect("the critical point's irrep is one of the basis");
    let ib = &adapted.irreps[mu];
    let block = ib.first();
    let x = study.model.positions(&cp.state, &cp.parameters);
    let rigid = study
        .model
        .rigid_motions()
        .iter()
        .any(|m| block.restrict_rigid(m, &x, study.model.layout()).amax() > 1e-9);
    if rigid {
        return Err(RunError::Curve(format!(
            "the block of {} holds rigid-body modes; following its critical points is not \
             supported yet",
            cp.irrep
        )));
    }
    let length = study
        .model
        .reference()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    let border = block.restrict(&cp.mode);
    let test = BlockTest::new(&study.model, block, &study.basis, mu == 0, &border, length)
        .with_constraints(&study.constraints, &cp.state, &cp.parameters)
        .map_err(|e| RunError::Curve(format!("the critical point's constraints: {e}")))?;
    let inner = SymmetricProblem::new(
        &study.model,
        &study.basis,
        &study.constraints,
        cp.parameters.clone(),
        Some(second),
    )
    .with_free_parameter(control);
    let free: Vec<usize> = std::iter::once(second)
        .chain(study.constraints.iter().map(|c| c.frees()))
        .chain(std::iter::once(control))
        .collect();
    let lambda0 = inner.free_values(&cp.parameters);
    let q0 = study.basis.restrict(&cp.state);
    let bounds = |i: usize| {
        let p = &study.scene.parameters[&study.parameters[i]];
        (
            p.min.unwrap_or(f64::NEG_INFINITY),
            p.max.unwrap_or(f64::INFINITY),
        )
    };
    let opts = PathOptions {
        initial_step: analysis.initial_step,
        min_step: analysis.min_step,
        max_step: analysis.max_step,
        max_steps: analysis.steps,
        max_iterations: analysis.max_iterations,
        tolerance: analysis.tolerance,
        bounds: bounds(second),
        parameter_scales: vec![1.0; free.len()],
        state_scale: super::equilibrium::state_scale(study),
        direction: match analysis.direction {
            Direction::Increase => 1.0,
            Direction::Decrease => -1.0,
        },
    };
    let last = free.len() - 1;
    let problem = CurveProblem::new(inner, test, free);
    let mut driver = Continuation::start(problem, &q0, &lambda0, opts).map_err(|e| {
        RunError::Curve(format!(
            "the critical point did not converge as the first point of the curve: {e}"
        ))
    })?;
    let control_bounds = bounds(control);
    // `trace` watches the turning points of λ_0, the second parameter: cusps and folds.
    let mut refresh = RefreshBorder;
    let mut others = OtherBlocks {
        crossings,
        own: mu,
        previous: None,
    };
    let mut count = 0usize;
    let branch = {
        let mut extra: Vec<&mut dyn Detector<CurveProblem>> = vec![&mut refresh];
        if analysis.watch {
            extra.push(&mut others);
        }
        crate::continuation::events::trace(
            &mut driver,
            analysis.steps,
            |_, p: &PathPoint| {
                let c = p.lambda[last];
                (c < control_bounds.0 || c > control_bounds.1).then_some(StopReason::Bounds)
            },
            &mut extra,
            |problem: &CurveProblem, p| {
                observer.progress(count, p.lambda[0]);
                observer.state(&problem.displacement(&p.q), &problem.parameters(&p.lambda));
                count += 1;
            },
        )
    };
    let mut problem = driver.into_problem();
    let mut report = CurveReport {
        control: analysis.control.clone(),
        second: analysis.second.clone(),
        irrep: cp.irrep.clone(),
        kind: cp.kind,
        multiplicity: cp.multiplicity,
        parameters: study.parameters.clone(),
        measures: study.measures.iter().map(|(n, _)| n.clone()).collect(),
        rows: Vec::new(),
        events: Vec::new(),
        stop: branch.stop.clone(),
        warnings: branch
            .events
            .iter()
            .filter_map(|e| match e {
                Event::Warning(w) => Some(w.clone()),
                _ => None,
            })
            .collect(),
    };
    for (i, p) in branch.points.iter().enumerate() {
        let u = problem.displacement(&p.q);
        let params = problem.parameters(&p.lambda);
        let test = problem.test_mut();
        let (critical, second_eigenvalue) = test
            .rescale(&u, &params)
            .and_then(|()| test.block_tangent(&u, &params))
            .map(|(k, scale)| nearest_eigenvalues(&k, scale))
            .unwrap_or((f64::NAN, f64::NAN));
        report.rows.push(CurveRow {
            step: i,
            arclength: p.arclength,
            measures: study.measure(&u, &params),
            parameters: params,
            iterations: p.iterations,
            critical_eigenvalue: critical,
            second_eigenvalue,
        });
    }
    let event = |kind, extremum, after_step: usize, point: &PathPoint| {
        let u = problem.displacement(&point.q);
        let params = problem.parameters(&point.lambda);
        CurveEvent {
            kind,
            extremum,
            irrep: None,
            residual_eigenvalue: None,
            after_step,
            measures: study.measure(&u, &params),
            parameters: params,
        }
    };
    report
        .events
        .push(event(CurveEventKind::Start, None, 0, &branch.points[0]));
    for t in branch.turning_points() {
        let kind = if mu == 0 {
            CurveEventKind::Cusp
        } else {
            CurveEventKind::Fold
        };
        report
            .events
            .push(event(kind, Some(t.kind), t.after_step, &t.point));
    }
    for other in branch.critical_points() {
        // The other block singular together with the curve's.
        let nu = adapted
            .irreps
            .iter()
            .position(|ib| ib.name == other.irrep)
            .expect("the crossing's irrep is one of the basis");
        let kind = crossing_kind(mu, nu);
        report.events.push(CurveEvent {
            kind,
            extremum: None,
            irrep: Some(other.irrep.clone()),
            residual_eigenvalue: Some(other.residual_eigenvalue),
            after_step: other.after_step,
            parameters: other.parameters.clone(),
            measures: other.measures.clone(),
        });
    }
    // In curve order (stable: a turning point and a crossing in one step keep their order).
    report.events[1..].sort_by_key(|e| e.after_step);
    let n = branch.points.len() - 1;
    report
        .events
        .push(event(CurveEventKind::End, None, n, &branch.points[n]));
    Ok(report)
}

/// The eigenvalue of the symmetric `k` nearest zero and the next nearest, relative to
/// `scale`.
fn nearest_eigenvalues(k: &DMatrix<f64>, scale: f64) -> (f64, f64) {
    let n = k.nrows();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (k[(i, j)] + k[(j, i)]));
    let Ok(mut values) = m.self_adjoint_eigenvalues(faer::Side::Lower) else {
        return (f64::NAN, f64::NAN);
    };
    values.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    let at = |i: usize| values.get(i).map_or(f64::NAN, |v| v / scale);
    (at(0), at(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The events a curve's watch reports along a constructed sequence of negative counts
    /// (blocks A1, A2, E1, E2): on the E1 curve a change of E2 is a change of the critical
    /// irrep, a change of A1 a hilltop, and E1's own count never an event; on the limit curve
    /// (A1) every other block's change is a hilltop.
    #[test]
    fn the_watch_names_irrep_changes_and_hilltops_along_a_sequence() {
        let names = ["A1", "A2", "E1", "E2"];
        let sequence: [[usize; 4]; 5] = [
            [0, 0, 0, 0],
            [0, 0, 1, 0], // E1's own count: noise on its own curve
            [0, 0, 0, 1], // E2 becomes unstable: the E1 and E2 curves cross
            [1, 0, 1, 1], // A1: the E1 curve meets the limit curve
            [1, 1, 0, 1], // A2
        ];
        let events = |own: usize| -> Vec<(usize, &str, CurveEventKind)> {
            sequence
                .windows(2)
                .enumerate()
                .flat_map(|(step, w)| {
                    changed_blocks(own, &w[0], &w[1])
                        .into_iter()
                        .map(move |nu| (step, names[nu], crossing_kind(own, nu)))
                })
                .collect()
        };
        assert_eq!(
            events(2),
            vec![
                (1, "E2", CurveEventKind::IrrepChange),
                (2, "A1", CurveEventKind::Hilltop),
                (3, "A2", CurveEventKind::IrrepChange),
            ]
        );
        assert_eq!(
            events(0),
            vec![
                (0, "E1", CurveEventKind::Hilltop),
                (1, "E1", CurveEventKind::Hilltop),
                (1, "E2", CurveEventKind::Hilltop),
                (2, "E1", CurveEventKind::Hilltop),
                (3, "A2", CurveEventKind::Hilltop),
                (3, "E1", CurveEventKind::Hilltop),
            ]
        );
    }
}
