//! The ponding ladder (docs/theory.md §13.3): critical densities of the flat,
//! pre-stretched, clamped disc under fluid at its rim, by irrep, against the closed form
//! γ_{m,k} = j²_{m,k} T0/(μ H λ0²). Modes are identified by their irrep and their Fourier
//! content (the wave number m of the mode's deflection), never by sorted order; doubles are
//! exact on symmetric meshes and splits are measured, with their gap under refinement.

use memstab::analysis::run;
use memstab::model::Model;
use memstab::reference::{BESSEL_J2, PONDING_SCALE};
use memstab::results::CriticalPoint;
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;

/// T0/(μ H λ0²) for k = 0, λ0 = 1.1.
const SCALE: f64 = PONDING_SCALE;

/// j²_{m,k} from the reference table.
fn j2(m: usize, k: usize) -> f64 {
    BESSEL_J2
        .iter()
        .find(|e| e.0 == (m, k))
        .map(|e| e.1)
        .expect("tabulated")
}

/// A critical point with the wave number of its mode.
#[derive(Debug, Clone)]
struct Rung {
    irrep: String,
    multiplicity: usize,
    rho: f64,
    m: usize,
}

/// The ponding scene on a disc with these options: its critical points with wave numbers.
fn ladder(
    sectors: usize,
    divisions: usize,
    group: Option<&str>,
    max: f64,
    samples: usize,
) -> Vec<Rung> {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/ponding.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut text = text
        .replace("sectors = 7 ", &format!("sectors = {sectors} "))
        .replace("divisions = 16 ", &format!("divisions = {divisions} "))
        .replace("max = 46.0 ", &format!("max = {max} "))
        .replace("samples = 92", &format!("samples = {samples}"));
    if let Some(g) = group {
        text = text.replace("divisions =", &format!("group = \"{g}\"\ndivisions ="));
    }
    let scene = Scene::from_toml_str(&text, "ponding variant").unwrap();
    let mut study = MeshStudy::build(scene).unwrap();
    let r = run(&mut study, |_, _| {}).unwrap().report;
    assert!(r.stability_note.is_none(), "{:?}", r.stability_note);
    r.critical
        .iter()
        .map(|c| {
            assert!(
                c.residual_eigenvalue < 1e-9,
                "{} in {} not localised: {:e}",
                c.kind,
                c.irrep,
                c.residual_eigenvalue
            );
            Rung {
                irrep: c.irrep.clone(),
                multiplicity: c.multiplicity,
                rho: c.parameters[0],
                m: wave_number(&study, c),
            }
        })
        .collect()
}

/// The m (0..=12) whose cos/sin mθ carries most of the mode's deflection.
fn wave_number(study: &MeshStudy, c: &CriticalPoint) -> usize {
    let layout = study.model.layout();
    let nodes = study.model.reference();
    (0..=12)
        .max_by(|&a, &b| {
            power(nodes, layout, &c.mode, a).total_cmp(&power(nodes, layout, &c.mode, b))
        })
        .unwrap()
}

fn power(
    nodes: &[nalgebra::Vector3<f64>],
    layout: &memstab::model::Layout,
    mode: &[f64],
    m: usize,
) -> f64 {
    let (mut c, mut s, mut nc, mut ns) = (0.0, 0.0, 0.0, 0.0);
    for (i, x) in nodes.iter().enumerate() {
        let Some(d) = layout.dof(i, 2) else { continue };
        let t = x.y.atan2(x.x) * m as f64;
        let r = x.x.hypot(x.y);
        c += mode[d] * t.cos() * r;
        s += mode[d] * t.sin() * r;
        nc += (t.cos() * r).powi(2);
        ns += (t.sin() * r).powi(2);
    }
    c * c / nc.max(1e-300) + if ns > 1e-12 { s * s / ns } else { 0.0 }
}

/// The rungs of wave number m, in increasing ρ.
fn of(rungs: &[Rung], m: usize) -> Vec<&Rung> {
    rungs.iter().filter(|r| r.m == m).collect()
}

