//! Changes of stability along a path, for any model whose tangent splits into blocks
//! (docs/theory.md §8, §10, §11, §15.3): the [`Blocks`] of a model at its states (the irreps
//! of a group on a 3-D mesh, the wave numbers of a meridian), [`Crossings`] — where a block's
//! negative count changes between two points, its eigenvalue's zero localised and the point
//! classified — and [`IndexChanges`], the detector that watches the index at every point of a
//! path and rejects steps that leave the connected path.

use super::driver::{Accepted, Continuation, PathPoint, Problem, SignChange};
use super::events::{
    locate_within, Admission, Detector, Event, MeasureFn, States, REJECTED_STEP_FACTOR,
};
use crate::linalg::eigen::EigenError;
use crate::model::ModelError;
use crate::results::{Bracket, CriticalKind, CriticalPoint, Isotropy};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Relative size below which a localised eigenvalue counts as zero.
pub(crate) const ZERO_EIGENVALUE: f64 = 1e-10;
/// The narrowest bracket, relative to the step, in which a crossing is localised: states that
/// close differ in an eigenvalue by far less than [`ZERO_EIGENVALUE`] unless it jumps.
const LOCATE_WIDTH: f64 = 1e-10;
/// Relative size of the best eigenvalue found above which a crossing is not localised (docs/theory.md §8.9): the
/// eigenvalue jumps instead of crossing zero (two branches, not one).
const JUMP_EIGENVALUE: f64 = 1e-8;
/// Rejections in a row, each step a quarter of the one before, after which a step that still
/// leaves the path ([`leaves_path`]) is accepted: the count then changes at a branch point of
/// the fixed-point path itself (a symmetric bifurcation inside the fixed-point space, as on a
/// mesh of more symmetry than the scene's group), or the mesh's imperfection is below what
/// 1/64 of the step resolves. Shorter steps are not rejected until the path has passed the
/// place.
const MAX_REJECTIONS: usize = 3;
/// Steps of inverse iteration that turn the test function's border towards the crossing
/// eigenvector at the earlier end of a step (docs/theory.md §11.2): σ's zero does not depend
/// on the border, only how nearly linear σ is along the step.
const INVERSE_ITERATIONS: usize = 4;

/// The spectrum of one block (an irrep's, a wave number's).
#[derive(Debug, Clone, Serialize)]
pub struct BlockSpectrum {
    /// Irrep name.
    pub irrep: String,
    /// Irrep dimension d (every eigenvalue below occurs d times in K).
    pub dim: usize,
    /// Block size m_μ (columns of one partner; complex columns for a complex-type irrep,
    /// whose eigenvectors have the 2m real coordinates of its basis).
    pub size: usize,
    /// Rigid-body zero modes found in this block (deflated).
    pub rigid_modes: usize,
    /// Mean motions held in this block ([`crate::model::Model::held_motions`]: the rolling of
    /// a spherical reference), deflated like the rigid modes but not zero modes.
    pub held: usize,
    /// Largest |B_μᵀ K r| over the rigid modes r, relative to ‖K‖ (≈ 0 at an equilibrium);
    /// measured with the eigenvalues, 0 where only the inertia was asked for.
    pub rigid_residual: f64,
    /// Eigenvalues on the complement of the rigid modes (and of the constraints' border for the
    /// trivial block), ascending: all of them when [`BlockSpectrum::complete`], else the lowest
    /// ones (every negative one and at least one more); empty when none were asked for or
    /// they could not be computed ([`BlockSpectrum::eigen_error`]).
    pub eigenvalues: Vec<f64>,
    /// Whether `eigenvalues` is the whole spectrum of the block (a dense solve) rather than
    /// its lowest values (Lanczos).
    pub complete: bool,
    /// Why the eigenvalues could not be computed, when they were asked for and are missing.
    #[serde(skip)]
    pub eigen_error: Option<EigenError>,
    /// Number of negative eigenvalues.
    pub negative: usize,
    /// Eigenvectors (columns, in block coordinates of the first partner) of the lowest
    /// eigenvalues, kept for critical modes.
    #[serde(skip)]
    pub vectors: DMatrix<f64>,
}

/// The spectrum of a state by block.
#[derive(Debug, Clone, Serialize)]
pub struct Spectrum {
    /// One per irrep, the trivial first.
    pub blocks: Vec<BlockSpectrum>,
    /// Instability index Σ_μ d_μ neg_μ (0 = stable).
    pub index: usize,
    /// max |K_ij|, the scale for "zero".
    pub scale: f64,
}

impl Spectrum {
    /// Negative counts per block, for comparing states.
    pub fn negatives(&self) -> Vec<usize> {
        self.blocks.iter().map(|b| b.negative).collect()
    }
}

