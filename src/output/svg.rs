//! `path.svg`: the path diagram — two chosen quantities of every path point as a polyline,
//! with turning points (and, later, critical points) marked and labelled, and optionally the
//! stable and unstable stretches of the path drawn differently.
//!
//! Rendered with plotters' SVG backend, built without its `ttf` and `ab_glyph` features: text
//! is written as SVG `<text>` elements that the viewer renders with its own fonts, and plotters
//! only estimates text extents for the layout, so no font file is read or needed.

use super::{check_finite, write_whole, OutputError};
use crate::report::{PathReport, TurningRow};
use plotters::prelude::*;
use std::error::Error;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// What a [`Marker`] marks; decides its symbol and colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerKind {
    /// A maximum of the control (a limit point): red disc, label above.
    Maximum,
    /// A minimum of the control: red disc, label below.
    Minimum,
    /// A bifurcation point: black cross.
    Bifurcation,
    /// Anything else: black circle.
    Other,
}

/// A labelled point of the diagram, given by all its parameters and measures (like a
/// [`PathRow`](crate::report::PathRow)), so it is placed whatever the axes are.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Parameter values, in the order of [`PathReport::parameters`].
    pub parameters: Vec<f64>,
    /// Measure values, in the order of [`PathReport::measures`].
    pub measures: Vec<f64>,
    /// The text written next to the point.
    pub label: String,
    /// Symbol and colour.
    pub kind: MarkerKind,
}

impl Marker {
    /// The marker of a turning point of the control, labelled like `max p = 1.3551`.
    pub fn turning(report: &PathReport, t: &TurningRow) -> Self {
        let kind = if t.kind == "minimum" {
            MarkerKind::Minimum
        } else {
            MarkerKind::Maximum
        };
        let word = if kind == MarkerKind::Minimum {
            "min"
        } else {
            "max"
        };
        let value = report
            .parameters
            .iter()
            .position(|p| *p == report.control)
            .and_then(|i| t.parameters.get(i));
        let label = match value {
            Some(v) => format!("{word} {} = {}", report.control, short(*v)),
            None => format!("{word} {}", report.control),
        };
        Self {
            parameters: t.parameters.clone(),
            measures: t.measures.clone(),
            label,
            kind,
        }
    }

    /// A marker at path row `row` (an index into [`PathReport::rows`]); `None` if there is no
    /// such row.
    pub fn at_row(
        report: &PathReport,
        row: usize,
        label: impl Into<String>,
        kind: MarkerKind,
    ) -> Option<Self> {
        let r = report.rows.get(row)?;
        Some(Self {
            parameters: r.parameters.clone(),
            measures: r.measures.clone(),
            label: label.into(),
            kind,
        })
    }
}

/// A stretch of the path, rows `first..=last` (indices into [`PathReport::rows`]), known to be
/// stable (drawn solid blue) or unstable (dashed red).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// First row of the stretch.
    pub first: usize,
    /// Last row of the stretch (inclusive).
    pub last: usize,
    /// True if the equilibria on it are stable.
    pub stable: bool,
}

/// What to draw: axes, extra markers, stability segments, file name and size.
///
/// `Diagram::new("stretch", "p")` draws the path in blue with the report's turning points;
/// [`Diagram::segments`] and [`Diagram::markers`] add stability and critical points.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagram {
    /// Quantity on the horizontal axis: a parameter or measure name.
    pub x: String,
    /// Quantity on the vertical axis: a parameter or measure name.
    pub y: String,
    /// Stable and unstable stretches; rows outside every segment are drawn in grey (when
    /// there are no segments, the whole path is drawn in blue).
    pub segments: Vec<Segment>,
    /// Markers drawn in addition to the turning points.
    pub markers: Vec<Marker>,
    /// Mark the report's turning points (default true).
    pub turning_points: bool,
    /// File name in the output directory (default `path.svg`).
    pub file: String,
    /// Width and height in pixels (default 800 × 600).
    pub size: (u32, u32),
}

impl Diagram {
    /// `y` against `x`, turning points marked, into `path.svg`, 800 × 600.
    pub fn new(x: impl Into<String>, y: impl Into<String>) -> Self {
        Self {
            x: x.into(),
            y: y.into(),
            segments: Vec::new(),
            markers: Vec::new(),
            turning_points: true,
            file: "path.svg".to_string(),
            size: (800, 600),
        }
    }

    /// With stability segments.
    #[must_use]
    pub fn segments(mut self, segments: Vec<Segment>) -> Self {
        self.segments = segments;
        self
    }

    /// With extra markers.
    #[must_use]
    pub fn markers(mut self, markers: Vec<Marker>) -> Self {
        self.markers = markers;
        self
    }

