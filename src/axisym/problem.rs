//! The axisymmetric model as a path-following problem: the residual, tangent, loads and
//! constraint rows of the meridian in its own unknowns q, the control and the parameter a
//! constraint frees, and more free parameters for a critical curve — what the driver follows
//! ([`crate::continuation::Followed`]); its stability is [`super::blocks::MeridianBlocks`].

use super::{AxisymError, AxisymModel};
use crate::continuation::events::States;
use crate::continuation::{Linearization, Problem, Tangent};
use crate::linalg::bordered::SharedFactorization;
use crate::linalg::SymmetricPattern;
use crate::model::{ModelError, StateDefect};
use crate::results::PhaseTimes;
use nalgebra::{DMatrix, DVector};
use std::sync::Arc;
use std::time::Instant;

/// The axisymmetric model at every parameter's value, the control free.
pub struct AxisymProblem {
    /// The model.
    pub model: AxisymModel,
    /// Every parameter (the control's entry is overwritten by λ_0).
    pub params: Vec<f64>,
    /// The control's index among the parameters.
    pub control: usize,
    /// The fluid-volume constraint, when its level is free (the second free parameter).
    pub volume: Option<VolumeTarget>,
    /// The gas-amount constraint, when its gas's pressure is free (the second free
    /// parameter; never together with `volume`).
    pub gas: Option<GasTarget>,
    pattern: Arc<SymmetricPattern>,
    /// Per element, (local i, local j, slot in the tangent's values).
    slots: Vec<Vec<(usize, usize, usize)>>,
    /// More free parameters after the control and the constraint's (a critical curve's
    /// control).
    pub also: Vec<usize>,
    /// How many of `params` are the scene's (a dummy control slot may follow them).
    pub named: usize,
    solver: SharedFactorization,
    times: PhaseTimes,
}

/// The fluid-volume constraint on the path (`super::volume`): the row
/// g = scale · (V_f(q, h) − V*), scale = −ρ g, frees the level parameter `level`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeTarget {
    /// The level's parameter index.
    pub level: usize,
    /// V* (when `target_parameter` is `None`).
    pub target: f64,
    /// −ρ g (the row's scale, so that ∂g/∂q is the level's load).
    pub scale: f64,
    /// The parameter that is V*, if any.
    pub target_parameter: Option<usize>,
}

impl VolumeTarget {
    /// V* at the parameters `params`.
    pub fn amount(&self, params: &[f64]) -> f64 {
        self.target_parameter.map_or(self.target, |j| params[j])
    }
}

/// The gas-amount constraint on the path (`super::gas`): the row
/// g = (P_atm + p) V(q) − C* frees the gas's pressure parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasTarget {
    /// The gas's pressure parameter and the ambient pressure.
    pub gas: super::GasAmountBorder,
    /// C* (when `target_parameter` is `None`).
    pub target: f64,
    /// The parameter that is C*, if any.
    pub target_parameter: Option<usize>,
}

impl GasTarget {
    /// C* at the parameters `params`.
    pub fn amount(&self, params: &[f64]) -> f64 {
        self.target_parameter.map_or(self.target, |j| params[j])
    }
}

pub(super) fn model_error(e: AxisymError) -> ModelError {
    match e {
        AxisymError::Degenerate(element) => ModelError::Element {
            effect: "membrane".into(),
            triangle: element,
            what: "an element of the meridian inverted or collapsed".into(),
        },
        AxisymError::NonFinite => ModelError::NonFinite {
            effect: "axisymmetric".into(),
            what: "energy",
        },
        AxisymError::Material(what) => ModelError::Global {
            effect: "membrane".into(),
            what,
        },
        other => ModelError::Global {
            effect: "axisymmetric".into(),
            what: other.to_string(),
        },
    }
}

