//! The readers read back what the writers write — nodes bit-exact, the same triangles, the
//! same node sets — for every format they support, and malformed files are errors that say
//! where, never panics.

use meshes::generators::{
    disc, icosphere, truncated_sphere, DiscOptions, IcosphereOptions, TruncatedSphereOptions,
};
use meshes::read::{read_mesh, SUPPORTED};
use meshes::write::{write_mesh, Fields, Format};
use meshes::{Mesh, MeshError, SymmetricMesh, Vec3};
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// The formats the readers support, with a file name of the right extension.
const READABLE: [(Format, &str); 3] = [
    (Format::Msh41, "m.msh"),
    (Format::VtuAscii, "m.vtu"),
    (Format::VtuBase64, "m.vtu"),
];

/// Fields of every kind, which the readers must read past.
fn extra_fields(mesh: &Mesh) -> Fields {
    let (n, m) = (mesh.nodes.len(), mesh.triangles.len());
    Fields::new()
        .point_scalar("w", (0..n).map(|i| i as f64 * 0.1))
        .point_vector("u", (0..n).map(|i| [i as f64, -0.5, 1e-300]))
        .cell_scalar("t", (0..m).map(|t| t as f64))
        .cell_vector("v", (0..m).map(|t| [1.0, t as f64 / 3.0, -0.0]))
}

/// Writes `mesh` (with `fields`) in `format` into a fresh directory and reads it back.
fn round_trip(mesh: &Mesh, fields: &Fields, format: Format, name: &str) -> Mesh {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_mesh(&path, mesh, fields, format).unwrap_or_else(|e| panic!("{format:?}: {e}"));
    read_mesh(&path).unwrap_or_else(|e| panic!("{format:?}: {e}"))
}

/// Nodes bit for bit, triangles and node sets exactly.
fn assert_same(read: &Mesh, written: &Mesh, what: &str) {
    assert_eq!(read.nodes.len(), written.nodes.len(), "{what}: node count");
    for (i, (a, b)) in read.nodes.iter().zip(&written.nodes).enumerate() {
        let bits = |x: &Vec3| x.map(f64::to_bits);
        assert_eq!(bits(a), bits(b), "{what}: node {i}: {a:?} vs {b:?}");
    }
    assert_eq!(read.triangles, written.triangles, "{what}: triangles");
    assert_eq!(read.boundaries, written.boundaries, "{what}: node sets");
}

fn generated() -> Vec<(&'static str, SymmetricMesh)> {
    let disc_with = |group: Option<&str>| {
        disc(&DiscOptions {
            radius: 1.1,
            sectors: 8,
            divisions: 4,
            group: group.map(str::to_string),
        })
        .unwrap()
    };
    vec![
        ("disc C8v", disc_with(None)),
        // A perturbed disc: coordinates with all their digits.
        ("disc C2v", disc_with(Some("C2v"))),
        (
            "icosphere",
            icosphere(&IcosphereOptions {
                radius: 1.0,
                frequency: 3,
            })
            .unwrap(),
        ),
        (
            "truncated sphere",
            truncated_sphere(&TruncatedSphereOptions {
                divisions: 4,
                ..TruncatedSphereOptions::for_pattern("C8v")
            })
            .unwrap(),
        ),
    ]
}

#[test]
fn generator_meshes_round_trip_in_every_readable_format() {
    for (what, sym) in generated() {
        let mesh = &sym.mesh;
        for (format, name) in READABLE {
            for fields in [Fields::new(), extra_fields(mesh)] {
                let read = round_trip(mesh, &fields, format, name);
                assert_same(&read, mesh, &format!("{what} as {format:?}"));
                // The mesh read back carries the generator's group and verifies.
                let again = SymmetricMesh::new(read, sym.group().clone())
                    .unwrap_or_else(|e| panic!("{what} as {format:?}: {e}"));
                again.verify().unwrap();
            }
        }
    }
    // The node sets are really there.
    let (_, sym) = &generated()[0];
    let read = round_trip(&sym.mesh, &Fields::new(), Format::Msh41, "d.msh");
    assert_eq!(read.boundaries["rim"].len(), 8 * 4);
}

