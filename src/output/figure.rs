//! The one style of memstab's figures: a [`Plot`] of lines, filled polygons and labelled
//! marks in two dimensionless quantities, drawn into an SVG with
//!
//! - the title above and a caption line below naming the scene and its mesh (generator,
//!   triangles, group);
//! - stable stretches solid and unstable ones dashed (the caller's [`Line`]s say which);
//! - a legend of the line styles the figure shows and of every marker kind drawn (and of
//!   nothing else), in the corner of the plot that hides the fewest data;
//! - marker labels placed without overlapping each other, the legend, the marks or the
//!   inset, joined to their point by a leader line when placed away from it;
//! - an inset that zooms on the largest cluster of marks closer together than a label's
//!   height, where their labels are placed instead, in a free corner that covers no mark
//!   (none left: no inset, the labels placed with leaders).
//!
//! The layout (label boxes, legend entries and box, marker kinds drawn, inset) is computed
//! here, not by the plotting library, and is written into the SVG as a `<metadata>` element
//! ([`Layout`], read back by [`read_layout`]) so that a test can check a written figure
//! without a renderer. Text widths are estimated from the advance widths of DejaVu Sans, the
//! first font the SVG asks for and the one [`png`](super::png) renders with.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::{Deserialize, Serialize};
use std::error::Error;
use std::ops::Range;

/// The font families the SVG's text asks for, first to last.
pub const FONT_FAMILY: &str = "DejaVu Sans, Verdana, Arial, Helvetica, sans-serif";

/// The id of the SVG's `<metadata>` element that holds the [`Layout`].
pub const LAYOUT_ID: &str = "memstab-layout";

/// An axis-aligned box in pixels (y grows downwards).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rect {
    /// Left.
    pub x0: f64,
    /// Top.
    pub y0: f64,
    /// Right.
    pub x1: f64,
    /// Bottom.
    pub y1: f64,
}

impl Rect {
    /// The box from its left top corner and size.
    pub fn at(x: f64, y: f64, w: f64, h: f64) -> Self {
        Self {
            x0: x,
            y0: y,
            x1: x + w,
            y1: y + h,
        }
    }

    /// True if the two boxes share interior points.
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    /// True if `o` lies within this box.
    pub fn holds(&self, o: &Rect) -> bool {
        o.x0 >= self.x0 && o.x1 <= self.x1 && o.y0 >= self.y0 && o.y1 <= self.y1
    }

    /// True if the point lies within this box.
    pub fn contains(&self, p: (f64, f64)) -> bool {
        p.0 >= self.x0 && p.0 <= self.x1 && p.1 >= self.y0 && p.1 <= self.y1
    }

    /// The point of the box nearest to `p`.
    fn nearest(&self, p: (f64, f64)) -> (f64, f64) {
        (p.0.clamp(self.x0, self.x1), p.1.clamp(self.y0, self.y1))
    }
}

/// A label as placed: its text, its box and whether a leader line joins it to its point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlacedLabel {
    /// The text.
    pub text: String,
    /// Its box.
    pub rect: Rect,
    /// True if a leader line joins it to its point.
    pub leader: bool,
    /// True if it is placed in the inset.
    pub in_inset: bool,
    /// The point it labels, in pixels (in the inset for a label placed there).
    #[serde(default)]
    pub at: (f64, f64),
}

/// The layout of a written figure: what a test checks.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    /// Canvas width in pixels.
    pub width: u32,
    /// Canvas height in pixels.
    pub height: u32,
    /// The plot area (inside the axes).
    pub plot: Option<Rect>,
    /// The marker labels.
    pub labels: Vec<PlacedLabel>,
    /// The legend's entries, top to bottom.
    pub legend: Vec<String>,
    /// The legend's box.
    pub legend_box: Option<Rect>,
    /// The marker kinds drawn (their legend text), each once.
    pub marker_kinds: Vec<String>,
    /// The marker kinds the legend shows.
    pub legend_markers: Vec<String>,
    /// The kinds of the keyed lines ([`Line::kind`]) drawn inside the plot, each once.
    #[serde(default)]
    pub line_kinds: Vec<String>,
    /// The legend's entries for keyed lines.
    #[serde(default)]
    pub legend_lines: Vec<String>,
    /// The inset's box, if there is one.
    pub inset: Option<Rect>,
    /// The caption line.
    pub caption: String,
    /// Labels that found no place (and are not drawn).
    pub dropped: Vec<String>,
    /// The dimensionless groups of the figure's quantities, for a script that draws the same
    /// run in the same style.
    #[serde(default)]
    pub scales: Vec<QuantityScale>,
}

/// A quantity of a figure and its dimensionless group: the axis title and the factor its
/// values are multiplied by (1 and the quantity's name where the scene fixes no scale).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuantityScale {
    /// The parameter or measure, by name.
    pub quantity: String,
    /// The axis title.
    pub label: String,
    /// The factor.
    pub factor: f64,
}

impl QuantityScale {
    /// `quantity` with its scale.
    pub fn new(quantity: &str, scale: &super::svg::AxisScale) -> Self {
        Self {
            quantity: quantity.to_string(),
            label: scale.label.clone(),
            factor: scale.factor,
        }
    }
}

/// The layout written into an SVG by memstab, `None` if it has none (or it does not parse).
pub fn read_layout(svg: &str) -> Option<Layout> {
    let open = format!("<metadata id=\"{LAYOUT_ID}\">");
    let start = svg.find(&open)? + open.len();
    let end = start + svg[start..].find("</metadata>")?;
    let json = svg[start..end]
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&json).ok()
}

/// The SVG text of a plotting backend, finished in the figures' style: the text's font
/// families set to [`FONT_FAMILY`] and the layout inserted as `<metadata>` after the opening
/// `<svg …>` tag, its texts as the SVG draws them.
pub fn finish(svg: &str, layout: &Layout) -> String {
    let svg = svg.replace(
        "font-family=\"sans-serif\"",
        &format!("font-family=\"{FONT_FAMILY}\""),
    );
    // The layout's texts as the SVG draws them (characters XML does not allow replaced).
    let clean = super::svg::xml_chars;
    let mut layout = layout.clone();
    layout.caption = clean(&layout.caption);
    for t in layout
        .legend
        .iter_mut()
        .chain(&mut layout.marker_kinds)
        .chain(&mut layout.legend_markers)
        .chain(&mut layout.line_kinds)
        .chain(&mut layout.legend_lines)
        .chain(&mut layout.dropped)
        .chain(layout.labels.iter_mut().map(|l| &mut l.text))
        .chain(layout.scales.iter_mut().map(|s| &mut s.label))
    {
        *t = clean(t);
    }
    let json = serde_json::to_string(&layout).unwrap_or_default();
    let json = json
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let meta = format!("<metadata id=\"{LAYOUT_ID}\">{json}</metadata>\n");
    match svg
        .find("<svg")
        .and_then(|s| svg[s..].find('>').map(|e| s + e + 1))
    {
        Some(at) => {
            let (head, tail) = svg.split_at(at);
            format!("{head}\n{meta}{}", tail.trim_start_matches('\n'))
        }
        None => svg,
    }
}

