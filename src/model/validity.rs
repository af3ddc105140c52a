//! Whether a displacement is a membrane state at all (docs/theory.md §7.5.1).
//!
//! Newton and the path corrector converge on the residual; nothing in that test stops them
//! at a membrane that collapsed to a point, tore into needles or turned inside out, and the
//! potentials of some effects stay finite there. An accepted state must have
//!
//! - every node at a finite position;
//! - in every triangle, both principal stretches λ₁, λ₂ of its in-plane deformation within
//!   [[`STRETCH_MIN`], [`STRETCH_MAX`]] — with G and g the reference and current metrics of
//!   the triangle's edges, λ₁² and λ₂² are the eigenvalues of G⁻¹g:
//!   λ² = (I₁ ± √(I₁² − 4J²))/2, I₁ = tr G⁻¹g, J² = det g / det G;
//! - for a closed membrane, an enclosed volume V = Σ x_a·(x_b × x_c)/6 of the reference's
//!   sign (a membrane turned inside out has the opposite one).

use super::Vec3;
use std::collections::HashMap;

/// The smallest principal stretch of an accepted state (a thousandfold compression).
pub const STRETCH_MIN: f64 = 1e-3;
/// The largest principal stretch of an accepted state (a thousandfold extension).
pub const STRETCH_MAX: f64 = 1e3;

/// Why a displacement is not a membrane state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StateDefect {
    /// A node's position is not finite.
    #[error("node {node} is at a non-finite position")]
    NotFinite {
        /// The node.
        node: usize,
    },
    /// A triangle collapsed or was drawn out beyond any membrane's range.
    #[error(
        "triangle {triangle} has a principal stretch of {stretch:.1e}, outside [{STRETCH_MIN:e}, {STRETCH_MAX:e}] (the membrane collapsed or tore)"
    )]
    Stretch {
        /// The triangle.
        triangle: usize,
        /// Its principal stretch furthest outside the range.
        stretch: f64,
    },
    /// A closed membrane's enclosed volume has the opposite sign of the reference's.
    #[error("the enclosed volume is {volume:.3e}, of the opposite sign of the reference's (the membrane turned inside out)")]
    InsideOut {
        /// The enclosed volume found.
        volume: f64,
    },
}

/// The principal stretches (λ₁ ≥ λ₂) of the triangle with reference corners `r` and current
/// corners `x`.
pub fn principal_stretches(r: [Vec3; 3], x: [Vec3; 3]) -> (f64, f64) {
    let (e1, e2) = (r[1] - r[0], r[2] - r[0]);
    let (f1, f2) = (x[1] - x[0], x[2] - x[0]);
    let (g11, g12, g22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let (h11, h12, h22) = (f1.dot(&f1), f1.dot(&f2), f2.dot(&f2));
    // det G = |E₁ × E₂|² and det g = |e₁ × e₂|², free of the cancellation in g₁₁g₂₂ − g₁₂².
    let det_g = e1.cross(&e2).norm_squared();
    // tr(G⁻¹ g) with G⁻¹ = [[g22, −g12], [−g12, g11]] / det G.
    let i1 = (g22 * h11 - 2.0 * g12 * h12 + g11 * h22) / det_g;
    let j2 = f1.cross(&f2).norm_squared() / det_g;
    let root = (i1 * i1 - 4.0 * j2).max(0.0).sqrt();
    let big = 0.5 * (i1 + root);
    // The smaller root as J²/big, which keeps its digits when it is tiny.
    let small = if big > 0.0 { j2 / big } else { 0.0 };
    (big.max(0.0).sqrt(), small.max(0.0).sqrt())
}

/// The edges of `triangles` at once: whether every edge is shared by exactly two of them
/// ([`is_closed`]), and the rim — the nodes a on a directed edge (a, b) of some triangle
/// whose reverse (b, a) is no triangle's edge, sorted — from one sort of the directed edges
/// (no hashing: the answer of a mesh's every state check and of its relabellings).
pub fn edge_summary(triangles: &[[usize; 3]]) -> (bool, Vec<usize>) {
    let key = |a: usize, b: usize| ((a as u128) << 64) | b as u128;
    let mut directed: Vec<u128> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| key(t[k], t[(k + 1) % 3])))
        .collect();
    directed.sort_unstable();
    let count = |k: u128| {
        let lo = directed.partition_point(|&x| x < k);
        directed[lo..].iter().take_while(|&&x| x == k).count()
    };
    let mut closed = !triangles.is_empty();
    let mut rim = Vec::new();
    let mut k = 0;
    while k < directed.len() {
        let here = directed[k];
        let run = directed[k..].iter().take_while(|&&x| x == here).count();
        let (a, b) = ((here >> 64) as usize, here as u64 as usize);
        let reverse = count(key(b, a));
        if reverse == 0 {
            rim.push(a);
        }
        closed &= run + reverse == 2;
        k += run;
    }
    rim.sort_unstable();
    rim.dedup();
    (closed, rim)
}

/// Whether every edge of `triangles` is shared by exactly two of them.
pub fn is_closed(triangles: &[[usize; 3]]) -> bool {
    let mut count: HashMap<(usize, usize), u32> = HashMap::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    !triangles.is_empty() && count.values().all(|&c| c == 2)
}

