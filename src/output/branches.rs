//! The outputs of branch switching (`memstab branch`, `[analysis.branches]`): one directory per branch
//! with the usual path files (`branch_01/path.csv`, …), `branches.json` — the graph of
//! critical points and branches — and `diagram.svg`, every branch in one bifurcation diagram.

use super::diagram::{write_bifurcation_diagram, BifurcationDiagram, DiagramLine, DiagramMark};
use super::{write_run, write_whole, OutputError, WriteRunError};
use crate::results::{
    Branches, CriticalKind, Node, NormalForm, PathReport, PrimaryPath, RunResult, StopReason,
    ASYMMETRY,
};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};

/// What [`write_branches`] wrote.
#[derive(Debug, Clone)]
pub struct BranchesWritten {
    /// `branches.json`.
    pub json: PathBuf,
    /// `diagram.svg`.
    pub diagram: PathBuf,
    /// The branch directories, in order.
    pub directories: Vec<PathBuf>,
    /// Every file, in the order written.
    pub files: Vec<PathBuf>,
}

#[derive(Serialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
enum NodeJson<'a> {
    Critical {
        id: usize,
        on: String,
        number: usize,
        kind: CriticalKind,
        irrep: &'a str,
        multiplicity: usize,
        parameters: BTreeMap<&'a str, f64>,
        step: usize,
        isotropy: &'a str,
        branches: Vec<String>,
        #[serde(skip_serializing_if = "Option::is_none")]
        skipped: Option<String>,
    },
    End {
        id: usize,
        branch: String,
        stop: &'a StopReason,
    },
}

#[derive(Serialize)]
struct Stretch {
    first: usize,
    last: usize,
    stable: bool,
}

#[derive(Serialize)]
struct BranchJson<'a> {
    id: String,
    directory: String,
    from: usize,
    to: usize,
    on: String,
    irrep: &'a str,
    isotropy: &'a str,
    isotropy_order: usize,
    isotropy_in_parent: &'a str,
    half: String,
    halves: String,
    bifurcation: String,
    path_slope: f64,
    mode_slope: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    normal_form: Option<NormalFormJson>,
    points: usize,
    symmetric_unknowns: usize,
    isotropy_of_states: String,
    isotropy_exact: bool,
    stability: Vec<Stretch>,
    critical: usize,
    end: BTreeMap<&'a str, f64>,
    stop: &'a StopReason,
    #[serde(skip_serializing_if = "Option::is_none")]
    stability_note: Option<&'a str>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    warnings: Vec<&'a str>,
}

/// λ − λ_c ≈ c A^k at the branch's critical point, and what it predicts.
#[derive(Serialize)]
struct NormalFormJson {
    power: u32,
    coefficient: f64,
    error: f64,
    amplitudes: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    criticality: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mode_stable: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    observed: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    observed_amplitude: Option<f64>,
}

impl NormalFormJson {
    fn of(nf: &NormalForm) -> Option<Self> {
        let finite = [nf.coefficient, nf.error]
            .into_iter()
            .chain(nf.amplitudes)
            .chain(nf.observed)
            .chain(nf.observed_amplitude)
            .all(f64::is_finite);
        finite.then(|| NormalFormJson {
            power: nf.power,
            coefficient: nf.coefficient,
            error: nf.error,
            amplitudes: nf.amplitudes,
            criticality: nf.criticality.map(|c| c.to_string()),
            mode_stable: nf.mode_stable,
            observed: nf.observed,
            observed_amplitude: nf.observed_amplitude,
        })
    }
}

/// A branch reaching a point already in the graph: its own node there and that point's.
#[derive(Serialize)]
struct ConnectionJson {
    branch: String,
    at: usize,
    to: usize,
}

#[derive(Serialize)]
struct GraphJson<'a> {
    scene: &'a str,
    group: &'a str,
    control: &'a str,
    depth: usize,
    nodes: Vec<NodeJson<'a>>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    connections: Vec<ConnectionJson>,
    branches: Vec<BranchJson<'a>>,
}

