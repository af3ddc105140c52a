//! Sparse symmetric linear algebra shared by every solver.
//!
//! - [`SymmetricPattern`]: a fixed CSC pattern of a symmetric matrix (both triangles), with
//!   the values kept by the caller in a `Vec<f64>` aligned with it;
//! - [`SymmetricFactorization`]: symbolic analysis once per pattern, then a pivoted sparse
//!   `LBLᵀ` factorisation per set of values, solves and the inertia (numbers of
//!   negative / zero / positive eigenvalues).
//!
//! The factorisation runs faer's kernels sequentially ([`FactorOptions::par`] defaults to
//! [`faer::Par::Seq`]); [`set_sequential`] does the same for faer's dense routines called
//! elsewhere (eigen solvers), which was faster than rayon on the project's 2-core machines.

pub mod bordered;
pub mod bordered_block;
pub mod eigen;
pub mod hermitian;
mod ldlt;
mod sparse;

pub use ldlt::{FactorError, FactorOptions, Inertia, SymmetricFactorization};
pub use sparse::SymmetricPattern;

/// Makes faer's global parallelism sequential (`faer::set_global_parallelism(Par::Seq)`).
/// Affects every faer routine that uses the global setting; the sparse factorisation takes
/// its own [`FactorOptions::par`].
pub fn set_sequential() {
    faer::set_global_parallelism(faer::Par::Seq);
}
