//! VTK XML unstructured grid (`.vtu`), as [`crate::write`] writes it (see `write/vtu.rs` and
//! "VTK File Formats", section "XML File Formats").
//!
//! The document is parsed with quick-xml into a small element tree (depth-limited, so that a
//! hostile file cannot exhaust the stack), then read as:
//! - `<VTKFile type="UnstructuredGrid">` with `byte_order` (`LittleEndian`, the default, or
//!   `BigEndian`) and `header_type` (`UInt32`, VTK's default, or `UInt64`); a `compressor` is
//!   refused (our writer does not compress).
//! - exactly one `<Piece NumberOfPoints NumberOfCells>` holding `<Points>` (one 3-component
//!   array), `<Cells>` (`connectivity`, `offsets`, `types`) and optionally `<PointData>`, whose
//!   scalar arrays named `set_<name>` are the node sets; `<CellData>` is not read.
//! - each `<DataArray>` is `format="ascii"` (whitespace-separated numbers) or
//!   `format="binary"` (base64 of one block: a `header_type` byte count, then the raw values in
//!   `byte_order`); `format="appended"` is refused. Any VTK scalar type is accepted; integer
//!   arrays (cells) must hold integers, and cell types must all be `VTK_TRIANGLE` (5).
//!
//! Errors name the element or data array, e.g. `DataArray "offsets": …`, or the line of an XML
//! syntax error.

use super::{distinct, finite_node, Parts};
use crate::mesh::{Mesh, Vec3};
use base64::Engine;
use quick_xml::events::{BytesStart, Event};
use quick_xml::{Reader, XmlVersion};
use std::collections::BTreeMap;

/// `VTK_TRIANGLE` in VTK's cell type enumeration.
const VTK_TRIANGLE: i64 = 5;

/// Deeper nesting than this is not a VTU file (ours nests 6 deep).
const MAX_DEPTH: usize = 32;

/// Parses a whole `.vtu` text.
pub(super) fn parse(text: &str) -> Result<Mesh, String> {
    let (root, layout) = document(text)?;
    mesh_of(&root, layout)
}

/// Parses a whole `.vtu` text: the mesh, and the 3-component point field `field` (as the
/// state writers store a displacement or a mode).
pub(super) fn parse_with_field(text: &str, field: &str) -> Result<(Mesh, Vec<[f64; 3]>), String> {
    let (root, layout) = document(text)?;
    let mesh = mesh_of(&root, layout)?;
    let piece = root.only_child("UnstructuredGrid")?.only_child("Piece")?;
    let points = piece.count_attr("NumberOfPoints")?;
    let array = piece
        .children("PointData")
        .flat_map(|d| d.children("DataArray"))
        .find(|a| a.attrs.get("Name").is_some_and(|n| n == field))
        .ok_or_else(|| format!("<PointData> has no DataArray \"{field}\""))?;
    let components = array.count_attr("NumberOfComponents").unwrap_or(1);
    if components != 3 {
        return Err(format!(
            "{}: {components} components, expected 3",
            array.label()
        ));
    }
    let values = read_floats(array, layout, 3, points)?;
    let mut out = Vec::with_capacity(points);
    for (i, c) in values.chunks_exact(3).enumerate() {
        if !c.iter().all(|v| v.is_finite()) {
            return Err(format!("{}: point {i} is not finite", array.label()));
        }
        out.push([c[0], c[1], c[2]]);
    }
    Ok((mesh, out))
}

