//! Writers that meshio 5.3.5 (and ParaView / Gmsh) read: VTU, Gmsh 4.1, XDMF, and ParaView PVD
//! collections of VTU files.
//!
//! ```no_run
//! use meshes::write::{write_mesh, Fields, Format};
//! # fn demo(mesh: &meshes::Mesh, w: Vec<f64>, p: Vec<f64>) -> Result<(), meshes::MeshError> {
//! let path = std::path::Path::new("out/state.vtu");
//! let fields = Fields::new().point_scalar("w", w).cell_scalar("pressure", p);
//! write_mesh(path, mesh, &fields, Format::from_path(path, true)?)?;
//! # Ok(()) }
//! ```
//!
//! What every writer guarantees:
//! - **Validation first.** Field lengths must equal the node / triangle count, every
//!   coordinate and value must be finite, field names must be non-empty, unique per kind and
//!   printable (no `"`, no control characters, no surrounding whitespace), triangles and node
//!   sets must refer to existing nodes. On any error nothing is written and an existing target
//!   is left untouched.
//! - **Whole files.** Each file is written into a temporary file in the target directory,
//!   flushed to disk, and renamed over the target, so a reader never sees a half-written file.
//!   New files get mode 0644 (Unix). XDMF with side files: the side files are renamed into
//!   place before the `.xdmf` that refers to them.
//! - **Exact numbers.** Text formats print every `f64` with the shortest decimal that parses
//!   back to the same bits (`-0` keeps its sign, subnormals survive); binary formats store the
//!   IEEE little-endian bytes.
//! - **Node sets as point data.** Each named node set of the mesh (`Mesh::boundaries`, e.g.
//!   `rim`) is written as an extra point scalar `set_<name>`: 1.0 on the set's nodes, 0.0
//!   elsewhere (see [`node_set_field`]). A user point field with the same name is an error.
//!
//! Reading back with meshio 5.3.5 (checked by `scripts/meshio_roundtrip.sh`): every format
//! reads back bit-exactly. Its XDMF reader needs `h5py` installed even for files without HDF5
//! data, and resolves [`Format::XdmfBinary`] side files against the *current directory*; its
//! Gmsh reader adds `gmsh:dim_tags` point data and `gmsh:geometrical` cell data.
//!
//! One format per source file: `vtu.rs` (VTK XML `UnstructuredGrid`), `gmsh.rs` (MSH 4.1
//! ascii), `xdmf.rs` (XDMF 3, inline XML or raw binary side files) and `pvd.rs` (ParaView
//! collections, [`write_pvd`]); `atomic.rs` does the write-then-rename.

mod atomic;
mod gmsh;
mod pvd;
mod vtu;
mod xdmf;

pub use atomic::{check_target, write_whole, TEMPORARY_PREFIX, TEMPORARY_SUFFIX};
pub use pvd::{write_pvd, write_pvd_named};

use crate::mesh::Mesh;
use crate::MeshError;
use std::collections::BTreeSet;
use std::fmt;
use std::path::Path;

/// Values of one field: one scalar or one 3-vector per node (or per triangle).
#[derive(Debug, Clone, PartialEq)]
pub enum FieldData {
    /// One number per entity.
    Scalar(Vec<f64>),
    /// One 3-vector per entity (x, y, z components).
    Vector(Vec<[f64; 3]>),
}

impl FieldData {
    /// Number of entities (nodes or triangles) the field covers.
    pub fn len(&self) -> usize {
        match self {
            FieldData::Scalar(v) => v.len(),
            FieldData::Vector(v) => v.len(),
        }
    }

    /// True if the field has no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Components per entity: 1 or 3.
    pub fn components(&self) -> usize {
        match self {
            FieldData::Scalar(_) => 1,
            FieldData::Vector(_) => 3,
        }
    }

    /// All values, entity by entity, components interleaved (x0 y0 z0 x1 …).
    pub fn flat(&self) -> &[f64] {
        match self {
            FieldData::Scalar(v) => v,
            FieldData::Vector(v) => v.as_flattened(),
        }
    }
}

/// A named field.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Name as it appears in the file (and in meshio's `point_data` / `cell_data`).
    pub name: String,
    /// The values.
    pub data: FieldData,
}