#[test]
fn c7v_disc_doubles_in_e_k_and_m7_splits_into_a1_a2() {
    let rungs = ladder(7, 16, None, 48.0, 96);
    let m0 = of(&rungs, 0);
    assert_eq!(m0[0].irrep, "A1");
    assert!(
        (m0[0].rho / (SCALE * j2(0, 1)) - 1.0).abs() < 0.01,
        "{m0:?}"
    );
    for (m, irrep) in [(1, "E1"), (2, "E2"), (3, "E3")] {
        let r = of(&rungs, m);
        assert_eq!(
            (r[0].irrep.as_str(), r[0].multiplicity),
            (irrep, 2),
            "m = {m}: {r:?}"
        );
        assert!(
            (r[0].rho / (SCALE * j2(m, 1)) - 1.0).abs() < 0.03,
            "m = {m}: {r:?}"
        );
    }
    // m = 7 ≡ 0 (mod 7): cos 7θ in A1 and sin 7θ in A2, two simple points.
    let m7 = of(&rungs, 7);
    let names: Vec<&str> = m7.iter().map(|r| r.irrep.as_str()).collect();
    assert!(
        names.contains(&"A1") && names.contains(&"A2"),
        "m = 7: {m7:?}"
    );
    assert!(m7.iter().all(|r| r.multiplicity == 1));
}

#[test]
fn critical_densities_converge_at_second_order() {
    let coarse = ladder(7, 8, None, 16.0, 48);
    let fine = ladder(7, 16, None, 16.0, 48);
    for (m, k) in [(0, 1), (1, 1), (2, 1), (3, 1)] {
        let exact = SCALE * j2(m, k);
        let err = |rungs: &[Rung]| (of(rungs, m)[0].rho - exact).abs() / exact;
        let (e1, e2) = (err(&coarse), err(&fine));
        let rate = (e1 / e2).log2();
        assert!(
            (1.7..2.4).contains(&rate),
            "(m, k) = ({m}, {k}): errors {e1:e} → {e2:e}, rate {rate}"
        );
    }
}

/// The gap between the two simple points of wave number m, and their irreps.
fn split(rungs: &[Rung], m: usize) -> (f64, Vec<String>) {
    let r = of(rungs, m);
    assert!(r.len() >= 2, "m = {m}: expected a split pair, got {r:?}");
    assert!(r[0].multiplicity == 1 && r[1].multiplicity == 1, "{r:?}");
    (
        (r[1].rho - r[0].rho).abs(),
        vec![r[0].irrep.clone(), r[1].irrep.clone()],
    )
}

#[test]
fn c8v_disc_splits_m4_into_b1_b2_and_the_gap_shrinks_at_second_order() {
    let (g1, names) = split(&ladder(8, 8, None, 22.5, 45), 4);
    let (g2, _) = split(&ladder(8, 16, None, 22.5, 45), 4);
    let mut names = names;
    names.sort();
    assert_eq!(names, ["B1", "B2"]);
    let rate = (g1 / g2).log2();
    assert!(
        g2 > 0.0 && (1.5..2.6).contains(&rate),
        "gaps {g1:e} → {g2:e}, rate {rate}"
    );
}

/// On the C2v and C1v discs the symmetry is broken by a smooth perturbation of the node
/// positions whose amplitude is a fixed fraction of the element size (meshes::generators::disc),
/// so the mesh's departure from C_Nv is itself O(h), and the split gap — the asymmetric part
/// of the O(h²) discretisation error — shrinks faster than second order: measured about 3 for
/// between 3 and 5 here (printed). The test asserts at least second order. (On the C8v disc
/// the B1/B2 split of m = 4 comes from the structured mesh alone and is second order.)
#[test]
fn c2v_and_c1v_discs_split_every_pair() {
    for (sectors, group, expected) in [
        (8, "C2v", [("B1", "B2"), ("A1", "A2")]),
        (6, "C1v", [("A1", "A2"), ("A1", "A2")]),
    ] {
        let coarse = ladder(sectors, 8, Some(group), 10.5, 42);
        let fine = ladder(sectors, 16, Some(group), 10.5, 42);
        for (m, pair) in [(1, expected[0]), (2, expected[1])] {
            let (g1, mut names) = split(&coarse, m);
            let (g2, _) = split(&fine, m);
            names.sort();
            assert_eq!(names, [pair.0, pair.1], "{group}, m = {m}");
            let order = (g1 / g2).log2();
            eprintln!("{group}, m = {m}: gaps {g1:e} → {g2:e}, order {order:.2}");
            assert!(
                g2 > 0.0 && order > 1.8,
                "{group}, m = {m}: gaps {g1:e} → {g2:e}, order {order}"
            );
        }
    }
}

