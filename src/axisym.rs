//! The axisymmetric reference (docs/theory.md §15): a membrane of revolution as its meridian,
//! discretised by quadratic elements, and the tangent at an axisymmetric state split by
//! Fourier mode.
//!
//! A state is the meridian (r, z)(s) rotated about z. A displacement of wave number m is
//!
//! ```text
//!   δx = U(s) cos mθ e_r + V(s) sin mθ e_θ + W(s) cos mθ e_z          (m ≥ 1)
//!   δx = U(s) e_r + V(s) e_θ + W(s) e_z                              (m = 0)
//! ```
//!
//! with U, V, W interpolated by the elements' shape functions. The second variation of an
//! axisymmetric energy couples no two wave numbers (∫ cos mθ cos m'θ dθ = 0 for m ≠ m'), and
//! for m ≥ 1 the partner family (U sin mθ, −V cos mθ, W sin mθ) is the first rotated by
//! π/(2m) about z: its block is the same matrix, so every eigenvalue of a block m ≥ 1 is double
//! by construction. Each block is integrated exactly in θ (the trapezoidal rule with more than
//! 2m points integrates the trigonometric products exactly) and by Gauss–Legendre quadrature
//! along the meridian.
//!
//! Energies: the Mooney–Rivlin membrane of [`crate::effects::membrane`] (the same W(F), F the
//! in-plane deformation gradient in an orthonormal stress-free frame: f1 = λ0 x_ξ/|X_ξ|,
//! f2 = λ0 x_θ/R, stress-free area dA0 = |X_ξ| R dξ dθ/λ0²), and a hydrostatic pressure
//! p = ρ g (h − z) on the side the fluid wets (the potential whose first variation is
//! ∫ p n·δx dA, n dA = x_ξ × x_θ dξ dθ), whose second variation is the symmetric bilinear form
//!
//! ```text
//!   −ρ g ∫ Δz (n dA·δx) + ∫ p δx·(Δx_ξ × x_θ + x_ξ × Δx_θ) dξ dθ,   symmetrised,
//! ```
//!
//! valid where the boundary terms vanish (a clamped rim, p = 0 on a wetting line).
//!
//! Boundary conditions: a clamped end holds U = V = W = 0; a node on the axis (R = 0) holds
//! the regularity of the field there: U = V = 0 for m = 0, W = 0 and U + V = 0 for m = 1
//! (the field is then the constant U e_x), everything for m ≥ 2.
//!
//! A state and the modes of its blocks are drawn on the meridian revolved about z into a
//! triangulated surface ([`revolved_mesh`], [`revolved_positions`], [`revolved_mode`];
//! docs/theory.md §15.17).

pub mod blocks;
pub mod critical_test;
mod gas;
mod held;
mod model;
mod plane;
mod problem;
mod revolve;
mod spin;
mod volume;

pub use gas::{GasAmountBorder, GasAmountRow};
pub use model::{AxisymModel, Block, BlockLayout, Evaluated, Pressure};
pub use plane::FloorPlane;
pub use problem::{AxisymProblem, GasTarget, VolumeTarget};
pub use revolve::{
    default_segments, mode_amplitudes, revolved_mesh, revolved_mode, revolved_positions,
    revolved_rings,
};

use crate::effects::membrane::{MooneyRivlin, Wrinkling};
use crate::effects::Quantity;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// Gauss–Legendre points and weights on [−1, 1], 4 points (exact to degree 7).
const GAUSS: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// The part of an element below a fluid level h: z(ξ) = Σ N_k z_k ≤ h (docs/theory.md
/// §15.14).
#[derive(Debug, Clone)]
struct WetPart {
    /// The 4-point Gauss rule mapped onto each wet sub-interval of [−1, 1] (empty: dry).
    rule: Vec<(f64, f64)>,
    /// The wetting lines inside the element: (ξ*, z_ξ(ξ*)), z(ξ*) = h.
    crossings: Vec<(f64, f64)>,
    /// The level h.
    level: f64,
}

