//! Group actions on meshes: for every group element `g`, the orthogonal matrix `R_g` and the
//! node permutation `π_g` with `R_g X_i = X_{π_g(i)}`, and the induced triangle permutation.

use crate::mesh::{Mesh, Vec3};
use crate::MeshError;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;
use symmetry::{Group, Invariant, Matrix3, Subgroup};

/// A hash map with a fast, fixed hasher (foldhash): the keys are grid cells and node
/// triples of our own meshes, not untrusted input, and SipHash made the lookups the cost
/// of computing an action (≈ 20 s for Ih on an f = 128 icosphere).
type FastMap<K, V> = HashMap<K, V, foldhash::fast::FixedState>;

/// Relative tolerance (to the mesh size) for `R_g X_i = X_{π_g(i)}`.
pub const ACTION_TOL: f64 = 1e-10;

/// One permutation per group element, shared.
type Perms = Vec<Arc<[usize]>>;

/// Elements reached level by level from the identity, each as (h, p, s) with h = p·s.
type Levels = Vec<Vec<(usize, usize, usize)>>;

/// A group acting on a mesh by permuting its nodes and triangles.
///
/// Every element's permutations are shared (`Arc`): the action of a subgroup
/// ([`GroupAction::restrict`]) and a clone hold the same arrays, not copies (at f = 128 an
/// icosphere's 120 node and triangle permutations take 470 MB).
#[derive(Debug, Clone)]
pub struct GroupAction {
    group: Group,
    node_perm: Vec<Arc<[usize]>>,
    triangle_perm: Vec<Arc<[usize]>>,
}

/// A mesh together with the group that maps it onto itself.
#[derive(Debug, Clone)]
pub struct SymmetricMesh {
    /// The mesh.
    pub mesh: Mesh,
    /// Its symmetry group acting on nodes and triangles.
    pub action: GroupAction,
}

/// What [`SymmetricMesh::verify`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Verification {
    /// Largest `|R_g X_i − X_{π_g(i)}|` over all g and i, relative to the mesh size.
    pub max_position_error: f64,
    /// True if the mesh is closed.
    pub closed: bool,
    /// Number of boundary loops.
    pub boundary_loops: usize,
}

/// Finds nodes near a point with a uniform hash grid.
pub(crate) struct NodeLocator {
    cell: f64,
    grid: FastMap<[i64; 3], Vec<usize>>,
}

impl NodeLocator {
    pub(crate) fn new(nodes: &[Vec3], cell: f64) -> Self {
        let mut loc = Self {
            cell,
            grid: FastMap::default(),
        };
        for (i, x) in nodes.iter().enumerate() {
            loc.insert(i, x);
        }
        loc
    }

    fn key(&self, x: &Vec3) -> [i64; 3] {
        [0, 1, 2].map(|k| (x[k] / self.cell).floor() as i64)
    }

    pub(crate) fn insert(&mut self, i: usize, x: &Vec3) {
        let key = self.key(x);
        self.grid.entry(key).or_default().push(i);
    }

    /// A node within `tol` of `x` (`tol` must be below the cell size). Nodes of a mesh are
    /// far apart compared with `tol`, so such a node is unique; the point's own cell is probed
    /// first and the 26 around it only when that finds nothing.
    pub(crate) fn find_within(&self, nodes: &[Vec3], x: &Vec3, tol: f64) -> Option<usize> {
        let k = self.key(x);
        let hit = |key: &[i64; 3]| {
            self.grid
                .get(key)
                .and_then(|list| list.iter().copied().find(|&i| (nodes[i] - x).norm() <= tol))
        };
        hit(&k).or_else(|| {
            (-1..=1)
                .flat_map(|dx| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| [dx, dy, dz])))
                .filter(|d| *d != [0, 0, 0])
                .find_map(|[dx, dy, dz]| hit(&[k[0] + dx, k[1] + dy, k[2] + dz]))
        })
    }
}

