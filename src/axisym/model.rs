//! Equilibria of a membrane of revolution and their Fourier-mode blocks (docs/theory.md §15).
//!
//! The unknowns are the displacements (u_r, u_z) of the meridian's nodes that are free: a
//! clamped end holds both, a node on the axis holds u_r = 0 (regularity), and on a closed
//! meridian (both ends on the axis, none clamped) the first node's u_z is held too, which
//! removes the rigid translation along z and costs nothing at an equilibrium of a
//! self-equilibrated load (a gas in a closed membrane exerts no net force), unless a plane
//! carries the membrane (docs/theory.md §15.16).
//!
//! The potential is Π = Π_membrane + Σ Π_pressure, each integrated by Gauss–Legendre
//! quadrature along the meridian and exactly in θ (a factor 2π):
//!
//! ```text
//!   Π_membrane = 2π H ∫ W(F) |X_ξ| R / λ0² dξ,   f1 = λ0 x_ξ/|X_ξ|,  f2 = λ0 r/R e_θ,
//!   Π_pressure = −s π ∫ r² p(z) z_ξ dξ,
//! ```
//!
//! with μ, k and H (in W and H) numbers or parameters read at every evaluation, their loads
//! exact (docs/theory.md §15.18), and where a pressure p(z) pushes along −s n with
//! n dA = x_ξ × x_θ dξ dθ: its first variation is s ∫ p n·δx dA (integrating by parts, the
//! end terms vanish on the axis, r = 0, and at a clamped end, δz = 0). A gas of over-pressure
//! P on the side n points away from is s = −1, p = P (Π = −P V with V = −π ∫ r² z_ξ dξ); a
//! fluid of density ρ under gravity g with its level at h has p = ρ g (h − z), s = +1 on the
//! side n points to ("above" a floor whose meridian runs outward from the axis) and s = −1
//! behind it, integrated over the part of each element below the level (z(ξ) < h, between
//! the roots of a quadratic), where a moving wetting line adds a term to the tangent
//! (docs/theory.md §15.14).
//!
//! The blocks of wave number m are the second variations of the same potentials for the 3-D
//! displacement δx = U cos mθ e_r + V sin mθ e_θ + W cos mθ e_z (docs/theory.md §15.2): with
//! δx = C cos mθ + S sin mθ, the θ integrals of the products are π (CᵀHC + SᵀHS) for m ≥ 1
//! and 2π (C + S)ᵀH(C + S) for m = 0, exactly.

use super::{AxisymError, FloorPlane, Meridian};
use crate::effects::membrane::{MooneyRivlin, TensionState};
use crate::effects::Quantity;
use crate::linalg::SymmetricPattern;
use nalgebra::{Matrix3, SMatrix, Vector3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::Arc;

/// A pressure on the meridian (see the module docs for the potential).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pressure {
    /// A gas at over-pressure `pressure` on the side n points away from (inside a
    /// closed meridian that runs from the north pole to the south pole, below a disc).
    Gas {
        /// The over-pressure P.
        pressure: Quantity,
    },
    /// A fluid p = ρ g (h − z), on the side n points to (`front`) or behind it.
    Fluid {
        /// ρ.
        density: Quantity,
        /// g.
        gravity: Quantity,
        /// h.
        level: Quantity,
        /// True: the fluid is on the side n points to (s = +1).
        front: bool,
        /// The enclosure is completely filled (docs/theory.md §15.10): the pressure is
        /// ρ g (h − z) on the whole meridian, also where it is negative, and no node is above
        /// a wetting line.
        filled: bool,
    },
    /// Fluid spinning about z behind the membrane: the centrifugal pressure p = ρ ω² r²/2,
    /// potential in [`super::spin`].
    Spin {
        /// ρ.
        density: Quantity,
        /// ω².
        omega2: Quantity,
    },
    /// A fixed amount of gas at constant temperature on the side n points away from,
    /// sharing the enclosure with the fluid amount `fluid` (docs/theory.md §3.5, §15.16):
    /// Π = −C ln V_g + P_atm V_g with V_g = V − V*, the over-pressure C/V_g − P_atm. A global
    /// term: the model resolves it to a gas at that over-pressure for the integrals along the
    /// meridian and adds the rank-one stiffness (C/V_g²) ∇V ∇Vᵀ ([`super::gas`]).
    GasAmount {
        /// C = absolute pressure × gas volume.
        amount: Quantity,
        /// The ambient (absolute) pressure P_atm.
        ambient: f64,
        /// V*: the fluid's amount in the same enclosure (none: the gas fills it).
        fluid: Option<Quantity>,
    },
}

/// p, p'(z), and the same for the derivative along parameter `j` (when it enters).
struct PressureAt {
    sign: f64,
    p: f64,
    dp: f64,
}

impl Pressure {
    fn sign(&self) -> f64 {
        match self {
            Pressure::Gas { .. } | Pressure::Spin { .. } | Pressure::GasAmount { .. } => -1.0,
            Pressure::Fluid { front, .. } => {
                if *front {
                    1.0
                } else {
                    -1.0
                }
            }
        }
    }

    /// ∂p/∂r at radius r (the spin's; 0 for a pressure of z alone).
    fn radial(&self, r: f64, params: &[f64]) -> f64 {
        match self {
            Pressure::Gas { .. } | Pressure::Fluid { .. } | Pressure::GasAmount { .. } => 0.0,
            Pressure::Spin { density, omega2 } => density.value(params) * omega2.value(params) * r,
        }
    }

    /// p and ∂p/∂z at (r, z), or their derivatives along parameter `along` when given.
    fn at(&self, r: f64, z: f64, params: &[f64], along: Option<usize>) -> PressureAt {
        let sign = self.sign();
        let (p, dp) = match (*self, along) {
            (Pressure::Spin { density, omega2 }, along) => {
                let (rho, w2) = (density.value(params), omega2.value(params));
                let d = match along {
                    None => rho * w2,
                    Some(j) => spin_along(density, omega2, params, j),
                };
                (0.5 * d * r * r, 0.0)
            }
            // Resolved to a gas at its over-pressure before any integral (`resolved_pressures`).
            (Pressure::GasAmount { .. }, _) => (0.0, 0.0),
            (Pressure::Gas { pressure }, None) => (pressure.value(params), 0.0),
            (Pressure::Gas { pressure }, Some(j)) => (
                if pressure.parameter() == Some(j) {
                    1.0
                } else {
                    0.0
                },
                0.0,
            ),
            (
                Pressure::Fluid {
                    density,
                    gravity,
                    level,
                    ..
                },
                along,
            ) => {
                let (rho, g, h) = (
                    density.value(params),
                    gravity.value(params),
                    level.value(params),
                );
                match along {
                    None => (rho * g * (h - z), -rho * g),
                    Some(j) => {
                        let mut p = 0.0;
                        let mut dp = 0.0;
                        if density.parameter() == Some(j) {
                            p += g * (h - z);
                            dp -= g;
                        }
                        if gravity.parameter() == Some(j) {
                            p += rho * (h - z);
                            dp -= rho;
                        }
                        if level.parameter() == Some(j) {
                            p += rho * g;
                        }
                        (p, dp)
                    }
                }
            }
        };
        PressureAt { sign, p, dp }
    }

    /// The parameter index of the level of a fluid with a wetting line.
    pub(super) fn level_parameter(&self) -> Option<usize> {
        match self {
            Pressure::Gas { .. } | Pressure::Spin { .. } | Pressure::GasAmount { .. } => None,
            Pressure::Fluid { filled: true, .. } => None,
            Pressure::Fluid { level, .. } => level.parameter(),
        }
    }

    pub(super) fn level(&self, params: &[f64]) -> Option<f64> {
        match self {
            Pressure::Gas { .. } | Pressure::Spin { .. } | Pressure::GasAmount { .. } => None,
            Pressure::Fluid { filled: true, .. } => None,
            Pressure::Fluid { level, .. } => Some(level.value(params)),
        }
    }
}

/// ∂(ρ ω²)/∂λ_j.
fn spin_along(density: Quantity, omega2: Quantity, params: &[f64], j: usize) -> f64 {
    let mut d = 0.0;
    if density.parameter() == Some(j) {
        d += omega2.value(params);
    }
    if omega2.parameter() == Some(j) {
        d += density.value(params);
    }
    d
}

/// The equilibrium problem of a membrane of revolution: a meridian and its pressures.
#[derive(Debug, Clone)]
pub struct AxisymModel {
    /// The meridian (stress-free data, clamped ends).
    pub meridian: Meridian,
    /// The pressures.
    pub pressures: Vec<Pressure>,
    /// Rigid planes normal to the axis ([`super::plane`]).
    pub planes: Vec<FloorPlane>,
    /// The parameter index of a fluid level governed by the fluid-volume constraint
    /// ([`super::volume`]): the block m = 0 is then bordered by the volume's gradient.
    pub volume_level: Option<usize>,
    /// The gas whose amount the gas-amount constraint holds ([`super::gas`]): the block
    /// m = 0 is then bordered by the volume's gradient with a negative corner.
    pub gas_amount: Option<super::gas::GasAmountBorder>,
    /// The free unknowns: (node, component 0 = r, 1 = z).
    free: Vec<(usize, usize)>,
    /// Per node and component, the index of the unknown (None: held).
    index: Vec<[Option<usize>; 2]>,
}

/// The free unknowns of `meridian` and the index of every node's components: a clamped end
/// holds both, a node on the axis its r, a sliding end its z, and the first pole's z when
/// `hold_pole`.
type Unknowns = (Vec<(usize, usize)>, Vec<[Option<usize>; 2]>);

