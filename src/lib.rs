//! memstab — stability of pressurized thin membranes.
//!
//! Data flows one way (docs/architecture.md): scene → mesh + group → effects → model →
//! analysis → results → writers. The lower layers are crates of their own, re-exported here:
//! - [`symmetry`]: finite point groups, real irreps, characters, subgroups and isotropy;
//! - [`meshes`]: symmetric meshes with verified group actions, readers, and writers that
//!   meshio reads.
//!
//! This crate, bottom up:
//! - [`linalg`]: sparse symmetric LBLᵀ with inertia, bordered solves, shift-invert Lanczos;
//! - [`scene`]: the scene file (parse, validate); [`study`]: a scene made into a model;
//! - [`effects`]: one potential per file; [`model`]: assembly of Π, F, K on a fixed pattern;
//! - [`adapted`]: symmetry-adapted bases; [`stability`]: inertia and spectra by irrep;
//! - [`analysis`]: the path driver, events, the analyses a scene asks for, and branch
//!   switching at their bifurcation points;
//! - [`results`]: typed results; [`output`]: the writers;
//! - [`reference`](mod@reference): closed forms; [`demo`]: the bundled demo;
//!   [`bench`](mod@bench): the studies behind
//!   `memstab bench` (a leaf: nothing else uses it); [`sweep`]: parameter sweeps, run here
//!   or by a scheduler, and their collected table (a leaf too); [`text`]: number formatting.

pub use meshes;
pub use symmetry;
pub mod adapted;
pub mod analysis;
pub mod axisym;
pub mod bench;
pub mod continuation;
pub mod demo;
pub mod effects;
pub mod limits;
pub mod linalg;
pub mod model;
pub mod output;
pub mod reference;
pub mod results;
pub mod scene;
pub mod stability;
pub mod study;
pub mod sweep;
pub mod text;
