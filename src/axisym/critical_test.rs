//! The minimally augmented test function of one Fourier block of the meridian (docs/theory.md
//! §11.7, §15.19): σ from the bordered block [[K̃_m, b], [bᵀ, 0]] [v; σ] = [0; 1], K̃_m the
//! block of wave number m with its border (the held motions and, for m = 0, the
//! constraints), singular exactly where the block restricted to its border's complement is.
//! Its derivatives σ_z = −vᵀ (∂K̃_m/∂z) v (K̃_m symmetric: the left and right null vectors
//! coincide) are central differences of the block's entries in every unknown q_i and every
//! parameter Λ_j, the unknowns of nodes that share no element shifted together where each
//! element's entries depend on its own nodes alone (§15.19) — the [`CriticalTest`] a critical
//! curve of the meridian follows.

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

    /// −vᵀ (∂K̃_m/∂q) v by central differences of the whole block in one unknown at a time:
    /// 2 n block evaluations.
    fn gradient_one_by_one(
        &self,
        u: &[f64],
        params: &[f64],
        v: &DVector<f64>,
        h: f64,
    ) -> Result<DVector<f64>, ModelError> {
        let mut grad = DVector::zeros(u.len());
        let mut shifted = u.to_vec();
        for i in 0..u.len() {
            grad[i] = -central(&mut shifted, i, h, |q| self.quadratic(q, params, v))?;
        }
        Ok(grad)
    }

    /// The same gradient when each element's part of the block depends on its own nodes
    /// alone (docs/theory.md §15.19): the unknowns of nodes i ≡ c (mod 3) in one component
    /// touch no element together (an element spans three consecutive nodes), so all of them
    /// are shifted at once and each element's difference goes to the one shifted unknown it
    /// holds — 12 evaluations of the elements' parts instead of 2 n of the block. The
    /// border's part (held motions and constraints, no Gauss points) is differenced one
    /// unknown at a time, its scale (the elements' largest entry at u) held fixed: the
    /// singular set does not depend on that scale, so σ = 0 is unchanged and the Jacobian
    /// only errs by O(σ) away from it.
    fn coloured_gradient(
        &self,
        u: &[f64],
        params: &[f64],
        v: &DVector<f64>,
        h: f64,
    ) -> Result<DVector<f64>, ModelError> {
        let pattern = &self.layout.pattern;
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut weights = vec![0.0; pattern.nnz()];
        for j in 0..pattern.n() {
            for k in col_ptr[j]..col_ptr[j + 1] {
                weights[k] = v[row_idx[k]] * v[j];
            }
        }
        let err = super::problem::model_error;
        let free = self.model.free();
        let elements = self.model.meridian.elements();
        let mut grad = DVector::zeros(u.len());
        let mut shifted = u.to_vec();
        for colour in 0..6 {
            let of_colour = |k: &usize| {
                let (node, c) = free[*k];
                node % 3 + 3 * c == colour
            };
            let unknowns: Vec<usize> = (0..u.len()).filter(of_colour).collect();
            if unknowns.is_empty() {
                continue;
            }
            let mut part = |sign: f64| {
                for &k in &unknowns {
                    shifted[k] = u[k] + sign * h;
                }
                self.model
                    .block_quadratic_by_element(&self.layout, &shifted, params, &weights)
                    .map_err(err)
            };
            let plus = part(1.0)?;
            let minus = part(-1.0)?;
            for &k in &unknowns {
                shifted[k] = u[k];
                let node = free[k].0;
                // The elements holding node i: those from (i − 2)/2 to i/2.
                let first = node.saturating_sub(1) / 2;
                let last = (node / 2).min(elements - 1);
                grad[k] = -(first..=last).map(|e| plus[e] - minus[e]).sum::<f64>() / (2.0 * h);
            }
        }
        if self.layout.border > 0 {
            // The elements' largest entry, as `set_border` takes it.
            let values = self
                .model
                .block_values(&self.layout, u, params)
                .map_err(err)?;
            let kept = self.layout.kept;
            let mut scale = 0.0f64;
            for j in 0..kept {
                for k in col_ptr[j]..col_ptr[j + 1] {
                    if row_idx[k] < kept {
                        scale = scale.max(values[k].abs());
                    }
                }
            }
            let scale = scale.max(1e-300);
            let border = |q: &[f64]| {
                Ok::<_, ModelError>(self.model.border_quadratic(
                    &self.layout,
                    q,
                    params,
                    scale,
                    &weights,
                ))
            };
            for k in 0..u.len() {
                grad[k] -= central(&mut shifted, k, h, border)?;
            }
        }
        Ok(grad)
    }
}

