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
/// solid, bifurcation lines dashed), the paths cut at [`budget_cut`] where they stopped on
/// their step budget at different values of a.
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
pub(super) fn index_colour(index: Option<usize>) -> RGBColor {
    match index {
        None => RGBColor(150, 150, 150),
        Some(0) => RGBColor(31, 87, 180),
        Some(1) => RGBColor(230, 120, 20),
        Some(2) => RGBColor(200, 30, 30),
        Some(_) => RGBColor(120, 40, 140),
    }
}

/// Where the surface's figure cuts its paths so that its edge is not ragged where paths
/// stopped on their step budget: every path's last monotone stretch in a (after its last
/// turn) is cut at the value of a where the first of them stopped on the budget.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BudgetCut {
    /// The value of a (unscaled).
    pub at: f64,
    /// +1 where the last stretches run towards larger a, −1 towards smaller.
    pub direction: f64,
    /// The number of paths shortened by the cut.
    pub paths: usize,
}

/// The first vertex of a path's last monotone stretch in a (column `a`) and its direction
/// (+1 or −1); `None` for a path of fewer than two vertices or one that does not move in a.
fn last_stretch(p: &crate::results::SurfacePath, a: usize) -> Option<(usize, f64)> {
    let x: Vec<f64> = p.vertices.iter().map(|v| v.parameters[a]).collect();
    let steps: Vec<f64> = x
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d != 0.0)
        .collect();
    let direction = steps.last()?.signum();
    let mut start = x.len() - 1;
    while start > 0 && (x[start] - x[start - 1]) * direction >= 0.0 {
        start -= 1;
    }
    Some((start, direction))
}

/// The cut of the surface's figure ([`BudgetCut`]): where one or more of its paths stopped on
/// the step budget, the paths' last stretches all run the same way in a (column `a`) and every
/// one reaches the value of a where the first budget-stopped path ended. `None` otherwise
/// (nothing to cut, or a cut that would not give a straight edge): the figure then draws every
/// point.
pub fn budget_cut(s: &SurfaceReport, a: usize) -> Option<BudgetCut> {
    if s.paths.len() < 2 {
        return None;
    }
    let stretches: Vec<(usize, f64)> = s
        .paths
        .iter()
        .map(|p| last_stretch(p, a))
        .collect::<Option<_>>()?;
    let direction = stretches[0].1;
    if stretches.iter().any(|&(_, d)| d != direction) {
        return None;
    }
    let end = |p: &crate::results::SurfacePath| p.vertices.last().map_or(0.0, |v| v.parameters[a]);
    let at = s
        .paths
        .iter()
        .filter(|p| matches!(p.stop, crate::results::StopReason::StepBudget { .. }))
        .map(|p| end(p) * direction)
        .fold(f64::INFINITY, f64::min)
        * direction;
    if !at.is_finite() {
        return None;
    }
    // Every path's last stretch must reach back to the cut.
    let reaches = s
        .paths
        .iter()
        .zip(&stretches)
        .all(|(p, &(start, _))| p.vertices[start].parameters[a] * direction <= at * direction);
    if !reaches {
        return None;
    }
    let paths = s
        .paths
        .iter()
        .filter(|p| (end(p) - at) * direction > 0.0)
        .count();
    Some(BudgetCut {
        at,
        direction,
        paths,
    })
}

/// How far past the cut each vertex lies (positive: cut away), path after path: (a − cut) ×
/// direction on a path's last stretch, at most 0 elsewhere.
fn beyond(s: &SurfaceReport, a: usize, cut: &BudgetCut) -> Vec<f64> {
    let mut out = Vec::with_capacity(s.vertex_count());
    for p in &s.paths {
        let start = last_stretch(p, a).map_or(usize::MAX, |(k, _)| k);
        for (k, v) in p.vertices.iter().enumerate() {
            let t = (v.parameters[a] - cut.at) * cut.direction;
            out.push(if k >= start { t } else { t.min(0.0) });
        }
    }
    out
}

