//! `memstab run` on a linear-buckling sweep (a coarse ponding disc, C7v): `path.svg` plots the
//! lowest eigenvalue of every irrep block against the control with the zero line and the
//! critical points, `path.json` holds the same spectra, and the two agree with the critical
//! points found; nothing non-finite is written.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

use crate::common::{polylines, texts};

/// The ponding scene on a 6-division disc (252 triangles) swept in 46 samples: a fraction of
/// a second.
fn coarse_ponding(dir: &Path) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/ponding.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let text = text
        .replace("divisions = 16 ", "divisions = 6 ")
        .replace("samples = 92", "samples = 46");
    assert!(text.contains("divisions = 6 ") && text.contains("samples = 46"));
    let path = dir.join("ponding6.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn a_linear_buckling_run_plots_the_spectrum_by_irrep() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = coarse_ponding(tmp.path());
    let dir = tmp.path().join("out");
    let out = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(["run", &scene, "--out", dir.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("path.svg   lowest eigenvalue / max|K_ij| per irrep against rho"),
        "{stdout}"
    );

    // The held state is written under its own name, and no file name has a space.
    assert!(dir.join("held_state.vtu").exists());
    // path.pvd lists the held state (the state of every sample), events.pvd every critical
    // state, each named with its irrep.
    let pvd = std::fs::read_to_string(dir.join("path.pvd")).unwrap();
    assert!(pvd.contains("file=\"held_state.vtu\""), "{pvd}");
    let events = std::fs::read_to_string(dir.join("events.pvd")).unwrap();
    let critical_files = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            let name = e.as_ref().unwrap().file_name().into_string().unwrap();
            name.starts_with("critical_") && name.ends_with(".vtu")
        })
        .count();
    assert!(critical_files > 0);
    assert_eq!(
        events.matches("<DataSet").count(),
        critical_files,
        "{events}"
    );
    for k in 1..=critical_files {
        assert!(
            events.contains(&format!(
                "file=\"critical_{k:02}.vtu\" name=\"critical_{k:02}: "
            )),
            "{events}"
        );
    }
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(' '), "{name}");
    }

    // No NaN or infinity in any text output (as a word: `NaN`, `inf`, `-inf`, `Infinity`).
    for name in [
        "path.csv",
        "path.json",
        "critical.json",
        "path.svg",
        "path.pvd",
    ] {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        let bad = text
            .split(|c: char| !c.is_ascii_alphanumeric())
            .find(|w| ["nan", "inf", "infinity"].contains(&w.to_lowercase().as_str()));
        assert!(bad.is_none(), "{bad:?} in {name}");
    }

    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("path.json")).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 47);
    let spectra = &json["spectra"];
    let irreps: Vec<(String, u64)> = spectra["irreps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            assert_eq!(i["eigenvalues"], true, "{i}");
            (
                i["name"].as_str().unwrap().to_string(),
                i["dim"].as_u64().unwrap(),
            )
        })
        .collect();
    let names: Vec<&str> = irreps.iter().map(|i| i.0.as_str()).collect();
    assert_eq!(names, ["A1", "A2", "E1", "E2", "E3"]);
    let srows = spectra["rows"].as_array().unwrap();
    assert_eq!(srows.len(), rows.len(), "a spectrum row per path row");
    // lowest[mu] per sample, every one computed and finite.
    let lowest: Vec<Vec<f64>> = srows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            assert_eq!(r["step"], i);
            assert_eq!(r["control"], rows[i]["parameters"][0]);
            r["lowest"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().expect("a number"))
                .collect()
        })
        .collect();

    // The first critical point of each irrep lies where that irrep's lowest eigenvalue
    // changes sign, between the samples `step` and `step + 1`, and nowhere else; an irrep
    // without a critical point keeps a positive lowest eigenvalue.
    let critical: Vec<Value> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("critical.json")).unwrap()).unwrap();
    let mut first: BTreeMap<&str, (u64, f64)> = BTreeMap::new();
    for c in &critical {
        first.entry(c["irrep"].as_str().unwrap()).or_insert((
            c["step"].as_u64().unwrap(),
            c["parameters"]["rho"].as_f64().unwrap(),
        ));
    }
    assert!(first.contains_key("A1"), "{critical:?}");
    for (mu, name) in names.iter().enumerate() {
        let changes: Vec<usize> = (0..lowest.len() - 1)
            .filter(|&i| (lowest[i][mu] > 0.0) != (lowest[i + 1][mu] > 0.0))
            .collect();
        match first.get(name) {
            Some(&(step, rho)) => {
                assert_eq!(changes, [step as usize], "{name}");
                let s = step as usize;
                assert!(lowest[s][mu] > 0.0 && lowest[s + 1][mu] < 0.0, "{name}");
                let (r0, r1) = (
                    srows[s]["control"].as_f64().unwrap(),
                    srows[s + 1]["control"].as_f64().unwrap(),
                );
                assert!(r0 < rho && rho < r1, "{name}: {rho} not in ({r0}, {r1})");
            }
            None => assert!(
                changes.is_empty() && lowest.iter().all(|l| l[mu] > 0.0),
                "{name}"
            ),
        }
    }
    // The negative counts agree with the instability index of the rows.
    for (r, s) in rows.iter().zip(srows) {
        let index: u64 = s["negative"]
            .as_array()
            .unwrap()
            .iter()
            .zip(&irreps)
            .map(|(n, i)| n.as_u64().unwrap() * i.1)
            .sum();
        assert_eq!(r["index"].as_u64(), Some(index));
    }

    // path.svg: a line of all 47 samples per irrep, each in its own colour, the zero line,
    // the legend with every irrep and its dimension, a label per critical point.
    crate::common::figures::check_svg(&dir.join("path.svg"));
    let svg = std::fs::read_to_string(dir.join("path.svg")).unwrap();
    let lines = polylines(&svg);
    let data: Vec<_> = lines.iter().filter(|l| l.1.len() == 47).collect();
    assert_eq!(data.len(), names.len(), "one line per irrep");
    let colours: BTreeSet<&str> = data.iter().map(|l| l.0.as_str()).collect();
    assert_eq!(colours.len(), names.len(), "{colours:?}");
    let zero: Vec<_> = lines
        .iter()
        .filter(|l| l.0 == "#404040" && l.1.len() == 2 && l.1[0].1 == l.1[1].1)
        .collect();
    assert_eq!(zero.len(), 1, "one zero line");
    let y0 = zero[0].1[0].1;
    // The lines in the SVG cross the zero line exactly for the irreps with a critical point
    // (SVG y grows downwards: above zero is y < y0).
    let crossing = data
        .iter()
        .filter(|l| l.1.first().unwrap().1 < y0 && l.1.last().unwrap().1 > y0)
        .count();
    assert_eq!(crossing, first.len());
    let texts = texts(&svg);
    for (name, dim) in &irreps {
        let entry = format!("{name} (×{dim})");
        assert!(texts.contains(&entry), "no {entry:?} in {texts:?}");
    }
    // Each critical point labelled with its kind, irrep and rung (m, k): the k-th point of
    // wave number m along the sweep (the Bessel zero j_{m,k} of the ponding ladder).
    let mut rungs: BTreeMap<u64, u64> = BTreeMap::new();
    for c in &critical {
        let kind = c["kind"].as_str().unwrap().split(' ').next().unwrap();
        let m = c["m"].as_u64().expect("a wave number on the disc");
        let k = rungs.entry(m).or_insert(0);
        *k += 1;
        let label = format!("{kind} {} ({m}, {k})", c["irrep"].as_str().unwrap());
        assert!(texts.contains(&label), "no {label:?} in {texts:?}");
    }
    assert!(
        texts.contains(&"symmetric A1 (0, 1)".to_string()),
        "the first rung, j_0,1: {texts:?}"
    );
    assert!(
        texts.contains(&"critical point (m, k)".to_string()),
        "{texts:?}"
    );
    // The control's axis in the load number of the ponding floor.
    assert!(
        texts.iter().any(|t| t.starts_with("ρ g a²/(μH) (")),
        "{texts:?}"
    );
    assert!(texts.contains(&"lowest eigenvalue / max|K_ij|".to_string()));
}
