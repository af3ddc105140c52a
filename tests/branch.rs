//! Branch switching by the equivariant branching lemma (docs/theory.md §14): the branches an
//! abstract Hg potential has in closed form, the mirror branches of the upward-loaded C7v disc,
//! the reflection classes of E1, E2, E3 (and the kernels of B1, A2) on a C8v disc, and a split
//! pair on a C2v disc whose branches approach the C8v double's under refinement.

use crate::common::identity::act;
use memstab::analysis::run;
use memstab::bench::branching::{ih_branches, ih_problem, IH_COEFFICIENTS};
use memstab::model::Model;
use memstab::results::{
    Bifurcation, Branches, CriticalPoint, Half, Halves, Node, Skip, StopReason, SwitchedBranch,
};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use nalgebra::DVector;
use petgraph::graph::NodeIndex;

fn study(text: &str) -> MeshStudy {
    let scene = Scene::from_toml_str(text, "test").expect("scene");
    MeshStudy::build(scene).expect("study")
}

/// The bundled upward-loaded disc with other sectors, divisions, mesh group and bound, and
/// without its `[analysis.branches]` when `branches` is false.
fn upward(
    sectors: usize,
    divisions: usize,
    group: Option<&str>,
    max: f64,
    branches: bool,
) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/disc_upward.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut text = text
        .replace("sectors = 7\n", &format!("sectors = {sectors}\n"))
        .replace("divisions = 16 ", &format!("divisions = {divisions} "))
        .replace("max = 4.9 ", &format!("max = {max} "));
    if let Some(g) = group {
        text = text.replace("[material]", &format!("group = \"{g}\"\n\n[material]"));
    }
    if !branches {
        let cut = text
            .find("\n[analysis.branches]")
            .expect("the scene has branches");
        text.truncate(cut);
    }
    text
}

/// The elements of the study's group that map u to itself (to 1e-9 relative).
fn stabiliser(study: &MeshStudy, u: &[f64]) -> Vec<usize> {
    let norm = u.iter().map(|v| v * v).sum::<f64>().sqrt();
    (0..study.action.group().order())
        .filter(|&g| {
            let d: f64 = act(study, g, u)
                .iter()
                .zip(u)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            d <= 1e-9 * norm
        })
        .collect()
}

/// The branches leaving the path's critical point `k` (1-based).
fn leaving(b: &Branches, k: usize) -> Vec<&SwitchedBranch> {
    let n = b.graph.path_point(k).expect("the point is a node");
    b.graph
        .leaving(n)
        .into_iter()
        .map(|i| &b.graph.branches[i])
        .collect()
}

fn control(b: &SwitchedBranch, k: usize) -> f64 {
    b.points[k].parameters[0]
}

