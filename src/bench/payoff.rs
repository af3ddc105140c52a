//! The symmetry payoff on one tangent matrix: every eigenvalue of K by irrep blocks against a
//! dense full eigen-decomposition of K and a sparse shift-invert of K
//! ([`crate::linalg::eigen`]), for the Ih balloon at its pressure maximum ([`payoff`]) and a
//! C8v disc sagging under fluid ([`c8v_payoff`]).

use super::peer::PeerResult;
use crate::adapted::AdaptedBasis;
use crate::linalg::{eigen, SymmetricFactorization};
use crate::model::{Evaluation, FeModel, Model, Request};
use crate::scene::Scene;
use crate::stability::Stability;
use crate::study::mesh::MeshStudy;
use nalgebra::DMatrix;
use std::time::{Duration, Instant};

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
        eigen::nearest(
            self.by_blocks
                .iter()
                .flat_map(|b| std::iter::repeat_n(b.value, b.multiplicity)),
            shift,
            n,
        )
    }
}

/// A symmetry-payoff case of the bench: a short name for the CSV, the payoff, and the scipy
/// peer's result when it was run on this case.
#[derive(Debug, Clone)]
pub struct PayoffCase {
    /// The case's name in `payoff.csv` (`balloon-Ih-f16`, `disc-C8v-d16`).
    pub name: String,
    /// The payoff.
    pub payoff: Payoff,
    /// The peer's result (or why it was skipped), when it was tried on this case.
    pub peer: Option<Result<PeerResult, String>>,
}

/// The `n` eigenvalues of K nearest `shift` by sparse shift-invert: LBLᵀ of K − σI (our
/// [`SymmetricFactorization`]) as the operator of faer's `partial_self_adjoint_eigen`
/// ([`eigen::nearest_eigenvalues_faer`]).
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
    let values = eigen::shifted_values(pattern, &eval.tangent, shift).map_err(|e| e.to_string())?;
    let mut f = SymmetricFactorization::new(pattern).map_err(|e| e.to_string())?;
    f.factorize(&values).map_err(|e| e.to_string())?;
    let factorisation = t.elapsed();
    let t = Instant::now();
    let found = eigen::nearest_eigenvalues_faer(&f, shift, n).map_err(|e| e.to_string())?;
    let lanczos = t.elapsed();
    Ok(ShiftInvert {
        shift,
        factorisation,
        lanczos,
        values: found.values,
        converged: found.converged,
    })
}

/// The symmetry payoff at the state (u, params) of `study`: every eigenvalue of K by irrep
/// blocks against a dense full eigen-decomposition of K (when `dense`), and a sparse
/// shift-invert of K for the `lowest` eigenvalues nearest a small negative shift (when
/// `sparse`).
pub fn payoff(
    study: &MeshStudy,
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
        let k = super::dense_tangent(model, &eval);
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
pub const DISC_FLUID_ABOVE_TOML: &str = include_str!("../../scenes/disc_fluid_above.toml");

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
    let mut study = MeshStudy::build(c8v_disc_scene(divisions)?).map_err(|e| e.to_string())?;
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
    let u = super::solve_start(&mut study, &params)?;
    let mut po = payoff(&study, &u, &params, dense, sparse, lowest)?;
    po.case = format!(
        "clamped disc under fluid (`disc_fluid_above` with 8 sectors, {divisions} divisions, \
         {} triangles), solved at ρ = {C8V_DENSITY}",
        study.model.layout().triangles().len()
    );
    Ok(po)
}
