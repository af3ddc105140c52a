//! Readers for the mesh files our writers produce, so that a scene can name a mesh *file*
//! instead of a generator.
//!
//! ```no_run
//! # fn demo() -> Result<(), meshes::MeshError> {
//! let mesh = meshes::read::read_mesh(std::path::Path::new("disc.msh"))?;
//! println!("{} nodes, node sets {:?}", mesh.nodes.len(), mesh.boundaries.keys());
//! # Ok(()) }
//! ```
//!
//! Supported, by extension (case-insensitive; see [`SUPPORTED`]):
//! - `.msh`: Gmsh MSH 4.1 **ascii**, the format [`crate::write`] writes (it writes no binary
//!   MSH, so none is read). Element blocks of dimension 0 and 1 (points and lines that Gmsh
//!   puts on geometric points and curves) are skipped; any other element than the 3-node
//!   triangle is an error.
//! - `.vtu`: VTK XML `UnstructuredGrid`, one piece, arrays `format="ascii"` or
//!   `format="binary"` (inline base64, header `UInt32` or `UInt64`, either byte order, no
//!   compression) — both as our writer emits them; every cell must be a triangle (type 5).
//!
//! What a reader returns is a [`Mesh`] whose nodes and triangles are in file order (node i is
//! the i-th node of the file; coordinates are parsed to the same bits our writers printed) and
//! whose named node sets are recovered from the point data our writers add for them: a scalar
//! point field `set_<name>` with 1.0 on the set's nodes and 0.0 elsewhere (see
//! [`crate::write::node_set_field`]). Every other field is read past and dropped.
//!
//! Malformed input never panics: every problem is a [`MeshError::Read`] naming the file and
//! where — `line 12:` of a Gmsh file, `DataArray "connectivity":` of a VTU file — and what
//! was expected. A missing or unreadable file is a [`MeshError::Io`]. The reader checks
//! what it needs to build the mesh (counts, node references, finite coordinates, 0/1 node
//! sets); whether the mesh is a sound surface with a given symmetry is
//! [`crate::SymmetricMesh::verify`]'s business.
//!
//! One format per source file: `gmsh.rs` and `vtu.rs`.

mod gmsh;
mod vtu;

use crate::mesh::{Mesh, Vec3};
use crate::MeshError;
use std::collections::BTreeMap;
use std::path::Path;

/// The extensions [`read_mesh`] accepts, with what it reads from them.
pub const SUPPORTED: &str = ".msh (Gmsh 4.1 ascii), .vtu (VTK XML unstructured grid, ascii or \
                             inline base64)";

/// Prefix of the point fields that carry node sets (`set_rim` is the node set `rim`).
pub const NODE_SET_PREFIX: &str = "set_";

/// Reads a `.vtu` file as [`read_mesh`] does, and its 3-component point field `field` (a
/// state's `displacement`, a critical point's `critical_mode` …), one vector per node.
///
/// # Errors
/// [`MeshError::Io`] if the file cannot be read; [`MeshError::Read`] if it is not a VTU file
/// our readers accept, or has no such field, or one of another size.
pub fn read_vtu_field(path: &Path, field: &str) -> Result<(Mesh, Vec<[f64; 3]>), MeshError> {
    let fail = |message: String| MeshError::Read {
        path: path.to_path_buf(),
        message,
    };
    let is_vtu = path
        .extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("vtu"));
    if !is_vtu {
        return Err(fail("expected a .vtu file".into()));
    }
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| fail(format!("not UTF-8 text: {e}")))?;
    vtu::parse_with_field(&text, field).map_err(fail)
}

/// Reads a mesh file, choosing the reader by the extension (`.msh`, `.vtu`; see the
/// [module docs](self)).
///
/// # Errors
/// [`MeshError::Io`] if the file cannot be read; [`MeshError::Read`] for an unsupported
/// extension (the message lists the supported ones) or malformed content (the message names
/// the line or the data array).
pub fn read_mesh(path: &Path) -> Result<Mesh, MeshError> {
    let fail = |message: String| MeshError::Read {
        path: path.to_path_buf(),
        message,
    };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let parse: fn(&str) -> Result<Mesh, String> = match ext.as_str() {
        "msh" => gmsh::parse,
        "vtu" => vtu::parse,
        "" => return Err(fail(format!("no file extension; supported: {SUPPORTED}"))),
        other => {
            return Err(fail(format!(
                "unsupported mesh file extension \".{other}\"; supported: {SUPPORTED}"
            )))
        }
    };
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        fail(format!(
            "not a text file (invalid UTF-8 at byte {}); only ascii and base64 data are read",
            e.utf8_error().valid_up_to()
        ))
    })?;
    parse(&text).map_err(fail)
}

/// What a reader collected, before it becomes a [`Mesh`]: nodes, triangles as node indices,
/// and the point fields named `set_<name>` (one value per node).
#[derive(Debug, Default)]
struct Parts {
    nodes: Vec<Vec3>,
    triangles: Vec<[usize; 3]>,
    /// Node-set fields by set name (without the prefix), with where they were found.
    sets: BTreeMap<String, (Vec<f64>, String)>,
}

impl Parts {
    /// Records the values of point field `field` (found at `place`) if it is a node set;
    /// other fields are ignored. A second field with the same set name is an error.
    fn add_point_field(
        &mut self,
        field: &str,
        place: &str,
        values: Vec<f64>,
    ) -> Result<(), String> {
        let Some(name) = field.strip_prefix(NODE_SET_PREFIX) else {
            return Ok(());
        };
        if name.is_empty() {
            return Err(format!(
                "{place}: point field \"{field}\" names no node set (expected set_<name>)"
            ));
        }
        if let Some((_, first)) = self.sets.get(name) {
            return Err(format!(
                "{place}: a second point field \"{field}\" (the first is at {first})"
            ));
        }
        self.sets
            .insert(name.to_string(), (values, place.to_string()));
        Ok(())
    }

    /// The mesh with its node sets: every set field must have one value per node, each 0 or 1.
    fn into_mesh(self) -> Result<Mesh, String> {
        if self.triangles.is_empty() {
            return Err("the file has no triangles".into());
        }
        let n = self.nodes.len();
        let mut mesh = Mesh::new(self.nodes, self.triangles).map_err(|e| e.to_string())?;
        for (name, (values, place)) in self.sets {
            if values.len() != n {
                return Err(format!(
                    "{place}: node set field \"{NODE_SET_PREFIX}{name}\" has {} values, the mesh \
                     has {n} nodes",
                    values.len()
                ));
            }
            let mut nodes = Vec::new();
            for (i, &v) in values.iter().enumerate() {
                if v == 1.0 {
                    nodes.push(i);
                } else if v != 0.0 {
                    return Err(format!(
                        "{place}: node set field \"{NODE_SET_PREFIX}{name}\" has the value {v} at \
                         node index {i} (from 0); a node set is 1 on its nodes and 0 elsewhere"
                    ));
                }
            }
            mesh.set_boundary(name, nodes);
        }
        Ok(mesh)
    }
}

/// Fails unless every coordinate of node `i` is finite; `place` says where it was read.
fn finite_node(x: &Vec3, place: &str) -> Result<(), String> {
    match x.iter().find(|c| !c.is_finite()) {
        Some(c) => Err(format!("{place}: non-finite coordinate {c}")),
        None => Ok(()),
    }
}

/// Fails if triangle `tri` (read at `place`) repeats a node.
fn distinct(tri: &[usize; 3], place: &str) -> Result<(), String> {
    if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
        Err(format!("{place}: the triangle repeats a node"))
    } else {
        Ok(())
    }
}
