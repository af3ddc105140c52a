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
//! and come back as groups of their own, with their own irreps and names.
//!
//! Real irreps come in two kinds ([`IrrepKind`]): *real type* (absolutely irreducible; all
//! irreps of `C_nv`, `I`, `Ih`) and *complex type* (the 2-D irreps `E_k` of `C_n`, whose
//! complexification splits into two conjugate 1-D irreps). Schur's relations differ between
//! the two, see [`Irrep::kind`].

mod axial;
mod group;
mod icosahedral;
mod irrep;
mod subgroup;

pub use group::{Group, GroupError, Matrix3};
pub use irrep::{Irrep, IrrepKind};
pub use subgroup::{Invariant, Subgroup};

/// Tolerance used to compare orthogonal matrices (entries are O(1)).
pub const MATRIX_TOL: f64 = 1e-9;