/// Stability by blocks at states of one model (docs/theory.md §8, §10, §15.3): the tangent
/// at a state splits into blocks (the irreps of a group, the wave numbers of a meridian), each
/// standing for `dim` identical copies in the full tangent, and what a crossing needs of them —
/// every block's negative count, its lowest eigenvalues and eigenvectors, the critical mode of
/// an eigenvector and the subgroup that keeps it. The blocks are labelled in every
/// [`Spectrum`] they return, the trivial block (the model's own symmetric states) first.
pub trait Blocks {
    /// The blocks' names (`A1`, `E2`, `m3` …), the trivial block first: the names their
    /// spectra carry.
    fn names(&self) -> Vec<String>;
    /// The negative count of every block (no eigenvalues): what every path point needs to
    /// detect a change of stability.
    fn index(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum>;
    /// Every block's negative count and lowest eigenvalues.
    fn spectrum(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum>;
    /// The lowest `lowest` eigenvalues of block `block` (all of them for a block solved
    /// dense), with eigenvectors when asked for; the other blocks left empty.
    fn block_eigen(
        &mut self,
        u: &[f64],
        params: &[f64],
        block: usize,
        lowest: usize,
        vectors: bool,
    ) -> Option<Spectrum>;
    /// The minimally augmented test function of block `block` at (u, params)
    /// (docs/theory.md §11.2): τ = 1/(bᵀ S⁻¹ b) for the block's matrix S and a unit border
    /// b (−σ of the bordered system [[S, b], [bᵀ, 0]] [v; σ] = [0; 1]), zero exactly where S
    /// is singular, of the sign of the crossing eigenvalue near its zero, from one
    /// factorisation of the block; with
    /// `border` `None` a start vector, turned by `iterations` steps of inverse iteration
    /// towards the eigenvector of the eigenvalue nearest zero. Returns τ and the border
    /// used. `None` (the default) where the blocks do not provide it: their crossings are
    /// then localised on the eigenvalue alone.
    fn test_function(
        &mut self,
        _u: &[f64],
        _params: &[f64],
        _block: usize,
        _border: Option<&[f64]>,
        _iterations: usize,
    ) -> Option<(f64, Vec<f64>)> {
        None
    }
    /// The mode of block `block`'s eigenvector `v` (its coordinates in the block), in the
    /// coordinates a critical point carries it in (not yet normalised).
    fn mode(&self, block: usize, v: &[f64]) -> Vec<f64>;
    /// The subgroup that keeps the (unit) mode of block `block`.
    fn isotropy(&self, block: usize, mode: &[f64]) -> Isotropy;
    /// How many of the model's switches ([`crate::model::Model::switches`]: nodes in
    /// contact …) differ between two states (u, params): where the tangent may jump. `None`
    /// (the default) for a smooth model.
    fn switched(&self, _a: (&[f64], &[f64]), _b: (&[f64], &[f64])) -> Option<usize> {
        None
    }
    /// The size, relative to the spectrum's scale, below which a localised eigenvalue counts
    /// as zero: a crossing is localised until its eigenvalue is that small (or its bracket
    /// at round-off). Models whose block evaluations are cheap localise to round-off (0).
    fn zero_eigenvalue(&self) -> f64 {
        ZERO_EIGENVALUE
    }
}

/// σ, the null vector of the bordered block and the derivatives of σ.
#[derive(Debug, Clone)]
pub struct TestValue {
    /// σ.
    pub sigma: f64,
    /// v in the block's coordinates (bᵀ v = 1).
    pub vector: DVector<f64>,
    /// ∂σ/∂q in the coordinates of the problem the curve follows.
    pub grad_q: DVector<f64>,
    /// ∂σ/∂Λ_j for every parameter of the model.
    pub grad_params: Vec<f64>,
}

/// The minimally augmented test function of one block at states of a model (docs/theory.md
/// §11.7): σ from the bordered block [[K_b, b], [bᵀ, 0]] [v; σ] = [0; 1], zero exactly where
/// the block is singular, with its derivatives — the extra equation of a critical curve.
pub trait CriticalTest {
    /// σ, v and the derivatives of σ at the state (u, params).
    fn evaluate(&mut self, u: &[f64], params: &[f64]) -> Result<TestValue, ModelError>;
    /// σ and v at (u, params).
    fn value(&mut self, u: &[f64], params: &[f64]) -> Result<(f64, DVector<f64>), ModelError>;
    /// Replaces the border (normalised); σ's zero set does not change.
    fn set_border(&mut self, border: &DVector<f64>);
    /// Takes the scales of the block's constraint rows at (u, params), where it has them.
    fn rescale(&mut self, _u: &[f64], _params: &[f64]) -> Result<(), ModelError> {
        Ok(())
    }
    /// The matrix whose singularity σ tests at (u, params), dense and symmetric, and the
    /// tangent's scale max|K_ij|.
    fn block_tangent(
        &mut self,
        u: &[f64],
        params: &[f64],
    ) -> Result<(DMatrix<f64>, f64), ModelError>;
}

/// A state on one side of a sign change: (arclength from the earlier end, u, every parameter).
pub type StateSide = (f64, Vec<f64>, Vec<f64>);

/// A test function of a state (u, every parameter).
pub type StateTest<'a> = dyn FnMut(&[f64], &[f64]) -> Option<f64> + 'a;

/// A zero of a block's test function found on a step ([`Trials::zero`]): the state (u,
/// every parameter), the function's value there, and the nearest converged states found on
/// each side of its sign change, (s, u, every parameter) — the earlier end's side first;
/// `None` where the search found none inside the step.
pub struct ZeroFound {
    /// The displacement.
    pub u: Vec<f64>,
    /// Every parameter.
    pub params: Vec<f64>,
    /// The test function there.
    pub value: f64,
    /// Its arclength from the earlier end.
    pub s: f64,
    /// The nearest states of either sign found inside the step.
    pub sides: [Option<StateSide>; 2],
}

/// The states of one step that [`Crossings::localise`] evaluates its crossings at: a converged
/// state at any arclength s of the step and, where the states come from a path that can be
/// solved together with a test function, the zero of that function directly
/// ([`super::driver::zero_on_step`]). Any `FnMut(f64) -> Option<(u, params)>` gives the states
/// alone.
pub trait Trials {
    /// (u, params) at s ∈ [0, s1] (s = 0 at the earlier end), `None` where it cannot be found.
    fn state(&mut self, s: f64) -> Option<(Vec<f64>, Vec<f64>)>;
    /// The state of the step where `test` (of (u, params)) is zero, from the sign change
    /// `change`, by Newton on the path's equations and the test function together; `None`
    /// (the default) where the states cannot do that or it fails: the caller then searches
    /// on [`Trials::state`].
    fn zero(&mut self, _change: SignChange, _test: &mut StateTest<'_>) -> Option<ZeroFound> {
        None
    }
}

impl<F: FnMut(f64) -> Option<(Vec<f64>, Vec<f64>)>> Trials for F {
    fn state(&mut self, s: f64) -> Option<(Vec<f64>, Vec<f64>)> {
        self(s)
    }
}

/// Index changes of the blocks, localised and classified: the stability analysis of states of
/// one model (docs/theory.md §8, §10, §11), by any [`Blocks`].
pub struct Crossings<'a> {
    blocks: Box<dyn Blocks + 'a>,
    measure: MeasureFn<'a>,
    control: Option<usize>,
    held: bool,
}

impl<'a> Crossings<'a> {
    /// The analysis of states by `blocks`; critical points get the measures of
    /// `measure(u, params)`; `control` is the parameter a path follows, and `held` states
    /// (linear buckling) name a singular trivial block a symmetric bifurcation.
    pub fn new(
        blocks: Box<dyn Blocks + 'a>,
        measure: MeasureFn<'a>,
        control: Option<usize>,
        held: bool,
    ) -> Self {
        Self {
            blocks,
            measure,
            control,
            held,
        }
    }

