//! The eigenvalues of a sparse symmetric matrix A nearest a shift σ, by shift-invert Lanczos.
//!
//! # The method
//! The eigenpairs (λ, x) of A and those of the inverse of the shifted matrix are the same
//! vectors with
//!
//! ```text
//!     (A − σI)⁻¹ x = θ x,   θ = 1 / (λ − σ),   λ = σ + 1/θ,
//! ```
//!
//! so the eigenvalues of A nearest σ are the θ of largest |θ|, the ones a Krylov method finds
//! first. One sparse `LBLᵀ` factorisation of A − σI ([`SymmetricFactorization`]) gives the
//! operator: each Lanczos step is one solve.
//!
//! [`nearest_eigenvalues`] runs Lanczos on (A − σI)⁻¹ with **full reorthogonalisation**: with
//! V_m = [v_1 … v_m] orthonormal and T_m tridiagonal (diagonal α_j, off-diagonal β_j),
//!
//! ```text
//!     (A − σI)⁻¹ V_m = V_m T_m + β_m v_{m+1} e_mᵀ,
//! ```
//!
//! every new vector is orthogonalised against all earlier ones (classical Gram–Schmidt,
//! twice), so no spurious copies of converged Ritz values appear. The Ritz values θ_i of T_m
//! (eigenvector s_i) approximate eigenvalues of (A − σI)⁻¹ with residual
//! ‖(A − σI)⁻¹ V_m s_i − θ_i V_m s_i‖ = |β_m s_mi|; an eigenvalue is accepted when that is at
//! most 1e-8 |θ_i| — relative to its *own* θ, so that the distance |λ_i − σ| = 1/|θ_i| is
//! known to 1e-8 relative whatever the other values are (the error of θ_i is of the order of
//! the residual's square over the gap).
//!
//! **Restarts on breakdown.** When β_j ≈ 0 (below 1e-12 max|α|) the Krylov space is an
//! invariant subspace. With a symmetric A this is common: a single start vector reaches one
//! direction per *distinct* eigenvalue (e.g. only 130 of the 486 of a frequency-4 icosphere
//! balloon's tangent), so repeated eigenvalues would be found once. The iteration then goes
//! on from a fresh pseudo-random direction orthogonal to V_j (β_j = 0 is kept in T, whose
//! relation above still holds), so it never stalls and finds further copies of degenerate
//! eigenvalues. The space grows from max(3n, 40) by max(n, 30) vectors at a time until the
//! n Ritz values of largest |θ| have converged or the space is the whole space.
//!
//! **Operators.** The iteration ([`nearest_eigenpairs`]) runs on any [`Operator`]: a plain
//! factorisation of A − σI, or [`Bordered`], the leading block of the inverse of a bordered
//! matrix [[A − σI, U], [Uᵀ, E]] on the complement of the border's E = 0 columns — the
//! restricted operator whose inertia a stability block counts (docs/theory.md §8.8). Ritz
//! vectors come with the values when asked for.
//!
//! **Pairs.** An operator with a complex structure J ([`Operator::partner`]: the real form
//! of a Hermitian operator, every eigenvalue double with eigenvectors x and J x) has each new
//! Lanczos vector and every fresh direction orthogonalised against the partners J v_i too, and
//! its rank counted in pairs: the iteration is complex Lanczos on the Hermitian operator and
//! finds each double eigenvalue once (docs/theory.md §10.6).
//!
//! **The lowest eigenvalues, certified.** [`lowest_eigenpairs`] finds the n lowest
//! eigenvalues of a [`ShiftFamily`] (a matrix that can be factorised at any shift, with the
//! inertia of each factorisation): the inertia at σ says how many eigenvalues lie below σ,
//! which the Lanczos result must reproduce, and a second factorisation just above the n-th
//! value found must count exactly n. A value missed by the iteration (a near-double whose
//! second copy the Krylov space has not reached) fails that count and the search repeats;
//! no uncertified list is returned.
//!
//! **The shift.** A σ that is an eigenvalue to round-off fails the factorisation
//! ([`EigenError::Factor`]); [`lowest_eigenpairs`] then moves it.
//!
//! [`nearest_eigenvalues_faer`] is faer's `partial_self_adjoint_eigen` (thick-restart
//! Lanczos) on the same operator, kept for comparison: it can loop forever in its
//! reorthogonalisation once the Krylov space is exhausted, so it is only for matrices whose
//! wanted eigenvalues are simple.
//!
//! Nothing here knows of a model: the matrix is a [`SymmetricPattern`] with its values, or a
//! factorisation of A − σI made by the caller.

use super::{FactorError, SymmetricFactorization, SymmetricPattern};

/// A Ritz value has converged when its residual |β_m s_mi| is at most this times its |θ_i|.
const RESIDUAL_TOLERANCE: f64 = 1e-8;
/// β_j below this times max|α| is a breakdown of the Lanczos recurrence.
const BREAKDOWN_TOLERANCE: f64 = 1e-12;
/// The state of the pseudo-random directions (xorshift), fixed: results are reproducible.
const SEED: u64 = 0x2545_F491_4F6C_DD1D;
/// The smallest Krylov space of the first Lanczos pass.
const START_SPACE: usize = 40;

/// Why the eigenvalues could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// The values do not match the pattern.
    #[error("{values} values for a pattern of {nnz} entries")]
    Length {
        /// Values given.
        values: usize,
        /// Entries of the pattern.
        nnz: usize,
    },
    /// The symbolic analysis or the numeric factorisation of A − σI failed (σ is an
    /// eigenvalue of A to round-off, or the factorisation broke down).
    #[error("factorising A − σI: {0}")]
    Factor(FactorError),
    /// A solve with the factorisation failed (it was not factorised, or its last
    /// factorisation failed).
    #[error("solving with A − σI: {0}")]
    Solve(FactorError),
    /// faer's iteration needs more unknowns than its Krylov space
    /// ([`nearest_eigenvalues_faer`]).
    #[error("{dim} unknowns: faer's Lanczos needs more than its Krylov space of {krylov}")]
    TooSmall {
        /// Unknowns of A.
        dim: usize,
        /// The largest Krylov space, max(4n, 64).
        krylov: usize,
    },
    /// No start vector could be drawn.
    #[error("empty start vector")]
    StartVector,
    /// The dense eigenproblem of the Lanczos tridiagonal matrix failed.
    #[error("Lanczos tridiagonal eigen: {0}")]
    Tridiagonal(String),
    /// The inertia of the realification of a Hermitian matrix (an operator with a complex
    /// structure, [`Operator::partner`]) counted an odd number of eigenvalues below a shift:
    /// its double eigenvalues have come apart, and half the count would be wrong.
    #[error("the real form of a Hermitian block counts {counted} eigenvalues below the shift, an odd number")]
    OddPairedCount {
        /// The count of the real form.
        counted: usize,
    },
    /// The eigenvalues found did not reproduce the inertia ([`lowest_eigenpairs`]).
    #[error("after {attempts} attempts the inertia counts {counted} eigenvalues where Lanczos found {found}")]
    Unverified {
        /// Attempts made.
        attempts: usize,
        /// The count by inertia in the last check.
        counted: usize,
        /// The count of the values found.
        found: usize,
    },
}

