//! The accuracy-versus-cost study behind `memstab bench` (issue 5): the k = 0.1 balloon against
//! its closed form under icosphere refinement with the time of each level split by phase, the
//! symmetry payoff on one tangent matrix (eigenvalues by irrep blocks against a dense full
//! eigen-decomposition and a sparse shift-invert of K), and the ponding ladder against its
//! closed form. Numbers are produced here; the command line formats and writes them.
//!
//! How the phases are timed (no hooks inside [`crate::run`]): the balloon path is followed
//! with the library calls `run` makes ([`solve_at`] for the start, [`follow`] for the path,
//! [`Stability::spectrum_of`] at every converged point), reading the phase times that
//! [`crate::adapted::SymmetricProblem`] keeps: `model.evaluate` (assembly) and the restriction
//! of residual, loads and tangent to the fixed-point space (projection). What is left of the path follower's wall time is the dense linear algebra
//! of the fixed-point system (factorisations and solves of a matrix of size m + 1, m the
//! symmetric unknowns) and step control. The stability phase is timed around each
//! `spectrum_of`, which assembles K again; that assembly is re-timed by one extra
//! `model.evaluate` at the same point (not counted in the totals) and moved to the assembly
//! column. Critical-point localisation and output writing, which `run` also does, are not
//! part of this study.

use crate::adapted::{AdaptedBasis, SymmetricProblem};
use crate::continuation::{follow, solve_at, PathOptions};
use crate::linalg::SymmetricFactorization;
use crate::model::{Evaluation, FeModel, Model, Request};
use crate::scene::{Analysis, Scene};
use crate::stability::Stability;
use crate::study::{Measure, Study};
use nalgebra::DMatrix;
use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

/// Closed-form pressure maximum p R/(μH) of the k = 0.1 balloon.
pub const P_MAX: f64 = 1.3551069;
/// Closed-form pressure minimum p R/(μH) of the k = 0.1 balloon.
pub const P_MIN: f64 = 1.1487477;
/// T0/(μ H λ0²) of the ponding scene (k = 0, λ0 = 1.1): γ_{m,k} = this × j²_{m,k}.
pub const PONDING_SCALE: f64 = 0.3599389;

/// The bundled balloon scene text (k = 0.1, icosphere `frequency = 8`).
pub const BALLOON_TOML: &str = include_str!("../scenes/balloon.toml");
/// The bundled ponding scene text (C7v disc, `divisions = 16`).
pub const PONDING_TOML: &str = include_str!("../scenes/ponding.toml");

/// j²_{m,k}, squares of the zeros of the Bessel functions J_m, for the rungs the study uses.
pub const BESSEL_J2: [((usize, usize), f64); 4] = [
    ((0, 1), 5.783186),
    ((1, 1), 14.681971),
    ((2, 1), 26.374616),
    ((3, 1), 40.706466),
];

/// The balloon scene on an icosphere of `frequency`.
pub fn balloon_scene(frequency: usize) -> Result<Scene, String> {
    let text = BALLOON_TOML.replace("frequency = 8 ", &format!("frequency = {frequency} "));
    Scene::from_toml_str(&text, &format!("balloon, frequency {frequency}"))
        .map_err(|e| e.to_string())
}

/// The ponding scene on a C7v disc with `divisions`, density swept over [0, `max`] in
/// `samples` steps.
pub fn ponding_scene(divisions: usize, max: f64, samples: usize) -> Result<Scene, String> {
    let text = PONDING_TOML
        .replace("divisions = 16 ", &format!("divisions = {divisions} "))
        .replace("max = 46.0 ", &format!("max = {max} "))
        .replace("samples = 92", &format!("samples = {samples}"));
    Scene::from_toml_str(&text, &format!("ponding, divisions {divisions}"))
        .map_err(|e| e.to_string())
}

pub use crate::run::{path_options, state_scale};

