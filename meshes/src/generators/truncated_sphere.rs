//! The truncated sphere ([`truncated_sphere`]): the spherical cap z ≥ c of a sphere, pole at
//! the top, built from the disc's sector pattern; the map is documented on
//! [`truncated_sphere`].

use super::disc::{check_pattern, check_radius, sector_domain, AxialSymmetry};
use crate::{Mesh, MeshError, SymmetricMesh, Vec3};

/// Number of sectors of the underlying pattern (its symmetry is `C8v`).
const SECTORS: usize = 8;

/// The default scaling s of the polar-angle map (see [`truncated_sphere`]).
const MAP_SCALE: f64 = 2.0;

/// The largest radial/tangential stretch ratio A(α_c) the map may cause at the cut.
const MAX_STRETCH: f64 = 2.0;

/// Reference element counts per pattern, which [`TruncatedSphereOptions::for_pattern`] matches.
const REFERENCE_ELEMENTS: [(&str, usize); 3] = [("C8v", 6656), ("C2v", 5472), ("C1v", 5520)];

/// Options of [`truncated_sphere`].
#[derive(Debug, Clone, PartialEq)]
pub struct TruncatedSphereOptions {
    /// Radius R of the sphere.
    pub radius: f64,
    /// Height c of the cut plane, −R < c < R; the membrane is the part with z ≥ c.
    pub cut_height: f64,
    /// Declared symmetry about z: `C8v` (the pattern's own), `C2v` or `C1v`; also accepted are
    /// the other subgroups of `C8v`: `C4v`, `C8`, `C4`, `C2`, `C1`.
    pub pattern: String,
    /// Number d of rings between the pole and the cut: 8 d² triangles.
    pub divisions: usize,
}

impl TruncatedSphereOptions {
    /// R = 1, c = −0.5, the given pattern, and d chosen so that 8 d² is closest to the
    /// reference element count of that pattern: `C8v` ≈ 6656 → d = 29 (6728 triangles),
    /// `C2v` ≈ 5472 and `C1v` ≈ 5520 → d = 26 (5408 triangles); other patterns as `C8v`.
    pub fn for_pattern(pattern: &str) -> Self {
        let target = REFERENCE_ELEMENTS
            .iter()
            .find(|(name, _)| *name == pattern)
            .map_or(REFERENCE_ELEMENTS[0].1, |&(_, n)| n);
        Self {
            radius: 1.0,
            cut_height: -0.5,
            pattern: pattern.to_string(),
            divisions: (target as f64 / SECTORS as f64).sqrt().round() as usize,
        }
    }
}

impl Default for TruncatedSphereOptions {
    /// `for_pattern("C8v")`: R = 1, c = −0.5, d = 29 — 6728 triangles, 3481 nodes.
    fn default() -> Self {
        Self::for_pattern("C8v")
    }
}

