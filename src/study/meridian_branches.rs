//! Branch switching on the meridian (docs/theory.md §14, §15.20). A critical point of wave
//! number m ≥ 1 is a bifurcation whose branches leave the axisymmetric states: the meridian
//! cannot follow them, and says which 3-D mesh symmetry can. One of m = 0 on a path, where
//! the control does not turn (a symmetric bifurcation), is a bifurcation inside the
//! axisymmetric states with no symmetry between its halves: its kernel direction φ is the
//! block's null vector in the meridian's unknowns (U, W of §15.1; a twist V would leave the
//! meridian's states too), the reduced equation g(a, s) = a (b s + ½ C a) gives the branch's
//! tangent φ + κ t_path with κ = −C/(2b) (a transcritical branch; a pitchfork when C is zero
//! to round-off), and both halves are followed like a path, with the index by wave number at
//! every point.

use super::meridian::MeridianStudy;
use super::normal_form::{normal_form, observe};
use super::switching::{branch_run, follow_branch};
use super::{BranchOptions, Followed, Free, Study};
use crate::axisym::blocks::{wave_number, MERIDIAN_GROUP};
use crate::axisym::mode_amplitudes;
use crate::continuation::crossings::{Crossings, IndexChanges};
use crate::continuation::{point_at, step_off, Continuation, PathOptions, PathPoint, Stalled};
use crate::results::{
    Bifurcation, BranchGraph, BranchPoint, Branches, CriticalKind, CriticalPoint, Half, Halves,
    Node, Reduced, Skip, StopReason, SwitchedBranch,
};
use nalgebra::DVector;
use petgraph::graph::NodeIndex;

/// Step along the path (scaled arclength) for b, the rate of φᵀKφ along it.
const PATH_DELTA: f64 = 1e-4;
/// Amplitude along φ (in units of the state scale) for C, the rate of φᵀKφ along φ.
const MODE_DELTA: f64 = 1e-4;
/// |ΔφᵀKφ| / ‖K‖ below which the quadratic coefficient counts as zero (a pitchfork).
const QUADRATIC_ZERO: f64 = 1e-9;
/// |b| / ‖K‖ below which the critical eigenvalue does not cross transversally.
const TRANSVERSAL_ZERO: f64 = 1e-10;
/// The share of a kernel direction's norm in the twist V above which it leaves the meridian's
/// states.
const TWIST: f64 = 1e-6;

/// Why a branch of wave number m ≥ 1 is not followed on the meridian, and where it is.
pub fn refusal(number: usize, m: usize) -> String {
    format!(
        "critical point {number} (m = {m}): its branches leave the axisymmetric states, which \
         the meridian cannot follow; switch at it on a 3-D mesh whose group keeps its mode's \
         isotropy C{m}v (a disc or truncated sphere of group C{}v, say)",
        4 * m
    )
}