/// The eigenvalues of A nearest the shift.
#[derive(Debug, Clone, PartialEq)]
pub struct Nearest {
    /// At most the number asked for, ascending.
    pub values: Vec<f64>,
    /// How many of them converged (all of them unless the space was exhausted first).
    pub converged: usize,
}

/// The values of A − `shift`·I on `pattern` (A's values in `values`, aligned with the
/// pattern's row indices; every diagonal entry is in a [`SymmetricPattern`]).
pub fn shifted_values(
    pattern: &SymmetricPattern,
    values: &[f64],
    shift: f64,
) -> Result<Vec<f64>, EigenError> {
    if values.len() != pattern.nnz() {
        return Err(EigenError::Length {
            values: values.len(),
            nnz: pattern.nnz(),
        });
    }
    let mut shifted = values.to_vec();
    for i in 0..pattern.n() {
        let p = pattern.position(i, i).expect("diagonal in pattern");
        shifted[p] -= shift;
    }
    Ok(shifted)
}

/// The (at most) `n` eigenvalues of A nearest `shift`, ascending: A − σI factorised
/// (symbolic analysis and numeric `LBLᵀ`), then [`nearest_eigenvalues`].
pub fn shift_invert(
    pattern: &SymmetricPattern,
    values: &[f64],
    shift: f64,
    n: usize,
) -> Result<Nearest, EigenError> {
    let shifted = shifted_values(pattern, values, shift)?;
    let mut f = SymmetricFactorization::new(pattern).map_err(EigenError::Factor)?;
    f.factorize(&shifted).map_err(EigenError::Factor)?;
    nearest_eigenvalues(&f, shift, n)
}

/// The `n` values of `values` nearest `shift`, ascending: the reference selection to compare
/// a shift-invert result with (e.g. every eigenvalue of a dense solve, or of blocks, each as
/// often as its multiplicity).
pub fn nearest(values: impl IntoIterator<Item = f64>, shift: f64, n: usize) -> Vec<f64> {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(|a, b| (a - shift).abs().total_cmp(&(b - shift).abs()));
    v.truncate(n);
    v.sort_by(f64::total_cmp);
    v
}

/// The (at most) `n` eigenvalues of A nearest `shift`, ascending, from a factorisation `f` of
/// A − shift·I: Lanczos on (A − shift·I)⁻¹ with full reorthogonalisation, restarted from a
/// fresh direction on breakdown (see the [module documentation](self)). Returns the values and
/// how many of them converged; fewer than asked converge only when the Krylov space is the
/// whole space (then every value is exact to round-off anyway) or no direction is left.
pub fn nearest_eigenvalues(
    f: &SymmetricFactorization,
    shift: f64,
    n: usize,
) -> Result<Nearest, EigenError> {
    let pairs = nearest_eigenpairs(f, shift, n, false, 0)?;
    Ok(Nearest {
        values: pairs.values,
        converged: pairs.converged,
    })
}

/// A symmetric operator for shift-invert Lanczos: x ↦ (A − σI)⁻¹ x on a subspace of ℝⁿ (all
/// of it for a plain factorisation; the complement of a constraint border for [`Bordered`]).
pub trait Operator {
    /// Length n of the vectors.
    fn dim(&self) -> usize;
    /// Dimension of the subspace the operator acts on (its range).
    fn rank(&self) -> usize {
        self.dim()
    }
    /// x ← (A − σI)⁻¹ x, the result in the subspace.
    fn apply(&self, x: &mut [f64]) -> Result<(), FactorError>;
    /// x ← its orthogonal projection onto the subspace (the identity by default).
    fn project(&self, _x: &mut [f64]) {}
    /// x ← J x for a complex structure J of the operator (Jᵀ = −J, J² = −I, J commuting
    /// with the operator and the projection), when the operator is the realification of a
    /// Hermitian one: every eigenvalue is then double, with eigenvectors x and J x, and
    /// [`Operator::rank`] counts each such pair once. Returns `false` (the default) when
    /// there is none, leaving x alone.
    fn partner(&self, _x: &mut [f64]) -> bool {
        false
    }
}

impl Operator for SymmetricFactorization {
    fn dim(&self) -> usize {
        self.n()
    }
    fn apply(&self, x: &mut [f64]) -> Result<(), FactorError> {
        self.solve_in_place(x)
    }
}

/// The shift-invert operator of a matrix restricted and bordered as a stability block is
/// (docs/theory.md §8.8): `factorization` holds the bordered matrix
///
/// ```text
///     M_σ = [[A − σI, U], [Uᵀ, E]]      (A: m × m, U: m × b, E: b × b),
/// ```
///
/// whose border columns with E = 0 span a subspace P (orthonormal basis `constrained`) and
/// whose other border columns have an invertible E_D. With Z an orthonormal basis of P's
/// complement and S = Zᵀ (A − U_D E_D⁻¹ U_Dᵀ) Z, the first m rows of M_σ⁻¹ [y; 0] are
/// Z (S − σI)⁻¹ Zᵀ y: this operator on ℝᵐ has the eigenvalues 1/(λ − σ) of S on the
/// complement and 0 on P, so Lanczos on it finds the eigenvalues of S nearest σ, and its
/// Ritz vectors are S's eigenvectors in the coordinates of A.
pub struct Bordered<'a> {
    factorization: &'a SymmetricFactorization,
    m: usize,
    constrained: &'a [Vec<f64>],
}

impl<'a> Bordered<'a> {
    /// The operator of the leading m × m block of `factorization`'s inverse, on the
    /// complement of the orthonormal columns `constrained` (each of length m).
    pub fn new(
        factorization: &'a SymmetricFactorization,
        m: usize,
        constrained: &'a [Vec<f64>],
    ) -> Self {
        debug_assert!(m <= factorization.n());
        debug_assert!(constrained.iter().all(|c| c.len() == m));
        Self {
            factorization,
            m,
            constrained,
        }
    }
}

