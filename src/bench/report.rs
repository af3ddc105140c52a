//! The tables, CSV files and the plot of `memstab bench`, built from the numbers of the
//! studies: the markdown of `accuracy.md` and `scaling.md` (every table is also printed by
//! the command), `accuracy.csv`, `payoff.csv`, `scaling.csv` and `accuracy.svg`. Each
//! function returns the text; [`crate::bench::run`] writes the files.

use super::full_path::{FullPathStability, FULL_INDEX_SHIFT, SHIFT_INVERT_SHIFT};
use super::payoff::PayoffCase;
use super::ponding::PondingLevel;
use super::scaling::{ScalingFits, ScalingLevel};
use super::{observed_order, richardson, BalloonLevel};
use crate::reference::{PONDING_SCALE, P_MAX, P_MIN};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::time::Duration;

fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

fn ms(d: Duration) -> String {
    format!("{:.1}", d.as_secs_f64() * 1e3)
}

fn opt_ms(d: Option<Duration>) -> String {
    d.map_or_else(|| "–".to_string(), ms)
}

/// A CSV cell: empty for `None`.
fn opt_cell(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| format!("{v:e}"))
}

fn mib(kib: Option<u64>) -> Option<f64> {
    kib.map(|k| k as f64 / 1024.0)
}

/// The scaling study's table of `scaling.md`, with the fitted growth exponents.
pub fn scaling_table(levels: &[ScalingLevel], fits: &ScalingFits, points: usize) -> String {
    let mut text = String::new();
    let md = &mut text;
    let _ = writeln!(
        md,
        "## Scaling: balloon paths of {points} points with stability at every point\n\n\
         The k = 0.1 balloon (`scenes/balloon.toml`, frequency replaced) followed for {points} \
         converged points (start included; fewer when it reaches the stretch 4 first) in the \
         Ih fixed-point space, with the index of every irrep block at every point \
         (`Stability::analyse` with `Detail::Inertia`, as `memstab run` computes it). Wall \
         times in ms, phases as in the bench: path = assembly of the path + projection + \
         continuation; stability = adapted basis (once) + the index at every point with its \
         assembly. Memory: resident set at the start of the level and its peak during the \
         level (high-water mark reset before the level through `/proc/self/clear_refs`, then \
         `VmHWM`), MiB; memory the allocator kept from earlier levels counts in both.\n"
    );
    let _ = writeln!(
        md,
        "| f | elements | unknowns | symmetric | points | err max | err min | total | assembly | projection | continuation | basis | index by blocks | rest | path | stability | points/s | points/s per point (path + index) | RSS at start (MiB) | peak RSS (MiB) |"
    );
    let _ = writeln!(md, "|{}", "---|".repeat(20));
    let mem = |v: Option<u64>| mib(v).map_or_else(|| "n/a".to_string(), |m| format!("{m:.0}"));
    let err = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |e| format!("{e:.3e}"));
    for s in levels {
        let l = &s.level;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {} | {} | {} |",
            l.frequency,
            l.elements,
            l.unknowns,
            l.symmetric_unknowns,
            l.points,
            err(l.err_max()),
            err(l.err_min()),
            ms(l.total),
            ms(l.assembly),
            ms(l.projection),
            ms(l.continuation),
            ms(l.adapted_basis),
            opt_ms(l.index),
            ms(l.rest()),
            ms(l.path_time()),
            ms(l.stability_time()),
            l.points_per_second(),
            l.steady_points_per_second()
                .map_or_else(|| "–".to_string(), |p| format!("{p:.1}")),
            mem(s.rss_start_kib),
            mem(s.peak_kib),
        );
    }
    let show = |b: Option<f64>| {
        b.map_or_else(
            || "n/a (needs two levels of different size)".to_string(),
            |b| format!("**{b:.2}**"),
        )
    };
    let _ = writeln!(
        md,
        "\nGrowth exponents b of time ∝ unknowns^b, least squares on log–log over {} level(s):\n\n\
         - total: {}\n- path (no stability): {}\n- stability (basis + spectra): {}\n\
         - peak memory ∝ unknowns^b: {}",
        levels.len(),
        show(fits.total),
        show(fits.path),
        show(fits.stability),
        if levels.iter().any(|l| l.peak_kib.is_none()) {
            "n/a (no /proc/self/clear_refs here)".to_string()
        } else {
            show(fits.memory)
        }
    );
    text
}