fn unknowns(meridian: &Meridian, hold_pole: bool) -> Unknowns {
    let n = meridian.nodes.len();
    let mut free = Vec::new();
    let mut index = vec![[None; 2]; n];
    for (i, x) in meridian.nodes.iter().enumerate() {
        if meridian.is_clamped(i) {
            continue;
        }
        for (c, slot) in index[i].iter_mut().enumerate() {
            let held = (c == 0 && x[0] == 0.0)
                || (c == 1 && hold_pole && i == 0)
                || (c == 1 && meridian.is_sliding(i));
            if !held {
                *slot = Some(free.len());
                free.push((i, c));
            }
        }
    }
    (free, index)
}

/// Π, its gradient and its Hessian over the free unknowns.
#[derive(Debug, Clone)]
pub struct Evaluated {
    /// Π.
    pub energy: f64,
    /// ∂Π/∂q.
    pub gradient: Vec<f64>,
    /// ∂²Π/∂q² (dense, symmetric).
    pub tangent: nalgebra::DMatrix<f64>,
    /// ∂²Π/∂q∂λ_j for every parameter j (columns).
    pub loads: nalgebra::DMatrix<f64>,
    /// Rank-one terms c a aᵀ of the tangent (a gas amount's), over the free unknowns: part
    /// of [`Self::tangent`] in [`AxisymModel::evaluate`], handed on separately by
    /// [`AxisymModel::evaluate_elements`].
    pub rank_one: Vec<(f64, Vec<f64>)>,
}

/// A symmetric Fourier block on its own pattern (both triangles stored).
#[derive(Debug, Clone)]
pub struct Block {
    /// The pattern.
    pub pattern: Arc<SymmetricPattern>,
    /// Values aligned with the pattern's row indices.
    pub values: Vec<f64>,
}

impl AxisymModel {
    /// The model of `meridian` under `pressures`.
    pub fn new(meridian: Meridian, pressures: Vec<Pressure>) -> Self {
        let (free, index) = unknowns(&meridian, meridian.closed());
        Self {
            meridian,
            pressures,
            planes: Vec::new(),
            volume_level: None,
            gas_amount: None,
            free,
            index,
        }
    }

    /// Sets the rigid planes. A closed meridian resting on a plane is not self-equilibrated
    /// (the plane carries the fluid's weight), so its first pole's height is then free: the
    /// plane's contact holds the translation along z, and a start that does not touch it yet
    /// holds the mean height instead (`[start] hold-translation`, docs/theory.md §15.16).
    pub fn set_planes(&mut self, planes: Vec<FloorPlane>) {
        self.planes = planes;
        (self.free, self.index) = unknowns(&self.meridian, self.pole_held());
    }

    /// Whether the first pole's height is held: on a closed meridian without a plane.
    pub fn pole_held(&self) -> bool {
        self.meridian.closed() && self.planes.is_empty()
    }

    /// The index of the unknown of node `node`, component `c` (0: r, 1: z), if it is free.
    pub fn unknown(&self, node: usize, c: usize) -> Option<usize> {
        self.index[node][c]
    }

    /// The (node, component) of unknown k.
    pub fn free_unknown(&self, k: usize) -> (usize, usize) {
        self.free[k]
    }

    /// Number of unknowns.
    pub fn dim(&self) -> usize {
        self.free.len()
    }

    /// The nodes (r, z) at the displacement `q`.
    pub fn positions(&self, q: &[f64]) -> Vec<[f64; 2]> {
        let mut x = self.meridian.nodes.clone();
        for (k, &(i, c)) in self.free.iter().enumerate() {
            x[i][c] += q[k];
        }
        x
    }

    /// The node and component (0 = r, 1 = z) of every unknown of q.
    pub fn free(&self) -> &[(usize, usize)] {
        &self.free
    }

    /// The displacement q that puts the nodes at `x` (held components are ignored).
    pub fn displacement_of(&self, x: &[[f64; 2]]) -> Vec<f64> {
        self.free
            .iter()
            .map(|&(i, c)| x[i][c] - self.meridian.nodes[i][c])
            .collect()
    }

    /// The enclosed volume V = −π ∫ r² z_ξ dξ at the nodes `x`.
    pub fn volume(&self, x: &[[f64; 2]]) -> f64 {
        (0..self.meridian.elements())
            .flat_map(|e| super::volume::volume_points(x, e))
            .map(|p| -PI * p.r * p.r * p.dz * p.w)
            .sum()
    }

