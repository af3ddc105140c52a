//! Stability by irrep (DESIGN §3, §4.3): every block K_μ = B_μᵀ K B_μ of the tangent at a
//! symmetric state, its eigenvalues, negative count and zero modes.
//!
//! - Rigid-body modes. A free body has a zero eigenvalue for every rigid motion all its
//!   effects keep (see [`crate::model::FeModel::rigid_motions`]); at the current positions
//!   those fields u_i = t + ω × x_i are projected into each block, reported there as zero
//!   modes (T1u and T1g for a free sphere in Ih) and deflated: the block's spectrum is taken on
//!   their orthogonal complement, so they never count in the index.
//! - Physical constraints. With augmenting equations g = 0 active (their parameters free) the
//!   trivial block is bordered, K̃ = [[K_A, L], [Lᵀ, C]], each constraint row scaled so that
//!   the border is symmetric (L = Bᵀ ∂F/∂μ and s·∂g/∂q agree; DESIGN §2.3 "scale it by −ρg").
//!   By Haynsworth the index is that of the Schur complement: on the constraints' tangent
//!   space Zᵀ K_A Z when C = 0, K_A − L C⁻¹ Lᵀ when C is invertible; that matrix's spectrum is
//!   reported for the trivial block.
//!
//! The index of the state is Σ_μ d_μ · neg(block μ).

use crate::adapted::AdaptedBasis;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, FeModel, Model, ModelError, Request};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::Serialize;

/// The spectrum of one irrep's block.
#[derive(Debug, Clone, Serialize)]
pub struct BlockSpectrum {
    /// Irrep name.
    pub irrep: String,
    /// Irrep dimension d (every eigenvalue below occurs d times in K).
    pub dim: usize,
    /// Block size m_μ (columns of one partner).
    pub size: usize,
    /// Rigid-body zero modes found in this block (deflated).
    pub rigid_modes: usize,
    /// Largest |B_μᵀ K r| over the rigid modes r, relative to ‖K‖ (≈ 0 at an equilibrium).
    pub rigid_residual: f64,
    /// Eigenvalues on the complement of the rigid modes (and of the constraints' border for the
    /// trivial block), ascending.
    pub eigenvalues: Vec<f64>,
    /// Number of negative eigenvalues.
    pub negative: usize,
    /// Eigenvectors (columns, in block coordinates of the first partner) of the lowest
    /// eigenvalues, kept for critical modes.
    #[serde(skip)]
    pub vectors: DMatrix<f64>,
}

/// The spectrum of a state by irrep.
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

/// Everything needed to analyse states of one model under one group.
pub struct Stability<'a> {
    model: &'a FeModel,
    basis: &'a AdaptedBasis,
    motions: Vec<[f64; 6]>,
}

/// The orthogonal complement of the columns of an m × c matrix r (c small: rigid modes,
/// constraint gradients), as Q = H_1 ⋯ H_k, a product of Householder reflections from a
/// QR factorisation of r with column pivoting: the first k columns of Q span r's columns,
/// the other m − k their complement. Restricting a block to the complement then costs
/// O(k m²) (a reflection from both sides per column) instead of the O(m³) of forming Z
/// explicitly.
struct Complement {
    /// Unit Householder vectors v (H = I − 2 v vᵀ), zero above their pivot row.
    reflectors: Vec<DVector<f64>>,
}

impl Complement {
    /// Columns count when the part of them not yet spanned has squared norm above `floor`
    /// (callers pass columns whose genuine parts are of order one).
    fn of(r: &DMatrix<f64>, floor: f64) -> Self {
        let m = r.nrows();
        let mut a = r.clone();
        let mut reflectors = Vec::new();
        for k in 0..r.ncols().min(m) {
            let (pivot, norm2) = (k..a.ncols())
                .map(|j| (j, a.view((k, j), (m - k, 1)).norm_squared()))
                .fold((k, -1.0), |best, x| if x.1 > best.1 { x } else { best });
            if norm2 <= floor {
                break;
            }
            a.swap_columns(k, pivot);
            let mut v = DVector::zeros(m);
            v.rows_mut(k, m - k).copy_from(&a.view((k, k), (m - k, 1)));
            let alpha = -v[k].signum() * norm2.sqrt();
            v[k] -= alpha;
            v /= v.norm();
            let vta = v.transpose() * &a;
            a -= &v * vta * 2.0;
            reflectors.push(v);
        }
        Self { reflectors }
    }

    /// The rank k of r.
    fn rank(&self) -> usize {
        self.reflectors.len()
    }

    /// (Qᵀ K Q) without its first k rows and columns: K on the complement.
    fn restrict(&self, mut k: DMatrix<f64>) -> DMatrix<f64> {
        if self.reflectors.is_empty() {
            return k;
        }
        for v in &self.reflectors {
            // H K H = K − 2 v wᵀ − 2 w vᵀ + 4 (vᵀ w) v vᵀ with w = K v.
            let w = &k * v;
            let vw = v.dot(&w);
            k -= (v * w.transpose() + &w * v.transpose()) * 2.0;
            k += v * v.transpose() * (4.0 * vw);
        }
        let (n, r) = (k.nrows(), self.rank());
        k.view((r, r), (n - r, n - r)).into_owned()
    }

