//! What a critical mode is, on a 3-D mesh with its group: the subgroup of the group that keeps
//! it (its isotropy), and its wave number about z on a mesh with an axis (docs/theory.md §11).

use crate::model::Layout;
use crate::results::Isotropy;
use meshes::GroupAction;

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
