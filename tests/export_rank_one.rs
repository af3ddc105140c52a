//! `memstab export-matrix` on a tangent with rank-one terms (a `gas-amount` effect): the sparse
//! part goes to K.mtx, the terms c_k a_k a_kᵀ to K.rank1.mtx. Read back here (by a small
//! independent Matrix Market reader), S x + Σ c_k a_k (a_k · x) must be the model's K x, and
//! `scripts/peer_eigsh.py` (shift-invert by sparse LU + Sherman–Morrison–Woodbury) must find
//! eigenvalues of that K — when a python with scipy is available (CI has none: then the script
//! part is skipped with a note).

use memstab::model::{Model, Request};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A k = 0.1 balloon on a frequency-4 icosphere holding a fixed amount of gas at a stretch of
/// about 2, between its pressure maximum and minimum: unstable under pressure control, stable
/// with the amount fixed — the rank-one term is what makes the trivial block positive.
const SCENE: &str = r#"
[scene]
name = "balloon-gas-amount"
description = "k = 0.1 balloon holding a fixed amount of gas, between its pressure maximum and minimum"

[mesh]
generator = "icosphere"
radius = 1.0
frequency = 4

[material]
model = "mooney-rivlin"
mu = 100.0
k = 0.1
thickness = 0.01

[[effect]]
type = "gas-amount"
amount = "C"
ambient-pressure = 1.0

[parameters.C]
start = 75.5               # (1 + p) V of the sphere at stretch 2 (closed form p = 1.2528)

[analysis]
type = "equilibrium"

[start]
stretch = 2.0
"#;

/// A Matrix Market file: (header line, comment lines without '%', data lines).
fn read_mm(path: &Path) -> (String, Vec<String>, Vec<String>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let (mut comments, mut data) = (Vec::new(), Vec::new());
    for l in lines {
        if let Some(c) = l.strip_prefix('%') {
            assert!(data.is_empty(), "comment after the size line: {l}");
            comments.push(c.trim().to_string());
        } else if !l.trim().is_empty() {
            data.push(l.to_string());
        }
    }
    (header, comments, data)
}

/// The sparse symmetric part: n and the entries (i, j, v), 0-based, lower triangle.
pub(crate) fn read_sparse(path: &Path) -> (usize, Vec<(usize, usize, f64)>, Vec<String>) {
    let (header, comments, data) = read_mm(path);
    assert_eq!(header, "%%MatrixMarket matrix coordinate real symmetric");
    let size: Vec<usize> = data[0]
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(size.len(), 3);
    assert_eq!(size[0], size[1]);
    let entries: Vec<(usize, usize, f64)> = data[1..]
        .iter()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(f.len(), 3, "{l}");
            let (i, j): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
            assert!(i >= j && j >= 1 && i <= size[0], "{l}");
            (i - 1, j - 1, f[2].parse().unwrap())
        })
        .collect();
    assert_eq!(entries.len(), size[2]);
    (size[0], entries, comments)
}

/// The rank-one terms: (c_k, a_k).
fn read_rank_one(path: &Path) -> Vec<(f64, Vec<f64>)> {
    let (header, comments, data) = read_mm(path);
    assert_eq!(header, "%%MatrixMarket matrix array real general");
    let coefficients: Vec<f64> = comments
        .iter()
        .find_map(|c| c.strip_prefix("coefficients:"))
        .expect("a '% coefficients:' line")
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    let size: Vec<usize> = data[0]
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    let (n, r) = (size[0], size[1]);
    assert_eq!(r, coefficients.len());
    let values: Vec<f64> = data[1..]
        .iter()
        .map(|l| l.trim().parse().unwrap())
        .collect();
    assert_eq!(values.len(), n * r);
    coefficients
        .into_iter()
        .enumerate()
        .map(|(k, c)| (c, values[k * n..(k + 1) * n].to_vec()))
        .collect()
}

