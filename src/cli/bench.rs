//! `memstab bench [--quick] [--out DIR] [--frequencies LIST]`: what accuracy costs in time;
//! `memstab bench --scaling LIST [--scaling-points N] [--out DIR]`: the scaling study.
//!
//! This command checks its flags, calls [`memstab::bench::run_accuracy`] (or
//! [`memstab::bench::run_scaling`]), which run the studies and write the files, and prints
//! the report they return. What they run:
//!
//! 1. The k = 0.1 balloon on icospheres of increasing frequency: the pressure maximum and
//!    minimum against the closed form, the wall time of each level split by phase (see
//!    [`memstab::bench`] for how the phases are timed), the observed order between levels and
//!    the Richardson-extrapolated values (order 2).
//! 2. The symmetry payoff on one tangent K (the balloon at its pressure maximum, group Ih):
//!    every eigenvalue by irrep blocks against faer's dense full eigen of K, and the lowest 20
//!    by blocks against a sparse shift-invert of K (faer Lanczos on our sparse LBLᵀ), and
//!    against scipy `eigsh` on the exported K.mtx (`scripts/peer_eigsh.py`) when python3 with
//!    scipy is available (`.venv-bench/bin/python` first, then `python3`; else skipped, said
//!    so). The same on a C8v tangent: the clamped disc sagging under fluid
//!    ([`memstab::bench::c8v_payoff`]).
//! 3. Stability along the balloon path with and without symmetry (f ≤ 16; quick f ≤ 8): at
//!    every converged point (i) the spectrum by irrep as `run` computes it against (ii) the
//!    index from the inertia of a sparse LBLᵀ of the full K + τI plus the 20 eigenvalues
//!    nearest σ by sparse shift-invert, and (iii) at the small sizes (f ≤ 8; quick f = 4) a
//!    dense eigen-decomposition of the full K ([`memstab::bench::full_path_stability`]).
//! 4. The ponding ladder on a C7v disc at two refinements against its closed form.
//! 5. Branch switching: every branch from the 5-fold Hg point of the abstract invariant
//!    potential on the icosahedron (against its closed form), and the branches of the
//!    upward-loaded C7v disc's first E1 point on the thesis mesh (quick: 8 divisions).
//!
//! Writes DIR/accuracy.md (every table, also printed), DIR/accuracy.csv (the balloon levels,
//! with the path comparison of 3.), DIR/payoff.csv (one row per payoff case), DIR/accuracy.svg
//! (error against time, log–log) and, with a peer, DIR/K.mtx.
//!
//! `--scaling` runs only the scaling study: per frequency a balloon path of `--scaling-points`
//! (20) points with the spectrum by irrep at every point, its time split by phase and its peak
//! resident memory (the high-water mark reset before each level through
//! `/proc/self/clear_refs`, then `VmHWM` of `/proc/self/status`; "n/a" where unsupported), and
//! the growth exponents of time (and memory) against unknowns fitted by least squares on
//! log–log axes. Writes DIR/scaling.md and DIR/scaling.csv.
//!
//! No timing is asserted anywhere; the figures are for BENCHMARKS.md.

use super::CliError;
use clap::Args;
use memstab::bench::{
    run_accuracy, run_curves, run_scaling, run_thesis, AccuracyOptions, BenchFiles, ScalingOptions,
    ThesisOptions,
};
use std::path::{Path, PathBuf};

/// Shown by `memstab bench --help`.
const BENCH_HELP: &str = "\
Outputs (in DIR):
  accuracy.md    every table of the bench (also printed)
  accuracy.csv   one row per balloon level: errors, observed order, Richardson values, wall
                 times by phase (s); for f <= 16 (quick: <= 8) also stability along the path
                 with and without symmetry (stab_* and index_* columns, empty elsewhere)
  payoff.csv     one row per symmetry-payoff case (the Ih balloon at its pressure maximum,
                 f = 16 / quick 8; the C8v disc under fluid, 16 / quick 8 divisions)
  accuracy.svg   relative error of the turning pressures against wall time, log-log
  K.mtx          the Ih payoff tangent, when a python with scipy runs scripts/peer_eigsh.py
