//! Bundled scenes run end to end through scene → study → path: the right turning points,
//! finite numbers everywhere, and a stop reason that says why.

use memstab::analysis::run;
use memstab::reference::{L_MAX, L_MIN, P_MAX, P_MIN};
use memstab::results::CriticalKind;
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;

fn run_scene(name: &str) -> memstab::results::RunResult {
    let scene = Scene::load(format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR")))
        .expect("bundled scene loads");
    let mut study = MeshStudy::build(scene).expect("bundled scene builds");
    let result = run(&mut study, |_, _| {}).expect("the start converges");
    for r in &result.report.rows {
        assert!(
            r.parameters
                .iter()
                .chain(&r.measures)
                .all(|v| v.is_finite()),
            "non-finite row {r:?}"
        );
    }
    result
}

fn column(report: &memstab::results::PathReport, name: &str) -> usize {
    report
        .measures
        .iter()
        .position(|m| m == name)
        .unwrap_or_else(|| panic!("measure {name}"))
}

/// Along the path only the index is computed at every point; where it changes the crossing
/// must still be localised and classified: under pressure control the balloon's maximum
/// and minimum are limit points in Ag, at the pressures of the turning points.
#[test]
fn demo_balloon_path_finds_its_limit_points_in_the_trivial_irrep() {
    let r = run_scene("demo.toml").report;
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let found: Vec<(CriticalKind, &str)> = r
        .critical
        .iter()
        .map(|c| (c.kind, c.irrep.as_str()))
        .collect();
    assert_eq!(
        found,
        [
            (CriticalKind::LimitPoint, "Ag"),
            (CriticalKind::LimitPoint, "Ag")
        ]
    );
    let p = r.parameters.iter().position(|n| n == "p").unwrap();
    for (c, t) in r.critical.iter().zip(&r.turning_points) {
        let (pc, pt) = (c.parameters[p], t.parameters[p]);
        assert!(
            (pc - pt).abs() <= 1e-6 * pt,
            "critical p {pc} vs turning p {pt}"
        );
    }
}

#[test]
fn demo_balloon_passes_the_pressure_maximum_and_minimum() {
    let r = run_scene("demo.toml").report;
    assert_eq!(r.group, "Ih");
    assert!(r.stop.to_string().contains("stretch"), "{}", r.stop);
    let kinds: Vec<String> = r
        .turning_points
        .iter()
        .map(|t| t.kind.to_string())
        .collect();
    assert_eq!(kinds, ["maximum", "minimum"]);
    let s = column(&r, "stretch");
    let max = &r.turning_points[0];
    // f = 4 is coarse: within 2 % of the closed form 1.3551 at stretch 1.476.
    assert!(
        (max.parameters[0] - P_MAX).abs() < 0.03 * P_MAX,
        "{:?}",
        max.parameters
    );
    assert!((max.measures[s] - L_MAX).abs() < 0.01, "{:?}", max.measures);
}

#[test]
fn balloon_scene_matches_the_closed_form() {
    let r = run_scene("balloon.toml").report;
    let s = column(&r, "stretch");
    let max = &r.turning_points[0];
    let min = &r.turning_points[1];
    assert!(
        (max.parameters[0] / P_MAX - 1.0).abs() < 5e-3,
        "{:?}",
        max.parameters
    );
    assert!(
        (min.parameters[0] / P_MIN - 1.0).abs() < 5e-3,
        "{:?}",
        min.parameters
    );
    assert!((min.measures[s] - L_MIN).abs() < 0.01, "{:?}", min.measures);
}

/// J0 by its power series (enough terms for |x| < 5).
fn bessel_j0(x: f64) -> f64 {
    let (mut term, mut sum) = (1.0, 1.0);
    for k in 1..40 {
        term *= -(x * x / 4.0) / (k * k) as f64;
        sum += term;
    }
    sum
}

#[test]
fn ponding_disc_sags_as_the_bessel_solution_below_the_first_rung() {
    // Below the ponding ladder the pre-stretched disc (tension T0) under fluid to the level h
    // sags by d(r) = h (J0(k r)/J0(k a) − 1), k² = ρ g/T0, a = λ0 a0 the clamped radius:
    // T0 ∇²d + ρ g d = −ρ g h. At ρ = 1 the deflection is small and the membrane linear.
    let text = std::fs::read_to_string(format!(
        "{}/scenes/disc_fluid_above.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let (body, _) = text.split_once("[analysis]").expect("an analysis section");
    let text =
        body.replace("start = 0.0 ", "start = 1.0 ") + "[analysis]\ntype = \"equilibrium\"\n";
    let scene = Scene::from_toml_str(&text, "ponding-equilibrium").expect("the variant loads");
    let (h, rho, a) = (0.001, 1.0, 1.1);
    let t0 = 1.0 - 1.1f64.powi(-6); // k = 0: T0/(μH) = 1 − λ0⁻⁶, μH = 1
    let k = (rho / t0).sqrt();
    let exact = h * (1.0 / bessel_j0(k * a) - 1.0);
    let mut study = MeshStudy::build(scene).unwrap();
    let r = run(&mut study, |_, _| {}).unwrap().report;
    assert_eq!(r.rows.len(), 1);
    assert_eq!(r.rows[0].parameters[0], 1.0);
    let d = r.rows[0].measures[column(&r, "max_displacement")];
    assert!(
        (d / exact - 1.0).abs() < 0.01,
        "centre deflection {d:e}, Bessel solution {exact:e}"
    );
}
