//! `memstab bench [--quick] [--out DIR] [--frequencies LIST]`: what accuracy costs in time.
//!
//! 1. The k = 0.1 balloon on icospheres of increasing frequency: the pressure maximum and
//!    minimum against the closed form, the wall time of each level split by phase (see
//!    [`memstab::bench`] for how the phases are timed), the observed order between levels and
//!    the Richardson-extrapolated values (order 2).
//! 2. The symmetry payoff on one tangent K (the balloon at its pressure maximum): every
//!    eigenvalue by irrep blocks against faer's dense full eigen of K, and the lowest 20 by
//!    blocks against a sparse shift-invert of K (faer Lanczos on our sparse LBLᵀ), and against
//!    scipy `eigsh` on the exported K.mtx (`scripts/peer_eigsh.py`) when python3 with scipy is
//!    available (`.venv-bench/bin/python` first, then `python3`; else skipped, said so).
//! 3. The ponding ladder on a C7v disc at two refinements against its closed form.
//!
//! Writes DIR/accuracy.md (every table, also printed), DIR/accuracy.csv (the balloon levels),
//! DIR/accuracy.svg (error against time, log–log) and, with a peer, DIR/K.mtx. No timing is
//! asserted anywhere; the figures are for BENCHMARKS.md.

use super::CliError;
use clap::Args;
use memstab::bench::{
    balloon_level, observed_order, payoff, ponding_level, richardson, write_atomic,
    write_matrix_market, BalloonLevel, Payoff, PondingLevel, P_MAX, P_MIN,
};
use memstab::model::{Model, Request};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Arguments of `memstab bench`.
#[derive(Debug, Args)]
pub(crate) struct BenchArgs {
    /// Small sizes only (balloon f = 4, 8; payoff at f = 8; ponding divisions 4, 8).
    #[arg(long)]
    quick: bool,
    /// Output directory (created if missing; its parent must exist).
    #[arg(long, default_value = "memstab-bench")]
    out: PathBuf,
    /// Balloon frequencies, comma-separated (default 4,8,16,32; quick 4,8). Stability spectra
    /// are computed at every point for f ≤ 32 only; the symmetry payoff runs when the list
    /// has 16 (quick: 8).
    #[arg(long, value_delimiter = ',')]
    frequencies: Vec<usize>,
}

fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

fn ms(d: Duration) -> String {
    format!("{:.1}", d.as_secs_f64() * 1e3)
}

fn opt_ms(d: Option<Duration>) -> String {
    d.map_or_else(|| "–".to_string(), ms)
}