/// (a) The abstract potential Π = ½|u|² − ½λ|z|² + c₃ I₃ + c₃' J₃ + c₄|z|⁴ on the Hg part z
/// of the icosahedron's radial fields: the trivial path has one 5-fold point in Hg at λ = 1;
/// the branching lemma gives one branch per axial class of Hg — D5d and D3d — and both are
/// self-normalising, so both halves of each are followed: four branches, no symmetric copy.
/// On every branch point, z = a v with v fixed, v has the closed form of its class (D5d: the
/// two vertices on the 5-fold axis at ±1/√2.4, the ten others at ∓1/(5√2.4); D3d: the two
/// triangles around the 3-fold axis at ±1/√12, the other six vertices at ∓1/√12), the
/// displacement is purely radial and λ = 1 + 3 (c₃ I₃(v) + c₃' J₃(v)) a + 4 c₄ a² (§14.6).
#[test]
fn abstract_hg_potential_has_the_d5d_and_d3d_branches_in_closed_form() {
    let problem = ih_problem(IH_COEFFICIENTS).expect("problem");
    let run = ih_branches(&problem, 15).expect("switched");
    assert_eq!(
        run.critical.len(),
        1,
        "one critical point on the trivial path: {:?}",
        run.path
    );
    let cp = &run.critical[0];
    assert_eq!((cp.irrep.as_str(), cp.multiplicity), ("Hg", 5));
    assert!(
        (cp.parameters[0] - 1.0).abs() < 1e-9,
        "at λ = {}",
        cp.parameters[0]
    );
    let branches = &run.graph.branches;
    let mut found: Vec<(String, Half)> = branches
        .iter()
        .map(|b| (b.isotropy.clone(), b.half))
        .collect();
    found.sort_by(|a, b| (a.0.as_str(), a.1.sign() < 0.0).cmp(&(b.0.as_str(), b.1.sign() < 0.0)));
    assert_eq!(
        found,
        vec![
            ("D3d".to_string(), Half::Plus),
            ("D3d".to_string(), Half::Minus),
            ("D5d".to_string(), Half::Plus),
            ("D5d".to_string(), Half::Minus),
        ],
        "each axial class once, both halves"
    );
    let [c3, c3t, c4] = IH_COEFFICIENTS;
    let a5 = 1.0 / 2.4f64.sqrt();
    for b in branches {
        assert_eq!(b.halves, Halves::Distinct, "{}", b.isotropy);
        assert!(
            b.isotropy_exact(),
            "{}: {:?} {} {:?}",
            b.isotropy,
            b.warnings,
            b.stop,
            b.reduced
        );
        assert!(
            b.points.len() >= 10,
            "{}: {} points",
            b.isotropy,
            b.points.len()
        );
        let state = |k: usize| {
            let x = problem
                .model
                .positions(&b.points[k].u, &b.points[k].parameters);
            problem.potential.project(&problem.potential.radial(&x))
        };
        let first = state(1);
        let v: DVector<f64> = first.normalize();
        // The closed form of v.
        let mut mags: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        mags.sort_by(f64::total_cmp);
        let expected: Vec<f64> = match b.isotropy.as_str() {
            "D5d" => [vec![a5 / 5.0; 10], vec![a5; 2]].concat(),
            "D3d" => vec![1.0 / 12f64.sqrt(); 12],
            other => panic!("unexpected class {other}"),
        };
        for (m, e) in mags.iter().zip(&expected) {
            assert!(
                (m - e).abs() < 1e-9,
                "{}: |v_i| = {m}, expected {e}",
                b.isotropy
            );
        }
        assert!(v.iter().sum::<f64>().abs() < 1e-9, "v has no constant part");
        let (i3, j3) = problem.potential.cubics(&v);
        let slope = 3.0 * (c3 * i3 + c3t * j3);
        assert!(
            slope.abs() > 1e-3,
            "{}: the cubic is not zero on the line",
            b.isotropy
        );
        assert_eq!(
            b.reduced.bifurcation,
            Bifurcation::Transcritical,
            "{}",
            b.isotropy
        );
        // The corrector converges to 1e-10 of the state scale √12 per unknown: states are
        // exact to about 1e-9, the tolerance of the checks below.
        for k in 1..b.points.len() {
            let z = state(k);
            let a = z.dot(&v);
            let off = (&z - &v * a).norm();
            assert!(off < 1e-8, "{}: z leaves the line by {off:e}", b.isotropy);
            let u = DVector::from_vec(b.points[k].u.clone());
            let radial = (u.norm() - z.norm()).abs();
            assert!(radial < 1e-8, "not purely radial Hg: {radial:e}");
            let lambda = control(b, k);
            let exact = 1.0 + slope * a + 4.0 * c4 * a * a;
            assert!(
                (lambda - exact).abs() < 1e-8,
                "{} {}: λ = {lambda}, closed form {exact} at a = {a}",
                b.isotropy,
                b.half
            );
            assert!(b.points[k].index.is_some(), "stability along the branch");
        }
    }
    // The normal form of each half: λ − 1 = c A (A = a/σ along the kernel direction φ,
    // which is +v on the + half and −v on the − half), c = 3 (c₃ I₃ + c₃' J₃)(φ) σ exactly
    // (the closed form is linear plus quadratic in a, so one Richardson step is exact); its
    // first point gives c + 4 c₄ σ² A; the half that goes to λ > 1, where the trivial path is
    // unstable in Hg, is stable in its mode.
    let sigma = 12f64.sqrt();
    for b in branches {
        let nf = b.normal_form.as_ref().expect("a normal form");
        let v = {
            let x = problem
                .model
                .positions(&b.points[1].u, &b.points[1].parameters);
            problem
                .potential
                .project(&problem.potential.radial(&x))
                .normalize()
        };
        let (i3, j3) = problem.potential.cubics(&v);
        let expected = 3.0 * (c3 * i3 + c3t * j3) * sigma * b.half.sign();
        assert_eq!(nf.power, 1, "{} {}", b.isotropy, b.half);
        assert!(
            (nf.coefficient - expected).abs() < 1e-6 * expected.abs()
                && nf.error < 1e-3 * expected.abs(),
            "{} {}: c = {} ± {}, closed form {expected}",
            b.isotropy,
            b.half,
            nf.coefficient,
            nf.error
        );
        let (observed, a) = (
            nf.observed.expect("observed"),
            nf.observed_amplitude.unwrap(),
        );
        let first = expected + 4.0 * c4 * sigma * sigma * a;
        assert!(
            (observed - first).abs() < 1e-6 * first.abs(),
            "{} {}: the first point gives {observed}, closed form {first}",
            b.isotropy,
            b.half
        );
        assert_eq!(nf.criticality, None, "transcritical");
        assert_eq!(
            nf.mode_stable,
            Some(control(b, 1) > 1.0),
            "{} {}: stable in its mode where λ > 1",
            b.isotropy,
            b.half
        );
    }
    // Transcritical: the two halves of a class leave on opposite sides of λ = 1.
    for class in ["D5d", "D3d"] {
        let sides: Vec<f64> = branches
            .iter()
            .filter(|b| b.isotropy == class)
            .map(|b| (control(b, 1) - 1.0).signum())
            .collect();
        assert_eq!(sides.len(), 2);
        assert!(
            sides[0] * sides[1] < 0.0,
            "{class}: halves on opposite sides"
        );
    }
}

