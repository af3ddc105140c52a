//! Assembly on a fixed pattern, without allocation per element.
//!
//! The [`Layout`] is built once per model: the unknown numbers of every node (fixed nodes
//! have none), the symmetric sparsity pattern of the tangent, and for every triangle the 9
//! unknowns and 81 value slots its local Hessian scatters into (for every node its 3×3
//! diagonal block). An evaluation runs each effect's kernel over all triangles in parallel
//! and adds the results into per-triangle sums owned by the [`Evaluation`] (allocated once);
//! after the last effect the sums are scattered once, in parallel over ranges of unknowns
//! that each own their entries ([`ScatterPlan`]), so the scatter costs one pass however many
//! effects act on triangles.

use super::Local;
use super::{ModelError, Vec3};
use crate::linalg::SymmetricPattern;
use rayon::prelude::*;

/// Marks a fixed degree of freedom (no unknown, no slot).
const NONE: u32 = u32::MAX;

/// Unknown numbering, sparsity pattern and scatter slots of a mesh with fixed nodes.
#[derive(Debug, Clone)]
pub struct Layout {
    triangles: Vec<[usize; 3]>,
    dof_of: Vec<[u32; 3]>,
    unknowns: usize,
    pattern: SymmetricPattern,
    tri_dofs: Vec<[u32; 9]>,
    tri_slots: Vec<[u32; 81]>,
    node_slots: Vec<[u32; 9]>,
    /// For every node that slides in a plane, the plane's unit normal (docs/theory.md §6.2).
    slide: Vec<Option<Vec3>>,
    /// Held coordinates that move with a parameter ([`Layout::with_held_motion`]).
    held: Option<HeldMotion>,
    /// Whether the triangles form a closed surface (every edge in two of them), found once:
    /// every state's validity check asks ([`super::validity::state_defect_of`]).
    closed: bool,
    /// The nodes on the rim: on an edge that only one triangle has in its direction
    /// ([`super::validity::edge_summary`]), sorted.
    rim: Vec<usize>,
    /// How the whole mesh's triangle sums are scattered.
    plan: ScatterPlan,
}

/// The scatter of per-triangle sums by ownership: the unknowns are cut into ranges of
/// consecutive numbers, and every range lists, in order, the triangles with an unknown in it.
/// A range adds only into its own entries — its rows of the residual and the load vectors,
/// its columns of the tangent (contiguous in the column-major values) — so the ranges run in
/// parallel without sharing a write, and every entry receives its terms in triangle order
/// whatever the number of threads.
#[derive(Debug, Clone, PartialEq, Eq)]
struct ScatterPlan {
    /// Range r holds the unknowns `bounds[r]..bounds[r + 1]`.
    bounds: Vec<u32>,
    /// The triangles (positions in the evaluation's triangle list) of range r are
    /// `members[start[r]..start[r + 1]]`.
    start: Vec<usize>,
    members: Vec<u32>,
}

impl ScatterPlan {
    /// The plan for the triangles `list` (by position) of `tri_dofs`, with the unknowns cut into
    /// `ranges` ranges of about equal numbers of tangent values (`col_ptr`: the pattern's).
    fn new(
        tri_dofs: &[[u32; 9]],
        list: impl Iterator<Item = usize>,
        col_ptr: &[usize],
        ranges: usize,
    ) -> Self {
        let unknowns = col_ptr.len() - 1;
        let nnz = col_ptr[unknowns];
        let ranges = ranges.clamp(1, unknowns.max(1));
        let mut bounds = vec![0u32];
        for r in 1..ranges {
            let target = nnz * r / ranges;
            let c = col_ptr.partition_point(|&p| p < target).min(unknowns) as u32;
            if c > *bounds.last().expect("starts with 0") {
                bounds.push(c);
            }
        }
        bounds.push(unknowns as u32);
        let count = bounds.len() - 1;
        let range_of = |d: u32| bounds.partition_point(|&b| b <= d) - 1;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (k, t) in list.enumerate() {
            let mut seen = [usize::MAX; 9];
            for (j, &d) in tri_dofs[t].iter().enumerate() {
                if d == NONE {
                    continue;
                }
                let r = range_of(d);
                if !seen[..j].contains(&r) {
                    lists[r].push(k as u32);
                }
                seen[j] = r;
            }
        }
        let mut start = vec![0];
        for l in &lists {
            start.push(start.last().expect("starts with 0") + l.len());
        }
        Self {
            bounds,
            start,
            members: lists.concat(),
        }
    }

    /// Number of ranges.
    fn ranges(&self) -> usize {
        self.bounds.len() - 1
    }
}