/// The permutation a matrix induces on the nodes, if it maps every node onto a node within
/// `tol`; `None` otherwise.
fn node_permutation(mesh: &Mesh, loc: &NodeLocator, r: &Matrix3, tol: f64) -> Option<Vec<usize>> {
    let perm: Vec<usize> = mesh
        .nodes
        .iter()
        .map(|x| loc.find_within(&mesh.nodes, &(r * x), tol))
        .collect::<Option<_>>()?;
    let mut hit = vec![false; perm.len()];
    for &j in &perm {
        if std::mem::replace(&mut hit[j], true) {
            return None;
        }
    }
    Some(perm)
}

fn triangle_key(t: &[usize; 3]) -> [usize; 3] {
    let mut k = *t;
    k.sort_unstable();
    k
}

/// Triangles by their sorted node triple.
fn triangle_index(mesh: &Mesh) -> FastMap<[usize; 3], usize> {
    mesh.triangles
        .iter()
        .enumerate()
        .map(|(t, tri)| (triangle_key(tri), t))
        .collect()
}

/// The permutation of triangles induced by a node permutation, if every image is a triangle
/// of the mesh with the orientation a symmetry gives it: the same cyclic order for a proper
/// rotation (det R = 1), the reverse for an improper element (det R = −1), because the
/// element maps the surface's normal field onto itself.
fn triangle_permutation(
    mesh: &Mesh,
    index: &FastMap<[usize; 3], usize>,
    perm: &[usize],
    proper: bool,
) -> Result<Vec<usize>, String> {
    mesh.triangles
        .iter()
        .enumerate()
        .map(|(t, tri)| {
            let image = tri.map(|i| perm[i]);
            let &u = index
                .get(&triangle_key(&image))
                .ok_or_else(|| format!("the image of triangle {t} is not a triangle"))?;
            let target = mesh.triangles[u];
            let shift = (0..3).find(|&s| target[s] == image[0]).unwrap_or(0);
            let same_order = target[(shift + 1) % 3] == image[1];
            if same_order != proper {
                return Err(format!(
                    "triangle {t} maps onto triangle {u} with the wrong orientation"
                ));
            }
            Ok(u)
        })
        .collect()
}

/// Whether `stored` is the triangle permutation the node permutation `perm` induces: it is
/// a permutation, and triangle t goes to a triangle with the nodes π(t) in the cyclic order
/// of t for a proper element (`proper`), in the reverse order for an improper one. O(1) per
/// triangle; [`triangle_permutation`] finds the images by search when this fails.
fn maps_triangles(mesh: &Mesh, perm: &[usize], stored: &[usize], proper: bool) -> bool {
    let m = mesh.triangles.len();
    if stored.len() != m {
        return false;
    }
    let mut hit = vec![false; m];
    mesh.triangles.iter().zip(stored).all(|(tri, &u)| {
        if u >= m || std::mem::replace(&mut hit[u], true) {
            return false;
        }
        let image = tri.map(|i| perm[i]);
        let target = mesh.triangles[u];
        let Some(shift) = (0..3).find(|&s| target[s] == image[0]) else {
            return false;
        };
        let (next, last) = (target[(shift + 1) % 3], target[(shift + 2) % 3]);
        if proper {
            next == image[1] && last == image[2]
        } else {
            next == image[2] && last == image[1]
        }
    })
}

/// Orbits of the points permuted by `perms` (one permutation per group element).
fn orbits(perms: &[Arc<[usize]>]) -> Vec<Vec<usize>> {
    let n = perms.first().map_or(0, |p| p.len());
    let mut seen = vec![false; n];
    let mut orbits = Vec::new();
    for i in 0..n {
        if seen[i] {
            continue;
        }
        let mut orbit: Vec<usize> = perms.iter().map(|p| p[i]).collect();
        orbit.sort_unstable();
        orbit.dedup();
        for &j in &orbit {
            seen[j] = true;
        }
        orbits.push(orbit);
    }
    orbits
}

fn tolerance(mesh: &Mesh) -> f64 {
    ACTION_TOL * mesh.size().max(f64::MIN_POSITIVE)
}

/// Two nodes of `mesh` at the same point (within the tolerance group actions are verified
/// to, relative to the mesh size), if there are any: a mesh file that repeats a node.
pub fn coincident_nodes(mesh: &Mesh) -> Option<(usize, usize)> {
    let tol = tolerance(mesh);
    let mut loc = NodeLocator::new(&[], tol * 4.0);
    for (i, x) in mesh.nodes.iter().enumerate() {
        if let Some(j) = loc.find_within(&mesh.nodes, x, tol) {
            return Some((j, i));
        }
        loc.insert(i, x);
    }
    None
}

