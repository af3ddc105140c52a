//! The icosphere ([`icosphere`], [`icosphere_oriented`]): a subdivided icosahedron projected
//! onto the sphere, with symmetry `Ih`; the construction is documented on [`icosphere`].

use super::disc::{check_radius, MAX_TRIANGLES};
use crate::{Mesh, MeshError, SymmetricMesh, Vec3};
use std::collections::HashMap;
use symmetry::{Group, Matrix3};

/// The golden ratio φ = (1 + √5)/2.
const PHI: f64 = 1.618_033_988_749_895;

/// Options of [`icosphere`].
#[derive(Debug, Clone, PartialEq)]
pub struct IcosphereOptions {
    /// Radius R of the sphere.
    pub radius: f64,
    /// Frequency f: each icosahedron edge is divided into f segments.
    pub frequency: usize,
}

impl Default for IcosphereOptions {
    /// R = 1, f = 4: 320 triangles, 162 nodes.
    fn default() -> Self {
        Self {
            radius: 1.0,
            frequency: 4,
        }
    }
}

/// What points straight down (along −z) in [`icosphere_oriented`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Down {
    /// A vertex of the icosahedron (5-fold axis): a scene keeping −z keeps `C5v`.
    Vertex,
    /// The centre of a face (3-fold axis): `C3v`.
    Face,
    /// The midpoint of an edge (2-fold axis): `C2v`.
    Edge,
}

/// A closed sphere of radius R triangulated as a frequency-f icosphere, outward oriented,
/// with the full icosahedral group `Ih` (order 120) in the orientation of
/// [`Group::icosahedral_full`].
///
/// 20 f² triangles and 10 f² + 2 nodes (12 of them the icosahedron's vertices, with five
/// neighbours; all others have six); no named node sets. f = 16 gives 5120 triangles and 2562
/// nodes; the default f = 4 gives 320 and 162. The radial projection makes sizes vary: for
/// large f the longest edge is about 1.45 times the shortest and the largest triangle about
/// 1.9 times the smallest in area (1.28 and 1.5 at f = 4); all angles exceed 50°.
///
/// # Construction
///
/// Icosahedron in the orientation of [`Group::icosahedral_full`]: vertices at the cyclic
/// permutations of (0, ±1, ±φ), φ = (1 + √5)/2, so the coordinate axes are 2-fold axes and the
/// coordinate planes are mirrors. A face (V0, V1, V2) at frequency f carries the nodes
///
/// ```text
/// X(j, l) = R (i V0 + j V1 + l V2) / |i V0 + j V1 + l V2|,   i = f − j − l,   j + l ≤ f,
/// ```
///
/// joined by the up triangles (j, l)(j+1, l)(j, l+1) and the down triangles
/// (j+1, l)(j+1, l+1)(j, l+1), oriented like the face. The face is cut by its three
/// mirrors into six copies of the fundamental domain of `Ih`; the generator keeps the
/// triangles whose barycentre (in the face's barycentric coordinates) satisfies
/// i ≥ j ≥ l — the region between V0, the midpoint of V0V1 and the face centre — and
/// replicates them by the 120 elements of `Ih`. Triangles cut by a mirror are symmetric
/// under it and are kept whole; replication drops their duplicate images.
///
/// # Symmetry
///
/// Exactly `Ih`: the mesh is the union of the `Ih`-images of one domain, so `Ih` acts on it;
/// the symmetry group of a finite point set that is not collinear is finite, and `Ih` is a
/// maximal finite subgroup of O(3), so there is no further symmetry.
///
/// # Errors
///
/// [`MeshError::Option`], naming the option and value: radius not finite and > 0,
/// frequency = 0, or more than 5·10⁷ triangles.
pub fn icosphere(opts: &IcosphereOptions) -> Result<SymmetricMesh, MeshError> {
    check_radius(opts.radius)?;
    let f = opts.frequency;
    if f == 0 {
        return Err(MeshError::Option {
            option: "frequency".into(),
            message: format!("must be >= 1, got {f}"),
        });
    }
    if f.checked_mul(f)
        .and_then(|f2| f2.checked_mul(20))
        .is_none_or(|t| t > MAX_TRIANGLES)
    {
        return Err(MeshError::Option {
            option: "frequency".into(),
            message: format!("= {f} gives more than {MAX_TRIANGLES} triangles"),
        });
    }
    // Three mutually adjacent vertices (edge length 2), counter-clockwise seen from outside.
    let face = [
        Vec3::new(0.0, 1.0, PHI),
        Vec3::new(0.0, -1.0, PHI),
        Vec3::new(PHI, 0.0, 1.0),
    ];
    debug_assert!(
        (face[1] - face[0])
            .cross(&(face[2] - face[0]))
            .dot(&face[0])
            > 0.0
    );
    let mut index: HashMap<(usize, usize), usize> = HashMap::new();
    let mut nodes = Vec::new();
    // Node (j, l) has barycentric weights (i, j, l) = (f − j − l, j, l) on (V0, V1, V2).
    let mut node = |j: usize, l: usize| -> usize {
        *index.entry((j, l)).or_insert_with(|| {
            let i = f - j - l;
            let p = face[0] * i as f64 + face[1] * j as f64 + face[2] * l as f64;
            nodes.push(p * (opts.radius / p.norm()));
            nodes.len() - 1
        })
    };
    // Keep a triangle iff the sums (c0, c1, c2) of its nodes' weights satisfy c0 >= c1 >= c2.
    let inside = |tri: &[(usize, usize); 3]| {
        let c1: usize = tri.iter().map(|&(j, _)| j).sum();
        let c2: usize = tri.iter().map(|&(_, l)| l).sum();
        let c0 = 3 * f - c1 - c2;
        c0 >= c1 && c1 >= c2
    };
    let mut triangles = Vec::new();
    for j in 0..f {
        for l in 0..f - j {
            let mut candidates = vec![[(j, l), (j + 1, l), (j, l + 1)]];
            if j + l + 2 <= f {
                candidates.push([(j + 1, l), (j + 1, l + 1), (j, l + 1)]);
            }
            for tri in candidates.iter().filter(|t| inside(t)) {
                triangles.push(tri.map(|(j, l)| node(j, l)));
            }
        }
    }
    let domain = Mesh::new(nodes, triangles)?;
    SymmetricMesh::replicate(&domain, Group::icosahedral_full())
}