/// Solves the start state as `run` does (the reference scaled by `start.stretch`, every
/// parameter at `params`, no constraint active, at least 50 Newton iterations), then sets the
/// `"initial"` constraint targets there. Returns the displacement over all unknowns.
pub fn solve_start(study: &mut Study, params: &[f64]) -> Result<Vec<f64>, String> {
    crate::run::solve_start(study, params)
        .map(|(u, _, _)| u)
        .map_err(|e| e.to_string())
}

/// One refinement level of the balloon study.
#[derive(Debug, Clone)]
pub struct BalloonLevel {
    /// Icosphere frequency f.
    pub frequency: usize,
    /// Triangles (20 f²).
    pub elements: usize,
    /// Unknowns N (3 × nodes).
    pub unknowns: usize,
    /// Unknowns of the Ih fixed-point space the path is solved in.
    pub symmetric_unknowns: usize,
    /// Converged path points.
    pub points: usize,
    /// Model evaluations along the path (start and path).
    pub evaluations: usize,
    /// Pressure maximum found.
    pub p_max: f64,
    /// Pressure minimum found.
    pub p_min: f64,
    /// Time of model.evaluate (path + stability).
    pub assembly: Duration,
    /// Time of restrictions to the fixed-point basis during the path.
    pub projection: Duration,
    /// Rest of the path follower: dense factorisations/solves of the fixed-point system, steps.
    pub continuation: Duration,
    /// Building the adapted basis (once).
    pub adapted_basis: Duration,
    /// Stability spectra at every point, without their assembly; `None` when skipped.
    pub eigen: Option<Duration>,
    /// Of `eigen`: the block restrictions (estimated from three points).
    pub eigen_restrict: Option<Duration>,
    /// Wall time of the whole level (scene to last spectrum), without the re-timing evaluations.
    pub total: Duration,
    /// The state (u, params) at the pressure maximum.
    pub at_max: (Vec<f64>, Vec<f64>),
}

impl BalloonLevel {
    /// Relative error of the pressure maximum against the closed form.
    pub fn err_max(&self) -> f64 {
        (self.p_max - P_MAX).abs() / P_MAX
    }
    /// Relative error of the pressure minimum against the closed form.
    pub fn err_min(&self) -> f64 {
        (self.p_min - P_MIN).abs() / P_MIN
    }
    /// The rest: total minus the named phases.
    pub fn rest(&self) -> Duration {
        self.total
            .saturating_sub(self.assembly)
            .saturating_sub(self.projection)
            .saturating_sub(self.continuation)
            .saturating_sub(self.adapted_basis)
            .saturating_sub(self.eigen.unwrap_or_default())
    }
}