/// Advance width of `c` in DejaVu Sans, in em (a table of its classes; wide when unsure).
fn advance(c: char) -> f64 {
    match c {
        ' ' | '.' | ',' | ':' | ';' | '!' | '\'' | '|' => 0.34,
        'i' | 'j' | 'l' | 'I' | 'J' => 0.30,
        '(' | ')' | '[' | ']' | '{' | '}' | '/' | '\\' => 0.40,
        'f' | 't' | 'r' | '-' | '²' | '³' | '¹' | '⁰'..='⁹' | '⁻' => 0.44,
        '0'..='9' | '$' | '#' | '_' | '*' => 0.64,
        'm' | 'w' => 0.98,
        'M' | 'W' | '%' | '@' => 1.0,
        'A'..='Z' => 0.78,
        '=' | '+' | '−' | '×' | '<' | '>' | '~' | '≈' | '≤' | '≥' => 0.84,
        'a'..='z' => 0.64,
        _ => 0.72,
    }
}

/// The font size in pixels that the SVG backend writes for a plotters font of `size`.
fn px(size: u32) -> f64 {
    f64::from(size) / 1.24
}

/// Estimated (width, height) in pixels of `text` in a plotters font of `size`.
pub fn text_size(text: &str, size: u32) -> (f64, f64) {
    let em = px(size);
    let w: f64 = text.chars().map(advance).sum::<f64>() * em;
    (w.ceil() + 2.0, (1.2 * em).ceil())
}

/// The symbol of a mark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Symbol {
    /// A filled disc.
    Disc(RGBColor),
    /// An open circle.
    Ring(RGBColor),
    /// A cross (×).
    Cross(RGBColor),
    /// A filled square.
    Square(RGBColor),
}

/// Half the size of a symbol in pixels.
const SYMBOL: i32 = 6;

impl Symbol {
    /// The symbol as an element at `at` (pixels).
    fn draw(
        self,
        area: &DrawingArea<SVGBackend, Shift>,
        at: (i32, i32),
    ) -> Result<(), Box<dyn Error>> {
        match self {
            Symbol::Disc(c) => area.draw(&Circle::new(at, 5, c.filled()))?,
            Symbol::Ring(c) => area.draw(&Circle::new(at, 5, c.stroke_width(2)))?,
            Symbol::Cross(c) => area.draw(&Cross::new(at, 6, c.stroke_width(2)))?,
            Symbol::Square(c) => area.draw(&Rectangle::new(
                [(at.0 - 5, at.1 - 5), (at.0 + 5, at.1 + 5)],
                c.filled(),
            ))?,
        }
        Ok(())
    }
}

/// A polyline of the plot in data coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// Points (x, y), already scaled.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub colour: RGBColor,
    /// Opacity (1 opaque).
    pub alpha: f64,
    /// Stroke width in pixels.
    pub width: u32,
    /// Dash and gap in pixels; `None`: solid.
    pub dash: Option<(u32, u32)>,
    /// What the line is, as its legend entry says: a keyed line gets its entry from the
    /// figure, once per kind, and only when a piece of it is drawn inside the plot.
    pub kind: Option<String>,
}

impl Line {
    /// A solid or dashed line.
    pub fn new(
        points: Vec<(f64, f64)>,
        colour: RGBColor,
        width: u32,
        dash: Option<(u32, u32)>,
    ) -> Self {
        Self {
            points,
            colour,
            alpha: 1.0,
            width,
            dash,
            kind: None,
        }
    }

    /// The line keyed by `kind` (its legend entry).
    pub fn kind(mut self, kind: impl Into<String>) -> Self {
        self.kind = Some(kind.into());
        self
    }
}

/// A wide translucent band: points, colour, width in pixels.
pub type Band = (Vec<(f64, f64)>, RGBAColor, u32);

/// Marks to label: each mark's index and its point in pixels.
type ToLabel = Vec<(usize, (f64, f64))>;

/// A labelled point of the plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    /// Where, in data coordinates.
    pub at: (f64, f64),
    /// Its symbol.
    pub symbol: Symbol,
    /// What kind of point it is: the legend's entry for its symbol.
    pub kind: String,
    /// The text next to it (none if empty).
    pub label: String,
}

/// What a legend entry shows left of its text.
#[derive(Debug, Clone, PartialEq)]
pub enum Sample {
    /// A line of this colour, width and dash.
    Line(RGBColor, u32, Option<(u32, u32)>),
    /// A wide translucent band.
    Band(RGBAColor, u32),
    /// A symbol.
    Symbol(Symbol),
    /// A filled square of this colour: a shaded region.
    Patch(RGBAColor),
    /// Nothing: the entry is a note.
    Note,
}

/// One entry of the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Its text.
    pub text: String,
    /// Its sample.
    pub sample: Sample,
}

impl Entry {
    /// An entry.
    pub fn new(text: impl Into<String>, sample: Sample) -> Self {
        Self {
            text: text.into(),
            sample,
        }
    }
}

/// A figure: title, caption, axes, what is drawn and the legend of its lines (the marks'
/// kinds are added to it).
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Caption line below it (scene, mesh, group).
    pub caption: String,
    /// Horizontal axis title.
    pub x_label: String,
    /// Vertical axis title.
    pub y_label: String,
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Filled polygons, drawn first.
    pub polygons: Vec<(Vec<(f64, f64)>, RGBAColor)>,
    /// Wide translucent bands under the lines, (points, colour, width).
    pub bands: Vec<Band>,
    /// Lines, drawn in order.
    pub lines: Vec<Line>,
    /// Marks, drawn over the lines.
    pub marks: Vec<Mark>,
    /// The legend's entries for what is not a mark.
    pub legend: Vec<Entry>,
    /// Include y = 0 in the vertical range.
    pub with_zero: bool,
    /// Logarithmic axes (x, y): the points' values on such an axis are log10 of the
    /// quantity, and its ticks are labelled with the decades (`1e-3`, `1`, `10`).
    pub log: (bool, bool),
    /// The axes' ranges, when given (default: the data's, padded).
    pub ranges: Option<(Range<f64>, Range<f64>)>,
}