impl AxisymProblem {
    /// The problem of `model` with `params` and the control `control`.
    pub fn new(model: AxisymModel, params: Vec<f64>, control: usize) -> Self {
        // Unknowns of one element couple: the pattern of the tangent.
        let elements = model.meridian.elements();
        let dofs: Vec<Vec<usize>> = (0..elements)
            .map(|e| (0..6).filter_map(|i| model.element_unknown(e, i)).collect())
            .collect();
        let pattern = SymmetricPattern::from_entries(
            model.dim(),
            dofs.iter()
                .flat_map(|d| d.iter().flat_map(|&a| d.iter().map(move |&b| (a, b)))),
        );
        // Where each element's 6 × 6 entries go in the pattern's values.
        let slots = (0..elements)
            .map(|e| {
                let mut s = Vec::new();
                for i in 0..6 {
                    let Some(a) = model.element_unknown(e, i) else {
                        continue;
                    };
                    for j in 0..6 {
                        if let Some(b) = model.element_unknown(e, j) {
                            s.push((i, j, pattern.position(a, b).expect("an element entry")));
                        }
                    }
                }
                s
            })
            .collect();
        Self {
            model,
            params,
            control,
            also: Vec::new(),
            named: usize::MAX,
            volume: None,
            gas: None,
            pattern: Arc::new(pattern),
            slots,
            solver: SharedFactorization::default(),
            times: PhaseTimes::default(),
        }
    }

    /// Every parameter at the free parameters λ.
    pub fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        let mut p = self.all_parameters(lambda);
        p.truncate(self.named);
        p
    }

    /// [`Self::parameters`] with a dummy control slot, as the model is evaluated.
    fn all_parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        let mut p = self.params.clone();
        for (k, v) in self.free_indices().into_iter().zip(lambda.iter()) {
            p[k] = *v;
        }
        p
    }

    /// The parameter index of every free parameter: the control, the one a constraint
    /// frees, then [`Self::also`].
    pub fn free_indices(&self) -> Vec<usize> {
        std::iter::once(self.control)
            .chain(self.second())
            .chain(self.also.iter().copied())
            .collect()
    }

    /// The parameter a constraint frees: the fluid's level or the gas's pressure.
    pub fn second(&self) -> Option<usize> {
        self.volume
            .map(|v| v.level)
            .or(self.gas.map(|g| g.gas.pressure))
    }

    /// The free parameters at every parameter's value `params` (the control, then the level
    /// a constraint frees).
    pub fn free_values(&self, params: &[f64]) -> DVector<f64> {
        DVector::from_iterator(
            self.free_indices().len(),
            self.free_indices().into_iter().map(|k| params[k]),
        )
    }
}