impl Field {
    /// A scalar field.
    pub fn scalar(name: impl Into<String>, values: impl IntoIterator<Item = f64>) -> Self {
        Self {
            name: name.into(),
            data: FieldData::Scalar(values.into_iter().collect()),
        }
    }

    /// A 3-vector field; accepts `[f64; 3]` or [`crate::Vec3`] items.
    pub fn vector<V: Into<[f64; 3]>>(
        name: impl Into<String>,
        values: impl IntoIterator<Item = V>,
    ) -> Self {
        Self {
            name: name.into(),
            data: FieldData::Vector(values.into_iter().map(Into::into).collect()),
        }
    }
}

/// Point (per node) and cell (per triangle) fields to write with a mesh.
///
/// Built with chained calls:
/// `Fields::new().point_scalar("w", w).point_vector("u", u).cell_scalar("area", a)`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Fields {
    /// Per-node fields, in file order.
    pub point: Vec<Field>,
    /// Per-triangle fields, in file order.
    pub cell: Vec<Field>,
}

impl Fields {
    /// No fields.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a per-node scalar.
    #[must_use]
    pub fn point_scalar(
        mut self,
        name: impl Into<String>,
        v: impl IntoIterator<Item = f64>,
    ) -> Self {
        self.point.push(Field::scalar(name, v));
        self
    }

    /// Adds a per-node 3-vector (`[f64; 3]` or [`crate::Vec3`] items).
    #[must_use]
    pub fn point_vector<V: Into<[f64; 3]>>(
        mut self,
        name: impl Into<String>,
        v: impl IntoIterator<Item = V>,
    ) -> Self {
        self.point.push(Field::vector(name, v));
        self
    }

    /// Adds a per-triangle scalar.
    #[must_use]
    pub fn cell_scalar(
        mut self,
        name: impl Into<String>,
        v: impl IntoIterator<Item = f64>,
    ) -> Self {
        self.cell.push(Field::scalar(name, v));
        self
    }

    /// Adds a per-triangle 3-vector (`[f64; 3]` or [`crate::Vec3`] items).
    #[must_use]
    pub fn cell_vector<V: Into<[f64; 3]>>(
        mut self,
        name: impl Into<String>,
        v: impl IntoIterator<Item = V>,
    ) -> Self {
        self.cell.push(Field::vector(name, v));
        self
    }

    /// True if there are neither point nor cell fields.
    pub fn is_empty(&self) -> bool {
        self.point.is_empty() && self.cell.is_empty()
    }
}

/// A file format [`write_mesh`] can write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// VTK XML unstructured grid (`.vtu`), numbers as text.
    VtuAscii,
    /// VTK XML unstructured grid (`.vtu`), inline base64 of raw little-endian arrays
    /// (`format="binary"`, `header_type="UInt64"`, no compression).
    VtuBase64,
    /// Gmsh MSH 4.1 ascii (`.msh`) with `$NodeData` / `$ElementData` for fields.
    Msh41,
    /// XDMF 3 (`.xdmf`) with the arrays inline as text (`Format="XML"`): one self-contained file.
    Xdmf,
    /// XDMF 3 (`.xdmf`) whose arrays are raw little-endian binary side files
    /// (`Format="Binary"`) next to it, named `<stem>.<part>.bin`
    /// (`geometry`, `topology`, `point0`, …, `cell0`, …) and referenced by file name only, so
    /// the files can be moved together. Rewriting with fewer fields leaves the old surplus
    /// side files in place (unreferenced).
    XdmfBinary,
}

