//! XDMF 3 (<https://www.xdmf.org/index.php/XDMF_Model_and_Format>): light data (structure) in
//! XML, heavy data (arrays) either inline as text or in raw binary side files.
//!
//! The points that matter to readers:
//! - `<Xdmf Version="3.0"><Domain>` with exactly one `<Grid>` (meshio reads only one) holding
//!   `<Geometry GeometryType="XYZ">`, `<Topology TopologyType="Triangle" NumberOfElements
//!   NodesPerElement="3">` and one `<Attribute Name AttributeType="Scalar|Vector"
//!   Center="Node|Cell">` per field, each with exactly one `<DataItem>`.
//! - A `DataItem` has `DataType` (`Float` / `Int`), `Precision` (bytes: 8), `Dimensions`
//!   (`"N 3"` or `"N"`) and `Format`. `Format="XML"`: whitespace-separated numbers as the
//!   element text. `Format="Binary"`: the text is a file name holding the raw array (C order);
//!   `Endian="Little"` says the byte order (we always write little-endian).
//! - meshio's reader quirks (5.3.5): it imports `h5py` for every `DataItem`, whatever the
//!   format, so reading any XDMF needs h5py installed; for `Format="Binary"` it passes the file
//!   name to `numpy.fromfile` as is — relative to the *current directory*, not to the `.xdmf`
//!   (ParaView resolves it against the `.xdmf`'s directory) — and ignores `Endian` and `Seek`.
//!   Hence one side file per array (no `Seek`), referenced by bare file name, so the pair can be
//!   moved together; read with meshio from the file's directory.

use super::atomic::{self, Staged};
use super::{xml_escape, Field, FieldData, MeshData, Num};
use crate::MeshError;
use std::borrow::Cow;
use std::io::{self, Write};
use std::path::Path;

/// Where a data item's values go.
enum Heavy {
    /// Inline text.
    Xml,
    /// Raw binary file with this (bare, relative) name.
    Binary(String),
}

/// One array: geometry, topology or a field, with its part name for side files.
struct Item<'a> {
    part: String,
    values: Values<'a>,
    per_entity: usize,
    /// The field and its `Center` (`Node` / `Cell`); `None` for geometry and topology.
    attribute: Option<(&'a Field, &'static str)>,
}

enum Values<'a> {
    F64(Cow<'a, [f64]>),
    I64(Vec<i64>),
}

impl Values<'_> {
    fn len(&self) -> usize {
        match self {
            Values::F64(v) => v.len(),
            Values::I64(v) => v.len(),
        }
    }

    fn data_type(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float",
            Values::I64(_) => "Int",
        }
    }

    fn le_bytes(&self) -> Vec<u8> {
        match self {
            Values::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::I64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }

    fn write_text(&self, w: &mut dyn Write, per_entity: usize) -> io::Result<()> {
        match self {
            Values::F64(v) => rows(w, v.chunks(per_entity), |w, &x| write!(w, "{}", Num(x))),
            Values::I64(v) => rows(w, v.chunks(per_entity), |w, x| write!(w, "{x}")),
        }
    }
}

