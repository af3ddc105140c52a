//! Writers without Python: validation (nothing written on error), whole-file replacement, and
//! structure and exact values of every format, read back with an XML parser (quick-xml) or by
//! hand. The meshio round trip is `scripts/meshio_roundtrip.sh`.

use base64::Engine;
use meshes::write::{write_mesh, write_pvd, FieldData, Fields, Format};
use meshes::{Mesh, MeshError, Vec3};
use quick_xml::events::{BytesStart, Event};
use quick_xml::{Reader, XmlVersion};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

const ALL: [(Format, &str); 5] = [
    (Format::VtuAscii, "m.vtu"),
    (Format::VtuBase64, "m.vtu"),
    (Format::Msh41, "m.msh"),
    (Format::Xdmf, "m.xdmf"),
    (Format::XdmfBinary, "m.xdmf"),
];

/// A square pyramid without its base: 5 nodes, 4 triangles, node set `rim` = the 4 base nodes.
fn pyramid() -> Mesh {
    let nodes = vec![
        Vec3::new(0.0, 0.0, 1.0 / 3.0),
        Vec3::new(1.0, -0.0, 1e-300),
        Vec3::new(0.1 + 0.2, 1.0, 0.0),
        Vec3::new(-1.0, 5e-324, 0.0),
        Vec3::new(0.0, -1e300, 0.0),
    ];
    let triangles = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
    let mut mesh = Mesh::new(nodes, triangles).unwrap();
    mesh.set_boundary("rim", vec![1, 2, 3, 4]);
    mesh
}

fn fields() -> Fields {
    Fields::new()
        .point_scalar("w", [0.5, -0.0, f64::MAX, 5e-324, -1.0 / 7.0])
        .point_vector(
            "u",
            (0..5).map(|k| Vec3::new(k as f64, 0.1 * k as f64, -1e-300)),
        )
        .cell_scalar("p & <q>", [1.0, 2.0, 3.0, 4.0])
        .cell_vector("n", [[0.0, 0.0, 1.0]; 4])
}

/// Every array a file must hold, by name: `Points`, `connectivity`, then the fields
/// (node-set fields included), values flattened.
fn expected_arrays(mesh: &Mesh, fields: &Fields) -> BTreeMap<String, Vec<f64>> {
    let mut out = BTreeMap::new();
    let pts = mesh.nodes.iter().flat_map(|x| [x.x, x.y, x.z]).collect();
    out.insert("Points".to_string(), pts);
    let conn = (mesh.triangles.iter())
        .flat_map(|t| t.map(|i| i as f64))
        .collect();
    out.insert("connectivity".to_string(), conn);
    for f in fields.point.iter().chain(&fields.cell) {
        out.insert(f.name.clone(), f.data.flat().to_vec());
    }
    out.insert("set_rim".to_string(), vec![0.0, 1.0, 1.0, 1.0, 1.0]);
    out
}

fn assert_bits(what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(
            g.to_bits(),
            w.to_bits(),
            "{what}[{k}]: got {g:e}, want {w:e}"
        );
    }
}

fn numbers(text: &str) -> Vec<f64> {
    text.split_whitespace()
        .map(|t| t.parse().unwrap_or_else(|e| panic!("{t:?}: {e}")))
        .collect()
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

// ---------------------------------------------------------------------------------------------
// A minimal DOM on top of quick-xml: parsing fails on anything not well-formed.

#[derive(Debug, Default)]
struct Node {
    name: String,
    attrs: BTreeMap<String, String>,
    children: Vec<Node>,
    text: String,
}

impl Node {
    fn attr(&self, key: &str) -> &str {
        self.attrs
            .get(key)
            .unwrap_or_else(|| panic!("<{}> has no attribute {key}", self.name))
    }

    fn child(&self, name: &str) -> &Node {
        let mut it = self.children.iter().filter(|c| c.name == name);
        let c = it
            .next()
            .unwrap_or_else(|| panic!("<{}> has no <{name}>", self.name));
        assert!(it.next().is_none(), "<{}> has several <{name}>", self.name);
        c
    }

    fn descendants<'a>(&'a self, name: &str, out: &mut Vec<&'a Node>) {
        for c in &self.children {
            if c.name == name {
                out.push(c);
            }
            c.descendants(name, out);
        }
    }

    fn all(&self, name: &str) -> Vec<&Node> {
        let mut out = Vec::new();
        self.descendants(name, &mut out);
        out
    }
}