/// Where a path lies: `path` or its branch's directory.
fn on_name(on: Option<usize>) -> String {
    on.map_or_else(|| "path".to_string(), crate::results::directory)
}

/// The stable (index 0) and unstable stretches of a branch's rows (row 0, the critical
/// point, has no index and joins the first stretch).
fn stretches(report: &PathReport) -> Vec<Stretch> {
    let mut out: Vec<Stretch> = Vec::new();
    for (k, r) in report.rows.iter().enumerate() {
        let Some(i) = r.index else { continue };
        let stable = i == 0;
        match out.last_mut() {
            Some(s) if s.stable == stable => s.last = k,
            _ => out.push(Stretch {
                first: if out.is_empty() { 0 } else { k },
                last: k,
                stable,
            }),
        }
    }
    out
}

/// Writes `out/branches.json` from the graph; returns its path.
///
/// # Errors
/// [`OutputError::Invalid`] if a number is not finite (nothing is written), else as
/// [`write_whole`].
pub fn write_branch_graph(
    out: &Path,
    branches: &Branches,
    primary: &PrimaryPath,
) -> Result<PathBuf, OutputError> {
    let path = out.join("branches.json");
    let json = graph_json(&path, branches, primary)?;
    write_whole(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &json).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}

/// Writes `out/diagram.json`: the graph of `branches.json` with `partners`, the second
/// pieces beside the path's folds; returns its path.
///
/// # Errors
/// As [`write_branch_graph`].
pub fn write_diagram_graph<T: Serialize>(
    out: &Path,
    branches: &Branches,
    primary: &PrimaryPath,
    partners: &T,
) -> Result<PathBuf, OutputError> {
    #[derive(Serialize)]
    struct DiagramJson<'a, T> {
        #[serde(flatten)]
        graph: GraphJson<'a>,
        partners: &'a T,
    }
    let path = out.join("diagram.json");
    let graph = graph_json(&path, branches, primary)?;
    write_whole(&path, |w| {
        let json = DiagramJson { graph, partners };
        serde_json::to_writer_pretty(&mut *w, &json).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    Ok(path)
}

/// The graph as written, checked: every number finite (else an error naming `path`).
fn graph_json<'a>(
    path: &Path,
    branches: &'a Branches,
    primary: &'a PrimaryPath,
) -> Result<GraphJson<'a>, OutputError> {
    let g = &branches.graph;
    let by_name = |values: &[f64]| -> BTreeMap<&str, f64> {
        primary
            .parameters
            .iter()
            .map(String::as_str)
            .zip(values.iter().copied())
            .collect()
    };
    let mut nodes = Vec::new();
    for n in g.graph.node_indices() {
        nodes.push(match &g.graph[n] {
            Node::Critical {
                on,
                number,
                point,
                skipped,
            } => NodeJson::Critical {
                id: n.index(),
                on: on_name(*on),
                number: *number,
                kind: point.kind,
                irrep: &point.irrep,
                multiplicity: point.multiplicity,
                parameters: by_name(&point.parameters),
                step: point.after_step,
                isotropy: &point.isotropy.name,
                branches: g
                    .leaving(n)
                    .into_iter()
                    .map(crate::results::directory)
                    .collect(),
                skipped: skipped.as_ref().map(|s| s.to_string()),
            },
            Node::End { branch, stop } => NodeJson::End {
                id: n.index(),
                branch: crate::results::directory(*branch),
                stop,
            },
        });
    }
    let mut list = Vec::new();
    for e in g.graph.edge_indices() {
        let (from, to) = g.graph.edge_endpoints(e).expect("an edge of the graph");
        let i = g.graph[e];
        let b = &g.branches[i];
        let run = &branches.runs[i];
        let last = b.points.last().expect("the critical point at least");
        let mut end = by_name(&last.parameters);
        end.insert(ASYMMETRY, last.asymmetry);
        let classes: Vec<&str> = b.points[1..]
            .iter()
            .map(|p| p.stabiliser_class.as_str())
            .collect();
        let of_states = match classes.first() {
            Some(c) if classes.iter().all(|x| x == c) => c.to_string(),
            Some(_) => "mixed".to_string(),
            None => "none".to_string(),
        };
        list.push(BranchJson {
            id: run.directory.clone(),
            directory: run.directory.clone(),
            from: from.index(),
            to: to.index(),
            on: on_name(b.parent),
            irrep: &b.irrep,
            isotropy: &b.isotropy,
            isotropy_order: b.elements.len(),
            isotropy_in_parent: &b.class_in_parent,
            half: b.half.to_string(),
            halves: b.halves.to_string(),
            bifurcation: b.reduced.bifurcation.to_string(),
            path_slope: b.reduced.path_slope,
            mode_slope: b.reduced.mode_slope,
            normal_form: b.normal_form.as_ref().and_then(NormalFormJson::of),
            points: b.points.len(),
            symmetric_unknowns: b.symmetric_unknowns,
            isotropy_of_states: of_states,
            isotropy_exact: b.isotropy_exact(),
            stability: stretches(&run.report),
            critical: b.critical.len(),
            end,
            stop: &b.stop,
            stability_note: b.stability_note.as_deref(),
            warnings: b.warnings.iter().map(String::as_str).collect(),
        });
    }
    for b in &list {
        let bad = [("path_slope", b.path_slope), ("mode_slope", b.mode_slope)]
            .into_iter()
            .chain(b.end.iter().map(|(k, v)| (*k, *v)))
            .find(|(_, v)| !v.is_finite());
        if let Some((name, v)) = bad {
            return Err(OutputError::invalid(
                path,
                format!("branch {}: {name} is {v} (not finite)", b.id),
            ));
        }
    }
    let json = GraphJson {
        scene: &primary.scene,
        group: &primary.group,
        control: &primary.control,
        depth: branches.depth,
        nodes,
        connections: g
            .connections
            .iter()
            .map(|c| ConnectionJson {
                branch: crate::results::directory(c.branch),
                at: c.at.index(),
                to: c.to.index(),
            })
            .collect(),
        branches: list,
    };
    Ok(json)
}