/// The roots in (−1, 1) of a ξ² + b ξ + c, ascending, a double root once.
fn roots_inside(a: f64, b: f64, c: f64) -> Vec<f64> {
    let mut roots = Vec::new();
    let scale = a.abs().max(b.abs()).max(c.abs());
    if scale == 0.0 {
        return roots;
    }
    if a.abs() <= 1e-14 * scale {
        if b != 0.0 {
            roots.push(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            // The stable pair: q = −(b + sgn b √disc)/2, roots q/a and c/q.
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            if q == 0.0 {
                roots.push(0.0);
            } else {
                roots.push(q / a);
                roots.push(c / q);
            }
        }
    }
    roots.retain(|r| r.is_finite() && *r > -1.0 && *r < 1.0);
    roots.sort_by(f64::total_cmp);
    roots.dedup();
    roots
}

/// The wet part of an element with node heights `z` under the level `h`: the sub-intervals
/// between the roots of the quadratic z(ξ) − h on which z ≤ h, each with the 4-point rule (an
/// element lying on the level, z ≡ h, is wet: the one-sided tangent of a floor that the
/// fluid wets as soon as it sags, as for the ponding floor with its level at the rim).
fn wet_part(z: [f64; 3], h: f64) -> WetPart {
    // z(ξ) = z1 + ξ (z2 − z0)/2 + ξ² ((z0 + z2)/2 − z1).
    let (a, b, c) = (0.5 * (z[0] + z[2]) - z[1], 0.5 * (z[2] - z[0]), z[1] - h);
    let roots = roots_inside(a, b, c);
    let mut cuts = vec![-1.0];
    cuts.extend(&roots);
    cuts.push(1.0);
    let mut rule = Vec::new();
    for s in cuts.windows(2) {
        let (lo, hi) = (s[0], s[1]);
        let mid = 0.5 * (lo + hi);
        if (a * mid + b) * mid + c <= 0.0 {
            let half = 0.5 * (hi - lo);
            rule.extend(GAUSS.iter().map(|&(t, w)| (mid + half * t, half * w)));
        }
    }
    let crossings = roots
        .iter()
        .map(|&r| (r, 2.0 * a * r + b))
        .filter(|&(_, slope)| slope != 0.0)
        .collect();
    WetPart {
        rule,
        crossings,
        level: h,
    }
}

/// Quadratic shape functions and their derivatives at ξ ∈ [−1, 1].
fn shape(xi: f64) -> ([f64; 3], [f64; 3]) {
    (
        [0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)],
        [xi - 0.5, -2.0 * xi, xi + 0.5],
    )
}

/// Errors of the axisymmetric model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AxisymError {
    /// Bad construction input.
    #[error("{0}")]
    Input(String),
    /// The membrane is not defined at the state (an element inverted or collapsed).
    #[error("the membrane is not defined at the state (J <= 0 in element {0})")]
    Degenerate(usize),
    /// The membrane's block is not positive definite, so critical loads of a load block are
    /// not defined by it.
    #[error("the membrane block of wave number {0} is not positive definite")]
    Indefinite(usize),
    /// A non-finite number appeared in the energy, its derivatives or a block.
    #[error("a non-finite value in the axisymmetric model")]
    NonFinite,
    /// A material quantity is out of its range at the parameters.
    #[error("{0}")]
    Material(String),
}

/// The meridian's material: the shear modulus μ, the Mooney–Rivlin ratio k = c2/c1 and the
/// stress-free thickness H, each a number or a parameter, evaluated at the parameters in
/// every evaluation (docs/theory.md §15.18). The pre-stretch is a number,
/// [`Meridian::prestretch`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeridianMaterial {
    /// μ > 0.
    pub mu: Quantity,
    /// k ≥ 0.
    pub k: Quantity,
    /// H > 0.
    pub thickness: Quantity,
}

impl From<MooneyRivlin> for MeridianMaterial {
    /// The constants of `material` as numbers.
    fn from(material: MooneyRivlin) -> Self {
        Self {
            mu: Quantity::Value(material.mu()),
            k: Quantity::Value(material.k()),
            thickness: Quantity::Value(material.thickness),
        }
    }
}

impl MeridianMaterial {
    /// (μ, k, H) at `params`; an error naming the quantity that left its range.
    pub fn values(&self, params: &[f64]) -> Result<[f64; 3], AxisymError> {
        let v = [
            self.mu.value(params),
            self.k.value(params),
            self.thickness.value(params),
        ];
        for (i, (&x, name)) in v.iter().zip(["mu", "k", "thickness"]).enumerate() {
            let ok = x.is_finite() && if i == 1 { x >= 0.0 } else { x > 0.0 };
            if !ok {
                return Err(AxisymError::Material(format!(
                    "the material's {name} = {x} is out of its range ({})",
                    if i == 1 { ">= 0" } else { "> 0" }
                )));
            }
        }
        Ok(v)
    }

