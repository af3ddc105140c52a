//! `surface.vtu`, `surface.json` and `surface.svg`: an equilibrium surface
//! ([`SurfaceReport`]).

use super::figure::{self, finish, Entry, Layout, Line, Mark, Plot, Sample, Symbol};
use super::scales::Scales;
use super::svg::xml_chars;
use super::{write_whole, Num, OutputError};
use crate::results::{CriticalKind, SurfaceReport};
use plotters::prelude::*;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// VTK's cell type of a triangle.
const VTK_TRIANGLE: u8 = 5;
/// VTK's cell type of a line segment.
const VTK_LINE: u8 = 3;

/// The columns of a, b and the chosen measure, or why they are missing.
fn columns(path: &Path, s: &SurfaceReport) -> Result<(usize, usize, usize), OutputError> {
    match (s.parameter(&s.a), s.parameter(&s.b), s.measure_column()) {
        (Some(a), Some(b), Some(m)) => Ok((a, b, m)),
        _ => Err(OutputError::invalid(
            path,
            format!(
                "'{}', '{}' or the measure '{}' is not a column of the surface",
                s.a, s.b, s.measure
            ),
        )),
    }
}

/// Refuses a surface with a non-finite number, naming the path, the vertex and the column.
fn check_finite(path: &Path, s: &SurfaceReport) -> Result<(), OutputError> {
    let names: Vec<&str> = s
        .parameters
        .iter()
        .chain(&s.measures)
        .map(String::as_str)
        .collect();
    for (j, p) in s.paths.iter().enumerate() {
        let values =
            p.vertices
                .iter()
                .map(|v| (format!("vertex {}", v.step), &v.parameters, &v.measures))
                .chain(
                    p.critical.iter().enumerate().map(|(c, cp)| {
                        (format!("critical point {c}"), &cp.parameters, &cp.measures)
                    }),
                );
        for (what, params, measures) in values {
            if let Some((name, v)) = names
                .iter()
                .zip(params.iter().chain(measures))
                .find(|(_, v)| !v.is_finite())
            {
                return Err(OutputError::invalid(
                    path,
                    format!("path {j}, {what}: {name} is {v} (not finite)"),
                ));
            }
        }
    }
    Ok(())
}