/// The abstract potential's residual, tangent (its rank-one terms included) and load
/// against central differences at a state with every term active.
#[test]
fn abstract_potential_derivatives() {
    let problem = ih_problem(IH_COEFFICIENTS).expect("problem");
    let n = problem.model.unknowns();
    let u: Vec<f64> = (0..n).map(|i| 0.1 * ((i as f64) * 0.7).sin()).collect();
    let d: Vec<f64> = (0..n).map(|i| ((i as f64) * 1.3).cos()).collect();
    let e = memstab::model::check::check_derivatives(&problem.model, &u, &[0.8], &d, 1e-5)
        .expect("evaluates");
    assert!(e.residual < 1e-8, "{e:?}");
    assert!(e.tangent < 1e-7, "{e:?}");
    assert!(e.asymmetry < 1e-12, "{e:?}");
    assert!(e.loads < 1e-7, "{e:?}");
}

/// (b) The upward-loaded C7v disc of the first paper (k = 0.1; 7 sectors, coarse divisions):
/// its first critical point is the E1 double point. E1 of C7v has one axial class, the mirror
/// C1v (m = 7 odd), and no element maps v to −v: two branches, both halves, each followed
/// for at least 20 points. On every state of a branch the mirror is the only element that
/// maps the state to itself (checked here by applying the group, not the library's check),
/// and every point has its index by the irreps of C1v.
#[test]
fn upward_disc_e1_point_has_two_mirror_branches() {
    let mut s = study(&upward(7, 6, None, 4.9, true));
    let result = run(&mut s, |_, _| {}).expect("runs");
    let first = &result.report.critical[0];
    assert_eq!(first.irrep, "E1", "{:?}", result.report.critical);
    let b = result.branches.as_ref().expect("branches");
    let out = leaving(b, 1);
    assert_eq!(out.len(), 2, "one class, two halves");
    let mirror = s.action.group().order() / 2; // the first mirror, the plane y = 0
    let mut halves = Vec::new();
    for br in &out {
        assert_eq!((br.irrep.as_str(), br.isotropy.as_str()), ("E1", "C1v"));
        assert_eq!(br.halves, Halves::Distinct);
        assert_eq!(
            br.reduced.bifurcation,
            Bifurcation::Pitchfork,
            "no invariant cubic"
        );
        assert!(br.points.len() > 20, "{} points", br.points.len());
        assert!(br.reduced.path_slope.abs() > 1e-8, "transversal crossing");
        for (k, p) in br.points.iter().enumerate().skip(1) {
            assert_eq!(stabiliser(&s, &p.u), vec![0, mirror], "point {k}");
            assert!(
                p.index.is_some(),
                "point {k}: stability by the irreps of C1v"
            );
            assert!(p.asymmetry > 0.0);
        }
        assert!(br.isotropy_exact());
        halves.push(br.half);
    }
    halves.sort_by_key(|h| h.sign() < 0.0);
    assert_eq!(halves, vec![Half::Plus, Half::Minus]);
    // The halves are not mapped onto each other: the states at the same distance from the
    // point differ by more than any element of C7v can account for.
    let (p, m) = (&out[0].points[3].u, &out[1].points[3].u);
    for g in 0..s.action.group().order() {
        let gp = act(&s, g, p);
        let d: f64 = gp
            .iter()
            .zip(m)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d > 1e-6, "element {g} maps one half onto the other");
    }
}