pub(crate) fn run(args: &BenchArgs) -> Result<(), CliError> {
    let out = &args.out;
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
    let mut freqs = args.frequencies.clone();
    if freqs.is_empty() {
        freqs = if args.quick {
            vec![4, 8]
        } else {
            vec![4, 8, 16, 32]
        };
    }
    if let Some(f) = freqs.iter().find(|&&f| f == 0) {
        return Err(CliError::Input(format!(
            "--frequencies: {f} is not a frequency"
        )));
    }
    // The payoff runs on the level of this frequency when the list has it.
    let payoff_f = if args.quick { 8 } else { 16 };
    freqs.sort_unstable();
    freqs.dedup();
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::Failure(format!("{}: {e}", out.display())))?;
    let started = Instant::now();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# memstab bench{}\n\nmemstab {}; {} core(s) seen; faer and rayon parallelism as in `memstab run`.\n",
        if args.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );

    // 1. The balloon.
    let mut levels: Vec<BalloonLevel> = Vec::new();
    let mut payoff_result: Option<Payoff> = None;
    let mut peer: Result<PeerResult, String> = Err("not run".into());
    for &f in &freqs {
        eprintln!("bench: balloon f = {f} …");
        let (level, study) = balloon_level(f, f <= 32).map_err(|e| {
            CliError::Failure(format!("balloon f = {f}: {}", super::common::one_line(&e)))
        })?;
        if f == payoff_f {
            eprintln!("bench: symmetry payoff at f = {f} …");
            let (u, p) = &level.at_max;
            let mut po = payoff(&study, u, p, true, true, 20)
                .map_err(|e| CliError::Failure(format!("payoff at f = {f}: {e}")))?;
            po.frequency = f;
            let sigma = po.shift_invert.as_ref().map_or(0.0, |s| s.shift);
            peer = run_peer(out, &study, u, p, sigma);
            payoff_result = Some(po);
        }
        levels.push(level);
    }
    balloon_tables(&mut md, &levels);

    // 2. The payoff.
    if let Some(po) = &payoff_result {
        payoff_tables(&mut md, po, &peer);
    }

    // 3. Ponding.
    let divisions: [usize; 2] = if args.quick { [4, 8] } else { [8, 16] };
    let mut ponding = Vec::new();
    for d in divisions {
        eprintln!("bench: ponding, C7v disc with {d} divisions …");
        ponding.push(ponding_level(d).map_err(|e| {
            CliError::Failure(format!("ponding d = {d}: {}", super::common::one_line(&e)))
        })?);
    }
    ponding_table(&mut md, &ponding);
    let _ = writeln!(
        md,
        "\nTotal wall time of the bench: {:.1} s.",
        started.elapsed().as_secs_f64()
    );

    // Outputs.
    let md_path = out.join("accuracy.md");
    write_atomic(&md_path, |w| w.write_all(md.as_bytes()))
        .map_err(|e| CliError::Failure(format!("{}: {e}", md_path.display())))?;
    let csv_path = out.join("accuracy.csv");
    let csv = balloon_csv(&levels);
    write_atomic(&csv_path, |w| w.write_all(csv.as_bytes()))
        .map_err(|e| CliError::Failure(format!("{}: {e}", csv_path.display())))?;
    let svg_path = out.join("accuracy.svg");
    let svg = plot(&levels).map_err(|e| CliError::Failure(format!("accuracy.svg: {e}")))?;
    write_atomic(&svg_path, |w| w.write_all(svg.as_bytes()))
        .map_err(|e| CliError::Failure(format!("{}: {e}", svg_path.display())))?;
    print!("{md}");
    println!(
        "\nwrote {}, {}, {}",
        md_path.display(),
        csv_path.display(),
        svg_path.display()
    );
    Ok(())
}

fn balloon_tables(md: &mut String, levels: &[BalloonLevel]) {
    let _ = writeln!(
        md,
        "## Balloon (k = 0.1): accuracy against cost\n\n\
         Closed form: p_max = {P_MAX}, p_min = {P_MIN} (p R/(μH)). Relative errors of the \
         turning points found by the path follower (Ih fixed-point space), wall times in ms. \
         Phases: assembly = `model.evaluate` (path + stability); projection = restriction to \
         the fixed-point basis along the path; continuation = the path follower's dense \
         solves and step control; basis = building the adapted basis by irrep; eigen = the \
         stability spectrum by irrep at every path point without its assembly (of which \
         `restrict` is the block restrictions B_μᵀ K B_μ, estimated from three points); \
         rest = the remainder (scene, mesh, study).\n"
    );
    let _ = writeln!(
        md,
        "| f | elements | unknowns | symmetric | points | evals | p_max | err max | p_min | err min | total | assembly | projection | continuation | basis | eigen | (restrict) | rest | points/s |"
    );
    let _ = writeln!(md, "|{}", "---|".repeat(19));
    for l in levels {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {:.7} | {:.3e} | {:.7} | {:.3e} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |",
            l.frequency,
            l.elements,
            l.unknowns,
            l.symmetric_unknowns,
            l.points,
            l.evaluations,
            l.p_max,
            l.err_max(),
            l.p_min,
            l.err_min(),
            ms(l.total),
            ms(l.assembly),
            ms(l.projection),
            ms(l.continuation),
            if l.eigen.is_some() { ms(l.adapted_basis) } else { "–".into() },
            opt_ms(l.eigen),
            opt_ms(l.eigen_restrict),
            ms(l.rest()),
            l.points as f64 / secs(l.total)
        );
    }
    if levels.len() >= 2 {
        let _ = writeln!(
            md,
            "\nObserved order log2(e_f / e_2f) and Richardson extrapolation (4 p_2f − p_f)/3 \
             (order 2 assumed), with the relative error of the extrapolated value:\n"
        );
        let _ = writeln!(
            md,
            "| levels | order (max) | order (min) | Richardson p_max | its error | Richardson p_min | its error |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|");
        for w in levels.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            let doubling = b.frequency == 2 * a.frequency;
            let rmax = richardson(a.p_max, b.p_max);
            let rmin = richardson(a.p_min, b.p_min);
            let _ = writeln!(
                md,
                "| {} → {} | {:.2} | {:.2} | {} | {} | {} | {} |",
                a.frequency,
                b.frequency,
                observed_order(a.err_max(), b.err_max()) * if doubling { 1.0 } else { f64::NAN },
                observed_order(a.err_min(), b.err_min()) * if doubling { 1.0 } else { f64::NAN },
                if doubling {
                    format!("{rmax:.8}")
                } else {
                    "–".into()
                },
                if doubling {
                    format!("{:.2e}", (rmax - P_MAX).abs() / P_MAX)
                } else {
                    "–".into()
                },
                if doubling {
                    format!("{rmin:.8}")
                } else {
                    "–".into()
                },
                if doubling {
                    format!("{:.2e}", (rmin - P_MIN).abs() / P_MIN)
                } else {
                    "–".into()
                },
            );
        }
    }
}

