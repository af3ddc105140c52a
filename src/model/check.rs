//! Derivative checks of an assembled model (docs/theory.md §1.2).
//!
//! At a state (u, Λ): the residual against central differences of Π, the tangent (sparse part
//! plus rank-one terms) against central differences of the residual, its symmetry, and every
//! load vector against central differences of F in Λ_j. Used by the effect property tests.

use super::{Evaluation, Model, ModelError, Request};

/// The largest errors found, each relative to the size of the quantity checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DerivativeErrors {
    /// max |∂Π/∂u·d − FD| / max(|F|·|d|, tiny).
    pub residual: f64,
    /// max |K d − FD of F| / max(‖K‖, tiny).
    pub tangent: f64,
    /// max |K_ij − K_ji| / ‖K‖.
    pub asymmetry: f64,
    /// max |∂F/∂Λ − FD| / max(|∂F/∂Λ|, tiny).
    pub loads: f64,
}

/// `K d` for the full tangent of an evaluation.
pub fn tangent_times<M: Model + ?Sized>(model: &M, eval: &Evaluation, d: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; d.len()];
    model.pattern().matvec(&eval.tangent, d, &mut y);
    for (c, a) in &eval.rank_one {
        let s: f64 = a.iter().zip(d).map(|(ai, di)| ai * di).sum();
        y.iter_mut().zip(a).for_each(|(yi, ai)| *yi += c * s * ai);
    }
    y
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Checks the derivatives of `model` at (u, Λ) along the direction `d` with step `h`.
pub fn check_derivatives<M: Model + ?Sized>(
    model: &M,
    u: &[f64],
    params: &[f64],
    d: &[f64],
    h: f64,
) -> Result<DerivativeErrors, ModelError> {
    let n = u.len();
    let mut e0 = model.new_evaluation();
    let mut ep = model.new_evaluation();
    let mut em = model.new_evaluation();
    model.evaluate(u, params, Request::ALL, &mut e0)?;
    let shifted = |s: f64| -> Vec<f64> { u.iter().zip(d).map(|(a, b)| a + s * b).collect() };
    model.evaluate(&shifted(h), params, Request::RESIDUAL, &mut ep)?;
    model.evaluate(&shifted(-h), params, Request::RESIDUAL, &mut em)?;
    let tiny = 1e-300;
    // Π along d.
    let fd = (ep.energy - em.energy) / (2.0 * h);
    let exact: f64 = e0.residual.iter().zip(d).map(|(f, di)| f * di).sum();
    let residual = (fd - exact).abs() / (max_abs(&e0.residual) * max_abs(d) * n as f64).max(tiny);
    // F along d.
    let kd = tangent_times(model, &e0, d);
    let k_norm = max_abs(&e0.tangent).max(
        e0.rank_one
            .iter()
            .map(|(c, a)| c.abs() * max_abs(a).powi(2))
            .fold(0.0, f64::max),
    );
    let tangent = (0..n)
        .map(|i| ((ep.residual[i] - em.residual[i]) / (2.0 * h) - kd[i]).abs())
        .fold(0.0, f64::max)
        / (k_norm * max_abs(d)).max(tiny);
    // Symmetry of the sparse part (rank-one terms are symmetric by construction).
    let pattern = model.pattern();
    let mut asym: f64 = 0.0;
    for j in 0..pattern.n() {
        for p in pattern.col_ptr()[j]..pattern.col_ptr()[j + 1] {
            let i = pattern.row_idx()[p];
            let q = pattern.position(j, i).expect("the pattern is symmetric");
            asym = asym.max((e0.tangent[p] - e0.tangent[q]).abs());
        }
    }
    // Loads: central differences in each parameter.
    let mut loads: f64 = 0.0;
    for j in 0..params.len() {
        let hj = h * params[j].abs().max(1.0);
        let mut pp = params.to_vec();
        pp[j] += hj;
        model.evaluate(u, &pp, Request::RESIDUAL, &mut ep)?;
        pp[j] -= 2.0 * hj;
        model.evaluate(u, &pp, Request::RESIDUAL, &mut em)?;
        let scale = max_abs(&e0.loads[j])
            .max(max_abs(&e0.residual) / params[j].abs().max(1.0))
            .max(tiny);
        for i in 0..n {
            let fd = (ep.residual[i] - em.residual[i]) / (2.0 * hj);
            loads = loads.max((fd - e0.loads[j][i]).abs() / scale);
        }
    }
    Ok(DerivativeErrors {
        residual,
        tangent,
        asymmetry: asym / k_norm.max(tiny),
        loads,
    })
}
