//! `memstab mesh <disc|icosphere|truncated-sphere> [options] [--out FILE] [--json]`.
//!
//! Generates the mesh with its symmetry group, verifies the group action and that the mesh
//! has no symmetry the group does not declare, and writes it (format from the extension)
//! with the node and triangle orbits as point and cell data.

use super::CliError;
use clap::{Args, Subcommand, ValueEnum};
use memstab::limits::Limits;
use memstab::scene::{DiscMesh, DownSpec, IcosphereMesh, MeshSpec, TruncatedSphereMesh};
use meshes::write::{orbit_fields, write_mesh, Format};
use meshes::MeshError;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct MeshArgs {
    #[command(subcommand)]
    kind: MeshKind,
    /// Output file; the format follows the extension (.vtu, .msh, .xdmf).
    #[arg(long, global = true)]
    out: Option<PathBuf>,
    /// Binary (base64) data in VTU files.
    #[arg(long, global = true)]
    binary: bool,
    /// Print one JSON object.
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Debug, Subcommand)]
enum MeshKind {
    /// Flat circular membrane from N sectors with d divisions (N·d² triangles).
    Disc {
        /// Radius.
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        radius: f64,
        /// Number of sectors N.
        #[arg(long, default_value_t = 7)]
        sectors: usize,
        /// Divisions d of each sector edge.
        #[arg(long, default_value_t = 16)]
        divisions: usize,
        /// Declared group, a subgroup of C<N>v: C<M>v or C<M> with M dividing N
        /// (default C<N>v). Lower groups get a smooth perturbation that breaks the rest.
        #[arg(long)]
        group: Option<String>,
    },
    /// Geodesic icosphere: 20·f² triangles, 10·f²+2 nodes, group Ih.
    Icosphere {
        /// Radius.
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        radius: f64,
        /// Frequency f (subdivisions of each icosahedron edge).
        #[arg(long, default_value_t = 4)]
        frequency: usize,
        /// Turn the sphere so that a vertex, a face centre or an edge midpoint points down (−z).
        #[arg(long, value_enum)]
        down: Option<DownArg>,
    },
    /// Sphere cut by the plane z = cut-height; the part above, with the cut circle named `cut`.
    TruncatedSphere {
        /// Radius.
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        radius: f64,
        /// Height of the cutting plane, strictly between −radius and radius.
        #[arg(long, default_value_t = -0.5, allow_negative_numbers = true)]
        cut_height: f64,
        /// Symmetry pattern: C8v, C2v or C1v.
        #[arg(long, default_value = "C8v")]
        pattern: String,
        /// Divisions (default: about the reference element count for the pattern).
        #[arg(long)]
        divisions: Option<usize>,
    },
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum DownArg {
    Vertex,
    Face,
    Edge,
}

#[derive(Serialize)]
struct MeshJson {
    nodes: usize,
    elements: usize,
    group: String,
    order: usize,
    verified: bool,
    max_position_error: f64,
    hidden_symmetries: Vec<String>,
    boundaries: BTreeMap<String, usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    file: Option<PathBuf>,
}

fn input(e: MeshError) -> CliError {
    CliError::Input(e.to_string())
}

/// The scene's mesh options for these arguments.
fn spec(kind: &MeshKind) -> MeshSpec {
    match kind {
        MeshKind::Disc {
            radius,
            sectors,
            divisions,
            group,
        } => MeshSpec::Disc(DiscMesh {
            radius: *radius,
            sectors: *sectors,
            divisions: *divisions,
            group: group.clone(),
        }),
        MeshKind::Icosphere {
            radius,
            frequency,
            down,
        } => MeshSpec::Icosphere(IcosphereMesh {
            radius: *radius,
            frequency: *frequency,
            down: down.map(|d| match d {
                DownArg::Vertex => DownSpec::Vertex,
                DownArg::Face => DownSpec::Face,
                DownArg::Edge => DownSpec::Edge,
            }),
        }),
        MeshKind::TruncatedSphere {
            radius,
            cut_height,
            pattern,
            divisions,
        } => MeshSpec::TruncatedSphere(TruncatedSphereMesh {
            radius: *radius,
            cut_height: *cut_height,
            pattern: pattern.clone(),
            divisions: *divisions,
        }),
    }
}

pub(crate) fn run(args: &MeshArgs) -> Result<(), CliError> {
    // Check the output format before any work, so that a bad name costs nothing.
    let format = args
        .out
        .as_deref()
        .map(|p| Format::from_path(p, args.binary))
        .transpose()
        .map_err(input)?;
    if let Some(out) = &args.out {
        super::common::check_out_file("--out", out)?;
    }
    let spec = spec(&args.kind);
    let limits = Limits::from_env().map_err(|e| CliError::Input(e.to_string()))?;
    limits
        .check_group(&spec.group_name())
        .and_then(|()| limits.check_memory(spec.describe(), spec.estimated_bytes()))
        .map_err(|e| CliError::Input(e.to_string()))?;
    let sym = spec.generate().map_err(input)?;
    let check = sym
        .verify()
        .map_err(|e| CliError::Failure(format!("the generated mesh failed verification: {e}")))?;
    let hidden = sym.hidden_symmetries();
    if let (Some(path), Some(format)) = (&args.out, format) {
        let fields = orbit_fields(&sym);
        write_mesh(path, &sym.mesh, &fields, format)
            .map_err(|e| CliError::Failure(e.to_string()))?;
    }
    let mesh = &sym.mesh;
    let summary = MeshJson {
        nodes: mesh.nodes.len(),
        elements: mesh.triangles.len(),
        group: sym.group().name().to_string(),
        order: sym.group().order(),
        verified: true,
        max_position_error: check.max_position_error,
        hidden_symmetries: hidden,
        boundaries: mesh
            .boundaries
            .iter()
            .map(|(k, v)| (k.clone(), v.len()))
            .collect(),
        file: args.out.clone(),
    };
    if args.json {
        let text = serde_json::to_string(&summary).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
    } else {
        out!(
            "{} nodes, {} triangles, group {} (order {}), action verified (max |R X - X_pi| = {:.1e} of the mesh size)",
            summary.nodes, summary.elements, summary.group, summary.order, summary.max_position_error
        );
        for (name, count) in &summary.boundaries {
            out!("node set '{name}': {count} nodes");
        }
        if summary.hidden_symmetries.is_empty() {
            out!("no symmetry beyond {}", summary.group);
        } else {
            out!(
                "warning: symmetry beyond {}: {}",
                summary.group,
                summary.hidden_symmetries.join("; ")
            );
        }
        if let Some(p) = &summary.file {
            out!("wrote {}", p.display());
        }
    }
    Ok(())
}