fn element(e: &BytesStart<'_>) -> Node {
    let mut attrs = BTreeMap::new();
    for a in e.attributes() {
        let a = a.expect("well-formed attribute");
        let key = String::from_utf8(a.key.as_ref().to_vec()).unwrap();
        let value = a.normalized_value(XmlVersion::Explicit1_0).unwrap();
        assert!(
            attrs.insert(key, value.into_owned()).is_none(),
            "duplicate attribute"
        );
    }
    Node {
        name: String::from_utf8(e.name().as_ref().to_vec()).unwrap(),
        attrs,
        ..Node::default()
    }
}

/// Parses a whole document and returns its root element.
fn parse_xml(text: &str) -> Node {
    let mut reader = Reader::from_str(text);
    let mut stack = vec![Node::default()];
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Start(e) => stack.push(element(&e)),
            Event::Empty(e) => stack.last_mut().unwrap().children.push(element(&e)),
            Event::End(_) => {
                let done = stack.pop().unwrap();
                stack.last_mut().expect("balanced tags").children.push(done);
            }
            Event::Text(t) => stack.last_mut().unwrap().text += &t.decode().unwrap(),
            Event::GeneralRef(r) => panic!("unexpected entity &{:?}; in text", r),
            Event::CData(_) | Event::DocType(_) => panic!("unexpected CDATA / DOCTYPE"),
            Event::Eof => break,
            Event::Comment(_) | Event::Decl(_) | Event::PI(_) => {}
        }
    }
    assert_eq!(stack.len(), 1, "unclosed elements at the end");
    let mut doc = stack.pop().unwrap();
    assert_eq!(doc.children.len(), 1, "exactly one root element");
    assert!(doc.text.trim().is_empty(), "text outside the root");
    doc.children.pop().unwrap()
}

// ---------------------------------------------------------------------------------------------
// Format selection and validation.

#[test]
fn formats_come_from_extensions() {
    let f = |p: &str, b| Format::from_path(Path::new(p), b).unwrap();
    assert_eq!(f("a/b.vtu", false), Format::VtuAscii);
    assert_eq!(f("b.VTU", true), Format::VtuBase64);
    assert_eq!(f("b.msh", false), Format::Msh41);
    assert_eq!(f("b.msh", true), Format::Msh41);
    assert_eq!(f("b.xdmf", false), Format::Xdmf);
    assert_eq!(f("b.xmf", true), Format::XdmfBinary);
}

#[test]
fn unknown_extension_is_an_error_naming_it() {
    for (p, needle) in [
        ("mesh.obj", ".obj"),
        ("mesh.vtk", ".vtk"),
        ("mesh", "no file extension"),
    ] {
        match Format::from_path(Path::new(p), false) {
            Err(MeshError::Invalid(msg)) => assert!(msg.contains(needle), "{msg}"),
            other => panic!("{p}: {other:?}"),
        }
    }
}

fn expect_invalid(r: Result<(), MeshError>, needle: &str) {
    match r {
        Err(MeshError::Invalid(msg)) => assert!(msg.contains(needle), "{msg:?} lacks {needle:?}"),
        other => panic!("expected Invalid({needle}), got {other:?}"),
    }
}

#[test]
fn wrong_field_length_writes_nothing() {
    let mesh = pyramid();
    let cases = [
        (
            fields().point_scalar("short", [1.0; 4]),
            "\"short\" has 4 values",
        ),
        (
            fields().cell_vector("long", [[1.0; 3]; 5]),
            "\"long\" has 5 values",
        ),
    ];
    for (fields, needle) in cases {
        for (format, name) in ALL {
            let dir = tempfile::tempdir().unwrap();
            expect_invalid(
                write_mesh(&dir.path().join(name), &mesh, &fields, format),
                needle,
            );
            assert!(
                files_in(dir.path()).is_empty(),
                "{format:?} left files behind"
            );
        }
    }
}

