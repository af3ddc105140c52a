//! Following equilibria of any problem, knowing no membrane (docs/theory.md §7, §8, §11): the
//! stepping driver (`driver`: pseudo-arclength continuation in several parameters from any
//! converged point), the one event mechanism ([`events`]: turning points, stops, the detectors
//! every analysis runs), the changes of stability of a model whose tangent splits into blocks
//! ([`crossings`]), deflated Newton for the solutions other than the known ones
//! ([`deflation`]), the dips of a path beside a broken double and the piece beyond them
//! ([`near_miss`]), the start homotopy of a free body ([`release`]) and the interrupt flag
//! ([`interrupt`]) the long loops check.
//!
//! What a model must give to be followed: a [`Problem`] (residual, tangent, loads, augmenting
//! equations in its own coordinates), the [`events::States`] those coordinates stand for, and
//! for its stability the [`crossings::Blocks`] of its tangent.

pub mod crossings;
pub mod deflation;
mod driver;
pub mod events;
mod followed;
pub mod interrupt;
pub mod near_miss;
pub mod release;

pub use driver::*;
pub use followed::Followed;
