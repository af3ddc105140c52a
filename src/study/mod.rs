//! A scene made ready to follow — the seam between the models and the analyses
//! (docs/architecture.md): every analysis runs against the [`Study`] trait, and two models
//! implement it, the 3-D mesh with its symmetry group ([`mesh::MeshStudy`]) and the meridian of
//! a membrane of revolution ([`meridian::MeridianStudy`]). A study names its parameters and
//! measures, solves its start state, hands out the problem to follow in its own coordinates
//! ([`Followed`]), the [`Blocks`] its tangent splits into (irreps, or wave numbers m), the test
//! function of a critical block for critical curves, and the branches that leave a critical
//! point; the writers see it only as the states it draws.

pub mod block_test;
pub mod checks;
pub mod meridian;
mod meridian_branches;
pub mod mesh;
pub mod normal_form;
pub mod switching;

mod symmetric;

pub use symmetric::{held_gauge, sparse_is_cheaper, SymmetricProblem, SPARSE_TANGENT_FROM};

use crate::continuation::crossings::{Blocks, CriticalTest};
pub use crate::continuation::Followed;
use crate::continuation::{PathOptions, SolveError};
use crate::model::StateDefect;
use crate::results::{Branches, CriticalPoint, MeshInfo, PhaseTimes, RecordedPoint, RunResult};
use crate::scene::{self, Scene};

/// The study of a scene: the meridian's on an axisymmetric mesh, the 3-D mesh's otherwise
/// (within the limits of the environment, [`crate::limits::Limits::from_env`]). An error is the
/// scene's (bad input), in one line that names the key.
pub fn build(scene: Scene) -> Result<Box<dyn Study>, String> {
    if let scene::MeshSpec::Axisymmetric(_) = scene.mesh {
        let origin = scene.origin.clone();
        return meridian::MeridianStudy::build(scene)
            .map(|s| Box::new(s) as Box<dyn Study>)
            .map_err(|e| format!("{origin}: {e}"));
    }
    mesh::MeshStudy::build(scene)
        .map(|s| Box::new(s) as Box<dyn Study>)
        .map_err(|e| e.to_string())
}

/// Fails, naming the key, when the scene's analysis names a measure (a surface's
/// `analysis.measure`) that is not one of the study's `measures`.
fn check_measure(scene: &Scene, measures: &[String]) -> Result<(), String> {
    match scene.analysis.measure() {
        Some(name) if !measures.iter().any(|n| n == name) => Err(format!(
            "'analysis.measure' = \"{name}\": not a measure of this scene (it has {})",
            measures.join(", ")
        )),
        _ => Ok(()),
    }
}

/// A parameter an analysis moves: its place among the scene's parameters, its name and the
/// bounds a path in it stops at — built once from the scene by the study, handed to the driver
/// and on to a branch's start.
#[derive(Debug, Clone, PartialEq)]
pub struct Control {
    /// Its index among the parameters (scene order).
    pub index: usize,
    /// Its name.
    pub name: String,
    /// `[parameters.NAME] min` (−∞ without one).
    pub min: f64,
    /// `[parameters.NAME] max` (+∞ without one).
    pub max: f64,
}

impl Control {
    /// The handle of parameter `index` of `scene` (its parameters by name, `names` in scene
    /// order), with its bounds.
    pub fn of(scene: &Scene, names: &[String], index: usize) -> Self {
        let p = &scene.parameters[&names[index]];
        Self {
            index,
            name: names[index].clone(),
            min: p.min.unwrap_or(f64::NEG_INFINITY),
            max: p.max.unwrap_or(f64::INFINITY),
        }
    }

    /// (min, max).
    pub fn bounds(&self) -> (f64, f64) {
        (self.min, self.max)
    }

    /// Its value among every parameter's.
    pub fn value(&self, params: &[f64]) -> f64 {
        params[self.index]
    }
}

/// A state of a study: the displacement over its unknowns and every parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// The displacement over the model's unknowns.
    pub u: Vec<f64>,
    /// Every parameter (scene order).
    pub params: Vec<f64>,
    /// Newton iterations it took.
    pub iterations: usize,
    /// Where the time of its solve's evaluations went.
    pub times: PhaseTimes,
}