/// The branches of the meridian's critical points `critical` that `options` asks for; a point
/// of wave number m ≥ 1 is a node without branches, [`refusal`] its reason
/// ([`Skip::Elsewhere`]).
pub fn switch(
    study: &MeridianStudy,
    critical: &[CriticalPoint],
    options: BranchOptions,
) -> Result<Branches, String> {
    let t = std::time::Instant::now();
    let mut g = BranchGraph::default();
    for (k, cp) in critical.iter().enumerate() {
        let node = g.graph.add_node(Node::Critical {
            on: None,
            number: k + 1,
            point: Box::new(cp.clone()),
            skipped: None,
        });
        let requested = options.points.as_ref().is_none_or(|p| p.contains(&(k + 1)));
        let skip = match wave_number(&cp.irrep) {
            _ if !requested => Some(Skip::NotRequested),
            Some(m) if m >= 1 => Some(Skip::Elsewhere(refusal(k + 1, m))),
            _ if cp.kind == CriticalKind::LimitPoint => Some(Skip::LimitPoint),
            _ => None,
        };
        if let Some(skip) = skip {
            set_skip(&mut g, node, skip);
            continue;
        }
        match Switch::new(study, cp, &options) {
            Ok(switch) => {
                for half in [Half::Plus, Half::Minus] {
                    let t1 = std::time::Instant::now();
                    let mut branch = switch.follow(half);
                    branch.from = node;
                    branch.time = t1.elapsed();
                    let id = g.branches.len();
                    let end = g.graph.add_node(Node::End {
                        branch: id,
                        stop: branch.stop.clone(),
                    });
                    g.graph.add_edge(node, end, id);
                    for (j, c) in branch.critical.iter().enumerate() {
                        let n = g.graph.add_node(Node::Critical {
                            on: Some(id),
                            number: j + 1,
                            point: Box::new(c.clone()),
                            skipped: None,
                        });
                        set_skip(&mut g, n, Skip::Depth);
                    }
                    g.branches.push(branch);
                }
            }
            Err(why) => set_skip(&mut g, node, Skip::Failed(why)),
        }
    }
    let save_every = options.save_every.max(1);
    let runs = g
        .branches
        .iter()
        .enumerate()
        .map(|(i, b)| {
            branch_run(
                study,
                &|_| 0.0,
                &|c| {
                    c.iter()
                        .map(|cp| wave_number(&cp.irrep).unwrap_or(0))
                        .collect()
                },
                b,
                i,
                save_every,
            )
        })
        .collect();
    Ok(Branches {
        graph: g,
        runs,
        depth: 1,
        time: t.elapsed(),
    })
}

fn set_skip(g: &mut BranchGraph, node: NodeIndex, skip: Skip) {
    if let Node::Critical { skipped, .. } = &mut g.graph[node] {
        skipped.get_or_insert(skip);
    }
}

/// A symmetric bifurcation of the meridian's path: its kernel direction, the path's tangent
/// and the reduced equation.
struct Switch<'a> {
    study: &'a MeridianStudy,
    cp: &'a CriticalPoint,
    options: &'a BranchOptions,
    /// φ over the meridian's unknowns, unit norm.
    phi: DVector<f64>,
    /// The path's unit tangent (scaled variables) at the point, the control increasing.
    path: DVector<f64>,
    reduced: Reduced,
}