    /// The number of block `name` (0 the trivial one), if it is one.
    pub fn block(&self, name: &str) -> Option<usize> {
        self.blocks.names().iter().position(|n| n == name)
    }

    /// How many of the model's switches differ between the states `a` and `b` (u, params);
    /// `None` for a smooth model ([`Blocks::switched`]).
    pub fn switched(&self, a: (&[f64], &[f64]), b: (&[f64], &[f64])) -> Option<usize> {
        self.blocks.switched(a, b)
    }

    /// The negative count of every block only: what every path point needs to detect a
    /// change of stability.
    pub fn index(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.blocks.index(u, params)
    }

    /// Every block's negative count and eigenvalues.
    pub fn spectrum(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.blocks.spectrum(u, params)
    }

    fn block_eigen(
        &mut self,
        u: &[f64],
        params: &[f64],
        mu: usize,
        lowest: usize,
        vectors: bool,
    ) -> Option<Spectrum> {
        self.blocks.block_eigen(u, params, mu, lowest, vectors)
    }

    /// The eigenvalue of block `block` nearest zero at (u, params), the block's negative
    /// count, and (when `mode`) a point carrying that eigenvalue's mode, irrep and isotropy
    /// as a critical point does (`after_step` its step; no bracket): what names the mode of
    /// a dip of the path (docs/theory.md §16.7). `None` where the eigenvalues could not be
    /// computed.
    pub fn nearest_zero(
        &mut self,
        u: &[f64],
        params: &[f64],
        block: usize,
        mode: bool,
        after_step: usize,
    ) -> Option<(f64, usize, Option<CriticalPoint>)> {
        let mut sp = self.block_eigen(u, params, block, 1, mode)?;
        let negative = sp.blocks.get(block)?.negative;
        if negative > 0 && sp.blocks[block].eigenvalues.len() <= negative {
            sp = self.block_eigen(u, params, block, negative + 1, mode)?;
        }
        let b = sp.blocks.get(block)?;
        let (k, sigma) = b
            .eigenvalues
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, e)| e.is_finite())
            .min_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))?;
        if !mode {
            return Some((sigma, b.negative, None));
        }
        let point = self
            .critical_point(
                block,
                k,
                (u.to_vec(), params.to_vec(), &sp, sigma),
                Bracket {
                    width: 0.0,
                    ends: [(u.to_vec(), params.to_vec()), (u.to_vec(), params.to_vec())],
                },
                after_step,
                false,
            )
            .ok()
            .map(|mut cp| {
                cp.bracket = None;
                cp
            });
        Some((sigma, b.negative, point))
    }

    /// Localises every eigenvalue of every block whose negative count differs between the
    /// ends `a` and `b` of a step (index spectra, with or without eigenvalues, and their
    /// states), with `state(s)` giving (u, params) for s ∈ [0, s1] (s = 0 at a, s1 at b): a
    /// crossing of the k-th lowest eigenvalue of the block (k between the two counts) is
    /// found by [`locate`](super::events::locate) on that eigenvalue, computed at each trial point — densely or by
    /// Lanczos, whatever the block's size (`Stability::analyse`). Returns the critical
    /// points sorted by the control, and the crossings that could not be localised as
    /// warnings. `control_turns` says whether the control turns between `a` and `b`: a zero
    /// of the trivial block is a limit point only there (docs/theory.md §11.3); elsewhere,
    /// and on a held state, it is a symmetric bifurcation.
    pub fn localise(
        &mut self,
        a: End<'_>,
        b: End<'_>,
        after_step: usize,
        s1: f64,
        control_turns: bool,
        mut trials: impl Trials,
    ) -> Vec<Event> {
        let mut found = Vec::new();
        let mut warnings = Vec::new();
        let control = self.control;
        for mu in 0..a.spectrum.blocks.len() {
            let (n0, n1) = (
                a.spectrum.blocks[mu].negative,
                b.spectrum.blocks[mu].negative,
            );
            if n0 == n1 {
                continue;
            }
            let irrep = a.spectrum.blocks[mu].irrep.clone();
            let not_localised = |why: &str| {
                format!(
                    "the index of {irrep} changed between steps {after_step} and {} (by {}) but the crossing could not be localised ({why})",
                    after_step + 1,
                    n1 as i64 - n0 as i64,
                )
            };
            // A signal ends the localisation between trial points: the crossings found so
            // far are kept, the others are named as not localised.
            let stopped = "a signal stopped its localisation";
            if super::interrupt::requested() {
                warnings.push(not_localised(stopped));
                continue;
            }
            // One eigenvalue crosses: first on the block's test function, which needs one
            // factorisation per trial point instead of an eigenvalue solve.
            if n0.abs_diff(n1) == 1 {
                let k = n0.min(n1);
                if let Some((u, p, sp, g, bracket)) =
                    self.by_test_function(&a, &b, mu, k, s1, &mut trials)
                {
                    let at = (u, p, &sp, g);
                    match self.critical_point(mu, k, at, bracket, after_step, control_turns) {
                        Ok(point) => {
                            found.push(point);
                            continue;
                        }
                        Err(why) => {
                            warnings.push(not_localised(why));
                            continue;
                        }
                    }
                }
            }
            // The eigenvalues k = min(n0, n1) … max(n0, n1) − 1 at both ends.
            let needed = n0.max(n1) + 1;
            let mut ends: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
            let mut missing = None;
            for (slot, end) in ends.iter_mut().zip([&a, &b]) {
                let block = &end.spectrum.blocks[mu];
                if block.complete || block.eigenvalues.len() >= needed {
                    *slot = block.eigenvalues.clone();
                    continue;
                }
                match self.block_eigen(end.u, end.params, mu, needed, false) {
                    Some(sp) if !sp.blocks[mu].eigenvalues.is_empty() => {
                        *slot = sp.blocks[mu].eigenvalues.clone()
                    }
                    Some(sp) => {
                        missing = Some(sp.blocks[mu].eigen_error.as_ref().map_or_else(
                            || "no eigenvalues were computed".to_string(),
                            |e| format!("its eigenvalues could not be computed: {e}"),
                        ))
                    }
                    None => missing = Some("the end state could not be evaluated".into()),
                }
            }
            if let Some(why) = missing {
                warnings.push(not_localised(&why));
                continue;
            }
            for k in n0.min(n1)..n0.max(n1) {
                if super::interrupt::requested() {
                    warnings.push(not_localised(stopped));
                    break;
                }
                let g0 = ends[0].get(k).copied().unwrap_or(0.0);
                let g1 = ends[1].get(k).copied().unwrap_or(0.0);
                let tol = self.blocks.zero_eigenvalue() * a.spectrum.scale;
                let mut failure = None;
                // Every evaluated (s, eigenvalue, control), to tell a jump from a crossing.
                let mut tried: Vec<(f64, f64, Option<f64>)> = Vec::new();
                // The bracket's ends as the localisation narrows it (the side of g0, the
                // side of g1), with their states.
                let mut sides = [
                    (0.0, a.u.to_vec(), a.params.to_vec()),
                    (s1, b.u.to_vec(), b.params.to_vec()),
                ];
                let located = locate_within(
                    |s| {
                        if super::interrupt::requested() {
                            return None;
                        }
                        let Some((u, p)) = trials.state(s) else {
                            failure = Some(format!(
                                "the state at {:.3} of the step did not converge",
                                s / s1
                            ));
                            return None;
                        };
                        let sp = self.block_eigen(&u, &p, mu, k + 1, false)?;
                        let value = sp.blocks[mu].eigenvalues.get(k).copied();
                        if let Some(g) = value {
                            tried.push((s, g, control.and_then(|c| p.get(c).copied())));
                            // As `locate_within` moves its ends.
                            let side = usize::from(g.signum() == g1.signum());
                            sides[side] = (s, u, p);
                        }
                        if value.is_none() {
                            failure = Some(sp.blocks[mu].eigen_error.as_ref().map_or_else(
                                || "no eigenvalue was computed".to_string(),
                                |e| format!("its eigenvalues could not be computed: {e}"),
                            ));
                        }
                        value
                    },
                    g0,
                    s1,
                    g1,
                    tol,
                    LOCATE_WIDTH,
                );
                if super::interrupt::requested() {
                    warnings.push(not_localised(stopped));
                    break;
                }
                let Some((s_best, g_best)) = located else {
                    warnings.push(not_localised(
                        failure
                            .as_deref()
                            .unwrap_or("the tangent at a state could not be evaluated"),
                    ));
                    continue;
                };
                let switched = self.blocks.switched(
                    (sides[0].1.as_slice(), sides[0].2.as_slice()),
                    (sides[1].1.as_slice(), sides[1].2.as_slice()),
                );
                if g_best.abs() > JUMP_EIGENVALUE * a.spectrum.scale
                    && switched.is_some_and(|n| n > 0)
                {
                    // The bracket's ends: the nearest trial states on either side of the jump.
                    let bracket = bracket_of(sides, s1);
                    // The eigenvalue jumps across zero where the model's switches change (a
                    // node enters or leaves contact): the stability changes there, at the
                    // jump itself. It is reported at the side whose eigenvalue is nearer
                    // zero, with the jump's two states as its bracket; its residual
                    // eigenvalue says that it is not a smooth zero.
                    let evaluated: Vec<(Vec<f64>, Vec<f64>, Spectrum, f64)> = bracket
                        .ends
                        .iter()
                        .filter_map(|(u, p)| {
                            let sp = self.block_eigen(u, p, mu, k + 1, true)?;
                            let g = sp.blocks[mu].eigenvalues.get(k).copied()?;
                            Some((u.clone(), p.clone(), sp, g))
                        })
                        .collect();
                    let Some((u, p, sp, g)) = evaluated
                        .into_iter()
                        .min_by(|x, y| x.3.abs().total_cmp(&y.3.abs()))
                    else {
                        warnings.push(not_localised(
                            "the states of the jump could not be evaluated",
                        ));
                        continue;
                    };
                    match self.critical_point(
                        mu,
                        k,
                        (u, p, &sp, g),
                        bracket,
                        after_step,
                        control_turns,
                    ) {
                        Ok(point) => found.push(point),
                        Err(why) => warnings.push(not_localised(why)),
                    }
                    continue;
                }
                if g_best.abs() > JUMP_EIGENVALUE * a.spectrum.scale {
                    // No zero: the eigenvalue jumps between two neighbouring states.
                    let side = |positive: bool| {
                        tried
                            .iter()
                            .filter(|t| (t.1 > 0.0) == positive)
                            .min_by(|x, y| (x.0 - s_best).abs().total_cmp(&(y.0 - s_best).abs()))
                            .copied()
                    };
                    let why = match (side(true), side(false)) {
                        (Some(p), Some(n)) => format!(
                            "its eigenvalue jumps from {:+.2e} to {:+.2e} of max|K_ij|{} between states {:.1e} of the step apart instead of crossing zero: the step went over a sharp turn of the path, as at a nearly symmetric bifurcation that the mesh breaks, onto another branch; no critical point is reported",
                            p.1 / a.spectrum.scale,
                            n.1 / a.spectrum.scale,
                            p.2.map_or_else(String::new, |c| format!(" at control {c:.6}")),
                            (p.0 - n.0).abs() / s1,
                        ),
                        _ => format!(
                            "the smallest |eigenvalue| found is {:.1e} of max|K_ij|",
                            g_best.abs() / a.spectrum.scale
                        ),
                    };
                    warnings.push(not_localised(&why));
                    continue;
                }
                // The bracket's ends: the nearest states on either side of the zero.
                let blocks = &mut self.blocks;
                tighten(
                    &mut sides,
                    s_best,
                    reach(g0, g1, s1, g_best, tol),
                    g0 > 0.0,
                    |s| {
                        let (u, p) = trials.state(s)?;
                        let sp = blocks.block_eigen(&u, &p, mu, k + 1, false)?;
                        let g = sp.blocks[mu].eigenvalues.get(k).copied()?;
                        Some((g, u, p))
                    },
                );
                let bracket = bracket_of(sides, s1);
                // Re-evaluate at the best point, with the eigenvectors for the critical mode.
                let evaluated = trials.state(s_best).and_then(|(u, p)| {
                    let sp = self.block_eigen(&u, &p, mu, k + 1, true)?;
                    Some((u, p, sp))
                });
                let Some((u, p, sp)) = evaluated else {
                    warnings.push(not_localised("the best point could not be evaluated"));
                    continue;
                };
                let at = (u, p, &sp, g_best);
                match self.critical_point(mu, k, at, bracket, after_step, control_turns) {
                    Ok(point) => found.push(point),
                    Err(why) => warnings.push(not_localised(why)),
                }
            }
        }
        let control = |p: &CriticalPoint| self.control.map_or(0.0, |c| p.parameters[c]);
        found.sort_by(|x, y| control(x).total_cmp(&control(y)));
        warnings
            .into_iter()
            .map(Event::Warning)
            .chain(found.into_iter().map(Event::Critical))
            .collect()
    }
}