impl Format {
    /// The format for a file name: `.vtu` → VTU (base64 if `binary`, else ascii), `.msh` → Gmsh
    /// 4.1 ascii (`binary` is ignored: only ascii is written), `.xdmf` / `.xmf` → XDMF (binary
    /// side files if `binary`, else inline XML). Case-insensitive; anything else is
    /// [`MeshError::Invalid`] naming the extension.
    ///
    /// # Errors
    /// [`MeshError::Invalid`] for a missing or unknown extension.
    pub fn from_path(path: &Path, binary: bool) -> Result<Format, MeshError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .ok_or_else(|| {
                MeshError::Invalid(format!(
                    "{}: no file extension; use .vtu, .msh or .xdmf",
                    path.display()
                ))
            })?;
        match (ext.as_str(), binary) {
            ("vtu", false) => Ok(Format::VtuAscii),
            ("vtu", true) => Ok(Format::VtuBase64),
            ("msh", _) => Ok(Format::Msh41),
            ("xdmf" | "xmf", false) => Ok(Format::Xdmf),
            ("xdmf" | "xmf", true) => Ok(Format::XdmfBinary),
            _ => Err(MeshError::Invalid(format!(
                "{}: unknown mesh file extension \".{ext}\"; use .vtu, .msh or .xdmf",
                path.display()
            ))),
        }
    }
}

/// Writes `mesh` with `fields` (plus one `set_<name>` point scalar per node set) to `path`.
///
/// Validates everything first (see the [module docs](self)); on error nothing is written and
/// an existing file at `path` is kept. The file is written whole through a temporary file and
/// a rename. [`Format::XdmfBinary`] also writes side files next to `path`.
///
/// # Errors
/// [`MeshError::Invalid`] naming the offending field, node, triangle or node set;
/// [`MeshError::Io`] if the directory cannot be written (missing, read-only, full).
pub fn write_mesh(
    path: &Path,
    mesh: &Mesh,
    fields: &Fields,
    format: Format,
) -> Result<(), MeshError> {
    let sets = validate(mesh, fields)?;
    let data = MeshData {
        mesh,
        point: fields.point.iter().chain(&sets).collect(),
        cell: fields.cell.iter().collect(),
    };
    match format {
        Format::VtuAscii => {
            atomic::stage(path, |w| vtu::write(w, &data, vtu::Encoding::Ascii))?.commit()
        }
        Format::VtuBase64 => {
            atomic::stage(path, |w| vtu::write(w, &data, vtu::Encoding::Base64))?.commit()
        }
        Format::Msh41 => atomic::stage(path, |w| gmsh::write(w, &data))?.commit(),
        Format::Xdmf => atomic::stage(path, |w| xdmf::write_inline(w, &data))?.commit(),
        Format::XdmfBinary => xdmf::write_with_side_files(path, &data),
    }
}

/// The node and triangle orbit numbers of a symmetric mesh (`node_orbit`, `triangle_orbit`),
/// to see its fundamental domain and the domain's images.
pub fn orbit_fields(sym: &crate::SymmetricMesh) -> Fields {
    let numbers = |n: usize, orbits: Vec<Vec<usize>>| -> Vec<f64> {
        let mut id = vec![0.0; n];
        for (k, orbit) in orbits.iter().enumerate() {
            for &i in orbit {
                id[i] = k as f64;
            }
        }
        id
    };
    Fields::new()
        .point_scalar(
            "node_orbit",
            numbers(sym.mesh.nodes.len(), sym.action.node_orbits()),
        )
        .cell_scalar(
            "triangle_orbit",
            numbers(sym.mesh.triangles.len(), sym.action.triangle_orbits()),
        )
}

/// The `set_<name>` point scalar written for node set `name`: 1.0 on `nodes`, 0.0 elsewhere.
pub fn node_set_field(name: &str, nodes: &[usize], num_nodes: usize) -> Field {
    let mut v = vec![0.0; num_nodes];
    for &i in nodes {
        if i < num_nodes {
            v[i] = 1.0;
        }
    }
    Field::scalar(format!("set_{name}"), v)
}

/// A validated mesh with the fields to write, node-set fields appended to the point fields.
pub(crate) struct MeshData<'a> {
    pub mesh: &'a Mesh,
    pub point: Vec<&'a Field>,
    pub cell: Vec<&'a Field>,
}