    /// The Mooney–Rivlin material at `params`.
    pub fn at(&self, params: &[f64]) -> Result<MooneyRivlin, AxisymError> {
        let [mu, k, thickness] = self.values(params)?;
        Ok(MooneyRivlin::new(mu, k, thickness))
    }

    /// Whether μ, k or H is a parameter.
    pub fn has_parameter(&self) -> bool {
        [self.mu, self.k, self.thickness]
            .iter()
            .any(|q| q.parameter().is_some())
    }
}

/// A meridian of quadratic elements: the stress-free data of a membrane of revolution.
#[derive(Debug, Clone)]
pub struct Meridian {
    /// Reference nodes (R, Z), 2E + 1 of them; element e has nodes 2e, 2e + 1, 2e + 2.
    pub nodes: Vec<[f64; 2]>,
    /// The isotropic pre-stretch λ0 (the stress-free metric is the reference one / λ0²).
    pub prestretch: f64,
    /// The material (μ, k, H: numbers or parameters).
    pub material: MeridianMaterial,
    /// Which ends are clamped: (first node, last node).
    pub clamped: (bool, bool),
    /// Which ends slide on a plane z = const (docs/theory.md §15.9): the end node keeps its
    /// height (W = 0 for every wave number) and moves freely in r and θ.
    pub sliding: (bool, bool),
    /// How the membrane carries compression: the plain energy, or the relaxed
    /// (tension-field) energy of docs/theory.md §2.9, the same law as on a 3-D mesh.
    pub wrinkling: Wrinkling,
}

/// A meridian's radius must be finite and positive, and it needs at least one element.
fn check_size(radius: f64, elements: usize) -> Result<(), AxisymError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(AxisymError::Input(format!(
            "radius: must be finite and > 0, got {radius}"
        )));
    }
    if elements == 0 {
        return Err(AxisymError::Input(
            "elements: must be at least 1, got 0".into(),
        ));
    }
    Ok(())
}

impl Meridian {
    /// The flat disc of radius `radius` in z = 0 from the axis to a clamped rim, `elements`
    /// quadratic elements of equal length.
    pub fn disc(
        radius: f64,
        elements: usize,
        prestretch: f64,
        material: impl Into<MeridianMaterial>,
    ) -> Result<Self, AxisymError> {
        check_size(radius, elements)?;
        let n = 2 * elements;
        Ok(Self {
            nodes: (0..=n)
                .map(|i| [radius * i as f64 / n as f64, 0.0])
                .collect(),
            prestretch,
            material: material.into(),
            clamped: (false, true),
            sliding: (false, false),
            wrinkling: Wrinkling::None,
        })
    }

    /// The sphere of radius `radius` as a meridian from the north pole to the south pole
    /// (outward normals), `elements` quadratic elements of equal angle; no end clamped.
    pub fn sphere(
        radius: f64,
        elements: usize,
        prestretch: f64,
        material: impl Into<MeridianMaterial>,
    ) -> Result<Self, AxisymError> {
        Self::arc(
            radius,
            std::f64::consts::PI,
            elements,
            prestretch,
            material.into(),
            false,
        )
    }

    /// The cap z ≥ `cut_height` of the sphere of radius `radius`, from the pole to a clamped
    /// cut (outward normals), `elements` quadratic elements of equal angle.
    pub fn truncated_sphere(
        radius: f64,
        cut_height: f64,
        elements: usize,
        prestretch: f64,
        material: impl Into<MeridianMaterial>,
    ) -> Result<Self, AxisymError> {
        if !(cut_height.is_finite() && cut_height.abs() < radius) {
            return Err(AxisymError::Input(format!(
                "cut-height: must be finite and inside (-radius, radius), got {cut_height}"
            )));
        }
        let angle = (cut_height / radius).acos();
        Self::arc(radius, angle, elements, prestretch, material.into(), true)
    }

    fn arc(
        radius: f64,
        angle: f64,
        elements: usize,
        prestretch: f64,
        material: MeridianMaterial,
        clamped: bool,
    ) -> Result<Self, AxisymError> {
        check_size(radius, elements)?;
        let n = 2 * elements;
        let nodes = (0..=n)
            .map(|i| {
                let phi = angle * i as f64 / n as f64;
                // Exactly on the axis at the poles.
                let r = if i == 0 || (i == n && !clamped) {
                    0.0
                } else {
                    radius * phi.sin()
                };
                [r, radius * phi.cos()]
            })
            .collect();
        Ok(Self {
            nodes,
            prestretch,
            material,
            clamped: (false, clamped),
            sliding: (false, false),
            wrinkling: Wrinkling::None,
        })
    }

