//! The orbit-local form of a block (see the module docs of [`crate::adapted`]): what the
//! formulas need of the group action, the seeds of each column, and the kernels that build
//! columns and restrict the tangent from the orbit representatives.

use super::SparseBasis;
use crate::linalg::SymmetricPattern;
use crate::model::Layout;
use meshes::GroupAction;
use nalgebra::{DMatrix, Matrix3, SymmetricEigen, Vector3};
use std::ops::Range;
use std::sync::Arc;

/// What the orbit-local formulas need of a group action, shared by all blocks of one basis.
#[derive(Debug)]
pub(super) struct OrbitFrame {
    /// |G|.
    pub(super) order: usize,
    /// R_g.
    pub(super) rotations: Vec<Matrix3<f64>>,
    /// For each unknown, its (node, component).
    pub(super) node_of: Vec<(u32, u8)>,
    /// For each node, the index of its orbit (in `GroupAction::node_orbits` order).
    pub(super) orbit_of: Vec<u32>,
    /// For each node j, the elements g with π_g(j) = representative of j's orbit, as a CSR
    /// list: `to_rep[to_rep_ptr[j]..to_rep_ptr[j + 1]]` (|H| elements per node).
    pub(super) to_rep_ptr: Vec<u32>,
    pub(super) to_rep: Vec<u16>,
    /// For orbit o, the images π_g(i₀) of its representative i₀ (its smallest node):
    /// `images[o * order + g]`.
    pub(super) images: Vec<u32>,
    /// For each node, its unknowns (`u32::MAX` where it has none).
    pub(super) dofs: Vec<[u32; 3]>,
}

impl OrbitFrame {
    /// The 3×3 blocks of K between the node `i0` (columns) and each of its neighbours j (rows)
    /// by K's pattern: `touched` the neighbours in the order met, `blocks[t]` the block of
    /// `touched[t]` (row component, column component).
    pub(super) fn neighbour_blocks(
        &self,
        layout: &Layout,
        tangent: &[f64],
        i0: usize,
        touched: &mut Vec<u32>,
        blocks: &mut Vec<Matrix3<f64>>,
    ) {
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        touched.clear();
        blocks.clear();
        for c in 0..3 {
            let dof = layout.dof(i0, c).expect("a free orbit has unknowns");
            let range = col_ptr[dof]..col_ptr[dof + 1];
            for (&r, &k) in row_idx[range.clone()].iter().zip(&tangent[range]) {
                let (j, comp) = self.node_of[r];
                let t = match touched.iter().position(|&n| n == j) {
                    Some(t) => t,
                    None => {
                        touched.push(j);
                        blocks.push(Matrix3::zeros());
                        touched.len() - 1
                    }
                };
                blocks[t][(comp as usize, c)] += k;
            }
        }
    }

    /// The (row, column) pairs of a block whose column e has its seed at node `rep[e]` and
    /// whose columns on orbit o are `by_orbit[o]`: column e meets every column on an orbit
    /// that holds a neighbour of e's representative (by K's pattern).
    pub(super) fn column_neighbours(
        &self,
        layout: &Layout,
        rep: &[u32],
        by_orbit: &[Range<u32>],
    ) -> Vec<(usize, usize)> {
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut entries = Vec::new();
        let mut orbits: Vec<u32> = Vec::new();
        for (e, &i0) in rep.iter().enumerate() {
            orbits.clear();
            for c in 0..3 {
                let dof = layout
                    .dof(i0 as usize, c)
                    .expect("a free orbit has unknowns");
                for &r in &row_idx[col_ptr[dof]..col_ptr[dof + 1]] {
                    let o = self.orbit_of[self.node_of[r].0 as usize];
                    if !orbits.contains(&o) {
                        orbits.push(o);
                    }
                }
            }
            for &o in &orbits {
                entries.extend(by_orbit[o as usize].clone().map(|f| (f as usize, e)));
            }
        }
        entries
    }

