//! The flat disc ([`disc`]), and the structured sector pattern it shares with the truncated
//! sphere (`sector_domain`); both the pattern and its symmetry-breaking perturbation are
//! documented on [`disc`].

use crate::{Mesh, MeshError, SymmetricMesh, Vec3};
use std::collections::HashMap;
use std::f64::consts::PI;
use symmetry::Group;

/// Largest number of triangles a generator builds (a guard against absurd input).
pub(crate) const MAX_TRIANGLES: usize = 50_000_000;

/// Options of [`disc`].
#[derive(Debug, Clone, PartialEq)]
pub struct DiscOptions {
    /// Radius R of the disc.
    pub radius: f64,
    /// Number N of sectors (N ≥ 3).
    pub sectors: usize,
    /// Number d of rings (divisions of a sector edge).
    pub divisions: usize,
    /// Declared symmetry: `C{M}v` or `C{M}` about z with M dividing N; `None` means `C{N}v`.
    pub group: Option<String>,
}

impl Default for DiscOptions {
    /// R = 1, N = 7, d = 16, group `C7v`: 1792 triangles, 953 nodes.
    fn default() -> Self {
        Self {
            radius: 1.0,
            sectors: 7,
            divisions: 16,
            group: None,
        }
    }
}

/// A flat disc of radius R in the plane z = 0, normal +z, with exactly the declared symmetry.
///
/// The mesh is the sector pattern below, scaled by R: N·d² triangles, N·d(d+1)/2 + 1 nodes,
/// counter-clockwise seen from +z. The node set `rim` holds the N·d nodes on the circle
/// r = R. The default (N = 7, d = 16) has 1792 triangles and 953 nodes.
///
/// The declared group (`C{N}v` by default) must be a subgroup of `C_Nv`: `C{M}v` or `C{M}`
/// with M | N. For a proper subgroup the interior nodes are moved by the smooth perturbation
/// described below (the centre and the rim stay put), so the mesh has *exactly* the declared
/// symmetry and no more; without it, the pattern would carry the hidden symmetry `C_Nv`. A
/// perturbed mesh is a smooth reparametrisation of the same disc (the displacement is 15 % of
/// a node spacing and shrinks with it), so splittings of degenerate eigenvalues that it
/// induces are discretisation effects and shrink under refinement.
///
/// # Pattern
///
/// In polar parameters (ρ, θ) with ρ ∈ [0, 1]: `N` sectors, each the isosceles triangle
/// from the centre between θ = 2πj/N and 2π(j+1)/N, subdivided into d² triangles. Ring
/// k = 0 … d sits at ρ = k/d and holds N·k nodes evenly spaced in angle,
///
/// ```text
/// node (k, m):   ρ = k/d,   θ = 2π m / (N k),   m = 0 … N k − 1      (k = 0: the centre)
/// ```
///
/// Between rings k and k+1, sector j has the k+1 nodes a_i = (k, jk + i) and the k+2 nodes
/// b_i = (k+1, j(k+1) + i), joined by the 2k+1 triangles (a_i, b_i, b_{i+1}), i = 0 … k, and
/// (a_i, b_{i+1}, a_{i+1}), i = 0 … k−1, counter-clockwise in the (x, y) = ρ(cos θ, sin θ)
/// plane. In total N d² triangles and N d(d+1)/2 + 1 nodes, N·d of them on the outer ring.
///
/// The pattern's symmetry is exactly `C_Nv` about the centre: ring 1 (N nodes 2π/N apart)
/// admits no other rotation or mirror, and each sector is mirror-symmetric about its
/// bisector (i ↦ k − i), so the mirrors through the sector edges and through the bisectors
/// — N in all — are all symmetries.
///
/// # Declared symmetry and its breaking
///
/// A subgroup `C_M` or `C_Mv` (M | N, first mirror θ = 0) of `C_Nv` is declared by building
/// the pattern on the group's fundamental wedge — 0 ≤ θ ≤ π/M for `C_Mv`, 0 ≤ θ ≤ 2π/M for
/// `C_M` — perturbing it smoothly and replicating it. A wedge that ends on a sector bisector
/// (N/M odd) cuts triangles in half; such a triangle is mirror-symmetric and is kept whole (its
/// mirror image is the same triangle, which replication drops as a duplicate). With the
/// amplitude `a = 0.15 · min(1, 2π/N) / d` (15 % of the smaller node spacing, in units of ρ)
/// and the envelope `g(ρ) = (27/4) ρ² (1 − ρ)` (maximum 1 at ρ = 2/3, zero at the centre and on
/// the outer ring):
///
/// ```text
/// ρ' = ρ + a g(ρ) cos(Mθ)                 if M < N     (breaks C_N down to C_M)
/// θ' = θ + a g(ρ) / ρ = θ + (27/4) a ρ(1 − ρ)   if chiral (a twist: breaks every mirror)
/// ```
///
/// `cos(Mθ)` is invariant under exactly the rotations by 2π/M and the mirrors θ ↦ 2πj/M − θ,
/// i.e. `C_Mv`; the twist commutes with all rotations and anti-commutes with every mirror.
/// Both are equivariant under the declared group, so nodes on its mirror lines stay on them,
/// and both are small (≤ 15 % of a spacing), so no symmetry outside `C_Nv` can appear.
///
/// # Errors
///
/// [`MeshError::Option`], naming the option and value: radius not finite and > 0,
/// sectors < 3, divisions = 0, a group that does not parse or is not a subgroup of `C_Nv`,
/// divisions = 1 with a proper subgroup (no interior node can be moved to break the
/// symmetry), or more than 5·10⁷ triangles.
pub fn disc(opts: &DiscOptions) -> Result<SymmetricMesh, MeshError> {
    check_radius(opts.radius)?;
    check_pattern(opts.sectors, opts.divisions)?;
    let symmetry = match &opts.group {
        Some(name) => AxialSymmetry::parse(name, opts.sectors, "group")?,
        None => AxialSymmetry {
            order: opts.sectors,
            mirrors: true,
        },
    };
    let pattern = sector_domain(opts.sectors, opts.divisions, symmetry)?;
    let nodes = pattern
        .params
        .iter()
        .map(|&(rho, theta)| {
            let r = opts.radius * rho;
            Vec3::new(r * theta.cos(), r * theta.sin(), 0.0)
        })
        .collect();
    let mut domain = Mesh::new(nodes, pattern.triangles)?;
    domain.set_boundary("rim", pattern.outer);
    SymmetricMesh::replicate(&domain, symmetry.group())
}