#[test]
fn non_finite_value_keeps_the_existing_file() {
    let mesh = pyramid();
    let cases = [
        (
            fields().point_scalar("bad", [1.0, 2.0, f64::NAN, 4.0, 5.0]),
            "\"bad\" has a non-finite value NaN at entry 2",
        ),
        (
            fields().cell_vector(
                "dir",
                [
                    [0.0, 0.0, 1.0],
                    [0.0, f64::INFINITY, 0.0],
                    [0.0; 3],
                    [0.0; 3],
                ],
            ),
            "\"dir\" has a non-finite value inf at entry 1, component 1",
        ),
    ];
    for (fields, needle) in cases {
        for (format, name) in ALL {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join(name);
            fs::write(&path, "previous content").unwrap();
            expect_invalid(write_mesh(&path, &mesh, &fields, format), needle);
            assert_eq!(fs::read_to_string(&path).unwrap(), "previous content");
            assert_eq!(files_in(dir.path()), vec![name.to_string()], "{format:?}");
        }
    }
    let mut mesh = pyramid();
    mesh.nodes[3].y = f64::NEG_INFINITY;
    let dir = tempfile::tempdir().unwrap();
    expect_invalid(
        write_mesh(
            &dir.path().join("m.vtu"),
            &mesh,
            &fields(),
            Format::VtuAscii,
        ),
        "node 3 has a non-finite coordinate 1",
    );
}

#[test]
fn bad_names_and_references_are_errors() {
    let mesh = pyramid();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.msh");
    let write = |f: &Fields, m: &Mesh| write_mesh(&path, m, f, Format::Msh41);
    for name in ["", "a\"b", " x", "x\n", "tab\there"] {
        let f = Fields::new().cell_scalar(name, [0.0; 4]);
        expect_invalid(write(&f, &mesh), "cell field name");
    }
    let twice = Fields::new()
        .cell_scalar("a", [0.0; 4])
        .cell_vector("a", [[0.0; 3]; 4]);
    expect_invalid(write(&twice, &mesh), "two cell fields are named \"a\"");
    let clash = Fields::new().point_scalar("set_rim", [0.0; 5]);
    expect_invalid(
        write(&clash, &mesh),
        "two point fields are named \"set_rim\"",
    );
    let mut m = pyramid();
    m.boundaries.insert("cut".into(), vec![2, 9]);
    expect_invalid(write(&fields(), &m), "node set \"cut\" refers to node 9");
    let mut m = pyramid();
    m.triangles[2][1] = 5;
    expect_invalid(write(&fields(), &m), "triangle 2 refers to node 5");
    let empty = Mesh::new(vec![], vec![]).unwrap();
    expect_invalid(write(&Fields::new(), &empty), "0 nodes and 0 triangles");
    assert!(files_in(dir.path()).is_empty());
}

#[test]
fn missing_directory_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no/such/dir/m.vtu");
    match write_mesh(&path, &pyramid(), &fields(), Format::VtuAscii) {
        Err(MeshError::Io { path: p, .. }) => assert_eq!(p, path),
        other => panic!("{other:?}"),
    }
}

#[test]
fn rewriting_replaces_the_whole_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.vtu");
    let mesh = pyramid();
    write_mesh(&path, &mesh, &fields(), Format::VtuAscii).unwrap();
    let first = fs::read_to_string(&path).unwrap();
    write_mesh(&path, &mesh, &Fields::new(), Format::VtuAscii).unwrap();
    let second = fs::read_to_string(&path).unwrap();
    assert!(second.len() < first.len());
    parse_xml(&second);
    assert_eq!(files_in(dir.path()), vec!["m.vtu".to_string()]);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o644);
    }
}

// ---------------------------------------------------------------------------------------------
// Structure and exact values, format by format.

fn write_one(format: Format, name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_mesh(&path, &pyramid(), &fields(), format).unwrap();
    (dir, path)
}