    /// Into another file of the output directory.
    #[must_use]
    pub fn file(mut self, file: impl Into<String>) -> Self {
        self.file = file.into();
        self
    }
}

/// The default axes of the diagram, `(x, y)`: x is the measure `stretch` if the report has it,
/// else `max_displacement`, else its first measure (else the control); y is the control
/// parameter. For a balloon this is the classic pressure–stretch curve.
pub fn default_axes(report: &PathReport) -> (String, String) {
    let has = |name: &str| report.measures.iter().any(|m| m == name);
    let x = ["stretch", "max_displacement"]
        .into_iter()
        .find(|n| has(n))
        .map(str::to_string)
        .or_else(|| report.measures.first().cloned())
        .unwrap_or_else(|| report.control.clone());
    (x, report.control.clone())
}

/// Writes `dir/path.svg`: `y` against `x` (parameter or measure names, see [`default_axes`])
/// with the report's turning points marked; returns the file's path. Same as
/// [`write_diagram_with`] with [`Diagram::new`]`(x, y)`.
///
/// # Errors
/// As [`write_diagram_with`].
pub fn write_diagram(
    dir: &Path,
    report: &PathReport,
    x: &str,
    y: &str,
) -> Result<PathBuf, OutputError> {
    write_diagram_with(dir, report, &Diagram::new(x, y))
}

/// Writes the diagram described by `diagram` into `dir/<diagram.file>` and returns its path.
///
/// The SVG shows the title `<scene> (group <group>)`, axes titled with the two names, the path
/// as a polyline, every marker as a symbol with its label, and a legend when there are
/// segments. It is rendered into memory and written whole.
///
/// # Errors
/// [`OutputError::Invalid`] if an axis names no parameter or measure, a segment or marker does
/// not fit the report, or a value is not finite (nothing is written);
/// [`OutputError::NoDirectory`] / [`OutputError::Io`] if the file cannot be written.
pub fn write_diagram_with(
    dir: &Path,
    report: &PathReport,
    diagram: &Diagram,
) -> Result<PathBuf, OutputError> {
    let path = dir.join(&diagram.file);
    let invalid = |m: String| OutputError::invalid(&path, m);
    check_finite(&path, report)?;
    let xa = Axis::find(report, &diagram.x).ok_or_else(|| invalid(unknown(report, &diagram.x)))?;
    let ya = Axis::find(report, &diagram.y).ok_or_else(|| invalid(unknown(report, &diagram.y)))?;
    let n = report.rows.len();
    if let Some(s) = diagram
        .segments
        .iter()
        .find(|s| s.first > s.last || s.last >= n)
    {
        return Err(invalid(format!(
            "segment of rows {}..={} does not fit a path of {n} rows",
            s.first, s.last
        )));
    }
    let mut markers: Vec<Marker> = Vec::new();
    if diagram.turning_points {
        markers.extend(
            report
                .turning_points
                .iter()
                .map(|t| Marker::turning(report, t)),
        );
    }
    markers.extend(diagram.markers.iter().cloned());
    let mut points = Vec::with_capacity(markers.len());
    for m in &markers {
        match (
            xa.at(&m.parameters, &m.measures),
            ya.at(&m.parameters, &m.measures),
        ) {
            (Some(x), Some(y)) if x.is_finite() && y.is_finite() => points.push((x, y)),
            _ => {
                return Err(invalid(format!(
                    "marker {:?} has no finite {} and {}",
                    m.label, diagram.x, diagram.y
                )))
            }
        }
    }
    let path_points: Vec<(f64, f64)> = report
        .rows
        .iter()
        .map(|r| {
            let x = xa.at(&r.parameters, &r.measures).unwrap_or(f64::NAN);
            let y = ya.at(&r.parameters, &r.measures).unwrap_or(f64::NAN);
            (x, y)
        })
        .collect();

    let svg = render(report, diagram, &path_points, &markers, &points)
        .map_err(|e| invalid(format!("plotting failed: {e}")))?;
    write_whole(&path, |w| w.write_all(svg.as_bytes()))?;
    Ok(path)
}