    /// The largest principal stretch at displacement `q` over the elements' quadrature
    /// points, from the stress-free state: the larger of the meridional λ_s = λ₀|x_ξ|/|X_ξ|
    /// and the hoop λ_θ = λ₀ r/R (λ₀ the pre-stretch; the two are principal, x_ξ lying in
    /// the (r, z) plane and the hoop direction normal to it; docs/theory.md §15.2).
    pub fn largest_stretch(&self, q: &[f64]) -> f64 {
        let x = self.positions(q);
        let lam = self.meridian.prestretch;
        (0..self.meridian.elements())
            .flat_map(|e| super::points(&self.meridian, &x, e))
            .map(|p| {
                let (s, t) = p.stretches(lam);
                s.max(t)
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The elements with a negative principal tension at one of their quadrature points at
    /// displacement `q`: the meridional and hoop directions are principal, and the
    /// incompressible Mooney–Rivlin membrane's tension along λ₁ is
    /// 2H(λ₁ − λ₁⁻³λ₂⁻²)(c₁ + c₂λ₂²), negative exactly where λ₁⁴λ₂² < 1 (c₁ > 0, c₂ ≥ 0) — the
    /// 3-D mesh's `wrinkled` triangles, counted per element (docs/theory.md §8.10).
    pub fn wrinkled_elements(&self, q: &[f64]) -> usize {
        let x = self.positions(q);
        let lam = self.meridian.prestretch;
        (0..self.meridian.elements())
            .filter(|&e| {
                super::points(&self.meridian, &x, e).iter().any(|p| {
                    let (s, t) = p.stretches(lam);
                    s.powi(4) * t * t < 1.0 || t.powi(4) * s * s < 1.0
                })
            })
            .count()
    }

    /// The current areas of the membrane in the wrinkled and in the slack state of the
    /// relaxed energy at displacement `q` ([`TensionState::of_stretches`] of the meridional
    /// and hoop stretches, the principal ones of a state of revolution, at each Gauss
    /// point, 2π r |x_ξ| w of area each).
    pub fn tension_areas(&self, q: &[f64]) -> [f64; 2] {
        let x = self.positions(q);
        let lam = self.meridian.prestretch;
        let mut areas = [0.0; 2];
        for e in 0..self.meridian.elements() {
            for p in super::points(&self.meridian, &x, e) {
                let (s, t) = p.stretches(lam);
                let area = 2.0 * PI * p.r * p.x_xi.norm() * p.weight;
                match TensionState::of_stretches(s, t) {
                    TensionState::Taut => {}
                    TensionState::Wrinkled => areas[0] += area,
                    TensionState::Slack => areas[1] += area,
                }
            }
        }
        areas
    }

    /// Every node's deepest penetration ⟨d − n_z z⟩ of the planes at displacement `q` (0
    /// where it is clear of them) and the mean length of the elements' chords (two per
    /// quadratic element) there; `None` without a plane.
    pub fn penetrations(&self, q: &[f64], params: &[f64]) -> Option<(Vec<f64>, f64)> {
        if self.planes.is_empty() {
            return None;
        }
        let x = self.positions(q);
        let depth = x
            .iter()
            .map(|p| {
                self.planes
                    .iter()
                    .map(|plane| (plane.offset.value(params) - plane.normal_z * p[1]).max(0.0))
                    .fold(0.0, f64::max)
            })
            .collect();
        let chords: f64 = x
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum();
        Some((depth, chords / (x.len() - 1).max(1) as f64))
    }

    /// How many nodes (rings) are in contact with a plane at one of the states `a` and `b`,
    /// each (q, params), and not at the other; `None` without a plane.
    pub fn contact_changes(&self, a: (&[f64], &[f64]), b: (&[f64], &[f64])) -> Option<usize> {
        let (before, _) = self.penetrations(a.0, a.1)?;
        let (after, _) = self.penetrations(b.0, b.1)?;
        Some(
            before
                .iter()
                .zip(&after)
                .filter(|(x, y)| (**x > 0.0) != (**y > 0.0))
                .count(),
        )
    }

    /// Π, gradient, tangent and parameter loads at displacement `q`, parameters `params`.
    pub fn evaluate(&self, q: &[f64], params: &[f64]) -> Result<Evaluated, AxisymError> {
        let nq = self.dim();
        let mut tangent = nalgebra::DMatrix::zeros(nq, nq);
        let mut out = self.evaluate_elements(q, params, |e, kk| {
            for i in 0..6 {
                let Some(a) = self.element_unknown(e, i) else {
                    continue;
                };
                for j in 0..6 {
                    if let Some(b) = self.element_unknown(e, j) {
                        tangent[(a, b)] += kk[(i, j)];
                    }
                }
            }
        })?;
        for (c, a) in &out.rank_one {
            let a = nalgebra::DVector::from_column_slice(a);
            tangent += &a * a.transpose() * *c;
        }
        out.tangent = tangent;
        Ok(out)
    }

    /// The unknown of element e's local unknown i (r, z per node, node-major), if free.
    pub fn element_unknown(&self, e: usize, i: usize) -> Option<usize> {
        self.index[2 * e + i / 2][i % 2]
    }

    /// Π, gradient and parameter loads at displacement `q`, each element's 6 × 6 tangent
    /// (over [`Self::element_unknown`]) handed to `tangent` instead of assembled; the
    /// returned [`Evaluated::tangent`] is empty.
    pub fn evaluate_elements(
        &self,
        q: &[f64],
        params: &[f64],
        mut tangent: impl FnMut(usize, &SMatrix<f64, 6, 6>),
    ) -> Result<Evaluated, AxisymError> {
        let x = self.positions(q);
        let nq = self.dim();
        let mut out = Evaluated {
            energy: 0.0,
            gradient: vec![0.0; nq],
            tangent: nalgebra::DMatrix::zeros(0, 0),
            loads: nalgebra::DMatrix::zeros(nq, params.len()),
            rank_one: Vec::new(),
        };
        let pressures = self.resolved_pressures(&x, params)?;
        let lam = self.meridian.prestretch;
        let quantities = &self.meridian.material;
        let [mu, k, h] = quantities.values(params)?;
        let material = MooneyRivlin::new(mu, k, h);
        // The material's parameters: W is linear in μ (through c1, c2) and the energy in H,
        // so their loads are the membrane's gradient over μ and over H; W is linear in
        // (c1, c2), so the load of k is the gradient of the material (∂c1/∂k, ∂c2/∂k)
        // (docs/theory.md §2.5, §15.18).
        let (mu_slot, k_slot, h_slot) = (
            quantities.mu.parameter(),
            quantities.k.parameter(),
            quantities.thickness.parameter(),
        );
        let along_k = k_slot.map(|_| MooneyRivlin::derivative_in_k(mu, k, h));
        for e in 0..self.meridian.elements() {
            // Element gradient and Hessian over its 6 unknowns (r, z per node, node-major).
            let mut g = [0.0; 6];
            let mut kk = SMatrix::<f64, 6, 6>::zeros();
            let mut loads = vec![[0.0; 6]; params.len()];
            for p in super::points(&self.meridian, &x, e) {
                let a = lam / p.dx_ref;
                let b = lam / p.big_r;
                let f = [p.x_xi * a, Vector3::new(0.0, p.r * b, 0.0)];
                let (w, pk, hf) = self
                    .meridian
                    .energy_in_f(&material, &f)
                    .ok_or(AxisymError::Degenerate(e))?;
                let da = 2.0 * PI * h * p.dx_ref * p.big_r / (lam * lam) * p.weight;
                out.energy += w * da;
                // ∂f_i/∂(node k, component c).
                let df = |k: usize, c: usize| -> [Vector3<f64>; 2] {
                    if c == 0 {
                        [
                            Vector3::new(a * p.dn[k], 0.0, 0.0),
                            Vector3::new(0.0, b * p.n[k], 0.0),
                        ]
                    } else {
                        [Vector3::new(0.0, 0.0, a * p.dn[k]), Vector3::zeros()]
                    }
                };
                for i in 0..6 {
                    let di = df(i / 2, i % 2);
                    g[i] += (pk[0].dot(&di[0]) + pk[1].dot(&di[1])) * da;
                    for j in 0..6 {
                        let dj = df(j / 2, j % 2);
                        let mut s = 0.0;
                        for u in 0..2 {
                            for v in 0..2 {
                                s += di[u].dot(&(hf[u][v] * dj[v]));
                            }
                        }
                        kk[(i, j)] += s * da;
                    }
                }
                if let (Some(j), Some(dmat)) = (k_slot, &along_k) {
                    let (_, dpk, _) = self
                        .meridian
                        .energy_in_f(dmat, &f)
                        .ok_or(AxisymError::Degenerate(e))?;
                    for (i, l) in loads[j].iter_mut().enumerate() {
                        let di = df(i / 2, i % 2);
                        *l += (dpk[0].dot(&di[0]) + dpk[1].dot(&di[1])) * da;
                    }
                }
            }
            // Here g is the membrane's gradient alone.
            for (slot, value) in [(mu_slot, mu), (h_slot, h)] {
                if let Some(j) = slot {
                    for (l, gi) in loads[j].iter_mut().zip(g) {
                        *l += gi / value;
                    }
                }
            }
            // Pressures: Π = −s π ∫ r² p(z) z_ξ dξ, a fluid with a wetting line over the
            // element's wet part only (docs/theory.md §15.14).
            let zs = [x[2 * e][1], x[2 * e + 1][1], x[2 * e + 2][1]];
            for load in &pressures {
                if let Pressure::Spin { .. } = load {
                    // On the 5-point rule below.
                    continue;
                }
                let wet = load.level(params).map(|lv| super::wet_part(zs, lv));
                let rule = wet.as_ref().map_or(&super::GAUSS[..], |w| &w.rule[..]);
                for p in super::points_on(&self.meridian, &x, e, rule) {
                    let (r, dz) = (p.r, p.x_xi[2]);
                    let z: f64 = (0..3).map(|k| p.n[k] * x[2 * e + k][1]).sum();
                    let pa = load.at(r, z, params, None);
                    let c = -pa.sign * PI * p.weight;
                    out.energy += c * r * r * pa.p * dz;
                    let grad = |pa: &PressureAt, gr: &mut [f64; 6]| {
                        for k in 0..3 {
                            gr[2 * k] += c * 2.0 * r * pa.p * dz * p.n[k];
                            gr[2 * k + 1] += c * r * r * (pa.dp * dz * p.n[k] + pa.p * p.dn[k]);
                        }
                    };
                    grad(&pa, &mut g);
                    for (j, l) in loads.iter_mut().enumerate() {
                        let pj = load.at(r, z, params, Some(j));
                        if pj.p != 0.0 || pj.dp != 0.0 {
                            grad(&pj, l);
                        }
                    }
                    for k in 0..3 {
                        for l in 0..3 {
                            let (nk, nl, dk, dl) = (p.n[k], p.n[l], p.dn[k], p.dn[l]);
                            kk[(2 * k, 2 * l)] += c * 2.0 * pa.p * dz * nk * nl;
                            let rz =
                                c * (2.0 * r * pa.dp * dz * nk * nl + 2.0 * r * pa.p * nk * dl);
                            kk[(2 * k, 2 * l + 1)] += rz;
                            kk[(2 * l + 1, 2 * k)] += rz;
                            kk[(2 * k + 1, 2 * l + 1)] += c * r * r * pa.dp * (nk * dl + dk * nl);
                        }
                    }
                }
                // The moving wetting line: the gradient's integrand there is −s π r² p' z_ξ N_k
                // on the z unknowns (p = 0), and the limit moves by ∂ξ*/∂z_l = −N_l/z_ξ and
                // ∂ξ*/∂h = 1/z_ξ, with the sign of the limit (+ at an upper one, z_ξ > 0).
                for (w, &(xi, slope)) in wet
                    .iter()
                    .flat_map(|w| w.crossings.iter().map(move |c| (w, c)))
                {
                    let (n, _) = super::shape(xi);
                    let r: f64 = (0..3).map(|k| n[k] * x[2 * e + k][0]).sum();
                    let pa = load.at(r, w.level, params, None);
                    let c = -pa.sign * PI * r * r * pa.dp * slope.signum();
                    for k in 0..3 {
                        for l in 0..3 {
                            kk[(2 * k + 1, 2 * l + 1)] -= c * n[k] * n[l];
                        }
                        for (j, lj) in loads.iter_mut().enumerate() {
                            if load.level_parameter() == Some(j) {
                                lj[2 * k + 1] += c * n[k];
                            }
                        }
                    }
                }
            }
            // The spin: r⁴ z_ξ is of degree 9 on a quadratic element.
            for load in &pressures {
                let Pressure::Spin { density, omega2 } = *load else {
                    continue;
                };
                for p in super::points_on(&self.meridian, &x, e, &super::GAUSS5) {
                    let (r, dz) = (p.r, p.x_xi[2]);
                    let base = PI / 4.0 * p.weight;
                    let k = base * density.value(params) * omega2.value(params);
                    let (n, dn) = (&p.n, &p.dn);
                    let mut energy = 0.0;
                    super::spin::add_point(k, r, dz, n, dn, &mut energy, &mut g, Some(&mut kk));
                    out.energy += energy;
                    for (j, l) in loads.iter_mut().enumerate() {
                        let d = spin_along(density, omega2, params, j);
                        if d != 0.0 {
                            super::spin::add_point(base * d, r, dz, n, dn, &mut 0.0, l, None);
                        }
                    }
                }
            }
            // The planes, on the nodes this element owns.
            for k in self.owned_nodes(e) {
                let z = x[2 * e + k][1];
                for plane in &self.planes {
                    let c = plane.at(z, params);
                    out.energy += c.energy;
                    g[2 * k + 1] += c.gradient;
                    kk[(2 * k + 1, 2 * k + 1)] += c.stiffness;
                    for (j, l) in loads.iter_mut().enumerate() {
                        l[2 * k + 1] += c.loads[j];
                    }
                }
            }
            for i in 0..6 {
                let Some(a) = self.element_unknown(e, i) else {
                    continue;
                };
                out.gradient[a] += g[i];
                for (j, l) in loads.iter().enumerate() {
                    out.loads[(a, j)] += l[i];
                }
            }
            tangent(e, &kk);
        }
        self.add_gas_amounts(q, &x, params, &mut out)?;
        if !out.energy.is_finite() || out.gradient.iter().any(|v| !v.is_finite()) {
            return Err(AxisymError::NonFinite);
        }
        Ok(out)
    }

    /// The local nodes (0, 1, 2) of element e that it owns for node-wise terms: 0 and 1, and
    /// 2 on the last element.
    fn owned_nodes(&self, e: usize) -> std::ops::Range<usize> {
        if e + 1 == self.meridian.elements() {
            0..3
        } else {
            0..2
        }
    }

    /// The kept unknowns of a block of wave number m: for every full unknown (U, V, W per
    /// node), the kept columns it is made of, and their number. Clamped ends hold everything;
    /// a node on the axis keeps W for m = 0, U = −V for m = 1 and nothing for m ≥ 2; on a
    /// closed meridian the rigid motions of the block are removed by holding unknowns that
    /// meet them (docs/theory.md §15.2): W at the first node for m = 0 (translation along z;
    /// not with a plane, which holds it, §15.16) and V at the widest node (rotation about z); for m = 1 the first node's U = −V
    /// (translation) and W at the widest node (rotation about a horizontal axis).
    pub(super) fn kept_map(&self, m: usize) -> (Vec<Option<(usize, f64)>>, usize) {
        let nodes = &self.meridian.nodes;
        let n = nodes.len();
        let widest = (0..n)
            .max_by(|&a, &b| nodes[a][0].total_cmp(&nodes[b][0]))
            .unwrap_or(0);
        let closed = self.meridian.closed();
        let mut map = vec![None; 3 * n];
        let mut cols = 0;
        for (i, x) in nodes.iter().enumerate() {
            if self.meridian.is_clamped(i) {
                continue;
            }
            let rigid = |c: usize| {
                closed
                    && match (m, c) {
                        (0, 2) => i == 0 && self.pole_held(),
                        (0, 1) | (1, 2) => i == widest,
                        _ => false,
                    }
            };
            if x[0] == 0.0 {
                match m {
                    0 if !rigid(2) => {
                        map[3 * i + 2] = Some((cols, 1.0));
                        cols += 1;
                    }
                    1 if !(closed && i == 0) => {
                        map[3 * i] = Some((cols, 1.0));
                        map[3 * i + 1] = Some((cols, -1.0));
                        cols += 1;
                    }
                    _ => {}
                }
                continue;
            }
            // A sliding end keeps its height: W = 0 for every wave number.
            let slides = self.meridian.is_sliding(i);
            for c in 0..3 {
                let held = rigid(c) || (slides && c == 2);
                if !held {
                    map[3 * i + c] = Some((cols, 1.0));
                    cols += 1;
                }
            }
        }
        (map, cols)
    }

    /// The layout of the block of wave number m: its pattern on the kept unknowns of
    /// [`Self::kept_map`] and, per element, where each entry of its 9 × 9 matrix goes. It
    /// depends on m and the meridian only, so a run builds it once per wave number.
    pub fn block_layout(&self, m: usize) -> BlockLayout {
        let (map, cols) = self.kept_map(m);
        let border = self.border_count(m);
        let mut entries: Vec<(usize, usize)> = (cols..cols + border)
            .flat_map(|j| (0..cols + border).map(move |i| (i, j)))
            .collect();
        for e in 0..self.meridian.elements() {
            for i in 0..9 {
                let Some((a, _)) = map[6 * e + i] else {
                    continue;
                };
                for j in 0..9 {
                    if let Some((b, _)) = map[6 * e + j] {
                        entries.push((a, b));
                    }
                }
            }
        }
        let pattern = SymmetricPattern::from_entries(cols + border, entries);
        let mut slots = Vec::with_capacity(self.meridian.elements());
        for e in 0..self.meridian.elements() {
            let mut local = Vec::new();
            for i in 0..9 {
                let Some((a, ca)) = map[6 * e + i] else {
                    continue;
                };
                for j in 0..9 {
                    if let Some((b, cb)) = map[6 * e + j] {
                        let k = pattern.position(a, b).expect("an entry of the pattern");
                        local.push((i + 9 * j, k, ca * cb)); // column-major, as the matrix
                    }
                }
            }
            slots.push(local);
        }
        BlockLayout {
            m,
            pattern: Arc::new(pattern),
            slots,
            kept: cols,
            border,
        }
    }

    /// The block of wave number m at displacement `q` (membrane and pressures), on the kept
    /// unknowns of [`Self::kept_map`] (its layout built afresh; a run reuses one through
    /// [`Self::block_values`]).
    pub fn block(&self, m: usize, q: &[f64], params: &[f64]) -> Result<Block, AxisymError> {
        let layout = self.block_layout(m);
        let values = self.block_values(&layout, q, params)?;
        Ok(Block {
            pattern: layout.pattern,
            values,
        })
    }

    /// The values of the block of `layout`'s wave number at displacement `q`, aligned with
    /// its pattern.
    pub fn block_values(
        &self,
        layout: &BlockLayout,
        q: &[f64],
        params: &[f64],
    ) -> Result<Vec<f64>, AxisymError> {
        let mut all = self.blocks_values(std::slice::from_ref(layout), q, params)?;
        Ok(all.remove(0))
    }

    /// The values of the blocks of every layout at displacement `q`, from one pass over the
    /// Gauss points (the material's Hessian and the pressures evaluated once for all).
    pub fn blocks_values(
        &self,
        layouts: &[BlockLayout],
        q: &[f64],
        params: &[f64],
    ) -> Result<Vec<Vec<f64>>, AxisymError> {
        let x = self.positions(q);
        let points = self.element_points(&x, params)?;
        // The wave numbers are independent: one task each.
        let values: Vec<Vec<f64>> = layouts
            .par_iter()
            .map(|layout| {
                let mut v = vec![0.0; layout.pattern.nnz()];
                for (e, points) in points.iter().enumerate() {
                    let local = self.element_block(e, points, layout.m, &x, params);
                    for &(ij, k, c) in &layout.slots[e] {
                        v[k] += c * local.as_slice()[ij];
                    }
                }
                self.set_border(layout, &x, params, &mut v);
                v
            })
            .collect();
        if values.iter().flatten().any(|v| !v.is_finite()) {
            return Err(AxisymError::NonFinite);
        }
        Ok(values)
    }

    /// Each element's part of wᵀ K_m w at displacement `q` (`weights[k]` = w_r w_c for the
    /// pattern's entry k in row r and column c): its Gauss points and the planes at the nodes
    /// it owns, without the border. Element e's part depends on the nodes of e alone when
    /// [`AxisymModel::blocks_are_local`].
    pub fn block_quadratic_by_element(
        &self,
        layout: &BlockLayout,
        q: &[f64],
        params: &[f64],
        weights: &[f64],
    ) -> Result<Vec<f64>, AxisymError> {
        let x = self.positions(q);
        let points = self.element_points(&x, params)?;
        let parts: Vec<f64> = points
            .par_iter()
            .enumerate()
            .map(|(e, points)| {
                let local = self.element_block(e, points, layout.m, &x, params);
                layout.slots[e]
                    .iter()
                    .map(|&(ij, k, c)| c * local.as_slice()[ij] * weights[k])
                    .sum()
            })
            .collect();
        if parts.iter().any(|v| !v.is_finite()) {
            return Err(AxisymError::NonFinite);
        }
        Ok(parts)
    }

    /// wᵀ B w for the border B of block `layout` alone (the held motions and constraints,
    /// [`super::held`]), its columns scaled by `scale` (what the elements' largest entry
    /// sets in [`AxisymModel::blocks_values`]).
    pub fn border_quadratic(
        &self,
        layout: &BlockLayout,
        q: &[f64],
        params: &[f64],
        scale: f64,
        weights: &[f64],
    ) -> f64 {
        if layout.border == 0 {
            return 0.0;
        }
        let x = self.positions(q);
        let mut v = vec![0.0; layout.pattern.nnz()];
        self.set_border_scaled(layout, &x, params, scale, &mut v);
        v.iter().zip(weights).map(|(a, w)| a * w).sum()
    }

    /// Whether a block's entries on each element depend on that element's nodes alone (no
    /// effect resolves its pressure from the whole membrane, as a fixed amount of gas does
    /// from the volume): what lets [`AxisymModel::block_quadratic_by_element`] be
    /// differenced element by element.
    pub fn blocks_are_local(&self) -> bool {
        !self
            .pressures
            .iter()
            .any(|p| matches!(p, Pressure::GasAmount { .. }))
    }

    /// The Gauss points of every element for the blocks at the nodes `x`: the spin on the
    /// 5-point rule (its terms are of degree 9), a fluid with a wetting line on its
    /// element's wet part (docs/theory.md §15.14), the rest on 4 points.
    fn element_points(
        &self,
        x: &[[f64; 2]],
        params: &[f64],
    ) -> Result<Vec<Vec<BlockPoint>>, AxisymError> {
        let material = self.meridian.material.at(params)?;
        let (spin, rest): (Vec<Pressure>, Vec<Pressure>) = self
            .resolved_pressures(x, params)?
            .into_iter()
            .partition(|p| matches!(p, Pressure::Spin { .. }));
        let (wetting, rest): (Vec<Pressure>, Vec<Pressure>) =
            rest.into_iter().partition(|p| p.level(params).is_some());
        (0..self.meridian.elements())
            .map(|e| {
                let mut points =
                    block_points(&self.meridian, x, e, Some(&material), &rest, params)?;
                if !spin.is_empty() {
                    let rule = &super::GAUSS5;
                    points.extend(block_points_on(&self.meridian, x, e, &spin, params, rule));
                }
                let zs = [x[2 * e][1], x[2 * e + 1][1], x[2 * e + 2][1]];
                for load in &wetting {
                    let level = load.level(params).expect("a fluid with a level");
                    let rule = super::wet_part(zs, level).rule;
                    let one = std::slice::from_ref(load);
                    points.extend(block_points_on(&self.meridian, x, e, one, params, &rule));
                }
                Ok(points)
            })
            .collect()
    }

    /// Element e's 9 × 9 block of wave number m from its Gauss points, with the planes'
    /// stiffness at the nodes it owns.
    fn element_block(
        &self,
        e: usize,
        points: &[BlockPoint],
        m: usize,
        x: &[[f64; 2]],
        params: &[f64],
    ) -> SMatrix<f64, 9, 9> {
        let mut local = block_local(points, m, self.meridian.prestretch);
        let factor = FloorPlane::block_factor(m);
        for k in self.owned_nodes(e) {
            for plane in &self.planes {
                let c = plane.at(x[2 * e + k][1], params);
                local[(3 * k + 2, 3 * k + 2)] += factor * c.stiffness;
            }
        }
        local
    }
}

/// Where the entries of a block of one wave number go: its pattern and, per element, the
/// (local entry i + 9 j, slot in the pattern's values, coefficient) of every kept entry.
#[derive(Debug, Clone)]
pub struct BlockLayout {
    /// The wave number m.
    pub m: usize,
    /// The pattern.
    pub pattern: Arc<SymmetricPattern>,
    slots: Vec<Vec<(usize, usize, f64)>>,
    /// The kept unknowns (the block proper comes first in the pattern).
    pub kept: usize,
    /// The border columns after them: held motions and the volume constraint
    /// ([`super::held`]); the block's index is the bordered matrix's less this.
    pub border: usize,
}

/// The cos and sin parts of δx, δx_ξ, δx_θ at a Gauss point for the 9 unknowns of an
/// element (U, V, W per node): δ = C cos mθ + S sin mθ (m = 0: C + S is the field).
fn parts(p: &super::Point, m: usize) -> [[SMatrix<f64, 3, 9>; 2]; 3] {
    let mf = m as f64;
    let z = SMatrix::<f64, 3, 9>::zeros();
    let (mut xc, mut xs, mut gc, mut gs, mut tc, mut ts) = (z, z, z, z, z, z);
    for k in 0..3 {
        let (u, v, w) = (3 * k, 3 * k + 1, 3 * k + 2);
        let (n, dn) = (p.n[k], p.dn[k]);
        xc[(0, u)] = n;
        xc[(2, w)] = n;
        xs[(1, v)] = n;
        gc[(0, u)] = dn;
        gc[(2, w)] = dn;
        gs[(1, v)] = dn;
        // ∂/∂θ in the rotating frame (∂e_r/∂θ = e_θ, ∂e_θ/∂θ = −e_r).
        tc[(1, u)] = n;
        tc[(1, v)] = mf * n;
        ts[(0, u)] = -mf * n;
        ts[(0, v)] = -n;
        ts[(2, w)] = -mf * n;
    }
    [[xc, xs], [gc, gs], [tc, ts]]
}

/// ∫ dθ of a bilinear form of the two families: π Σ (cos, sin) for m ≥ 1, 2π of the sums
/// for m = 0.
fn families(m: usize, pr: &[[SMatrix<f64, 3, 9>; 2]; 3]) -> (Vec<[SMatrix<f64, 3, 9>; 3]>, f64) {
    if m == 0 {
        (
            vec![[
                pr[0][0] + pr[0][1],
                pr[1][0] + pr[1][1],
                pr[2][0] + pr[2][1],
            ]],
            2.0 * PI,
        )
    } else {
        (
            vec![
                [pr[0][0], pr[1][0], pr[2][0]],
                [pr[0][1], pr[1][1], pr[2][1]],
            ],
            PI,
        )
    }
}

/// What the blocks of every wave number share at one Gauss point of an element.
struct BlockPoint {
    p: super::Point,
    /// The membrane's H ∂²W/∂f_i∂f_k dA0 as one 6 × 6 (the θ factor apart), if included.
    membrane: Option<SMatrix<f64, 6, 6>>,
    /// Per pressure: (s × Gauss weight, p, ∂p/∂r, ∂p/∂z).
    pressures: Vec<(f64, f64, f64, f64)>,
    /// n dA / (dξ dθ) = x_ξ × x_θ and x_θ = r e_θ.
    nda: Vector3<f64>,
    x_th: Vector3<f64>,
}

/// The Gauss points of element e at the nodes `x` with the membrane of the material
/// `membrane` (when given: the meridian's at the parameters) and the `pressures` evaluated
/// once for the blocks of every wave number.
fn block_points(
    meridian: &Meridian,
    x: &[[f64; 2]],
    e: usize,
    membrane: Option<&MooneyRivlin>,
    pressures: &[Pressure],
    params: &[f64],
) -> Result<Vec<BlockPoint>, AxisymError> {
    let lam = meridian.prestretch;
    super::points(meridian, x, e)
        .into_iter()
        .map(|p| {
            let membrane = if let Some(material) = membrane {
                let h = material.thickness;
                let f = [
                    p.x_xi * (lam / p.dx_ref),
                    Vector3::new(0.0, lam * p.r / p.big_r, 0.0),
                ];
                let (_, _, hf) = meridian
                    .energy_in_f(material, &f)
                    .ok_or(AxisymError::Degenerate(e))?;
                let da0 = p.dx_ref * p.big_r / (lam * lam) * p.weight;
                let mut hh = SMatrix::<f64, 6, 6>::zeros();
                for (i, row) in hf.iter().enumerate() {
                    for (k, hik) in row.iter().enumerate() {
                        let hik: &Matrix3<f64> = hik;
                        hh.fixed_view_mut::<3, 3>(3 * i, 3 * k).copy_from(hik);
                    }
                }
                Some(hh * (h * da0))
            } else {
                None
            };
            Ok(block_point(p, membrane, x, e, pressures, params))
        })
        .collect()
}

/// The Gauss point `p` of element e at the nodes `x`, with `membrane` and the `pressures`
/// evaluated there.
fn block_point(
    p: super::Point,
    membrane: Option<SMatrix<f64, 6, 6>>,
    x: &[[f64; 2]],
    e: usize,
    pressures: &[Pressure],
    params: &[f64],
) -> BlockPoint {
    let z: f64 = (0..3).map(|k| p.n[k] * x[2 * e + k][1]).sum();
    let pressures = pressures
        .iter()
        .map(|load| {
            let pa = load.at(p.r, z, params, None);
            (pa.sign * p.weight, pa.p, load.radial(p.r, params), pa.dp)
        })
        .collect();
    let x_th = Vector3::new(0.0, p.r, 0.0);
    let nda = p.x_xi.cross(&x_th);
    BlockPoint {
        p,
        membrane,
        pressures,
        nda,
        x_th,
    }
}

/// The Gauss points of element e on the rule `rule` with the `pressures` only (no membrane).
fn block_points_on(
    meridian: &Meridian,
    x: &[[f64; 2]],
    e: usize,
    pressures: &[Pressure],
    params: &[f64],
    rule: &[(f64, f64)],
) -> Vec<BlockPoint> {
    super::points_on(meridian, x, e, rule)
        .into_iter()
        .map(|p| block_point(p, None, x, e, pressures, params))
        .collect()
}

/// The cross product a × · as a matrix.
fn cross_matrix(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0)
}

/// The 9 × 9 block of wave number m of an element from its [`block_points`]: the membrane
/// term of §15.2 and, per pressure, the symmetrised second variation
/// s ∫ [∇p·δx₂ (n dA·δx₁) + p δx₁·(δx₂,ξ × x_θ + x_ξ × δx₂,θ)] dξ dθ of the potential whose
/// first variation is s ∫ p n·δx dA (∇p = p_r e_r + p_z e_z).
fn block_local(points: &[BlockPoint], m: usize, lam: f64) -> SMatrix<f64, 9, 9> {
    let mut local = SMatrix::<f64, 9, 9>::zeros();
    for bp in points {
        let p = &bp.p;
        let (fams, theta) = families(m, &parts(p, m));
        let (cx, ct) = (cross_matrix(&p.x_xi), cross_matrix(&bp.x_th));
        for [dx, dxi, dth] in fams {
            if let Some(hh) = &bp.membrane {
                let mut b = SMatrix::<f64, 6, 9>::zeros();
                b.fixed_view_mut::<3, 9>(0, 0)
                    .copy_from(&(dxi * (lam / p.dx_ref)));
                b.fixed_view_mut::<3, 9>(3, 0)
                    .copy_from(&(dth * (lam / p.big_r)));
                // For m ≥ 1 each family strains three of the six components (cos: f1_r,
                // f1_z, f2_θ; sin: the others): the product on those rows alone.
                let mut rows = [0usize; 6];
                let mut n = 0;
                for r in 0..6 {
                    if b.row(r).iter().any(|v| *v != 0.0) {
                        rows[n] = r;
                        n += 1;
                    }
                }
                if n <= 3 {
                    let mut bc = SMatrix::<f64, 3, 9>::zeros();
                    let mut hc = Matrix3::<f64>::zeros();
                    for a in 0..n {
                        bc.row_mut(a).copy_from(&b.row(rows[a]));
                        for c in 0..n {
                            hc[(a, c)] = hh[(rows[a], rows[c])];
                        }
                    }
                    local += bc.transpose() * (hc * bc) * theta;
                } else {
                    local += b.transpose() * (hh * b) * theta;
                }
            }
            if bp.pressures.is_empty() {
                continue;
            }
            // δ(n dA) per unknown: δx_ξ × x_θ + x_ξ × δx_θ; (n dA·δx) per unknown.
            let dn = cx * dth - ct * dxi;
            let w = dx.transpose() * bp.nda;
            let (dr, dz) = (dx.row(0), dx.row(2));
            let work = dx.transpose() * dn;
            let mut a = SMatrix::<f64, 9, 9>::zeros();
            for &(c, pr, dp_r, dp_z) in &bp.pressures {
                // ∇p·δx₂ (n dA·δx₁) + p δx₁·δ(n dA)₂.
                a += (w * (dr * dp_r + dz * dp_z) + work * pr) * c;
            }
            local += (a + a.transpose()) * (0.5 * theta);
        }
    }
    local
}

/// The membrane's 9 × 9 block of wave number m on element e at the nodes `x` and the
/// parameters `params`.
#[cfg(test)]
fn membrane_local(
    meridian: &Meridian,
    x: &[[f64; 2]],
    params: &[f64],
    e: usize,
    m: usize,
) -> Result<SMatrix<f64, 9, 9>, AxisymError> {
    let material = meridian.material.at(params)?;
    let points = block_points(meridian, x, e, Some(&material), &[], &[])?;
    Ok(block_local(&points, m, meridian.prestretch))
}

/// A pressure's 9 × 9 block of wave number m on element e (see [`block_local`]).
#[cfg(test)]
fn pressure_local(
    meridian: &Meridian,
    x: &[[f64; 2]],
    e: usize,
    m: usize,
    load: &Pressure,
    params: &[f64],
) -> SMatrix<f64, 9, 9> {
    let points = block_points(meridian, x, e, None, &[*load], params).expect("no membrane");
    block_local(&points, m, meridian.prestretch)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A clamped cap, stretched and bent away from its reference, under a gas pressure and a
    /// fluid below it: every potential of the model at a generic state.
    fn generic() -> (AxisymModel, Vec<f64>, Vec<f64>) {
        let mat = MooneyRivlin::new(1.0, 0.2, 0.1);
        let meridian = Meridian::truncated_sphere(1.0, -0.3, 5, 1.05, mat).unwrap();
        let pressures = vec![
            Pressure::Gas {
                pressure: Quantity::Parameter(0),
            },
            Pressure::Fluid {
                density: Quantity::Parameter(1),
                gravity: Quantity::Value(1.3),
                level: Quantity::Parameter(2),
                front: false,
                filled: false,
            },
            Pressure::Spin {
                density: Quantity::Value(0.9),
                omega2: Quantity::Parameter(3),
            },
        ];
        let model = AxisymModel::new(meridian, pressures);
        let q: Vec<f64> = (0..model.dim())
            .map(|k| 0.03 * ((k as f64) * 1.7).sin() + 0.02)
            .collect();
        (model, q, vec![0.7, 0.4, 2.0, 1.7])
    }

    /// A cap cut at the equator whose edge slides on the floor z = 0 (the plane a parameter
    /// pushed up through the lowest nodes), completely filled with fluid whose head is below
    /// the top (negative pressure there), spinning: the Paper 4 potentials at a generic state.
    pub(crate) fn generic_filled() -> (AxisymModel, Vec<f64>, Vec<f64>) {
        let mat = MooneyRivlin::new(1.0, 0.2, 0.1);
        let mut meridian = Meridian::truncated_sphere(1.0, 0.0, 5, 1.05, mat).unwrap();
        meridian.clamped = (false, false);
        meridian.sliding = (false, true);
        let pressures = vec![
            Pressure::Fluid {
                density: Quantity::Parameter(0),
                gravity: Quantity::Value(1.3),
                level: Quantity::Parameter(1),
                front: false,
                filled: true,
            },
            Pressure::Spin {
                density: Quantity::Value(0.9),
                omega2: Quantity::Parameter(2),
            },
        ];
        let mut model = AxisymModel::new(meridian, pressures);
        for exponent in [1, 3] {
            model.planes.push(FloorPlane {
                normal_z: 1.0,
                offset: Quantity::Parameter(3),
                penalty: Quantity::Parameter(4),
                exponent,
            });
        }
        model.volume_level = Some(1);
        let q: Vec<f64> = (0..model.dim())
            .map(|k| 0.03 * ((k as f64) * 1.7).sin() + 0.02)
            .collect();
        (model, q, vec![0.7, 0.6, 1.7, 0.2, 50.0])
    }

    /// A closed sphere stretched off its reference, resting on a plane (its pole's height
    /// free), holding a fixed amount of gas above a fluid whose level crosses an element:
    /// the Paper 2 potentials at a generic state. Parameters: C, V*, ρ, h, the plane's
    /// offset.
    pub(crate) fn generic_paper2() -> (AxisymModel, Vec<f64>, Vec<f64>) {
        let mat = MooneyRivlin::new(1.0, 0.1, 0.1);
        let meridian = Meridian::sphere(1.0, 6, 1.05, mat).unwrap();
        let pressures = vec![
            Pressure::GasAmount {
                amount: Quantity::Parameter(0),
                ambient: 0.7,
                fluid: Some(Quantity::Parameter(1)),
            },
            Pressure::Fluid {
                density: Quantity::Parameter(2),
                gravity: Quantity::Value(1.3),
                level: Quantity::Parameter(3),
                front: false,
                filled: false,
            },
        ];
        let mut model = AxisymModel::new(meridian, pressures);
        model.set_planes(vec![FloorPlane {
            normal_z: 1.0,
            offset: Quantity::Parameter(4),
            penalty: Quantity::Value(40.0),
            exponent: 3,
        }]);
        model.volume_level = Some(3);
        let q: Vec<f64> = (0..model.dim())
            .map(|k| 0.03 * ((k as f64) * 1.7).sin() - 0.01)
            .collect();
        // The plane 0.02 above the south pole: the pole's ring through it.
        let pole = model.positions(&q).last().unwrap()[1];
        (model, q, vec![6.0, 0.9, 0.8, -0.3, pole + 0.02])
    }

    /// The sphere on its plane: the gas amount sharing the enclosure with a partly wet fluid
    /// (its rank-one stiffness and the loads of C and V*), the plane on the free pole.
    #[test]
    fn gas_amount_above_fluid_on_a_plane_matches_finite_differences() {
        let (model, q, params) = generic_paper2();
        assert!(!model.pole_held() && model.unknown(0, 1).is_some());
        let x = model.positions(&q);
        assert!(x[x.len() - 1][1] < params[4] && x[x.len() - 3][1] > params[4]);
        assert!(x.iter().any(|p| p[1] > params[3]) && x.iter().any(|p| p[1] < params[3]));
        let e = model.evaluate(&q, &params).unwrap();
        assert_eq!(e.rank_one.len(), 1);
        check_derivatives(&model, &q, &params);
        block_is_tangent(&model, &q, &params);
    }

    /// Central differences of the energy and the gradient against the gradient, the tangent
    /// and the loads.
    fn check_derivatives(model: &AxisymModel, q: &[f64], params: &[f64]) {
        let (q, params) = (q.to_vec(), params.to_vec());
        let e = model.evaluate(&q, &params).unwrap();
        let h = 1e-6;
        for k in 0..model.dim() {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[k] += h;
            qm[k] -= h;
            let (ep, em) = (
                model.evaluate(&qp, &params).unwrap(),
                model.evaluate(&qm, &params).unwrap(),
            );
            let g = (ep.energy - em.energy) / (2.0 * h);
            assert!(
                (g - e.gradient[k]).abs() < 1e-7 * (1.0 + g.abs()),
                "gradient {k}: {g} vs {}",
                e.gradient[k]
            );
            for j in 0..model.dim() {
                let t = (ep.gradient[j] - em.gradient[j]) / (2.0 * h);
                assert!(
                    (t - e.tangent[(j, k)]).abs() < 1e-6 * (1.0 + t.abs()),
                    "tangent ({j}, {k}): {t} vs {}",
                    e.tangent[(j, k)]
                );
            }
        }
        for p in 0..params.len() {
            let (mut pp, mut pm) = (params.clone(), params.clone());
            pp[p] += h;
            pm[p] -= h;
            let (ep, em) = (
                model.evaluate(&q, &pp).unwrap(),
                model.evaluate(&q, &pm).unwrap(),
            );
            for j in 0..model.dim() {
                let l = (ep.gradient[j] - em.gradient[j]) / (2.0 * h);
                assert!(
                    (l - e.loads[(j, p)]).abs() < 1e-6 * (1.0 + l.abs()),
                    "load ({j}, {p}): {l} vs {}",
                    e.loads[(j, p)]
                );
            }
        }
        assert!(e.tangent.amax() > 0.1 && e.loads.amax() > 0.01);
    }

    #[test]
    fn gradient_tangent_and_loads_match_finite_differences() {
        let (model, q, params) = generic();
        check_derivatives(&model, &q, &params);
    }

    /// The generic cap with μ, k and H the parameters 4, 5 and 6 (docs/theory.md §15.18).
    fn generic_material() -> (AxisymModel, Vec<f64>, Vec<f64>) {
        let (mut model, q, mut params) = generic();
        model.meridian.material = super::super::MeridianMaterial {
            mu: Quantity::Parameter(4),
            k: Quantity::Parameter(5),
            thickness: Quantity::Parameter(6),
        };
        params.extend([1.3, 0.25, 0.08]);
        (model, q, params)
    }

    /// μ, k and H as parameters: the gradient, the tangent and every load (theirs beside the
    /// pressures') against central differences, the block m = 0 against the tangent and the
    /// exact blocks m = 0..4 against the sampled ones, all at the parameters.
    #[test]
    fn material_parameters_match_finite_differences_and_the_blocks() {
        let (model, q, params) = generic_material();
        let e = model.evaluate(&q, &params).unwrap();
        assert!((4..7).all(|j| e.loads.column(j).amax() > 1e-3));
        check_derivatives(&model, &q, &params);
        block_is_tangent(&model, &q, &params);
        exact_equals_sampled(&model, &q, &params);
    }

    /// The filled fluid (negative pressure above the head), the planes (linear and cubic,
    /// some nodes through them) and the sliding edge.
    #[test]
    fn filled_fluid_plane_and_slide_match_finite_differences() {
        let (model, q, params) = generic_filled();
        let x = model.positions(&q);
        assert!(
            x.iter().any(|p| p[1] > params[1]),
            "some node above the head"
        );
        let through = x.iter().filter(|p| p[1] < params[3]).count();
        assert!(through >= 2, "{through} nodes through the plane");
        let last = x.len() - 1;
        assert_eq!(
            x[last][1], model.meridian.nodes[last][1],
            "the edge keeps its height"
        );
        assert!(model.unknown(last, 0).is_some() && model.unknown(last, 1).is_none());
        check_derivatives(&model, &q, &params);
    }

    /// The plane's block entry is the θ-sampled second variation of the ring's mean penalty
    /// (1/2π) ∫ κ/(q+1) ⟨−δ(θ)⟩^(q+1) dθ along W cos mθ: κ q ⟨−δ⟩^(q−1) times the mean of
    /// cos² mθ.
    #[test]
    fn the_plane_blocks_are_the_sampled_ring_penalty() {
        let (model, q, params) = generic_filled();
        let mut bare = model.clone();
        bare.planes.clear();
        bare.volume_level = None;
        let mut with = model.clone();
        with.volume_level = None;
        let x = model.positions(&q);
        for m in 0..4 {
            let b = with.block(m, &q, &params).unwrap();
            let b0 = bare.block(m, &q, &params).unwrap();
            let (d, d0) = (
                b.pattern.to_dense(&b.values),
                b0.pattern.to_dense(&b0.values),
            );
            let (map, _) = model.kept_map(m);
            let nt = 2 * m + 4;
            let mean = (0..nt)
                .map(|t| (m as f64 * 2.0 * PI * t as f64 / nt as f64).cos().powi(2))
                .sum::<f64>()
                / nt as f64;
            let mut seen = 0;
            for (i, p) in x.iter().enumerate() {
                let Some((k, _)) = map[3 * i + 2] else {
                    continue;
                };
                let expect: f64 = model
                    .planes
                    .iter()
                    .map(|pl| pl.at(p[1], &params).stiffness * mean)
                    .sum();
                let got = d[(k, k)] - d0[(k, k)];
                assert!(
                    (got - expect).abs() < 1e-9 * (1.0 + expect),
                    "m = {m}, node {i}"
                );
                seen += usize::from(expect > 0.0);
            }
            assert!(seen >= 1, "m = {m}: a node in contact");
        }
    }

    /// The gradient of the pressure potentials is s ∫ p n·δx dA: for the gas alone, −P δV.
    #[test]
    fn the_gas_potential_is_minus_pressure_times_volume() {
        let (mut model, q, params) = generic();
        model.pressures.truncate(1);
        let mut bare = model.clone();
        bare.pressures.clear();
        let (e, b) = (
            model.evaluate(&q, &params).unwrap(),
            bare.evaluate(&q, &params).unwrap(),
        );
        let v = model.volume(&model.positions(&q));
        assert!((e.energy - b.energy + params[0] * v).abs() < 1e-12 * v.abs());
    }

    /// The spin potential is −(ρ ω²/2) ∫_V r² dV: on a sphere of radius a, ∫_V r² dV =
    /// 8π a⁵/15 (to the meridian's O(h⁴) error).
    #[test]
    fn the_spin_potential_is_the_centrifugal_energy_of_the_enclosed_fluid() {
        let mat = MooneyRivlin::new(1.0, 0.2, 0.1);
        let a = 1.3;
        let meridian = Meridian::sphere(a, 32, 1.0, mat).unwrap();
        let spin = Pressure::Spin {
            density: Quantity::Value(0.8),
            omega2: Quantity::Parameter(0),
        };
        let model = AxisymModel::new(meridian.clone(), vec![spin]);
        let bare = AxisymModel::new(meridian, Vec::new());
        let q = vec![0.0; model.dim()];
        let w2 = 2.5;
        let pi_spin =
            model.evaluate(&q, &[w2]).unwrap().energy - bare.evaluate(&q, &[w2]).unwrap().energy;
        let exact = -0.5 * 0.8 * w2 * 8.0 * PI * a.powi(5) / 15.0;
        assert!((pi_spin / exact - 1.0).abs() < 1e-6, "{pi_spin} vs {exact}");
    }

    /// A sphere scaled by c from its reference (pre-stretch λ₀) has both principal stretches
    /// λ₀c: every element is wrinkled just below λ₀c = 1 and none just above. Stretched to
    /// 1.02 and flattened (z scaled by 0.9), it keeps a hoop stretch of 1.02 and shortens its
    /// meridians near the equator: only the elements where λ_s⁴λ_θ² or λ_θ⁴λ_s² drops below
    /// 1 are counted, fewer than all and more than none.
    #[test]
    fn wrinkled_elements_are_those_with_a_negative_principal_tension() {
        let mat = MooneyRivlin::new(1.0, 0.2, 0.1);
        let lam = 1.05;
        let model = AxisymModel::new(Meridian::sphere(1.0, 16, lam, mat).unwrap(), Vec::new());
        let scaled = |c: f64, b: f64| scaled_about_the_pole(&model, c, b, 0.0);
        let n = model.meridian.elements();
        assert_eq!(model.wrinkled_elements(&scaled(0.99 / lam, 1.0)), n);
        assert_eq!(model.wrinkled_elements(&scaled(1.01 / lam, 1.0)), 0);
        let flat = model.wrinkled_elements(&scaled(1.02 / lam, 0.9));
        assert!(flat > 0 && flat < n, "{flat} of {n}");
    }

    /// The displacement that scales a closed meridian by `c` about its first pole (whose
    /// height it holds), its heights by `b` more, its radii by 1 + `ripple` sin(1.7 i) at
    /// node i.
    fn scaled_about_the_pole(model: &AxisymModel, c: f64, b: f64, ripple: f64) -> Vec<f64> {
        let z0 = model.meridian.nodes[0][1];
        let x: Vec<[f64; 2]> = model
            .meridian
            .nodes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let w = 1.0 + ripple * (1.7 * i as f64).sin();
                [w * c * p[0], z0 + b * c * (p[1] - z0)]
            })
            .collect();
        model.displacement_of(&x)
    }

