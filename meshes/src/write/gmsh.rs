//! Gmsh MSH 4.1, ascii (Gmsh reference manual, section "MSH file format",
//! <https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format>).
//!
//! The points that matter to readers:
//! - `$MeshFormat` is `4.1 0 8`: version 4.1, file-type 0 (ascii), data-size 8 (`size_t`).
//! - `$Entities` declares one surface (tag 1) with its bounding box, no physical tags and no
//!   bounding curves. meshio's reader looks up each element block's entity there when the
//!   section is present (and adds `gmsh:geometrical` cell data and `gmsh:dim_tags` point data
//!   of its own).
//! - `$Nodes`: header `numEntityBlocks numNodes minNodeTag maxNodeTag`, then one block
//!   `entityDim entityTag parametric numNodesInBlock` (2 1 0 N), the N node tags, then the N
//!   coordinate lines. Tags are 1-based: node i of the mesh is tag i + 1.
//! - `$Elements`: same header, one block `2 1 2 M` (element type 2 = 3-node triangle), then
//!   lines `elementTag n1 n2 n3`.
//! - Fields are post-processing views: `$NodeData` / `$ElementData` with one string tag (the
//!   quoted name; meshio strips every `"` from it), one real tag (time 0), three integer tags
//!   (time step 0, number of components 1 or 3, number of entities), then lines
//!   `tag v1 [v2 v3]`. meshio assigns values in file order and ignores the tags.

use super::{FieldData, MeshData, Num};
use crate::mesh::Vec3;
use std::io::{self, Write};

/// Gmsh element type of the 3-node triangle.
const GMSH_TRIANGLE: u32 = 2;
/// The one geometric entity: surface 1.
const SURFACE_TAG: u32 = 1;

/// Writes the whole `.msh` document.
pub(crate) fn write(w: &mut dyn Write, data: &MeshData<'_>) -> io::Result<()> {
    let mesh = data.mesh;
    let (n, m) = (mesh.nodes.len(), mesh.triangles.len());

    writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;

    let (lo, hi) = bounding_box(&mesh.nodes);
    writeln!(w, "$Entities\n0 0 1 0")?;
    writeln!(
        w,
        "{SURFACE_TAG} {} {} {} {} {} {} 0 0",
        Num(lo.x),
        Num(lo.y),
        Num(lo.z),
        Num(hi.x),
        Num(hi.y),
        Num(hi.z)
    )?;
    writeln!(w, "$EndEntities")?;

    writeln!(w, "$Nodes\n1 {n} 1 {n}\n2 {SURFACE_TAG} 0 {n}")?;
    for i in 1..=n {
        writeln!(w, "{i}")?;
    }
    for x in &mesh.nodes {
        writeln!(w, "{} {} {}", Num(x.x), Num(x.y), Num(x.z))?;
    }
    writeln!(w, "$EndNodes")?;

    writeln!(
        w,
        "$Elements\n1 {m} 1 {m}\n2 {SURFACE_TAG} {GMSH_TRIANGLE} {m}"
    )?;
    for (t, [a, b, c]) in mesh.triangles.iter().enumerate() {
        writeln!(w, "{} {} {} {}", t + 1, a + 1, b + 1, c + 1)?;
    }
    writeln!(w, "$EndElements")?;

    for f in &data.point {
        write_view(w, "NodeData", &f.name, &f.data)?;
    }
    for f in &data.cell {
        write_view(w, "ElementData", &f.name, &f.data)?;
    }
    Ok(())
}

fn bounding_box(nodes: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = nodes[0];
    let mut hi = nodes[0];
    for x in nodes {
        lo = lo.inf(x);
        hi = hi.sup(x);
    }
    (lo, hi)
}

/// One `$NodeData` or `$ElementData` section.
fn write_view(w: &mut dyn Write, section: &str, name: &str, data: &FieldData) -> io::Result<()> {
    let c = data.components();
    writeln!(
        w,
        "${section}\n1\n\"{name}\"\n1\n0\n3\n0\n{c}\n{}",
        data.len()
    )?;
    for (k, row) in data.flat().chunks(c).enumerate() {
        write!(w, "{}", k + 1)?;
        for &v in row {
            write!(w, " {}", Num(v))?;
        }
        writeln!(w)?;
    }
    writeln!(w, "$End{section}")
}
