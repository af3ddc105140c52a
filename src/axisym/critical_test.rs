//! The minimally augmented test function of one Fourier block of the meridian (docs/theory.md
//! §11.7, §15.19): σ from the bordered block [[K̃_m, b], [bᵀ, 0]] [v; σ] = [0; 1], K̃_m the
//! block of wave number m with its border (the held motions and, for m = 0, the
//! constraints), singular exactly where the block restricted to its border's complement is.
//! Its derivatives σ_z = −vᵀ (∂K̃_m/∂z) v (K̃_m symmetric: the left and right null vectors
//! coincide) are central differences of the block's entries in every unknown q_i and every
//! parameter Λ_j: a meridian block costs a few hundred element evaluations, so the gradient
//! over a few hundred unknowns is cheap — the [`CriticalTest`] a critical curve of the meridian
//! follows.

use super::{AxisymModel, BlockLayout};
use crate::continuation::crossings::{CriticalTest, TestValue};
use crate::model::ModelError;
use nalgebra::{DMatrix, DVector};

/// The step of the differences, relative to the meridian's size (for an unknown) or to
/// max(|Λ_j|, 1) (for a parameter): central differences err by O(h²) from truncation and
/// O(u_round/h) from round-off, balanced near u_round^(1/3).
pub const DIFFERENCE_STEP: f64 = 1e-5;

/// The test function of the block of wave number m of a meridian model.
pub struct MeridianTest {
    model: AxisymModel,
    layout: BlockLayout,
    border: DVector<f64>,
    length: f64,
}

impl MeridianTest {
    /// The test function of block `m` of `model` (its constraint borders as set on it),
    /// bordered by `border` (a vector over the block's kept unknowns: the critical mode),
    /// normalised and padded with zeros over the block's border columns.
    pub fn new(model: AxisymModel, m: usize, border: &[f64]) -> Self {
        let layout = model.block_layout(m);
        let n = layout.kept + layout.border;
        let mut b = DVector::zeros(n);
        for (i, v) in border.iter().take(layout.kept).enumerate() {
            b[i] = *v;
        }
        let length = model
            .meridian
            .nodes
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0, f64::max)
            .max(1e-300);
        Self {
            border: &b / b.norm().max(1e-300),
            model,
            layout,
            length,
        }
    }

    /// The bordered block at (q, params), dense and symmetrised, and its largest entry.
    fn matrix(&self, q: &[f64], params: &[f64]) -> Result<(DMatrix<f64>, f64), ModelError> {
        let values = self
            .model
            .block_values(&self.layout, q, params)
            .map_err(super::problem::model_error)?;
        let scale = values
            .iter()
            .fold(0.0f64, |s, v| s.max(v.abs()))
            .max(1e-300);
        let n = self.layout.kept + self.layout.border;
        let d = self.layout.pattern.to_dense(&values);
        let k = DMatrix::from_fn(n, n, |i, j| 0.5 * (d[(i, j)] + d[(j, i)]));
        Ok((k, scale))
    }

    /// σ and v from the bordered block `k`.
    fn solve(&self, k: &DMatrix<f64>) -> Result<(f64, DVector<f64>), ModelError> {
        crate::linalg::bordered::test_function(k, &self.border).ok_or_else(|| ModelError::Global {
            effect: "critical block".into(),
            what: "the bordered block is singular (its border is orthogonal to the kernel)".into(),
        })
    }

    /// vᵀ K̃_m v at (q, params).
    fn quadratic(&self, q: &[f64], params: &[f64], v: &DVector<f64>) -> Result<f64, ModelError> {
        let values = self
            .model
            .block_values(&self.layout, q, params)
            .map_err(super::problem::model_error)?;
        let n = v.len();
        let mut y = vec![0.0; n];
        self.layout.pattern.matvec(&values, v.as_slice(), &mut y);
        Ok(v.iter().zip(&y).map(|(a, b)| a * b).sum())
    }
}

impl CriticalTest for MeridianTest {
    fn evaluate(&mut self, u: &[f64], params: &[f64]) -> Result<TestValue, ModelError> {
        let (sigma, vector) = self.value(u, params)?;
        let h = DIFFERENCE_STEP * self.length;
        let mut grad_q = DVector::zeros(u.len());
        let mut shifted = u.to_vec();
        for i in 0..u.len() {
            shifted[i] = u[i] + h;
            let plus = self.quadratic(&shifted, params, &vector)?;
            shifted[i] = u[i] - h;
            let minus = self.quadratic(&shifted, params, &vector)?;
            shifted[i] = u[i];
            grad_q[i] = -(plus - minus) / (2.0 * h);
        }
        let mut grad_params = vec![0.0; params.len()];
        let mut p = params.to_vec();
        for j in 0..params.len() {
            let h = DIFFERENCE_STEP * params[j].abs().max(1.0);
            p[j] = params[j] + h;
            let plus = self.quadratic(u, &p, &vector)?;
            p[j] = params[j] - h;
            let minus = self.quadratic(u, &p, &vector)?;
            p[j] = params[j];
            grad_params[j] = -(plus - minus) / (2.0 * h);
        }
        Ok(TestValue {
            sigma,
            vector,
            grad_q,
            grad_params,
        })
    }

    fn value(&mut self, u: &[f64], params: &[f64]) -> Result<(f64, DVector<f64>), ModelError> {
        let (k, _) = self.matrix(u, params)?;
        self.solve(&k)
    }

    fn set_border(&mut self, border: &DVector<f64>) {
        self.border = border / border.norm().max(1e-300);
    }

    fn block_tangent(
        &mut self,
        u: &[f64],
        params: &[f64],
    ) -> Result<(DMatrix<f64>, f64), ModelError> {
        self.matrix(u, params)
    }
}