    /// The membrane's energy per stress-free volume W, its gradient and its Hessian blocks in
    /// F = [f1 f2] for `material` (the meridian's at the parameters, or its derivative in
    /// k: every term is linear in (c1, c2), the relaxed energy's states and blends
    /// included), under the meridian's law of compression. `None` where J ≤ 0.
    #[allow(clippy::type_complexity)]
    pub fn energy_in_f(
        &self,
        material: &MooneyRivlin,
        f: &[Vector3<f64>; 2],
    ) -> Option<(f64, [Vector3<f64>; 2], [[nalgebra::Matrix3<f64>; 2]; 2])> {
        match self.wrinkling {
            Wrinkling::None => material.energy_in_f(f),
            Wrinkling::Relaxed { stiffness, width } => material
                .relaxed_in_f(f, stiffness, width)
                .map(|(w, p, hf, _)| (w, p, hf)),
        }
    }

    /// Whether node `i` is at a clamped end.
    pub fn is_clamped(&self, i: usize) -> bool {
        (i == 0 && self.clamped.0) || (i + 1 == self.nodes.len() && self.clamped.1)
    }

    /// Whether node `i` is at a sliding end.
    pub fn is_sliding(&self, i: usize) -> bool {
        (i == 0 && self.sliding.0) || (i + 1 == self.nodes.len() && self.sliding.1)
    }

    /// Whether the meridian closes the surface: both ends on the axis, none clamped.
    pub fn closed(&self) -> bool {
        let last = self.nodes.len() - 1;
        self.nodes[0][0] == 0.0 && self.nodes[last][0] == 0.0 && !self.clamped.0 && !self.clamped.1
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        (self.nodes.len() - 1) / 2
    }

    /// The unknowns (U, V, W per node, node-major) that a block of wave number m keeps, as
    /// the columns of T: full = T · kept (clamped ends and the axis conditions above).
    fn kept(&self, m: usize) -> DMatrix<f64> {
        let n = self.nodes.len();
        let mut cols: Vec<Vec<(usize, f64)>> = Vec::new();
        for (i, x) in self.nodes.iter().enumerate() {
            let clamped = (i == 0 && self.clamped.0) || (i == n - 1 && self.clamped.1);
            if clamped {
                continue;
            }
            if x[0] == 0.0 {
                match m {
                    0 => cols.push(vec![(3 * i + 2, 1.0)]),
                    1 => cols.push(vec![(3 * i, 1.0), (3 * i + 1, -1.0)]),
                    _ => {}
                }
                continue;
            }
            let slides = self.is_sliding(i);
            for c in 0..3 {
                if !(slides && c == 2) {
                    cols.push(vec![(3 * i + c, 1.0)]);
                }
            }
        }
        let mut t = DMatrix::zeros(3 * n, cols.len());
        for (j, col) in cols.iter().enumerate() {
            for &(r, v) in col {
                t[(r, j)] = v;
            }
        }
        t
    }
}

/// A hydrostatic load per unit density: pressure g (h − z) on the side of n = x_ξ × x_θ (for
/// a floor whose meridian runs outward from the axis, the fluid above it), where z < h: a
/// partly wet element is integrated over its wet part (docs/theory.md §15.14).
#[derive(Debug, Clone, Copy)]
pub struct Hydrostatic {
    /// Gravity g.
    pub gravity: f64,
    /// The fluid level h.
    pub level: f64,
}

/// Per Gauss point of an element: the reference and current geometry the blocks need.
struct Point {
    n: [f64; 3],
    dn: [f64; 3],
    weight: f64,
    big_r: f64,
    dx_ref: f64,
    r: f64,
    x_xi: Vector3<f64>,
}

impl Point {
    /// The principal stretches of a state of revolution from the stress-free one
    /// (pre-stretch λ0): meridional λ0 |x_ξ|/|X_ξ| and hoop λ0 r/R.
    fn stretches(&self, prestretch: f64) -> (f64, f64) {
        (
            prestretch * self.x_xi.norm() / self.dx_ref,
            prestretch * self.r / self.big_r,
        )
    }
}

