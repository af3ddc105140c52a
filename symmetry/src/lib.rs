//! Finite point groups in three dimensions, their real irreducible representations,
//! characters and conjugacy classes.
//!
//! This crate knows nothing of finite elements: a [`Group`] is a list of orthogonal 3×3
//! matrices closed under multiplication, with its multiplication table, inverses, conjugacy
//! classes and a complete set of real irreducible representations ([`Irrep`]), each given by
//! explicit orthogonal matrices for every element.
//!
//! Families:
//! - [`Group::cyclic`] `C_n`: rotations about z by multiples of 2π/n;
//! - [`Group::cyclic_v`] `C_nv`: `C_n` plus n vertical mirrors, the first containing the x-axis
//!   (`C1v` is a single mirror, the plane y = 0);
//! - [`Group::icosahedral`] `I` (order 60) and [`Group::icosahedral_full`] `Ih` (order 120),
//!   in the orientation whose 2-fold axes are the coordinate axes (icosahedron vertices at the
//!   cyclic permutations of (0, ±1, ±φ)).
//!
//! Subgroups that keep a set of directions or planes are found with [`Group::stabilizer`]
//! and come back as groups of their own, with their own irreps and names. Any subgroup (given
//! by element indices, e.g. a class of the lattice below: `D5d`, `Th`, `D2h`, `S10`, …)
//! becomes a group of its own with [`Group::subgroup`]: axial ones exactly as the stabiliser
//! builds them, the others with irreps computed by decomposing the restrictions of the
//! parent's irreps and named with Mulliken labels (`A1g`, `E2u`, `B3g`, …).
//!
//! For equivariant branch switching: [`Group::subgroup_lattice`] lists the subgroups up to
//! conjugacy ([`SubgroupClass`], with Schoenflies names and the containment relation), and
//! [`Group::isotropy`] gives, for an irrep, its kernel and its isotropy subgroups
//! ([`IsotropySubgroup`]: fixed-space dimension and basis, normaliser, and for the axial ones
//! whether `±v` are conjugate); [`Group::fixed_dim`] and [`Group::fixed_space`] work for any
//! subgroup.
//!
//! Real irreps come in two kinds ([`IrrepKind`]): *real type* (absolutely irreducible; all
//! irreps of `C_nv`, `I`, `Ih`) and *complex type* (the 2-D irreps `E_k` of `C_n`, and the
//! `E` irreps of subgroups such as `T`, `Th`, `S10`, whose complexification splits into two
//! conjugate 1-D irreps). Schur's relations differ between
//! the two, see [`Irrep::kind`].

mod axial;
mod decompose;
mod fourier;
mod group;
mod icosahedral;
mod irrep;
mod isotropy;
mod lattice;
mod mulliken;
mod subgroup;

pub use group::{Group, GroupError, Matrix3};
pub use irrep::{Irrep, IrrepKind};
pub use isotropy::{IrrepIsotropy, IsotropySubgroup};
pub use lattice::{SubgroupClass, SubgroupLattice};
pub use subgroup::{Invariant, Subgroup};

/// Tolerance used to compare orthogonal matrices (entries are O(1)).
pub const MATRIX_TOL: f64 = 1e-9;