    pub(super) fn new(action: &GroupAction, layout: &Layout, orbits: &[Vec<usize>]) -> Self {
        let group = action.group();
        let nodes = layout.nodes();
        let mut orbit_of = vec![u32::MAX; nodes];
        let mut rep = vec![usize::MAX; nodes];
        for (o, orbit) in orbits.iter().enumerate() {
            for &j in orbit {
                orbit_of[j] = o as u32;
                rep[j] = orbit[0];
            }
        }
        let mut to_rep_ptr = vec![0u32; nodes + 1];
        let mut to_rep = Vec::with_capacity(nodes);
        for j in 0..nodes {
            if rep[j] != usize::MAX {
                to_rep.extend(
                    (0..group.order())
                        .filter(|&g| action.node_perm(g)[j] == rep[j])
                        .map(|g| g as u16),
                );
            }
            to_rep_ptr[j + 1] = to_rep.len() as u32;
        }
        let mut node_of = vec![(0, 0); layout.unknowns()];
        let mut dofs = vec![[u32::MAX; 3]; nodes];
        for (i, node_dofs) in dofs.iter_mut().enumerate() {
            for (k, slot) in node_dofs.iter_mut().enumerate() {
                if let Some(d) = layout.dof(i, k) {
                    node_of[d] = (i as u32, k as u8);
                    *slot = d as u32;
                }
            }
        }
        let images = orbits
            .iter()
            .flat_map(|orbit| (0..group.order()).map(|g| action.node_perm(g)[orbit[0]] as u32))
            .collect();
        Self {
            order: group.order(),
            rotations: group.elements().to_vec(),
            node_of,
            orbit_of,
            to_rep_ptr,
            to_rep,
            images,
            dofs,
        }
    }

    pub(super) fn to_rep(&self, j: usize) -> &[u16] {
        &self.to_rep[self.to_rep_ptr[j] as usize..self.to_rep_ptr[j + 1] as usize]
    }
}

/// The orbit-local description of a block's columns (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct Seeds {
    pub(super) frame: Arc<OrbitFrame>,
    /// Irrep dimension d.
    pub(super) d: usize,
    /// D(g), row-major d × d per element.
    pub(super) matrices: Arc<Vec<f64>>,
    /// Representative node of each column's orbit.
    pub(super) rep: Vec<u32>,
    /// The unknowns of each column's representative node.
    pub(super) rep_dofs: Vec<[u32; 3]>,
    /// Seeds, d per column: `seeds[e * d + b]` = s_{e,b}.
    pub(super) seeds: Vec<Vector3<f64>>,
    /// The columns on each orbit (contiguous, as they are built orbit by orbit).
    pub(super) by_orbit: Vec<Range<u32>>,
    /// For each column whose 3d seed numbers have a single nonzero, (its index 3b + c, its
    /// value): every column of a free orbit, whose seeds are scaled unit vectors (their Gram
    /// matrix is a multiple of the identity). The restriction then reads one column of each
    /// 3 × 3 block and one number of each orbit sum instead of contracting with the seeds.
    pub(super) unit: Vec<Option<(u32, f64)>>,
    /// Whether every column of the orbit has a unit seed.
    pub(super) unit_orbit: Vec<bool>,
    /// For each b < d, (d/|G|) Σ_g D_{b0}(g) R_g and (d/|G|) Σ_g D_{b0}(g) det(R_g) R_g: how
    /// P_{b0} acts on the translation and the rotation of a rigid motion.
    pub(super) rigid_maps: Vec<(Matrix3<f64>, Matrix3<f64>)>,
}

impl Seeds {
    pub(super) fn dmat(&self, g: usize) -> &[f64] {
        &self.matrices[g * self.d * self.d..(g + 1) * self.d * self.d]
    }