fn locator(mesh: &Mesh) -> NodeLocator {
    let cell = (mesh.min_edge() * 0.25).max(tolerance(mesh) * 4.0);
    NodeLocator::new(&mesh.nodes, cell)
}

/// A generating set of `group` and every other element as a product: the generators are
/// taken greedily in element order (each one not yet generated by those before it), and
/// the elements are reached breadth first from the identity, level by level, as (h, p, s)
/// with h = p·s, s a generator and p on an earlier level.
fn words(group: &Group) -> (Vec<usize>, Levels) {
    let n = group.order();
    let mut generators = Vec::new();
    loop {
        let mut reached = vec![false; n];
        reached[0] = true;
        let mut levels: Levels = Vec::new();
        let mut frontier = vec![0];
        while !frontier.is_empty() {
            let mut level = Vec::new();
            for &p in &frontier {
                for &s in &generators {
                    let h = group.mul(p, s);
                    if !std::mem::replace(&mut reached[h], true) {
                        level.push((h, p, s));
                    }
                }
            }
            frontier = level.iter().map(|&(h, _, _)| h).collect();
            if !level.is_empty() {
                levels.push(level);
            }
        }
        match reached.iter().position(|&r| !r) {
            Some(g) => generators.push(g),
            None => return (generators, levels),
        }
    }
}

/// Every element's node and triangle permutations from the generators' ([`GroupAction::compute`]);
/// `None` when a generator does not map the mesh onto itself or a product's nodes are not
/// where its matrix puts them.
fn by_generators(
    mesh: &Mesh,
    group: &Group,
    loc: &NodeLocator,
    index: &FastMap<[usize; 3], usize>,
    tol: f64,
) -> Option<(Perms, Perms)> {
    let (generators, levels) = words(group);
    let n = group.order();
    let mut nodes: Vec<Option<Arc<[usize]>>> = vec![None; n];
    let mut triangles: Vec<Option<Arc<[usize]>>> = vec![None; n];
    nodes[0] = Some((0..mesh.nodes.len()).collect());
    triangles[0] = Some((0..mesh.triangles.len()).collect());
    let found: Vec<_> = generators
        .par_iter()
        .map(|&s| {
            let r = group.element(s);
            let perm = node_permutation(mesh, loc, r, tol)?;
            let tri = triangle_permutation(mesh, index, &perm, r.determinant() > 0.0).ok()?;
            Some((perm, tri))
        })
        .collect();
    for (&s, f) in generators.iter().zip(found) {
        let (perm, tri) = f?;
        nodes[s] = Some(perm.into());
        triangles[s] = Some(tri.into());
    }
    for level in &levels {
        let products: Vec<_> = level
            .par_iter()
            .filter(|&&(h, _, _)| nodes[h].is_none())
            .map(|&(h, p, s)| {
                let get = |v: &[Option<Arc<[usize]>>], g: usize| -> Arc<[usize]> {
                    v[g].clone().expect("an earlier level")
                };
                (
                    h,
                    compose(&get(&nodes, p), &get(&nodes, s)),
                    compose(&get(&triangles, p), &get(&triangles, s)),
                )
            })
            .collect();
        for (h, perm, tri) in products {
            nodes[h] = Some(perm);
            triangles[h] = Some(tri);
        }
    }
    let nodes: Vec<Arc<[usize]>> = nodes.into_iter().collect::<Option<_>>()?;
    let triangles: Vec<Arc<[usize]>> = triangles.into_iter().collect::<Option<_>>()?;
    let placed = (0..n).into_par_iter().all(|g| {
        let r = group.element(g);
        mesh.nodes
            .iter()
            .zip(nodes[g].iter())
            .all(|(x, &j)| (r * x - mesh.nodes[j]).norm() <= tol)
    });
    placed.then_some((nodes, triangles))
}

