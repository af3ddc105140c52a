//! Stability along a path *without* symmetry: at every state the index from the inertia of a
//! sparse `LBLᵀ` of the full K + τI, the lowest eigenvalues by shift-invert Lanczos
//! ([`crate::linalg::eigen::nearest_eigenvalues`]) and, for small problems, every eigenvalue
//! by a dense eigen-decomposition of K — against the index by irrep blocks of the same path.

use crate::adapted::AdaptedBasis;
use crate::linalg::{eigen, SymmetricFactorization};
use crate::model::{Model, Request};
use crate::stability::{Detail, Stability};
use crate::study::mesh::MeshStudy;
use std::time::{Duration, Instant};

/// τ / max|K_ij| of [`full_path_stability`]: the index without symmetry is the negative count
/// of K + τI, which puts the rigid-body zero modes (≈ 1e-16 max|K_ij| at an equilibrium) on
/// the positive side; an eigenvalue of a deformation mode in (−τ, 0) would be missed.
pub const FULL_INDEX_SHIFT: f64 = 1e-8;
/// σ / max|K_ij| of the shift-invert: σ = −1e-3 max|K_ij| (as in the payoff).
pub const SHIFT_INVERT_SHIFT: f64 = -1e-3;

/// Dense eigenvalues of the full K along a path (small problems only).
#[derive(Debug, Clone)]
pub struct DensePath {
    /// Building the dense K at every point.
    pub build: Duration,
    /// faer `self_adjoint_eigenvalues` at every point.
    pub eigen: Duration,
    /// Negative count below −τ max|K_ij| at every point.
    pub indices: Vec<usize>,
    /// Eigenvalues in [−τ, τ] max|K_ij| at every point (the rigid-body modes).
    pub zero_cluster: Vec<usize>,
    /// The lowest eigenvalue outside that cluster at every point.
    pub lowest: Vec<f64>,
}

/// Stability along a path *without* symmetry, on the full K at every state.
#[derive(Debug, Clone)]
pub struct FullPathStability {
    /// States analysed.
    pub points: usize,
    /// The eigenvalues asked of the shift-invert at every point.
    pub lowest_count: usize,
    /// Symbolic analysis of the pattern (once per path; our [`SymmetricFactorization::new`]).
    pub symbolic: Duration,
    /// `model.evaluate` at every point.
    pub assembly: Duration,
    /// Numeric LBLᵀ of K + τI (τ = [`FULL_INDEX_SHIFT`] max|K_ij|) and its inertia.
    pub inertia: Duration,
    /// Numeric LBLᵀ of K − σI (σ = [`SHIFT_INVERT_SHIFT`] max|K_ij|).
    pub shift_invert_factorisation: Duration,
    /// Lanczos on (K − σI)⁻¹ (ours, full reorthogonalisation, restarted on breakdown; faer's
    /// `partial_self_adjoint_eigen` can loop forever on these matrices, see
    /// [`eigen::nearest_eigenvalues`]).
    pub lanczos: Duration,
    /// The index (negative count of K + τI) at every point.
    pub indices: Vec<usize>,
    /// neg(K − τI) − neg(K + τI) at every point: the eigenvalues in (−τ, τ], expected to be
    /// the rigid-body modes (a check, not timed).
    pub zero_cluster: Vec<usize>,
    /// Rigid motions the model keeps (6 for a free body).
    pub rigid_modes: usize,
    /// The lowest eigenvalue the shift-invert found outside [−τ, τ] max|K_ij| at every point
    /// (NaN when none).
    pub lowest: Vec<f64>,
    /// max|K_ij| at every point.
    pub scales: Vec<f64>,
    /// The fewest eigenvalues the Lanczos iteration reported converged at a point.
    pub converged_min: usize,
    /// Dense eigenvalues of K at every point, when asked for.
    pub dense: Option<DensePath>,
    /// The index by irrep blocks of the same states, timed as the index without symmetry
    /// is: one pass over the states right before that one's, a fresh analysis (its
    /// blocks' symbolic analyses included; the adapted basis and its patterns built before,
    /// as K's pattern is with the model).
    pub blocks_index: Duration,
    /// The index by blocks at every point of that pass.
    pub blocks_indices: Vec<usize>,
    /// The same blocks' index at the same states once more, with the caller paused
    /// [`PAUSE`] before each state (the analysis kept from the pass above, its
    /// factorisations made): the cost of the index when the thread pool has been idle for a
    /// while, as it is between a path's steps.
    pub blocks_index_paused: Duration,
}