/// The document's root `<VTKFile>` and its binary layout.
fn document(text: &str) -> Result<(Element, Layout), String> {
    let root = parse_xml(text)?;
    if root.name != "VTKFile" {
        return Err(format!(
            "the root element is <{}>, expected <VTKFile>",
            root.name
        ));
    }
    match root.attrs.get("type").map(String::as_str) {
        Some("UnstructuredGrid") => {}
        Some(other) => {
            return Err(format!(
                "<VTKFile type=\"{other}\">: only UnstructuredGrid files are read"
            ))
        }
        None => return Err("<VTKFile> has no type attribute".into()),
    }
    if let Some(c) = root.attrs.get("compressor") {
        return Err(format!(
            "<VTKFile compressor=\"{c}\">: compressed data is not supported"
        ));
    }
    let layout = Layout {
        big_endian: match root.attrs.get("byte_order").map(String::as_str) {
            None | Some("LittleEndian") => false,
            Some("BigEndian") => true,
            Some(other) => return Err(format!("<VTKFile byte_order=\"{other}\"> is not known")),
        },
        header_bytes: match root.attrs.get("header_type").map(String::as_str) {
            None | Some("UInt32") => 4,
            Some("UInt64") => 8,
            Some(other) => {
                return Err(format!(
                    "<VTKFile header_type=\"{other}\">: expected UInt32 or UInt64"
                ))
            }
        },
    };
    Ok((root, layout))
}

/// The mesh of a parsed document.
fn mesh_of(root: &Element, layout: Layout) -> Result<Mesh, String> {
    let grid = root.only_child("UnstructuredGrid")?;
    let piece = grid.only_child("Piece")?;
    let points = piece.count_attr("NumberOfPoints")?;
    let cells = piece.count_attr("NumberOfCells")?;

    let mut parts = Parts::default();
    let xyz = piece.only_child("Points")?.only_child("DataArray")?;
    let coords = read_floats(xyz, layout, 3, points)?;
    for (i, c) in coords.chunks_exact(3).enumerate() {
        let x = Vec3::new(c[0], c[1], c[2]);
        finite_node(&x, &format!("{}, point {i}", xyz.label()))?;
        parts.nodes.push(x);
    }

    let cell_part = piece.only_child("Cells")?;
    let array = |name: &str| cell_part.data_array(name);
    let connectivity = read_ints(array("connectivity")?, layout)?;
    let offsets = read_ints(array("offsets")?, layout)?;
    let types = read_ints(array("types")?, layout)?;
    for (what, values) in [("offsets", &offsets), ("types", &types)] {
        if values.len() != cells {
            return Err(format!(
                "DataArray \"{what}\": {} values, NumberOfCells is {cells}",
                values.len()
            ));
        }
    }
    let mut begin = 0i64;
    for (k, (&end, &kind)) in offsets.iter().zip(&types).enumerate() {
        let place = format!("cell {k}");
        if kind != VTK_TRIANGLE {
            return Err(format!(
                "DataArray \"types\": {place} has VTK type {kind}{}; only triangles (type 5) \
                 are read",
                cell_name(kind)
            ));
        }
        if end != begin + 3 {
            return Err(format!(
                "DataArray \"offsets\": {place} ends at {end}, expected {} (3 nodes after {begin})",
                begin + 3
            ));
        }
        let mut tri = [0usize; 3];
        for (slot, j) in tri.iter_mut().zip(begin..end) {
            let node = usize::try_from(j)
                .ok()
                .and_then(|j| connectivity.get(j))
                .ok_or_else(|| {
                    format!(
                        "DataArray \"connectivity\": {} values, too few for {place} (offset {end})",
                        connectivity.len()
                    )
                })?;
            *slot = usize::try_from(*node)
                .ok()
                .filter(|&i| i < points)
                .ok_or_else(|| {
                    format!(
                        "DataArray \"connectivity\": {place} refers to point {node}, \
                         NumberOfPoints is {points}"
                    )
                })?;
        }
        distinct(&tri, &format!("DataArray \"connectivity\": {place}"))?;
        parts.triangles.push(tri);
        begin = end;
    }
    if usize::try_from(begin).ok() != Some(connectivity.len()) {
        return Err(format!(
            "DataArray \"connectivity\": {} values, the offsets use {begin}",
            connectivity.len()
        ));
    }

    if let Some(point_data) = piece.children("PointData").next() {
        for array in point_data.children("DataArray") {
            let name = array.attrs.get("Name").cloned().unwrap_or_default();
            if name.starts_with(super::NODE_SET_PREFIX) {
                let values = read_floats(array, layout, 1, points)?;
                parts.add_point_field(&name, &array.label(), values)?;
            }
        }
    }
    parts.into_mesh()
}