    /// Column e of Bᵀ K B (module docs) added into `out_col`: w_b = K s_{e,b} gathered by
    /// node (the neighbours j of e's representative), then ⟨s_{f,b'}, T(g) w_b⟩ for the
    /// elements g carrying j to the representative of the columns f on j's orbit.
    pub(super) fn tangent_column(
        &self,
        e: usize,
        layout: &Layout,
        tangent: &[f64],
        scratch: &mut ColumnScratch,
        out_col: &mut [f64],
    ) {
        let frame = &*self.frame;
        let d = self.d;
        let coef = d as f64 / frame.order as f64;
        let i0 = self.rep[e] as usize;
        let s_e = &self.seeds[e * d..(e + 1) * d];
        let ColumnScratch {
            touched,
            blocks,
            w,
            v,
            u,
        } = scratch;
        frame.neighbour_blocks(layout, tangent, i0, touched, blocks);
        w.clear();
        for block in blocks.iter() {
            w.extend(s_e.iter().map(|s| block * s));
        }
        for (t, &j) in touched.iter().enumerate() {
            let cols = self.by_orbit[frame.orbit_of[j as usize] as usize].clone();
            if cols.is_empty() {
                continue;
            }
            for &g in frame.to_rep(j as usize) {
                let r = &frame.rotations[g as usize];
                let dm = self.dmat(g as usize);
                for b in 0..d {
                    v[b] = r * w[t * d + b];
                }
                for b2 in 0..d {
                    u[b2] = (0..d).fold(Vector3::zeros(), |acc, b| acc + v[b] * dm[b2 * d + b]);
                }
                for f in cols.clone() {
                    let s_f = &self.seeds[f as usize * d..(f as usize + 1) * d];
                    let x: f64 = s_f.iter().zip(u.iter()).map(|(s, u)| s.dot(u)).sum();
                    out_col[f as usize] += coef * x;
                }
            }
        }
    }