impl Operator for Bordered<'_> {
    fn dim(&self) -> usize {
        self.m
    }
    fn rank(&self) -> usize {
        self.m.saturating_sub(self.constrained.len())
    }
    fn apply(&self, x: &mut [f64]) -> Result<(), FactorError> {
        let mut w = vec![0.0; self.factorization.n()];
        w[..self.m].copy_from_slice(x);
        self.factorization.solve_in_place(&mut w)?;
        x.copy_from_slice(&w[..self.m]);
        self.project(x);
        Ok(())
    }
    fn project(&self, x: &mut [f64]) {
        // Twice, as the Lanczos vectors are orthogonalised.
        for _ in 0..2 {
            for c in self.constrained {
                let d: f64 = c.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
                x.iter_mut().zip(c).for_each(|(xi, ci)| *xi -= d * ci);
            }
        }
    }
}

/// Eigenpairs nearest a shift.
#[derive(Debug, Clone, PartialEq)]
pub struct Pairs {
    /// At most the number asked for, ascending.
    pub values: Vec<f64>,
    /// How many of them converged (all of them unless the space was exhausted first).
    pub converged: usize,
    /// Unit eigenvectors (Ritz vectors), one per value, when asked for.
    pub vectors: Vec<Vec<f64>>,
    /// Whether the Krylov space became the whole subspace (every eigenvalue found).
    pub exhausted: bool,
}

/// The (at most) `n` eigenpairs of the operator's matrix nearest `shift`, ascending: Lanczos
/// on `op` = (A − shift·I)⁻¹ with full reorthogonalisation, restarted from a fresh direction
/// on breakdown (see the [module documentation](self)); with `vectors`, the Ritz vectors too.
/// `attempt` varies the start vector (0 is the default one).
///
/// With a complex structure J ([`Operator::partner`]) every new Lanczos vector (and every
/// fresh direction) is also orthogonalised against the partners J v_i of the earlier ones:
/// the Krylov space V then stays orthogonal to J V (as it is in exact arithmetic, vᵀ J w
/// vanishing for any two Krylov vectors of one start because J times a power of the operator
/// is antisymmetric), so the iteration is complex Lanczos on the Hermitian operator and
/// finds each double eigenvalue once.
pub fn nearest_eigenpairs(
    op: &dyn Operator,
    shift: f64,
    n: usize,
    vectors: bool,
    attempt: u64,
) -> Result<Pairs, EigenError> {
    let dim = op.dim();
    let rank = op.rank().min(dim);
    let k = n.min(rank);
    if k == 0 {
        return Ok(Pairs {
            values: Vec::new(),
            converged: 0,
            vectors: Vec::new(),
            exhausted: rank == 0,
        });
    }
    let mut rng = SEED ^ attempt.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut target = (3 * k).max(START_SPACE).min(rank);
    // Columns 0..=m: the Lanczos vectors and the next one; with a complex structure, their
    // partners J v_i.
    let paired = op.partner(&mut vec![0.0; dim]);
    let mut v = faer::Mat::<f64>::zeros(dim, target + 1);
    let mut jv = faer::Mat::<f64>::zeros(if paired { dim } else { 0 }, target + 1);
    let set_partner = |jv: &mut faer::Mat<f64>, j: usize, x: faer::ColRef<'_, f64>| {
        if paired {
            let mut y: Vec<f64> = x.iter().copied().collect();
            op.partner(&mut y);
            jv.col_mut(j).iter_mut().zip(&y).for_each(|(a, b)| *a = *b);
        }
    };
    let start =
        fresh_direction(op, v.as_ref(), jv.as_ref(), 0, &mut rng).ok_or(EigenError::StartVector)?;
    v.col_mut(0).copy_from(&start);
    set_partner(&mut jv, 0, v.col(0));
    let (mut alpha, mut beta): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut exhausted = false;
    let mut largest = 0.0f64;
    let mut w = vec![0.0; dim];
    loop {
        if v.ncols() < target + 1 {
            v.resize_with(dim, target + 1, |_, _| 0.0);
            jv.resize_with(jv.nrows(), target + 1, |_, _| 0.0);
        }
        while alpha.len() < target && !exhausted {
            let j = alpha.len();
            for (wi, vi) in w.iter_mut().zip(v.col(j).iter()) {
                *wi = *vi;
            }
            op.apply(&mut w).map_err(EigenError::Solve)?;
            let mut wc = faer::ColMut::from_slice_mut(&mut w);
            let a = v.col(j).transpose() * wc.as_ref();
            alpha.push(a);
            largest = largest.max(a.abs());
            orthogonalise_paired(v.as_ref(), jv.as_ref(), j + 1, wc.as_mut());
            let b = wc.norm_l2();
            if b > BREAKDOWN_TOLERANCE * largest && j + 1 < rank {
                wc /= faer::Scale(b);
                beta.push(b);
                v.col_mut(j + 1).copy_from(wc.as_ref());
            } else {
                beta.push(0.0);
                match (j + 1 < rank)
                    .then(|| fresh_direction(op, v.as_ref(), jv.as_ref(), j + 1, &mut rng))
                    .flatten()
                {
                    Some(r) => v.col_mut(j + 1).copy_from(&r),
                    None => exhausted = true,
                }
            }
            if !exhausted {
                set_partner(&mut jv, j + 1, v.col(j + 1));
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
            .map_err(|e| EigenError::Tridiagonal(format!("{e:?}")))?;
        let (theta, s) = (eig.S(), eig.U());
        let trailing = beta[m - 1];
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&x, &y| theta[y].abs().total_cmp(&theta[x].abs()));
        order.truncate(k);
        // Each Ritz value against its own size: the eigenvalue nearest the shift (largest θ)
        // does not let the others pass unconverged.
        let converged = order
            .iter()
            .filter(|&&i| (trailing * s[(m - 1, i)]).abs() <= RESIDUAL_TOLERANCE * theta[i].abs())
            .count();
        if converged == order.len() || exhausted || m >= rank {
            order.sort_by(|&x, &y| (shift + 1.0 / theta[x]).total_cmp(&(shift + 1.0 / theta[y])));
            let values = order.iter().map(|&i| shift + 1.0 / theta[i]).collect();
            let vectors = if vectors {
                let basis = v.subcols(0, m);
                order
                    .iter()
                    .map(|&i| {
                        let x = basis * s.col(i);
                        let norm = x.norm_l2().max(1e-300);
                        x.iter().map(|xi| xi / norm).collect()
                    })
                    .collect()
            } else {
                Vec::new()
            };
            return Ok(Pairs {
                values,
                converged,
                vectors,
                exhausted: exhausted || m >= rank,
            });
        }
        target = (target + k.max(30)).min(rank);
    }
}