fn points(meridian: &Meridian, x: &[[f64; 2]], e: usize) -> Vec<Point> {
    points_on(meridian, x, e, &GAUSS)
}

/// Gauss–Legendre points and weights on [−1, 1], 5 points (exact to degree 9: the spin's
/// r⁴ z_ξ and its variations on quadratic elements, so that its discrete gradient is the
/// discrete pressure form exactly, as 4 points are for the p(z) potentials).
const GAUSS5: [(f64, f64); 5] = [
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.0, 0.568_888_888_888_888_9),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// The points of element e on the rule `rule`.
fn points_on(meridian: &Meridian, x: &[[f64; 2]], e: usize, rule: &[(f64, f64)]) -> Vec<Point> {
    rule.iter()
        .map(|&(xi, w)| {
            let (n, dn) = shape(xi);
            let node = |k: usize| 2 * e + k;
            let mut rz = [0.0; 2];
            let mut drz = [0.0; 2];
            let mut rz0 = [0.0; 2];
            let mut drz0 = [0.0; 2];
            for k in 0..3 {
                for c in 0..2 {
                    rz[c] += n[k] * x[node(k)][c];
                    drz[c] += dn[k] * x[node(k)][c];
                    rz0[c] += n[k] * meridian.nodes[node(k)][c];
                    drz0[c] += dn[k] * meridian.nodes[node(k)][c];
                }
            }
            Point {
                n,
                dn,
                weight: w,
                big_r: rz0[0],
                dx_ref: drz0[0].hypot(drz0[1]),
                r: rz[0],
                x_xi: Vector3::new(drz[0], 0.0, drz[1]),
            }
        })
        .collect()
}

/// The perturbation of family "cos" rotated by `phase` about z, at angle θ in the rotating
/// frame (e_r, e_θ, e_z), for the element's 9 unknowns (U, V, W per node): δx, δx_ξ and δx_θ
/// as 3 × 9 matrices. (Rotating the field by α reads its components at θ − α.)
fn perturbation(p: &Point, m: usize, theta: f64, phase: f64) -> [nalgebra::SMatrix<f64, 3, 9>; 3] {
    let mf = m as f64;
    let (c, s) = if m == 0 {
        (1.0, 1.0)
    } else {
        ((mf * (theta - phase)).cos(), (mf * (theta - phase)).sin())
    };
    let mut dx = nalgebra::SMatrix::<f64, 3, 9>::zeros();
    let mut dxi = dx;
    let mut dth = dx;
    for k in 0..3 {
        let (u, v, w) = (3 * k, 3 * k + 1, 3 * k + 2);
        // δx = U c e_r + V s e_θ + W c e_z (m = 0: c = s = 1).
        dx[(0, u)] = p.n[k] * c;
        dx[(1, v)] = p.n[k] * s;
        dx[(2, w)] = p.n[k] * c;
        dxi[(0, u)] = p.dn[k] * c;
        dxi[(1, v)] = p.dn[k] * s;
        dxi[(2, w)] = p.dn[k] * c;
        // ∂/∂θ in the rotating frame: ∂e_r/∂θ = e_θ, ∂e_θ/∂θ = −e_r.
        let (dc, ds) = if m == 0 {
            (0.0, 0.0)
        } else {
            (-mf * s, mf * c)
        };
        dth[(0, u)] = p.n[k] * dc;
        dth[(1, u)] = p.n[k] * c;
        dth[(1, v)] = p.n[k] * ds;
        dth[(0, v)] = -p.n[k] * s;
        dth[(2, w)] = p.n[k] * dc;
    }
    [dx, dxi, dth]
}

/// Angles for the θ integral of a block of wave number m: the trapezoidal rule on this many
/// equispaced points is exact for the products of two harmonics of order ≤ m.
fn angles(m: usize) -> usize {
    2 * m + 4
}

/// Scatters an element's 9 × 9 matrix into the full 3(2E+1) matrix.
fn scatter(full: &mut DMatrix<f64>, e: usize, local: &nalgebra::SMatrix<f64, 9, 9>) {
    let base = 3 * 2 * e;
    for i in 0..9 {
        for j in 0..9 {
            full[(base + i, base + j)] += local[(i, j)];
        }
    }
}