/// Follows the balloon of `frequency` through its pressure maximum and minimum, timing each
/// phase; with `stability` the spectrum by irrep is computed at every converged point (as
/// `run` does). Returns the level and the study (for the payoff at the maximum).
pub fn balloon_level(frequency: usize, stability: bool) -> Result<(BalloonLevel, Study), String> {
    let start = Instant::now();
    let mut study = Study::build(balloon_scene(frequency)?).map_err(|e| e.to_string())?;
    let params0 = study.start.clone();
    let mut assembly = Duration::ZERO;
    let mut projection = Duration::ZERO;
    let mut evaluations = 0;
    let t_start = Instant::now();
    // The start, timed like the path.
    let (q_start, params_start) = {
        let opts = PathOptions {
            max_iterations: path_options(&study).max_iterations.max(50),
            ..path_options(&study)
        };
        let u0 = study.start_displacement();
        let q0 = study.basis.restrict(&u0);
        let mut problem = SymmetricProblem::new(
            &study.model,
            &study.basis,
            &[],
            params0.clone(),
            study.control,
        );
        let lambda = problem.free_values(&params0);
        let (q, lambda, _) = solve_at(&mut problem, &q0, &lambda, &opts)
            .map_err(|e| format!("the start state did not converge: {e}"))?;
        assembly += problem.times.assembly;
        projection += problem.times.projection;
        evaluations += problem.times.evaluations;
        (q, problem.parameters(&lambda))
    };
    let u_start = {
        let mut u = vec![0.0; study.basis.unknowns()];
        study.basis.expand(&q_start, &mut u);
        u
    };
    study.set_targets(&u_start, &params_start);
    let study_ref: &Study = &study;
    let opts = path_options(study_ref);
    let stretch = study_ref
        .measures
        .iter()
        .position(|(_, m)| *m == Measure::Stretch)
        .ok_or("the balloon has no stretch measure")?;
    let stop_stretch = match &study_ref.scene.analysis {
        Analysis::Path(p) => p.stop_stretch,
        _ => None,
    };
    let problem_for = || {
        SymmetricProblem::new(
            &study_ref.model,
            &study_ref.basis,
            &study_ref.constraints,
            params_start.clone(),
            study_ref.control,
        )
    };
    let mut problem = problem_for();
    let lambda0 = problem.free_values(&params_start);
    let probe = problem_for();
    let path = follow(
        &mut problem,
        &q_start,
        &lambda0,
        &opts,
        |p| {
            stop_stretch.is_some_and(|s| {
                let u = probe.displacement(&p.q);
                study_ref.measure(&u, &probe.parameters(&p.lambda))[stretch] >= s
            })
        },
        |_| {},
    )?;
    let path_time = t_start.elapsed();
    assembly += problem.times.assembly;
    projection += problem.times.projection;
    evaluations += problem.times.evaluations;
    let continuation = path_time.saturating_sub(assembly + projection);
    let turning = |kind: f64| {
        path.turning_points
            .iter()
            .find(|t| t.kind * kind > 0.0)
            .map(|t| t.point.clone())
    };
    let max = turning(1.0).ok_or("the path has no pressure maximum")?;
    let min = turning(-1.0).ok_or("the path has no pressure minimum")?;
    let at_max = (probe.displacement(&max.q), probe.parameters(&max.lambda));

    let (mut adapted_basis, mut eigen, mut eigen_restrict) = (Duration::ZERO, None, None);
    let mut retimed = Duration::ZERO;
    if stability {
        let t = Instant::now();
        let adapted = AdaptedBasis::new(&study_ref.action, study_ref.model.layout())
            .map_err(|e| e.to_string())?;
        adapted_basis = t.elapsed();
        let stab = Stability::new(&study_ref.model, &adapted);
        let mut eval = study_ref.model.new_evaluation();
        let mut spectra = Duration::ZERO;
        let mut in_spectra_assembly = Duration::ZERO;
        let mut restrict = Duration::ZERO;
        let sample = [0, path.points.len() / 2, path.points.len() - 1];
        let mut work = Vec::new();
        for (i, p) in path.points.iter().enumerate() {
            let u = probe.displacement(&p.q);
            let params = probe.parameters(&p.lambda);
            let t = Instant::now();
            stab.spectrum_of(&u, &params, &study_ref.constraints, &mut eval, None, false)
                .map_err(|e| e.to_string())?;
            spectra += t.elapsed();
            // Re-timing (not counted in the total): the assembly inside spectrum_of, and at
            // three points the block restrictions.
            let t = Instant::now();
            study_ref
                .model
                .evaluate(&u, &params, Request::ALL, &mut eval)
                .map_err(|e| e.to_string())?;
            let dt = t.elapsed();
            in_spectra_assembly += dt;
            retimed += dt;
            if sample.contains(&i) {
                let t = Instant::now();
                for ib in &adapted.irreps {
                    let k =
                        ib.partners[0].restrict_tangent(study_ref.model.layout(), &eval, &mut work);
                    std::hint::black_box(k);
                }
                let dt = t.elapsed();
                restrict += dt;
                retimed += dt;
            }
        }
        assembly += in_spectra_assembly;
        eigen = Some(spectra.saturating_sub(in_spectra_assembly));
        eigen_restrict = Some(restrict.mul_f64(path.points.len() as f64 / sample.len() as f64));
    }
    let total = start.elapsed().saturating_sub(retimed);
    let level = BalloonLevel {
        frequency,
        elements: study_ref.model.layout().triangles().len(),
        unknowns: study_ref.basis.unknowns(),
        symmetric_unknowns: study_ref.basis.dim(),
        points: path.points.len(),
        evaluations,
        p_max: max.lambda[0],
        p_min: min.lambda[0],
        assembly,
        projection,
        continuation,
        adapted_basis,
        eigen,
        eigen_restrict,
        total,
        at_max,
    };
    Ok((level, study))
}

