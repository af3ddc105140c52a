//! A near miss of a path (docs/theory.md §16.7): where a double point is broken by an
//! imperfection that makes it supercritical, the path passes beside it without a fold and
//! without a change of index; the smallest eigenvalue of the path's own block only dips
//! towards zero and rises again, and the solutions of the other half of the broken
//! pitchfork lie on a second piece, with a fold of its own, that the path never reaches.
//! Here: where the dips are, and a first state on the second piece by solves at fixed
//! amplitude along the dip's mode from the path's state there.

use super::driver::{solve_on_plane, PathOptions, PathPoint, Problem};
use nalgebra::DVector;

/// The fixed amplitudes tried on each side: h·2^k for k in [`FIRST`]..=[`LAST`], h the
/// path's step at the dip (scaled units).
pub const FIRST: i32 = -3;
/// See [`FIRST`].
pub const LAST: i32 = 5;

/// A dip counts when its |σ| is at most this fraction of the largest |σ| on each side of it
/// along the path: a clear minimum, not the ripple of a flat eigenvalue.
pub const DEPTH: f64 = 0.5;

/// The interior points of a path where |σ| (the smallest eigenvalue of its own block at each
/// point, `sigma`) has a local minimum with the same negative count of that block
/// (`negatives`) at the point and its two neighbours — no crossing, so no critical point
/// is found there — and is at most [`DEPTH`] times the largest |σ| before it and after it.
/// A non-finite value is no minimum and breaks no other.
pub fn dips(sigma: &[f64], negatives: &[usize]) -> Vec<usize> {
    let n = sigma.len().min(negatives.len());
    let a: Vec<f64> = sigma[..n].iter().map(|s| s.abs()).collect();
    let mut found = Vec::new();
    for k in 1..n.saturating_sub(1) {
        let (l, c, r) = (a[k - 1], a[k], a[k + 1]);
        if !(l.is_finite() && c.is_finite() && r.is_finite()) {
            continue;
        }
        if !(c < l && c <= r)
            || negatives[k - 1] != negatives[k]
            || negatives[k + 1] != negatives[k]
        {
            continue;
        }
        let before = a[..k]
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, &v| m.max(v));
        let after = a[k + 1..]
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, &v| m.max(v));
        if c <= DEPTH * before && c <= DEPTH * after {
            found.push(k);
        }
    }
    found
}

/// What the solves beside a dip found.
#[derive(Debug, Clone)]
pub struct Beside {
    /// The solves tried.
    pub tried: usize,
    /// The first state accepted, with the signed amplitude along the mode that met it.
    pub found: Option<(PathPoint, f64)>,
}