/// The signed volume Σ x_a·(x_b × x_c)/6 of a closed surface.
pub fn enclosed_volume(triangles: &[[usize; 3]], x: &[Vec3]) -> f64 {
    triangles
        .iter()
        .map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c])))
        .sum::<f64>()
        / 6.0
}

/// The first defect of the state with positions `x` of the mesh (`reference`, `triangles`),
/// or `None` for a membrane state.
pub fn state_defect(
    reference: &[Vec3],
    triangles: &[[usize; 3]],
    x: &[Vec3],
) -> Option<StateDefect> {
    state_defect_of(reference, triangles, x, is_closed(triangles))
}

/// As [`state_defect`], with whether the mesh is closed known ([`is_closed`]; the layout
/// keeps it): an inside-out state is tested only on a closed mesh.
pub fn state_defect_of(
    reference: &[Vec3],
    triangles: &[[usize; 3]],
    x: &[Vec3],
    closed: bool,
) -> Option<StateDefect> {
    if let Some(node) = x.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Some(StateDefect::NotFinite { node });
    }
    for (triangle, &[a, b, c]) in triangles.iter().enumerate() {
        let (l1, l2) = principal_stretches(
            [reference[a], reference[b], reference[c]],
            [x[a], x[b], x[c]],
        );
        if l1.is_nan() || l1 > STRETCH_MAX {
            return Some(StateDefect::Stretch {
                triangle,
                stretch: l1,
            });
        }
        if l2.is_nan() || l2 < STRETCH_MIN {
            return Some(StateDefect::Stretch {
                triangle,
                stretch: l2,
            });
        }
    }
    if closed {
        let (v0, v) = (
            enclosed_volume(triangles, reference),
            enclosed_volume(triangles, x),
        );
        if v * v0.signum() <= 0.0 {
            return Some(StateDefect::InsideOut { volume: v });
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let x = vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ];
        // Outward orientation.
        let t = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        (x, t)
    }

    #[test]
    fn principal_stretches_of_a_homogeneous_deformation() {
        let r = [
            Vec3::zeros(),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.3, 0.8, 0.0),
        ];
        // x = R · diag(3, 0.5, ·) X with a rotation R about z: stretches 3 and 0.5.
        let (c, s) = (0.6f64, 0.8f64);
        let map = |p: Vec3| {
            let (a, b) = (3.0 * p.x, 0.5 * p.y);
            Vec3::new(c * a - s * b, s * a + c * b, 7.0)
        };
        let (l1, l2) = principal_stretches(r, [map(r[0]), map(r[1]), map(r[2])]);
        assert!(
            (l1 - 3.0).abs() < 1e-14 && (l2 - 0.5).abs() < 1e-14,
            "{l1} {l2}"
        );
        // A tiny stretch keeps its relative digits.
        let tiny = |p: Vec3| Vec3::new(p.x, 1e-12 * p.y, 0.0);
        let (_, l2) = principal_stretches(r, [tiny(r[0]), tiny(r[1]), tiny(r[2])]);
        assert!((l2 / 1e-12 - 1.0).abs() < 1e-6, "{l2}");
    }

    #[test]
    fn a_scaled_state_is_accepted_until_its_stretch_leaves_the_range() {
        let (x, t) = tetrahedron();
        assert!(is_closed(&t) && !is_closed(&t[..3]));
        assert_eq!(edge_summary(&t), (true, vec![]));
        // Without the fourth face, its three nodes are the rim.
        let mut missing = t[3].to_vec();
        missing.sort_unstable();
        assert_eq!(edge_summary(&t[..3]), (false, missing));
        assert_eq!(edge_summary(&[]), (false, vec![]));
        let scaled = |f: f64| x.iter().map(|p| p * f).collect::<Vec<_>>();
        assert_eq!(state_defect(&x, &t, &scaled(1.0)), None);
        assert_eq!(state_defect(&x, &t, &scaled(0.9 * STRETCH_MAX)), None);
        assert!(matches!(
            state_defect(&x, &t, &scaled(0.5 * STRETCH_MIN)),
            Some(StateDefect::Stretch { stretch, .. }) if (stretch / (0.5 * STRETCH_MIN) - 1.0).abs() < 1e-12
        ));
        assert!(matches!(
            state_defect(&x, &t, &scaled(2.0 * STRETCH_MAX)),
            Some(StateDefect::Stretch { .. })
        ));
    }

    #[test]
    fn a_point_reflection_turns_a_closed_membrane_inside_out() {
        let (x, t) = tetrahedron();
        let reflected: Vec<Vec3> = x.iter().map(|p| -p).collect();
        assert!(matches!(
            state_defect(&x, &t, &reflected),
            Some(StateDefect::InsideOut { volume }) if volume < 0.0
        ));
        // An open membrane may be reflected.
        assert_eq!(state_defect(&x, &t[..3], &reflected), None);
        // A reference oriented inwards keeps its sign.
        let inward: Vec<[usize; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert_eq!(state_defect(&x, &inward, &x), None);
    }

    #[test]
    fn a_non_finite_node_is_named() {
        let (x, t) = tetrahedron();
        let mut bad = x.clone();
        bad[2].y = f64::NAN;
        assert_eq!(
            state_defect(&x, &t, &bad),
            Some(StateDefect::NotFinite { node: 2 })
        );
    }
}