fn rows<'a, T: 'a>(
    w: &mut dyn Write,
    chunks: impl Iterator<Item = &'a [T]>,
    mut one: impl FnMut(&mut dyn Write, &T) -> io::Result<()>,
) -> io::Result<()> {
    for row in chunks {
        for (k, x) in row.iter().enumerate() {
            if k > 0 {
                w.write_all(b" ")?;
            }
            one(w, x)?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Geometry, topology, then one item per point field and per cell field.
fn items<'a>(data: &MeshData<'a>) -> Vec<Item<'a>> {
    let mesh = data.mesh;
    let geometry: Vec<f64> = mesh.nodes.iter().flat_map(|x| [x.x, x.y, x.z]).collect();
    let topology: Vec<i64> = (mesh.triangles.iter())
        .flat_map(|t| t.map(|i| i as i64))
        .collect();
    let mut items = vec![
        Item {
            part: "geometry".into(),
            values: Values::F64(geometry.into()),
            per_entity: 3,
            attribute: None,
        },
        Item {
            part: "topology".into(),
            values: Values::I64(topology),
            per_entity: 3,
            attribute: None,
        },
    ];
    let fields = (data
        .point
        .iter()
        .enumerate()
        .map(|(k, f)| (f, "Node", format!("point{k}"))))
    .chain(
        data.cell
            .iter()
            .enumerate()
            .map(|(k, f)| (f, "Cell", format!("cell{k}"))),
    );
    for (f, center, part) in fields {
        items.push(Item {
            part,
            values: Values::F64(f.data.flat().into()),
            per_entity: f.data.components(),
            attribute: Some((f, center)),
        });
    }
    items
}

fn write_item(w: &mut dyn Write, item: &Item<'_>, heavy: &Heavy) -> io::Result<()> {
    let n = item.values.len() / item.per_entity;
    let dims = match item.per_entity {
        1 => format!("{n}"),
        c => format!("{n} {c}"),
    };
    write!(
        w,
        "<DataItem DataType=\"{}\" Precision=\"8\" Dimensions=\"{dims}\" ",
        item.values.data_type()
    )?;
    match heavy {
        Heavy::Xml => {
            writeln!(w, "Format=\"XML\">")?;
            item.values.write_text(w, item.per_entity)?;
        }
        Heavy::Binary(file) => {
            write!(
                w,
                "Format=\"Binary\" Endian=\"Little\">{}",
                xml_escape(file)
            )?;
        }
    }
    writeln!(w, "</DataItem>")
}

/// Writes the XML document; `heavy(item)` says where the item's values go.
fn write_xml(
    w: &mut dyn Write,
    num_triangles: usize,
    items: &[Item<'_>],
    heavy: impl Fn(&Item<'_>) -> Heavy,
) -> io::Result<()> {
    let [geometry, topology, attributes @ ..] = items else {
        unreachable!("items() always starts with geometry and topology")
    };
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(w, "<!-- written by memstab (meshes::write) -->")?;
    writeln!(w, "<Xdmf Version=\"3.0\">")?;
    writeln!(w, "<Domain>")?;
    writeln!(w, "<Grid Name=\"mesh\" GridType=\"Uniform\">")?;
    writeln!(w, "<Geometry GeometryType=\"XYZ\">")?;
    write_item(w, geometry, &heavy(geometry))?;
    writeln!(w, "</Geometry>")?;
    writeln!(
        w,
        "<Topology TopologyType=\"Triangle\" NumberOfElements=\"{num_triangles}\" \
         NodesPerElement=\"3\">"
    )?;
    write_item(w, topology, &heavy(topology))?;
    writeln!(w, "</Topology>")?;
    for item in attributes {
        let (f, center) = item
            .attribute
            .expect("fields come after geometry and topology");
        let kind = match f.data {
            FieldData::Scalar(_) => "Scalar",
            FieldData::Vector(_) => "Vector",
        };
        writeln!(
            w,
            "<Attribute Name=\"{}\" AttributeType=\"{kind}\" Center=\"{center}\">",
            xml_escape(&f.name)
        )?;
        write_item(w, item, &heavy(item))?;
        writeln!(w, "</Attribute>")?;
    }
    writeln!(w, "</Grid>")?;
    writeln!(w, "</Domain>")?;
    writeln!(w, "</Xdmf>")
}

/// Writes one self-contained XDMF document with inline (`Format="XML"`) arrays.
pub(crate) fn write_inline(w: &mut dyn Write, data: &MeshData<'_>) -> io::Result<()> {
    write_xml(w, data.mesh.triangles.len(), &items(data), |_| Heavy::Xml)
}

/// Writes `path` and its side files `<stem>.<part>.bin` (`Format="Binary"`). All files are
/// staged first; the side files are renamed into place before the `.xdmf`.
pub(crate) fn write_with_side_files(path: &Path, data: &MeshData<'_>) -> Result<(), MeshError> {
    let stem = (path.file_stem().and_then(|s| s.to_str()))
        .filter(|s| !s.is_empty())
        .ok_or_else(|| {
            MeshError::Invalid(format!(
                "{}: XDMF side files need a UTF-8 file name",
                path.display()
            ))
        })?;
    let side_name = |item: &Item<'_>| format!("{stem}.{}.bin", item.part);
    let items = items(data);
    let mut staged: Vec<Staged> = Vec::with_capacity(items.len() + 1);
    for item in &items {
        let bytes = item.values.le_bytes();
        let side = path.with_file_name(side_name(item));
        staged.push(atomic::stage(&side, |w| w.write_all(&bytes))?);
    }
    staged.push(atomic::stage(path, |w| {
        write_xml(w, data.mesh.triangles.len(), &items, |item| {
            Heavy::Binary(side_name(item))
        })
    })?);
    // The .xdmf is last: it never refers to a side file that is not in place yet.
    for s in staged {
        s.commit()?;
    }
    Ok(())
}
