//! `memstab._memstab`: the native part of the Python package, over the memstab library.
//!
//! Plain values cross the boundary (TOML and JSON text, lists of numbers); the Python layer
//! (`memstab/__init__.py`) makes them into pandas frames, meshio meshes and scipy matrices.
//! Every error is a `memstab.MemstabError` carrying the one line the command line prints.
//!
//! Long work (a run, a comparison, a spectrum) runs on a thread of its own while the calling
//! thread, without the GIL, waits for it: every 50 ms it takes the GIL back briefly to pass
//! on the progress and to run Python's signal handlers, and a `KeyboardInterrupt` there sets
//! the library's interrupt flag, as the command line's signal handler does. The work then
//! stops at its next point, writes what it found, and the `KeyboardInterrupt` is raised.

use memstab::continuation::interrupt;
use memstab::model::{Model as _, Request};
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

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

/// What the work reports while it goes: points so far, the fraction of the control's range
/// (none without one), and the command line's progress message.
type Update = (usize, Option<f64>, String);

/// Runs `work` on a thread of its own (the GIL released) while this thread passes its
/// updates to `progress` and runs Python's signal handlers every 50 ms. A handler's
/// exception (`KeyboardInterrupt` at Ctrl-C) or the progress callback's sets the library's
/// interrupt flag, the work stops at its next point, and the exception comes back beside the
/// work's value; the flag is cleared once the work has returned. Also returns whether a stop
/// was requested at all (the test hooks request one from inside).
fn watched<T, F>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: F,
) -> PyResult<(T, Option<PyErr>, bool)>
where
    T: Send,
    F: FnOnce(&mpsc::Sender<Update>) -> T + Send,
{
    let (tx, rx) = mpsc::channel::<Update>();
    std::thread::scope(|s| {
        let worker = std::thread::Builder::new()
            .name("memstab".into())
            .stack_size(64 << 20)
            .spawn_scoped(s, move || work(&tx))
            .map_err(|e| error(format!("cannot start a thread for the work: {e}")))?;
        let mut rx = rx;
        let mut stop: Option<PyErr> = None;
        let mut report = progress;
        loop {
            let (got, back) = py.detach(move || {
                let got = rx.recv_timeout(Duration::from_millis(50));
                (got, rx)
            });
            rx = back;
            match got {
                Ok(mut update) => {
                    while let Ok(next) = rx.try_recv() {
                        update = next;
                    }
                    if let Some(r) = report {
                        if let Err(e) = r.call1(update) {
                            interrupt::request();
                            stop.get_or_insert(e);
                            report = None;
                        }
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
            if stop.is_none() {
                if let Err(e) = py.check_signals() {
                    interrupt::request();
                    stop = Some(e);
                }
            }
        }
        let value = worker
            .join()
            .map_err(|_| error("the work's thread panicked"))?;
        let requested = interrupt::requested();
        interrupt::clear();
        Ok((value, stop, requested))
    })
}

/// The outcome of watched work as Python sees it: a signal's exception (a
/// `KeyboardInterrupt` gets `message`), else with a stop requested (a test hook) a
/// `KeyboardInterrupt` with `message`, else the work's error as a `MemstabError`.
fn settle<T>(
    py: Python<'_>,
    (value, stop, requested): (Result<T, String>, Option<PyErr>, bool),
    message: impl FnOnce(Option<&String>) -> String,
) -> PyResult<T> {
    if let Some(e) = stop {
        if !e.is_instance_of::<PyKeyboardInterrupt>(py) {
            return Err(e);
        }
        return Err(PyKeyboardInterrupt::new_err(message(value.as_ref().err())));
    }
    if requested {
        return Err(PyKeyboardInterrupt::new_err(message(value.as_ref().err())));
    }
    value.map_err(error)
}

/// Runs the scene `text` into the directory `out` (made if missing, its parent must exist)
/// as `memstab run` does, without holding the GIL; returns why its path stopped. `progress`
/// is called with (points, fraction of the control's range or None, message) as points
/// converge. Ctrl-C (or the library's test hooks) stops the run at its next point, its
/// outputs written, and raises `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (text, origin, out, progress=None))]
fn run(
    py: Python<'_>,
    text: &str,
    origin: &str,
    out: &str,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    let scene = Scene::from_toml_str(text, origin).map_err(error)?;
    let out = PathBuf::from(out);
    let dir = out.display().to_string();
    let outcome = watched(py, progress.as_ref(), move |tx| -> Result<String, String> {
        if !out.is_dir() {
            std::fs::create_dir(&out).map_err(|e| {
                format!(
                    "cannot create the output directory '{}': {e}",
                    out.display()
                )
            })?;
        }
        let _lock = memstab::output::RunLock::acquire(&out).map_err(|e| e.to_string())?;
        let stop = memstab::sweep::run_scene_reporting(scene, &out, &mut |t| {
            let _ = tx.send((t.points, t.fraction, t.message.clone()));
        })?;
        Ok(stop.to_string())
    })?;
    settle(py, outcome, |failed| match failed {
        Some(m) => format!("interrupted: {}", memstab::text::one_line(m)),
        None => format!("interrupted: the path so far is written into {dir}"),
    })
}

/// The tangent's spectrum by irrep at path point `point` or at critical point `critical`
/// (from 1) of the finished run in `run_dir` of the scene `text`, as `memstab spectrum
/// RUN_DIR --point N` gives it: JSON with the parameters, the index, the scale max |K_ij|
/// and per irrep its dimension, block size, negative count, zero and held modes and the
/// `count` lowest eigenvalues (in units of the scale).
#[pyfunction]
#[pyo3(signature = (text, origin, run_dir, point=None, critical=None, count=6))]
#[allow(clippy::too_many_arguments)]
fn spectrum(
    py: Python<'_>,
    text: &str,
    origin: &str,
    run_dir: &str,
    point: Option<usize>,
    critical: Option<usize>,
    count: usize,
) -> PyResult<String> {
    use memstab::analysis::restart;
    let scene = Scene::from_toml_str(text, origin).map_err(error)?;
    three_d(&scene)?;
    let dir = PathBuf::from(run_dir);
    let outcome = watched(py, None, move |_| -> Result<String, String> {
        let study = MeshStudy::build(scene).map_err(|e| e.to_string())?;
        let run = memstab::output::FinishedRun::read(&dir).map_err(|e| e.to_string())?;
        restart::check_model(&run, &study).map_err(|e| e.to_string())?;
        let (u, params) = match (point, critical) {
            (Some(n), None) => restart::point(&run, &study, n).map_err(|e| e.to_string())?,
            (None, Some(n)) => {
                let (u, _mode) =
                    restart::critical_state(&run, &study, n).map_err(|e| e.to_string())?;
                (u, run.critical[n - 1].parameters.clone())
            }
            _ => return Err("give one of a path point and a critical point".into()),
        };
        let spectrum = study
            .spectrum_at(&u, &params, count)
            .map_err(|e| e.to_string())?;
        let scale = spectrum.scale;
        let json = serde_json::json!({
            "group": study.action.group().name(),
            "parameters": study.parameters.iter().cloned().zip(params.into_iter().map(serde_json::Value::from)).collect::<serde_json::Map<String, serde_json::Value>>(),
            "index": spectrum.index,
            "scale": scale,
            "irreps": spectrum.blocks.iter().map(|b| serde_json::json!({
                "irrep": b.irrep,
                "dim": b.dim,
                "size": b.size,
                "negative": b.negative,
                "zero_modes": b.rigid_modes,
                "held_motions": b.held,
                "lowest": b.eigenvalues.iter().take(count).map(|v| v / scale).collect::<Vec<f64>>(),
            })).collect::<Vec<_>>(),
        });
        Ok(json.to_string())
    })?;
    settle(py, outcome, |_| {
        "interrupted: stopped between the tangent's blocks".to_string()
    })
}

/// `memstab compare`: the scene `text` on the meshes `meshes` (as `--meshes` takes them) with
/// the options of the command; the comparison as JSON (what `compare --json` prints).
/// `progress` is called with (0, None, line) for every progress line.
#[pyfunction]
#[pyo3(signature = (text, origin, meshes, refine=false, max=None, divisions=None, samples=None, include_flagged=false, progress=None))]
#[allow(clippy::too_many_arguments)]
fn compare(
    py: Python<'_>,
    text: &str,
    origin: &str,
    meshes: Vec<String>,
    refine: bool,
    max: Option<f64>,
    divisions: Option<usize>,
    samples: Option<usize>,
    include_flagged: bool,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<String> {
    use memstab::analysis::compare::{parse_meshes, CompareError, CompareOptions};
    let message = |e: CompareError| match e {
        CompareError::Input(m) | CompareError::Failure(m) | CompareError::Interrupted(m) => m,
    };
    let scene = Scene::from_toml_str(text, origin).map_err(error)?;
    let options = CompareOptions {
        meshes: parse_meshes(&meshes).map_err(|e| error(message(e)))?,
        refine,
        max,
        divisions,
        samples,
        include_flagged,
    };
    let outcome = watched(py, progress.as_ref(), move |tx| -> Result<String, String> {
        let tx = std::sync::Mutex::new(tx.clone());
        let line = |l: &str| {
            if let Ok(tx) = tx.lock() {
                let _ = tx.send((0, None, l.to_string()));
            }
        };
        let comparison =
            memstab::analysis::compare::compare(&scene, &options, &line).map_err(message)?;
        serde_json::to_string(&comparison).map_err(|e| e.to_string())
    })?;
    settle(py, outcome, |failed| {
        failed.map_or_else(
            || "interrupted: the comparison stopped".to_string(),
            |m| format!("interrupted: {}", memstab::text::one_line(m)),
        )
    })
}

/// `memstab mesh`: the mesh of the `[mesh]` table `table` (TOML text, as in a scene) built
/// with its group, the action verified, written to `out` (the format from its extension)
/// with the node and triangle orbits; returns (group, order, nodes, triangles, the largest
/// position error of the action, the node sets with their sizes).
#[pyfunction]
#[allow(clippy::type_complexity)]
fn mesh(
    table: &str,
    out: &str,
) -> PyResult<(String, usize, usize, usize, f64, Vec<(String, usize)>)> {
    use memstab::meshes::write::{orbit_fields, write_mesh, Format};
    let spec = memstab::scene::MeshSpec::parse(table, "mesh").map_err(error)?;
    let limits = memstab::limits::Limits::from_env().map_err(error)?;
    limits
        .check_group(&spec.group_name())
        .and_then(|()| limits.check_memory(spec.describe(), spec.estimated_bytes()))
        .map_err(error)?;
    let sym = spec.build().map_err(error)?;
    let check = sym
        .verify()
        .map_err(|e| error(format!("the generated mesh failed verification: {e}")))?;
    let path = Path::new(out);
    let format = Format::from_path(path, false).map_err(error)?;
    write_mesh(path, &sym.mesh, &orbit_fields(&sym), format).map_err(error)?;
    Ok((
        sym.group().name().to_string(),
        sym.group().order(),
        sym.mesh.nodes.len(),
        sym.mesh.triangles.len(),
        check.max_position_error,
        sym.mesh
            .boundaries
            .iter()
            .map(|(k, v)| (k.clone(), v.len()))
            .collect(),
    ))
}

/// `memstab group NAME`: the point group as JSON: name, order, classes (element numbers),
/// irreps (name, dim, kind, the character of every element).
#[pyfunction]
fn group(name: &str) -> PyResult<String> {
    use memstab::symmetry::{Group, IrrepKind};
    memstab::limits::Limits::from_env()
        .and_then(|l| l.check_group(name))
        .map_err(error)?;
    let g = Group::by_name(name).map_err(error)?;
    let json = serde_json::json!({
        "name": g.name(),
        "order": g.order(),
        "classes": g.classes(),
        "irreps": g.irreps().iter().map(|r| serde_json::json!({
            "name": r.name(),
            "dim": r.dim(),
            "kind": match r.kind() { IrrepKind::Real => "real", IrrepKind::Complex => "complex" },
            "characters": r.characters(),
        })).collect::<Vec<_>>(),
    });
    Ok(json.to_string())
}

/// `memstab collect DIR [--x KEY]`: the sweep in `dir` collected and its table and figure
/// written (`collected.csv`, `collected.svg`, …); returns the table as JSON and the files.
#[pyfunction]
#[pyo3(signature = (dir, x=None))]
fn collect(dir: &str, x: Option<&str>) -> PyResult<(String, Vec<String>)> {
    let dir = Path::new(dir);
    let table = memstab::sweep::collect(dir).map_err(error)?;
    let axis = memstab::output::figure_axis(&table, x).map_err(error)?;
    let files = memstab::output::write_sweep_table(dir, &table, axis).map_err(error)?;
    Ok((
        serde_json::to_string(&table).map_err(error)?,
        files.iter().map(|f| f.display().to_string()).collect(),
    ))
}

/// Refuses an axisymmetric (meridian) scene where a 3-D model is needed.
fn three_d(scene: &Scene) -> PyResult<()> {
    if matches!(scene.mesh, memstab::scene::MeshSpec::Axisymmetric(_)) {
        return Err(error(format!(
            "{}: the model of an axisymmetric (meridian) scene is not exposed; give a 3-D mesh",
            scene.origin
        )));
    }
    Ok(())
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
        three_d(&scene)?;
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

    /// The fixed-point basis of the scene's group (its columns orthonormal over the free
    /// unknowns): (values, row indices, column pointers, columns).
    #[allow(clippy::type_complexity)]
    fn fixed_point(&self) -> (Vec<f64>, Vec<usize>, Vec<usize>, usize) {
        csc(self.study.basis.columns())
    }

    /// The symmetry-adapted basis by irrep (the group's order, the trivial one first): per
    /// irrep its name, dimension d, whether it is of complex type, and the columns of its
    /// first partner (values, row indices, column pointers, columns); B_μᵀ K B_μ is its
    /// block, each eigenvalue of which is d-fold in K (a complex-type block holds the whole
    /// isotypic component, its eigenvalues in pairs).
    #[allow(clippy::type_complexity)]
    fn adapted(
        &self,
    ) -> PyResult<
        Vec<(
            String,
            usize,
            bool,
            (Vec<f64>, Vec<usize>, Vec<usize>, usize),
        )>,
    > {
        let adapted =
            memstab::adapted::AdaptedBasis::new(&self.study.action, self.study.model.layout())
                .map_err(error)?;
        Ok(adapted
            .irreps
            .iter()
            .map(|b| (b.name.clone(), b.dim, b.complex, csc(b.first().columns())))
            .collect())
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

/// Sparse columns as compressed columns: (values, row indices, column pointers, columns).
fn csc(columns: &[Vec<(usize, f64)>]) -> (Vec<f64>, Vec<usize>, Vec<usize>, usize) {
    let mut values = Vec::new();
    let mut rows = Vec::new();
    let mut pointers = vec![0];
    for column in columns {
        for &(r, v) in column {
            rows.push(r);
            values.push(v);
        }
        pointers.push(rows.len());
    }
    (values, rows, pointers, columns.len())
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
    m.add_function(wrap_pyfunction!(spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(mesh, m)?)?;
    m.add_function(wrap_pyfunction!(group, m)?)?;
    m.add_function(wrap_pyfunction!(collect, m)?)?;
    m.add_class::<Model>()?;
    Ok(())
}