    /// (Qᵀ L) without its first k rows: the columns of L in complement coordinates.
    fn restrict_columns(&self, mut l: DMatrix<f64>) -> DMatrix<f64> {
        for v in &self.reflectors {
            let vtl = v.transpose() * &l;
            l -= v * vtl * 2.0;
        }
        let r = self.rank();
        l.rows(r, l.nrows() - r).into_owned()
    }

    /// Q [0; y]: complement coordinates back to block coordinates.
    fn lift(&self, y: &DMatrix<f64>) -> DMatrix<f64> {
        let r = self.rank();
        let mut x = DMatrix::zeros(y.nrows() + r, y.ncols());
        x.rows_mut(r, y.nrows()).copy_from(y);
        for v in self.reflectors.iter().rev() {
            let vtx = v.transpose() * &x;
            x -= v * vtx * 2.0;
        }
        x
    }
}

/// Sorted eigen-decomposition of a symmetric matrix (empty-safe), by faer's dense
/// self-adjoint eigensolver (much faster than nalgebra's on blocks of a few hundred).
fn sorted_eigen(a: &DMatrix<f64>, with_vectors: bool) -> (Vec<f64>, DMatrix<f64>) {
    let n = a.nrows();
    if n == 0 {
        return (Vec::new(), DMatrix::zeros(0, 0));
    }
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    if !with_vectors {
        if let Ok(values) = m.self_adjoint_eigenvalues(faer::Side::Lower) {
            let mut values = values;
            values.sort_by(f64::total_cmp);
            return (values, DMatrix::zeros(n, 0));
        }
    }
    match m.self_adjoint_eigen(faer::Side::Lower) {
        Ok(eig) => {
            // faer returns the eigenvalues in ascending order.
            let s = eig.S();
            let u = eig.U();
            let values = (0..n).map(|k| s[k]).collect();
            let vectors = DMatrix::from_fn(n, n, |i, j| u[(i, j)]);
            (values, vectors)
        }
        Err(_) => {
            let eig = SymmetricEigen::new(a.clone());
            let mut idx: Vec<usize> = (0..n).collect();
            idx.sort_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y]));
            let values = idx.iter().map(|&k| eig.eigenvalues[k]).collect();
            let vectors = DMatrix::from_fn(n, n, |i, j| eig.eigenvectors[(i, idx[j])]);
            (values, vectors)
        }
    }
}

impl<'a> Stability<'a> {
    /// The analysis of `model` with the adapted `basis` of the scene's group.
    pub fn new(model: &'a FeModel, basis: &'a AdaptedBasis) -> Self {
        Self {
            model,
            basis,
            motions: model.rigid_motions(),
        }
    }

    /// The basis by irrep.
    pub fn basis(&self) -> &AdaptedBasis {
        self.basis
    }

    /// The spectrum by irrep at (u, params) with `constraints` active; `governed[k]` is the
    /// parameter constraint k frees. `eval` is a reusable buffer.
    pub fn spectrum(
        &self,
        u: &[f64],
        params: &[f64],
        constraints: &[Box<dyn Constraint>],
        eval: &mut Evaluation,
    ) -> Result<Spectrum, ModelError> {
        self.spectrum_of(u, params, constraints, eval, None, true)
    }

