//! What branch switching found (docs/theory.md §14): the branches that leave the critical
//! points of a path, the graph that connects them (petgraph), each branch as a path report,
//! and what the bifurcation diagram needs of the path they leave.

use super::{CriticalPoint, Extremum, PathReport, State, StopReason};
use petgraph::graph::{DiGraph, NodeIndex};

/// Which half of an axial line a branch leaves along: +φ or −φ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Half {
    /// Along +φ.
    Plus,
    /// Along −φ.
    Minus,
}

impl Half {
    /// +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Half::Plus => 1.0,
            Half::Minus => -1.0,
        }
    }
}

impl std::fmt::Display for Half {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Half::Plus => "+",
            Half::Minus => "-",
        })
    }
}

/// Whether the two halves of an axial line are one branch up to symmetry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Halves {
    /// Some element of the normaliser maps v to −v: one branch, followed along +φ.
    Conjugate,
    /// No element maps v to −v: two branches, both followed.
    Distinct,
}

impl std::fmt::Display for Halves {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Halves::Conjugate => "conjugate",
            Halves::Distinct => "distinct",
        })
    }
}

/// The bifurcation in Fix(Σ), by the reduced equation's quadratic coefficient.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bifurcation {
    /// C₃ = 0 (by symmetry, or measured at round-off): the branch leaves tangent to φ.
    Pitchfork,
    /// C₃ ≠ 0: the branch crosses the path; its halves go to either side in the control.
    Transcritical,
}

impl std::fmt::Display for Bifurcation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Bifurcation::Pitchfork => "pitchfork",
            Bifurcation::Transcritical => "transcritical",
        })
    }
}

/// Why a critical point was not switched at (or not at all of its directions).
#[derive(Debug, Clone, PartialEq)]
pub enum Skip {
    /// The trivial irrep: a fold of the path, no branch leaves it.
    LimitPoint,
    /// Not among the requested points (`points`).
    NotRequested,
    /// A critical point of a branch at the requested depth.
    Depth,
    /// A complex-type irrep (a chiral group): no axial subgroup.
    ComplexIrrep(String),
    /// The irrep has no axial isotropy subgroup.
    NoAxialSubgroup(String),
    /// Something the switch could not do (names what).
    Failed(String),
    /// Its branches leave the states the study follows (a mode of wave number m ≥ 1 of a
    /// meridian): the reason names the model to switch on.
    Elsewhere(String),
    /// The same point, up to symmetry, as a critical point already in the graph (the
    /// branch it lies on connects to it): switched at there, not again.
    Connection {
        /// The path it lies on (`None`: the primary path).
        on: Option<usize>,
        /// Its number among that path's critical points.
        number: usize,
    },
    /// The eigenvalue jumps across zero here (where the model's switches change: a node
    /// enters or leaves contact) instead of crossing it smoothly, |eigenvalue|/|K| at the
    /// point given: no reduced equation holds at a jump, so nothing is switched to; a branch
    /// may still reach the point from elsewhere, as a connection.
    Jump(f64),
    /// Every branch the lemma predicts here is one already followed, up to symmetry: a
    /// branch that passed through this point along the same direction (by index).
    Known(Vec<usize>),
    /// The critical eigenvalue touches zero instead of crossing it: its rate of change along
    /// the path (b/‖K‖ per unit scaled arclength, given) moves it by less than what counts as
    /// zero over the longest step, so the branching lemma's transversality fails and no
    /// branch is predicted. (The other half of a double point's kernel, at round-off on the
    /// branch's first steps, is [`Skip::AtOrigin`].)
    NotTransversal(f64),
    /// On a branch, the critical eigenvalue has not left zero since the point the branch
    /// left: its rate here (b/‖K‖ per unit scaled arclength), over the scaled distance back to
    /// that point, moves it by less than what counts as zero. It is the rest of that point's
    /// kernel (the other half of a double point), leaving zero to high order along the branch,
    /// whose sign over the branch's first steps is round-off: not a critical point of its own,
    /// and nothing is switched to.
    AtOrigin {
        /// b/‖K‖ per unit scaled arclength at the point.
        rate: f64,
        /// The scaled distance back to the point the branch left.
        distance: f64,
    },
}

