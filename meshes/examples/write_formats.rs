//! Writes one awkward test mesh in every format of `meshes::write`, plus a `.pvd` and an
//! `expected.json` with the exact nodes, triangles and fields, for
//! `scripts/meshio_roundtrip.py` to compare against what meshio reads.
//!
//! ```text
//! cargo run --release -p meshes --example write_formats -- OUTDIR
//! ```
//!
//! The mesh is a 6 × 5 node grid on a saddle (40 triangles) with coordinates such as 1/3 and
//! 0.1 + 0.2, negative values, a subnormal, ±1e-300 and 1e300; the fields carry -0, the
//! smallest subnormal, the largest finite `f64` and similar values that a lossy writer or
//! reader would change. It is built here by hand, independent of the mesh generators.

use meshes::write::{write_mesh, write_pvd, Fields, Format};
use meshes::{Mesh, Vec3};
use serde_json::{json, Map, Value};
use std::path::PathBuf;

const NX: usize = 6;
const NY: usize = 5;

/// The grid mesh with its node sets `rim` (grid boundary) and `corner` (node 0).
fn test_mesh() -> Mesh {
    let mut nodes = Vec::new();
    for j in 0..NY {
        for i in 0..NX {
            let x = -1.0 + i as f64 / 3.0;
            let y = -0.5 + j as f64 * 0.3;
            let z = (x * x - y * y) / 7.0;
            nodes.push(Vec3::new(x, y, z));
        }
    }
    // Extreme coordinates: tiny, subnormal, huge, signed zero.
    nodes[0].z = 1e-300;
    nodes[1].z = -1e-300;
    nodes[2].y = 5e-324;
    nodes[NX - 1].x = -0.0;
    nodes[NX * NY - 1].z = 1e300;
    nodes[NX + 1].x = 0.1 + 0.2;
    let mut triangles = Vec::new();
    for j in 0..NY - 1 {
        for i in 0..NX - 1 {
            let a = j * NX + i;
            let (b, c, d) = (a + 1, a + NX + 1, a + NX);
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    let mut mesh = Mesh::new(nodes, triangles).expect("grid mesh");
    let rim = (0..NX * NY)
        .filter(|k| {
            let (i, j) = (k % NX, k / NX);
            i == 0 || j == 0 || i == NX - 1 || j == NY - 1
        })
        .collect();
    mesh.set_boundary("rim", rim);
    mesh.set_boundary("corner", vec![0]);
    mesh
}

/// Values that must survive exactly, spliced into the smooth fields.
const SPECIAL: [f64; 8] = [
    -0.0,
    5e-324,
    f64::MAX,
    f64::MIN_POSITIVE,
    1e300,
    -1e-300,
    0.1 + 0.2,
    -1.0 / 3.0,
];

fn fields(mesh: &Mesh) -> Fields {
    let n = mesh.nodes.len();
    let m = mesh.triangles.len();
    let mut head: Vec<f64> = (0..n).map(|k| (k as f64 * 0.7).sin() * 1e3).collect();
    head[..SPECIAL.len()].copy_from_slice(&SPECIAL);
    let displacement: Vec<[f64; 3]> = (mesh.nodes.iter().enumerate())
        .map(|(k, x)| {
            let x = if x.norm() > 1e10 { Vec3::zeros() } else { *x };
            [x.x / 7.0, -x.y * 1e-12, (k as f64 / 10.0).exp()]
        })
        .collect();
    let mut tension: Vec<f64> = (0..m)
        .map(|t| if t % 2 == 0 { 1.0 } else { -1.0 } / (t as f64 + 1.0))
        .collect();
    tension[m - SPECIAL.len()..].copy_from_slice(&SPECIAL);
    let direction: Vec<[f64; 3]> = (0..m)
        .map(|t| {
            let t = t as f64;
            [t / 3.0, -t * 1e-300, 1e300 / (t + 1.0)]
        })
        .collect();
    Fields::new()
        .point_scalar("pressure head", head)
        .point_vector("displacement", displacement)
        .cell_scalar("tension σ [N/m] & <co>", tension)
        .cell_vector("direction", direction)
}

/// The data a reader must find: mesh, user fields and the `set_<name>` node-set fields.
fn expected(mesh: &Mesh, fields: &Fields) -> (Map<String, Value>, Map<String, Value>) {
    let to_json = |f: &meshes::write::Field| match &f.data {
        meshes::write::FieldData::Scalar(v) => json!(v),
        meshes::write::FieldData::Vector(v) => json!(v),
    };
    let mut point: Map<String, Value> = (fields.point.iter())
        .map(|f| (f.name.clone(), to_json(f)))
        .collect();
    for (name, set) in &mesh.boundaries {
        let v: Vec<f64> = (0..mesh.nodes.len())
            .map(|k| if set.contains(&k) { 1.0 } else { 0.0 })
            .collect();
        point.insert(format!("set_{name}"), json!(v));
    }
    let cell = (fields.cell.iter())
        .map(|f| (f.name.clone(), to_json(f)))
        .collect();
    (point, cell)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: write_formats OUTDIR")?,
    );
    std::fs::create_dir_all(&out)?;
    let mesh = test_mesh();
    let fields = fields(&mesh);

    // (label, file name, binary hint): the format comes from the name, as a caller would do it.
    let files = [
        ("vtu_ascii", "mesh_ascii.vtu", false),
        ("vtu_base64", "mesh_base64.vtu", true),
        ("msh41", "mesh.msh", false),
        ("xdmf_inline", "mesh_inline.xdmf", false),
        ("xdmf_binary", "mesh_binary.xdmf", true),
    ];
    let mut written = Vec::new();
    for (label, name, binary) in files {
        let path = out.join(name);
        let format = Format::from_path(&path, binary)?;
        write_mesh(&path, &mesh, &fields, format)?;
        written.push(json!({"label": label, "file": name, "format": format!("{format:?}")}));
    }
    let pvd_entries = vec![
        (0.0, PathBuf::from("mesh_ascii.vtu")),
        (0.25, PathBuf::from("./mesh_base64.vtu")),
    ];
    write_pvd(&out.join("series.pvd"), &pvd_entries)?;

    let (point_data, cell_data) = expected(&mesh, &fields);
    let nodes: Vec<[f64; 3]> = mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    let doc = json!({
        "nodes": nodes,
        "triangles": mesh.triangles,
        "point_data": point_data,
        "cell_data": cell_data,
        "files": written,
        "pvd": {
            "file": "series.pvd",
            "entries": [
                {"time": 0.0, "file": "mesh_ascii.vtu"},
                {"time": 0.25, "file": "mesh_base64.vtu"},
            ],
        },
    });
    let json_path = out.join("expected.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&doc)?)?;
    println!(
        "wrote {} files, a pvd and {} ({} nodes, {} triangles)",
        files.len(),
        json_path.display(),
        mesh.nodes.len(),
        mesh.triangles.len()
    );
    Ok(())
}
