//! Branch switching, timed: every branch from the 5-fold Hg point of the abstract invariant
//! potential on the icosahedron ([`crate::effects::invariant`], branches in closed form), and
//! the branches from the first E1 double point of the upward-loaded C7v disc
//! (`scenes/disc_upward.toml`) on a mesh of the given divisions (16: the thesis mesh).

use crate::continuation::crossings::{Crossings, IndexChanges};
use crate::continuation::events::trace;
use crate::continuation::events::Detector;
use crate::continuation::{Continuation, PathOptions};
use crate::effects::invariant::IrrepPotential;
use crate::model::{FeModel, Model};
use crate::results::{BranchGraph, Branches, CriticalPoint, RunResult, StopReason};
use crate::scene::Scene;
use crate::stability::{IrrepBlocks, Stability};
use crate::study::mesh::MeshStudy;
use crate::study::switching::{Level, Switching};
use crate::study::{BranchOptions, SymmetricProblem};
use meshes::generators::{icosphere, IcosphereOptions};
use meshes::SymmetricMesh;
use nalgebra::DVector;
use std::time::{Duration, Instant};

/// The bundled upward-loaded disc (C7v, 16 divisions, k = 0.1, `[analysis.branches]`).
pub const DISC_UPWARD_TOML: &str = include_str!("../../scenes/disc_upward.toml");

/// The coefficients [c₃, c₃', c₄] of the abstract potential used by the bench and the tests.
pub const IH_COEFFICIENTS: [f64; 3] = [0.3, 0.2, 0.5];

/// The abstract problem: the icosahedron (12 nodes, Ih) with the Hg potential.
pub struct IhProblem {
    /// [c₃, c₃', c₄].
    pub coefficients: [f64; 3],
    /// The mesh and its action.
    pub mesh: SymmetricMesh,
    /// The potential (also inside the model).
    pub potential: IrrepPotential,
    /// The model: one effect, one parameter λ.
    pub model: FeModel,
}

/// The icosahedron with Π = ½|u|² − ½ λ |z|² + c₃ I₃ + c₃' J₃ + c₄ |z|⁴ on the Hg part z of
/// its radial fields.
pub fn ih_problem(coefficients: [f64; 3]) -> Result<IhProblem, String> {
    ih_problem_curved(coefficients, 0.0)
}

/// The same with −½ f(λ) |z|², f(λ) = λ − μ λ² (`mu` = μ): two Hg points on the trivial
/// path, joined by every axial branch (docs/theory.md §14.6).
pub fn ih_problem_curved(coefficients: [f64; 3], mu: f64) -> Result<IhProblem, String> {
    let mesh = icosphere(&IcosphereOptions {
        frequency: 1,
        radius: 1.0,
    })
    .map_err(|e| e.to_string())?;
    let potential = IrrepPotential::new(&mesh.action, &mesh.mesh.nodes, "Hg", 0, coefficients)?
        .with_curvature(mu);
    let model = FeModel::new(
        mesh.mesh.nodes.clone(),
        mesh.mesh.triangles.clone(),
        &[],
        vec![Box::new(potential.clone())],
        vec!["lambda".to_string()],
    );
    Ok(IhProblem {
        coefficients,
        mesh,
        potential,
        model,
    })
}

/// A switch: the path's critical points, the branch graph and the times.
pub struct Switched {
    /// The path's critical points.
    pub critical: Vec<CriticalPoint>,
    /// The path's points, why it ended and what it could not settle.
    pub path: (usize, StopReason, Vec<String>),
    /// The branches.
    pub graph: BranchGraph,
    /// The path (the trivial solution u = 0 from λ = 0.5 to 1.5, with its index).
    pub path_time: Duration,
    /// Every switch and branch.
    pub branch_time: Duration,
}

/// The trivial path of the abstract problem from λ = 0.52 to 1.5 (its 5-fold Hg point at
/// λ = 1, between two path points) and every branch of its critical points, `steps` points
/// each.
pub fn ih_branches(problem: &IhProblem, steps: usize) -> Result<Switched, String> {
    ih_branches_over(problem, steps, (0.5, 1.5), 0.52)
}

/// The trivial path of the abstract problem from λ = `start` within `bounds` and every
/// branch of its critical points, `steps` points each.
pub fn ih_branches_over(
    problem: &IhProblem,
    steps: usize,
    bounds: (f64, f64),
    start: f64,
) -> Result<Switched, String> {
    let t = Instant::now();
    let model = &problem.model;
    let layout = model.layout();
    let top = Level::top(&problem.mesh.action, layout);
    let adapted = top.adapted.as_ref().map_err(|e| e.clone())?;
    let measure = |u: &[f64], _: &[f64]| vec![u.iter().map(|v| v * v).sum::<f64>().sqrt()];
    let opts = PathOptions {
        initial_step: 0.05,
        max_step: 0.05,
        bounds,
        state_scale: (layout.nodes() as f64).sqrt(),
        ..PathOptions::default()
    };
    let p = SymmetricProblem::new(model, &top.basis, &[], vec![start], Some(0));
    let q0 = DVector::zeros(top.basis.dim());
    let mut driver = Continuation::start(p, &q0, &DVector::from_element(1, start), opts.clone())
        .map_err(|e| e.to_string())?;
    let crossings = Crossings::new(
        Box::new(IrrepBlocks::new(
            Stability::new(model, adapted),
            model,
            &[],
            &problem.mesh.action,
        )),
        &measure,
        Some(0),
        false,
    );
    let mut index = IndexChanges::new(crossings);
    let path = {
        let mut extra: Vec<&mut dyn Detector<SymmetricProblem>> = vec![&mut index];
        trace(&mut driver, 100, |_, _| None, &mut extra, |_, _| {})
    };
    let critical: Vec<CriticalPoint> = path.critical_points().cloned().collect();
    let warnings = path
        .events
        .iter()
        .filter_map(|e| match e {
            crate::continuation::events::Event::Warning(w) => Some(w.clone()),
            _ => None,
        })
        .collect();
    let path_summary = (path.points.len(), path.stop.clone(), warnings);
    let path_time = t.elapsed();
    let t = Instant::now();
    let switching = Switching {
        model,
        constraints: &[],
        measure: &measure,
        control: Some(0),
        top: &top,
        options: BranchOptions {
            save_every: 10,
            depth: 1,
            steps,
            points: None,
            path: PathOptions {
                max_step: 0.05,
                initial_step: 0.02,
                max_steps: steps,
                ..opts
            },
        },
    };
    let graph = switching.run(&critical);
    Ok(Switched {
        critical,
        path: path_summary,
        graph,
        path_time,
        branch_time: t.elapsed(),
    })
}