/// A family of shifted matrices A − σI (restricted and bordered as the operator is) that can
/// be factorised at any shift, with the inertia of each factorisation: what
/// [`lowest_eigenpairs`] needs.
pub trait ShiftFamily: Operator {
    /// Factorises at `shift` and returns the number of eigenvalues below it (Sylvester's law
    /// of inertia on the factorisation); [`Operator::apply`] then solves at that shift.
    fn factor(&mut self, shift: f64) -> Result<usize, EigenError>;
}

/// The lowest eigenpairs of a [`ShiftFamily`], certified by inertia.
#[derive(Debug, Clone, PartialEq)]
pub struct Lowest {
    /// The lowest eigenvalues λ_0 ≤ λ_1 ≤ …, as many as asked (fewer only if the space is
    /// smaller).
    pub values: Vec<f64>,
    /// Unit eigenvectors, one per value, when asked for.
    pub vectors: Vec<Vec<f64>>,
    /// The shift the Lanczos iteration ran at.
    pub shift: f64,
    /// The number of eigenvalues below that shift, from the inertia of its factorisation.
    pub below_shift: usize,
    /// The shift above the last value at which the inertia was checked (`None` when every
    /// eigenvalue of the space was found, so no check was needed) and its count, which
    /// equals `values.len()`.
    pub checked_at: Option<f64>,
}

/// Attempts of [`lowest_eigenpairs`] before it gives up.
const LOWEST_ATTEMPTS: usize = 8;

/// The `n` lowest eigenvalues (and, with `vectors`, eigenvectors) of a [`ShiftFamily`], by
/// shift-invert Lanczos at a shift near them and the inertia as the count the result must
/// reproduce (docs/theory.md §8.8):
///
/// 1. factorise at σ (starting from `shift`; a singular factorisation moves σ down by
///    `step`) and read ν = #{λ < σ} from the inertia;
/// 2. Lanczos for the n + ν + 1 eigenvalues nearest σ; it must find exactly ν below σ (fewer:
///    the lowest lie further down, so σ moves below what was found and the search repeats);
/// 3. the lowest n are then the first n found, and the inertia at a shift σ′ between the
///    n-th value and the next one must count exactly n — otherwise an eigenvalue was missed
///    and the search repeats with more vectors and another start vector.
///
/// Errors when no attempt passes the checks ([`EigenError::Unverified`]).
pub fn lowest_eigenpairs(
    family: &mut dyn ShiftFamily,
    n: usize,
    shift: f64,
    step: f64,
    vectors: bool,
) -> Result<Lowest, EigenError> {
    let rank = family.rank();
    let n = n.min(rank);
    let step = step.abs().max(f64::MIN_POSITIVE);
    let mut sigma = shift;
    let mut extra = 0;
    let mut last = None;
    for attempt in 0..LOWEST_ATTEMPTS {
        let nu = match family.factor(sigma) {
            Ok(nu) => nu,
            Err(EigenError::Factor(FactorError::Singular { .. })) => {
                sigma -= step * (1 << attempt) as f64;
                continue;
            }
            Err(e) => return Err(e),
        };
        if n == 0 {
            return Ok(Lowest {
                values: Vec::new(),
                vectors: Vec::new(),
                shift: sigma,
                below_shift: nu,
                checked_at: None,
            });
        }
        let want = (n + nu + 1 + extra).min(rank);
        let pairs = nearest_eigenpairs(&*family, sigma, want, vectors, attempt as u64)?;
        let below = pairs.values.iter().filter(|&&v| v < sigma).count();
        if below < nu {
            // The ν − below missing eigenvalues lie below σ and farther from it than every
            // value found (those are the nearest): move the shift beyond that reach. (Moving
            // it only below the lowest value found would move it up when all of them lie
            // above σ, as a cluster of small positive values next to one negative does.)
            let reach = pairs
                .values
                .iter()
                .fold(step, |r, &v| r.max((v - sigma).abs()));
            sigma -= 2.0 * reach;
            last = Some((nu, below));
            continue;
        }
        if below > nu || pairs.values.len() < n {
            last = Some((nu, below));
            extra += n + 1;
            continue;
        }
        let values = pairs.values[..n].to_vec();
        let vecs = if vectors {
            pairs.vectors[..n].to_vec()
        } else {
            Vec::new()
        };
        let done = |checked_at| Lowest {
            values: values.clone(),
            vectors: vecs.clone(),
            shift: sigma,
            below_shift: nu,
            checked_at,
        };
        if pairs.exhausted && pairs.values.len() >= rank {
            return Ok(done(None));
        }
        // The check above the n-th value: between it and the next value found, past any
        // cluster of equal values (the count must then include the whole cluster).
        let scale = pairs.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gap = 1e-12 * scale.max(f64::MIN_POSITIVE);
        let j = (n..pairs.values.len()).find(|&j| pairs.values[j] - pairs.values[j - 1] > gap);
        let Some(j) = j else {
            extra += n + 1;
            last = Some((n, pairs.values.len()));
            continue;
        };
        let top = 0.5 * (pairs.values[j - 1] + pairs.values[j]);
        match family.factor(top) {
            Ok(count) if count == j => return Ok(done(Some(top))),
            Ok(count) => {
                last = Some((count, j));
                extra += n + 1;
            }
            Err(EigenError::Factor(FactorError::Singular { .. })) => extra += 1,
            Err(e) => return Err(e),
        }
    }
    let (counted, found) = last.unwrap_or((0, 0));
    Err(EigenError::Unverified {
        attempts: LOWEST_ATTEMPTS,
        counted,
        found,
    })
}