/// Every element's node and triangle permutations by search, each element on its own (one
/// rayon task each); the error names the first element in order that fails.
fn by_search(
    mesh: &Mesh,
    group: &Group,
    loc: &NodeLocator,
    index: &FastMap<[usize; 3], usize>,
    tol: f64,
) -> Result<(Perms, Perms), MeshError> {
    Ok(group
        .elements()
        .par_iter()
        .enumerate()
        .map(|(g, r)| {
            let perm = node_permutation(mesh, loc, r, tol).ok_or_else(|| {
                MeshError::Symmetry(format!(
                    "element {g} of {} does not map the nodes onto nodes",
                    group.name()
                ))
            })?;
            let tri =
                triangle_permutation(mesh, index, &perm, r.determinant() > 0.0).map_err(|m| {
                    MeshError::Symmetry(format!("element {g} of {}: {m}", group.name()))
                })?;
            Ok((Arc::from(perm), Arc::from(tri)))
        })
        .collect::<Vec<Result<_, MeshError>>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()? // the first failing element, in order
        .into_iter()
        .unzip())
}

/// The composition `p ∘ q` of two permutations: i ↦ p[q[i]].
fn compose(p: &[usize], q: &[usize]) -> Arc<[usize]> {
    q.iter().map(|&i| p[i]).collect()
}

/// (g, s) with π_{gs} ≠ π_g ∘ π_s for a generator s, if any. Over the generators only this
/// is the whole homomorphism check: if π_{gs} = π_g ∘ π_s for every g and every generator s,
/// then for h = s₁⋯s_k, by induction on k, π_{gh} = π_{g s₁⋯s_{k−1}} ∘ π_{s_k} =
/// π_g ∘ π_{s₁⋯s_{k−1}} ∘ π_{s_k} = π_g ∘ π_h (a finite group needs no inverses in its words).
fn homomorphism_defect(
    group: &Group,
    generators: &[usize],
    perm: impl Fn(usize) -> Arc<[usize]> + Sync,
) -> Option<(usize, usize)> {
    (0..group.order()).into_par_iter().find_map_first(|g| {
        let pg = perm(g);
        generators.iter().find_map(|&s| {
            let (ps, pgs) = (perm(s), perm(group.mul(g, s)));
            (0..pg.len()).any(|i| pgs[i] != pg[ps[i]]).then_some((g, s))
        })
    })
}

impl GroupAction {
    /// Finds, for every element of `group`, the node and triangle permutations it induces on
    /// `mesh`; fails (naming the element) if some element does not map the mesh onto itself.
    ///
    /// The generators' permutations are found geometrically (a node within the tolerance
    /// of R_s X_i, the image of a triangle among the triangles, with the orientation the
    /// element gives it); every other element's are products, π_{ps} = π_p ∘ π_s (and so for
    /// triangles), checked against its matrix node by node (|R_g X_i − X_{π_g(i)}| within the
    /// tolerance, O(1) per node, no search). When a generator does not act or a product
    /// fails its check, every element is searched on its own, as the error names the first
    /// failing element in order.
    pub fn compute(mesh: &Mesh, group: Group) -> Result<Self, MeshError> {
        let tol = tolerance(mesh);
        let loc = locator(mesh);
        let index = triangle_index(mesh);
        if let Some((node_perm, triangle_perm)) = by_generators(mesh, &group, &loc, &index, tol) {
            return Ok(Self {
                group,
                node_perm,
                triangle_perm,
            });
        }
        let (node_perm, triangle_perm) = by_search(mesh, &group, &loc, &index, tol)?;
        Ok(Self {
            group,
            node_perm,
            triangle_perm,
        })
    }

    /// The acting group.
    pub fn group(&self) -> &Group {
        &self.group
    }

    /// `π_g`: node `i` is mapped to node `node_perm(g)[i]`.
    pub fn node_perm(&self, g: usize) -> &[usize] {
        &self.node_perm[g]
    }

    /// Triangle `t` is mapped to triangle `triangle_perm(g)[t]`.
    pub fn triangle_perm(&self, g: usize) -> &[usize] {
        &self.triangle_perm[g]
    }

    /// Node orbits, each sorted, in order of their smallest node.
    pub fn node_orbits(&self) -> Vec<Vec<usize>> {
        orbits(&self.node_perm)
    }

    /// Triangle orbits, each sorted, in order of their smallest triangle.
    pub fn triangle_orbits(&self) -> Vec<Vec<usize>> {
        orbits(&self.triangle_perm)
    }