/// The upward-loaded disc with `divisions` as `run` computes it: its path to h = 4.9 and the
/// branches of its bifurcation points (the first E1 double point), `steps` points each. The
/// branches' own wall time is [`Branches::time`].
pub fn disc_upward_branches(
    divisions: usize,
    steps: usize,
) -> Result<(RunResult, Branches), String> {
    let text = DISC_UPWARD_TOML
        .replace("divisions = 16 ", &format!("divisions = {divisions} "))
        .replace("steps = 30 ", &format!("steps = {steps} "));
    let scene = Scene::from_toml_str(&text, &format!("disc-upward, divisions {divisions}"))
        .map_err(|e| e.to_string())?;
    let mut study = MeshStudy::build(scene).map_err(|e| e.to_string())?;
    let mut result = crate::analysis::run(&mut study, |_, _| {}).map_err(|e| e.to_string())?;
    let branches = result
        .branches
        .take()
        .ok_or("the scene asks for no branches")?;
    Ok((result, branches))
}

/// The largest |λ − λ_closed-form| over the points of the abstract problem's branches, with
/// λ = 1 + 3 (c₃ I₃(v) + c₃' J₃(v)) a + 4 c₄ a² on the line z = a v of each branch
/// (docs/theory.md §14.6).
pub fn closed_form_error(problem: &IhProblem, graph: &BranchGraph) -> f64 {
    let [c3, c3t, c4] = problem.coefficients;
    let mut worst: f64 = 0.0;
    for b in &graph.branches {
        let z = |k: usize| {
            let x = problem
                .model
                .positions(&b.points[k].u, &b.points[k].parameters);
            problem.potential.project(&problem.potential.radial(&x))
        };
        if b.points.len() < 2 {
            continue;
        }
        let v = z(1).normalize();
        let (i3, j3) = problem.potential.cubics(&v);
        for k in 1..b.points.len() {
            let a = z(k).dot(&v);
            let exact = 1.0 + 3.0 * (c3 * i3 + c3t * j3) * a + 4.0 * c4 * a * a;
            worst = worst.max((b.points[k].parameters[0] - exact).abs());
        }
    }
    worst
}

/// The bench's branch-switching section (markdown): the abstract Hg problem (every branch
/// of its 5-fold point, against the closed form) and the upward-loaded disc on
/// `divisions` (16: the thesis mesh), each timed.
pub fn branching_section(divisions: usize) -> Result<String, String> {
    use std::fmt::Write;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n## Branch switching\n\n\
         All branches from a bifurcation point by the equivariant branching lemma \
         (docs/theory.md §14): one per conjugacy class of axial isotropy subgroups (both \
         halves where they are not conjugate), each followed in its fixed-point space with the \
         index by the irreps of its isotropy subgroup at every point and its critical points \
         localised. Time: wall time of all switches and branches (the path before them \
         apart). Target: < 10 s each.\n"
    );
    let _ = writeln!(
        md,
        "| case | unknowns | point | branches | points per branch | closed form max error | path (s) | branches (s) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    let problem = ih_problem(IH_COEFFICIENTS)?;
    let run = ih_branches(&problem, 20)?;
    let names = |g: &BranchGraph| {
        g.branches
            .iter()
            .map(|b| format!("{}{}", b.isotropy, b.half))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let points = |g: &BranchGraph| {
        g.branches
            .iter()
            .map(|b| b.points.len().to_string())
            .collect::<Vec<_>>()
            .join("/")
    };
    let point = |c: &[CriticalPoint]| {
        c.first().map_or("none".to_string(), |c| {
            format!("{} in {} at {:.6}", c.kind, c.irrep, c.parameters[0])
        })
    };
    let _ = writeln!(
        md,
        "| abstract Hg potential, icosahedron (Ih) | {} | {} | {} | {} | {:.1e} | {:.3} | {:.3} |",
        problem.model.unknowns(),
        point(&run.critical),
        names(&run.graph),
        points(&run.graph),
        closed_form_error(&problem, &run.graph),
        run.path_time.as_secs_f64(),
        run.branch_time.as_secs_f64()
    );
    let t = Instant::now();
    let (result, branches) = disc_upward_branches(divisions, 30)?;
    let total = t.elapsed();
    let _ = writeln!(
        md,
        "| upward-loaded disc (C7v, k = 0.1, {} triangles) | {} | {} | {} | {} | – | {:.3} | {:.3} |",
        result.report.mesh.elements,
        result.report.unknowns,
        point(&result.report.critical),
        names(&branches.graph),
        points(&branches.graph),
        (total.saturating_sub(branches.time)).as_secs_f64(),
        branches.time.as_secs_f64()
    );
    Ok(md)
}
