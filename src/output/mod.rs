//! Writers of a run's results into an output directory.
//!
//! | file | writer | content |
//! | --- | --- | --- |
//! | `path.csv` | [`write_csv`] | a row per path point: step, arclength, parameters, measures, iterations |
//! | `path.json` | [`write_json`] | the whole [`PathReport`]: metadata, path, turning points, saved states |
//! | `path.svg` | [`write_diagram`], [`write_diagram_with`] | the path in two chosen quantities, turning points marked |
//! | `path.svg` (linear buckling) | [`write_spectrum_diagram`] | the lowest eigenvalue of every irrep block against the control, critical points marked |
//! | `curve.csv`, `curve.json`, `curve.svg` | [`write_curve`] | a critical curve: a row per point (both parameters, the measures, the block's eigenvalues, the irrep), its events, the second parameter against the control |
//! | `surface.vtu`, `surface.json`, `surface.svg` | [`write_surface`] | an equilibrium surface: its vertices at (a, b, measure) with the index, its triangles and critical lines; the report; the measure against a by index |
//! | `state_NNNN.vtu`, `path.pvd`, `events.pvd` | [`StateWriter`] | displaced meshes (base64 VTU) with the fields a [`Drawing`] gives, the ParaView collection of the path's states and that of the turning and critical states |
//! | `path.states` | [`store::write_states`] | every path point's parameters and displacement, binary (what `[start] from` reads, [`store::read_states`]) |
//! | `branch_NN/…` | [`write_branches`] | one directory per branch (`[analysis.branches]`), with the files above |
//! | `branches.json` | [`write_branch_graph`] | the graph of critical points and branches |
//! | `diagram.svg` | [`write_bifurcation_diagram`] | the path and every branch in one bifurcation diagram |
//! | `*.png` | [`write_png_beside`] | every figure again as a PNG image, rendered with the bundled font |
//! | `refine.json` | [`write_refine`] | with `--refine`: every critical and turning point on the refined meshes, with its error per level |
//!
//! [`write_run`] writes all of them for a finished run.
//!
//! [`Progress`] is the terminal progress bar (silent when quiet or when stderr is not a
//! terminal).
//!
//! Every file is written whole: into a temporary file in the target directory, flushed to
//! disk and renamed over the target, so a reader never sees half a file and a failed write
//! leaves nothing (or the previous file) behind. Nothing non-finite is ever written: the
//! writers check the report (or the state) first and return an [`OutputError`] naming the file
//! and the offending value. One writer per file: `csv.rs`, `json.rs`, `svg.rs`, `states.rs`,
//! `progress.rs`; every figure is drawn in the one style of `figure.rs` (see [`Layout`]) and
//! rendered as PNG by `png.rs`.
//!
//! [`PathReport`]: crate::results::PathReport

mod branches;
mod csv;
mod curve;
mod cusps;
mod deflation;
mod diagram;
pub(crate) mod figure;
mod json;
mod lock;
mod manifest;
mod matrix_market;
mod mode;
mod partners;
mod png;
mod progress;
mod refine;
mod reopen;
mod run;
mod scales;
mod states;
pub mod store;
mod surface;
mod svg;
mod sweep;