/// Strategy: a small mesh with extreme but finite coordinates, triangles of distinct nodes and
/// up to three node sets whose names need escaping in XML.
fn small_mesh() -> impl Strategy<Value = Mesh> {
    let coordinate = prop_oneof![
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
        Just(-0.0),
        Just(5e-324),
        -10.0..10.0f64,
    ];
    (3usize..12)
        .prop_flat_map(move |n| {
            let nodes = prop::collection::vec(
                [coordinate.clone(), coordinate.clone(), coordinate.clone()],
                n,
            );
            let triangle = prop::sample::subsequence((0..n).collect::<Vec<_>>(), 3)
                .prop_shuffle()
                .prop_map(|v| [v[0], v[1], v[2]]);
            let triangles = prop::collection::vec(triangle, 1..10);
            let sets = prop::collection::btree_map(
                "[a-z<>&'][a-z<>&' _]{0,4}[a-z]",
                prop::collection::vec(0..n, 0..n),
                0..3,
            );
            (nodes, triangles, sets)
        })
        .prop_map(|(nodes, triangles, sets)| {
            let nodes = nodes.into_iter().map(Vec3::from).collect();
            let mut mesh = Mesh::new(nodes, triangles).unwrap();
            for (name, set) in sets {
                mesh.set_boundary(name, set);
            }
            mesh
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_meshes_round_trip(mesh in small_mesh(), with_fields in any::<bool>()) {
        let fields = if with_fields { extra_fields(&mesh) } else { Fields::new() };
        for (format, name) in READABLE {
            let read = round_trip(&mesh, &fields, format, name);
            assert_same(&read, &mesh, &format!("{format:?}"));
        }
    }

    #[test]
    fn garbage_is_an_error_not_a_panic(text in "\\PC{0,400}", vtu in any::<bool>()) {
        let name = if vtu { "g.vtu" } else { "g.msh" };
        prop_assert!(read_text(name, &text).is_err());
    }

    #[test]
    fn files_with_a_line_replaced_never_panic(
        line in 0usize..200,
        value in prop_oneof![
            Just(String::new()),
            Just("18446744073709551615 3 1 2".to_string()),
            Just("3 1 1 18446744073709551615".to_string()),
            Just("9223372036854775807 0 0".to_string()),
            Just("nan inf -inf".to_string()),
            Just("$EndNodes".to_string()),
            Just("<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">".to_string()),
            Just("</Piece>".to_string()),
            "[0-9 -]{0,24}",
            "[A-Za-z0-9+/=]{0,24}",
        ],
        format in 0usize..3,
    ) {
        let (format, name) = READABLE[format];
        let text: String = disc_text(format, name)
            .lines()
            .enumerate()
            .map(|(i, l)| if i == line { format!("{value}\n") } else { format!("{l}\n") })
            .collect();
        let _ = read_text(name, &text);
    }

    #[test]
    fn gmsh_like_garbage_is_an_error_not_a_panic(
        text in "(\\$[A-Za-z]{0,12}\n|4\\.1 [0-9] 8\n|[0-9 .e-]{0,16}\n){0,30}"
    ) {
        let _ = read_text("g.msh", &text);
    }
}

// ---------------------------------------------------------------------------------------------
// Malformed files.

/// A small disc with node set `rim`, its text in `format`.
fn disc_text(format: Format, name: &str) -> String {
    let sym = disc(&DiscOptions {
        radius: 1.0,
        sectors: 3,
        divisions: 2,
        group: None,
    })
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_mesh(&path, &sym.mesh, &extra_fields(&sym.mesh), format).unwrap();
    std::fs::read_to_string(&path).unwrap()
}

/// Writes `text` to a file `name` in a fresh directory and reads it.
fn read_text(name: &str, text: &str) -> Result<Mesh, MeshError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    read_mesh(&path)
}

/// The message of a [`MeshError::Read`] for `text` as file `name`; it must contain every
/// needle and be one line.
fn rejected(name: &str, text: &str, needles: &[&str]) -> String {
    let message = match read_text(name, text) {
        Err(MeshError::Read { message, .. }) => message,
        Err(other) => panic!("not a read error: {other}"),
        Ok(_) => panic!("accepted:\n{text}"),
    };
    assert_eq!(message.lines().count(), 1, "not one line: {message}");
    for needle in needles {
        assert!(message.contains(needle), "{needle:?} not in: {message}");
    }
    message
}

/// `text` with the first line equal to `from` replaced by `to` (which must exist).
fn replace_line(text: &str, from: &str, to: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let k = lines
        .iter()
        .position(|l| *l == from)
        .unwrap_or_else(|| panic!("no line {from:?}"));
    let mut out = String::new();
    for (i, l) in lines.iter().enumerate() {
        out.push_str(if i == k { to } else { l });
        out.push('\n');
    }
    out
}

#[test]
fn gmsh_cut_at_any_line_is_an_error_unless_a_section_ended() {
    let text = disc_text(Format::Msh41, "d.msh");
    let lines: Vec<&str> = text.lines().collect();
    let end_elements = lines.iter().position(|l| *l == "$EndElements").unwrap();
    for k in 0..lines.len() {
        let cut: String = lines[..k].iter().map(|l| format!("{l}\n")).collect();
        let result = read_text("d.msh", &cut);
        let whole_sections = k > end_elements && lines[k - 1].starts_with("$End");
        match result {
            Ok(mesh) => {
                assert!(whole_sections, "cut after {k} lines was accepted");
                assert_eq!(mesh.triangles.len(), 12);
            }
            Err(MeshError::Read { message, .. }) => {
                assert!(!whole_sections, "cut after {k} lines: {message}");
                assert_eq!(message.lines().count(), 1);
            }
            Err(e) => panic!("{e}"),
        }
    }
}

#[test]
fn vtu_cut_anywhere_is_an_error() {
    for format in [Format::VtuAscii, Format::VtuBase64] {
        let text = disc_text(format, "d.vtu");
        let end = text.trim_end().len();
        for k in (0..end).step_by(7).chain([end - 1]) {
            match read_text("d.vtu", &text[..k]) {
                Err(MeshError::Read { message, .. }) => {
                    assert_eq!(message.lines().count(), 1, "{message}")
                }
                other => panic!("{format:?} cut at byte {k}: {other:?}"),
            }
        }
        assert!(read_text("d.vtu", &text[..end]).is_ok());
    }
}

#[test]
fn gmsh_wrong_counts_name_the_line() {
    let text = disc_text(Format::Msh41, "d.msh");
    // 3 sectors, 2 divisions: 10 nodes, 12 triangles.
    rejected(
        "d.msh",
        &replace_line(&text, "1 10 1 10", "1 11 1 11"),
        &["line 30", "announces 11 nodes"],
    );
    rejected(
        "d.msh",
        &replace_line(&text, "2 1 0 10", "2 1 0 9"),
        &["line 20", "'10'"],
    );
    rejected(
        "d.msh",
        &replace_line(&text, "2 1 2 12", "2 1 2 13"),
        &["line 47", "triangle line", "'$EndElements'"],
    );
    rejected(
        "d.msh",
        &replace_line(&text, "1 12 1 12", "1 11 1 11"),
        &["announces 11 elements"],
    );
    // A triangle that refers to a node that does not exist.
    rejected(
        "d.msh",
        &replace_line(&text, "1 1 2 3", "1 1 2 99"),
        &["node tag 99"],
    );
    rejected(
        "d.msh",
        &replace_line(&text, "1 1 2 3", "1 1 2 2"),
        &["repeats a node"],
    );
}

#[test]
fn gmsh_other_elements_are_refused_and_lines_skipped() {
    let text = disc_text(Format::Msh41, "d.msh");
    // A quadrangle block instead of the triangles.
    let quads = replace_line(&text, "2 1 2 12", "2 1 3 12");
    rejected(
        "d.msh",
        &quads,
        &["element type 3", "quadrangle", "triangles"],
    );
    // Lines on a curve (as Gmsh writes for boundaries) are skipped.
    let with_lines = replace_line(&text, "1 12 1 12", "2 13 1 13")
        .replace("$EndElements", "1 7 1 1\n13 2 3\n$EndElements");
    let mesh = read_text("d.msh", &with_lines).unwrap();
    assert_eq!(mesh.triangles.len(), 12);
    assert_eq!(mesh.boundaries["rim"].len(), 6);
}

#[test]
fn gmsh_bad_headers_and_values_are_refused() {
    let text = disc_text(Format::Msh41, "d.msh");
    rejected(
        "d.msh",
        &replace_line(&text, "4.1 0 8", "4.1 1 8"),
        &["line 2", "binary MSH is not supported"],
    );
    rejected(
        "d.msh",
        &replace_line(&text, "4.1 0 8", "2.2 0 8"),
        &["line 2", "version 2.2"],
    );
    rejected(
        "d.msh",
        &text.replacen("$MeshFormat", "$Mesh", 1),
        &["line 1"],
    );
    rejected("d.msh", "", &["empty"]);
    // A coordinate that is not finite, and one that is missing.
    // Line 22 holds the coordinates of the second node.
    assert_eq!(text.lines().nth(21), Some("0.5 0 0"));
    rejected(
        "d.msh",
        &replace_line(&text, "0.5 0 0", "0.5 nan 0"),
        &["line 22", "non-finite"],
    );
    rejected(
        "d.msh",
        &replace_line(&text, "0.5 0 0", "0.5 0"),
        &["line 22", "expected 3 numbers"],
    );
    // A node set that is not 0/1 (node tag 4 is on the rim).
    let set = text.find("\"set_rim\"").unwrap();
    let one = set + text[set..].find("\n4 1\n").unwrap();
    let half = format!("{}\n4 0.5\n{}", &text[..one], &text[one + 5..]);
    rejected("d.msh", &half, &["set_rim", "0.5", "node index 3"]);
    // An unknown section without its end.
    rejected(
        "d.msh",
        &format!("{text}$Comments\nhello\n"),
        &["$Comments", "no $EndComments"],
    );
    // Unknown sections are skipped.
    let commented = format!("{text}$Comments\nhello\n$EndComments\n");
    assert!(read_text("d.msh", &commented).is_ok());
}

#[test]
fn vtu_wrong_counts_and_cells_are_refused() {
    let text = disc_text(Format::VtuAscii, "d.vtu");
    rejected(
        "d.vtu",
        &text.replace("NumberOfPoints=\"10\"", "NumberOfPoints=\"11\""),
        &["DataArray \"Points\"", "expected 11 x 3"],
    );
    rejected(
        "d.vtu",
        &text.replace("NumberOfCells=\"12\"", "NumberOfCells=\"13\""),
        &["\"offsets\"", "NumberOfCells is 13"],
    );
    // A quad where a triangle was.
    let types = text.find("Name=\"types\"").unwrap();
    let first = types + text[types..].find("\n5 ").unwrap();
    let quad = format!("{}\n9 {}", &text[..first], &text[first + 3..]);
    rejected("d.vtu", &quad, &["cell 0", "VTK type 9", "quad"]);
    // A node index beyond the points.
    let conn = text.find("Name=\"connectivity\"").unwrap();
    let line = conn + text[conn..].find('\n').unwrap() + 1;
    let bad = format!("{}99{}", &text[..line], &text[line + 1..]);
    rejected("d.vtu", &bad, &["cell 0", "point 99"]);
    rejected(
        "d.vtu",
        &text.replace("format=\"ascii\"", "format=\"appended\""),
        &["appended"],
    );
    rejected(
        "d.vtu",
        &text.replace(
            "header_type=\"UInt64\"",
            "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"",
        ),
        &["compressor"],
    );
    rejected(
        "d.vtu",
        &text.replace("UnstructuredGrid\" version", "PolyData\" version"),
        &["PolyData"],
    );
}

#[test]
fn vtu_base64_with_a_wrong_byte_count_is_refused() {
    let text = disc_text(Format::VtuBase64, "d.vtu");
    // The header of the points block says 240 bytes (10 x 3 x 8): 8 bytes, little-endian.
    let header = base64::Engine::encode(
        &base64::engine::general_purpose::STANDARD,
        240u64.to_le_bytes(),
    );
    assert!(text.contains(&header[..8]), "{header}");
    let wrong = base64::Engine::encode(
        &base64::engine::general_purpose::STANDARD,
        248u64.to_le_bytes(),
    );
    rejected(
        "d.vtu",
        &text.replacen(&header[..8], &wrong[..8], 1),
        &["DataArray \"Points\"", "248 bytes"],
    );
}

#[test]
fn unsupported_extensions_list_the_supported_ones() {
    for name in ["m.xdmf", "m.obj", "m"] {
        let message = match read_mesh(Path::new(name)) {
            Err(MeshError::Read { message, .. }) => message,
            other => panic!("{name}: {other:?}"),
        };
        assert!(message.contains(SUPPORTED), "{message}");
    }
    // Case-insensitive.
    let text = disc_text(Format::Msh41, "d.msh");
    assert!(read_text("D.MSH", &text).is_ok());
}

#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let path = PathBuf::from("/nonexistent/disc.msh");
    match read_mesh(&path) {
        Err(e @ MeshError::Io { .. }) => assert!(e.to_string().contains("/nonexistent/disc.msh")),
        other => panic!("{other:?}"),
    }
}