    /// The same action restricted to the subgroup that keeps `keep` (a scene's loads and
    /// boundary conditions); the subgroup carries its own irreps and name.
    pub fn restrict(&self, keep: &[Invariant]) -> Result<Self, MeshError> {
        let sub = self
            .group
            .stabilizer(keep)
            .map_err(|e| MeshError::Symmetry(e.to_string()))?;
        self.restrict_to(&sub)
    }

    /// The action of a subgroup of the acting group, e.g. an isotropy subgroup `Σ` made a
    /// group of its own by [`Group::subgroup`]: its element `i` acts by the permutations of
    /// the parent's element `subgroup.parent_index[i]`, so symmetry-adapted bases of `Σ` (its
    /// own irreps) can be built on this mesh.
    ///
    /// Fails if `subgroup` does not belong to this action's group: an index out of range, or
    /// an element whose matrix is not the parent element's (to [`symmetry::MATRIX_TOL`]).
    pub fn restrict_to(&self, subgroup: &Subgroup) -> Result<Self, MeshError> {
        let sub = &subgroup.group;
        if subgroup.parent_index.len() != sub.order() {
            return Err(MeshError::Symmetry(format!(
                "subgroup {} has {} elements but {} parent indices",
                sub.name(),
                sub.order(),
                subgroup.parent_index.len()
            )));
        }
        for (i, &g) in subgroup.parent_index.iter().enumerate() {
            let same = g < self.group.order()
                && (sub.element(i) - self.group.element(g)).amax() <= symmetry::MATRIX_TOL;
            if !same {
                return Err(MeshError::Symmetry(format!(
                    "element {i} of {} is not element {g} of {}",
                    sub.name(),
                    self.group.name()
                )));
            }
        }
        let pick = |perms: &[Arc<[usize]>]| -> Vec<Arc<[usize]>> {
            subgroup
                .parent_index
                .iter()
                .map(|&g| perms[g].clone())
                .collect()
        };
        Ok(Self {
            node_perm: pick(&self.node_perm),
            triangle_perm: pick(&self.triangle_perm),
            group: sub.clone(),
        })
    }
}

impl SymmetricMesh {
    /// Pairs a mesh with a group, computing the action; fails if the group is not a symmetry.
    pub fn new(mesh: Mesh, group: Group) -> Result<Self, MeshError> {
        let action = GroupAction::compute(&mesh, group)?;
        Ok(Self { mesh, action })
    }

    /// The symmetry group.
    pub fn group(&self) -> &Group {
        self.action.group()
    }

