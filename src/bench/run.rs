//! `memstab bench` as a library call: every study of the bench ([`run_accuracy`]) or the
//! scaling study alone ([`run_scaling`]), their tables built by [`super::report`] and written
//! whole into an output directory. The command line checks its flags, calls one of these and
//! prints the markdown they return.

use super::balloon::{balloon_level_with, BalloonLevel, LevelOptions};
use super::full_path::{full_path_stability, FullPathStability};
use super::one_line;
use super::payoff::{c8v_payoff, payoff, PayoffCase};
use super::peer::run_peer;
use super::ponding::{ponding_level, ponding_level_in};
use super::report;
use super::scaling::{scaling_level, ScalingFits};
use crate::output::write_atomic;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What [`run_accuracy`] runs.
#[derive(Debug, Clone, Default)]
pub struct AccuracyOptions {
    /// The output directory (created if missing; its parent must exist).
    pub out: PathBuf,
    /// Small sizes only: balloon f = 4, 8; the payoff at f = 8 and on a C8v disc of 8
    /// divisions; the path comparison at f = 4, 8, dense at f = 4; ponding divisions 4, 8.
    pub quick: bool,
    /// Balloon frequencies, each at least 1 (empty: 4, 8, 16, 32; quick 4, 8). Stability
    /// spectra at every point for f ≤ 32 only; the Ih payoff at f = 16 (quick 8) when the
    /// list has it; stability without symmetry along the path for f ≤ 16 (quick 8).
    pub frequencies: Vec<usize>,
}

/// What [`run_scaling`] runs.
#[derive(Debug, Clone, Default)]
pub struct ScalingOptions {
    /// The output directory (created if missing; its parent must exist).
    pub out: PathBuf,
    /// Icosphere frequencies, each at least 1.
    pub frequencies: Vec<usize>,
    /// Points of each path, the start included (at least 2).
    pub points: usize,
}

/// What a run of the bench wrote.
#[derive(Debug, Clone)]
pub struct BenchFiles {
    /// The markdown report (the content of `accuracy.md` or `scaling.md`).
    pub markdown: String,
    /// The files written, the markdown first (the peer's `K.mtx` not listed).
    pub files: Vec<PathBuf>,
}

/// Writes `text` to `out`/`name` whole.
fn write_text(out: &Path, name: &str, text: &str) -> Result<PathBuf, String> {
    let path = out.join(name);
    write_atomic(&path, |w| w.write_all(text.as_bytes())).map_err(|e| e.to_string())?;
    Ok(path)
}

/// Tells `progress` of the next study, unless a signal asked to stop: then the bench ends
/// there, its files so far written.
fn stage(progress: &mut dyn FnMut(&str), what: &str) -> Result<(), String> {
    if crate::continuation::interrupt::requested() {
        return Err(format!(
            "a signal stopped the bench before {}; the files written so far are left",
            what.trim_end_matches(" …")
        ));
    }
    progress(what);
    Ok(())
}

fn create_dir(out: &Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))
}