pub use branches::{diagram, write_branch_graph, write_branches, BranchesWritten};
pub use csv::write_csv;
pub use curve::{write_curve, write_curve_with};
pub use cusps::write_cusp_curve;
pub use deflation::write_deflation;
pub use diagram::{
    write_bifurcation_diagram, BifurcationDiagram, DiagramLine, DiagramMark, ASYMMETRY_AXIS,
};
pub use figure::{read_layout, Layout, PlacedLabel, QuantityScale, Rect};
pub use json::{write_critical, write_critical_with, write_json};
pub use lock::{LockError, RunLock, LOCK};
pub use manifest::{
    add_to_manifest, remove_manifest, sha256, sweep_temporaries, verify, verify_or_warn,
    write_manifest, Verified, MANIFEST,
};
pub use matrix_market::{
    rank_one_path, write_atomic, write_matrix_market, MatrixFiles, RANK_ONE_COEFFICIENTS_TAG,
    RANK_ONE_FILE_TAG,
};
pub use partners::write_partners;
pub use png::{render_png, write_png_beside, PNG_SCALE};
pub use progress::{fraction as progress_fraction, message as progress_message, Progress};
pub use refine::{write_refine, REFINE_JSON};
pub use reopen::{FinishedRun, ReopenError};
pub use run::{
    file_name, node_normals, write_run, write_run_with, CriticalSummary, Described, OwnFiles,
    RunSummary, TurningSummary, WriteRunError, Written, RUN_FILES,
};
pub use scales::{balloon_closed_form, Scales};
pub use states::{Drawing, PvdTime, StateWriter, EVENTS_PVD};
pub use surface::{write_surface, write_surface_with};
pub use svg::{
    caption_of, default_axes, write_diagram, write_diagram_with, write_spectrum_diagram,
    write_spectrum_diagram_with, AxisScale, Diagram, Marker, MarkerKind, ReferenceCurve, Segment,
    SPECTRUM_AXIS, ZERO_LINE,
};
pub use sweep::{figure_axis, write_sweep_table, COLLECTED_CSV, COLLECTED_RUNS_CSV, COLLECTED_SVG};

use crate::results::PathReport;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Why an output file could not be written; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output directory does not exist (or is not a directory).
    #[error("cannot write {path}: the output directory {dir} does not exist")]
    NoDirectory {
        /// The file that was to be written.
        path: PathBuf,
        /// The missing directory.
        dir: PathBuf,
    },
    /// Creating, writing, syncing or renaming the file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
    /// The path exists and is not a regular file (a directory, a device, a FIFO, a symbolic
    /// link …); it is never replaced.
    #[error("cannot write {path}: it exists and is {what}, not a regular file")]
    NotRegular {
        /// The path.
        path: PathBuf,
        /// What it is.
        what: &'static str,
    },
    /// The data cannot be written as asked: a non-finite value, an unknown axis name, a
    /// field of the wrong length, a failure of the plotting library.
    #[error("cannot write {path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the value.
        message: String,
    },
}

impl OutputError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            OutputError::NoDirectory { path, .. }
            | OutputError::Io { path, .. }
            | OutputError::NotRegular { path, .. }
            | OutputError::Invalid { path, .. } => path,
        }
    }

    fn invalid(path: &Path, message: impl Into<String>) -> Self {
        OutputError::Invalid {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    /// Converts an error of the mesh writers, which already name the file for i/o errors.
    fn from_mesh(path: &Path, e: meshes::MeshError) -> Self {
        match e {
            meshes::MeshError::Io { path, source } => OutputError::Io { path, source },
            meshes::MeshError::Target { path, what } => OutputError::NotRegular { path, what },
            other => OutputError::invalid(path, other.to_string()),
        }
    }
}

/// Fails with [`OutputError::NoDirectory`] unless the directory `path` would go into exists.
fn check_dir(path: &Path) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if dir.is_dir() {
        Ok(())
    } else {
        Err(OutputError::NoDirectory {
            path: path.to_path_buf(),
            dir: dir.to_path_buf(),
        })
    }
}

/// Writes `path` whole: `fill` writes into a temporary file in the same directory, which is
/// flushed, synced, made world-readable (0644 on Unix) and renamed over `path`. On error the
/// temporary file is removed and an existing `path` is left as it was.
fn write_whole(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), OutputError> {
    check_dir(path)?;
    meshes::write::write_whole(path, fill).map_err(|e| OutputError::from_mesh(path, e))
}

/// Opens `path` for reading when it is a regular file; a FIFO, a device or a directory is an
/// error of kind `InvalidInput` saying what it is, found from its metadata before it is opened
/// (opening a FIFO waits for a writer, and a signal does not end that wait).
pub fn open_regular(path: &Path) -> io::Result<std::fs::File> {
    if let Some(what) = crate::scene::not_regular(path) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {what}, not a regular file"),
        ));
    }
    std::fs::File::open(path)
}

/// The bytes of the regular file `path` ([`open_regular`]).
pub fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    io::Read::read_to_end(&mut open_regular(path)?, &mut bytes)?;
    Ok(bytes)
}

