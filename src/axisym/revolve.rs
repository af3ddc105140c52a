//! A meridian state drawn as a 3-D surface (docs/theory.md §15.17): the meridian revolved
//! about z into a triangulated [`Mesh`], the revolved positions of a state, and the 3-D
//! displacement field of a Fourier mode on it, so that a meridian run can be written and
//! viewed as a 3-D run is.
//!
//! Every meridian node i becomes a ring of `segments` nodes at the angles
//! θ_k = 2πk/`segments` (θ = 0 on +x, e_r = (cos θ, sin θ, 0), e_θ = (−sin θ, cos θ, 0)),
//! numbered ring after ring along the meridian and by k within a ring, except a node on the
//! axis (R = 0 in the reference), which is one pole node. The quad between the rings of
//! nodes i and i + 1 and the angles θ_k, θ_k+1 is split along its diagonal
//! (i, k)–(i + 1, k + 1) into the triangles ((i, k), (i + 1, k), (i + 1, k + 1)) and
//! ((i, k), (i + 1, k + 1), (i, k + 1)); next to a pole one of the two collapses and the
//! other is a triangle of the pole's fan. Their area vectors point along x_ξ × x_θ, the
//! meridian's orientation (outward on a sphere from the north pole to the south pole and
//! on a cap from its pole to its cut, +z on a disc from the axis to its rim), as the
//! triangles of the 3-D generators do. A quad between two rings is an isosceles trapezoid
//! (planar), so area and enclosed volume converge at second order in the meridian's node
//! spacing and in 2π/`segments`.
//!
//! Node sets are named as the 3-D generators name them: the ring of a meridian end off the
//! axis is `rim` on a flat meridian (every reference Z equal: a disc) and `cut` on a curved
//! one (a truncated sphere); a sphere has none. (A meridian with both ends off the axis,
//! which no constructor builds, names its first end's ring `rim_first` or `cut_first`.)
//!
//! These are pure functions of the model's data: nothing here writes a file.

use super::{AxisymError, AxisymModel, Meridian};
use meshes::{Mesh, Vec3};
use std::f64::consts::PI;
use std::ops::Range;

/// The fewest segments a ring is drawn with: its polygon then lies within
/// 1 − cos(π/48) ≈ 0.2 % of the radius of the circle.
const MIN_SEGMENTS: usize = 48;

/// Segments per wavelength of cos mθ: the polygon through the samples of cos mθ then departs
/// from it by at most (2π/16)²/8 ≈ 1.9 % of the amplitude.
const SEGMENTS_PER_WAVE: usize = 16;

/// The default number of segments for drawing a state, or a mode of wave number `m`:
/// max(48, 16 m), rounded up to a multiple of 4.
///
/// 48 segments draw a ring within 0.2 % of its radius; 16 per wavelength draw cos mθ within
/// 1.9 % of its amplitude, well above the 2m + 1 samples a harmonic of order m needs to be
/// resolved at all; a multiple of 4 puts nodes on the ±x and ±y axes, so the drawn surface
/// keeps the mirror planes x = 0 and y = 0 and the quarter turns about z. m ≤ 3 take 48
/// segments, m = 24 takes 384.
pub fn default_segments(m: usize) -> usize {
    MIN_SEGMENTS
        .max(SEGMENTS_PER_WAVE.saturating_mul(m))
        .next_multiple_of(4)
}

/// The revolved nodes of every meridian node: a range of `segments` nodes (θ_k at the k-th),
/// or of one node on the axis.
struct Rings {
    rings: Vec<Range<usize>>,
    segments: usize,
}

impl Rings {
    fn new(meridian: &Meridian, segments: usize) -> Result<Self, AxisymError> {
        if segments < 3 {
            return Err(AxisymError::Input(format!(
                "segments: must be at least 3, got {segments}"
            )));
        }
        let mut start = 0;
        let rings = meridian
            .nodes
            .iter()
            .map(|x| {
                let len = if on_axis(x) { 1 } else { segments };
                start += len;
                start - len..start
            })
            .collect();
        Ok(Self { rings, segments })
    }