impl Plot {
    /// An empty plot of 900 × 650 pixels.
    pub fn new(
        title: impl Into<String>,
        caption: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            caption: caption.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            size: (900, 650),
            polygons: Vec::new(),
            bands: Vec::new(),
            lines: Vec::new(),
            marks: Vec::new(),
            legend: Vec::new(),
            with_zero: false,
            log: (false, false),
            ranges: None,
        }
    }

    /// The legend: the plot's entries, one per kind of keyed line drawn (`drawn`: the lines
    /// with a piece inside the plot), one per kind of mark in order of appearance, then the
    /// plot's notes.
    fn entries(&self, drawn: &[bool]) -> Vec<Entry> {
        let (notes, mut out): (Vec<Entry>, Vec<Entry>) = self
            .legend
            .iter()
            .cloned()
            .partition(|e| e.sample == Sample::Note);
        let mut kinds: Vec<String> = Vec::new();
        for (l, _) in self.lines.iter().zip(drawn).filter(|(_, &d)| d) {
            if let Some(k) = &l.kind {
                if !kinds.contains(k) {
                    kinds.push(k.clone());
                    out.push(Entry::new(
                        k.clone(),
                        Sample::Line(l.colour, l.width, l.dash),
                    ));
                }
            }
        }
        let mut marks: Vec<String> = Vec::new();
        for m in &self.marks {
            if !marks.contains(&m.kind) {
                marks.push(m.kind.clone());
                out.push(Entry::new(m.kind.clone(), Sample::Symbol(m.symbol)));
            }
        }
        out.extend(notes);
        out
    }
}

/// The range of `values` widened by 5 % on each side (a single value: ±5 % of it, or ±1 at
/// zero; no values: 0..1).
pub fn padded(values: impl Iterator<Item = f64>) -> Range<f64> {
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

/// A tick label on an axis spanning `span`: decimals to resolve a hundredth of the span,
/// and a plain `0` for a tick at zero up to round-off (never `-0.0`).
pub fn tick(v: f64, span: f64) -> String {
    if !v.is_finite() || !span.is_finite() || span <= 0.0 {
        return format!("{v}");
    }
    if v.abs() <= 1e-9 * span {
        return "0".to_string();
    }
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

/// The tick label of a logarithmic axis at log10 value `v`: the decade (`1e-3`, `1`, `10`,
/// `100`, `1e3`) at a whole power of ten, nothing between.
pub fn decade(v: f64) -> String {
    if !v.is_finite() || (v - v.round()).abs() > 1e-9 {
        return String::new();
    }
    match v.round() as i32 {
        0 => "1".to_string(),
        1 => "10".to_string(),
        2 => "100".to_string(),
        e => format!("1e{e}"),
    }
}

/// Font size of the title.
const TITLE: u32 = 24;
/// Font size of the caption line and legend.
const SMALL: u32 = 16;
/// Font size of the marks' labels.
pub const LABEL: u32 = 16;
/// Font size of the tick labels.
const TICKS: u32 = 16;
/// Height of the caption line in pixels.
pub const CAPTION_H: u32 = 26;

/// The plotters chart of the figures' style on `root`: the title, the axes over `xr` ×
/// `yr` with their titles, light grid lines and tick labels to the span's resolution; room
/// for the caption line below when there is one.
pub fn chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    title: &str,
    (x, y): (&str, &str),
    xr: Range<f64>,
    yr: Range<f64>,
    caption: bool,
    log: (bool, bool),
) -> Result<super::svg::Chart<'a, 'b>, Box<dyn Error>> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", TITLE))
        .margin(18)
        .margin_bottom(if caption { 18 + CAPTION_H } else { 18 })
        .x_label_area_size(52)
        .y_label_area_size(78)
        .build_cartesian_2d(xr.clone(), yr.clone())?;
    let (xs, ys) = (xr.end - xr.start, yr.end - yr.start);
    let label = |v: f64, span: f64, log: bool| if log { decade(v) } else { tick(v, span) };
    let xf = |v: &f64| label(*v, xs, log.0);
    let yf = |v: &f64| label(*v, ys, log.1);
    chart
        .configure_mesh()
        .x_desc(x)
        .y_desc(y)
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .label_style(("sans-serif", TICKS))
        .axis_desc_style(("sans-serif", 18))
        .bold_line_style(RGBColor(225, 225, 225))
        .light_line_style(RGBColor(245, 245, 245))
        .draw()?;
    Ok(chart)
}

/// Draws the caption line at the bottom left of `root`.
pub fn draw_caption(
    root: &DrawingArea<SVGBackend, Shift>,
    caption: &str,
    size: (u32, u32),
) -> Result<(), Box<dyn Error>> {
    if caption.is_empty() {
        return Ok(());
    }
    let font = ("sans-serif", SMALL)
        .into_font()
        .color(&RGBColor(70, 70, 70))
        .pos(Pos::new(HPos::Left, VPos::Top));
    let y = size.1 as i32 - CAPTION_H as i32 + 2;
    root.draw(&Text::new(caption.to_string(), (14, y), font))?;
    Ok(())
}

/// A line in pixel coordinates, drawn solid or dashed.
fn draw_line(
    area: &DrawingArea<SVGBackend, Shift>,
    pts: &[(i32, i32)],
    style: ShapeStyle,
    dash: Option<(u32, u32)>,
) -> Result<(), Box<dyn Error>> {
    if pts.len() < 2 {
        return Ok(());
    }
    match dash {
        None => area.draw(&PathElement::new(pts.to_vec(), style))?,
        Some((on, off)) => {
            for piece in dashes(pts, f64::from(on), f64::from(off)) {
                area.draw(&PathElement::new(piece, style))?;
            }
        }
    }
    Ok(())
}

/// The dashes of a polyline in pixels: pieces of length `on` with gaps `off`, the pattern
/// running on across the polyline's vertices.
fn dashes(pts: &[(i32, i32)], on: f64, off: f64) -> Vec<Vec<(i32, i32)>> {
    let mut out = Vec::new();
    let mut piece: Vec<(f64, f64)> = vec![(f64::from(pts[0].0), f64::from(pts[0].1))];
    let (mut drawing, mut left) = (true, on);
    for w in pts.windows(2) {
        let (a, b) = (
            (f64::from(w[0].0), f64::from(w[0].1)),
            (f64::from(w[1].0), f64::from(w[1].1)),
        );
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        let mut t = 0.0;
        while len - t > left {
            t += left;
            let p = (a.0 + (b.0 - a.0) * t / len, a.1 + (b.1 - a.1) * t / len);
            if drawing {
                piece.push(p);
                out.push(std::mem::take(&mut piece));
                left = off;
            } else {
                piece = vec![p];
                left = on;
            }
            drawing = !drawing;
        }
        left -= len - t;
        if drawing {
            piece.push(b);
        }
    }
    if drawing && piece.len() > 1 {
        out.push(piece);
    }
    out.into_iter()
        .map(|p| {
            p.into_iter()
                .map(|(x, y)| (x.round() as i32, y.round() as i32))
                .collect()
        })
        .collect()
}

/// The parts of a polyline inside the box [x0, x1] × [y0, y1] (segments clipped).
fn clip(points: &[(f64, f64)], xr: &Range<f64>, yr: &Range<f64>) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for w in points.windows(2) {
        let Some((a, b)) = clip_segment(w[0], w[1], xr, yr) else {
            open = false;
            continue;
        };
        if !open {
            runs.push(vec![a]);
            open = true;
        }
        if let Some(r) = runs.last_mut() {
            r.push(b);
        }
        // Leaving the box ends the run.
        if b != w[1] {
            open = false;
        }
    }
    runs
}