    /// As [`Stability::spectrum`], but with `only = Some(μ)` the other blocks are left empty
    /// (for localising a crossing in one block), and eigenvectors only when asked for.
    pub fn spectrum_of(
        &self,
        u: &[f64],
        params: &[f64],
        constraints: &[Box<dyn Constraint>],
        eval: &mut Evaluation,
        only: Option<usize>,
        with_vectors: bool,
    ) -> Result<Spectrum, ModelError> {
        let model = self.model;
        let layout = model.layout();
        model.evaluate(u, params, Request::ALL, eval)?;
        let scale = eval
            .tangent
            .iter()
            .fold(0.0f64, |a, b| a.max(b.abs()))
            .max(
                eval.rank_one
                    .iter()
                    .map(|(c, a)| c.abs() * a.iter().fold(0.0f64, |m, v| m.max(v * v)))
                    .fold(0.0, f64::max),
            )
            .max(1e-300);
        let x = model.positions(u);
        // Unit rigid fields: their projections onto a block are of order one or round-off.
        let rigid: Vec<Vec<f64>> = model
            .rigid_modes(&self.motions, &x)
            .into_iter()
            .map(|v| {
                let n = v.iter().map(|a| a * a).sum::<f64>().sqrt().max(1e-300);
                v.into_iter().map(|a| a / n).collect()
            })
            .collect();
        let mut work = Vec::new();
        let mut blocks = Vec::with_capacity(self.basis.irreps.len());
        for (mu, ib) in self.basis.irreps.iter().enumerate() {
            let b = &ib.partners[0];
            let m = b.dim();
            if only.is_some_and(|o| o != mu) {
                blocks.push(BlockSpectrum {
                    irrep: ib.name.clone(),
                    dim: ib.dim,
                    size: m,
                    rigid_modes: 0,
                    rigid_residual: 0.0,
                    eigenvalues: Vec::new(),
                    negative: 0,
                    vectors: DMatrix::zeros(m, 0),
                });
                continue;
            }
            let k = b.restrict_tangent(layout, eval, &mut work);
            // Rigid modes in this block, deflated.
            let r = if rigid.is_empty() {
                DMatrix::zeros(m, 0)
            } else {
                DMatrix::from_columns(
                    &rigid
                        .iter()
                        .map(|v| b.restrict(v))
                        .collect::<Vec<DVector<f64>>>(),
                )
            };
            let rigid = Complement::of(&r, 1e-12);
            let rigid_modes = rigid.rank();
            let rigid_residual = if rigid_modes > 0 {
                (&k * &r).amax() / (scale * r.amax().max(1e-300))
            } else {
                0.0
            };
            let mut kz = rigid.restrict(k);
            // The constraints' border on the trivial block.
            let mut border = None;
            if mu == 0 && !constraints.is_empty() && kz.nrows() > 0 {
                let c = constraints.len();
                let mut l = DMatrix::zeros(m, c);
                let mut cc = DMatrix::zeros(c, c);
                for (kk, con) in constraints.iter().enumerate() {
                    let v = con.evaluate(layout, &x, params);
                    let gq = b.restrict(&v.grad_u);
                    let load = b.restrict(&eval.loads[con.frees()]);
                    let s = if gq.norm_squared() > 0.0 {
                        gq.dot(&load) / gq.norm_squared()
                    } else {
                        1.0
                    };
                    l.set_column(kk, &load);
                    for (jj, other) in constraints.iter().enumerate() {
                        cc[(kk, jj)] = s * v.grad_params[other.frees()];
                    }
                }
                let cc = (&cc + cc.transpose()) * 0.5;
                let lz = rigid.restrict_columns(l);
                if cc.amax() <= 1e-12 * scale {
                    let lz = &lz / lz.amax().max(1e-300);
                    let zc = Complement::of(&lz, 1e-12);
                    kz = zc.restrict(kz);
                    border = Some(zc);
                } else if let Some(ci) = cc.clone().try_inverse() {
                    kz -= &lz * ci * lz.transpose();
                }
            }
            let (values, vecs) = sorted_eigen(&kz, with_vectors);
            let keep = values.len().min(8).min(vecs.ncols());
            let vectors = if keep > 0 {
                let y = vecs.columns(0, keep).into_owned();
                let y = match &border {
                    Some(zc) => zc.lift(&y),
                    None => y,
                };
                rigid.lift(&y)
            } else {
                DMatrix::zeros(m, 0)
            };
            let negative = values.iter().filter(|&&v| v < 0.0).count();
            blocks.push(BlockSpectrum {
                irrep: ib.name.clone(),
                dim: ib.dim,
                size: m,
                rigid_modes,
                rigid_residual,
                eigenvalues: values,
                negative,
                vectors,
            });
        }
        let index = blocks.iter().map(|b| b.dim * b.negative).sum();
        Ok(Spectrum {
            blocks,
            index,
            scale,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::Complement;
    use nalgebra::DMatrix;

    /// Q is orthogonal, its last m − k columns are orthogonal to r, and `restrict` is Zᵀ K Z
    /// for those columns Z; a column dependent on the others does not count in the rank.
    #[test]
    fn complement_is_orthogonal_and_restricts() {
        let m = 9;
        let f = |i: usize, j: usize| ((i * 7 + j * 3) as f64 * 0.37).sin();
        let mut r = DMatrix::from_fn(m, 3, f);
        let dependent = r.column(0) * 2.0 - r.column(1) * 0.5;
        r.set_column(2, &dependent);
        let c = Complement::of(&r, 1e-12);
        assert_eq!(c.rank(), 2);
        let q = c.lift(&DMatrix::identity(m - 2, m - 2));
        assert!((q.transpose() * &q - DMatrix::identity(m - 2, m - 2)).amax() < 1e-14);
        assert!((q.transpose() * &r).amax() < 1e-14);
        let a = DMatrix::from_fn(m, m, |i, j| f(i + j, i * j));
        let k = &a + a.transpose();
        let expected = q.transpose() * &k * &q;
        assert!((c.restrict(k.clone()) - expected).amax() < 1e-13);
        let l = DMatrix::from_fn(m, 2, |i, j| f(j, i + 1));
        assert!((c.restrict_columns(l.clone()) - q.transpose() * l).amax() < 1e-14);
    }
}
