//! The tangent K of a model in Matrix Market format, for external solvers (`memstab
//! export-matrix`, scipy `eigsh` through `scripts/peer_eigsh.py`).
//!
//! K = S + Σ_k c_k a_k a_kᵀ: the sparse part S goes to `K.mtx`, the rank-one terms (a
//! `gas-amount` effect), when there are any, to the companion file `K.rank1.mtx`
//! ([`rank_one_path`]) that `K.mtx` names on a comment line ([`RANK_ONE_FILE_TAG`]).

use super::{write_whole, OutputError};
use crate::linalg::SymmetricPattern;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The comment line of K.mtx that names its rank-one companion file (the rest of the line is
/// the file name, relative to K.mtx's directory).
pub const RANK_ONE_FILE_TAG: &str = "rank-one file:";
/// The comment line of the companion file that lists the coefficients c_1 … c_r.
pub const RANK_ONE_COEFFICIENTS_TAG: &str = "coefficients:";

/// Writes `path` whole, as every writer of this module does: `fill` writes into a temporary
/// file in the same directory, which is flushed, synced and renamed over `path`
/// ([`OutputError::NoDirectory`] when that directory does not exist). For files written
/// outside the output module (the tables of `memstab bench`).
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), OutputError> {
    write_whole(path, fill)
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

/// What [`write_matrix_market`] wrote.
#[derive(Debug, Clone)]
pub struct MatrixFiles {
    /// Entries of the sparse part written (lower triangle of the pattern).
    pub entries: usize,
    /// The rank-one companion file and its number of terms, when K has rank-one terms.
    pub rank_one: Option<(PathBuf, usize)>,
}

/// Writes the full tangent K = S + Σ_k c_k a_k a_kᵀ for an external solver: S the values
/// `tangent` on `pattern`, the terms (c_k, a_k) `rank_one_terms`.
///
/// - `path` (e.g. `K.mtx`): the sparse part S (the values on the pattern) in
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
    pattern: &SymmetricPattern,
    tangent: &[f64],
    rank_one_terms: &[(f64, Vec<f64>)],
    comment: &str,
) -> Result<MatrixFiles, OutputError> {
    let rank_one = if rank_one_terms.is_empty() {
        None
    } else {
        let file = rank_one_path(path);
        write_rank_one(&file, path, pattern.n(), rank_one_terms, comment)?;
        Some((file, rank_one_terms.len()))
    };
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    let n = pattern.n();
    let count = (0..n)
        .map(|j| {
            (col_ptr[j]..col_ptr[j + 1])
                .filter(|&p| row_idx[p] >= j)
                .count()
        })
        .sum::<usize>();
    write_whole(path, |w| {
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
            for (&i, &v) in row_idx[range.clone()].iter().zip(&tangent[range]) {
                if i >= j {
                    writeln!(w, "{} {} {v:.17e}", i + 1, j + 1)?;
                }
            }
        }
        Ok(())
    })?;
    Ok(MatrixFiles {
        entries: count,
        rank_one,
    })
}

/// The rank-one companion file of [`write_matrix_market`].
fn write_rank_one(
    file: &Path,
    sparse: &Path,
    n: usize,
    terms: &[(f64, Vec<f64>)],
    comment: &str,
) -> Result<(), OutputError> {
    let r = terms.len();
    if let Some((_, a)) = terms.iter().find(|(_, a)| a.len() != n) {
        return Err(OutputError::invalid(
            file,
            format!("a rank-one vector has {} entries, K has {n} rows", a.len()),
        ));
    }
    let sparse_name = sparse
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_whole(file, |w| {
        writeln!(w, "%%MatrixMarket matrix array real general")?;
        writeln!(
            w,
            "% rank-one terms of K = S + sum_k c_k a_k a_k^T, S in {sparse_name}: column k is a_k"
        )?;
        write!(w, "% {RANK_ONE_COEFFICIENTS_TAG}")?;
        for (c, _) in terms {
            write!(w, " {c:.17e}")?;
        }
        writeln!(w)?;
        for line in comment.lines() {
            writeln!(w, "% {line}")?;
        }
        writeln!(w, "{n} {r}")?;
        for (_, a) in terms {
            for v in a {
                writeln!(w, "{v:.17e}")?;
            }
        }
        Ok(())
    })
}