/// Where an analysis starts.
#[derive(Debug, Clone)]
pub enum Start {
    /// Newton from the scene's first guess (`start.stretch` times the reference, and the
    /// start homotopy of `[start] hold-translation`).
    Solve,
    /// Newton from a saved state (`[start] from`): its displacement is the first guess, its
    /// parameters the start values.
    From {
        /// The displacement over the model's unknowns.
        u: Vec<f64>,
        /// Every parameter (scene order).
        params: Vec<f64>,
    },
    /// A critical point of a finished run, as it was saved (its state and mode): where a
    /// critical curve's `from-run` and a branch start, without a path.
    Critical(Box<CriticalPoint>),
}

/// What every report says of a study.
#[derive(Debug, Clone)]
pub struct About {
    /// The scene's name.
    pub scene: String,
    /// Where it came from.
    pub origin: String,
    /// The mesh (a 3-D mesh, or the meridian).
    pub mesh: MeshInfo,
    /// The group the states are followed in (`C∞v` for the meridian).
    pub group: String,
    /// Its order (0: infinite).
    pub group_order: usize,
    /// The model's unknowns.
    pub unknowns: usize,
    /// The unknowns of the space the path is solved in.
    pub symmetric_unknowns: usize,
    /// Parameter names (scene order).
    pub parameters: Vec<String>,
    /// Measure names (`max_displacement`, `min_z`, `max_z`, `volume`, `stretch`, …).
    pub measures: Vec<String>,
}

/// Which parameters a problem frees: the control first, then those the constraints govern
/// (when they are active), then `also`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Free {
    /// The control (none for a single equilibrium).
    pub control: Option<usize>,
    /// Whether the scene's constraints are active (each frees its parameter).
    pub constraints: bool,
    /// More free parameters after those (a critical curve's control).
    pub also: Vec<usize>,
    /// Whether the neutral motions are held besides the rigid ones (a start, docs/theory.md
    /// §7.9), until [`Followed::release_held`].
    pub hold_neutral: bool,
}

impl Free {
    /// The path in `control` with the constraints active, its neutral motions held at the
    /// start.
    pub fn path(control: Option<usize>) -> Self {
        Self {
            control,
            constraints: true,
            also: Vec::new(),
            hold_neutral: true,
        }
    }
}

/// Why a run failed before it produced a path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// Newton did not converge at the start (or a signal stopped it).
    #[error("{}", start_message(.error, .control.as_deref(), .cause.as_deref()))]
    Start {
        /// Why.
        error: SolveError,
        /// The control parameter's name (none for a single equilibrium).
        control: Option<String>,
        /// Which known cause fits, and what to try ([`start_cause`]).
        cause: Option<String>,
    },
    /// Newton converged to a membrane turned inside out.
    #[error("the start state did not converge: Newton converged to an inside-out membrane (enclosed volume {volume:e}); start closer to the intended state (start.stretch, the start values)")]
    InsideOut {
        /// The enclosed volume found.
        volume: f64,
    },
    /// A critical curve could not be found or started.
    #[error("critical curve: {0}")]
    Curve(String),
    /// No path of a surface could be started.
    #[error("surface: {0}")]
    Surface(String),
    /// Branches could not be switched to.
    #[error("branches: {0}")]
    Branches(String),
    /// Newton converged to a state that is no membrane state.
    #[error("the start state did not converge: Newton converged to an inadmissible state: {0}; check the material (mu, thickness), the mesh's size and start.stretch against the loads")]
    Degenerate(StateDefect),
}

/// The message of [`RunError::Start`].
fn start_message(error: &SolveError, control: Option<&str>, cause: Option<&str>) -> String {
    match error {
        SolveError::Interrupted => {
            "a signal stopped the start solve between its Newton iterations".into()
        }
        e => format!(
            "the start state did not converge: {}{}",
            e.describe(control),
            cause.map_or_else(String::new, |c| format!("; {c}"))
        ),
    }
}

