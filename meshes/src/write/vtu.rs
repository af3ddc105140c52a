//! VTK XML unstructured grid (`.vtu`), after "VTK File Formats", section "XML File Formats"
//! (VTK User's Guide; <https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html>).
//!
//! The points that matter to readers:
//! - Root `<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian"
//!   header_type="UInt64">`; one `<Piece NumberOfPoints NumberOfCells>` holding `<Points>`
//!   (one `Float64` array, `NumberOfComponents="3"`), `<Cells>` (`connectivity`, `offsets` =
//!   running end index of each cell's connectivity, i.e. 3, 6, 9, …, and `types` = 5 for
//!   `VTK_TRIANGLE`), then `<PointData>` and `<CellData>`.
//! - Vector fields have `NumberOfComponents="3"`, values interleaved x y z.
//! - `format="ascii"`: whitespace-separated numbers. `format="binary"`: base64 of one block made
//!   of a `header_type` integer (the number of data *bytes*, here UInt64) followed by the raw
//!   data, all in `byte_order`. meshio reads `header_type` (default UInt32) and `byte_order`;
//!   it accepts versions 0.1 and 1.0. We always write little-endian, whatever the host.
//! - meshio parses the file with Python's `xml.etree` (a malformed file falls back to an
//!   "appended raw" parser with a confusing error), so names are XML-escaped.

use super::{xml_escape, FieldData, MeshData, Num};
use base64::Engine;
use std::io::{self, Write};

/// How data arrays are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// `format="ascii"`.
    Ascii,
    /// `format="binary"`: base64 of UInt64 byte count + little-endian data.
    Base64,
}

/// `VTK_TRIANGLE` in VTK's cell type enumeration.
const VTK_TRIANGLE: u8 = 5;

/// A typed array to write.
enum Array<'a> {
    F64 {
        values: &'a [f64],
        per_entity: usize,
    },
    I64(&'a [i64]),
    U8(&'a [u8]),
}

impl Array<'_> {
    fn vtk_type(&self) -> &'static str {
        match self {
            Array::F64 { .. } => "Float64",
            Array::I64(_) => "Int64",
            Array::U8(_) => "UInt8",
        }
    }

    fn components(&self) -> usize {
        match self {
            Array::F64 { per_entity, .. } => *per_entity,
            _ => 1,
        }
    }

    fn le_bytes(&self) -> Vec<u8> {
        match self {
            Array::F64 { values, .. } => values.iter().flat_map(|v| v.to_le_bytes()).collect(),
            Array::I64(v) => v.iter().flat_map(|v| v.to_le_bytes()).collect(),
            Array::U8(v) => v.to_vec(),
        }
    }

    fn write_ascii(&self, w: &mut dyn Write) -> io::Result<()> {
        match self {
            Array::F64 { values, per_entity } => {
                for row in values.chunks(*per_entity) {
                    write_row(w, row.iter().map(|&x| Num(x)))?;
                }
            }
            Array::I64(v) => {
                for row in v.chunks(3) {
                    write_row(w, row.iter())?;
                }
            }
            Array::U8(v) => {
                for row in v.chunks(16) {
                    write_row(w, row.iter())?;
                }
            }
        }
        Ok(())
    }
}

fn write_row<T: std::fmt::Display>(
    w: &mut dyn Write,
    row: impl Iterator<Item = T>,
) -> io::Result<()> {
    for (k, x) in row.enumerate() {
        if k > 0 {
            w.write_all(b" ")?;
        }
        write!(w, "{x}")?;
    }
    w.write_all(b"\n")
}

fn write_array(
    w: &mut dyn Write,
    name: &str,
    array: &Array<'_>,
    encoding: Encoding,
) -> io::Result<()> {
    let components = match array.components() {
        1 => String::new(),
        c => format!(" NumberOfComponents=\"{c}\""),
    };
    let format = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::Base64 => "binary",
    };
    writeln!(
        w,
        "<DataArray type=\"{}\" Name=\"{}\"{components} format=\"{format}\">",
        array.vtk_type(),
        xml_escape(name)
    )?;
    match encoding {
        Encoding::Ascii => array.write_ascii(w)?,
        Encoding::Base64 => {
            let data = array.le_bytes();
            let mut block = Vec::with_capacity(8 + data.len());
            block.extend_from_slice(&(data.len() as u64).to_le_bytes());
            block.extend_from_slice(&data);
            let text = base64::engine::general_purpose::STANDARD.encode(&block);
            w.write_all(text.as_bytes())?;
            w.write_all(b"\n")?;
        }
    }
    writeln!(w, "</DataArray>")
}

fn field_array(data: &FieldData) -> Array<'_> {
    Array::F64 {
        values: data.flat(),
        per_entity: data.components(),
    }
}

/// Writes the whole `.vtu` document.
pub(crate) fn write(w: &mut dyn Write, data: &MeshData<'_>, encoding: Encoding) -> io::Result<()> {
    let mesh = data.mesh;
    let points: Vec<f64> = mesh.nodes.iter().flat_map(|x| [x.x, x.y, x.z]).collect();
    let connectivity: Vec<i64> = mesh
        .triangles
        .iter()
        .flat_map(|t| t.map(|i| i as i64))
        .collect();
    let offsets: Vec<i64> = (1..=mesh.triangles.len() as i64).map(|k| 3 * k).collect();
    let types = vec![VTK_TRIANGLE; mesh.triangles.len()];

    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">"
    )?;
    writeln!(w, "<!-- written by memstab (meshes::write) -->")?;
    writeln!(w, "<UnstructuredGrid>")?;
    writeln!(
        w,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        mesh.triangles.len()
    )?;
    writeln!(w, "<Points>")?;
    let pts = Array::F64 {
        values: &points,
        per_entity: 3,
    };
    write_array(w, "Points", &pts, encoding)?;
    writeln!(w, "</Points>")?;
    writeln!(w, "<Cells>")?;
    write_array(w, "connectivity", &Array::I64(&connectivity), encoding)?;
    write_array(w, "offsets", &Array::I64(&offsets), encoding)?;
    write_array(w, "types", &Array::U8(&types), encoding)?;
    writeln!(w, "</Cells>")?;
    writeln!(w, "<PointData>")?;
    for f in &data.point {
        write_array(w, &f.name, &field_array(&f.data), encoding)?;
    }
    writeln!(w, "</PointData>")?;
    writeln!(w, "<CellData>")?;
    for f in &data.cell {
        write_array(w, &f.name, &field_array(&f.data), encoding)?;
    }
    writeln!(w, "</CellData>")?;
    writeln!(w, "</Piece>")?;
    writeln!(w, "</UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}