/// The icosphere of [`icosphere`] rotated so that a vertex, a face centre or an edge midpoint
/// points along −z, carrying `Ih` conjugated by the same rotation (still named `Ih`).
///
/// The rotation Q maps the chosen direction u onto −z and the normal n of a mirror of `Ih`
/// that contains u onto +y, so that mirror becomes the plane y = 0 — the first mirror of
/// the axial groups — and `action.restrict(&[Invariant::Direction(−z)])` gives `C5v`, `C3v`
/// or `C2v` with that mirror among its elements:
///
/// | `down`   | u                            | n  |
/// |----------|------------------------------|----|
/// | `Vertex` | (0, 1, φ)                    | x̂  |
/// | `Face`   | (φ, 0, 2φ + 1) (face centre) | ŷ  |
/// | `Edge`   | (0, 0, 1) (edge midpoint)    | x̂  |
///
/// `Q = [−ẑ ŷ x̂] [û n̂ (û × n̂)]ᵀ` (columns), a proper rotation. Counts and errors as for
/// [`icosphere`].
pub fn icosphere_oriented(opts: &IcosphereOptions, down: Down) -> Result<SymmetricMesh, MeshError> {
    let sphere = icosphere(opts)?;
    let (u, n) = match down {
        Down::Vertex => (Vec3::new(0.0, 1.0, PHI), Vec3::x()),
        Down::Face => (Vec3::new(PHI, 0.0, 2.0 * PHI + 1.0), Vec3::y()),
        Down::Edge => (Vec3::z(), Vec3::x()),
    };
    let u = u.normalize();
    let from = Matrix3::from_columns(&[u, n, u.cross(&n)]);
    let to = Matrix3::from_columns(&[-Vec3::z(), Vec3::y(), Vec3::x()]);
    let q = to * from.transpose();
    let group = sphere.group().conjugated(&q, sphere.group().name());
    let mut mesh = sphere.mesh;
    for x in &mut mesh.nodes {
        *x = q * *x;
    }
    SymmetricMesh::new(mesh, group)
}
