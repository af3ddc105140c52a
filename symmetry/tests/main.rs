//! The integration tests of the symmetry crate, as one test binary.

mod gap_tables;
mod isotropy;
mod lattice;
mod lattice_gap;
mod representations;
mod subgroup_irreps;
mod subgroups;
