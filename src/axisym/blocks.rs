//! The meridian's stability by wave number (docs/theory.md §15.3, §15.12), as the
//! [`Blocks`] every analysis reads: the block of wave number m = 0..=M at a state, each
//! standing for one (m = 0) or two (m ≥ 1, the cos/sin pair) identical copies in the full
//! tangent, bordered by the motions the analysis holds and the constraints (`axisym/held.rs`).
//!
//! A block's index is the inertia of one sparse LBLᵀ of the bordered block less its border
//! (Haynsworth); its lowest eigenvalues, where a crossing is localised or a spectrum asked for,
//! those of the block restricted to the complement of its hard border columns (held motions,
//! a filled enclosure's volume) with the soft ones (a gas amount's rank-one stiffness, a fluid
//! volume with a free surface) eliminated — by shift-invert Lanczos on the same factorisation
//! ([`BorderedBlock`]), certified by its inertia, or dense where Lanczos cannot certify them.
//! A critical mode is the block's eigenvector, kept in the block's coordinates (the amplitudes
//! U, V, W of §15.1 at the kept unknowns) and drawn on the revolved surface
//! ([`super::revolved_mode`]).

use super::{AxisymModel, BlockLayout};
use crate::continuation::crossings::{BlockSpectrum, Blocks, Spectrum};
use crate::linalg::bordered_block::{BorderedBlock, Complement};
use crate::linalg::SymmetricFactorization;
use crate::results::Isotropy;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// The shift of the Lanczos iteration below zero, relative to the block's largest entry (as
/// in the 3-D blocks).
const LANCZOS_SHIFT: f64 = 1e-6;

/// The lowest eigenvalues of every block a spectrum asks for (as of the 3-D blocks).
const SPECTRUM_LOWEST: usize = 8;

/// The name of the group a meridian's states keep: every rotation about z and every vertical
/// mirror.
pub const MERIDIAN_GROUP: &str = "O(2)";

/// The name of the block of wave number m (`m0`, `m1`, …): the `index_m<m>` column of a
/// path's table.
pub fn block_name(m: usize) -> String {
    format!("m{m}")
}

/// The wave number of a block named by [`block_name`].
pub fn wave_number(name: &str) -> Option<usize> {
    name.strip_prefix('m')?.parse().ok()
}

/// The subgroup that keeps a mode of wave number m: every rotation and mirror about z for
/// m = 0; for m ≥ 1 the rotations by 2π/m and the m mirrors through the crests of cos mθ,
/// C_mv.
pub fn isotropy(m: usize) -> Isotropy {
    match m {
        0 => Isotropy {
            name: MERIDIAN_GROUP.into(),
            order: 0,
            elements: Vec::new(),
        },
        m => Isotropy {
            name: format!("C{m}v"),
            order: 2 * m,
            elements: Vec::new(),
        },
    }
}

/// The blocks m = 0..=M of a meridian at its states.
pub struct MeridianBlocks {
    model: AxisymModel,
    layouts: Vec<BlockLayout>,
    /// Per block, the sparse LBLᵀ of its bordered pattern (symbolic analysis once).
    factorizations: Vec<Option<SymmetricFactorization>>,
}

impl MeridianBlocks {
    /// The blocks m = 0..=`modes` of `model` (its constraint borders as set on it).
    pub fn new(model: AxisymModel, modes: usize) -> Self {
        let layouts: Vec<BlockLayout> = (0..=modes).map(|m| model.block_layout(m)).collect();
        Self {
            factorizations: layouts.iter().map(|_| None).collect(),
            layouts,
            model,
        }
    }

    /// The multiplicity of block m in the full tangent.
    fn dim(m: usize) -> usize {
        if m == 0 {
            1
        } else {
            2
        }
    }

    /// The bordered block of `layout` with `values`: its hard border columns (zero corner)
    /// spanning the constrained subspace, the others eliminated with their corners.
    fn bordered(layout: &BlockLayout, values: &[f64]) -> BorderedBlock {
        let (m, b) = (layout.kept, layout.border);
        let pattern = &layout.pattern;
        let diagonal = (0..m)
            .map(|j| pattern.position(j, j).expect("a diagonal entry"))
            .collect();
        let entry = |i: usize, j: usize| pattern.position(i, j).map_or(0.0, |k| values[k]);
        let mut hard = Vec::new();
        let mut d_negative = 0;
        for t in m..m + b {
            let corner = entry(t, t);
            if corner == 0.0 {
                hard.push(DVector::from_iterator(m, (0..m).map(|i| entry(i, t))));
            } else if corner < 0.0 {
                d_negative += 1;
            }
        }
        let constrained = if hard.is_empty() {
            Vec::new()
        } else {
            let span = Complement::of(&DMatrix::from_columns(&hard), 1e-24);
            (0..span.rank())
                .map(|k| span.span_column(k, m).as_slice().to_vec())
                .collect()
        };
        BorderedBlock {
            m,
            constrained,
            d_negative,
            values: values.to_vec(),
            diagonal,
            paired: false,
        }
    }

