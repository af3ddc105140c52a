//! The integration tests of the meshes crate, as one test binary.

mod actions;
mod generators;
mod readers;
mod subgroup_actions;
mod writers;