/// The cap z ≥ c of the sphere of radius R, outward oriented, open along the cut circle, with
/// exactly the declared symmetry about z.
///
/// 8 d² triangles and 4 d(d+1) + 1 nodes (one at the pole (0, 0, R)); the node set `cut` holds
/// the 8 d nodes on the circle z = c, x² + y² = R² − c², which are evenly spaced. The
/// default (d = 29) has 6728 triangles and 3481 nodes.
///
/// # Construction
///
/// The 8-sector pattern of [`disc`](crate::generators::disc()), built on the fundamental wedge
/// of the declared group and with its symmetry-breaking perturbation, is mapped from polar
/// parameters (ρ, θ) onto the cap by keeping θ and choosing the polar angle α (from +z):
///
/// ```text
/// tan(α / 2s) = ρ tan(α_c / 2s),   cos α_c = c / R,
/// X = R (sin α cos θ, sin α sin θ, cos α),
/// ```
///
/// and replicated by the group. s = 1 is the stereographic (conformal) map: triangles keep the
/// pattern's shape, but near a low cut they are much smaller than at the pole (4 times at
/// c = −R/2, linearly). As s → ∞ the map tends to the equidistant one (α ∝ ρ), which keeps
/// sizes closer but stretches the triangles radially near a low cut; the equal-area map
/// (1 − cos α ∝ ρ²) stretches them even more (by 4 at c = −R/2). The map stretches a triangle
/// at polar angle α radially relative to tangentially by
///
/// ```text
/// A(α) = s sin(α/s) / sin α     (1 at the pole, increasing with α and with s),
/// ```
///
/// so s = 2 is used — A ≤ 2 down to c = −R/2, where the cut triangles are about half the
/// size of the pole triangles and the smallest angle is about 20° — unless that gives
/// A(α_c) > 2 (c < −R/2); then s ∈ [1, 2) solves A(α_c) = 2. Triangles then keep their shape,
/// but for c → −R they shrink towards the cut (the cut circle still carries 8 d nodes): the
/// pattern suits caps down to about c = −0.9 R.
///
/// # Symmetry
///
/// The unperturbed pattern is mapped by a rotationally symmetric map, so the mesh has the
/// pattern's `C8v`, and no more (its ring next to the pole has 8 nodes 45° apart). For `C2v`,
/// `C1v` (and the other proper subgroups) the disc pattern's perturbation — radial `cos(Mθ)`
/// and, for the chiral groups, a twist, both vanishing at the pole and at the cut and at most
/// 15 % of a node spacing — is applied before the map, so the mesh has exactly the declared
/// group and no hidden symmetry, while being a smooth reparametrisation of the same cap
/// (discretisation-induced splitting shrinks under refinement).
///
/// # Errors
///
/// [`MeshError::Option`], naming the option and value: radius not finite and > 0, cut_height
/// not within (−R, R), an unknown pattern, divisions = 0, or divisions = 1 with a pattern
/// other than `C8v` (no interior node to break the symmetry with).
pub fn truncated_sphere(opts: &TruncatedSphereOptions) -> Result<SymmetricMesh, MeshError> {
    let r = opts.radius;
    check_radius(r)?;
    let c = opts.cut_height;
    if !(c.is_finite() && c > -r && c < r) {
        return Err(MeshError::Option {
            option: "cut_height".into(),
            message: format!(
                "must lie strictly between -radius and radius ({}, {r}), got {c}",
                -r
            ),
        });
    }
    let symmetry = AxialSymmetry::parse(&opts.pattern, SECTORS, "pattern")?;
    check_pattern(SECTORS, opts.divisions)?;
    let pattern = sector_domain(SECTORS, opts.divisions, symmetry)?;
    let cut_angle = (c / r).acos();
    let scale = map_scale(cut_angle);
    let t = (0.5 * cut_angle / scale).tan();
    let nodes = pattern
        .params
        .iter()
        .map(|&(rho, theta)| {
            // (distance from the axis, height); the cut ring exactly on z = c.
            let (radial, z) = if rho >= 1.0 {
                ((r * r - c * c).sqrt(), c)
            } else {
                let alpha = 2.0 * scale * (rho * t).atan();
                (r * alpha.sin(), r * alpha.cos())
            };
            Vec3::new(radial * theta.cos(), radial * theta.sin(), z)
        })
        .collect();
    let mut domain = Mesh::new(nodes, pattern.triangles)?;
    domain.set_boundary("cut", pattern.outer);
    SymmetricMesh::replicate(&domain, symmetry.group())
}

/// The scaling s of the polar-angle map for the cut at polar angle `cut_angle` ∈ (0, π):
/// [`MAP_SCALE`], or less if needed to keep the stretch ratio A(α_c) = s sin(α_c/s)/sin α_c at
/// most [`MAX_STRETCH`] (A increases with s and is 1 at s = 1; bisection).
fn map_scale(cut_angle: f64) -> f64 {
    let stretch = |s: f64| s * (cut_angle / s).sin() / cut_angle.sin();
    if stretch(MAP_SCALE) <= MAX_STRETCH {
        return MAP_SCALE;
    }
    let (mut lo, mut hi) = (1.0, MAP_SCALE);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if stretch(mid) > MAX_STRETCH {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}