fn balloon_csv(levels: &[BalloonLevel]) -> String {
    let mut s = String::from(
        "frequency,elements,unknowns,symmetric_unknowns,points,evaluations,p_max,err_max,p_min,err_min,total_s,assembly_s,projection_s,continuation_s,adapted_basis_s,eigen_s,eigen_restrict_s,rest_s,order_max,order_min,richardson_max,richardson_max_err,richardson_min,richardson_min_err\n",
    );
    for (i, l) in levels.iter().enumerate() {
        let prev = i.checked_sub(1).map(|j| &levels[j]);
        let pair = prev.filter(|a| l.frequency == 2 * a.frequency);
        let opt = |v: Option<f64>| v.map_or_else(String::new, |v| format!("{v:e}"));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{:e},{},{},{},{},{},{}",
            l.frequency,
            l.elements,
            l.unknowns,
            l.symmetric_unknowns,
            l.points,
            l.evaluations,
            l.p_max,
            l.err_max(),
            l.p_min,
            l.err_min(),
            secs(l.total),
            secs(l.assembly),
            secs(l.projection),
            secs(l.continuation),
            secs(l.adapted_basis),
            opt(l.eigen.map(secs)),
            opt(l.eigen_restrict.map(secs)),
            secs(l.rest()),
            opt(pair.map(|a| observed_order(a.err_max(), l.err_max()))),
            opt(pair.map(|a| observed_order(a.err_min(), l.err_min()))),
            opt(pair.map(|a| richardson(a.p_max, l.p_max))),
            opt(pair.map(|a| (richardson(a.p_max, l.p_max) - P_MAX).abs() / P_MAX)),
            opt(pair.map(|a| richardson(a.p_min, l.p_min))),
            opt(pair.map(|a| (richardson(a.p_min, l.p_min) - P_MIN).abs() / P_MIN)),
        );
    }
    s
}

/// The peer solver's result on the exported K.
struct PeerResult {
    python: String,
    seconds: f64,
    values: Vec<f64>,
    sigma: f64,
}

