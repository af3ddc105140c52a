//! `state_NNNN.vtu`, `path.pvd` and `events.pvd`: displaced meshes for ParaView, and their
//! collections.

use super::{check_dir, OutputError};
use crate::results::{SavedState, State};
use meshes::write::{write_mesh, write_pvd, write_pvd_named, Field, Fields, Format};
use meshes::{Mesh, Vec3};
use std::path::{Path, PathBuf};

/// The name of the collection of the states written beside the path.
pub const EVENTS_PVD: &str = "events.pvd";

/// What the PVD collection uses as each state's "time".
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PvdTime {
    /// The control parameter's value (ParaView's time axis then reads as the load). Along a
    /// path that turns back, times repeat or decrease; ParaView orders datasets by time.
    #[default]
    Control,
    /// The path step (always increasing: the animation follows the path).
    Step,
}

/// Writes saved states as `state_NNNN.vtu` (NNNN = path step, at least four digits) and keeps
/// `path.pvd` listing them, and `events.pvd` listing the states written beside the path
/// (turning and critical points: time = their number in path order, 0, 1, …, and each named
/// `<file stem>: <label>`, e.g. `critical_01: double bifurcation in E1`, which ParaView shows
/// as the block's name).
///
/// Each VTU holds the *displaced* mesh — node coordinates are the current positions — with the
/// point vector `displacement` (current minus reference position), any extra fields the caller
/// gives, and the mesh's node sets as `set_<name>` scalars; arrays are base64
/// ([`Format::VtuBase64`]). After every saved state `path.pvd` is rewritten, so an interrupted
/// run still leaves a consistent collection. All files are written whole (temporary file +
/// rename) and nothing non-finite is written: a NaN position or field is an
/// [`OutputError::Invalid`] naming the file and the node, and leaves no file behind.
///
/// ```no_run
/// # use memstab::output::StateWriter;
/// # fn run(mesh: &meshes::Mesh, x: Vec<meshes::Vec3>) -> Result<(), memstab::output::OutputError> {
/// let mut states = StateWriter::new("out".as_ref(), mesh)?;
/// states.save(0, 0.0, &x, meshes::write::Fields::new())?;
/// let saved = states.finish()?; // goes into PathReport::saved
/// # Ok(()) }
/// ```
#[derive(Debug, Clone)]
pub struct StateWriter {
    dir: PathBuf,
    reference: Mesh,
    time: PvdTime,
    saved: Vec<SavedState>,
}

/// What the writers draw a run's states on — the studies implement it, so that the writers
/// see a mesh and arrays, never a model: the mesh, and for each state its positions (in the
/// mesh's node order) and fields.
pub trait Drawing {
    /// The mesh the states are drawn over (the reference mesh; a meridian revolved).
    fn mesh(&self) -> &Mesh;
    /// A state's positions and fields; a critical state's mode is the point vector field
    /// `critical_mode`. A non-finite value (never at an accepted state) is drawn as 0.
    fn draw(&self, state: &State) -> (Vec<Vec3>, Fields);
    /// The model's unknowns (the length of a state's displacement).
    fn unknowns(&self) -> usize;
    /// The displacement over the model's unknowns of coordinates `q` of the space a path is
    /// solved in (what `path.states` keeps).
    fn expand(&self, q: &[f64]) -> Vec<f64>;
}

