//! What a scene says of an effect, and what the effect makes of it.
//!
//! Each effect's `[[effect]]` keys are a serde struct in the effect's own file, beside its
//! potential. It implements [`EffectSpec`]: the quantities it takes (a number or a
//! parameter, each with the range a number must lie in), its own checks, the dimensionless
//! groups its parameters are drawn in, the potential it adds to the 3-D model and, where it
//! has one, its load on the meridian. The scene reads `[[effect]]` through
//! [`super::REGISTRY`], the one place a `type` is mapped to its struct; validation, the
//! models, the figures and the writers learn about an effect through this trait only.

use super::gas::GasAmount;
use super::hydrostatic::Fluid;
use super::volume::ClosingFace;
use crate::axisym::{FloorPlane, Pressure};
use crate::model;
use crate::text::key_value;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize};
use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

/// A numeric quantity of a scene: a fixed number, or the name of a declared parameter (its
/// value on the path). In TOML: `pressure = 0.5` or `pressure = "p"`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Quantity {
    /// A fixed number.
    Value(f64),
    /// The name of a parameter in `[parameters]`.
    Parameter(String),
}

impl Quantity {
    /// The parameter this quantity follows, if any.
    pub fn parameter(&self) -> Option<&str> {
        match self {
            Quantity::Value(_) => None,
            Quantity::Parameter(name) => Some(name),
        }
    }

    /// The value, looking parameters up in `values` (`None` for a missing parameter).
    pub fn value(&self, values: &BTreeMap<String, f64>) -> Option<f64> {
        match self {
            Quantity::Value(v) => Some(*v),
            Quantity::Parameter(name) => values.get(name).copied(),
        }
    }

    /// The fixed number, if it is one (not a parameter).
    pub fn number(&self) -> Option<f64> {
        match self {
            Quantity::Value(v) => Some(*v),
            Quantity::Parameter(_) => None,
        }
    }
}