/// Observed order between two levels of frequency f and 2f: log2(e_f / e_2f).
pub fn observed_order(coarse: f64, fine: f64) -> f64 {
    (coarse / fine).log2()
}

/// Richardson extrapolation assuming order 2 with h halved: (4 p_fine − p_coarse) / 3.
pub fn richardson(coarse: f64, fine: f64) -> f64 {
    (4.0 * fine - coarse) / 3.0
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

/// One eigenvalue of K found by blocks: value, irrep, multiplicity d_μ.
#[derive(Debug, Clone)]
pub struct BlockValue {
    /// Eigenvalue.
    pub value: f64,
    /// Irrep name.
    pub irrep: String,
    /// d_μ, exact by construction.
    pub multiplicity: usize,
}

/// The symmetry payoff on one tangent matrix.
#[derive(Debug, Clone)]
pub struct Payoff {
    /// Icosphere frequency.
    pub frequency: usize,
    /// Group.
    pub group: String,
    /// Unknowns N.
    pub unknowns: usize,
    /// (irrep, d, block size) per irrep.
    pub blocks: Vec<(String, usize, usize)>,
    /// Building the adapted basis (once per mesh and group, not per matrix).
    pub adapted_basis: Duration,
    /// Assembling K (model.evaluate).
    pub assembly: Duration,
    /// Restricting K to every block (B_μᵀ K B_μ).
    pub restrict: Duration,
    /// Dense eigenvalues of every block (faer self_adjoint_eigenvalues).
    pub block_eigen: Duration,
    /// Every eigenvalue by blocks, ascending.
    pub by_blocks: Vec<BlockValue>,
    /// One [`Stability::spectrum_of`] at the state, as `run` calls it at every path point
    /// (assembly, restriction, rigid-mode deflation, Zᵀ K Z, dense eigen, no vectors).
    pub stability_spectrum: Duration,
    /// Building the dense K, when the dense comparison ran.
    pub dense_build: Option<Duration>,
    /// Dense full eigenvalues of K (faer), when run.
    pub dense_eigen: Option<Duration>,
    /// max |λ_blocks − λ_dense| / max |λ| over the sorted multisets.
    pub dense_difference: Option<f64>,
    /// Sparse shift-invert: (shift, factorisation time, Lanczos time, the values nearest the
    /// shift ascending, max relative difference from the blocks' values).
    pub shift_invert: Option<ShiftInvert>,
}

/// A sparse shift-invert solve of the full K by faer.
#[derive(Debug, Clone)]
pub struct ShiftInvert {
    /// The shift σ.
    pub shift: f64,
    /// Symbolic analysis + numeric LBLᵀ of K − σI.
    pub factorisation: Duration,
    /// faer `partial_self_adjoint_eigen` on (K − σI)⁻¹.
    pub lanczos: Duration,
    /// The eigenvalues of K it found, ascending.
    pub values: Vec<f64>,
    /// Converged count reported by faer.
    pub converged: usize,
}

impl Payoff {
    /// Time of all eigenvalues by blocks (restriction + dense block eigen).
    pub fn blocks_time(&self) -> Duration {
        self.restrict + self.block_eigen
    }

    /// The `n` eigenvalues of K nearest `shift` by blocks (each d_μ times), ascending.
    pub fn nearest(&self, shift: f64, n: usize) -> Vec<f64> {
        nearest(
            self.by_blocks
                .iter()
                .flat_map(|b| std::iter::repeat_n(b.value, b.multiplicity)),
            shift,
            n,
        )
    }
}

fn nearest(values: impl Iterator<Item = f64>, shift: f64, n: usize) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(|a, b| (a - shift).abs().total_cmp(&(b - shift).abs()));
    v.truncate(n);
    v.sort_by(f64::total_cmp);
    v
}

