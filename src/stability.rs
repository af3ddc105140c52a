//! Stability by irrep (docs/theory.md §8, §10): every block K_μ = B_μᵀ K B_μ of the tangent at a
//! symmetric state, its eigenvalues, negative count and zero modes.
//!
//! - Rigid-body modes. A free body has a zero eigenvalue for every rigid motion all its
//!   effects keep (see [`crate::model::Model::rigid_motions`]); at the current positions
//!   those fields u_i = t + ω × x_i are projected into each block, reported there as zero
//!   modes (T1u and T1g for a free sphere in Ih) and deflated: the block's spectrum is taken on
//!   their orthogonal complement, so they never count in the index.
//! - Held mean motions. The rolling of a spherical reference (its material points rotated
//!   along an unchanged shape) is neutral in the continuum but only nearly so on a mesh; the
//!   model's [`crate::model::Model::held_motions`] are deflated like rigid modes (the mean
//!   rotation Σ (X_i − c) × u_i held) and reported as `held`, never counted.
//! - Physical constraints. With augmenting equations g = 0 active (their parameters free) the
//!   trivial block is bordered, K̃ = [[K_A, L], [Lᵀ, C]], each constraint row scaled so that
//!   the border is symmetric (L = Bᵀ ∂F/∂μ and s·∂g/∂q agree; docs/theory.md §8.3).
//!   By Haynsworth the index is that of the Schur complement: on the constraints' tangent
//!   space Zᵀ K_A Z when C = 0, K_A − L C⁻¹ Lᵀ when C is invertible; that matrix's spectrum is
//!   reported for the trivial block.
//!
//! The index of the state is Σ_μ d_μ · neg(block μ).
//!
//! A complex-type irrep (the E_k of a chiral C_n) has a Hermitian block H (docs/theory.md
//! §10.6), each eigenvalue d = 2 times in K. Solved dense, its eigenvalues are H's; solved
//! sparse, the real block R = [[A, C], [−C, A]] is bordered J-invariantly (J [p; q] = [−q; p]),
//! its inertia halved (an odd count is an error, and the block goes dense) and its Lanczos
//! kept orthogonal to the partners J v, so each double eigenvalue is found once.
//!
//! How a block is solved (docs/theory.md §8.6–§8.8):
//! - the negative count, at every path point, from the inertia of one sparse LBLᵀ of the
//!   block bordered by its rigid modes, constraints and rank-one terms (Haynsworth);
//! - eigenvalues, where they are needed (a crossing to localise, `spectrum`, a linear-buckling
//!   sweep): either every eigenvalue of the dense restricted matrix, or the lowest few by
//!   shift-invert Lanczos on the same bordered sparse factorisation — the operator is the
//!   leading block of its inverse, which is the inverse of the restricted matrix on the
//!   complement ([`crate::linalg::eigen::Bordered`]) — certified by the inertia. Which one is
//!   chosen by their estimated cost ([`BlockEigen::ByCost`]), not by a size limit: both give
//!   the eigenvalues of the same matrix.

use crate::adapted::labels::isotropy;
use crate::adapted::AdaptedBasis;
use crate::continuation::crossings::{BlockSpectrum, Blocks, Spectrum};
use crate::linalg::bordered_block::{
    bordered_pattern, partner_in_place, with_partners, BorderedBlock, Complement,
};
use crate::linalg::eigen::{Bordered, Operator};
use crate::linalg::SymmetricFactorization;
use crate::model::constraint::Constraint;
use crate::model::{Evaluation, Model, ModelError, Request};
use crate::results::Isotropy;
use meshes::GroupAction;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rayon::prelude::*;
use std::sync::Mutex;

/// How much of each block [`Stability::analyse`] computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detail {
    /// The negative count only (inertia of a sparse LBLᵀ); no eigenvalues.
    Inertia,
    /// Eigenvalues: all of a block solved dense, at least the `lowest` lowest (and every
    /// negative one) of a block solved by Lanczos.
    Eigenvalues {
        /// The lowest eigenvalues wanted.
        lowest: usize,
    },
    /// Eigenvalues as above and the eigenvectors of the lowest ones.
    Vectors {
        /// The lowest eigenvalues wanted.
        lowest: usize,
    },
}

impl Detail {
    /// The lowest eigenvalues wanted (0 for the inertia).
    pub fn lowest(self) -> usize {
        match self {
            Detail::Inertia => 0,
            Detail::Eigenvalues { lowest } | Detail::Vectors { lowest } => lowest,
        }
    }
}

/// How the eigenvalues of a block are computed when they are asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockEigen {
    /// Dense or Lanczos, whichever is estimated cheaper for the block ([`lanczos_is_cheaper`]).
    ByCost,
    /// Every block dense: all its eigenvalues.
    Dense,
    /// Every block by shift-invert Lanczos on its bordered sparse factorisation: its lowest
    /// eigenvalues.
    Lanczos,
    /// Dense up to this many columns; larger blocks get their negative count only (no
    /// eigenvalues). For comparisons with the inertia alone.
    DenseUpTo(usize),
}

/// The lowest eigenvalues [`Stability::spectrum_of`] asks of a block solved by Lanczos (all of
/// a dense block are computed anyway).
pub const DEFAULT_LOWEST: usize = 8;

/// Seconds per m³ of faer's dense eigenvalues of an m × m block (tridiagonalisation and QR),
/// an estimate from the timings of the thesis study on the project's 2-core machine
/// (BENCHMARKS.md §7, where `benches/crossover.rs` checks the choice it leads to).
const DENSE_EIGEN_SECONDS_PER_M3: f64 = 2.2e-10;
/// Seconds per estimated flop of a numeric sparse LBLᵀ ([`SymmetricFactorization::flops`]),
/// estimated as above.
const SPARSE_FACTOR_SECONDS_PER_FLOP: f64 = 1.0e-9;
/// Seconds per stored factor value of one sparse solve, estimated as above.
const SPARSE_SOLVE_SECONDS_PER_VALUE: f64 = 4.0e-9;

