//! `surface.vtu`, `surface.json` and `surface.svg`: an equilibrium surface
//! ([`SurfaceReport`]).

use super::svg::{chart, padded, xml_chars};
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

/// Writes `surface.vtu`, `surface.json` and `surface.svg` into `dir`; returns their paths.
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
    let vtu = dir.join("surface.vtu");
    let json = dir.join("surface.json");
    let svg_path = dir.join("surface.svg");
    check_finite(&vtu, s)?;
    let (a, b, m) = columns(&vtu, s)?;
    if s.vertex_count() == 0 {
        return Err(OutputError::invalid(&vtu, "the surface has no vertices"));
    }
    let svg = render(s, a, m)
        .map_err(|e| OutputError::invalid(&svg_path, format!("plotting failed: {e}")))?;
    write_whole(&vtu, |w| write_vtu(w, s, (a, b, m)))?;
    write_whole(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, s).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    write_whole(&svg_path, |w| w.write_all(xml_chars(&svg).as_bytes()))?;
    Ok(vec![vtu, json, svg_path])
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
/// critical lines over them.
fn render(s: &SurfaceReport, a: usize, m: usize) -> Result<String, Box<dyn std::error::Error>> {
    let vertices: Vec<_> = s.vertices().collect();
    let at = |i: usize| (vertices[i].parameters[a], vertices[i].measures[m]);
    let xr = padded(vertices.iter().map(|v| v.parameters[a]));
    let yr = padded(vertices.iter().map(|v| v.measures[m]));
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (800, 600)).into_drawing_area();
        root.fill(&WHITE)?;
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
        let mut chart = chart(&root, &title, &s.a, &s.measure, xr, yr)?;
        chart.draw_series(s.triangles.iter().map(|t| {
            let index = t.iter().map(|&v| vertices[v].index).max().flatten();
            Polygon::new(
                t.iter().map(|&v| at(v)).collect::<Vec<_>>(),
                index_colour(index).mix(0.18).filled(),
            )
        }))?;
        let mut legend: Vec<Option<usize>> = Vec::new();
        for p in &s.paths {
            for pair in p.vertices.windows(2) {
                let index = pair[0].index;
                let series = chart.draw_series(LineSeries::new(
                    pair.iter().map(|v| (v.parameters[a], v.measures[m])),
                    index_colour(index).stroke_width(2),
                ))?;
                if !legend.contains(&index) {
                    legend.push(index);
                    let c = index_colour(index);
                    let label = match index {
                        Some(0) => "index 0 (stable)".to_string(),
                        Some(i) => format!("index {i}"),
                        None => "index not computed".to_string(),
                    };
                    series.label(label).legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], c.stroke_width(2))
                    });
                }
            }
        }
        let (mut limit_legend, mut bifurcation_legend) = (false, false);
        for l in &s.lines {
            let points: Vec<(f64, f64)> = l
                .points
                .iter()
                .map(|p| (p.parameters[a], p.measures[m]))
                .collect();
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, BLACK.filled())))?;
            if l.kind == CriticalKind::LimitPoint {
                let series = chart.draw_series(LineSeries::new(points, BLACK.stroke_width(3)))?;
                if !std::mem::replace(&mut limit_legend, true) {
                    series.label("limit line (fold)").legend(|(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(3))
                    });
                }
            } else {
                let series = chart.draw_series(DashedLineSeries::new(
                    points,
                    6,
                    4,
                    BLACK.stroke_width(2),
                ))?;
                if !std::mem::replace(&mut bifurcation_legend, true) {
                    series.label("bifurcation line").legend(|(x, y)| {
                        PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2))
                    });
                }
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
        root.present()?;
    }
    Ok(out)
}