/// How many ranges a [`ScatterPlan`] cuts the unknowns into: a few per thread, so that a
/// thread slowed by other work leaves its share to the others.
fn scatter_ranges() -> usize {
    4 * rayon::current_num_threads().max(1)
}

/// Held coordinates that move with a parameter Λ_p: node i sits at X_i + (Λ_p − Λ_p⁰) r_i,
/// where r_i = ∂x_i/∂Λ_p is non-zero only in held directions (all three of a fixed node, the
/// normal of a sliding one). The residual's load ∂F/∂Λ_p then has the implicit part
/// K_{u,x} r, the tangent's coupling of the unknowns to the moving coordinates
/// (docs/theory.md §2.8), which the assembler adds from every local Hessian.
#[derive(Debug, Clone)]
struct HeldMotion {
    parameter: usize,
    start: f64,
    rates: Vec<Vec3>,
    /// For every triangle, whether one of its nodes moves.
    moving: Vec<bool>,
}

impl Layout {
    /// Numbers the free nodes' coordinates in node order (x, y, z of each free node) and
    /// computes the pattern and slots.
    pub fn new(nodes: usize, triangles: Vec<[usize; 3]>, fixed: &[usize]) -> Self {
        let mut is_fixed = vec![false; nodes];
        for &i in fixed {
            is_fixed[i] = true;
        }
        let mut next = 0u32;
        let dof_of: Vec<[u32; 3]> = is_fixed
            .iter()
            .map(|&f| {
                if f {
                    [NONE; 3]
                } else {
                    next += 3;
                    [next - 3, next - 2, next - 1]
                }
            })
            .collect();
        let unknowns = next as usize;
        assert!(
            unknowns < NONE as usize,
            "too many unknowns for u32 numbering"
        );
        let tri_dofs: Vec<[u32; 9]> = triangles
            .iter()
            .map(|t| std::array::from_fn(|a| dof_of[t[a / 3]][a % 3]))
            .collect();
        // Every pair of unknowns of a triangle, without listing the 81 pairs per triangle.
        let pattern = SymmetricPattern::from_cliques(unknowns, &tri_dofs, NONE);
        let slot = |r: u32, c: u32| -> u32 {
            if r == NONE || c == NONE {
                NONE
            } else {
                pattern
                    .position(r as usize, c as usize)
                    .map_or(NONE, |p| u32::try_from(p).expect("pattern fits u32"))
            }
        };
        let (closed, rim) = super::validity::edge_summary(&triangles);
        let tri_slots = tri_dofs
            .iter()
            .map(|d| std::array::from_fn(|k| slot(d[k / 9], d[k % 9])))
            .collect();
        let plan = ScatterPlan::new(
            &tri_dofs,
            0..triangles.len(),
            pattern.col_ptr(),
            scatter_ranges(),
        );
        let node_slots = dof_of
            .iter()
            .map(|d| std::array::from_fn(|k| slot(d[k / 3], d[k % 3])))
            .collect();
        Self {
            closed,
            rim,
            triangles,
            dof_of,
            unknowns,
            pattern,
            tri_dofs,
            tri_slots,
            node_slots,
            slide: vec![None; nodes],
            held: None,
            plan,
        }
    }

    /// Moves held coordinates with the parameter `parameter`: node i at X_i + (Λ_p − `start`)
    /// `rates[i]`. A rate must lie in the node's held directions: zero for a free node, along
    /// the normal for a sliding one, anything for a fixed one (checked; panics otherwise, a
    /// programming error). Call after [`Layout::with_sliding`].
    pub fn with_held_motion(mut self, parameter: usize, start: f64, rates: Vec<Vec3>) -> Self {
        assert_eq!(rates.len(), self.nodes(), "one rate per node");
        for (i, r) in rates.iter().enumerate() {
            let held = match (self.dof_of[i][0] == NONE, self.slide[i]) {
                (true, _) => true,
                (false, Some(n)) => (r - n * n.dot(r)).norm() <= 1e-12 * r.norm(),
                (false, None) => *r == Vec3::zeros(),
            };
            assert!(held, "node {i} moves in a direction it is not held in");
        }
        let moving = self
            .triangles
            .iter()
            .map(|t| t.iter().any(|&i| rates[i] != Vec3::zeros()))
            .collect();
        self.held = Some(HeldMotion {
            parameter,
            start,
            rates,
            moving,
        });
        self
    }

    /// The parameter the held coordinates move with, if any.
    pub fn held_parameter(&self) -> Option<usize> {
        self.held.as_ref().map(|h| h.parameter)
    }