/// The bench: the balloon levels (with the Ih payoff at one level and stability without
/// symmetry along the path at the small ones), the C8v payoff, the ponding ladder; writes
/// `accuracy.md`, `accuracy.csv`, `payoff.csv`, `accuracy.svg` (and, with a peer, `K.mtx`)
/// into [`AccuracyOptions::out`]. `progress` is told what starts, e.g. `balloon f = 8 …`.
pub fn run_accuracy(
    options: &AccuracyOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchFiles, String> {
    let out = &options.out;
    let quick = options.quick;
    let mut freqs = options.frequencies.clone();
    if freqs.is_empty() {
        freqs = if quick {
            vec![4, 8]
        } else {
            vec![4, 8, 16, 32]
        };
    }
    // The payoff runs on the level of this frequency when the list has it.
    let payoff_f = if quick { 8 } else { 16 };
    // Stability without symmetry along the path up to this frequency, dense up to the other.
    let (compare_max_f, dense_path_max_f) = if quick { (8, 4) } else { (16, 8) };
    let disc_divisions = if quick { 8 } else { 16 };
    freqs.sort_unstable();
    freqs.dedup();
    create_dir(out)?;
    let started = Instant::now();
    let mut md = report::accuracy_heading(quick);

    // 1. The balloon, with the Ih payoff at one level and the path comparison at the small ones.
    let mut levels: Vec<BalloonLevel> = Vec::new();
    let mut cases: Vec<PayoffCase> = Vec::new();
    let mut paths: Vec<(usize, FullPathStability)> = Vec::new();
    for &f in &freqs {
        stage(progress, &format!("balloon f = {f} …"))?;
        let stability = f <= 32;
        let options = LevelOptions {
            stability,
            keep_states: stability && f <= compare_max_f,
            max_points: None,
            index_only: false,
        };
        let failure = |e: &str| format!("balloon f = {f}: {}", one_line(e));
        let (mut level, study) = balloon_level_with(f, &options).map_err(|e| failure(&e))?;
        if level.p_max.is_none() || level.p_min.is_none() {
            return Err(failure("the path did not reach both turning points"));
        }
        if f == payoff_f {
            stage(progress, &format!("symmetry payoff at f = {f} …"))?;
            let (u, p) = level
                .at_max
                .as_ref()
                .ok_or_else(|| failure("no state at the pressure maximum"))?;
            let mut po = payoff(&study, u, p, true, true, 20)
                .map_err(|e| format!("payoff at f = {f}: {e}"))?;
            po.frequency = f;
            po.case = format!("the balloon of frequency {f} at its pressure maximum");
            let sigma = po.shift_invert.as_ref().map_or(0.0, |s| s.shift);
            let peer = run_peer(out, &study, u, p, sigma);
            cases.push(PayoffCase {
                name: format!("balloon-Ih-f{f}"),
                payoff: po,
                peer: Some(peer),
            });
        }
        if !level.states.is_empty() {
            stage(
                progress,
                &format!("stability along the path without symmetry at f = {f} …"),
            )?;
            let full = full_path_stability(&study, &level.states, 20, f <= dense_path_max_f)
                .map_err(|e| failure(&format!("stability without symmetry: {e}")))?;
            level.states = Vec::new();
            paths.push((f, full));
        }
        levels.push(level);
    }
    stage(
        progress,
        &format!("symmetry payoff on a C8v disc with {disc_divisions} divisions …"),
    )?;
    let mut c8v = c8v_payoff(disc_divisions, true, true, 20).map_err(|e| {
        format!(
            "C8v payoff (disc, {disc_divisions} divisions): {}",
            one_line(&e)
        )
    })?;
    c8v.frequency = 0;
    cases.push(PayoffCase {
        name: format!("disc-C8v-d{disc_divisions}"),
        payoff: c8v,
        peer: None,
    });
    md += &report::balloon_tables(&levels);

    // 2. The payoffs.
    for case in &cases {
        md += &report::payoff_table(case);
    }

    // 3. Stability along the path with and without symmetry.
    md += &report::path_tables(&levels, &paths);

    // 4. Ponding.
    let divisions: [usize; 2] = if quick { [4, 8] } else { [8, 16] };
    let mut ponding = Vec::new();
    for d in divisions {
        stage(progress, &format!("ponding, C7v disc with {d} divisions …"))?;
        ponding.push(ponding_level(d).map_err(|e| format!("ponding d = {d}: {}", one_line(&e)))?);
    }
    md += &report::ponding_table(&ponding);
    // The same ladder on the chiral C7 disc of the finest level: complex-type E_k blocks.
    let d = divisions[1];
    stage(
        progress,
        &format!("ponding, chiral C7 disc with {d} divisions …"),
    )?;
    let chiral = ponding_level_in(d, Some("C7"))
        .map_err(|e| format!("ponding on C7, d = {d}: {}", one_line(&e)))?;
    if let Some(reference) = ponding.last() {
        md += &report::ponding_chiral_table(reference, &chiral);
    }

    // 5. Branch switching.
    let branch_divisions = if quick { 8 } else { 16 };
    stage(progress, &format!(
        "branch switching: the abstract Hg problem, the upward disc with {branch_divisions} divisions …"
    ))?;
    md += &super::branching::branching_section(branch_divisions)
        .map_err(|e| format!("branch switching: {}", one_line(&e)))?;
    md += &report::total_time("bench", started.elapsed());

    // Outputs.
    let md_path = write_text(out, "accuracy.md", &md)?;
    let csv_path = write_text(out, "accuracy.csv", &report::balloon_csv(&levels, &paths))?;
    let payoff_path = write_text(out, "payoff.csv", &report::payoff_csv(&cases))?;
    let svg = report::accuracy_svg(&levels).map_err(|e| format!("accuracy.svg: {e}"))?;
    let svg_path = write_text(out, "accuracy.svg", &svg)?;
    Ok(BenchFiles {
        markdown: md,
        files: vec![md_path, csv_path, payoff_path, svg_path],
    })
}

/// The branch-switching study alone (the same table as in the whole bench; the disc on 8 divisions when
/// `quick`, else 16): writes `branching.md` into `out`.
pub fn run_branching(
    out: &Path,
    quick: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchFiles, String> {
    create_dir(out)?;
    let started = Instant::now();
    let divisions = if quick { 8 } else { 16 };
    stage(
        progress,
        &format!(
        "branch switching: the abstract Hg problem, the upward disc with {divisions} divisions …"
    ),
    )?;
    let mut md = "# memstab bench: branch switching\n".to_string();
    md += &super::branching::branching_section(divisions)
        .map_err(|e| format!("branch switching: {}", one_line(&e)))?;
    md += &report::total_time("study", started.elapsed());
    let md_path = write_text(out, "branching.md", &md)?;
    Ok(BenchFiles {
        markdown: md,
        files: vec![md_path],
    })
}

/// The axisymmetric study alone: the balloon on a meridian of 200 elements (quick: 64) with
/// the index of every wave number m = 0..20 at every point, timed; writes `axisym.md`.
pub fn run_axisym(
    out: &Path,
    quick: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchFiles, String> {
    create_dir(out)?;
    let started = Instant::now();
    let levels: &[usize] = if quick { &[64] } else { &[64, 200] };
    stage(
        progress,
        &format!("axisymmetric balloon with modes 0..20 at every point, {levels:?} elements …"),
    )?;
    let mut md = "# memstab bench: the axisymmetric model
"
    .to_string();
    for &e in levels {
        md += &super::axisym::axisym_section(e)
            .map_err(|err| format!("axisymmetric balloon: {}", one_line(&err)))?;
    }
    let caps: &[usize] = if quick { &[128] } else { &[128, 256] };
    stage(
        progress,
        &format!("axisymmetric Paper 4 cap with modes 0..8 at every point, {caps:?} elements …"),
    )?;
    md += &super::axisym::paper4_section(caps)
        .map_err(|err| format!("axisymmetric Paper 4 cap: {}", one_line(&err)))?;
    md += &report::total_time("study", started.elapsed());
    let md_path = write_text(out, "axisym.md", &md)?;
    Ok(BenchFiles {
        markdown: md,
        files: vec![md_path],
    })
}

/// The scaling study alone: per frequency a balloon path of [`ScalingOptions::points`]
/// points with the index by irrep at every point, its time by phase and peak memory, and the
/// growth exponents; writes `scaling.md` and `scaling.csv` into [`ScalingOptions::out`].
pub fn run_scaling(
    options: &ScalingOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchFiles, String> {
    let out = &options.out;
    let points = options.points;
    let mut freqs = options.frequencies.clone();
    freqs.sort_unstable();
    freqs.dedup();
    create_dir(out)?;
    let started = Instant::now();
    let mut levels = Vec::new();
    for &f in &freqs {
        stage(
            progress,
            &format!("scaling, balloon f = {f}, {points} points with stability …"),
        )?;
        levels.push(
            scaling_level(f, points).map_err(|e| format!("scaling f = {f}: {}", one_line(&e)))?,
        );
    }
    let fits = ScalingFits::new(&levels);
    let mut md = report::scaling_heading(&freqs);
    md += &report::scaling_table(&levels, &fits, points);
    md += &report::total_time("study", started.elapsed());
    let md_path = write_text(out, "scaling.md", &md)?;
    let csv_path = write_text(out, "scaling.csv", &report::scaling_csv(&levels, &fits))?;
    Ok(BenchFiles {
        markdown: md,
        files: vec![md_path, csv_path],
    })
}

/// What [`run_thesis`] runs.
#[derive(Debug, Clone, Default)]
pub struct ThesisOptions {
    /// The output directory (created if missing; its parent must exist).
    pub out: PathBuf,
    /// Small caps only (8 divisions, 512 triangles), without the finest level.
    pub quick: bool,
}

/// The thesis-size study ([`super::thesis`]): the spinning cap on C8v, C4v, C2v, C1v and C1
/// at 26 divisions (5 408 triangles), each against the same states without symmetry, and on
/// C2v at 52 divisions (21 632 triangles); writes `thesis.md` into [`ThesisOptions::out`]
/// (and `K.mtx`, the last C2v point's tangent, when scipy is found).
pub fn run_thesis(
    options: &ThesisOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchFiles, String> {
    use super::thesis::{thesis_run, thesis_table};
    let out = &options.out;
    create_dir(out)?;
    let started = Instant::now();
    let (divisions, finest) = if options.quick {
        (8, None)
    } else {
        (26, Some(52))
    };
    let steps = 8;
    let mut runs = Vec::new();
    for pattern in ["C8v", "C4v", "C2v", "C1v", "C1"] {
        stage(
            progress,
            &format!("thesis cap, {pattern}, {divisions} divisions …"),
        )?;
        let peer = (pattern == "C2v").then_some(out.as_path());
        runs.push(
            thesis_run(pattern, divisions, steps, true, peer)
                .map_err(|e| format!("thesis cap {pattern}: {}", one_line(&e)))?,
        );
    }
    // On C1v the path turns at the fold of the broken m = 1 pair and meets the mirror-breaking
    // bifurcations on the way back: three times the points to reach them.
    stage(
        progress,
        &format!("thesis cap, C1v through its fold, {divisions} divisions …"),
    )?;
    runs.push(
        thesis_run("C1v", divisions, 3 * steps, true, None)
            .map_err(|e| format!("thesis cap C1v, {} steps: {}", 3 * steps, one_line(&e)))?,
    );
    if let Some(d) = finest {
        stage(progress, &format!("thesis cap, C2v, {d} divisions …"))?;
        runs.push(
            thesis_run("C2v", d, steps, false, None)
                .map_err(|e| format!("thesis cap C2v, {d} divisions: {}", one_line(&e)))?,
        );
    }
    let mut md = format!(
        "# memstab bench --thesis{}\n\nmemstab {}; {} core(s) seen.\n\n",
        if options.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    md += &thesis_table(&runs);
    if !options.quick {
        md += &thesis_scenes(progress)?;
    }
    md += &report::total_time("study", started.elapsed());
    let md_path = write_text(out, "thesis.md", &md)?;
    Ok(BenchFiles {
        markdown: md,
        files: vec![md_path],
    })
}

/// The bundled thesis scenes (`scenes/thesis/*.toml`, embedded in the binary and written with
/// the meshes they read into a temporary directory), each run and timed: the section of
/// `thesis.md` that lists them.
fn thesis_scenes(progress: &mut dyn FnMut(&str)) -> Result<String, String> {
    use super::thesis::{scene_run, scenes_table, write_thesis_scenes};
    let dir = tempfile::tempdir().map_err(|e| format!("a temporary directory: {e}"))?;
    let files = write_thesis_scenes(dir.path())?;
    let mut runs = Vec::new();
    for f in &files {
        let name = f
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        stage(progress, &format!("thesis scene {name} …"))?;
        runs.push(scene_run(f).map_err(|e| format!("{name}: {}", one_line(&e)))?);
    }
    Ok(scenes_table(&runs))
}

/// The critical-curve study ([`super::curves`]): 200 points of the balloon's fold line at
/// f = 16 (quick: 8) through its cusp, with the other blocks watched and without, and the C7v
/// disc's first E1 double point followed in
/// its prestretch at 16 divisions (quick: 8); writes `curves.md` into `options.out`.
pub fn run_curves(
    options: &ThesisOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchFiles, String> {
    use super::curves::{curve_run, curves_table, double_curve_scene, fold_line_scene};
    let out = &options.out;
    create_dir(out)?;
    let started = Instant::now();
    let (frequency, divisions) = if options.quick { (8, 8) } else { (16, 16) };
    stage(progress, &format!("balloon fold line, f = {frequency} …"))?;
    let fold = curve_run(
        &format!("balloon fold line in (p, k), f = {frequency}"),
        fold_line_scene(frequency, 199, 0.012, true)?,
    )
    .map_err(|e| format!("balloon fold line: {}", one_line(&e)))?;
    stage(
        progress,
        &format!("balloon fold line, f = {frequency}, watch = false …"),
    )?;
    let unwatched = curve_run(
        &format!("balloon fold line in (p, k), f = {frequency}, watch = false"),
        fold_line_scene(frequency, 199, 0.012, false)?,
    )
    .map_err(|e| format!("balloon fold line (watch = false): {}", one_line(&e)))?;
    stage(
        progress,
        &format!("C7v disc double curve, {divisions} divisions …"),
    )?;
    let double = curve_run(
        &format!("C7v disc E1 double point in (h, prestretch), {divisions} divisions"),
        double_curve_scene(divisions, 40)?,
    )
    .map_err(|e| format!("C7v double curve: {}", one_line(&e)))?;
    let mut md = format!(
        "# memstab bench --curves{}\n\nmemstab {}; {} core(s) seen.\n\n",
        if options.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    md += &curves_table(&[fold, unwatched, double]);
    md += &report::total_time("study", started.elapsed());
    let md_path = write_text(out, "curves.md", &md)?;
    Ok(BenchFiles {
        markdown: md,
        files: vec![md_path],
    })
}
