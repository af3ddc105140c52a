//! `memstab._memstab`: the native part of the Python package, over the memstab library.
//!
//! Plain values cross the boundary (TOML and JSON text, lists of numbers); the Python layer
//! (`memstab/__init__.py`) makes them into pandas frames, meshio meshes and scipy matrices.
//! Every error is a `memstab.MemstabError` carrying the one line the command line prints.

use memstab::model::{Model as _, Request};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::path::Path;

create_exception!(
    _memstab,
    MemstabError,
    PyException,
    "A scene, run or model that cannot be used: the command line's one-line message."
);

fn error(message: impl std::fmt::Display) -> PyErr {
    MemstabError::new_err(memstab::text::one_line(&message.to_string()))
}

/// Reads and validates the scene file `path`; returns its TOML text (relative file names
/// resolved) and its origin.
#[pyfunction]
fn scene_load(path: &str) -> PyResult<(String, String)> {
    let scene = Scene::load(path).map_err(error)?;
    scene.build_mesh().map_err(error)?;
    Ok((scene.to_toml(), scene.origin.clone()))
}

/// Parses and validates the scene `text` (its mesh built too); returns it as TOML again.
#[pyfunction]
fn scene_check(text: &str, origin: &str) -> PyResult<String> {
    let scene = Scene::from_toml_str(text, origin).map_err(error)?;
    scene.build_mesh().map_err(error)?;
    Ok(scene.to_toml())
}

/// TOML text as JSON text.
#[pyfunction]
fn toml_to_json(text: &str) -> PyResult<String> {
    let table: toml::Table = text.parse().map_err(error)?;
    serde_json::to_string(&table).map_err(error)
}

/// JSON text (an object) as TOML text.
#[pyfunction]
fn json_to_toml(text: &str) -> PyResult<String> {
    let value: serde_json::Value = serde_json::from_str(text).map_err(error)?;
    let table: toml::Table = serde_json::from_value(value).map_err(|e| {
        error(format!(
            "not a scene: {e} (values must be numbers, strings, booleans, lists, tables)"
        ))
    })?;
    toml::to_string(&table).map_err(error)
}

/// Runs the scene `text` into the directory `out` (made if missing, its parent must exist)
/// as `memstab run` does, without holding the GIL; returns why its path stopped.
#[pyfunction]
fn run(py: Python<'_>, text: &str, origin: &str, out: &str) -> PyResult<String> {
    let scene = Scene::from_toml_str(text, origin).map_err(error)?;
    let out = Path::new(out).to_path_buf();
    py.detach(move || -> Result<String, String> {
        if !out.is_dir() {
            std::fs::create_dir(&out).map_err(|e| {
                format!(
                    "cannot create the output directory '{}': {e}",
                    out.display()
                )
            })?;
        }
        let _lock = memstab::output::RunLock::acquire(&out).map_err(|e| e.to_string())?;
        memstab::sweep::run_scene(scene, &out).map(|stop| stop.to_string())
    })
    .map_err(error)
}

/// A scene's finite-element model on its 3-D mesh: the residual F(u, Λ) = ∂Π/∂u, the
/// tangent K = ∂F/∂u on its symmetric sparse pattern (compressed columns) with its rank-one
/// terms, and the loads ∂F/∂Λ_j.
#[pyclass(unsendable)]
struct Model {
    study: MeshStudy,
}

#[pymethods]
impl Model {
    #[new]
    fn new(text: &str, origin: &str) -> PyResult<Self> {
        let scene = Scene::from_toml_str(text, origin).map_err(error)?;
        if matches!(scene.mesh, memstab::scene::MeshSpec::Axisymmetric(_)) {
            return Err(error(format!(
                "{origin}: the model of an axisymmetric (meridian) scene is not exposed; give a 3-D mesh"
            )));
        }
        let study = MeshStudy::build(scene).map_err(error)?;
        Ok(Self { study })
    }

    /// The number of unknowns (3 per free node).
    #[getter]
    fn unknowns(&self) -> usize {
        self.study.model.unknowns()
    }

    /// The parameter names, in scene order.
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.study.parameters.clone()
    }

    /// The parameters' start values.
    #[getter]
    fn start_values(&self) -> Vec<f64> {
        self.study.start.clone()
    }

    /// The start state as `memstab run` solves it: (u, parameters).
    fn start(&mut self, py: Python<'_>) -> PyResult<(Vec<f64>, Vec<f64>)> {
        let start = memstab::analysis::restart::start_of(&self.study).map_err(error)?;
        let _ = py;
        let point = memstab::analysis::equilibrium::state_at(&mut self.study, &[], &start)
            .map_err(error)?;
        Ok((point.u, point.params))
    }

    /// The nodes' current positions X + u (and a held motion's), three numbers a node.
    fn positions(&self, u: Vec<f64>, params: Vec<f64>) -> PyResult<Vec<f64>> {
        self.check(&u, &params)?;
        Ok(self
            .study
            .model
            .positions(&u, &params)
            .iter()
            .flat_map(|x| [x.x, x.y, x.z])
            .collect())
    }

    /// F(u, Λ).
    fn residual(&self, u: Vec<f64>, params: Vec<f64>) -> PyResult<Vec<f64>> {
        Ok(self.evaluate(&u, &params)?.residual)
    }

    /// ∂F/∂Λ_j, one list per parameter.
    fn loads(&self, u: Vec<f64>, params: Vec<f64>) -> PyResult<Vec<Vec<f64>>> {
        Ok(self.evaluate(&u, &params)?.loads)
    }

    /// K(u, Λ): (values, row indices, column pointers) of its sparse part on the full
    /// symmetric pattern, and its rank-one terms [(c, a)] (K = S + Σ c a aᵀ).
    #[allow(clippy::type_complexity)]
    fn tangent(
        &self,
        u: Vec<f64>,
        params: Vec<f64>,
    ) -> PyResult<(Vec<f64>, Vec<usize>, Vec<usize>, Vec<(f64, Vec<f64>)>)> {
        let eval = self.evaluate(&u, &params)?;
        let pattern = self.study.model.pattern();
        Ok((
            eval.tangent,
            pattern.row_idx().to_vec(),
            pattern.col_ptr().to_vec(),
            eval.rank_one,
        ))
    }
}

impl Model {
    fn check(&self, u: &[f64], params: &[f64]) -> PyResult<()> {
        let n = self.study.model.unknowns();
        if u.len() != n {
            return Err(error(format!(
                "u has {} values; the model has {n} unknowns",
                u.len()
            )));
        }
        if params.len() != self.study.parameters.len() {
            return Err(error(format!(
                "{} parameter values for the parameters {:?}",
                params.len(),
                self.study.parameters
            )));
        }
        if let Some(i) = u.iter().chain(params).position(|v| !v.is_finite()) {
            return Err(error(format!(
                "value {i} of u and the parameters is not finite"
            )));
        }
        Ok(())
    }

    fn evaluate(&self, u: &[f64], params: &[f64]) -> PyResult<memstab::model::Evaluation> {
        self.check(u, params)?;
        let mut eval = self.study.model.new_evaluation();
        self.study
            .model
            .evaluate(u, params, Request::ALL, &mut eval)
            .map_err(error)?;
        Ok(eval)
    }
}

#[pymodule]
fn _memstab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MemstabError", m.py().get_type::<MemstabError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(scene_load, m)?)?;
    m.add_function(wrap_pyfunction!(scene_check, m)?)?;
    m.add_function(wrap_pyfunction!(toml_to_json, m)?)?;
    m.add_function(wrap_pyfunction!(json_to_toml, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_class::<Model>()?;
    Ok(())
}