impl StateWriter {
    /// A writer into `dir` for states of `reference` (the undeformed mesh; its triangles and
    /// node sets are reused for every state).
    ///
    /// # Errors
    /// [`OutputError::NoDirectory`] if `dir` does not exist.
    pub fn new(dir: &Path, reference: &Mesh) -> Result<Self, OutputError> {
        check_dir(&dir.join("path.pvd"))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            reference: reference.clone(),
            time: PvdTime::default(),
            saved: Vec::new(),
        })
    }

    /// Uses `time` as the PVD time of the states (default [`PvdTime::Control`]).
    #[must_use]
    pub fn with_time(mut self, time: PvdTime) -> Self {
        self.time = time;
        self
    }

    /// The path of the collection, `dir/path.pvd`.
    pub fn pvd_path(&self) -> PathBuf {
        self.dir.join("path.pvd")
    }

    /// The path of the second collection, `dir/events.pvd`: the states written beside the
    /// path (turning and critical points).
    pub fn events_path(&self) -> PathBuf {
        self.dir.join(EVENTS_PVD)
    }

    /// Writes the state of path step `step` at control value `control` with current node
    /// positions `positions` (one per reference node) and `extra` point and cell fields, then
    /// rewrites `path.pvd`. Saving a step again replaces its file and entry.
    ///
    /// # Errors
    /// [`OutputError::Invalid`] for a wrong number of positions, a non-finite position,
    /// displacement, control value or field value, or a bad field (wrong length, duplicate
    /// name, a field named `displacement`) — nothing is written; [`OutputError::Io`] if a file
    /// cannot be written.
    pub fn save(
        &mut self,
        step: usize,
        control: f64,
        positions: &[Vec3],
        extra: Fields,
    ) -> Result<&SavedState, OutputError> {
        let name = format!("state_{step:04}");
        self.save_as(
            &name,
            &format!("step {step}"),
            true,
            step,
            control,
            positions,
            extra,
        )
    }

    /// As [`StateWriter::save`], with the file name `name.vtu`, a label, and whether the
    /// state belongs to the path collection (`path.pvd`) or is written beside it (turning and
    /// critical points). Saving the same name again replaces its file and entry.
    #[allow(clippy::too_many_arguments)]
    pub fn save_as(
        &mut self,
        name: &str,
        label: &str,
        in_collection: bool,
        step: usize,
        control: f64,
        positions: &[Vec3],
        extra: Fields,
    ) -> Result<&SavedState, OutputError> {
        let file = format!("{name}.vtu");
        let path = self.dir.join(&file);
        let invalid = |message: String| OutputError::invalid(&path, message);
        let n = self.reference.nodes.len();
        if positions.len() != n {
            return Err(invalid(format!(
                "{} positions for a mesh of {n} nodes",
                positions.len()
            )));
        }
        if !control.is_finite() {
            return Err(invalid(format!(
                "the control value of step {step} is {control}"
            )));
        }
        if let Some(i) = positions
            .iter()
            .position(|x| x.iter().any(|c| !c.is_finite()))
        {
            let x = positions[i];
            return Err(invalid(format!(
                "node {i} has a non-finite position ({}, {}, {}) at step {step}",
                x[0], x[1], x[2]
            )));
        }
        let displacement: Vec<[f64; 3]> = positions
            .iter()
            .zip(&self.reference.nodes)
            .map(|(x, x0)| (x - x0).into())
            .collect();
        let mut fields = Fields {
            point: vec![Field::vector("displacement", displacement)],
            cell: extra.cell,
        };
        fields.point.extend(extra.point);
        let mesh = Mesh {
            nodes: positions.to_vec(),
            triangles: self.reference.triangles.clone(),
            boundaries: self.reference.boundaries.clone(),
        };
        write_mesh(&path, &mesh, &fields, Format::VtuBase64)
            .map_err(|e| OutputError::from_mesh(&path, e))?;

        let entry = SavedState {
            step,
            control,
            file,
            label: label.to_string(),
            in_collection,
        };
        let k = match self.saved.iter().position(|s| s.file == entry.file) {
            Some(k) => {
                self.saved[k] = entry;
                k
            }
            None => {
                self.saved.push(entry);
                self.saved.len() - 1
            }
        };
        self.write_collection()?;
        Ok(&self.saved[k])
    }

    /// The states saved so far, in the order saved.
    pub fn saved(&self) -> &[SavedState] {
        &self.saved
    }

    /// Writes `path.pvd` (also when no state was saved: an empty collection) and returns the
    /// saved states for [`PathReport::saved`](crate::results::PathReport::saved).
    ///
    /// # Errors
    /// [`OutputError::Io`] if `path.pvd` cannot be written.
    pub fn finish(self) -> Result<Vec<SavedState>, OutputError> {
        self.write_collection()?;
        Ok(self.saved)
    }

    /// Rewrites `path.pvd` and `events.pvd` from the saved states.
    fn write_collection(&self) -> Result<(), OutputError> {
        let events = self.events_path();
        check_dir(&events)?;
        // In path order (a stable sort by step keeps the order saved within a step).
        let mut beside: Vec<&SavedState> = self.saved.iter().filter(|s| !s.in_collection).collect();
        beside.sort_by_key(|s| s.step);
        let entries: Vec<(f64, PathBuf, String)> = beside
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let stem = s.file.strip_suffix(".vtu").unwrap_or(&s.file);
                (
                    k as f64,
                    PathBuf::from(&s.file),
                    format!("{stem}: {}", s.label),
                )
            })
            .collect();
        write_pvd_named(&events, &entries).map_err(|e| OutputError::from_mesh(&events, e))?;
        let path = self.pvd_path();
        check_dir(&path)?;
        let entries: Vec<(f64, PathBuf)> = self
            .saved
            .iter()
            .filter(|s| s.in_collection)
            .map(|s| {
                let t = match self.time {
                    PvdTime::Control => s.control,
                    PvdTime::Step => s.step as f64,
                };
                (t, PathBuf::from(&s.file))
            })
            .collect();
        write_pvd(&path, &entries).map_err(|e| OutputError::from_mesh(&path, e))
    }
}