    /// The revolved node of meridian node i at θ_k (k taken modulo the segments; a pole at
    /// every k).
    fn node(&self, i: usize, k: usize) -> usize {
        let ring = &self.rings[i];
        if ring.len() == 1 {
            ring.start
        } else {
            ring.start + k % self.segments
        }
    }

    /// The number of revolved nodes.
    fn count(&self) -> usize {
        self.rings.last().map_or(0, |r| r.end)
    }

    /// (cos θ_k, sin θ_k) for k = 0 … segments − 1.
    fn angles(&self) -> Vec<(f64, f64)> {
        (0..self.segments)
            .map(|k| {
                let (s, c) = (2.0 * PI * k as f64 / self.segments as f64).sin_cos();
                (c, s)
            })
            .collect()
    }

    /// Meridian nodes (r, z) revolved onto the rings (a pole on the axis at its height).
    fn revolve(&self, x: &[[f64; 2]]) -> Vec<Vec3> {
        let angles = self.angles();
        let mut nodes = Vec::with_capacity(self.count());
        for (ring, &[r, z]) in self.rings.iter().zip(x) {
            if ring.len() == 1 {
                nodes.push(Vec3::new(0.0, 0.0, z));
            } else {
                nodes.extend(angles.iter().map(|&(c, s)| Vec3::new(r * c, r * s, z)));
            }
        }
        nodes
    }
}

/// Whether a reference node is on the axis (the model's criterion: R = 0 exactly).
fn on_axis(x: &[f64; 2]) -> bool {
    x[0] == 0.0
}

/// The revolved nodes of every meridian node of `meridian` drawn with `segments` segments:
/// node i at θ_k is `rings[i].start + k`, a node on the axis is the single node of its range.
///
/// # Errors
/// [`AxisymError::Input`] if `segments` < 3.
pub fn revolved_rings(
    meridian: &Meridian,
    segments: usize,
) -> Result<Vec<Range<usize>>, AxisymError> {
    Ok(Rings::new(meridian, segments)?.rings)
}

/// The name of the node set of a meridian end off the axis: `rim` on a flat meridian (a
/// disc), `cut` on a curved one (a truncated sphere).
fn edge_name(meridian: &Meridian) -> &'static str {
    let z0 = meridian.nodes[0][1];
    if meridian.nodes.iter().all(|x| x[1] == z0) {
        "rim"
    } else {
        "cut"
    }
}

/// The reference surface of `meridian` revolved about z with `segments` segments per ring
/// (see the module docs for the numbering, the triangles, their orientation and the node
/// sets).
///
/// # Errors
/// [`AxisymError::Input`] if `segments` < 3, or if the revolved triangles do not make a mesh
/// (a meridian with two consecutive nodes on the axis).
pub fn revolved_mesh(meridian: &Meridian, segments: usize) -> Result<Mesh, AxisymError> {
    let rings = Rings::new(meridian, segments)?;
    let n = meridian.nodes.len();
    let mut triangles = Vec::with_capacity(2 * segments * n);
    for i in 0..n - 1 {
        for k in 0..segments {
            let a = rings.node(i, k);
            let b = rings.node(i + 1, k);
            let c = rings.node(i + 1, k + 1);
            let d = rings.node(i, k + 1);
            for t in [[a, b, c], [a, c, d]] {
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    triangles.push(t);
                }
            }
        }
    }
    let mut mesh = Mesh::new(rings.revolve(&meridian.nodes), triangles)
        .map_err(|e| AxisymError::Input(format!("the revolved meridian: {e}")))?;
    let name = edge_name(meridian);
    let open = |i: usize| !on_axis(&meridian.nodes[i]);
    if open(n - 1) {
        mesh.set_boundary(name, rings.rings[n - 1].clone().collect());
    }
    if open(0) {
        let first = if open(n - 1) {
            format!("{name}_first")
        } else {
            name.to_string()
        };
        mesh.set_boundary(first, rings.rings[0].clone().collect());
    }
    Ok(mesh)
}