/// The operator (K − σI)⁻¹ by a sparse LBLᵀ factorisation.
#[derive(Debug)]
struct InverseOp<'a>(&'a SymmetricFactorization);

impl faer::matrix_free::LinOp<f64> for InverseOp<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: faer::Par) -> faer::dyn_stack::StackReq {
        faer::dyn_stack::StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.0.n()
    }
    fn ncols(&self) -> usize {
        self.0.n()
    }
    fn apply(
        &self,
        mut out: faer::MatMut<'_, f64>,
        rhs: faer::MatRef<'_, f64>,
        _par: faer::Par,
        _stack: &mut faer::dyn_stack::MemStack,
    ) {
        out.copy_from(rhs);
        self.0
            .solve_mat_in_place(out)
            .expect("the shifted matrix was factorised");
    }
    fn conj_apply(
        &self,
        out: faer::MatMut<'_, f64>,
        rhs: faer::MatRef<'_, f64>,
        par: faer::Par,
        stack: &mut faer::dyn_stack::MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

/// The `n` eigenvalues of K nearest `shift` by sparse shift-invert: LBLᵀ of K − σI (our
/// [`SymmetricFactorization`]) as the operator of faer's `partial_self_adjoint_eigen`.
pub fn shift_invert(
    model: &FeModel,
    eval: &Evaluation,
    shift: f64,
    n: usize,
) -> Result<ShiftInvert, String> {
    if !eval.rank_one.is_empty() {
        return Err("K has rank-one terms; the sparse shift-invert does not handle them".into());
    }
    let pattern = model.pattern();
    let t = Instant::now();
    let mut values = eval.tangent.clone();
    for i in 0..pattern.n() {
        let p = pattern.position(i, i).expect("diagonal in pattern");
        values[p] -= shift;
    }
    let mut f = SymmetricFactorization::new(pattern).map_err(|e| e.to_string())?;
    f.factorize(&values).map_err(|e| e.to_string())?;
    let factorisation = t.elapsed();
    let t = Instant::now();
    let dim = pattern.n();
    let op = InverseOp(&f);
    let params = faer::matrix_free::eigen::PartialEigenParams {
        min_dim: (2 * n).max(32).min(dim),
        max_dim: (4 * n).max(64).min(dim),
        max_restarts: 1000,
        ..Default::default()
    };
    let par = faer::Par::Seq;
    let mut vecs = faer::Mat::<f64>::zeros(dim, n);
    let mut vals = vec![0.0; n];
    let v0 = faer::Col::<f64>::from_fn(dim, |i| 1.0 + ((i * 7919) % 101) as f64 / 101.0);
    let mut mem = faer::dyn_stack::MemBuffer::new(
        faer::matrix_free::eigen::partial_self_adjoint_eigen_scratch(&op, n, par, params),
    );
    let info = faer::matrix_free::eigen::partial_self_adjoint_eigen(
        vecs.as_mut(),
        &mut vals,
        &op,
        v0.as_ref(),
        1e-12,
        par,
        faer::dyn_stack::MemStack::new(&mut mem),
        params,
    );
    let lanczos = t.elapsed();
    let mut values: Vec<f64> = vals
        .iter()
        .take(info.n_converged_eigen)
        .map(|&theta| shift + 1.0 / theta)
        .collect();
    values.sort_by(f64::total_cmp);
    Ok(ShiftInvert {
        shift,
        factorisation,
        lanczos,
        values,
        converged: info.n_converged_eigen,
    })
}

/// The symmetry payoff at the state (u, params) of `study`: every eigenvalue of K by irrep
/// blocks against a dense full eigen-decomposition of K (when `dense`), and a sparse
/// shift-invert of K for the `lowest` eigenvalues nearest a small negative shift (when
/// `sparse`).
pub fn payoff(
    study: &Study,
    u: &[f64],
    params: &[f64],
    dense: bool,
    sparse: bool,
    lowest: usize,
) -> Result<Payoff, String> {
    let model = &study.model;
    let t = Instant::now();
    let adapted = AdaptedBasis::new(&study.action, model.layout()).map_err(|e| e.to_string())?;
    let adapted_basis = t.elapsed();
    let mut eval = model.new_evaluation();
    let t = Instant::now();
    model
        .evaluate(u, params, Request::ALL, &mut eval)
        .map_err(|e| e.to_string())?;
    let assembly = t.elapsed();
    let mut work = Vec::new();
    let t = Instant::now();
    let blocks_k: Vec<DMatrix<f64>> = adapted
        .irreps
        .iter()
        .map(|ib| ib.partners[0].restrict_tangent(model.layout(), &eval, &mut work))
        .collect();
    let restrict = t.elapsed();
    let t = Instant::now();
    let mut by_blocks = Vec::new();
    for (ib, k) in adapted.irreps.iter().zip(&blocks_k) {
        let n = k.nrows();
        if n == 0 {
            continue;
        }
        let m = faer::Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)]);
        let values = m
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .map_err(|e| format!("block {}: {e:?}", ib.name))?;
        by_blocks.extend(values.into_iter().map(|value| BlockValue {
            value,
            irrep: ib.name.clone(),
            multiplicity: ib.dim,
        }));
    }
    let block_eigen = t.elapsed();
    by_blocks.sort_by(|a, b| a.value.total_cmp(&b.value));
    let stab = Stability::new(model, &adapted);
    let mut eval2 = model.new_evaluation();
    let t = Instant::now();
    stab.spectrum_of(u, params, &study.constraints, &mut eval2, None, false)
        .map_err(|e| e.to_string())?;
    let stability_spectrum = t.elapsed();
    let blocks = adapted
        .irreps
        .iter()
        .map(|ib| (ib.name.clone(), ib.dim, ib.partners[0].dim()))
        .collect();
    let mut out = Payoff {
        frequency: 0,
        group: study.action.group().name().to_string(),
        unknowns: model.unknowns(),
        blocks,
        adapted_basis,
        assembly,
        restrict,
        block_eigen,
        by_blocks,
        stability_spectrum,
        dense_build: None,
        dense_eigen: None,
        dense_difference: None,
        shift_invert: None,
    };
    let all: Vec<f64> = out
        .by_blocks
        .iter()
        .flat_map(|b| std::iter::repeat_n(b.value, b.multiplicity))
        .collect();
    if dense {
        let t = Instant::now();
        let k = dense_tangent(model, &eval);
        out.dense_build = Some(t.elapsed());
        let t = Instant::now();
        let mut values = k
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .map_err(|e| format!("dense eigen: {e:?}"))?;
        out.dense_eigen = Some(t.elapsed());
        values.sort_by(f64::total_cmp);
        if values.len() != all.len() {
            return Err(format!(
                "the blocks give {} eigenvalues (with multiplicity), K has {}",
                all.len(),
                values.len()
            ));
        }
        let scale = values
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300);
        out.dense_difference = Some(
            values
                .iter()
                .zip(&all)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
                / scale,
        );
    }
    if sparse {
        // A small negative shift: K is singular (six rigid-body modes).
        let scale = all.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let shift = -1e-3 * scale;
        out.shift_invert = Some(shift_invert(model, &eval, shift, lowest)?);
    }
    Ok(out)
}

