//! Mesh generators. Each builds a fundamental domain and replicates it with its group
//! ([`crate::SymmetricMesh::replicate`]), so the action is exact to rounding.

mod disc;
mod icosphere;
mod truncated_sphere;

pub use disc::*;
pub use icosphere::*;
pub use truncated_sphere::*;