/// How binary arrays are laid out (from the `<VTKFile>` attributes).
#[derive(Clone, Copy)]
struct Layout {
    big_endian: bool,
    header_bytes: usize,
}

/// An XML element: name, attributes, child elements and its own text.
#[derive(Debug, Default)]
struct Element {
    name: String,
    attrs: BTreeMap<String, String>,
    children: Vec<Element>,
    text: String,
}

impl Element {
    fn children<'a, 'n>(
        &'a self,
        name: &'n str,
    ) -> impl Iterator<Item = &'a Element> + use<'a, 'n> {
        self.children.iter().filter(move |c| c.name == name)
    }

    /// The one child `<name>`; none or several is an error.
    fn only_child(&self, name: &str) -> Result<&Element, String> {
        let mut it = self.children(name);
        match (it.next(), it.next()) {
            (Some(c), None) => Ok(c),
            (None, _) => Err(format!("<{}> has no <{name}>", self.name)),
            (Some(_), Some(_)) => Err(format!(
                "<{}> has {} <{name}> elements; only one is read",
                self.name,
                self.children(name).count()
            )),
        }
    }

    /// The `<DataArray Name="name">` child.
    fn data_array(&self, name: &str) -> Result<&Element, String> {
        self.children("DataArray")
            .find(|a| a.attrs.get("Name").is_some_and(|n| n == name))
            .ok_or_else(|| format!("<{}> has no DataArray \"{name}\"", self.name))
    }

    /// A non-negative integer attribute such as `NumberOfPoints`.
    fn count_attr(&self, key: &str) -> Result<usize, String> {
        let value = self
            .attrs
            .get(key)
            .ok_or_else(|| format!("<{}> has no {key}", self.name))?;
        value.trim().parse().map_err(|_| {
            format!(
                "<{} {key}=\"{value}\">: expected a non-negative integer",
                self.name
            )
        })
    }

    /// How a data array is named in messages: `DataArray "Points"`.
    fn label(&self) -> String {
        match self.attrs.get("Name") {
            Some(n) => format!("{} \"{n}\"", self.name),
            None => format!("{} without a Name", self.name),
        }
    }
}

/// Parses the document into its root element.
fn parse_xml(text: &str) -> Result<Element, String> {
    let mut reader = Reader::from_str(text);
    let line_of = |pos: u64| {
        let pos = usize::try_from(pos).unwrap_or(usize::MAX).min(text.len());
        text.as_bytes()[..pos]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    };
    let mut stack = vec![Element::default()];
    loop {
        let event = reader.read_event().map_err(|e| {
            format!(
                "line {}: not well-formed XML: {e}",
                line_of(reader.error_position())
            )
        })?;
        let open = |e: &BytesStart<'_>| {
            element(e, reader.decoder())
                .map_err(|m| format!("line {}: {m}", line_of(reader.buffer_position())))
        };
        match event {
            Event::Start(e) => {
                if stack.len() > MAX_DEPTH {
                    return Err(format!(
                        "line {}: elements nest deeper than {MAX_DEPTH} levels",
                        line_of(reader.buffer_position())
                    ));
                }
                let el = open(&e)?;
                stack.push(el);
            }
            Event::Empty(e) => {
                let el = open(&e)?;
                if let Some(top) = stack.last_mut() {
                    top.children.push(el);
                }
            }
            Event::End(_) => {
                // quick-xml checks that end tags match start tags.
                match (stack.pop(), stack.last_mut()) {
                    (Some(done), Some(parent)) => parent.children.push(done),
                    _ => {
                        return Err(format!(
                            "line {}: an end tag without a start tag",
                            line_of(reader.buffer_position())
                        ))
                    }
                }
            }
            Event::Text(t) => {
                let s = t.decode().map_err(|e| format!("text is not UTF-8: {e}"))?;
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&s);
                }
            }
            Event::CData(t) => {
                let s = t.decode().map_err(|e| format!("CDATA is not UTF-8: {e}"))?;
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&s);
                }
            }
            Event::GeneralRef(r) => {
                // Entities never occur in numeric data; keep them so that parsing names them.
                let s = r.decode().map_err(|e| format!("text is not UTF-8: {e}"))?;
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&format!("&{s};"));
                }
            }
            Event::Eof => break,
            Event::Comment(_) | Event::Decl(_) | Event::PI(_) | Event::DocType(_) => {}
        }
    }
    let mut doc = match stack.pop() {
        Some(doc) if stack.is_empty() => doc,
        _ => return Err("the file ends inside an element (truncated?)".into()),
    };
    match doc.children.len() {
        1 => Ok(doc.children.remove(0)),
        0 => Err("the file has no XML element".into()),
        n => Err(format!(
            "the file has {n} root elements, expected one <VTKFile>"
        )),
    }
}

