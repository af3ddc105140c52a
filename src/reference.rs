//! Closed-form reference solutions (docs/theory.md §13), shared by the tests, `memstab demo`
//! and `memstab bench`: the inflated Mooney–Rivlin sphere, the ponding ladder of a
//! pre-stretched clamped disc and the tension field of a wrinkled annulus.

/// The over-pressure of an inflated incompressible Mooney–Rivlin sphere at equibiaxial
/// stretch λ, as p R/(μH) with R and H the stress-free radius and thickness:
/// 2/(1+k) (λ⁻¹ − λ⁻⁷)(1 + kλ²).
pub fn sphere_pressure(k: f64, stretch: f64) -> f64 {
    let l = stretch;
    2.0 / (1.0 + k) * (1.0 / l - l.powi(-7)) * (1.0 + k * l * l)
}

/// d/dλ of (λ⁻¹ − λ⁻⁷)(1 + kλ²), up to the factor 2/(1+k): −λ⁻² + 7λ⁻⁸ + k + 5kλ⁻⁶.
fn sphere_slope(k: f64, l: f64) -> f64 {
    -l.powi(-2) + 7.0 * l.powi(-8) + k + 5.0 * k * l.powi(-6)
}

/// The stretches λ in (1, 20) at which the inflated sphere holds the pressure p R/(μH) =
/// `pressure`, increasing: one below the pressure maximum's value, three between the minimum's
/// and the maximum's (the roots deflation finds, docs/theory.md §16). Bisection to round-off on
/// a fine bracket grid.
pub fn sphere_stretches(k: f64, pressure: f64) -> Vec<f64> {
    let f = |l: f64| sphere_pressure(k, l) - pressure;
    let n = 20_000;
    let at = |i: usize| 1.0 + 19.0 * i as f64 / n as f64;
    let mut roots = Vec::new();
    for i in 0..n {
        let (mut a, mut b) = (at(i), at(i + 1));
        if f(a) == 0.0 {
            roots.push(a);
            continue;
        }
        // A root on the grid is taken at the interval it starts.
        if f(a) * f(b) > 0.0 || f(b) == 0.0 {
            continue;
        }
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m == a || m == b {
                break;
            }
            if f(a) * f(m) <= 0.0 {
                b = m;
            } else {
                a = m;
            }
        }
        roots.push(0.5 * (a + b));
    }
    roots
}

/// An extremum of the sphere's pressure along its inflation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereExtremum {
    /// The stretch λ there.
    pub stretch: f64,
    /// p R/(μH) there.
    pub pressure: f64,
    /// True for a maximum, false for a minimum.
    pub maximum: bool,
}

/// The extrema of the sphere's pressure for λ in (1, 20), in increasing λ: for 0 ≤ k below
/// [`SPHERE_CUSP`]`.k` a maximum (and for k > 0 a minimum after it), none above. Found by
/// bisection on the slope to round-off.
pub fn sphere_extrema(k: f64) -> Vec<SphereExtremum> {
    let n = 20_000;
    let at = |i: usize| 1.0 + 19.0 * i as f64 / n as f64;
    let mut found = Vec::new();
    for i in 1..n {
        let (mut a, mut b) = (at(i), at(i + 1));
        let (fa, fb) = (sphere_slope(k, a), sphere_slope(k, b));
        if fa == 0.0 || fa.signum() == fb.signum() {
            continue;
        }
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if sphere_slope(k, m).signum() == fa.signum() {
                a = m;
            } else {
                b = m;
            }
        }
        let stretch = 0.5 * (a + b);
        found.push(SphereExtremum {
            stretch,
            pressure: sphere_pressure(k, stretch),
            maximum: fa > 0.0,
        });
    }
    found
}

/// The cusp of the sphere's fold line in (p, k): where its pressure maximum and minimum
/// merge (the slope and its derivative in λ vanish together).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cusp {
    /// k there.
    pub k: f64,
    /// λ there.
    pub stretch: f64,
    /// p R/(μH) there.
    pub pressure: f64,
}

/// The sphere's cusp, tabulated (10 digits; the tests recompute it from the slope).
pub const SPHERE_CUSP: Cusp = Cusp {
    k: 0.2144583510,
    stretch: 1.8407344175,
    pressure: 1.5050470052,
};