/// Whether the lowest `lowest` eigenvalues of an m-column block cost less by shift-invert
/// Lanczos on `factorization` (its bordered sparse LBLᵀ, symbolic analysis done) than all its
/// eigenvalues by a dense solve: three numeric factorisations (the count at 0, the shift,
/// the check) and about max(3·lowest, 40) + 20 solves, against the m³ of the dense solve.
pub fn lanczos_is_cheaper(m: usize, lowest: usize, factorization: &SymmetricFactorization) -> bool {
    lanczos_beats(
        DENSE_EIGEN_SECONDS_PER_M3 * (m as f64).powi(3),
        lowest,
        factorization,
    )
}

/// As [`lanczos_is_cheaper`] for a complex-type block of 2m real columns (`factorization`
/// of its real form): the dense solve is of the Hermitian m × m block, about four times the
/// flops of a real one of that size.
pub fn lanczos_is_cheaper_complex(
    m: usize,
    lowest: usize,
    factorization: &SymmetricFactorization,
) -> bool {
    lanczos_beats(
        4.0 * DENSE_EIGEN_SECONDS_PER_M3 * (m as f64).powi(3),
        lowest,
        factorization,
    )
}

/// Whether the Lanczos estimate on `factorization` is below `dense` seconds.
fn lanczos_beats(dense: f64, lowest: usize, factorization: &SymmetricFactorization) -> bool {
    let solves = (3 * lowest).max(40) as f64 + 20.0;
    let sparse = 3.0 * SPARSE_FACTOR_SECONDS_PER_FLOP * factorization.flops()
        + solves * SPARSE_SOLVE_SECONDS_PER_VALUE * factorization.factor_len() as f64;
    sparse < dense
}

/// Everything needed to analyse states of one model under one group.
pub struct Stability<'a> {
    model: &'a dyn Model,
    basis: &'a AdaptedBasis,
    motions: Vec<[f64; 6]>,
    /// Mean motions held (fields at the reference positions).
    holds: Vec<[f64; 6]>,
    /// How block eigenvalues are computed.
    method: BlockEigen,
    /// Whether a stop request skips the blocks not started yet ([`Stability::interruptible`]).
    interruptible: bool,
    /// Per block, the sparse factorisation of its bordered matrix and its border size.
    factorizations: Vec<Mutex<Option<(usize, SymmetricFactorization)>>>,
    /// Per block, the positions of its diagonal in its values (the block's pattern is fixed).
    diagonals: Vec<std::sync::OnceLock<Vec<usize>>>,
    /// Per block, the buffer its values are restricted into, kept from one point to the next.
    buffers: Vec<Mutex<Vec<f64>>>,
}

/// A block's bordered sparse matrix with what the stability analysis reports of its
/// border: the rigid modes and held motions deflated there.
struct SparseBlock {
    /// The bordered matrix.
    bordered: BorderedBlock,
    /// Rigid modes found in the block.
    rigid_modes: usize,
    /// Mean motions held in the block.
    held: usize,
    /// Largest |B_μᵀ K r| over the rigid modes, relative to ‖K‖.
    rigid_residual: f64,
}

/// The shift of the Lanczos iteration below zero, relative to max|K_ij|: far enough from a
/// crossing eigenvalue (zero at the critical point) for the factorisation to stay regular,
/// close enough to keep the wanted eigenvalues the nearest.
const LANCZOS_SHIFT: f64 = 1e-6;

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