    /// Moves the held coordinates of the positions `x` to where the parameters `params`
    /// put them (nothing without a held motion).
    pub fn add_held_motion(&self, params: &[f64], x: &mut [Vec3]) {
        if let Some(h) = &self.held {
            let d = params[h.parameter] - h.start;
            for (xi, r) in x.iter_mut().zip(&h.rates) {
                *xi += r * d;
            }
        }
    }

    /// Σ_t (per-triangle gradient `grad(t, x_t)`) gathered over the unknowns, with the
    /// quantity's rate along the held motion, Σ_i g_i · r_i over every node, unknown or held
    /// (0 without one), in one pass.
    pub fn gather(
        &self,
        x: &[Vec3],
        grad: impl Fn(usize, &[Vec3; 3]) -> [f64; 9],
    ) -> GlobalGradient {
        let mut v = vec![0.0; self.unknowns];
        let mut along_held = 0.0;
        for (t, &[a, b, c]) in self.triangles.iter().enumerate() {
            let g = grad(t, &[x[a], x[b], x[c]]);
            for (k, &d) in self.tri_dofs[t].iter().enumerate() {
                if d != NONE {
                    v[d as usize] += g[k];
                }
            }
            if let Some(h) = self.held.as_ref().filter(|h| h.moving[t]) {
                for (k, node) in [a, b, c].into_iter().enumerate() {
                    along_held += (0..3).map(|c| g[3 * k + c] * h.rates[node][c]).sum::<f64>();
                }
            }
        }
        GlobalGradient {
            unknowns: v,
            along_held,
        }
    }

    /// Lets each `(node, normal)` slide in the plane through its reference position with that
    /// normal (a free node; normalised here). The node keeps its three unknowns; the bases the
    /// solvers work in ([`crate::adapted`]) span only displacements with u·n = 0 there.
    pub fn with_sliding(mut self, sliding: &[(usize, Vec3)]) -> Self {
        for &(i, n) in sliding {
            if self.dof_of[i][0] != NONE {
                self.slide[i] = Some(n.normalize());
            }
        }
        self
    }

    /// The unit normal of the plane node `node` slides in, if it slides.
    pub fn slide_normal(&self, node: usize) -> Option<Vec3> {
        self.slide[node]
    }

    /// True if some node slides.
    pub fn slides(&self) -> bool {
        self.slide.iter().any(Option::is_some)
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.dof_of.len()
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.unknowns
    }

    /// The tangent's sparsity pattern.
    pub fn pattern(&self) -> &SymmetricPattern {
        &self.pattern
    }

    /// Triangles (node indices).
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Whether the triangles form a closed surface ([`super::validity::is_closed`]).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The rim's nodes, sorted: empty for a closed, consistently oriented surface.
    pub fn rim(&self) -> &[usize] {
        &self.rim
    }

    /// The unknown of coordinate `k` of node `i`, or `None` for a fixed node.
    pub fn dof(&self, node: usize, k: usize) -> Option<usize> {
        let d = self.dof_of[node][k];
        (d != NONE).then_some(d as usize)
    }

    /// Adds the displacements `u` to the positions `x` of the free nodes.
    pub fn add_displacements(&self, u: &[f64], x: &mut [Vec3]) {
        for (xi, d) in x.iter_mut().zip(&self.dof_of) {
            if d[0] != NONE {
                for k in 0..3 {
                    xi[k] += u[d[k] as usize];
                }
            }
        }
    }
}

/// What an evaluation should compute (Π and F are always computed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Request {
    /// The tangent K.
    pub tangent: bool,
    /// The load vectors ∂F/∂Λ.
    pub loads: bool,
}

impl Request {
    /// Π and F only.
    pub const RESIDUAL: Request = Request {
        tangent: false,
        loads: false,
    };
    /// Π, F, K and ∂F/∂Λ.
    pub const ALL: Request = Request {
        tangent: true,
        loads: true,
    };
}

/// How many parameter derivatives of its gradient one kernel call can return (the membrane's
/// μ, k, H, λ0 and reference radius).
pub const LOAD_SLOTS: usize = 5;

/// One triangle's terms: its [`Local`] and up to [`LOAD_SLOTS`] parameter derivatives of its
/// gradient.
#[derive(Debug, Clone, Copy, Default)]
pub struct TriangleTerms {
    /// Value, gradient and Hessian.
    pub local: Local,
    /// ∂(gradient)/∂Λ for the parameters named in the assembler call.
    pub loads: [[f64; 9]; LOAD_SLOTS],
}