/// The membrane's block of wave number m at the state `x` and the parameters `params` (all
/// 3(2E+1) unknowns, before the boundary conditions).
fn membrane_full(
    meridian: &Meridian,
    x: &[[f64; 2]],
    params: &[f64],
    m: usize,
    phase: f64,
) -> Result<DMatrix<f64>, AxisymError> {
    let lam = meridian.prestretch;
    let material = meridian.material.at(params)?;
    let h = material.thickness;
    let nt = angles(m);
    let mut k = DMatrix::zeros(3 * meridian.nodes.len(), 3 * meridian.nodes.len());
    for e in 0..meridian.elements() {
        let mut local = nalgebra::SMatrix::<f64, 9, 9>::zeros();
        for p in points(meridian, x, e) {
            let f = [
                p.x_xi * (lam / p.dx_ref),
                Vector3::new(0.0, lam * p.r / p.big_r, 0.0),
            ];
            let (_, _, hf) = meridian
                .energy_in_f(&material, &f)
                .ok_or(AxisymError::Degenerate(e))?;
            let da0 = p.dx_ref * p.big_r / (lam * lam) * p.weight;
            for t in 0..nt {
                let theta = 2.0 * std::f64::consts::PI * t as f64 / nt as f64;
                let [_, dxi, dth] = perturbation(&p, m, theta, phase);
                let b = [dxi * (lam / p.dx_ref), dth * (lam / p.big_r)];
                let dtheta = 2.0 * std::f64::consts::PI / nt as f64;
                for i in 0..2 {
                    for kk in 0..2 {
                        let hik: &Matrix3<f64> = &hf[i][kk];
                        local += b[i].transpose() * hik * b[kk] * (h * da0 * dtheta);
                    }
                }
            }
        }
        scatter(&mut k, e, &local);
    }
    Ok(k)
}

/// The hydrostatic block of wave number m per unit density (the tangent is linear in ρ),
/// fluid on the side of n = x_ξ × x_θ (above a floor whose meridian runs outward).
fn hydrostatic_full(
    meridian: &Meridian,
    x: &[[f64; 2]],
    load: &Hydrostatic,
    m: usize,
    phase: f64,
    wet_only: bool,
) -> DMatrix<f64> {
    let nt = angles(m);
    let mut k = DMatrix::zeros(3 * meridian.nodes.len(), 3 * meridian.nodes.len());
    for e in 0..meridian.elements() {
        let mut local = nalgebra::SMatrix::<f64, 9, 9>::zeros();
        let rule = if wet_only {
            let zs = [x[2 * e][1], x[2 * e + 1][1], x[2 * e + 2][1]];
            wet_part(zs, load.level).rule
        } else {
            GAUSS.to_vec()
        };
        for p in points_on(meridian, x, e, &rule) {
            let z: f64 = (0..3).map(|k| p.n[k] * x[2 * e + k][1]).sum();
            let pressure = load.gravity * (load.level - z);
            let x_th = Vector3::new(0.0, p.r, 0.0);
            let nda = p.x_xi.cross(&x_th);
            let dtheta = 2.0 * std::f64::consts::PI / nt as f64;
            for t in 0..nt {
                let theta = 2.0 * std::f64::consts::PI * t as f64 / nt as f64;
                let [dx, dxi, dth] = perturbation(&p, m, theta, phase);
                let mut a = nalgebra::SMatrix::<f64, 9, 9>::zeros();
                for j in 0..9 {
                    let (dj, dxij, dthj) = (dx.column(j), dxi.column(j), dth.column(j));
                    // δ(n dA) along unknown j.
                    let dn = dxij.cross(&x_th) + p.x_xi.cross(&dthj);
                    for i in 0..9 {
                        let di = dx.column(i);
                        a[(i, j)] = -load.gravity * dj[2] * nda.dot(&di) + pressure * di.dot(&dn);
                    }
                }
                local += (a + a.transpose()) * (0.5 * p.weight * dtheta);
            }
        }
        scatter(&mut k, e, &local);
    }
    k
}

/// One Fourier block: its wave number, multiplicity in the 3-D problem and critical loads.
#[derive(Debug, Clone)]
pub struct ModeLoads {
    /// The wave number m.
    pub m: usize,
    /// 1 for m = 0, 2 for m ≥ 1 (the cos and sin families share the block).
    pub multiplicity: usize,
    /// The lowest densities ρ at which K_membrane + ρ K_fluid is singular, ascending.
    pub densities: Vec<f64>,
}