/// Draws the diagram into an SVG string.
fn render(
    report: &PathReport,
    diagram: &Diagram,
    path: &[(f64, f64)],
    markers: &[Marker],
    marker_points: &[(f64, f64)],
) -> Result<String, Box<dyn Error>> {
    let all = || path.iter().chain(marker_points);
    let xr = padded(all().map(|p| p.0));
    let yr = padded(all().map(|p| p.1));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, diagram.size).into_drawing_area();
        root.fill(&WHITE)?;
        let title = format!("{} (group {})", report.scene, report.group);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(xr, yr)?;
        chart
            .configure_mesh()
            .x_desc(diagram.x.as_str())
            .y_desc(diagram.y.as_str())
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;

        let blue = RGBColor(31, 87, 180);
        let red = RGBColor(200, 30, 30);
        let base = if diagram.segments.is_empty() {
            blue.stroke_width(2)
        } else {
            RGBColor(170, 170, 170).stroke_width(1)
        };
        chart.draw_series(LineSeries::new(path.iter().copied(), base))?;

        let (mut stable_legend, mut unstable_legend) = (false, false);
        for s in &diagram.segments {
            let pts = path[s.first..=s.last].iter().copied();
            if s.stable {
                let series = chart.draw_series(LineSeries::new(pts, blue.stroke_width(3)))?;
                if !std::mem::replace(&mut stable_legend, true) {
                    series.label("stable").legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], blue.stroke_width(3))
                    });
                }
            } else {
                let style = red.stroke_width(3);
                let series = chart.draw_series(DashedLineSeries::new(pts, 8, 5, style))?;
                if !std::mem::replace(&mut unstable_legend, true) {
                    series.label("unstable").legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], red.stroke_width(3))
                    });
                }
            }
        }
        if stable_legend || unstable_legend {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .draw()?;
        }

        for (m, &(x, y)) in markers.iter().zip(marker_points) {
            let text_at = if m.kind == MarkerKind::Minimum {
                (8, 6)
            } else {
                (8, -22)
            };
            let font = ("sans-serif", 15).into_font().color(&BLACK);
            let label = Text::new(m.label.clone(), text_at, font);
            match m.kind {
                MarkerKind::Maximum | MarkerKind::Minimum => chart.draw_series(std::iter::once(
                    EmptyElement::at((x, y)) + Circle::new((0, 0), 5, red.filled()) + label,
                ))?,
                MarkerKind::Bifurcation => chart.draw_series(std::iter::once(
                    EmptyElement::at((x, y)) + Cross::new((0, 0), 6, BLACK.stroke_width(2)) + label,
                ))?,
                MarkerKind::Other => chart.draw_series(std::iter::once(
                    EmptyElement::at((x, y))
                        + Circle::new((0, 0), 5, BLACK.stroke_width(2))
                        + label,
                ))?,
            };
        }
        root.present()?;
    }
    Ok(svg)
}

/// A quantity of the report: a parameter or a measure, by index.
#[derive(Debug, Clone, Copy)]
enum Axis {
    Parameter(usize),
    Measure(usize),
}

impl Axis {
    /// The parameter named `name`, else the measure.
    fn find(report: &PathReport, name: &str) -> Option<Self> {
        let p = report.parameters.iter().position(|p| p == name);
        let m = report.measures.iter().position(|m| m == name);
        p.map(Axis::Parameter).or(m.map(Axis::Measure))
    }

    /// Its value at a point with these parameters and measures.
    fn at(self, parameters: &[f64], measures: &[f64]) -> Option<f64> {
        match self {
            Axis::Parameter(i) => parameters.get(i).copied(),
            Axis::Measure(i) => measures.get(i).copied(),
        }
    }
}

/// The message for an axis name that is neither a parameter nor a measure.
fn unknown(report: &PathReport, name: &str) -> String {
    format!(
        "no parameter or measure is named {name:?} (parameters: {}; measures: {})",
        report.parameters.join(", "),
        report.measures.join(", ")
    )
}

/// The range of `values` widened by 5 % on each side (a single value: ±5 % of it, or ±1 at
/// zero; no values: 0..1).
fn padded(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo > hi {
        return 0.0..1.0;
    }
    let span = hi - lo;
    let pad = if span > 1e-12 * hi.abs().max(lo.abs()) {
        0.05 * span
    } else if hi != 0.0 {
        0.05 * hi.abs()
    } else {
        1.0
    };
    (lo - pad)..(hi + pad)
}

/// `x` with five significant digits (`1.3551`, `0.0012346`, `12346`, `1.2346e7`).
fn short(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{x}");
    }
    let e = a.log10().floor() as i32;
    if (-3..5).contains(&e) {
        let decimals = (4 - e).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.4e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers() {
        assert_eq!(short(1.3551069), "1.3551");
        assert_eq!(short(1.1487477), "1.1487");
        assert_eq!(short(0.00123456), "0.0012346");
        assert_eq!(short(12345.6), "12346");
        assert_eq!(short(123456.7), "1.2346e5");
        assert_eq!(short(-2.0), "-2.0000");
    }

    #[test]
    fn padded_ranges() {
        assert_eq!(padded([1.0, 3.0].into_iter()), 0.9..3.1);
        assert_eq!(padded(std::iter::empty()), 0.0..1.0);
        assert_eq!(padded([0.0].into_iter()), -1.0..1.0);
        let r = padded([2.0].into_iter());
        assert!(r.start < 2.0 && r.end > 2.0);
    }
}