/// `scaling.csv`: one row per level, the fitted exponents repeated on every row.
pub fn scaling_csv(levels: &[ScalingLevel], fits: &ScalingFits) -> String {
    let mut s = String::from(
        "frequency,elements,unknowns,symmetric_unknowns,points,err_max,err_min,total_s,assembly_s,projection_s,continuation_s,adapted_basis_s,index_s,rest_s,path_s,stability_s,points_per_s,rss_start_mib,peak_rss_mib,exponent_total,exponent_path,exponent_stability,exponent_memory\n",
    );
    for sl in levels {
        let l = &sl.level;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{},{:e},{:e},{:e},{:e},{},{},{},{},{},{}",
            l.frequency,
            l.elements,
            l.unknowns,
            l.symmetric_unknowns,
            l.points,
            opt_cell(l.err_max()),
            opt_cell(l.err_min()),
            secs(l.total),
            secs(l.assembly),
            secs(l.projection),
            secs(l.continuation),
            secs(l.adapted_basis),
            opt_cell(l.index.map(secs)),
            secs(l.rest()),
            secs(l.path_time()),
            secs(l.stability_time()),
            l.points_per_second(),
            opt_cell(mib(sl.rss_start_kib)),
            opt_cell(mib(sl.peak_kib)),
            opt_cell(fits.total),
            opt_cell(fits.path),
            opt_cell(fits.stability),
            opt_cell(fits.memory),
        );
    }
    s
}

/// A value of a level that the main bench always has (both turning points).
fn turning(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}

/// max |a_i − b_i| / s_i over the points where both values are finite.
fn max_scaled_difference(a: &[f64], b: &[f64], scales: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .zip(scales)
        .filter(|((a, b), _)| a.is_finite() && b.is_finite())
        .map(|((a, b), s)| (a - b).abs() / s)
        .fold(0.0, f64::max)
}

/// The balloon tables of `accuracy.md`: accuracy against cost per level, and (with two
/// levels or more) the observed order and Richardson extrapolation.
pub fn balloon_tables(levels: &[BalloonLevel]) -> String {
    let mut text = String::new();
    let md = &mut text;
    let _ = writeln!(
        md,
        "## Balloon (k = 0.1): accuracy against cost\n\n\
         Closed form: p_max = {P_MAX}, p_min = {P_MIN} (p R/(μH)). Relative errors of the \
         turning points found by the path follower (Ih fixed-point space), wall times in ms. \
         Phases: assembly = `model.evaluate` (path + stability); projection = restriction to \
         the fixed-point basis along the path; continuation = the path follower's dense \
         solves and step control; basis = building the adapted basis by irrep; index by \
         blocks = the negative count of every irrep block at every path point, as `memstab \
         run` computes it (`Stability::analyse` with `Detail::Inertia`: sparse LBLᵀ per \
         block, assembly around the orbit representatives included); eigen = in addition, \
         all eigenvalues of every block at every point (`spectrum_of` with \
         `BlockEigen::Dense`: a dense solve per block) without its assembly (of which `restrict` is the block \
         restrictions B_μᵀ K B_μ, estimated from three points); rest = the remainder (scene, \
         mesh, study). points/s = points / (total − eigenvalue spectra), i.e. path + index \
         at every point, what `run` pays.\n"
    );
    let _ = writeln!(
        md,
        "| f | elements | unknowns | symmetric | points | evals | p_max | err max | p_min | err min | total | assembly | projection | continuation | basis | index by blocks | eigen | (restrict) | rest | points/s | points/s per point (path + index) |"
    );
    let _ = writeln!(md, "|{}", "---|".repeat(21));
    for l in levels {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {:.7} | {:.3e} | {:.7} | {:.3e} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} | {} |",
            l.frequency,
            l.elements,
            l.unknowns,
            l.symmetric_unknowns,
            l.points,
            l.evaluations,
            turning(l.p_max),
            turning(l.err_max()),
            turning(l.p_min),
            turning(l.err_min()),
            ms(l.total),
            ms(l.assembly),
            ms(l.projection),
            ms(l.continuation),
            if l.index.is_some() { ms(l.adapted_basis) } else { "–".into() },
            opt_ms(l.index),
            opt_ms(l.eigen),
            opt_ms(l.eigen_restrict),
            ms(l.rest()),
            l.points_per_second(),
            l.steady_points_per_second()
                .map_or_else(|| "–".to_string(), |p| format!("{p:.1}"))
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
            let dash = || "–".to_string();
            let rmax = richardson(turning(a.p_max), turning(b.p_max));
            let rmin = richardson(turning(a.p_min), turning(b.p_min));
            let order = |e: fn(&BalloonLevel) -> Option<f64>| {
                if doubling {
                    format!("{:.2}", observed_order(turning(e(a)), turning(e(b))))
                } else {
                    dash()
                }
            };
            let _ = writeln!(
                md,
                "| {} → {} | {} | {} | {} | {} | {} | {} |",
                a.frequency,
                b.frequency,
                order(BalloonLevel::err_max),
                order(BalloonLevel::err_min),
                if doubling {
                    format!("{rmax:.8}")
                } else {
                    dash()
                },
                if doubling {
                    format!("{:.2e}", (rmax - P_MAX).abs() / P_MAX)
                } else {
                    dash()
                },
                if doubling {
                    format!("{rmin:.8}")
                } else {
                    dash()
                },
                if doubling {
                    format!("{:.2e}", (rmin - P_MIN).abs() / P_MIN)
                } else {
                    dash()
                },
            );
        }
    }
    text
}