/// The constraints' border of the trivial block: L = Bᵀ ∂F/∂μ_k (the loads of the parameters
/// the constraints free) and C, each constraint row scaled by s so that s·∂g/∂q agrees with
/// L (the border is symmetric; docs/theory.md §8.3).
fn constraint_border(
    b: &crate::adapted::SparseBasis,
    layout: &crate::model::Layout,
    x: &[meshes::Vec3],
    params: &[f64],
    constraints: &[Box<dyn Constraint>],
    eval: &Evaluation,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let c = constraints.len();
    let mut l = DMatrix::zeros(b.dim(), c);
    let mut cc = DMatrix::zeros(c, c);
    for (kk, con) in constraints.iter().enumerate() {
        let v = con.evaluate(layout, x, params);
        let gq = b.restrict(&v.grad_u);
        let load = b.restrict_invariant(&eval.loads[con.frees()]);
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
    (l, cc)
}

/// max|K_ij| of an evaluation (with its rank-one terms c a aᵀ): the scale of "zero" for a
/// block's eigenvalues.
fn tangent_scale(eval: &Evaluation) -> f64 {
    // An evaluation of a subset writes only its slots; the others hold zeros.
    let sparse_part = match eval.subset() {
        Some(subset) => subset
            .slots()
            .iter()
            .fold(0.0f64, |a, &p| a.max(eval.tangent[p as usize].abs())),
        None => eval.tangent.iter().fold(0.0f64, |a, b| a.max(b.abs())),
    };
    sparse_part
        .max(
            eval.rank_one
                .iter()
                .map(|(c, a)| c.abs() * a.iter().fold(0.0f64, |m, v| m.max(v * v)))
                .fold(0.0, f64::max),
        )
        .max(1e-300)
}

/// ‖t + ω × X_i‖ over the free nodes at the positions X (the norm of a rigid or held field).
fn reference_norms(motion: &[f64; 6], x: &[meshes::Vec3], layout: &crate::model::Layout) -> f64 {
    let t = nalgebra::Vector3::new(motion[0], motion[1], motion[2]);
    let w = nalgebra::Vector3::new(motion[3], motion[4], motion[5]);
    (0..x.len())
        .filter(|&i| layout.dof(i, 0).is_some())
        .map(|i| (t + w.cross(&x[i])).norm_squared())
        .sum::<f64>()
        .sqrt()
        .max(1e-300)
}

/// The spectrum of a complex-type block (docs/theory.md §10.6) from its real restriction `k`
/// (2m × 2m in the basis [u, v]) and the real coordinates `r` of the rigid modes: the
/// eigenvalues of the Hermitian m × m block on the complement of the rigid modes' complex
/// span, each double in K by construction; eigenvectors back in real coordinates.
fn complex_block(
    ib: &crate::adapted::IrrepBasis,
    k: &DMatrix<f64>,
    (r, rigid_modes): (&DMatrix<f64>, usize),
    scale: f64,
    with_vectors: bool,
) -> BlockSpectrum {
    use crate::adapted::{hermitian, to_complex, to_real};
    use crate::linalg::hermitian::{hermitian_eigen, ComplexComplement};
    let h = hermitian(k);
    let m = h.nrows();
    let rc_cols: Vec<Vec<_>> = r.column_iter().map(|c| to_complex(c.as_slice())).collect();
    let rc = DMatrix::from_fn(m, rc_cols.len(), |i, j| rc_cols[j][i]);
    // ‖z‖ = ‖[p; q]‖: a rigid column of order one stays of order one.
    let rigid = ComplexComplement::of(&rc, 1e-12);
    let held = rigid.rank().saturating_sub(rigid_modes);
    let rigid_residual = if r.ncols() > 0 {
        (k * r).amax() / (scale * r.amax().max(1e-300))
    } else {
        0.0
    };
    let (values, vecs) = hermitian_eigen(&rigid.restrict(h), with_vectors);
    let keep = values.len().min(8).min(vecs.ncols());
    let vectors = if keep > 0 {
        let y = rigid.lift(&vecs.columns(0, keep).into_owned());
        let cols: Vec<Vec<f64>> = y.column_iter().map(|z| to_real(z.as_slice())).collect();
        DMatrix::from_fn(2 * m, keep, |i, j| cols[j][i])
    } else {
        DMatrix::zeros(2 * m, 0)
    };
    let negative = values.iter().filter(|&&v| v < 0.0).count();
    BlockSpectrum {
        irrep: ib.name.clone(),
        dim: ib.dim,
        size: m,
        rigid_modes,
        held,
        rigid_residual,
        eigenvalues: values,
        complete: true,
        eigen_error: None,
        negative,
        vectors,
    }
}

impl<'a> Stability<'a> {
    /// The analysis of `model` with the adapted `basis` of the scene's group.
    pub fn new(model: &'a dyn Model, basis: &'a AdaptedBasis) -> Self {
        Self {
            model,
            basis,
            motions: model.rigid_motions(),
            holds: model.held_motions(),
            method: BlockEigen::ByCost,
            interruptible: false,
            factorizations: basis.irreps.iter().map(|_| Mutex::new(None)).collect(),
            diagonals: basis.irreps.iter().map(|_| Default::default()).collect(),
            buffers: basis.irreps.iter().map(|_| Default::default()).collect(),
        }
    }

    /// Builds every block's sparse pattern now, in parallel (the first analysis builds
    /// those not built yet): the blocks' structure, fixed for the mesh and the group, as the
    /// layout's pattern is for the whole K. For an analysis that follows a path.
    pub fn with_patterns(self) -> Self {
        let layout = self.model.layout();
        self.basis
            .irreps
            .par_iter()
            .for_each(|ib| ib.first().prepare_pattern(layout));
        self
    }

    /// Blocks with more than `limit` columns are analysed by the inertia of a sparse LBLᵀ
    /// factorisation of the block, bordered by its rigid modes, constraints and rank-one
    /// terms (Haynsworth): the negative count is exact, no eigenvalues are computed. With
    /// `usize::MAX` every block gets its full dense spectrum. (`BlockEigen::DenseUpTo`.)
    pub fn with_dense_limit(mut self, limit: usize) -> Self {
        self.method = BlockEigen::DenseUpTo(limit);
        self
    }

    /// A stop request ([`interrupt::requested`](crate::continuation::interrupt::requested))
    /// skips the blocks not started yet: their spectra come back empty and incomplete, so the
    /// caller must check the request before it uses the result. For a one-point spectrum (a
    /// large mesh has many blocks, each a long eigenvalue solve); a path's index at every point
    /// is never cut short this way. Each block done counts for the test hook
    /// [`AFTER_BLOCKS`](crate::continuation::interrupt::AFTER_BLOCKS).
    pub fn interruptible(mut self) -> Self {
        self.interruptible = true;
        self
    }

    /// How block eigenvalues are computed (default [`BlockEigen::ByCost`]).
    pub fn with_block_eigen(mut self, method: BlockEigen) -> Self {
        self.method = method;
        self
    }

    /// The bordered matrix of block `mu` by Haynsworth's inertia additivity (docs/theory.md
    /// §8.6), M = [[K_μ, U], [Uᵀ, E]]: U holds an orthonormal basis of the rigid modes r and,
    /// for the trivial block, of the zero-C constraint loads L (E = 0 for those), then the
    /// rank-one vectors a with E = −1/c and the loads L with E = C when C is invertible.
    /// Eliminating the invertible part D of E and then the zero part (p columns, full rank)
    /// gives In(M) = In(D) + In(Zᵀ (K + Σ c a aᵀ − L C⁻¹ Lᵀ) Z) + (p, p, 0): the same
    /// matrix the dense path takes eigenvalues of. Makes sure the block's cached
    /// factorisation has M's pattern. `None` if the block has no orbit-local form. The rigid
    /// modes' residual |B_μᵀ K r| is measured only `with_residual` (it is reported with the
    /// eigenvalues, not with the inertia alone).
    #[allow(clippy::too_many_arguments)]
    fn bordered_block(
        &self,
        mu: usize,
        b: &crate::adapted::SparseBasis,
        layout: &crate::model::Layout,
        eval: &Evaluation,
        (r, rigid_modes): (&DMatrix<f64>, usize),
        border: Option<&(DMatrix<f64>, DMatrix<f64>)>,
        (scale, with_residual): (f64, bool),
    ) -> Option<SparseBlock> {
        let buffer = self.buffers[mu]
            .lock()
            .map(|mut kept| std::mem::take(&mut *kept))
            .unwrap_or_default();
        let (pattern, values) = b.restrict_tangent_sparse_into(layout, eval, buffer)?;
        let m = b.dim();
        let paired = b.is_complex();
        // Border columns: zero-E first (rigid and held span, zero-C constraints), then
        // invertible D. A complex-type block borders J-invariantly: the rigid columns with
        // their partners, each rank-one term c a aᵀ as (c/2)(a aᵀ + J a (J a)ᵀ) — the part of
        // it that commutes with J, as the dense Hermitian block takes it.
        let paired_r;
        let r = if paired {
            paired_r = with_partners(r);
            &paired_r
        } else {
            r
        };
        let rigid = Complement::of(r, 1e-12);
        let deflated = rigid.rank();
        let mut zero_cols: Vec<DVector<f64>> =
            (0..deflated).map(|k| rigid.span_column(k, m)).collect();
        let mut d_cols: Vec<DVector<f64>> = Vec::new();
        let mut d_block: Vec<(usize, usize, f64)> = Vec::new();
        let mut d_negative = 0;
        for (c, a) in &eval.rank_one {
            if *c == 0.0 {
                continue;
            }
            let ar = b.restrict(a);
            if paired {
                let mut jar: Vec<f64> = ar.iter().copied().collect();
                partner_in_place(&mut jar);
                for col in [ar, DVector::from_vec(jar)] {
                    let k = d_cols.len();
                    d_cols.push(col);
                    d_block.push((k, k, -2.0 / c));
                    d_negative += usize::from(*c > 0.0);
                }
            } else {
                let k = d_cols.len();
                d_cols.push(ar);
                d_block.push((k, k, -1.0 / c));
                d_negative += usize::from(*c > 0.0);
            }
        }
        if let Some((l, cc)) = border {
            if cc.amax() <= 1e-12 * scale {
                let norm = l.amax().max(1e-300);
                zero_cols.extend(l.column_iter().map(|c| c / norm));
            } else {
                let k0 = d_cols.len();
                d_cols.extend(l.column_iter().map(|c| c.into_owned()));
                for i in 0..cc.nrows() {
                    for j in 0..cc.ncols() {
                        d_block.push((k0 + i, k0 + j, cc[(i, j)]));
                    }
                }
                d_negative += cc
                    .symmetric_eigenvalues()
                    .iter()
                    .filter(|&&v| v < 0.0)
                    .count();
            }
        }
        // An orthonormal basis of the zero-E columns (dependent ones dropped).
        let constrained: Vec<Vec<f64>> = if zero_cols.is_empty() {
            Vec::new()
        } else {
            let span = Complement::of(&DMatrix::from_columns(&zero_cols), 1e-12);
            (0..span.rank())
                .map(|k| span.span_column(k, m).as_slice().to_vec())
                .collect()
        };
        let p = constrained.len();
        let nb = p + d_cols.len();
        {
            let mut guard = self.factorizations[mu].lock().ok()?;
            if guard.as_ref().is_none_or(|(n, _)| *n != nb) {
                let fact = SymmetricFactorization::new(&bordered_pattern(&pattern, nb)).ok()?;
                *guard = Some((nb, fact));
            }
        }
        let rigid_residual = if rigid_modes > 0 && with_residual {
            let mut worst = 0.0f64;
            let mut y = vec![0.0; m];
            let rank_one: Vec<(f64, DVector<f64>)> = eval
                .rank_one
                .iter()
                .map(|(c, a)| (*c, b.restrict(a)))
                .collect();
            for col in r.column_iter().take(self.motions.len()) {
                pattern.matvec(&values, col.as_slice(), &mut y);
                let mut ky = DVector::from_vec(y.clone());
                for (c, ar) in &rank_one {
                    ky += ar * (c * ar.dot(&col));
                }
                worst = worst.max(ky.amax() / col.amax().max(1e-300));
            }
            worst / scale
        } else {
            0.0
        };
        let (mv, diagonal) = if nb == 0 {
            // Without a border the bordered matrix is the block itself.
            let diagonal = self.diagonals[mu].get_or_init(|| {
                (0..m)
                    .map(|j| pattern.position(j, j).expect("diagonal in pattern"))
                    .collect()
            });
            (values, diagonal.clone())
        } else {
            let bordered = Self::with_border(&pattern, &values, (&constrained, &d_cols), &d_block);
            self.recycle(mu, values);
            bordered
        };
        Some(SparseBlock {
            bordered: BorderedBlock {
                m,
                constrained,
                d_negative,
                values: mv,
                diagonal,
                paired,
            },
            rigid_modes,
            held: if paired { deflated / 2 } else { deflated }.saturating_sub(rigid_modes),
            rigid_residual,
        })
    }

    /// Keeps `values` as block `mu`'s buffer for its next restriction.
    fn recycle(&self, mu: usize, values: Vec<f64>) {
        if let Ok(mut kept) = self.buffers[mu].lock() {
            *kept = values;
        }
    }

    /// The values of the block on `pattern` (`values`) bordered by the columns u (the
    /// orthonormal zero-E ones, then the D columns) and E (`d_block`), on
    /// [`bordered_pattern`], and the positions of the block's diagonal in them.
    fn with_border(
        pattern: &crate::linalg::SymmetricPattern,
        values: &[f64],
        (constrained, d_cols): (&[Vec<f64>], &[DVector<f64>]),
        d_block: &[(usize, usize, f64)],
    ) -> (Vec<f64>, Vec<usize>) {
        let m = pattern.n();
        let p = constrained.len();
        let nb = p + d_cols.len();
        let col_ptr = pattern.col_ptr();
        let u = |i: usize, t: usize| {
            if t < p {
                constrained[t][i]
            } else {
                d_cols[t - p][i]
            }
        };
        let mut e = DMatrix::zeros(nb, nb);
        for &(i, j, v) in d_block {
            e[(p + i, p + j)] = v;
        }
        let mut mv = Vec::with_capacity(pattern.nnz() + 2 * nb * m + nb * nb);
        let mut diagonal = Vec::with_capacity(m);
        for j in 0..m {
            let diag = pattern.position(j, j).expect("diagonal in pattern") - col_ptr[j];
            diagonal.push(mv.len() + diag);
            mv.extend_from_slice(&values[col_ptr[j]..col_ptr[j + 1]]);
            mv.extend((0..nb).map(|t| u(j, t)));
        }
        for t in 0..nb {
            mv.extend((0..m).map(|i| u(i, t)));
            mv.extend((0..nb).map(|t2| e[(t2, t)]));
        }
        (mv, diagonal)
    }

    /// The negative count of block `mu` from the inertia of its bordered sparse LBLᵀ `block`
    /// and, with `lowest > 0`, its lowest eigenvalues (at least `lowest`, and every negative
    /// one) by shift-invert Lanczos on the same factorisation
    /// ([`eigen::lowest_eigenpairs`]), with their eigenvectors when asked for. `None` if its
    /// inertia could not be computed (the caller then goes dense).
    fn block_sparse(
        &self,
        mu: usize,
        sparse: &SparseBlock,
        scale: f64,
        lowest: usize,
        vectors: bool,
    ) -> Option<BlockSpectrum> {
        let block = &sparse.bordered;
        let mut guard = self.factorizations[mu].lock().ok()?;
        let (_, fact) = guard.as_mut()?;
        let negative = block.count_below(fact, 0.0, false).ok()?;
        let m = block.m;
        let mut spectrum = BlockSpectrum {
            irrep: String::new(),
            dim: 0,
            size: if block.paired { m / 2 } else { m },
            rigid_modes: sparse.rigid_modes,
            held: sparse.held,
            rigid_residual: sparse.rigid_residual,
            eigenvalues: Vec::new(),
            complete: false,
            eigen_error: None,
            negative,
            vectors: DMatrix::zeros(m, 0),
        };
        if lowest == 0 {
            return Some(spectrum);
        }
        let shift = -LANCZOS_SHIFT * scale;
        let wanted = lowest.max(negative + 1);
        match block.lowest(fact, wanted, shift, vectors) {
            (Ok(found), rank) => {
                spectrum.complete = found.values.len() >= rank;
                if vectors && !found.vectors.is_empty() {
                    spectrum.vectors =
                        DMatrix::from_fn(m, found.vectors.len(), |i, j| found.vectors[j][i]);
                }
                spectrum.eigenvalues = found.values;
            }
            (Err(e), _) => spectrum.eigen_error = Some(e),
        }
        Some(spectrum)
    }

    /// ‖t + ω × x_i‖ over the free nodes at positions `x` for every rigid motion: the norm of
    /// each rigid field, without building it (unit rigid fields project onto a block as
    /// vectors of order one or round-off).
    fn rigid_norms(&self, x: &[meshes::Vec3]) -> Vec<f64> {
        let layout = self.model.layout();
        self.motions
            .iter()
            .map(|m| reference_norms(m, x, layout))
            .collect()
    }

    /// What block `ib` deflates at positions `x`: its rigid modes' restricted fields (unit
    /// fields, `rigid_norms` their norms) followed by the held mean motions' (at the
    /// reference positions), the number of rigid modes in it (complex-type: the complex
    /// span of r and J r, each pair one mode), and the rigid fields alone.
    fn deflated(
        &self,
        ib: &crate::adapted::IrrepBasis,
        x: &[meshes::Vec3],
        rigid_norms: &[f64],
    ) -> (DMatrix<f64>, usize, DMatrix<f64>) {
        let (model, layout, b) = (self.model, self.model.layout(), ib.first());
        let m = b.dim();
        if !b.holds_rigid_motions() {
            // No rigid or held motion has a component in this block.
            return (DMatrix::zeros(m, 0), 0, DMatrix::zeros(m, 0));
        }
        let r = if self.motions.is_empty() {
            DMatrix::zeros(m, 0)
        } else {
            DMatrix::from_columns(
                &self
                    .motions
                    .iter()
                    .zip(rigid_norms)
                    .map(|(motion, n)| b.restrict_rigid(motion, x, layout) / *n)
                    .collect::<Vec<DVector<f64>>>(),
            )
        };
        let rigid_modes = if ib.complex {
            Complement::of(&with_partners(&r), 1e-12).rank() / 2
        } else {
            Complement::of(&r, 1e-12).rank()
        };
        let r_rigid = r.clone();
        let r = if self.holds.is_empty() {
            r
        } else {
            let reference = model.reference();
            let held = self.holds.iter().map(|motion| {
                let v = b.restrict_rigid(motion, reference, layout);
                &v / reference_norms(motion, reference, layout)
            });
            DMatrix::from_columns(
                &r.column_iter()
                    .map(|c| c.into_owned())
                    .chain(held)
                    .collect::<Vec<_>>(),
            )
        };
        (r, rigid_modes, r_rigid)
    }

    /// The minimally augmented test function of block `mu` at (u, params) (docs/theory.md
    /// §11.2): with S the block's matrix on the complement of its border (the matrix whose
    /// eigenvalues [`Stability::analyse`] gives) and a border vector b, τ = 1/(bᵀ S⁻¹ b) =
    /// −σ, σ the last component of the solution of [[S, b], [bᵀ, 0]] [v; σ] = [0; 1]; zero
    /// exactly where S is singular (b not orthogonal to its kernel), of the sign of the
    /// eigenvalue nearest zero when b is near its eigenvector. S⁻¹ b comes from one sparse LBLᵀ of the bordered block M_μ at σ = 0
    /// (§8.8: its leading rows of M_μ⁻¹ [b; 0] are Z S⁻¹ Zᵀ b). Without `border` the border
    /// is a fixed start vector; `iterations` steps of inverse iteration (b ← S⁻¹ b / ‖·‖)
    /// then turn it towards the eigenvector of the eigenvalue nearest zero before σ is
    /// taken. Returns τ and the border used (unit, block coordinates); τ = 0 where the
    /// factorisation finds the block singular to round-off. `None` for a block without
    /// orbit-local form or a failed factorisation. `eval` may assemble only around the
    /// orbit representatives ([`Stability::new_evaluation`]).
    #[allow(clippy::too_many_arguments)]
    pub fn test_function(
        &self,
        u: &[f64],
        params: &[f64],
        constraints: &[Box<dyn Constraint>],
        eval: &mut Evaluation,
        mu: usize,
        border: Option<&[f64]>,
        iterations: usize,
    ) -> Result<Option<(f64, Vec<f64>)>, ModelError> {
        let (model, layout) = (self.model, self.model.layout());
        let Some(ib) = self.basis.irreps.get(mu) else {
            return Ok(None);
        };
        model.evaluate(u, params, Request::ALL, eval)?;
        let scale = tangent_scale(eval);
        let x = model.positions(u, params);
        let rigid_norms = self.rigid_norms(&x);
        let (r, rigid_modes, _) = self.deflated(ib, &x, &rigid_norms);
        let b = ib.first();
        let constraint = (mu == 0 && !constraints.is_empty())
            .then(|| constraint_border(b, layout, &x, params, constraints, eval));
        let eval: &Evaluation = eval;
        let Some(sparse) = self.bordered_block(
            mu,
            b,
            layout,
            eval,
            (&r, rigid_modes),
            constraint.as_ref(),
            (scale, false),
        ) else {
            return Ok(None);
        };
        let block = &sparse.bordered;
        let Ok(mut guard) = self.factorizations[mu].lock() else {
            return Ok(None);
        };
        let Some((_, fact)) = guard.as_mut() else {
            return Ok(None);
        };
        let m = block.m;
        let op = Bordered::new(fact, m, &block.constrained);
        let mut v: Vec<f64> = match border {
            Some(v) if v.len() == m => v.to_vec(),
            _ => (0..m)
                .map(|i| 1.0 + ((i as f64) * 0.618_034).fract())
                .collect(),
        };
        op.project(&mut v);
        let unit = |v: &mut Vec<f64>| -> bool {
            let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            v.iter_mut().for_each(|x| *x /= n.max(1e-300));
            n > 0.0 && n.is_finite()
        };
        if !unit(&mut v) {
            return Ok(None);
        }
        match fact.factorize(&block.values) {
            Ok(()) => {}
            Err(crate::linalg::FactorError::Singular { .. }) => return Ok(Some((0.0, v))),
            Err(_) => return Ok(None),
        }
        let op = Bordered::new(fact, m, &block.constrained);
        for _ in 0..iterations {
            let mut w = v.clone();
            if op.apply(&mut w).is_err() || !unit(&mut w) {
                return Ok(None);
            }
            v = w;
        }
        let mut w = v.clone();
        if op.apply(&mut w).is_err() {
            return Ok(None);
        }
        let btw: f64 = v.iter().zip(&w).map(|(a, b)| a * b).sum();
        if !btw.is_finite() || btw == 0.0 {
            return Ok(None);
        }
        Ok(Some((1.0 / btw, v)))
    }

    /// The basis by irrep.
    pub fn basis(&self) -> &'a AdaptedBasis {
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
    /// (for localising a crossing in one block), and eigenvectors only when asked for: all
    /// eigenvalues of a block solved dense, the lowest [`DEFAULT_LOWEST`] (and every negative
    /// one) of a block solved by Lanczos.
    pub fn spectrum_of(
        &self,
        u: &[f64],
        params: &[f64],
        constraints: &[Box<dyn Constraint>],
        eval: &mut Evaluation,
        only: Option<usize>,
        with_vectors: bool,
    ) -> Result<Spectrum, ModelError> {
        let lowest = DEFAULT_LOWEST;
        let detail = if with_vectors {
            Detail::Vectors { lowest }
        } else {
            Detail::Eigenvalues { lowest }
        };
        self.analyse(u, params, constraints, eval, only, detail)
    }

    /// An evaluation buffer for [`Stability::analyse`] that assembles only the triangles
    /// around the orbit representatives (all a block restriction reads; ≈ 1/|G| of the
    /// mesh). Its F and K are exact only there. With a block without orbit-local form the
    /// whole mesh is assembled.
    pub fn new_evaluation(&self) -> Evaluation {
        // A block without orbit-local form reads K everywhere.
        let Some(reps) = self
            .basis
            .irreps
            .iter()
            .map(|ib| ib.first().representatives())
            .collect::<Option<Vec<Vec<usize>>>>()
        else {
            return self.model.new_evaluation();
        };
        let reps: Vec<usize> = reps.into_iter().flatten().collect();
        self.model
            .new_evaluation()
            .restricted_to(std::sync::Arc::new(crate::model::Subset::around(
                self.model.layout(),
                &reps,
            )))
    }

    /// The analysis by irrep at (u, params) with `constraints` active, to the `detail`
    /// asked for: [`Detail::Inertia`] gives every block's exact negative count from a
    /// sparse LBLᵀ (the cheap test of stability at every path point); the other two give
    /// the eigenvalues (and vectors) of every block, dense or by Lanczos as
    /// [`BlockEigen`] says, the negative count always from the inertia (a Lanczos block) or the
    /// dense eigenvalues (a dense one). `only = Some(μ)` leaves
    /// the other blocks empty. `eval` is a reusable buffer, from `model.new_evaluation()` or
    /// [`Stability::new_evaluation`].
    pub fn analyse(
        &self,
        u: &[f64],
        params: &[f64],
        constraints: &[Box<dyn Constraint>],
        eval: &mut Evaluation,
        only: Option<usize>,
        detail: Detail,
    ) -> Result<Spectrum, ModelError> {
        let with_vectors = matches!(detail, Detail::Vectors { .. });
        let lowest = detail.lowest();
        let model = self.model;
        let layout = model.layout();
        model.evaluate(u, params, Request::ALL, eval)?;
        let scale = tangent_scale(eval);
        let x = model.positions(u, params);
        let rigid_norms = self.rigid_norms(&x);
        let eval: &Evaluation = eval;
        // The constraints' border of the trivial block, before the blocks go parallel.
        let border0 = match self.basis.irreps.first() {
            Some(ib) if !constraints.is_empty() && only.is_none_or(|o| o == 0) => Some(
                constraint_border(ib.first(), layout, &x, params, constraints, eval),
            ),
            _ => None,
        };
        let block = |(mu, ib): (usize, &crate::adapted::IrrepBasis)| -> BlockSpectrum {
            let b = ib.first();
            let m = b.dim();
            let skipped = self.interruptible && crate::continuation::interrupt::requested();
            if skipped || only.is_some_and(|o| o != mu) {
                return BlockSpectrum {
                    irrep: ib.name.clone(),
                    dim: ib.dim,
                    size: if ib.complex { m / 2 } else { m },
                    rigid_modes: 0,
                    held: 0,
                    rigid_residual: 0.0,
                    eigenvalues: Vec::new(),
                    complete: false,
                    eigen_error: None,
                    negative: 0,
                    vectors: DMatrix::zeros(m, 0),
                };
            }
            let (r, rigid_modes, r_rigid) = self.deflated(ib, &x, &rigid_norms);
            let border = if mu == 0 { border0.clone() } else { None };
            // The sparse bordered block first, unless the dense solve is certain.
            const ALWAYS_DENSE: usize = 64;
            // Blocks up to this size fall back to dense eigenvalues when Lanczos fails.
            const DENSE_FALLBACK: usize = 2500;
            let inertia_only = match self.method {
                _ if detail == Detail::Inertia => true,
                BlockEigen::DenseUpTo(limit) => m > limit,
                _ => false,
            };
            let sparse_first = inertia_only
                || match self.method {
                    BlockEigen::Lanczos => true,
                    BlockEigen::ByCost => m > ALWAYS_DENSE,
                    BlockEigen::Dense | BlockEigen::DenseUpTo(_) => false,
                };
            if sparse_first {
                if let Some(block) = self.bordered_block(
                    mu,
                    b,
                    layout,
                    eval,
                    (&r, rigid_modes),
                    border.as_ref(),
                    (scale, !inertia_only),
                ) {
                    let lanczos = !inertia_only
                        && match self.method {
                            BlockEigen::Lanczos => true,
                            BlockEigen::ByCost => self.factorizations[mu].lock().is_ok_and(|g| {
                                g.as_ref().is_some_and(|(_, f)| {
                                    if ib.complex {
                                        lanczos_is_cheaper_complex(m / 2, lowest, f)
                                    } else {
                                        lanczos_is_cheaper(m, lowest, f)
                                    }
                                })
                            }),
                            BlockEigen::Dense | BlockEigen::DenseUpTo(_) => false,
                        };
                    if inertia_only || lanczos {
                        let wanted = if lanczos { lowest } else { 0 };
                        // A Lanczos that could not certify its eigenvalues falls back to
                        // the dense solve where that is affordable.
                        let certified = |s: &BlockSpectrum| {
                            inertia_only || s.eigen_error.is_none() || m > DENSE_FALLBACK
                        };
                        let spectrum = self
                            .block_sparse(mu, &block, scale, wanted, with_vectors)
                            .filter(certified);
                        self.recycle(mu, block.bordered.values);
                        if let Some(spectrum) = spectrum {
                            return BlockSpectrum {
                                irrep: ib.name.clone(),
                                dim: ib.dim,
                                ..spectrum
                            };
                        }
                    }
                }
            }
            let k = b.restrict_tangent(layout, eval, &mut Vec::new());
            if ib.complex {
                return complex_block(ib, &k, (&r, rigid_modes), scale, with_vectors);
            }
            let rigid = Complement::of(&r, 1e-12);
            let held = rigid.rank() - rigid_modes;
            let rigid_residual = if rigid_modes > 0 {
                (&k * &r_rigid).amax() / (scale * r_rigid.amax().max(1e-300))
            } else {
                0.0
            };
            let mut kz = rigid.restrict(k);
            // The constraints' border on the trivial block.
            let mut deflated = None;
            if let Some((l, cc)) = border.filter(|_| kz.nrows() > 0) {
                let lz = rigid.restrict_columns(l);
                if cc.amax() <= 1e-12 * scale {
                    let lz = &lz / lz.amax().max(1e-300);
                    let zc = Complement::of(&lz, 1e-12);
                    kz = zc.restrict(kz);
                    deflated = Some(zc);
                } else if let Some(ci) = cc.clone().try_inverse() {
                    kz -= &lz * ci * lz.transpose();
                }
            }
            let (values, vecs) = sorted_eigen(&kz, with_vectors);
            let keep = values.len().min(8).min(vecs.ncols());
            let vectors = if keep > 0 {
                let y = vecs.columns(0, keep).into_owned();
                let y = match &deflated {
                    Some(zc) => zc.lift(&y),
                    None => y,
                };
                rigid.lift(&y)
            } else {
                DMatrix::zeros(m, 0)
            };
            let negative = values.iter().filter(|&&v| v < 0.0).count();
            BlockSpectrum {
                irrep: ib.name.clone(),
                dim: ib.dim,
                size: m,
                rigid_modes,
                held,
                rigid_residual,
                eigenvalues: values,
                complete: true,
                eigen_error: None,
                negative,
                vectors,
            }
        };
        // Blocks are independent: one rayon task each.
        let blocks: Vec<BlockSpectrum> = self
            .basis
            .irreps
            .par_iter()
            .enumerate()
            .map(|item| {
                let done = block(item);
                if self.interruptible {
                    crate::continuation::interrupt::block_done();
                }
                done
            })
            .collect();
        let index = blocks.iter().map(|b| b.dim * b.negative).sum();
        Ok(Spectrum {
            blocks,
            index,
            scale,
        })
    }
}

/// The blocks of a 3-D model by the irreps of the scene's group: every block's inertia from a
/// sparse LBLᵀ around the orbit representatives, its eigenvalues dense or by Lanczos
/// ([`Stability`]), the critical mode expanded from the first partner's basis, its isotropy
/// under the group's action.
pub struct IrrepBlocks<'a> {
    stability: Stability<'a>,
    constraints: &'a [Box<dyn Constraint>],
    action: &'a GroupAction,
    model: &'a dyn Model,
    /// The model's evaluation buffer, reused by every spectrum (the tangent of a large mesh
    /// is megabytes; a fresh buffer per point would allocate it every time).
    eval: Evaluation,
    /// The evaluation around the orbit representatives, for the index at every point.
    local: Evaluation,
}

