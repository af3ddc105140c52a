//! The sparse symmetric factorisation: solves against dense faer, inertia against dense
//! eigenvalues (and analytic Laplacian spectra), refactorisation on a fixed pattern,
//! bordered and saddle-point systems, singular matrices, and no allocation per step.
//!
//! Run with `cargo test --release --test linalg` (faer is very slow unoptimised).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use memstab::linalg::{FactorError, Inertia, SymmetricFactorization, SymmetricPattern};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------
// Allocation counter (per thread, so parallel tests do not disturb each other).

struct CountingAlloc;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

// ---------------------------------------------------------------------------------------
// Helpers.

/// Small deterministic generator (SplitMix64) for the large matrices.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [-1, 1).
    fn sym(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// A sparse symmetric matrix: pattern + values.
struct Sym {
    pattern: SymmetricPattern,
    values: Vec<f64>,
}

impl Sym {
    /// Builds from symmetric triplets: each `(i, j, v)` with `i != j` adds `v` at both
    /// `(i, j)` and `(j, i)`; duplicates are summed.
    fn from_triplets(n: usize, triplets: &[(usize, usize, f64)]) -> Self {
        let pattern = SymmetricPattern::from_entries(n, triplets.iter().map(|&(i, j, _)| (i, j)));
        let mut values = vec![0.0; pattern.nnz()];
        for &(i, j, v) in triplets {
            values[pattern.position(i, j).unwrap()] += v;
            if i != j {
                values[pattern.position(j, i).unwrap()] += v;
            }
        }
        Self { pattern, values }
    }

    fn dense(&self) -> Mat<f64> {
        self.pattern.to_dense(&self.values)
    }

    fn shift(&mut self, sigma: f64) {
        for i in 0..self.pattern.n() {
            self.values[self.pattern.position(i, i).unwrap()] -= sigma;
        }
    }
}

/// The lower-triangle triplets of `a` (to build a bordered matrix around it).
fn lower_triplets(a: &Sym) -> Vec<(usize, usize, f64)> {
    let (col_ptr, row_idx) = (a.pattern.col_ptr(), a.pattern.row_idx());
    (0..a.pattern.n())
        .flat_map(|j| (col_ptr[j]..col_ptr[j + 1]).map(move |p| (row_idx[p], j, p)))
        .filter(|&(i, j, _)| i >= j)
        .map(|(i, j, p)| (i, j, a.values[p]))
        .collect()
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// ‖A x − b‖ / (‖A‖_max·√nnz·‖x‖ + ‖b‖): a backward-error style relative residual.
fn relative_residual(a: &Sym, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    a.pattern.matvec(&a.values, x, &mut ax);
    let r: Vec<f64> = ax.iter().zip(b).map(|(p, q)| p - q).collect();
    let a_norm =
        a.values.iter().fold(0.0f64, |m, v| m.max(v.abs())) * (a.values.len() as f64).sqrt();
    norm(&r) / (a_norm * norm(x) + norm(b))
}

fn dense_inertia(a: &Mat<f64>, tol: f64) -> Inertia {
    let eig = a.self_adjoint_eigenvalues(Side::Lower).unwrap();
    let mut inertia = Inertia::default();
    for l in eig {
        if l.abs() <= tol {
            inertia.zero += 1;
        } else if l < 0.0 {
            inertia.negative += 1;
        } else {
            inertia.positive += 1;
        }
    }
    inertia
}

/// Smallest |eigenvalue| and largest |eigenvalue| of a dense symmetric matrix.
fn dense_extreme_eigs(a: &Mat<f64>) -> (f64, f64) {
    let eig = a.self_adjoint_eigenvalues(Side::Lower).unwrap();
    let min = eig.iter().fold(f64::INFINITY, |m, l| m.min(l.abs()));
    let max = eig.iter().fold(0.0f64, |m, l| m.max(l.abs()));
    (min, max)
}

/// An FE-like matrix on a structured triangulation of an `m × m` grid of nodes with `dofs`
/// unknowns per node: every triangle adds a random symmetric positive semi-definite element
/// matrix `G Gᵀ` (`G` random of size `k × (k − 1)`, `k = 3·dofs`: rank-deficient like a
/// real element), plus a small diagonal so the sum is positive definite. Tests make it
/// indefinite with [`Sym::shift`].
fn fe_like(m: usize, dofs: usize, rng: &mut Rng) -> Sym {
    let node = |i: usize, j: usize| i * m + j;
    let n = m * m * dofs;
    let mut triplets = Vec::new();
    let k = 3 * dofs;
    for i in 0..m - 1 {
        for j in 0..m - 1 {
            let quads = [
                [node(i, j), node(i + 1, j), node(i + 1, j + 1)],
                [node(i, j), node(i + 1, j + 1), node(i, j + 1)],
            ];
            for tri in quads {
                let idx: Vec<usize> = tri
                    .iter()
                    .flat_map(|&v| (0..dofs).map(move |d| v * dofs + d))
                    .collect();
                let rank = k - 1;
                let g: Vec<f64> = (0..k * rank).map(|_| rng.sym()).collect();
                for a in 0..k {
                    for b in 0..=a {
                        let v: f64 = (0..rank).map(|r| g[a * rank + r] * g[b * rank + r]).sum();
                        triplets.push((idx[a], idx[b], v));
                    }
                }
            }
        }
    }
    for i in 0..n {
        triplets.push((i, i, 0.05));
    }
    Sym::from_triplets(n, &triplets)
}

/// 5-point (2D, `d = 2`) or 7-point (3D, `d = 3`) Dirichlet Laplacian on an `m^d` grid.
fn laplacian(m: usize, d: u32) -> Sym {
    let n = m.pow(d);
    let mut triplets = Vec::new();
    for p in 0..n {
        triplets.push((p, p, 2.0 * d as f64));
        let mut stride = 1;
        for _ in 0..d {
            if (p / stride) % m + 1 < m {
                triplets.push((p + stride, p, -1.0));
            }
            stride *= m;
        }
    }
    Sym::from_triplets(n, &triplets)
}

/// Number of eigenvalues of `laplacian(m, d)` below `sigma` (analytic spectrum:
/// `Σ_k (2 − 2 cos(i_k π / (m+1)))`).
fn laplacian_eigs_below(m: usize, d: u32, sigma: f64) -> usize {
    let lam: Vec<f64> = (1..=m)
        .map(|i| 2.0 - 2.0 * (i as f64 * std::f64::consts::PI / (m + 1) as f64).cos())
        .collect();
    let mut count = 0;
    let n = m.pow(d);
    for p in 0..n {
        let (mut q, mut sum) = (p, 0.0);
        for _ in 0..d {
            sum += lam[q % m];
            q /= m;
        }
        if sum < sigma {
            count += 1;
        }
    }
    count
}

fn rhs(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng(seed);
    (0..n).map(|_| rng.sym()).collect()
}

fn solve(f: &SymmetricFactorization, b: &[f64]) -> Vec<f64> {
    let mut x = b.to_vec();
    f.solve_in_place(&mut x).expect("solve");
    x
}

// ---------------------------------------------------------------------------------------
// The pattern.

#[test]
fn pattern_merges_duplicates_closes_symmetry_and_has_the_diagonal() {
    let p = SymmetricPattern::from_entries(4, [(1, 0), (1, 0), (0, 1), (3, 1)]);
    assert_eq!(p.n(), 4);
    // diagonal 4 + (0,1),(1,0) + (1,3),(3,1)
    assert_eq!(p.nnz(), 8);
    assert_eq!(p.col_ptr(), &[0, 2, 5, 6, 8]);
    assert_eq!(p.row_idx(), &[0, 1, 0, 1, 3, 2, 1, 3]);
    for i in 0..4 {
        assert!(p.position(i, i).is_some());
    }
    assert_eq!(p.position(3, 1), Some(4));
    assert_eq!(p.position(1, 3), Some(6));
    assert_eq!(p.position(2, 0), None);
    assert_eq!(p.position(0, 7), None);
    let view = p.as_faer(&[1.0; 8]);
    assert_eq!(view.nrows(), 4);
    assert_eq!(view.compute_nnz(), 8);
}

#[test]
fn pattern_of_cliques_is_the_pattern_of_their_pairs() {
    // Triangles of a strip with three unknowns per node, some held (u32::MAX), and a
    // repeated clique: the pattern equals that of every pair within every clique.
    const NONE: u32 = u32::MAX;
    let mut rng = Rng(11);
    let n = 40;
    let cliques: Vec<[u32; 6]> = (0..60)
        .map(|_| {
            std::array::from_fn(|_| {
                let k = (rng.next_u64() % (n as u64 + 6)) as u32;
                if k >= n as u32 {
                    NONE
                } else {
                    k
                }
            })
        })
        .chain([[0, 1, 2, NONE, 1, 0], [0, 1, 2, NONE, 1, 0]])
        .collect();
    let pairs = cliques.iter().flat_map(|c| {
        c.iter().filter(|&&i| i != NONE).flat_map(move |&i| {
            c.iter()
                .filter(|&&j| j != NONE)
                .map(move |&j| (i as usize, j as usize))
        })
    });
    let by_pairs = SymmetricPattern::from_entries(n, pairs);
    let by_cliques = SymmetricPattern::from_cliques(n, &cliques, NONE);
    assert_eq!(by_cliques.col_ptr(), by_pairs.col_ptr());
    assert_eq!(by_cliques.row_idx(), by_pairs.row_idx());
    // An index alone in no clique still has its diagonal.
    let lonely = SymmetricPattern::from_cliques(3, &[[0u32, 1]], NONE);
    assert_eq!(lonely.col_ptr(), &[0, 2, 4, 5]);
    assert_eq!(lonely.row_idx(), &[0, 1, 0, 1, 2]);
}

#[test]
fn matvec_matches_dense() {
    let mut rng = Rng(7);
    let a = fe_like(5, 2, &mut rng);
    let x = rhs(a.pattern.n(), 3);
    let mut y = vec![0.0; x.len()];
    a.pattern.matvec(&a.values, &x, &mut y);
    let d = a.dense();
    let xm = Mat::from_fn(x.len(), 1, |i, _| x[i]);
    let ym = &d * &xm;
    for (i, yi) in y.iter().enumerate() {
        assert!((yi - ym[(i, 0)]).abs() < 1e-12);
    }
}

// ---------------------------------------------------------------------------------------
// Random sparse symmetric matrices against dense faer.

/// A random graph-Laplacian-like pattern: a path (so it is connected) plus random edges,
/// random positive edge weights, diagonal = weighted degree shifted by `shift`, except the
/// diagonal entries listed in `zeros` (mod n), which are exactly zero (saddle-point-like).
fn random_matrix(
    n: usize,
    extra: &[(usize, usize)],
    weights: &[f64],
    shift: f64,
    zeros: &[usize],
) -> Sym {
    let mut triplets = Vec::new();
    let mut diag = vec![0.1; n];
    let mut add = |i: usize, j: usize, w: f64, diag: &mut Vec<f64>| {
        triplets.push((i, j, -w));
        diag[i] += w;
        diag[j] += w;
    };
    for i in 1..n {
        add(i, i - 1, weights[i % weights.len()], &mut diag);
    }
    for (k, &(i, j)) in extra.iter().enumerate() {
        let (i, j) = (i % n, j % n);
        if i != j {
            add(i, j, weights[k % weights.len()], &mut diag);
        }
    }
    for &z in zeros {
        diag[z % n] = shift;
    }
    for (i, d) in diag.into_iter().enumerate() {
        triplets.push((i, i, d - shift));
    }
    Sym::from_triplets(n, &triplets)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_indefinite_solve_and_inertia_match_dense(
        n in 1usize..60,
        extra in prop::collection::vec((0usize..1000, 0usize..1000), 0..120),
        weights in prop::collection::vec(0.1f64..10.0, 1..20),
        shift_frac in 0.0f64..1.0,
        zeros in prop::collection::vec(0usize..1000, 0..15),
        seed in any::<u64>(),
    ) {
        let probe = random_matrix(n, &extra, &weights, 0.0, &[]);
        let (_, max_eig) = dense_extreme_eigs(&probe.dense());
        let zeros = &zeros[..zeros.len().min(n / 4)];
        let a = random_matrix(n, &extra, &weights, shift_frac * max_eig, zeros);
        let dense = a.dense();
        let (min_eig, max_eig) = dense_extreme_eigs(&dense);
        prop_assume!(min_eig > 1e-6 * max_eig);

        let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
        match f.factorize(&a.values) {
            Ok(()) => {
                prop_assert_eq!(f.inertia().unwrap(), dense_inertia(&dense, 0.0));
                let b = rhs(n, seed);
                let x = solve(&f, &b);
                prop_assert!(x.iter().all(|v| v.is_finite()));
                let res = relative_residual(&a, &x, &b);
                prop_assert!(res < 1e-10, "relative residual {res:e}");
                let xd = dense.partial_piv_lu().solve(Mat::from_fn(n, 1, |i, _| b[i]));
                let err: f64 = (0..n).map(|i| (x[i] - xd[(i, 0)]).powi(2)).sum::<f64>().sqrt();
                let cond = max_eig / min_eig;
                prop_assert!(err <= 1e-11 * cond * norm(&x).max(1e-300), "error {err:e}, cond {cond:e}");
                let det_sign = if dense_inertia(&dense, 0.0).negative & 1 == 0 { 1 } else { -1 };
                prop_assert_eq!(f.determinant_sign(), Some(det_sign));
            }
            // Allowed (pivoting only within supernodes), but must not happen silently.
            Err(FactorError::Singular { .. }) | Err(FactorError::NonFinite { .. }) => {
                let mut x = vec![1.0; n];
                prop_assert!(f.solve_in_place(&mut x).is_err());
                prop_assert!(x.iter().all(|&v| v == 1.0));
            }
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }
}

/// `[[K, Cᵀ], [C, 0]]`: Lagrange multipliers with zero diagonals coupled to one to three
/// unknowns each. AMD eliminates such a multiplier before its neighbours, which defeats
/// pivoting within supernodes; the factorisation must re-order and succeed.
#[test]
fn lagrange_multipliers_with_zero_diagonal() {
    for (ncons, width, shift) in [
        (10, 1, 0.0),
        (10, 1, 1.0),
        (10, 3, 0.0),
        (40, 1, 1.0),
        (40, 2, 0.5),
    ] {
        let mut rng = Rng(ncons as u64 * 7 + width as u64);
        let mut k = fe_like(12, 3, &mut rng);
        k.shift(shift);
        let n = k.pattern.n();
        let mut t = lower_triplets(&k);
        for c in 0..ncons {
            let first = (c * 37) % (n - width);
            for w in 0..width {
                t.push((n + c, first + w, 1.0 + w as f64));
            }
            t.push((n + c, n + c, 0.0));
        }
        let a = Sym::from_triplets(n + ncons, &t);
        let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
        let case = format!("{ncons} constraints of width {width}, shift {shift}");
        f.factorize(&a.values)
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        assert_eq!(
            f.inertia().unwrap(),
            dense_inertia(&a.dense(), 0.0),
            "{case}"
        );
        let b = rhs(n + ncons, 3);
        assert!(relative_residual(&a, &solve(&f, &b), &b) < 1e-12, "{case}");
        // New values on the same pattern: no re-analysis needed, same success.
        let scaled: Vec<f64> = a.values.iter().map(|v| 2.0 * v).collect();
        f.factorize(&scaled)
            .unwrap_or_else(|e| panic!("{case}, scaled: {e}"));
    }
}

#[test]
fn fe_like_inertia_matches_dense_eigenvalues() {
    let mut rng = Rng(11);
    let a = fe_like(12, 3, &mut rng); // 432 unknowns
    let n = a.pattern.n();
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    f.factorize(&a.values).unwrap();
    assert_eq!(
        f.inertia().unwrap(),
        Inertia {
            negative: 0,
            zero: 0,
            positive: n
        }
    );

    let eig = a.dense().self_adjoint_eigenvalues(Side::Lower).unwrap();
    // Shift half-way between two well-separated eigenvalues, at several depths.
    for q in [0.1, 0.3, 0.6, 0.9] {
        let k = (q * n as f64) as usize;
        let (lo, hi) = (eig[k - 1], eig[k]);
        let mut shifted = Sym {
            pattern: a.pattern.clone(),
            values: a.values.clone(),
        };
        shifted.shift(0.5 * (lo + hi));
        f.factorize(&shifted.values).unwrap();
        assert_eq!(
            f.inertia().unwrap(),
            Inertia {
                negative: k,
                zero: 0,
                positive: n - k
            },
            "q = {q}"
        );
        let b = rhs(n, 5);
        let x = solve(&f, &b);
        assert!(relative_residual(&shifted, &x, &b) < 1e-10);
    }
    // The unshifted matrix again, on the same factorisation object.
    f.factorize(&a.values).unwrap();
    assert_eq!(f.inertia().unwrap().negative, 0);
}

#[test]
fn repeated_factorisations_on_one_pattern() {
    let mut rng = Rng(3);
    let a = fe_like(10, 2, &mut rng);
    let n = a.pattern.n();
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    let b = rhs(n, 1);
    for step in 0..6 {
        // New values on the same pattern: scale and shift deeper each step.
        let mut s = Sym {
            pattern: a.pattern.clone(),
            values: a
                .values
                .iter()
                .map(|v| v * (1.0 + 0.1 * step as f64))
                .collect(),
        };
        s.shift(0.7 * step as f64);
        let dense = s.dense();
        let (min_eig, _) = dense_extreme_eigs(&dense);
        if min_eig < 1e-8 {
            continue;
        }
        f.factorize(&s.values).unwrap();
        assert_eq!(
            f.inertia().unwrap(),
            dense_inertia(&dense, 0.0),
            "step {step}"
        );
        let x = solve(&f, &b);
        assert!(relative_residual(&s, &x, &b) < 1e-10, "step {step}");
        let expected: f64 = dense
            .self_adjoint_eigenvalues(Side::Lower)
            .unwrap()
            .iter()
            .map(|l| l.abs().ln())
            .sum();
        let got = f.log_abs_det().unwrap();
        assert!(
            (got - expected).abs() < 1e-8 * expected.abs().max(1.0),
            "{got} vs {expected}"
        );
    }
}

#[test]
fn several_right_hand_sides() {
    let mut rng = Rng(5);
    let mut a = fe_like(8, 3, &mut rng);
    a.shift(2.0);
    let n = a.pattern.n();
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    f.factorize(&a.values).unwrap();
    let k = 11; // more than one internal block of 8
    let b: Vec<f64> = rhs(n * k, 9);
    let mut x = b.clone();
    f.solve_many_in_place(&mut x).unwrap();
    for j in 0..k {
        let (xj, bj) = (&x[j * n..(j + 1) * n], &b[j * n..(j + 1) * n]);
        assert!(relative_residual(&a, xj, bj) < 1e-10, "column {j}");
        let single = solve(&f, bj);
        let diff: Vec<f64> = xj.iter().zip(&single).map(|(p, q)| p - q).collect();
        assert!(norm(&diff) <= 1e-12 * norm(&single), "column {j}");
    }
}

// ---------------------------------------------------------------------------------------
// Indefinite structures.

#[test]
fn bordered_system_with_positive_definite_block() {
    let k = laplacian(20, 2); // n = 400, SPD
    let n = k.pattern.n();
    let mut triplets = lower_triplets(&k);
    let border = rhs(n, 21);
    for (i, &v) in border.iter().enumerate() {
        triplets.push((n, i, v));
    }
    triplets.push((n, n, 0.0));
    let a = Sym::from_triplets(n + 1, &triplets);
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    f.factorize(&a.values).unwrap();
    assert_eq!(
        f.inertia().unwrap(),
        Inertia {
            negative: 1,
            zero: 0,
            positive: n
        }
    );
    assert_eq!(f.determinant_sign(), Some(-1));
    let b = rhs(n + 1, 22);
    let x = solve(&f, &b);
    assert!(relative_residual(&a, &x, &b) < 1e-12);
}

/// A shift between the `count`-th and `count+1`-th smallest eigenvalue of `laplacian(m, 2)`.
fn laplacian_eigs_sigma(m: usize, count: usize) -> f64 {
    let lam: Vec<f64> = (1..=m)
        .map(|i| 2.0 - 2.0 * (i as f64 * std::f64::consts::PI / (m + 1) as f64).cos())
        .collect();
    let mut all: Vec<f64> = lam
        .iter()
        .flat_map(|a| lam.iter().map(move |b| a + b))
        .collect();
    all.sort_by(f64::total_cmp);
    assert!(
        all[count] - all[count - 1] > 1e-8,
        "no gap after {count} eigenvalues"
    );
    0.5 * (all[count - 1] + all[count])
}

#[test]
fn bordered_indefinite_block() {
    let m = 20;
    let mut k = laplacian(m, 2);
    let sigma = laplacian_eigs_sigma(m, 6); // past a double eigenvalue
    k.shift(sigma);
    let n = k.pattern.n();
    let mut triplets = lower_triplets(&k);
    let border = rhs(n, 31);
    for (i, &v) in border.iter().enumerate() {
        triplets.push((n, i, v));
    }
    triplets.push((n, n, 0.5));
    let a = Sym::from_triplets(n + 1, &triplets);
    let dense = a.dense();
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    f.factorize(&a.values).unwrap();
    assert_eq!(f.inertia().unwrap(), dense_inertia(&dense, 0.0));
    let b = rhs(n + 1, 32);
    let x = solve(&f, &b);
    assert!(relative_residual(&a, &x, &b) < 1e-10);
}

/// Zero leading pivots, all diagonals zero: `[[0, a], [a, 0]]` blocks, alone or chained.
/// No partner with a nonzero diagonal exists, so this is the intranode Bunch–Kaufman's job
/// (each pair lands in one supernode); the brief allows a reported failure here, but it
/// does solve them, and a wrong answer would fail the inertia and residual checks.
#[test]
fn zero_leading_pivots_are_pivoted() {
    for chained in [false, true] {
        let blocks = 6;
        let n = 2 * blocks;
        let mut triplets = Vec::new();
        for b in 0..blocks {
            triplets.push((2 * b + 1, 2 * b, 1.0 + b as f64));
            triplets.push((2 * b, 2 * b, 0.0));
            triplets.push((2 * b + 1, 2 * b + 1, 0.0));
            if chained && b > 0 {
                triplets.push((2 * b, 2 * b - 1, 0.3));
            }
        }
        let a = Sym::from_triplets(n, &triplets);
        let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
        f.factorize(&a.values)
            .unwrap_or_else(|e| panic!("chained = {chained}: {e}"));
        assert_eq!(
            f.inertia().unwrap(),
            Inertia {
                negative: blocks,
                zero: 0,
                positive: blocks
            }
        );
        assert_eq!(f.inertia().unwrap(), dense_inertia(&a.dense(), 0.0));
        let b = rhs(n, 41);
        let x = solve(&f, &b);
        assert!(relative_residual(&a, &x, &b) < 1e-12, "chained = {chained}");
    }
}

#[test]
fn saddle_point_system() {
    // [[M, Bᵀ], [B, 0]] with M SPD (n × n) and B full-rank (p × n): n positive, p negative.
    let (nm, p) = (30, 6);
    let mut rng = Rng(17);
    let mut triplets = Vec::new();
    for i in 0..nm {
        triplets.push((i, i, 4.0));
        if i + 1 < nm {
            triplets.push((i + 1, i, -1.0));
        }
    }
    for c in 0..p {
        for j in 0..nm {
            if (j + c) % 3 == 0 || j == c {
                triplets.push((nm + c, j, rng.sym()));
            }
        }
        triplets.push((nm + c, nm + c, 0.0));
    }
    let a = Sym::from_triplets(nm + p, &triplets);
    let dense = a.dense();
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    f.factorize(&a.values).unwrap();
    assert_eq!(
        f.inertia().unwrap(),
        Inertia {
            negative: p,
            zero: 0,
            positive: nm
        }
    );
    assert_eq!(f.inertia().unwrap(), dense_inertia(&dense, 0.0));
    let b = rhs(nm + p, 43);
    let x = solve(&f, &b);
    assert!(relative_residual(&a, &x, &b) < 1e-12);
}

// ---------------------------------------------------------------------------------------
// Singular matrices.

#[test]
fn singular_neumann_laplacian_is_reported() {
    // Graph Laplacian of a 2D grid (rows sum to zero): one zero eigenvalue.
    let m = 30;
    let n = m * m;
    let mut triplets = Vec::new();
    let mut diag = vec![0.0; n];
    for i in 0..m {
        for j in 0..m {
            let p = i * m + j;
            for q in [(i + 1 < m).then(|| p + m), (j + 1 < m).then(|| p + 1)]
                .into_iter()
                .flatten()
            {
                triplets.push((q, p, -1.0));
                diag[p] += 1.0;
                diag[q] += 1.0;
            }
        }
    }
    triplets.extend(diag.iter().enumerate().map(|(i, &d)| (i, i, d)));
    let a = Sym::from_triplets(n, &triplets);
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    let err = f.factorize(&a.values).unwrap_err();
    assert!(matches!(err, FactorError::Singular { .. }), "{err}");
    assert_eq!(
        f.inertia(),
        Some(Inertia {
            negative: 0,
            zero: 1,
            positive: n - 1
        })
    );
    assert_eq!(f.determinant_sign(), Some(0));
    let b = rhs(n, 51);
    let mut x = b.clone();
    assert_eq!(f.solve_in_place(&mut x), Err(err));
    assert_eq!(x, b, "a refused solve leaves rhs untouched");

    // Making it nonsingular again on the same object works.
    let mut g = Sym {
        pattern: a.pattern.clone(),
        values: a.values.clone(),
    };
    g.shift(-1e-3);
    f.factorize(&g.values).unwrap();
    assert_eq!(
        f.inertia(),
        Some(Inertia {
            negative: 0,
            zero: 0,
            positive: n
        })
    );
    assert!(relative_residual(&g, &solve(&f, &b), &b) < 1e-12);
}

#[test]
fn zero_rows_and_nan_input_do_not_panic() {
    // An unconstrained unknown in the middle: its row and column are zero.
    let mut a = laplacian(10, 2);
    let n = a.pattern.n();
    let dead = 37;
    for j in 0..n {
        for p in a.pattern.col_ptr()[j]..a.pattern.col_ptr()[j + 1] {
            if j == dead || a.pattern.row_idx()[p] == dead {
                a.values[p] = 0.0;
            }
        }
    }
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    // The zero diagonal makes the factorisation re-order once (the dead unknown goes last,
    // having no partner), then the zero pivot is reported at the right unknown.
    for _ in 0..2 {
        let err = f.factorize(&a.values).unwrap_err();
        assert!(
            matches!(err, FactorError::Singular { index, .. } if index == dead),
            "{err}"
        );
        assert_eq!(
            f.inertia(),
            Some(Inertia {
                negative: 0,
                zero: 1,
                positive: n - 1
            })
        );
    }
    let mut x = vec![1.0; n];
    assert!(f.solve_in_place(&mut x).is_err());

    // A NaN value.
    let mut a = laplacian(10, 2);
    a.values[5] = f64::NAN;
    let err = f.factorize(&a.values).unwrap_err();
    assert!(matches!(err, FactorError::NonFinite { .. }), "{err}");
    assert_eq!(f.inertia(), None);
    assert!(f.solve_in_place(&mut x).is_err());
}

#[test]
fn solve_before_factorize_is_refused() {
    let a = laplacian(4, 2);
    let f = SymmetricFactorization::new(&a.pattern).unwrap();
    let mut x = vec![1.0; 16];
    assert_eq!(f.solve_in_place(&mut x), Err(FactorError::NotFactorized));
    assert_eq!(f.inertia(), None);
}

// ---------------------------------------------------------------------------------------
// Larger Laplacians: inertia against the analytic spectrum.

#[test]
fn laplacian_2d_and_3d_inertia_and_solve() {
    for (m, d) in [(60, 2), (15, 3)] {
        let base = laplacian(m, d);
        let n = base.pattern.n();
        let mut f = SymmetricFactorization::new(&base.pattern).unwrap();
        for sigma in [0.0, 0.37, 1.9, 3.3, 4.1] {
            let below = laplacian_eigs_below(m, d, sigma);
            // Keep away from (multiple) eigenvalues for a clean count.
            let near =
                laplacian_eigs_below(m, d, sigma + 1e-6) - laplacian_eigs_below(m, d, sigma - 1e-6);
            assert_eq!(near, 0, "sigma {sigma} too close to an eigenvalue");
            let mut a = Sym {
                pattern: base.pattern.clone(),
                values: base.values.clone(),
            };
            a.shift(sigma);
            f.factorize(&a.values).unwrap();
            assert_eq!(
                f.inertia().unwrap(),
                Inertia {
                    negative: below,
                    zero: 0,
                    positive: n - below
                },
                "m = {m}, d = {d}, sigma = {sigma}"
            );
            let b = rhs(n, 61);
            let x = solve(&f, &b);
            let res = relative_residual(&a, &x, &b);
            assert!(
                res < 1e-10,
                "m = {m}, d = {d}, sigma = {sigma}: residual {res:e}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// No allocation per Newton step.

#[test]
fn factorize_and_solve_do_not_allocate() {
    let mut rng = Rng(23);
    let mut a = fe_like(15, 3, &mut rng);
    a.shift(3.0);
    let n = a.pattern.n();
    let mut f = SymmetricFactorization::new(&a.pattern).unwrap();
    f.factorize(&a.values).unwrap(); // warm-up (faer may initialise lazily)
    let mut x = rhs(n, 71);
    let mut many = rhs(3 * n, 72);
    let before = allocations();
    f.factorize(&a.values).unwrap();
    f.solve_in_place(&mut x).unwrap();
    f.solve_many_in_place(&mut many).unwrap();
    let _ = f.inertia();
    assert_eq!(allocations() - before, 0);
}