    /// Verifies everything a symmetric mesh promises:
    /// - `R_g X_i = X_{π_g(i)}` to [`ACTION_TOL`] relative to the mesh size;
    /// - each `π_g` is a permutation and triangles map onto triangles, with the orientation
    ///   a symmetry of the normal field gives them;
    /// - `π_{gh} = π_g ∘ π_h` (the action is a homomorphism), and likewise for triangles,
    ///   checked for every g and every h of a generating set, which implies it for every h
    ///   (`homomorphism_defect`);
    /// - named node sets are mapped onto themselves;
    /// - the mesh is a connected, consistently oriented 2-manifold; a closed mesh encloses a
    ///   positive volume (outward orientation).
    pub fn verify(&self) -> Result<Verification, MeshError> {
        let mesh = &self.mesh;
        let group = self.group();
        let fail = |m: String| Err(MeshError::Symmetry(m));
        let topo = mesh.topology()?;
        if topo.closed && mesh.volume() <= 0.0 {
            return Err(MeshError::Topology(
                "the closed mesh is not outward oriented (its volume is not positive)".into(),
            ));
        }
        let size = mesh.size().max(f64::MIN_POSITIVE);
        let mut max_err: f64 = 0.0;
        let n = mesh.nodes.len();
        let index = std::sync::OnceLock::new();
        for g in 0..group.order() {
            let perm = self.action.node_perm(g);
            if perm.len() != n {
                return fail(format!("element {g}: the permutation has the wrong length"));
            }
            let mut hit = vec![false; n];
            for (i, &j) in perm.iter().enumerate() {
                if j >= n || std::mem::replace(&mut hit[j], true) {
                    return fail(format!("element {g} does not permute the nodes"));
                }
                let err = (group.element(g) * mesh.nodes[i] - mesh.nodes[j]).norm() / size;
                max_err = max_err.max(err);
            }
            let proper = group.element(g).determinant() > 0.0;
            let stored = self.action.triangle_perm(g);
            if !maps_triangles(mesh, perm, stored, proper) {
                // Say what is wrong as the search over the triangles finds it.
                let index = index.get_or_init(|| triangle_index(mesh));
                let tri = triangle_permutation(mesh, index, perm, proper)
                    .map_err(|m| MeshError::Symmetry(format!("element {g}: {m}")))?;
                if tri != stored {
                    return fail(format!("element {g}: stored triangle permutation is wrong"));
                }
            }
            for (name, set) in &mesh.boundaries {
                if set.iter().any(|&i| set.binary_search(&perm[i]).is_err()) {
                    return fail(format!(
                        "element {g} does not map node set '{name}' onto itself"
                    ));
                }
            }
        }
        if max_err > ACTION_TOL {
            return fail(format!(
                "R_g X_i differs from X_pi(i) by {max_err:.3e} of the mesh size (tolerance {ACTION_TOL:.0e})"
            ));
        }
        let (generators, _) = words(group);
        let nodes = |g: usize| self.action.node_perm[g].clone();
        if let Some((g, h)) = homomorphism_defect(group, &generators, nodes) {
            return fail(format!("pi_(gh) != pi_g o pi_h for g = {g}, h = {h}"));
        }
        let triangles = |g: usize| self.action.triangle_perm[g].clone();
        if let Some((g, h)) = homomorphism_defect(group, &generators, triangles) {
            return fail(format!(
                "the triangle permutations: tau_(gh) != tau_g o tau_h for g = {g}, h = {h}"
            ));
        }
        Ok(Verification {
            max_position_error: max_err,
            closed: topo.closed,
            boundary_loops: topo.boundary_loops.len(),
        })
    }

    /// Builds a symmetric mesh from a fundamental domain: every triangle of `domain` is copied
    /// by every element of `group` (orientation reversed for improper elements), nodes that
    /// land within the tolerance of an existing node are merged onto it, and named node sets
    /// are copied along. Images of the domain therefore coincide to rounding.
    pub fn replicate(domain: &Mesh, group: Group) -> Result<Self, MeshError> {
        let tol = 1e-8 * domain.min_edge();
        let mut nodes: Vec<Vec3> = Vec::new();
        let mut loc = NodeLocator::new(&[], (domain.min_edge() * 0.25).max(tol * 4.0));
        let mut triangles = Vec::new();
        let mut seen: FastMap<[usize; 3], usize> = FastMap::default();
        let mut sets: HashMap<String, Vec<usize>> = HashMap::new();
        for r in group.elements() {
            let map: Vec<usize> = domain
                .nodes
                .iter()
                .map(|x| {
                    let y = r * x;
                    match loc.find_within(&nodes, &y, tol) {
                        Some(j) => j,
                        None => {
                            nodes.push(y);
                            loc.insert(nodes.len() - 1, &y);
                            nodes.len() - 1
                        }
                    }
                })
                .collect();
            let proper = r.determinant() > 0.0;
            for tri in &domain.triangles {
                let mut t = tri.map(|i| map[i]);
                if !proper {
                    t.swap(1, 2);
                }
                if seen.insert(triangle_key(&t), triangles.len()).is_none() {
                    triangles.push(t);
                }
            }
            for (name, set) in &domain.boundaries {
                sets.entry(name.clone())
                    .or_default()
                    .extend(set.iter().map(|&i| map[i]));
            }
        }
        let mut mesh = Mesh::new(nodes, triangles)?;
        for (name, set) in sets {
            mesh.set_boundary(name, set);
        }
        Self::new(mesh, group)
    }

