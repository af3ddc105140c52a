//! Triangle surface meshes with named boundary node sets, and their topology checks.

use crate::MeshError;
use nalgebra::Vector3;
use petgraph::graph::UnGraph;
use std::collections::{BTreeMap, HashMap};

/// A point or vector in 3-D.
pub type Vec3 = Vector3<f64>;

/// A triangulated surface: nodes, triangles (counter-clockwise seen from the side the normal
/// points to) and named node sets such as `rim`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Node coordinates.
    pub nodes: Vec<Vec3>,
    /// Triangles as node indices.
    pub triangles: Vec<[usize; 3]>,
    /// Named node sets (sorted, no duplicates), e.g. `rim`, `cut`.
    pub boundaries: BTreeMap<String, Vec<usize>>,
}

/// What [`Mesh::topology`] found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topology {
    /// True if every edge is shared by exactly two triangles.
    pub closed: bool,
    /// Boundary loops as node sequences (each edge used by one triangle, chained).
    pub boundary_loops: Vec<Vec<usize>>,
    /// Euler characteristic V − E + F.
    pub euler: i64,
}

impl Mesh {
    /// A mesh without named boundaries; fails on a node index out of range or a triangle that
    /// repeats a node.
    pub fn new(nodes: Vec<Vec3>, triangles: Vec<[usize; 3]>) -> Result<Self, MeshError> {
        for (t, tri) in triangles.iter().enumerate() {
            if tri.iter().any(|&i| i >= nodes.len()) {
                return Err(MeshError::Invalid(format!(
                    "triangle {t} refers to a node beyond {}",
                    nodes.len()
                )));
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(MeshError::Invalid(format!("triangle {t} repeats a node")));
            }
        }
        Ok(Self {
            nodes,
            triangles,
            boundaries: BTreeMap::new(),
        })
    }

    /// Adds (or replaces) a named node set.
    pub fn set_boundary(&mut self, name: impl Into<String>, mut nodes: Vec<usize>) {
        nodes.sort_unstable();
        nodes.dedup();
        self.boundaries.insert(name.into(), nodes);
    }