/// Which of the known causes of a failed start solve fits `error` in `scene`, and what to
/// try: no equilibrium near the start (a load past its fold), a motion nothing holds (a free
/// body, a plane it does not touch yet), a singular tangent, iterates that ran off, a held
/// translation that met no support.
pub fn start_cause(scene: &Scene, error: &SolveError) -> Option<String> {
    let planes = scene
        .effects
        .iter()
        .any(|e| e.get::<scene::PlaneEffect>().is_some());
    let unheld = unheld(scene);
    // A body on planes that nothing else holds has no equilibrium until it touches one: its
    // tangent is singular along the free translation, and whether the factorisation sees an
    // exact zero pivot or Newton wanders is round-off.
    let free_over_planes = planes
        && scene.start.hold_translation.is_none()
        && scene.boundary.fixed.is_empty()
        && scene.boundary.slide.is_empty();
    let cause = match error {
        SolveError::NotConverged {
            residual,
            tolerance,
            ..
        } if *residual <= *tolerance => format!("likely cause: {unheld}"),
        SolveError::NotConverged { .. } | SolveError::Diverged { .. } | SolveError::Model(_)
            if free_over_planes =>
        {
            format!("likely cause: {unheld}")
        }
        SolveError::NotConverged { .. } | SolveError::Diverged { .. } => "likely cause: no \
             equilibrium near the start (a load past its fold, e.g. a fluid level above the \
             highest one held); start at a smaller load and follow a path, or `[start] from`"
            .to_string(),
        SolveError::Singular { .. } | SolveError::SingularTangent => {
            let flat = match &scene.mesh {
                scene::MeshSpec::Disc(_) => true,
                scene::MeshSpec::Axisymmetric(a) => a.shape == scene::AxisymShape::Disc,
                _ => false,
            };
            if flat && scene.start_value(&scene.material.prestretch) == 1.0 && !planes {
                "likely cause: material.prestretch = 1 (an unstretched flat part carries no \
                 load normal to it; give a pre-stretch > 1), or a free motion nothing holds"
                    .to_string()
            } else {
                format!("likely cause: {unheld}")
            }
        }
        SolveError::NotReleased { .. } => "likely cause: the held body met no support along \
             `[start] hold-translation`; give the direction along which it meets its plane"
            .to_string(),
        SolveError::Model(_) | SolveError::Interrupted => return None,
    };
    Some(cause)
}

/// What a singular direction at the start of `scene` most likely is, and what holds it: a
/// plane the body does not touch yet, a free body, or another motion nothing holds.
pub fn unheld(scene: &Scene) -> &'static str {
    let planes = scene
        .effects
        .iter()
        .any(|e| e.get::<scene::PlaneEffect>().is_some());
    let held = scene.start.hold_translation.is_some();
    let supported = !scene.boundary.fixed.is_empty() || !scene.boundary.slide.is_empty();
    if planes && !held {
        "a plane the body does not touch yet, which holds nothing; bring the body onto it with \
         `[start] hold-translation` (its free direction, e.g. [0, 0, 1]) or move the plane"
    } else if !supported && !held {
        "a free body nothing holds; add a support (`boundary.fixed`, a plane it rests on) or \
         `[start] hold-translation`"
    } else {
        "a motion nothing holds (a rigid motion the supports leave free, a neutral mode); hold \
         it with a support"
    }
}

/// The one line a path stuck at a start accepted at round-off along a near-singular direction
/// gets: a motion nothing holds, whatever the kind of its failed steps.
pub fn stall_hint_unheld(
    scene: &Scene,
    stalled: &crate::results::Stalled,
    control: &str,
) -> String {
    format!(
        "the path could not leave its start point ({control} = {}; every step failed: {}): \
         likely cause (the start was accepted at round-off, its tangent near-singular): {}",
        crate::text::num(stalled.control),
        stalled.why,
        unheld(scene)
    )
}

/// The one line a branch that stalled gets: at its critical point (it never left it), that
/// its first step found no state — a direction of its fixed-point space that nothing stiffens
/// there, or a second branch close by; after some points, the path's hint for the kind of its
/// last failure, the points numbered from the critical point.
pub fn branch_stall_hint(
    scene: &Scene,
    stalled: &crate::results::Stalled,
    control: &str,
    opts: &PathOptions,
) -> String {
    if stalled.after == 0 {
        return format!(
            "the branch could not leave its critical point ({control} = {}; every first step \
             failed: {}): likely cause: a direction of the branch's fixed-point space that \
             nothing stiffens there (a nearly neutral mode, a drift) or another branch close \
             by; try a smaller `max-step` in [analysis.branches], or switch at a point of the \
             path of a finer mesh",
            crate::text::num(stalled.control),
            stalled.why
        );
    }
    stall_hint(scene, stalled, control, opts).replacen("the path stopped", "the branch stopped", 1)
}

