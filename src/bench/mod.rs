//! The accuracy-versus-cost study behind `memstab bench`, one file per study:
//!
//! - [`balloon`]: the k = 0.1 balloon against its closed form under icosphere refinement, the
//!   time of each level split by phase;
//! - [`payoff`](mod@payoff): the symmetry payoff on one tangent matrix (eigenvalues by irrep
//!   blocks against a dense full eigen-decomposition and a sparse shift-invert of K) for the
//!   Ih balloon and a C8v disc, with scipy `eigsh` as a peer when available ([`peer`]);
//! - [`full_path`]: stability along the balloon path with and without symmetry;
//! - [`scaling`]: the scaling study with peak memory;
//! - [`ponding`]: the ponding ladder against its closed form;
//! - [`thesis`]: the thesis-size spinning cap on meshes of five symmetry groups, against the
//!   same states without symmetry;
//! - [`curves`]: critical curves timed — the balloon's fold line through its cusp, a double
//!   point of the C7v disc followed in its prestretch;
//! - [`branching`]: branch switching, timed — the abstract Hg potential on the icosahedron
//!   (branches in closed form) and the upward-loaded disc;
//! - [`report`]: the markdown tables, CSV files and the accuracy plot of those numbers;
//! - [`run`]: the whole bench (or the scaling study) into an output directory.
//!
//! The closed forms are those of [`crate::reference`]. Nothing else in the library depends
//! on this module.
//!
//! How the phases are timed: the balloon path is what `memstab run` computes
//! ([`crate::analysis::run_with`]: start solve, adapted basis, the path with the index by
//! irrep blocks at every point and the critical points localised), with the run's own phase
//! times ([`crate::results::RunTimes`]): `model.evaluate` (assembly) and the restriction of
//! residual, loads and tangent to the fixed-point space (projection) as the fixed-point
//! problem counts them; what is left of the start solve and the steps is the dense linear
//! algebra of the fixed-point system (factorisations and solves of a matrix of size m + 1, m
//! the symmetric unknowns) and step control. An observer keeps every accepted state; the
//! eigenvalue spectra by irrep ([`crate::stability::Stability::spectrum_of`]) are computed on
//! those states afterwards and timed apart, their assembly re-timed by one extra
//! `model.evaluate` at the same point (not counted in the totals) and moved to the assembly
//! column. Output writing, which `run` also does, is not part of this study.

pub mod axisym;
pub mod balloon;
pub mod branching;
pub mod curves;
pub mod full_path;
pub mod payoff;
pub mod peer;
pub mod ponding;
pub mod report;
pub mod run;
pub mod scaling;
pub mod thesis;

pub use balloon::{
    balloon_level, balloon_level_with, balloon_scene, BalloonLevel, LevelOptions, BALLOON_TOML,
};
pub use full_path::{
    full_path_stability, DensePath, FullPathStability, FULL_INDEX_SHIFT, SHIFT_INVERT_SHIFT,
};
pub use payoff::{
    c8v_disc_scene, c8v_payoff, payoff, shift_invert, BlockValue, Payoff, PayoffCase, ShiftInvert,
    C8V_DENSITY, DISC_FLUID_ABOVE_TOML,
};
pub use peer::{run_peer, PeerResult};
pub use ponding::{
    ponding_level, ponding_level_in, ponding_scene, wave_number, PondingLevel, Rung, PONDING_TOML,
};
pub use run::{
    run_accuracy, run_axisym, run_branching, run_curves, run_scaling, run_thesis, AccuracyOptions,
    BenchFiles, ScalingOptions, ThesisOptions,
};
pub use scaling::{fit_exponent, memory, scaling_level, ScalingFits, ScalingLevel};
pub use thesis::{spinning_cap_scene, thesis_run, thesis_table, ThesisRun, SPINNING_CAP_TOML};

use crate::model::{Evaluation, FeModel, Model};
use crate::study::mesh::MeshStudy;

/// The start state as `run` solves it ([`crate::study::Study::solve_start`], with the
/// options of the scene's analysis): the displacement over all unknowns.
pub fn solve_start(study: &mut MeshStudy, params: &[f64]) -> Result<Vec<f64>, String> {
    let opts = crate::analysis::analysis_of(&study.scene.analysis).options(study);
    crate::study::Study::solve_start(study, None, params, &opts)
        .map(|p| p.u)
        .map_err(|e| e.to_string())
}

/// Observed order between two levels of frequency f and 2f: log2(e_f / e_2f).
pub fn observed_order(coarse: f64, fine: f64) -> f64 {
    (coarse / fine).log2()
}

/// Richardson extrapolation assuming order 2 with h halved: (4 p_fine − p_coarse) / 3.
pub fn richardson(coarse: f64, fine: f64) -> f64 {
    crate::analysis::compare::richardson(coarse, fine, 2.0)
}

/// The full tangent K as a dense matrix (sparse part plus rank-one terms).
pub fn dense_tangent(model: &FeModel, eval: &Evaluation) -> faer::Mat<f64> {
    let mut k = model.pattern().to_dense(&eval.tangent);
    for (c, a) in &eval.rank_one {
        for j in 0..a.len() {
            if a[j] == 0.0 {
                continue;
            }
            for i in 0..a.len() {
                k[(i, j)] += c * a[i] * a[j];
            }
        }
    }
    k
}

/// `s` on one line (runs of white space, newlines included, as one space): error messages.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Fails, before any level runs, when the balloon of some frequency is over the limits
/// ([`crate::limits`]): the message names the flag and the estimate.
pub fn check_frequencies(flag: &str, frequencies: &[usize]) -> Result<(), String> {
    let limits = crate::limits::Limits::from_env().map_err(|e| e.to_string())?;
    for &f in frequencies {
        let scene = balloon::balloon_scene(f)?;
        limits
            .check_memory(format!("{flag} {f}: the balloon"), scene.estimated_bytes())
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}