/// The first E1 point's number among the path's critical points, and its branches' classes.
fn classes(b: &Branches, k: usize) -> Vec<(String, usize)> {
    let mut c: Vec<(String, usize)> = leaving(b, k)
        .iter()
        .map(|x| (x.isotropy.clone(), x.elements.len()))
        .collect();
    c.sort();
    c
}

/// (c) A C8v disc: E1, E2, E3 double points give the two reflection classes C_dv and C_dv'
/// (d = gcd(8, k): C1v, C1v' for E1 and E3; C2v, C2v' for E2), one branch each (m = 8/d is
/// even, so the half-turn of D_m maps v to −v: the halves are conjugate); the simple B1 point
/// gives the kernel C4v and the A2 point the kernel C8 (chiral: its E_k blocks are Hermitian,
/// and its branch has its index by irreps like the others).
#[test]
fn c8v_disc_points_give_the_classes_of_the_lemma() {
    let mut s = study(&upward(8, 6, None, 12.0, false));
    let result = run(&mut s, |_, _| {}).expect("runs");
    let critical = &result.report.critical;
    let first = |irrep: &str| {
        critical
            .iter()
            .position(|c| c.irrep == irrep)
            .unwrap_or_else(|| panic!("no {irrep} point: {critical:?}"))
            + 1
    };
    let wanted = [
        first("E1"),
        first("E2"),
        first("E3"),
        first("B1"),
        first("A2"),
    ];
    let mut opts = branch_options(&s, None);
    opts.steps = 6;
    opts.path.max_steps = 6;
    opts.points = Some(wanted.to_vec());
    let b = memstab::study::switching::run(&s, critical, opts);
    let two = |d: usize| vec![(format!("C{d}v"), 2 * d), (format!("C{d}v'"), 2 * d)];
    assert_eq!(classes(&b, wanted[0]), two(1), "E1");
    assert_eq!(classes(&b, wanted[1]), two(2), "E2");
    assert_eq!(classes(&b, wanted[2]), two(1), "E3");
    assert_eq!(classes(&b, wanted[3]), vec![("C4v".to_string(), 8)], "B1");
    assert_eq!(classes(&b, wanted[4]), vec![("C8".to_string(), 8)], "A2");
    for &k in &wanted {
        for br in leaving(&b, k) {
            assert_eq!(br.halves, Halves::Conjugate, "{} {}", br.irrep, br.isotropy);
            assert_eq!(br.half, Half::Plus);
            assert_eq!(br.reduced.bifurcation, Bifurcation::Pitchfork);
            assert!(
                br.points.len() > 3,
                "{} {}: {:?}",
                br.irrep,
                br.isotropy,
                br.stop
            );
            assert!(
                br.isotropy_exact(),
                "{} {}: {:?}",
                br.irrep,
                br.isotropy,
                br.warnings
            );
            for p in &br.points[1..] {
                assert_eq!(
                    stabiliser(&s, &p.u),
                    br.elements,
                    "{} {}",
                    br.irrep,
                    br.isotropy
                );
            }
            assert!(br.stability_note.is_none(), "{:?}", br.stability_note);
            assert!(br.points[1].index.is_some(), "{} {}", br.irrep, br.isotropy);
        }
    }
    // The points not asked for are nodes without branches, marked so.
    let skipped = b
        .graph
        .graph
        .node_weights()
        .filter(|n| {
            matches!(
                n,
                Node::Critical {
                    on: None,
                    skipped: Some(Skip::NotRequested),
                    ..
                }
            )
        })
        .count();
    assert_eq!(skipped, critical.len() - wanted.len());
}

