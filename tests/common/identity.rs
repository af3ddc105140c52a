//! Whether two branches of a diagram are one branch up to symmetry, checked independently of
//! the library's own identity test: by the study's group action applied here, point by point.

use memstab::model::Model;
use memstab::results::SwitchedBranch;
use memstab::study::mesh::MeshStudy;

/// T(g) u of the study's action (independent of the library's).
pub fn act(study: &MeshStudy, g: usize, u: &[f64]) -> Vec<f64> {
    let layout = study.model.layout();
    let r = study.action.group().element(g);
    let mut out = vec![0.0; u.len()];
    for (i, &j) in study.action.node_perm(g).iter().enumerate() {
        let (Some(a), Some(b)) = (layout.dof(i, 0), layout.dof(j, 0)) else {
            continue;
        };
        let v = r * nalgebra::Vector3::new(u[a], u[a + 1], u[a + 2]);
        out[b..b + 3].copy_from_slice(v.as_slice());
    }
    out
}

/// A point of a branch as one vector of the diagram's space: the state over `state_scale`
/// and the control over `control_scale`.
fn scaled(u: &[f64], control: f64, state_scale: f64, control_scale: f64) -> Vec<f64> {
    let mut v: Vec<f64> = u.iter().map(|x| x / state_scale).collect();
    v.push(control / control_scale);
    v
}

fn distance_to_segment(p: &[f64], a: &[f64], b: &[f64]) -> f64 {
    let (mut ab2, mut apab) = (0.0, 0.0);
    for ((p, a), b) in p.iter().zip(a).zip(b) {
        ab2 += (b - a) * (b - a);
        apab += (p - a) * (b - a);
    }
    let t = if ab2 > 0.0 {
        (apab / ab2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.iter()
        .zip(a)
        .zip(b)
        .map(|((p, a), b)| {
            let d = p - a - t * (b - a);
            d * d
        })
        .sum::<f64>()
        .sqrt()
}

/// A stretch of a branch that runs along another branch up to the group.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Common {
    /// The branch whose points they are.
    pub branch: usize,
    /// The branch it runs along, up to the group.
    pub along: usize,
    /// Its points that do, consecutive.
    pub points: std::ops::Range<usize>,
}

/// How near another branch's image a point must lie to be on it: a twentieth of its own
/// branch's longest step. A branch followed twice lies within the chord error of its other
/// copy's polyline, far less; a branch that crosses or meets another does so at one point, and
/// branches that leave one point draw apart at a finite angle.
pub const ON_ANOTHER: f64 = 0.05;

/// The stretches of two or more consecutive points along which a branch of `branches` runs
/// along a group image of another: for every ordered pair (j, i), j ≠ i, the points of j but
/// its first (on its parent) and last (where it may end on a known point) whose distance from
/// the polyline of T(g)·(points of i), for the nearest g of the group, is below
/// [`ON_ANOTHER`] of j's longest step. Each axis is scaled by its spread over the diagram:
/// the control (parameter `control` of the points) by its range, the state by the largest
/// distance of a branch's state from its first. Empty when no branch repeats another.
pub fn common_stretches(
    study: &MeshStudy,
    branches: &[SwitchedBranch],
    control: usize,
) -> Vec<Common> {
    let mut near = shared_points(study, branches, control);
    near.sort_unstable();
    let mut out: Vec<Common> = Vec::new();
    for (j, i, k) in near {
        match out.last_mut() {
            Some(c) if c.branch == j && c.along == i && c.points.end == k => c.points.end = k + 1,
            _ => out.push(Common {
                branch: j,
                along: i,
                points: k..k + 1,
            }),
        }
    }
    out.retain(|c| c.points.len() >= 2);
    out
}

/// The points (j, i, k) of [`common_stretches`]: point k of branch j lies on branch i.
fn shared_points(
    study: &MeshStudy,
    branches: &[SwitchedBranch],
    control: usize,
) -> Vec<(usize, usize, usize)> {
    // Each axis over the diagram's spread of it: the control's range, and the largest
    // distance of a branch's state from its first (the critical point it leaves).
    let controls = branches
        .iter()
        .flat_map(|b| b.points.iter().map(|p| p.parameters[control]));
    let (lo, hi) = controls.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
        (lo.min(c), hi.max(c))
    });
    let control_scale = (hi - lo).max(f64::MIN_POSITIVE);
    let state_scale = branches
        .iter()
        .flat_map(|b| {
            let first = &b.points[0].u;
            b.points.iter().map(move |p| {
                p.u.iter()
                    .zip(first)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            })
        })
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let point = |p: &memstab::results::BranchPoint| -> Vec<f64> {
        scaled(&p.u, p.parameters[control], state_scale, control_scale)
    };
    let order = study.action.group().order();
    // Every branch's points and all their images.
    let images: Vec<Vec<Vec<Vec<f64>>>> = branches
        .iter()
        .map(|b| {
            (0..order)
                .map(|g| {
                    b.points
                        .iter()
                        .map(|p| {
                            let mut v = point(p);
                            let c = v.pop().unwrap();
                            let mut w = act(study, g, &v);
                            w.push(c);
                            w
                        })
                        .collect()
                })
                .collect()
        })
        .collect();
    let mut shared = Vec::new();
    for j in 0..branches.len() {
        let own = &images[j][0];
        let step = own
            .windows(2)
            .map(|w| distance_to_segment(&w[1], &w[0], &w[0]))
            .fold(0.0, f64::max);
        if own.len() < 3 || step == 0.0 {
            continue;
        }
        for (k, p) in own.iter().enumerate().take(own.len() - 1).skip(1) {
            for (i, of_i) in images.iter().enumerate() {
                if i == j {
                    continue;
                }
                let c = p[p.len() - 1];
                let nearest = of_i
                    .iter()
                    .flat_map(|pts| pts.windows(2))
                    .filter(|w| {
                        let (a, b) = (w[0][w[0].len() - 1], w[1][w[1].len() - 1]);
                        c >= a.min(b) - step && c <= a.max(b) + step
                    })
                    .map(|w| distance_to_segment(p, &w[0], &w[1]))
                    .fold(f64::INFINITY, f64::min);
                if nearest < ON_ANOTHER * step {
                    shared.push((j, i, k));
                }
            }
        }
    }
    shared
}
