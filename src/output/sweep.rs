//! A sweep's collected table ([`SweepTable`]): `collected.csv` (a row per turning or critical
//! point of every finished run and per end of a pair of cusps of a `cusp-curve` run, the
//! swept values as columns), `collected_runs.csv` (a row per run with its status) and
//! `collected.svg` (the turning and critical points' control values against a swept value,
//! one colour per irrep and wave number, the caption naming the runs' meshes).

use super::csv::quote;
use super::figure::{self, Line, Mark, Plot, Symbol};
use super::svg::{xml_chars, PALETTE};
use super::{write_whole, Num, OutputError};
use crate::results::sweep::{SweepPoint, SweepPointKind, SweepTable};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The collected points' file.
pub const COLLECTED_CSV: &str = "collected.csv";
/// The runs' statuses.
pub const COLLECTED_RUNS_CSV: &str = "collected_runs.csv";
/// The figure.
pub const COLLECTED_SVG: &str = "collected.svg";

/// The swept key a figure of `table` is drawn against: `wanted` if given (it must be a key
/// whose every value is a number), else the first key whose values are numbers and not all
/// equal; `None` when no key qualifies (the figure is then drawn against the task number).
///
/// # Errors
/// One line naming `wanted` when it is not a numeric key of the sweep.
pub fn figure_axis(table: &SweepTable, wanted: Option<&str>) -> Result<Option<usize>, String> {
    let numeric = |k: usize| {
        table
            .runs
            .iter()
            .all(|r| r.values.get(k).is_some_and(|v| v.number.is_some()))
    };
    if let Some(w) = wanted {
        return match table.keys.iter().position(|k| k == w) {
            Some(k) if numeric(k) => Ok(Some(k)),
            Some(_) => Err(format!("--x '{w}': its values are not all numbers")),
            None => Err(format!(
                "--x '{w}': not a swept key (the sweep's keys: {})",
                table.keys.join(", ")
            )),
        };
    }
    Ok((0..table.keys.len()).find(|&k| {
        numeric(k) && {
            let mut v = table.runs.iter().filter_map(|r| r.values[k].number);
            let first = v.next();
            v.any(|x| Some(x) != first)
        }
    }))
}

/// Writes `collected.csv`, `collected_runs.csv` and `collected.svg` into `dir`, the figure
/// against key `axis` (see [`figure_axis`]); returns their paths.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite value (nothing is written), else as the other
/// writers.
pub fn write_sweep_table(
    dir: &Path,
    table: &SweepTable,
    axis: Option<usize>,
) -> Result<Vec<PathBuf>, OutputError> {
    let csv = dir.join(COLLECTED_CSV);
    if let Some(p) = table.points.iter().find(|p| !p.value.is_finite()) {
        return Err(OutputError::invalid(
            &csv,
            format!(
                "task {}: a {} point's value is {}",
                p.task, p.point, p.value
            ),
        ));
    }
    let svg_path = dir.join(COLLECTED_SVG);
    let svg = render(table, axis)
        .map_err(|e| OutputError::invalid(&svg_path, format!("plotting failed: {e}")))?;
    let cells = |task: usize| -> Vec<String> {
        let run = table.run(task);
        let mut c = vec![task.to_string(), quote(run.map_or("", |r| r.dir.as_str()))];
        c.extend(
            (0..table.keys.len())
                .map(|k| quote(run.and_then(|r| r.values.get(k)).map_or("", |v| &v.text))),
        );
        c
    };
    let keys: Vec<String> = table.keys.iter().map(|k| quote(k)).collect();
    write_whole(&csv, |w| {
        let mut header = vec!["task".to_string(), "dir".to_string()];
        header.extend(keys.iter().cloned());
        header.extend(
            [
                "point",
                "kind",
                "irrep",
                "multiplicity",
                "isotropy",
                "m",
                "step",
                "value",
                "valid",
                "flags",
            ]
            .map(str::to_string),
        );
        writeln!(w, "{}", header.join(","))?;
        for p in &table.points {
            let opt = |o: Option<String>| o.map(|s| quote(&s)).unwrap_or_default();
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{}",
                cells(p.task).join(","),
                p.point,
                quote(&p.kind),
                opt(p.irrep.clone()),
                opt(p.multiplicity.map(|m| m.to_string())),
                opt(p.isotropy.clone()),
                opt(p.m.map(|m| m.to_string())),
                opt(p.step.map(|s| s.to_string())),
                Num(p.value),
                p.valid,
                quote(&p.flags.join(";")),
            )?;
        }
        Ok(())
    })?;
    let runs = dir.join(COLLECTED_RUNS_CSV);
    write_whole(&runs, |w| {
        let mut header = vec!["task".to_string(), "dir".to_string()];
        header.extend(keys.iter().cloned());
        header.extend(["status", "stop", "message"].map(str::to_string));
        writeln!(w, "{}", header.join(","))?;
        for r in &table.runs {
            writeln!(
                w,
                "{},{},{},{}",
                cells(r.task).join(","),
                r.status,
                quote(r.stop.as_deref().unwrap_or("")),
                quote(r.message.as_deref().unwrap_or("")),
            )?;
        }
        Ok(())
    })?;
    write_whole(&svg_path, |w| w.write_all(xml_chars(&svg).as_bytes()))?;
    Ok(vec![csv, runs, svg_path])
}