/// The nodes of the surface of [`revolved_mesh`] (same numbering) at the state of
/// displacement `q`: the current meridian nodes [`AxisymModel::positions`] revolved, for
/// writing the state over the revolved reference mesh.
///
/// # Errors
/// [`AxisymError::Input`] if `segments` < 3 or `q` has not [`AxisymModel::dim`] entries.
pub fn revolved_positions(
    model: &AxisymModel,
    q: &[f64],
    segments: usize,
) -> Result<Vec<Vec3>, AxisymError> {
    if q.len() != model.dim() {
        return Err(AxisymError::Input(format!(
            "state: {} unknowns for a model of {}",
            q.len(),
            model.dim()
        )));
    }
    let rings = Rings::new(&model.meridian, segments)?;
    Ok(rings.revolve(&model.positions(q)))
}

/// The amplitudes (U, V, W) at every meridian node of the displacement of wave number `m`
/// whose kept unknowns ([`AxisymModel::block_layout`]'s `kept`) are the first entries of
/// `mode` (border entries after them are ignored): zero where the block holds them, and on
/// the axis for m = 1 U = −V = the node's kept entry.
///
/// # Errors
/// [`AxisymError::Input`] if `mode` is shorter than the block's kept unknowns.
pub fn mode_amplitudes(
    model: &AxisymModel,
    m: usize,
    mode: &[f64],
) -> Result<Vec<[f64; 3]>, AxisymError> {
    let (map, kept) = model.kept_map(m);
    if mode.len() < kept {
        return Err(AxisymError::Input(format!(
            "mode: {} entries for the {kept} kept unknowns of the block m = {m}",
            mode.len()
        )));
    }
    let mut amplitudes = vec![[0.0; 3]; model.meridian.nodes.len()];
    for (row, entry) in map.iter().enumerate() {
        if let Some((col, coefficient)) = *entry {
            amplitudes[row / 3][row % 3] = coefficient * mode[col];
        }
    }
    Ok(amplitudes)
}

/// The value on the axis of the field of wave number `m` with amplitudes (U, V, W) there: its
/// mean over θ, which is its limit r → 0 when the field is regular (the held components of
/// docs/theory.md §15.1): W e_z for m = 0, ((U − V)/2) e_x for m = 1 (U e_x when U = −V),
/// zero for m ≥ 2.
fn pole_value(m: usize, [u, v, w]: [f64; 3]) -> [f64; 3] {
    match m {
        0 => [0.0, 0.0, w],
        1 => [0.5 * (u - v), 0.0, 0.0],
        _ => [0.0; 3],
    }
}

