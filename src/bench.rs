//! The accuracy-versus-cost study behind `memstab bench` (issue 5): the k = 0.1 balloon against
//! its closed form under icosphere refinement with the time of each level split by phase, the
//! symmetry payoff on one tangent matrix (eigenvalues by irrep blocks against a dense full
//! eigen-decomposition and a sparse shift-invert of K) for the Ih balloon and a C8v disc
//! ([`payoff`], [`c8v_payoff`]), stability along the balloon path with and without symmetry
//! ([`full_path_stability`]), the scaling study with peak memory ([`scaling_level`],
//! [`memory`], [`fit_exponent`]), and the ponding ladder against its closed form. Numbers are
//! produced here; the command line formats and writes them. [`write_matrix_market`] writes a
//! tangent (with its rank-one terms, if any) for external solvers.
//!
//! How the phases are timed (no hooks inside [`crate::run`]): the balloon path is followed
//! with the library calls `run` makes ([`solve_at`] for the start, [`follow`] for the path,
//! [`Stability::spectrum_of`] at every converged point), reading the phase times that
//! [`crate::adapted::SymmetricProblem`] keeps: `model.evaluate` (assembly) and the restriction
//! of residual, loads and tangent to the fixed-point space (projection). What is left of the
//! path follower's wall time is the dense linear algebra of the fixed-point system
//! (factorisations and solves of a matrix of size m + 1, m the symmetric unknowns) and step
//! control. The stability phase is timed around each
//! `spectrum_of`, which assembles K again; that assembly is re-timed by one extra
//! `model.evaluate` at the same point (not counted in the totals) and moved to the assembly
//! column. Critical-point localisation and output writing, which `run` also does, are not
//! part of this study.

use crate::adapted::AdaptedBasis;
use crate::analysis::events::Extremum;
use crate::linalg::{SymmetricFactorization, SymmetricPattern};
use crate::model::{Evaluation, FeModel, Model, Request};
use crate::report::StateKind;
use crate::scene::{Analysis, Scene};
use crate::stability::{Stability, DENSE_BLOCK_LIMIT};
use crate::study::Study;
use nalgebra::DMatrix;
use std::io::Write;
use std::path::{Path, PathBuf};
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

/// The start state as `run` solves it ([`crate::analysis::equilibrium::solve_start`]): the
/// displacement over all unknowns.
pub fn solve_start(study: &mut Study, params: &[f64]) -> Result<Vec<f64>, String> {
    crate::analysis::equilibrium::solve_start(study, params)
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
    /// Pressure maximum found (`None` when the path ended before it).
    pub p_max: Option<f64>,
    /// Pressure minimum found (`None` when the path ended before it).
    pub p_min: Option<f64>,
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
    /// Wall time of all `spectrum_of` calls, their assembly included (what stability by
    /// irrep costs along the path, the adapted basis excepted); `None` when skipped.
    pub spectra: Option<Duration>,
    /// Wall time of the index by irrep blocks at every point, as `run` computes it
    /// ([`crate::stability::Detail::Inertia`] on the representatives' evaluation, its assembly
    /// included); `None` without stability.
    pub index: Option<Duration>,
    /// The rest of the run's events: turning points, and eigenvalues and localisation where
    /// the index changed.
    pub localisation: Duration,
    /// The instability index by irrep blocks at every point (empty without stability).
    pub indices: Vec<usize>,
    /// The lowest eigenvalue over all blocks at every point (rigid modes deflated; empty
    /// without stability).
    pub lowest: Vec<f64>,
    /// Wall time of the whole level (scene to last spectrum), without the re-timing evaluations.
    pub total: Duration,
    /// The state (u, params) at the pressure maximum (`None` when not reached).
    pub at_max: Option<(Vec<f64>, Vec<f64>)>,
    /// Every converged state (u, params), when asked for ([`LevelOptions::keep_states`]).
    pub states: Vec<(Vec<f64>, Vec<f64>)>,
}