/// One node's terms.
#[derive(Debug, Clone, Copy, Default)]
pub struct NodeTerms {
    /// The contribution.
    pub value: f64,
    /// Its gradient.
    pub grad: [f64; 3],
    /// Its Hessian.
    pub hess: [[f64; 3]; 3],
    /// ∂(gradient)/∂Λ for the parameters named in the assembler call.
    pub loads: [[f64; 3]; LOAD_SLOTS],
}

/// The result of an evaluation, with the scratch buffers reused from call to call.
///
/// The full tangent is `K = K_sparse + Σ_k c_k a_k a_kᵀ`: the sparse part on the pattern,
/// plus the rank-one terms of global potentials such as a fixed amount of gas, which a
/// solver treats by bordering or Sherman–Morrison rather than by filling K.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Π.
    pub energy: f64,
    /// F = ∂Π/∂u.
    pub residual: Vec<f64>,
    /// Values of the sparse part of K on the pattern.
    pub tangent: Vec<f64>,
    /// ∂F/∂Λ_j, one vector per parameter.
    pub loads: Vec<Vec<f64>>,
    /// Rank-one terms (c_k, a_k) of K.
    pub rank_one: Vec<(f64, Vec<f64>)>,
    pub(super) positions: Vec<Vec3>,
    /// For every triangle assembled, the sum of the triangle effects' value, gradient and
    /// (when the tangent is requested) Hessian, scattered once by [`Evaluation::finish`].
    tri_sums: Vec<Local>,
    /// For every triangle assembled, `load_width` gradients: the sum of the effects' loads
    /// of parameter p at `k * load_width + p` (when the loads are requested).
    tri_loads: Vec<[f64; 9]>,
    load_width: usize,
    /// Whether `tri_sums` holds this evaluation's terms (else the next effect overwrites).
    tri_pending: bool,
    /// For every parameter, whether `tri_loads` holds this evaluation's loads of it.
    loads_pending: Vec<bool>,
    /// Whether the tangent still holds the previous evaluation's values: it is cleared
    /// where it is written first — by the scatter of the triangle sums, range by range in
    /// parallel, or before a node effect's scatter ([`Evaluation::clear_tangent`]).
    tangent_stale: bool,
    /// Whether the scatter has checked every tangent value it could have written for
    /// finiteness (so that [`Evaluation::check_finite`] need not read the tangent again).
    tangent_checked: bool,
    node_terms: Vec<NodeTerms>,
    request: Request,
    /// When set, only these triangles and nodes are assembled (see [`Subset`]).
    subset: Option<std::sync::Arc<Subset>>,
}

/// The triangles and nodes around a set of nodes: every triangle that contains one of them,
/// and the nodes themselves. An evaluation restricted to a subset computes F, ∂F/∂Λ and the
/// columns of K at those nodes exactly (every term that reaches them is assembled) and
/// nothing else is meaningful: the other entries and Π are partial sums. Global quantities
/// an effect computes itself (the enclosed volume of a gas amount, its rank-one gradient)
/// stay complete. At a symmetric state the orbit representatives are all the symmetric
/// solver needs (see [`crate::adapted`]), about 1/|G| of the mesh.
///
/// Such an evaluation writes only the tangent's slots of its triangles and nodes; the others
/// stay zero, so it clears and checks only those (≈ 1/|G| of K's values, 83 MB at f = 128).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subset {
    triangles: Vec<usize>,
    nodes: Vec<usize>,
    /// The tangent slots its triangles and nodes write, sorted.
    slots: Vec<u32>,
    /// How its triangles' sums are scattered.
    plan: ScatterPlan,
}

impl Subset {
    /// The triangles containing any of `nodes`, and `nodes` (sorted, deduplicated).
    pub fn around(layout: &Layout, nodes: &[usize]) -> Self {
        let mut mark = vec![false; layout.nodes()];
        for &i in nodes {
            mark[i] = true;
        }
        let triangles: Vec<usize> = (0..layout.triangles.len())
            .filter(|&t| layout.triangles[t].iter().any(|&i| mark[i]))
            .collect();
        let mut nodes = nodes.to_vec();
        nodes.sort_unstable();
        nodes.dedup();
        let mut slots: Vec<u32> = triangles
            .iter()
            .flat_map(|&t: &usize| layout.tri_slots[t])
            .chain(nodes.iter().flat_map(|&i| layout.node_slots[i]))
            .filter(|&k| k != NONE)
            .collect();
        slots.sort_unstable();
        slots.dedup();
        let plan = ScatterPlan::new(
            &layout.tri_dofs,
            triangles.iter().copied(),
            layout.pattern.col_ptr(),
            scatter_ranges(),
        );
        Self {
            triangles,
            nodes,
            slots,
            plan,
        }
    }