/// The centre node's horizontal displacement (the tilt of an m = 1 branch) and the control at
/// every point of a branch.
fn tilt(s: &MeshStudy, b: &SwitchedBranch) -> Vec<(f64, f64)> {
    let layout = s.model.layout();
    let centre = s
        .model
        .reference()
        .iter()
        .position(|x| x.norm() < 1e-12)
        .expect("a node at the centre");
    let d = layout.dof(centre, 0).expect("free");
    b.points
        .iter()
        .map(|p| (p.u[d].hypot(p.u[d + 1]), p.parameters[0]))
        .collect()
}

/// The control where the tilt first reaches `target` (linear interpolation).
fn control_at(curve: &[(f64, f64)], target: f64) -> f64 {
    let k = curve
        .windows(2)
        .position(|w| (w[0].0 - target) * (w[1].0 - target) <= 0.0)
        .expect("the branch reaches the tilt");
    let (a, b) = (curve[k], curve[k + 1]);
    a.1 + (b.1 - a.1) * (target - a.0) / (b.0 - a.0)
}

/// Switches at the given critical points of a disc's path; the branches, in point order.
fn branches_at(s: &MeshStudy, critical: &[CriticalPoint], points: Vec<usize>) -> Branches {
    let mut opts = branch_options(s, None);
    opts.steps = 12;
    opts.path.max_steps = 12;
    opts.points = Some(points);
    memstab::study::switching::run(s, critical, opts)
}

/// (d) On a C2v disc (8 sectors) the E1 double point of C8v is split into two simple points,
/// B1 and B2 (measured, never inferred). Each is switched on its own: the kernel of B1 is the
/// mirror y = 0 (C1v) and that of B2 the mirror x = 0 (C1v'), one branch each. Both approach
/// the C8v branch of the mirror class (whose mirrors are y = 0 and, conjugate to it, x = 0)
/// under refinement: the control at a given tilt of the centre differs from C8v's by less on
/// the finer mesh — a measured difference that shrinks, on top of the split of the points.
#[test]
fn split_pair_branches_approach_the_double_point_branch() {
    let mut gaps = Vec::new();
    for divisions in [4, 8] {
        let mut c8 = study(&upward(8, divisions, None, 4.7, false));
        let r8 = run(&mut c8, |_, _| {}).expect("runs").report.critical;
        let e1 = r8.iter().position(|c| c.irrep == "E1").expect("E1") + 1;
        let b8 = branches_at(&c8, &r8, vec![e1]);
        let mirror = leaving(&b8, e1)
            .into_iter()
            .find(|b| b.isotropy == "C1v")
            .expect("the mirror class");
        let reference = tilt(&c8, mirror);
        let mut c2 = study(&upward(8, divisions, Some("C2v"), 4.7, false));
        let r2 = run(&mut c2, |_, _| {}).expect("runs").report.critical;
        let pos = |i: &str| r2.iter().position(|c| c.irrep == i).expect(i) + 1;
        let (p1, p2) = (pos("B1"), pos("B2"));
        let split = (r2[p1 - 1].parameters[0] - r2[p2 - 1].parameters[0]).abs();
        assert!(
            split > 1e-8 * r2[p1 - 1].parameters[0],
            "the pair is split: {split}"
        );
        let b2 = branches_at(&c2, &r2, vec![p1, p2]);
        let target = 0.5 * reference.iter().map(|p| p.0).fold(0.0, f64::max);
        let h8 = control_at(&reference, target);
        let mut worst: f64 = 0.0;
        for (k, class, mirror) in [(p1, "C1v", 2), (p2, "C1v'", 3)] {
            let out = leaving(&b2, k);
            assert_eq!(out.len(), 1, "one branch from a simple point");
            let br = out[0];
            assert_eq!(br.isotropy, class);
            assert_eq!(br.elements, vec![0, mirror], "the kernel of {}", br.irrep);
            assert!(br.isotropy_exact());
            let h2 = control_at(&tilt(&c2, br), target);
            worst = worst.max((h2 - h8).abs());
        }
        eprintln!("divisions {divisions}: split {split:e}, branch gap {worst:e} at tilt {target}");
        gaps.push(worst);
    }
    assert!(
        gaps[1] < 0.5 * gaps[0],
        "the branches approach C8v's: {gaps:?}"
    );
}