/// Exports K at (u, p) to DIR/K.mtx and runs scripts/peer_eigsh.py on it, if a python with
/// scipy is found.
fn run_peer(
    out: &Path,
    study: &memstab::study::Study,
    u: &[f64],
    p: &[f64],
    sigma: f64,
) -> Result<PeerResult, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = root.join("scripts/peer_eigsh.py");
    if !script.is_file() {
        return Err(format!("{} not found", script.display()));
    }
    let candidates = [
        root.join(".venv-bench/bin/python")
            .to_string_lossy()
            .into_owned(),
        "python3".to_string(),
    ];
    let python = candidates
        .iter()
        .find(|py| {
            std::process::Command::new(py)
                .args(["-c", "import scipy, numpy"])
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        })
        .ok_or("no python3 with scipy (make one: python3 -m venv .venv-bench && .venv-bench/bin/pip install scipy)")?
        .clone();
    let mut eval = study.model.new_evaluation();
    study
        .model
        .evaluate(u, p, Request::ALL, &mut eval)
        .map_err(|e| e.to_string())?;
    let mtx = out.join("K.mtx");
    write_matrix_market(
        &mtx,
        &study.model,
        &eval,
        "memstab bench: the balloon at its pressure maximum",
    )?;
    let output = std::process::Command::new(&python)
        .arg(&script)
        .arg(&mtx)
        .args([
            "--k".to_string(),
            "20".to_string(),
            format!("--sigma={sigma:e}"),
        ])
        .output()
        .map_err(|e| format!("{python}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "peer_eigsh.py failed: {}",
            super::common::one_line(&String::from_utf8_lossy(&output.stderr))
        ));
    }
    let v: serde_json::Value =
        serde_json::from_slice(&output.stdout).map_err(|e| format!("peer_eigsh.py output: {e}"))?;
    let values = v["eigenvalues"]
        .as_array()
        .ok_or("peer_eigsh.py: no eigenvalues")?
        .iter()
        .filter_map(|x| x.as_f64())
        .collect();
    Ok(PeerResult {
        python,
        seconds: v["seconds"].as_f64().unwrap_or(f64::NAN),
        values,
        sigma: v["sigma"].as_f64().unwrap_or(f64::NAN),
    })
}

/// Matches the `reference` multiset against `found` (each found value used once, within
/// 1e-8 × scale): the number of reference values left unmatched, and the largest relative
/// difference of the matched ones.
fn compare_multisets(reference: &[f64], found: &[f64], scale: f64) -> (usize, f64) {
    let scale = scale.max(1e-300);
    let mut used = vec![false; found.len()];
    let (mut missed, mut diff) = (0, 0.0f64);
    for &r in reference {
        let best = found
            .iter()
            .enumerate()
            .filter(|(i, _)| !used[*i])
            .min_by(|a, b| (a.1 - r).abs().total_cmp(&(b.1 - r).abs()));
        match best {
            Some((i, &f)) if (f - r).abs() <= 1e-8 * scale => {
                used[i] = true;
                diff = diff.max((f - r).abs() / scale);
            }
            _ => missed += 1,
        }
    }
    (missed, diff)
}