/// A crossing located on the test function: the state (u, every parameter), the block's
/// spectrum there with its eigenvectors, the crossing eigenvalue, and the bracket it was found
/// in.
type Located = (Vec<f64>, Vec<f64>, Spectrum, f64, Bracket);

impl Crossings<'_> {
    /// The crossing of the `k`-th eigenvalue of block `mu` between the ends `a` and `b` (s = 0
    /// and s1; the block's count changes by one), localised on the block's test function σ
    /// (docs/theory.md §11.2): its border b from inverse iteration at `a`, σ at both ends of
    /// opposite signs (that of the crossing eigenvalue), the same regula falsi on s as on
    /// the eigenvalue, each trial one state and one factorisation of the block; then the
    /// eigenvalues and eigenvectors at the best state, accepted when the `k`-th is zero to
    /// the same tolerance as the eigenvalue's own localisation. `None` where any of this
    /// fails: the caller then localises on the eigenvalue itself.
    fn by_test_function(
        &mut self,
        a: &End<'_>,
        b: &End<'_>,
        mu: usize,
        k: usize,
        s1: f64,
        trials: &mut dyn Trials,
    ) -> Option<Located> {
        let tol = self.blocks.zero_eigenvalue() * a.spectrum.scale;
        if tol <= 0.0 {
            return None;
        }
        // The crossing eigenvalue is positive at the end with fewer negatives.
        let rising = b.spectrum.blocks[mu].negative > a.spectrum.blocks[mu].negative;
        let (g0, border) =
            self.blocks
                .test_function(a.u, a.params, mu, None, INVERSE_ITERATIONS)?;
        let (g1, _) = self
            .blocks
            .test_function(b.u, b.params, mu, Some(&border), 0)?;
        if (g0 > 0.0) != rising || g1 == 0.0 || (g1 > 0.0) == rising {
            return None;
        }
        // Newton on the path's equations and σ together, where the states allow it.
        if let Some(located) = self.by_newton(a, b, mu, k, s1, (g0, g1, &border), trials) {
            return Some(located);
        }
        // The best trial's state, kept for the eigenvalues there.
        let mut best: Option<(f64, f64, Vec<f64>, Vec<f64>)> = None;
        // The bracket's ends as the search narrows it (the side of g0, the side of g1).
        let mut sides = [
            (0.0, a.u.to_vec(), a.params.to_vec()),
            (s1, b.u.to_vec(), b.params.to_vec()),
        ];
        let blocks = &mut self.blocks;
        let (s_best, _) = locate_within(
            |s| {
                if super::interrupt::requested() {
                    return None;
                }
                let (u, p) = trials.state(s)?;
                let (g, _) = blocks.test_function(&u, &p, mu, Some(&border), 0)?;
                sides[usize::from((g > 0.0) == (g1 > 0.0))] = (s, u.clone(), p.clone());
                if best.as_ref().is_none_or(|t| g.abs() < t.1.abs()) {
                    best = Some((s, g, u, p));
                }
                Some(g)
            },
            g0,
            s1,
            g1,
            tol,
            LOCATE_WIDTH,
        )?;
        let (u, p, g_best) = match best {
            Some((s, g, u, p)) if s == s_best => (u, p, g),
            _ => return None,
        };
        let (sp, g) = self.certified(&u, &p, mu, k, tol)?;
        let blocks = &mut self.blocks;
        tighten(
            &mut sides,
            s_best,
            reach(g0, g1, s1, g_best, tol),
            g0 > 0.0,
            |s| {
                let (u, p) = trials.state(s)?;
                let (g, _) = blocks.test_function(&u, &p, mu, Some(&border), 0)?;
                Some((g, u, p))
            },
        );
        Some((u, p, sp, g, bracket_of(sides, s1)))
    }

    /// Block `mu`'s spectrum with its eigenvectors at (u, p) and its `k`-th eigenvalue, when
    /// that is zero to `tol`: what makes a located state a crossing.
    fn certified(
        &mut self,
        u: &[f64],
        p: &[f64],
        mu: usize,
        k: usize,
        tol: f64,
    ) -> Option<(Spectrum, f64)> {
        let sp = self.block_eigen(u, p, mu, k + 1, true)?;
        let g = *sp.blocks[mu].eigenvalues.get(k)?;
        (g.abs() <= tol).then_some((sp, g))
    }

    /// The crossing of the `k`-th eigenvalue of block `mu` as the zero of the block's test
    /// function τ (border `border`, τ = g0 at `a`, g1 at `b`) found by Newton on the path's
    /// equations and τ together ([`Trials::zero`], docs/theory.md §11.2), then certified as
    /// [`Crossings::by_test_function`] certifies its best trial: the block's eigenvalues and
    /// eigenvectors at the state, its `k`-th within the tolerance. `None` where the trials
    /// cannot solve for the zero, the iteration fails or the certificate does not hold.
    #[allow(clippy::too_many_arguments)]
    fn by_newton(
        &mut self,
        a: &End<'_>,
        b: &End<'_>,
        mu: usize,
        k: usize,
        s1: f64,
        (g0, g1, border): (f64, f64, &[f64]),
        trials: &mut dyn Trials,
    ) -> Option<Located> {
        let tol = self.blocks.zero_eigenvalue() * a.spectrum.scale;
        let blocks = &mut self.blocks;
        let change = SignChange {
            first: (0.0, g0),
            second: (s1, g1),
            tolerance: tol,
            width: LOCATE_WIDTH * s1.abs(),
        };
        let zero = trials.zero(change, &mut |u, p| {
            blocks
                .test_function(u, p, mu, Some(border), 0)
                .map(|(g, _)| g)
        })?;
        let (sp, g) = self.certified(&zero.u, &zero.params, mu, k, tol)?;
        let [first, second] = zero.sides;
        let mut sides = [
            first.unwrap_or((0.0, a.u.to_vec(), a.params.to_vec())),
            second.unwrap_or((s1, b.u.to_vec(), b.params.to_vec())),
        ];
        let blocks = &mut self.blocks;
        tighten(
            &mut sides,
            zero.s,
            reach(g0, g1, s1, zero.value, tol),
            g0 > 0.0,
            |s| {
                let (u, p) = trials.state(s)?;
                let (g, _) = blocks.test_function(&u, &p, mu, Some(border), 0)?;
                Some((g, u, p))
            },
        );
        Some((zero.u, zero.params, sp, g, bracket_of(sides, s1)))
    }

    /// The critical point of the `k`-th eigenvalue `g` of block `mu` at the state (u, p),
    /// whose block spectrum `sp` has its eigenvectors, localised within `bracket`: its kind,
    /// mode and isotropy, or why it has none.
    fn critical_point(
        &self,
        mu: usize,
        k: usize,
        (u, p, sp, g): (Vec<f64>, Vec<f64>, &Spectrum, f64),
        bracket: Bracket,
        after_step: usize,
        control_turns: bool,
    ) -> Result<CriticalPoint, &'static str> {
        let block = &sp.blocks[mu];
        if block.vectors.ncols() <= k {
            return Err("no eigenvector at the best point");
        }
        let v: Vec<f64> = block.vectors.column(k).iter().copied().collect();
        let mut mode = self.blocks.mode(mu, &v);
        let norm = mode.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
        mode.iter_mut().for_each(|x| *x /= norm);
        let dim = block.dim;
        Ok(CriticalPoint {
            kind: CriticalKind::of(mu == 0, dim, self.held || !control_turns),
            irrep: block.irrep.clone(),
            multiplicity: dim,
            measures: (self.measure)(&u, &p),
            parameters: p,
            after_step,
            residual_eigenvalue: g.abs() / sp.scale,
            isotropy: self.blocks.isotropy(mu, &mode),
            mode,
            state: u,
            bracket: Some(bracket),
        })
    }
}