/// Depth 2: the critical points found along the C1v branches of the upward disc are switched
/// in their turn, in C1v: a simple point in A2 (the antisymmetric irrep of the mirror) gets
/// one branch with the kernel of A2 as isotropy — the trivial group C1 — and a limit point
/// (A1) none. At depth 1 the same points are nodes without branches.
#[test]
fn depth_two_switches_at_the_branches_points() {
    let mut s = study(&upward(7, 6, None, 4.9, false));
    let critical = run(&mut s, |_, _| {}).expect("runs").report.critical;
    let scene: Scene = Scene::from_toml_str(&upward(7, 6, None, 4.9, true), "t").unwrap();
    let Some(p) = scene.analysis.get::<memstab::scene::PathAnalysis>() else {
        panic!("a path")
    };
    let mut opts = branch_options(&s, p.branches.as_ref());
    opts.depth = 2;
    opts.steps = 40;
    opts.path.max_steps = 40;
    let b = memstab::study::switching::run(&s, &critical, opts);
    let primary: Vec<&SwitchedBranch> = b
        .graph
        .branches
        .iter()
        .filter(|x| x.parent.is_none())
        .collect();
    assert_eq!(primary.len(), 2);
    let mut secondary = 0;
    let mut connected = 0;
    for n in b.graph.graph.node_indices() {
        let Node::Critical {
            on: Some(parent),
            point,
            skipped,
            ..
        } = &b.graph.graph[n]
        else {
            continue;
        };
        let out = b.graph.leaving(n);
        if b.graph.branches[*parent].parent.is_some() {
            // On a branch of depth 2: not switched again — or the point is, up to
            // symmetry, a critical point of another branch already followed, where this one
            // ends, connected to it.
            assert!(out.is_empty());
            match skipped {
                Some(Skip::LimitPoint | Skip::Depth) => {}
                Some(Skip::Connection { on: Some(k), .. }) => {
                    assert_ne!(*k, *parent, "another branch");
                    assert!(
                        b.graph.branches[*k].elements.len()
                            >= b.graph.branches[*parent].elements.len(),
                        "at least as symmetric"
                    );
                    assert!(matches!(
                        b.graph.branches[*parent].stop,
                        StopReason::Connected { .. }
                    ));
                    connected += 1;
                }
                other => panic!("{other:?}"),
            }
            continue;
        }
        match point.irrep.as_str() {
            "A1" => {
                assert!(out.is_empty());
                assert_eq!(skipped, &Some(Skip::LimitPoint));
            }
            "A2" if matches!(skipped, Some(Skip::Known(_))) => {
                // The one C1 half here is a branch followed from another A2 point, which
                // reaches this one: known, not followed again.
                let Some(Skip::Known(known)) = skipped else {
                    unreachable!()
                };
                assert!(out.is_empty());
                assert!(known.iter().all(
                    |&k| b.graph.branches[k].isotropy == "C1" && b.graph.branches[k].from != n
                ));
            }
            "A2" => {
                assert_eq!(out.len(), 1, "the kernel of A2, one branch");
                let br = &b.graph.branches[out[0]];
                assert_eq!(br.parent, Some(*parent));
                assert_eq!((br.irrep.as_str(), br.isotropy.as_str()), ("A2", "C1"));
                assert_eq!(br.elements, vec![0]);
                assert!(br.points.len() > 3, "{:?}", br.stop);
                assert!(br.isotropy_exact(), "{:?}", br.warnings);
                for q in &br.points[1..] {
                    assert_eq!(stabiliser(&s, &q.u), vec![0]);
                }
                secondary += 1;
            }
            other => panic!("unexpected critical point in {other} on a C1v branch"),
        }
    }
    assert!(secondary >= 1, "some A2 point on the C1v branches");
    eprintln!("depth 2: {connected} connections");
}

/// The branch options of a study's path analysis with `[analysis.branches]` `b` (the defaults
/// without it).
fn branch_options(
    s: &MeshStudy,
    b: Option<&memstab::scene::BranchesAnalysis>,
) -> memstab::study::BranchOptions {
    memstab::analysis::path_of(&s.scene.analysis)
        .expect("a path analysis")
        .branch_options(s, b)
}