/// An element with its (unescaped) attributes.
fn element(e: &BytesStart<'_>, decoder: quick_xml::encoding::Decoder) -> Result<Element, String> {
    let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    let mut attrs = BTreeMap::new();
    for a in e.attributes() {
        let a = a.map_err(|err| format!("<{name}>: bad attribute: {err}"))?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let value = a
            .decoded_and_normalized_value(XmlVersion::Implicit1_0, decoder)
            .map_err(|err| format!("<{name} {key}>: bad attribute value: {err}"))?;
        if attrs.insert(key.clone(), value.into_owned()).is_some() {
            return Err(format!("<{name}> has the attribute {key} twice"));
        }
    }
    Ok(Element {
        name,
        attrs,
        ..Element::default()
    })
}

/// VTK scalar types: (byte size, is a float type).
fn scalar_type(name: &str) -> Option<(usize, bool)> {
    Some(match name {
        "Float32" => (4, true),
        "Float64" => (8, true),
        "Int8" | "UInt8" => (1, false),
        "Int16" | "UInt16" => (2, false),
        "Int32" | "UInt32" => (4, false),
        "Int64" | "UInt64" => (8, false),
        _ => return None,
    })
}

/// The values of a data array as numbers: floats as they are, integers converted exactly.
enum Values {
    Float(Vec<f64>),
    Int(Vec<i64>),
}