    /// The columns E = `by_orbit[o]` of Bᵀ K B at once, on or below the diagonal of orbits:
    /// only the rows f on orbits whose columns start at or after E's (the others are the
    /// transposes of entries computed for those orbits' columns). `out` is E's values on the
    /// block pattern laid out by `rows` (the columns of E one after the other, each with the
    /// rows of every orbit E meets); the entries above the diagonal of orbits are left as
    /// they are ([`Seeds::mirror`] fills them).
    ///
    /// The formula of [`Seeds::tangent_column`] with its sums reordered: the columns of E
    /// share the representative i₀, so K's 3 × 3 blocks K_{j i₀} are gathered once, each
    /// A = R_g K_{j i₀} is formed once for all of E, and U_e = Σ_{(j, g)} Σ_b D_{·b}(g) A s_{e,b}
    /// is summed over every (j, g) that lands on the same orbit before the seeds s_f of that
    /// orbit are applied: (Bᵀ K B)_{fe} = (d/|G|) ⟨s_f, U_e⟩ over f's 3d seed components.
    pub(super) fn tangent_orbit_lower(
        &self,
        o: usize,
        layout: &Layout,
        tangent: &[f64],
        rows: &OrbitRows,
        scratch: &mut OrbitScratch,
        out: &mut [f64],
    ) {
        let cols_e = self.by_orbit[o].clone();
        let ne = cols_e.len();
        if ne == 0 {
            return;
        }
        let frame = &*self.frame;
        let d = self.d;
        let w3 = 3 * d;
        let len = out.len() / ne;
        let coef = d as f64 / frame.order as f64;
        let i0 = self.rep[cols_e.start as usize] as usize;
        let OrbitScratch {
            touched,
            blocks,
            targets,
            sums,
            v,
        } = scratch;
        frame.neighbour_blocks(layout, tangent, i0, touched, blocks);
        targets.clear();
        sums.clear();
        for (t, &j) in touched.iter().enumerate() {
            let target = frame.orbit_of[j as usize];
            let cols_f = self.by_orbit[target as usize].clone();
            if cols_f.is_empty() || cols_f.start < cols_e.start {
                continue;
            }
            let slot = match targets.iter().position(|&x| x == target) {
                Some(s) => s,
                None => {
                    targets.push(target);
                    sums.resize(sums.len() + ne * w3, 0.0);
                    targets.len() - 1
                }
            };
            let sum = &mut sums[slot * ne * w3..(slot + 1) * ne * w3];
            for &g in frame.to_rep(j as usize) {
                let a = frame.rotations[g as usize] * blocks[t];
                let dm = self.dmat(g as usize);
                for (le, e) in cols_e.clone().enumerate() {
                    let u_e = &mut sum[le * w3..(le + 1) * w3];
                    if let Some((k, value)) = self.unit[e as usize] {
                        // s_{e,b} = value · e_c for b = b₀ only: U_e,b₂ += D_{b₂b₀} value A e_c.
                        let (b0, c) = (k as usize / 3, k as usize % 3);
                        let x = a.column(c) * value;
                        for (b2, u) in u_e.chunks_exact_mut(3).enumerate() {
                            let dd = dm[b2 * d + b0];
                            u[0] += dd * x[0];
                            u[1] += dd * x[1];
                            u[2] += dd * x[2];
                        }
                        continue;
                    }
                    let s_e = &self.seeds[e as usize * d..(e as usize + 1) * d];
                    for (vb, s) in v.iter_mut().zip(s_e) {
                        *vb = a * s;
                    }
                    for (b2, u) in u_e.chunks_exact_mut(3).enumerate() {
                        let row = &dm[b2 * d..(b2 + 1) * d];
                        let x = v
                            .iter()
                            .zip(row)
                            .fold(Vector3::zeros(), |acc, (vb, &dd)| acc + vb * dd);
                        u[0] += x[0];
                        u[1] += x[1];
                        u[2] += x[2];
                    }
                }
            }
        }
        // Every orbit on or below E's diagonal, in E's rows: from its sums, or zero where no
        // neighbour of i₀ lies on it.
        for &(target, offset) in rows.of(o) {
            let cols_f = self.by_orbit[target as usize].clone();
            if cols_f.start < cols_e.start {
                continue;
            }
            let at = |le: usize| le * len + offset as usize;
            let nf = cols_f.len();
            let Some(slot) = targets.iter().position(|&x| x == target) else {
                for le in 0..ne {
                    out[at(le)..at(le) + nf].fill(0.0);
                }
                continue;
            };
            let sum = &sums[slot * ne * w3..(slot + 1) * ne * w3];
            if self.unit_orbit[target as usize] {
                // ⟨s_f, U_e⟩ = value_f · (U_e)_{k_f}.
                let units = &self.unit[cols_f.start as usize..cols_f.end as usize];
                for (le, u_e) in sum.chunks_exact(w3).enumerate() {
                    for (x, unit) in out[at(le)..at(le) + nf].iter_mut().zip(units) {
                        let (k, value) = unit.expect("a unit orbit");
                        *x = coef * value * u_e[k as usize];
                    }
                }
                continue;
            }
            let s_f = &self.seeds[cols_f.start as usize * d..cols_f.end as usize * d];
            for (le, u_e) in sum.chunks_exact(w3).enumerate() {
                for (x, s) in out[at(le)..at(le) + nf].iter_mut().zip(s_f.chunks_exact(d)) {
                    // ⟨s_f, U_e⟩ over the 3d numbers in order.
                    *x = coef
                        * s.iter()
                            .flat_map(|v| v.iter())
                            .zip(u_e)
                            .map(|(a, b)| a * b)
                            .sum::<f64>();
                }
            }
        }
    }