/// Fails unless `radius` is finite and positive.
pub(crate) fn check_radius(radius: f64) -> Result<(), MeshError> {
    if radius.is_finite() && radius > 0.0 {
        Ok(())
    } else {
        Err(MeshError::Option {
            option: "radius".into(),
            message: format!("must be finite and > 0, got {radius}"),
        })
    }
}

/// Fails unless the sector pattern with these parameters is well defined and not absurdly
/// large.
pub(crate) fn check_pattern(sectors: usize, divisions: usize) -> Result<(), MeshError> {
    if sectors < 3 {
        return Err(MeshError::Option {
            option: "sectors".into(),
            message: format!(
                "must be >= 3 (a sector must be narrower than a half-plane), got {sectors}"
            ),
        });
    }
    if divisions == 0 {
        return Err(MeshError::Option {
            option: "divisions".into(),
            message: format!("must be >= 1, got {divisions}"),
        });
    }
    match divisions
        .checked_mul(divisions)
        .and_then(|d2| d2.checked_mul(sectors))
    {
        Some(n) if n <= MAX_TRIANGLES => Ok(()),
        _ => Err(MeshError::Option {
            option: "sectors".into(),
            message: format!(
                "= {sectors}, divisions = {divisions}: more than {MAX_TRIANGLES} triangles"
            ),
        }),
    }
}

/// A declared axial symmetry of a sector pattern: `C_M` (rotations only) or `C_Mv` about z.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct AxialSymmetry {
    /// M, the number of rotations.
    pub order: usize,
    /// True for `C_Mv` (M vertical mirrors, the first the plane y = 0).
    pub mirrors: bool,
}

impl AxialSymmetry {
    /// Parses `C{M}v` or `C{M}` and checks that it is a subgroup of `C_Nv` (M divides N =
    /// `sectors`); errors name `option`.
    pub(crate) fn parse(name: &str, sectors: usize, option: &str) -> Result<Self, MeshError> {
        let bad = |why: String| MeshError::Option {
            option: option.to_string(),
            message: format!("'{name}' {why}"),
        };
        let rest = name
            .strip_prefix('C')
            .ok_or_else(|| bad("is not of the form C<M> or C<M>v".into()))?;
        let (digits, mirrors) = match rest.strip_suffix('v') {
            Some(d) => (d, true),
            None => (rest, false),
        };
        let order: usize = match digits.parse() {
            Ok(m) if digits.bytes().all(|b| b.is_ascii_digit()) && m >= 1 => m,
            _ => return Err(bad("is not of the form C<M> or C<M>v with M >= 1".into())),
        };
        if !sectors.is_multiple_of(order) {
            return Err(bad(format!(
                "is not a subgroup of C{sectors}v: {order} does not divide {sectors}"
            )));
        }
        Ok(Self { order, mirrors })
    }