/// The pause before each state of [`FullPathStability::blocks_index_paused`].
pub const PAUSE: Duration = Duration::from_millis(10);

impl FullPathStability {
    /// The index alone without symmetry, all points: symbolic analysis, assembly and the
    /// inertia factorisation (no eigenvalues, no irreps).
    pub fn index_only(&self) -> Duration {
        self.symbolic + self.assembly + self.inertia
    }

    /// Index and lowest eigenvalues without symmetry, all points: symbolic analysis,
    /// assembly, the inertia factorisation and the shift-invert.
    pub fn total(&self) -> Duration {
        self.symbolic
            + self.assembly
            + self.inertia
            + self.shift_invert_factorisation
            + self.lanczos
    }
}

/// The index by irrep blocks at every state, one pass timed as [`full_path_stability`]'s
/// index without symmetry: a fresh [`Stability`] of a fresh adapted basis, whose patterns are
/// built before the clock starts (K's pattern comes with the model), its blocks' symbolic
/// analyses at the first state inside it. The time and the index at every state, then the
/// time of a second pass with a [`PAUSE`] before each state (not timed).
fn blocks_index_pass(
    study: &MeshStudy,
    states: &[(Vec<f64>, Vec<f64>)],
) -> Result<(Duration, Vec<usize>, Duration), String> {
    let model = &study.model;
    let adapted = AdaptedBasis::new(&study.action, model.layout()).map_err(|e| e.to_string())?;
    let stability = Stability::new(model, &adapted).with_patterns();
    let mut eval = stability.new_evaluation();
    let mut index = |(u, params): &(Vec<f64>, Vec<f64>)| {
        stability
            .analyse(
                u,
                params,
                &study.constraints,
                &mut eval,
                None,
                Detail::Inertia,
            )
            .map(|spectrum| spectrum.index)
            .map_err(|e| e.to_string())
    };
    let t = Instant::now();
    let indices = states
        .iter()
        .map(&mut index)
        .collect::<Result<Vec<_>, _>>()?;
    let time = t.elapsed();
    let mut paused = Duration::ZERO;
    for state in states {
        std::thread::sleep(PAUSE);
        let t = Instant::now();
        index(state)?;
        paused += t.elapsed();
    }
    Ok((time, indices, paused))
}

/// The negative count of the matrix `values` on `f`'s pattern, by factorising it. A pivot
/// counted as zero (`FactorError::Singular`) still gives the inertia.
fn negative_count(f: &mut SymmetricFactorization, values: &[f64]) -> Result<usize, String> {
    let result = f.factorize(values);
    match (f.inertia(), result) {
        (Some(i), _) => Ok(i.negative),
        (None, Err(e)) => Err(e.to_string()),
        (None, Ok(())) => Err("the factorisation gave no inertia".into()),
    }
}

/// The values of K − `shift`·I on the pattern of K.
fn shifted(
    pattern: &crate::linalg::SymmetricPattern,
    tangent: &[f64],
    shift: f64,
) -> Result<Vec<f64>, String> {
    eigen::shifted_values(pattern, tangent, shift).map_err(|e| e.to_string())
}

