//! `diagram.svg`: the bifurcation diagram of a run with branches — the path and every branch
//! in one picture, the control against the signed asymmetry (the RMS of the part of the state
//! outside the scene group's fixed-point space, signed by the branch's half: 0 on the path).
//! Stable stretches are solid, unstable ones dashed; the path is black, each branch is
//! coloured by its isotropy subgroup's class (one legend entry per class); critical points
//! are crosses labelled with their kind and irrep.

use super::svg::{padded, place_marker_labels, short, PALETTE};
use super::{write_whole, OutputError};
use plotters::prelude::*;
use std::error::Error;
use std::path::{Path, PathBuf};

/// One line of the diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramLine {
    /// The legend entry it belongs to: the isotropy class (`C1v`, `D5d`, …) or `path (G)`.
    pub class: String,
    /// True for the path the branches leave (drawn black).
    pub path: bool,
    /// (control, signed asymmetry) of every point.
    pub points: Vec<(f64, f64)>,
    /// Stability of every point: `Some(true)` for index 0, `None` where not known (the
    /// critical point a branch leaves); a stretch takes its second point's.
    pub stable: Vec<Option<bool>>,
}

/// A labelled critical point.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramMark {
    /// Control.
    pub x: f64,
    /// Signed asymmetry.
    pub y: f64,
    /// `double E1`, `simple A2`, `limit A1` …
    pub label: String,
}

/// What `diagram.svg` shows.
#[derive(Debug, Clone, PartialEq)]
pub struct BifurcationDiagram {
    /// The title.
    pub title: String,
    /// The control's name (the x axis).
    pub control: String,
    /// The path first, then the branches.
    pub lines: Vec<DiagramLine>,
    /// The critical points.
    pub marks: Vec<DiagramMark>,
    /// The y axis' title ([`ASYMMETRY_AXIS`] for branches).
    pub y_axis: String,
    /// The file's name in its directory (`diagram.svg` for branches).
    pub file: String,
}

/// The y-axis title of the bifurcation diagram.
pub const ASYMMETRY_AXIS: &str = "asymmetry (RMS of u outside Fix(G), signed by the half)";

/// Writes the diagram into `dir` (as [`BifurcationDiagram::file`]) and returns its path.
///
/// # Errors
/// [`OutputError::Invalid`] if a value is not finite or a line's stability does not match its
/// points (nothing is written); [`OutputError::NoDirectory`] / [`OutputError::Io`] if the file
/// cannot be written.
pub fn write_bifurcation_diagram(
    dir: &Path,
    diagram: &BifurcationDiagram,
) -> Result<PathBuf, OutputError> {
    let path = dir.join(&diagram.file);
    for (k, l) in diagram.lines.iter().enumerate() {
        if l.stable.len() != l.points.len() {
            return Err(OutputError::invalid(
                &path,
                format!(
                    "line {k} ({}) has {} points and {} stability flags",
                    l.class,
                    l.points.len(),
                    l.stable.len()
                ),
            ));
        }
        if let Some((i, p)) = l
            .points
            .iter()
            .enumerate()
            .find(|(_, p)| !(p.0.is_finite() && p.1.is_finite()))
        {
            return Err(OutputError::invalid(
                &path,
                format!(
                    "line {k} ({}), point {i}: ({}, {}) is not finite",
                    l.class, p.0, p.1
                ),
            ));
        }
    }
    if let Some(m) = diagram
        .marks
        .iter()
        .find(|m| !(m.x.is_finite() && m.y.is_finite()))
    {
        return Err(OutputError::invalid(
            &path,
            format!(
                "critical point {}: ({}, {}) is not finite",
                m.label, m.x, m.y
            ),
        ));
    }
    let svg = render(diagram)
        .map_err(|e| OutputError::invalid(&path, format!("plotting failed: {e}")))?;
    write_whole(&path, |w| w.write_all(svg.as_bytes()))?;
    Ok(path)
}

/// The isotropy classes of the branches, in order of first appearance (their colours).
fn classes(diagram: &BifurcationDiagram) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for l in diagram.lines.iter().filter(|l| !l.path) {
        if !out.contains(&l.class) {
            out.push(l.class.clone());
        }
    }
    out
}

fn render(diagram: &BifurcationDiagram) -> Result<String, Box<dyn Error>> {
    let all = || {
        diagram
            .lines
            .iter()
            .flat_map(|l| l.points.iter().copied())
            .chain(diagram.marks.iter().map(|m| (m.x, m.y)))
    };
    let xr = padded(all().map(|p| p.0));
    let yr = padded(all().map(|p| p.1).chain(std::iter::once(0.0)));
    let classes = classes(diagram);
    let colour = |class: &str| {
        classes
            .iter()
            .position(|c| c == class)
            .map_or(BLACK, |k| PALETTE[k % PALETTE.len()])
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 650)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(diagram.title.as_str(), ("sans-serif", 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(xr, yr)?;
        chart
            .configure_mesh()
            .x_desc(diagram.control.as_str())
            .y_desc(diagram.y_axis.as_str())
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        let mut legend_done: Vec<String> = Vec::new();
        for l in &diagram.lines {
            let c = if l.path { BLACK } else { colour(&l.class) };
            let width = if l.path { 2 } else { 3 };
            // Stretches of one stability drawn whole, so that a dash pattern runs across
            // short steps instead of restarting (and looking solid) at every point.
            let mut runs: Vec<(bool, Vec<(f64, f64)>)> = Vec::new();
            for (k, w) in l.points.windows(2).enumerate() {
                let stable = l.stable[k + 1].or(l.stable[k]).unwrap_or(true);
                match runs.last_mut() {
                    Some((s, pts)) if *s == stable => pts.push(w[1]),
                    _ => runs.push((stable, vec![w[0], w[1]])),
                }
            }
            for (stable, pts) in runs {
                let pts = pts.into_iter();
                let series = if stable {
                    chart.draw_series(LineSeries::new(pts, c.stroke_width(width)))?
                } else {
                    chart.draw_series(DashedLineSeries::new(pts, 7, 5, c.stroke_width(width)))?
                };
                if !legend_done.contains(&l.class) {
                    legend_done.push(l.class.clone());
                    series.label(l.class.clone()).legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], c.stroke_width(width))
                    });
                }
            }
        }
        let labels: Vec<String> = diagram
            .marks
            .iter()
            .map(|m| format!("{} ({})", m.label, short(m.x)))
            .collect();
        let wanted: Vec<(f64, f64, usize, bool)> = diagram
            .marks
            .iter()
            .zip(&labels)
            .map(|(m, l)| {
                let (x, y) = chart.backend_coord(&(m.x, m.y));
                (f64::from(x), f64::from(y), l.chars().count(), false)
            })
            .collect();
        let offsets = place_marker_labels(&wanted);
        for ((m, label), &at) in diagram.marks.iter().zip(labels).zip(&offsets) {
            let font = ("sans-serif", 13).into_font().color(&BLACK);
            chart.draw_series(std::iter::once(
                EmptyElement::at((m.x, m.y))
                    + Cross::new((0, 0), 6, BLACK.stroke_width(2))
                    + Text::new(label, at, font),
            ))?;
        }
        // The line styles, as legend entries without a line of their own.
        let grey = RGBColor(90, 90, 90);
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
            .label("stable: solid")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey.stroke_width(2)));
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
            .label("unstable: dashed")
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new([(0, 0), (7, 0)], grey.stroke_width(2))
                    + PathElement::new([(12, 0), (19, 0)], grey.stroke_width(2))
            });
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        root.present()?;
    }
    Ok(svg)
}
