//! The summary `memstab run` and `memstab demo` print after a run: the mesh and group, the
//! path, turning and critical points (with each mode's wave number where the mesh has an
//! axis), where the membrane wrinkles, the files written; and a critical curve's events.

use memstab::output::{file_name, Written};
use memstab::results::refine::Refinement;
use memstab::results::{PathReport, RunResult};
use memstab::scene::Scene;
use memstab::text::sig_digits;
use std::path::Path;

/// The index of the measure `stretch`, if the report has it.
fn stretch_index(report: &PathReport) -> Option<usize> {
    report.measures.iter().position(|m| m == "stretch")
}

/// The index of the control among the parameters.
fn control_index(report: &PathReport) -> Option<usize> {
    report.parameters.iter().position(|p| *p == report.control)
}

pub(super) fn print_summary(scene: &Scene, result: &RunResult, out: &Path, written: &Written) {
    let report = &result.report;
    let (own, curve_events) = memstab::analysis::summary(scene, result);
    let m = &report.mesh;
    out!("scene '{}' ({})", report.scene, report.origin);
    if m.order == 0 {
        // The blocks are listed where the rows carry their counts (a path, a sweep).
        let range = match report.irreps.len() {
            0 => String::new(),
            n => format!(" = 0..{}", n - 1),
        };
        out!(
            "mesh: {} meridian with {} nodes, {} quadratic elements; its states keep {} \
             (stability by wave number m{range})",
            m.generator,
            m.nodes,
            m.elements,
            m.group
        );
        out!("solved in {} unknowns", report.unknowns);
    } else {
        out!(
            "mesh: {} with {} nodes, {} triangles, group {} (order {})",
            m.generator,
            m.nodes,
            m.elements,
            m.group,
            m.order
        );
        out!(
            "scene group {} (order {}): solved in {} symmetric unknowns of {}",
            report.group,
            report.group_order,
            report.symmetric_unknowns,
            report.unknowns
        );
    }
    let c = control_index(report);
    let s = stretch_index(report);
    let n = report.rows.len();
    let points = if n == 1 {
        "1 point".to_string()
    } else {
        format!("{n} points")
    };
    match (c, report.rows.first(), report.rows.last()) {
        (Some(c), Some(first), Some(last)) if n > 1 => out!(
            "path: {points}, {} from {} to {}",
            report.control,
            sig_digits6(first.parameters[c]),
            sig_digits6(last.parameters[c])
        ),
        (Some(c), Some(first), _) => {
            out!(
                "path: {points}, {} = {}",
                report.control,
                sig_digits6(first.parameters[c])
            )
        }
        _ => out!("equilibrium: {points}"),
    }
    // A closed membrane with a negative enclosed volume has turned inside out: the numbers
    // are finite but not physical.
    if let Some(v) = report.measures.iter().position(|m| m == "volume") {
        if let Some(r) = report.rows.iter().find(|r| r.measures[v] <= 0.0) {
            out!(
                "warning: the enclosed volume is {} at step {}: the membrane is inside out there, \
                 the path is not physical",
                sig_digits6(r.measures[v]),
                r.step
            );
        }
    }
    if report.turning_points.is_empty() {
        if c.is_some() {
            out!("turning points of {}: none", report.control);
        }
    } else {
        out!("turning points of {}:", report.control);
        for (k, t) in report.turning_points.iter().enumerate() {
            let value = c.map_or_else(|| "?".to_string(), |c| sig_digits6(t.parameters[c]));
            let stretch = s.map_or_else(String::new, |s| {
                format!(" at stretch {}", sig_digits6(t.measures[s]))
            });
            let why: Vec<String> = report
                .turning_flags(k)
                .iter()
                .map(ToString::to_string)
                .collect();
            let flagged = if why.is_empty() {
                String::new()
            } else {
                format!(" — flagged: {}", why.join("; "))
            };
            out!(
                "  {:<7} {} = {value}{stretch} (after step {}){flagged}",
                t.kind,
                report.control,
                t.after_step
            );
        }
    }
    for w in &report.warnings {
        out!("warning: {w}");
    }
    if let Some(note) = &report.stability_note {
        out!("{note}");
    } else if report.critical.is_empty() {
        match report.index_range() {
            Some((lo, hi)) if lo == hi => out!("critical points: none (the index stays {lo})"),
            Some((lo, hi)) => out!(
                "critical points: none localised, although the index ranges from {lo} to {hi} \
                 along the path (see the warnings)"
            ),
            None => out!("critical points: none (no index was computed)"),
        }
    } else {
        // The valid points first; those with a flag apart, with the reasons.
        let line = |k: usize| {
            let cp = &report.critical[k];
            let value = c.map_or_else(|| "?".to_string(), |c| sig_digits6(cp.parameters[c]));
            let m = report
                .wave_numbers
                .get(k)
                .map_or_else(String::new, |m| format!(", m = {m}"));
            format!(
                "  {:<20} in {:<4} x{} at {} = {value} (isotropy {}{m}, |eigenvalue|/|K| = {:.0e})",
                cp.kind,
                cp.irrep,
                cp.multiplicity,
                report.control,
                cp.isotropy.name,
                cp.residual_eigenvalue
            )
        };
        let (valid, flagged): (Vec<usize>, Vec<usize>) =
            (0..report.critical.len()).partition(|&k| report.flags(k).is_empty());
        if valid.is_empty() {
            out!("critical points: none valid");
        } else {
            out!("critical points (irrep of the singular block, multiplicity in K, isotropy of the mode):");
        }
        for &k in &valid {
            out!("{}", line(k));
        }
        if !flagged.is_empty() {
            out!(
                "critical points flagged (not results of the model as it stands; numbered as in critical.json):"
            );
            for &k in &flagged {
                let why: Vec<String> = report.flags(k).iter().map(ToString::to_string).collect();
                out!("{} — point {}: {}", line(k), k + 1, why.join("; "));
            }
        }
    }
    print_wrinkling(report);
    out!("stopped: {}", report.stop);
    if let Some(r) = &report.refinement {
        print_refinement(r);
    }
    for line in &own {
        out!("{line}");
    }
    out!(
        "wrote {} files into {}:",
        written.files().len(),
        out.display()
    );
    let header = report
        .parameters
        .iter()
        .chain(&report.measures)
        .map(String::as_str)
        .collect::<Vec<_>>()
        .join(", ");
    let blocks = if report.irreps.is_empty() {
        String::new()
    } else {
        format!(
            ", index_{} … index_{}",
            report.irreps[0],
            report.irreps[report.irreps.len() - 1]
        )
    };
    out!(
        "  {:<10} {} rows: step, arclength, {header}, iterations, index{blocks}, flags",
        file_name(&written.csv),
        report.rows.len()
    );
    out!(
        "  {:<10} the report: metadata, path, turning points, critical points, saved states",
        file_name(&written.json)
    );
    let events = match curve_events {
        0 => String::new(),
        n => format!(" and the curve's {n} events"),
    };
    out!(
        "  {:<10} {} critical points{events}: kind, irrep, multiplicity, parameters, step",
        file_name(&written.critical),
        report.critical.len()
    );
    out!("  {:<10} {}", file_name(&written.svg), written.plotted);
    out!(
        "  {:<10} the same figure as an image",
        file_name(&written.png)
    );
    let in_collection = report.saved.iter().filter(|s| s.in_collection).count();
    out!(
        "  {:<10} ParaView collection of the {in_collection} path state{} (time = path step)",
        file_name(&written.pvd),
        if in_collection == 1 { "" } else { "s" }
    );
    let events = report.saved.len() - in_collection;
    out!(
        "  {:<10} ParaView collection of the {events} turning and critical state{} (time = 0, 1, ... in path order)",
        file_name(&written.events),
        if events == 1 { "" } else { "s" }
    );
    if let Some(points) = &written.points {
        out!(
            "  {:<10} every point's parameters and displacement, binary ([start] from reads it)",
            file_name(points),
        );
    }
    for chunk in written.states.chunks(5) {
        let names: Vec<String> = chunk.iter().map(|p| file_name(p)).collect();
        out!("  {}", names.join(" "));
    }
    // A file of a subdirectory (a second piece's) is named by its directory, once.
    let dir = written.csv.parent();
    for d in written.own.iter().filter(|d| !d.what.is_empty()) {
        let name = match (dir, d.path.parent()) {
            (Some(a), Some(b)) if a != b => {
                format!("{}/", b.file_name().unwrap_or_default().to_string_lossy())
            }
            _ => file_name(&d.path),
        };
        out!("  {:<10} {}", name, d.what);
    }
    if let (Some(b), Some(w)) = (&result.branches, &written.branches) {
        super::branch::print_branches(b, w, &report.control);
    }
}