/// The bracket between two trial states (s, u, params) of a step of arclength `s1`: its
/// width as a share of the step, and the states.
fn bracket_of([(s0, u0, p0), (s2, u2, p2)]: [(f64, Vec<f64>, Vec<f64>); 2], s1: f64) -> Bracket {
    Bracket {
        width: (s2 - s0).abs() / s1.abs().max(f64::MIN_POSITIVE),
        ends: [(u0, p0), (u2, p2)],
    }
}

/// How many times [`tighten`] doubles its reach before it leaves a side as it is.
const TIGHTEN_TRIES: usize = 24;

/// A trial state of a step with a function's value there: (g, u, every parameter).
type Trial = (f64, Vec<f64>, Vec<f64>);

/// The distance from a localised zero at which [`tighten`] first looks for a state of either
/// sign: twice the distance over which g, at its mean slope over the step (g0 at 0, g1 at s1),
/// changes by the larger of the tolerance and |g| at the zero, and never less than the
/// localisation's width.
fn reach(g0: f64, g1: f64, s1: f64, g_best: f64, tol: f64) -> f64 {
    let slope = (g1 - g0).abs() / s1.abs().max(f64::MIN_POSITIVE);
    let r = 2.0 * tol.max(g_best.abs()) / slope;
    let floor = LOCATE_WIDTH * s1.abs();
    if r.is_finite() {
        r.max(floor)
    } else {
        floor
    }
}

