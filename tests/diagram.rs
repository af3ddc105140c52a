//! The global diagram (`type = "diagram"`, docs/theory.md §16.4): beside a fold of the path
//! that a mesh of less symmetry made out of a bifurcation, the second piece — which the path
//! never reaches — is found, measured (its gap) and followed, with its index and its
//! critical points; a fold of the path alone has none. `compare` lists the second piece's
//! points as the images of the symmetric mesh's doubles.

use crate::common::identity::{act, common_stretches};
use crate::common::{memstab, text};
use memstab::analysis::run;
use memstab::results::partner::Partner;
use memstab::results::{CriticalKind, RunResult};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;

fn bundled(name: &str) -> String {
    std::fs::read_to_string(format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// Runs the scene `text`; the diagram's search beside each fold and the run.
fn diagram(text: &str) -> (Vec<Partner>, RunResult) {
    let scene = Scene::from_toml_str(text, "diagram").unwrap();
    let mut study = memstab::study::build(scene).unwrap();
    let result = run(&mut *study, |_, _| {}).unwrap();
    let partners = result
        .outcome::<Vec<Partner>>()
        .cloned()
        .expect("the diagram's search beside the folds");
    (partners, result)
}

/// Paper 4's spinning cap on the C2v mesh, as a diagram: the path, the branches of its
/// bifurcation points (`depth = 1`, a few steps) and the second pieces.
fn c2v_cap(partner_steps: usize) -> String {
    bundled("thesis/paper4_spinning_cap.toml")
        .replace("pattern = \"C8v\"", "pattern = \"C2v\"")
        .replace(
            "type = \"path\"",
            &format!(
                "type = \"diagram\"\ndepth = 1\nbranch-steps = 2\npartner-steps = {partner_steps}"
            ),
        )
        .replace("steps = 300", "steps = 100")
}

fn w2(result: &RunResult, parameters: &[f64]) -> f64 {
    let c = result.report.parameters.iter().position(|n| n == "w2");
    parameters[c.unwrap()]
}

/// cos 2θ lies in A1 of C2v: the cap's m = 2 double becomes a fold of the path (16.697 at
/// 12 divisions, just below the C8v double, 16.761). Beyond it the connected path never goes;
/// the diagram finds the second piece at the fold's control value, apart from the fold's
/// state, unstable (the other half of the broken pitchfork), and follows it to the C8v
/// cap's m = 1 double, which C2v splits into two simple points in B1 and B2.
#[test]
fn the_second_piece_of_the_c2v_caps_broken_double_carries_the_m1_pair() {
    // The C8v cap's m = 2 and m = 1 doubles, the values the C2v mesh breaks.
    let c8v = bundled("thesis/paper4_spinning_cap.toml").replace("steps = 300", "steps = 200");
    let mut study = memstab::study::build(Scene::from_toml_str(&c8v, "c8v").unwrap()).unwrap();
    let reference = run(&mut *study, |_, _| {}).unwrap();
    let double = |m: usize| {
        let r = &reference.report;
        r.critical
            .iter()
            .zip(&r.wave_numbers)
            .find(|(c, &k)| k == m && c.multiplicity == 2)
            .map(|(c, _)| w2(&reference, &c.parameters))
            .unwrap_or_else(|| panic!("no m = {m} double on C8v: {:?}", r.critical))
    };
    let (e2, e1) = (double(2), double(1));
    let (partners, result) = diagram(&c2v_cap(35));
    let report = &result.report;
    let folds: Vec<_> = report
        .critical
        .iter()
        .enumerate()
        .filter(|(_, c)| c.kind == CriticalKind::LimitPoint)
        .collect();
    assert_eq!(folds.len(), 1, "{:?}", report.critical);
    let (k, fold) = folds[0];
    assert_eq!(report.wave_numbers[k], 2);
    let at = w2(&result, &fold.parameters);
    // Just below the double it breaks.
    assert!(
        at < e2 && at > 0.99 * e2,
        "the fold at w2 = {at}, the C8v double at {e2}"
    );
    // The connected path stays on its side of the fold.
    let reach = report
        .rows
        .iter()
        .map(|r| w2(&result, &r.parameters))
        .fold(f64::MIN, f64::max);
    assert!(reach <= at * (1.0 + 1e-12), "the path reaches {reach}");

    assert_eq!(partners.len(), 1);
    let p = &partners[0];
    assert_eq!((p.fold, p.value), (k + 1, at));
    let piece = p.piece.as_ref().unwrap_or_else(|| panic!("{p:?}"));
    assert!(
        piece.gap > 1e-3 && piece.gap.is_finite(),
        "gap {}",
        piece.gap
    );
    let r = &piece.run.report;
    // It starts at the fold's control value, unstable, and goes on beyond the fold.
    assert_eq!(w2(&result, &r.rows[0].parameters), at);
    assert!(r.rows[0].index.unwrap() >= 1, "{:?}", r.rows[0]);
    let beyond = r
        .rows
        .iter()
        .map(|row| w2(&result, &row.parameters))
        .fold(f64::MIN, f64::max);
    assert!(beyond > at + 1.0, "the piece reaches only {beyond}");
    // The m = 1 pair of the C8v cap (18.095), split by the C2v mesh into B1 and B2.
    let m1: Vec<(&str, f64)> = r
        .critical
        .iter()
        .zip(&r.wave_numbers)
        .filter(|(c, &m)| m == 1 && c.kind == CriticalKind::SimpleBifurcation)
        .map(|(c, _)| (c.irrep.as_str(), w2(&result, &c.parameters)))
        .collect();
    assert_eq!(m1.len(), 2, "{m1:?}");
    let mut irreps: Vec<&str> = m1.iter().map(|x| x.0).collect();
    irreps.sort_unstable();
    assert_eq!(irreps, ["B1", "B2"]);
    for (_, v) in &m1 {
        assert!(
            ((v - e1) / e1).abs() < 0.01,
            "{m1:?} against the C8v double at {e1}"
        );
    }
}

/// The balloon's pressure maximum and minimum are folds of the path alone: beside neither
/// is there a second piece (every fixed-amplitude solve meets the path's own piece).
#[test]
fn a_fold_of_the_path_alone_has_no_second_piece() {
    let text = bundled("balloon.toml")
        .replace("type = \"path\"", "type = \"diagram\"\ndepth = 1")
        .replace("frequency = 8", "frequency = 4");
    let (partners, result) = diagram(&text);
    assert_eq!(result.report.turning_points.len(), 2);
    assert_eq!(partners.len(), 2, "{partners:?}");
    for p in &partners {
        assert!(p.piece.is_none(), "{p:?}");
        assert!(p.tried > 0);
        assert!(p.note.as_deref().unwrap().contains("no second piece"));
    }
}

/// The files: `diagram.json` with the graph and the search beside each fold, the piece's
/// directory with the files of a path, `partners.svg`; the summary names the gap.
#[test]
fn a_diagram_run_writes_the_second_piece_and_its_graph() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("cap.toml");
    std::fs::write(&scene, c2v_cap(4)).unwrap();
    let out = dir.path().join("out");
    let o = memstab(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    assert!(
        stdout.contains("second pieces: 1 of the path's 1 folds"),
        "{stdout}"
    );
    assert!(stdout.contains("partner_01/"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagram.json")).unwrap()).unwrap();
    assert!(json["nodes"].is_array() && json["branches"].is_array());
    let p = &json["partners"][0];
    assert_eq!(p["found"], true);
    assert_eq!(p["directory"], "partner_01");
    assert!(p["gap"].as_f64().unwrap() > 0.0);
    assert_eq!(p["points"], 5);
    // The piece's points carry their validity, as critical.json's do.
    for c in p["critical"].as_array().unwrap() {
        assert!(c["valid"].is_boolean(), "{c}");
    }
    for f in ["path.csv", "path.json", "critical.json", "manifest.json"] {
        assert!(out.join("partner_01").join(f).is_file(), "{f}");
    }
    crate::common::figures::check_svg(&out.join("partners.svg"));
    // The run's manifest lists the piece's files: the run verifies.
    let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
    assert!(manifest.contains("partner_01/path.csv"), "{manifest}");
}

/// `compare` seeks the second piece beside a fold that is the image of a double (a fold
/// whose mode has m ≥ 1) and matches the points on it. On Paper 4's cap, C2v and C1v both
/// break the m = 2 double into a fold of the connected path with the other, unconnected
/// piece beside it: the fold names the piece's distance (`piece_gap`), the distance shrinks
/// under `--refine` (6 and 12 divisions) and its observed order is printed; the C8v cap's
/// m = 1 double is found split on that second piece on both meshes.
#[test]
fn compare_lists_both_pieces_of_the_broken_m2_double_on_c2v_and_c1v_with_the_gaps_order() {
    let path = format!(
        "{}/scenes/thesis/paper4_spinning_cap.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = memstab(&[
        "compare",
        &path,
        "--meshes",
        "C8v,C2v,C1v",
        "--divisions",
        "6",
        "--refine",
        "--quiet",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rung = |m: u64| {
        c["rungs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["m"] == m)
            .unwrap_or_else(|| panic!("no rung m = {m}"))
            .clone()
    };
    let (m2, m1) = (rung(2), rung(1));
    for (mesh, label) in [(1, "C2v"), (2, "C1v")] {
        let image = &m2["images"][mesh];
        assert_eq!(image["mesh"], label);
        let mut gaps = Vec::new();
        for level in image["levels"].as_array().unwrap() {
            let verdict = level["verdict"].as_str().unwrap();
            assert!(verdict.starts_with("imperfect"), "{label}: {verdict}");
            assert!(
                verdict.contains("its partner lies on a second piece beside it, at RMS distance")
                    && !verdict.contains("not found"),
                "{label}: {verdict}"
            );
            gaps.push(level["piece_gap"].as_f64().expect("the piece's distance"));
        }
        let [coarse, fine] = gaps[..] else {
            panic!("{label}: two levels")
        };
        assert!(fine > 0.0 && fine < coarse, "{label}: {coarse} → {fine}");
        let order = image["order"].as_f64().expect("the distance's order");
        assert!(
            ((coarse / fine).log2() - order).abs() < 1e-12 && order > 0.5,
            "{label}: order {order}"
        );
        // The other piece carries the C8v cap's m = 1 double, split by the mesh.
        for level in m1["images"][mesh]["levels"].as_array().unwrap() {
            assert_eq!(
                level["points"].as_array().unwrap().len(),
                2,
                "{label}: {level}"
            );
            let verdict = level["verdict"].as_str().unwrap();
            assert!(
                verdict.starts_with("split") && verdict.contains("on the second piece"),
                "{label}: {verdict}"
            );
        }
        for level in c["meshes"][mesh]["levels"].as_array().unwrap() {
            let pieces = level["pieces"].as_array().unwrap();
            assert!(pieces.iter().any(|p| p["m"] == 2), "{label}: {pieces:?}");
        }
    }
    // A rung that is not an imperfect fold has no piece distance.
    assert!(m1["images"][0]["levels"][0]["piece_gap"].is_null());
}

/// Paper 4's cap clamped at its cut (`scenes/thesis/paper4_spinning_cap_clamped.toml`), where
/// the first instability is the m = 1 double: on C2v, cos θ and sin θ lie in B1 and B2, so
/// the double splits into two simple bifurcation points with single zero eigenvalues — the
/// thesis's "two slightly split bifurcation points" — on the connected path, each of isotropy
/// C1v, and their gap shrinks faster than the mesh size (order about 3 from 12 to 24
/// divisions), while the C8v mesh keeps the double exact.
#[test]
fn the_clamped_caps_m1_double_splits_into_two_simple_points_on_c2v_with_a_vanishing_gap() {
    let path = format!(
        "{}/scenes/thesis/paper4_spinning_cap_clamped.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = memstab(&[
        "compare", &path, "--meshes", "C8v,C2v", "--refine", "--quiet", "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rung = c["rungs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["m"] == 1)
        .expect("the m = 1 rung")
        .clone();
    for level in rung["images"][0]["levels"].as_array().unwrap() {
        assert_eq!(level["multiplicity"], 2, "{level}");
        assert_eq!(level["gap"], 0.0, "C8v keeps the double: {level}");
    }
    let c2v = &rung["images"][1];
    let levels = c2v["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 2);
    let mut gaps = Vec::new();
    for level in levels {
        assert_eq!(level["verdict"], "split", "{level}");
        let mut irreps: Vec<&str> = level["irreps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i.as_str().unwrap())
            .collect();
        irreps.sort_unstable();
        assert_eq!(irreps, ["B1", "B2"], "{level}");
        let gap = level["gap"].as_f64().unwrap();
        let value = level["values"][0].as_f64().unwrap();
        assert!(gap > 0.0 && gap < 5e-3 * value, "a slight split: {level}");
        gaps.push(gap);
    }
    assert!(gaps[1] < gaps[0] / 4.0, "the gap shrinks: {gaps:?}");
    let order = c2v["order"].as_f64().unwrap();
    assert!((2.5..3.5).contains(&order), "order {order}");
}

/// A diagram's own keys are checked like every key: one line naming it.
#[test]
fn a_diagrams_bad_keys_are_refused_naming_them() {
    let base = bundled("balloon.toml").replace("type = \"path\"", "type = \"diagram\"");
    for (key, value, words) in [
        ("depth", "0", "analysis.depth"),
        ("depth", "4", "analysis.depth"),
        ("partner-steps", "0", "analysis.partner-steps"),
        ("branch-steps", "0", "analysis.branch-steps"),
        ("branch-max-step", "-1.0", "analysis.branch-max-step"),
    ] {
        let text = base.replace(
            "type = \"diagram\"",
            &format!("type = \"diagram\"\n{key} = {value}"),
        );
        let e = Scene::from_toml_str(&text, "bad").unwrap_err().to_string();
        assert!(e.contains(words), "{key} = {value}: {e}");
    }
}

/// Paper 1's disc from below at k = 0.1, where the symmetric mesh meets its E1 double before
/// the fold. On the irregular mesh (no symmetry) the path avoids the bifurcation point: it
/// turns at a fold just below the symmetric double, stable up to it. Beside the fold lies the
/// independent piece, unstable in the double's two modes, which runs on to the symmetric
/// disc's fold (`scenes/thesis/paper1_disc_irregular_diagram.toml`).
#[test]
fn the_irregular_disc_avoids_the_double_and_has_an_independent_piece_beside_it() {
    // The symmetric disc: its E1 double and its fold.
    let symmetric = bundled("disc_fluid_below.toml")
        .replace("k = 0.0", "k = 0.1")
        .replace("max = 4.0", "max = 40.0")
        .replace("steps = 400", "steps = 36");
    let mut study =
        memstab::study::build(Scene::from_toml_str(&symmetric, "symmetric").unwrap()).unwrap();
    let sym = run(&mut *study, |_, _| {}).unwrap().report;
    let value = |k: CriticalKind| {
        sym.critical
            .iter()
            .find(|c| c.kind == k)
            .map(|c| c.parameters[0])
            .unwrap_or_else(|| panic!("no {k:?} in {:?}", sym.critical))
    };
    let (double, fold) = (
        value(CriticalKind::MultipleBifurcation(2)),
        value(CriticalKind::LimitPoint),
    );
    assert!(double < fold, "{double} {fold}");

    let path = format!(
        "{}/scenes/thesis/paper1_disc_irregular_diagram.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut study = memstab::study::build(Scene::load(&path).unwrap()).unwrap();
    let result = run(&mut *study, |_, _| {}).unwrap();
    let report = &result.report;
    let turn = &report.critical[0];
    assert_eq!(turn.kind, CriticalKind::LimitPoint);
    let at = turn.parameters[0];
    // Just below the symmetric double, stable up to it.
    assert!(at < double && at > 0.99 * double, "{at} against {double}");
    assert!(report.rows[..=turn.after_step]
        .iter()
        .all(|r| r.index == Some(0)));
    let partners = result.outcome::<Vec<Partner>>().unwrap();
    let piece = partners[0].piece.as_ref().expect("the independent piece");
    let r = &piece.run.report;
    assert_eq!(r.rows[0].parameters[0], at);
    assert_eq!(r.rows[0].index, Some(2), "{:?}", r.rows[0]);
    let own = r
        .critical
        .iter()
        .find(|c| c.kind == CriticalKind::LimitPoint)
        .map(|c| c.parameters[0])
        .expect("the piece's fold");
    assert!(((own - fold) / fold).abs() < 0.02, "{own} against {fold}");
}

/// Paper 3's linear-penalty squeeze as a diagram, to a = 0.105
/// (`scenes/thesis/paper3_gas_fluid_squeeze_linear_diagram.toml`): past the smooth B1 point at
/// a = 0.10981 the path's B1 (and A2) eigenvalue jumps across zero where four nodes enter or
/// leave contact; that is reported as a point at the jump, flagged, and nothing is switched to
/// there. The B1 branch of the smooth point returns to the path's states and ends on the jump
/// point: one connection between two B1 points of the path, the thesis's penalty-induced
/// closed circuit — not a branch running on along the path. The A2 branch does the same.
#[test]
fn the_linear_penalty_squeeze_closes_a_circuit_between_two_b1_points_of_its_path() {
    use memstab::results::validity::Flag;
    use memstab::results::{Node, Skip};
    let text = bundled("thesis/paper3_gas_fluid_squeeze_linear_diagram.toml");
    let scene = Scene::from_toml_str(&text, "squeeze").unwrap();
    let mut study = memstab::study::build(scene).unwrap();
    let result = run(&mut *study, |_, _| {}).unwrap();
    let report = &result.report;
    let d = |p: &[f64]| p[report.parameters.iter().position(|n| n == "d").unwrap()];
    let b1: Vec<(usize, f64)> = report
        .critical
        .iter()
        .enumerate()
        .filter(|(_, c)| c.irrep == "B1")
        .map(|(k, c)| (k, d(&c.parameters)))
        .collect();
    assert_eq!(b1.len(), 3, "{:?}", report.critical);
    // The jump: flagged contact-jump and not-localised, past the smooth pair.
    let (jump, at) = b1[2];
    assert!((-0.1080..-0.1070).contains(&at), "{at}");
    let flags = report.flags(jump);
    assert!(
        flags
            .iter()
            .any(|f| matches!(f, Flag::ContactJump { nodes, .. } if *nodes > 0)),
        "{flags:?}"
    );
    assert!(
        flags.iter().any(|f| matches!(f, Flag::NotLocalised { .. })),
        "{flags:?}"
    );
    // The smooth points are not flagged.
    for &(k, _) in &b1[..2] {
        assert!(report.flags(k).is_empty(), "{:?}", report.flags(k));
    }
    let branches = result.branches.as_ref().expect("the diagram's branches");
    let g = &branches.graph;
    let path_node = |k: usize| {
        g.graph
            .node_indices()
            .find(|&n| matches!(&g.graph[n], Node::Critical { on: None, number, .. } if *number == k + 1))
            .unwrap()
    };
    // Nothing is switched to at the jump.
    assert!(matches!(
        &g.graph[path_node(jump)],
        Node::Critical {
            skipped: Some(Skip::Jump(_)),
            ..
        }
    ));
    // One connection, from the branch of the second smooth B1 point to the jump.
    let to_jump: Vec<_> = g
        .connections
        .iter()
        .filter(|c| c.to == path_node(jump))
        .collect();
    assert_eq!(to_jump.len(), 1, "{:?}", g.connections);
    let branch = &g.branches[to_jump[0].branch];
    assert_eq!(branch.from, path_node(b1[1].0));
    assert_eq!(branch.irrep, "B1");
    assert!(branch.isotropy_exact());
    // It leaves and returns: off the path's states in between, on them at both ends.
    let asym: Vec<f64> = branch.points.iter().map(|p| p.asymmetry).collect();
    let peak = asym.iter().copied().fold(0.0, f64::max);
    assert!(peak > 1e-3, "{asym:?}");
    assert!(
        asym[0] < 1e-12 * peak.max(1.0) && *asym.last().unwrap() < 1e-9,
        "{asym:?}"
    );
    let last = branch.points.last().unwrap();
    assert!((d(&last.parameters) - at).abs() < 1e-12);
    // The first B1 point's branch is no part of the circuit: it does not connect.
    assert!(g
        .connections
        .iter()
        .all(|c| g.branches[c.branch].from != path_node(b1[0].0)));
    // The same in A2, whose branch (isotropy C2) holds the relabelling about z: from the
    // smooth A2 point to the A2 jump.
    let a2: Vec<usize> = report
        .critical
        .iter()
        .enumerate()
        .filter(|(_, c)| c.irrep == "A2")
        .map(|(k, _)| k)
        .collect();
    assert_eq!(a2.len(), 2, "{:?}", report.critical);
    assert!(report.critical[a2[0]].residual_eigenvalue < 1e-10);
    assert!((d(&report.critical[a2[1]].parameters) - at).abs() < 1e-9);
    let to_a2_jump: Vec<_> = g
        .connections
        .iter()
        .filter(|c| c.to == path_node(a2[1]))
        .collect();
    assert_eq!(to_a2_jump.len(), 1, "{:?}", g.connections);
    let branch = &g.branches[to_a2_jump[0].branch];
    assert_eq!(branch.from, path_node(a2[0]));
    assert!(branch.isotropy_exact());
    assert_eq!(g.connections.len(), 2, "{:?}", g.connections);
}

/// The bundled upward-loaded disc on a coarse mesh (6 divisions) as `kind` with `extra` keys
/// under `[analysis]`, written into `dir`; its path.
fn coarse_disc(dir: &std::path::Path, kind: &str, extra: &str, name: &str) -> String {
    let text = bundled("disc_upward.toml");
    let cut = text.find("\n[analysis.branches]").expect("branches");
    let text = text[..cut]
        .replace("divisions = 16 ", "divisions = 6 ")
        .replace("type = \"path\"", &format!("type = \"{kind}\"\n{extra}"));
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

fn json_of(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap_or_else(|_| panic!("{path:?}")))
        .unwrap()
}

/// Every branch of a graph as (isotropy, half, points, control at its end to 1e-9).
fn branch_list(graph: &serde_json::Value) -> Vec<(String, String, u64, String)> {
    graph["branches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            (
                b["isotropy"].as_str().unwrap().to_string(),
                b["half"].as_str().unwrap().to_string(),
                b["points"].as_u64().unwrap(),
                format!("{:.9}", b["end"]["h"].as_f64().expect("the end's h")),
            )
        })
        .collect()
}

/// `memstab diagram RUN_DIR` computes from a finished path what a `type = "diagram"` run of
/// the same scene adds to its path: the same branches at depth 2 (each once), ending at the
/// same control, and the same graph; its files join the run's manifest, so the run still
/// verifies when `memstab branch` reads it afterwards.
#[test]
fn memstab_diagram_of_a_finished_path_is_the_diagram_run_of_its_scene() {
    let tmp = tempfile::tempdir().unwrap();
    let path_scene = coarse_disc(tmp.path(), "path", "", "path.toml");
    let diagram_scene = coarse_disc(
        tmp.path(),
        "diagram",
        "depth = 2\nbranch-steps = 8",
        "diagram.toml",
    );
    let (run_dir, whole) = (tmp.path().join("run"), tmp.path().join("whole"));
    for (scene, dir) in [(&path_scene, &run_dir), (&diagram_scene, &whole)] {
        let o = memstab(&["run", scene, "--out", dir.to_str().unwrap(), "--quiet"]);
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    assert!(!run_dir.join("branches.json").exists());
    let o = memstab(&[
        "diagram",
        run_dir.to_str().unwrap(),
        "--depth",
        "2",
        "--steps",
        "8",
    ]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    assert!(stdout.contains("branches (depth 2)"), "{stdout}");
    assert!(stdout.contains("second pieces:"), "{stdout}");
    let (a, b) = (
        json_of(&run_dir.join("diagram.json")),
        json_of(&whole.join("diagram.json")),
    );
    let list = branch_list(&a);
    assert!(list.len() >= 2, "{list:?}");
    assert_eq!(list, branch_list(&b));
    assert_eq!(
        a["nodes"].as_array().unwrap().len(),
        b["nodes"].as_array().unwrap().len()
    );
    assert_eq!(a["partners"], b["partners"]);
    let manifest = std::fs::read_to_string(run_dir.join("manifest.json")).unwrap();
    for f in [
        "diagram.json",
        "branches.json",
        "branch_01/path.csv",
        "partners.svg",
    ] {
        assert!(manifest.contains(f), "{f} not in the manifest");
    }
    let o = memstab(&[
        "branch",
        run_dir.to_str().unwrap(),
        "--critical",
        "1",
        "--steps",
        "2",
        "--out",
        tmp.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

/// Bad input to `memstab diagram` is one line and exit 2, nothing written: no run, a bad
/// flag, a run whose states are gone, a run of an analysis that is no path.
#[test]
fn memstab_diagram_refuses_bad_input_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = coarse_disc(tmp.path(), "path", "", "path.toml");
    let run_dir = tmp.path().join("run");
    let o = memstab(&["run", &scene, "--out", run_dir.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let dir = run_dir.to_str().unwrap();
    for (args, needle) in [
        (vec!["diagram", empty.to_str().unwrap()], "path.json"),
        (vec!["diagram", dir, "--depth", "9"], "--depth 9"),
        (vec!["diagram", dir, "--depth", "0"], "--depth 0"),
        (vec!["diagram", dir, "--steps", "0"], "--steps 0"),
        (
            vec!["diagram", dir, "--partner-steps", "0"],
            "--partner-steps 0",
        ),
        (vec!["diagram", dir, "--max-step", "0"], "--max-step 0"),
        (vec!["diagram", dir, "--out", "/nonexistent/x"], "--out"),
    ] {
        let out = memstab(&args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "'{needle}' not in {err}");
    }
    assert!(!run_dir.join("diagram.json").exists(), "nothing written");
    // A run whose states are gone (the manifest names them: refused naming the file).
    std::fs::remove_file(run_dir.join("path.states")).unwrap();
    let out = memstab(&["diagram", dir]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("path.states"), "{err}");
    assert!(!run_dir.join("diagram.json").exists(), "nothing written");
    // A held state's run is no path.
    let held = bundled("ponding.toml");
    let held_scene = tmp.path().join("ponding.toml");
    std::fs::write(&held_scene, held).unwrap();
    let held_dir = tmp.path().join("held");
    let o = memstab(&[
        "run",
        held_scene.to_str().unwrap(),
        "--out",
        held_dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = memstab(&["diagram", held_dir.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("linear-buckling analysis"), "{err}");
    assert!(!held_dir.join("diagram.json").exists());
}

/// A signal during `memstab diagram` ends it as a run's does: exit 130, what was found written
/// and listed in the manifest, which says `interrupted` and still verifies (the run reads
/// back afterwards).
#[test]
fn an_interrupted_memstab_diagram_exits_130_with_a_manifest_that_verifies() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = coarse_disc(tmp.path(), "path", "", "path.toml");
    let run_dir = tmp.path().join("run");
    let o = memstab(&["run", &scene, "--out", run_dir.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(["diagram", run_dir.to_str().unwrap(), "--steps", "8"])
        .env("MEMSTAB_INTERRUPT_AFTER_STEPS", "3")
        .output()
        .unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    let manifest = json_of(&run_dir.join("manifest.json"));
    assert_eq!(manifest["stop"], "interrupted");
    assert!(run_dir.join("branches.json").is_file());
    let o = memstab(&[
        "branch",
        run_dir.to_str().unwrap(),
        "--critical",
        "1",
        "--steps",
        "2",
        "--out",
        tmp.path().to_str().unwrap(),
    ]);
    assert!(
        o.status.success(),
        "the run still verifies: {}",
        text(&o.stderr)
    );
}

/// The upward disc's E1 double point (C7v, m = 1): on the C1v− branch the other half of the
/// kernel (the pattern's orientation, neutral in the axisymmetric continuum) has an
/// eigenvalue at round-off at the branch's first point, so the index counts an A2 crossing
/// there (h = 4.14106, 2·10⁻⁴ below the double). Its eigenvalue has not left zero since the
/// double: its rate, over the distance back to the double, moves it by less than what counts
/// as zero (and over a whole step too), so no branch is switched to (before, a C1 branch was
/// tried and could not take its first step); the E1 point itself is transversal and has its
/// two branches.
#[test]
fn a_zero_eigenvalue_that_does_not_cross_is_no_bifurcation() {
    use memstab::results::{Node, Skip};
    let text = bundled("disc_upward.toml")
        .replace("depth = 1 ", "depth = 2 ")
        .replace("steps = 30 ", "steps = 4 ");
    let scene = Scene::from_toml_str(&text, "disc").unwrap();
    let mut study = memstab::study::build(scene).unwrap();
    let result = run(&mut *study, |_, _| {}).unwrap();
    let g = &result.branches.as_ref().expect("branches").graph;
    assert_eq!(g.branches.len(), 2, "only the double's two halves leave");
    assert!(g.branches.iter().all(|b| b.isotropy == "C1v"));
    let mut touched = 0;
    for n in g.graph.node_indices() {
        let Node::Critical {
            on, point, skipped, ..
        } = &g.graph[n]
        else {
            continue;
        };
        match on {
            None => {
                assert_eq!(point.irrep, "E1");
                assert_eq!(g.leaving(n).len(), 2);
                let b = g.branches[0].reduced.path_slope.abs();
                assert!(b > 1e-4, "the double crosses transversally: {b}");
            }
            Some(_) => {
                let Some(Skip::AtOrigin { rate, distance }) = skipped else {
                    panic!("{} on a branch: {skipped:?}", point.irrep);
                };
                assert!(rate.abs() * distance < 1e-10, "{rate} over {distance}");
                assert_eq!(point.irrep, "A2");
                assert!(g.leaving(n).is_empty());
                // At the branch's first point, orders of magnitude slower than the double.
                assert!(point.after_step <= 1, "{}", point.after_step);
                assert!(rate.abs() < 1e-9, "{rate}");
                touched += 1;
            }
        }
    }
    assert_eq!(touched, 1, "the A2 point of the C1v− branch");
}

/// Runs the diagram of `scene` (a path with `[analysis.branches]`) and checks that no two
/// of its branches are one branch up to the group, over two or more points (docs/theory.md
/// §14.8; `control` names the path's control).
fn followed_once(scene: Scene, control: &str) -> (MeshStudy, RunResult) {
    let mut study = MeshStudy::build(scene).unwrap();
    let result = run(&mut study, |_, _| {}).unwrap();
    let g = &result.branches.as_ref().expect("branches").graph;
    let c = result.report.parameters.iter().position(|n| n == control);
    let common = common_stretches(&study, &g.branches, c.unwrap());
    assert!(common.is_empty(), "branches followed twice: {common:?}");
    (study, result)
}

/// Paper 4's cap (C8v) at depth 3: the C1 branch between the A2 points of the E3 branches
/// (ω² ≈ 15.2587 on C1v, 15.2814 on C1v′) and the one between the E1 branches' A2 points
/// (ω² ≈ 18.0548) are each followed once. Followed from the point switched first, the branch
/// reaches the other as a fold or crossing within one step of it and ends there as a
/// connection; at the other point that one half of its class is known as this branch and not
/// followed again (docs/theory.md §14.8). Over the whole diagram no branch runs along a group
/// image of another.
#[test]
fn the_caps_depth_three_diagram_follows_every_branch_once_its_c1_branches_between_two_points() {
    let text = bundled("thesis/paper4_spinning_cap.toml") + "\n[analysis.branches]\ndepth = 3\n";
    let scene = Scene::from_toml_str(&text, "cap").unwrap();
    let (_, result) = followed_once(scene, "w2");
    let b = result.branches.as_ref().expect("branches");
    let g = &b.graph;
    let w2 = |p: &[f64]| {
        p[result
            .report
            .parameters
            .iter()
            .position(|n| n == "w2")
            .unwrap()]
    };
    let point = |n: petgraph::graph::NodeIndex| match &g.graph[n] {
        memstab::results::Node::Critical { point, .. } => w2(&point.parameters),
        _ => panic!("not a critical point"),
    };
    let c1: Vec<usize> = (0..g.branches.len())
        .filter(|&i| g.branches[i].isotropy == "C1")
        .collect();
    assert_eq!(c1.len(), 2, "one C1 branch per pair of points: {c1:?}");
    let budget = 41;
    for &i in &c1 {
        let br = &g.branches[i];
        let from = point(br.from);
        let conn = g
            .connections
            .iter()
            .find(|c| c.branch == i)
            .unwrap_or_else(|| panic!("C1 branch from {from} ends {}", br.stop));
        let to = point(conn.to);
        assert!(
            matches!(br.stop, memstab::results::StopReason::Connected { .. }),
            "{}",
            br.stop
        );
        assert!(
            br.points.len() < budget,
            "{from}: {} points",
            br.points.len()
        );
        // At the other end, the one C1 half is this branch, known and not followed again.
        match &g.graph[conn.to] {
            memstab::results::Node::Critical {
                skipped: Some(memstab::results::Skip::Known(known)),
                ..
            } => assert!(known.contains(&i), "{from} → {to}: known {known:?}"),
            other => panic!("{from} → {to}: {other:?}"),
        }
        let pair = if from < 17.0 {
            [15.2587, 15.2814]
        } else {
            [18.05475, 18.05477]
        };
        for x in [from, to] {
            assert!(
                pair.iter().any(|p| (x - p).abs() < 2e-4),
                "{from} → {to} against {pair:?}"
            );
        }
    }
    // The E3 branches' A2 eigenvalue (the other half of the E3 kernel) leaves zero to high
    // order in the amplitude: the index counts it in the branches' first steps, at a place
    // round-off decides, and it has not left zero there — on both E3 branches, whatever the
    // round-off, and nothing is switched to.
    let at_origin: Vec<f64> = g
        .graph
        .node_indices()
        .filter_map(|n| match &g.graph[n] {
            memstab::results::Node::Critical {
                point,
                skipped: Some(memstab::results::Skip::AtOrigin { .. }),
                ..
            } => {
                assert_eq!(point.irrep, "A2");
                assert!(point.after_step <= 2, "{}", point.after_step);
                assert!(g.leaving(n).is_empty());
                Some(w2(&point.parameters))
            }
            _ => None,
        })
        .collect();
    assert_eq!(at_origin.len(), 2, "{at_origin:?}");
    assert!(
        at_origin.iter().all(|w| (w - 18.826).abs() < 0.02),
        "{at_origin:?}"
    );
}

/// The upward disc's diagram to depth 3 (the bundled 1 792-triangle C7v disc): its two C1v
/// branches, one per half of the E1 double, which C7v does not map onto each other, are
/// followed once each and run along no image of the other. The check itself finds a branch
/// followed twice: a group image of one branch, sampled at other points, runs along it.
#[test]
fn the_upward_discs_depth_three_diagram_follows_every_branch_once() {
    let text = bundled("disc_upward.toml").replace("depth = 1 ", "depth = 3 ");
    let scene = Scene::from_toml_str(&text, "disc").unwrap();
    let (study, result) = followed_once(scene, "h");
    let g = &result.branches.as_ref().expect("branches").graph;
    let control = result.report.parameters.iter().position(|n| n == "h");
    let control = control.unwrap();
    let classes: Vec<&str> = g.branches.iter().map(|b| b.isotropy.as_str()).collect();
    assert_eq!(classes, ["C1v", "C1v"], "one branch per half of E1");

    // A copy of the first branch moved by a rotation of the group and sampled half-way
    // between its points: the check must say it runs along the first.
    let first = &g.branches[0];
    let mid = &first.points[first.points.len() / 2].u;
    let rotation = (1..study.action.group().order())
        .find(|&e| {
            let moved = act(&study, e, mid);
            let d: f64 = moved.iter().zip(mid).map(|(a, b)| (a - b).abs()).sum();
            d > 1e-3 * mid.iter().map(|v| v.abs()).sum::<f64>()
        })
        .expect("an element that moves the branch");
    let mut copy = first.clone();
    copy.points = first
        .points
        .windows(2)
        .map(|w| {
            let half = |a: &[f64], b: &[f64]| -> Vec<f64> {
                a.iter().zip(b).map(|(a, b)| 0.5 * (a + b)).collect()
            };
            let mut p = w[0].clone();
            p.u = act(&study, rotation, &half(&w[0].u, &w[1].u));
            p.parameters = half(&w[0].parameters, &w[1].parameters);
            p
        })
        .collect();
    let mut with_copy = g.branches.clone();
    with_copy.push(copy);
    let common = common_stretches(&study, &with_copy, control);
    let n = with_copy.len() - 1;
    assert!(
        common
            .iter()
            .any(|c| c.branch == n && c.along == 0 && c.points == (1..first.points.len() - 2)),
        "the copy runs along the first branch: {common:?}"
    );
}