    /// The triangles assembled.
    pub fn triangles(&self) -> &[usize] {
        &self.triangles
    }

    /// The nodes whose rows and columns are exact.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The tangent slots its triangles and nodes write (sorted): an evaluation of the subset
    /// holds zeros in every other slot.
    pub fn slots(&self) -> &[u32] {
        &self.slots
    }
}

impl Evaluation {
    pub(super) fn new(layout: &Layout, parameters: usize) -> Self {
        let n = layout.unknowns();
        Self {
            energy: 0.0,
            residual: vec![0.0; n],
            tangent: vec![0.0; layout.pattern().nnz()],
            loads: vec![vec![0.0; n]; parameters],
            rank_one: Vec::new(),
            positions: Vec::with_capacity(layout.dof_of.len()),
            // Sized by the first assembly (`add_triangles`, `add_nodes`), for the whole mesh
            // or the subset: ≈ 0.8 kB per triangle, not worth holding in an evaluation that
            // is restricted or never assembled.
            tri_sums: Vec::new(),
            tri_loads: Vec::new(),
            load_width: parameters.max(1),
            tri_pending: false,
            loads_pending: vec![false; parameters],
            tangent_stale: false,
            tangent_checked: false,
            node_terms: Vec::new(),
            request: Request::ALL,
            subset: None,
        }
    }

    /// The same buffer, assembling only `subset` from now on.
    pub fn restricted_to(mut self, subset: std::sync::Arc<Subset>) -> Self {
        self.tri_sums = Vec::new();
        self.tri_loads = Vec::new();
        self.node_terms = Vec::new();
        self.tangent_stale = false;
        // Zero outside the subset's slots from now on (fresh, so its pages stay unwritten).
        self.tangent = vec![0.0; self.tangent.len()];
        self.subset = Some(subset);
        self
    }

    /// The subset this evaluation assembles (`None`: the whole mesh).
    pub fn subset(&self) -> Option<&Subset> {
        self.subset.as_deref()
    }

    pub(super) fn reset(&mut self, request: Request) {
        self.request = request;
        self.energy = 0.0;
        self.residual.fill(0.0);
        self.tri_pending = false;
        self.loads_pending.fill(false);
        self.tangent_checked = false;
        if request.tangent {
            self.tangent_stale = true;
            self.rank_one.clear();
        }
        if request.loads {
            self.loads.iter_mut().for_each(|l| l.fill(0.0));
        }
    }

    /// Zeroes the tangent values an evaluation can write (all, or the subset's), unless done.
    fn clear_tangent(&mut self) {
        if !std::mem::take(&mut self.tangent_stale) {
            return;
        }
        match &self.subset {
            Some(subset) => subset
                .slots
                .iter()
                .for_each(|&k| self.tangent[k as usize] = 0.0),
            None => self.tangent.fill(0.0),
        }
    }

    /// Completes an evaluation after its last effect: scatters the triangle sums
    /// ([`ScatterPlan`]) into Π, the residual, the tangent and the load vectors, with the
    /// implicit load of moving held coordinates, Σ_b H_ab r_b, from the summed Hessians.
    pub(super) fn finish(&mut self, layout: &Layout) {
        if self.tri_pending {
            self.scatter_triangles(layout);
        }
        if self.request.tangent {
            self.clear_tangent();
        }
    }