impl Problem for AxisymProblem {
    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn free_parameters(&self) -> usize {
        1 + usize::from(self.second().is_some()) + self.also.len()
    }

    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        let t = Instant::now();
        let params = self.all_parameters(lambda);
        let mut values = vec![0.0; self.pattern.nnz()];
        let slots = &self.slots;
        let e = self
            .model
            .evaluate_elements(q.as_slice(), &params, |el, kk| {
                for &(i, j, k) in &slots[el] {
                    values[k] += kk[(i, j)];
                }
            })
            .map_err(model_error)?;
        let n = self.dim();
        self.times.assembly += t.elapsed();
        self.times.evaluations += 1;
        let free = self.free_parameters();
        let mut loads = DMatrix::zeros(n, free);
        loads.set_column(0, &e.loads.column(self.control));
        let first_also = free - self.also.len();
        for (j, &k) in self.also.iter().enumerate() {
            loads.set_column(first_also + j, &e.loads.column(k));
        }
        let mut constraint_lambda = DMatrix::zeros(0, free);
        let (constraints, constraint_q) = match (self.volume, self.gas) {
            (Some(v), _) => {
                loads.set_column(1, &e.loads.column(v.level));
                constraint_lambda = DMatrix::zeros(1, free);
                let x = self.model.positions(q.as_slice());
                let fluid = self
                    .model
                    .held_fluid(&x, &params)
                    .expect("a fluid-volume constraint has its fluid");
                let dv = self.model.free_part(&fluid.gradient);
                // ∂g/∂h = scale · A_s, ∂g/∂V* = −scale.
                constraint_lambda[(0, 1)] = v.scale * fluid.section;
                for (j, k) in self.free_indices().into_iter().enumerate() {
                    if j != 1 && v.target_parameter == Some(k) {
                        constraint_lambda[(0, j)] = -v.scale;
                    }
                }
                (
                    DVector::from_element(1, v.scale * (fluid.volume - v.amount(&params))),
                    DMatrix::from_row_slice(1, n, &dv) * v.scale,
                )
            }
            (None, Some(g)) => {
                loads.set_column(1, &e.loads.column(g.gas.pressure));
                let row =
                    self.model
                        .gas_amount_row(&g.gas, g.amount(&params), q.as_slice(), &params);
                constraint_lambda = DMatrix::zeros(1, free);
                constraint_lambda[(0, 1)] = row.grad_p;
                for (j, k) in self.free_indices().into_iter().enumerate() {
                    if j != 1 && g.target_parameter == Some(k) {
                        constraint_lambda[(0, j)] = -1.0;
                    }
                }
                (
                    DVector::from_element(1, row.value),
                    DMatrix::from_row_slice(1, n, &row.grad_q),
                )
            }
            (None, None) => (DVector::zeros(0), DMatrix::zeros(0, n)),
        };
        Ok(Linearization {
            residual: DVector::from_vec(e.gradient),
            tangent: Tangent::Sparse {
                pattern: self.pattern.clone(),
                values,
                rank_one: e
                    .rank_one
                    .into_iter()
                    .map(|(c, a)| (c, DVector::from_vec(a)))
                    .collect(),
                solver: self.solver.clone(),
            },
            loads,
            constraint_lambda,
            constraints,
            constraint_q,
        })
    }

    fn phase_times(&self) -> PhaseTimes {
        self.times
    }

    /// A closed meridian (both ends on the axis) turned inside out: its enclosed volume of
    /// the opposite sign of the reference's, as the 3-D model's check (docs/theory.md §7.5).
    fn defect(&self, q: &DVector<f64>, _lambda: &DVector<f64>) -> Option<StateDefect> {
        let nodes = &self.model.meridian.nodes;
        let on_axis = |p: &[f64; 2]| p[0].abs() <= 1e-12 * (p[0].abs() + p[1].abs() + 1.0);
        if !(nodes.first().is_some_and(on_axis) && nodes.last().is_some_and(on_axis)) {
            return None;
        }
        let v0 = self.model.volume(nodes);
        let v = self.model.volume(&self.model.positions(q.as_slice()));
        (v0 != 0.0 && v * v0.signum() <= 0.0).then_some(StateDefect::InsideOut { volume: v })
    }

    /// The nodes (rings) whose contact with a penalty plane differs between `a` and `b`, as
    /// the 3-D model's: where the tangent and the path's direction may jump (a turn there is
    /// located at the switch, docs/theory.md §7.6); `None` without a plane.
    fn switched(
        &self,
        a: (&DVector<f64>, &DVector<f64>),
        b: (&DVector<f64>, &DVector<f64>),
    ) -> Option<usize> {
        self.model.contact_changes(
            (a.0.as_slice(), &self.all_parameters(a.1)),
            (b.0.as_slice(), &self.all_parameters(b.1)),
        )
    }
}

impl States for AxisymProblem {
    fn displacement(&self, q: &DVector<f64>) -> Vec<f64> {
        q.iter().copied().collect()
    }

    fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        AxisymProblem::parameters(self, lambda)
    }
}

impl crate::continuation::Followed for AxisymProblem {
    fn coordinates(&self, u: &[f64]) -> DVector<f64> {
        DVector::from_column_slice(u)
    }

    fn free_values(&self, params: &[f64]) -> DVector<f64> {
        AxisymProblem::free_values(self, params)
    }

    fn free_indices(&self) -> Vec<usize> {
        AxisymProblem::free_indices(self)
    }
}
