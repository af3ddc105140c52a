//! `path.svg`: the path diagram — two chosen quantities of every path point as a polyline,
//! with turning points (and, later, critical points) marked and labelled, and optionally the
//! stable and unstable stretches of the path drawn differently. For a linear-buckling sweep,
//! whose held state makes every measure constant, [`write_spectrum_diagram`] draws instead the
//! lowest eigenvalue of every irrep block against the control, with the critical points on the
//! zero line.
//!
//! Rendered with plotters' SVG backend, built without its `ttf` and `ab_glyph` features: text
//! is written as SVG `<text>` elements that the viewer renders with its own fonts, and plotters
//! only estimates text extents for the layout, so no font file is read or needed.

use super::{check_finite, write_whole, OutputError};
use crate::report::{PathReport, TurningRow};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
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
        let kind = if t.kind == crate::analysis::events::Extremum::Minimum {
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
    let svg = xml_chars(&svg);
    write_whole(&path, |w| w.write_all(svg.as_bytes()))?;
    Ok(path)
}

/// A chart of the diagrams' one style on `root`: the title above, white background already
/// filled by the caller, the axes over `xr` × `yr` with their titles and light grid lines.
pub(super) type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// Builds the [`Chart`] of the diagrams' style (caption, margins, axis titles, grid).
pub(super) fn chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: &str,
    x: &str,
    y: &str,
    xr: Range<f64>,
    yr: Range<f64>,
) -> Result<Chart<'a, 'b>, Box<dyn Error>> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(xr, yr)?;
    chart
        .configure_mesh()
        .x_desc(x)
        .y_desc(y)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    Ok(chart)
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
        let mut chart = chart(&root, &title, &diagram.x, &diagram.y, xr, yr)?;

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

/// Colours of the irreps' lines, in irrep order; past the last one they repeat, dashed.
pub(super) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of the spectrum diagram's zero line (dark grey, unlike the black axes).
pub const ZERO_LINE: RGBColor = RGBColor(64, 64, 64);

/// The y-axis title of the spectrum diagram.
pub const SPECTRUM_AXIS: &str = "lowest eigenvalue / max|K_ij|";

/// Writes `dir/path.svg` for a linear-buckling sweep (a report with [`Spectra`]): per irrep
/// block, its lowest eigenvalue relative to the tangent's scale (λ/‖K‖, as in
/// [`Spectra`]) against the control, one coloured line per irrep with a legend entry
/// `E1 (×2)`; a horizontal zero line; every critical point of the report as a cross in its
/// irrep's colour on the zero line, labelled by its kind and irrep like the path diagram's
/// markers (`double E1`, `symmetric A1`). The first critical point of an irrep is where its
/// line crosses zero; later ones in the same irrep are higher eigenvalues of the block
/// crossing, under a line that is already negative.
///
/// Blocks without eigenvalues (larger than the dense limit, where only the negative count is
/// computed, or empty) get no line — nothing non-finite is drawn — and a legend entry that
/// says so; samples where a block has no value break its line.
///
/// [`Spectra`]: crate::report::Spectra
///
/// # Errors
/// [`OutputError::Invalid`] if the report has no spectra, a number (of the report, its spectra
/// or a critical point's control) is not finite, or plotting fails — nothing is written;
/// [`OutputError::NoDirectory`] / [`OutputError::Io`] if the file cannot be written.
pub fn write_spectrum_diagram(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    let path = dir.join("path.svg");
    let invalid = |m: String| OutputError::invalid(&path, m);
    check_finite(&path, report)?;
    let spectra = &report.spectra;
    if spectra.is_empty() {
        return Err(invalid(
            "the report has no spectra to plot (only a linear-buckling run with a stability analysis records them)".into(),
        ));
    }
    let control = report.parameters.iter().position(|p| *p == report.control);
    let mut marks = Vec::with_capacity(report.critical.len());
    for cp in &report.critical {
        let x = control.and_then(|c| cp.parameters.get(c).copied());
        match x {
            Some(x) if x.is_finite() => marks.push(CriticalMark {
                x,
                label: format!("{} {}", cp.kind.short(), cp.irrep),
                irrep: spectra.irrep(&cp.irrep),
            }),
            _ => {
                return Err(invalid(format!(
                    "the critical point {} in {} has no finite {}",
                    cp.kind, cp.irrep, report.control
                )))
            }
        }
    }
    marks.sort_by(|a, b| a.x.total_cmp(&b.x));
    let curves: Vec<Vec<Vec<(f64, f64)>>> = (0..spectra.irreps.len())
        .map(|mu| {
            let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
            let mut open = false;
            for row in &spectra.rows {
                match row.lowest[mu] {
                    Some(v) if v.is_finite() => {
                        if !open {
                            runs.push(Vec::new());
                            open = true;
                        }
                        if let Some(run) = runs.last_mut() {
                            run.push((row.control, v));
                        }
                    }
                    _ => open = false,
                }
            }
            runs
        })
        .collect();
    let svg = render_spectra(report, &curves, &marks)
        .map_err(|e| invalid(format!("plotting failed: {e}")))?;
    let svg = xml_chars(&svg);
    write_whole(&path, |w| w.write_all(svg.as_bytes()))?;
    Ok(path)
}