/// One rung of the ponding ladder found on a mesh.
#[derive(Debug, Clone)]
pub struct Rung {
    /// (m, k) of the closed form.
    pub mk: (usize, usize),
    /// Irrep of the singular block.
    pub irrep: String,
    /// Multiplicity d_μ.
    pub multiplicity: usize,
    /// Critical density found.
    pub rho: f64,
    /// Closed form PONDING_SCALE × j²_{m,k}.
    pub exact: f64,
}

/// A ponding run on one disc.
#[derive(Debug, Clone)]
pub struct PondingLevel {
    /// Radial divisions of the C7v disc.
    pub divisions: usize,
    /// Triangles.
    pub elements: usize,
    /// Unknowns.
    pub unknowns: usize,
    /// Rungs found (the first of each tabulated (m, 1)).
    pub rungs: Vec<Rung>,
    /// Wall time of `run` (start state, sweep, localisation).
    pub time: Duration,
}

/// The ponding ladder on a C7v disc with `divisions`, density swept over [0, 20] in 60 steps
/// (past the (3, 1) rung at 14.65 even on coarse discs), by [`crate::run::run`].
pub fn ponding_level(divisions: usize) -> Result<PondingLevel, String> {
    let t = Instant::now();
    let mut study = Study::build(ponding_scene(divisions, 20.0, 60)?).map_err(|e| e.to_string())?;
    let r = crate::run::run(&mut study, |_, _| {})
        .map_err(|e| e.to_string())?
        .report;
    let time = t.elapsed();
    let mut rungs = Vec::new();
    for &((m, k), j2) in &BESSEL_J2 {
        let found = r
            .critical
            .iter()
            .filter(|c| wave_number(&study, &c.mode) == m)
            .min_by(|a, b| a.parameters[0].total_cmp(&b.parameters[0]));
        if let Some(c) = found {
            rungs.push(Rung {
                mk: (m, k),
                irrep: c.irrep.clone(),
                multiplicity: c.multiplicity,
                rho: c.parameters[0],
                exact: PONDING_SCALE * j2,
            });
        }
    }
    Ok(PondingLevel {
        divisions,
        elements: study.model.layout().triangles().len(),
        unknowns: study.model.unknowns(),
        rungs,
        time,
    })
}