/// The number of points where two index sequences differ.
fn mismatches(a: &[usize], b: &[usize]) -> usize {
    a.iter().zip(b).filter(|(x, y)| x != y).count() + a.len().abs_diff(b.len())
}

/// `accuracy.csv`: one row per balloon level, with the stability along the path without
/// symmetry of that level (`paths`, by frequency) where it ran.
pub fn balloon_csv(levels: &[BalloonLevel], paths: &[(usize, FullPathStability)]) -> String {
    let mut s = String::from(
        "frequency,elements,unknowns,symmetric_unknowns,points,evaluations,p_max,err_max,p_min,err_min,total_s,assembly_s,projection_s,continuation_s,adapted_basis_s,eigen_s,eigen_restrict_s,rest_s,order_max,order_min,richardson_max,richardson_max_err,richardson_min,richardson_min_err,\
         stab_points,stab_blocks_s,stab_full_s,stab_full_index_only_s,stab_full_inertia_s,stab_full_shift_invert_s,stab_full_over_blocks,stab_dense_s,stab_dense_over_blocks,index_max,index_mismatches,index_mismatches_dense,stab_blocks_index_s,stab_full_index_over_blocks_index,index_mismatches_blocks_pass\n",
    );
    for (i, l) in levels.iter().enumerate() {
        let prev = i.checked_sub(1).map(|j| &levels[j]);
        let pair = prev.filter(|a| l.frequency == 2 * a.frequency);
        let (pmax, pmin) = (turning(l.p_max), turning(l.p_min));
        let (emax, emin) = (turning(l.err_max()), turning(l.err_min()));
        let _ = write!(
            s,
            "{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{:e},{},{},{},{},{},{}",
            l.frequency,
            l.elements,
            l.unknowns,
            l.symmetric_unknowns,
            l.points,
            l.evaluations,
            pmax,
            emax,
            pmin,
            emin,
            secs(l.total),
            secs(l.assembly),
            secs(l.projection),
            secs(l.continuation),
            secs(l.adapted_basis),
            opt_cell(l.eigen.map(secs)),
            opt_cell(l.eigen_restrict.map(secs)),
            secs(l.rest()),
            opt_cell(pair.map(|a| observed_order(turning(a.err_max()), emax))),
            opt_cell(pair.map(|a| observed_order(turning(a.err_min()), emin))),
            opt_cell(pair.map(|a| richardson(turning(a.p_max), pmax))),
            opt_cell(pair.map(|a| (richardson(turning(a.p_max), pmax) - P_MAX).abs() / P_MAX)),
            opt_cell(pair.map(|a| richardson(turning(a.p_min), pmin))),
            opt_cell(pair.map(|a| (richardson(turning(a.p_min), pmin) - P_MIN).abs() / P_MIN)),
        );
        match paths.iter().find(|(f, _)| *f == l.frequency) {
            Some((_, full)) => {
                let blocks = secs(l.stability_time());
                let dense = full.dense.as_ref().map(|d| secs(d.build + d.eigen));
                let _ = writeln!(
                    s,
                    ",{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{:e},{:e},{}",
                    full.points,
                    blocks,
                    secs(full.total()),
                    secs(full.index_only()),
                    secs(full.inertia),
                    secs(full.shift_invert_factorisation + full.lanczos),
                    secs(full.total()) / blocks,
                    opt_cell(dense),
                    opt_cell(dense.map(|d| d / blocks)),
                    l.indices.iter().max().copied().unwrap_or(0),
                    mismatches(&l.indices, &full.indices),
                    full.dense
                        .as_ref()
                        .map_or_else(String::new, |d| mismatches(&l.indices, &d.indices)
                            .to_string()),
                    secs(full.blocks_index),
                    secs(full.index_only()) / secs(full.blocks_index),
                    mismatches(&l.indices, &full.blocks_indices),
                );
            }
            None => {
                let _ = writeln!(s, "{}", ",".repeat(15));
            }
        }
    }
    s
}