    /// Symmetries of the mesh that the declared group lacks (hidden symmetry), described in
    /// words; empty when the group is the mesh's full symmetry among the candidates.
    ///
    /// Candidates: for a polyhedral group (rotation axes in more than one direction, here `I`
    /// or `Ih` in any orientation) the elements ±R of the group: `I` can only grow into `Ih`,
    /// a maximal finite group. Otherwise every rotation about z and every vertical mirror that
    /// maps one reference node onto a node of its own ring, each also combined with the
    /// horizontal mirror z → −z. Any symmetry that keeps the z-axis is among them, so for
    /// discs and truncated spheres the search is exhaustive.
    pub fn hidden_symmetries(&self) -> Vec<String> {
        let candidates = if is_polyhedral(self.group()) {
            self.group()
                .elements()
                .iter()
                .enumerate()
                .flat_map(|(g, r)| {
                    [
                        (format!("element {g}"), *r),
                        (format!("minus element {g}"), -r),
                    ]
                })
                .collect()
        } else {
            candidates_about_z(&self.mesh)
        };
        let tol = tolerance(&self.mesh);
        let loc = locator(&self.mesh);
        let index = triangle_index(&self.mesh);
        let mut found: Vec<String> = candidates
            .iter()
            .filter(|(_, r)| self.group().find(r).is_none())
            .filter(|(_, r)| {
                node_permutation(&self.mesh, &loc, r, tol).is_some_and(|perm| {
                    triangle_permutation(&self.mesh, &index, &perm, r.determinant() > 0.0).is_ok()
                })
            })
            .map(|(name, _)| name.clone())
            .collect();
        found.dedup();
        found
    }
}

/// True if the group's rotations have axes in more than one direction.
fn is_polyhedral(group: &Group) -> bool {
    let axes: Vec<Vec3> = group
        .elements()
        .iter()
        .filter(|r| r.determinant() > 0.0 && (*r - Matrix3::identity()).amax() > 1e-9)
        .map(|r| {
            // The axis spans the kernel of R − I: the largest cross product of two rows.
            let m = r - Matrix3::identity();
            let (r0, r1, r2) = (
                m.row(0).transpose(),
                m.row(1).transpose(),
                m.row(2).transpose(),
            );
            [r0.cross(&r1), r1.cross(&r2), r2.cross(&r0)]
                .into_iter()
                .max_by(|a, b| a.norm().total_cmp(&b.norm()))
                .map(|v| v.normalize())
                .unwrap_or_else(Vec3::z)
        })
        .collect();
    axes.iter().any(|a| a.cross(&axes[0]).norm() > 1e-6)
}