/// Liang–Barsky clipping of the segment a–b to the box.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    xr: &Range<f64>,
    yr: &Range<f64>,
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - xr.start),
        (dx, xr.end - a.0),
        (-dy, a.1 - yr.start),
        (dy, yr.end - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
    Some((
        if t0 > 0.0 { at(t0) } else { a },
        if t1 < 1.0 { at(t1) } else { b },
    ))
}

/// Places the labels of marks at pixel points `points` (text sizes `sizes`) inside `frame`
/// without overlapping each other, `obstacles` or any mark's symbol: each label in turn (left
/// to right) takes the free box of least cost around its point — the distance plus a
/// penalty per data point (`data`, pixels) it would hide — at growing distances in eight
/// directions. Returns each box and whether it needs a leader line (placed away from its
/// point); a label that finds no free box is left out (`None`).
pub fn place_labels(
    points: &[(f64, f64)],
    sizes: &[(f64, f64)],
    frame: Rect,
    obstacles: &[Rect],
    data: &[(f64, f64)],
) -> Vec<Option<(Rect, bool)>> {
    let s = f64::from(SYMBOL) + 1.0;
    let symbols: Vec<Rect> = points
        .iter()
        .map(|p| Rect::at(p.0 - s, p.1 - s, 2.0 * s, 2.0 * s))
        .collect();
    let mut taken: Vec<Rect> = obstacles.to_vec();
    taken.extend(symbols.iter().copied());
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0));
    let mut out = vec![None; points.len()];
    const RADII: [f64; 14] = [
        3.0, 12.0, 22.0, 34.0, 48.0, 64.0, 82.0, 104.0, 130.0, 160.0, 195.0, 235.0, 280.0, 330.0,
    ];
    // Directions: right-up first (the usual place of a label), then around.
    const DIRS: [(f64, f64); 8] = [
        (1.0, -1.0),
        (1.0, 1.0),
        (-1.0, -1.0),
        (-1.0, 1.0),
        (0.0, -1.0),
        (0.0, 1.0),
        (1.0, 0.0),
        (-1.0, 0.0),
    ];
    for k in order {
        let (p, (w, h)) = (points[k], sizes[k]);
        let mut best: Option<(f64, Rect, f64)> = None;
        for &r in &RADII {
            if best.as_ref().is_some_and(|b| b.0 < r) {
                break;
            }
            for (di, &(dx, dy)) in DIRS.iter().enumerate() {
                let ax = p.0 + dx * (r + s);
                let ay = p.1 + dy * (r + s);
                let x0 = if dx > 0.0 {
                    ax
                } else if dx < 0.0 {
                    ax - w
                } else {
                    p.0 - w / 2.0
                };
                let y0 = if dy > 0.0 {
                    ay
                } else if dy < 0.0 {
                    ay - h
                } else {
                    p.1 - h / 2.0
                };
                // The box, and the box slid along the frame's edge where it sticks out.
                let b = Rect::at(x0, y0, w, h);
                let slid = Rect::at(
                    x0.clamp(frame.x0, (frame.x1 - w).max(frame.x0)),
                    y0.clamp(frame.y0, (frame.y1 - h).max(frame.y0)),
                    w,
                    h,
                );
                for (k, b) in [b, slid].into_iter().enumerate() {
                    if !frame.holds(&b) || taken.iter().any(|o| o.overlaps(&b)) {
                        continue;
                    }
                    let hidden = data.iter().filter(|d| b.contains(**d)).count() as f64;
                    let d = distance(&b, p);
                    // A box as near to another point as to its own needs a leader line;
                    // one that does not is preferred.
                    let shared = ambiguous(&b, p, points);
                    let cost = d
                        + 12.0 * hidden
                        + di as f64 * 0.5
                        + k as f64 * 4.0
                        + if shared { AMBIGUOUS } else { 0.0 };
                    if best.as_ref().is_none_or(|b| cost < b.0) {
                        best = Some((cost, b, if shared { f64::INFINITY } else { d }));
                    }
                }
            }
        }
        if let Some((_, b, r)) = best {
            taken.push(b);
            out[k] = Some((b, r > f64::from(SYMBOL) + 14.0));
        }
    }
    out
}

/// What a box near another point than its own costs the placement, in pixels of distance.
const AMBIGUOUS: f64 = 40.0;

/// Points closer than this (pixels) are drawn as one: a label of either labels both.
pub const SAME_POINT: f64 = 4.0;

/// The distance from `p` to the box `b` (zero inside).
pub fn distance(b: &Rect, p: (f64, f64)) -> f64 {
    let n = b.nearest(p);
    (n.0 - p.0).hypot(n.1 - p.1)
}

/// True if a label in box `b` of the point `own` would be read as labelling another of
/// `points`: one apart from `own` (by [`SAME_POINT`] or more) that is no farther from the box
/// than `own` plus two pixels. Such a label needs a leader line.
pub fn ambiguous(b: &Rect, own: (f64, f64), points: &[(f64, f64)]) -> bool {
    let d = distance(b, own);
    points
        .iter()
        .any(|&q| (q.0 - own.0).hypot(q.1 - own.1) >= SAME_POINT && distance(b, q) <= d + 2.0)
}

