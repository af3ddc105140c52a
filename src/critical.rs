//! Critical points (DESIGN §3, §4.4): where the negative count of an irrep's block changes
//! between two states of a path, the crossing eigenvalue is localised by a safeguarded secant
//! search on the path parameter until it is at round-off relative to ‖K‖, and the point is
//! classified by its irrep:
//!
//! - trivial irrep → **limit point** (a symmetric fold);
//! - non-trivial 1-D irrep → **simple symmetry-breaking bifurcation**;
//! - d-dimensional irrep → **d-fold bifurcation** (double, 3-, 4-, 5-fold): the eigenvalue is
//!   d-fold in K by construction, the d partner blocks being identical.
//!
//! A change of the index of a block is seen even when two eigenvalues cross together, which
//! a determinant sign would miss. Two close simple points on a mesh of lower symmetry are
//! two separate crossings here, in two different 1-D irreps — never inferred, measured.

use crate::model::Layout;
use meshes::GroupAction;
use serde::Serialize;

/// The subgroup that leaves a mode invariant.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Isotropy {
    /// A name when the subgroup is axial about z (`C4v`, `C2`, `C1` …), else `order N`.
    pub name: String,
    /// Its order.
    pub order: usize,
    /// Indices (in the scene's group) of its elements.
    pub elements: Vec<usize>,
}

/// A localised and classified critical point.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalPoint {
    /// `limit point`, `simple bifurcation`, `double bifurcation`, `3-fold bifurcation` …
    pub kind: String,
    /// The irrep whose block became singular.
    pub irrep: String,
    /// Multiplicity of the zero eigenvalue in K (the irrep's dimension).
    pub multiplicity: usize,
    /// Every parameter at the point (scene order).
    pub parameters: Vec<f64>,
    /// Every measure at the point (the report's order).
    pub measures: Vec<f64>,
    /// The path step (or sample) just before the point.
    pub after_step: usize,
    /// |eigenvalue| / ‖K‖ at the localised point.
    pub residual_eigenvalue: f64,
    /// Isotropy subgroup of the critical mode (first partner).
    pub isotropy: Isotropy,
    /// The critical mode over the unknowns (unit norm).
    #[serde(skip)]
    pub mode: Vec<f64>,
    /// The state over the unknowns.
    #[serde(skip)]
    pub state: Vec<f64>,
}

/// The name of a critical point in an irrep of dimension `dim` (`trivial`: the first irrep).
/// On a path the trivial block becomes singular at a fold of the path (a limit point); on a
/// held state (linear buckling) the state cannot fold, and a singular trivial block is a
/// symmetric bifurcation of the held state.
pub fn classify(trivial: bool, dim: usize) -> String {
    classify_on(trivial, dim, false)
}

/// As [`classify`], for a held state when `held`.
pub fn classify_on(trivial: bool, dim: usize, held: bool) -> String {
    match (trivial, dim) {
        (true, _) if held => "symmetric bifurcation".into(),
        (true, _) => "limit point".into(),
        (false, 1) => "simple bifurcation".into(),
        (false, 2) => "double bifurcation".into(),
        (false, d) => format!("{d}-fold bifurcation"),
    }
}

