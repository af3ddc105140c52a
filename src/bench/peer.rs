//! The peer solver of the symmetry payoff: scipy `eigsh` (ARPACK, shift-invert) on our K,
//! exported in Matrix Market format and solved by `scripts/peer_eigsh.py`, when a python with
//! scipy is found (`.venv-bench/bin/python` first, then `python3`).

use crate::model::{Model, Request};
use crate::output::write_matrix_market;
use crate::study::mesh::MeshStudy;
use std::path::Path;

/// The peer solver's result on the exported K.
#[derive(Debug, Clone)]
pub struct PeerResult {
    /// The python that ran the script.
    pub python: String,
    /// `eigsh` alone, its factorisation of K − σI included (as the script measures it).
    pub seconds: f64,
    /// The eigenvalues it found, ascending.
    pub values: Vec<f64>,
    /// The shift it used.
    pub sigma: f64,
}

/// Exports K at (u, p) to `out`/K.mtx and runs `scripts/peer_eigsh.py` on it for the 20
/// eigenvalues nearest `sigma`, if a python with scipy is found; the error says why not.
pub fn run_peer(
    out: &Path,
    study: &MeshStudy,
    u: &[f64],
    p: &[f64],
    sigma: f64,
) -> Result<PeerResult, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = root.join("scripts/peer_eigsh.py");
    if !script.is_file() {
        return Err(format!("{} not found", script.display()));
    }
    let candidates = [
        root.join(".venv-bench/bin/python")
            .to_string_lossy()
            .into_owned(),
        "python3".to_string(),
    ];
    let python = candidates
        .iter()
        .find(|py| {
            std::process::Command::new(py)
                .args(["-c", "import scipy, numpy"])
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        })
        .ok_or("no python3 with scipy (make one: python3 -m venv .venv-bench && .venv-bench/bin/pip install scipy)")?
        .clone();
    let mut eval = study.model.new_evaluation();
    study
        .model
        .evaluate(u, p, Request::ALL, &mut eval)
        .map_err(|e| e.to_string())?;
    let mtx = out.join("K.mtx");
    write_matrix_market(
        &mtx,
        study.model.pattern(),
        &eval.tangent,
        &eval.rank_one,
        "memstab bench: the balloon at its pressure maximum",
    )
    .map_err(|e| e.to_string())?;
    let output = std::process::Command::new(&python)
        .arg(&script)
        .arg(&mtx)
        .args([
            "--k".to_string(),
            "20".to_string(),
            format!("--sigma={sigma:e}"),
        ])
        .output()
        .map_err(|e| format!("{python}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "peer_eigsh.py failed: {}",
            super::one_line(&String::from_utf8_lossy(&output.stderr))
        ));
    }
    let v: serde_json::Value =
        serde_json::from_slice(&output.stdout).map_err(|e| format!("peer_eigsh.py output: {e}"))?;
    let values = v["eigenvalues"]
        .as_array()
        .ok_or("peer_eigsh.py: no eigenvalues")?
        .iter()
        .filter_map(|x| x.as_f64())
        .collect();
    Ok(PeerResult {
        python,
        seconds: v["seconds"].as_f64().unwrap_or(f64::NAN),
        values,
        sigma: v["sigma"].as_f64().unwrap_or(f64::NAN),
    })
}