    /// The pattern of Bᵀ K B: column e meets every column on an orbit that holds a
    /// neighbour of e's representative (by K's pattern), and (the transpose) every column
    /// whose representative has a neighbour on e's orbit.
    ///
    /// All columns of one orbit share their representative, so the pattern is the graph of
    /// orbits (with columns in this block) expanded by their column ranges: the orbits met
    /// are found once per orbit, and each column's rows are the ranges of its orbit's
    /// neighbours in column order, already sorted and distinct.
    pub(super) fn block_pattern(&self, layout: &Layout) -> (SymmetricPattern, OrbitRows) {
        let frame = &*self.frame;
        let pattern = layout.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let orbits = self.by_orbit.len();
        let used = |o: usize| !self.by_orbit[o].is_empty();
        let mut met: Vec<Vec<u32>> = vec![Vec::new(); orbits];
        for o in (0..orbits).filter(|&o| used(o)) {
            met[o].push(o as u32);
            let e = self.by_orbit[o].start as usize;
            for &dof in &self.rep_dofs[e] {
                let dof = dof as usize;
                for &r in &row_idx[col_ptr[dof]..col_ptr[dof + 1]] {
                    let t = frame.orbit_of[frame.node_of[r].0 as usize];
                    if used(t as usize) {
                        met[o].push(t);
                        met[t as usize].push(o as u32);
                    }
                }
            }
        }
        for list in &mut met {
            list.sort_unstable_by_key(|&t| self.by_orbit[t as usize].start);
            list.dedup();
        }
        let m = self.rep.len();
        let mut starts = Vec::with_capacity(m + 1);
        starts.push(0usize);
        let mut rows = Vec::new();
        for &i0 in &self.rep {
            let o = frame.orbit_of[i0 as usize] as usize;
            for &t in &met[o] {
                rows.extend(self.by_orbit[t as usize].clone().map(|f| f as usize));
            }
            starts.push(rows.len());
        }
        let mut orbit_rows = OrbitRows {
            ptr: Vec::with_capacity(orbits + 1),
            met: Vec::new(),
        };
        orbit_rows.ptr.push(0);
        for list in &met {
            let mut offset = 0u32;
            for &t in list {
                orbit_rows.met.push((t, offset));
                offset += self.by_orbit[t as usize].len() as u32;
            }
            orbit_rows.ptr.push(orbit_rows.met.len() as u32);
        }
        (
            SymmetricPattern::from_sorted_columns(m, starts, rows),
            orbit_rows,
        )
    }

    /// Fills the entries of Bᵀ K B above the diagonal of orbits in `values` (on the pattern
    /// of [`Seeds::block_pattern`], laid out by `rows`) from their transposes below it, and
    /// replaces each pair of transposed entries in a diagonal orbit block (both computed,
    /// equal up to round-off) by their mean.
    pub(super) fn mirror(&self, rows: &OrbitRows, col_ptr: &[usize], values: &mut [f64]) {
        for (o, cols_e) in self.by_orbit.iter().enumerate() {
            let es = cols_e.start as usize;
            for &(t, offset) in rows.of(o) {
                let cols_f = &self.by_orbit[t as usize];
                let fs = cols_f.start as usize;
                if fs > es {
                    continue;
                }
                let offset = offset as usize;
                if fs == es {
                    for le in 0..cols_e.len() {
                        for lf in le + 1..cols_e.len() {
                            let p = col_ptr[es + le] + offset + lf;
                            let q = col_ptr[es + lf] + offset + le;
                            let mean = 0.5 * (values[p] + values[q]);
                            values[p] = mean;
                            values[q] = mean;
                        }
                    }
                    continue;
                }
                // Orbit t's columns come first: (f, e) is the transpose of (e, f), in column
                // f at the offset of o's rows there.
                let back = rows.offset(t as usize, o as u32);
                for le in 0..cols_e.len() {
                    let at = col_ptr[es + le] + offset;
                    for lf in 0..cols_f.len() {
                        values[at + lf] = values[col_ptr[fs + lf] + back + le];
                    }
                }
            }
        }
    }

    /// Partner a of column e, Σ_b P_{ab} s_{e,b}, summed over the whole group.
    pub(super) fn column(&self, e: usize, a: usize) -> Vec<(usize, f64)> {
        let d = self.d;
        let frame = &*self.frame;
        let coef = d as f64 / frame.order as f64;
        let i0 = self.rep[e] as usize;
        let images = &frame.images[frame.orbit_of[i0] as usize * frame.order..][..frame.order];
        let s = &self.seeds[e * d..(e + 1) * d];
        let mut at: Vec<(usize, Vector3<f64>)> = Vec::new();
        for (g, &image) in images.iter().enumerate() {
            let dm = self.dmat(g);
            let mut v = Vector3::zeros();
            for (b, sb) in s.iter().enumerate() {
                v += sb * dm[a * d + b];
            }
            if v == Vector3::zeros() {
                continue;
            }
            let j = image as usize;
            let w = frame.rotations[g] * v * coef;
            match at.iter_mut().find(|(n, _)| *n == j) {
                Some((_, x)) => *x += w,
                None => at.push((j, w)),
            }
        }
        let mut col = Vec::with_capacity(3 * at.len());
        for (j, w) in at {
            for k in 0..3 {
                if w[k].abs() > 1e-15 {
                    let dof = frame.dofs[j][k];
                    assert!(dof != u32::MAX, "a free orbit has unknowns");
                    col.push((dof as usize, w[k]));
                }
            }
        }
        col.sort_unstable_by_key(|&(dof, _)| dof);
        col
    }
}