/// The k = 0.1 sphere's pressure maximum p R/(μH), tabulated (7 digits).
pub const P_MAX: f64 = 1.3551069;
/// The stretch at the k = 0.1 sphere's pressure maximum.
pub const L_MAX: f64 = 1.4760698;
/// The k = 0.1 sphere's pressure minimum p R/(μH), tabulated (7 digits).
pub const P_MIN: f64 = 1.1487477;
/// The stretch at the k = 0.1 sphere's pressure minimum.
pub const L_MIN: f64 = 3.1426213;
/// The k = 0 (neo-Hookean) sphere's pressure maximum p R/(μH), tabulated (7 digits).
pub const P_MAX_K0: f64 = 1.2394629;

/// The pre-stretch tension T0/(μH) = [(1 − λ0⁻⁶) + k(λ0² − λ0⁻⁴)]/(1 + k) of an
/// equibiaxially pre-stretched flat membrane.
pub fn prestretch_tension(k: f64, prestretch: f64) -> f64 {
    let l = prestretch;
    ((1.0 - l.powi(-6)) + k * (l * l - l.powi(-4))) / (1.0 + k)
}

/// The ponding ladder's scale T0/(μHλ0²): the rung of Bessel zero j_{m,k} is at
/// ρ g a²/(μH) = j²_{m,k} × this.
pub fn ponding_scale(k: f64, prestretch: f64) -> f64 {
    prestretch_tension(k, prestretch) / (prestretch * prestretch)
}

/// [`ponding_scale`] of the bundled ponding scene (k = 0, λ0 = 1.1), tabulated (7 digits).
pub const PONDING_SCALE: f64 = 0.3599389;

/// j²_{m,k}, squares of the zeros of the Bessel functions J_m, in increasing order: the
/// rungs ((m, k), j²) of the ponding ladder.
pub const BESSEL_J2: [((usize, usize), f64); 15] = [
    ((0, 1), 5.783186),
    ((1, 1), 14.681971),
    ((2, 1), 26.374616),
    ((0, 2), 30.471262),
    ((3, 1), 40.706466),
    ((1, 2), 49.218456),
    ((4, 1), 57.582941),
    ((2, 2), 70.849999),
    ((0, 3), 74.887007),
    ((5, 1), 76.938928),
    ((3, 2), 95.277573),
    ((6, 1), 98.726272),
    ((1, 3), 103.499454),
    ((4, 2), 122.427796),
    ((7, 1), 122.907600),
];

/// The tension field of a flat annulus (docs/theory.md §13.5): a stress-free annulus
/// a ≤ R ≤ b of incompressible Mooney–Rivlin (c1, c2) whose rims are held at the radii
/// r_a < r_b, so far apart radially and so close together in hoop that it is wrinkled
/// everywhere, the tension rays radial. The relaxed energy per stress-free volume is
/// w(λ) = c1(λ² + 2/λ − 3) + c2(2λ + λ⁻² − 3) of the radial stretch λ = dr/dR alone, so
/// equilibrium, d/dR (R w′(λ)) = 0, gives R w′(λ(R)) = K, and
/// r(R) = r_a + ∫_a^R λ, with K fixed by r(b) = r_b. The radial force on either rim is 2π H K.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnnulusTensionField {
    c1: f64,
    c2: f64,
    a: f64,
    b: f64,
    inner: f64,
    /// K = R w′(λ(R)), the same at every radius.
    pub constant: f64,
}

/// Five-point Gauss–Legendre nodes and weights on [−1, 1].
const GAUSS5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