/// Groups of marks (indices) whose pixel points lie closer than `gap` to another of the
/// group; only groups of two or more.
pub fn clusters(points: &[(f64, f64)], gap: f64) -> Vec<Vec<usize>> {
    let n = points.len();
    let mut group: Vec<usize> = (0..n).collect();
    fn root(g: &mut [usize], mut i: usize) -> usize {
        while g[i] != i {
            g[i] = g[g[i]];
            i = g[i];
        }
        i
    }
    for i in 0..n {
        for j in 0..i {
            let d = (points[i].0 - points[j].0).hypot(points[i].1 - points[j].1);
            if d < gap {
                let (a, b) = (root(&mut group, i), root(&mut group, j));
                group[a] = b;
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut roots: Vec<usize> = Vec::new();
    for i in 0..n {
        let r = root(&mut group, i);
        match roots.iter().position(|&x| x == r) {
            Some(k) => out[k].push(i),
            None => {
                roots.push(r);
                out.push(vec![i]);
            }
        }
    }
    out.retain(|g| g.len() > 1);
    out
}

/// The corners of `plot` for a box of `size`, with a margin: upper right, upper left, lower
/// right, lower left.
pub(super) fn corners(plot: Rect, size: (f64, f64)) -> [Rect; 4] {
    let m = 8.0;
    let (w, h) = size;
    [
        Rect::at(plot.x1 - m - w, plot.y0 + m, w, h),
        Rect::at(plot.x0 + m, plot.y0 + m, w, h),
        Rect::at(plot.x1 - m - w, plot.y1 - m - h, w, h),
        Rect::at(plot.x0 + m, plot.y1 - m - h, w, h),
    ]
}

/// Line samples in pixels: the points of every line and 8 between each pair.
fn samples(lines: &[Vec<(f64, f64)>]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for l in lines {
        for w in l.windows(2) {
            for k in 0..8 {
                let t = f64::from(k) / 8.0;
                out.push((
                    w[0].0 + t * (w[1].0 - w[0].0),
                    w[0].1 + t * (w[1].1 - w[0].1),
                ));
            }
        }
        out.extend(l.last().copied());
    }
    out
}

/// Draws the legend's entries into the box `b`; returns the texts of the entries that show
/// a marker's symbol.
pub(super) fn draw_legend(
    root: &DrawingArea<SVGBackend, Shift>,
    b: Rect,
    entries: &[Entry],
) -> Result<Vec<String>, Box<dyn Error>> {
    let mut symbols = Vec::new();
    let (x0, y0) = (b.x0 as i32, b.y0 as i32);
    root.draw(&Rectangle::new(
        [(x0, y0), (b.x1 as i32, b.y1 as i32)],
        WHITE.mix(0.9).filled(),
    ))?;
    root.draw(&Rectangle::new(
        [(x0, y0), (b.x1 as i32, b.y1 as i32)],
        RGBColor(60, 60, 60).stroke_width(1),
    ))?;
    for (k, e) in entries.iter().enumerate() {
        let y = y0 + 6 + LEGEND_ROW * k as i32 + LEGEND_ROW / 2;
        let (a, z) = (x0 + 8, x0 + 36);
        match &e.sample {
            Sample::Line(c, w, dash) => {
                draw_line(root, &[(a, y), (z, y)], c.stroke_width(*w), *dash)?;
            }
            Sample::Band(c, w) => {
                root.draw(&PathElement::new([(a, y), (z, y)], c.stroke_width(*w)))?;
            }
            Sample::Symbol(s) => {
                s.draw(root, ((a + z) / 2, y))?;
                symbols.push(e.text.clone());
            }
            Sample::Patch(c) => {
                root.draw(&Rectangle::new([(a, y - 7), (z, y + 7)], c.filled()))?;
                root.draw(&Rectangle::new(
                    [(a, y - 7), (z, y + 7)],
                    RGBColor(120, 120, 120).stroke_width(1),
                ))?;
            }
            Sample::Note => {}
        }
        let font = ("sans-serif", SMALL)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        root.draw(&Text::new(e.text.clone(), (x0 + 44, y), font))?;
    }
    Ok(symbols)
}

/// Height of a legend row in pixels.
const LEGEND_ROW: i32 = 21;

/// The legend's size in pixels.
pub(super) fn legend_size(entries: &[Entry]) -> (f64, f64) {
    let w = entries
        .iter()
        .map(|e| text_size(&e.text, SMALL).0)
        .fold(0.0, f64::max);
    (
        52.0 + w,
        12.0 + f64::from(LEGEND_ROW) * entries.len() as f64,
    )
}

/// Draws `plot` into an SVG string with its layout (see the module's description).
///
/// # Errors
/// A failure of the plotting library.
pub fn render(plot: &Plot) -> Result<(String, Layout), Box<dyn Error>> {
    let all = || {
        plot.lines
            .iter()
            .flat_map(|l| l.points.iter().copied())
            .chain(plot.polygons.iter().flat_map(|p| p.0.iter().copied()))
            .chain(plot.marks.iter().map(|m| m.at))
    };
    let (xr, yr) = plot.ranges.clone().unwrap_or_else(|| {
        (
            padded(all().map(|p| p.0)),
            padded(all().map(|p| p.1).chain(plot.with_zero.then_some(0.0))),
        )
    });
    // A line is drawn when a piece of it lies inside the axes' ranges.
    let drawn: Vec<bool> = plot
        .lines
        .iter()
        .map(|l| match plot.ranges {
            None => l.points.len() > 1,
            Some(_) => !clip(&l.points, &xr, &yr).is_empty(),
        })
        .collect();
    let entries = plot.entries(&drawn);
    // A caption line longer than the canvas widens it.
    let size = (
        plot.size
            .0
            .max(text_size(&plot.caption, SMALL).0.ceil() as u32 + 28),
        plot.size.1,
    );
    let mut layout = Layout {
        width: size.0,
        height: size.1,
        caption: plot.caption.clone(),
        legend: entries.iter().map(|e| e.text.clone()).collect(),
        ..Layout::default()
    };
    for (l, _) in plot.lines.iter().zip(&drawn).filter(|(_, &d)| d) {
        if let Some(k) = &l.kind {
            if !layout.line_kinds.contains(k) {
                layout.line_kinds.push(k.clone());
            }
        }
    }
    let keyed: Vec<&String> = plot.lines.iter().filter_map(|l| l.kind.as_ref()).collect();
    layout.legend_lines = entries
        .iter()
        .filter(|e| keyed.contains(&&e.text))
        .map(|e| e.text.clone())
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let chart = chart(
            &root,
            &plot.title,
            (&plot.x_label, &plot.y_label),
            xr.clone(),
            yr.clone(),
            !plot.caption.is_empty(),
            plot.log,
        )?;
        let (pxr, pyr) = chart.plotting_area().get_pixel_range();
        let frame = Rect {
            x0: f64::from(pxr.start),
            y0: f64::from(pyr.start),
            x1: f64::from(pxr.end),
            y1: f64::from(pyr.end),
        };
        layout.plot = Some(frame);
        let to_px = |p: (f64, f64)| {
            let (x, y) = chart.backend_coord(&p);
            (f64::from(x), f64::from(y))
        };
        let ipx = |p: (f64, f64)| chart.backend_coord(&p);
        // Given ranges cut the lines at the axes.
        let window = plot.ranges.as_ref().map(|_| (&xr, &yr));
        draw_data(&root, plot, &ipx, window)?;

        // Where the data are, in pixels: the legend and inset go where they hide least (the
        // legend where it hides the fewest marks, then the fewest line samples).
        let lines_px: Vec<Vec<(f64, f64)>> = plot
            .lines
            .iter()
            .flat_map(|l| match window {
                None => vec![l.points.clone()],
                Some((xr, yr)) => clip(&l.points, xr, yr),
            })
            .map(|l| l.iter().map(|&p| to_px(p)).collect())
            .collect();
        let mut data = samples(&lines_px);
        let mark_px: Vec<(f64, f64)> = plot.marks.iter().map(|m| to_px(m.at)).collect();
        data.extend(mark_px.iter().copied());
        let polys: Vec<(f64, f64)> = plot
            .polygons
            .iter()
            .flat_map(|p| p.0.iter().map(|&q| to_px(q)))
            .collect();
        let hidden = |b: &Rect, pts: &[(f64, f64)]| pts.iter().filter(|p| b.contains(**p)).count();
        let legend_size = legend_size(&entries);
        let mut free = corners(frame, legend_size).to_vec();
        let mut used: Vec<Rect> = Vec::new();
        if !entries.is_empty() {
            let b = *free
                .iter()
                .min_by_key(|b| (hidden(b, &mark_px), hidden(b, &data), hidden(b, &polys)))
                .unwrap_or(&free[0]);
            layout.legend_box = Some(b);
            used.push(b);
            free.clear();
        }

        // The largest cluster of labelled marks closer than a label's height goes into an
        // inset, when one fits.
        let label_h = text_size("Hg", LABEL).1;
        let labelled: Vec<usize> = (0..plot.marks.len())
            .filter(|&i| !plot.marks[i].label.is_empty())
            .collect();
        let lp: Vec<(f64, f64)> = labelled.iter().map(|&i| mark_px[i]).collect();
        let cluster: Vec<usize> = clusters(&lp, label_h)
            .into_iter()
            .max_by_key(Vec::len)
            .unwrap_or_default()
            .into_iter()
            .map(|k| labelled[k])
            .collect();
        let mut in_inset = vec![false; plot.marks.len()];
        let mut inset_left = Vec::new();
        if !cluster.is_empty() {
            let inset_size = (
                ((frame.x1 - frame.x0) * 0.46).round(),
                ((frame.y1 - frame.y0) * 0.46).round(),
            );
            // Never over a mark: the cluster's, or any other the inset would hide.
            let choices: Vec<Rect> = corners(frame, inset_size)
                .into_iter()
                .filter(|b| !used.iter().any(|u| u.overlaps(b)))
                .filter(|b| !mark_px.iter().any(|p| b.contains(*p)))
                .collect();
            if let Some(b) = choices.iter().min_by_key(|b| hidden(b, &data)).copied() {
                layout.inset = Some(b);
                used.push(b);
                for &i in &cluster {
                    in_inset[i] = true;
                }
                inset_left = draw_inset(&root, plot, b, &cluster, (&xr, &yr), &chart, &mut layout)?;
            }
        }

        for m in &plot.marks {
            let (x, y) = ipx(m.at);
            m.symbol.draw(&root, (x, y))?;
            if !layout.marker_kinds.contains(&m.kind) {
                layout.marker_kinds.push(m.kind.clone());
            }
        }
        let mut todo: Vec<(usize, (f64, f64))> = (0..plot.marks.len())
            .filter(|&i| !in_inset[i] && !plot.marks[i].label.is_empty())
            .map(|i| (i, mark_px[i]))
            .collect();
        // Labels the inset had no room for come first, from their point in the inset.
        todo.splice(0..0, inset_left);
        // The marks of the inset's cluster are obstacles too.
        let mut obstacles = used.clone();
        obstacles.extend(
            (0..plot.marks.len())
                .filter(|&i| in_inset[i])
                .map(|i| Rect::at(mark_px[i].0 - 8.0, mark_px[i].1 - 8.0, 16.0, 16.0)),
        );
        let left = label_marks(
            &root,
            plot,
            todo,
            &[frame],
            &obstacles,
            &data,
            false,
            &mut layout,
        )?;
        layout.dropped = left
            .into_iter()
            .map(|(i, _)| plot.marks[i].label.clone())
            .collect();
        if let Some(b) = layout.legend_box {
            layout.legend_markers = draw_legend(&root, b, &entries)?;
        }
        draw_caption(&root, &plot.caption, size)?;
        root.present()?;
    }
    Ok((svg, layout))
}

/// Draws the labels `placed` of the marks `which` (index and pixel point) with their leader
/// lines, and records them in `layout`; returns the marks whose label found no place.
fn draw_labels(
    root: &DrawingArea<SVGBackend, Shift>,
    plot: &Plot,
    which: &[(usize, (f64, f64))],
    placed: &[Option<(Rect, bool)>],
    inset: bool,
    layout: &mut Layout,
) -> Result<ToLabel, Box<dyn Error>> {
    let mut failed = Vec::new();
    for (&(i, from), p) in which.iter().zip(placed) {
        let Some((b, leader)) = *p else {
            failed.push((i, from));
            continue;
        };
        let m = &plot.marks[i];
        if leader {
            let to = b.nearest(from);
            // From the symbol's edge to the box.
            let len = (to.0 - from.0).hypot(to.1 - from.1).max(1e-9);
            // (from the point itself when the box is nearer than the symbol's edge)
            let s = (f64::from(SYMBOL) + 1.0).min(len / 2.0);
            let start = (
                from.0 + (to.0 - from.0) * s / len,
                from.1 + (to.1 - from.1) * s / len,
            );
            root.draw(&PathElement::new(
                [
                    (start.0.round() as i32, start.1.round() as i32),
                    (to.0.round() as i32, to.1.round() as i32),
                ],
                RGBColor(110, 110, 110).stroke_width(1),
            ))?;
        }
        let font = ("sans-serif", LABEL)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Top));
        root.draw(&Text::new(
            m.label.clone(),
            ((b.x0 + 1.0).round() as i32, b.y0.round() as i32),
            font,
        ))?;
        layout.labels.push(PlacedLabel {
            text: m.label.clone(),
            rect: b,
            leader,
            in_inset: inset,
            at: from,
        });
    }
    Ok(failed)
}

