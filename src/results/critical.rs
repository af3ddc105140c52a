//! Critical points, localised and classified by irrep (docs/theory.md §11.3), and the
//! isotropy subgroup of a mode.

use serde::Serialize;

/// The subgroup that leaves a mode invariant.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Isotropy {
    /// A name when the subgroup is axial about z (`C4v`, `C2`, `C1` …), else `order N`.
    pub name: String,
    /// Its order.
    pub order: usize,
    /// Indices (in the scene's group) of its elements.
    pub elements: Vec<usize>,
}

/// What kind of critical point a singular block makes (docs/theory.md §11.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CriticalKind {
    /// The trivial block on a path: a symmetric fold of the path.
    LimitPoint,
    /// The trivial block where the path cannot fold: on a held state (linear buckling), or on
    /// a path where the control does not turn (a branch point within the symmetric states).
    SymmetricBifurcation,
    /// A non-trivial 1-D irrep: a simple symmetry-breaking bifurcation.
    SimpleBifurcation,
    /// A d-dimensional irrep (d ≥ 2): a d-fold bifurcation, the zero d-fold in K.
    MultipleBifurcation(usize),
}

impl CriticalKind {
    /// The kind of a singular block in an irrep of dimension `dim` (`trivial`: the first
    /// irrep); `held` where the path cannot fold — a held state, or a step of a path in which
    /// the control does not turn: there a singular trivial block is a bifurcation within the
    /// symmetric states, not a fold.
    pub fn of(trivial: bool, dim: usize, held: bool) -> Self {
        match (trivial, dim) {
            (true, _) if held => Self::SymmetricBifurcation,
            (true, _) => Self::LimitPoint,
            (false, 1) => Self::SimpleBifurcation,
            (false, d) => Self::MultipleBifurcation(d),
        }
    }

    /// The first word of the name: `limit`, `symmetric`, `simple`, `double`, `3-fold` …
    pub fn short(&self) -> String {
        match self {
            Self::LimitPoint => "limit".into(),
            Self::SymmetricBifurcation => "symmetric".into(),
            Self::SimpleBifurcation => "simple".into(),
            Self::MultipleBifurcation(2) => "double".into(),
            Self::MultipleBifurcation(d) => format!("{d}-fold"),
        }
    }
}

impl std::fmt::Display for CriticalKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::LimitPoint => f.write_str("limit point"),
            Self::SymmetricBifurcation => f.write_str("symmetric bifurcation"),
            Self::SimpleBifurcation => f.write_str("simple bifurcation"),
            Self::MultipleBifurcation(2) => f.write_str("double bifurcation"),
            Self::MultipleBifurcation(d) => write!(f, "{d}-fold bifurcation"),
        }
    }
}

impl Serialize for CriticalKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// A localised and classified critical point.
#[derive(Debug, Clone, Serialize)]
pub struct CriticalPoint {
    /// `limit point`, `simple bifurcation`, `double bifurcation`, `3-fold bifurcation` …
    pub kind: CriticalKind,
    /// The irrep whose block became singular.
    pub irrep: String,
    /// Multiplicity of the zero eigenvalue in K (the irrep's dimension).
    pub multiplicity: usize,
    /// Every parameter at the point (scene order).
    pub parameters: Vec<f64>,
    /// Every measure at the point (the report's order).
    pub measures: Vec<f64>,
    /// The path step (or sample) just before the point (`step` in the outputs).
    #[serde(rename = "step")]
    pub after_step: usize,
    /// |eigenvalue| / ‖K‖ at the localised point.
    pub residual_eigenvalue: f64,
    /// Isotropy subgroup of the critical mode (first partner).
    pub isotropy: Isotropy,
    /// The critical mode over the unknowns (unit norm).
    #[serde(skip)]
    pub mode: Vec<f64>,
    /// The state over the unknowns.
    #[serde(skip)]
    pub state: Vec<f64>,
    /// The localisation's last bracket (`None` for a point not localised in a step: one
    /// read back from a finished run, or found on a branch's start).
    #[serde(skip)]
    pub bracket: Option<Bracket>,
}

/// The last bracket of a crossing's localisation (docs/theory.md §11.2): the nearest states on
/// either side of the eigenvalue's change of sign, between which the point lies.
#[derive(Debug, Clone, PartialEq)]
pub struct Bracket {
    /// Its width, as a share of the step's arclength (1e-10 at the narrowest).
    pub width: f64,
    /// Its ends, each (the state over the unknowns, every parameter).
    pub ends: [(Vec<f64>, Vec<f64>); 2],
}

#[cfg(test)]
mod tests {
    use super::CriticalKind;

    #[test]
    fn names() {
        assert_eq!(CriticalKind::of(true, 1, false).to_string(), "limit point");
        assert_eq!(
            CriticalKind::of(true, 1, true).to_string(),
            "symmetric bifurcation"
        );
        assert_eq!(
            CriticalKind::of(false, 1, false).to_string(),
            "simple bifurcation"
        );
        assert_eq!(
            CriticalKind::of(false, 2, false).to_string(),
            "double bifurcation"
        );
        assert_eq!(
            CriticalKind::of(false, 5, false).to_string(),
            "5-fold bifurcation"
        );
        assert_eq!(CriticalKind::of(false, 5, false).short(), "5-fold");
        assert_eq!(
            serde_json::to_string(&CriticalKind::of(false, 2, false)).unwrap(),
            "\"double bifurcation\""
        );
    }
}
