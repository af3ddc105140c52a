//! Closed-form reference solutions (docs/theory.md §13), shared by the tests, `memstab demo`
//! and `memstab bench`: the inflated Mooney–Rivlin sphere and the ponding ladder of a
//! pre-stretched clamped disc.

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

    #[test]
    fn tabulated_ponding_scale() {
        assert!((ponding_scale(0.0, 1.1) - PONDING_SCALE).abs() < 6e-8);
        assert!((prestretch_tension(0.0, 1.1) - 0.4355261).abs() < 6e-8);
    }
}
