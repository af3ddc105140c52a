//! The other piece of a broken bifurcation (docs/theory.md §16.4): where a mesh of less
//! symmetry puts one mode of a multiple point in the path's own fixed-point space, the
//! bifurcation is imperfect — the path turns at a fold and the solutions beyond it lie on a
//! second piece that the path does not reach. What the search at each fold of the path found.

use super::BranchRun;

/// The search for a second piece at one fold (limit point) of the path, or at one dip.
#[derive(Debug, Clone)]
pub struct Partner {
    /// The fold: its number among the path's critical points (from 1, as in `critical.json`);
    /// 0 for a search beside a dip ([`Partner::dip`]).
    pub fold: usize,
    /// The path's step at a dip (docs/theory.md §16.7) the search was made beside, instead of
    /// a fold: a minimum of the |eigenvalue| of the path's own block with no change of index.
    pub dip: Option<usize>,
    /// The control's value at the fold (or the dip).
    pub value: f64,
    /// The fixed-amplitude solves tried.
    pub tried: usize,
    /// The piece found, if one was.
    pub piece: Option<PartnerPiece>,
    /// Why no piece was found, or what could not be settled about it.
    pub note: Option<String>,
}

/// A piece of solutions beside a fold that the path does not reach.
#[derive(Debug, Clone)]
pub struct PartnerPiece {
    /// The signed amplitude along the fold's mode (scaled like the corrector's unknowns) of
    /// the fixed-amplitude solve that met the piece.
    pub amplitude: f64,
    /// The gap: the distance between the fold's state and the piece's state at the fold's
    /// control value, the root mean square over the nodes of the difference of their
    /// displacements (length units; for an imperfect pitchfork λ x + x³ + ε = 0 it is 3 (ε/2)^(1/3)
    /// in the mode's amplitude, vanishing with the imperfection).
    pub gap: f64,
    /// The piece, followed from the fold's control value beyond the fold (where the path does
    /// not go): its first row is the state the gap is measured to, its critical points are
    /// classified as the path's.
    pub run: BranchRun,
}
