//! The spectra of a linear-buckling sweep: the lowest eigenvalues of every irrep block.

use serde::Serialize;

/// An irrep block as listed in [`Spectra`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SpectrumIrrep {
    /// Irrep name (`A1`, `E2`, `T1u` …).
    pub name: String,
    /// Its dimension d (every eigenvalue of the block is d-fold in K).
    pub dim: usize,
    /// Block size m (columns of one partner).
    pub size: usize,
    /// Whether the block's eigenvalues are computed (at any sample); an empty block, or one
    /// whose eigenvalues could not be computed, has its negative count only and `lowest`
    /// `null` throughout.
    pub eigenvalues: bool,
}

/// The most eigenvalues per block a [`SpectrumRow`] keeps.
pub const SPECTRUM_EIGENVALUES: usize = 6;

/// The spectra of one sample: per irrep (in the order of [`Spectra::irreps`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectrumRow {
    /// The path row (sample) this belongs to.
    pub step: usize,
    /// The control's value there.
    pub control: f64,
    /// max |K_ij| of the tangent there, the unit of `lowest`.
    pub scale: f64,
    /// The block's lowest eigenvalue over `scale` (λ/‖K‖, rigid modes excluded), or `None`
    /// where it was not computed (a large block, or no spectrum at this sample).
    pub lowest: Vec<Option<f64>>,
    /// Per block, its lowest eigenvalues over `scale`, ascending, as many as were computed up
    /// to [`SPECTRUM_EIGENVALUES`] (empty where none was): the first is `lowest`, the others
    /// are the higher eigenvalues that cross zero later in the sweep.
    pub eigenvalues: Vec<Vec<f64>>,
    /// The block's number of negative eigenvalues (`None` where no spectrum was computed).
    pub negative: Vec<Option<usize>>,
}

/// The lowest eigenvalue of every irrep block along a linear-buckling sweep: what `path.svg`
/// plots for that analysis, stored in `path.json` so that the two agree.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Spectra {
    /// The irrep blocks, the trivial first.
    pub irreps: Vec<SpectrumIrrep>,
    /// One per sample, matching [`PathReport::rows`](super::PathReport::rows) (all `None`
    /// where no spectrum was computed).
    pub rows: Vec<SpectrumRow>,
}

impl Spectra {
    /// True when no spectrum was recorded (every analysis but linear buckling, or a run whose
    /// stability was not analysed).
    pub fn is_empty(&self) -> bool {
        self.irreps.is_empty() || self.rows.is_empty()
    }

    /// The index of the irrep named `name`.
    pub fn irrep(&self, name: &str) -> Option<usize> {
        self.irreps.iter().position(|i| i.name == name)
    }
}