    fn scatter_triangles(&mut self, layout: &Layout) {
        let (want_k, want_l) = (self.request.tangent, self.request.loads);
        let subset = self.subset.clone();
        let plan = subset.as_ref().map_or(&layout.plan, |s| &s.plan);
        let ids = subset.as_ref().map(|s| s.triangles.as_slice());
        let id = |k: usize| ids.map_or(k, |s| s[k]);
        self.energy += self.tri_sums.iter().map(|s| s.value).sum::<f64>();
        let held = layout.held.as_ref().filter(|_| want_l);
        // The load vectors this scatter adds to: those an effect named, and the held one.
        let active: Vec<bool> = (0..self.loads.len())
            .map(|p| want_l && (self.loads_pending[p] || held.is_some_and(|h| h.parameter == p)))
            .collect();
        let zero = std::mem::take(&mut self.tangent_stale);
        let col_ptr = layout.pattern.col_ptr();
        // Cut every output into the plan's ranges.
        let mut residual = self.residual.as_mut_slice();
        let mut tangent = self.tangent.as_mut_slice();
        let mut loads: Vec<(usize, &mut [f64])> = self
            .loads
            .iter_mut()
            .enumerate()
            .filter(|(p, _)| active[*p])
            .map(|(p, l)| (p, l.as_mut_slice()))
            .collect();
        let mut pieces = Vec::with_capacity(plan.ranges());
        for r in 0..plan.ranges() {
            let (c0, c1) = (plan.bounds[r] as usize, plan.bounds[r + 1] as usize);
            let (res, rest) = std::mem::take(&mut residual).split_at_mut(c1 - c0);
            residual = rest;
            let (tan, rest) = std::mem::take(&mut tangent).split_at_mut(col_ptr[c1] - col_ptr[c0]);
            tangent = rest;
            let piece_loads: Vec<(usize, &mut [f64])> = loads
                .iter_mut()
                .map(|(p, l)| {
                    let (head, rest) = std::mem::take(l).split_at_mut(c1 - c0);
                    *l = rest;
                    (*p, head)
                })
                .collect();
            pieces.push((r, res, tan, piece_loads));
        }
        let (sums, tri_loads, width) = (&self.tri_sums, &self.tri_loads, self.load_width);
        let pending = &self.loads_pending;
        let slot_list = subset.as_ref().map(|s| s.slots.as_slice());
        let finite = pieces
            .into_par_iter()
            .map(|(r, residual, tangent, mut loads)| {
                let c0 = plan.bounds[r];
                let len = residual.len();
                let s0 = col_ptr[c0 as usize];
                // The subset's slots in this range, or all of them.
                let own = slot_list.map(|slots| {
                    let a = slots.partition_point(|&k| (k as usize) < s0);
                    let b = slots.partition_point(|&k| (k as usize) < s0 + tangent.len());
                    &slots[a..b]
                });
                if zero {
                    match own {
                        Some(slots) => slots.iter().for_each(|&k| tangent[k as usize - s0] = 0.0),
                        None => tangent.fill(0.0),
                    }
                }
                for &k in &plan.members[plan.start[r]..plan.start[r + 1]] {
                    let k = k as usize;
                    let t = id(k);
                    let (dofs, sum) = (&layout.tri_dofs[t], &sums[k]);
                    let slots = &layout.tri_slots[t];
                    let moving = held.filter(|h| h.moving[t]);
                    for (a, &d) in dofs.iter().enumerate() {
                        // NONE (a fixed coordinate) is past every range.
                        let i = d.wrapping_sub(c0) as usize;
                        if i >= len {
                            continue;
                        }
                        residual[i] += sum.grad[a];
                        for (p, l) in loads.iter_mut() {
                            if pending[*p] {
                                l[i] += tri_loads[k * width + *p][a];
                            }
                            // The implicit load of moving held coordinates: Σ_b H_ab r_b.
                            if let Some(h) = moving.filter(|h| h.parameter == *p) {
                                let tri = &layout.triangles[t];
                                l[i] += (0..9)
                                    .map(|b| sum.hess[a][b] * h.rates[tri[b / 3]][b % 3])
                                    .sum::<f64>();
                            }
                        }
                        if want_k {
                            // Column d: the slots of rows b, values H_ba.
                            for b in 0..9 {
                                let slot = slots[9 * b + a];
                                if slot != NONE {
                                    tangent[slot as usize - s0] += sum.hess[b][a];
                                }
                            }
                        }
                    }
                }
                !want_k
                    || match own {
                        Some(slots) => slots.iter().all(|&k| tangent[k as usize - s0].is_finite()),
                        None => tangent.iter().all(|v| v.is_finite()),
                    }
            })
            .reduce(|| true, |a, b| a && b);
        self.tangent_checked = want_k && finite;
        self.tri_pending = false;
    }

    pub(super) fn check_finite(&self) -> Result<(), ModelError> {
        let bad = |what| {
            Err(ModelError::NonFinite {
                effect: "(sum)".into(),
                what,
            })
        };
        if !self.energy.is_finite() {
            return bad("energy");
        }
        if !self.residual.iter().all(|v| v.is_finite()) {
            return bad("residual");
        }
        let tangent_finite = || {
            self.tangent_checked
                || match &self.subset {
                    Some(subset) => subset
                        .slots
                        .iter()
                        .all(|&k| self.tangent[k as usize].is_finite()),
                    None => self.tangent.iter().all(|v| v.is_finite()),
                }
        };
        if self.request.tangent && !tangent_finite() {
            return bad("tangent");
        }
        if self.request.loads && !self.loads.iter().flatten().all(|v| v.is_finite()) {
            return bad("load vector");
        }
        Ok(())
    }