    /// Length of the bounding-box diagonal: the mesh's size for relative tolerances.
    pub fn size(&self) -> f64 {
        let mut lo = Vec3::repeat(f64::INFINITY);
        let mut hi = Vec3::repeat(f64::NEG_INFINITY);
        for x in &self.nodes {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        if self.nodes.is_empty() {
            0.0
        } else {
            (hi - lo).norm()
        }
    }

    /// The shortest edge length.
    pub fn min_edge(&self) -> f64 {
        self.triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .map(|(a, b)| (self.nodes[a] - self.nodes[b]).norm())
            .fold(f64::INFINITY, f64::min)
    }

    /// Reverses every triangle's orientation (its normal), keeping the triangles' numbers.
    pub fn reverse_orientation(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// The area vector `½ (x2 − x1) × (x3 − x1)` of triangle `t`.
    pub fn area_vector(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.triangles[t];
        let (xa, xb, xc) = (self.nodes[a], self.nodes[b], self.nodes[c]);
        0.5 * (xb - xa).cross(&(xc - xa))
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| self.area_vector(t).norm())
            .sum()
    }

    /// Enclosed volume `(1/6) Σ x1·(x2 × x3)` (positive for a closed, outward-oriented mesh).
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|&[a, b, c]| self.nodes[a].dot(&self.nodes[b].cross(&self.nodes[c])))
            .sum::<f64>()
            / 6.0
    }

    /// Undirected edges `(min, max)`, sorted, with the triangles that use them, each with the
    /// direction it runs in that triangle (true if from min to max); from one sort of the
    /// triangles' edges.
    pub(crate) fn edges(&self) -> Edges {
        let mut all: Vec<(usize, usize, usize, bool)> = self
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(t, tri)| {
                (0..3).map(move |k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    (a.min(b), a.max(b), t, a < b)
                })
            })
            .collect();
        all.sort_unstable();
        let mut edges = Edges {
            keys: Vec::new(),
            start: vec![0],
            uses: Vec::with_capacity(all.len()),
        };
        for (a, b, t, dir) in all {
            if edges.keys.last() != Some(&(a, b)) {
                if !edges.keys.is_empty() {
                    edges.start.push(edges.uses.len());
                }
                edges.keys.push((a, b));
            }
            edges.uses.push((t, dir));
        }
        edges.start.push(edges.uses.len());
        edges
    }

    /// Checks that the mesh is a connected, consistently oriented 2-manifold (with boundary)
    /// without unused nodes, and reports whether it is closed and its boundary loops.
    pub fn topology(&self) -> Result<Topology, MeshError> {
        let bad = |m: String| Err(MeshError::Topology(m));
        let edges = self.edges();
        let mut boundary_next: HashMap<usize, usize> = HashMap::new();
        for ((a, b), uses) in edges.iter() {
            match uses {
                [(t, dir)] => {
                    // Boundary edge, oriented as in its triangle.
                    let (from, to) = if *dir { (a, b) } else { (b, a) };
                    if boundary_next.insert(from, to).is_some() {
                        return bad(format!("node {from} starts two boundary edges (pinched boundary near triangle {t})"));
                    }
                }
                [(t1, d1), (t2, d2)] => {
                    if d1 == d2 {
                        return bad(format!(
                            "triangles {t1} and {t2} are oriented inconsistently across edge ({a}, {b})"
                        ));
                    }
                }
                _ => {
                    return bad(format!(
                        "edge ({a}, {b}) is shared by {} triangles",
                        uses.len()
                    ))
                }
            }
        }
        let mut used = vec![false; self.nodes.len()];
        self.triangles
            .iter()
            .flatten()
            .for_each(|&i| used[i] = true);
        if let Some(i) = used.iter().position(|u| !u) {
            return bad(format!("node {i} belongs to no triangle"));
        }
        // Connectivity over shared edges (petgraph union-find on the triangle graph).
        let mut graph = UnGraph::<(), ()>::with_capacity(self.triangles.len(), edges.len());
        for _ in 0..self.triangles.len() {
            graph.add_node(());
        }
        for (_, uses) in edges.iter() {
            if let [(t1, _), (t2, _)] = uses {
                graph.add_edge((*t1 as u32).into(), (*t2 as u32).into(), ());
            }
        }
        let parts = petgraph::algo::connected_components(&graph);
        if parts != 1 {
            return bad(format!("the mesh has {parts} connected parts"));
        }
        // Each node's triangles must form one fan (no two surfaces touching at a vertex).
        self.check_vertex_fans(&edges)?;
        let mut loops = Vec::new();
        let mut seen: HashMap<usize, bool> = HashMap::new();
        let mut starts: Vec<usize> = boundary_next.keys().copied().collect();
        starts.sort_unstable();
        for start in starts {
            if seen.contains_key(&start) {
                continue;
            }
            let mut lp = vec![start];
            seen.insert(start, true);
            let mut cur = boundary_next[&start];
            while cur != start {
                if seen.insert(cur, true).is_some() {
                    return bad(format!("boundary loop through node {cur} does not close"));
                }
                lp.push(cur);
                cur = match boundary_next.get(&cur) {
                    Some(&n) => n,
                    None => return bad(format!("boundary ends at node {cur}")),
                };
            }
            loops.push(lp);
        }
        let euler = self.nodes.len() as i64 - edges.len() as i64 + self.triangles.len() as i64;
        Ok(Topology {
            closed: boundary_next.is_empty(),
            boundary_loops: loops,
            euler,
        })
    }

    fn check_vertex_fans(&self, edges: &Edges) -> Result<(), MeshError> {
        // Around node v, triangles sharing an edge through v are adjacent; they must form a
        // single connected fan.
        let mut around: Vec<Vec<usize>> = vec![Vec::new(); self.nodes.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                around[v].push(t);
            }
        }
        let mut parent: Vec<usize> = (0..self.triangles.len()).collect();
        fn root(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        let mut link_edges: Vec<Vec<(usize, usize)>> = vec![Vec::new(); self.nodes.len()];
        for ((a, b), uses) in edges.iter() {
            if let [(t1, _), (t2, _)] = uses {
                link_edges[a].push((*t1, *t2));
                link_edges[b].push((*t1, *t2));
            }
        }
        for v in 0..self.nodes.len() {
            for &(t1, t2) in &link_edges[v] {
                let (r1, r2) = (root(&mut parent, t1), root(&mut parent, t2));
                parent[r1] = r2;
            }
            let r0 = around[v].first().map(|&t| root(&mut parent, t));
            if around[v].iter().any(|&t| Some(root(&mut parent, t)) != r0) {
                return Err(MeshError::Topology(format!(
                    "node {v} joins surfaces that share only this node"
                )));
            }
            for &t in &around[v] {
                parent[t] = t;
            }
        }
        Ok(())
    }
}

/// The undirected edges of a mesh ([`Mesh::edges`]): the keys `(min, max)` sorted, and the
/// uses of edge e — (triangle, runs from min to max) — at `uses[start[e]..start[e + 1]]`.
pub(crate) struct Edges {
    keys: Vec<(usize, usize)>,
    start: Vec<usize>,
    uses: Vec<(usize, bool)>,
}

impl Edges {
    /// The number of edges.
    pub(crate) fn len(&self) -> usize {
        self.keys.len()
    }

    /// Every edge with its uses.
    pub(crate) fn iter(&self) -> impl Iterator<Item = ((usize, usize), &[(usize, bool)])> {
        self.keys
            .iter()
            .enumerate()
            .map(|(e, &k)| (k, &self.uses[self.start[e]..self.start[e + 1]]))
    }
}
