//! `curve.csv`, `curve.json` and `curve.svg`: a critical curve ([`CurveReport`]).

use super::figure::{self, finish, Entry, Layout, Line, Mark, Plot, Sample, Symbol};
use super::scales::Scales;
use super::svg::{xml_chars, AxisScale};
use super::{write_whole, Num, OutputError};
use crate::results::{CriticalKind, CurveEventKind, CurveReport, PathReport};
use plotters::style::colors::BLACK;
use plotters::style::RGBColor;
use std::io;
use std::path::{Path, PathBuf};

/// Refuses a curve with a non-finite number, naming the row (or event) and the column.
fn check_finite(path: &Path, curve: &CurveReport) -> Result<(), OutputError> {
    let names = curve.parameters.iter().chain(&curve.measures);
    for row in &curve.rows {
        let values = row.parameters.iter().chain(&row.measures);
        let extra = [
            ("critical_eigenvalue", row.critical_eigenvalue),
            ("second_eigenvalue", row.second_eigenvalue),
            ("arclength", row.arclength),
        ];
        let bad = names
            .clone()
            .map(String::as_str)
            .zip(values.copied())
            .chain(extra)
            .find(|(_, v)| !v.is_finite());
        if let Some((name, v)) = bad {
            return Err(OutputError::invalid(
                path,
                format!("curve point {}: {name} is {v} (not finite)", row.step),
            ));
        }
    }
    for e in &curve.events {
        if let Some((name, v)) = names
            .clone()
            .zip(e.parameters.iter().chain(&e.measures))
            .find(|(_, v)| !v.is_finite())
        {
            return Err(OutputError::invalid(
                path,
                format!("curve event {}: {name} is {v} (not finite)", e.kind),
            ));
        }
    }
    Ok(())
}

/// Writes `curve.csv`, `curve.json`, `curve.svg` and `curve.png` (the same figure as an image)
/// into `dir`; returns their paths.
///
/// `curve.csv` has a row per curve point: `step,arclength,<each parameter>,<each
/// measure>,critical_eigenvalue,second_eigenvalue,irrep,iterations` (the eigenvalues of the
/// critical block nearest zero, relative to max|K_ij|). `curve.json` is the whole report,
/// with the events (start, cusps, folds, end). `curve.svg` plots the second parameter
/// against the control with the events marked (hilltops and irrep changes with the other
/// irrep) and, given the path that found the curve ([`write_curve_with`]), that path across
/// it by its index.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite value (nothing is written), else as the other
/// writers.
pub fn write_curve(dir: &Path, curve: &CurveReport) -> Result<Vec<PathBuf>, OutputError> {
    write_curve_with(dir, curve, None, &Scales::default(), "")
}

/// As [`write_curve`], `curve.svg`'s axes titled and scaled by `scales` (the control's and
/// the second parameter's dimensionless groups, where the scene fixes them) and `caption`
/// (the scene and its mesh) written below the plot. `path`, the path in the control that found
/// the curve's first point, shows which side of the curve is stable where it is known: the
/// path is drawn across the curve by its index (stable solid, unstable dashed, a legend entry
/// for each index drawn inside the axes, which span the curve), its states either side of
/// that point are ringed and labelled with their index, and a note says so when the path's
/// index was not computed.
///
/// # Errors
/// As [`write_curve`].
pub fn write_curve_with(
    dir: &Path,
    curve: &CurveReport,
    path: Option<&PathReport>,
    scales: &Scales,
    caption: &str,
) -> Result<Vec<PathBuf>, OutputError> {
    let csv = dir.join("curve.csv");
    check_finite(&csv, curve)?;
    let json = dir.join("curve.json");
    let svg_path = dir.join("curve.svg");
    let column = |name: &str| curve.parameters.iter().position(|p| p == name);
    let (Some(c), Some(s)) = (column(&curve.control), column(&curve.second)) else {
        return Err(OutputError::invalid(
            &svg_path,
            "the control or the second parameter is not a parameter of the curve".to_string(),
        ));
    };
    if curve.rows.is_empty() {
        return Err(OutputError::invalid(
            &csv,
            "the curve has no points".to_string(),
        ));
    }
    let axes = (
        scales.or_name(&curve.control),
        scales.or_name(&curve.second),
    );
    let sides = path.map(|p| sides(curve, p, c, s)).unwrap_or_default();
    let across = path.map(|p| across(curve, p, c, s)).unwrap_or_default();
    let (svg, mut layout) = render(curve, (c, s), (&sides, &across), &axes, caption)
        .map_err(|e| OutputError::invalid(&svg_path, format!("plotting failed: {e}")))?;
    layout.scales = vec![
        figure::QuantityScale::new(&curve.control, &axes.0),
        figure::QuantityScale::new(&curve.second, &axes.1),
    ];
    let svg = finish(&svg, &layout);
    write_whole(&csv, |w| {
        let header: Vec<&str> = ["step", "arclength"]
            .into_iter()
            .chain(curve.parameters.iter().map(String::as_str))
            .chain(curve.measures.iter().map(String::as_str))
            .chain([
                "critical_eigenvalue",
                "second_eigenvalue",
                "irrep",
                "iterations",
            ])
            .collect();
        writeln!(w, "{}", header.join(","))?;
        for r in &curve.rows {
            write!(w, "{},{}", r.step, Num(r.arclength))?;
            for &v in r.parameters.iter().chain(&r.measures) {
                write!(w, ",{}", Num(v))?;
            }
            writeln!(
                w,
                ",{},{},{},{}",
                Num(r.critical_eigenvalue),
                Num(r.second_eigenvalue),
                curve.irrep,
                r.iterations
            )?;
        }
        Ok(())
    })?;
    write_whole(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, curve).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    write_whole(&svg_path, |w| w.write_all(xml_chars(&svg).as_bytes()))?;
    let png = super::write_png_beside(&svg_path)?;
    Ok(vec![csv, json, svg_path, png])
}