/// Rotations about z and vertical mirrors (each alone and with z → −z) that map a reference
/// node (the off-axis node nearest the axis, then lowest index) onto a node of its ring.
fn candidates_about_z(mesh: &Mesh) -> Vec<(String, Matrix3)> {
    let tol = tolerance(mesh);
    let radius = |x: &Vec3| x.x.hypot(x.y);
    let Some(i0) = (0..mesh.nodes.len())
        .filter(|&i| radius(&mesh.nodes[i]) > 1e3 * tol)
        .min_by(|&a, &b| radius(&mesh.nodes[a]).total_cmp(&radius(&mesh.nodes[b])))
    else {
        return Vec::new();
    };
    let x0 = mesh.nodes[i0];
    let (r0, t0) = (radius(&x0), x0.y.atan2(x0.x));
    let flip = Matrix3::from_diagonal(&Vec3::new(1.0, 1.0, -1.0));
    let mut out = Vec::new();
    for x in &mesh.nodes {
        if (radius(x) - r0).abs() > 1e3 * tol {
            continue;
        }
        let t = x.y.atan2(x.x);
        let (rot_angle, mirror_angle) = (t - t0, 0.5 * (t + t0));
        let (c, s) = (rot_angle.cos(), rot_angle.sin());
        let rot = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let (c2, s2) = ((2.0 * mirror_angle).cos(), (2.0 * mirror_angle).sin());
        let mirror = Matrix3::new(c2, s2, 0.0, s2, -c2, 0.0, 0.0, 0.0, 1.0);
        let deg = |a: f64| a.to_degrees().rem_euclid(360.0);
        // A node at the same height is reached without z → −z, one at the mirrored height
        // with it; in the plane z = 0 both.
        for (flipped, height) in [(false, x0.z), (true, -x0.z)] {
            if (x.z - height).abs() > 1e3 * tol {
                continue;
            }
            let (tail, f) = if flipped {
                (" combined with z -> -z", flip)
            } else {
                ("", Matrix3::identity())
            };
            out.push((
                format!("rotation by {:.4} deg about z{tail}", deg(rot_angle)),
                f * rot,
            ));
            out.push((
                format!(
                    "mirror through z at {:.4} deg from x{tail}",
                    deg(mirror_angle).rem_euclid(180.0)
                ),
                f * mirror,
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::{disc, icosphere, DiscOptions, IcosphereOptions};

    fn meshes() -> Vec<SymmetricMesh> {
        let c7v = disc(&DiscOptions {
            radius: 1.0,
            sectors: 7,
            divisions: 3,
            group: None,
        })
        .unwrap();
        let ih = icosphere(&IcosphereOptions {
            radius: 1.0,
            frequency: 3,
        })
        .unwrap();
        vec![c7v, ih]
    }

    #[test]
    fn words_generate_every_element_once() {
        for m in meshes() {
            let group = m.group();
            let (generators, levels) = words(group);
            assert!(generators.len() < group.order());
            let mut seen = vec![false; group.order()];
            seen[0] = true;
            for level in &levels {
                for &(h, p, s) in level {
                    assert!(seen[p] && generators.contains(&s) && group.mul(p, s) == h);
                    assert!(!std::mem::replace(&mut seen[h], true), "{h} twice");
                }
            }
            assert!(seen.iter().all(|&x| x), "{}", group.name());
        }
    }

    #[test]
    fn the_action_by_generators_is_the_action_by_search() {
        for m in meshes() {
            let (mesh, group) = (&m.mesh, m.group());
            let (loc, index, tol) = (locator(mesh), triangle_index(mesh), tolerance(mesh));
            let (nodes, triangles) = by_generators(mesh, group, &loc, &index, tol).unwrap();
            let (n2, t2) = by_search(mesh, group, &loc, &index, tol).unwrap();
            assert_eq!(nodes, n2, "{}", group.name());
            assert_eq!(triangles, t2, "{}", group.name());
        }
    }

    #[test]
    fn a_group_that_does_not_act_is_refused_naming_the_first_element() {
        // C8v on a C7v disc: its generators fail, and the search names element 1.
        let m = &meshes()[0];
        let err = GroupAction::compute(&m.mesh, Group::cyclic_v(8)).unwrap_err();
        assert!(err.to_string().contains("element 1 of C8v"), "{err}");
    }

    #[test]
    fn verify_rejects_a_wrong_triangle_permutation() {
        let mut m = meshes().remove(1);
        m.verify().unwrap();
        // Two images of element 5 exchanged: still a permutation, no longer the induced one.
        let mut tri = m.action.triangle_perm[5].to_vec();
        tri.swap(0, 1);
        m.action.triangle_perm[5] = tri.into();
        let err = m.verify().unwrap_err();
        assert!(
            err.to_string()
                .contains("element 5: stored triangle permutation is wrong"),
            "{err}"
        );
    }

    #[test]
    fn the_homomorphism_check_on_generators_finds_what_the_full_check_finds() {
        let m = &meshes()[1];
        let group = m.group();
        let (generators, _) = words(group);
        let full = |perm: &dyn Fn(usize) -> Arc<[usize]>| {
            (0..group.order()).any(|g| {
                (0..group.order()).any(|h| {
                    let (pg, ph, pgh) = (perm(g), perm(h), perm(group.mul(g, h)));
                    (0..pg.len()).any(|i| pgh[i] != pg[ph[i]])
                })
            })
        };
        let good = |g: usize| m.action.node_perm[g].clone();
        assert!(homomorphism_defect(group, &generators, good).is_none());
        assert!(!full(&good));
        // Element g's permutation replaced by element k's (a valid permutation of the nodes,
        // the wrong one): both checks see it, for generators and for products alike.
        for (g, k) in [(generators[0], 7), (7, 11), (group.order() - 1, 0), (0, 3)] {
            let wrong = |h: usize| m.action.node_perm[if h == g { k } else { h }].clone();
            assert!(full(&wrong), "g = {g}");
            assert!(
                homomorphism_defect(group, &generators, wrong).is_some(),
                "g = {g}, k = {k}"
            );
        }
    }
}
