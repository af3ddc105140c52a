//! `path.csv`: the path as a table, one row per converged point.

use super::{check_finite, write_whole, Num, OutputError};
use crate::results::PathReport;
use std::path::{Path, PathBuf};

/// Writes `dir/path.csv` and returns its path.
///
/// The header is `step,arclength,<each parameter>,<each measure>,iterations,index`, when
/// the rows have their blocks' negative counts `index_<irrep>` for every irrep of
/// [`PathReport::irreps`] (names quoted as in RFC 4180 if they contain a comma, a quote or a
/// line break), and `flags`, followed by one row per [`PathRow`](crate::results::PathRow); `index` is the
/// instability index Σ d·neg at the point and `index_<irrep>` the negative count neg of that
/// irrep's block (each such eigenvalue is d-fold in K), empty where it was not computed (no
/// stability analysis, a singular block). The last column, `flags`, names the flags of the
/// row's state (`wrinkled`, `stretch`; docs/theory.md §8.10) separated by `;`, empty where the
/// state is valid or was not measured. Numbers are printed with the fewest digits that parse
/// back to the same `f64` (`1.5`, `-0`, `2.5e-7`), so the table is exact. Lines end in `\n`.
///
/// # Errors
/// [`OutputError::NoDirectory`] if `dir` does not exist, [`OutputError::Invalid`] if a value of
/// the report is not finite or a row has the wrong number of values (nothing is written),
/// [`OutputError::Io`] if the file cannot be written.
pub fn write_csv(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    let path = dir.join("path.csv");
    check_finite(&path, report)?;
    write_whole(&path, |w| {
        let names = ["step", "arclength"]
            .into_iter()
            .chain(report.parameters.iter().map(String::as_str))
            .chain(report.measures.iter().map(String::as_str))
            .chain(["iterations", "index"])
            .map(str::to_string)
            .chain(report.irreps.iter().map(|i| format!("index_{i}")))
            .chain(["flags".to_string()])
            .map(|n| quote(&n))
            .collect::<Vec<_>>();
        writeln!(w, "{}", names.join(","))?;
        for (i, row) in report.rows.iter().enumerate() {
            write!(w, "{},{}", row.step, Num(row.arclength))?;
            for &v in row.parameters.iter().chain(&row.measures) {
                write!(w, ",{}", Num(v))?;
            }
            match row.index {
                Some(i) => write!(w, ",{},{i}", row.iterations)?,
                None => write!(w, ",{},", row.iterations)?,
            }
            for k in 0..report.irreps.len() {
                match row.negative.as_ref().and_then(|n| n.get(k)) {
                    Some(n) => write!(w, ",{n}")?,
                    None => write!(w, ",")?,
                }
            }
            writeln!(w, ",{}", report.row_flags(i).join(";"))?;
        }
        Ok(())
    })?;
    Ok(path)
}

/// A header cell: as is, or in double quotes (inner quotes doubled) when it needs them.
pub(super) fn quote(name: &str) -> String {
    if name.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", name.replace('"', "\"\""))
    } else {
        name.to_string()
    }
}