/// y = (S + Σ c a aᵀ) x with S given by its lower triangle.
fn apply(
    n: usize,
    lower: &[(usize, usize, f64)],
    terms: &[(f64, Vec<f64>)],
    x: &[f64],
) -> Vec<f64> {
    let mut y = vec![0.0; n];
    for &(i, j, v) in lower {
        y[i] += v * x[j];
        if i != j {
            y[j] += v * x[i];
        }
    }
    for (c, a) in terms {
        let d: f64 = a.iter().zip(x).map(|(p, q)| p * q).sum();
        for (yi, ai) in y.iter_mut().zip(a) {
            *yi += c * d * ai;
        }
    }
    y
}

/// Deterministic pseudo-random vector in [−1, 1] (xorshift).
fn random_vector(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// A python that imports scipy and numpy: `.venv-bench/bin/python` first, then `python3`.
fn python_with_scipy() -> Option<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        root.join(".venv-bench/bin/python")
            .to_string_lossy()
            .into_owned(),
        "python3".to_string(),
    ]
    .into_iter()
    .find(|py| {
        Command::new(py)
            .args(["-c", "import scipy, numpy"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

#[test]
fn export_with_rank_one_terms_round_trips_and_scipy_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("balloon_amount.toml");
    std::fs::write(&scene_path, SCENE).unwrap();
    let mtx: PathBuf = dir.path().join("K.mtx");
    let o = Command::new(env!("CARGO_BIN_EXE_memstab"))
        .arg("export-matrix")
        .arg(&scene_path)
        .arg("--out")
        .arg(&mtx)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "export-matrix failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    let rank1 = dir.path().join("K.rank1.mtx");
    assert_eq!(rank1, memstab::output::rank_one_path(&mtx));
    assert!(stdout.contains("K.rank1.mtx"), "{stdout}");
    let (n, lower, comments) = read_sparse(&mtx);
    assert!(
        comments.iter().any(|c| c == "rank-one file: K.rank1.mtx"),
        "{comments:?}"
    );
    let terms = read_rank_one(&rank1);
    assert_eq!(terms.len(), 1, "one gas-amount effect, one term");
    assert!(terms[0].0 > 0.0 && terms[0].1.len() == n);

    // The same state by the library: the model's K (sparse part and its rank-one terms).
    let scene = memstab::scene::Scene::load(&scene_path).unwrap();
    let mut study = memstab::study::mesh::MeshStudy::build(scene).unwrap();
    let params = study.start.clone();
    let u = memstab::bench::solve_start(&mut study, &params).unwrap();
    let model = &study.model;
    assert_eq!(model.unknowns(), n);
    let mut eval = model.new_evaluation();
    model
        .evaluate(&u, &params, Request::ALL, &mut eval)
        .unwrap();
    assert_eq!(eval.rank_one.len(), 1);
    let scale = eval.tangent.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut eval_fd = model.new_evaluation();
    for seed in 1..=4 {
        let x = random_vector(n, seed);
        let from_files = apply(n, &lower, &terms, &x);
        let mut kx = vec![0.0; n];
        model.pattern().matvec(&eval.tangent, &x, &mut kx);
        for (c, a) in &eval.rank_one {
            let d: f64 = a.iter().zip(&x).map(|(p, q)| p * q).sum();
            for (k, ai) in kx.iter_mut().zip(a) {
                *k += c * d * ai;
            }
        }
        let diff: Vec<f64> = from_files.iter().zip(&kx).map(|(a, b)| a - b).collect();
        assert!(
            norm(&diff) <= 1e-12 * scale * norm(&x),
            "seed {seed}: |(S + Σ c a aᵀ) x − K x| = {:e}, |K x| = {:e}",
            norm(&diff),
            norm(&kx)
        );
        // And K x is the derivative of the residual (central differences): the rank-one term
        // is part of the physics, not a bookkeeping artefact.
        let h = 1e-6;
        let shifted = |sign: f64, out: &mut Vec<f64>, eval: &mut memstab::model::Evaluation| {
            let v: Vec<f64> = u.iter().zip(&x).map(|(a, b)| a + sign * h * b).collect();
            model
                .evaluate(&v, &params, Request::RESIDUAL, eval)
                .unwrap();
            out.clone_from(&eval.residual);
        };
        let (mut plus, mut minus) = (Vec::new(), Vec::new());
        shifted(1.0, &mut plus, &mut eval_fd);
        shifted(-1.0, &mut minus, &mut eval_fd);
        let fd: Vec<f64> = plus
            .iter()
            .zip(&minus)
            .map(|(p, m)| (p - m) / (2.0 * h))
            .collect();
        let err: Vec<f64> = fd.iter().zip(&from_files).map(|(a, b)| a - b).collect();
        assert!(
            norm(&err) <= 1e-5 * norm(&from_files),
            "seed {seed}: finite differences of F differ from the exported K x by {:e} (|K x| = {:e})",
            norm(&err),
            norm(&from_files)
        );
    }

    // Our eigenvalues: dense, of the full K, and of S alone (which has a negative one: the
    // state is past the pressure maximum, stable only with the amount of gas fixed).
    let mut dense = model.pattern().to_dense(&eval.tangent);
    for (c, a) in &eval.rank_one {
        for j in 0..n {
            for i in 0..n {
                dense[(i, j)] += c * a[i] * a[j];
            }
        }
    }
    let mut ours = dense.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    ours.sort_by(f64::total_cmp);
    let sparse_only = model
        .pattern()
        .to_dense(&eval.tangent)
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .unwrap();
    let zero = 1e-8 * scale;
    assert!(ours[0] > -zero, "K with the gas amount fixed is stable");
    assert!(
        sparse_only.iter().any(|&v| v < -zero),
        "S alone is unstable: the rank-one term matters here"
    );

    let Some(python) = python_with_scipy() else {
        eprintln!(
            "note: no python3 with scipy (tried .venv-bench/bin/python and python3); \
             scripts/peer_eigsh.py not run"
        );
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/peer_eigsh.py");
    let sigma = -1e-3 * scale;
    let k = 16;
    let o = Command::new(&python)
        .arg(&script)
        .arg(&mtx)
        .arg(format!("--k={k}"))
        .arg(format!("--sigma={sigma:e}"))
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "peer_eigsh.py failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["rank_one_terms"].as_u64(), Some(1), "{v}");
    assert_eq!(v["n"].as_u64(), Some(n as u64));
    let scipy: Vec<f64> = v["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(scipy.len(), k);
    let tol = 1e-8 * scale;
    // Every value scipy returns is an eigenvalue of K (S + Σ c a aᵀ), none of S alone's
    // negative ones.
    for &s in &scipy {
        let d = ours
            .iter()
            .map(|o| (o - s).abs())
            .fold(f64::INFINITY, f64::min);
        assert!(
            d <= tol,
            "scipy's {s:e} is {d:e} from every eigenvalue of K"
        );
        assert!(
            s > -zero,
            "scipy's {s:e}: the rank-one term was not applied"
        );
    }
    // Every distinct eigenvalue of K nearer σ than scipy's farthest value is among scipy's
    // (ARPACK may return fewer copies of a degenerate eigenvalue than its multiplicity, so
    // the multiplicities are not compared).
    let reach = scipy
        .iter()
        .map(|s| (s - sigma).abs())
        .fold(0.0f64, f64::max);
    for &o in ours.iter().filter(|&&o| (o - sigma).abs() < reach - tol) {
        assert!(
            scipy.iter().any(|s| (s - o).abs() <= tol),
            "our eigenvalue {o:e} (nearer σ = {sigma:e} than scipy's farthest) is missing from scipy's {scipy:?}"
        );
    }
    eprintln!(
        "peer_eigsh.py ({python}) agrees: {k} eigenvalues nearest σ = {sigma:e}, lowest {:e}",
        scipy[0]
    );
}
