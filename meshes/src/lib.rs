//! Symmetric triangle surface meshes that carry their own symmetry group.
//!
//! A generator returns a [`SymmetricMesh`]: the [`Mesh`] (nodes, triangles, named boundary
//! node sets) and its [`GroupAction`] — for every element g of a [`symmetry::Group`], the
//! orthogonal matrix `R_g` and the node permutation `π_g` with `R_g X_i = X_{π_g(i)}`.
//! Meshes are built from a fundamental domain replicated by the group
//! ([`SymmetricMesh::replicate`]), so images coincide to rounding, and every action can be
//! checked with [`SymmetricMesh::verify`]. [`SymmetricMesh::hidden_symmetries`] finds symmetry
//! a mesh has but does not declare.
//!
//! [`write`] writes meshes with fields (VTU, Gmsh, XDMF); [`read`] reads the VTU and Gmsh files
//! back, node sets included, so that a mesh can come from a file.
//!
//! This crate knows groups but no physics.

mod action;
pub mod generators;
mod mesh;
pub mod read;
pub mod write;

pub use action::{coincident_nodes, GroupAction, SymmetricMesh, Verification, ACTION_TOL};
pub use mesh::{Mesh, Topology, Vec3};

/// Errors from building, verifying, reading or writing meshes.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// Bad input to a generator or constructor (names the bad value).
    #[error("{0}")]
    Invalid(String),
    /// A generator option has a bad value: `option` is its name (as in the generator's
    /// options struct), `message` the rest of the sentence, e.g. `must be >= 1, got 0`.
    #[error("{option} {message}")]
    Option {
        /// The option's name.
        option: String,
        /// What is wrong with its value.
        message: String,
    },
    /// The mesh is not a connected, consistently oriented 2-manifold.
    #[error("topology: {0}")]
    Topology(String),
    /// The declared group does not act on the mesh as it should.
    #[error("symmetry: {0}")]
    Symmetry(String),
    /// Reading or writing a file failed.
    #[error("i/o on {path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// An output path exists and is not a regular file; it is never replaced.
    #[error("{path}: exists and is {what}, not a regular file; refusing to replace it")]
    Target {
        /// The path.
        path: std::path::PathBuf,
        /// What it is: `a directory`, `a FIFO`, `a device`, `a symbolic link` …
        what: &'static str,
    },
    /// A mesh file cannot be read: an unsupported extension, or content that is malformed or
    /// not supported ([`read`]); the message says where (a line, a data array) and what.
    #[error("{path}: {message}")]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// Where and what, e.g. `line 12: expected 3 numbers …`.
        message: String,
    },
}