/// A critical point on the spectrum diagram: its control value, label and irrep (index into
/// the spectra's irreps, for the colour).
struct CriticalMark {
    x: f64,
    label: String,
    irrep: Option<usize>,
}

/// Draws the spectrum diagram into an SVG string: `curves[mu]` are the runs of irrep `mu`'s
/// line, `marks` the critical points sorted by control value.
fn render_spectra(
    report: &PathReport,
    curves: &[Vec<Vec<(f64, f64)>>],
    marks: &[CriticalMark],
) -> Result<String, Box<dyn Error>> {
    let spectra = &report.spectra;
    let size = (800u32, 600u32);
    let points = || curves.iter().flatten().flatten();
    let xs = spectra.rows.iter().map(|r| r.control);
    let xr = padded(xs.chain(marks.iter().map(|m| m.x)));
    let yr = padded(points().map(|p| p.1).chain(std::iter::once(0.0)));
    // Room for the vertical labels of the critical points on either side of the zero line.
    let (plot_w, plot_h) = (
        f64::from(size.0 - 2 * 20 - 80),
        f64::from(size.1 - 2 * 20 - 90),
    );
    let px = plot_w / (xr.end - xr.start);
    let (labels, need) = place_labels(marks.iter().map(|m| (m.x * px, m.label.len())));
    let yr = headroom(yr, need.0 / plot_h, need.1 / plot_h);
    let colour = |mu: usize| PALETTE[mu % PALETTE.len()];
    let dashed = |mu: usize| mu >= PALETTE.len();
    let legend: Vec<String> = spectra
        .irreps
        .iter()
        .enumerate()
        .map(|(mu, irrep)| {
            let name = format!("{} (×{})", irrep.name, irrep.dim);
            if !curves[mu].is_empty() {
                return name;
            }
            let why = if irrep.size == 0 {
                "empty block".to_string()
            } else if irrep.eigenvalues {
                "no eigenvalue at any sample".to_string()
            } else {
                format!("{} columns, negative count only", irrep.size)
            };
            format!("{name}: not plotted ({why})")
        })
        .chain((!marks.is_empty()).then(|| "critical point".to_string()))
        .collect();
    // The legend's estimated size as fractions of the plot, to find a corner it fits in.
    let chars = legend.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    let legend_box = (
        (45.0 + chars as f64 * LEGEND_CHAR) / plot_w,
        (12.0 + legend.len() as f64 * 18.0) / plot_h,
    );
    // The lines, sampled between their points, and the critical points on the zero line.
    let dense = curves.iter().flatten().flat_map(|run| {
        run.windows(2).flat_map(|w| {
            (0..8).map(move |k| {
                let t = f64::from(k) / 8.0;
                (
                    w[0].0 + t * (w[1].0 - w[0].0),
                    w[0].1 + t * (w[1].1 - w[0].1),
                )
            })
        })
    });
    let occupied: Vec<(f64, f64)> = dense
        .chain(points().copied())
        .chain(marks.iter().map(|m| (m.x, 0.0)))
        .collect();
    let (legend_at, yr) = legend_place(&occupied, &xr, yr, legend_box);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let title = format!(
            "{} (group {}): lowest eigenvalue by irrep",
            report.scene, report.group
        );
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(xr.clone(), yr.clone())?;
        let y_span = yr.end - yr.start;
        let y_label = |v: &f64| tick(*v, y_span);
        let x_span = xr.end - xr.start;
        let x_label = |v: &f64| tick(*v, x_span);
        chart
            .configure_mesh()
            .x_desc(report.control.as_str())
            .y_desc(SPECTRUM_AXIS)
            .y_label_formatter(&y_label)
            .x_label_formatter(&x_label)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        chart.draw_series(LineSeries::new(
            [(xr.start, 0.0), (xr.end, 0.0)],
            ZERO_LINE.stroke_width(1),
        ))?;
        for (mu, (runs, name)) in curves.iter().zip(&legend).enumerate() {
            let c = colour(mu);
            if runs.is_empty() {
                chart
                    .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                    .label(name.clone())
                    .legend(|(x, y)| EmptyElement::at((x, y)));
                continue;
            }
            for (k, run) in runs.iter().enumerate() {
                let style = c.stroke_width(2);
                let series = if dashed(mu) {
                    chart.draw_series(DashedLineSeries::new(run.iter().copied(), 8, 4, style))?
                } else {
                    chart.draw_series(LineSeries::new(run.iter().copied(), style))?
                };
                if k == 0 {
                    series.label(name.clone()).legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], c.stroke_width(2))
                    });
                }
            }
        }
        if !marks.is_empty() {
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label("critical point")
                .legend(|(x, y)| Cross::new((x + 10, y), 5, BLACK.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .position(legend_at)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;

        for (m, &(up, start)) in marks.iter().zip(&labels) {
            let c = m.irrep.map_or(BLACK, colour);
            let (transform, offset) = if up {
                (FontTransform::Rotate270, (0, -start))
            } else {
                (FontTransform::Rotate90, (0, start))
            };
            let font = ("sans-serif", 13)
                .into_font()
                .transform(transform)
                .color(&c)
                .pos(Pos::new(HPos::Left, VPos::Center));
            chart.draw_series(std::iter::once(
                EmptyElement::at((m.x, 0.0))
                    + Cross::new((0, 0), 6, c.stroke_width(2))
                    + Text::new(m.label.clone(), offset, font),
            ))?;
        }
        root.present()?;
    }
    Ok(svg)
}

/// Pixels per character of a 14 px legend entry (an estimate).
const LEGEND_CHAR: f64 = 7.5;
/// Pixels per character of a 13 px label (an estimate: the viewer's font decides).
const LABEL_CHAR: f64 = 7.2;
/// Gap between the zero line and a label, and between stacked labels, in pixels.
const LABEL_GAP: f64 = 12.0;
/// Labels closer than this (pixels along the control) would overlap side by side.
const LABEL_WIDTH: f64 = 16.0;

/// Places the vertical labels of the critical points `(x in pixels, characters)`, sorted by
/// x: each goes above or below the zero line, into the lane where it can start nearest to the
/// line without overlapping an earlier label (labels less than [`LABEL_WIDTH`] apart stack
/// outwards; above on a tie). Returns per label (above?, pixels from the line to its start)
/// and the pixels the labels need above and below the line.
fn place_labels(labels: impl Iterator<Item = (f64, usize)>) -> (Vec<(bool, i32)>, (f64, f64)) {
    // Per lane (above, below): the placed labels as (x, far end from the line).
    let mut lanes: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut placed = Vec::new();
    for (x, chars) in labels {
        let start = |lane: &Vec<(f64, f64)>| {
            lane.iter()
                .filter(|(x0, _)| (x - x0).abs() < LABEL_WIDTH)
                .map(|(_, end)| end + LABEL_GAP / 2.0)
                .fold(LABEL_GAP, f64::max)
        };
        let (up_start, down_start) = (start(&lanes[0]), start(&lanes[1]));
        let up = up_start <= down_start;
        let begin = if up { up_start } else { down_start };
        let end = begin + chars as f64 * LABEL_CHAR;
        lanes[usize::from(!up)].push((x, end));
        placed.push((up, begin.round() as i32));
    }
    let reach =
        |lane: &Vec<(f64, f64)>| lane.iter().map(|(_, end)| end + 4.0).fold(0.0f64, f64::max);
    (placed, (reach(&lanes[0]), reach(&lanes[1])))
}

/// `yr` widened so that at least the fractions `above` and `below` of its span lie above and
/// below zero (each capped so that the two leave the data at least a tenth).
fn headroom(yr: Range<f64>, above: f64, below: f64) -> Range<f64> {
    let (mut fa, mut fb) = (above.clamp(0.0, 0.9), below.clamp(0.0, 0.9));
    if fa + fb > 0.9 {
        let k = 0.9 / (fa + fb);
        fa *= k;
        fb *= k;
    }
    let (a, b) = (yr.end.max(0.0), (-yr.start).max(0.0));
    let total = a + b;
    if total <= 0.0 {
        return yr;
    }
    // The two fractions sum to at most 1, so at most one side falls short.
    if a < fa * total {
        let t = b / (1.0 - fa);
        (-b)..(fa * t)
    } else if b < fb * total {
        let t = a / (1.0 - fb);
        (-fb * t)..a
    } else {
        yr
    }
}

/// Where the legend goes: the corner of the plot whose rectangle of `size` (fractions of the
/// plot's width and height, plus a margin) holds none of `points` (upper right first); when
/// every corner holds some, `yr` is extended downwards until the legend fits below them.
/// Returns the corner and the y range.
fn legend_place(
    points: &[(f64, f64)],
    xr: &Range<f64>,
    yr: Range<f64>,
    size: (f64, f64),
) -> (SeriesLabelPosition, Range<f64>) {
    let (corner, count) = emptiest_corner(points, xr, &yr, size);
    if count == 0 || size.1 + 0.04 >= 0.9 {
        return (corner, yr);
    }
    // The lowest point sits at the fraction bh of the new range: (y_min − lo)/(hi − lo) = bh.
    let bh = size.1 + 0.04;
    let y_min = points.iter().map(|p| p.1).fold(yr.start, f64::min);
    let lo = (y_min - bh * yr.end) / (1.0 - bh);
    let yr = lo.min(yr.start)..yr.end;
    (emptiest_corner(points, xr, &yr, size).0, yr)
}

/// The corner of the plot whose rectangle of `size` (fractions of the plot's width and
/// height, plus a margin) holds the fewest of `points` (upper right on a tie), and how many.
fn emptiest_corner(
    points: &[(f64, f64)],
    xr: &Range<f64>,
    yr: &Range<f64>,
    size: (f64, f64),
) -> (SeriesLabelPosition, usize) {
    let mut counts = [0usize; 4];
    let (w, h) = (xr.end - xr.start, yr.end - yr.start);
    let (bw, bh) = (size.0 + 0.04, size.1 + 0.04);
    for &(x, y) in points {
        let (fx, fy) = ((x - xr.start) / w, (y - yr.start) / h);
        let (left, right, low, high) = (fx < bw, fx > 1.0 - bw, fy < bh, fy > 1.0 - bh);
        for (k, inside) in [high && right, high && left, low && right, low && left]
            .into_iter()
            .enumerate()
        {
            counts[k] += usize::from(inside);
        }
    }
    let best = (0..4).min_by_key(|&k| (counts[k], k)).unwrap_or(0);
    let corner = match best {
        1 => SeriesLabelPosition::UpperLeft,
        2 => SeriesLabelPosition::LowerRight,
        3 => SeriesLabelPosition::LowerLeft,
        _ => SeriesLabelPosition::UpperRight,
    };
    (corner, counts[best])
}

/// A tick label on an axis spanning `span`: decimals to resolve a hundredth of the span,
/// and a plain `0` for a tick at zero up to round-off (never `-0.0`).
fn tick(v: f64, span: f64) -> String {
    if !v.is_finite() || !span.is_finite() || span <= 0.0 {
        return format!("{v}");
    }
    if v.abs() <= 1e-9 * span {
        return "0".to_string();
    }
    // Plotters puts about ten ticks on an axis: one more decimal than a tenth of the span
    // needs, then the trailing zeros trimmed.
    let decimals = (1 - (0.1 * span).log10().floor() as i32).clamp(0, 12) as usize;
    if (1e-3..1e5).contains(&v.abs()) || decimals <= 6 {
        let text = format!("{v:.decimals$}");
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            text
        }
    } else {
        format!("{v:.2e}")
    }
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
pub(super) fn padded(values: impl Iterator<Item = f64>) -> Range<f64> {
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
pub(super) fn short(x: f64) -> String {
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

/// `text` with every character XML 1.0 does not allow (control characters but tab, newline
/// and carriage return; the surrogates; U+FFFE and U+FFFF) replaced by U+FFFD: names from a
/// scene file reach the diagram's text, and the plotting library escapes only markup.
pub(super) fn xml_chars(text: &str) -> String {
    text.chars()
        .map(|c| match c {
            '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' => c,
            c if c >= '\u{10000}' => c,
            _ => '\u{FFFD}',
        })
        .collect()
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
    fn tick_labels() {
        assert_eq!(tick(-1e-18, 0.2), "0");
        assert_eq!(tick(0.05, 0.2), "0.05");
        assert_eq!(tick(-0.15, 0.2), "-0.15");
        assert_eq!(tick(-0.0125, 0.085), "-0.0125");
        assert_eq!(tick(20.0, 46.0), "20");
        assert_eq!(tick(0.30000000000000004, 1.0), "0.3");
        assert_eq!(tick(2e-9, 4e-9), "2.00e-9");
    }

    #[test]
    fn labels_stack_where_they_would_overlap() {
        // Far apart: all above, at the base gap. Close: above, below, then stacked above.
        let (placed, need) = place_labels([(0.0, 10), (100.0, 10)].into_iter());
        assert_eq!(placed, [(true, 12), (true, 12)]);
        assert!((need.0 - (12.0 + 72.0 + 4.0)).abs() < 1e-9 && need.1 == 0.0);
        let (placed, _) = place_labels([(0.0, 10), (3.0, 10), (6.0, 10)].into_iter());
        assert_eq!(placed[0], (true, 12));
        assert_eq!(placed[1], (false, 12));
        assert!(placed[2].0 && placed[2].1 > 12 + 72, "{placed:?}");
    }

    #[test]
    fn headroom_keeps_room_above_and_below_zero() {
        // Data mostly below zero: the top is raised to a quarter of the span.
        let r = headroom(-0.9..0.1, 0.25, 0.1);
        assert!((r.start + 0.9).abs() < 1e-12);
        assert!((r.end / (r.end - r.start) - 0.25).abs() < 1e-12, "{r:?}");
        // Enough room already: unchanged.
        assert_eq!(headroom(-1.0..1.0, 0.2, 0.2), -1.0..1.0);
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