/// As [`nearest_eigenvalues`], by faer's `partial_self_adjoint_eigen` (thick-restart Lanczos)
/// on (A − shift·I)⁻¹, with a Krylov space of 2n to 4n vectors (at least 32 to 64), tolerance
/// 1e-12 and up to 1000 restarts; only the values faer reports converged are returned. A
/// must have more unknowns than that space ([`EigenError::TooSmall`] otherwise: faer would
/// panic).
///
/// faer's iteration can loop forever in its reorthogonalisation when the Krylov space is
/// exhausted (a single start vector of a symmetric A with repeated eigenvalues): use
/// [`nearest_eigenvalues`] unless the matrix is known to be free of that.
pub fn nearest_eigenvalues_faer(
    f: &SymmetricFactorization,
    shift: f64,
    n: usize,
) -> Result<Nearest, EigenError> {
    let dim = f.n();
    let n = n.min(dim);
    if n == 0 {
        return Ok(Nearest {
            values: Vec::new(),
            converged: 0,
        });
    }
    let krylov = (4 * n).max(64);
    if dim <= krylov {
        return Err(EigenError::TooSmall { dim, krylov });
    }
    // The operator cannot report a failed solve to faer: check once that solves work (a
    // factorisation either solves every right-hand side or none).
    f.solve_in_place(&mut vec![0.0; dim])
        .map_err(EigenError::Solve)?;
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
    Ok(Nearest {
        values,
        converged: info.n_converged_eigen,
    })
}

/// The operator (A − σI)⁻¹ by a sparse `LBLᵀ` factorisation (whose solves are known to work).
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

/// `w` minus its projections on the first `j` columns of `v` and, when `jv` has rows, of
/// their partners `jv` (orthonormal together), twice.
fn orthogonalise_paired(
    v: faer::MatRef<'_, f64>,
    jv: faer::MatRef<'_, f64>,
    j: usize,
    mut w: faer::ColMut<'_, f64>,
) {
    orthogonalise(v, j, w.as_mut());
    if jv.nrows() > 0 {
        orthogonalise(jv, j, w.as_mut());
        orthogonalise(v, j, w.as_mut());
    }
}