impl<'de> Deserialize<'de> for Quantity {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Quantity;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or a parameter name")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Quantity, E> {
                Ok(Quantity::Value(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Quantity, E> {
                Ok(Quantity::Value(v as f64))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Quantity, E> {
                Ok(Quantity::Value(v))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Quantity, E> {
                Ok(Quantity::Parameter(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// What a literal value of a quantity must be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Range {
    /// Any finite number.
    Finite,
    /// Finite and ≥ 0.
    NonNegative,
    /// Finite and > 0.
    Positive,
}

impl Range {
    /// `Ok` if `x` lies in the range, else what is wrong with it, to follow the key in a
    /// message (`must be >= 0, got -1`): the one wording of every range check of a scene.
    pub fn check(self, x: f64) -> Result<(), String> {
        if !x.is_finite() {
            return Err(format!("must be a finite number, got {}", key_value(x)));
        }
        match self {
            Range::Finite => Ok(()),
            Range::NonNegative if x >= 0.0 => Ok(()),
            Range::NonNegative => Err(format!("must be >= 0, got {}", key_value(x))),
            Range::Positive if x > 0.0 => Ok(()),
            Range::Positive => Err(format!("must be > 0, got {}", key_value(x))),
        }
    }
}

/// An effect's key refused: the scene reports `'effect[i].<key>' <what>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// The key, relative to the effect's table.
    pub key: &'static str,
    /// What is wrong, after the key (e.g. `must be 1 or 3, got 2`).
    pub what: String,
}

impl Refusal {
    /// `'<key>' <what>`.
    pub fn at(key: &'static str, what: impl Into<String>) -> Self {
        Refusal {
            key,
            what: what.into(),
        }
    }
}

/// The membrane's natural scales, where the scene fixes them: a length a (the stress-free
/// mesh radius), a tension μH, and the symbol the length is written with (`a` or `R`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Natural {
    /// The length a, if the mesh has a radius and the prestretch is a number.
    pub length: Option<f64>,
    /// The tension μH, if μ and H are numbers.
    pub tension: Option<f64>,
    /// How the length is written.
    pub symbol: &'static str,
}

/// One parameter's dimensionless axis: the parameter times `factor` is the group `group`,
/// written with the values it was formed with.
#[derive(Debug, Clone, PartialEq)]
pub struct Scale {
    /// The parameter.
    pub parameter: String,
    /// The group, e.g. `p a/(μH)`.
    pub group: String,
    /// The fixed quantities the group uses, by symbol.
    pub values: Vec<(String, f64)>,
    /// The factor from the parameter to the group.
    pub factor: f64,
}

/// What an effect is built from besides its own keys: the parameter index of a named
/// quantity, the plate closing an open membrane's rim (if any), and the fluid amount sharing
/// the enclosure with a gas (held by a fluid-volume constraint).
pub struct Build<'a> {
    /// The model's quantity of a scene quantity (its parameter by index).
    pub quantity: &'a dyn Fn(&Quantity) -> super::Quantity,
    /// The plate closing the rim of an open membrane, if the rim is fixed in a plane.
    pub closing: Option<Arc<ClosingFace>>,
    /// The amount of fluid inside the enclosure, if a constraint holds it at a known value.
    pub fluid_amount: Option<super::Quantity>,
}

/// An effect built for the 3-D model, and what it adds to the measures of a path.
pub struct Built {
    /// Its potential.
    pub effect: Box<dyn model::Effect>,
    /// The measure it adds, if any.
    pub measured: Option<Measured>,
}

/// A measure an effect adds along a path.
#[derive(Clone)]
pub enum Measured {
    /// The volume of a fluid (`fluid_volume`).
    FluidVolume(Fluid),
    /// The over-pressure of a gas of fixed amount (`gas_pressure`).
    GasPressure(GasAmount),
}

/// An effect's load on the meridian (the axisymmetric model).
pub enum MeridianLoad {
    /// A pressure on the meridian.
    Pressure(Pressure),
    /// A plane normal to the axis.
    Plane(FloorPlane),
}

/// One `[[effect]]` type: its keys (a serde struct) and what the scene, the models and the
/// figures need of it.
pub trait EffectSpec: fmt::Debug + Send + Sync + Erased {
    /// Its quantities with their keys and the range a number must lie in, in the order of
    /// its keys.
    fn quantities(&self) -> Vec<(&'static str, &Quantity, Range)>;
    /// Checks its other keys (the quantities are checked before); may normalise them.
    fn check(&mut self) -> Result<(), Refusal> {
        Ok(())
    }
    /// Checks what needs the mesh: whether the membrane is `closed`; `the_mesh` names it.
    fn check_mesh(&self, _closed: bool, _the_mesh: &str) -> Result<(), Refusal> {
        Ok(())
    }
    /// True if it loads the region the membrane encloses, so it needs a closed membrane or
    /// an open one whose whole rim is fixed.
    fn needs_enclosure(&self) -> bool {
        true
    }
    /// True if it loads the membrane by a pressure normal to it (a gas, a fluid), which a
    /// flat membrane without pre-stretch cannot carry at its start.
    fn presses_normally(&self) -> bool {
        false
    }
    /// True if it acts on the enclosed volume itself (a gas, a fluid inside), so the path
    /// measures that volume.
    fn measures_enclosure(&self) -> bool {
        false
    }
    /// The dimensionless groups its parameters are drawn in, where `natural` has the scales
    /// they need.
    fn scales(&self, _natural: &Natural) -> Vec<Scale> {
        Vec::new()
    }
    /// Its potential in the 3-D model.
    fn build(&self, cx: &Build) -> Built;
    /// Its load on the meridian; by default refused (the effect has no axisymmetric form).
    fn meridian(&self, _cx: &Build) -> Result<MeridianLoad, Refusal> {
        Err(Refusal::at(
            "type",
            "has no form on the axisymmetric model; use a 3-D mesh",
        ))
    }
}

/// What makes an [`EffectSpec`] a value: cloned, compared, written back as TOML and read as
/// its concrete type. Implemented for every serde struct that is one.
pub trait Erased {
    /// A copy.
    fn clone_box(&self) -> Box<dyn EffectSpec>;
    /// Whether `other` is the same type with equal keys.
    fn eq_dyn(&self, other: &dyn EffectSpec) -> bool;
    /// Its keys as a TOML table.
    fn table(&self) -> toml::Table;
    /// As its concrete type.
    fn as_any(&self) -> &dyn Any;
}

impl<T: EffectSpec + Clone + PartialEq + Serialize + 'static> Erased for T {
    fn clone_box(&self) -> Box<dyn EffectSpec> {
        Box::new(self.clone())
    }
    fn eq_dyn(&self, other: &dyn EffectSpec) -> bool {
        other.as_any().downcast_ref::<T>() == Some(self)
    }
    fn table(&self) -> toml::Table {
        toml::Table::try_from(self).expect("an effect's keys serialise to a TOML table")
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// The error of reading an effect's table (with the path to the offending key).
pub type ReadError = serde_path_to_error::Error<toml::de::Error>;

/// One line of [`super::REGISTRY`]: an effect's `type` and how its table is read.
pub struct Entry {
    /// The `type` in a scene.
    pub kind: &'static str,
    /// Reads the table (without `type`).
    pub read: fn(toml::Value) -> Result<Box<dyn EffectSpec>, ReadError>,
}

impl Entry {
    /// The entry of the effect whose keys are `T`.
    pub const fn of<T: EffectSpec + serde::de::DeserializeOwned + 'static>(
        kind: &'static str,
    ) -> Entry {
        Entry {
            kind,
            read: read::<T>,
        }
    }
}

fn read<T: EffectSpec + serde::de::DeserializeOwned + 'static>(
    v: toml::Value,
) -> Result<Box<dyn EffectSpec>, ReadError> {
    serde_path_to_error::deserialize::<_, T>(v).map(|t| Box::new(t) as Box<dyn EffectSpec>)
}

/// Refuses `x` unless it is finite and ≥ 0.
pub fn non_negative(key: &'static str, x: f64) -> Result<(), Refusal> {
    Range::NonNegative
        .check(x)
        .map_err(|what| Refusal::at(key, what))
}