impl<'a> Switch<'a> {
    fn new(
        study: &'a MeridianStudy,
        cp: &'a CriticalPoint,
        options: &'a BranchOptions,
    ) -> Result<Self, String> {
        let model = &study.model;
        let amplitudes = mode_amplitudes(model, 0, &cp.mode).map_err(|e| e.to_string())?;
        let mut phi = DVector::zeros(model.dim());
        for k in 0..model.dim() {
            let (i, c) = model.free_unknown(k);
            phi[k] = if c == 0 {
                amplitudes[i][0]
            } else {
                amplitudes[i][2]
            };
        }
        let total: f64 = amplitudes
            .iter()
            .map(|a| a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            .sum();
        let twist: f64 = amplitudes.iter().map(|a| a[1] * a[1]).sum();
        if twist > TWIST * total || phi.norm() == 0.0 {
            return Err(
                "its mode twists the meridian about the axis (V of m = 0): the branch leaves \
                 the meridian's untwisted states; switch at it on a 3-D mesh"
                    .into(),
            );
        }
        phi /= phi.norm();
        let opts = &options.path;
        let mut problem = study.problem(&cp.parameters, &Free::path(Some(control(study)?)));
        let q = problem.coordinates(&cp.state);
        let lambda = problem.free_values(&cp.parameters);
        let up = PathOptions {
            direction: 1.0,
            ..opts.clone()
        };
        let path = point_at(&mut problem, q.clone(), lambda.clone(), 0, &up, None)
            .map_err(|e| format!("the path's tangent at the critical point: {e}"))?
            .tangent;
        let m = q.len();
        let mut form = |q: &DVector<f64>, l: &DVector<f64>| -> Result<(f64, f64), String> {
            let lin = problem.evaluate(q, l).map_err(|e| e.to_string())?;
            let kphi =
                lin.tangent
                    .times(&nalgebra::DMatrix::from_column_slice(m, 1, phi.as_slice()));
            Ok((phi.dot(&kphi.column(0)), lin.tangent.amax().max(1e-300)))
        };
        let along = |s: f64| -> (DVector<f64>, DVector<f64>) {
            let qs = &q + path.rows(0, m) * (s * opts.state_scale);
            let mut ls = lambda.clone();
            for j in 0..ls.len() {
                ls[j] += path[m + j] * s * opts.parameter_scale(j);
            }
            (qs, ls)
        };
        let (qp, lp) = along(PATH_DELTA);
        let (qm, lm) = along(-PATH_DELTA);
        let (b_plus, scale) = form(&qp, &lp)?;
        let (b_minus, _) = form(&qm, &lm)?;
        let b = (b_plus - b_minus) / (2.0 * PATH_DELTA);
        let h = MODE_DELTA * opts.state_scale;
        let (c_plus, _) = form(&(&q + &phi * h), &lambda)?;
        let (c_minus, _) = form(&(&q - &phi * h), &lambda)?;
        let path_slope = b / scale;
        let quadratic = (c_plus - c_minus).abs() > QUADRATIC_ZERO * scale;
        let mode_slope = if quadratic {
            (c_plus - c_minus) / (2.0 * h) * opts.state_scale / scale
        } else {
            0.0
        };
        let path_per_amplitude = if quadratic && path_slope.abs() > TRANSVERSAL_ZERO {
            -mode_slope / (2.0 * path_slope)
        } else {
            0.0
        };
        Ok(Self {
            study,
            cp,
            options,
            phi,
            path,
            reduced: Reduced {
                path_slope,
                mode_slope,
                bifurcation: if quadratic {
                    Bifurcation::Transcritical
                } else {
                    Bifurcation::Pitchfork
                },
                path_per_amplitude,
            },
        })
    }

    /// A point of the branch.
    fn point(
        u: &[f64],
        params: &[f64],
        arclength: f64,
        iterations: usize,
        index: Option<usize>,
    ) -> BranchPoint {
        BranchPoint {
            u: u.to_vec(),
            parameters: params.to_vec(),
            arclength,
            iterations,
            index,
            asymmetry: 0.0,
            stabiliser: Vec::new(),
            stabiliser_class: MERIDIAN_GROUP.into(),
        }
    }

    /// Where the branch on `half` with ds/dA = `k` leaves from: the critical point, the
    /// tangent φ + k t_path (normalised) and the plane of fixed amplitude along φ.
    fn departure(
        &self,
        problem: &mut dyn Followed,
        half: Half,
        k: f64,
    ) -> (PathPoint, DVector<f64>, DVector<f64>) {
        let cp = self.cp;
        let m = self.phi.len();
        let mut tangent = DVector::zeros(self.path.len());
        tangent
            .rows_mut(0, m)
            .copy_from(&(&self.phi + self.path.rows(0, m) * k));
        for j in m..self.path.len() {
            tangent[j] = k * self.path[j];
        }
        let tangent = &tangent * (half.sign() / tangent.norm());
        let start = PathPoint {
            q: problem.coordinates(&cp.state),
            lambda: problem.free_values(&cp.parameters),
            arclength: 0.0,
            iterations: 0,
            tangent: tangent.clone(),
        };
        let mut plane = DVector::zeros(tangent.len());
        plane.rows_mut(0, m).copy_from(&(&self.phi * half.sign()));
        (start, tangent, plane)
    }

    /// The branch's first point on `half` with ds/dA = `k` (its tangent φ + k t_path):
    /// the step leaves the point on the plane of fixed amplitude along φ, which the path does
    /// not meet (docs/theory.md §14.4), halved down to the smallest step.
    fn first_step(
        &self,
        problem: &mut dyn Followed,
        half: Half,
        k: f64,
    ) -> Result<PathPoint, crate::continuation::StepError> {
        let opts = &self.options.path;
        let (start, tangent, plane) = self.departure(problem, half, k);
        let mut s = opts.initial_step;
        loop {
            match step_off(problem, &start, &tangent, &plane, s, opts) {
                Ok(p) => return Ok(p),
                Err(why) => {
                    s *= 0.5;
                    if s < opts.min_step {
                        return Err(why);
                    }
                }
            }
        }
    }

    /// Follows one half of the branch from the point.
    fn follow(&self, half: Half) -> SwitchedBranch {
        let (study, cp, opts) = (self.study, self.cp, &self.options.path);
        let mut branch = SwitchedBranch {
            from: NodeIndex::new(0),
            parent: None,
            irrep: cp.irrep.clone(),
            isotropy: MERIDIAN_GROUP.into(),
            elements: Vec::new(),
            class_in_parent: MERIDIAN_GROUP.into(),
            half,
            halves: Halves::Distinct,
            reduced: self.reduced,
            normal_form: None,
            symmetric_unknowns: study.model.dim(),
            points: vec![Self::point(&cp.state, &cp.parameters, 0.0, 0, None)],
            turning: Vec::new(),
            critical: Vec::new(),
            stop: StopReason::Condition,
            stability_note: None,
            warnings: Vec::new(),
            sign: half.sign(),
            time: std::time::Duration::ZERO,
        };
        let Ok(c) = control(study) else {
            branch.warnings.push("the scene has no control".into());
            return branch;
        };
        let mut problem: Box<dyn Followed + '_> =
            study.problem(&cp.parameters, &Free::path(Some(c)));
        problem.release_held();
        // The reduced equation's direction first; where its first step cannot be taken (the
        // quadratic coefficient of a point where the loads are not smooth, as a fluid level
        // at the membrane, is no coefficient), the kernel direction itself.
        let mut first = None;
        let mut why = None;
        for k in [self.reduced.path_per_amplitude, 0.0] {
            if first.is_some()
                || (k == 0.0 && why.is_none() && self.reduced.path_per_amplitude == 0.0)
            {
                continue;
            }
            match self.first_step(&mut *problem, half, k) {
                Ok(p) => {
                    if k != self.reduced.path_per_amplitude {
                        branch.warnings.push(format!(
                            "the branch left along its kernel direction: the first step along \
                             the reduced equation's direction (ds/dA = {k0:.3e}) was cut below \
                             the smallest step ({})",
                            why.as_ref()
                                .map_or_else(String::new, |w: &crate::continuation::StepError| w
                                    .to_string()),
                            k0 = self.reduced.path_per_amplitude,
                        ));
                    }
                    first = Some(p);
                    // The normal form along the direction the branch could leave by.
                    let (start, tangent, plane) = self.departure(&mut *problem, half, k);
                    match normal_form(
                        &mut *problem,
                        &start,
                        &tangent,
                        &plane,
                        &self.phi,
                        &self.reduced,
                        opts,
                    ) {
                        Ok(nf) => branch.normal_form = Some(nf),
                        Err(e) => branch.warnings.push(format!("no normal form: {e}")),
                    }
                }
                Err(e) => why = Some(e),
            }
        }
        let Some(first) = first else {
            branch.stop = StopReason::Stalled(
                Stalled {
                    min_step: opts.min_step,
                    after: 0,
                    control: cp.parameters[c],
                    why: why.expect("a failed step has its reason"),
                    bound: None,
                }
                .into(),
            );
            return branch;
        };
        let mut driver = Continuation::new(problem, first, opts.clone());
        let measure = |u: &[f64], p: &[f64]| study.measure(u, p);
        let index = study
            .blocks()
            .ok()
            .map(|b| IndexChanges::new(Crossings::new(b, &measure, Some(c), false)));
        follow_branch(
            &mut driver,
            index,
            self.options.steps,
            &mut branch,
            Self::point,
        );
        observe(&mut branch, c, self.phi.as_slice(), opts.state_scale);
        branch
    }
}

/// The control's index: a branch leaves a path.
fn control(study: &MeridianStudy) -> Result<usize, String> {
    study
        .control()
        .map(|c| c.index)
        .ok_or_else(|| "the scene has no control (branches leave the points of a path)".into())
}
