//! Deflated Newton at a fixed control (Farrell, Birkisson & Funke, SIAM J. Sci. Comput. 37
//! (2015) A2026–A2045; docs/theory.md §16): solutions other than the known ones r_1 … r_k of
//! R(z) = 0, from Newton on the deflated residual G(z) = η(z) R(z) with
//!
//! η(z) = Π_i (‖z − r_i‖^(−p) + σ).
//!
//! G vanishes where R does, except at the r_i, where η blows up: Newton on G is pushed away
//! from them. Its step needs no new factorisation: with the ordinary Newton step
//! δ = −R_z⁻¹ R, Sherman–Morrison gives the deflated step δ_G = τ δ with
//! τ = 1/(1 − ∇(ln η)·δ), a scalar factor ([`Deflation::factor`]). z is the unknown of the
//! corrector at fixed control — the state and the constraints' parameters in the driver's
//! scaled units — so one σ serves every mesh.

use super::{PathOptions, Problem, SolveError};
use nalgebra::DVector;

/// The known solutions and the deflation's power p and shift σ.
#[derive(Debug, Clone)]
pub struct Deflation {
    /// The known solutions, as scaled unknowns z = (q/σ_q, λ_1/σ_1 … λ_c/σ_c).
    pub roots: Vec<DVector<f64>>,
    /// The power p (> 0; 2 is usual).
    pub power: f64,
    /// The shift σ (> 0; 1 is usual): keeps G from vanishing far from every root.
    pub shift: f64,
}

impl Deflation {
    /// ∇(ln η)(z) = Σ_i −p ‖z − r_i‖^(−p−2) (z − r_i) / (‖z − r_i‖^(−p) + σ).
    pub fn log_gradient(&self, z: &DVector<f64>) -> DVector<f64> {
        let mut g = DVector::zeros(z.len());
        for r in &self.roots {
            let d = z - r;
            let n = d.norm();
            if n == 0.0 {
                continue;
            }
            let m = n.powf(-self.power);
            g -= d * (self.power * m / (n * n) / (m + self.shift));
        }
        g
    }

    /// τ with δ_G = τ δ: the deflated step from the Newton step `delta` at `z`.
    pub fn factor(&self, z: &DVector<f64>, delta: &DVector<f64>) -> f64 {
        1.0 / (1.0 - self.log_gradient(z).dot(delta))
    }

    /// min over the roots of ‖z − r_i‖ (∞ without roots).
    pub fn distance(&self, z: &DVector<f64>) -> f64 {
        self.roots
            .iter()
            .map(|r| (z - r).norm())
            .fold(f64::INFINITY, f64::min)
    }
}

/// The scaled unknowns z of the corrector at fixed control: q/σ_q and the free parameters
/// after the control, each over its scale.
pub fn scaled(q: &DVector<f64>, lambda: &DVector<f64>, opts: &PathOptions) -> DVector<f64> {
    let m = q.len();
    let c = lambda.len().saturating_sub(1);
    DVector::from_fn(m + c, |i, _| {
        if i < m {
            q[i] / opts.state_scale
        } else {
            lambda[i - m + 1] / opts.parameter_scale(i - m + 1)
        }
    })
}