/// Checks a parsed VTU against the test mesh; `decode` turns a DataArray into f64 values.
fn check_vtu(root: &Node, decode: impl Fn(&Node) -> Vec<f64>) {
    assert_eq!(root.name, "VTKFile");
    assert_eq!(root.attr("type"), "UnstructuredGrid");
    assert_eq!(root.attr("byte_order"), "LittleEndian");
    assert_eq!(root.attr("header_type"), "UInt64");
    let piece = root.child("UnstructuredGrid").child("Piece");
    assert_eq!(piece.attr("NumberOfPoints"), "5");
    assert_eq!(piece.attr("NumberOfCells"), "4");
    let want = expected_arrays(&pyramid(), &fields());
    let mut seen = Vec::new();
    for da in piece.all("DataArray") {
        let name = da.attr("Name");
        let values = decode(da);
        match name {
            "offsets" => assert_eq!(values, [3.0, 6.0, 9.0, 12.0]),
            "types" => assert_eq!(values, [5.0; 4]),
            _ => assert_bits(name, &values, &want[name]),
        }
        let comps = da
            .attrs
            .get("NumberOfComponents")
            .map_or("1", String::as_str);
        let want_comps = if ["Points", "u", "n"].contains(&name) {
            "3"
        } else {
            "1"
        };
        assert_eq!(comps, want_comps, "{name}");
        seen.push(name.to_string());
    }
    let expect = [
        "Points",
        "connectivity",
        "offsets",
        "types",
        "w",
        "u",
        "set_rim",
        "p & <q>",
        "n",
    ];
    assert_eq!(seen, expect);
    let names = |n: &Node| -> Vec<String> {
        n.children
            .iter()
            .map(|c| c.attr("Name").to_string())
            .collect()
    };
    assert_eq!(names(piece.child("PointData")), ["w", "u", "set_rim"]);
    assert_eq!(names(piece.child("CellData")), ["p & <q>", "n"]);
}

#[test]
fn vtu_ascii_parses_and_holds_the_exact_values() {
    let (_dir, path) = write_one(Format::VtuAscii, "m.vtu");
    let root = parse_xml(&fs::read_to_string(&path).unwrap());
    check_vtu(&root, |da| {
        assert_eq!(da.attr("format"), "ascii");
        numbers(&da.text)
    });
}

#[test]
fn vtu_base64_decodes_back_to_the_same_bytes() {
    let (_dir, path) = write_one(Format::VtuBase64, "m.vtu");
    let root = parse_xml(&fs::read_to_string(&path).unwrap());
    check_vtu(&root, |da| {
        assert_eq!(da.attr("format"), "binary");
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(da.text.trim())
            .expect("valid base64");
        let (header, data) = bytes.split_at(8);
        let n = u64::from_le_bytes(header.try_into().unwrap());
        assert_eq!(
            n as usize,
            data.len(),
            "UInt64 header = number of data bytes"
        );
        match da.attr("type") {
            "Float64" => data
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
                .collect(),
            "Int64" => data
                .chunks_exact(8)
                .map(|b| i64::from_le_bytes(b.try_into().unwrap()) as f64)
                .collect(),
            "UInt8" => data.iter().map(|&b| b as f64).collect(),
            t => panic!("unexpected type {t}"),
        }
    });
}

/// Checks a parsed XDMF against the test mesh; `values` reads a DataItem.
fn check_xdmf(root: &Node, values: impl Fn(&Node) -> Vec<f64>) {
    assert_eq!(root.name, "Xdmf");
    assert_eq!(root.attr("Version"), "3.0");
    let grid = root.child("Domain").child("Grid");
    let geometry = grid.child("Geometry");
    assert_eq!(geometry.attr("GeometryType"), "XYZ");
    let topology = grid.child("Topology");
    assert_eq!(topology.attr("TopologyType"), "Triangle");
    assert_eq!(topology.attr("NumberOfElements"), "4");
    let want = expected_arrays(&pyramid(), &fields());
    let item = |n: &Node, dims: &str, ty: &str| -> Vec<f64> {
        let d = n.child("DataItem");
        assert_eq!(d.attr("Dimensions"), dims);
        assert_eq!(d.attr("DataType"), ty);
        assert_eq!(d.attr("Precision"), "8");
        values(d)
    };
    assert_bits("geometry", &item(geometry, "5 3", "Float"), &want["Points"]);
    assert_bits(
        "topology",
        &item(topology, "4 3", "Int"),
        &want["connectivity"],
    );
    let attrs = grid.all("Attribute");
    let got: Vec<(&str, &str, &str)> = (attrs.iter())
        .map(|a| (a.attr("Name"), a.attr("Center"), a.attr("AttributeType")))
        .collect();
    assert_eq!(
        got,
        [
            ("w", "Node", "Scalar"),
            ("u", "Node", "Vector"),
            ("set_rim", "Node", "Scalar"),
            ("p & <q>", "Cell", "Scalar"),
            ("n", "Cell", "Vector"),
        ]
    );
    for a in attrs {
        let name = a.attr("Name");
        let n = if a.attr("Center") == "Node" { 5 } else { 4 };
        let dims = match a.attr("AttributeType") {
            "Vector" => format!("{n} 3"),
            _ => format!("{n}"),
        };
        assert_bits(name, &item(a, &dims, "Float"), &want[name]);
    }
}

