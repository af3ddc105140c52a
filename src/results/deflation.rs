//! What deflated Newton found at one value of the control: the solutions other than the start
//! state, whether the path through the start reaches each, and the piece of path through
//! each (docs/theory.md §16).

use super::StopReason;
use serde::Serialize;

/// The solutions at the start's control value (`type = "deflation"`).
#[derive(Debug, Clone, Serialize)]
pub struct DeflationReport {
    /// The control's name.
    pub control: String,
    /// The control's value, where every solution was sought.
    pub value: f64,
    /// The parameters' names (the order of every point's values).
    pub parameters: Vec<String>,
    /// The measures' names.
    pub measures: Vec<String>,
    /// The blocks' names (the order of every point's negative counts), empty without a
    /// stability analysis.
    pub blocks: Vec<String>,
    /// The start state first, then every other solution in the order found.
    pub solutions: Vec<Solution>,
    /// The first guesses tried.
    pub guesses: usize,
    /// The solutions of the equations that are no state of the membrane (inside out, or
    /// stretched beyond the model's range), set aside: why each is not.
    pub rejected: Vec<String>,
    /// What could not be settled (a guess that failed is not a warning).
    pub warnings: Vec<String>,
}

/// One solution at the control value.
#[derive(Debug, Clone, Serialize)]
pub struct Solution {
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// Every measure.
    pub measures: Vec<f64>,
    /// The negative count of every block, where computed.
    pub negative: Option<Vec<usize>>,
    /// The triangles with a negative principal tension (where the membrane would wrinkle:
    /// the membrane energy does not describe the state there), where the model says.
    pub wrinkled: Option<usize>,
    /// The flags of its state (`wrinkled` under the plain energy, `stretch`; docs/theory.md
    /// §8.10): empty where it is valid or the model does not measure it.
    pub flags: Vec<super::validity::Flag>,
    /// Deflated Newton's iterations (0 for the start state).
    pub iterations: usize,
    /// The distance to the nearest solution known before it, in the corrector's scaled
    /// units (none for the start state).
    pub distance: Option<f64>,
    /// The row of the run's path (through the start) whose step crosses the control value
    /// at this solution, if the path reaches it; `None`: a piece the path does not reach.
    pub on_path: Option<usize>,
    /// The piece of path through it in the control (empty unless asked for, and for the
    /// start state, whose path is the run's).
    pub piece: Vec<PiecePoint>,
    /// Why its piece ended.
    pub piece_stop: Option<StopReason>,
}

/// A point of a piece of path.
#[derive(Debug, Clone, Serialize)]
pub struct PiecePoint {
    /// Every parameter.
    pub parameters: Vec<f64>,
    /// Every measure.
    pub measures: Vec<f64>,
    /// The instability index (negative eigenvalues over all blocks), where computed.
    pub index: Option<usize>,
}