/// Newton at the fixed control λ_0 on the deflated residual, from (q0, λ0): the step of
/// [`solve_at`](super::solve_at) times τ ([`Deflation::factor`]), no longer than `max_step`
/// (scaled units; a deflated step far from every root may be long). Converged when the
/// residual is small and the undeflated correction below the tolerance, as for `solve_at`.
/// Returns q, λ and the iterations taken; a solution may still be one of the roots (the
/// caller checks the distance).
pub fn deflated_solve_at<P: Problem + ?Sized>(
    problem: &mut P,
    q0: &DVector<f64>,
    lambda0: &DVector<f64>,
    opts: &PathOptions,
    deflation: &Deflation,
    max_step: f64,
    budget: usize,
) -> Result<(DVector<f64>, DVector<f64>, usize), SolveError> {
    let (mut q, mut lambda) = (q0.clone(), lambda0.clone());
    let (mut residual, mut correction) = (f64::NAN, f64::NAN);
    for it in 1..=budget {
        let newton = super::driver::newton_step(problem, &q, &lambda, opts)?;
        residual = newton.residual;
        let d = newton.correction;
        correction = d.amax();
        let m = q.len();
        // d holds the scaled corrections of (q, λ_0, λ_1 … λ_c), the fixed control's 0.
        let delta = DVector::from_fn(
            m + lambda.len() - 1,
            |i, _| if i < m { d[i] } else { d[i + 1] },
        );
        let tau = deflation.factor(&scaled(&q, &lambda, opts), &delta);
        let length = (tau * delta.norm()).abs();
        if !length.is_finite() {
            return Err(SolveError::Diverged { control: lambda[0] });
        }
        let cut = if length > max_step {
            max_step / length
        } else {
            1.0
        };
        super::driver::apply_correction(&mut q, &mut lambda, &(d * (tau * cut)), opts)?;
        if newton.converged && correction <= opts.tolerance {
            return Ok((q, lambda, it));
        }
    }
    Err(SolveError::NotConverged {
        control: lambda[0],
        iterations: budget,
        residual,
        correction,
        tolerance: opts.tolerance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Newton on G = η R for a scalar R(z) = (z − 1)(z − 2)(z − 4), deflating z = 1: the
    /// Sherman–Morrison step τ δ equals −G/G' (with G' by central differences).
    #[test]
    fn the_deflated_step_is_newton_on_the_deflated_residual() {
        let r = |z: f64| (z - 1.0) * (z - 2.0) * (z - 4.0);
        let dr = |z: f64| (z - 2.0) * (z - 4.0) + (z - 1.0) * (z - 4.0) + (z - 1.0) * (z - 2.0);
        let deflation = Deflation {
            roots: vec![DVector::from_element(1, 1.0)],
            power: 2.0,
            shift: 1.0,
        };
        let eta = |z: f64| (z - 1.0).abs().powf(-2.0) + 1.0;
        let g = |z: f64| eta(z) * r(z);
        for z in [1.3, 1.7, 2.6, 3.1, 5.0] {
            let delta = DVector::from_element(1, -r(z) / dr(z));
            let tau = deflation.factor(&DVector::from_element(1, z), &delta);
            let h = 1e-6;
            let dg = (g(z + h) - g(z - h)) / (2.0 * h);
            let newton_g = -g(z) / dg;
            assert!(
                (tau * delta[0] - newton_g).abs() <= 1e-7 * newton_g.abs().max(1.0),
                "z = {z}: τδ = {}, −G/G' = {newton_g}",
                tau * delta[0]
            );
        }
    }

    /// Deflated Newton from one first guess finds every root on its side one after another
    /// (deflation pushes it away from the known ones, never across them: from the left of
    /// the smallest root only that root is found).
    #[test]
    fn deflation_finds_the_roots_of_a_cubic_one_after_another() {
        let r = |z: f64| (z - 1.0) * (z - 2.0) * (z - 4.0);
        let dr = |z: f64| (z - 2.0) * (z - 4.0) + (z - 1.0) * (z - 4.0) + (z - 1.0) * (z - 2.0);
        let mut deflation = Deflation {
            roots: Vec::new(),
            power: 2.0,
            shift: 1.0,
        };
        let solve = |deflation: &Deflation, mut z: f64| {
            for _ in 0..100 {
                let delta = DVector::from_element(1, -r(z) / dr(z));
                let tau = deflation.factor(&DVector::from_element(1, z), &delta);
                z += (tau * delta[0]).clamp(-0.5, 0.5);
                if delta[0].abs() < 1e-12 {
                    return Some(z);
                }
            }
            None
        };
        for guess in [0.0, 3.0, 3.0] {
            let z = solve(&deflation, guess).expect("converges");
            let z = DVector::from_element(1, z);
            assert!(deflation.distance(&z) > 1e-6, "{z} again");
            deflation.roots.push(z);
        }
        let found: Vec<f64> = deflation.roots.iter().map(|r| r[0]).collect();
        for (f, want) in found.iter().zip([1.0, 2.0, 4.0]) {
            assert!((f - want).abs() < 1e-10, "{found:?}");
        }
        // Every root deflated: from 3 Newton finds none.
        assert_eq!(solve(&deflation, 3.0), None);
    }
}
