//! The normal form of a branch at its critical point (docs/theory.md §14.7), for either
//! model: the control along the branch, λ − λ_c ≈ c A^k, from three solves on the plane of
//! fixed amplitude along the critical mode — the first step of the branch, taken three times at a
//! fraction of its size — and what the reduced equation then says of the branch's stability
//! in that mode.

use crate::continuation::{step_off, PathOptions, PathPoint, Problem};
use crate::results::{Bifurcation, Criticality, NormalForm, Reduced, SwitchedBranch};
use nalgebra::DVector;

/// The larger of the two fixed-amplitude solves, as a fraction of the branch's first step.
const FRACTION: f64 = 0.25;

/// Below this |b| (relative to ‖K‖) the crossing is not transversal: no prediction of the
/// stability (as the branching lemma's own test, [`Reduced::path_slope`]).
const TRANSVERSAL_ZERO: f64 = 1e-10;

/// The amplitude along the unit mode `phi` of the displacement `u` from the critical state
/// `uc`, per state scale σ.
fn amplitude(phi: &[f64], u: &[f64], uc: &[f64], scale: f64) -> f64 {
    phi.iter()
        .zip(u.iter().zip(uc))
        .map(|(f, (a, b))| f * (a - b))
        .sum::<f64>()
        / scale
}

/// The normal form of the half of a branch that leaves `start` (the critical point) along
/// `tangent` on the plane `plane` (scaled variables, as the branch's first step), `phi` the
/// unit critical mode in the problem's coordinates and `reduced` the reduced equation: λ − λ_c ≈ c A^k from the solves at s = ¼ and ⅛ of the
/// first step, extrapolated to A → 0 (the error of c(A) is O(A)).
#[allow(clippy::too_many_arguments)]
pub fn normal_form<P: Problem + ?Sized>(
    problem: &mut P,
    start: &PathPoint,
    tangent: &DVector<f64>,
    plane: &DVector<f64>,
    phi: &DVector<f64>,
    reduced: &Reduced,
    opts: &PathOptions,
) -> Result<NormalForm, String> {
    let mut power: u32 = match reduced.bifurcation {
        Bifurcation::Transcritical => 1,
        Bifurcation::Pitchfork => 2,
    };
    let scale = opts.state_scale;
    let mut sample = |s: f64| -> Result<(f64, f64), String> {
        let p = step_off(problem, start, tangent, plane, s, opts)
            .map_err(|e| format!("the solve at fixed amplitude (s = {s:.3e}): {e}"))?;
        let a = amplitude(phi.as_slice(), p.q.as_slice(), start.q.as_slice(), scale);
        let dl = p.lambda[0] - start.lambda[0];
        if a == 0.0 || !a.is_finite() || !dl.is_finite() {
            return Err(format!(
                "the solve at fixed amplitude (s = {s:.3e}) did not leave the critical point"
            ));
        }
        Ok((a, dl))
    };
    // Smaller amplitudes where the larger ones do not converge (a branch leaving close to
    // another point), down to the smallest step.
    let mut s = FRACTION * opts.initial_step;
    let samples = loop {
        let tried: Result<Vec<(f64, f64)>, String> = [s, 0.5 * s, 0.25 * s]
            .into_iter()
            .map(&mut sample)
            .collect();
        match tried {
            Ok(samples) => break samples,
            Err(e) if 0.125 * s < opts.min_step => return Err(e),
            Err(_) => s *= 0.25,
        }
    };
    // c(A) = c + O(A), the amplitudes in the ratio 2: one Richardson step on each pair; the
    // two extrapolations differ by the error of the first, O(A²).
    let fit = |power: u32| {
        let c: Vec<f64> = samples
            .iter()
            .map(|(a, dl)| dl / a.powi(power as i32))
            .collect();
        let richardson = |i: usize| {
            let ratio = samples[i].0 / samples[i + 1].0;
            (ratio * c[i + 1] - c[i]) / (ratio - 1.0)
        };
        let coefficient = richardson(1);
        (coefficient, (coefficient - richardson(0)).abs())
    };
    let (mut coefficient, mut error) = fit(power);
    // A linear term the reduced equation allows but that is zero within its error (a load
    // that is not smooth at the point, as a fluid level at the membrane): the next order.
    if power == 1 && coefficient.abs() <= error {
        power = 2;
        (coefficient, error) = fit(power);
    }
    if !(coefficient.is_finite() && error.is_finite()) {
        return Err(format!(
            "the control along the branch is not finite (λ − λ_c = {:e} at A = {:e})",
            samples[0].1, samples[0].0
        ));
    }
    let d1 = samples[0].1;
    // The eigenvalue along φ on the branch is −b s (transcritical) or −2 b s (pitchfork),
    // s the path's arclength at the branch's control, which has the sign of Δλ (the path's
    // tangent has the control increasing): stable where b Δλ < 0.
    let transversal = reduced.path_slope.abs() > TRANSVERSAL_ZERO;
    // Where c is zero within its error the side is not known.
    let known = transversal && coefficient.abs() > error && d1 != 0.0;
    let mode_stable = known.then_some(reduced.path_slope * d1 < 0.0);
    let criticality = match (power, mode_stable) {
        (2, Some(true)) => Some(Criticality::Supercritical),
        (2, Some(false)) => Some(Criticality::Subcritical),
        _ => None,
    };
    Ok(NormalForm {
        power,
        coefficient,
        error,
        amplitudes: [samples[0].0, samples[1].0, samples[2].0],
        criticality,
        mode_stable,
        observed: None,
        observed_amplitude: None,
    })
}

/// Records in `branch`'s normal form what its first followed point says (Δλ/A^k there),
/// `phi` the unit critical mode over the unknowns, and warns when the branch left to the
/// other side of the control than predicted.
pub fn observe(branch: &mut SwitchedBranch, control: usize, phi: &[f64], scale: f64) {
    let (Some(nf), [cp, first, ..]) = (branch.normal_form.as_mut(), branch.points.as_slice())
    else {
        return;
    };
    if phi.len() != cp.u.len() {
        return;
    }
    let a = amplitude(phi, &first.u, &cp.u, scale);
    let dl = first.parameters[control] - cp.parameters[control];
    if a == 0.0 || !a.is_finite() {
        return;
    }
    let observed = dl / a.powi(nf.power as i32);
    nf.observed = Some(observed);
    nf.observed_amplitude = Some(a);
    let predicted = nf.coefficient * a.powi(nf.power as i32);
    if predicted.abs() > nf.error * a.abs().powi(nf.power as i32) && predicted * dl < 0.0 {
        let warning = format!(
            "the branch left toward Δλ = {dl:.3e}, its normal form predicts {predicted:.3e} at its first point"
        );
        branch.warnings.push(warning);
    }
}
