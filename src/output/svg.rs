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

use super::figure::{self, finish, Entry, Layout, Line, Mark, Plot, Sample, Symbol};
pub(super) use super::figure::{padded, tick};
use super::{check_finite, write_whole, OutputError};
use crate::results::{PathReport, TurningRow};
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
/// [`PathRow`](crate::results::PathRow)), so it is placed whatever the axes are.
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
    /// The path step just before the point, where it is inserted into the path's polyline
    /// when the diagram is drawn by index ([`Diagram::by_index`]); `None`: only marked.
    pub after_step: Option<usize>,
    /// True for a critical point: drawn by index, the path takes the next row's index from
    /// here on (the stable/unstable switch is drawn at the point, not at the next row).
    pub switches: bool,
}

impl Marker {
    /// The marker of a turning point of the control, labelled like `max p = 1.3551`.
    pub fn turning(report: &PathReport, t: &TurningRow) -> Self {
        Self::turning_scaled(report, t, None)
    }

    /// As [`Marker::turning`], the value given in the control's dimensionless group when
    /// `scale` is its axis (`max ρ ω² R³/(μH) = 3.3461`: the group is the axis title up to
    /// its list of values), so that the label reads off the axis.
    pub fn turning_scaled(report: &PathReport, t: &TurningRow, scale: Option<&AxisScale>) -> Self {
        let kind = if t.kind == crate::results::Extremum::Minimum {
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
        let (name, factor) = match scale {
            Some(s) => (
                s.label.split(" (").next().unwrap_or(&s.label).to_string(),
                s.factor,
            ),
            None => (report.control.clone(), 1.0),
        };
        let label = match value {
            Some(v) => format!("{word} {name} = {}", short(*v * factor)),
            None => format!("{word} {name}"),
        };
        Self {
            parameters: t.parameters.clone(),
            measures: t.measures.clone(),
            label,
            kind,
            after_step: Some(t.after_step),
            switches: false,
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
            after_step: None,
            switches: false,
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

/// What an axis shows: its title and the factor its values are multiplied by (a
/// dimensionless group such as `p R/(μH)`, see [`Scales`](super::Scales)).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisScale {
    /// The axis title.
    pub label: String,
    /// The factor applied to the quantity's values.
    pub factor: f64,
}

/// A thin grey curve drawn under the path, such as a closed form, with its legend entry; its
/// points are in the axes' quantities before scaling.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceCurve {
    /// The legend entry.
    pub label: String,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
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
    /// Width and height in pixels (default 900 × 650).
    pub size: (u32, u32),
    /// Draw the path by the rows' instability index, one colour and line style per index
    /// with a legend entry each, the markers with an `after_step` inserted into the polyline
    /// (default false; `segments` are then not used).
    pub by_index: bool,
    /// Title and factor of the horizontal axis (default: the quantity's name, factor 1).
    pub x_scale: Option<AxisScale>,
    /// Title and factor of the vertical axis.
    pub y_scale: Option<AxisScale>,
    /// A reference curve under the path (default none).
    pub reference: Option<ReferenceCurve>,
    /// The dimensionless groups of the report's other quantities, recorded in the figure's
    /// layout beside its axes' (default none).
    pub quantities: Vec<figure::QuantityScale>,
}

impl Diagram {
    /// `y` against `x`, turning points marked, into `path.svg`, 900 × 650.
    pub fn new(x: impl Into<String>, y: impl Into<String>) -> Self {
        Self {
            x: x.into(),
            y: y.into(),
            segments: Vec::new(),
            markers: Vec::new(),
            turning_points: true,
            file: "path.svg".to_string(),
            size: (900, 650),
            by_index: false,
            x_scale: None,
            y_scale: None,
            reference: None,
            quantities: Vec::new(),
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

    /// Drawn by the rows' instability index (see [`Diagram::by_index`]).
    #[must_use]
    pub fn by_index(mut self) -> Self {
        self.by_index = true;
        self
    }

    /// With these axis titles and factors.
    #[must_use]
    pub fn scales(mut self, x: AxisScale, y: AxisScale) -> Self {
        self.x_scale = Some(x);
        self.y_scale = Some(y);
        self
    }

    /// With a reference curve under the path.
    #[must_use]
    pub fn reference(mut self, curve: ReferenceCurve) -> Self {
        self.reference = Some(curve);
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
    let (fx, fy) = (
        diagram.x_scale.as_ref().map_or(1.0, |s| s.factor),
        diagram.y_scale.as_ref().map_or(1.0, |s| s.factor),
    );
    let scale = |p: (f64, f64)| (p.0 * fx, p.1 * fy);
    let points: Vec<(f64, f64)> = points.into_iter().map(scale).collect();
    let path_points: Vec<(f64, f64)> = report
        .rows
        .iter()
        .map(|r| {
            let x = xa.at(&r.parameters, &r.measures).unwrap_or(f64::NAN);
            let y = ya.at(&r.parameters, &r.measures).unwrap_or(f64::NAN);
            scale((x, y))
        })
        .collect();
    let reference: Vec<(f64, f64)> = diagram
        .reference
        .iter()
        .flat_map(|c| c.points.iter().copied().map(scale))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    let runs = if diagram.by_index {
        let rows: Vec<(usize, Option<usize>)> =
            report.rows.iter().map(|r| (r.step, r.index)).collect();
        let events: Vec<(usize, bool, (f64, f64))> = markers
            .iter()
            .zip(&points)
            .filter_map(|(m, &p)| Some((m.after_step?, m.switches, p)))
            .collect();
        index_runs(&rows, &path_points, &events)
    } else {
        Vec::new()
    };
    let (svg, mut layout) = render(
        report,
        diagram,
        &Drawn {
            path: &path_points,
            runs: &runs,
            reference: &reference,
            markers: &markers,
            marker_points: &points,
        },
    )
    .map_err(|e| invalid(format!("plotting failed: {e}")))?;
    let unscaled = |name: &str| AxisScale {
        label: name.to_string(),
        factor: 1.0,
    };
    layout.scales = vec![
        figure::QuantityScale::new(
            &diagram.x,
            &diagram
                .x_scale
                .clone()
                .unwrap_or_else(|| unscaled(&diagram.x)),
        ),
        figure::QuantityScale::new(
            &diagram.y,
            &diagram
                .y_scale
                .clone()
                .unwrap_or_else(|| unscaled(&diagram.y)),
        ),
    ];
    for q in &diagram.quantities {
        if !layout.scales.iter().any(|s| s.quantity == q.quantity) {
            layout.scales.push(q.clone());
        }
    }
    let svg = xml_chars(&finish(&svg, &layout));
    write_whole(&path, |w| w.write_all(svg.as_bytes()))?;
    Ok(path)
}

/// A plotters chart of the figures' style (see [`figure::chart`]).
pub(super) type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// A stretch of the path at one instability index: the index and its points.
pub(crate) type IndexRun = (Option<usize>, Vec<(f64, f64)>);

/// What [`render`] draws, in plot coordinates (scaled).
struct Drawn<'a> {
    path: &'a [(f64, f64)],
    runs: &'a [IndexRun],
    reference: &'a [(f64, f64)],
    markers: &'a [Marker],
    marker_points: &'a [(f64, f64)],
}

/// The path as runs of one instability index each. `rows` are (step, index) of the path's
/// points `path`; `events` are (the step before, switches, point): each is inserted after the
/// row of that step, several in one gap in order of their distance from that row (in
/// fractions of the data's span). The index of a stretch is the row's before it; a switching
/// event (a critical point) takes the next row's index from there, so a change of index is
/// drawn at the critical point; without one it happens at the row. A row without an index
/// keeps the one before it (the first known index at the start).
pub(crate) fn index_runs(
    rows: &[(usize, Option<usize>)],
    path: &[(f64, f64)],
    events: &[(usize, bool, (f64, f64))],
) -> Vec<IndexRun> {
    let n = rows.len().min(path.len());
    if n == 0 {
        return Vec::new();
    }
    let span = |f: fn(&(f64, f64)) -> f64| {
        let (lo, hi) = path[..n]
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        if hi > lo {
            hi - lo
        } else {
            1.0
        }
    };
    let (sx, sy) = (span(|p| p.0), span(|p| p.1));
    let mut current = rows[..n].iter().find_map(|r| r.1);
    let mut runs: Vec<IndexRun> = Vec::new();
    let mut points = vec![path[0]];
    let mut switch =
        |to: Option<usize>, current: &mut Option<usize>, points: &mut Vec<(f64, f64)>| {
            if to.is_some() && to != *current {
                let last = *points.last().expect("a run has a point");
                runs.push((*current, std::mem::replace(points, vec![last])));
                *current = to;
            }
        };
    for i in 0..n {
        if i > 0 {
            points.push(path[i]);
            switch(rows[i].1, &mut current, &mut points);
        }
        let mut gap: Vec<&(usize, bool, (f64, f64))> =
            events.iter().filter(|e| e.0 == rows[i].0).collect();
        let from = path[i];
        let d = |p: (f64, f64)| ((p.0 - from.0) / sx).hypot((p.1 - from.1) / sy);
        gap.sort_by(|a, b| d(a.2).total_cmp(&d(b.2)));
        for &(_, switches, p) in gap {
            points.push(p);
            if switches {
                let next = rows.get(i + 1).filter(|_| i + 1 < n).and_then(|r| r.1);
                switch(next, &mut current, &mut points);
            }
        }
    }
    runs.push((current, points));
    runs.retain(|r| r.1.len() > 1);
    runs
}

/// The colour and dash pattern (dash, gap; none for solid) of instability index `i`.
fn index_style(i: Option<usize>) -> (RGBColor, Option<(u32, u32)>) {
    const COLOURS: [RGBColor; 5] = [
        RGBColor(31, 87, 180),
        RGBColor(200, 30, 30),
        RGBColor(230, 130, 0),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
    ];
    const DASHES: [(u32, u32); 4] = [(8, 5), (3, 4), (14, 4), (6, 3)];
    match i {
        None => (RGBColor(150, 150, 150), None),
        Some(0) => (COLOURS[0], None),
        Some(i) => (
            COLOURS[i % COLOURS.len()],
            Some(DASHES[(i - 1) % DASHES.len()]),
        ),
    }
}

/// The legend entry of instability index `i`.
pub(crate) fn index_legend(i: Option<usize>) -> String {
    match i {
        None => "index not computed".to_string(),
        Some(0) => "index 0 (stable)".to_string(),
        Some(i) => format!("index {i}"),
    }
}

/// The caption line of a run's figures: its scene and its mesh (generator, triangles, the
/// mesh's group) and the group it is solved in.
pub fn caption_of(report: &PathReport) -> String {
    format!(
        "scene {} · mesh: {} · solved in group {}",
        report.scene,
        report.mesh.describe(),
        report.group
    )
}

/// The symbol and legend entry of a marker kind; `control` names the control parameter.
fn marker_style(kind: MarkerKind, control: &str) -> (Symbol, String) {
    match kind {
        MarkerKind::Maximum | MarkerKind::Minimum => (
            Symbol::Disc(RGBColor(200, 30, 30)),
            format!("turning point of {control}"),
        ),
        MarkerKind::Bifurcation => (Symbol::Cross(BLACK), "bifurcation point".to_string()),
        MarkerKind::Other => (Symbol::Ring(BLACK), "critical point".to_string()),
    }
}

/// Draws the diagram into an SVG string with its layout.
fn render(
    report: &PathReport,
    diagram: &Diagram,
    d: &Drawn,
) -> Result<(String, Layout), Box<dyn Error>> {
    let path = d.path;
    let x_title = diagram
        .x_scale
        .as_ref()
        .map_or(diagram.x.as_str(), |s| s.label.as_str());
    let y_title = diagram
        .y_scale
        .as_ref()
        .map_or(diagram.y.as_str(), |s| s.label.as_str());
    let title = format!("{} (group {})", report.scene, report.group);
    let mut plot = Plot::new(title, caption_of(report), x_title, y_title);
    plot.size = diagram.size;
    let blue = RGBColor(31, 87, 180);
    let red = RGBColor(200, 30, 30);
    if let Some(r) = &diagram.reference {
        let grey = RGBColor(110, 110, 110);
        plot.lines
            .push(Line::new(d.reference.to_vec(), grey, 1, None));
        plot.legend
            .push(Entry::new(r.label.clone(), Sample::Line(grey, 1, None)));
    }
    // Under the path: its flagged stretches, wide and translucent orange.
    let row_flags: Vec<Vec<&str>> = (0..path.len()).map(|i| report.row_flags(i)).collect();
    let flagged: Vec<usize> = (1..path.len())
        .filter(|&i| !row_flags[i - 1].is_empty() || !row_flags[i].is_empty())
        .collect();
    if !flagged.is_empty() {
        let mut names: Vec<&str> = row_flags.iter().flatten().copied().collect();
        names.sort_unstable();
        names.dedup();
        let band = RGBAColor(255, 150, 0, 0.45);
        for &i in &flagged {
            plot.bands.push((vec![path[i - 1], path[i]], band, 11));
        }
        plot.legend.push(Entry::new(
            format!("flagged: {}", names.join(", ")),
            Sample::Band(band, 11),
        ));
    }
    if diagram.by_index {
        let mut done: Vec<Option<usize>> = Vec::new();
        for (index, run) in d.runs {
            let (c, dash) = index_style(*index);
            let width = if index.is_some() { 3 } else { 1 };
            plot.lines.push(Line::new(run.clone(), c, width, dash));
            if !done.contains(index) {
                done.push(*index);
                plot.legend.push(Entry::new(
                    index_legend(*index),
                    Sample::Line(c, width, dash),
                ));
            }
        }
    } else if diagram.segments.is_empty() {
        plot.lines.push(Line::new(path.to_vec(), blue, 2, None));
    } else {
        let grey = RGBColor(170, 170, 170);
        plot.lines.push(Line::new(path.to_vec(), grey, 1, None));
        let (mut stable, mut unstable) = (false, false);
        for s in &diagram.segments {
            let pts = path[s.first..=s.last].to_vec();
            if s.stable {
                plot.lines.push(Line::new(pts, blue, 3, None));
                stable = true;
            } else {
                plot.lines.push(Line::new(pts, red, 3, Some((8, 5))));
                unstable = true;
            }
        }
        if stable {
            plot.legend
                .push(Entry::new("stable", Sample::Line(blue, 3, None)));
        }
        if unstable {
            plot.legend
                .push(Entry::new("unstable", Sample::Line(red, 3, Some((8, 5)))));
        }
    }
    for (m, &at) in d.markers.iter().zip(d.marker_points) {
        let (symbol, kind) = marker_style(m.kind, &report.control);
        plot.marks.push(Mark {
            at,
            symbol,
            kind,
            label: m.label.clone(),
        });
    }
    figure::render(&plot)
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

/// The legend entry of the spectrum diagram's higher eigenvalues.
pub const HIGHER_LEGEND: &str = "dashed: higher eigenvalues crossing zero";

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
/// [`Spectra`]: crate::results::Spectra
///
/// # Errors
/// [`OutputError::Invalid`] if the report has no spectra, a number (of the report, its spectra
/// or a critical point's control) is not finite, or plotting fails — nothing is written;
/// [`OutputError::NoDirectory`] / [`OutputError::Io`] if the file cannot be written.
pub fn write_spectrum_diagram(dir: &Path, report: &PathReport) -> Result<PathBuf, OutputError> {
    write_spectrum_diagram_with(dir, report, None, false)
}

/// As [`write_spectrum_diagram`], the control's axis titled and its values scaled by
/// `control` (none: the control's name, unscaled); the higher eigenvalues of a block that
/// cross zero in the sweep (the later critical points of its irrep) are drawn dashed in the
/// block's colour, so that every critical point sits where a line crosses zero. A critical
/// point whose wave number m is known ([`PathReport::wave_numbers`]) has it in its label,
/// `m = 2`; with `rungs` (a ponding floor, where the k-th point of wave number m is the rung
/// j_{m,k}) as `(2, 1)`, and the legend's entry reads `critical point (m, k)`.
///
/// # Errors
/// As [`write_spectrum_diagram`].
pub fn write_spectrum_diagram_with(
    dir: &Path,
    report: &PathReport,
    control_scale: Option<&AxisScale>,
    rungs: bool,
) -> Result<PathBuf, OutputError> {
    let path = dir.join("path.svg");
    let f = control_scale.map_or(1.0, |s| s.factor);
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
    let mut rung = std::collections::BTreeMap::<usize, usize>::new();
    for (k, cp) in report.critical.iter().enumerate() {
        let x = control.and_then(|c| cp.parameters.get(c).copied());
        let base = format!("{} {}", cp.kind.short(), cp.irrep);
        let label = match report.wave_numbers.get(k) {
            Some(&m) if rungs => {
                let n = rung.entry(m).or_insert(0);
                *n += 1;
                format!("{base} ({m}, {n})")
            }
            Some(&m) => format!("{base} m = {m}"),
            None => base,
        };
        match x {
            Some(x) if x.is_finite() => marks.push(CriticalMark {
                x: x * f,
                label,
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
                            run.push((row.control * f, v));
                        }
                    }
                    _ => open = false,
                }
            }
            runs
        })
        .collect();
    let higher: Vec<Vec<Vec<(f64, f64)>>> = (0..spectra.irreps.len())
        .map(|mu| {
            let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
            for j in 1..crate::results::SPECTRUM_EIGENVALUES {
                let value = |row: &crate::results::SpectrumRow| {
                    row.eigenvalues
                        .get(mu)
                        .and_then(|e| e.get(j).copied())
                        .filter(|v| v.is_finite())
                };
                // Only an eigenvalue that crosses zero somewhere in the sweep is drawn.
                if !spectra
                    .rows
                    .iter()
                    .any(|r| value(r).is_some_and(|v| v <= 0.0))
                {
                    continue;
                }
                let mut open = false;
                for row in &spectra.rows {
                    match value(row) {
                        Some(v) => {
                            if !open {
                                runs.push(Vec::new());
                                open = true;
                            }
                            if let Some(run) = runs.last_mut() {
                                run.push((row.control * f, v));
                            }
                        }
                        None => open = false,
                    }
                }
            }
            runs.retain(|r| r.len() > 1);
            runs
        })
        .collect();
    let x_title = control_scale.map_or(report.control.as_str(), |s| s.label.as_str());
    let legend = if rungs && !report.wave_numbers.is_empty() {
        "critical point (m, k)"
    } else {
        "critical point"
    };
    let (svg, layout) = render_spectra(report, &curves, &higher, &marks, (x_title, f, legend))
        .map_err(|e| invalid(format!("plotting failed: {e}")))?;
    let svg = xml_chars(&finish(&svg, &layout));
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
    higher: &[Vec<Vec<(f64, f64)>>],
    marks: &[CriticalMark],
    (x_title, f, mark_legend): (&str, f64, &str),
) -> Result<(String, Layout), Box<dyn Error>> {
    let spectra = &report.spectra;
    let size = (800u32, 600u32 + figure::CAPTION_H);
    let points = || curves.iter().chain(higher).flatten().flatten();
    let xs = spectra.rows.iter().map(|r| r.control * f);
    let xr = padded(xs.chain(marks.iter().map(|m| m.x)));
    let yr = padded(points().map(|p| p.1).chain(std::iter::once(0.0)));
    // Room for the vertical labels of the critical points on either side of the zero line.
    let (plot_w, plot_h) = (
        f64::from(size.0 - 2 * 20 - 80),
        f64::from(size.1 - figure::CAPTION_H - 2 * 20 - 90),
    );
    let px = plot_w / (xr.end - xr.start);
    let (labels, need) = place_labels(
        marks
            .iter()
            .map(|m| (m.x * px, figure::text_size(&m.label, SPECTRUM_LABEL).0)),
    );
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
        .chain(
            higher
                .iter()
                .any(|r| !r.is_empty())
                .then(|| HIGHER_LEGEND.to_string()),
        )
        .chain((!marks.is_empty()).then(|| mark_legend.to_string()))
        .collect();
    let entries: Vec<Entry> = legend
        .iter()
        .enumerate()
        .map(|(k, text)| {
            let sample = if k < spectra.irreps.len() {
                if curves[k].is_empty() {
                    Sample::Note
                } else {
                    Sample::Line(colour(k), 2, dashed(k).then_some((8, 4)))
                }
            } else if text == HIGHER_LEGEND {
                Sample::Line(RGBColor(90, 90, 90), 1, Some((5, 4)))
            } else {
                Sample::Symbol(Symbol::Cross(BLACK))
            };
            Entry::new(text.clone(), sample)
        })
        .collect();
    // The legend's size as fractions of the plot, to find a corner it fits in.
    let (lw, lh) = figure::legend_size(&entries);
    let legend_box = (lw / plot_w, lh / plot_h);
    // The lines, sampled between their points, and the critical points on the zero line.
    let dense = curves.iter().chain(higher).flatten().flat_map(|run| {
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
    let caption = caption_of(report);
    let mut layout = Layout {
        width: size.0,
        height: size.1,
        legend: legend.clone(),
        caption: caption.clone(),
        ..Layout::default()
    };
    let mut svg = String::new();
    {
        let canvas = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        canvas.fill(&WHITE)?;
        let (root, _) = canvas.split_vertically(size.1 - figure::CAPTION_H);
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
            .x_desc(x_title)
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
        for (mu, runs) in curves.iter().enumerate() {
            let c = colour(mu);
            for run in runs {
                let style = c.stroke_width(2);
                if dashed(mu) {
                    chart.draw_series(DashedLineSeries::new(run.iter().copied(), 8, 4, style))?;
                } else {
                    chart.draw_series(LineSeries::new(run.iter().copied(), style))?;
                }
            }
        }
        for (mu, runs) in higher.iter().enumerate() {
            let c = colour(mu);
            for run in runs {
                chart.draw_series(DashedLineSeries::new(
                    run.iter().copied(),
                    5,
                    4,
                    c.stroke_width(1),
                ))?;
            }
        }
        let (pxr, pyr) = chart.plotting_area().get_pixel_range();
        layout.plot = Some(figure::Rect {
            x0: f64::from(pxr.start),
            y0: f64::from(pyr.start),
            x1: f64::from(pxr.end),
            y1: f64::from(pyr.end),
        });
        let crosses: Vec<(f64, f64)> = marks
            .iter()
            .map(|m| {
                let (x, y) = chart.backend_coord(&(m.x, 0.0));
                (f64::from(x), f64::from(y))
            })
            .collect();
        for (m, &(up, start)) in marks.iter().zip(&labels) {
            let (x, y) = chart.backend_coord(&(m.x, 0.0));
            let (len, thick) = figure::text_size(&m.label, SPECTRUM_LABEL);
            let (x, y, s) = (f64::from(x), f64::from(y), f64::from(start));
            let (y0, y1) = if up {
                (y - s - len, y - s)
            } else {
                (y + s, y + s + len)
            };
            let rect = figure::Rect {
                x0: x - thick / 2.0,
                y0,
                x1: x + thick / 2.0,
                y1,
            };
            // A label stacked over another point's: a leader line from its own cross.
            let leader = figure::ambiguous(&rect, (x, y), &crosses);
            if leader {
                let (from, to) = if up {
                    (y - 7.0, y - s)
                } else {
                    (y + 7.0, y + s)
                };
                let px = x.round() as i32;
                canvas.draw(&PathElement::new(
                    vec![(px, from.round() as i32), (px, to.round() as i32)],
                    RGBColor(110, 110, 110).stroke_width(1),
                ))?;
            }
            layout.labels.push(figure::PlacedLabel {
                text: m.label.clone(),
                rect,
                leader,
                in_inset: false,
                at: (x, y),
            });
            let c = m.irrep.map_or(BLACK, colour);
            let (transform, offset) = if up {
                (FontTransform::Rotate270, (0, -start))
            } else {
                (FontTransform::Rotate90, (0, start))
            };
            let font = ("sans-serif", SPECTRUM_LABEL)
                .into_font()
                .transform(transform)
                .color(&c)
                .pos(Pos::new(HPos::Left, VPos::Center));
            chart.draw_series(std::iter::once(
                EmptyElement::at((m.x, 0.0))
                    + Cross::new((0, 0), 6, c.stroke_width(2))
                    + Text::new(m.label.clone(), offset, font),
            ))?;
            if layout.marker_kinds.is_empty() {
                layout.marker_kinds.push(mark_legend.to_string());
            }
        }
        // The legend: in the corner that covers no label and the fewest data.
        let frame = layout.plot.unwrap_or(figure::Rect::at(0.0, 0.0, 0.0, 0.0));
        let data: Vec<(f64, f64)> = occupied
            .iter()
            .map(|p| {
                let (x, y) = chart.backend_coord(p);
                (f64::from(x), f64::from(y))
            })
            .collect();
        let preferred = match legend_at {
            SeriesLabelPosition::UpperRight => 0,
            SeriesLabelPosition::UpperLeft => 1,
            SeriesLabelPosition::LowerRight => 2,
            _ => 3,
        };
        let corners = figure::corners(frame, figure::legend_size(&entries));
        let cost = |k: usize| {
            let b = &corners[k];
            (
                layout.labels.iter().filter(|l| l.rect.overlaps(b)).count(),
                data.iter().filter(|p| b.contains(**p)).count(),
                usize::from(k != preferred),
            )
        };
        let best = (0..4).min_by_key(|&k| cost(k)).unwrap_or(preferred);
        layout.legend_markers = figure::draw_legend(&canvas, corners[best], &entries)?;
        layout.legend_box = Some(corners[best]);
        figure::draw_caption(&canvas, &caption, size)?;
        canvas.present()?;
    }
    Ok((svg, layout))
}

/// Font size of the spectrum diagram's vertical labels.
const SPECTRUM_LABEL: u32 = 14;

/// Gap between the zero line and a label, and between stacked labels, in pixels.
const LABEL_GAP: f64 = 12.0;
/// Labels closer than this (pixels along the control) would overlap side by side.
const LABEL_WIDTH: f64 = 16.0;

/// Places the vertical labels of the critical points `(x, length)` in pixels, sorted by
/// x: each goes above or below the zero line, into the lane where it can start nearest to the
/// line without overlapping an earlier label (labels less than [`LABEL_WIDTH`] apart stack
/// outwards; above on a tie). Returns per label (above?, pixels from the line to its start)
/// and the pixels the labels need above and below the line.
fn place_labels(labels: impl Iterator<Item = (f64, f64)>) -> (Vec<(bool, i32)>, (f64, f64)) {
    // Per lane (above, below): the placed labels as (x, far end from the line).
    let mut lanes: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut placed = Vec::new();
    for (x, length) in labels {
        let start = |lane: &Vec<(f64, f64)>| {
            lane.iter()
                .filter(|(x0, _)| (x - x0).abs() < LABEL_WIDTH)
                .map(|(_, end)| end + LABEL_GAP / 2.0)
                .fold(LABEL_GAP, f64::max)
        };
        let (up_start, down_start) = (start(&lanes[0]), start(&lanes[1]));
        let up = up_start <= down_start;
        let begin = if up { up_start } else { down_start };
        let end = begin + length;
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
    fn labels_stack_where_they_would_overlap() {
        // Far apart: all above, at the base gap. Close: above, below, then stacked above.
        let (placed, need) = place_labels([(0.0, 72.0), (100.0, 72.0)].into_iter());
        assert_eq!(placed, [(true, 12), (true, 12)]);
        assert!((need.0 - (12.0 + 72.0 + 4.0)).abs() < 1e-9 && need.1 == 0.0);
        let (placed, _) = place_labels([(0.0, 72.0), (3.0, 72.0), (6.0, 72.0)].into_iter());
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
    fn index_runs_switch_at_the_critical_point() {
        // Rows 0..=3 with index 0, 0, 1, 1; a critical point between rows 1 and 2 and a
        // turning point (no switch) between rows 2 and 3.
        let rows = [(0, Some(0)), (1, Some(0)), (2, Some(1)), (3, Some(1))];
        let path = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (3.0, 0.0)];
        let events = [(1, true, (1.5, 0.1)), (2, false, (2.5, 0.2))];
        let runs = index_runs(&rows, &path, &events);
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[0], (Some(0), vec![(0.0, 0.0), (1.0, 0.0), (1.5, 0.1)]));
        assert_eq!(
            runs[1],
            (
                Some(1),
                vec![(1.5, 0.1), (2.0, 0.0), (2.5, 0.2), (3.0, 0.0)]
            )
        );
        // Without the critical point the index changes at the row.
        let runs = index_runs(&rows, &path, &events[1..]);
        assert_eq!(runs[0].1.last(), Some(&(2.0, 0.0)));
        assert_eq!(runs[1].1.first(), Some(&(2.0, 0.0)));
        // A row without an index (a branch's first) joins the first known index.
        let rows = [(0, None), (1, Some(2)), (2, Some(2))];
        let runs = index_runs(&rows, &path[..3], &[]);
        assert_eq!(runs, [(Some(2), path[..3].to_vec())]);
    }
}
