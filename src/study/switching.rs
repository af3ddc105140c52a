//! Branch switching at critical points by the equivariant branching lemma (docs/theory.md
//! §14): the branches that leave a bifurcation point of a path, one per conjugacy class of
//! axial isotropy subgroups of its irrep (and per half where ±v are not conjugate), each
//! followed in its own fixed-point space with stability by the irreps of its isotropy
//! subgroup — and, to a chosen depth, the branches that leave those.
//!
//! At a critical point of a path in Fix(G) whose block μ is singular:
//! 1. the kernel V_μ is spanned by the d partners x_a = P_{a0} x_0 of the block's null vector
//!    x_0 (§10.1); for an axial isotropy subgroup Σ of μ (dim Fix_{V_μ}(Σ) = 1, from
//!    [`symmetry::Group::isotropy`]) the kernel direction in Fix(Σ) is φ = Σ_a c_a x_a with c
//!    spanning Fix_{V_μ}(Σ) in the irrep's coordinates (§14.2);
//! 2. in Fix(Σ) the point is a simple bifurcation of the path; the reduced equation along φ,
//!    g(a, s) = a (b s + ½ C₃ a + …), gives the branch's tangent: (φ, 0) for a pitchfork
//!    (C₃ = 0 by symmetry: −v conjugate to v, or no invariant cubic), φ + κ t_path with
//!    κ = −C₃/(2b) for a transcritical one (§14.3);
//! 3. the branch is followed by the pseudo-arclength driver in Fix(Σ) from the critical point
//!    along that tangent (both halves when ±v are not conjugate), its index by the irreps of
//!    Σ at every point, its critical points localised and classified in Σ (§14.4).
//!
//! Limit points (the trivial irrep) have no branches; a simple point in a 1-D irrep has one
//! axial subgroup, the irrep's kernel. A split pair of simple points is two such points, each
//! switched on its own. Complex-type irreps (chiral groups) have no axial subgroup and are
//! refused.
//!
//! The result is a graph ([`BranchGraph`], petgraph): nodes are critical points (of the path
//! and of the branches) and the ends of branches, edges are branches.

use super::mesh::MeshStudy;
use super::normal_form::{normal_form, observe};
use super::{BranchOptions, Study, SymmetricProblem};
use crate::adapted::labels::isotropy;
use crate::adapted::{AdaptedBasis, SparseBasis};
use crate::continuation::crossings::{Crossings, IndexChanges};
use crate::continuation::events::trace;
use crate::continuation::events::{Detector, Event, MeasureFn, States};
use crate::continuation::{point_at, step_off, Continuation, PathOptions, PathPoint, Stalled};
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Layout, Model, Request};
use crate::results::{
    directory, Bifurcation, BranchGraph, BranchPoint, BranchRun, BranchTurning, Branches,
    Connection, CriticalKind, CriticalPoint, Half, Halves, Node, PathReport, PathRow,
    RecordedPoint, Reduced, Skip, State, StateKind, StopReason, SwitchedBranch, TurningRow,
    ASYMMETRY,
};
use crate::stability::{IrrepBlocks, Stability};
use meshes::GroupAction;
use nalgebra::DVector;
use petgraph::graph::NodeIndex;
use symmetry::{IrrepKind, SubgroupLattice};

/// Step along the parent path (scaled arclength) for the derivative of the critical
/// eigenvalue, b.
const PATH_DELTA: f64 = 1e-4;
/// Amplitude along the kernel direction (in units of the state scale) for C₃.
const MODE_DELTA: f64 = 1e-4;
/// |φᵀK(u + hφ)φ − φᵀK(u − hφ)φ| / ‖K‖ above which a quadratic coefficient that symmetry
/// allows counts as non-zero (round-off of the difference is about 1e-14).
const QUADRATIC_ZERO: f64 = 1e-9;
/// |b| / ‖K‖ below which the critical eigenvalue does not cross transversally.
const TRANSVERSAL_ZERO: f64 = 1e-10;
/// |eigenvalue|/‖K‖ that counts as zero where a crossing is localised: a critical
/// eigenvalue whose rate along the path moves it by less than this over the longest step
/// does not cross transversally.
const CROSSING_ZERO: f64 = crate::continuation::crossings::ZERO_EIGENVALUE;
/// Tolerance of the checks that a kernel direction is what the representation theory says.
const DIRECTION_TOL: f64 = 1e-6;
/// Two critical points are one (up to symmetry) when their controls and a group image of
/// one state and the other differ by at most this, relative to the path's scales (their
/// localisation is to 10⁻¹⁰ of the arclength).
const SAME_POINT: f64 = 1e-6;
/// A branch leaves a point along a known branch's direction when the cosine of the two is
/// above this (the known branch's points next to the point are a step away, so its chord
/// is not its tangent).
const SAME_DIRECTION: f64 = 0.9;

/// An event along a branch in step order: the step before it, which (`Ok(k)` its k-th
/// critical point, `Err(k)` its k-th turning point), its state and its parameters.
type Reach<'a> = (usize, Result<usize, usize>, &'a [f64], &'a [f64]);

/// A group acting on the model, with what switching at a critical point of a path in its
/// fixed-point space needs: the fixed-point basis, the symmetry-adapted basis (for stability
/// by its irreps), its subgroup lattice, and where its elements are in the scene's group.
pub struct Level {
    /// The group's action on the mesh.
    pub action: GroupAction,
    /// An orthonormal basis of Fix(group).
    pub basis: SparseBasis,
    /// The adapted basis, or why there is none (a complex-type irrep).
    pub adapted: Result<AdaptedBasis, String>,
    /// The group's subgroups up to conjugacy.
    pub lattice: SubgroupLattice,
    /// Element i of this group is element `top_index[i]` of the scene's group.
    pub top_index: Vec<usize>,
}

impl Level {
    /// The level of `action`'s group on `layout`; `top_index` places its elements in the
    /// scene's group.
    pub fn new(action: GroupAction, layout: &Layout, top_index: Vec<usize>) -> Self {
        let basis = SparseBasis::fixed_point(&action, layout);
        let adapted = AdaptedBasis::new(&action, layout).map_err(|e| e.to_string());
        let lattice = action.group().subgroup_lattice();
        Self {
            action,
            basis,
            adapted,
            lattice,
            top_index,
        }
    }

    /// The part of `u` outside Fix(group): u less its orthogonal projection on Fix(group).
    pub fn asymmetric_part(&self, u: &[f64]) -> Vec<f64> {
        let mut sym = vec![0.0; u.len()];
        self.basis.expand(&self.basis.restrict(u), &mut sym);
        u.iter().zip(&sym).map(|(v, s)| v - s).collect()
    }

    /// The scene's group itself.
    pub fn top(action: &GroupAction, layout: &Layout) -> Self {
        let n = action.group().order();
        Self::new(action.clone(), layout, (0..n).collect())
    }
}

/// A direction of the kernel along which the branching lemma predicts a branch.
#[derive(Debug, Clone)]
pub struct Direction {
    /// The axial isotropy subgroup Σ (sorted element indices of the level's group).
    pub elements: Vec<usize>,
    /// Its class name in the level's lattice.
    pub class: String,
    /// The unit vector spanning Fix_{V_μ}(Σ), in the irrep's coordinates.
    pub coefficients: DVector<f64>,
    /// φ = Σ_a c_a x_a over the unknowns (unit norm).
    pub field: Vec<f64>,
    /// Whether ±φ are conjugate.
    pub halves: Halves,
    /// Whether symmetry lets the quadratic coefficient be non-zero (an invariant cubic exists
    /// and ±φ are not conjugate).
    pub quadratic_allowed: bool,
}

/// What branch switching needs of the problem: the model and its constraints, the measures
/// of a state, the control, the scene's group and the options.
pub struct Switching<'a> {
    /// The model.
    pub model: &'a dyn Model,
    /// The active constraints.
    pub constraints: &'a [Box<dyn Constraint>],
    /// The measures of a state (critical points along branches carry them).
    pub measure: MeasureFn<'a>,
    /// The control parameter.
    pub control: Option<usize>,
    /// The scene's group.
    pub top: &'a Level,
    /// Depth, steps, continuation.
    pub options: BranchOptions,
}