    /// The request this evaluation was made with.
    pub fn request(&self) -> Request {
        self.request
    }
}

/// The interface an [`super::Effect`] assembles through.
pub struct Assembler<'a> {
    layout: &'a Layout,
    out: &'a mut Evaluation,
    request: Request,
    effect: &'a str,
}

impl<'a> Assembler<'a> {
    pub(super) fn new(
        layout: &'a Layout,
        out: &'a mut Evaluation,
        request: Request,
        effect: &'a str,
    ) -> Self {
        Self {
            layout,
            out,
            request,
            effect,
        }
    }

    /// What is being computed.
    pub fn request(&self) -> Request {
        self.request
    }

    /// The triangles of the mesh.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.layout.triangles
    }

    /// Runs `kernel` on every triangle (in parallel) and adds the results. `load_params[s]`
    /// names the parameter whose load vector receives `terms.loads[s]` (N ≤ [`LOAD_SLOTS`];
    /// a parameter named in two slots receives both).
    pub fn add_triangles<F, const N: usize>(
        &mut self,
        x: &[Vec3],
        load_params: [Option<usize>; N],
        kernel: F,
    ) -> Result<(), ModelError>
    where
        F: Fn(usize, &[Vec3; 3], &mut TriangleTerms) -> Result<(), String> + Sync,
    {
        const { assert!(N <= LOAD_SLOTS, "at most LOAD_SLOTS load parameters") };
        let tris = &self.layout.triangles;
        let (want_k, want_l) = (self.request.tangent, self.request.loads);
        let effect = self.effect;
        let out = &mut *self.out;
        let ids = out.subset.clone();
        let id = |k: usize| ids.as_ref().map_or(k, |s| s.triangles[k]);
        let count = ids.as_ref().map_or(tris.len(), |s| s.triangles.len());
        let width = out.load_width;
        out.tri_sums.resize(count, Local::ZERO);
        out.tri_loads.resize(count * width, [0.0; 9]);
        // A load slot writes its parameter's sums if it is the first to name it in this
        // evaluation, else adds to them.
        let mut fresh = [false; N];
        for (s, p) in load_params.iter().enumerate() {
            if let Some(p) = *p {
                fresh[s] = !out.loads_pending[p] && !load_params[..s].contains(&Some(p));
            }
        }
        let first = !out.tri_pending;
        out.tri_sums
            .par_iter_mut()
            .zip(out.tri_loads.par_chunks_mut(width))
            .enumerate()
            .try_for_each_init(TriangleTerms::default, |terms, (k, (sum, loads))| {
                let t = id(k);
                let [a, b, c] = tris[t];
                terms.loads = [[0.0; 9]; LOAD_SLOTS];
                kernel(t, &[x[a], x[b], x[c]], terms).map_err(|what| ModelError::Element {
                    effect: effect.to_string(),
                    triangle: t,
                    what,
                })?;
                if first {
                    *sum = terms.local;
                } else {
                    add_local(sum, &terms.local, want_k);
                }
                if want_l {
                    for (s, p) in load_params.iter().enumerate() {
                        if let Some(p) = *p {
                            if fresh[s] {
                                loads[p] = terms.loads[s];
                            } else {
                                loads[p]
                                    .iter_mut()
                                    .zip(&terms.loads[s])
                                    .for_each(|(l, v)| *l += v);
                            }
                        }
                    }
                }
                Ok(())
            })?;
        out.tri_pending = true;
        if want_l {
            for p in load_params.into_iter().flatten() {
                out.loads_pending[p] = true;
            }
        }
        Ok(())
    }

    /// Runs `kernel` on every node (in parallel) and adds the results (load slots as for
    /// [`Assembler::add_triangles`]).
    pub fn add_nodes<F, const N: usize>(
        &mut self,
        x: &[Vec3],
        load_params: [Option<usize>; N],
        kernel: F,
    ) -> Result<(), ModelError>
    where
        F: Fn(usize, &Vec3, &mut NodeTerms) -> Result<(), String> + Sync,
    {
        const { assert!(N <= LOAD_SLOTS, "at most LOAD_SLOTS load parameters") };
        let ids = self.out.subset.clone();
        let id = |k: usize| ids.as_ref().map_or(k, |s| s.nodes[k]);
        let count = ids
            .as_ref()
            .map_or(self.layout.dof_of.len(), |s| s.nodes.len());
        self.out.node_terms.resize(count, NodeTerms::default());
        self.out
            .node_terms
            .par_iter_mut()
            .enumerate()
            .try_for_each(|(k, terms)| {
                let i = id(k);
                *terms = NodeTerms::default();
                kernel(i, &x[i], terms).map_err(|what| ModelError::Global {
                    effect: self.effect.to_string(),
                    what: format!("{what} at node {i}"),
                })
            })?;
        let (want_k, want_l) = (self.request.tangent, self.request.loads);
        let out = &mut *self.out;
        if want_k {
            out.clear_tangent();
        }
        for (k, terms) in out.node_terms.iter().enumerate() {
            let i = id(k);
            out.energy += terms.value;
            let dofs = &self.layout.dof_of[i];
            if dofs[0] == NONE {
                continue;
            }
            for (k, &d) in dofs.iter().enumerate() {
                out.residual[d as usize] += terms.grad[k];
                if want_l {
                    for (s, p) in load_params.iter().enumerate() {
                        if let Some(p) = *p {
                            out.loads[p][d as usize] += terms.loads[s][k];
                        }
                    }
                }
            }
            if want_k {
                for (k, &slot) in self.layout.node_slots[i].iter().enumerate() {
                    out.tangent[slot as usize] += terms.hess[k / 3][k % 3];
                }
            }
            // The implicit load of a moving held coordinate of this (sliding) node.
            if let Some(h) = self.layout.held.as_ref().filter(|_| want_l) {
                let r = h.rates[i];
                for (k, &d) in dofs.iter().enumerate() {
                    out.loads[h.parameter][d as usize] +=
                        (0..3).map(|l| terms.hess[k][l] * r[l]).sum::<f64>();
                }
            }
        }
        Ok(())
    }

    /// Assembles Σ_t (per-triangle gradient) into a vector over the unknowns, for global
    /// potentials φ(Q(u)) whose tangent has the rank-one part φ''(Q) ∇Q ∇Qᵀ.
    pub fn gradient_vector<F>(&self, x: &[Vec3], kernel: F) -> GlobalGradient
    where
        F: Fn(usize, &[Vec3; 3]) -> [f64; 9],
    {
        self.layout.gather(x, kernel)
    }

    /// The gradient of a global potential that depends on each node's position, from one
    /// 3-vector per node, for its rank-one tangent terms (fixed nodes count only in the rate
    /// along the held motion).
    pub fn node_vector(&self, mut value: impl FnMut(usize) -> [f64; 3]) -> GlobalGradient {
        let mut v = vec![0.0; self.layout.unknowns];
        let mut along_held = 0.0;
        for (i, dofs) in self.layout.dof_of.iter().enumerate() {
            let x = value(i);
            if let Some(h) = &self.layout.held {
                along_held += (0..3).map(|k| x[k] * h.rates[i][k]).sum::<f64>();
            }
            if dofs[0] == NONE {
                continue;
            }
            for (k, &d) in dofs.iter().enumerate() {
                v[d as usize] = x[k];
            }
        }
        GlobalGradient {
            unknowns: v,
            along_held,
        }
    }

    /// Adds a constant to Π (the value of a global potential).
    pub fn add_energy(&mut self, value: f64) {
        self.out.energy += value;
    }

    /// Adds the rank-one term c a aᵀ to the tangent (only when the tangent is requested),
    /// and with a held motion its implicit load c a (a · r).
    pub fn add_rank_one(&mut self, c: f64, a: GlobalGradient) {
        if let Some(p) = self.layout.held_parameter().filter(|_| self.request.loads) {
            let w = c * a.along_held;
            for (l, ai) in self.out.loads[p].iter_mut().zip(&a.unknowns) {
                *l += w * ai;
            }
        }
        if self.request.tangent {
            self.out.rank_one.push((c, a.unknowns));
        }
    }
}

/// Adds the value, gradient and (if `hess`) Hessian of `terms` to `sum`.
fn add_local(sum: &mut Local, terms: &Local, hess: bool) {
    sum.value += terms.value;
    sum.grad
        .iter_mut()
        .zip(&terms.grad)
        .for_each(|(s, g)| *s += g);
    if hess {
        sum.hess
            .iter_mut()
            .flatten()
            .zip(terms.hess.iter().flatten())
            .for_each(|(s, h)| *s += h);
    }
}

/// The gradient ∇Q of a global quantity over the unknowns, and its rate along the layout's
/// held motion, Σ_i ∇_i Q · r_i over every node (fixed ones included; 0 without one).
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalGradient {
    /// ∂Q/∂u.
    pub unknowns: Vec<f64>,
    /// dQ/dΛ_p through the held coordinates alone.
    pub along_held: f64,
}

#[cfg(test)]
#[path = "scatter_tests.rs"]
mod tests;
