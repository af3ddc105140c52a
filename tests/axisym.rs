//! The axisymmetric reference (docs/theory.md §15): Fourier-mode blocks of a meridian of
//! quadratic elements. The ponding ladder of the flat pre-stretched clamped disc against the
//! closed form γ_{m,k} = j²_{m,k} T0/(μ H λ0²), to 1e-6 at 64 elements, with the observed
//! order of the error under refinement (≥ 4 for quadratic elements: the eigenvalue error of
//! degree-p elements is O(h^{2p})).

use memstab::axisym::{critical_densities, Hydrostatic, Meridian, ModeLoads};
use memstab::effects::membrane::MooneyRivlin;
use memstab::reference::{ponding_scale, BESSEL_J2};

fn j2(m: usize, k: usize) -> f64 {
    BESSEL_J2
        .iter()
        .find(|e| e.0 == (m, k))
        .map(|e| e.1)
        .expect("tabulated")
}

/// The ponding scene's disc (a = 1 clamped at λ0 a = 1.1, μ H = 1, g = 1, level at the rim
/// plane): critical densities by wave number.
fn ladder(elements: usize, modes: usize) -> Vec<ModeLoads> {
    let meridian = Meridian::disc(1.1, elements, 1.1, MooneyRivlin::new(100.0, 0.0, 0.01)).unwrap();
    let x = meridian.nodes.clone();
    let load = Hydrostatic {
        gravity: 1.0,
        level: 0.0,
    };
    critical_densities(&meridian, &x, &load, modes, 3).unwrap()
}

#[test]
fn the_ponding_ladder_to_the_closed_form_at_fourth_order() {
    let cases = [
        (0, 1),
        (0, 2),
        (1, 1),
        (1, 2),
        (2, 1),
        (3, 1),
        (4, 1),
        (7, 1),
    ];
    let fine = ladder(64, 7);
    let coarse = [ladder(8, 7), ladder(16, 7)];
    for (m, k) in cases {
        // j² is tabulated to 6 decimals (≤ 1e-7 relative), the scale computed exactly.
        let exact = ponding_scale(0.0, 1.1) * j2(m, k);
        let err = |l: &[ModeLoads]| (l[m].densities[k - 1] - exact).abs() / exact;
        let e64 = err(&fine);
        assert!(
            e64 < 1e-6,
            "(m, k) = ({m}, {k}): error {e64:e} at 64 elements"
        );
        let (e8, e16) = (err(&coarse[0]), err(&coarse[1]));
        let order = (e8 / e16).log2();
        eprintln!("(m, k) = ({m}, {k}): errors {e8:.2e}, {e16:.2e}, {e64:.2e}; order {order:.2}");
        assert!(
            order >= 3.8,
            "(m, k) = ({m}, {k}): errors {e8:e} → {e16:e}, order {order}"
        );
    }
    assert_eq!(fine[0].multiplicity, 1);
    assert!(fine[1..].iter().all(|b| b.multiplicity == 2));
}

#[test]
fn bad_input_is_refused() {
    let mat = MooneyRivlin::new(100.0, 0.0, 0.01);
    assert!(Meridian::disc(0.0, 4, 1.1, mat)
        .unwrap_err()
        .to_string()
        .contains("radius"));
    assert!(Meridian::disc(1.0, 0, 1.1, mat)
        .unwrap_err()
        .to_string()
        .contains("elements"));
    let meridian = Meridian::disc(1.0, 4, 1.1, mat).unwrap();
    let mut x = meridian.nodes.clone();
    x[3][1] = 0.1;
    let load = Hydrostatic {
        gravity: 1.0,
        level: 0.0,
    };
    let err = critical_densities(&meridian, &x, &load, 2, 1).unwrap_err();
    assert!(err.to_string().contains("node 3"), "{err}");
}