/// The sides of a zero localised at `s_best` narrowed about it (docs/theory.md §11.2). A
/// localisation ends once |g| is within its tolerance, which its first trial may meet, and a
/// Newton iteration at the zero may pass converged states on one side only: the other side
/// is then still the step's end, and the bracket as wide as the step. Each side farther than
/// `reach` from the zero is replaced by the state at s_best ± r towards it, for the first r
/// of reach, 2·reach, 4·reach, … ([`TIGHTEN_TRIES`] at most, never past the side) where g has
/// that side's sign (nearer the zero its sign is the noise of the tolerance); `positive`: g
/// is positive on `sides[0]`'s side; `g(s)` the function and state at s (`None`: no state
/// there, the side is kept).
fn tighten(
    sides: &mut [(f64, Vec<f64>, Vec<f64>); 2],
    s_best: f64,
    reach: f64,
    positive: bool,
    mut g: impl FnMut(f64) -> Option<Trial>,
) {
    for (k, side) in sides.iter_mut().enumerate() {
        let want_positive = (k == 0) == positive;
        let far = side.0 - s_best;
        let mut r = reach;
        for _ in 0..TIGHTEN_TRIES {
            if !(r > 0.0 && r < far.abs()) {
                break;
            }
            let s = s_best + r.copysign(far);
            match g(s) {
                Some((value, u, p)) if value != 0.0 && (value > 0.0) == want_positive => {
                    *side = (s, u, p);
                    break;
                }
                Some(_) => r *= 2.0,
                None => break,
            }
        }
    }
}

/// One end of a step for [`Crossings::localise`]: its spectrum (the index at least) and its
/// state.
#[derive(Debug, Clone, Copy)]
pub struct End<'s> {
    /// The spectrum there.
    pub spectrum: &'s Spectrum,
    /// The displacement.
    pub u: &'s [f64],
    /// Every parameter.
    pub params: &'s [f64],
}

/// The index of every block at every point, and the critical points where it changes: the
/// [`Crossings`] of a path's states.
pub struct IndexChanges<'a> {
    crossings: Crossings<'a>,
    /// The previous point's index spectrum and state.
    previous: Option<(Spectrum, Vec<f64>, Vec<f64>)>,
    /// The instability index at every point so far (`None` where it could not be computed).
    pub indices: Vec<Option<usize>>,
    /// The negative count of every block at every point (`None` where it could not be
    /// computed), in the order of `irreps`.
    pub negatives: Vec<Option<Vec<usize>>>,
    /// The blocks' irreps, from the first point with a spectrum.
    pub irreps: Vec<String>,
    /// Time spent on the index at every point (eigenvalues and localisation excepted).
    pub index_time: std::time::Duration,
    /// The index at the point [`Detector::admit`] last admitted (its arclength and
    /// parameters, to know it again), for [`Detector::check`].
    admitted: Option<Observed>,
    /// Where steps are being rejected ([`Detector::admit`]).
    rejecting: Option<Rejecting>,
}

