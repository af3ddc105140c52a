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
        self.points.len() > 1
            && self.points[1..]
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

/// The branches and how they connect: nodes are critical points and branch ends, edge
/// weights index [`BranchGraph::branches`].
#[derive(Debug, Clone, Default)]
pub struct BranchGraph {
    /// The graph.
    pub graph: DiGraph<Node, usize>,
    /// The branches, in the order followed.
    pub branches: Vec<SwitchedBranch>,
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
#[derive(Debug, Clone)]
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