#[test]
fn xdmf_inline_parses_and_holds_the_exact_values() {
    let (dir, path) = write_one(Format::Xdmf, "m.xdmf");
    assert_eq!(files_in(dir.path()), ["m.xdmf"]);
    let root = parse_xml(&fs::read_to_string(&path).unwrap());
    check_xdmf(&root, |d| {
        assert_eq!(d.attr("Format"), "XML");
        numbers(&d.text)
    });
}

#[test]
fn xdmf_side_files_hold_little_endian_arrays() {
    let (dir, path) = write_one(Format::XdmfBinary, "m.xdmf");
    let expect_files = [
        "m.cell0.bin",
        "m.cell1.bin",
        "m.geometry.bin",
        "m.point0.bin",
        "m.point1.bin",
        "m.point2.bin",
        "m.topology.bin",
        "m.xdmf",
    ];
    assert_eq!(files_in(dir.path()), expect_files);
    let root = parse_xml(&fs::read_to_string(&path).unwrap());
    check_xdmf(&root, |d| {
        assert_eq!(d.attr("Format"), "Binary");
        assert_eq!(d.attr("Endian"), "Little");
        let file = d.text.trim();
        assert!(
            !file.contains('/'),
            "side files are referenced by bare name: {file}"
        );
        let bytes = fs::read(dir.path().join(file)).unwrap();
        let words = bytes.chunks_exact(8).map(|b| b.try_into().unwrap());
        match d.attr("DataType") {
            "Float" => words.map(f64::from_le_bytes).collect(),
            "Int" => words.map(|w| i64::from_le_bytes(w) as f64).collect(),
            t => panic!("{t}"),
        }
    });
}

#[test]
fn gmsh_sections_and_values() {
    let (_dir, path) = write_one(Format::Msh41, "m.msh");
    let text = fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let sections: Vec<&str> = (lines.iter().copied())
        .filter(|l| l.starts_with('$') && !l.starts_with("$End"))
        .collect();
    let expect = [
        "$MeshFormat",
        "$Entities",
        "$Nodes",
        "$Elements",
        "$NodeData",
        "$NodeData",
        "$NodeData",
        "$ElementData",
        "$ElementData",
    ];
    assert_eq!(sections, expect);
    assert_eq!(lines[1], "4.1 0 8");
    // The body of a section: the lines between `$name` (the `nth` one) and `$Endname`.
    let section = |name: &str, nth: usize| -> Vec<&str> {
        let start = (lines.iter().enumerate())
            .filter(|(_, l)| **l == format!("${name}"))
            .nth(nth)
            .unwrap()
            .0;
        let len = lines[start..]
            .iter()
            .position(|l| *l == format!("$End{name}"))
            .unwrap();
        lines[start + 1..start + len].to_vec()
    };
    let entities = section("Entities", 0);
    assert_eq!(entities[0], "0 0 1 0");
    let bbox = numbers(entities[1]);
    assert_bits(
        "bbox",
        &bbox,
        &[1.0, -1.0, -1e300, 0.0, 1.0, 1.0, 1.0 / 3.0, 0.0, 0.0],
    );

    let want = expected_arrays(&pyramid(), &fields());
    let nodes = section("Nodes", 0);
    assert_eq!(&nodes[..2], ["1 5 1 5", "2 1 0 5"]);
    assert_eq!(&nodes[2..7], ["1", "2", "3", "4", "5"]);
    let coords: Vec<f64> = nodes[7..].iter().flat_map(|l| numbers(l)).collect();
    assert_bits("nodes", &coords, &want["Points"]);

    let elements = section("Elements", 0);
    assert_eq!(&elements[..2], ["1 4 1 4", "2 1 2 4"]);
    assert_eq!(&elements[2..], ["1 1 2 3", "2 1 3 4", "3 1 4 5", "4 1 5 2"]);

    let views = [
        ("NodeData", 0, "w", 1, 5),
        ("NodeData", 1, "u", 3, 5),
        ("NodeData", 2, "set_rim", 1, 5),
        ("ElementData", 0, "p & <q>", 1, 4),
        ("ElementData", 1, "n", 3, 4),
    ];
    for (kind, nth, name, comps, count) in views {
        let body = section(kind, nth);
        let head = format!("1\n\"{name}\"\n1\n0\n3\n0\n{comps}\n{count}");
        assert_eq!(body[..8].join("\n"), head, "{kind} {name}");
        let mut values = Vec::new();
        for (k, line) in body[8..].iter().enumerate() {
            let row = numbers(line);
            assert_eq!(row.len(), 1 + comps, "{name}: {line}");
            assert_eq!(row[0], (k + 1) as f64, "{name}: tags are 1-based");
            values.extend_from_slice(&row[1..]);
        }
        assert_bits(name, &values, &want[name]);
    }
}