/// Steps are being rejected near one place of the path: steps that leave the path and are
/// longer than `floor` are rejected until the path has passed `until` (an arclength) or a
/// step no longer than `floor` is accepted across it.
#[derive(Debug, Clone, Copy)]
struct Rejecting {
    floor: f64,
    until: f64,
}

/// The index spectrum at a point (where it could be computed) and the point's state.
struct Observed {
    arclength: f64,
    lambda: nalgebra::DVector<f64>,
    spectrum: Option<Spectrum>,
    u: Vec<f64>,
    params: Vec<f64>,
}

impl<'a> IndexChanges<'a> {
    /// Watches the index with `crossings`.
    pub fn new(crossings: Crossings<'a>) -> Self {
        Self {
            crossings,
            previous: None,
            indices: Vec::new(),
            negatives: Vec::new(),
            irreps: Vec::new(),
            index_time: Default::default(),
            admitted: None,
            rejecting: None,
        }
    }

    /// The stability analysis it watched with, to watch another path.
    pub fn into_crossings(self) -> Crossings<'a> {
        self.crossings
    }

    /// The index at `point` and its state.
    fn index_at<P: Problem + States>(&mut self, problem: &P, point: &PathPoint) -> Observed {
        let t = std::time::Instant::now();
        let u = problem.displacement(&point.q);
        let params = problem.parameters(&point.lambda);
        let spectrum = self.crossings.index(&u, &params);
        self.index_time += t.elapsed();
        Observed {
            arclength: point.arclength,
            lambda: point.lambda.clone(),
            spectrum,
            u,
            params,
        }
    }

    /// The index at `point` (the admitted one's, when it is that point), remembered with its
    /// state as the previous point's; returns the earlier previous point.
    fn observe<P: Problem + States>(
        &mut self,
        problem: &P,
        point: &PathPoint,
    ) -> Option<(Spectrum, Vec<f64>, Vec<f64>)> {
        let observed = match self.admitted.take() {
            Some(o) if o.arclength == point.arclength && o.lambda == point.lambda => o,
            _ => self.index_at(problem, point),
        };
        self.indices
            .push(observed.spectrum.as_ref().map(|s| s.index));
        let Observed {
            spectrum,
            u,
            params,
            ..
        } = observed;
        if let (Some(s), true) = (&spectrum, self.irreps.is_empty()) {
            self.irreps = s.blocks.iter().map(|b| b.irrep.clone()).collect();
        }
        let n = self.irreps.len();
        self.negatives.push(
            spectrum
                .as_ref()
                .map(Spectrum::negatives)
                .filter(|neg| neg.len() == n),
        );
        std::mem::replace(&mut self.previous, spectrum.map(|s| (s, u, params)))
    }
}

/// Whether the step from a point with fixed-point-block count `a` and control tangent `from`
/// to one with `b` and `to` leaves the connected path (docs/theory.md §7.5.2). Along a
/// connected regular path sign(det K₀)·sign(λ̇) is constant (K₀ the tangent in the
/// fixed-point space, bordered by the constraints; its determinant's sign is (−1)^count), so
/// the count's parity changes exactly where the control turns; and a step short enough to
/// resolve the path meets at most one fold, where the count changes by one. Any other change
/// — the parity without a turn, a turn without it, or a change by two or more (both
/// components of a broken pair at once) — is a step onto another piece of the path, or over
/// more than the step resolves.
fn leaves_path(a: usize, b: usize, from: f64, to: f64) -> bool {
    let turns = from.signum() != to.signum();
    let expected = usize::from(turns);
    a.abs_diff(b) != expected
}

impl<P: Problem + States> Detector<P> for IndexChanges<'_> {
    fn start(&mut self, driver: &mut Continuation<P>) -> Vec<Event> {
        let point = driver.point().clone();
        self.observe(driver.problem(), &point);
        Vec::new()
    }

    /// Rejects a step that leaves the connected path ([`leaves_path`]), down to
    /// [`MAX_REJECTIONS`] quarterings of the first step rejected there: a step over a nearly symmetric bifurcation
    /// inside the fixed-point space lands on another piece of the broken branch, where the
    /// fixed-point block's count has changed without a fold of the control. Shorter steps stay
    /// on the connected piece and follow it through its fold.
    fn admit(&mut self, driver: &mut Continuation<P>, step: &Accepted) -> Admission {
        let point = driver.point().clone();
        let observed = self.index_at(driver.problem(), &point);
        let m = driver.problem().dim();
        let leaves = match (&self.previous, &observed.spectrum) {
            (Some((a, _, _)), Some(b)) => leaves_path(
                a.blocks[0].negative,
                b.blocks[0].negative,
                step.from.tangent[m],
                point.tangent[m],
            ),
            _ => false,
        };
        let from = step.from.arclength;
        if self.rejecting.is_some_and(|r| from >= r.until) {
            self.rejecting = None;
        }
        if leaves {
            // The first rejection here sets the shortest step that is still rejected: that
            // of MAX_REJECTIONS rejections in a row. The floor holds for every point until
            // the place is passed, so that shorter steps towards a genuine branch point of
            // the fixed-point path do not approach it ever closer.
            let rejecting = self.rejecting.unwrap_or(Rejecting {
                floor: step.step * REJECTED_STEP_FACTOR.powi(MAX_REJECTIONS as i32) * (1.0 + 1e-9),
                until: from + step.step,
            });
            if step.step > rejecting.floor {
                self.rejecting = Some(rejecting);
                self.admitted = None;
                return Admission::Reject;
            }
            self.rejecting = None;
        }
        self.admitted = Some(observed);
        Admission::Accept
    }

    fn check(&mut self, driver: &mut Continuation<P>, step: &Accepted, after: usize) -> Vec<Event> {
        let point = driver.point().clone();
        let previous = self.observe(driver.problem(), &point);
        let (Some((a, u0, p0)), Some((b, u1, p1))) = (&previous, &self.previous) else {
            return Vec::new();
        };
        if a.negatives() == b.negatives() {
            return Vec::new();
        }
        // The index changed: localise in the blocks whose count changed.
        let s1 = point.arclength - step.from.arclength;
        let m = driver.problem().dim();
        let turns = step.from.tangent[m].signum() != point.tangent[m].signum();
        let ends = (
            End {
                spectrum: a,
                u: u0,
                params: p0,
            },
            End {
                spectrum: b,
                u: u1,
                params: p1,
            },
        );
        // The states inside the step, and the test function's zeros on it ([`StepTrials`]).
        let mut back = point.clone();
        back.tangent = -back.tangent;
        let trials = StepTrials {
            driver,
            from: &step.from,
            forward: Vec::new(),
            backward: vec![(s1, back)],
            fails_from: f64::INFINITY,
        };
        self.crossings
            .localise(ends.0, ends.1, after, s1, turns, trials)
    }
}