/// The one line a path that stalled gets: which known cause fits the kind
/// of its last failure, and what to try (`opts`: the options the path ran with; `control`:
/// the control's name).
pub fn stall_hint(
    scene: &Scene,
    stalled: &crate::results::Stalled,
    control: &str,
    opts: &PathOptions,
) -> String {
    use crate::results::StepFailure as F;
    let at = if stalled.after == 0 {
        format!(
            "the path could not leave its start point ({control} = {}; every step failed: {})",
            crate::text::num(stalled.control),
            stalled.why
        )
    } else {
        format!(
            "the path stopped after point {} ({control} = {})",
            stalled.after,
            crate::text::num(stalled.control)
        )
    };
    let step = crate::text::num(opts.max_step);
    let planes: Vec<&scene::PlaneEffect> = scene
        .effects
        .iter()
        .filter_map(|e| e.get::<scene::PlaneEffect>())
        .collect();
    let why = match stalled.kind {
        F::BranchJump if scene.material.relaxed_width() == Some(0.0) => format!(
            "likely cause: a corner of the path where triangles switch between taut, wrinkled \
             and slack (the relaxed energy's tangent jumps there), or a bifurcation close by; \
             a `wrinkling-width` in [material] (e.g. 1e-3) smooths the switching \
             (docs/theory.md §2.9), or try a smaller `max-step` in [analysis] (now {step})"
        ),
        F::BranchJump => format!(
            "likely cause: a sharp turn of the path (or a bifurcation close by), where the \
             corrector lands on another piece and the branch-jump guard refuses it; try a \
             smaller `max-step` in [analysis] (now {step})"
        ),
        F::NotConverged if !planes.is_empty() => {
            let cubic = if planes.iter().all(|p| p.exponent == 3) {
                "a softer `penalty` of the plane"
            } else {
                "the cubic penalty (`exponent = 3` of the plane), whose force starts smoothly"
            };
            format!(
                "likely cause: a contact change (nodes touching or leaving a plane) that the \
                 corrector cannot cross; try a smaller `max-step` in [analysis] (now {step}) or \
                 {cubic}"
            )
        }
        F::NotConverged => format!(
            "likely cause: a stretch of the path too curved for the corrector's budget \
             (`max-iterations` = {}); try a smaller `max-step` in [analysis] (now {step}) or \
             a larger `max-iterations`",
            opts.max_iterations
        ),
        F::Diverged => format!(
            "likely cause: a step too long for the corrector here; try a smaller `max-step` in \
             [analysis] (now {step})"
        ),
        F::Singular if stalled.after == 0 => format!(
            "likely cause (its tangent is singular there): {}; or a parameter at a degenerate \
             value",
            unheld(scene)
        ),
        F::Singular => format!(
            "likely cause: {control} reached a degenerate value, where the path's system is \
             singular (a parameter at zero, a bifurcation of the symmetric block); try a \
             bound on {control} (`[parameters.{control}] min`/`max`) before it, or a \
             different start"
        ),
        F::Model | F::Degenerate => format!(
            "likely cause: {control} reached a value the membrane cannot take (a triangle \
             inverted or collapsed, a volume gone to zero, the membrane inside out); end the \
             path before it with a bound on {control} (`[parameters.{control}] min`/`max`)"
        ),
    };
    format!("{at}: {why}")
}

impl RunError {
    /// Whether a signal stopped the run before it found anything.
    pub fn interrupted(&self) -> bool {
        matches!(
            self,
            Self::Start {
                error: SolveError::Interrupted,
                ..
            }
        )
    }

    /// A start failure of `study`'s solve, naming its control parameter.
    pub fn start(study: &(impl Study + ?Sized), error: SolveError) -> Self {
        Self::Start {
            cause: start_cause(study.scene(), &error),
            error,
            control: study.control().map(|c| c.name.clone()),
        }
    }
}

