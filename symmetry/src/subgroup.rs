//! Subgroups that keep given directions or planes, identified as groups of their own.
//!
//! A scene restricts the mesh's group to the elements that keep every load and boundary
//! condition: gravity keeps the direction −z, a rigid plane keeps the plane. Inside `Ih` the
//! stabiliser of a direction is `C5v`, `C3v`, `C2v`, `C1v` or `C1` (a vertex, a face centre, an
//! edge midpoint, a point on a mirror, or a generic point along the direction). Such
//! stabilisers are axial groups, which are recognised here and given their own irreps
//! (see the `axial` module) while keeping the parent's matrices.

use crate::axial::axial;
use crate::group::{Group, GroupError, Matrix3};
use crate::MATRIX_TOL;
use nalgebra::Vector3;

/// Something a group element may keep or move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Invariant {
    /// A direction `v` (not just its line): kept when `R v = v`.
    Direction(Vector3<f64>),
    /// A line through the origin along `v`: kept when `R v = ±v`.
    Axis(Vector3<f64>),
    /// The plane `n·x = offset`: kept when `R n = n`, or also `R n = −n` if the plane passes
    /// through the origin (`offset = 0`).
    Plane {
        /// The plane normal.
        normal: Vector3<f64>,
        /// The plane's offset along the normal.
        offset: f64,
    },
}

impl Invariant {
    /// True if the orthogonal matrix `r` keeps this invariant (to 1e-9 relative).
    pub fn kept_by(&self, r: &Matrix3) -> bool {
        let close = |a: Vector3<f64>, b: Vector3<f64>| (a - b).amax() < 1e-9 * b.amax().max(1.0);
        match *self {
            Invariant::Direction(v) => close(r * v, v),
            Invariant::Axis(v) => close(r * v, v) || close(r * v, -v),
            Invariant::Plane { normal, offset } => {
                close(r * normal, normal)
                    || (offset.abs() <= 1e-12 * normal.norm() && close(r * normal, -normal))
            }
        }
    }

    /// The direction it is about (a direction, the axis's, the plane's normal).
    pub fn direction(&self) -> Vector3<f64> {
        match *self {
            Invariant::Direction(v) | Invariant::Axis(v) => v,
            Invariant::Plane { normal, .. } => normal,
        }
    }
}

/// A subgroup as a group of its own, with the indices of its elements in the parent.
#[derive(Debug, Clone)]
pub struct Subgroup {
    /// The subgroup, with its own element order, irreps and name.
    pub group: Group,
    /// `parent_index[i]` is the index in the parent group of the subgroup's element `i`.
    pub parent_index: Vec<usize>,
}

impl Group {
    /// The subgroup of elements that keep every invariant in `keep`.
    ///
    /// If every element keeps them, this is the group itself (same name and order). An axial
    /// stabiliser (`C_n` or `C_nv` — always the case when a direction or an off-origin plane
    /// is kept) is built about the first invariant's direction; any other (an axis kept as a
    /// line, such as the spin axis of an icosphere: `D2h`, `D3d`, `D5d`) by
    /// [`Group::subgroup`], with its own irreps.
    pub fn stabilizer(&self, keep: &[Invariant]) -> Result<Subgroup, GroupError> {
        let members: Vec<usize> = (0..self.order())
            .filter(|&g| keep.iter().all(|k| k.kept_by(self.element(g))))
            .collect();
        if members.len() == self.order() {
            return Ok(Subgroup {
                group: self.clone(),
                parent_index: members,
            });
        }
        self.axial_subgroup(&members, keep.first().map(Invariant::direction))
            .or_else(|_| self.subgroup(&members))
    }

    /// Recognises the elements `members` (a subgroup) as `C_n` or `C_nv` about a common axis.
    pub(crate) fn axial_subgroup(
        &self,
        members: &[usize],
        hint: Option<Vector3<f64>>,
    ) -> Result<Subgroup, GroupError> {
        let unsupported = |why: &str| {
            GroupError::Unsupported(format!("{} in {}: {why}", members.len(), self.name()))
        };
        let (rotations, improper): (Vec<usize>, Vec<usize>) = members
            .iter()
            .partition(|&&g| self.element(g).determinant() > 0.0);
        let n = rotations.len();
        let axis = match rotations.iter().find(|&&g| g != 0) {
            Some(&g) => rotation_axis(self.element(g)),
            None => match improper.first() {
                // A lone mirror: any direction in its plane serves as the (trivial) axis.
                Some(&m) => in_plane_direction(self.element(m), hint),
                None => hint.unwrap_or_else(Vector3::z),
            },
        };
        let axis = match hint {
            Some(h) if axis.dot(&h) < 0.0 => -axis,
            _ => axis,
        };
        if rotations
            .iter()
            .any(|&g| (self.element(g) * axis - axis).amax() > 1e-9)
        {
            return Err(unsupported("the rotations do not share an axis"));
        }
        let mirror = match improper.len() {
            0 => None,
            m if m == n => {
                let is_mirror = |g: usize| {
                    let r = self.element(g);
                    (r.trace() - 1.0).abs() < 1e-9 && (r * axis - axis).amax() < 1e-9
                };
                if !improper.iter().all(|&g| is_mirror(g)) {
                    return Err(unsupported(
                        "improper elements that are not mirrors through the axis",
                    ));
                }
                Some(*self.element(improper[0]))
            }
            _ => return Err(unsupported("neither C_n nor C_nv")),
        };
        let name = format!("C{n}{}", if mirror.is_some() { "v" } else { "" });
        let model = axial(name.clone(), n, &axis, mirror);
        let parent_index: Vec<usize> = model
            .elements()
            .iter()
            .map(|m| self.find(m))
            .collect::<Option<_>>()
            .ok_or_else(|| unsupported("the axial model's elements are not all in the group"))?;
        if parent_index.iter().any(|g| !members.contains(g)) {
            return Err(unsupported("the axial model leaves the stabiliser"));
        }
        let elements = parent_index.iter().map(|&g| *self.element(g)).collect();
        let group = Group::from_parts(name, elements, model.irreps().to_vec())?;
        Ok(Subgroup {
            group,
            parent_index,
        })
    }
}

/// The unit axis of a rotation `R ≠ I`: `R + Rᵀ − (tr R − 1) I = 2 (1 − cos θ) a aᵀ`.
pub(crate) fn rotation_axis(r: &Matrix3) -> Vector3<f64> {
    let m = r + r.transpose() - Matrix3::identity() * (r.trace() - 1.0);
    let col = (0..3)
        .max_by(|&a, &b| m.column(a).norm().total_cmp(&m.column(b).norm()))
        .unwrap_or(0);
    let a: Vector3<f64> = m.column(col).into();
    a.normalize()
}

/// A unit vector in the plane of the mirror `m`, as close to `hint` as possible.
fn in_plane_direction(m: &Matrix3, hint: Option<Vector3<f64>>) -> Vector3<f64> {
    // The mirror is I − 2 n nᵀ; its normal is the axis of the half-turn −m.
    let normal = rotation_axis(&(-m));
    let candidates = [
        hint.unwrap_or_else(Vector3::z),
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
    ];
    candidates
        .iter()
        .map(|c| c - normal * normal.dot(c))
        .find(|v| v.norm() > MATRIX_TOL.sqrt())
        .map(|v| v.normalize())
        .unwrap_or_else(Vector3::z)
}