/// The states of one accepted step of a driver, for [`Crossings::localise`]: a state inside
/// the step corrected from the earlier point (without the branch-jump guard, which a step next
/// to a branch point of the path would trip); where that fails — near a singular point of the
/// path, such as a nearly symmetric (imperfect) bifurcation that the step went over, where the
/// corrector's basin shrinks — from the nearest state found so far on the same side, forwards
/// from the earlier point's side or backwards from the later point's. A test function's zero
/// by Newton on the path's equations and the function together ([`super::driver::zero_on_step`]).
struct StepTrials<'d, P> {
    driver: &'d mut Continuation<P>,
    from: &'d PathPoint,
    forward: Vec<(f64, PathPoint)>,
    backward: Vec<(f64, PathPoint)>,
    /// The corrector from the earlier point failed at and beyond this s (not tried again).
    fails_from: f64,
}

impl<P: Problem + States> Trials for StepTrials<'_, P> {
    fn state(&mut self, s: f64) -> Option<(Vec<f64>, Vec<f64>)> {
        let driver = &mut *self.driver;
        let direct = if s < self.fails_from {
            driver.corrected_from(self.from, s).ok()
        } else {
            None
        };
        let q = match direct {
            Some(q) => q,
            None => {
                self.fails_from = self.fails_from.min(s);
                let near_forward = self
                    .forward
                    .iter()
                    .filter(|(t, _)| *t < s)
                    .max_by(|x, y| x.0.total_cmp(&y.0));
                let chained = near_forward.and_then(|(t, p)| driver.step_from(p, s - t).ok());
                match chained {
                    Some(q) => q,
                    None => {
                        let (t, p) = self
                            .backward
                            .iter()
                            .filter(|(t, _)| *t > s)
                            .min_by(|x, y| x.0.total_cmp(&y.0))?;
                        let q = driver.step_from(p, t - s).ok()?;
                        self.backward.push((s, q.clone()));
                        let problem = driver.problem();
                        return Some((problem.displacement(&q.q), problem.parameters(&q.lambda)));
                    }
                }
            }
        };
        self.forward.push((s, q.clone()));
        let problem = self.driver.problem();
        Some((problem.displacement(&q.q), problem.parameters(&q.lambda)))
    }

    fn zero(&mut self, change: SignChange, test: &mut StateTest<'_>) -> Option<ZeroFound> {
        let found = self
            .driver
            .zero_on_step(self.from, change, &mut |p: &P, q, l, _| {
                test(&p.displacement(q), &p.parameters(l))
            })?;
        let problem = self.driver.problem();
        let state = |q: &nalgebra::DVector<f64>, l: &nalgebra::DVector<f64>| {
            (problem.displacement(q), problem.parameters(l))
        };
        let (u, params) = state(&found.point.q, &found.point.lambda);
        let [first, second] = found.sides;
        let side = |x: Option<(f64, nalgebra::DVector<f64>, nalgebra::DVector<f64>)>| {
            x.map(|(s, q, l)| {
                let (u, p) = state(&q, &l);
                (s, u, p)
            })
        };
        Some(ZeroFound {
            u,
            params,
            value: found.value,
            s: found.point.arclength - self.from.arclength,
            sides: [side(first), side(second)],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{leaves_path, reach, tighten};

    /// A zero met at once (at s = 0.3, the first trial within the tolerance) leaves the far
    /// side at the step's end; tightening brings each side to a state of its sign next to the
    /// zero, where g(s) = s − 0.3 is noise (of the wrong sign) within 1e-9 of the zero.
    #[test]
    fn a_zero_met_at_once_gets_the_bracket_of_its_tolerance() {
        let g = |s: f64| {
            let d = s - 0.3;
            if d.abs() < 1e-9 {
                -d
            } else {
                d
            }
        };
        let state = |s: f64| (s, vec![s], vec![2.0 * s]);
        // The zero's own state on the positive side, the negative side still the step's start.
        let mut sides = [state(0.0), state(0.3 + 1e-12)];
        let r = reach(g(0.0), g(1.0), 1.0, 1e-12, 1e-10);
        assert!((r - 2e-10).abs() < 1e-22, "{r}");
        let mut trials = 0;
        tighten(&mut sides, 0.3 + 1e-12, r, false, |s| {
            trials += 1;
            let (s, u, p) = state(s);
            Some((g(s), u, p))
        });
        let [(a, ua, pa), (b, _, _)] = &sides;
        assert!(g(*a) < 0.0 && *a < 0.3 && 0.3 - a < 1e-8, "{a}");
        assert_eq!((ua[0], pa[0]), (*a, 2.0 * a));
        assert_eq!(*b, 0.3 + 1e-12);
        assert!(trials > 1 && trials < 10, "{trials}");
        // A side already within reach is kept, and so is one where no state is found.
        let mut near = [state(0.3 - 1e-11), state(0.9)];
        tighten(&mut near, 0.3, 1e-10, false, |_| None);
        assert_eq!((near[0].0, near[1].0), (0.3 - 1e-11, 0.9));
    }

    /// At a fold the count changes by one and the control turns; between two regular points
    /// neither happens. Anything else leaves the path: the parity without a turn, a turn
    /// without it, or a change by two (both components of a broken pair at once).
    #[test]
    fn a_step_stays_on_the_path_only_where_the_count_follows_the_folds() {
        assert!(!leaves_path(0, 1, 1.0, -1.0));
        assert!(!leaves_path(2, 1, -1.0, 1.0));
        assert!(!leaves_path(2, 2, 0.5, 0.4));
        assert!(leaves_path(0, 1, 1.0, 0.9));
        assert!(leaves_path(1, 1, 1.0, -0.9));
        assert!(leaves_path(3, 2, -1.0, -0.2));
        assert!(leaves_path(1, 3, -0.5, -0.4));
        assert!(leaves_path(0, 2, 0.5, 0.4));
        assert!(leaves_path(0, 3, 0.5, -0.4));
    }
}