/// Stability along a path without symmetry at `states` (e.g.
/// [`crate::bench::BalloonLevel::states`]): at every state K is assembled, the index is the
/// negative count of a sparse LBLᵀ of K + τI (our [`SymmetricFactorization`], symbolic
/// analysis once), and the `lowest` eigenvalues nearest σ = [`SHIFT_INVERT_SHIFT`] max|K_ij|
/// come from a sparse shift-invert Lanczos on a second numeric factorisation (of K − σI; the
/// Lanczos is ours, [`eigen::nearest_eigenvalues`], because faer's can loop forever once the
/// Krylov space of a symmetric K is exhausted); with `dense`, also every eigenvalue by a
/// dense eigen-decomposition of K. Refused when the study has active constraints (the index
/// by blocks is then that of the bordered system) or K has rank-one terms.
pub fn full_path_stability(
    study: &MeshStudy,
    states: &[(Vec<f64>, Vec<f64>)],
    lowest: usize,
    dense: bool,
) -> Result<FullPathStability, String> {
    if !study.constraints.is_empty() {
        return Err("the study has constraints: its index is that of the bordered system".into());
    }
    let model = &study.model;
    let (blocks_index, blocks_indices, blocks_index_paused) = blocks_index_pass(study, states)?;
    let pattern = model.pattern();
    let t = Instant::now();
    let mut f = SymmetricFactorization::new(pattern).map_err(|e| e.to_string())?;
    let symbolic = t.elapsed();
    let mut eval = model.new_evaluation();
    let mut out = FullPathStability {
        points: states.len(),
        lowest_count: lowest,
        symbolic,
        assembly: Duration::ZERO,
        inertia: Duration::ZERO,
        shift_invert_factorisation: Duration::ZERO,
        lanczos: Duration::ZERO,
        indices: Vec::with_capacity(states.len()),
        zero_cluster: Vec::with_capacity(states.len()),
        rigid_modes: model.rigid_motions().len(),
        lowest: Vec::with_capacity(states.len()),
        scales: Vec::with_capacity(states.len()),
        converged_min: usize::MAX,
        dense: dense.then(|| DensePath {
            build: Duration::ZERO,
            eigen: Duration::ZERO,
            indices: Vec::new(),
            zero_cluster: Vec::new(),
            lowest: Vec::new(),
        }),
        blocks_index,
        blocks_indices,
        blocks_index_paused,
    };
    let scale_of = |eval: &crate::model::Evaluation| {
        eval.tangent
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300)
    };
    // The index alone, one pass over the states (as the blocks' pass above): what the
    // eigenvalues below would otherwise put between two points is not in its time. K + τI
    // is written into one kept buffer, its diagonal found once (as the blocks do).
    let diagonal: Vec<usize> = (0..pattern.n())
        .map(|i| pattern.position(i, i).expect("diagonal in pattern"))
        .collect();
    let mut plus_tau = vec![0.0; pattern.nnz()];
    for (u, params) in states {
        let t = Instant::now();
        model
            .evaluate(u, params, Request::ALL, &mut eval)
            .map_err(|e| e.to_string())?;
        out.assembly += t.elapsed();
        if !eval.rank_one.is_empty() {
            return Err("K has rank-one terms; the sparse inertia does not include them".into());
        }
        let tau = FULL_INDEX_SHIFT * scale_of(&eval);
        // The index: inertia of K + τI.
        let t = Instant::now();
        plus_tau.copy_from_slice(&eval.tangent);
        for &p in &diagonal {
            plus_tau[p] += tau;
        }
        let index = negative_count(&mut f, &plus_tau)?;
        out.inertia += t.elapsed();
        out.indices.push(index);
    }
    // The checks and the eigenvalues, a second pass (its assembly not timed again).
    for ((u, params), &index) in states.iter().zip(&out.indices) {
        model
            .evaluate(u, params, Request::ALL, &mut eval)
            .map_err(|e| e.to_string())?;
        let scale = scale_of(&eval);
        let tau = FULL_INDEX_SHIFT * scale;
        out.scales.push(scale);
        // The check (not timed): how many eigenvalues lie in (−τ, τ].
        let below = negative_count(&mut f, &shifted(pattern, &eval.tangent, tau)?)?;
        out.zero_cluster.push(below.saturating_sub(index));
        // The lowest eigenvalues by shift-invert.
        let shift = SHIFT_INVERT_SHIFT * scale;
        let t = Instant::now();
        f.factorize(&shifted(pattern, &eval.tangent, shift)?)
            .map_err(|e| e.to_string())?;
        out.shift_invert_factorisation += t.elapsed();
        let t = Instant::now();
        let eigen::Nearest { values, converged } =
            eigen::nearest_eigenvalues(&f, shift, lowest).map_err(|e| e.to_string())?;
        out.lanczos += t.elapsed();
        out.converged_min = out.converged_min.min(converged);
        out.lowest.push(
            values
                .iter()
                .copied()
                .filter(|v| v.abs() > tau)
                .fold(f64::NAN, f64::min),
        );
        if let Some(d) = out.dense.as_mut() {
            let t = Instant::now();
            let k = super::dense_tangent(model, &eval);
            d.build += t.elapsed();
            let t = Instant::now();
            let values = k
                .self_adjoint_eigenvalues(faer::Side::Lower)
                .map_err(|e| format!("dense eigen: {e:?}"))?;
            d.eigen += t.elapsed();
            d.indices.push(values.iter().filter(|&&v| v < -tau).count());
            d.zero_cluster
                .push(values.iter().filter(|&&v| v.abs() <= tau).count());
            d.lowest.push(
                values
                    .iter()
                    .copied()
                    .filter(|v| v.abs() > tau)
                    .fold(f64::NAN, f64::min),
            );
        }
    }
    if states.is_empty() {
        out.converged_min = 0;
    }
    Ok(out)
}