/// The bifurcation diagram of the path and its branches.
pub fn diagram(branches: &Branches, primary: &PrimaryPath) -> BifurcationDiagram {
    let g = &branches.graph;
    let c = primary
        .parameters
        .iter()
        .position(|p| *p == primary.control);
    let control = |p: &[f64]| c.map_or(0.0, |c| p[c]);
    let mut lines = vec![DiagramLine {
        class: format!("path ({})", primary.group),
        path: true,
        points: primary.values.iter().map(|&x| (x, 0.0)).collect(),
        stable: primary.index.iter().map(|i| i.map(|i| i == 0)).collect(),
    }];
    for (b, run) in g.branches.iter().zip(&branches.runs) {
        lines.push(DiagramLine {
            class: b.isotropy.clone(),
            path: false,
            points: b
                .points
                .iter()
                .map(|p| (control(&p.parameters), b.sign * p.asymmetry))
                .collect(),
            stable: run
                .report
                .rows
                .iter()
                .map(|r| r.index.map(|i| i == 0))
                .collect(),
        });
    }
    let mut marks = Vec::new();
    for n in g.graph.node_indices() {
        // A branch's own point where it reaches a known one: a connection, its own symbol.
        let connects = g.connections.iter().any(|c| c.at == n);
        if let Node::Critical { on, point, .. } = &g.graph[n] {
            let y = match on {
                None => 0.0,
                Some(b) => {
                    let sign = g.branches[*b].sign;
                    let asym = branches.runs[*b]
                        .report
                        .critical
                        .iter()
                        .find(|c| c.after_step == point.after_step && c.irrep == point.irrep)
                        .and_then(|c| c.measures.last().copied())
                        .unwrap_or(0.0);
                    sign * asym
                }
            };
            marks.push(DiagramMark {
                x: control(&point.parameters),
                y,
                label: format!("{} {}", point.kind.short(), point.irrep),
                kind: if connects {
                    "connection: a branch reaching a known point".to_string()
                } else {
                    "critical point".to_string()
                },
            });
        }
    }
    BifurcationDiagram {
        title: format!(
            "{} (group {}): path and branches",
            primary.scene, primary.group
        ),
        caption: format!(
            "scene {} · mesh: {} · path solved in group {}",
            primary.scene, primary.mesh, primary.group
        ),
        control: primary.control.clone(),
        lines,
        marks,
        y_axis: super::diagram::ASYMMETRY_AXIS.to_string(),
        file: "diagram.svg".to_string(),
    }
}