/// The text of the regular file `path` ([`open_regular`]).
pub fn read_regular_string(path: &Path) -> io::Result<String> {
    String::from_utf8(read_regular(path)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))
}

/// Fails with [`OutputError::NotRegular`] when `path` exists and is not a regular file: what
/// every writer refuses to replace, for commands to check before they start work.
pub fn check_target(path: &Path) -> Result<(), OutputError> {
    meshes::write::check_target(path).map_err(|e| OutputError::from_mesh(path, e))
}

/// Checks that every number of the report is finite; the error names the row (or turning
/// point, or saved state) and the column.
fn check_finite(path: &Path, report: &PathReport) -> Result<(), OutputError> {
    let bad = |what: String, name: &str, v: f64| {
        OutputError::invalid(path, format!("{what}: {name} is {v} (not finite)"))
    };
    let columns = |params: &[f64], measures: &[f64]| {
        let p = report.parameters.iter().zip(params);
        let m = report.measures.iter().zip(measures);
        p.chain(m)
            .find(|(_, v)| !v.is_finite())
            .map(|(n, v)| (n.clone(), *v))
    };
    for row in &report.rows {
        let what = || format!("path row {}", row.step);
        if !row.arclength.is_finite() {
            return Err(bad(what(), "arclength", row.arclength));
        }
        check_lengths(path, report, &what(), &row.parameters, &row.measures)?;
        if let Some((n, v)) = columns(&row.parameters, &row.measures) {
            return Err(bad(what(), &n, v));
        }
    }
    for (k, t) in report.turning_points.iter().enumerate() {
        let what = || {
            format!(
                "turning point {k} ({}, after step {})",
                t.kind, t.after_step
            )
        };
        check_lengths(path, report, &what(), &t.parameters, &t.measures)?;
        if let Some((n, v)) = columns(&t.parameters, &t.measures) {
            return Err(bad(what(), &n, v));
        }
    }
    for s in &report.saved {
        if !s.control.is_finite() {
            return Err(bad(format!("saved state {}", s.file), "control", s.control));
        }
    }
    check_spectra(path, report)
}

/// Checks the report's [`Spectra`](crate::results::Spectra): a value per irrep in every row,
/// every number finite (a lowest eigenvalue that was not computed is `None`, never NaN).
fn check_spectra(path: &Path, report: &PathReport) -> Result<(), OutputError> {
    let spectra = &report.spectra;
    let n = spectra.irreps.len();
    for row in &spectra.rows {
        let what = format!("spectra row {}", row.step);
        if row.lowest.len() != n || row.negative.len() != n {
            return Err(OutputError::invalid(
                path,
                format!(
                    "{what} has {} lowest eigenvalues and {} negative counts, the spectra name {n} irreps",
                    row.lowest.len(),
                    row.negative.len()
                ),
            ));
        }
        let bad = |name: &str, v: f64| {
            OutputError::invalid(path, format!("{what}: {name} is {v} (not finite)"))
        };
        if !row.control.is_finite() {
            return Err(bad("control", row.control));
        }
        if !row.scale.is_finite() {
            return Err(bad("scale", row.scale));
        }
        for (irrep, v) in spectra.irreps.iter().zip(&row.lowest) {
            if let Some(v) = v.filter(|v| !v.is_finite()) {
                return Err(bad(&format!("the lowest eigenvalue of {}", irrep.name), v));
            }
        }
    }
    Ok(())
}

/// A row must have one value per parameter name and one per measure name.
fn check_lengths(
    path: &Path,
    report: &PathReport,
    what: &str,
    params: &[f64],
    measures: &[f64],
) -> Result<(), OutputError> {
    if params.len() != report.parameters.len() || measures.len() != report.measures.len() {
        return Err(OutputError::invalid(
            path,
            format!(
                "{what} has {} parameters and {} measures, the report names {} and {}",
                params.len(),
                measures.len(),
                report.parameters.len(),
                report.measures.len()
            ),
        ));
    }
    Ok(())
}

/// Shortest round-trip numbers, as the mesh writers print them.
use meshes::write::Num;