impl BalloonLevel {
    /// Relative error of the pressure maximum against the closed form.
    pub fn err_max(&self) -> Option<f64> {
        self.p_max.map(|p| (p - P_MAX).abs() / P_MAX)
    }
    /// Relative error of the pressure minimum against the closed form.
    pub fn err_min(&self) -> Option<f64> {
        self.p_min.map(|p| (p - P_MIN).abs() / P_MIN)
    }
    /// The rest: total minus the named phases.
    pub fn rest(&self) -> Duration {
        self.total
            .saturating_sub(self.assembly)
            .saturating_sub(self.projection)
            .saturating_sub(self.continuation)
            .saturating_sub(self.adapted_basis)
            .saturating_sub(self.eigen.unwrap_or_default())
            .saturating_sub(self.index.unwrap_or_default())
    }
    /// What `memstab run` pays for this path: everything but the eigenvalue spectra (the
    /// path, the adapted basis and the index by blocks at every point).
    pub fn run_time(&self) -> Duration {
        self.total.saturating_sub(self.spectra.unwrap_or_default())
    }
    /// Path points per second of the per-point work alone: the path (assembly, projection,
    /// continuation) and the index by blocks at every point, without the one-off set-up
    /// (scene, mesh, start solve, adapted basis); `None` without stability.
    pub fn steady_points_per_second(&self) -> Option<f64> {
        let t = self.path_time() + self.index?;
        Some(self.points as f64 / t.as_secs_f64().max(1e-12))
    }
    /// Path points per second of [`BalloonLevel::run_time`].
    pub fn points_per_second(&self) -> f64 {
        self.points as f64 / self.run_time().as_secs_f64().max(1e-12)
    }
    /// The path without stability: assembly (of the path) + projection + continuation. The
    /// assembly re-timed inside the spectra is not counted.
    pub fn path_time(&self) -> Duration {
        let stability_assembly = self
            .spectra
            .zip(self.eigen)
            .map_or(Duration::ZERO, |(s, e)| s.saturating_sub(e));
        self.assembly.saturating_sub(stability_assembly) + self.projection + self.continuation
    }
    /// Stability by irrep along the path: the adapted basis (once) and every spectrum with
    /// its assembly; zero when skipped.
    pub fn stability_time(&self) -> Duration {
        self.adapted_basis + self.index.unwrap_or_default() + self.spectra.unwrap_or_default()
    }
}

/// What [`balloon_level_with`] computes besides the path.
#[derive(Debug, Clone, Copy, Default)]
pub struct LevelOptions {
    /// The spectrum by irrep at every converged point, as `run` computes it.
    pub stability: bool,
    /// Keep every converged state in [`BalloonLevel::states`] (for
    /// [`full_path_stability`]).
    pub keep_states: bool,
    /// Stop after this many converged points, the start included (`None`: where the scene's
    /// path ends, at the stretch 4).
    pub max_points: Option<usize>,
    /// Only the index by blocks at every point, no eigenvalue spectra (the scaling study).
    pub index_only: bool,
}

/// Follows the balloon of `frequency` through its pressure maximum and minimum, timing each
/// phase; with `stability` the spectrum by irrep is computed at every converged point (as
/// `run` does). Returns the level and the study (for the payoff at the maximum). The level
/// must reach both turning points.
pub fn balloon_level(frequency: usize, stability: bool) -> Result<(BalloonLevel, Study), String> {
    let opts = LevelOptions {
        stability,
        ..LevelOptions::default()
    };
    let (level, study) = balloon_level_with(frequency, &opts)?;
    if level.p_max.is_none() {
        return Err("the path has no pressure maximum".into());
    }
    if level.p_min.is_none() {
        return Err("the path has no pressure minimum".into());
    }
    Ok((level, study))
}