/// The meshes of a sweep's finished runs for its caption: `mesh: disc, 1792 triangles, group
/// C7v` when all ran on one, `meshes: disc, 72 to 648 triangles, group C7v` for one generator
/// and group at several sizes, else each mesh.
fn meshes(table: &SweepTable) -> String {
    let mut all: Vec<&crate::results::MeshInfo> =
        table.runs.iter().filter_map(|r| r.mesh.as_ref()).collect();
    all.sort_by(|a, b| {
        (&a.generator, &a.group, a.elements).cmp(&(&b.generator, &b.group, b.elements))
    });
    all.dedup_by(|a, b| a.describe() == b.describe());
    match all.as_slice() {
        [] => "mesh: not read (no finished run)".to_string(),
        [one] => format!("mesh: {}", one.describe()),
        [first, .., last]
            if all
                .iter()
                .all(|m| m.generator == first.generator && m.group == first.group) =>
        {
            format!(
                "meshes: {}, {} to {} triangles, group {}",
                first.generator, first.elements, last.elements, first.group
            )
        }
        _ => {
            let each: Vec<String> = all.iter().map(|m| m.describe()).collect();
            format!("meshes: {}", each.join("; "))
        }
    }
}

/// The points the figure draws: the turning and critical points, whose values are the
/// control's.
fn plotted(table: &SweepTable) -> impl Iterator<Item = &SweepPoint> {
    table
        .points
        .iter()
        .filter(|p| p.point != SweepPointKind::CuspEnd)
}

/// A point's legend label: the irrep and wave number of a critical point, `maximum`/`minimum`
/// of a turning point.
fn label(p: &SweepPoint) -> String {
    match p.point {
        SweepPointKind::Turning => format!("{} (turning)", p.kind),
        SweepPointKind::CuspEnd => format!("{} (cusp end)", p.kind),
        SweepPointKind::Critical => {
            let irrep = p.irrep.as_deref().unwrap_or("?");
            match p.m {
                Some(m) => format!("{irrep}, m = {m}"),
                None => irrep.to_string(),
            }
        }
    }
}

/// A series of the figure: its label's number, the values of the other keys, the rank of
/// its points among their runs' points of that label; its points are (x, y, valid).
type SeriesKey = (usize, String, usize);

/// The points' values against the swept key `axis` (the task number without one): a series
/// per label, per values of the other keys and per rank of the point among the run's points
/// of that label, joined by a line in the order of the axis; flagged points hollow.
fn render(table: &SweepTable, axis: Option<usize>) -> Result<String, Box<dyn std::error::Error>> {
    let x_of = |task: usize| -> f64 {
        match axis {
            Some(k) => table
                .run(task)
                .and_then(|r| r.values[k].number)
                .unwrap_or(f64::NAN),
            None => task as f64,
        }
    };
    let others = |task: usize| -> String {
        table.run(task).map_or(String::new(), |r| {
            r.values
                .iter()
                .enumerate()
                .filter(|(k, _)| Some(*k) != axis)
                .map(|(_, v)| v.text.clone())
                .collect::<Vec<_>>()
                .join(",")
        })
    };
    let labels: Vec<String> = {
        let mut l: Vec<String> = plotted(table).map(label).collect();
        l.sort();
        l.dedup();
        l
    };
    let mut series: BTreeMap<SeriesKey, Vec<(f64, f64, bool)>> = BTreeMap::new();
    let mut rank: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    // A cusp end's value is its third parameter, not the control of the figure's axis.
    for p in plotted(table) {
        let l = labels.iter().position(|l| *l == label(p)).unwrap_or(0);
        let r = rank.entry((p.task, l)).or_insert(0);
        series
            .entry((l, others(p.task), *r))
            .or_default()
            .push((x_of(p.task), p.value, p.valid));
        *r += 1;
    }
    let x_title = axis.map_or("task", |k| table.keys[k].as_str());
    let y_title = table.control.as_deref().unwrap_or("control");
    let mut plot = Plot::new(
        format!("{}: critical and turning values", table.name),
        format!(
            "sweep {} · {} runs · {}",
            table.name,
            table.runs.len(),
            meshes(table)
        ),
        x_title,
        y_title,
    );
    for ((l, _, _), points) in &mut series {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let colour = PALETTE[*l % PALETTE.len()];
        plot.lines.push(Line::new(
            points.iter().map(|p| (p.0, p.1)).collect(),
            colour,
            1,
            None,
        ));
        for &(x, y, valid) in points.iter() {
            let (symbol, kind) = if valid {
                (Symbol::Disc(colour), labels[*l].clone())
            } else {
                (Symbol::Ring(colour), format!("{} (flagged)", labels[*l]))
            };
            plot.marks.push(Mark {
                at: (x, y),
                symbol,
                kind,
                label: String::new(),
            });
        }
    }
    let (svg, layout) = figure::render(&plot)?;
    Ok(figure::finish(&svg, &layout))
}