fn payoff_tables(md: &mut String, po: &Payoff, peer: &Result<PeerResult, String>) {
    let scale = po
        .by_blocks
        .iter()
        .fold(0.0f64, |m, b| m.max(b.value.abs()));
    let _ = writeln!(
        md,
        "\n## Symmetry payoff on one tangent matrix\n\n\
         The balloon of frequency {} at its pressure maximum: K of {} unknowns, group {} \
         ({} irreps; block sizes {}).\n",
        po.frequency,
        po.unknowns,
        po.group,
        po.blocks.len(),
        po.blocks
            .iter()
            .map(|(n, d, m)| format!("{n}: {m}×{d}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(md, "| what | time (ms) |\n|---|---|");
    let _ = writeln!(
        md,
        "| assembly of K (`model.evaluate`) | {} |",
        ms(po.assembly)
    );
    let _ = writeln!(
        md,
        "| adapted basis (once per mesh and group, not per matrix) | {} |",
        ms(po.adapted_basis)
    );
    let _ = writeln!(
        md,
        "| (a) restrict K to every block | {} |",
        ms(po.restrict)
    );
    let _ = writeln!(
        md,
        "| (a) dense eigenvalues of every block (faer) | {} |",
        ms(po.block_eigen)
    );
    let _ = writeln!(
        md,
        "| (a) all eigenvalues by blocks, total | {} |",
        ms(po.blocks_time())
    );
    let _ = writeln!(
        md,
        "| (a') `Stability::spectrum_of` as `run` calls it (assembly, restriction, rigid-mode \
         deflation, Zᵀ K Z, eigen) | {} |",
        ms(po.stability_spectrum)
    );
    let _ = writeln!(md, "| (b) build dense K | {} |", opt_ms(po.dense_build));
    let _ = writeln!(
        md,
        "| (b) dense full eigenvalues of K (faer `self_adjoint_eigenvalues`) | {} |",
        opt_ms(po.dense_eigen)
    );
    if let Some(si) = &po.shift_invert {
        let _ = writeln!(
            md,
            "| (d) sparse LBLᵀ of K − σI (symbolic + numeric) | {} |",
            ms(si.factorisation)
        );
        let _ = writeln!(
            md,
            "| (d) faer `partial_self_adjoint_eigen` on (K − σI)⁻¹, 20 values | {} |",
            ms(si.lanczos)
        );
    }
    if let Ok(p) = peer {
        let _ = writeln!(
            md,
            "| (e) scipy `eigsh(K, k=20, sigma={:.3e}, which='LM')` incl. its factorisation | {:.1} |",
            p.sigma,
            p.seconds * 1e3
        );
    }
    let _ = writeln!(md);
    if let (Some(de), Some(diff)) = (po.dense_eigen, po.dense_difference) {
        let _ = writeln!(
            md,
            "- (a) vs (b): all {} eigenvalues by blocks in {} ms vs dense in {} ms: **{:.1}×** \
             (counting the block restriction; {:.1}× for the block eigen-solves alone). The \
             multisets agree (block eigenvalues repeated d_μ times, rigid modes included): \
             max |Δλ| / max |λ| = {:.2e}.",
            po.unknowns,
            ms(po.blocks_time()),
            ms(de),
            secs(de) / secs(po.blocks_time()),
            secs(de) / secs(po.block_eigen),
            diff
        );
    }
    if let Some(si) = &po.shift_invert {
        let by_blocks = po.nearest(si.shift, 20);
        let (missed, diff) = compare_multisets(&by_blocks, &si.values, scale);
        let _ = writeln!(
            md,
            "- (c) vs (d): the 20 eigenvalues nearest σ = {:.3e} are by-products of (a) ({} ms, \
             every block solved densely) against {} ms for faer's sparse shift-invert \
             (**{:.2}×**). faer converged {} of 20; of the 20 values by blocks (with \
             multiplicity) {} are not among faer's (matched within 1e-8 max |λ|; matched ones \
             differ by at most {:.2e} max |λ|): a single-vector Krylov method finds \
             degenerate eigenvalues of a symmetric K only through round-off, and can return \
             fewer copies than d_μ and a value beyond the cluster instead. By blocks the \
             multiplicities are exact (d_μ).",
            si.shift,
            ms(po.blocks_time()),
            ms(si.factorisation + si.lanczos),
            secs(si.factorisation + si.lanczos) / secs(po.blocks_time()),
            si.converged,
            missed,
            diff
        );
        let lowest: Vec<String> = {
            let mut v: Vec<_> = po.by_blocks.iter().collect();
            v.sort_by(|a, b| {
                (a.value - si.shift)
                    .abs()
                    .total_cmp(&(b.value - si.shift).abs())
            });
            let mut n = 0;
            let mut out = Vec::new();
            for b in v {
                if n >= 20 {
                    break;
                }
                n += b.multiplicity;
                out.push(format!(
                    "{:.4e} ({}, ×{})",
                    b.value, b.irrep, b.multiplicity
                ));
            }
            out
        };
        let _ = writeln!(md, "- Nearest σ by blocks: {}.", lowest.join(", "));
        let _ = writeln!(
            md,
            "- Found by faer's shift-invert: {}.",
            si.values
                .iter()
                .map(|v| format!("{v:.4e}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    match peer {
        Ok(p) => {
            let by_blocks = po.nearest(p.sigma, p.values.len());
            let (missed, diff) = compare_multisets(&by_blocks, &p.values, scale);
            let _ = writeln!(
                md,
                "- (c) vs (e): scipy `eigsh` ({}) on DIR/K.mtx took {:.1} ms against {} ms by \
                 blocks: **{:.2}×**; {} of the {} values by blocks not among scipy's, matched \
                 ones differ by at most {:.2e} max |λ|.\n- Found by scipy: {}.",
                p.python,
                p.seconds * 1e3,
                ms(po.blocks_time()),
                p.seconds / secs(po.blocks_time()),
                missed,
                by_blocks.len(),
                diff,
                p.values
                    .iter()
                    .map(|v| format!("{v:.4e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        Err(why) => {
            let _ = writeln!(md, "- (e) scipy `eigsh` comparison skipped: {why}.");
        }
    }
}

fn ponding_table(md: &mut String, levels: &[PondingLevel]) {
    let _ = writeln!(
        md,
        "\n## Ponding ladder (C7v disc): critical densities against the closed form\n\n\
         γ_(m,k) = 0.3599389 j²_(m,k); each disc by `run` (density swept over [0, 20] in 60 \
         samples, crossings localised); modes identified by irrep and wave number.\n"
    );
    let _ = write!(md, "| (m, k) | irrep | exact |");
    for l in levels {
        let _ = write!(md, " d = {} | rel. error |", l.divisions);
    }
    let _ = writeln!(md, " order |");
    let _ = writeln!(md, "|{}", "---|".repeat(4 + 2 * levels.len()));
    if let Some(first) = levels.first() {
        for r in &first.rungs {
            let _ = write!(
                md,
                "| ({}, {}) | {} (×{}) | {:.6} |",
                r.mk.0, r.mk.1, r.irrep, r.multiplicity, r.exact
            );
            let mut errs = Vec::new();
            for l in levels {
                match l.rungs.iter().find(|s| s.mk == r.mk) {
                    Some(s) => {
                        let e = (s.rho - s.exact).abs() / s.exact;
                        errs.push(e);
                        let _ = write!(md, " {:.6} | {:.3e} |", s.rho, e);
                    }
                    None => {
                        errs.push(f64::NAN);
                        let _ = write!(md, " – | – |");
                    }
                }
            }
            let order = if errs.len() >= 2 {
                observed_order(errs[errs.len() - 2], errs[errs.len() - 1])
            } else {
                f64::NAN
            };
            let _ = writeln!(md, " {order:.2} |");
        }
    }
    let _ = writeln!(md);
    for l in levels {
        let _ = writeln!(
            md,
            "- d = {}: {} triangles, {} unknowns, `run` in {} ms.",
            l.divisions,
            l.elements,
            l.unknowns,
            ms(l.time)
        );
    }
}

/// Relative error against wall time, log–log, one series for the maximum and one for the
/// minimum, each point labelled with its frequency. No font files are read (SVG text).
fn plot(levels: &[BalloonLevel]) -> Result<String, Box<dyn std::error::Error>> {
    let pts = |f: fn(&BalloonLevel) -> f64| -> Vec<(f64, f64, usize)> {
        levels
            .iter()
            .map(|l| (secs(l.total).max(1e-6), f(l).max(1e-16), l.frequency))
            .collect()
    };
    let max = pts(BalloonLevel::err_max);
    let min = pts(BalloonLevel::err_min);
    let all: Vec<&(f64, f64, usize)> = max.iter().chain(&min).collect();
    let range = |v: Vec<f64>| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo / 2.0)..(hi * 2.0)
    };
    let xr = range(all.iter().map(|p| p.0).collect());
    let yr = range(all.iter().map(|p| p.1).collect());
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 560)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "balloon k = 0.1: relative error of the turning pressures vs wall time",
                ("sans-serif", 18),
            )
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(xr.log_scale(), yr.log_scale())?;
        chart
            .configure_mesh()
            .x_desc("wall time of the level (s)")
            .y_desc("relative error")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .x_label_formatter(&|v| format!("{v:.2e}"))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        let blue = RGBColor(31, 87, 180);
        let red = RGBColor(200, 30, 30);
        for (series, colour, name) in [(&max, blue, "p_max"), (&min, red, "p_min")] {
            chart
                .draw_series(LineSeries::new(
                    series.iter().map(|p| (p.0, p.1)),
                    colour.stroke_width(2),
                ))?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
            chart.draw_series(series.iter().map(|p| {
                EmptyElement::at((p.0, p.1))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(format!("f={}", p.2), (6, -14), ("sans-serif", 12))
            }))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
        root.present()?;
    }
    Ok(svg)
}
