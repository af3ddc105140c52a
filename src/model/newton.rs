//! Newton's method in the full space at fixed parameters, with the sparse LDLᵀ of the tangent
//! (faer, through [`crate::linalg::SymmetricFactorization`]): symbolic analysis once, one
//! numeric factorisation per iteration, and the rank-one terms of global potentials (a fixed
//! amount of gas) applied by Sherman–Morrison–Woodbury on that factorisation:
//!
//! ```text
//!   (K + Σ c_k a_k a_kᵀ) Δu = −F:   Δu = y − Z (C⁻¹ + AᵀZ)⁻¹ Aᵀ y,  y = K⁻¹(−F),  Z = K⁻¹ A
//! ```
//!
//! A step that makes the model fail (an inverted element) or raises the residual is halved
//! (at most `max_cuts` times) before it is taken. Symmetric paths are solved in the
//! fixed-point space ([`crate::adapted`]); this solver is their check and the fallback for
//! states without symmetry. A free body's rigid-body modes make K singular: such models are
//! refused with a clear message (fix nodes or use the symmetric solver).

use crate::linalg::{SymmetricFactorization, SymmetricPattern};
use crate::model::{FeModel, Model, Request};
use nalgebra::{DMatrix, DVector};

/// Settings of [`newton`].
#[derive(Debug, Clone)]
pub struct NewtonOptions {
    /// Converged when ‖F‖∞ ≤ `tolerance` · max(‖F(u0)‖∞, force scale) and the correction is
    /// below `tolerance` relative to the displacement scale.
    pub tolerance: f64,
    /// Iterations before giving up.
    pub max_iterations: usize,
    /// Step halvings per iteration before giving up.
    pub max_cuts: usize,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 30,
            max_cuts: 12,
        }
    }
}

/// A converged Newton solve.
#[derive(Debug, Clone)]
pub struct NewtonResult {
    /// The solution.
    pub u: Vec<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// Final ‖F‖∞.
    pub residual: f64,
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Solves F(u; Λ) = 0 from `u0` at fixed `params`.
pub fn newton(
    model: &FeModel,
    u0: &[f64],
    params: &[f64],
    opts: &NewtonOptions,
) -> Result<NewtonResult, String> {
    if !model.rigid_motions().is_empty() {
        return Err("the model has rigid-body modes (a free body): its tangent is singular in the full space; \
             fix nodes or solve in the symmetric subspace"
            .into());
    }
    let n = model.unknowns();
    let pattern: &SymmetricPattern = model.pattern();
    let mut factor =
        SymmetricFactorization::new(pattern).map_err(|e| format!("symbolic analysis: {e}"))?;
    let mut eval = model.new_evaluation();
    let mut trial = model.new_evaluation();
    let mut u = u0.to_vec();
    model
        .evaluate(&u, params, Request::ALL, &mut eval)
        .map_err(|e| format!("at the start: {e}"))?;
    let size = model
        .reference()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    let force_scale = max_abs(&eval.tangent) * size;
    for it in 1..=opts.max_iterations {
        let r = max_abs(&eval.residual);
        factor
            .factorize(&eval.tangent)
            .map_err(|e| format!("iteration {it}: factorisation failed: {e}"))?;
        // y = K⁻¹(−F); Woodbury for the rank-one terms.
        let mut du: Vec<f64> = eval.residual.iter().map(|f| -f).collect();
        factor.solve_in_place(&mut du).map_err(|e| e.to_string())?;
        let k = eval.rank_one.len();
        if k > 0 {
            let mut z = vec![0.0; n * k];
            for (j, (_, a)) in eval.rank_one.iter().enumerate() {
                z[j * n..(j + 1) * n].copy_from_slice(a);
            }
            factor
                .solve_many_in_place(&mut z)
                .map_err(|e| e.to_string())?;
            let at = |j: usize, v: &[f64]| -> f64 {
                eval.rank_one[j].1.iter().zip(v).map(|(a, b)| a * b).sum()
            };
            let mut small = DMatrix::zeros(k, k);
            for i in 0..k {
                small[(i, i)] += 1.0 / eval.rank_one[i].0;
                for j in 0..k {
                    small[(i, j)] += at(i, &z[j * n..(j + 1) * n]);
                }
            }
            let rhs = DVector::from_fn(k, |i, _| at(i, &du));
            let w = small.lu().solve(&rhs).ok_or("singular Woodbury system")?;
            for j in 0..k {
                for (d, zi) in du.iter_mut().zip(&z[j * n..(j + 1) * n]) {
                    *d -= w[j] * zi;
                }
            }
        }
        // Step cutting: halve until the model accepts the state and the residual does not grow.
        let mut scale = 1.0;
        let mut accepted = false;
        for _ in 0..=opts.max_cuts {
            let candidate: Vec<f64> = u.iter().zip(&du).map(|(a, b)| a + scale * b).collect();
            if model
                .evaluate(&candidate, params, Request::ALL, &mut trial)
                .is_ok()
                && max_abs(&trial.residual) <= r.max(1e-300) * 1.5
            {
                u = candidate;
                std::mem::swap(&mut eval, &mut trial);
                accepted = true;
                break;
            }
            scale *= 0.5;
        }
        if !accepted {
            return Err(format!(
                "iteration {it}: no step along the Newton direction is acceptable (residual {r:e})"
            ));
        }
        let res = max_abs(&eval.residual);
        if res <= opts.tolerance * force_scale && scale * max_abs(&du) <= opts.tolerance * size {
            return Ok(NewtonResult {
                u,
                iterations: it,
                residual: res,
            });
        }
    }
    Err(format!(
        "no convergence in {} iterations (residual {:e})",
        opts.max_iterations,
        max_abs(&eval.residual)
    ))
}