/// Per-thread scratch of [`Seeds::tangent_column`].
pub(super) struct ColumnScratch {
    pub(super) touched: Vec<u32>,
    pub(super) blocks: Vec<Matrix3<f64>>,
    pub(super) w: Vec<Vector3<f64>>,
    pub(super) v: Vec<Vector3<f64>>,
    pub(super) u: Vec<Vector3<f64>>,
}

impl ColumnScratch {
    pub(super) fn new(d: usize) -> Self {
        Self {
            touched: Vec::new(),
            blocks: Vec::new(),
            w: Vec::new(),
            v: vec![Vector3::zeros(); d],
            u: vec![Vector3::zeros(); d],
        }
    }
}

/// Where each orbit's rows sit in the columns of a block pattern of
/// [`Seeds::block_pattern`]: every column of orbit o has the same rows, those of the orbits o
/// meets in column order, so orbit t's rows start at the same offset in each of them.
#[derive(Debug, Clone)]
pub(super) struct OrbitRows {
    /// Orbit o's entries are `met[ptr[o]..ptr[o + 1]]`: (orbit t, offset of t's rows).
    ptr: Vec<u32>,
    met: Vec<(u32, u32)>,
}

impl OrbitRows {
    /// The orbits o meets, with the offsets of their rows in o's columns.
    pub(super) fn of(&self, o: usize) -> &[(u32, u32)] {
        &self.met[self.ptr[o] as usize..self.ptr[o + 1] as usize]
    }

    /// The offset of orbit t's rows in o's columns.
    ///
    /// # Panics
    /// If o does not meet t.
    fn offset(&self, o: usize, t: u32) -> usize {
        let (_, offset) = self
            .of(o)
            .iter()
            .find(|&&(x, _)| x == t)
            .expect("the orbit graph is symmetric");
        *offset as usize
    }
}

/// Per-thread scratch of [`Seeds::tangent_orbit_lower`]: the nodes next to the
/// representative, K's 3 × 3 blocks there, the orbits they land on and the sums U_e for each.
pub(super) struct OrbitScratch {
    touched: Vec<u32>,
    blocks: Vec<Matrix3<f64>>,
    targets: Vec<u32>,
    sums: Vec<f64>,
    v: Vec<Vector3<f64>>,
}

impl OrbitScratch {
    pub(super) fn new(d: usize) -> Self {
        Self {
            touched: Vec::new(),
            blocks: Vec::new(),
            targets: Vec::new(),
            sums: Vec::new(),
            v: vec![Vector3::zeros(); d],
        }
    }
}