/// The radius of the drawn mesh ([`crate::results::MeshInfo::radius`]).
fn drawing_radius(drawing: &dyn super::Drawing) -> Option<f64> {
    let nodes: Vec<[f64; 3]> = drawing
        .mesh()
        .nodes
        .iter()
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    crate::results::MeshInfo::radius_of(&nodes, &drawing.mesh().triangles)
}

/// Writes every branch's directory (the files of [`write_run`]), then `branches.json` and
/// `diagram.svg`, into `out`.
///
/// # Errors
/// The first error, with the files already written.
pub fn write_branches(
    drawing: &dyn super::Drawing,
    scene: &crate::scene::Scene,
    branches: &Branches,
    primary: &PrimaryPath,
    out: &Path,
) -> Result<BranchesWritten, WriteRunError> {
    let mut done: Vec<PathBuf> = Vec::new();
    let mut directories = Vec::new();
    for run in &branches.runs {
        let dir = out.join(&run.directory);
        if !dir.is_dir() {
            if let Err(source) = std::fs::create_dir(&dir) {
                return Err(WriteRunError {
                    error: OutputError::Io { path: dir, source },
                    done,
                    dir: out.to_path_buf(),
                });
            }
        }
        let mut result = RunResult {
            report: run.report.clone(),
            states: run.states.clone(),
            points: Vec::new(),
            times: Default::default(),
            branches: None,
            outcome: None,
        };
        match write_run(drawing, scene, &mut result, &dir) {
            Ok(w) => done.extend(w.files()),
            Err(mut e) => {
                done.append(&mut e.done);
                return Err(WriteRunError {
                    error: e.error,
                    done,
                    dir: out.to_path_buf(),
                });
            }
        }
        directories.push(dir);
    }
    let json = match write_branch_graph(out, branches, primary) {
        Ok(p) => p,
        Err(error) => {
            return Err(WriteRunError {
                error,
                done,
                dir: out.to_path_buf(),
            })
        }
    };
    done.push(json.clone());
    let mut picture = diagram(branches, primary);
    let scale = super::Scales::of_scene(scene, drawing_radius(drawing)).or_name(&primary.control);
    picture.control = scale.label;
    for l in &mut picture.lines {
        for p in &mut l.points {
            p.0 *= scale.factor;
        }
    }
    for m in &mut picture.marks {
        m.x *= scale.factor;
    }
    let diagram = match write_bifurcation_diagram(out, &picture) {
        Ok(p) => p,
        Err(error) => {
            return Err(WriteRunError {
                error,
                done,
                dir: out.to_path_buf(),
            })
        }
    };
    done.push(diagram.clone());
    match super::write_png_beside(&diagram) {
        Ok(png) => done.push(png),
        Err(error) => {
            return Err(WriteRunError {
                error,
                done,
                dir: out.to_path_buf(),
            })
        }
    }
    Ok(BranchesWritten {
        json,
        diagram,
        directories,
        files: done,
    })
}