impl AnnulusTensionField {
    /// The field of the annulus a < b with rims held at r_a < r_b; `None` unless it is
    /// wrinkled everywhere: r_b − r_a > b − a (every radial fibre stretched) and the hoop
    /// stretch r/R below the natural width λ^(−1/2) at every radius.
    pub fn new(c1: f64, c2: f64, a: f64, b: f64, inner: f64, outer: f64) -> Option<Self> {
        if !(0.0 < a && a < b && 0.0 < inner && inner < outer && outer - inner > b - a) {
            return None;
        }
        let mut field = Self {
            c1,
            c2,
            a,
            b,
            inner,
            constant: 0.0,
        };
        // ∫ λ grows with K from b − a (K = 0): bracket, then bisect to round-off.
        let gap = |f: &Self, k: f64| {
            let g = Self { constant: k, ..*f };
            g.radius(b) - outer
        };
        let mut hi = c1 + c2;
        while gap(&field, hi) < 0.0 {
            hi *= 2.0;
        }
        let mut lo = 0.0;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if gap(&field, mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        field.constant = 0.5 * (lo + hi);
        let wrinkled = (0..=1000).all(|i| {
            let r = a + (b - a) * f64::from(i) / 1000.0;
            field.radius(r) / r < 1.0 / field.stretch(r).sqrt()
        });
        wrinkled.then_some(field)
    }

    /// w′(λ) = 2c1(λ − λ⁻²) + 2c2(1 − λ⁻³), increasing for λ ≥ 1, and its derivative.
    fn slope(&self, l: f64) -> (f64, f64) {
        let (c1, c2) = (self.c1, self.c2);
        (
            2.0 * c1 * (l - 1.0 / (l * l)) + 2.0 * c2 * (1.0 - 1.0 / (l * l * l)),
            2.0 * c1 * (1.0 + 2.0 / (l * l * l)) + 6.0 * c2 / (l * l * l * l),
        )
    }

    /// The radial stretch λ(R) ≥ 1 with w′(λ) = K/R (Newton, kept in its bracket).
    pub fn stretch(&self, radius: f64) -> f64 {
        let target = self.constant / radius;
        let (mut lo, mut hi) = (1.0, 2.0);
        while self.slope(hi).0 < target {
            hi *= 2.0;
        }
        let mut l = 0.5 * (lo + hi);
        for _ in 0..100 {
            let (f, df) = self.slope(l);
            if f < target {
                lo = l;
            } else {
                hi = l;
            }
            let next = l - (f - target) / df;
            let next = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if (next - l).abs() <= 1e-16 * l {
                return next;
            }
            l = next;
        }
        l
    }

    /// The current radius r(R) = r_a + ∫_a^R λ (Gauss–Legendre on 400 panels).
    pub fn radius(&self, radius: f64) -> f64 {
        let panels = 400;
        let h = (radius - self.a) / f64::from(panels);
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = self.a + h * (f64::from(p) + 0.5);
            for (x, w) in GAUSS5 {
                sum += w * 0.5 * h * self.stretch(mid + 0.5 * h * x);
            }
        }
        self.inner + sum
    }

    /// The radial force on either rim of an annulus of stress-free thickness H: 2π H K.
    pub fn rim_force(&self, thickness: f64) -> f64 {
        2.0 * std::f64::consts::PI * thickness * self.constant
    }