    /// The group about z.
    pub(crate) fn group(&self) -> Group {
        if self.mirrors {
            Group::cyclic_v(self.order)
        } else {
            Group::cyclic(self.order)
        }
    }
}

/// The sector pattern on the fundamental wedge of a declared symmetry, in polar parameters.
pub(crate) struct SectorDomain {
    /// Perturbed node parameters (ρ', θ'); ρ' = 0 only at the centre, ρ' = 1 exactly on the
    /// outer ring.
    pub params: Vec<(f64, f64)>,
    /// Triangles, counter-clockwise in the (ρ cos θ, ρ sin θ) plane.
    pub triangles: Vec<[usize; 3]>,
    /// The nodes on the outer ring (ρ = 1).
    pub outer: Vec<usize>,
}

/// The part of the N-sector, d-ring pattern that covers the fundamental wedge of `symmetry`
/// (see [`disc`]), with the symmetry-breaking perturbation applied. The caller has checked
/// the input ([`check_pattern`], [`AxialSymmetry::parse`]); this fails if the pattern has no
/// interior nodes (d = 1) to break its `C_Nv` down to `symmetry`.
pub(crate) fn sector_domain(
    sectors: usize,
    divisions: usize,
    symmetry: AxialSymmetry,
) -> Result<SectorDomain, MeshError> {
    let (n, d) = (sectors, divisions);
    if d < 2 && (symmetry.order < n || !symmetry.mirrors) {
        return Err(MeshError::Option {
            option: "divisions".into(),
            message: format!(
                "= {d} leaves no interior node to break C{n}v down to {}; use divisions >= 2",
                symmetry.group().name()
            ),
        });
    }
    // The wedge in half-sectors: π/M = N/M half-sectors, 2π/M = 2N/M.
    let half_sectors = if symmetry.mirrors {
        n / symmetry.order
    } else {
        2 * n / symmetry.order
    };
    let mut index: HashMap<(usize, usize), usize> = HashMap::new();
    let mut params = Vec::new();
    let mut outer = Vec::new();
    let mut node = |(k, m): (usize, usize)| -> usize {
        let m = if k == 0 { 0 } else { m % (n * k) };
        *index.entry((k, m)).or_insert_with(|| {
            let (rho, theta) = if k == 0 {
                (0.0, 0.0)
            } else {
                (k as f64 / d as f64, 2.0 * PI * m as f64 / (n * k) as f64)
            };
            params.push(perturb(rho, theta, n, d, symmetry));
            if k == d {
                outer.push(params.len() - 1);
            }
            params.len() - 1
        })
    };
    let mut triangles = Vec::new();
    for j in 0..half_sectors.div_ceil(2) {
        for k in 0..d {
            // Up triangle i is centred at the fraction (2i + 1)/den of sector j, down triangle
            // i at 2(i + 1)/den (den = 2(k + 1); the bisector mirror maps p to 1 − p). It lies
            // in the wedge iff j + num/den <= half_sectors/2, in exact integers:
            let den = 2 * (k + 1);
            let inside = |num: usize| 2 * (j * den + num) <= half_sectors * den;
            let a = |i: usize| (k, j * k + i);
            let b = |i: usize| (k + 1, j * (k + 1) + i);
            for i in 0..=k {
                if inside(2 * i + 1) {
                    triangles.push([a(i), b(i), b(i + 1)].map(&mut node));
                }
                if i < k && inside(2 * (i + 1)) {
                    triangles.push([a(i), b(i + 1), a(i + 1)].map(&mut node));
                }
            }
        }
    }
    Ok(SectorDomain {
        params,
        triangles,
        outer,
    })
}

/// The symmetry-breaking perturbation (see [`disc`]) applied to (ρ, θ).
fn perturb(rho: f64, theta: f64, n: usize, d: usize, symmetry: AxialSymmetry) -> (f64, f64) {
    let amplitude = 0.15 * (2.0 * PI / n as f64).min(1.0) / d as f64;
    let envelope = 6.75 * rho * rho * (1.0 - rho);
    let mut rho_p = rho;
    let mut theta_p = theta;
    if symmetry.order < n {
        rho_p += amplitude * envelope * (symmetry.order as f64 * theta).cos();
    }
    if !symmetry.mirrors {
        theta_p += 6.75 * amplitude * rho * (1.0 - rho);
    }
    (rho_p, theta_p)
}