/// As [`balloon_level`], with the options of [`LevelOptions`]; a turning point the path does
/// not reach is `None`.
///
/// The path is what `memstab run` computes ([`crate::analysis::run_with`]: start solve,
/// adapted basis, path with the index by blocks at every point and the critical points
/// localised), with the run's own phase times; the eigenvalue spectra of `stability` are
/// computed by an observer at every accepted state and timed apart.
pub fn balloon_level_with(
    frequency: usize,
    options: &LevelOptions,
) -> Result<(BalloonLevel, Study), String> {
    if options.max_points == Some(0) {
        return Err("a path has at least one point".into());
    }
    let start = Instant::now();
    let mut scene = balloon_scene(frequency)?;
    if let (Some(n), Analysis::Path(p)) = (options.max_points, &mut scene.analysis) {
        // The path accepts up to `steps` steps after the start.
        p.steps = p.steps.min(n - 1);
    }
    let mut study = Study::build(scene).map_err(|e| e.to_string())?;
    let mut observer = SpectraObserver::default();
    let result = crate::analysis::run_with(&mut study, &mut observer).map_err(|e| e.to_string())?;
    let wall = start.elapsed();
    let study_ref: &Study = &study;
    let report = &result.report;
    let times = result.times;
    let turning = |kind: Extremum| {
        report
            .turning_points
            .iter()
            .find(|t| t.kind == kind)
            .map(|t| t.parameters[0])
    };
    let at_max = result.states.iter().find_map(|s| match &s.kind {
        StateKind::Turning(Extremum::Maximum) => {
            let mut params = study_ref.start.clone();
            params[0] = s.control;
            Some((s.u.clone(), params))
        }
        _ => None,
    });
    let indices: Vec<usize> = if options.stability {
        report.rows.iter().filter_map(|r| r.index).collect()
    } else {
        Vec::new()
    };
    // The eigenvalue spectra at every state, as a second pass over the states the observer
    // kept (timed apart: not part of what `run` does).
    let (mut eigen, mut eigen_restrict, mut spectra_wall) = (None, None, None);
    let mut lowest = Vec::new();
    let mut retimed_assembly = Duration::ZERO;
    if options.stability && !options.index_only {
        let adapted = AdaptedBasis::new(&study_ref.action, study_ref.model.layout())
            .map_err(|e| e.to_string())?;
        let stab = Stability::new(&study_ref.model, &adapted);
        let mut eval = study_ref.model.new_evaluation();
        let (mut spectra, mut restrict) = (Duration::ZERO, Duration::ZERO);
        let n = observer.states.len();
        let sample = [0, n / 2, n.saturating_sub(1)];
        let mut work = Vec::new();
        for (i, ((u, params), index)) in observer.states.iter().zip(&indices).enumerate() {
            let t = Instant::now();
            let spectrum = stab
                .spectrum_of(u, params, &study_ref.constraints, &mut eval, None, false)
                .map_err(|e| e.to_string())?;
            spectra += t.elapsed();
            if spectrum.index != *index {
                return Err(format!(
                    "f = {frequency}, point {i}: the index by eigenvalues {} and by inertia {index} differ",
                    spectrum.index
                ));
            }
            lowest.push(
                spectrum
                    .blocks
                    .iter()
                    .flat_map(|b| b.eigenvalues.first())
                    .copied()
                    .fold(f64::INFINITY, f64::min),
            );
            // The assembly inside spectrum_of, and at three points the block restrictions
            // (dense, or sparse above the dense limit).
            let t = Instant::now();
            study_ref
                .model
                .evaluate(u, params, Request::ALL, &mut eval)
                .map_err(|e| e.to_string())?;
            retimed_assembly += t.elapsed();
            if sample.contains(&i) {
                let t = Instant::now();
                let layout = study_ref.model.layout();
                for ib in &adapted.irreps {
                    if ib.first().dim() > DENSE_BLOCK_LIMIT {
                        std::hint::black_box(ib.first().restrict_tangent_sparse(layout, &eval));
                    } else {
                        std::hint::black_box(ib.first().restrict_tangent(layout, &eval, &mut work));
                    }
                }
                restrict += t.elapsed();
            }
        }
        spectra_wall = Some(spectra);
        eigen = Some(spectra.saturating_sub(retimed_assembly));
        eigen_restrict = Some(restrict.mul_f64(n as f64 / sample.len() as f64));
    }
    let problem = {
        let mut p = times.start_problem;
        p += times.steps.steps_problem;
        p
    };
    // The path follower without its evaluations: the start solve and the steps.
    let continuation =
        (times.start + times.steps.steps).saturating_sub(problem.assembly + problem.projection);
    let total = wall.saturating_sub(times.steps.progress);
    let level = BalloonLevel {
        frequency,
        elements: study_ref.model.layout().triangles().len(),
        unknowns: study_ref.basis.unknowns(),
        symmetric_unknowns: study_ref.basis.dim(),
        points: report.rows.len(),
        evaluations: problem.evaluations,
        p_max: turning(Extremum::Maximum),
        p_min: turning(Extremum::Minimum),
        assembly: problem.assembly + retimed_assembly,
        projection: problem.projection,
        continuation,
        adapted_basis: times.adapted_basis,
        eigen,
        eigen_restrict,
        spectra: spectra_wall,
        index: options.stability.then_some(times.index),
        localisation: times.steps.events.saturating_sub(times.index),
        indices,
        lowest,
        total: total + spectra_wall.unwrap_or_default(),
        at_max,
        states: if options.keep_states {
            observer.states
        } else {
            Vec::new()
        },
    };
    Ok((level, study))
}