/// Builds the seeds and first-partner columns of one real irrep (given by its matrices
/// D(g), d × d) on the free orbits.
pub(super) fn orbit_basis(
    action: &GroupAction,
    layout: &Layout,
    frame: &Arc<OrbitFrame>,
    orbits: &[Vec<usize>],
    matrices: &[DMatrix<f64>],
) -> SparseBasis {
    let group = action.group();
    let d = matrices[0].nrows();
    let order = group.order() as f64;
    let flat: Vec<f64> = matrices
        .iter()
        .flat_map(|m| (0..d * d).map(move |k| m[(k / d, k % d)]))
        .collect();
    let mut seeds = Seeds {
        frame: frame.clone(),
        d,
        matrices: Arc::new(flat),
        rep: Vec::new(),
        rep_dofs: Vec::new(),
        seeds: Vec::new(),
        by_orbit: Vec::with_capacity(orbits.len()),
        unit: Vec::new(),
        unit_orbit: Vec::with_capacity(orbits.len()),
        rigid_maps: (0..d)
            .map(|b| {
                (0..group.order()).fold((Matrix3::zeros(), Matrix3::zeros()), |(t, w), g| {
                    let c = matrices[g][(b, 0)] * d as f64 / order;
                    let r = group.element(g);
                    (t + r * c, w + r * (c * r.determinant()))
                })
            })
            .collect(),
    };
    for orbit in orbits {
        let i0 = orbit[0];
        let start = seeds.rep.len() as u32;
        // Gram matrix of the candidates P_{0b} e_{i0,c} (index 3b + c), from the stabiliser.
        let mut gram = DMatrix::<f64>::zeros(3 * d, 3 * d);
        let mut stabiliser = 0;
        for h in (0..group.order()).filter(|&h| action.node_perm(h)[i0] == i0) {
            stabiliser += 1;
            let r = group.element(h);
            let dm = &matrices[h];
            for b in 0..d {
                for b2 in 0..d {
                    let x = dm[(b, b2)] * d as f64 / order;
                    if x == 0.0 {
                        continue;
                    }
                    for c in 0..3 {
                        for c2 in 0..3 {
                            gram[(3 * b + c, 3 * b2 + c2)] += x * r[(c, c2)];
                        }
                    }
                }
            }
        }
        // A node sliding in a plane: only candidates within the plane (u·n = 0).
        if let Some(n) = layout.slide_normal(i0) {
            let p = Matrix3::identity() - n * n.transpose();
            let mut lift = DMatrix::<f64>::zeros(3 * d, 3 * d);
            for b in 0..d {
                lift.view_mut((3 * b, 3 * b), (3, 3)).copy_from(&p);
            }
            gram = &lift * gram * &lift;
        }
        // On a free orbit (the stabiliser is the identity alone, no sliding) the Gram matrix
        // is (d/|G|) I exactly in theory, and the candidates themselves are orthogonal: the
        // seeds are the scaled unit vectors, not an eigenbasis of round-off in D(e).
        let free = stabiliser == 1 && layout.slide_normal(i0).is_none();
        let eig = if free {
            let lam = d as f64 / order;
            SymmetricEigen {
                eigenvalues: nalgebra::DVector::from_element(3 * d, lam),
                eigenvectors: DMatrix::identity(3 * d, 3 * d),
            }
        } else {
            SymmetricEigen::new((&gram + gram.transpose()) * 0.5)
        };
        // Genuine directions have eigenvalues of order d|H|/|G|, round-off ones of 1e-16.
        for (k, &lam) in eig.eigenvalues.iter().enumerate() {
            if lam <= 1e-10 {
                continue;
            }
            let y = eig.eigenvectors.column(k) / lam.sqrt();
            seeds.rep.push(i0 as u32);
            seeds
                .rep_dofs
                .push([0, 1, 2].map(|c| layout.dof(i0, c).expect("free orbit") as u32));
            for b in 0..d {
                seeds
                    .seeds
                    .push(Vector3::new(y[3 * b], y[3 * b + 1], y[3 * b + 2]));
            }
            let mut nonzero = y.iter().enumerate().filter(|(_, v)| **v != 0.0);
            seeds.unit.push(match (nonzero.next(), nonzero.next()) {
                (Some((k, &v)), None) => Some((k as u32, v)),
                _ => None,
            });
        }
        let cols = start as usize..seeds.rep.len();
        seeds
            .unit_orbit
            .push(seeds.unit[cols].iter().all(Option::is_some));
        seeds.by_orbit.push(start..seeds.rep.len() as u32);
    }
    SparseBasis::with_seeds(layout.unknowns(), seeds)
}

#[cfg(test)]
mod tests {
    use crate::adapted::AdaptedBasis;
    use crate::linalg::SymmetricPattern;
    use crate::model::Layout;
    use meshes::generators::{disc, icosphere, DiscOptions, IcosphereOptions};