/// The wave number of a critical mode about z (see [`crate::critical::wave_number`]).
pub fn wave_number(study: &Study, mode: &[f64]) -> usize {
    crate::critical::wave_number(study.model.reference(), study.model.layout(), mode, 12)
}

/// Writes `path` whole: into a temporary file in the same directory, then renamed over it.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    meshes::write::write_whole(path, fill).map_err(|e| match e {
        meshes::MeshError::Io { source, .. } => source,
        other => std::io::Error::other(other.to_string()),
    })
}

/// Writes the full tangent K of `eval` (sparse part only; rank-one terms are refused) in
/// Matrix Market coordinate real symmetric format, lower triangle, 1-based; returns the
/// number of entries written.
pub fn write_matrix_market(
    path: &Path,
    model: &FeModel,
    eval: &Evaluation,
    comment: &str,
) -> Result<usize, String> {
    if !eval.rank_one.is_empty() {
        return Err(format!(
            "the tangent has {} rank-one term(s) (a global constraint such as a gas amount); \
             a sparse Matrix Market file cannot hold them and this version does not add them",
            eval.rank_one.len()
        ));
    }
    let pattern = model.pattern();
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    let n = pattern.n();
    let count = (0..n)
        .map(|j| {
            (col_ptr[j]..col_ptr[j + 1])
                .filter(|&p| row_idx[p] >= j)
                .count()
        })
        .sum::<usize>();
    write_atomic(path, |w| {
        writeln!(w, "%%MatrixMarket matrix coordinate real symmetric")?;
        for line in comment.lines() {
            writeln!(w, "% {line}")?;
        }
        writeln!(w, "{n} {n} {count}")?;
        for j in 0..n {
            let range = col_ptr[j]..col_ptr[j + 1];
            for (&i, &v) in row_idx[range.clone()].iter().zip(&eval.tangent[range]) {
                if i >= j {
                    writeln!(w, "{} {} {v:.17e}", i + 1, j + 1)?;
                }
            }
        }
        Ok(())
    })
    .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(count)
}