impl std::fmt::Display for Skip {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Skip::LimitPoint => f.write_str("a limit point: no branches leave it"),
            Skip::NotRequested => f.write_str("not requested"),
            Skip::Depth => f.write_str("beyond the requested depth"),
            Skip::ComplexIrrep(i) => write!(
                f,
                "irrep {i} is of complex type (a chiral group): it has no axial subgroup, branch switching is not supported"
            ),
            Skip::NoAxialSubgroup(i) => write!(f, "irrep {i} has no axial isotropy subgroup"),
            Skip::Failed(why) => write!(f, "switching failed: {why}"),
            Skip::Elsewhere(why) => f.write_str(why),
            Skip::Connection { on, number } => write!(
                f,
                "the same point, up to symmetry, as critical point {number} of {}: a connection",
                on.map_or_else(|| "the path".to_string(), directory)
            ),
            Skip::Jump(r) => write!(
                f,
                "its eigenvalue jumps across zero (|eigenvalue|/|K| = {r:.0e} at the point): no branch is switched to at a jump"
            ),
            Skip::NotTransversal(b) => write!(
                f,
                "its eigenvalue touches zero without crossing it (rate {b:.1e} of |K| per unit arclength: below zero over a whole step): not a bifurcation by the branching lemma, nothing is switched to"
            ),
            Skip::AtOrigin { rate, distance } => write!(
                f,
                "its eigenvalue has not left zero since the point the branch left (rate {rate:.1e} of |K| per unit arclength over {distance:.1e} back to it: below zero): the rest of that point's kernel, not a critical point of its own, nothing is switched to"
            ),
            Skip::Known(b) => write!(
                f,
                "its branches are already followed: {}",
                b.iter().map(|&i| directory(i)).collect::<Vec<_>>().join(", ")
            ),
        }
    }
}

/// The reduced bifurcation equation along φ in Fix(Σ): g(a, s) = a (b s + ½ C₃ a + …), a the
/// amplitude along φ, s the parent path's scaled arclength (docs/theory.md §14.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reduced {
    /// b/‖K‖: the critical eigenvalue's rate of change along the path (per unit scaled
    /// arclength).
    pub path_slope: f64,
    /// C₃ σ/‖K‖: its rate of change along φ (per unit scaled amplitude, σ the state scale);
    /// exactly 0 where symmetry forbids a quadratic term.
    pub mode_slope: f64,
    /// Pitchfork or transcritical.
    pub bifurcation: Bifurcation,
    /// ds/dA at the point (A the scaled amplitude): −mode_slope/(2 path_slope), 0 for a
    /// pitchfork.
    pub path_per_amplitude: f64,
}

/// Whether a pitchfork's branch leaves toward the side where the path has lost stability in
/// the critical mode (supercritical: the branch is stable in that mode) or toward the side
/// where it is still stable (subcritical: the branch is unstable in it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Criticality {
    /// The branch is stable in the critical mode near the point.
    Supercritical,
    /// The branch is unstable in the critical mode near the point.
    Subcritical,
}

impl std::fmt::Display for Criticality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Criticality::Supercritical => "supercritical",
            Criticality::Subcritical => "subcritical",
        })
    }
}

/// The normal form of one half of a branch at its critical point (docs/theory.md §14.7):
/// the control along the branch, λ − λ_c ≈ c A^k with A = a/σ the scaled amplitude along the
/// critical mode φ (k = 1 transcritical, k = 2 pitchfork), measured by three solves at fixed
/// amplitude and extrapolated, and what it predicts of the branch's stability.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalForm {
    /// k: 1 (transcritical) or 2 (pitchfork).
    pub power: u32,
    /// c, control units per A^k.
    pub coefficient: f64,
    /// The estimated error of c: the difference of the extrapolations from the larger and
    /// the smaller pair of amplitudes.
    pub error: f64,
    /// The amplitudes A of the three solves.
    pub amplitudes: [f64; 3],
    /// A pitchfork's criticality (none for a transcritical point, whose halves go to either
    /// side, or where the crossing is not transversal).
    pub criticality: Option<Criticality>,
    /// Whether the half is stable in the critical mode near the point (its eigenvalue along
    /// φ is −b s for a transcritical point and −2 b s for a pitchfork, s the path's arclength
    /// at the branch's control): none where the crossing is not transversal.
    pub mode_stable: Option<bool>,
    /// c as the followed branch's first point gives it (Δλ/A^k there), if it has one.
    pub observed: Option<f64>,
    /// The amplitude A of that point.
    pub observed_amplitude: Option<f64>,
}