/// The 3-D displacement of the mode of wave number `m` whose kept unknowns are the first
/// entries of `mode` (see [`mode_amplitudes`]) at every node of [`revolved_mesh`]:
///
/// ```text
///   δx = U cos mθ e_r + V sin mθ e_θ + W cos mθ e_z     (m ≥ 1),
///   δx = U e_r + V e_θ + W e_z                          (m = 0),
/// ```
///
/// at θ_k on the ring of each meridian node, and on the axis its limit there (W e_z for
/// m = 0, U e_x for m = 1, zero for m ≥ 2: the block holds the rest).
///
/// # Errors
/// [`AxisymError::Input`] if `segments` < 3 or `mode` is shorter than the block's kept
/// unknowns.
pub fn revolved_mode(
    model: &AxisymModel,
    m: usize,
    mode: &[f64],
    segments: usize,
) -> Result<Vec<[f64; 3]>, AxisymError> {
    let amplitudes = mode_amplitudes(model, m, mode)?;
    let rings = Rings::new(&model.meridian, segments)?;
    let angles = rings.angles();
    // cos mθ_k and sin mθ_k from the angle of (m k mod segments) (m = 0: both 1).
    let harmonic: Vec<(f64, f64)> = (0..segments)
        .map(|k| {
            if m == 0 {
                (1.0, 1.0)
            } else {
                angles[(m % segments) * k % segments]
            }
        })
        .collect();
    let mut field = Vec::with_capacity(rings.count());
    for (ring, &a) in rings.rings.iter().zip(&amplitudes) {
        if ring.len() == 1 {
            field.push(pole_value(m, a));
            continue;
        }
        let [u, v, w] = a;
        field.extend(angles.iter().zip(&harmonic).map(|(&(ct, st), &(c, s))| {
            let (ur, ut) = (u * c, v * s);
            [ur * ct - ut * st, ur * st + ut * ct, w * c]
        }));
    }
    Ok(field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axisym::{FloorPlane, Pressure};
    use crate::effects::membrane::MooneyRivlin;
    use crate::effects::Quantity;

    /// The models whose blocks hold unknowns in every way: a clamped disc, a closed sphere
    /// (rigid motions held), a sphere on a plane (its pole's height free), a cap whose cut
    /// slides.
    fn models() -> Vec<AxisymModel> {
        let mat = MooneyRivlin::new(1.0, 0.2, 0.1);
        let gas = Pressure::Gas {
            pressure: Quantity::Value(0.1),
        };
        let disc = AxisymModel::new(Meridian::disc(1.0, 3, 1.05, mat).unwrap(), vec![]);
        let sphere = AxisymModel::new(Meridian::sphere(1.0, 4, 1.05, mat).unwrap(), vec![gas]);
        let mut on_plane = sphere.clone();
        on_plane.set_planes(vec![FloorPlane {
            normal_z: 1.0,
            offset: Quantity::Value(-1.0),
            penalty: Quantity::Value(10.0),
            exponent: 1,
        }]);
        let mut cap = Meridian::truncated_sphere(1.0, 0.0, 4, 1.05, mat).unwrap();
        cap.clamped = (false, false);
        cap.sliding = (false, true);
        let cap = AxisymModel::new(cap, vec![gas]);
        vec![disc, sphere, on_plane, cap]
    }

    /// Where the block of wave number m holds a node's U, V or W, the mode's field has no
    /// e_r, e_θ or e_z component on that node's ring, whatever the kept entries; where it
    /// keeps one, the component is not zero on a generic vector (off the axis).
    #[test]
    fn held_components_vanish_on_their_rings() {
        let segments = 13;
        for model in models() {
            let rings = revolved_rings(&model.meridian, segments).unwrap();
            for m in 0..4 {
                let (map, kept) = model.kept_map(m);
                let mode: Vec<f64> = (0..kept).map(|j| 1.0 + 0.37 * j as f64).collect();
                let field = revolved_mode(&model, m, &mode, segments).unwrap();
                for (i, ring) in rings.iter().enumerate() {
                    for (kk, node) in ring.clone().enumerate() {
                        let theta = 2.0 * PI * kk as f64 / segments as f64;
                        let (s, c) = theta.sin_cos();
                        let f = field[node];
                        let cyl = [f[0] * c + f[1] * s, -f[0] * s + f[1] * c, f[2]];
                        for comp in 0..3 {
                            let held = map[3 * i + comp].is_none();
                            if held {
                                assert!(
                                    cyl[comp].abs() < 1e-14,
                                    "m = {m}, node {i}, component {comp}: {}",
                                    cyl[comp]
                                );
                            }
                        }
                        if ring.len() > 1 && kk == 1 {
                            for comp in 0..3 {
                                if map[3 * i + comp].is_some() {
                                    assert!(cyl[comp].abs() > 1e-3, "m = {m}, node {i}");
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
