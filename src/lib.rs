//! memstab — stability of pressurized thin membranes.
//!
//! The toolkit is layered so that data flows one way: scene → mesh + group → effects →
//! model → solver → path and critical points → writers. The lower layers are crates of
//! their own and are re-exported here:
//! - [`symmetry`]: finite point groups, real irreps, characters, stabilisers;
//! - [`meshes`]: symmetric meshes with verified group actions, and writers that meshio reads.

pub use meshes;
pub use symmetry;
pub mod adapted;
pub mod analysis;
pub mod bench;
pub mod demo;
pub mod effects;
pub mod linalg;
pub mod model;
pub mod newton;
pub mod output;
pub mod reference;
pub mod report;
pub mod scene;
pub mod stability;
pub mod study;
pub mod text;