/// The seam: a scene made into a model that the analyses follow (module documentation), and
/// that the writers draw ([`crate::output::Drawing`]).
pub trait Study: Sync + crate::output::Drawing {
    /// What every report says of it.
    fn about(&self) -> &About;
    /// The scene.
    fn scene(&self) -> &Scene;
    /// The scene's control, if it has one.
    fn control(&self) -> Option<&Control>;
    /// The handle of parameter `index`, with its bounds.
    fn parameter(&self, index: usize) -> Control;
    /// Every parameter's start value (scene order).
    fn start_values(&self) -> &[f64];
    /// What the set-up found that a run should report.
    fn warnings(&self) -> &[String];
    /// Whether the last start solve was accepted at round-off along a near-singular direction
    /// (a motion nothing holds): what a path stuck at its start most likely meets.
    fn start_drifted(&self) -> bool {
        false
    }
    /// The measures of a state, in the order of [`About::measures`].
    fn measure(&self, u: &[f64], params: &[f64]) -> Vec<f64>;
    /// The unit of the state in the arclength.
    fn state_scale(&self) -> f64;
    /// The coordinates of a state in the space the path is solved in (what `path.states`
    /// keeps; [`crate::output::Drawing::expand`] is the way back).
    fn coordinates(&self, u: &[f64]) -> Vec<f64>;
    /// Solves the start state with every parameter at `params` and no constraint active,
    /// from `guess` (a saved state) or the scene's first guess, with the tolerances of
    /// `opts`; sets the targets of the constraints declared `"initial"` there.
    fn solve_start(
        &mut self,
        guess: Option<&[f64]>,
        params: &[f64],
        opts: &PathOptions,
    ) -> Result<Point, RunError>;
    /// The problem at `params` freeing `free`, in the study's coordinates.
    fn problem(&self, params: &[f64], free: &Free) -> Box<dyn Followed + '_>;
    /// The blocks its tangent splits into at a state. An error says why stability is not
    /// analysed.
    fn blocks(&self) -> Result<Box<dyn Blocks + '_>, String>;
    /// The test function of the critical point's block, for a critical curve.
    fn critical_test(&self, cp: &CriticalPoint) -> Result<Box<dyn CriticalTest + '_>, String>;
    /// The branches that leave the critical points `critical` of a path (those `options`
    /// asks for), followed.
    fn branches(
        &self,
        critical: &[CriticalPoint],
        options: BranchOptions,
    ) -> Result<Branches, String>;
    /// The critical points a finished run recorded, as this study's: point `n` (1-based) with
    /// its `state` and unit `mode` as the run saved them, the others without (they are nodes
    /// of a branch graph, not switched at). Fails naming the block when the study has no
    /// such block.
    fn recorded(
        &self,
        recorded: &[RecordedPoint],
        n: usize,
        state: Vec<f64>,
        mode: Vec<f64>,
    ) -> Result<Vec<CriticalPoint>, String>;
    /// Labels the study adds to a finished run (the wave numbers of critical modes, where the
    /// membrane wrinkles, the scales of its axes).
    fn annotate(&self, result: &mut RunResult);
    /// The wave number m about z of a critical point's mode, where the model has an axis (a
    /// disc, a truncated sphere, the meridian), `None` otherwise: what names a mode alike on
    /// models whose blocks are named differently.
    fn wave_number(&self, _cp: &CriticalPoint) -> Option<usize> {
        None
    }
    /// The number of triangles of the state (u, Λ) with a negative principal tension (where
    /// the membrane would wrinkle), `None` where the model does not say.
    fn wrinkled(&self, _u: &[f64], _params: &[f64]) -> Option<usize> {
        None
    }
    /// What the state (u, Λ) says of its validity (docs/theory.md §8.10): its wrinkled
    /// elements and largest principal stretch, each `None` where the model does not measure
    /// it (and both for a state that is not one of the model's).
    fn state_check(&self, _u: &[f64], _params: &[f64]) -> crate::results::validity::StateCheck {
        crate::results::validity::StateCheck::default()
    }
    /// The penetration ⟨−δ⟩ of every node into the penalty planes at the state (u, Λ) (the
    /// deepest over the planes, 0 where a node is clear) and the mean element size there;
    /// `None` without a plane, or for a state that is not one of the model's.
    fn penetrations(&self, _u: &[f64], _params: &[f64]) -> Option<(Vec<f64>, f64)> {
        None
    }
    /// The validity flags of the state (u, Λ) (`wrinkled` under the plain energy, `stretch`
    /// beyond `material.max-stretch`; docs/theory.md §8.10), empty where the model does not
    /// measure them ([`checks::state_flags`] of [`Study::state_check`]).
    fn state_flags(&self, u: &[f64], params: &[f64]) -> Vec<crate::results::validity::Flag> {
        checks::state_flags(self, u, params)
    }
}

/// Settings of branch switching: how deep, and the continuation along each branch.
#[derive(Debug, Clone)]
pub struct BranchOptions {
    /// 1: the branches of the path's critical points; 2: also those of their critical
    /// points; …
    pub depth: usize,
    /// Points of each branch after the critical point it leaves (the step budget).
    pub steps: usize,
    /// The critical points of the path to switch at (1-based, in the order found); `None`:
    /// every one.
    pub points: Option<Vec<usize>>,
    /// The continuation along a branch (first step, largest step, bounds, tolerances,
    /// scales).
    pub path: PathOptions,
    /// Write every n-th state of a branch.
    pub save_every: usize,
}