/// Decodes a `<DataArray>` with `components` per entity (checked against
/// `NumberOfComponents`, default 1).
fn decode(array: &Element, layout: Layout, components: usize) -> Result<Values, String> {
    let label = array.label();
    let type_name = array
        .attrs
        .get("type")
        .ok_or_else(|| format!("{label} has no type"))?;
    let (size, float) =
        scalar_type(type_name).ok_or_else(|| format!("{label}: unknown type \"{type_name}\""))?;
    let given = match array.attrs.get("NumberOfComponents") {
        None => 1,
        Some(c) => c
            .trim()
            .parse()
            .map_err(|_| format!("{label}: NumberOfComponents=\"{c}\" is not a count"))?,
    };
    if given != components {
        return Err(format!(
            "{label}: NumberOfComponents is {given}, expected {components}"
        ));
    }
    let format = array.attrs.get("format").map(String::as_str);
    match format {
        Some("ascii") => {
            let words = array.text.split_ascii_whitespace().enumerate();
            if float {
                words
                    .map(|(k, w)| {
                        w.parse::<f64>()
                            .map_err(|_| format!("{label}: value {k} is not a number: \"{w}\""))
                    })
                    .collect::<Result<_, _>>()
                    .map(Values::Float)
            } else {
                words
                    .map(|(k, w)| {
                        w.parse::<i64>()
                            .map_err(|_| format!("{label}: value {k} is not an integer: \"{w}\""))
                    })
                    .collect::<Result<_, _>>()
                    .map(Values::Int)
            }
        }
        Some("binary") => {
            let compact: String = array
                .text
                .chars()
                .filter(|c| !c.is_ascii_whitespace())
                .collect();
            let bytes = base64::engine::general_purpose::STANDARD
                .decode(compact.as_bytes())
                .map_err(|e| format!("{label}: bad base64: {e}"))?;
            let h = layout.header_bytes;
            if bytes.len() < h {
                return Err(format!(
                    "{label}: {} bytes, too short for the {h}-byte header",
                    bytes.len()
                ));
            }
            let (header, data) = bytes.split_at(h);
            let count = unsigned(header, layout.big_endian);
            if count != data.len() as u64 {
                return Err(format!(
                    "{label}: the header announces {count} bytes of data, the block holds {}",
                    data.len()
                ));
            }
            if data.len() % size != 0 {
                return Err(format!(
                    "{label}: {} bytes of data is not a whole number of {type_name} values",
                    data.len()
                ));
            }
            let chunks = data.chunks_exact(size);
            let be = layout.big_endian;
            Ok(match type_name.as_str() {
                "Float32" => Values::Float(
                    chunks
                        .map(|c| f32::from_bits(unsigned(c, be) as u32) as f64)
                        .collect(),
                ),
                "Float64" => {
                    Values::Float(chunks.map(|c| f64::from_bits(unsigned(c, be))).collect())
                }
                t if t.starts_with("UInt") => Values::Int(
                    chunks
                        .enumerate()
                        .map(|(k, c)| {
                            i64::try_from(unsigned(c, be))
                                .map_err(|_| format!("{label}: value {k} is too large"))
                        })
                        .collect::<Result<_, _>>()?,
                ),
                _ => Values::Int(chunks.map(|c| signed(c, be)).collect()),
            })
        }
        Some("appended") => Err(format!(
            "{label}: format=\"appended\" is not supported; write ascii or inline base64 \
             (binary) data"
        )),
        Some(other) => Err(format!("{label}: unknown format \"{other}\"")),
        None => Err(format!("{label} has no format")),
    }
}

/// An unsigned integer of 1–8 bytes in the given byte order.
fn unsigned(bytes: &[u8], big_endian: bool) -> u64 {
    let fold = |acc: u64, &b: &u8| (acc << 8) | u64::from(b);
    if big_endian {
        bytes.iter().fold(0, fold)
    } else {
        bytes.iter().rev().fold(0, fold)
    }
}

/// A two's-complement signed integer of 1–8 bytes in the given byte order.
fn signed(bytes: &[u8], big_endian: bool) -> i64 {
    let bits = 8 * bytes.len() as u32;
    let u = unsigned(bytes, big_endian);
    // Sign-extend from `bits` to 64.
    ((u << (64 - bits)) as i64) >> (64 - bits)
}

/// A float array of `count` entities with `components` each.
fn read_floats(
    array: &Element,
    layout: Layout,
    components: usize,
    count: usize,
) -> Result<Vec<f64>, String> {
    let values = match decode(array, layout, components)? {
        Values::Float(v) => v,
        // Exact for the integers a node set (or a coordinate) can sensibly hold.
        Values::Int(v) => v.into_iter().map(|x| x as f64).collect(),
    };
    if Some(values.len()) != count.checked_mul(components) {
        return Err(format!(
            "{}: {} values, expected {count} x {components} (NumberOfPoints x components)",
            array.label(),
            values.len()
        ));
    }
    Ok(values)
}

/// An integer array (cells).
fn read_ints(array: &Element, layout: Layout) -> Result<Vec<i64>, String> {
    match decode(array, layout, 1)? {
        Values::Int(v) => Ok(v),
        Values::Float(_) => Err(format!(
            "{}: expected an integer type, got {}",
            array.label(),
            array.attrs.get("type").map_or("?", String::as_str)
        )),
    }
}

/// A few VTK cell types by name, for messages.
fn cell_name(kind: i64) -> &'static str {
    match kind {
        1 => " (vertex)",
        3 => " (line)",
        7 => " (polygon)",
        9 => " (quad)",
        10 => " (tetra)",
        12 => " (hexahedron)",
        22 => " (quadratic triangle)",
        _ => "",
    }
}