/// Without the cubic terms the Hg point is a pitchfork on every axial line: λ = 1 + 4 c₄ a²,
/// so the normal form is λ − 1 ≈ 4 c₄ σ² A² on both halves of both classes, supercritical
/// (the branch at λ > 1, stable in its mode, where the trivial path is unstable) for c₄ > 0
/// and subcritical for c₄ < 0.
#[test]
fn hg_pitchfork_normal_form_is_the_closed_form_and_says_which_side() {
    use memstab::results::Criticality;
    let sigma2 = 12.0;
    for (c4, criticality) in [
        (0.5, Criticality::Supercritical),
        (-0.5, Criticality::Subcritical),
    ] {
        let problem = ih_problem([0.0, 0.0, c4]).expect("problem");
        let run = ih_branches(&problem, 4).expect("switched");
        let branches = &run.graph.branches;
        assert!(!branches.is_empty(), "branches for c4 = {c4}");
        for b in branches {
            assert_eq!(b.reduced.bifurcation, Bifurcation::Pitchfork);
            let nf = b.normal_form.as_ref().expect("a normal form");
            let expected = 4.0 * c4 * sigma2;
            assert_eq!(nf.power, 2);
            assert!(
                (nf.coefficient - expected).abs() < 1e-6 * expected.abs(),
                "c4 = {c4}, {} {}: c = {} ± {}, closed form {expected}",
                b.isotropy,
                b.half,
                nf.coefficient,
                nf.error
            );
            assert_eq!(nf.criticality, Some(criticality), "c4 = {c4}");
            assert_eq!(
                nf.mode_stable,
                Some(criticality == Criticality::Supercritical)
            );
            let observed = nf.observed.expect("observed");
            assert!(
                (observed - expected).abs() < 1e-6 * expected.abs(),
                "c4 = {c4}: the first point gives {observed}, closed form {expected}"
            );
            assert_eq!(
                (control(b, 1) - 1.0).signum(),
                c4.signum(),
                "the branch on the predicted side"
            );
        }
    }
}

/// With f(λ) = λ − μ λ², μ = 2/9, the trivial path of the abstract potential has two Hg points,
/// at λ = 3/2 and 3, and every axial branch is a closed curve f(λ) = 1 + κ a + 4 c₄ a² through
/// both (κ = 3 (c₃ I₃ + c₃' J₃)(v)). The two halves of each class leave the first point and
/// trace the curve in opposite senses; each ends where it reaches the second point, a
/// connection: the closed circuit of two branches between two bifurcation points. At the
/// second point every half the lemma predicts arrived along one of them, so none is followed
/// again: four branches, not eight, and none goes around twice.
#[test]
fn branches_joining_two_points_form_a_closed_circuit_followed_once() {
    use memstab::bench::branching::{ih_branches_over, ih_problem_curved};
    let mu = 2.0 / 9.0;
    let problem = ih_problem_curved(IH_COEFFICIENTS, mu).expect("problem");
    let run = ih_branches_over(&problem, 160, (0.5, 3.6), 0.52).expect("switched");
    let at: Vec<f64> = run.critical.iter().map(|c| c.parameters[0]).collect();
    assert_eq!(
        at.len(),
        2,
        "two critical points on the trivial path: {at:?}"
    );
    assert!(
        (at[0] - 1.5).abs() < 1e-8 && (at[1] - 3.0).abs() < 1e-8,
        "{at:?}"
    );
    let g = &run.graph;
    let path = [g.path_point(1).unwrap(), g.path_point(2).unwrap()];
    let classes: Vec<(String, Half, NodeIndex)> = g
        .branches
        .iter()
        .map(|b| (b.isotropy.clone(), b.half, b.from))
        .collect();
    assert_eq!(
        classes,
        vec![
            ("D5d".to_string(), Half::Plus, path[0]),
            ("D5d".to_string(), Half::Minus, path[0]),
            ("D3d".to_string(), Half::Plus, path[0]),
            ("D3d".to_string(), Half::Minus, path[0]),
        ],
        "both halves of each class from the first point, none from the second"
    );
    let [c3, c3t, c4] = IH_COEFFICIENTS;
    for (i, b) in g.branches.iter().enumerate() {
        // On the closed curve (or, where a last step was drawn onto it, on the path u = 0).
        let z = |k: usize| {
            let x = problem
                .model
                .positions(&b.points[k].u, &b.points[k].parameters);
            problem.potential.project(&problem.potential.radial(&x))
        };
        let v = z(1).normalize();
        let (i3, j3) = problem.potential.cubics(&v);
        for k in 1..b.points.len() {
            let a = z(k).dot(&v);
            let l = b.points[k].parameters[0];
            let f = l - mu * l * l;
            let exact = 1.0 + 3.0 * (c3 * i3 + c3t * j3) * a + 4.0 * c4 * a * a;
            assert!(
                (f - exact).abs() < 1e-8 || z(k).norm() < 1e-8,
                "{} {}: f(λ) = {f}, closed form {exact}",
                b.isotropy,
                b.half
            );
        }
        // It ends at the second point, connected to it.
        assert!(
            matches!(b.stop, StopReason::Connected { .. }),
            "{} {}: {}",
            b.isotropy,
            b.half,
            b.stop
        );
        let last = b.points.last().unwrap();
        assert!(
            (last.parameters[0] - 3.0).abs() < 1e-6,
            "ends at λ = {}",
            last.parameters[0]
        );
        let to: Vec<NodeIndex> = g
            .connections
            .iter()
            .filter(|c| c.branch == i)
            .map(|c| c.to)
            .collect();
        assert!(
            !to.is_empty() && to.iter().all(|&n| n == path[1]),
            "{} {}: connects to {to:?}",
            b.isotropy,
            b.half
        );
    }
    assert!(g.leaving(path[1]).is_empty());
    match &g.graph[path[1]] {
        Node::Critical {
            skipped: Some(Skip::Known(b)),
            ..
        } => assert_eq!(b.len(), 4, "{b:?}"),
        other => panic!("the second point: {other:?}"),
    }
}

