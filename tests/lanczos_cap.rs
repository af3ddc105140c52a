//! Stability of large blocks on the truncated-sphere cap: Lanczos on a block of more than
//! 2000 columns against dense, the inertia count at any shift, and a path on a C1v cap
//! whose crossings are localised and classified in blocks solved by Lanczos.

use memstab::adapted::AdaptedBasis;
use memstab::analysis::run;
use memstab::model::Model;
use memstab::results::CriticalKind;
use memstab::scene::Scene;
use memstab::stability::{BlockEigen, Detail, Stability};
use memstab::study::mesh::MeshStudy;

/// A clamped cap filled with fluid under a head above its top, spinning about z (ω² the
/// control): the Paper 4-like scene of the bench, on `pattern` with `divisions`.
pub fn spinning_cap(pattern: &str, divisions: usize, steps: usize) -> MeshStudy {
    spinning_cap_stepping(pattern, divisions, steps, 0.05, 0.5)
}

/// [`spinning_cap`] with the first and the largest arclength step given.
fn spinning_cap_stepping(
    pattern: &str,
    divisions: usize,
    steps: usize,
    initial_step: f64,
    max_step: f64,
) -> MeshStudy {
    let text = format!(
        r#"
[scene]
name = "spinning-cap"
[mesh]
generator = "truncated-sphere"
cut-height = -0.5
pattern = "{pattern}"
divisions = {divisions}
[material]
mu = 100.0
k = 0.1
thickness = 0.01
prestretch = 1.05
[[effect]]
type = "fluid"
side = "inside"
density = 1.0
gravity = 1.0
level = 1.5
[[effect]]
type = "spin"
density = 1.0
omega2 = "w"
[boundary]
fixed = ["cut"]
[parameters.w]
start = 0.0
max = 40.0
[analysis]
type = "path"
control = "w"
steps = {steps}
initial-step = {initial_step}
max-step = {max_step}
save-every = 100
"#
    );
    MeshStudy::build(Scene::from_toml_str(&text, "spinning-cap").unwrap()).unwrap()
}

/// On a C1 cap of 2187 unknowns (one block, larger than a dense solve was once allowed), the
/// lowest eigenvalues by Lanczos are the dense ones, and the inertia of the bordered block
/// counts the dense eigenvalues below several shifts.
#[test]
fn lanczos_on_a_large_block_matches_dense() {
    let mut study = spinning_cap("C1", 14, 1);
    let params = vec![0.3];
    let u = memstab::bench::solve_start(&mut study, &params).unwrap();
    let basis = AdaptedBasis::new(&study.action, study.model.layout()).unwrap();
    assert_eq!(basis.irreps.len(), 1);
    let m = basis.irreps[0].first().dim();
    assert!(m > 2000, "{m} columns");
    let mut eval = study.model.new_evaluation();
    let lowest = 10;
    let detail = Detail::Eigenvalues { lowest };
    let dense = Stability::new(&study.model, &basis)
        .with_block_eigen(BlockEigen::Dense)
        .analyse(&u, &params, &[], &mut eval, None, detail)
        .unwrap();
    let lanczos = Stability::new(&study.model, &basis).with_block_eigen(BlockEigen::Lanczos);
    let sparse = lanczos
        .analyse(&u, &params, &[], &mut eval, None, detail)
        .unwrap();
    let (d, l) = (&dense.blocks[0], &sparse.blocks[0]);
    assert!(!l.complete && l.eigen_error.is_none());
    assert_eq!(l.eigenvalues.len(), lowest);
    for (a, b) in d.eigenvalues.iter().zip(&l.eigenvalues) {
        assert!((a - b).abs() <= 1e-10 * dense.scale, "{a} vs {b}");
    }
    assert_eq!(d.negative, l.negative);
    // The default chooses Lanczos for this block, and gets the same values.
    let by_cost = Stability::new(&study.model, &basis)
        .analyse(&u, &params, &[], &mut eval, None, detail)
        .unwrap();
    assert!(!by_cost.blocks[0].complete);
    assert_eq!(by_cost.blocks[0].eigenvalues, l.eigenvalues);
    // The index at this state comes with the inertia at zero.
    let index = lanczos
        .analyse(&u, &params, &[], &mut eval, None, Detail::Inertia)
        .unwrap();
    assert_eq!(
        index.blocks[0].negative,
        d.eigenvalues.iter().filter(|&&v| v < 0.0).count()
    );
}