/// The chiral C7 disc (a twisted pattern, no mirror): the E_k blocks are Hermitian, so every
/// E_k rung is one crossing of multiplicity 2 — a double by construction — at the closed
/// form's m = k; m = 7 ≡ 0 (mod 7) puts both cos 7θ and sin 7θ in A, and the two are two
/// separate simple crossings of A whose gap is measured and shrinks under refinement (the
/// twist, like every symmetry-breaking perturbation of the generator, is a fixed fraction of
/// the node spacing).
#[test]
fn chiral_c7_disc_doubles_in_e_k_and_m7_gives_two_simple_points_in_a() {
    let coarse = ladder(7, 8, Some("C7"), 52.0, 104);
    let fine = ladder(7, 16, Some("C7"), 48.0, 96);
    for (m, irrep) in [(1, "E1"), (2, "E2"), (3, "E3")] {
        let r = of(&fine, m);
        assert_eq!(
            (r[0].irrep.as_str(), r[0].multiplicity),
            (irrep, 2),
            "m = {m}: {r:?}"
        );
        assert!(
            (r[0].rho / (SCALE * j2(m, 1)) - 1.0).abs() < 0.03,
            "m = {m}: {r:?}"
        );
    }
    assert!(fine
        .iter()
        .all(|r| r.multiplicity == if r.irrep == "A" { 1 } else { 2 }));
    // Every rung's irrep is one the Fourier pair of its wave number spans in C7.
    let c7 = memstab::symmetry::Group::by_name("C7").unwrap();
    for r in &fine {
        let spanned = c7.fourier_irreps(r.m).unwrap();
        assert!(
            spanned.iter().any(|(n, _)| *n == r.irrep),
            "{r:?}: {spanned:?}"
        );
    }
    let gap = |rungs: &[Rung]| {
        let r = of(rungs, 7);
        assert_eq!(r.len(), 2, "m = 7: {r:?}");
        assert!(
            r.iter().all(|x| x.irrep == "A" && x.multiplicity == 1),
            "m = 7: {r:?}"
        );
        assert!(
            r.iter()
                .all(|x| (x.rho / (SCALE * j2(7, 1)) - 1.0).abs() < 0.15),
            "m = 7: {r:?}"
        );
        (r[1].rho - r[0].rho).abs()
    };
    let (g1, g2) = (gap(&coarse), gap(&fine));
    let order = (g1 / g2).log2();
    eprintln!("C7, m = 7: gaps {g1:e} → {g2:e}, order {order:.2}");
    assert!(
        g2 > 0.0 && order > 1.8,
        "C7, m = 7: gaps {g1:e} → {g2:e}, order {order}"
    );
}

/// The axisymmetric reference (docs/theory.md §15) at 64 quadratic elements against the 3-D
/// C7v disc's Richardson values (4 ρ_32 − ρ_16)/3 from 16 and 32 divisions, with the scene's
/// fluid level a hair (1e-6) above the rim plane on both: the two discretisations of one
/// continuum problem meet to 1e-5 relative on the rungs (0, 1), (1, 1), (2, 1); on every rung
/// up to (3, 1) the Richardson value is at least 20 times closer to the reference than the
/// finer 3-D level (what is left is the 3-D mesh's next-order error, larger on the higher
/// rungs: 1.3e-5 on (0, 2)).
#[test]
fn the_axisymmetric_reference_meets_the_3d_richardson_values() {
    use memstab::axisym::{critical_densities, Hydrostatic, Meridian};
    use memstab::effects::membrane::MooneyRivlin;
    let coarse = ladder(7, 16, None, 16.0, 48);
    let fine = ladder(7, 32, None, 16.0, 48);
    let meridian = Meridian::disc(1.1, 64, 1.1, MooneyRivlin::new(100.0, 0.0, 0.01)).unwrap();
    let load = Hydrostatic {
        gravity: 1.0,
        level: 1e-6,
    };
    let axisym = critical_densities(&meridian, &meridian.nodes, &load, 3, 2).unwrap();
    for (m, k) in [(0, 1), (1, 1), (2, 1), (0, 2), (3, 1)] {
        let (q16, q32) = (of(&coarse, m)[k - 1].rho, of(&fine, m)[k - 1].rho);
        let richardson = (4.0 * q32 - q16) / 3.0;
        let reference = axisym[m].densities[k - 1];
        let distance = (richardson / reference - 1.0).abs();
        eprintln!(
            "(m, k) = ({m}, {k}): 3-D {q16:.7} / {q32:.7}, Richardson {richardson:.7}, \
             axisymmetric {reference:.7}, distance {distance:.1e}"
        );
        let finer = (q32 / reference - 1.0).abs();
        assert!(
            distance < 0.05 * finer,
            "(m, k) = ({m}, {k}): distance {distance:e}, finer level {finer:e}"
        );
        if k == 1 && m <= 2 {
            assert!(
                distance < 1e-5,
                "(m, k) = ({m}, {k}): distance {distance:e}"
            );
        }
    }
}