/// A pseudo-random unit vector in the operator's subspace orthogonal to the first `j` columns
/// of `v` and of their partners `jv` (xorshift state `rng`), or `None` when they span the
/// subspace.
fn fresh_direction(
    op: &dyn Operator,
    v: faer::MatRef<'_, f64>,
    jv: faer::MatRef<'_, f64>,
    j: usize,
    rng: &mut u64,
) -> Option<faer::Col<f64>> {
    let mut x: Vec<f64> = (0..v.nrows())
        .map(|_| {
            *rng ^= *rng << 13;
            *rng ^= *rng >> 7;
            *rng ^= *rng << 17;
            (*rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect();
    op.project(&mut x);
    let mut r = faer::Col::<f64>::from_fn(x.len(), |i| x[i]);
    let before = r.norm_l2();
    orthogonalise_paired(v, jv, j, r.as_mut());
    let norm = r.norm_l2();
    if norm.is_nan() || norm <= 1e-8 * before {
        return None;
    }
    r /= faer::Scale(norm);
    Some(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sparse symmetric matrix: its pattern and values, from a function of (i, j) on the
    /// entries (i, j) of `entries` (both triangles and the diagonal added).
    fn matrix(
        n: usize,
        entries: &[(usize, usize)],
        value: impl Fn(usize, usize) -> f64,
    ) -> (SymmetricPattern, Vec<f64>) {
        let pattern = SymmetricPattern::from_entries(n, entries.iter().copied());
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut values = vec![0.0; pattern.nnz()];
        for j in 0..n {
            for p in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[p];
                values[p] = value(i.min(j), i.max(j));
            }
        }
        (pattern, values)
    }

    /// An indefinite sparse matrix of `n` unknowns: a tridiagonal band with a diagonal
    /// running from negative to positive, and a long-range coupling (i, i + 7).
    fn indefinite(n: usize) -> (SymmetricPattern, Vec<f64>) {
        let mut entries = Vec::new();
        for i in 0..n {
            if i + 1 < n {
                entries.push((i + 1, i));
            }
            if i + 7 < n {
                entries.push((i + 7, i));
            }
        }
        matrix(n, &entries, |i, j| {
            if i == j {
                0.37 * (i as f64 - 0.4 * n as f64) + 0.01 * ((i * 31) % 7) as f64
            } else if j == i + 1 {
                1.0
            } else {
                0.3
            }
        })
    }

    fn dense_eigenvalues(pattern: &SymmetricPattern, values: &[f64]) -> Vec<f64> {
        let mut v = pattern
            .to_dense(values)
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .unwrap();
        v.sort_by(f64::total_cmp);
        v
    }

    fn assert_close(found: &[f64], expected: &[f64], scale: f64, tol: f64) {
        assert_eq!(found.len(), expected.len(), "{found:?} vs {expected:?}");
        for (a, b) in found.iter().zip(expected) {
            assert!(
                (a - b).abs() <= tol * scale,
                "{a} vs {b} ({found:?} vs {expected:?})"
            );
        }
    }

    /// The eigenvalues nearest a shift inside an indefinite spectrum are the dense ones, for
    /// a Krylov space smaller than the matrix (the convergence test decides) and for one
    /// that is the whole space.
    #[test]
    fn nearest_eigenvalues_are_the_dense_ones() {
        for (dim, shift, count) in [(40, 0.1, 6), (200, 0.05, 5), (200, -3.17, 12)] {
            let (pattern, values) = indefinite(dim);
            let dense = dense_eigenvalues(&pattern, &values);
            assert!(dense[0] < 0.0 && dense[dim - 1] > 0.0, "indefinite");
            let scale = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let expected = nearest(dense.iter().copied(), shift, count);
            let found = shift_invert(&pattern, &values, shift, count).unwrap();
            assert_eq!(found.converged, count, "n = {dim}, σ = {shift}");
            assert_close(&found.values, &expected, scale, 1e-10);
            // faer's thick-restart Lanczos agrees on this matrix (simple eigenvalues), when it
            // is larger than faer's Krylov space.
            if dim <= 64 {
                continue;
            }
            let shifted = shifted_values(&pattern, &values, shift).unwrap();
            let mut f = SymmetricFactorization::new(&pattern).unwrap();
            f.factorize(&shifted).unwrap();
            let faer = nearest_eigenvalues_faer(&f, shift, count).unwrap();
            assert_eq!(faer.converged, count);
            assert_close(&faer.values, &expected, scale, 1e-10);
        }
    }

    /// Three uncoupled copies of one block: every eigenvalue is triple, which a single
    /// start vector cannot reach; the restarts on breakdown find every copy.
    #[test]
    fn repeated_eigenvalues_are_found_with_their_multiplicity() {
        let (block, copies) = (5, 3);
        let n = block * copies;
        let mut entries = Vec::new();
        for c in 0..copies {
            for i in 0..block {
                for j in 0..i {
                    entries.push((c * block + i, c * block + j));
                }
            }
        }
        let (pattern, values) = matrix(n, &entries, |i, j| {
            let (a, b) = (i % block, j % block);
            if a == b {
                a as f64 - 2.2
            } else {
                0.5 / (1.0 + a.abs_diff(b) as f64)
            }
        });
        let dense = dense_eigenvalues(&pattern, &values);
        let shift = 0.05;
        let expected = nearest(dense.iter().copied(), shift, 6);
        // Two distinct values, three copies each.
        assert!((expected[0] - expected[2]).abs() < 1e-12);
        assert!((expected[3] - expected[5]).abs() < 1e-12);
        let found = shift_invert(&pattern, &values, shift, 6).unwrap();
        assert_close(&found.values, &expected, 3.0, 1e-10);
    }

    #[test]
    fn counts_are_capped_by_the_dimension() {
        let (pattern, values) = indefinite(8);
        let dense = dense_eigenvalues(&pattern, &values);
        let found = shift_invert(&pattern, &values, 0.1, 20).unwrap();
        assert_close(&found.values, &dense, 10.0, 1e-10);
        let none = shift_invert(&pattern, &values, 0.1, 0).unwrap();
        assert!(none.values.is_empty() && none.converged == 0);
    }

    #[test]
    fn errors_name_the_cause() {
        let (pattern, values) = indefinite(10);
        assert_eq!(
            shift_invert(&pattern, &values[1..], 0.0, 3),
            Err(EigenError::Length {
                values: values.len() - 1,
                nnz: pattern.nnz()
            })
        );
        // A shift at an eigenvalue: A − σI is singular.
        let diagonal = matrix(4, &[], |i, _| i as f64).1;
        let diagonal_pattern = SymmetricPattern::from_entries(4, []);
        assert!(matches!(
            shift_invert(&diagonal_pattern, &diagonal, 2.0, 2),
            Err(EigenError::Factor(_))
        ));
        // A factorisation that was never made cannot be solved with.
        let f = SymmetricFactorization::new(&pattern).unwrap();
        assert!(matches!(
            nearest_eigenvalues(&f, 0.0, 3),
            Err(EigenError::Solve(FactorError::NotFactorized))
        ));
        let large = indefinite(100).0;
        let f = SymmetricFactorization::new(&large).unwrap();
        assert!(matches!(
            nearest_eigenvalues_faer(&f, 0.0, 3),
            Err(EigenError::Solve(FactorError::NotFactorized))
        ));
        // faer's Lanczos on a matrix no larger than its Krylov space.
        let mut f = SymmetricFactorization::new(&pattern).unwrap();
        f.factorize(&shifted_values(&pattern, &values, 0.1).unwrap())
            .unwrap();
        assert_eq!(
            nearest_eigenvalues_faer(&f, 0.1, 3),
            Err(EigenError::TooSmall {
                dim: 10,
                krylov: 64
            })
        );
    }

    /// A block as the stability analysis borders it: A (sparse, indefinite), p orthonormal
    /// constraint columns P (E = 0) and one rank-one column a with E = −1/c, factorised at
    /// any shift of A's diagonal.
    struct Family {
        values: Vec<f64>,
        diagonal: Vec<usize>,
        m: usize,
        d_negative: usize,
        constrained: Vec<Vec<f64>>,
        fact: SymmetricFactorization,
    }

    impl Family {
        /// The bordered matrix of A with `p` constraint columns and a rank-one term c a aᵀ
        /// (none for c = 0); also the dense restricted matrix Zᵀ (A + c a aᵀ) Z.
        fn new(a: (SymmetricPattern, Vec<f64>), p: usize, c: f64) -> (Self, faer::Mat<f64>) {
            let (pattern, values) = a;
            let m = pattern.n();
            let f = |i: usize, j: usize| ((i * 13 + j * 7 + 3) as f64 * 0.61).sin();
            // Orthonormal constraint columns (Gram–Schmidt).
            let mut constrained: Vec<Vec<f64>> = Vec::new();
            for j in 0..p {
                let mut v: Vec<f64> = (0..m).map(|i| f(i, j)).collect();
                for _ in 0..2 {
                    for q in &constrained {
                        let d: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
                        v.iter_mut().zip(q).for_each(|(x, y)| *x -= d * y);
                    }
                }
                let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                v.iter_mut().for_each(|x| *x /= n);
                constrained.push(v);
            }
            let a_col: Vec<f64> = (0..m).map(|i| f(i, 17) * 0.3).collect();
            // c = 0: no rank-one term.
            let nb = p + usize::from(c != 0.0);
            let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
            let entries = (0..m)
                .flat_map(|j| {
                    row_idx[col_ptr[j]..col_ptr[j + 1]]
                        .iter()
                        .map(move |&i| (i, j))
                })
                .chain((m..m + nb).flat_map(|j| (0..m + nb).map(move |i| (i, j))))
                .collect::<Vec<_>>();
            let bordered = SymmetricPattern::from_entries(m + nb, entries);
            let border = |i: usize, t: usize| {
                if t < p {
                    constrained[t][i]
                } else {
                    a_col[i]
                }
            };
            let mut mv = Vec::new();
            let mut diagonal = Vec::new();
            for j in 0..m {
                diagonal.push(mv.len() + pattern.position(j, j).unwrap() - col_ptr[j]);
                mv.extend_from_slice(&values[col_ptr[j]..col_ptr[j + 1]]);
                mv.extend((0..nb).map(|t| border(j, t)));
            }
            for t in 0..nb {
                mv.extend((0..m).map(|i| border(i, t)));
                mv.extend((0..nb).map(|t2| if t2 == t && t == p { -1.0 / c } else { 0.0 }));
            }
            assert_eq!(mv.len(), bordered.nnz());
            // The dense reference: Z spans the complement of P.
            let mut k = pattern.to_dense(&values);
            for i in 0..m {
                for j in 0..m {
                    k[(i, j)] += c * a_col[i] * a_col[j];
                }
            }
            let mut basis: Vec<Vec<f64>> = constrained.clone();
            let mut z = Vec::new();
            for e in 0..m {
                let mut v = vec![0.0; m];
                v[e] = 1.0;
                for _ in 0..2 {
                    for q in &basis {
                        let d: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
                        v.iter_mut().zip(q).for_each(|(x, y)| *x -= d * y);
                    }
                }
                let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 1e-6 {
                    v.iter_mut().for_each(|x| *x /= n);
                    basis.push(v.clone());
                    z.push(v);
                }
            }
            assert_eq!(z.len(), m - p);
            let zm = faer::Mat::<f64>::from_fn(m, m - p, |i, j| z[j][i]);
            let s = zm.transpose() * &k * &zm;
            let family = Self {
                values: mv,
                diagonal,
                m,
                d_negative: usize::from(c > 0.0),
                constrained,
                fact: SymmetricFactorization::new(&bordered).unwrap(),
            };
            (family, s)
        }
    }

    impl Operator for Family {
        fn dim(&self) -> usize {
            self.m
        }
        fn rank(&self) -> usize {
            self.m - self.constrained.len()
        }
        fn apply(&self, x: &mut [f64]) -> Result<(), FactorError> {
            Bordered::new(&self.fact, self.m, &self.constrained).apply(x)
        }
        fn project(&self, x: &mut [f64]) {
            Bordered::new(&self.fact, self.m, &self.constrained).project(x)
        }
    }

    impl ShiftFamily for Family {
        fn factor(&mut self, shift: f64) -> Result<usize, EigenError> {
            let mut v = self.values.clone();
            for &p in &self.diagonal {
                v[p] -= shift;
            }
            self.fact.factorize(&v).map_err(EigenError::Factor)?;
            let negative = self.fact.inertia().unwrap().negative;
            Ok(negative - self.constrained.len() - self.d_negative)
        }
    }

    fn sorted_dense(s: &faer::Mat<f64>) -> Vec<f64> {
        let mut v = s.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        v.sort_by(f64::total_cmp);
        v
    }

    /// The lowest eigenvalues of the restricted, bordered operator are those of the dense
    /// restricted matrix Zᵀ (A + c a aᵀ) Z, its Ritz vectors are its eigenvectors in A's
    /// coordinates (orthogonal to P), and the inertia of the bordered factorisation counts
    /// its eigenvalues below any shift.
    #[test]
    fn bordered_lowest_eigenpairs_are_those_of_the_restricted_matrix() {
        for (m, p, c, n) in [(60, 2, 0.7, 6), (150, 3, -0.4, 10), (40, 0, 1.3, 40)] {
            let (mut family, s) = Family::new(indefinite(m), p, c);
            let dense = sorted_dense(&s);
            let scale = dense.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for shift in [-0.3, 0.05, 2.1] {
                let below = dense.iter().filter(|&&v| v < shift).count();
                assert_eq!(family.factor(shift).unwrap(), below, "m = {m}, σ = {shift}");
            }
            let found = lowest_eigenpairs(&mut family, n, -1e-6 * scale, 1e-6 * scale, true)
                .unwrap_or_else(|e| panic!("m = {m}: {e}"));
            let n = n.min(m - p);
            assert_close(&found.values, &dense[..n], scale, 1e-10);
            assert_eq!(
                found.below_shift,
                dense.iter().filter(|&&v| v < found.shift).count()
            );
            // Eigenvectors: unit, orthogonal to P, and eigenvectors of the restricted matrix
            // (the residual of (A + c a aᵀ) x − λ x has no component in the complement).
            for (lambda, x) in found.values.iter().zip(&found.vectors) {
                let norm: f64 = x.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!((norm - 1.0).abs() < 1e-12);
                for q in &family.constrained {
                    let d: f64 = q.iter().zip(x).map(|(a, b)| a * b).sum();
                    assert!(d.abs() < 1e-10, "m = {m}: {d}");
                }
                // The shift-invert relation: (S − σ)⁻¹ x = x / (λ − σ) on the complement.
                family.factor(found.shift - 0.01 * scale).unwrap();
                let mut y = x.clone();
                family.apply(&mut y).unwrap();
                let theta = 1.0 / (lambda - (found.shift - 0.01 * scale));
                let r: f64 = y
                    .iter()
                    .zip(x)
                    .map(|(a, b)| (a - theta * b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(
                    r <= 1e-7 * theta.abs(),
                    "m = {m}: residual {r} of θ = {theta}"
                );
            }
            if found.values.len() < m - p {
                let top = found.checked_at.expect("checked by inertia");
                assert_eq!(
                    dense.iter().filter(|&&v| v < top).count(),
                    found.values.len()
                );
            }
        }
    }

    /// Repeated eigenvalues in one block (three uncoupled copies): the lowest are found with
    /// their multiplicity, or not at all — never a list that the inertia contradicts.
    #[test]
    fn lowest_eigenpairs_reproduce_the_inertia_with_repeated_values() {
        let (block, copies) = (7, 3);
        let n = block * copies;
        let mut entries = Vec::new();
        for c in 0..copies {
            for i in 0..block {
                for j in 0..i {
                    entries.push((c * block + i, c * block + j));
                }
            }
        }
        let a = matrix(n, &entries, |i, j| {
            let (a, b) = (i % block, j % block);
            if a == b {
                a as f64 - 2.2
            } else {
                0.5 / (1.0 + a.abs_diff(b) as f64)
            }
        });
        let (mut family, s) = Family::new(a, 0, 0.0);
        let dense = sorted_dense(&s);
        // Three copies of each value: the lowest 7 are 3 + 3 + 1.
        assert!((dense[0] - dense[2]).abs() < 1e-12 && (dense[3] - dense[5]).abs() < 1e-12);
        let found = lowest_eigenpairs(&mut family, 7, -3.0, 1e-3, false).unwrap();
        assert_close(&found.values, &dense[..7], 3.0, 1e-9);
        // The check above the 7th value includes the whole cluster it belongs to.
        let top = found.checked_at.unwrap();
        assert_eq!(dense.iter().filter(|&&v| v < top).count(), 9);
    }

    /// The lowest eigenvalue far below a cluster of small positive ones (a wrinkled membrane's
    /// soft in-plane modes next to one unstable mode): Lanczos at a shift just below zero finds
    /// the cluster first, none of it below the shift, and the search must move the shift
    /// down, beyond everything it found, until the inertia's count is reproduced.
    #[test]
    fn the_lowest_eigenvalue_is_found_beyond_a_cluster_nearer_the_shift() {
        let n = 160;
        let entries: Vec<(usize, usize)> = (1..n).map(|i| (i, i - 1)).collect();
        let a = matrix(n, &entries, |i, j| match (i == j, i) {
            (true, 0) => -0.5,
            (true, i) if i <= 60 => 1e-4 * i as f64,
            (true, i) => 1.0 + i as f64,
            (false, _) => 1e-7,
        });
        let (mut family, s) = Family::new(a, 0, 0.0);
        let dense = sorted_dense(&s);
        assert!(
            dense[0] < -0.4 && dense[1] > 0.0 && dense[1] < 1e-3,
            "{:?}",
            &dense[..3]
        );
        let found = lowest_eigenpairs(&mut family, 1, -1e-6, 1e-6, false).unwrap();
        assert_close(&found.values, &dense[..1], 1.0, 1e-9);
        assert_eq!(
            found.below_shift, 0,
            "the shift ends below the lowest value"
        );
    }

    #[test]
    fn nearest_selects_by_distance_and_sorts() {
        assert_eq!(
            nearest([5.0, -1.0, 0.2, 3.0, -0.1], 0.0, 3),
            vec![-1.0, -0.1, 0.2]
        );
        assert_eq!(nearest([1.0, 2.0], 0.0, 5), vec![1.0, 2.0]);
    }

    /// The real form R = [[A, C], [−C, A]] of a banded Hermitian H = A + i C (m × m) with
    /// J [p; q] = [−q; p]: its inertia halved, its partner map, its rank counted in pairs.
    struct Paired {
        pattern: SymmetricPattern,
        values: Vec<f64>,
        diagonal: Vec<usize>,
        fact: SymmetricFactorization,
        m: usize,
    }

    impl Paired {
        fn new(m: usize) -> (Self, Vec<f64>) {
            // H_ii, H_{i,i+1}, H_{i,i+3}: a spread of values around zero (some negative).
            let h = |i: usize, j: usize| -> (f64, f64) {
                let (a, b) = (i.min(j), i.max(j));
                let sign = if i <= j { 1.0 } else { -1.0 };
                match b - a {
                    0 => ((a as f64 * 0.37).sin() * 2.0 + 0.3, 0.0),
                    1 => (0.4 + 0.1 * (a as f64).cos(), sign * 0.3),
                    3 => (0.05, sign * (0.2 + 0.05 * (a as f64 * 1.3).sin())),
                    _ => (0.0, 0.0),
                }
            };
            let near = |i: usize, j: usize| matches!(i.abs_diff(j), 0 | 1 | 3);
            let r = |i: usize, j: usize| -> f64 {
                let (f, e) = (i % m, j % m);
                let (a, c) = h(f, e);
                match (i < m, j < m) {
                    (true, true) | (false, false) => a,
                    (true, false) => c,
                    (false, true) => -c,
                }
            };
            let entries = (0..2 * m)
                .flat_map(|j| (0..2 * m).map(move |i| (i, j)))
                .filter(|&(i, j)| near(i % m, j % m))
                .collect::<Vec<_>>();
            let pattern = SymmetricPattern::from_entries(2 * m, entries);
            let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
            let mut values = vec![0.0; pattern.nnz()];
            for j in 0..2 * m {
                for p in col_ptr[j]..col_ptr[j + 1] {
                    values[p] = r(row_idx[p], j);
                }
            }
            let diagonal = (0..2 * m)
                .map(|j| pattern.position(j, j).unwrap())
                .collect();
            // H's eigenvalues, each once: every other one of R's dense ones.
            let dense = sorted_dense(&pattern.to_dense(&values));
            for pair in dense.chunks(2) {
                assert!((pair[0] - pair[1]).abs() < 1e-12, "{pair:?} double");
            }
            let once = dense.iter().step_by(2).copied().collect();
            let fact = SymmetricFactorization::new(&pattern).unwrap();
            let paired = Self {
                pattern,
                values,
                diagonal,
                fact,
                m,
            };
            (paired, once)
        }
    }

    impl Operator for Paired {
        fn dim(&self) -> usize {
            2 * self.m
        }
        fn rank(&self) -> usize {
            self.m
        }
        fn apply(&self, x: &mut [f64]) -> Result<(), FactorError> {
            self.fact.solve_in_place(x)
        }
        fn partner(&self, x: &mut [f64]) -> bool {
            let (p, q) = x.split_at_mut(self.m);
            for (a, b) in p.iter_mut().zip(q.iter_mut()) {
                let (pa, qb) = (*a, *b);
                *a = -qb;
                *b = pa;
            }
            true
        }
    }

    impl ShiftFamily for Paired {
        fn factor(&mut self, shift: f64) -> Result<usize, EigenError> {
            let mut v = self.values.clone();
            for &p in &self.diagonal {
                v[p] -= shift;
            }
            self.fact.factorize(&v).map_err(EigenError::Factor)?;
            let negative = self.fact.inertia().unwrap().negative;
            assert_eq!(negative % 2, 0, "the real form counts in pairs");
            Ok(negative / 2)
        }
    }

    /// On the real form of a Hermitian matrix, Lanczos with partner orthogonalisation finds
    /// each double eigenvalue once (the lowest n of the Hermitian matrix, certified by the
    /// halved inertia), with unit eigenvectors x of R orthogonal to each other's partners;
    /// the whole space (rank m pairs) is exhausted after m values.
    #[test]
    fn paired_lanczos_finds_each_double_eigenvalue_once() {
        let m = 70;
        let (mut paired, once) = Paired::new(m);
        let negative = once.iter().filter(|&&v| v < 0.0).count();
        assert!(negative > 3, "{negative} negative values");
        let n = negative + 4;
        let found = lowest_eigenpairs(&mut paired, n, -1e-3, 1e-3, true).unwrap();
        assert_close(&found.values, &once[..n], 1.0, 1e-10);
        let dense = paired.pattern.to_dense(&paired.values);
        for (x, lam) in found.vectors.iter().zip(&found.values) {
            let xv = faer::Col::<f64>::from_fn(2 * m, |i| x[i]);
            let res = (&dense * &xv - &xv * faer::Scale(*lam)).norm_l2();
            assert!(res < 1e-8, "residual {res:e}");
        }
        for (i, x) in found.vectors.iter().enumerate() {
            for y in &found.vectors[..i] {
                let mut jy = y.clone();
                paired.partner(&mut jy);
                let (d, dj): (f64, f64) = (
                    x.iter().zip(y).map(|(a, b)| a * b).sum(),
                    x.iter().zip(&jy).map(|(a, b)| a * b).sum(),
                );
                assert!(d.abs() < 1e-8 && dj.abs() < 1e-8, "{d:e} {dj:e}");
            }
        }
        // Every pair once: m values exhaust the space.
        paired.factor(-10.0).unwrap();
        let all = nearest_eigenpairs(&paired, -10.0, 2 * m, false, 0).unwrap();
        assert!(all.exhausted);
        assert_close(&all.values, &once, 1.0, 1e-9);
    }
}