/// T(g) u: (T(g) u)_{π_g(i)} = R_g u_i.
fn act(action: &GroupAction, layout: &Layout, g: usize, u: &[f64]) -> Vec<f64> {
    let r = action.group().element(g);
    let perm = action.node_perm(g);
    let mut out = vec![0.0; u.len()];
    for (i, &j) in perm.iter().enumerate().take(layout.nodes()) {
        let (Some(di), Some(dj)) = (layout.dof(i, 0), layout.dof(j, 0)) else {
            continue;
        };
        let v = r * nalgebra::Vector3::new(u[di], u[di + 1], u[di + 2]);
        out[dj..dj + 3].copy_from_slice(v.as_slice());
    }
    out
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The partners x_a = P_{a0} x_0 = (d/|G|) Σ_g D_{a0}(g) T(g) x_0 of a mode x_0 of the first
/// partner of irrep `irrep` (docs/theory.md §14.2); x_0 itself first.
pub fn partners(
    action: &GroupAction,
    layout: &Layout,
    irrep: &symmetry::Irrep,
    mode: &[f64],
) -> Vec<Vec<f64>> {
    let group = action.group();
    let d = irrep.dim();
    let mut out = vec![vec![0.0; mode.len()]; d];
    for g in 0..group.order() {
        let moved = act(action, layout, g, mode);
        let m = irrep.matrix(g);
        for (a, x) in out.iter_mut().enumerate() {
            let w = m[(a, 0)];
            if w != 0.0 {
                x.iter_mut().zip(&moved).for_each(|(x, y)| *x += w * y);
            }
        }
    }
    let scale = d as f64 / group.order() as f64;
    out.iter_mut()
        .for_each(|x| x.iter_mut().for_each(|v| *v *= scale));
    out
}

/// The kernel directions of a critical point of a path in Fix(level's group), one per
/// conjugacy class of axial isotropy subgroups of its irrep (docs/theory.md §14.1–14.2); or
/// why there are none.
pub fn kernel_directions(
    level: &Level,
    layout: &Layout,
    cp: &CriticalPoint,
) -> Result<Vec<Direction>, Skip> {
    let group = level.action.group();
    let irrep = group
        .irrep(&cp.irrep)
        .ok_or_else(|| Skip::Failed(format!("{} has no irrep {}", group.name(), cp.irrep)))?;
    if irrep.is_trivial() || matches!(cp.kind, CriticalKind::LimitPoint) {
        return Err(Skip::LimitPoint);
    }
    if irrep.kind() != IrrepKind::Real {
        return Err(Skip::ComplexIrrep(cp.irrep.clone()));
    }
    let iso = group
        .isotropy(&level.lattice, irrep)
        .map_err(|e| Skip::Failed(e.to_string()))?;
    let x = partners(&level.action, layout, irrep, &cp.mode);
    // x_0 must be the first partner's vector (P_00 x_0 = x_0) and the partners orthonormal.
    let x0_err = norm(
        &x[0]
            .iter()
            .zip(&cp.mode)
            .map(|(a, b)| a - b)
            .collect::<Vec<_>>(),
    );
    if x0_err > DIRECTION_TOL * norm(&cp.mode).max(1e-300) {
        return Err(Skip::Failed(format!(
            "the mode is not in the first partner of {} (|P x - x| = {x0_err:.1e})",
            cp.irrep
        )));
    }
    let cubic = group.invariant_cubics(irrep) > 0;
    let mut dirs = Vec::new();
    for s in iso.axial() {
        let c = s.axis().expect("axial");
        let mut field = vec![0.0; cp.mode.len()];
        for (a, xa) in x.iter().enumerate() {
            field.iter_mut().zip(xa).for_each(|(f, v)| *f += c[a] * v);
        }
        let n = norm(&field);
        if (n - 1.0).abs() > DIRECTION_TOL {
            return Err(Skip::Failed(format!(
                "the kernel direction of {} in {} has norm {n}, not 1",
                s.name, cp.irrep
            )));
        }
        field.iter_mut().for_each(|v| *v /= n);
        // φ is fixed by Σ and by nothing else of the group.
        for g in 0..group.order() {
            let moved = act(&level.action, layout, g, &field);
            let err = norm(
                &moved
                    .iter()
                    .zip(&field)
                    .map(|(a, b)| a - b)
                    .collect::<Vec<_>>(),
            );
            if (err <= DIRECTION_TOL) != s.elements.contains(&g) {
                return Err(Skip::Failed(format!(
                    "the kernel direction of {} in {}: element {g} {} it",
                    s.name,
                    cp.irrep,
                    if err <= DIRECTION_TOL {
                        "fixes"
                    } else {
                        "does not fix"
                    }
                )));
            }
        }
        dirs.push(Direction {
            elements: s.elements.clone(),
            class: s.name.clone(),
            coefficients: c,
            field,
            halves: if s.halves_conjugate() {
                Halves::Conjugate
            } else {
                Halves::Distinct
            },
            quadratic_allowed: cubic && !s.halves_conjugate(),
        });
    }
    if dirs.is_empty() {
        return Err(Skip::NoAxialSubgroup(cp.irrep.clone()));
    }
    Ok(dirs)
}

/// φᵀ K φ at (u, params), and ‖K‖ = max |K_ij|.
fn quadratic_form(
    model: &dyn Model,
    eval: &mut Evaluation,
    u: &[f64],
    params: &[f64],
    phi: &[f64],
) -> Result<(f64, f64), crate::model::ModelError> {
    model.evaluate(u, params, Request::ALL, eval)?;
    let mut y = vec![0.0; phi.len()];
    model.pattern().matvec(&eval.tangent, phi, &mut y);
    let mut q: f64 = y.iter().zip(phi).map(|(a, b)| a * b).sum();
    let mut scale = eval.tangent.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (c, a) in &eval.rank_one {
        let d: f64 = a.iter().zip(phi).map(|(x, y)| x * y).sum();
        q += c * d * d;
        scale = scale.max(c.abs() * a.iter().fold(0.0f64, |m, v| m.max(v * v)));
    }
    Ok((q, scale.max(1e-300)))
}

impl Switching<'_> {
    /// Switches at every requested critical point of the path (`critical`, in the order
    /// found) and, to the options' depth, at the critical points of the branches.
    pub fn run(&self, critical: &[CriticalPoint]) -> BranchGraph {
        let mut g = BranchGraph::default();
        // Every point of the path first, so that a branch reaching one of them is known to
        // connect to it.
        let nodes: Vec<NodeIndex> = critical
            .iter()
            .enumerate()
            .map(|(k, cp)| {
                g.graph.add_node(Node::Critical {
                    on: None,
                    number: k + 1,
                    point: Box::new(cp.clone()),
                    skipped: None,
                })
            })
            .collect();
        for (k, cp) in critical.iter().enumerate() {
            let node = nodes[k];
            let requested = self
                .options
                .points
                .as_ref()
                .is_none_or(|p| p.contains(&(k + 1)));
            if !requested {
                set_skip(&mut g, node, Skip::NotRequested);
                continue;
            }
            self.switch_at(self.top, None, node, cp, 1, 1.0, &mut g);
        }
        self.late_connections(&mut g);
        self.meetings(&mut g);
        g
    }

    /// A branch followed before the point at its other end was known (depth first, the
    /// point lies on a branch switched later) is ended there now, as [`Self::connect`] would
    /// have ended it ([`Self::reached_known`]): the branch followed from that point is the
    /// same branch from its other end. Its points beyond are dropped, and its critical
    /// points there with them — unless a branch was followed from one of those, when it is
    /// left whole.
    fn late_connections(&self, g: &mut BranchGraph) {
        for i in 0..g.branches.len() {
            if matches!(
                g.branches[i].stop,
                StopReason::Connected { .. } | StopReason::Rejoined { .. }
            ) {
                continue;
            }
            let own: Vec<NodeIndex> = g
                .graph
                .node_indices()
                .filter(|&n| matches!(g.graph[n], Node::Critical { on: Some(k), .. } if k == i))
                .collect();
            let mut except = own.clone();
            except.push(g.branches[i].from);
            let mut b = g.branches[i].clone();
            let same = self.connect_except(g, &mut b, &except, false);
            let Some(to) = same.last().copied().flatten() else {
                continue;
            };
            let kept = b.critical.len();
            let dropped: Vec<NodeIndex> = own
                .iter()
                .copied()
                .filter(|&n| matches!(g.graph[n], Node::Critical { number, .. } if number >= kept))
                .collect();
            if dropped.iter().any(|&n| g.graph.edges(n).next().is_some()) {
                continue;
            }
            // The point itself: its node when it is one of the branch's critical points
            // (number `kept`), else a new node.
            let reused = g.branches[i]
                .critical
                .get(kept - 1)
                .is_some_and(|c| c.state == b.critical[kept - 1].state);
            let at = own.iter().copied().find(|&n| {
                reused && matches!(g.graph[n], Node::Critical { number, .. } if number == kept)
            });
            let mut dropped: Vec<NodeIndex> =
                dropped.into_iter().filter(|&n| Some(n) != at).collect();
            dropped.sort_unstable_by(|a, b| b.cmp(a));
            let mut to = to;
            let mut at = at;
            for n in dropped {
                let last = NodeIndex::new(g.graph.node_count() - 1);
                g.graph.remove_node(n);
                let moved = |x: &mut NodeIndex| {
                    if *x == last {
                        *x = n;
                    }
                };
                for br in &mut g.branches {
                    moved(&mut br.from);
                }
                for c in &mut g.connections {
                    moved(&mut c.at);
                    moved(&mut c.to);
                }
                moved(&mut to);
                if let Some(a) = at.as_mut() {
                    moved(a);
                }
                moved(&mut b.from);
            }
            let point = b.critical[kept - 1].clone();
            let at = at.unwrap_or_else(|| {
                g.graph.add_node(Node::Critical {
                    on: Some(i),
                    number: kept,
                    point: Box::new(point),
                    skipped: None,
                })
            });
            if let Node::Critical { on, number, .. } = g.graph[to] {
                set_skip(g, at, Skip::Connection { on, number });
            }
            g.connections.push(Connection { branch: i, at, to });
            for n in g.graph.node_indices() {
                if let Node::End { branch, stop } = &mut g.graph[n] {
                    if *branch == i {
                        *stop = b.stop.clone();
                    }
                }
            }
            g.branches[i] = b;
        }
    }

    /// Every branch that stalled within one longest step (scaled arclength) of a state of
    /// another branch of its isotropy class, up to the scene's symmetry, ends as
    /// [`StopReason::Met`]: the two branches, followed from different points, meet there
    /// (a branch followed from both of its ends). The halves of one point are not compared
    /// (they share their first state), nor a branch that did not leave its point.
    fn meetings(&self, g: &mut BranchGraph) {
        let Some(control) = self.control else {
            return;
        };
        let opts = &self.options.path;
        let layout = self.model.layout();
        let order = self.top.action.group().order();
        let reach = opts.max_step;
        let mut met = Vec::new();
        for (i, b) in g.branches.iter().enumerate() {
            let StopReason::Stalled(stalled) = &b.stop else {
                continue;
            };
            if b.points.len() < 2 {
                continue;
            }
            let last = &b.points[b.points.len() - 1];
            let images: Vec<Vec<f64>> = (0..order)
                .map(|e| act(&self.top.action, layout, e, &last.u))
                .collect();
            let mut best: Option<(usize, usize, f64)> = None;
            for (j, other) in g.branches.iter().enumerate() {
                if j == i || other.from == b.from || other.isotropy != b.isotropy {
                    continue;
                }
                for (k, p) in other.points.iter().enumerate() {
                    let dl = (p.parameters[control] - last.parameters[control]).abs()
                        / opts.parameter_scale(0);
                    if dl > reach {
                        continue;
                    }
                    let d = nearest_image(&images, &p.u, opts.state_scale).hypot(dl);
                    if d <= reach && best.is_none_or(|(_, _, e)| d < e) {
                        best = Some((j, k, d));
                    }
                }
            }
            if let Some((j, point, distance)) = best {
                met.push((i, stalled.clone(), j, point, distance));
            }
        }
        for (i, stalled, j, point, distance) in met {
            let stop = StopReason::Met {
                stalled,
                branch: directory(j),
                point,
                distance,
            };
            for n in g.graph.node_indices() {
                if let Node::End { branch, stop: s } = &mut g.graph[n] {
                    if *branch == i {
                        *s = stop.clone();
                    }
                }
            }
            g.branches[i].stop = stop;
        }
    }

    /// The scaled distance (state and control, as the path's steps measure it) from `cp` to
    /// the critical point that the branch `parent` left; `None` on the path.
    fn distance_to_origin(
        &self,
        g: &BranchGraph,
        parent: Option<usize>,
        cp: &CriticalPoint,
    ) -> Option<f64> {
        let control = self.control?;
        let Node::Critical { point, .. } = &g.graph[g.branches[parent?].from] else {
            return None;
        };
        let opts = &self.options.path;
        let dl =
            (cp.parameters[control] - point.parameters[control]).abs() / opts.parameter_scale(0);
        Some(
            nearest_image(
                std::slice::from_ref(&point.state),
                &cp.state,
                opts.state_scale,
            )
            .hypot(dl),
        )
    }

    /// Switches at `cp`, a critical point of a path in Fix(level's group) (the branch
    /// `parent`, or the path), and follows every branch; recurses while `depth` is within
    /// the options' depth.
    #[allow(clippy::too_many_arguments)]
    fn switch_at(
        &self,
        level: &Level,
        parent: Option<usize>,
        node: NodeIndex,
        cp: &CriticalPoint,
        depth: usize,
        sign: f64,
        g: &mut BranchGraph,
    ) {
        if cp.residual_eigenvalue > crate::results::validity::LOCALISED {
            set_skip(g, node, Skip::Jump(cp.residual_eigenvalue));
            return;
        }
        let layout = self.model.layout();
        let dirs = match kernel_directions(level, layout, cp) {
            Ok(d) => d,
            Err(skip) => {
                set_skip(g, node, skip);
                return;
            }
        };
        let mut known = Vec::new();
        for dir in &dirs {
            let t0 = std::time::Instant::now();
            let group = level.action.group();
            let child = match group
                .subgroup(&dir.elements)
                .map_err(|e| e.to_string())
                .and_then(|sub| {
                    let action = level.action.restrict_to(&sub).map_err(|e| e.to_string())?;
                    let top_index = sub
                        .parent_index
                        .iter()
                        .map(|&i| level.top_index[i])
                        .collect();
                    Ok(Level::new(action, layout, top_index))
                }) {
                Ok(c) => c,
                Err(e) => {
                    set_skip(
                        g,
                        node,
                        Skip::Failed(format!("isotropy subgroup {}: {e}", dir.class)),
                    );
                    continue;
                }
            };
            let reduced = match self.reduced(level, cp, dir) {
                Ok(r) => r,
                Err(e) => {
                    set_skip(g, node, Skip::Failed(e));
                    continue;
                }
            };
            // On a branch: an eigenvalue whose rate here, over the distance back to the point
            // the branch left, moves it by less than what counts as zero has not left zero
            // since that point. It is the rest of that point's kernel, leaving zero to high
            // order along the branch (the other half of a double point), whose sign is
            // round-off over the branch's first steps: not a critical point of its own.
            if let Some(distance) = self.distance_to_origin(g, parent, cp) {
                if reduced.path_slope.abs() * distance < CROSSING_ZERO {
                    set_skip(
                        g,
                        node,
                        Skip::AtOrigin {
                            rate: reduced.path_slope,
                            distance,
                        },
                    );
                    continue;
                }
            }
            // Transversality (the lemma's hypothesis): over the longest step the eigenvalue
            // must move by more than what the localisation counts as zero.
            if reduced.path_slope.abs() * self.options.path.max_step < CROSSING_ZERO {
                set_skip(g, node, Skip::NotTransversal(reduced.path_slope));
                continue;
            }
            let halves = match dir.halves {
                Halves::Conjugate => vec![Half::Plus],
                Halves::Distinct => vec![Half::Plus, Half::Minus],
            };
            let class = self.class_of(&child);
            // The set-up (Σ's action and bases, the reduced equation) is shared by the halves.
            let setup = t0.elapsed() / halves.len() as u32;
            for half in halves {
                // A half along which a branch of the same class already passed through this
                // point (up to symmetry, an earlier half's included) is that branch.
                if let Some(b) = self.known_half(g, node, cp, &class, &dir.field, half) {
                    known.push(b);
                    continue;
                }
                // A branch of this class followed earlier from another point that reaches this
                // one within a step (its other end, resolved to its step): where the halves are
                // group images of each other, the one half here is that branch (§14.8). It is
                // cut here after all switching ([`Self::late_connections`]).
                if matches!(dir.halves, Halves::Conjugate) {
                    if let Some(b) = self.reaching(g, node, &class) {
                        known.push(b);
                        continue;
                    }
                }
                let t1 = std::time::Instant::now();
                let mut branch = self.follow(level, &child, cp, dir, &reduced, half);
                branch.from = node;
                branch.parent = parent;
                let same = self.connect(g, &mut branch);
                branch.sign = sign * half.sign();
                branch.time = setup + t1.elapsed();
                let id = g.branches.len();
                let end = g.graph.add_node(Node::End {
                    branch: id,
                    stop: branch.stop.clone(),
                });
                g.graph.add_edge(node, end, id);
                let found: Vec<CriticalPoint> = branch.critical.clone();
                let branch_sign = branch.sign;
                g.branches.push(branch);
                for (k, c) in found.iter().enumerate() {
                    let same = same.get(k).copied().flatten();
                    let n = g.graph.add_node(Node::Critical {
                        on: Some(id),
                        number: k + 1,
                        point: Box::new(c.clone()),
                        skipped: None,
                    });
                    if let Some(to) = same {
                        if let Node::Critical { on, number, .. } = g.graph[to] {
                            set_skip(g, n, Skip::Connection { on, number });
                        }
                        g.connections.push(Connection {
                            branch: id,
                            at: n,
                            to,
                        });
                    } else if depth < self.options.depth {
                        self.switch_at(&child, Some(id), n, c, depth + 1, branch_sign, g);
                    } else if c.kind == CriticalKind::LimitPoint {
                        set_skip(g, n, Skip::LimitPoint);
                    } else {
                        set_skip(g, n, Skip::Depth);
                    }
                }
            }
        }
        if !known.is_empty() {
            known.dedup();
            set_skip(g, node, Skip::Known(known));
        }
    }

    /// Ends `branch` at its first critical point that is one already in the graph (up to
    /// symmetry): past it the branch would retrace what is known (the path, or a branch
    /// through that point). Its points up to the crossing, then the point itself; its
    /// critical points there (every block singular at it) kept, the later ones dropped.
    /// Returns, for each critical point kept, the known point it is.
    fn connect(&self, g: &BranchGraph, branch: &mut SwitchedBranch) -> Vec<Option<NodeIndex>> {
        self.connect_except(g, branch, &[branch.from], true)
    }

    /// As [`Self::connect`], the nodes `except` not counted as known (the point the branch
    /// left, and its own points when it is already in the graph); with `strict`, the
    /// identity check of its critical points and the return to its parent first.
    fn connect_except(
        &self,
        g: &BranchGraph,
        branch: &mut SwitchedBranch,
        except: &[NodeIndex],
        strict: bool,
    ) -> Vec<Option<NodeIndex>> {
        let order = branch.elements.len();
        let mut same: Vec<Option<NodeIndex>> = Vec::new();
        for c in branch.critical.iter().filter(|_| strict) {
            let known = self.same_as(g, c, order);
            // The first connection ends the branch, with its other blocks singular there.
            if same
                .iter()
                .flatten()
                .next()
                .is_some_and(|&to| known != Some(to))
            {
                break;
            }
            same.push(known);
        }
        if strict && !same.iter().any(Option::is_some) {
            if let Some(to) = self.rejoined_at(g, branch) {
                // The branch ends on the known point it returned to: its junction with the
                // path it left, a closed circuit.
                if let Node::Critical { point, .. } = &g.graph[to] {
                    let mut c = (**point).clone();
                    c.after_step = branch.points.len() - 1;
                    branch.critical.push(c);
                    same.push(Some(to));
                }
            }
        }
        let mut near = None;
        if !same.iter().any(Option::is_some) {
            if let Some((which, to, distance)) = self.reached_known(g, branch, except) {
                // The branch reaches a known point of a path at least as symmetric, to its
                // own resolution: the pitchfork where it meets that path, seen from the
                // branch as a crossing or a fold of its control near the point. Beyond it
                // the branch would retrace a group image of a known branch; it ends there,
                // connected, its critical points before it kept.
                match which {
                    Ok(k) => {
                        branch.critical.truncate(k + 1);
                        same.truncate(k);
                        same.resize(k, None);
                        same.push(Some(to));
                        near = Some(("critical point", distance));
                    }
                    Err(t) => {
                        if let Node::Critical { point, .. } = &g.graph[to] {
                            let turning = &branch.turning[t];
                            let keep = branch
                                .critical
                                .iter()
                                .take_while(|c| c.after_step < turning.after_step)
                                .count();
                            branch.critical.truncate(keep);
                            same.truncate(keep);
                            same.resize(keep, None);
                            let mut c = (**point).clone();
                            c.after_step = turning.after_step;
                            c.state = turning.u.clone();
                            c.parameters = turning.parameters.clone();
                            branch.critical.push(c);
                            same.push(Some(to));
                            near = Some(("fold of its control", distance));
                        }
                    }
                }
            }
        }
        let Some(first) = same.iter().position(Option::is_some) else {
            return same;
        };
        let to = same[first].expect("a connection");
        branch.critical.truncate(same.len());
        let c = &branch.critical[first];
        let j = c.after_step.min(branch.points.len() - 1);
        let arclength = branch.points[j].arclength;
        branch.points.truncate(j + 1);
        let end = self.point(&c.state, &c.parameters, arclength, 0, None);
        branch.points.push(end);
        branch.turning.retain(|t| t.after_step < j);
        if let Node::Critical { on, number, .. } = &g.graph[to] {
            let returned = match (&branch.stop, near) {
                (StopReason::Rejoined { between, estimate }, _) => format!(
                    " (it returned to that path's states between {:.6} and {:.6}, its amplitude vanishing at about {estimate:.6})",
                    between[0], between[1]
                ),
                (_, Some((event, distance))) => format!(
                    " (at a {event} of its own, a group image of whose state lies {distance:.1e} from it in scaled arclength, within one step)"
                ),
                _ => String::new(),
            };
            branch.stop = StopReason::Connected {
                to: format!(
                    "critical point {number} of {}{returned}",
                    on.map_or_else(|| "the path".to_string(), directory)
                ),
            };
        }
        same
    }

    /// The first critical point or turning point of the control along `branch` (by step)
    /// that lies within one longest step of a known critical point of a path at least as
    /// symmetric ([`Self::nearest_known`]), other than the point it left, from which a branch
    /// of `branch`'s isotropy class was followed: the pitchfork where it meets that branch
    /// followed from its other end, which `branch`, resolved to its step, sees as a crossing
    /// or a fold near the point. Returns the event (`Ok(k)` its k-th critical point, `Err(k)` its
    /// k-th turning point), the known node and their distance.
    fn reached_known(
        &self,
        g: &BranchGraph,
        branch: &SwitchedBranch,
        except: &[NodeIndex],
    ) -> Option<(Result<usize, usize>, NodeIndex, f64)> {
        self.first_near(g, branch, except)
            .filter(|&(_, n, _)| n != branch.from && leaves(g, n, &branch.isotropy))
    }

    /// The first event of `branch` (by step; a critical point or a turning point of the
    /// control) within one longest step of a known critical point other than those in
    /// `except` ([`Self::nearest_known`]), with that point and the distance.
    fn first_near(
        &self,
        g: &BranchGraph,
        branch: &SwitchedBranch,
        except: &[NodeIndex],
    ) -> Option<(Result<usize, usize>, NodeIndex, f64)> {
        let order = branch.elements.len();
        let mut events: Vec<Reach<'_>> = branch
            .critical
            .iter()
            .enumerate()
            .map(|(k, c)| {
                (
                    c.after_step,
                    Ok(k),
                    c.state.as_slice(),
                    c.parameters.as_slice(),
                )
            })
            .chain(branch.turning.iter().enumerate().map(|(k, t)| {
                (
                    t.after_step,
                    Err(k),
                    t.u.as_slice(),
                    t.parameters.as_slice(),
                )
            }))
            .collect();
        events.sort_by_key(|e| e.0);
        events.into_iter().find_map(|(_, which, u, params)| {
            self.nearest_known(g, u, params, order, except)
                .map(|(n, d)| (which, n, d))
        })
    }

    /// The branch of class `class`, followed earlier from another point and not yet ended,
    /// whose first event near a known point ([`Self::reached_known`]'s test) is `node`.
    fn reaching(&self, g: &BranchGraph, node: NodeIndex, class: &str) -> Option<usize> {
        let except: Vec<NodeIndex> = g.graph.node_indices().filter(|&n| n != node).collect();
        (0..g.branches.len()).find(|&i| {
            let b = &g.branches[i];
            b.isotropy == class
                && b.from != node
                && !matches!(
                    b.stop,
                    StopReason::Connected { .. } | StopReason::Rejoined { .. }
                )
                && self.first_near(g, b, &except).is_some()
        })
    }

    /// The known critical point nearest (u, params) up to the scene's group, other than those
    /// in `except`, on a path at least as symmetric as `order`, with its distance in scaled
    /// arclength (state over the state scale, control over its scale), if within one longest
    /// step.
    fn nearest_known(
        &self,
        g: &BranchGraph,
        u: &[f64],
        params: &[f64],
        order: usize,
        except: &[NodeIndex],
    ) -> Option<(NodeIndex, f64)> {
        let control = self.control?;
        let opts = &self.options.path;
        let layout = self.model.layout();
        let group = self.top.action.group().order();
        let reach = opts.max_step;
        let images: Vec<Vec<f64>> = (0..group)
            .map(|e| act(&self.top.action, layout, e, u))
            .collect();
        let mut best: Option<(NodeIndex, f64)> = None;
        for n in g.graph.node_indices() {
            if except.contains(&n) {
                continue;
            }
            let Node::Critical { point, on, .. } = &g.graph[n] else {
                continue;
            };
            if on.map_or(group, |k| g.branches[k].elements.len()) < order {
                continue;
            }
            let dl = (point.parameters[control] - params[control]).abs() / opts.parameter_scale(0);
            if dl > reach {
                continue;
            }
            let d = nearest_image(&images, &point.state, opts.state_scale).hypot(dl);
            if d <= reach && best.is_none_or(|(_, e)| d < e) {
                best = Some((n, d));
            }
        }
        best
    }

    /// The critical point of the path `branch` left that it returned to
    /// ([`StopReason::Rejoined`]): one of that path's with the irrep of the point the branch
    /// left, other than that point, within half a step of the control interval where it
    /// rejoined (the one nearest the estimate).
    fn rejoined_at(&self, g: &BranchGraph, branch: &SwitchedBranch) -> Option<NodeIndex> {
        let control = self.control?;
        let StopReason::Rejoined { between, estimate } = branch.stop else {
            return None;
        };
        let half = 0.5 * (between[1] - between[0]).abs();
        let (lo, hi) = (
            between[0].min(between[1]) - half,
            between[0].max(between[1]) + half,
        );
        g.graph
            .node_indices()
            .filter(|&n| n != branch.from)
            .filter_map(|n| match &g.graph[n] {
                Node::Critical { on, point, .. }
                    if *on == branch.parent && point.irrep == branch.irrep =>
                {
                    let x = point.parameters[control];
                    (lo..=hi).contains(&x).then_some((n, (x - estimate).abs()))
                }
                _ => None,
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(n, _)| n)
    }

    /// The class of a level's group in the scene group's lattice.
    fn class_of(&self, level: &Level) -> String {
        self.top
            .lattice
            .class_of(&level.top_index)
            .map(|c| self.top.lattice.classes()[c].name.clone())
            .unwrap_or_default()
    }

    /// The node of a critical point already in the graph that `c` is, up to the scene's
    /// symmetry: the same control and a state that is a group image of its state, both to
    /// [`SAME_POINT`] of the path's scales.
    ///
    /// Only points on paths at least as symmetric as `order` (the order of the isotropy of
    /// the branch `c` lies on) count: a branch crossing a point of a less symmetric one goes
    /// on into states nothing has followed.
    fn same_as(&self, g: &BranchGraph, c: &CriticalPoint, order: usize) -> Option<NodeIndex> {
        self.known_state(g, &c.state, &c.parameters, order, &[])
    }

    /// The node of a critical point already in the graph, other than those in `except`,
    /// whose control and state (up to the scene's group) are `params`' and `u`'s, both to
    /// [`SAME_POINT`] of the path's scales, on a path at least as symmetric as `order`.
    fn known_state(
        &self,
        g: &BranchGraph,
        u: &[f64],
        params: &[f64],
        order: usize,
        except: &[NodeIndex],
    ) -> Option<NodeIndex> {
        let control = self.control?;
        let opts = &self.options.path;
        let layout = self.model.layout();
        let group = self.top.action.group().order();
        g.graph.node_indices().find(|&n| {
            if except.contains(&n) {
                return false;
            }
            let Node::Critical { point, on, .. } = &g.graph[n] else {
                return false;
            };
            let symmetry = on.map_or(group, |k| g.branches[k].elements.len());
            if symmetry < order {
                return false;
            }
            let dl = (point.parameters[control] - params[control]).abs() / opts.parameter_scale(0);
            dl <= SAME_POINT
                && (0..group).any(|e| {
                    let image = act(&self.top.action, layout, e, u);
                    let d: f64 = image
                        .iter()
                        .zip(&point.state)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt();
                    d <= SAME_POINT * opts.state_scale
                })
        })
    }

    /// The branch already in the graph that the half `half` of the branch along `phi` from
    /// `cp` (at `node`) is, up to symmetry: one of the same isotropy class that passed
    /// through this point (a connection to it) leaving along the same direction — the
    /// non-symmetric part of its step next to the point within [`SAME_DIRECTION`] of a group
    /// image of ±φ.
    fn known_half(
        &self,
        g: &BranchGraph,
        node: NodeIndex,
        cp: &CriticalPoint,
        class: &str,
        phi: &[f64],
        half: Half,
    ) -> Option<usize> {
        let layout = self.model.layout();
        let top = self.top;
        let order = top.action.group().order();
        let along: Vec<f64> = phi.iter().map(|f| f * half.sign()).collect();
        g.connections
            .iter()
            .filter(|c| c.to == node && g.branches[c.branch].isotropy == class)
            .find_map(|c| {
                let b = &g.branches[c.branch];
                let Node::Critical { point, .. } = &g.graph[c.at] else {
                    return None;
                };
                // The branch's last points before the connection (it ends there): the
                // direction it arrived along, from the nearest one off the symmetric states
                // (a branch may be drawn onto the path in its last step).
                let j = point.after_step.min(b.points.len().saturating_sub(1));
                let floor = SAME_POINT * self.options.path.state_scale;
                let matches = (j.saturating_sub(2)..=j).rev().any(|k| {
                    let d: Vec<f64> = b.points[k]
                        .u
                        .iter()
                        .zip(&cp.state)
                        .map(|(a, b)| a - b)
                        .collect();
                    let asym = top.asymmetric_part(&d);
                    let n = norm(&asym);
                    n > floor
                        && (0..order).any(|e| {
                            let image = act(&top.action, layout, e, &along);
                            image.iter().zip(&asym).map(|(a, b)| a * b).sum::<f64>() / n
                                > SAME_DIRECTION
                        })
                });
                matches.then_some(c.branch)
            })
    }

    /// The reduced equation along `dir` at `cp` (docs/theory.md §14.3): b from φᵀKφ at the
    /// path's linear predictor ±δ, C₃ from φᵀKφ at u ± hφ (central differences, both
    /// exact to O(δ²)); C₃ = 0 exactly where symmetry forbids it.
    fn reduced(
        &self,
        level: &Level,
        cp: &CriticalPoint,
        dir: &Direction,
    ) -> Result<Reduced, String> {
        let tangent = self.path_tangent(level, cp)?;
        let opts = &self.options.path;
        let phi = &dir.field;
        let mut eval = self.model.new_evaluation();
        let problem = SymmetricProblem::new(
            self.model,
            &level.basis,
            self.constraints,
            cp.parameters.clone(),
            self.control,
        );
        let m = level.basis.dim();
        let lambda = problem.free_values(&cp.parameters);
        let mut at = |s: f64| -> Result<(f64, f64), String> {
            let q = level.basis.restrict(&cp.state) + tangent.rows(0, m) * (s * opts.state_scale);
            let mut l = lambda.clone();
            for j in 0..l.len() {
                l[j] += tangent[m + j] * s * opts.parameter_scale(j);
            }
            let u = problem.displacement(&q);
            let p = problem.parameters(&l);
            quadratic_form(self.model, &mut eval, &u, &p, phi).map_err(|e| e.to_string())
        };
        let (q_plus, scale) = at(PATH_DELTA)?;
        let (q_minus, _) = at(-PATH_DELTA)?;
        let b = (q_plus - q_minus) / (2.0 * PATH_DELTA);
        let h = MODE_DELTA * opts.state_scale;
        let shifted =
            |a: f64| -> Vec<f64> { cp.state.iter().zip(phi).map(|(u, f)| u + a * f).collect() };
        let mut eval2 = self.model.new_evaluation();
        let (c_plus, _) = quadratic_form(self.model, &mut eval2, &shifted(h), &cp.parameters, phi)
            .map_err(|e| e.to_string())?;
        let (c_minus, _) =
            quadratic_form(self.model, &mut eval2, &shifted(-h), &cp.parameters, phi)
                .map_err(|e| e.to_string())?;
        let c3 = (c_plus - c_minus) / (2.0 * h);
        let path_slope = b / scale;
        let quadratic = dir.quadratic_allowed && (c_plus - c_minus).abs() > QUADRATIC_ZERO * scale;
        let mode_slope = if quadratic {
            c3 * opts.state_scale / scale
        } else {
            0.0
        };
        let transversal = path_slope.abs() > TRANSVERSAL_ZERO;
        let path_per_amplitude = if quadratic && transversal {
            -mode_slope / (2.0 * path_slope)
        } else {
            0.0
        };
        Ok(Reduced {
            path_slope,
            mode_slope,
            bifurcation: if quadratic {
                Bifurcation::Transcritical
            } else {
                Bifurcation::Pitchfork
            },
            path_per_amplitude,
        })
    }

    /// The unit tangent (scaled variables) of the path in Fix(level's group) at `cp`, the
    /// control increasing (the critical point is a regular point of that path: its singular
    /// block is not the trivial one).
    fn path_tangent(&self, level: &Level, cp: &CriticalPoint) -> Result<DVector<f64>, String> {
        let mut problem = SymmetricProblem::new(
            self.model,
            &level.basis,
            self.constraints,
            cp.parameters.clone(),
            self.control,
        );
        let q = level.basis.restrict(&cp.state);
        let lambda = problem.free_values(&cp.parameters);
        let opts = PathOptions {
            direction: 1.0,
            ..self.options.path.clone()
        };
        point_at(&mut problem, q, lambda, 0, &opts, None)
            .map(|p| p.tangent)
            .map_err(|e| format!("the path's tangent at the critical point: {e}"))
    }

    /// The unit tangent of the branch at the critical point in Fix(Σ) (scaled variables,
    /// q/σ and λ): per unit scaled amplitude A = a/σ along φ the branch moves by ds/dA along
    /// the path's unit tangent t_path, so the direction is (φ + (ds/dA) t_q, (ds/dA) t_λ),
    /// normalised — (φ, 0) for a pitchfork — on the given half.
    fn branch_tangent(
        &self,
        level: &Level,
        child: &Level,
        cp: &CriticalPoint,
        dir: &Direction,
        reduced: &Reduced,
        half: Half,
    ) -> Result<DVector<f64>, String> {
        let m = child.basis.dim();
        let nf = self.constraints.len() + 1;
        let mut t = DVector::zeros(m + nf);
        t.rows_mut(0, m)
            .copy_from(&child.basis.restrict(&dir.field));
        let k = reduced.path_per_amplitude;
        if k != 0.0 {
            let tp = self.path_tangent(level, cp)?;
            let mp = level.basis.dim();
            let mut up = vec![0.0; level.basis.unknowns()];
            level.basis.expand(&tp.rows(0, mp).into_owned(), &mut up);
            let mut tq = t.rows(0, m).into_owned();
            tq += child.basis.restrict(&up) * k;
            t.rows_mut(0, m).copy_from(&tq);
            for j in 0..nf {
                t[m + j] = k * tp[mp + j];
            }
        }
        let n = t.norm();
        if n == 0.0 || !n.is_finite() {
            return Err("the branch direction is zero in Fix(Σ)".into());
        }
        Ok(t * (half.sign() / n))
    }

    /// Follows one half of the branch along `dir` from `cp`.
    fn follow(
        &self,
        level: &Level,
        child: &Level,
        cp: &CriticalPoint,
        dir: &Direction,
        reduced: &Reduced,
        half: Half,
    ) -> SwitchedBranch {
        let class_top = self
            .top
            .lattice
            .class_of(&child.top_index)
            .map(|c| self.top.lattice.classes()[c].name.clone())
            .unwrap_or_else(|| dir.class.clone());
        let mut elements = child.top_index.clone();
        elements.sort_unstable();
        let mut branch = SwitchedBranch {
            from: NodeIndex::new(0),
            parent: None,
            irrep: cp.irrep.clone(),
            isotropy: class_top,
            elements,
            class_in_parent: dir.class.clone(),
            half,
            halves: dir.halves,
            reduced: *reduced,
            normal_form: None,
            symmetric_unknowns: child.basis.dim(),
            points: vec![self.point(&cp.state, &cp.parameters, 0.0, 0, None)],
            turning: Vec::new(),
            critical: Vec::new(),
            stop: StopReason::Condition,
            stability_note: child
                .adapted
                .as_ref()
                .err()
                .map(|e| format!("stability not analysed: {e}")),
            warnings: Vec::new(),
            sign: half.sign(),
            time: std::time::Duration::ZERO,
        };
        let tangent = match self.branch_tangent(level, child, cp, dir, reduced, half) {
            Ok(t) => t,
            Err(e) => {
                branch.warnings.push(e);
                return branch;
            }
        };
        let mut problem = SymmetricProblem::new(
            self.model,
            &child.basis,
            self.constraints,
            cp.parameters.clone(),
            self.control,
        )
        .holding_neutral();
        let start = PathPoint {
            q: child.basis.restrict(&cp.state),
            lambda: problem.free_values(&cp.parameters),
            arclength: 0.0,
            iterations: 0,
            tangent: tangent.clone(),
        };
        // The first step leaves the critical point on the plane of fixed amplitude along φ
        // (§14.4), which the parent path does not meet; it is taken before any detector sees
        // a point: the singular block at the critical point is not a crossing of the branch.
        let m = child.basis.dim();
        let mut plane = DVector::zeros(tangent.len());
        plane
            .rows_mut(0, m)
            .copy_from(&(child.basis.restrict(&dir.field) * half.sign()));
        let opts = &self.options.path;
        if self.control.is_some() {
            match normal_form(
                &mut problem,
                &start,
                &tangent,
                &plane,
                &child.basis.restrict(&dir.field),
                reduced,
                opts,
            ) {
                Ok(nf) => branch.normal_form = Some(nf),
                Err(e) => branch.warnings.push(format!("no normal form: {e}")),
            }
        }
        let mut s = opts.initial_step;
        let first = loop {
            match step_off(&mut problem, &start, &tangent, &plane, s, opts) {
                Ok(p) => break p,
                Err(why) => {
                    s *= 0.5;
                    if s < opts.min_step {
                        branch.stop = StopReason::Stalled(
                            Stalled {
                                min_step: opts.min_step,
                                after: 0,
                                control: self.control.map_or(0.0, |c| cp.parameters[c]),
                                why,
                                bound: None,
                            }
                            .into(),
                        );
                        return branch;
                    }
                }
            }
        };
        let mut driver = Continuation::new(problem, first, self.options.path.clone());
        let crossings = child.adapted.as_ref().ok().map(|adapted| {
            Crossings::new(
                Box::new(IrrepBlocks::new(
                    Stability::new(self.model, adapted),
                    self.model,
                    self.constraints,
                    &child.action,
                )),
                self.measure,
                self.control,
                false,
            )
        });
        let index = crossings.map(IndexChanges::new);
        follow_branch(
            &mut driver,
            index,
            self.options.steps,
            &mut branch,
            |u, params, arclength, iterations, index| {
                self.point(u, params, arclength, iterations, index)
            },
        );
        if let Some(note) = held_note(driver.problem_mut(), &child.basis, &branch, opts) {
            branch.warnings.push(note);
        }
        if let Some(c) = self.control {
            observe(&mut branch, c, &dir.field, opts.state_scale);
        }
        if let Some(c) = self.control {
            rejoin(&mut branch, c, level.top_index.len());
        }
        if let Some(bad) = branch.points[1..]
            .iter()
            .position(|p| p.stabiliser != branch.elements)
        {
            branch.warnings.push(format!(
                "point {} of the branch has the stabiliser {} (order {}), not its isotropy subgroup {}",
                bad + 1,
                branch.points[bad + 1].stabiliser_class,
                branch.points[bad + 1].stabiliser.len(),
                branch.isotropy
            ));
        }
        branch
    }

    /// A branch point: its asymmetry and stabiliser in the scene's group.
    fn point(
        &self,
        u: &[f64],
        params: &[f64],
        arclength: f64,
        iterations: usize,
        index: Option<usize>,
    ) -> BranchPoint {
        let layout = self.model.layout();
        let top = self.top;
        let free = (0..layout.nodes())
            .filter(|&i| layout.dof(i, 0).is_some())
            .count()
            .max(1);
        let asym = norm(&top.asymmetric_part(u)) / (free as f64).sqrt();
        let stab = isotropy(&top.action, layout, u);
        let stabiliser_class = top
            .lattice
            .class_of(&stab.elements)
            .map(|c| top.lattice.classes()[c].name.clone())
            .unwrap_or(stab.name);
        BranchPoint {
            u: u.to_vec(),
            parameters: params.to_vec(),
            arclength,
            iterations,
            index,
            asymmetry: asym,
            stabiliser: stab.elements,
            stabiliser_class,
        }
    }
}

/// What a branch holds beyond the rigid motions (the model's held motions in its
/// fixed-point space: a drift across a spin axis, docs/theory.md §7.9), and the largest force
/// that holds them along its points relative to the residual's scale — an axle's force: the
/// branch is an equilibrium of the held body, as the stability blocks read every state.
/// `None` when it holds nothing more.
fn held_note(
    problem: &mut SymmetricProblem,
    basis: &crate::adapted::SparseBasis,
    branch: &SwitchedBranch,
    opts: &PathOptions,
) -> Option<String> {
    let extra = problem.held_beyond_rigid();
    if extra == 0 {
        return None;
    }
    let sigma = opts.parameter_scales.first().copied().unwrap_or(1.0);
    let force = branch
        .points
        .iter()
        .filter_map(|p| {
            let q = basis.restrict(&p.u);
            let lambda = problem.free_values(&p.parameters);
            problem
                .held_force(&q, &lambda, opts.state_scale, sigma)?
                .ok()
        })
        .fold(0.0, f64::max);
    Some(format!(
        "the branch holds {extra} neutral motion{} of the model in its fixed-point space (a \
         drift across the spin axis), as the stability analysis does: its states are \
         equilibria of the held body, with a holding force up to {} of the residual's scale",
        if extra == 1 { "" } else { "s" },
        crate::text::sig_digits(force, 3)
    ))
}

/// Ends `branch` where it returns to the states of the path it left (the stabiliser of its
/// states grows back to the parent's group, of order `parent_order`, with its asymmetry
/// going to zero): a branch that leaves its parent at one bifurcation point and rejoins it
/// at another, a closed circuit (docs/theory.md §16.7). Its points and findings up to the
/// last state off the parent are kept; its stop says where it rejoined — the control
/// between that state and the first one back on the parent, and the estimate where the
/// amplitude's law (A² linear in the control at a pitchfork, A at a transcritical point)
/// through its last two states off the parent reaches zero.
fn rejoin(branch: &mut SwitchedBranch, control: usize, parent_order: usize) {
    let own = branch.elements.len();
    let Some(k) = branch.points.iter().skip(2).position(|p| {
        p.stabiliser.len() > own
            && p.stabiliser.len() <= parent_order
            && branch.elements.iter().all(|e| p.stabiliser.contains(e))
    }) else {
        return;
    };
    let k = k + 2;
    let (last, back) = (&branch.points[k - 1], &branch.points[k]);
    if last.stabiliser != branch.elements {
        return;
    }
    let (x1, x2) = (last.parameters[control], back.parameters[control]);
    let prev = &branch.points[k - 2];
    let power = match branch.halves {
        Halves::Conjugate => 2,
        Halves::Distinct => 1,
    };
    let (a0, a1) = (prev.asymmetry.powi(power), last.asymmetry.powi(power));
    let x0 = prev.parameters[control];
    let fitted = (a0 > a1 && prev.stabiliser == branch.elements)
        .then(|| x1 + a1 * (x1 - x0) / (a0 - a1))
        .filter(|x| x.is_finite() && (x - x1) * (x - x2) <= 0.0);
    let estimate = fitted.unwrap_or(0.5 * (x1 + x2));
    branch.points.truncate(k);
    branch.critical.retain(|c| c.after_step + 1 < k);
    branch.turning.retain(|t| t.after_step + 1 < k);
    branch.stop = StopReason::Rejoined {
        between: [x1, x2],
        estimate,
    };
}

/// Follows a branch from its first point with `driver` for the rest of its budget of `steps`
/// points after the critical point, with the index by `index` (numbered by the branch's
/// points: the critical point is point 0), into `branch`: its points (`point` of each state),
/// critical and turning points, warnings and why it stopped.
pub(crate) fn follow_branch<P: crate::continuation::Problem + States>(
    driver: &mut Continuation<P>,
    index: Option<IndexChanges<'_>>,
    steps: usize,
    branch: &mut SwitchedBranch,
    point: impl Fn(&[f64], &[f64], f64, usize, Option<usize>) -> BranchPoint,
) {
    let mut index = index.map(Numbered);
    let followed = {
        let mut extra: Vec<&mut dyn Detector<P>> = Vec::new();
        if let Some(ix) = index.as_mut() {
            extra.push(ix);
        }
        trace(
            driver,
            steps.saturating_sub(1),
            |_, _| None,
            &mut extra,
            |_, _| {},
        )
    };
    // The budget counts the branch's points after the critical point, the first step
    // included.
    let stop = match followed.stop {
        StopReason::StepBudget { .. } => StopReason::StepBudget { steps },
        other => other,
    };
    let problem = driver.problem();
    let indices = index.map(|ix| ix.0.indices).unwrap_or_default();
    for (i, p) in followed.points.iter().enumerate() {
        let u = problem.displacement(&p.q);
        let params = problem.parameters(&p.lambda);
        let index = indices.get(i).copied().flatten();
        branch
            .points
            .push(point(&u, &params, p.arclength, p.iterations, index));
    }
    // Points of the followed path are numbered from 1 on the branch (0 is the critical
    // point it leaves); the index detector numbers its findings so already.
    for event in followed.events {
        match event {
            Event::Critical(c) => branch.critical.push(c),
            Event::Turning(t) => branch.turning.push(BranchTurning {
                kind: t.kind,
                after_step: t.after_step + 1,
                u: problem.displacement(&t.point.q),
                parameters: problem.parameters(&t.point.lambda),
            }),
            Event::Warning(w) => branch.warnings.push(w),
            Event::Stop(_) => {}
        }
    }
    branch.stop = stop;
}

/// A detector whose findings are numbered by the branch's points — the critical point the
/// branch leaves is point 0, the driver's first point is point 1.
struct Numbered<D>(D);

impl<P: crate::continuation::Problem, D: Detector<P>> Detector<P> for Numbered<D> {
    fn start(&mut self, driver: &mut Continuation<P>) -> Vec<Event> {
        self.0.start(driver)
    }

    fn check(
        &mut self,
        driver: &mut Continuation<P>,
        step: &crate::continuation::Accepted,
        after: usize,
    ) -> Vec<Event> {
        self.0.check(driver, step, after + 1)
    }
}

fn set_skip(g: &mut BranchGraph, node: NodeIndex, skip: Skip) {
    if let Node::Critical { skipped, .. } = &mut g.graph[node] {
        skipped.get_or_insert(skip);
    }
}

/// Switches at the path's critical points `critical` of `study` (in the scene's group) and
/// follows the branches; each becomes a [`BranchRun`].
pub fn run(study: &MeshStudy, critical: &[CriticalPoint], options: BranchOptions) -> Branches {
    let t = std::time::Instant::now();
    let save_every = options.save_every.max(1);
    let layout = study.model.layout();
    let top = Level::top(&study.action, layout);
    let measure = |u: &[f64], p: &[f64]| study.measure(u, p);
    let depth = options.depth;
    let switching = Switching {
        model: &study.model,
        constraints: &study.constraints,
        measure: &measure,
        control: study.control,
        top: &top,
        options,
    };
    let mut graph = switching.run(critical);
    // A branch that stalled gets the one line its path would: the cause that fits the kind of
    // its last failed step, and what to try.
    let name = Study::control(study).map_or_else(|| "the control".to_string(), |c| c.name.clone());
    for b in &mut graph.branches {
        if let StopReason::Stalled(s) = &b.stop {
            let hint = super::branch_stall_hint(&study.scene, s, &name, &switching.options.path);
            b.warnings.push(hint);
        }
    }
    let runs = graph
        .branches
        .iter()
        .enumerate()
        .map(|(i, b)| {
            branch_run(
                study,
                &|u| asymmetry(study, u),
                &|c| study.wave_numbers(c),
                b,
                i,
                save_every,
            )
        })
        .collect();
    Branches {
        graph,
        runs,
        depth,
        time: t.elapsed(),
    }
}

/// The report and states of one branch.
/// The report and states of branch `i` of `study` (its directory `branch_NN`): a row per
/// point with the measures and the asymmetry (`asym_of` of a state: the RMS of its part
/// outside the scene's symmetric states), every `save_every`-th state, the turning and
/// critical points; `wave_numbers` labels the critical modes.
pub fn branch_run(
    study: &dyn Study,
    asym_of: &dyn Fn(&[f64]) -> f64,
    wave_numbers: &dyn Fn(&[CriticalPoint]) -> Vec<usize>,
    b: &SwitchedBranch,
    i: usize,
    save_every: usize,
) -> BranchRun {
    let measures = |u: &[f64], p: &[f64], asym: f64| {
        let mut m = study.measure(u, p);
        m.push(asym);
        m
    };
    let control = |p: &[f64]| study.control().map_or(0.0, |c| p[c.index]);
    let rows: Vec<PathRow> = b
        .points
        .iter()
        .enumerate()
        .map(|(k, p)| PathRow {
            step: k,
            arclength: p.arclength,
            parameters: p.parameters.clone(),
            measures: measures(&p.u, &p.parameters, p.asymmetry),
            iterations: p.iterations,
            index: p.index,
            negative: None,
        })
        .collect();
    let last = b.points.len() - 1;
    let mut states: Vec<State> = Vec::new();
    let mut critical = b.critical.iter().peekable();
    for (k, p) in b.points.iter().enumerate() {
        if k % save_every == 0 || k == last {
            states.push(State {
                step: k,
                kind: StateKind::Step,
                control: control(&p.parameters),
                u: p.u.clone(),
                params: p.parameters.clone(),
                mode: None,
            });
        }
        while let Some(cp) = critical.next_if(|cp| cp.after_step + 1 == k) {
            states.push(State {
                step: cp.after_step,
                kind: StateKind::Critical {
                    kind: cp.kind,
                    irrep: cp.irrep.clone(),
                },
                control: control(&cp.parameters),
                u: cp.state.clone(),
                params: cp.parameters.clone(),
                mode: Some(cp.mode.clone()),
            });
        }
    }
    let mut turning = Vec::new();
    for t in &b.turning {
        states.push(State {
            step: t.after_step,
            kind: StateKind::Turning(t.kind),
            control: control(&t.parameters),
            u: t.u.clone(),
            params: t.parameters.clone(),
            mode: None,
        });
        turning.push(TurningRow {
            kind: t.kind,
            after_step: t.after_step,
            measures: measures(&t.u, &t.parameters, asym_of(&t.u)),
            parameters: t.parameters.clone(),
            corner: None,
        });
    }
    let mut critical = b.critical.clone();
    for c in &mut critical {
        c.measures.push(asym_of(&c.state));
    }
    let about = study.about();
    let mut measure_names = about.measures.clone();
    measure_names.push(ASYMMETRY.to_string());
    let mut report = PathReport {
        scene: about.scene.clone(),
        origin: about.origin.clone(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        mesh: about.mesh.clone(),
        group: b.isotropy.clone(),
        group_order: b.elements.len(),
        unknowns: about.unknowns,
        symmetric_unknowns: b.symmetric_unknowns,
        control: study.control().map_or_else(String::new, |c| c.name.clone()),
        parameters: about.parameters.clone(),
        measures: measure_names,
        rows,
        turning_points: turning,
        stop: b.stop.clone(),
        critical,
        warnings: b.warnings.clone(),
        stability_note: b.stability_note.clone(),
        saved: Vec::new(),
        spectra: Default::default(),
        states: None,
        wrinkling: None,
        wave_numbers: Vec::new(),
        refinement: None,
        checks: None,
        irreps: Vec::new(),
    };
    report.wave_numbers = wave_numbers(&report.critical);
    BranchRun {
        report,
        states,
        directory: directory(i),
    }
}

/// The recorded critical points of a run of `study` as [`CriticalPoint`]s, point `n`
/// (1-based) with its `state` and unit `mode` (the others have none: they are nodes of the
/// graph, not switched at). Fails naming the irrep when the study's group has no such irrep.
pub fn recorded_points(
    study: &MeshStudy,
    recorded: &[RecordedPoint],
    n: usize,
    state: Vec<f64>,
    mode: Vec<f64>,
) -> Result<Vec<CriticalPoint>, String> {
    let group = study.action.group();
    let layout = study.model.layout();
    let (mut state, mut mode) = (Some(state), Some(mode));
    let mut out = Vec::with_capacity(recorded.len());
    for (k, c) in recorded.iter().enumerate() {
        let irrep = group.irrep(&c.irrep).ok_or_else(|| {
            format!(
                "critical point {}: {} has no irrep {}",
                k + 1,
                group.name(),
                c.irrep
            )
        })?;
        let (u, m) = if k + 1 == n {
            (
                state.take().unwrap_or_default(),
                mode.take().unwrap_or_default(),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let iso = if m.is_empty() {
            isotropy(&study.action, layout, &vec![0.0; layout.unknowns()])
        } else {
            isotropy(&study.action, layout, &m)
        };
        out.push(CriticalPoint {
            kind: CriticalKind::of(irrep.is_trivial(), irrep.dim(), c.held()),
            irrep: c.irrep.clone(),
            multiplicity: irrep.dim(),
            parameters: c.parameters.clone(),
            measures: c.measures.clone(),
            after_step: c.after_step,
            residual_eigenvalue: c.residual_eigenvalue,
            isotropy: iso,
            mode: m,
            state: u,
            bracket: None,
        });
    }
    Ok(out)
}

/// The RMS over the free nodes of the part of u outside the fixed-point space of the scene's
/// group: 0 on the path, the amplitude of the symmetry breaking on a branch.
fn asymmetry(study: &MeshStudy, u: &[f64]) -> f64 {
    let mut s = vec![0.0; u.len()];
    study.basis.expand(&study.basis.restrict(u), &mut s);
    let free = study.basis.unknowns() as f64 / 3.0;
    s.iter()
        .zip(u)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
        / free.max(1.0).sqrt()
}

/// The distance of `u` from the nearest of `images` (group images of a state), over
/// `state_scale`.
fn nearest_image(images: &[Vec<f64>], u: &[f64], state_scale: f64) -> f64 {
    images
        .iter()
        .map(|image| {
            image
                .iter()
                .zip(u)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt()
        })
        .fold(f64::INFINITY, f64::min)
        / state_scale
}

/// Whether a branch of class `class` leaves node `n`, or is known there: followed from
/// another point, it is the one half of its class at `n` ([`Skip::Known`]).
fn leaves(g: &BranchGraph, n: NodeIndex, class: &str) -> bool {
    g.branches
        .iter()
        .any(|b| b.from == n && b.isotropy == class)
        || matches!(&g.graph[n], Node::Critical { skipped: Some(Skip::Known(known)), .. }
            if known.iter().any(|&k| g.branches[k].isotropy == class))
}