/// `payoff.csv`: one row per symmetry-payoff case.
pub fn payoff_csv(cases: &[PayoffCase]) -> String {
    let mut s = String::from(
        "case,group,unknowns,irreps,largest_block,adapted_basis_s,assembly_s,restrict_s,block_eigen_s,blocks_s,stability_spectrum_s,dense_build_s,dense_eigen_s,dense_over_blocks,dense_difference,shift_invert_s,shift_invert_over_blocks,peer_s,peer_over_blocks\n",
    );
    for c in cases {
        let po = &c.payoff;
        let blocks = secs(po.blocks_time());
        let si = po
            .shift_invert
            .as_ref()
            .map(|si| secs(si.factorisation + si.lanczos));
        let peer = c
            .peer
            .as_ref()
            .and_then(|p| p.as_ref().ok())
            .map(|p| p.seconds);
        let _ = writeln!(
            s,
            "{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{},{},{}",
            c.name,
            po.group,
            po.unknowns,
            po.blocks.len(),
            po.blocks.iter().map(|(_, _, m)| *m).max().unwrap_or(0),
            secs(po.adapted_basis),
            secs(po.assembly),
            secs(po.restrict),
            secs(po.block_eigen),
            blocks,
            secs(po.stability_spectrum),
            opt_cell(po.dense_build.map(secs)),
            opt_cell(po.dense_eigen.map(secs)),
            opt_cell(po.dense_eigen.map(|d| secs(d) / blocks)),
            opt_cell(po.dense_difference),
            opt_cell(si),
            opt_cell(si.map(|t| t / blocks)),
            opt_cell(peer),
            opt_cell(peer.map(|t| t / blocks)),
        );
    }
    s
}