/// Checks mesh and fields; returns the node-set fields.
fn validate(mesh: &Mesh, fields: &Fields) -> Result<Vec<Field>, MeshError> {
    let (n, m) = (mesh.nodes.len(), mesh.triangles.len());
    if n == 0 || m == 0 {
        return Err(MeshError::Invalid(format!(
            "cannot write a mesh with {n} nodes and {m} triangles"
        )));
    }
    for (i, x) in mesh.nodes.iter().enumerate() {
        if let Some(c) = x.iter().position(|c| !c.is_finite()) {
            return Err(MeshError::Invalid(format!(
                "node {i} has a non-finite coordinate {c}: {}",
                x[c]
            )));
        }
    }
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i >= n) {
            return Err(MeshError::Invalid(format!(
                "triangle {t} refers to node {i}, the mesh has {n} nodes"
            )));
        }
    }
    let mut sets = Vec::with_capacity(mesh.boundaries.len());
    for (name, nodes) in &mesh.boundaries {
        if let Some(&i) = nodes.iter().find(|&&i| i >= n) {
            return Err(MeshError::Invalid(format!(
                "node set \"{name}\" refers to node {i}, the mesh has {n} nodes"
            )));
        }
        sets.push(node_set_field(name, nodes, n));
    }
    let point = fields.point.iter().chain(&sets);
    check_fields("point", point, n, "nodes")?;
    check_fields("cell", fields.cell.iter(), m, "triangles")?;
    Ok(sets)
}

fn check_fields<'a>(
    kind: &str,
    fields: impl Iterator<Item = &'a Field>,
    count: usize,
    what: &str,
) -> Result<(), MeshError> {
    let mut seen = BTreeSet::new();
    for f in fields {
        check_name(kind, &f.name)?;
        if !seen.insert(f.name.as_str()) {
            return Err(MeshError::Invalid(format!(
                "two {kind} fields are named \"{}\" (node sets are written as point fields \
                 set_<name>)",
                f.name
            )));
        }
        if f.data.len() != count {
            return Err(MeshError::Invalid(format!(
                "{kind} field \"{}\" has {} values, the mesh has {count} {what}",
                f.name,
                f.data.len()
            )));
        }
        let c = f.data.components();
        if let Some(k) = f.data.flat().iter().position(|v| !v.is_finite()) {
            return Err(MeshError::Invalid(format!(
                "{kind} field \"{}\" has a non-finite value {} at entry {}{}",
                f.name,
                f.data.flat()[k],
                k / c,
                if c > 1 {
                    format!(", component {}", k % c)
                } else {
                    String::new()
                }
            )));
        }
    }
    Ok(())
}

/// Names go into XML attributes, quoted Gmsh string tags and line-based Gmsh sections.
fn check_name(kind: &str, name: &str) -> Result<(), MeshError> {
    let bad = if name.is_empty() {
        Some("is empty")
    } else if name.contains('"') {
        Some("contains '\"'")
    } else if name.chars().any(char::is_control) {
        Some("contains a control character")
    } else if name.trim() != name {
        Some("has leading or trailing whitespace")
    } else {
        None
    };
    match bad {
        Some(why) => Err(MeshError::Invalid(format!(
            "{kind} field name {name:?} {why}"
        ))),
        None => Ok(()),
    }
}

/// An `f64` printed with the fewest digits that parse back to the same bits: plain decimal for
/// 1e-4 ≤ |x| < 1e16 (and zero), `1.5e-300` style otherwise (like Python's `repr`). Never
/// `inf`/`NaN`: callers validate first.
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-4..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Escapes text for an XML attribute value or element content.
pub(crate) fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_and_are_short() {
        for x in [
            0.0,
            -0.0,
            1.0,
            -3.25,
            0.1,
            1.0 / 3.0,
            1e-4,
            9.99e-5,
            1e16,
            1e300,
            -1e-300,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            123456789.123,
        ] {
            let s = Num(x).to_string();
            let y: f64 = s.parse().unwrap();
            assert_eq!(x.to_bits(), y.to_bits(), "{x} printed as {s}");
            assert!(s.len() <= 24, "{s}");
        }
        assert_eq!(Num(0.1).to_string(), "0.1");
        assert_eq!(Num(1e300).to_string(), "1e300");
        assert_eq!(Num(-0.0).to_string(), "-0");
        assert_eq!(Num(2.0).to_string(), "2");
    }

    #[test]
    fn xml_escape_escapes() {
        assert_eq!(xml_escape("a<b>&'\""), "a&lt;b&gt;&amp;&apos;&quot;");
    }
}
