//! The axisymmetric model as a path-following problem with Fourier-mode blocks: the seam
//! between the meridian and the analysis ([`crate::analysis::modes::ModeProblem`]), which
//! knows blocks and wave numbers, not membranes.

use super::{AxisymError, AxisymModel, BlockLayout};
use crate::analysis::continuation::{Linearization, PhaseTimes, Problem, Tangent};
use crate::analysis::modes::{ModeBlock, ModeProblem};
use crate::linalg::bordered::SharedFactorization;
use crate::linalg::SymmetricPattern;
use crate::model::ModelError;
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
    /// The largest wave number analysed.
    pub modes: usize,
    pattern: Arc<SymmetricPattern>,
    /// Per element, (local i, local j, slot in the tangent's values).
    slots: Vec<Vec<(usize, usize, usize)>>,
    /// The layout of every block m = 0..=modes, built once.
    layouts: Vec<BlockLayout>,
    solver: SharedFactorization,
    times: PhaseTimes,
}

fn model_error(e: AxisymError) -> ModelError {
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
        other => ModelError::Global {
            effect: "axisymmetric".into(),
            what: other.to_string(),
        },
    }
}

impl AxisymProblem {
    /// The problem of `model` with `params`, the control `control`, blocks m = 0..=`modes`.
    pub fn new(model: AxisymModel, params: Vec<f64>, control: usize, modes: usize) -> Self {
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
            layouts: (0..=modes).map(|m| model.block_layout(m)).collect(),
            model,
            params,
            control,
            modes,
            pattern: Arc::new(pattern),
            slots,
            solver: SharedFactorization::default(),
            times: PhaseTimes::default(),
        }
    }

    /// Every parameter at the free parameters λ.
    pub fn parameters(&self, lambda: &DVector<f64>) -> Vec<f64> {
        let mut p = self.params.clone();
        p[self.control] = lambda[0];
        p
    }
}

impl Problem for AxisymProblem {
    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn free_parameters(&self) -> usize {
        1
    }

    fn evaluate(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Linearization, ModelError> {
        let t = Instant::now();
        let params = self.parameters(lambda);
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
        Ok(Linearization {
            residual: DVector::from_vec(e.gradient),
            tangent: Tangent::Sparse {
                pattern: self.pattern.clone(),
                values,
                rank_one: Vec::new(),
                solver: self.solver.clone(),
            },
            loads: DMatrix::from_column_slice(n, 1, e.loads.column(self.control).as_slice()),
            constraints: DVector::zeros(0),
            constraint_q: DMatrix::zeros(0, n),
            constraint_lambda: DMatrix::zeros(0, 1),
        })
    }

    fn phase_times(&self) -> PhaseTimes {
        self.times
    }
}

impl ModeProblem for AxisymProblem {
    fn modes(&self) -> usize {
        self.modes
    }

    fn block(
        &mut self,
        m: usize,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<(Arc<SymmetricPattern>, Vec<f64>), ModelError> {
        let params = self.parameters(lambda);
        let built;
        let layout = match self.layouts.get(m) {
            Some(l) => l,
            None => {
                built = self.model.block_layout(m);
                &built
            }
        };
        let values = self
            .model
            .block_values(layout, q.as_slice(), &params)
            .map_err(model_error)?;
        Ok((layout.pattern.clone(), values))
    }

    fn blocks(
        &mut self,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
    ) -> Result<Vec<ModeBlock>, ModelError> {
        let params = self.parameters(lambda);
        let values = self
            .model
            .blocks_values(&self.layouts, q.as_slice(), &params)
            .map_err(model_error)?;
        Ok(self
            .layouts
            .iter()
            .zip(values)
            .map(|(l, v)| (l.pattern.clone(), v))
            .collect())
    }
}