impl<'a> IrrepBlocks<'a> {
    /// The blocks of `stability` at states of `model` with `constraints` active; modes'
    /// isotropy under `action`. The blocks' patterns are built here
    /// ([`Stability::with_patterns`]), before the first point.
    pub fn new(
        stability: Stability<'a>,
        model: &'a dyn Model,
        constraints: &'a [Box<dyn Constraint>],
        action: &'a GroupAction,
    ) -> Self {
        Self {
            eval: model.new_evaluation(),
            local: stability.new_evaluation(),
            stability: stability.with_patterns(),
            constraints,
            action,
            model,
        }
    }
}

impl Blocks for IrrepBlocks<'_> {
    fn switched(&self, a: (&[f64], &[f64]), b: (&[f64], &[f64])) -> Option<usize> {
        let before = self.model.switches(a.0, a.1)?;
        let after = self.model.switches(b.0, b.1)?;
        Some(before.iter().zip(&after).filter(|(x, y)| x != y).count())
    }

    fn names(&self) -> Vec<String> {
        self.stability
            .basis()
            .irreps
            .iter()
            .map(|ib| ib.name.clone())
            .collect()
    }

    fn index(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.stability
            .analyse(
                u,
                params,
                self.constraints,
                &mut self.local,
                None,
                Detail::Inertia,
            )
            .ok()
    }

    fn spectrum(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.stability
            .spectrum_of(u, params, self.constraints, &mut self.eval, None, false)
            .ok()
    }

    fn block_eigen(
        &mut self,
        u: &[f64],
        params: &[f64],
        block: usize,
        lowest: usize,
        vectors: bool,
    ) -> Option<Spectrum> {
        let detail = if vectors {
            Detail::Vectors { lowest }
        } else {
            Detail::Eigenvalues { lowest }
        };
        // One block reads K only around its orbit representatives.
        self.stability
            .analyse(
                u,
                params,
                self.constraints,
                &mut self.local,
                Some(block),
                detail,
            )
            .ok()
    }

    fn test_function(
        &mut self,
        u: &[f64],
        params: &[f64],
        block: usize,
        border: Option<&[f64]>,
        iterations: usize,
    ) -> Option<(f64, Vec<f64>)> {
        self.stability
            .test_function(
                u,
                params,
                self.constraints,
                &mut self.local,
                block,
                border,
                iterations,
            )
            .ok()
            .flatten()
    }

    fn mode(&self, block: usize, v: &[f64]) -> Vec<f64> {
        let first = self.stability.basis().irreps[block].first();
        let mut mode = vec![0.0; first.unknowns()];
        first.expand(&nalgebra::DVector::from_column_slice(v), &mut mode);
        mode
    }

    fn isotropy(&self, _block: usize, mode: &[f64]) -> Isotropy {
        isotropy(self.action, self.model.layout(), mode)
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