impl NormalForm {
    /// One line: `supercritical: p − p_c ≈ 0.1234 A² (± 2e-5), stable in its mode; its first
    /// point gives 0.1229`.
    pub fn describe(&self, control: &str) -> String {
        let power = if self.power == 1 { "" } else { "²" };
        let kind = self
            .criticality
            .map_or_else(String::new, |c| format!("{c}: "));
        let stability = match self.mode_stable {
            Some(true) => ", stable in its mode",
            Some(false) => ", unstable in its mode",
            None => "",
        };
        let observed = self.observed.map_or_else(String::new, |o| {
            format!("; its first point gives {}", crate::text::sig_digits(o, 4))
        });
        format!(
            "{kind}{control} − {control}_c ≈ {} A{power} (± {}){stability}{observed}",
            crate::text::sig_digits(self.coefficient, 6),
            crate::text::sci(self.error),
        )
    }
}

/// One point of a branch.
#[derive(Debug, Clone)]
pub struct BranchPoint {
    /// Displacement over the unknowns.
    pub u: Vec<f64>,
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// Arclength from the critical point (scaled).
    pub arclength: f64,
    /// Newton iterations of the corrector (0 at the critical point).
    pub iterations: usize,
    /// Index Σ_ν d_ν neg_ν by the irreps of Σ (`None` at the critical point, where a block is
    /// singular, or where stability is not analysed).
    pub index: Option<usize>,
    /// RMS over the free nodes of the part of u outside Fix(G), G the scene's group: 0 on the
    /// path, the amplitude of the symmetry breaking on a branch.
    pub asymmetry: f64,
    /// The stabiliser of u in the scene's group: its elements, sorted.
    pub stabiliser: Vec<usize>,
    /// Its class name in the scene's group's lattice.
    pub stabiliser_class: String,
}

/// A turning point of the control along a branch.
#[derive(Debug, Clone)]
pub struct BranchTurning {
    /// Maximum or minimum.
    pub kind: Extremum,
    /// The branch point just before it.
    pub after_step: usize,
    /// Displacement.
    pub u: Vec<f64>,
    /// Every parameter.
    pub parameters: Vec<f64>,
}

/// A followed branch.
#[derive(Debug, Clone)]
pub struct SwitchedBranch {
    /// The node of the critical point it leaves.
    pub from: NodeIndex,
    /// The branch it leaves from (`None`: the path).
    pub parent: Option<usize>,
    /// The irrep of the critical point (of the parent's group).
    pub irrep: String,
    /// The isotropy subgroup's class name in the scene's group's lattice (`C1v`, `D5d`, …).
    pub isotropy: String,
    /// Σ as elements of the scene's group, sorted.
    pub elements: Vec<usize>,
    /// Σ's class name in the parent's lattice.
    pub class_in_parent: String,
    /// Which half.
    pub half: Half,
    /// Whether the halves are conjugate (then only `+` is followed).
    pub halves: Halves,
    /// The reduced equation at the critical point.
    pub reduced: Reduced,
    /// The normal form of this half, if it could be computed.
    pub normal_form: Option<NormalForm>,
    /// Unknowns of Fix(Σ).
    pub symmetric_unknowns: usize,
    /// The points, the critical point first.
    pub points: Vec<BranchPoint>,
    /// Turning points of the control along the branch.
    pub turning: Vec<BranchTurning>,
    /// Critical points along the branch, classified by the irreps of Σ.
    pub critical: Vec<CriticalPoint>,
    /// Why the branch ended.
    pub stop: StopReason,
    /// Why stability was not analysed along it, if it was not.
    pub stability_note: Option<String>,
    /// What could not be settled (crossings not localised, a state of another isotropy …).
    pub warnings: Vec<String>,
    /// The sign of the branch in the bifurcation diagram (its half, times its parent's).
    pub sign: f64,
    /// Wall time of the switch and the continuation.
    pub time: std::time::Duration,
}

impl SwitchedBranch {
    /// True when every point after the critical point has exactly Σ as its stabiliser.
    pub fn isotropy_exact(&self) -> bool {
        // A connection's last point is the known point it reached, on its own path.
        let end = match self.stop {
            StopReason::Connected { .. } => self.points.len().saturating_sub(1),
            _ => self.points.len(),
        };
        end > 1
            && self.points[1..end]
                .iter()
                .all(|p| p.stabiliser == self.elements)
    }
}

/// A node of the branch graph.
#[derive(Debug, Clone)]
pub enum Node {
    /// A critical point of the path (`on = None`) or of branch `on`.
    Critical {
        /// The branch it lies on (`None`: the path).
        on: Option<usize>,
        /// Its number among that path's critical points (1-based, in the order found).
        number: usize,
        /// The point.
        point: Box<CriticalPoint>,
        /// Why no branch (or not every predicted branch) leaves it.
        skipped: Option<Skip>,
    },
    /// Where branch `branch` ended.
    End {
        /// The branch.
        branch: usize,
        /// Why it ended.
        stop: StopReason,
    },
}