/// Keeps every accepted state of a run.
#[derive(Default)]
struct SpectraObserver {
    states: Vec<(Vec<f64>, Vec<f64>)>,
}

impl crate::analysis::Observer for SpectraObserver {
    fn state(&mut self, u: &[f64], params: &[f64]) {
        self.states.push((u.to_vec(), params.to_vec()));
    }
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
    /// What K is, for the report (set by the caller; empty from [`payoff`]).
    pub case: String,
    /// Icosphere frequency (0 when K is not the balloon's).
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

/// The values of K − `shift`·I on the pattern (the sparse part of K in `tangent`).
fn shifted_values(pattern: &SymmetricPattern, tangent: &[f64], shift: f64) -> Vec<f64> {
    let mut values = tangent.to_vec();
    for i in 0..pattern.n() {
        let p = pattern.position(i, i).expect("diagonal in pattern");
        values[p] -= shift;
    }
    values
}

/// The (at most) `n` eigenvalues of K nearest `shift`, ascending, from a factorisation `f` of
/// K − shift·I: faer's `partial_self_adjoint_eigen` (thick-restart Lanczos) on its inverse.
/// Returns the values and the converged count faer reports.
fn lanczos_nearest(f: &SymmetricFactorization, shift: f64, n: usize) -> (Vec<f64>, usize) {
    let dim = f.n();
    let n = n.min(dim);
    if n == 0 {
        return (Vec::new(), 0);
    }
    let op = InverseOp(f);
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
    let mut values: Vec<f64> = vals
        .iter()
        .take(info.n_converged_eigen)
        .map(|&theta| shift + 1.0 / theta)
        .collect();
    values.sort_by(f64::total_cmp);
    (values, info.n_converged_eigen)
}

/// `w` minus its projections on the first `j` (orthonormal) columns of `v`, twice (classical
/// Gram–Schmidt with reorthogonalisation, as two matrix–vector products each).
fn orthogonalise(v: faer::MatRef<'_, f64>, j: usize, mut w: faer::ColMut<'_, f64>) {
    use faer::linalg::matmul::matmul;
    if j == 0 {
        return;
    }
    let vj = v.subcols(0, j);
    let mut c = faer::Col::<f64>::zeros(j);
    for _ in 0..2 {
        matmul(
            c.as_mut(),
            faer::Accum::Replace,
            vj.transpose(),
            w.as_ref(),
            1.0,
            faer::Par::Seq,
        );
        matmul(
            w.as_mut(),
            faer::Accum::Add,
            vj,
            c.as_ref(),
            -1.0,
            faer::Par::Seq,
        );
    }
}

/// A pseudo-random unit vector orthogonal to the first `j` columns of `v` (xorshift state
/// `rng`), or `None` when they span the space.
fn fresh_direction(v: faer::MatRef<'_, f64>, j: usize, rng: &mut u64) -> Option<faer::Col<f64>> {
    let mut r = faer::Col::<f64>::from_fn(v.nrows(), |_| {
        *rng ^= *rng << 13;
        *rng ^= *rng >> 7;
        *rng ^= *rng << 17;
        (*rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let before = r.norm_l2();
    orthogonalise(v, j, r.as_mut());
    let norm = r.norm_l2();
    if norm.is_nan() || norm <= 1e-8 * before {
        return None;
    }
    r /= faer::Scale(norm);
    Some(r)
}

/// The (at most) `n` eigenvalues of K nearest `shift`, ascending, from a factorisation `f` of
/// K − shift·I, by Lanczos on (K − shift·I)⁻¹ with full reorthogonalisation. When the Krylov
/// space is exhausted (β ≈ 0: with a symmetric K a single start vector reaches one direction
/// per *distinct* eigenvalue, e.g. only 130 of 486 at f = 4), the iteration goes on from a
/// fresh pseudo-random direction orthogonal to the basis, so it never stalls and may find
/// further copies of degenerate eigenvalues. The Krylov space grows (from max(3n, 60) by
/// max(n, 30) at a time) until the `n` Ritz values of largest |θ| have residuals |β_m s_mi| ≤
/// 1e-8 max|θ| (eigenvalue errors of the order of its square) or the space is the whole
/// space. Returns the values and how many of them converged.
///
/// Used at every path point instead of faer's `partial_self_adjoint_eigen`, which loops
/// forever in its reorthogonalisation when the Krylov space is exhausted (observed at f = 4).
fn krylov_nearest(
    f: &SymmetricFactorization,
    shift: f64,
    n: usize,
) -> Result<(Vec<f64>, usize), String> {
    let dim = f.n();
    let k = n.min(dim);
    if k == 0 {
        return Ok((Vec::new(), 0));
    }
    let mut rng = 0x2545_F491_4F6C_DD1D_u64;
    let mut target = (3 * k).max(60).min(dim);
    // Columns 0..=m: the Lanczos vectors and the next one.
    let mut v = faer::Mat::<f64>::zeros(dim, target + 1);
    let start = fresh_direction(v.as_ref(), 0, &mut rng).ok_or("empty start vector")?;
    v.col_mut(0).copy_from(&start);
    let (mut alpha, mut beta): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut exhausted = false;
    let mut largest = 0.0f64;
    let mut w = vec![0.0; dim];
    loop {
        if v.ncols() < target + 1 {
            v.resize_with(dim, target + 1, |_, _| 0.0);
        }
        while alpha.len() < target && !exhausted {
            let j = alpha.len();
            for (wi, vi) in w.iter_mut().zip(v.col(j).iter()) {
                *wi = *vi;
            }
            f.solve_in_place(&mut w).map_err(|e| e.to_string())?;
            let mut wc = faer::ColMut::from_slice_mut(&mut w);
            let a = v.col(j).transpose() * wc.as_ref();
            alpha.push(a);
            largest = largest.max(a.abs());
            orthogonalise(v.as_ref(), j + 1, wc.as_mut());
            let b = wc.norm_l2();
            if b > 1e-12 * largest {
                wc /= faer::Scale(b);
                beta.push(b);
                v.col_mut(j + 1).copy_from(wc.as_ref());
            } else {
                beta.push(0.0);
                match fresh_direction(v.as_ref(), j + 1, &mut rng) {
                    Some(r) => v.col_mut(j + 1).copy_from(&r),
                    None => exhausted = true,
                }
            }
        }
        let m = alpha.len();
        let t = faer::Mat::<f64>::from_fn(m, m, |i, j| {
            if i == j {
                alpha[i]
            } else if i == j + 1 || j == i + 1 {
                beta[i.min(j)]
            } else {
                0.0
            }
        });
        let eig = t
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| format!("Lanczos tridiagonal eigen: {e:?}"))?;
        let (theta, s) = (eig.S(), eig.U());
        let trailing = beta[m - 1];
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&x, &y| theta[y].abs().total_cmp(&theta[x].abs()));
        order.truncate(k);
        let top = order.first().map_or(0.0, |&i| theta[i].abs());
        let converged = order
            .iter()
            .filter(|&&i| (trailing * s[(m - 1, i)]).abs() <= 1e-8 * top)
            .count();
        if converged == order.len() || exhausted || m >= dim {
            let mut values: Vec<f64> = order.iter().map(|&i| shift + 1.0 / theta[i]).collect();
            values.sort_by(f64::total_cmp);
            return Ok((values, converged));
        }
        target = (target + k.max(30)).min(dim);
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
    let values = shifted_values(pattern, &eval.tangent, shift);
    let mut f = SymmetricFactorization::new(pattern).map_err(|e| e.to_string())?;
    f.factorize(&values).map_err(|e| e.to_string())?;
    let factorisation = t.elapsed();
    let t = Instant::now();
    let (values, converged) = lanczos_nearest(&f, shift, n);
    let lanczos = t.elapsed();
    Ok(ShiftInvert {
        shift,
        factorisation,
        lanczos,
        values,
        converged,
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
        .map(|ib| {
            ib.first()
                .restrict_tangent(model.layout(), &eval, &mut work)
        })
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
        .map(|ib| (ib.name.clone(), ib.dim, ib.first().dim()))
        .collect();
    let mut out = Payoff {
        case: String::new(),
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

/// The bundled disc scene with fluid above (C7v disc, `divisions = 16`), the source of the
/// C8v payoff case.
pub const DISC_FLUID_ABOVE_TOML: &str = include_str!("../scenes/disc_fluid_above.toml");

/// The density of the C8v payoff state: below the ponding limit (≈ 2.08), so the disc sags
/// under the fluid and is stable; Newton reaches it from the flat disc in a few iterations.
pub const C8V_DENSITY: f64 = 1.5;

/// `text` with the one occurrence of `from` replaced by `to` (an error names the scene when
/// the bundled file no longer has exactly one).
fn replace_once(text: &str, from: &str, to: &str, scene: &str) -> Result<String, String> {
    match text.matches(from).count() {
        1 => Ok(text.replacen(from, to, 1)),
        k => Err(format!(
            "the bundled {scene} scene has {k} occurrences of '{from}' (expected one)"
        )),
    }
}

/// `scenes/disc_fluid_above.toml` on a disc of 8 sectors (group C8v) with `divisions`.
pub fn c8v_disc_scene(divisions: usize) -> Result<Scene, String> {
    let text = replace_once(
        DISC_FLUID_ABOVE_TOML,
        "sectors = 7 ",
        "sectors = 8 ",
        "disc_fluid_above",
    )?;
    let text = replace_once(
        &text,
        "divisions = 16 ",
        &format!("divisions = {divisions} "),
        "disc_fluid_above",
    )?;
    Scene::from_toml_str(
        &text,
        &format!("disc with fluid above, C8v, divisions {divisions}"),
    )
    .map_err(|e| e.to_string())
}

/// The symmetry payoff on a C8v tangent: the clamped pre-stretched disc of
/// [`c8v_disc_scene`] with `divisions`, sagging under fluid of density [`C8V_DENSITY`] (a
/// solved equilibrium: Newton from the flat disc, as `run` solves a start state). As
/// [`payoff`] otherwise; [`Payoff::case`] says which disc.
pub fn c8v_payoff(
    divisions: usize,
    dense: bool,
    sparse: bool,
    lowest: usize,
) -> Result<Payoff, String> {
    let mut study = Study::build(c8v_disc_scene(divisions)?).map_err(|e| e.to_string())?;
    let group = study.action.group().name().to_string();
    if group != "C8v" {
        return Err(format!("the disc's scene group is {group}, not C8v"));
    }
    let rho = study
        .parameters
        .iter()
        .position(|n| n == "rho")
        .ok_or("the disc scene has no parameter rho")?;
    let mut params = study.start.clone();
    params[rho] = C8V_DENSITY;
    let u = solve_start(&mut study, &params)?;
    let mut po = payoff(&study, &u, &params, dense, sparse, lowest)?;
    po.case = format!(
        "clamped disc under fluid (`disc_fluid_above` with 8 sectors, {divisions} divisions, \
         {} triangles), solved at ρ = {C8V_DENSITY}",
        study.model.layout().triangles().len()
    );
    Ok(po)
}

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
    /// `krylov_nearest`).
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
}

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

/// Stability along a path without symmetry at `states` (e.g. [`BalloonLevel::states`]): at
/// every state K is assembled, the index is the negative count of a sparse LBLᵀ of K + τI (our
/// [`SymmetricFactorization`], symbolic analysis once), and the `lowest` eigenvalues nearest
/// σ = [`SHIFT_INVERT_SHIFT`] max|K_ij| come from a sparse shift-invert Lanczos on a second
/// numeric factorisation (of K − σI; the Lanczos is ours, `krylov_nearest`, because faer's
/// can loop forever once the Krylov space of a symmetric K is exhausted); with `dense`, also every eigenvalue by a dense
/// eigen-decomposition of K. Refused when the study has active constraints (the index by
/// blocks is then that of the bordered system) or K has rank-one terms.
pub fn full_path_stability(
    study: &Study,
    states: &[(Vec<f64>, Vec<f64>)],
    lowest: usize,
    dense: bool,
) -> Result<FullPathStability, String> {
    if !study.constraints.is_empty() {
        return Err("the study has constraints: its index is that of the bordered system".into());
    }
    let model = &study.model;
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
    };
    for (u, params) in states {
        let t = Instant::now();
        model
            .evaluate(u, params, Request::ALL, &mut eval)
            .map_err(|e| e.to_string())?;
        out.assembly += t.elapsed();
        if !eval.rank_one.is_empty() {
            return Err("K has rank-one terms; the sparse inertia does not include them".into());
        }
        let scale = eval
            .tangent
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300);
        let tau = FULL_INDEX_SHIFT * scale;
        out.scales.push(scale);
        // The index: inertia of K + τI.
        let t = Instant::now();
        let index = negative_count(&mut f, &shifted_values(pattern, &eval.tangent, -tau))?;
        out.inertia += t.elapsed();
        out.indices.push(index);
        // The check (not timed): how many eigenvalues lie in (−τ, τ].
        let below = negative_count(&mut f, &shifted_values(pattern, &eval.tangent, tau))?;
        out.zero_cluster.push(below.saturating_sub(index));
        // The lowest eigenvalues by shift-invert.
        let shift = SHIFT_INVERT_SHIFT * scale;
        let t = Instant::now();
        f.factorize(&shifted_values(pattern, &eval.tangent, shift))
            .map_err(|e| e.to_string())?;
        out.shift_invert_factorisation += t.elapsed();
        let t = Instant::now();
        let (values, converged) = krylov_nearest(&f, shift, lowest)?;
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
            let k = dense_tangent(model, &eval);
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

/// Resident memory of this process, from `/proc/self` (Linux; elsewhere every function says
/// it cannot).
pub mod memory {
    /// Resets the peak resident set size (`VmHWM`) to the current one by writing "5" to
    /// `/proc/self/clear_refs` (Linux ≥ 4.0). `false` where that is not possible.
    pub fn reset_peak() -> bool {
        std::fs::write("/proc/self/clear_refs", "5").is_ok()
    }

    /// A `kB` field of `/proc/self/status`, in KiB.
    fn status_kib(field: &str) -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        status.lines().find_map(|l| {
            let rest = l.strip_prefix(field)?.strip_prefix(':')?;
            rest.split_whitespace().next()?.parse().ok()
        })
    }

    /// Peak resident set size since the start or the last [`reset_peak`] (`VmHWM`), KiB.
    pub fn peak_kib() -> Option<u64> {
        status_kib("VmHWM")
    }

    /// Current resident set size (`VmRSS`), KiB.
    pub fn current_kib() -> Option<u64> {
        status_kib("VmRSS")
    }
}

/// One level of the scaling study: a balloon path of a fixed number of points with the
/// spectrum by irrep at every point, and the memory it took.
#[derive(Debug, Clone)]
pub struct ScalingLevel {
    /// The path and its phase times ([`BalloonLevel::states`] not kept).
    pub level: BalloonLevel,
    /// Resident memory when the level started (after the previous level was dropped; the
    /// allocator may keep some of it), KiB.
    pub rss_start_kib: Option<u64>,
    /// Peak resident memory during the level (`VmHWM` after a reset at its start), KiB.
    pub peak_kib: Option<u64>,
}

/// A level of the scaling study: the balloon of `frequency` followed for `points` points
/// with full stability by irrep at every point ([`balloon_level_with`]), its peak resident
/// memory measured by resetting the high-water mark first ([`memory`]).
pub fn scaling_level(frequency: usize, points: usize) -> Result<ScalingLevel, String> {
    let reset = memory::reset_peak();
    let rss_start_kib = memory::current_kib();
    let options = LevelOptions {
        stability: true,
        keep_states: false,
        max_points: Some(points),
        index_only: true,
    };
    let (level, study) = balloon_level_with(frequency, &options)?;
    let peak_kib = if reset { memory::peak_kib() } else { None };
    drop(study);
    Ok(ScalingLevel {
        level,
        rss_start_kib,
        peak_kib,
    })
}

/// The exponent b of y ≈ a xᵇ by least squares on (ln x, ln y); `None` with fewer than two
/// distinct positive x or a non-positive value.
pub fn fit_exponent(points: &[(f64, f64)]) -> Option<f64> {
    if points
        .iter()
        .any(|&(x, y)| !(x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()))
    {
        return None;
    }
    let n = points.len() as f64;
    let lx: Vec<f64> = points.iter().map(|p| p.0.ln()).collect();
    let ly: Vec<f64> = points.iter().map(|p| p.1.ln()).collect();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    (points.len() >= 2 && sxx > 1e-12).then(|| sxy / sxx)
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
/// (past the (3, 1) rung at 14.65 even on coarse discs), by [`crate::analysis::run`].
pub fn ponding_level(divisions: usize) -> Result<PondingLevel, String> {
    let t = Instant::now();
    let mut study = Study::build(ponding_scene(divisions, 20.0, 60)?).map_err(|e| e.to_string())?;
    let r = crate::analysis::run(&mut study, |_, _| {})
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

/// The wave number of a critical mode about z (see [`crate::analysis::critical::wave_number`]).
pub fn wave_number(study: &Study, mode: &[f64]) -> usize {
    crate::analysis::critical::wave_number(study.model.reference(), study.model.layout(), mode, 12)
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

/// The companion file of the rank-one terms of a tangent written to `path`: the name with
/// `.mtx` replaced by `.rank1.mtx` (`K.mtx` → `K.rank1.mtx`; a name without `.mtx` gets
/// `.rank1.mtx` appended), in the same directory.
pub fn rank_one_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name.strip_suffix(".mtx").unwrap_or(&name);
    path.with_file_name(format!("{stem}.rank1.mtx"))
}

/// The comment line of K.mtx that names its rank-one companion file (the rest of the line is
/// the file name, relative to K.mtx's directory).
pub const RANK_ONE_FILE_TAG: &str = "rank-one file:";
/// The comment line of the companion file that lists the coefficients c_1 … c_r.
pub const RANK_ONE_COEFFICIENTS_TAG: &str = "coefficients:";

/// What [`write_matrix_market`] wrote.
#[derive(Debug, Clone)]
pub struct MatrixFiles {
    /// Entries of the sparse part written (lower triangle of the pattern).
    pub entries: usize,
    /// The rank-one companion file and its number of terms, when K has rank-one terms.
    pub rank_one: Option<(PathBuf, usize)>,
}

/// Writes the full tangent K = S + Σ_k c_k a_k a_kᵀ of `eval` for an external solver.
///
/// - `path` (e.g. `K.mtx`): the sparse part S (`eval.tangent` on the model's pattern) in
///   Matrix Market `coordinate real symmetric` format, lower triangle of the pattern
///   (explicit zeros included), 1-based. The lines of `comment` become `%` comment lines.
/// - When K has rank-one terms (a `gas-amount` effect), also the companion file
///   [`rank_one_path`] (`K.rank1.mtx`): a Matrix Market `array real general` matrix of n rows
///   and r columns, column k the vector a_k (column-major, one value a line), with a comment
///   line `% coefficients: c_1 … c_r`. K.mtx then names it in a comment line
///   `% rank-one file: K.rank1.mtx`; that line, not the file's existence, says that K has
///   rank-one terms (a stale companion of an earlier export is ignored by readers).
///
/// Each file is written whole (temporary file + rename), the companion first. Values are
/// written with 17 significant digits (exact round trip).
pub fn write_matrix_market(
    path: &Path,
    model: &FeModel,
    eval: &Evaluation,
    comment: &str,
) -> Result<MatrixFiles, String> {
    let rank_one = if eval.rank_one.is_empty() {
        None
    } else {
        let file = rank_one_path(path);
        write_rank_one(&file, path, eval, comment)?;
        Some((file, eval.rank_one.len()))
    };
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
        if let Some((file, r)) = &rank_one {
            let name = file
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            writeln!(
                w,
                "% K = (this sparse matrix) + sum_k c_k a_k a_k^T with {r} rank-one term(s), \
                 a_k and c_k in the file below (same directory)"
            )?;
            writeln!(w, "% {RANK_ONE_FILE_TAG} {name}")?;
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
    Ok(MatrixFiles {
        entries: count,
        rank_one,
    })
}

/// The rank-one companion file of [`write_matrix_market`].
fn write_rank_one(
    file: &Path,
    sparse: &Path,
    eval: &Evaluation,
    comment: &str,
) -> Result<(), String> {
    let n = eval.residual.len();
    let r = eval.rank_one.len();
    if let Some((_, a)) = eval.rank_one.iter().find(|(_, a)| a.len() != n) {
        return Err(format!(
            "a rank-one vector has {} entries, K has {n} rows",
            a.len()
        ));
    }
    let sparse_name = sparse
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_atomic(file, |w| {
        writeln!(w, "%%MatrixMarket matrix array real general")?;
        writeln!(
            w,
            "% rank-one terms of K = S + sum_k c_k a_k a_k^T, S in {sparse_name}: column k is a_k"
        )?;
        write!(w, "% {RANK_ONE_COEFFICIENTS_TAG}")?;
        for (c, _) in &eval.rank_one {
            write!(w, " {c:.17e}")?;
        }
        writeln!(w)?;
        for line in comment.lines() {
            writeln!(w, "% {line}")?;
        }
        writeln!(w, "{n} {r}")?;
        for (_, a) in &eval.rank_one {
            for v in a {
                writeln!(w, "{v:.17e}")?;
            }
        }
        Ok(())
    })
    .map_err(|e| format!("{}: {e}", file.display()))
}