With --thesis (nothing else is run):
  thesis.md      the spinning fluid-filled cap on C8v, C4v, C2v, C1v and C1 meshes of 5408
                 triangles (--quick: 512), on C1v also through its fold (3× the points),
                 and on C2v at 21632: time by phase, the critical points, the same
                 states without symmetry (full-K index per point); without --quick also
                 every scenes/thesis/*.toml as bundled: points, critical points, wall time
With --curves (nothing else is run):
  curves.md      200 points of the balloon's fold line in (p, k) at f = 16 (--quick: 8)
                 through its cusp (with the other blocks watched, and with watch = false),
                 and the C7v disc's first E1 double point followed in its
                 prestretch (16 divisions, --quick: 8): points, time of the path to the point
                 and of the curve, time per point, cusps and folds
With --branching (nothing else is run):
  branching.md   the branch-switching table of the bench alone (the abstract Hg problem; the
                 upward disc on 16 divisions, quick: 8)
With --axisym (nothing else is run):
  axisym.md      the balloon on a meridian of 64 and 200 elements (--quick: 64) with modes
                 0..20 at every point: points, wall time, time per point, turning pressures
                 against the closed form
With --scaling (nothing else is run):
  scaling.md     per frequency: a balloon path of --scaling-points points with the spectrum
                 by irrep at every point, time by phase, resident memory at the start of the
                 level and its peak (the high-water mark is reset before each level by writing
                 5 to /proc/self/clear_refs, then VmHWM is read from /proc/self/status; n/a
                 where unsupported), and growth exponents b of time ~ unknowns^b (and memory)
                 fitted by least squares on log-log axes
  scaling.csv    the same, one row per level; the fitted exponents repeated on every row";

/// Arguments of `memstab bench`.
#[derive(Debug, Args)]
#[command(after_long_help = BENCH_HELP)]
pub(crate) struct BenchArgs {
    /// Small sizes only (balloon f = 4, 8; payoff at f = 8 and on a C8v disc of 8 divisions;
    /// path comparison at f = 4, 8, dense at f = 4; ponding divisions 4, 8).
    #[arg(long, conflicts_with = "scaling")]
    quick: bool,
    /// Output directory (created if missing; its parent must exist).
    #[arg(long, default_value = "memstab-bench")]
    out: PathBuf,
    /// Balloon frequencies, comma-separated (default 4,8,16,32; quick 4,8). Stability spectra
    /// are computed at every point for f ≤ 32 only; the symmetry payoff runs when the list
    /// has 16 (quick: 8); stability without symmetry along the path for f ≤ 16 (quick: 8).
    #[arg(long, value_delimiter = ',', conflicts_with = "scaling")]
    frequencies: Vec<usize>,
    /// Scaling study instead of the bench: icosphere frequencies, comma-separated (e.g.
    /// 16,32,64,128), each a balloon path with the spectrum by irrep at every point, timed by
    /// phase, with its peak memory; writes scaling.md and scaling.csv.
    #[arg(long, value_delimiter = ',', value_name = "F1,F2,...")]
    scaling: Option<Vec<usize>>,
    /// The thesis-size study instead of the bench: the spinning fluid-filled cap on C8v, C4v,
    /// C2v, C1v and C1 meshes of 5 408 triangles (with --quick: 512) against the same states
    /// without symmetry, and on C2v at 21 632; without --quick also every bundled
    /// scenes/thesis scene, timed; writes thesis.md.
    #[arg(long, conflicts_with_all = ["scaling", "frequencies", "branching"])]
    thesis: bool,
    /// The critical-curve study instead of the bench: 200 points of the balloon's fold line
    /// in (p, k) at f = 16 (--quick: 8) through its cusp, and the C7v disc's E1 double point
    /// followed in its prestretch; writes curves.md.
    #[arg(long, conflicts_with_all = ["scaling", "frequencies", "thesis", "branching"])]
    curves: bool,
    /// Only the branch-switching study (quick: the disc on 8 divisions); writes
    /// branching.md.
    #[arg(long, conflicts_with_all = ["scaling", "frequencies"])]
    branching: bool,
    /// Only the axisymmetric study: the balloon on a meridian of 64 and 200 elements (quick:
    /// 64) with modes 0..20 at every point, timed; writes axisym.md.
    #[arg(long, conflicts_with_all = ["scaling", "frequencies", "thesis", "curves", "branching"])]
    axisym: bool,
    /// Points of each scaling path, the start included.
    #[arg(long, default_value_t = 20, requires = "scaling", value_name = "N")]
    scaling_points: usize,
}

/// Checks `--out` (its parent must exist, it must not be a file).
fn prepare_out(out: &Path) -> Result<(), CliError> {
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !parent.is_dir() {
        return Err(CliError::Input(format!(
            "--out {}: the parent directory {} does not exist",
            out.display(),
            parent.display()
        )));
    }
    if out.exists() && !out.is_dir() {
        return Err(CliError::Input(format!(
            "--out {}: is a file",
            out.display()
        )));
    }
    let dir = if out.is_dir() { out } else { parent.as_path() };
    super::common::check_writable("--out", out, dir)
}

/// A study that failed, or that a signal cut short (its path stopped early): the files
/// written so far are left.
fn failed(e: String) -> CliError {
    if e.starts_with("a signal stopped") {
        CliError::Interrupted(e)
    } else if memstab::continuation::interrupt::requested() {
        CliError::Interrupted(format!(
            "a signal stopped the bench ({e}); the files written so far are left"
        ))
    } else {
        CliError::Failure(e)
    }
}

/// Tells on stderr what the bench starts.
fn progress(message: &str) {
    eprintln!("bench: {message}");
}

/// Prints the report and the files written.
fn print(files: &BenchFiles) {
    print!("{}", files.markdown);
    out!(
        "\nwrote {}",
        files
            .files
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
}

pub(crate) fn run(args: &BenchArgs) -> Result<(), CliError> {
    if let Some(freqs) = &args.scaling {
        return scaling(args, freqs);
    }
    if args.thesis || args.curves {
        prepare_out(&args.out)?;
        let options = ThesisOptions {
            out: args.out.clone(),
            quick: args.quick,
        };
        let study = if args.curves { run_curves } else { run_thesis };
        let files = study(&options, &mut |m| progress(m)).map_err(failed)?;
        print(&files);
        return Ok(());
    }
    if args.branching || args.axisym {
        prepare_out(&args.out)?;
        let study = if args.axisym {
            memstab::bench::run_axisym
        } else {
            memstab::bench::run_branching
        };
        let files = study(&args.out, args.quick, &mut |m| progress(m)).map_err(failed)?;
        print(&files);
        return Ok(());
    }
    prepare_out(&args.out)?;
    if let Some(f) = args.frequencies.iter().find(|&&f| f == 0) {
        return Err(CliError::Input(format!(
            "--frequencies: {f} is not a frequency"
        )));
    }
    memstab::bench::check_frequencies("--frequencies", &args.frequencies)
        .map_err(CliError::Input)?;
    let options = AccuracyOptions {
        out: args.out.clone(),
        quick: args.quick,
        frequencies: args.frequencies.clone(),
    };
    let files = run_accuracy(&options, &mut |m| progress(m)).map_err(failed)?;
    print(&files);
    Ok(())
}

/// `memstab bench --scaling LIST`: the scaling study alone.
fn scaling(args: &BenchArgs, freqs: &[usize]) -> Result<(), CliError> {
    prepare_out(&args.out)?;
    if freqs.is_empty() {
        return Err(CliError::Input(
            "--scaling: no frequency given (e.g. --scaling 16,32,64,128)".into(),
        ));
    }
    if let Some(f) = freqs.iter().find(|&&f| f == 0) {
        return Err(CliError::Input(format!(
            "--scaling: {f} is not a frequency"
        )));
    }
    if args.scaling_points < 2 {
        return Err(CliError::Input(format!(
            "--scaling-points {}: a path needs at least 2 points",
            args.scaling_points
        )));
    }
    memstab::bench::check_frequencies("--scaling", freqs).map_err(CliError::Input)?;
    let options = ScalingOptions {
        out: args.out.clone(),
        frequencies: freqs.to_vec(),
        points: args.scaling_points,
    };
    let files = run_scaling(&options, &mut |m| progress(m)).map_err(failed)?;
    print(&files);
    Ok(())
}