/// The critical densities of a hydrostatic load on the state `x` (the current nodes (r, z),
/// held: linear buckling) by
/// wave number m = 0..=`modes`: the positive ρ with det(K_m + ρ K_f,m) = 0, from the
/// generalised symmetric eigenproblem with K_m positive definite (Cholesky K_m = L Lᵀ, the
/// eigenvalues μ of −L⁻¹ K_f Lᵀ⁻¹, ρ = 1/μ for μ > 0), the `lowest` of each. The material
/// must be numbers ([`critical_densities_at`] takes parameters).
pub fn critical_densities(
    meridian: &Meridian,
    x: &[[f64; 2]],
    load: &Hydrostatic,
    modes: usize,
    lowest: usize,
) -> Result<Vec<ModeLoads>, AxisymError> {
    if meridian.material.has_parameter() {
        return Err(AxisymError::Input(
            "material: mu, k or thickness is a parameter; critical_densities_at takes the parameters".into(),
        ));
    }
    critical_densities_at(meridian, x, &[], load, modes, lowest)
}

/// [`critical_densities`] with the material evaluated at the parameters `params`.
pub fn critical_densities_at(
    meridian: &Meridian,
    x: &[[f64; 2]],
    params: &[f64],
    load: &Hydrostatic,
    modes: usize,
    lowest: usize,
) -> Result<Vec<ModeLoads>, AxisymError> {
    if x.len() != meridian.nodes.len() {
        return Err(AxisymError::Input(format!(
            "state: {} nodes for a meridian of {}",
            x.len(),
            meridian.nodes.len()
        )));
    }
    (0..=modes)
        .map(|m| {
            let t = meridian.kept(m);
            let km = t.transpose() * membrane_full(meridian, x, params, m, 0.0)? * &t;
            let kf = t.transpose() * hydrostatic_full(meridian, x, load, m, 0.0, true) * &t;
            let l = nalgebra::Cholesky::new((&km + km.transpose()) * 0.5)
                .ok_or(AxisymError::Indefinite(m))?
                .l();
            let li = l.clone().try_inverse().ok_or(AxisymError::Indefinite(m))?;
            let s = -(&li * kf * li.transpose());
            let s = (&s + s.transpose()) * 0.5;
            let scale = s.amax().max(1e-300);
            let mut densities: Vec<f64> = s
                .symmetric_eigenvalues()
                .iter()
                .filter(|&&mu| mu > 1e-12 * scale)
                .map(|&mu| 1.0 / mu)
                .collect();
            densities.sort_by(f64::total_cmp);
            densities.truncate(lowest);
            Ok(ModeLoads {
                m,
                multiplicity: if m == 0 { 1 } else { 2 },
                densities,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The partner family of m ≥ 1 (the first rotated by π/(2m)) has the same blocks to
    /// round-off, on a curved, stretched meridian under a pressure that is not zero: the θ
    /// integral is exact, so the double is structural. The m-blocks of different m differ.
    #[test]
    fn partner_families_share_their_blocks() {
        let mat = MooneyRivlin::new(1.0, 0.2, 0.1);
        let mut meridian = Meridian::disc(1.0, 3, 1.05, mat).unwrap();
        meridian.nodes.iter_mut().for_each(|p| p[0] += 0.3);
        let x: Vec<[f64; 2]> = meridian
            .nodes
            .iter()
            .map(|p| [1.1 * p[0], -0.2 * (p[0] - 0.3) * (1.3 - p[0])])
            .collect();
        let load = Hydrostatic {
            gravity: 1.0,
            level: 0.5,
        };
        for m in 1..5 {
            let phase = std::f64::consts::PI / (2.0 * m as f64);
            let k0 = membrane_full(&meridian, &x, &[], m, 0.0).unwrap();
            let k1 = membrane_full(&meridian, &x, &[], m, phase).unwrap();
            assert!((&k0 - &k1).amax() < 1e-12 * k0.amax(), "membrane, m = {m}");
            let f0 = hydrostatic_full(&meridian, &x, &load, m, 0.0, true);
            let f1 = hydrostatic_full(&meridian, &x, &load, m, phase, true);
            assert!((&f0 - &f1).amax() < 1e-12 * f0.amax(), "fluid, m = {m}");
            let k2 = membrane_full(&meridian, &x, &[], m + 1, 0.0).unwrap();
            assert!((&k0 - &k2).amax() > 1e-3 * k0.amax());
        }
    }
}