/// The part of the polygon `pts` where `t` ≤ 0 (t linear along its edges).
fn keep_inside(pts: &[(f64, f64)], t: &[f64]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for i in 0..pts.len() {
        let j = (i + 1) % pts.len();
        let (p, q, tp, tq) = (pts[i], pts[j], t[i], t[j]);
        if tp <= 0.0 {
            out.push(p);
        }
        if (tp <= 0.0) != (tq <= 0.0) {
            let f = tp / (tp - tq);
            out.push((p.0 + f * (q.0 - p.0), p.1 + f * (q.1 - p.1)));
        }
    }
    out
}

/// The measure (column `m`) against a (column `a`): triangles and paths by index, the
/// critical lines over them; axes titled and scaled by `scales`. Where paths stopped on their
/// step budget the figure is cut at [`budget_cut`], said in the caption.
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
    let cut = budget_cut(s, a).filter(|c| c.paths > 0);
    let t = cut.map_or_else(|| vec![0.0; vertices.len()], |c| beyond(s, a, &c));
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
    // The cut said in the caption: where, and why.
    let caption = match &cut {
        Some(c) => format!(
            "{caption} · {} of {} paths cut at {} = {} (step budget)",
            c.paths,
            s.paths.len(),
            s.a,
            super::svg::short(c.at)
        ),
        None => caption.to_string(),
    };
    let mut plot = Plot::new(title, caption, &xs.label, &ys.label);
    // A triangle is shaded by the largest index of its corners: stable only where all three
    // are; a region whose index was not computed is grey.
    let mut shaded: Vec<Option<usize>> = Vec::new();
    for tri in &s.triangles {
        let index = tri.iter().map(|&v| vertices[v].index).max().flatten();
        let c = index_colour(index);
        let pts: Vec<(f64, f64)> = tri.iter().map(|&v| at(v)).collect();
        let kept = keep_inside(&pts, &tri.map(|v| t[v]));
        if kept.len() < 3 {
            continue;
        }
        plot.polygons
            .push((kept, RGBAColor(c.0, c.1, c.2, REGION_ALPHA)));
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
    let mut paths: Vec<(Option<usize>, Line)> = Vec::new();
    for p in &s.paths {
        let first = p.first_vertex;
        // Runs of one index, drawn whole so that a dash runs on across short steps; a path
        // ends where the cut crosses it.
        let mut runs: Vec<super::svg::IndexRun> = Vec::new();
        for k in 1..p.vertices.len() {
            let (u, v) = (first + k - 1, first + k);
            if t[u] > 0.0 {
                break;
            }
            let to = if t[v] > 0.0 {
                let f = t[u] / (t[u] - t[v]);
                let (p0, p1) = (at(u), at(v));
                (p0.0 + f * (p1.0 - p0.0), p0.1 + f * (p1.1 - p0.1))
            } else {
                at(v)
            };
            let index = vertices[u].index;
            match runs.last_mut() {
                Some((i, pts)) if *i == index => pts.push(to),
                _ => runs.push((index, vec![at(u), to])),
            }
        }
        for (index, pts) in runs {
            let (c, dash) = (index_colour(index), index_dash(index));
            let line = Line::new(pts, c, 2, dash).kind(super::svg::index_legend(index));
            paths.push((index, line));
        }
    }
    // The legend's entries (one per index drawn) in the order of the index.
    paths.sort_by_key(|(index, _)| *index);
    plot.lines.extend(paths.into_iter().map(|(_, l)| l));
    // A critical point past the cut goes with its path: it lies on a path's last stretch
    // (the vertex after it is cut away) and beyond the cut in a.
    let past = |p: &crate::results::CriticalLinePoint| {
        cut.is_some_and(|c| {
            let path = &s.paths[p.path];
            let after = path.critical[p.critical].after_step + 1;
            let next = path.vertices.iter().position(|v| v.step == after);
            next.is_some_and(|k| t[path.first_vertex + k] > 0.0)
                && (p.parameters[a] - c.at) * c.direction > 0.0
        })
    };
    let (mut limit, mut bifurcation) = (false, false);
    for l in &s.lines {
        let points: Vec<(f64, f64)> = l
            .points
            .iter()
            .filter(|p| !past(p))
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
        if points.len() < 2 {
            continue;
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
pub(super) fn index_dash(index: Option<usize>) -> Option<(u32, u32)> {
    match index {
        Some(0) => None,
        Some(_) => Some((8, 5)),
        None => Some((2, 4)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::{StopReason, SurfacePath, SurfaceVertex};

    /// A surface of paths in a (column 0) at b = 0, 1, …, each given by its values of a and
    /// why it stopped; the measure is a².
    fn surface(paths: &[(&[f64], StopReason)]) -> SurfaceReport {
        let mut first = 0;
        let paths = paths
            .iter()
            .enumerate()
            .map(|(j, (a, stop))| {
                let vertices: Vec<SurfaceVertex> = a
                    .iter()
                    .enumerate()
                    .map(|(k, &x)| SurfaceVertex {
                        step: k,
                        arclength: k as f64,
                        parameters: vec![x, j as f64],
                        measures: vec![x * x],
                        index: Some(0),
                    })
                    .collect();
                let p = SurfacePath {
                    b: j as f64,
                    first_vertex: first,
                    vertices,
                    critical: Vec::new(),
                    stop: stop.clone(),
                };
                first += a.len();
                p
            })
            .collect();
        SurfaceReport {
            a: "a".into(),
            b: "b".into(),
            measure: "m".into(),
            parameters: vec!["a".into(), "b".into()],
            measures: vec!["m".into()],
            paths,
            triangles: Vec::new(),
            lines: Vec::new(),
            warnings: Vec::new(),
        }
    }

    const BUDGET: StopReason = StopReason::StepBudget { steps: 5 };

    #[test]
    fn paths_stopped_on_their_budget_are_cut_where_the_first_ended() {
        // Three paths run up in a; the one that stopped first on its budget ends at 1.2.
        let s = surface(&[
            (&[0.0, 0.5, 1.0, 1.5], BUDGET),
            (&[0.0, 0.6, 1.2], BUDGET),
            (&[0.0, 0.4, 0.8, 1.2, 1.6, 2.0], StopReason::Bounds),
        ]);
        let cut = budget_cut(&s, 0).expect("a cut");
        assert_eq!(cut.at, 1.2);
        assert_eq!(cut.direction, 1.0);
        assert_eq!(cut.paths, 2);
        // Past the cut: the last two points of the third path and the last of the first.
        let t = beyond(&s, 0, &cut);
        let past: Vec<usize> = (0..t.len()).filter(|&i| t[i] > 0.0).collect();
        assert_eq!(past, [3, 11, 12]);
        // A triangle across the cut keeps its part before it.
        let kept = keep_inside(&[(1.0, 0.0), (1.5, 0.0), (1.0, 1.0)], &[-0.2, 0.3, -0.2]);
        assert_eq!(kept.len(), 4);
        assert!(kept.iter().all(|p| p.0 <= 1.2 + 1e-12), "{kept:?}");
        // Running down in a: cut at the largest end of a budget-stopped path.
        let s = surface(&[(&[2.0, 1.0, 0.5], BUDGET), (&[2.0, 1.5, 0.8], BUDGET)]);
        let cut = budget_cut(&s, 0).expect("a cut");
        assert_eq!((cut.at, cut.direction, cut.paths), (0.8, -1.0, 1));
    }

    #[test]
    fn no_cut_without_a_budget_stop_or_a_straight_edge() {
        // Every path left the range: its edge is the range's.
        let s = surface(&[
            (&[0.0, 1.0, 2.0], StopReason::Bounds),
            (&[0.0, 1.5, 2.1], StopReason::Bounds),
        ]);
        assert_eq!(budget_cut(&s, 0), None);
        // A path whose last stretch (after its fold at 1.6) starts past the other's end: a
        // cut would take away more than the ragged edge.
        let s = surface(&[(&[0.0, 0.5, 1.0], BUDGET), (&[0.0, 1.6, 1.3, 1.4], BUDGET)]);
        assert_eq!(budget_cut(&s, 0), None);
        // Last stretches running opposite ways.
        let s = surface(&[(&[0.0, 0.5, 1.0], BUDGET), (&[0.0, 1.0, 0.7], BUDGET)]);
        assert_eq!(budget_cut(&s, 0), None);
        // A single path.
        assert_eq!(budget_cut(&surface(&[(&[0.0, 1.0], BUDGET)]), 0), None);
    }
}
