//! The states a run writes (VTU): path points, turning and critical points, held states.

use super::{CriticalKind, Extremum};

/// What a state to write is.
#[derive(Debug, Clone, PartialEq)]
pub enum StateKind {
    /// A point of the path (every `save-every` steps, and the last one).
    Step,
    /// A turning point of the control.
    Turning(Extremum),
    /// A critical point, written with its mode.
    Critical {
        /// Its kind.
        kind: CriticalKind,
        /// The irrep of the singular block.
        irrep: String,
    },
    /// The held state of a linear-buckling sweep.
    Held,
}

impl StateKind {
    /// The state's label: `step N`, `maximum`, `double bifurcation in E1`, `held state`.
    pub fn label(&self, step: usize) -> String {
        match self {
            Self::Step => format!("step {step}"),
            Self::Turning(e) => e.to_string(),
            Self::Critical { kind, irrep } => format!("{kind} in {irrep}"),
            Self::Held => "held state".into(),
        }
    }
}

/// A state to write: path step, what it is, control value, full displacement, and a mode
/// for critical points.
#[derive(Debug, Clone)]
pub struct State {
    /// Path step (turning and critical points carry the step before them).
    pub step: usize,
    /// What the state is.
    pub kind: StateKind,
    /// The control's value.
    pub control: f64,
    /// Displacement over the unknowns.
    pub u: Vec<f64>,
    /// Every parameter's value there.
    pub params: Vec<f64>,
    /// The critical mode over the unknowns, for critical points.
    pub mode: Option<Vec<f64>>,
}

impl State {
    /// The state's label (see [`StateKind::label`]).
    pub fn label(&self) -> String {
        self.kind.label(self.step)
    }
}