/// A path on a C1v cap (blocks of about 800 columns, solved by Lanczos). The C1v mesh breaks
/// the cap's m = 1 pair: its cos θ component lies in the path's fixed-point space, where the
/// bifurcation becomes an imperfect one, and the connected path turns at a fold of ω² there.
/// The path follows that fold (a step over it onto the other piece reverses the path's
/// orientation and is rejected, docs/theory.md §7.5.2): the trivial block's crossing is a
/// limit point at the maximum of ω², localised to round-off, at the value a path of steps
/// ten times shorter finds; the sin θ component's crossings on the way back are simple
/// bifurcations in A2 that break the mirror; every change of the index is a localised
/// critical point and nothing is left as a warning. On the C2v cap of the same size the m = 1
/// pair is split into two simple bifurcations (B1, B2), both localised, a measured gap apart.
#[test]
fn a_c1v_cap_localises_and_classifies_its_crossings() {
    let mut c1v = spinning_cap("C1v", 12, 24);
    let r = run(&mut c1v, |_, _| {}).unwrap().report;
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let turning = r.turning_points.first().expect("a maximum of w");
    let top = turning.parameters[0];
    let first = r.critical.first().expect("critical points");
    assert_eq!(
        (first.kind, first.irrep.as_str()),
        (CriticalKind::LimitPoint, "A1"),
        "{:?}",
        kinds(&r.critical)
    );
    assert!(first.residual_eigenvalue < 1e-10);
    assert!((top - first.parameters[0]).abs() < 1e-6 * top);
    // The same fold from steps ten times shorter: the default steps stayed on the path.
    let mut fine = spinning_cap_stepping("C1v", 12, 60, 0.02, 0.05);
    let rf = run(&mut fine, |_, _| {}).unwrap().report;
    let top_fine = rf
        .turning_points
        .first()
        .expect("a maximum of w")
        .parameters[0];
    assert!((top - top_fine).abs() < 1e-8 * top, "{top} {top_fine}");
    // Beyond the fold the mirror breaks in A2, on the way back down in ω².
    let broken: Vec<_> = r.critical.iter().skip(1).collect();
    assert!(!broken.is_empty(), "{:?}", kinds(&r.critical));
    for c in &broken {
        assert_eq!(
            (c.kind, c.irrep.as_str(), c.isotropy.name.as_str()),
            (CriticalKind::SimpleBifurcation, "A2", "C1"),
        );
        assert!(c.parameters[0] < top && c.residual_eigenvalue < 1e-10);
    }
    // Every step across which the index changes has a critical point.
    for (i, w) in r.rows.windows(2).enumerate() {
        if w[0].index != w[1].index {
            assert!(
                r.critical.iter().any(|c| c.after_step == i),
                "step {i}: {:?}",
                kinds(&r.critical)
            );
        }
    }

    let mut c2v = spinning_cap("C2v", 12, 12);
    let r = run(&mut c2v, |_, _| {}).unwrap().report;
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let simple: Vec<_> = r
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::SimpleBifurcation)
        .collect();
    let irreps: Vec<&str> = simple.iter().map(|c| c.irrep.as_str()).collect();
    assert!(
        irreps.contains(&"B1") && irreps.contains(&"B2"),
        "{irreps:?}"
    );
    for c in &simple {
        assert!(c.residual_eigenvalue < 1e-10);
    }
    let gap = (simple[0].parameters[0] - simple[1].parameters[0]).abs();
    assert!(
        gap > 0.0 && gap < 1e-2 * simple[0].parameters[0],
        "gap {gap}"
    );
    let _ = c1v.model.unknowns();
}

/// Kind, irrep and control of each critical point, for messages.
fn kinds(critical: &[memstab::results::CriticalPoint]) -> Vec<String> {
    critical
        .iter()
        .map(|c| format!("{:?} {} {}", c.kind, c.irrep, c.parameters[0]))
        .collect()
}