/// Places and draws the labels of `which` (mark index, pixel point) in `frames` in turn
/// (each pass takes the labels the one before could not place), avoiding `obstacles`,
/// the boxes of `layout`'s labels and the data `data`; returns the marks left without a
/// place.
#[allow(clippy::too_many_arguments)]
fn label_marks(
    root: &DrawingArea<SVGBackend, Shift>,
    plot: &Plot,
    which: Vec<(usize, (f64, f64))>,
    frames: &[Rect],
    obstacles: &[Rect],
    data: &[(f64, f64)],
    inset: bool,
    layout: &mut Layout,
) -> Result<ToLabel, Box<dyn Error>> {
    let mut todo = which;
    for &frame in frames {
        if todo.is_empty() {
            break;
        }
        let mut taken = obstacles.to_vec();
        taken.extend(layout.labels.iter().map(|l| l.rect));
        let pts: Vec<(f64, f64)> = todo.iter().map(|t| t.1).collect();
        let sizes: Vec<(f64, f64)> = todo
            .iter()
            .map(|t| text_size(&plot.marks[t.0].label, LABEL))
            .collect();
        let placed = place_labels(&pts, &sizes, frame, &taken, data);
        todo = draw_labels(root, plot, &todo, &placed, inset, layout)?;
    }
    Ok(todo)
}

/// Draws the plot's polygons, bands and lines through `px` (data to pixels), each line clipped
/// to `window` (data ranges) when given.
fn draw_data(
    root: &DrawingArea<SVGBackend, Shift>,
    plot: &Plot,
    px: &dyn Fn((f64, f64)) -> (i32, i32),
    window: Option<(&Range<f64>, &Range<f64>)>,
) -> Result<(), Box<dyn Error>> {
    let pieces = |pts: &[(f64, f64)]| -> Vec<Vec<(i32, i32)>> {
        match window {
            None => vec![pts.iter().map(|&p| px(p)).collect()],
            Some((xr, yr)) => clip(pts, xr, yr)
                .into_iter()
                .map(|r| r.into_iter().map(px).collect())
                .collect(),
        }
    };
    for (poly, c) in &plot.polygons {
        if let Some((xr, yr)) = window {
            if !poly.iter().any(|p| xr.contains(&p.0) && yr.contains(&p.1)) {
                continue;
            }
        }
        let pts: Vec<(i32, i32)> = poly.iter().map(|&p| px(p)).collect();
        root.draw(&Polygon::new(pts, c.filled()))?;
    }
    for (pts, c, w) in &plot.bands {
        for piece in pieces(pts) {
            draw_line(root, &piece, c.stroke_width(*w), None)?;
        }
    }
    for l in &plot.lines {
        let style = l.colour.mix(l.alpha).stroke_width(l.width);
        for piece in pieces(&l.points) {
            draw_line(root, &piece, style, l.dash)?;
        }
    }
    Ok(())
}