/// The spinning cap's E1 double (Paper 4, C8v, 12 divisions, ω² = 18.095): its branches, of
/// isotropy C1v, contain the drift across the spin axis, which the stability blocks hold
/// (docs/theory.md §8.5) — the critical point is one of the held body. Held on the branch as
/// well, both branches (the two classes of mirrors, C1v and C1v') leave it as pitchforks, their states of exactly their isotropy; each
/// says that it is held and with what force. Free on the branch, no first step converged
/// (the critical point of the held blocks is no bifurcation of the free body).
#[test]
fn the_spinning_caps_e1_branches_hold_the_drift_and_leave() {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/thesis/paper4_spinning_cap.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("max = 30.0", "max = 18.4")
    .replace("stop-displacement = 1.2", "")
        + "\n[analysis.branches]\ndepth = 1\nsteps = 4\npoints = [2]\n";
    let mut s = study(&text);
    let result = run(&mut s, |_, _| {}).expect("run");
    let cp = &result.report.critical[1];
    assert_eq!((cp.irrep.as_str(), cp.multiplicity), ("E1", 2));
    assert!(
        (cp.parameters[1] - 18.0954).abs() < 1e-3,
        "{:?}",
        cp.parameters
    );
    let b = result.branches.as_ref().expect("branches");
    let leaving = leaving(b, 2);
    assert_eq!(
        leaving.len(),
        2,
        "one class, both halves or a conjugate pair"
    );
    for br in leaving {
        assert!(br.isotropy.starts_with("C1v"), "{}", br.isotropy);
        assert_eq!(
            br.points.len(),
            5,
            "{}: {:?} {:?}",
            br.isotropy,
            br.stop,
            br.warnings
        );
        assert!(br.isotropy_exact());
        assert!(
            br.warnings
                .iter()
                .any(|w| w.contains("holds 2 neutral motions")
                    || w.contains("holds 1 neutral motion")),
            "{:?}",
            br.warnings
        );
        // The branch leaves: its states move off the path's, with the control.
        let asymmetry: Vec<f64> = br.points.iter().map(|p| p.asymmetry).collect();
        assert!(
            asymmetry[1] > 0.0 && asymmetry.windows(2).all(|w| w[1] > w[0]),
            "{asymmetry:?}"
        );
        assert!(
            control(br, 4) < control(br, 0),
            "subcritical, as its normal form says"
        );
    }
}