/// From the path's state `from` at a dip, solves on the planes of fixed amplitude a along
/// the unit mode `phi` (scaled unknowns, no control part), the control free:
/// a = ±h·2^k for k in [`FIRST`]..=[`LAST`], the smaller amplitudes first, both signs. In the normal form
/// x³ − λx − ε = 0 of the broken pitchfork every amplitude has one solution, λ = x² − ε/x,
/// on the path's piece for x > 0 and on the other piece for x < 0: a large enough amplitude
/// against the path's side lands on the other piece. The first converged admissible state
/// that `accept` takes is returned: it refuses the path's own states, and those whose control
/// lies outside the path's range (where it cannot tell them from the path's).
pub fn beside_dip<P: Problem + ?Sized>(
    problem: &mut P,
    from: &PathPoint,
    phi: &DVector<f64>,
    h: f64,
    opts: &PathOptions,
    accept: &mut dyn FnMut(&mut P, &PathPoint) -> bool,
) -> Beside {
    let mut tried = 0;
    for k in FIRST..=LAST {
        for sign in [1.0, -1.0] {
            if super::interrupt::requested() {
                return Beside { tried, found: None };
            }
            let direction = phi * sign;
            let s = h * 2f64.powi(k);
            tried += 1;
            let Ok(p) = solve_on_plane(&mut *problem, from, &direction, phi, s, opts) else {
                continue;
            };
            if problem.defect(&p.q, &p.lambda).is_some() || !accept(problem, &p) {
                continue;
            }
            return Beside {
                tried,
                found: Some((p, sign * s)),
            };
        }
    }
    Beside { tried, found: None }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::continuation::events::trace;
    use crate::continuation::Continuation;
    use crate::results::Extremum;

    /// R(x, λ) = x³ − λx − ε: the gradient of V = x⁴/4 − λx²/2 − εx, the supercritical
    /// pitchfork broken by ε > 0.
    fn broken(eps: f64) -> impl Problem {
        crate::continuation::driver::Scalar(move |x: f64, l: f64| {
            Ok((x * x * x - l * x - eps, 3.0 * x * x - l, -x))
        })
    }

    fn options(direction: f64) -> PathOptions {
        PathOptions {
            initial_step: 0.02,
            min_step: 1e-8,
            max_step: 0.05,
            max_steps: 400,
            tolerance: 1e-12,
            bounds: (-1.0, 2.0),
            direction,
            ..PathOptions::default()
        }
    }

    /// The connected path of x³ − λx − ε = 0 (ε = 0.01) from λ = −1 to 2 has no fold and its
    /// eigenvalue 3x² − λ = 2x² + ε/x stays positive: one dip, at x³ = ε/4 (λ = −3 (ε/4)^(2/3)),
    /// and no other. From it the solves along the mode meet the other piece (x < 0), which
    /// followed towards lower λ turns at its fold: dλ/dx = 2x + ε/x² = 0 at
    /// x = −(ε/2)^(1/3), λ = (ε/2)^(2/3) + ε/(ε/2)^(1/3) = 3 (ε/2)^(2/3).
    #[test]
    fn the_broken_supercritical_pitchforks_other_piece_and_its_fold_are_found_beside_the_dip() {
        let eps = 0.01;
        let opts = options(1.0);
        // The start: the connected root at λ = −1 (the one real root, x > 0).
        let mut x = 0.01;
        for _ in 0..50 {
            x -= (x * x * x + x - eps) / (3.0 * x * x + 1.0);
        }
        let mut driver = Continuation::start(
            broken(eps),
            &DVector::from_element(1, x),
            &DVector::from_element(1, -1.0),
            opts.clone(),
        )
        .unwrap();
        let path = trace(&mut driver, opts.max_steps, |_, _| None, &mut [], |_, _| {});
        assert_eq!(path.turning_points().count(), 0, "the connected path folds");
        let sigma: Vec<f64> = path
            .points
            .iter()
            .map(|p| 3.0 * p.q[0] * p.q[0] - p.lambda[0])
            .collect();
        assert!(sigma.iter().all(|&s| s > 0.0));
        let negatives = vec![0; sigma.len()];
        let found = dips(&sigma, &negatives);
        assert_eq!(found.len(), 1, "{found:?}");
        let k = found[0];
        let lambda_dip = -3.0 * (eps / 4.0f64).powf(2.0 / 3.0);
        let at = &path.points[k];
        let step = path.points[k + 1].arclength - at.arclength;
        assert!(
            (at.lambda[0] - lambda_dip).abs() <= 2.0 * step,
            "dip at {} against {lambda_dip}",
            at.lambda[0]
        );
        // The mode: the unit state direction (the one unknown).
        let phi = DVector::from_vec(vec![1.0, 0.0]);
        // The path's own states: the connected root at the candidate's λ is the one with x > 0
        // (the largest root of the cubic); a state is refused when the path has it.
        let on_path = |p: &PathPoint| {
            !(opts.bounds.0..=opts.bounds.1).contains(&p.lambda[0])
                || path.points.windows(2).any(|w| {
                    let (a, b) = (&w[0], &w[1]);
                    let (la, lb) = (a.lambda[0], b.lambda[0]);
                    let l = p.lambda[0];
                    (la - l) * (lb - l) <= 0.0 && {
                        let t = if lb == la { 0.0 } else { (l - la) / (lb - la) };
                        let x = a.q[0] + t * (b.q[0] - a.q[0]);
                        (x - p.q[0]).abs() <= 10.0 * step
                    }
                })
        };
        let mut problem = broken(eps);
        let beside = beside_dip(&mut problem, at, &phi, step, &opts, &mut |_, p| !on_path(p));
        let (start, amplitude) = beside.found.expect("the other piece");
        assert!(amplitude < 0.0 && start.q[0] < 0.0, "{amplitude} {start:?}");
        // On the other piece: λ = x² + ε/|x| beyond its fold.
        let x = start.q[0];
        assert!((start.lambda[0] - (x * x - eps / x)).abs() <= 1e-10);
        // Followed towards lower λ it turns at its fold.
        let back = options(-1.0);
        let mut piece =
            Continuation::start(broken(eps), &start.q, &start.lambda, back.clone()).unwrap();
        let branch = trace(&mut piece, back.max_steps, |_, _| None, &mut [], |_, _| {});
        let folds: Vec<_> = branch.turning_points().collect();
        assert_eq!(folds.len(), 1, "{} folds", folds.len());
        let fold = folds[0];
        assert_eq!(fold.kind, Extremum::Minimum);
        let lambda_f = 3.0 * (eps / 2.0f64).powf(2.0 / 3.0);
        let x_f = -(eps / 2.0f64).powf(1.0 / 3.0);
        assert!(
            (fold.point.lambda[0] - lambda_f).abs() <= 1e-12,
            "fold at λ = {} against {lambda_f}",
            fold.point.lambda[0]
        );
        assert!(
            (fold.point.q[0] - x_f).abs() <= 1e-7,
            "fold at x = {} against {x_f}",
            fold.point.q[0]
        );
    }

    /// A dip needs a clear minimum with no crossing: a monotone eigenvalue has none, a
    /// crossing (the negative count changing) is no dip, a shallow ripple is none.
    #[test]
    fn dips_are_clear_minima_without_a_change_of_index() {
        assert!(dips(&[3.0, 2.0, 1.0, 0.5], &[0; 4]).is_empty());
        assert_eq!(dips(&[3.0, 1.0, 0.2, 1.0, 3.0], &[0; 5]), vec![2]);
        assert!(dips(&[3.0, 1.0, -0.2, 1.0, 3.0], &[0, 0, 1, 1, 1]).is_empty());
        assert!(dips(&[1.0, 0.95, 0.9, 0.95, 1.0], &[0; 5]).is_empty());
        assert!(dips(&[3.0, f64::NAN, 0.2, 1.0, 3.0], &[0; 5]).is_empty());
    }
}