/// Draws the inset in box `b`: the data around the marks `cluster` zoomed, with their
/// symbols and labels, and a frame around the cluster in the main plot joined to it; the
/// labels go into `layout`. Returns the marks (with their point in the inset) whose label
/// found no room in it.
fn draw_inset(
    root: &DrawingArea<SVGBackend, Shift>,
    plot: &Plot,
    b: Rect,
    cluster: &[usize],
    (xr, yr): (&Range<f64>, &Range<f64>),
    main: &super::svg::Chart,
    layout: &mut Layout,
) -> Result<ToLabel, Box<dyn Error>> {
    // The window: the cluster's box, widened to a fifth of the plot's span at least and by
    // 80 % each side, so that the labels find room.
    let at: Vec<(f64, f64)> = cluster.iter().map(|&i| plot.marks[i].at).collect();
    let widen = |v: &mut dyn Iterator<Item = f64>, span: f64| {
        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        let w = (hi - lo).max(span * 0.004);
        (lo - 0.8 * w)..(hi + 0.8 * w)
    };
    let wx = widen(&mut at.iter().map(|p| p.0), xr.end - xr.start);
    let wy = widen(&mut at.iter().map(|p| p.1), yr.end - yr.start);
    // The frame in the main plot.
    let (fa, fb) = (
        main.backend_coord(&(wx.start, wy.end)),
        main.backend_coord(&(wx.end, wy.start)),
    );
    let grey = RGBColor(90, 90, 90);
    root.draw(&Rectangle::new([fa, fb], grey.stroke_width(1)))?;
    let (bx0, by0, bx1, by1) = (b.x0 as i32, b.y0 as i32, b.x1 as i32, b.y1 as i32);
    // A connector from the frame to the inset's nearest corner.
    let fc = (f64::from(fa.0 + fb.0) / 2.0, f64::from(fa.1 + fb.1) / 2.0);
    let corner = b.nearest(fc);
    root.draw(&PathElement::new(
        [
            (fc.0.round() as i32, fc.1.round() as i32),
            (corner.0.round() as i32, corner.1.round() as i32),
        ],
        grey.mix(0.6).stroke_width(1),
    ))?;
    let area = root.clone().shrink(
        (bx0, by0),
        ((bx1 - bx0).max(1) as u32, (by1 - by0).max(1) as u32),
    );
    area.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&area)
        .margin(6)
        .x_label_area_size(26)
        .y_label_area_size(58)
        .build_cartesian_2d(wx.clone(), wy.clone())?;
    let (sx, sy) = (wx.end - wx.start, wy.end - wy.start);
    // On a logarithmic axis the inset's window is a fraction of a decade: its ticks give the
    // quantity's values.
    let label = |v: f64, span: f64, log: bool| {
        if log {
            super::svg::short(10f64.powf(v))
        } else {
            tick(v, span)
        }
    };
    let xf = |v: &f64| label(*v, sx, plot.log.0);
    let yf = |v: &f64| label(*v, sy, plot.log.1);
    chart
        .configure_mesh()
        .x_labels(3)
        .y_labels(4)
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .label_style(("sans-serif", 13))
        .bold_line_style(RGBColor(230, 230, 230))
        .light_line_style(WHITE)
        .draw()?;
    let ipx = |p: (f64, f64)| chart.backend_coord(&p);
    draw_data(root, plot, &ipx, Some((&wx, &wy)))?;
    root.draw(&Rectangle::new(
        [(bx0, by0), (bx1, by1)],
        grey.stroke_width(1),
    ))?;
    let (pxr, pyr) = chart.plotting_area().get_pixel_range();
    let frame = Rect {
        x0: f64::from(pxr.start),
        y0: f64::from(pyr.start),
        x1: f64::from(pxr.end),
        y1: f64::from(pyr.end),
    };
    let mark_px: Vec<(f64, f64)> = plot
        .marks
        .iter()
        .map(|m| {
            let (x, y) = ipx(m.at);
            (f64::from(x), f64::from(y))
        })
        .collect();
    // Every mark inside the window is drawn; the cluster's are labelled.
    let inside = |p: (f64, f64)| wx.contains(&p.0) && wy.contains(&p.1);
    for m in plot.marks.iter().filter(|m| inside(m.at)) {
        m.symbol.draw(root, ipx(m.at))?;
    }
    let lines_px: Vec<Vec<(f64, f64)>> = plot
        .lines
        .iter()
        .flat_map(|l| clip(&l.points, &wx, &wy))
        .map(|r| {
            r.into_iter()
                .map(|p| {
                    let (x, y) = ipx(p);
                    (f64::from(x), f64::from(y))
                })
                .collect()
        })
        .collect();
    let data = samples(&lines_px);
    let others: Vec<Rect> = plot
        .marks
        .iter()
        .enumerate()
        .filter(|(i, m)| !cluster.contains(i) && inside(m.at))
        .map(|(i, _)| Rect::at(mark_px[i].0 - 7.0, mark_px[i].1 - 7.0, 14.0, 14.0))
        .collect();
    let which: Vec<(usize, (f64, f64))> = cluster.iter().map(|&i| (i, mark_px[i])).collect();
    label_marks(root, plot, which, &[frame], &others, &data, true, layout)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_one_point_do_not_overlap_and_get_leaders() {
        let frame = Rect::at(0.0, 0.0, 800.0, 600.0);
        let pts = [(400.0, 300.0); 5];
        let sizes = [(90.0, 16.0); 5];
        let placed = place_labels(&pts, &sizes, frame, &[], &[]);
        let boxes: Vec<Rect> = placed.iter().map(|p| p.unwrap().0).collect();
        for i in 0..5 {
            assert!(frame.holds(&boxes[i]));
            for j in 0..i {
                assert!(!boxes[i].overlaps(&boxes[j]), "{boxes:?}");
            }
        }
        assert!(placed.iter().filter(|p| p.unwrap().1).count() >= 1);
    }

    #[test]
    fn a_label_nearer_another_point_than_its_own_gets_a_leader() {
        let frame = Rect::at(0.0, 0.0, 800.0, 600.0);
        // Three points a few pixels apart in a row, and one far away.
        let pts = [
            (400.0, 300.0),
            (410.0, 300.0),
            (420.0, 302.0),
            (100.0, 100.0),
        ];
        let sizes = [(110.0, 16.0); 4];
        let placed = place_labels(&pts, &sizes, frame, &[], &[]);
        for (k, p) in placed.iter().enumerate() {
            let (b, leader) = p.unwrap();
            assert!(
                leader || !ambiguous(&b, pts[k], &pts),
                "label {k} at {b:?} reads as another point's"
            );
        }
        // The lone point's label sits next to it.
        assert!(!placed[3].unwrap().1);
        // Points closer than SAME_POINT are one: a box beside both is not ambiguous.
        let b = Rect::at(410.0, 290.0, 50.0, 16.0);
        assert!(!ambiguous(&b, (400.0, 300.0), &[(401.0, 301.0)]));
        assert!(ambiguous(&b, (400.0, 300.0), &[(420.0, 300.0)]));
    }

    #[test]
    fn clusters_join_close_points() {
        let c = clusters(&[(0.0, 0.0), (5.0, 0.0), (100.0, 0.0), (9.0, 3.0)], 8.0);
        assert_eq!(c, [vec![0, 1, 3]]);
        assert!(clusters(&[(0.0, 0.0), (50.0, 0.0)], 8.0).is_empty());
    }

    #[test]
    fn dashes_run_across_vertices() {
        let d = dashes(&[(0, 0), (10, 0), (20, 0)], 8.0, 4.0);
        assert_eq!(d[0], [(0, 0), (8, 0)]);
        assert_eq!(d[1], [(12, 0), (20, 0)]);
        assert_eq!(
            dashes(&[(0, 0), (3, 0), (6, 0)], 8.0, 4.0),
            [vec![(0, 0), (3, 0), (6, 0)]]
        );
    }

    #[test]
    fn clipping_keeps_the_inside() {
        let r = clip(&[(-1.0, 0.5), (2.0, 0.5)], &(0.0..1.0), &(0.0..1.0));
        assert_eq!(r, [vec![(0.0, 0.5), (1.0, 0.5)]]);
        assert!(clip(&[(2.0, 2.0), (3.0, 3.0)], &(0.0..1.0), &(0.0..1.0)).is_empty());
    }

    fn mark(at: (f64, f64), symbol: Symbol, kind: &str, label: &str) -> Mark {
        Mark {
            at,
            symbol,
            kind: kind.into(),
            label: label.into(),
        }
    }

    #[test]
    fn the_legend_shows_exactly_the_marker_kinds_drawn() {
        let mut plot = Plot::new("t", "scene s · mesh: disc, 8 triangles", "x", "y");
        plot.lines
            .push(Line::new(vec![(0.0, 0.0), (1.0, 1.0)], BLACK, 2, None));
        plot.legend
            .push(Entry::new("path", Sample::Line(BLACK, 2, None)));
        let cross = Symbol::Cross(BLACK);
        plot.marks
            .push(mark((0.2, 0.2), cross, "bifurcation point", "a"));
        plot.marks
            .push(mark((0.8, 0.8), Symbol::Disc(BLACK), "turning point", "b"));
        plot.marks
            .push(mark((0.5, 0.5), cross, "bifurcation point", "c"));
        let (_, layout) = render(&plot).unwrap();
        assert_eq!(layout.marker_kinds, ["bifurcation point", "turning point"]);
        assert_eq!(layout.legend_markers, layout.marker_kinds);
        assert_eq!(
            layout.legend,
            ["path", "bifurcation point", "turning point"]
        );
        assert_eq!(layout.labels.len(), 3);
        plot.marks.clear();
        let (_, layout) = render(&plot).unwrap();
        assert!(layout.marker_kinds.is_empty() && layout.legend_markers.is_empty());
        assert_eq!(layout.legend, ["path"]);
    }

    #[test]
    fn keyed_lines_get_a_legend_entry_only_when_drawn() {
        let mut plot = Plot::new("t", "scene s · mesh: disc, 8 triangles", "x", "y");
        plot.lines
            .push(Line::new(vec![(0.0, 0.0), (1.0, 1.0)], BLACK, 2, None).kind("stable (index 0)"));
        plot.lines.push(
            Line::new(vec![(0.5, 0.5), (1.0, 0.0)], BLACK, 2, Some((8, 5)))
                .kind("stable (index 0)"),
        );
        plot.lines.push(
            Line::new(vec![(3.0, 3.0), (4.0, 4.0)], BLACK, 2, Some((8, 5)))
                .kind("unstable (index 1)"),
        );
        // Both inside: an entry each, the first line's style for the shared kind.
        let (_, layout) = render(&plot).unwrap();
        assert_eq!(
            layout.line_kinds,
            ["stable (index 0)", "unstable (index 1)"]
        );
        assert_eq!(layout.legend_lines, layout.line_kinds);
        assert_eq!(layout.legend, ["stable (index 0)", "unstable (index 1)"]);
        // The axes cut off the unstable line: no entry for it.
        plot.ranges = Some((0.0..2.0, 0.0..2.0));
        let (svg, layout) = render(&plot).unwrap();
        assert_eq!(layout.line_kinds, ["stable (index 0)"]);
        assert_eq!(layout.legend_lines, ["stable (index 0)"]);
        assert!(!svg.contains("unstable"));
    }

    #[test]
    fn a_cluster_of_marks_goes_into_an_inset() {
        let mut plot = Plot::new("t", "c", "x", "y");
        plot.lines.push(Line::new(
            (0..=100).map(|i| (f64::from(i) / 100.0, 0.1)).collect(),
            BLACK,
            2,
            None,
        ));
        let cross = Symbol::Cross(BLACK);
        for (k, x) in [0.100, 0.101, 0.102].into_iter().enumerate() {
            plot.marks.push(mark(
                (x, 0.1),
                cross,
                "bifurcation point",
                &format!("point {k}"),
            ));
        }
        plot.marks
            .push(mark((0.9, 0.1), cross, "bifurcation point", "far"));
        let (_, layout) = render(&plot).unwrap();
        let inset = layout.inset.expect("an inset");
        let zoomed: Vec<&PlacedLabel> = layout.labels.iter().filter(|l| l.in_inset).collect();
        assert_eq!(zoomed.len(), 3, "{:?}", layout.labels);
        assert!(zoomed.iter().all(|l| inset.holds(&l.rect)));
        let far = layout.labels.iter().find(|l| l.text == "far").unwrap();
        assert!(!far.in_inset && !far.rect.overlaps(&inset));
        for (i, a) in layout.labels.iter().enumerate() {
            for b in &layout.labels[..i] {
                assert!(!a.rect.overlaps(&b.rect), "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn layout_round_trips_through_the_svg() {
        let layout = Layout {
            width: 10,
            caption: "a <b> & c".into(),
            ..Layout::default()
        };
        let svg = finish(
            "<svg width=\"10\">\n<text font-family=\"sans-serif\">x</text></svg>",
            &layout,
        );
        assert!(svg.contains(FONT_FAMILY));
        assert_eq!(read_layout(&svg), Some(layout));
    }
}
