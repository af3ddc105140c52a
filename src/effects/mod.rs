//! Effects: every load a potential (docs/theory.md §1). One effect per file, its potential in the
//! module doc; the per-triangle kernels return value, gradient and Hessian ([`crate::model::Local`]).
//!
//! Beside its potential, an effect's file holds its `[[effect]]` keys as a struct implementing
//! [`spec::EffectSpec`] (checks, axis scales, the 3-D potential and the meridian's load it
//! becomes); [`REGISTRY`] maps each scene `type` to it, one line per effect.

pub mod gas;
pub mod hydrostatic;
pub mod invariant;
pub mod local;
pub mod membrane;
pub mod plane;
pub mod spec;
pub mod spin;
pub mod volume;

use spec::Entry;

/// The effects of `[[effect]] type = "…"`, one line each.
pub const REGISTRY: &[Entry] = &[
    Entry::of::<gas::GasEffect>("gas"),
    Entry::of::<gas::GasAmountEffect>("gas-amount"),
    Entry::of::<hydrostatic::FluidEffect>("fluid"),
    Entry::of::<spin::SpinEffect>("spin"),
    Entry::of::<plane::PlaneEffect>("plane"),
];

/// A number that is either fixed or one of the model's parameters Λ (by index).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Quantity {
    /// A fixed value.
    Value(f64),
    /// The parameter with this index.
    Parameter(usize),
}

impl Quantity {
    /// The current value.
    pub fn value(&self, params: &[f64]) -> f64 {
        match *self {
            Quantity::Value(v) => v,
            Quantity::Parameter(i) => params[i],
        }
    }

    /// The parameter index, if it is one.
    pub fn parameter(&self) -> Option<usize> {
        match *self {
            Quantity::Value(_) => None,
            Quantity::Parameter(i) => Some(i),
        }
    }
}