// ---------------------------------------------------------------------------------------------
// PVD collections.

#[test]
fn pvd_lists_times_and_relative_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("series.pvd");
    let entries = vec![
        (0.0, PathBuf::from("step_0.vtu")),
        (0.1 + 0.2, PathBuf::from("./steps/step_1.vtu")),
        (-2.5e-7, PathBuf::from("a&b.vtu")),
    ];
    write_pvd(&path, &entries).unwrap();
    let root = parse_xml(&fs::read_to_string(&path).unwrap());
    assert_eq!(root.name, "VTKFile");
    assert_eq!(root.attr("type"), "Collection");
    let sets = root.child("Collection").all("DataSet");
    let got: Vec<(f64, &str)> = (sets.iter())
        .map(|d| (d.attr("timestep").parse().unwrap(), d.attr("file")))
        .collect();
    assert_eq!(
        got,
        [
            (0.0, "step_0.vtu"),
            (0.1 + 0.2, "steps/step_1.vtu"),
            (-2.5e-7, "a&b.vtu")
        ]
    );
    for d in sets {
        assert_eq!(d.attr("part"), "0");
    }
    assert_eq!(files_in(dir.path()), ["series.pvd"]);
}

#[test]
fn pvd_rejects_bad_entries_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("series.pvd");
    let bad_time = vec![
        (0.0, PathBuf::from("a.vtu")),
        (f64::NAN, PathBuf::from("b.vtu")),
    ];
    expect_invalid(
        write_pvd(&path, &bad_time),
        "entry 1 (b.vtu) has a non-finite time",
    );
    for p in ["", ".", "dir/"] {
        expect_invalid(
            write_pvd(&path, &[(0.0, PathBuf::from(p))]),
            "names no file",
        );
    }
    assert!(files_in(dir.path()).is_empty());
    // An empty collection is valid.
    write_pvd(&path, &[]).unwrap();
    assert!(parse_xml(&fs::read_to_string(&path).unwrap())
        .child("Collection")
        .children
        .is_empty());
}

#[test]
fn field_helpers() {
    let f = fields();
    assert_eq!(f.point.len(), 2);
    assert_eq!(f.cell.len(), 2);
    assert_eq!(f.point[1].data.components(), 3);
    assert_eq!(f.point[1].data.flat().len(), 15);
    assert!(matches!(f.cell[0].data, FieldData::Scalar(ref v) if v.len() == 4));
    assert!(Fields::new().is_empty());
}

#[test]
#[should_panic(expected = "well-formed XML")]
fn the_xml_check_rejects_mismatched_tags() {
    parse_xml("<a><b></a></b>");
}

#[test]
#[should_panic(expected = "unclosed elements")]
fn the_xml_check_rejects_unclosed_elements() {
    parse_xml("<a><b></b>");
}

#[test]
fn a_named_collection_escapes_its_names_and_refuses_control_characters() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("events.pvd");
    meshes::write::write_pvd_named(
        &path,
        &[
            (0.0, "a.vtu".into(), "critical_01: <E1> & co".to_string()),
            (1.0, "b.vtu".into(), String::new()),
        ],
    )
    .unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("file=\"a.vtu\" name=\"critical_01: &lt;E1&gt; &amp; co\"/>"),
        "{text}"
    );
    assert!(text.contains("file=\"b.vtu\"/>"), "{text}");
    let bad = meshes::write::write_pvd_named(&path, &[(0.0, "a.vtu".into(), "x\ny".into())]);
    assert!(bad.is_err());
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        text,
        "the old file is kept"
    );
}
