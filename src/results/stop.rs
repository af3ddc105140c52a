//! How a path ended, and the extrema of a parameter along it.

use crate::text::num;
use serde::Serialize;

/// A maximum or a minimum of a parameter along the path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extremum {
    /// The parameter was increasing before the point.
    Maximum,
    /// The parameter was decreasing before the point.
    Minimum,
}

impl std::fmt::Display for Extremum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Maximum => "maximum",
            Self::Minimum => "minimum",
        })
    }
}

impl Serialize for Extremum {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Why a path ended.
#[derive(Debug, Clone, PartialEq)]
pub enum StopReason {
    /// The control left its `[min, max]` range; the last point is the first beyond it.
    Bounds,
    /// The control reached an end of its `[min, max]` range where the model cannot be
    /// evaluated beyond it (a material constant at 0): every step across the end failed, and
    /// the last point is within the minimum step of it.
    AtBound {
        /// The end of the range.
        bound: f64,
        /// The control at the last point.
        control: f64,
    },
    /// The budget of accepted steps was used.
    StepBudget {
        /// The budget.
        steps: usize,
    },
    /// A closed membrane's stretch reached the scene's `stop-stretch`.
    Stretch {
        /// The target.
        target: f64,
    },
    /// The largest displacement reached the scene's `stop-displacement`.
    Displacement {
        /// The target.
        target: f64,
    },
    /// A caller's stop condition held.
    Condition,
    /// The critical point the analysis looked for was found (a critical curve's start).
    CriticalPoint,
    /// The step was cut below the minimum.
    Stalled(Stalled),
    /// A single equilibrium was solved.
    Equilibrium,
    /// A held state's control swept its range.
    Swept {
        /// Lower end.
        min: f64,
        /// Upper end.
        max: f64,
        /// Number of steps.
        samples: usize,
    },
    /// A sweep without a control parameter.
    NoControl,
    /// A stop was requested (SIGINT, SIGTERM): the path ends at its last point.
    Interrupted,
    /// A branch reached a critical point already computed (up to symmetry): it ends there,
    /// connected to it.
    Connected {
        /// Where: `the path` or a branch's directory, and the point's number on it.
        to: String,
    },
    /// A branch returned to the states of the path it left, where no critical point of that
    /// path is known: it ends at its last state off it.
    Rejoined {
        /// The control at its last state off the parent and at its first one back on it.
        between: [f64; 2],
        /// Where its amplitude's law through its last states reaches zero.
        estimate: f64,
    },
    /// A branch stalled within one longest step of a state of another branch of its isotropy
    /// class (up to symmetry), one from another critical point: the two meet there, and
    /// neither could be followed through the other's states.
    Met {
        /// The stall itself.
        stalled: Stalled,
        /// The other branch's directory.
        branch: String,
        /// Its point nearest the stall.
        point: usize,
        /// Their distance in scaled arclength (state over the state scale, control over
        /// its scale).
        distance: f64,
    },
    /// The path of a finished run read back, which ended as its `path.json` says (in its
    /// words).
    Recorded(String),
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Bounds => f.write_str(
                "the control parameter left its [min, max] range (the last point is the first beyond it)",
            ),
            Self::AtBound { bound, control } => write!(
                f,
                "the control reached the end {} of its [min, max] range (the last point at {}), \
                 past which the model is not defined",
                num(*bound),
                num(*control)
            ),
            Self::StepBudget { steps } => write!(f, "the step budget ({steps}) was used"),
            Self::Stretch { target } => write!(f, "the stretch reached {}", num(*target)),
            Self::Displacement { target } => {
                write!(f, "the largest displacement reached {}", num(*target))
            }
            Self::Condition => f.write_str("the stop condition held"),
            Self::CriticalPoint => f.write_str("the critical point asked for was found"),
            Self::Stalled(s) => write!(f, "{s}"),
            Self::Equilibrium => f.write_str("equilibrium found"),
            Self::Swept { min, max, samples } => {
                write!(
                    f,
                    "the control swept [{}, {}] in {samples} steps",
                    num(*min),
                    num(*max)
                )
            }
            Self::NoControl => f.write_str("no control parameter"),
            Self::Interrupted => f.write_str("interrupted"),
            Self::Connected { to } => write!(f, "it reached {to}, already computed: a connection"),
            Self::Rejoined { between, estimate } => write!(
                f,
                "it returned to the states of the path it left between {:.6} and {:.6} (its amplitude vanishing at about {estimate:.6}), where that path has no known critical point",
                between[0], between[1]
            ),
            Self::Met {
                stalled,
                branch,
                point,
                distance,
            } => write!(
                f,
                "{stalled}; there it meets {branch}: a group image of its last state lies {distance:.1e} (scaled arclength) from that branch's point {point}, within one step"
            ),
            Self::Recorded(words) => f.write_str(words),
        }
    }
}

impl Serialize for StopReason {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Why the driver could not advance: every step was cut below the minimum. The plain-data
/// record of the driver's [`Stalled`](crate::continuation::Stalled), its failure
/// kept as its message; written in the same words.
#[derive(Debug, Clone, PartialEq)]
pub struct Stalled {
    /// The minimum step.
    pub min_step: f64,
    /// The index of the last accepted point.
    pub after: usize,
    /// The control's value there.
    pub control: f64,
    /// Why the last attempt failed, in words.
    pub why: String,
    /// The kind of that failure, for the cause a summary names.
    pub kind: StepFailure,
}

/// The kind of a failed continuation step, as plain data (the driver's `StepError` without
/// its numbers): what a stall's hint is chosen by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepFailure {
    /// The model could not be evaluated (an element or a global quantity left its domain).
    Model,
    /// The extended Jacobian, or the tangent system, was singular.
    Singular,
    /// The corrector left the finite numbers.
    Diverged,
    /// The branch-jump guard refused the step (far from the predictor, a sharp turn).
    BranchJump,
    /// The corrector converged to an inadmissible state (collapsed, torn, inside out).
    Degenerate,
    /// The corrector used its iteration budget.
    NotConverged,
}

impl std::fmt::Display for Stalled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "step cut below {:e} after point {} (control = {}): {}",
            self.min_step,
            self.after,
            num(self.control),
            self.why
        )
    }
}