/// A state of the path next to the curve's first point: (control, second) and its index.
type Side = ((f64, f64), Option<usize>);

/// The path's states either side of the curve's first point (its last critical point in the
/// curve's irrep lies between path steps k and k + 1): the rows k and k + 1 that exist, in
/// (control, second). Where the path crosses a bifurcation curve the two lie on either side of
/// it; where it turns at a limit curve both lie on the side the path came from.
fn sides(curve: &CurveReport, path: &PathReport, c: usize, s: usize) -> Vec<Side> {
    let (Some(pc), Some(ps)) = (
        path.parameters
            .iter()
            .position(|p| *p == curve.parameters[c]),
        path.parameters
            .iter()
            .position(|p| *p == curve.parameters[s]),
    ) else {
        return Vec::new();
    };
    let Some(cp) = path.critical.iter().rev().find(|p| p.irrep == curve.irrep) else {
        return Vec::new();
    };
    let k = cp.after_step;
    path.rows
        .iter()
        .filter(|r| r.step == k || r.step == k + 1)
        .filter(|r| r.parameters[pc] != cp.parameters[pc] || r.parameters[ps] != cp.parameters[ps])
        .map(|r| ((r.parameters[pc], r.parameters[ps]), r.index))
        .collect()
}

/// A stretch of the path of one index: the index and its points in (control, second), joined
/// to the next row so that the line has no gaps.
type Run = (Option<usize>, Vec<(f64, f64)>);

/// The path's runs of one index in (control, second): drawn across the curve, they show which
/// side of it is stable (at a bifurcation curve the index changes as the path crosses; at a
/// limit curve the path turns back on its own line, stable one way and unstable the other).
/// None when the path's report lacks either parameter.
fn across(curve: &CurveReport, path: &PathReport, c: usize, s: usize) -> Vec<Run> {
    let column = |name: &str| path.parameters.iter().position(|p| p == name);
    let (Some(pc), Some(ps)) = (column(&curve.parameters[c]), column(&curve.parameters[s])) else {
        return Vec::new();
    };
    let q = |p: &[f64]| (p[pc], p[ps]);
    let mut runs: Vec<Run> = Vec::new();
    let mut push = |index: Option<usize>, from: (f64, f64), to: (f64, f64)| match runs.last_mut() {
        Some((i, pts)) if *i == index => pts.push(to),
        _ => runs.push((index, vec![from, to])),
    };
    for pair in path.rows.windows(2) {
        let (from, to) = (q(&pair[0].parameters), q(&pair[1].parameters));
        // Where the index changes at a critical point of the path, the stretch before it has
        // the one index and the stretch after it the other.
        let split = path
            .critical
            .iter()
            .find(|cp| cp.after_step == pair[0].step)
            .filter(|_| pair[0].index != pair[1].index);
        match split {
            Some(cp) => {
                let at = q(&cp.parameters);
                push(pair[0].index, from, at);
                push(pair[1].index, at, to);
            }
            None => push(pair[0].index, from, to),
        }
    }
    runs
}

/// The colour of a path state's index: blue stable, warmer with every negative eigenvalue,
/// grey not computed (as on the surface's figure).
fn side_colour(index: Option<usize>) -> RGBColor {
    super::surface::index_colour(index)
}