impl CriticalTest for MeridianTest {
    fn evaluate(&mut self, u: &[f64], params: &[f64]) -> Result<TestValue, ModelError> {
        let (sigma, vector) = self.value(u, params)?;
        let h = DIFFERENCE_STEP * self.length;
        let grad_q = if self.model.blocks_are_local() {
            self.coloured_gradient(u, params, &vector, h)?
        } else {
            self.gradient_one_by_one(u, params, &vector, h)?
        };
        let mut grad_params = vec![0.0; params.len()];
        let mut p = params.to_vec();
        for j in 0..params.len() {
            let h = DIFFERENCE_STEP * params[j].abs().max(1.0);
            grad_params[j] = -central_in_range(&mut p, j, h, |p| self.quadratic(u, p, &vector))?;
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

/// The central difference (f(x + h e_i) − f(x − h e_i)) / 2h, x left as it was.
fn central(
    x: &mut [f64],
    i: usize,
    h: f64,
    mut f: impl FnMut(&[f64]) -> Result<f64, ModelError>,
) -> Result<f64, ModelError> {
    let x0 = x[i];
    x[i] = x0 + h;
    let plus = f(x);
    x[i] = x0 - h;
    let minus = f(x);
    x[i] = x0;
    Ok((plus? - minus?) / (2.0 * h))
}

/// As [`central`] in a parameter, but where x ± h e_i lies outside the model's range of the
/// parameter (a material constant at its bound, k = 0), the second-order one-sided
/// difference (∓3 f(x) ± 4 f(x ± h e_i) ∓ f(x ± 2h e_i)) / 2h on the side that is inside.
fn central_in_range(
    x: &mut [f64],
    i: usize,
    h: f64,
    mut f: impl FnMut(&[f64]) -> Result<f64, ModelError>,
) -> Result<f64, ModelError> {
    let x0 = x[i];
    let mut at = |x: &mut [f64], t: f64| {
        x[i] = x0 + t;
        let value = f(x);
        x[i] = x0;
        value
    };
    match (at(x, h), at(x, -h)) {
        (Ok(plus), Ok(minus)) => Ok((plus - minus) / (2.0 * h)),
        (Ok(plus), Err(_)) => {
            let (here, far) = (at(x, 0.0)?, at(x, 2.0 * h)?);
            Ok((-3.0 * here + 4.0 * plus - far) / (2.0 * h))
        }
        (Err(_), Ok(minus)) => {
            let (here, far) = (at(x, 0.0)?, at(x, -2.0 * h)?);
            Ok((3.0 * here - 4.0 * minus + far) / (2.0 * h))
        }
        (Err(e), Err(_)) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::super::model::tests::{generic_filled, generic_paper2, partly_wet};
    use super::*;

    /// At a parameter's bound the one-sided difference stands in for the central one, to
    /// second order: on f(x) = x³ + x at x = 0, where x < 0 is refused, it is exact but for
    /// 2h² (the third derivative's term), as the central difference would be but for h².
    #[test]
    fn a_parameter_at_its_bound_is_differenced_on_the_side_inside() {
        let f = |x: &[f64]| {
            if x[0] < 0.0 {
                Err(ModelError::Global {
                    effect: "test".into(),
                    what: "below the bound".into(),
                })
            } else {
                Ok(x[0].powi(3) + x[0])
            }
        };
        let h = 1e-3;
        let d = central_in_range(&mut [0.0], 0, h, f).unwrap();
        assert!((d - (1.0 - 2.0 * h * h)).abs() < 1e-12, "{d}");
        let d = central_in_range(&mut [0.5], 0, h, f).unwrap();
        assert!((d - (1.75 + h * h)).abs() < 1e-12, "{d}");
    }

    /// The coloured gradient (each element's difference sent to the one shifted unknown it
    /// holds) is the one-by-one central difference of the whole block, summed differently:
    /// equal to round-off on blocks without a border — a fluid filling the membrane, spin and
    /// two penalty planes, and a fluid whose wetting line crosses an element. A fixed amount
    /// of gas resolves its pressure from the whole volume: not local, so differenced one by
    /// one.
    #[test]
    fn the_coloured_gradient_is_the_one_by_one_gradient() {
        for (name, (model, q, params)) in [
            ("filled", generic_filled()),
            ("wetting line", partly_wet(0.55)),
        ] {
            assert!(model.blocks_are_local(), "{name}");
            for m in [2, 3] {
                let layout = model.block_layout(m);
                assert_eq!(layout.border, 0, "{name}, m = {m}");
                let border: Vec<f64> = (0..layout.kept)
                    .map(|k| ((k as f64) * 0.37).cos())
                    .collect();
                let mut test = MeridianTest::new(model.clone(), m, &border);
                let (_, v) = test.value(&q, &params).unwrap();
                let h = DIFFERENCE_STEP * test.length;
                let coloured = test.coloured_gradient(&q, &params, &v, h).unwrap();
                let one = test.gradient_one_by_one(&q, &params, &v, h).unwrap();
                let scale = one.amax();
                assert!(scale > 0.0, "{name}, m = {m}");
                let error = (&coloured - &one).amax() / scale;
                assert!(error < 1e-9, "{name}, m = {m}: {error:e}");
            }
        }
        assert!(!generic_paper2().0.blocks_are_local());
    }
}