/// Finds s in (0, s1) where `g` changes sign, given g(0) = g0 and g(s1) = g1 of opposite signs,
/// by the Illinois variant of regula falsi. Stops when |g| ≤ `tol` or after 60 evaluations;
/// returns the best s and g(s) found, or `None` when an evaluation fails.
pub fn locate_sign_change(
    mut g: impl FnMut(f64) -> Option<f64>,
    g0: f64,
    s1: f64,
    g1: f64,
    tol: f64,
) -> Option<(f64, f64)> {
    let (mut a, mut fa, mut b, mut fb) = (0.0, g0, s1, g1);
    let (mut best, mut fbest) = if fa.abs() < fb.abs() {
        (a, fa)
    } else {
        (b, fb)
    };
    let mut side = 0i8;
    for _ in 0..60 {
        if fbest.abs() <= tol || (b - a).abs() <= 1e-14 * s1.abs() {
            break;
        }
        let s = (a * fb - b * fa) / (fb - fa);
        let s = if s > a.min(b) && s < a.max(b) {
            s
        } else {
            0.5 * (a + b)
        };
        let fs = g(s)?;
        if fs.abs() < fbest.abs() {
            (best, fbest) = (s, fs);
        }
        if fs.signum() == fb.signum() {
            (b, fb) = (s, fs);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            (a, fa) = (s, fs);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
    }
    Some((best, fbest))
}

/// The elements g of the action's group with T(g) u = u (to 1e-8 relative), named.
pub fn isotropy(action: &GroupAction, layout: &Layout, u: &[f64]) -> Isotropy {
    let group = action.group();
    let norm = u.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
    let elements: Vec<usize> = (0..group.order())
        .filter(|&g| {
            let r = group.element(g);
            let perm = action.node_perm(g);
            let mut err = 0.0;
            for (i, &j) in perm.iter().enumerate().take(layout.nodes()) {
                let Some(d) = layout.dof(i, 0) else { continue };
                let ui = nalgebra::Vector3::new(u[d], u[d + 1], u[d + 2]);
                let dj = layout.dof(j, 0).expect("free nodes map to free nodes");
                let uj = nalgebra::Vector3::new(u[dj], u[dj + 1], u[dj + 2]);
                err += (r * ui - uj).norm_squared();
            }
            err.sqrt() <= 1e-8 * norm
        })
        .collect();
    let rotations = elements
        .iter()
        .filter(|&&g| group.element(g).determinant() > 0.0)
        .count();
    let mirrors = elements.len() - rotations;
    let about_z = elements.iter().all(|&g| {
        let z = group.element(g) * nalgebra::Vector3::z();
        (z - nalgebra::Vector3::z()).norm() < 1e-9
    });
    let name = if elements.len() == group.order() {
        group.name().to_string()
    } else if about_z && (mirrors == 0 || mirrors == rotations) {
        format!("C{rotations}{}", if mirrors > 0 { "v" } else { "" })
    } else {
        format!("order {}", elements.len())
    };
    Isotropy {
        name,
        order: elements.len(),
        elements,
    }
}

/// The wave number about z of a mode over the unknowns: the m (0…`max_m`) whose cos mθ and
/// sin mθ carry most of its cylindrical components (u_r, u_θ, u_z), nodes weighted by their
/// distance from the axis. Used to identify modes by Fourier content, never by sorted order.
pub fn wave_number(
    nodes: &[nalgebra::Vector3<f64>],
    layout: &Layout,
    mode: &[f64],
    max_m: usize,
) -> usize {
    let size = nodes.iter().map(|x| x.norm()).fold(0.0, f64::max);
    // (θ, r, [u_r, u_θ, u_z]) per free node off the axis.
    let samples: Vec<(f64, f64, [f64; 3])> = nodes
        .iter()
        .enumerate()
        .filter_map(|(i, x)| {
            let r = x.x.hypot(x.y);
            if r <= 1e-9 * size {
                return None;
            }
            let d = [layout.dof(i, 0)?, layout.dof(i, 1)?, layout.dof(i, 2)?];
            let t = x.y.atan2(x.x);
            let (s, c) = t.sin_cos();
            let (ux, uy, uz) = (mode[d[0]], mode[d[1]], mode[d[2]]);
            Some((t, r, [c * ux + s * uy, -s * ux + c * uy, uz]))
        })
        .collect();
    let power = |m: usize| {
        let mut total = 0.0;
        for k in 0..3 {
            let (mut c, mut s, mut nc, mut ns) = (0.0, 0.0, 0.0, 0.0);
            for (t, r, u) in &samples {
                let (sn, cs) = (t * m as f64).sin_cos();
                c += u[k] * cs * r;
                s += u[k] * sn * r;
                nc += (cs * r).powi(2);
                ns += (sn * r).powi(2);
            }
            total += c * c / nc.max(1e-300);
            if ns > 1e-12 * nc.max(1e-300) {
                total += s * s / ns;
            }
        }
        total
    };
    let mut best = (0, f64::NEG_INFINITY);
    for m in 0..=max_m {
        let p = power(m);
        if p > best.1 * (1.0 + 1e-9) {
            best = (m, p);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regula_falsi_finds_a_root_to_round_off() {
        let f = |s: f64| Some((s - 0.3).powi(3) + 0.5 * (s - 0.3));
        let (s, fs) = locate_sign_change(f, f(0.0).unwrap(), 1.0, f(1.0).unwrap(), 1e-14).unwrap();
        assert!((s - 0.3).abs() < 1e-12 && fs.abs() <= 1e-14, "{s} {fs}");
    }

    #[test]
    fn names() {
        assert_eq!(classify(true, 1), "limit point");
        assert_eq!(classify(false, 1), "simple bifurcation");
        assert_eq!(classify(false, 2), "double bifurcation");
        assert_eq!(classify(false, 5), "5-fold bifurcation");
    }
}