/// The second parameter (column `s`) against the control (column `c`), events marked, the
/// path's states `sides` next to the first point with their index.
fn render(
    curve: &CurveReport,
    (c, s): (usize, usize),
    (sides, across): (&[Side], &[Run]),
    (xs, ys): &(AxisScale, AxisScale),
    caption: &str,
) -> Result<(String, Layout), Box<dyn std::error::Error>> {
    let at = |p: &[f64]| (p[c] * xs.factor, p[s] * ys.factor);
    let title = format!("{} curve of {} ({})", curve.kind, curve.irrep, curve.second);
    let mut plot = Plot::new(title, caption, &xs.label, &ys.label);
    // The axes span the curve, its events and the path's states next to it: the path is cut
    // at them.
    let shown: Vec<(f64, f64)> = curve
        .rows
        .iter()
        .map(|r| at(&r.parameters))
        .chain(curve.events.iter().map(|e| at(&e.parameters)))
        .chain(
            sides
                .iter()
                .map(|&((x, y), _)| (x * xs.factor, y * ys.factor)),
        )
        .collect();
    plot.ranges = Some((
        figure::padded(shown.iter().map(|p| p.0)),
        figure::padded(shown.iter().map(|p| p.1)),
    ));
    plot.lines.push(
        Line::new(
            curve.rows.iter().map(|r| at(&r.parameters)).collect(),
            BLACK,
            2,
            None,
        )
        .kind(format!(
            "critical curve ({} in {})",
            curve.kind, curve.irrep
        )),
    );
    // The path across the curve: stable solid (drawn first and wider, so that an unstable
    // stretch back along the same line shows over it), unstable dashed.
    let held = across
        .first()
        .and_then(|(_, pts)| pts.first())
        .map(|p| super::svg::short(p.1));
    let mut runs: Vec<&Run> = across.iter().collect();
    runs.sort_by_key(|(i, _)| i.map_or(1, |i| usize::from(i > 0)));
    for (index, pts) in runs {
        let word = match index {
            Some(0) => "stable (index 0)".to_string(),
            Some(i) => format!("unstable (index {i})"),
            None => "index not computed".to_string(),
        };
        let kind = format!(
            "path in {} at {} = {}: {word}",
            curve.control,
            curve.second,
            held.clone().unwrap_or_default()
        );
        let width = if *index == Some(0) { 3 } else { 2 };
        let pts = pts
            .iter()
            .map(|&(x, y)| (x * xs.factor, y * ys.factor))
            .collect();
        plot.lines.push(
            Line::new(
                pts,
                side_colour(*index),
                width,
                super::surface::index_dash(*index),
            )
            .kind(kind),
        );
    }
    // The path's states next to the first point, ringed in the colour of their index.
    let mut known = false;
    for &((x, y), index) in sides {
        let colour = side_colour(index);
        let here = (x * xs.factor, y * ys.factor);
        let (kind, label) = match index {
            Some(0) => (
                format!("state of the path in {}: stable (index 0)", curve.control),
                "stable (index 0)".to_string(),
            ),
            Some(i) => (
                format!(
                    "state of the path in {}: unstable (index {i})",
                    curve.control
                ),
                format!("unstable (index {i})"),
            ),
            None => (
                format!("state of the path in {}: index not computed", curve.control),
                String::new(),
            ),
        };
        known |= index.is_some();
        plot.marks.push(Mark {
            at: here,
            symbol: Symbol::Ring(colour),
            kind,
            label,
        });
    }
    if known {
        if curve.kind == CriticalKind::LimitPoint {
            plot.legend.push(Entry::new(
                "at a limit curve the branch turns: both its states lie on one side",
                Sample::Note,
            ));
        }
    } else {
        plot.legend.push(Entry::new(
            "stability either side of the curve: not computed",
            Sample::Note,
        ));
    }
    for e in &curve.events {
        let (symbol, kind) = match e.kind {
            CurveEventKind::Cusp => (Symbol::Disc(RGBColor(200, 30, 30)), "cusp"),
            CurveEventKind::Fold => (Symbol::Disc(RGBColor(230, 130, 0)), "fold of the curve"),
            CurveEventKind::Hilltop => (Symbol::Square(RGBColor(20, 140, 60)), "hilltop"),
            CurveEventKind::IrrepChange => {
                (Symbol::Square(RGBColor(148, 103, 189)), "irrep change")
            }
            CurveEventKind::Start | CurveEventKind::End => {
                (Symbol::Ring(BLACK), "start or end of the curve")
            }
        };
        let label = match (&e.irrep, e.kind) {
            (Some(irrep), CurveEventKind::Hilltop | CurveEventKind::IrrepChange) => {
                format!("{} ({irrep})", e.kind)
            }
            _ => e.kind.to_string(),
        };
        plot.marks.push(Mark {
            at: at(&e.parameters),
            symbol,
            kind: kind.to_string(),
            label,
        });
    }
    figure::render(&plot)
}