/// `0 ×9, 1 ×12, 0 ×4`: an index sequence, run-length encoded.
fn runs(indices: &[usize]) -> String {
    let mut out: Vec<(usize, usize)> = Vec::new();
    for &i in indices {
        match out.last_mut() {
            Some((v, n)) if *v == i => *n += 1,
            _ => out.push((i, 1)),
        }
    }
    out.iter()
        .map(|(v, n)| format!("{v} ×{n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The table of `accuracy.md` on stability along the path with and without symmetry (empty
/// when no path was compared).
pub fn path_tables(levels: &[BalloonLevel], paths: &[(usize, FullPathStability)]) -> String {
    let mut text = String::new();
    let md = &mut text;
    if paths.is_empty() {
        return String::new();
    }
    let lowest = paths.first().map_or(20, |(_, p)| p.lowest_count);
    let _ = writeln!(
        md,
        "\n## Stability along the path, with and without symmetry\n\n\
         The balloon paths above, at every converged point: (i) by symmetry, \
         `Stability::spectrum_of` as `run` calls it (assembly, every irrep block restricted and \
         solved densely: all eigenvalues with exact multiplicities, rigid modes deflated, the \
         index Σ d_μ neg_μ), plus the adapted basis once per path; (ii) without symmetry, on \
         the full K: assembly, the index as the negative count of a sparse LBLᵀ of K + τI \
         (our `SymmetricFactorization`, its symbolic analysis once per path; τ = {FULL_INDEX_SHIFT:e} \
         max|K_ij| puts the six rigid-body zero modes of the free sphere, ≈ 1e-16 max|K_ij| \
         here, on the positive side) and the {lowest} eigenvalues nearest σ = {SHIFT_INVERT_SHIFT:e} \
         max|K_ij| by shift-invert Lanczos on a second numeric factorisation (K − σI): our \
         Lanczos with full reorthogonalisation, restarted from a fresh direction when the \
         Krylov space is exhausted (faer's `partial_self_adjoint_eigen`, used in the payoff \
         above, loops forever there: at f = 4 a single start vector reaches only the 130 \
         distinct eigenvalues of the 486-unknown K); (ii′) the index alone without \
         symmetry (symbolic analysis, assembly and the inertia factorisation of (ii): no \
         eigenvalues, no irreps); (iii) at the small sizes, every eigenvalue by a dense eigen-decomposition of K (build \
         + faer `self_adjoint_eigenvalues`), index = count below −τ max|K_ij|. Wall times in \
         ms, summed over the path.\n"
    );
    let _ = writeln!(
        md,
        "| f | unknowns | points | (i) basis (once) | (i) spectra | (i) total | (i) per point | (ii) symbolic (once) | (ii) assembly | (ii) inertia LBLᵀ | (ii) shift-invert LBLᵀ + Lanczos | (ii) total | (ii) per point | (ii) / (i) | (ii′) index only | (ii′) / (i) | (iii) dense | (iii) / (i) |"
    );
    let _ = writeln!(md, "|{}", "---|".repeat(18));
    for (f, full) in paths {
        let Some(l) = levels.iter().find(|l| l.frequency == *f) else {
            continue;
        };
        let blocks = l.stability_time();
        let spectra = l.spectra.unwrap_or_default();
        let n = full.points.max(1) as f64;
        let per_full = full.total().saturating_sub(full.symbolic);
        let dense = full.dense.as_ref().map(|d| d.build + d.eigen);
        let _ = writeln!(
            md,
            "| {f} | {} | {} | {} | {} | {} | {:.2} | {} | {} | {} | {} | {} | {:.2} | **{:.2}×** | {} | {:.2}× | {} | {} |",
            l.unknowns,
            full.points,
            ms(l.adapted_basis),
            ms(spectra),
            ms(blocks),
            secs(spectra) * 1e3 / n,
            ms(full.symbolic),
            ms(full.assembly),
            ms(full.inertia),
            ms(full.shift_invert_factorisation + full.lanczos),
            ms(full.total()),
            secs(per_full) * 1e3 / n,
            secs(full.total()) / secs(blocks),
            ms(full.index_only()),
            secs(full.index_only()) / secs(blocks),
            opt_ms(dense),
            dense.map_or_else(|| "–".into(), |d| format!("{:.1}×", secs(d) / secs(blocks))),
        );
    }
    let _ = writeln!(md);
    for (f, full) in paths {
        let Some(l) = levels.iter().find(|l| l.frequency == *f) else {
            continue;
        };
        let agree = |other: &[usize]| match mismatches(&l.indices, other) {
            0 => format!("agrees at all {} points", l.indices.len()),
            k => format!(
                "**differs at {k} of {} points** ({})",
                l.indices.len(),
                runs(other)
            ),
        };
        let clusters: Vec<usize> = {
            let mut c = full.zero_cluster.clone();
            c.sort_unstable();
            c.dedup();
            c
        };
        let lowest_diff = max_scaled_difference(&l.lowest, &full.lowest, &full.scales);
        let _ = writeln!(
            md,
            "- f = {f}: index along the path by blocks {}; without symmetry (inertia of K + τI) \
             it {}. Eigenvalues in (−τ, τ] (a second, untimed LBLᵀ of K − τI): {} at every \
             point (the model keeps {} rigid motions). Lowest eigenvalue outside that cluster, \
             by blocks vs by shift-invert: max difference {:.2e} max|K_ij|; Lanczos converged \
             at least {} of {} at every point. Ratio without the one-off set-ups (basis vs \
             symbolic analysis): {:.2}×.",
            runs(&l.indices),
            agree(&full.indices),
            clusters
                .iter()
                .map(|c| c.to_string())
                .collect::<Vec<_>>()
                .join(" or "),
            full.rigid_modes,
            lowest_diff,
            full.converged_min,
            full.lowest_count,
            secs(full.total().saturating_sub(full.symbolic)) / secs(l.spectra.unwrap_or_default()),
        );
        let in_path = l.index.unwrap_or_default();
        let _ = writeln!(
            md,
            "  The index alone at the same states, one pass each right after the other: by \
             blocks {} ms (a fresh analysis, its blocks' symbolic analyses included; index {}), \
             without symmetry (ii′) {} ms: **{:.2}×**. Along the path, as `run` computes it \
             between its steps: {} ms, {:.2}×; the blocks' pass again with the thread pool \
             left idle for {} ms before each state, as between the path's steps: {} ms \
             (BENCHMARKS.md §3.4).",
            ms(full.blocks_index),
            agree(&full.blocks_indices),
            ms(full.index_only()),
            secs(full.index_only()) / secs(full.blocks_index),
            ms(in_path),
            secs(full.index_only()) / secs(in_path),
            super::full_path::PAUSE.as_millis(),
            ms(full.blocks_index_paused),
        );
        if let Some(d) = &full.dense {
            let mut dz = d.zero_cluster.clone();
            dz.sort_unstable();
            dz.dedup();
            let dense_lowest = max_scaled_difference(&l.lowest, &d.lowest, &full.scales);
            let _ = writeln!(
                md,
                "  Dense (iii): index {}; eigenvalues in [−τ, τ]: {}; lowest outside them vs by \
                 blocks: max difference {:.2e} max|K_ij|; build {} ms + eigen {} ms.",
                agree(&d.indices),
                dz.iter()
                    .map(|c| c.to_string())
                    .collect::<Vec<_>>()
                    .join(" or "),
                dense_lowest,
                ms(d.build),
                ms(d.eigen),
            );
        }
    }
    text
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

/// The section of `accuracy.md` on one symmetry-payoff case.
pub fn payoff_table(case: &PayoffCase) -> String {
    let mut text = String::new();
    let md = &mut text;
    let po = &case.payoff;
    let scale = po
        .by_blocks
        .iter()
        .fold(0.0f64, |m, b| m.max(b.value.abs()));
    let heading = if po.group == "Ih" {
        "Symmetry payoff on one tangent matrix".to_string()
    } else {
        format!("Symmetry payoff on a {} tangent matrix", po.group)
    };
    let _ = writeln!(
        md,
        "\n## {heading}\n\n\
         K of {}: {} unknowns, group {} ({} irreps; block sizes {}).\n",
        po.case,
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
    let mut rows: Vec<(&str, String)> =
        vec![
        ("assembly of K (`model.evaluate`)", ms(po.assembly)),
        (
            "adapted basis (once per mesh and group, not per matrix)",
            ms(po.adapted_basis),
        ),
        ("(a) restrict K to every block", ms(po.restrict)),
        ("(a) dense eigenvalues of every block (faer)", ms(po.block_eigen)),
        ("(a) all eigenvalues by blocks, total", ms(po.blocks_time())),
        (
            "(a') `Stability::spectrum_of` as `run` calls it (assembly, restriction, rigid-mode \
             deflation, Zᵀ K Z, eigen)",
            ms(po.stability_spectrum),
        ),
        ("(b) build dense K", opt_ms(po.dense_build)),
        (
            "(b) dense full eigenvalues of K (faer `self_adjoint_eigenvalues`)",
            opt_ms(po.dense_eigen),
        ),
    ];
    if let Some(si) = &po.shift_invert {
        rows.push((
            "(d) sparse LBLᵀ of K − σI (symbolic + numeric)",
            ms(si.factorisation),
        ));
        rows.push((
            "(d) faer `partial_self_adjoint_eigen` on (K − σI)⁻¹, 20 values",
            ms(si.lanczos),
        ));
    }
    for (what, time) in rows {
        let _ = writeln!(md, "| {what} | {time} |");
    }
    if let Some(Ok(p)) = &case.peer {
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
             multisets agree (block eigenvalues repeated d_μ times, rigid modes if any \
             included): max |Δλ| / max |λ| = {:.2e}.",
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
    match &case.peer {
        Some(Ok(p)) => {
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
        Some(Err(why)) => {
            let _ = writeln!(md, "- (e) scipy `eigsh` comparison skipped: {why}.");
        }
        None => {}
    }
    text
}

/// The ponding ladder's table of `accuracy.md`.
pub fn ponding_table(levels: &[PondingLevel]) -> String {
    let mut text = String::new();
    let md = &mut text;
    let _ = writeln!(
        md,
        "\n## Ponding ladder (C7v disc): critical densities against the closed form\n\n\
         γ_(m,k) = {PONDING_SCALE} j²_(m,k); each disc by `run` (density swept over [0, 20] in 60 \
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
    text
}

/// The ponding ladder on the chiral disc beside the C7v one of the same divisions: the same
/// rungs (each E_k double on both), the difference of their densities, and both times.
pub fn ponding_chiral_table(reference: &PondingLevel, chiral: &PondingLevel) -> String {
    let mut text = String::new();
    let md = &mut text;
    let _ = writeln!(
        md,
        "\n### The same ladder on the chiral {} disc (d = {})\n\n\
         A twisted pattern without mirrors, so another mesh with its own discretisation \
         error; its E_k blocks are of complex type (docs/theory.md §10.6), solved dense or \
         sparse by cost like the real ones.\n",
        chiral.group, chiral.divisions
    );
    let _ = writeln!(
        md,
        "| (m, k) | {0} irrep | {0} | {1} irrep | {1} | difference |",
        reference.group, chiral.group
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for r in &reference.rungs {
        let _ = write!(
            md,
            "| ({}, {}) | {} (×{}) | {:.6} |",
            r.mk.0, r.mk.1, r.irrep, r.multiplicity, r.rho
        );
        match chiral.rungs.iter().find(|s| s.mk == r.mk) {
            Some(s) => {
                let _ = writeln!(
                    md,
                    " {} (×{}) | {:.6} | {:.3e} |",
                    s.irrep,
                    s.multiplicity,
                    s.rho,
                    (s.rho - r.rho).abs()
                );
            }
            None => {
                let _ = writeln!(md, " – | – | – |");
            }
        }
    }
    let _ = writeln!(
        md,
        "\n- {}: `run` in {} ms; {}: `run` in {} ms ({} unknowns each).",
        reference.group,
        ms(reference.time),
        chiral.group,
        ms(chiral.time),
        chiral.unknowns
    );
    text
}

/// Relative error against wall time, log–log, one series for the maximum and one for the
/// minimum, each point labelled with its frequency. No font files are read (SVG text).
pub fn accuracy_svg(levels: &[BalloonLevel]) -> Result<String, Box<dyn std::error::Error>> {
    let pts = |f: fn(&BalloonLevel) -> Option<f64>| -> Vec<(f64, f64, usize)> {
        levels
            .iter()
            .filter_map(|l| Some((secs(l.total).max(1e-6), f(l)?.max(1e-16), l.frequency)))
            .collect()
    };
    accuracy_plot(&pts(BalloonLevel::err_max), &pts(BalloonLevel::err_min))
}

/// The range of `values` widened to whole decades (at least one).
fn decades(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return 0.1..10.0;
    }
    let (a, mut b) = (lo.log10().floor(), hi.log10().ceil());
    if b <= a {
        b = a + 1.0;
    }
    10f64.powf(a)..10f64.powf(b)
}

/// The accuracy plot of points (wall time s, relative error, frequency) in memstab's figure
/// style: the maximum's solid blue with discs, the minimum's dashed red with squares (so that
/// both show where they overlap), each point labelled with its frequency (labels kept apart),
/// both axes logarithmic over whole decades with every decade labelled, a legend of both
/// lines and both markers, and a caption naming the meshes.
pub fn accuracy_plot(
    max: &[(f64, f64, usize)],
    min: &[(f64, f64, usize)],
) -> Result<String, Box<dyn std::error::Error>> {
    use crate::output::figure::{self, Entry, Line, Mark, Plot, Sample, Symbol};
    let all = || max.iter().chain(min);
    let log = |r: std::ops::Range<f64>| r.start.log10()..r.end.log10();
    let xr = log(decades(all().map(|p| p.0)));
    let yr = log(decades(all().map(|p| p.1)));
    let frequencies: Vec<usize> = all().map(|p| p.2).collect();
    let triangles = |f: Option<&usize>| f.map_or(0, |f| 20 * f * f);
    let caption = format!(
        "memstab bench · mesh: icosphere, {} to {} triangles, group Ih",
        triangles(frequencies.iter().min()),
        triangles(frequencies.iter().max())
    );
    let mut plot = Plot::new(
        "balloon k = 0.1: relative error of the turning pressures vs wall time",
        caption,
        "wall time of the level (s)",
        "relative error",
    );
    plot.log = (true, true);
    plot.ranges = Some((xr, yr));
    let blue = RGBColor(31, 87, 180);
    let red = RGBColor(200, 30, 30);
    let at = |p: &(f64, f64, usize)| (p.0.log10(), p.1.log10());
    for (points, colour, width, dash, name, symbol) in [
        (max, blue, 3, None, "p_max", Symbol::Disc(blue)),
        (min, red, 2, Some((7, 4)), "p_min", Symbol::Square(red)),
    ] {
        if points.is_empty() {
            continue;
        }
        plot.lines.push(Line::new(
            points.iter().map(at).collect(),
            colour,
            width,
            dash,
        ));
        plot.legend
            .push(Entry::new(name, Sample::Line(colour, width, dash)));
        for p in points {
            plot.marks.push(Mark {
                at: at(p),
                symbol,
                kind: format!("{name} of a level"),
                label: format!("f={}", p.2),
            });
        }
    }
    let (svg, layout) = figure::render(&plot)?;
    Ok(figure::finish(&svg, &layout))
}

/// The heading of `accuracy.md`: what ran, on how many cores.
pub fn accuracy_heading(quick: bool) -> String {
    format!(
        "# memstab bench{}\n\nmemstab {}; {} core(s) seen; faer and rayon parallelism as in `memstab run`.\n\n",
        if quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        cores()
    )
}

/// The heading of `scaling.md`: the frequencies, on how many cores.
pub fn scaling_heading(frequencies: &[usize]) -> String {
    format!(
        "# memstab bench --scaling {}\n\nmemstab {}; {} core(s) seen.\n\n",
        frequencies
            .iter()
            .map(|f| f.to_string())
            .collect::<Vec<_>>()
            .join(","),
        env!("CARGO_PKG_VERSION"),
        cores()
    )
}

/// The closing line of a report: `\nTotal wall time of the {what}: {t:.1} s.`
pub fn total_time(what: &str, time: Duration) -> String {
    format!(
        "\nTotal wall time of the {what}: {:.1} s.\n",
        time.as_secs_f64()
    )
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tick texts of an SVG.
    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                let body = &t[t.find('>')? + 1..];
                Some(body[..body.find("</text>")?].trim().to_string())
            })
            .collect()
    }

    #[test]
    fn accuracy_plot_labels_every_decade_and_draws_both_series() {
        // Errors over five decades, times over two; the minimum's errors equal the maximum's
        // at one level (the lines overlap there).
        let max = [(0.02, 3e-2, 2), (0.2, 8e-4, 4), (3.0, 2e-6, 8)];
        let min = [(0.02, 3e-2, 2), (0.2, 5e-3, 4), (3.0, 4e-5, 8)];
        let svg = accuracy_plot(&max, &min).unwrap();
        let texts = texts(&svg);
        for decade in ["1e-6", "1e-5", "1e-4", "1e-3", "1e-2", "1e-1", "1", "10"] {
            assert!(
                texts.iter().any(|t| t == decade),
                "no {decade:?} in {texts:?}"
            );
        }
        assert!(texts.iter().any(|t| t == "p_max") && texts.iter().any(|t| t == "p_min"));
        // Solid blue line of three points; the red one dashed (many short pieces).
        assert!(svg.contains("stroke=\"#1F57B4\""), "the maximum's line");
        let red_pieces = svg.matches("stroke=\"#C81E1E\"").count();
        assert!(
            red_pieces > 3,
            "the minimum's dashed line: {red_pieces} pieces"
        );
        assert_eq!(crate::output::figure::decade(0.002f64.log10()), "");
        assert_eq!(decades([0.002, 0.3].into_iter()), 0.001..1.0);
        // In the figures' style: a legend of both lines and both markers, every label placed.
        let layout = crate::output::read_layout(&svg).expect("a layout");
        assert_eq!(
            layout.marker_kinds,
            ["p_max of a level", "p_min of a level"]
        );
        assert_eq!(layout.legend_markers, layout.marker_kinds);
        assert_eq!(layout.labels.len(), 6);
        assert!(layout.dropped.is_empty());
        assert!(
            layout.caption.contains("80 to 1280 triangles"),
            "{}",
            layout.caption
        );
    }
}