    /// The eigenvalues (ascending) and eigenvectors of the restricted block, dense: the
    /// block proper with the soft border columns eliminated (A − U_D E_D⁻¹ U_Dᵀ), on the
    /// complement of the hard ones.
    fn dense(layout: &BlockLayout, values: &[f64], vectors: bool) -> (Vec<f64>, DMatrix<f64>) {
        let (m, b) = (layout.kept, layout.border);
        let full = layout.pattern.to_dense(values);
        let mut a = DMatrix::from_fn(m, m, |i, j| full[(i, j)]);
        let mut hard = Vec::new();
        for t in m..m + b {
            let u = DVector::from_fn(m, |i, _| full[(i, t)]);
            let corner = full[(t, t)];
            if corner == 0.0 {
                hard.push(u);
            } else {
                a -= &u * u.transpose() / corner;
            }
        }
        let a = (&a + a.transpose()) * 0.5;
        let complement =
            (!hard.is_empty()).then(|| Complement::of(&DMatrix::from_columns(&hard), 1e-24));
        let restricted = match &complement {
            Some(c) => c.restrict(a),
            None => a,
        };
        let eigen = nalgebra::SymmetricEigen::new(restricted);
        let mut order: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
        order.sort_by(|&x, &y| eigen.eigenvalues[x].total_cmp(&eigen.eigenvalues[y]));
        let values = order.iter().map(|&k| eigen.eigenvalues[k]).collect();
        let vecs = if vectors {
            let y = DMatrix::from_fn(eigen.eigenvectors.nrows(), order.len(), |i, j| {
                eigen.eigenvectors[(i, order[j])]
            });
            match &complement {
                Some(c) => c.lift(&y),
                None => y,
            }
        } else {
            DMatrix::zeros(m, 0)
        };
        (values, vecs)
    }

    /// Every block's negative count (and, for the blocks `only` selects, its lowest `lowest`
    /// eigenvalues, with eigenvectors when asked for).
    fn analyse(
        &mut self,
        q: &[f64],
        params: &[f64],
        only: Option<usize>,
        lowest: usize,
        vectors: bool,
    ) -> Option<Spectrum> {
        let values = self.model.blocks_values(&self.layouts, q, params).ok()?;
        let scale = values
            .iter()
            .flatten()
            .fold(0.0f64, |s, v| s.max(v.abs()))
            .max(1e-300);
        let blocks: Vec<Option<BlockSpectrum>> = self
            .factorizations
            .par_iter_mut()
            .zip(self.layouts.par_iter())
            .zip(values.par_iter())
            .map(|((cache, layout), values)| {
                let m = layout.m;
                let mut spectrum = BlockSpectrum {
                    irrep: block_name(m),
                    dim: Self::dim(m),
                    size: layout.kept,
                    rigid_modes: 0,
                    held: 0,
                    rigid_residual: 0.0,
                    eigenvalues: Vec::new(),
                    complete: false,
                    eigen_error: None,
                    negative: 0,
                    vectors: DMatrix::zeros(layout.kept, 0),
                };
                if only.is_some_and(|o| o != m) {
                    return Some(spectrum);
                }
                if cache.is_none() {
                    *cache = Some(SymmetricFactorization::new(&layout.pattern).ok()?);
                }
                let fact = cache.as_mut()?;
                let block = Self::bordered(layout, values);
                spectrum.negative = match block.count_below(fact, 0.0, false) {
                    Ok(n) => n,
                    Err(_) => return None,
                };
                if lowest == 0 {
                    return Some(spectrum);
                }
                let wanted = lowest.max(spectrum.negative + 1);
                let shift = -LANCZOS_SHIFT * scale;
                match block.lowest(fact, wanted, shift, vectors) {
                    (Ok(found), rank) => {
                        spectrum.complete = found.values.len() >= rank;
                        if vectors && !found.vectors.is_empty() {
                            spectrum.vectors =
                                DMatrix::from_fn(layout.kept, found.vectors.len(), |i, j| {
                                    found.vectors[j][i]
                                });
                        }
                        spectrum.eigenvalues = found.values;
                    }
                    (Err(_), _) => {
                        // Lanczos could not certify them: the whole spectrum, dense.
                        let (all, vecs) = Self::dense(layout, values, vectors);
                        spectrum.complete = true;
                        spectrum.eigenvalues = all;
                        spectrum.vectors = vecs;
                    }
                }
                Some(spectrum)
            })
            .collect();
        let blocks: Vec<BlockSpectrum> = blocks.into_iter().collect::<Option<_>>()?;
        let index = blocks.iter().map(|b| b.dim * b.negative).sum();
        Some(Spectrum {
            blocks,
            index,
            scale,
        })
    }
}

impl Blocks for MeridianBlocks {
    fn names(&self) -> Vec<String> {
        self.layouts.iter().map(|l| block_name(l.m)).collect()
    }

    fn index(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.analyse(u, params, None, 0, false)
    }

    fn spectrum(&mut self, u: &[f64], params: &[f64]) -> Option<Spectrum> {
        self.analyse(u, params, None, SPECTRUM_LOWEST, false)
    }

    fn block_eigen(
        &mut self,
        u: &[f64],
        params: &[f64],
        block: usize,
        lowest: usize,
        vectors: bool,
    ) -> Option<Spectrum> {
        self.analyse(u, params, Some(block), lowest, vectors)
    }

    fn mode(&self, _block: usize, v: &[f64]) -> Vec<f64> {
        v.to_vec()
    }

    /// The nodes (rings) whose contact with a plane differs between the states `a` and `b`
    /// (a linear penalty's stiffness starts there, docs/theory.md §8.9); `None` without a
    /// plane.
    fn switched(&self, a: (&[f64], &[f64]), b: (&[f64], &[f64])) -> Option<usize> {
        self.model.contact_changes(a, b)
    }

    /// A meridian block costs a few hundred element evaluations: crossings are localised to
    /// round-off (the bracket at round-off of the step), as a fold where its eigenvalue is
    /// weak against the block's largest entry (a stiff plane's penalty) would otherwise be
    /// left uncertain in the control.
    fn zero_eigenvalue(&self) -> f64 {
        0.0
    }

    fn isotropy(&self, block: usize, _mode: &[f64]) -> Isotropy {
        isotropy(self.layouts[block].m)
    }
}