/// A branch reaching a critical point already in the graph (up to symmetry): the thesis's
/// "branch connecting path", and how a closed circuit or a loop shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Connection {
    /// The branch.
    pub branch: usize,
    /// Its critical point there (a node of its own).
    pub at: NodeIndex,
    /// The critical point it is (a path's or an earlier branch's).
    pub to: NodeIndex,
}

/// The branches and how they connect: nodes are critical points and branch ends, edge
/// weights index [`BranchGraph::branches`].
#[derive(Debug, Clone, Default)]
pub struct BranchGraph {
    /// The graph.
    pub graph: DiGraph<Node, usize>,
    /// The branches, in the order followed.
    pub branches: Vec<SwitchedBranch>,
    /// Where branches reach critical points already in the graph.
    pub connections: Vec<Connection>,
}

impl BranchGraph {
    /// The branches leaving node `n`, in the order followed.
    pub fn leaving(&self, n: NodeIndex) -> Vec<usize> {
        let mut b: Vec<usize> = self.graph.edges(n).map(|e| *e.weight()).collect();
        b.sort_unstable();
        b
    }

    /// The node of the path's critical point number `k` (1-based).
    pub fn path_point(&self, k: usize) -> Option<NodeIndex> {
        self.graph.node_indices().find(
            |&n| matches!(self.graph[n], Node::Critical { on: None, number, .. } if number == k),
        )
    }
}

/// A branch as a path of its own: the report its directory's files are written from.
#[derive(Debug, Clone)]
pub struct BranchRun {
    /// The branch's path: rows (the critical point it leaves first, with no index), turning
    /// and critical points, why it stopped; its group is the isotropy subgroup, its measures
    /// the scene's and `asymmetry`.
    pub report: PathReport,
    /// Its states to write.
    pub states: Vec<State>,
    /// Its directory in the output directory (`branch_01`, …).
    pub directory: String,
}

/// The branches of a run.
#[derive(Debug, Clone, Default)]
pub struct Branches {
    /// The graph of critical points and branches.
    pub graph: BranchGraph,
    /// One per branch of the graph, in its order.
    pub runs: Vec<BranchRun>,
    /// The depth asked for.
    pub depth: usize,
    /// Wall time of all the switches and branches.
    pub time: std::time::Duration,
}

/// The measure name of a branch state's asymmetry (see [`BranchPoint::asymmetry`]).
pub const ASYMMETRY: &str = "asymmetry";

/// The directory of branch `i` (0-based): `branch_01`, `branch_02`, …
pub fn directory(i: usize) -> String {
    format!("branch_{:02}", i + 1)
}

/// A critical point as a finished run records it (`path.json`), without its state.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedPoint {
    /// Its kind, as the run wrote it (`limit point`, `symmetric bifurcation`, …; empty when
    /// the run did not).
    pub kind: String,
    /// Its irrep.
    pub irrep: String,
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// Every measure.
    pub measures: Vec<f64>,
    /// The path step before it.
    pub after_step: usize,
    /// |eigenvalue|/‖K‖ there.
    pub residual_eigenvalue: f64,
}

impl RecordedPoint {
    /// Whether the run recorded it where the path cannot fold (a symmetric bifurcation): its
    /// singular trivial block is then a branch point, not a fold.
    pub fn held(&self) -> bool {
        self.kind == super::CriticalKind::SymmetricBifurcation.to_string()
    }
}

/// What the diagram needs of the path the branches leave: the control and the index at
/// every point.
#[derive(Debug, Clone, PartialEq)]
pub struct PrimaryPath {
    /// The scene's name.
    pub scene: String,
    /// The scene's group.
    pub group: String,
    /// The mesh, as [`MeshInfo::describe`](super::MeshInfo::describe) names it (empty
    /// where not known).
    pub mesh: String,
    /// The control's name.
    pub control: String,
    /// Parameter names, in order.
    pub parameters: Vec<String>,
    /// The control at every point.
    pub values: Vec<f64>,
    /// The index at every point.
    pub index: Vec<Option<usize>>,
}

impl PrimaryPath {
    /// The path of a run's report.
    pub fn of(report: &PathReport) -> Self {
        let c = report.parameters.iter().position(|p| *p == report.control);
        Self {
            scene: report.scene.clone(),
            group: report.group.clone(),
            mesh: report.mesh.describe(),
            control: report.control.clone(),
            parameters: report.parameters.clone(),
            values: report
                .rows
                .iter()
                .map(|r| c.map_or(0.0, |c| r.parameters[c]))
                .collect(),
            index: report.rows.iter().map(|r| r.index).collect(),
        }
    }
}