/// Writes `surface.vtu`, `surface.json`, `surface.svg` and `surface.png` (the same figure as an
/// image) into `dir`; returns their paths.
///
/// `surface.vtu` (VTK XML unstructured grid, ASCII) has a point per path vertex at
/// (a, b, measure), path after path, then a point per point of every critical line; its
/// cells are the triangles between neighbouring paths and the segments of the critical lines.
/// Point data: `index` (the instability index; −1 where it was not computed and at the
/// critical points, where it changes), `path` (the path's number; −1 for critical points),
/// `critical_line` (the line's number; −1 for path vertices) and every measure.
/// `surface.json` is the whole report; `surface.svg` draws the measure against a: the
/// triangles and the paths coloured by index, the critical lines in black (limit lines
/// solid, bifurcation lines dashed).
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite value or a surface without vertices (nothing
/// is written), else as the other writers.
pub fn write_surface(dir: &Path, s: &SurfaceReport) -> Result<Vec<PathBuf>, OutputError> {
    write_surface_with(dir, s, &Scales::default(), "")
}

/// As [`write_surface`], `surface.svg`'s axes titled and scaled by `scales` and `caption`
/// (the scene and its mesh) written below the plot.
///
/// # Errors
/// As [`write_surface`].
pub fn write_surface_with(
    dir: &Path,
    s: &SurfaceReport,
    scales: &Scales,
    caption: &str,
) -> Result<Vec<PathBuf>, OutputError> {
    let vtu = dir.join("surface.vtu");
    let json = dir.join("surface.json");
    let svg_path = dir.join("surface.svg");
    check_finite(&vtu, s)?;
    let (a, b, m) = columns(&vtu, s)?;
    if s.vertex_count() == 0 {
        return Err(OutputError::invalid(&vtu, "the surface has no vertices"));
    }
    let (svg, mut layout) = render(s, a, m, scales, caption)
        .map_err(|e| OutputError::invalid(&svg_path, format!("plotting failed: {e}")))?;
    layout.scales = [&s.a, &s.b, &s.measure]
        .into_iter()
        .map(|q| figure::QuantityScale::new(q, &scales.or_name(q)))
        .collect();
    let svg = finish(&svg, &layout);
    write_whole(&vtu, |w| write_vtu(w, s, (a, b, m)))?;
    write_whole(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, s).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    write_whole(&svg_path, |w| w.write_all(xml_chars(&svg).as_bytes()))?;
    let png = super::write_png_beside(&svg_path)?;
    Ok(vec![vtu, json, svg_path, png])
}

/// One ASCII data array of the VTU.
fn array<T: std::fmt::Display>(
    w: &mut dyn Write,
    kind: &str,
    name: &str,
    components: usize,
    values: impl Iterator<Item = T>,
) -> io::Result<()> {
    let name = if name.is_empty() {
        String::new()
    } else {
        format!(" Name=\"{name}\"")
    };
    // Scalars without NumberOfComponents: readers then keep them one-dimensional.
    let components = if components > 1 {
        format!(" NumberOfComponents=\"{components}\"")
    } else {
        String::new()
    };
    write!(
        w,
        "        <DataArray type=\"{kind}\"{name}{components} format=\"ascii\">"
    )?;
    for (i, v) in values.enumerate() {
        if i > 0 {
            write!(w, " ")?;
        }
        write!(w, "{v}")?;
    }
    writeln!(w, "</DataArray>")
}

fn write_vtu(
    w: &mut dyn Write,
    s: &SurfaceReport,
    (a, b, m): (usize, usize, usize),
) -> io::Result<()> {
    let line_points = s.lines.iter().flat_map(|l| &l.points);
    let points: Vec<[f64; 3]> = s
        .vertices()
        .map(|v| [v.parameters[a], v.parameters[b], v.measures[m]])
        .chain(
            line_points
                .clone()
                .map(|p| [p.parameters[a], p.parameters[b], p.measures[m]]),
        )
        .collect();
    let nv = s.vertex_count();
    let mut segments: Vec<[usize; 2]> = Vec::new();
    let mut first = nv;
    for l in &s.lines {
        segments.extend((1..l.points.len()).map(|i| [first + i - 1, first + i]));
        first += l.points.len();
    }
    let cells = s.triangles.len() + segments.len();
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{cells}\">",
        points.len()
    )?;
    writeln!(w, "      <Points>")?;
    array(
        w,
        "Float64",
        "",
        3,
        points.iter().flatten().map(|&x| Num(x)),
    )?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    let connectivity = s
        .triangles
        .iter()
        .flatten()
        .chain(segments.iter().flatten());
    array(w, "Int64", "connectivity", 1, connectivity)?;
    let offsets = (1..=s.triangles.len())
        .map(|i| 3 * i)
        .chain((1..=segments.len()).map(|i| 3 * s.triangles.len() + 2 * i));
    array(w, "Int64", "offsets", 1, offsets)?;
    let types = std::iter::repeat_n(VTK_TRIANGLE, s.triangles.len())
        .chain(std::iter::repeat_n(VTK_LINE, segments.len()));
    array(w, "UInt8", "types", 1, types)?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "      <PointData>")?;
    let critical = line_points.clone().count();
    let index = s
        .vertices()
        .map(|v| v.index.map_or(-1, |i| i as i64))
        .chain(std::iter::repeat_n(-1, critical));
    array(w, "Int32", "index", 1, index)?;
    let path = s
        .paths
        .iter()
        .enumerate()
        .flat_map(|(j, p)| std::iter::repeat_n(j as i64, p.vertices.len()))
        .chain(std::iter::repeat_n(-1, critical));
    array(w, "Int32", "path", 1, path)?;
    let line = std::iter::repeat_n(-1i64, nv).chain(
        s.lines
            .iter()
            .enumerate()
            .flat_map(|(k, l)| std::iter::repeat_n(k as i64, l.points.len())),
    );
    array(w, "Int32", "critical_line", 1, line)?;
    for (k, name) in s.measures.iter().enumerate() {
        let values = s
            .vertices()
            .map(|v| v.measures[k])
            .chain(line_points.clone().map(|p| p.measures[k]))
            .map(Num);
        array(w, "Float64", name, 1, values)?;
    }
    writeln!(w, "      </PointData>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

/// The colour of an index: blue for the stable states, then warmer with every negative
/// eigenvalue; grey where it is unknown.
fn index_colour(index: Option<usize>) -> RGBColor {
    match index {
        None => RGBColor(150, 150, 150),
        Some(0) => RGBColor(31, 87, 180),
        Some(1) => RGBColor(230, 120, 20),
        Some(2) => RGBColor(200, 30, 30),
        Some(_) => RGBColor(120, 40, 140),
    }
}

/// The measure (column `m`) against a (column `a`): triangles and paths by index, the
/// critical lines over them; axes titled and scaled by `scales`.
fn render(
    s: &SurfaceReport,
    a: usize,
    m: usize,
    scales: &Scales,
    caption: &str,
) -> Result<(String, Layout), Box<dyn std::error::Error>> {
    let (xs, ys) = (scales.or_name(&s.a), scales.or_name(&s.measure));
    let vertices: Vec<_> = s.vertices().collect();
    let at = |i: usize| {
        (
            vertices[i].parameters[a] * xs.factor,
            vertices[i].measures[m] * ys.factor,
        )
    };
    let (lo, hi) = (
        s.paths.first().map_or(0.0, |p| p.b),
        s.paths.last().map_or(0.0, |p| p.b),
    );
    let title = format!(
        "equilibrium surface: {} paths in {} at {} = {} … {}",
        s.paths.len(),
        s.a,
        s.b,
        super::svg::short(lo),
        super::svg::short(hi)
    );
    let mut plot = Plot::new(title, caption, &xs.label, &ys.label);
    // A triangle is shaded by the largest index of its corners: stable only where all three
    // are; a region whose index was not computed is grey.
    let mut shaded: Vec<Option<usize>> = Vec::new();
    for t in &s.triangles {
        let index = t.iter().map(|&v| vertices[v].index).max().flatten();
        let c = index_colour(index);
        plot.polygons.push((
            t.iter().map(|&v| at(v)).collect(),
            RGBAColor(c.0, c.1, c.2, REGION_ALPHA),
        ));
        if !shaded.contains(&index) {
            shaded.push(index);
        }
    }
    shaded.sort();
    for index in shaded {
        let c = index_colour(index);
        plot.legend.push(Entry::new(
            region_legend(index),
            Sample::Patch(RGBAColor(c.0, c.1, c.2, REGION_ALPHA)),
        ));
    }
    let mut legend: Vec<Option<usize>> = Vec::new();
    for p in &s.paths {
        // Runs of one index, drawn whole so that a dash runs on across short steps.
        let mut runs: Vec<super::svg::IndexRun> = Vec::new();
        for pair in p.vertices.windows(2) {
            let index = pair[0].index;
            let q = |v: &crate::results::SurfaceVertex| {
                (v.parameters[a] * xs.factor, v.measures[m] * ys.factor)
            };
            match runs.last_mut() {
                Some((i, pts)) if *i == index => pts.push(q(&pair[1])),
                _ => runs.push((index, vec![q(&pair[0]), q(&pair[1])])),
            }
        }
        for (index, pts) in runs {
            let (c, dash) = (index_colour(index), index_dash(index));
            plot.lines.push(Line::new(pts, c, 2, dash));
            if !legend.contains(&index) {
                legend.push(index);
            }
        }
    }
    legend.sort();
    for index in legend {
        plot.legend.push(Entry::new(
            super::svg::index_legend(index),
            Sample::Line(index_colour(index), 2, index_dash(index)),
        ));
    }
    let (mut limit, mut bifurcation) = (false, false);
    for l in &s.lines {
        let points: Vec<(f64, f64)> = l
            .points
            .iter()
            .map(|p| (p.parameters[a] * xs.factor, p.measures[m] * ys.factor))
            .collect();
        for &p in &points {
            plot.marks.push(Mark {
                at: p,
                symbol: Symbol::Disc(BLACK),
                kind: "critical point of a path".to_string(),
                label: String::new(),
            });
        }
        if l.kind == CriticalKind::LimitPoint {
            plot.lines.push(Line::new(points, BLACK, 3, None));
            limit = true;
        } else {
            plot.lines.push(Line::new(points, BLACK, 2, Some((6, 4))));
            bifurcation = true;
        }
    }
    if limit {
        plot.legend.push(Entry::new(
            "limit line (fold)",
            Sample::Line(BLACK, 3, None),
        ));
    }
    if bifurcation {
        plot.legend.push(Entry::new(
            "bifurcation line",
            Sample::Line(BLACK, 2, Some((6, 4))),
        ));
    }
    figure::render(&plot)
}

/// The opacity of a shaded region of the surface.
const REGION_ALPHA: f64 = 0.18;

/// The legend's text for the region of triangles of one index.
fn region_legend(index: Option<usize>) -> String {
    match index {
        None => "region: index not computed".to_string(),
        Some(0) => "stable region (index 0)".to_string(),
        Some(i) => format!("unstable region (index {i})"),
    }
}

/// The dash of an index: stable solid, unstable dashed.
fn index_dash(index: Option<usize>) -> Option<(u32, u32)> {
    match index {
        Some(0) => None,
        Some(_) => Some((8, 5)),
        None => Some((2, 4)),
    }
}