/// Where the membrane would wrinkle: the first path point with wrinkled triangles (the
/// critical points in a wrinkled state are listed apart, flagged).
fn print_wrinkling(report: &PathReport) {
    let Some(w) = &report.wrinkling else {
        return;
    };
    match &w.first {
        None if w.relaxed => out!("wrinkling: none (every triangle is taut at every path point)"),
        None => out!("wrinkling: none (every triangle is in tension at every path point)"),
        Some(p) if w.relaxed => out!(
            "wrinkling: first at step {} ({} of {} triangles wrinkled or slack, under the \
             relaxed energy)",
            p.step,
            p.wrinkled,
            w.triangles
        ),
        Some(p) => out!(
            "wrinkling: first at step {} ({} of {} triangles have a negative principal \
             tension: a membrane cannot carry compression, the model is not valid there)",
            p.step,
            p.wrinkled,
            w.triangles
        ),
    }
    let jumped = report
        .warnings
        .iter()
        .any(|m| m.contains("could not be localised"));
    if w.relaxed && jumped && w.width > 0.0 {
        out!(
            "note: with the switching width {} the relaxed energy is twice differentiable, but \
             an eigenvalue may still change within a part of a step too short to resolve \
             (docs/theory.md §2.9): a smaller `max-step` in [analysis] may localise the index \
             changes above",
            memstab::text::num(w.width)
        );
    } else if w.relaxed && jumped {
        out!(
            "note: under the relaxed energy the tangent jumps where a triangle turns taut, \
             wrinkled or slack, so an eigenvalue may jump through zero there (docs/theory.md \
             §2.9): the index changes above that could not be localised may be such jumps; \
             a `wrinkling-width` in [material] smooths the switching into crossings"
        );
    }
}

/// The refinement's lines of the summary ([`memstab::results::refine::summary`]).
fn print_refinement(r: &Refinement) {
    for line in memstab::results::refine::summary(r) {
        out!("{line}");
    }
}

/// Six significant digits.
fn sig_digits6(x: f64) -> String {
    sig_digits(x, 6)
}