    /// The unit icosphere of `frequency` and the layout of its free nodes.
    fn icosphere_layout(frequency: usize) -> (meshes::SymmetricMesh, Layout) {
        let sym = icosphere(&IcosphereOptions {
            radius: 1.0,
            frequency,
        })
        .expect("a valid icosphere");
        let layout = Layout::new(sym.mesh.nodes.len(), sym.mesh.triangles.clone(), &[]);
        (sym, layout)
    }

    /// Every block's pattern, built from the graph of orbits, is the one from its columns'
    /// pairs (each column's neighbouring orbits, with the transposes added).
    fn same_patterns(action: &meshes::GroupAction, layout: &Layout) {
        let basis = AdaptedBasis::new(action, layout).unwrap();
        for ib in &basis.irreps {
            let Some(seeds) = &ib.first().seeds else {
                continue;
            };
            let (fast, _) = seeds.block_pattern(layout);
            let entries = seeds
                .frame
                .column_neighbours(layout, &seeds.rep, &seeds.by_orbit);
            let slow = SymmetricPattern::from_entries(seeds.rep.len(), entries);
            assert_eq!(fast.col_ptr(), slow.col_ptr(), "{}", ib.name);
            assert_eq!(fast.row_idx(), slow.row_idx(), "{}", ib.name);
        }
    }

    /// On an Ih sphere every orbit of trivial stabiliser is a unit orbit (its seeds scaled
    /// unit vectors, which the restriction reads as such), and the blocks that hold a rigid
    /// motion are T1u (translations) and T1g (rotations) alone: there the restricted motions
    /// are of order one, elsewhere they vanish.
    #[test]
    fn free_orbits_have_unit_seeds_and_only_the_vector_irreps_hold_rigid_motions() {
        // Frequency 8: the first with nodes off every mirror plane.
        let (sym, layout) = icosphere_layout(8);
        let basis = AdaptedBasis::new(&sym.action, &layout).unwrap();
        let order = sym.action.group().order();
        let x: Vec<nalgebra::Vector3<f64>> = sym.mesh.nodes.clone();
        let mut free_orbits = 0;
        for ib in &basis.irreps {
            let b = ib.first();
            let Some(seeds) = &b.seeds else {
                continue;
            };
            for (o, cols) in seeds.by_orbit.iter().enumerate() {
                let Some(&rep) = seeds.rep.get(cols.start as usize) else {
                    continue;
                };
                let stabiliser = (0..order)
                    .filter(|&h| sym.action.node_perm(h)[rep as usize] == rep as usize)
                    .count();
                if stabiliser == 1 && !cols.is_empty() {
                    assert!(seeds.unit_orbit[o], "{}: orbit {o}", ib.name);
                    free_orbits += 1;
                }
            }
            let holds = b.holds_rigid_motions();
            assert_eq!(holds, ib.name == "T1u" || ib.name == "T1g", "{}", ib.name);
            let largest = [
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            ]
            .iter()
            .map(|motion| b.restrict_rigid(motion, &x, &layout).amax())
            .fold(0.0, f64::max);
            if holds {
                assert!(largest > 1e-2, "{}: {largest:e}", ib.name);
            } else {
                assert!(largest < 1e-12, "{}: {largest:e}", ib.name);
            }
        }
        assert!(free_orbits > 0);
    }

    #[test]
    fn block_pattern_from_the_orbit_graph() {
        let (sym, layout) = icosphere_layout(4);
        same_patterns(&sym.action, &layout);
        // A clamped rim: orbits of fixed nodes hold no columns.
        let sym = disc(&DiscOptions {
            sectors: 6,
            divisions: 5,
            ..Default::default()
        })
        .unwrap();
        let fixed: Vec<usize> = (0..sym.mesh.nodes.len())
            .filter(|&i| sym.mesh.nodes[i].xy().norm() > 1.0 - 1e-9)
            .collect();
        let layout = Layout::new(sym.mesh.nodes.len(), sym.mesh.triangles.clone(), &fixed);
        same_patterns(&sym.action, &layout);
    }
}