    /// The stress-free outer radius b.
    pub fn outer_radius(&self) -> f64 {
        self.b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tabulated extrema are the computed ones to their 7 digits.
    #[test]
    fn tabulated_sphere_extrema_are_the_computed_ones() {
        let e = sphere_extrema(0.1);
        assert_eq!(e.len(), 2);
        assert!(e[0].maximum && !e[1].maximum);
        for (x, t) in [
            (e[0].pressure, P_MAX),
            (e[0].stretch, L_MAX),
            (e[1].pressure, P_MIN),
            (e[1].stretch, L_MIN),
        ] {
            assert!((x - t).abs() <= 5e-8, "{x} vs {t}");
        }
        let e0 = sphere_extrema(0.0);
        assert_eq!(e0.len(), 1);
        assert!((e0[0].pressure - P_MAX_K0).abs() < 6e-8);
        // Above the cusp there is no extremum; just below it, two close ones.
        assert!(sphere_extrema(SPHERE_CUSP.k + 1e-9).is_empty());
        let near = sphere_extrema(SPHERE_CUSP.k - 1e-9);
        assert_eq!(near.len(), 2);
        assert!((near[0].stretch - SPHERE_CUSP.stretch).abs() < 1e-3);
        assert!((near[0].pressure - SPHERE_CUSP.pressure).abs() < 1e-6);
    }

    /// The tabulated cusp has zero slope and zero curvature of the pressure.
    #[test]
    fn cusp_is_a_double_zero_of_the_slope() {
        let Cusp { k, stretch: l, .. } = SPHERE_CUSP;
        assert!(sphere_slope(k, l).abs() < 1e-10);
        // Central difference: truncation h²/6 |s'''| ≈ 1e-10, round-off ε/h ≈ 1e-11.
        let h = 1e-5;
        let curvature = (sphere_slope(k, l + h) - sphere_slope(k, l - h)) / (2.0 * h);
        assert!(curvature.abs() < 1e-8, "{curvature}");
        assert!((sphere_pressure(k, l) - SPHERE_CUSP.pressure).abs() < 1e-10);
    }

    /// J_m(x) by its power series (accurate to ~1e-11 for x ≤ 12).
    fn bessel_j(m: usize, x: f64) -> f64 {
        let mut term = (0.5 * x).powi(m as i32) / (1..=m).map(|i| i as f64).product::<f64>();
        let mut sum = term;
        for j in 1..80 {
            term *= -(0.25 * x * x) / (j as f64 * (j + m) as f64);
            sum += term;
        }
        sum
    }

    /// The tabulated j²_{m,k} are the squares of the zeros of J_m, recomputed here by
    /// bisection on the power series, in the table's increasing order.
    #[test]
    fn tabulated_bessel_zeros() {
        for &((m, k), j2) in &BESSEL_J2 {
            let mut zeros = Vec::new();
            let mut x = 0.5;
            while zeros.len() < k {
                let (a, b) = (x, x + 0.01);
                if bessel_j(m, a).signum() != bessel_j(m, b).signum() {
                    let (mut lo, mut hi) = (a, b);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if bessel_j(m, mid).signum() == bessel_j(m, lo).signum() {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    zeros.push(0.5 * (lo + hi));
                }
                x = b;
            }
            let z = zeros[k - 1];
            assert!((z * z - j2).abs() < 1e-5, "j({m},{k})² = {} vs {j2}", z * z);
        }
        assert!(BESSEL_J2.windows(2).all(|w| w[0].1 < w[1].1));
    }

    /// The annulus's field makes the relaxed energy 2πH ∫ w(r′) R dR stationary among radii
    /// with the same rims (a difference along a bump that vanishes there), is wrinkled, and
    /// has every fibre stretched.
    #[test]
    fn the_annulus_tension_field_is_an_equilibrium() {
        let (c1, c2) = (0.5 / 1.1, 0.05 / 1.1);
        let f = AnnulusTensionField::new(c1, c2, 0.25, 1.0, 0.1, 0.92).unwrap();
        assert!((f.radius(1.0) - 0.92).abs() < 1e-12);
        assert!(f.stretch(1.0) > 1.0 && f.stretch(0.25) > f.stretch(1.0));
        let w = |l: f64| c1 * (l * l + 2.0 / l - 3.0) + c2 * (2.0 * l + 1.0 / (l * l) - 3.0);
        let pi = std::f64::consts::PI;
        let energy = |d: f64| {
            let n = 4000;
            let h = 0.75 / f64::from(n);
            (0..n)
                .map(|i| {
                    let r = 0.25 + h * (f64::from(i) + 0.5);
                    let bump = d * pi / 0.75 * (pi * (r - 0.25) / 0.75).cos();
                    w(f.stretch(r) + bump) * r * h
                })
                .sum::<f64>()
        };
        let d = 1e-4;
        let first = (energy(d) - energy(-d)) / (2.0 * d);
        let second = (energy(d) - 2.0 * energy(0.0) + energy(-d)) / (d * d);
        assert!(first.abs() < 1e-8 * second, "{first:e} vs {second:e}");
        assert!(second > 0.0);
        // Rims too close radially, or a hoop stretch too large: not a tension field.
        assert!(AnnulusTensionField::new(c1, c2, 0.25, 1.0, 0.1, 0.8).is_none());
        assert!(AnnulusTensionField::new(c1, c2, 0.25, 1.0, 0.3, 1.2).is_none());
    }

    #[test]
    fn tabulated_ponding_scale() {
        assert!((ponding_scale(0.0, 1.1) - PONDING_SCALE).abs() < 6e-8);
        assert!((prestretch_tension(0.0, 1.1) - 0.4355261).abs() < 6e-8);
    }
}