    /// The relaxed energy on the meridian: equal to the plain energy in a taut state (ε = 0,
    /// to round-off: the same law), and in states with taut, wrinkled and slack Gauss points
    /// its gradient, tangent and loads (k among the parameters: the relaxed energy is linear
    /// in (c1, c2) in every state) are the differences of its energy and gradient; the areas
    /// of the states are the membrane's.
    #[test]
    fn the_relaxed_meridian_matches_its_differences_in_every_state() {
        use crate::effects::membrane::Wrinkling;
        let mat = super::super::MeridianMaterial {
            mu: Quantity::Value(1.0),
            k: Quantity::Parameter(1),
            thickness: Quantity::Value(0.1),
        };
        let lam = 1.05;
        let gas = vec![Pressure::Gas {
            pressure: Quantity::Parameter(0),
        }];
        let plain = AxisymModel::new(Meridian::sphere(1.0, 16, lam, mat).unwrap(), gas);
        let params = [0.3, 0.2];
        let z0 = plain.meridian.nodes[0][1];
        // A ripple, so that no two Gauss points share their stretches.
        let scaled = |c: f64, b: f64| scaled_about_the_pole(&plain, c, b, 0.0005);
        let relaxed = |stiffness: f64, width: f64| {
            let mut m = plain.clone();
            m.meridian.wrinkling = Wrinkling::Relaxed { stiffness, width };
            m
        };
        // Taut: the same numbers.
        let taut = scaled(1.03 / lam, 1.0);
        assert_eq!(plain.tension_areas(&taut), [0.0, 0.0]);
        let (a, b) = (
            plain.evaluate(&taut, &params).unwrap(),
            relaxed(0.0, 0.0).evaluate(&taut, &params).unwrap(),
        );
        assert!((a.energy - b.energy).abs() <= 1e-14 * a.energy.abs());
        let largest = a.gradient.iter().fold(0.0f64, |m, g| m.max(g.abs()));
        for (ga, gb) in a.gradient.iter().zip(&b.gradient) {
            assert!((ga - gb).abs() <= 1e-13 * largest);
        }
        assert!((&a.tangent - &b.tangent).amax() <= 1e-13 * a.tangent.amax());
        // Slack everywhere (stretched 0.99 from the stress-free state): the whole area of the
        // sphere of radius 0.99/λ0, to the quadrature's accuracy.
        let slack = plain.tension_areas(&scaled(0.99 / lam, 1.0));
        let sphere = 4.0 * PI * (0.99f64 / lam).powi(2);
        assert!(
            slack[0] == 0.0 && (slack[1] - sphere).abs() < 1e-3 * sphere,
            "{slack:?}"
        );
        // Flattened and stretched more towards the south pole: taut, wrinkled and slack
        // points together, none within 1e-4 in stretch of a switching surface (where the
        // Hessian jumps and differences of the gradient are not the tangent).
        let n = plain.meridian.nodes.len() as f64;
        let x: Vec<[f64; 2]> = plain
            .meridian
            .nodes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let c = (0.965 + 0.07 * i as f64 / n) / lam;
                [c * p[0], z0 + 0.9 * c * (p[1] - z0)]
            })
            .collect();
        let mixed = plain.displacement_of(&x);
        let mut states = [0usize; 3];
        for e in 0..plain.meridian.elements() {
            for p in super::super::points(&plain.meridian, &x, e) {
                let (s, t) = p.stretches(lam);
                let (l1, l2) = (s.max(t), s.min(t));
                let clear = (l1 - 1.0).abs().min((l1 * l2 * l2 - 1.0).abs());
                assert!(clear > 1e-4, "element {e}: stretches {s}, {t}");
                states[TensionState::of_stretches(s, t).code() as usize] += 1;
            }
        }
        assert!(states.iter().all(|&k| k > 0), "{states:?}");
        let [wrinkled, slack] = plain.tension_areas(&mixed);
        assert!(wrinkled > 0.0 && slack > 0.0 && wrinkled + slack < sphere);
        for stiffness in [1e-4, 0.0] {
            check_derivatives(&relaxed(stiffness, 0.0), &mixed, &params);
        }
    }

    /// The m = 0 block on (U, W) is the tangent of the axisymmetric problem.
    #[test]
    fn the_axisymmetric_block_is_the_tangent() {
        let (model, q, params) = generic();
        block_is_tangent(&model, &q, &params);
        let (model, q, params) = generic_filled();
        block_is_tangent(&model, &q, &params);
    }

    /// The m = 0 block without its border is the tangent less its rank-one terms.
    fn block_is_tangent(model: &AxisymModel, q: &[f64], params: &[f64]) {
        let mut e = model.evaluate(q, params).unwrap();
        for (c, a) in &e.rank_one {
            let a = nalgebra::DVector::from_column_slice(a);
            e.tangent -= &a * a.transpose() * *c;
        }
        let block = model.block(0, q, params).unwrap();
        let dense = block.pattern.to_dense(&block.values);
        let (map, _) = model.kept_map(0);
        for (a, &(i, c)) in model.free.iter().enumerate() {
            let ka = map[3 * i + 2 * c].unwrap().0;
            for (b, &(j, d)) in model.free.iter().enumerate() {
                let kb = map[3 * j + 2 * d].unwrap().0;
                let t = e.tangent[(a, b)];
                assert!(
                    (dense[(ka, kb)] - t).abs() < 1e-10 * e.tangent.amax(),
                    "({a}, {b}): block {} vs tangent {t}",
                    dense[(ka, kb)]
                );
            }
        }
    }

    /// The blocks integrated exactly in θ equal the blocks sampled in θ (the trapezoidal rule
    /// on 2m + 4 points, exact for these products), membrane and fluid.
    #[test]
    fn exact_theta_integrals_equal_the_sampled_blocks() {
        let (model, q, params) = generic();
        exact_equals_sampled(&model, &q, &params);
    }

    /// The exact blocks m = 0..4 of the membrane and of a fluid against the sampled ones.
    fn exact_equals_sampled(model: &AxisymModel, q: &[f64], params: &[f64]) {
        let x = model.positions(q);
        let load = super::super::Hydrostatic {
            gravity: 1.3,
            level: 2.0,
        };
        let fluid = Pressure::Fluid {
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.3),
            level: Quantity::Value(2.0),
            front: true,
            filled: false,
        };
        for m in 0..5 {
            let km = super::super::membrane_full(&model.meridian, &x, params, m, 0.0).unwrap();
            let kf = super::super::hydrostatic_full(&model.meridian, &x, &load, m, 0.0, true);
            let n = 3 * model.meridian.nodes.len();
            let (mut am, mut af) = (
                nalgebra::DMatrix::zeros(n, n),
                nalgebra::DMatrix::zeros(n, n),
            );
            for e in 0..model.meridian.elements() {
                let a = membrane_local(&model.meridian, &x, params, e, m).unwrap();
                let f = pressure_local(&model.meridian, &x, e, m, &fluid, &[]);
                super::super::scatter(&mut am, e, &a);
                super::super::scatter(&mut af, e, &f);
            }
            assert!((&am - &km).amax() < 1e-11 * km.amax(), "membrane, m = {m}");
            assert!((&af - &kf).amax() < 1e-11 * kf.amax(), "fluid, m = {m}");
            assert!(km.amax() > 0.0 && kf.amax() > 0.0);
        }
    }

    /// The filled fluid's blocks equal the θ-sampled second variation of ρ g (h − z) also
    /// where it is negative (a head below the top of the cap), and a filled fluid is not
    /// refused above its head.
    #[test]
    fn filled_fluid_blocks_equal_the_sampled_blocks_above_the_head() {
        let (model, q, params) = generic_filled();
        let x = model.positions(&q);
        let level = 0.5;
        assert!(x.iter().any(|p| p[1] > level));
        let load = super::super::Hydrostatic {
            gravity: 1.3,
            level,
        };
        let fluid = Pressure::Fluid {
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.3),
            level: Quantity::Value(level),
            front: true,
            filled: true,
        };
        for m in 0..5 {
            let kf = super::super::hydrostatic_full(&model.meridian, &x, &load, m, 0.0, false);
            let n = 3 * model.meridian.nodes.len();
            let mut af = nalgebra::DMatrix::zeros(n, n);
            for e in 0..model.meridian.elements() {
                let f = pressure_local(&model.meridian, &x, e, m, &fluid, &[]);
                super::super::scatter(&mut af, e, &f);
            }
            assert!(
                (&af - &kf).amax() < 1e-11 * kf.amax(),
                "filled fluid, m = {m}"
            );
        }
        let mut p = params.clone();
        p[1] = level;
        assert!(model.evaluate(&q, &p).is_ok());
    }

    /// The generic cap with the fluid's level at `level`: (model, q, params).
    pub(crate) fn partly_wet(level: f64) -> (AxisymModel, Vec<f64>, Vec<f64>) {
        let (model, q, mut params) = generic();
        params[2] = level;
        (model, q, params)
    }

    /// The elements a level crosses inside, with the wet fraction of each.
    fn crossed(model: &AxisymModel, q: &[f64], level: f64) -> Vec<(usize, f64)> {
        let x = model.positions(q);
        (0..model.meridian.elements())
            .filter_map(|e| {
                let w =
                    super::super::wet_part([x[2 * e][1], x[2 * e + 1][1], x[2 * e + 2][1]], level);
                let wet: f64 = w.rule.iter().map(|r| r.1).sum::<f64>() / 2.0;
                (!w.crossings.is_empty()).then_some((e, wet))
            })
            .collect()
    }

    /// A level across the cap, inside an element and a hair above a node: the wet part of
    /// each element is integrated exactly and the moving wetting line's terms make the
    /// tangent and the level's load the differences of the gradient.
    #[test]
    fn partly_wet_gradient_tangent_and_loads_match_finite_differences() {
        let (model, q, _) = generic();
        let x = model.positions(&q);
        let node = 5;
        for level in [0.35, x[node][1] + 1e-4, x[node][1] - 1e-4] {
            let (model, q, params) = partly_wet(level);
            let cut = crossed(&model, &q, level);
            assert_eq!(cut.len(), 1, "level {level}: {cut:?}");
            assert!(cut[0].1 > 0.0 && cut[0].1 < 1.0);
            assert!(x.iter().any(|p| p[1] > level) && x.iter().any(|p| p[1] < level));
            check_derivatives(&model, &q, &params);
            block_is_tangent(&model, &q, &params);
        }
    }

    /// Wholly wet and wholly dry elements are the plain rule and nothing: a level above the
    /// cap gives the old potential, one below it no fluid at all.
    #[test]
    fn a_level_above_or_below_the_meridian_wets_all_or_nothing() {
        let (model, q, params) = generic();
        let mut dry = model.clone();
        dry.pressures.remove(1);
        let (_, _, low) = partly_wet(-5.0);
        let (a, b) = (
            model.evaluate(&q, &low).unwrap(),
            dry.evaluate(&q, &low).unwrap(),
        );
        assert_eq!(a.energy, b.energy);
        assert!(crossed(&model, &q, params[2]).is_empty());
        let wet = model.evaluate(&q, &params).unwrap();
        assert!((wet.energy - b.energy).abs() > 1e-3);
    }

    /// The blocks m ≥ 1 of a partly wet fluid equal the θ-sampled second variation of
    /// ρ g (h − z) over the wet part (no term on the wetting circle: p = 0 there).
    #[test]
    fn partly_wet_blocks_equal_the_sampled_blocks() {
        let level = 0.35;
        let (model, q, params) = partly_wet(level);
        let mut fluid = model.clone();
        fluid.pressures = vec![model.pressures[1]];
        let mut bare = model.clone();
        bare.pressures.clear();
        let x = model.positions(&q);
        let load = super::super::Hydrostatic {
            gravity: 1.3,
            level,
        };
        for m in 0..5 {
            let (map, cols) = model.kept_map(m);
            let mut t = nalgebra::DMatrix::zeros(map.len(), cols);
            for (row, c) in map.iter().enumerate() {
                if let Some((col, v)) = c {
                    t[(row, *col)] = *v;
                }
            }
            // Fluid behind the membrane: s = −1, density params[1].
            let kf = super::super::hydrostatic_full(&model.meridian, &x, &load, m, 0.0, true);
            let expect = t.transpose() * kf * &t * (-params[1]);
            let (b, b0) = (
                fluid.block(m, &q, &params).unwrap(),
                bare.block(m, &q, &params).unwrap(),
            );
            let (d, d0) = (
                b.pattern.to_dense(&b.values),
                b0.pattern.to_dense(&b0.values),
            );
            let mut err = 0.0_f64;
            for a in 0..cols {
                for c in 0..cols {
                    err = err.max((d[(a, c)] - d0[(a, c)] - expect[(a, c)]).abs());
                }
            }
            assert!(err < 1e-11 * expect.amax(), "m = {m}: {err}");
            assert!(expect.amax() > 1e-3);
        }
    }
}
