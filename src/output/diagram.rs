//! `diagram.svg`: the bifurcation diagram of a run with branches — the path and every branch
//! in one picture, the control against the signed asymmetry (the RMS of the part of the state
//! outside the scene group's fixed-point space, signed by the branch's half: 0 on the path).
//! Stable stretches are solid, unstable ones dashed; the path is black, each branch is
//! coloured by its isotropy subgroup's class (one legend entry per class); critical points
//! are crosses labelled with their kind and irrep.

use super::figure::{self, finish, Entry, Layout, Line, Mark, Plot, Sample, Symbol};
use super::svg::{short, xml_chars, PALETTE};
use super::{write_whole, OutputError};
use plotters::style::colors::BLACK;
use plotters::style::RGBColor;
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
    /// What kind of point it is (`critical point`, `solution`, …): its legend entry; each
    /// kind has its own symbol.
    pub kind: String,
}

/// What `diagram.svg` shows.
#[derive(Debug, Clone, PartialEq)]
pub struct BifurcationDiagram {
    /// The title.
    pub title: String,
    /// The caption line below the plot: the scene and its mesh.
    pub caption: String,
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
    let (svg, layout) = render(diagram)
        .map_err(|e| OutputError::invalid(&path, format!("plotting failed: {e}")))?;
    let svg = xml_chars(&finish(&svg, &layout));
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

/// The symbols of the marks' kinds, in order of first appearance.
const SYMBOLS: [Symbol; 4] = [
    Symbol::Cross(BLACK),
    Symbol::Disc(RGBColor(200, 30, 30)),
    Symbol::Square(RGBColor(20, 140, 60)),
    Symbol::Ring(BLACK),
];

fn render(diagram: &BifurcationDiagram) -> Result<(String, Layout), Box<dyn Error>> {
    let classes = classes(diagram);
    let colour = |class: &str| {
        classes
            .iter()
            .position(|c| c == class)
            .map_or(BLACK, |k| PALETTE[k % PALETTE.len()])
    };
    let mut plot = Plot::new(
        diagram.title.as_str(),
        diagram.caption.as_str(),
        diagram.control.as_str(),
        diagram.y_axis.as_str(),
    );
    plot.with_zero = true;
    let mut legend_done: Vec<String> = Vec::new();
    let (mut any_stable, mut any_unstable) = (false, false);
    const DASH: (u32, u32) = (7, 5);
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
            any_stable |= stable;
            any_unstable |= !stable;
            plot.lines
                .push(Line::new(pts, c, width, (!stable).then_some(DASH)));
        }
        if !legend_done.contains(&l.class) {
            legend_done.push(l.class.clone());
            plot.legend
                .push(Entry::new(l.class.clone(), Sample::Line(c, width, None)));
        }
    }
    // The line styles, as legend entries of their own, for the styles drawn.
    let grey = RGBColor(90, 90, 90);
    if any_stable {
        plot.legend
            .push(Entry::new("stable: solid", Sample::Line(grey, 2, None)));
    }
    if any_unstable {
        plot.legend.push(Entry::new(
            "unstable: dashed",
            Sample::Line(grey, 2, Some(DASH)),
        ));
    }
    let mut kinds: Vec<&str> = Vec::new();
    for m in &diagram.marks {
        let k = kinds.iter().position(|k| *k == m.kind).unwrap_or_else(|| {
            kinds.push(&m.kind);
            kinds.len() - 1
        });
        plot.marks.push(Mark {
            at: (m.x, m.y),
            symbol: SYMBOLS[k % SYMBOLS.len()],
            kind: m.kind.clone(),
            label: format!("{} ({})", m.label, short(m.x)),
        });
    }
    figure::render(&plot)
}
