//! The thesis's Paper 1 findings on the bundled scenes: the clamped disc pushed up by fluid
//! from below, its limit point followed in the material's k
//! (`scenes/thesis/paper1_disc_limit_curve_k.toml`, the thesis's 1 792-triangle C7v mesh).

use memstab::analysis::run;
use memstab::report::CurveEventKind;
use memstab::scene::Scene;
use memstab::study::Study;

fn bundled(name: &str) -> Scene {
    Scene::load(format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))).expect("the scene loads")
}

/// The curve starts at the limit point of the k = 0 path of `scenes/disc_fluid_below.toml`
/// (the same mesh, found independently as that path's turning point). Along k ∈ [0, 0.2]
/// the limit level rises with k and never turns back (no cusp: the fold does not vanish in
/// this range), and the curve meets the E1 double point's curve once, at a hilltop near
/// k = 0.02: for larger k the disc bifurcates into m = 1 before its level reaches the fold.
#[test]
fn the_disc_limit_point_rises_with_k_and_meets_the_first_double_point_at_one_hilltop() {
    let mut path = Study::build(bundled("disc_fluid_below.toml")).unwrap();
    let path = run(&mut path, |_, _| {}).expect("the path runs").report;
    let h_path = path.parameters.iter().position(|p| p == "h").unwrap();
    let fold = path.turning_points.first().expect("the k = 0 path folds");

    let mut study = Study::build(bundled("thesis/paper1_disc_limit_curve_k.toml")).unwrap();
    let curve = run(&mut study, |_, _| {})
        .expect("the curve runs")
        .curve
        .unwrap();
    assert!(curve.warnings.is_empty(), "{:?}", curve.warnings);
    let index = |name: &str| curve.parameters.iter().position(|p| p == name).unwrap();
    let (h, k) = (index("h"), index("k"));
    let start = &curve.rows[0];
    assert!(
        (start.parameters[h] - fold.parameters[h_path]).abs() < 1e-7 * fold.parameters[h_path],
        "the curve starts at h = {}, the path folds at {}",
        start.parameters[h],
        fold.parameters[h_path]
    );
    assert_eq!(start.parameters[k], 0.0);
    let last = curve.rows.last().unwrap();
    assert!(
        last.parameters[k] >= 0.2,
        "the curve stops at k = {}",
        last.parameters[k]
    );
    for w in curve.rows.windows(2) {
        assert!(
            w[1].parameters[k] > w[0].parameters[k] && w[1].parameters[h] > w[0].parameters[h],
            "the curve turns between steps {} and {}",
            w[0].step,
            w[1].step
        );
    }
    assert!(!curve.events.iter().any(|e| e.kind == CurveEventKind::Cusp));
    let hilltops: Vec<_> = curve
        .events
        .iter()
        .filter(|e| e.kind == CurveEventKind::Hilltop)
        .collect();
    assert_eq!(hilltops.len(), 1, "{:?}", curve.events);
    let hilltop = hilltops[0];
    assert_eq!(hilltop.irrep.as_deref(), Some("E1"));
    assert!(
        hilltop.parameters[k] > 0.01 && hilltop.parameters[k] < 0.04,
        "the hilltop is at k = {}",
        hilltop.parameters[k]
    );
}
