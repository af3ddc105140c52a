//! Mulliken labels for the irreps of a point group, derived from their characters.
//!
//! A label is `letter`, `number`, `mark`, each read off the character `χ` of a real irrep at
//! a few elements chosen from the group's Schoenflies type (see [`crate::SubgroupClass`]):
//!
//! - **letter** by the real dimension: 1 → `A` or `B`, 2 → `E`, 3 → `T`, 4 → `G`, 5 → `H`.
//!   A complex-type irrep (a pair of complex-conjugate irreps, as `¹E`, `²E` of chemistry's
//!   tables) is 2-dimensional over ℝ and so an `E`. For 1-D irreps: `A` if `χ(p) = +1` for the
//!   *principal element* `p`, `B` if `χ(p) = −1`; `p` is the rotation by `2π/n` about the
//!   principal axis for `C_n`, `C_nv`, `C_nh`, `D_n`, `D_nh`, `D_nd` (n odd) and `S_2n` (n odd),
//!   and the improper rotation `S_2n` by `2π/2n` for `S_2n` and `D_nd` with n even. Groups
//!   without a principal axis (`C1`, `Ci`, `Cs`, `T`, `Th`, `Td`, `O`, `Oh`, `I`, `Ih`) only
//!   have `A`.
//! - **number**:
//!   - `E_j` (2-D irreps, when `p` has order ≥ 5, where several `E` occur): `χ(p) =
//!     2 cos(2πj/n)` with `n` the order of `p`;
//!   - `A_1`/`A_2`, `B_1`/`B_2` (`D` groups): `1` if `χ = +1` at a half-turn `C2'`
//!     perpendicular to the principal axis (for even n, where the `C2'` form two classes: the
//!     one of least element index), `2` if `−1`; in `C_nv` the same with the first mirror;
//!   - `D2`, `D2h`: the three half-turns are assigned to z, y, x (the axis closest to the
//!     coordinate z-axis is z, of the other two the one closest to y is y); `A` is symmetric
//!     under all three, `B1`, `B2`, `B3` under the half-turn about z, y, x only;
//!   - `O`, `Oh`, `Td`: `A1`/`A2`, `T1`/`T2` by the sign of `χ` at a 4-fold element (`C4`, or
//!     `S4` in `Td`); `I`, `Ih`: `T1`/`T2` by the sign of `χ` at the rotation by 72° (`φ` or
//!     `1 − φ`).
//! - **mark**: `g`/`u` by the sign of `χ(−I)` when `−I` is in the group; otherwise `'`/`''` by
//!   the sign of `χ(σh)` when there is a mirror `σh` perpendicular to the principal axis
//!   (`C_nh`, `D_nh` with n odd, and `Cs`).
//!
//! The irreps are ordered as in the standard tables: all `g` (or `'`) before all `u` (`''`),
//! then by letter `A, B, E, T, G, H`, then by number; the trivial irrep is always first. For
//! example `D5d`: `A1g, A2g, E1g, E2g, A1u, A2u, E1u, E2u`; `D2h`: `Ag, B1g, B2g, B3g, Au, B1u,
//! B2u, B3u`; `Th`: `Ag, Eg, Tg, Au, Eu, Tu`. Should two irreps of some unusual group get the
//! same label, the later ones are suffixed `#2`, `#3`, … so names stay unique.
//!
//! (The axial groups `C_n`, `C_nv` built by the `axial` module keep their own names, with `E_j`
//! numbered from `E1` even when there is only one.)

use crate::decompose::RawIrrep;
use crate::group::{Group, Matrix3};
use crate::irrep::{Irrep, IrrepKind};
use crate::lattice::PointGroup;
use crate::subgroup::rotation_axis;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Tolerance for traces and for perpendicular or parallel axes.
const TOL: f64 = 1e-6;

/// Dimensions that the subscript 1/2 applies to.
const ONE: &[usize] = &[1];
const ONE_THREE: &[usize] = &[1, 3];
const THREE: &[usize] = &[3];

/// Order of labels: mark (`g`/`'` first), letter (A, B, E, T, G, H), number.
type SortKey = (u8, u8, usize);

/// The elements whose characters decide the labels (module documentation).
#[derive(Debug, Default)]
struct Frame {
    /// The principal element `p` and its order.
    principal: Option<(usize, usize)>,
    /// Whether 2-D irreps are numbered `E_j`.
    numbered_e: bool,
    /// The element deciding the subscript 1/2, and the dimensions it applies to.
    secondary: Option<(usize, &'static [usize])>,
    /// For `D2`, `D2h`: the half-turns about (z, y, x).
    d2_axes: Option<[usize; 3]>,
    /// `−I`.
    inversion: Option<usize>,
    /// `σh`, when there is no inversion.
    horizontal: Option<usize>,
}

/// The irreps named and ordered (module documentation).
pub(crate) fn named_irreps(group: &Group, raw: Vec<RawIrrep>) -> Vec<Irrep> {
    let frame = Frame::of(group);
    // (sort key: non-trivial, mark, letter, number; label; irrep)
    type Labelled = ((bool, SortKey), String, RawIrrep);
    let mut labelled: Vec<Labelled> = raw
        .into_iter()
        .map(|r| {
            let (name, key) = frame.label(&r);
            ((!r.is_trivial(), key), name, r)
        })
        .collect();
    labelled.sort_by_key(|l| l.0);
    let mut used: Vec<String> = Vec::new();
    labelled
        .into_iter()
        .map(|(_, name, r)| {
            let count = used.iter().filter(|u| **u == name).count();
            used.push(name.clone());
            let name = if count == 0 {
                name
            } else {
                format!("{name}#{}", count + 1)
            };
            match (r.kind, r.complex_structure) {
                (IrrepKind::Complex, Some(j)) => Irrep::complex(name, r.matrices, j),
                _ => Irrep::real(name, r.matrices),
            }
        })
        .collect()
}

impl Frame {
    fn of(g: &Group) -> Self {
        let all: Vec<usize> = (0..g.order()).collect();
        let mut f = Frame {
            inversion: (0..g.order()).find(|&x| g.is_minus_identity(x)),
            ..Frame::default()
        };
        let proper = |k: usize| turn(g, k, true);
        let improper = |k: usize| turn(g, k, false);
        let perpendicular_half_turn = |p: Option<usize>| {
            let axis = p.map(|p| principal_axis(g.element(p)))?;
            (0..g.order()).find(|&x| {
                g.is_proper(x)
                    && x != 0
                    && g.element_order(x) == 2
                    && rotation_axis(g.element(x)).dot(&axis).abs() < TOL
            })
        };
        let horizontal_mirror = |p: Option<usize>| {
            let axis = p.map(|p| principal_axis(g.element(p)))?;
            (0..g.order()).find(|&x| {
                let m = g.element(x);
                !g.is_proper(x) && (m.trace() - 1.0).abs() < TOL && (m * axis + axis).amax() < TOL
            })
        };
        let first_mirror = (0..g.order()).find(|&x| !g.is_proper(x));
        match g.point_group(&all) {
            PointGroup::C(k) => f.principal = proper(k),
            PointGroup::Cv(k) => {
                f.principal = proper(k);
                f.secondary = first_mirror.map(|m| (m, ONE));
            }
            PointGroup::Ch(k) => {
                f.principal = proper(k);
                if f.inversion.is_none() {
                    f.horizontal = horizontal_mirror(f.principal.map(|p| p.0));
                }
            }
            PointGroup::S(m) => {
                f.principal = if (m / 2) % 2 == 1 {
                    proper(m / 2)
                } else {
                    improper(m)
                };
            }
            PointGroup::D(2) | PointGroup::Dh(2) => f.d2_axes = d2_axes(g),
            PointGroup::D(k) | PointGroup::Dh(k) | PointGroup::Dd(k) => {
                let is_dd = matches!(g.point_group(&all), PointGroup::Dd(_));
                f.principal = if is_dd && k % 2 == 0 {
                    improper(2 * k)
                } else {
                    proper(k)
                };
                let p = f.principal.map(|p| p.0);
                f.secondary = perpendicular_half_turn(p).map(|q| (q, ONE));
                if f.inversion.is_none() && !is_dd {
                    f.horizontal = horizontal_mirror(p);
                }
            }
            PointGroup::Cs => f.horizontal = first_mirror,
            PointGroup::Td => f.secondary = improper(4).map(|(q, _)| (q, ONE_THREE)),
            PointGroup::O | PointGroup::Oh => {
                f.secondary = proper(4).map(|(q, _)| (q, ONE_THREE));
            }
            PointGroup::I | PointGroup::Ih => {
                f.secondary = proper(5).map(|(q, _)| (q, THREE));
            }
            PointGroup::Ci | PointGroup::T | PointGroup::Th | PointGroup::Unknown(_) => {}
        }
        f.numbered_e = f.principal.is_some_and(|(_, n)| n >= 5);
        f
    }

    /// The label of one irrep and its sort key (mark, letter, number).
    fn label(&self, r: &RawIrrep) -> (String, SortKey) {
        let chi = &r.characters;
        let d = r.dim();
        let positive = |g: usize| chi[g] > 0.0;
        // D2, D2h: the first of the half-turns about z, y, x under which a 1-D irrep is
        // symmetric, unless it is symmetric under all three.
        let d2_symmetric = self.d2_axes.and_then(|axes| {
            let sym: Vec<bool> = axes.iter().map(|&h| positive(h)).collect();
            if sym.iter().all(|&s| s) {
                None
            } else {
                Some(sym.iter().position(|&s| s).map_or(0, |i| i + 1))
            }
        });
        let letter = match d {
            1 if d2_symmetric.is_some() => "B",
            1 if self.principal.is_some_and(|(p, _)| !positive(p)) => "B",
            1 => "A",
            2 => "E",
            3 => "T",
            4 => "G",
            5 => "H",
            _ => "Γ",
        };
        let number = match (d, self.secondary) {
            (1, _) if self.d2_axes.is_some() => d2_symmetric.unwrap_or(0),
            (2, _) if self.numbered_e => {
                // χ(p) = 2 cos(2πj/n).
                let (p, n) = self.principal.unwrap_or((0, 1));
                let angle = (chi[p] / 2.0).clamp(-1.0, 1.0).acos();
                (angle * n as f64 / (2.0 * PI)).round() as usize
            }
            (_, Some((q, dims))) if dims.contains(&d) => {
                if positive(q) {
                    1
                } else {
                    2
                }
            }
            _ => 0,
        };
        let (mark, side) = match (self.inversion, self.horizontal) {
            (Some(i), _) if positive(i) => ("g", 0),
            (Some(_), _) => ("u", 1),
            (None, Some(h)) if positive(h) => ("'", 0),
            (None, Some(_)) => ("''", 1),
            (None, None) => ("", 0),
        };
        let rank = ["A", "B", "E", "T", "G", "H"]
            .iter()
            .position(|l| *l == letter)
            .unwrap_or(6) as u8;
        let letter = if letter == "Γ" {
            format!("Γ{d}_")
        } else {
            letter.to_string()
        };
        let number_text = if number == 0 {
            String::new()
        } else {
            number.to_string()
        };
        (format!("{letter}{number_text}{mark}"), (side, rank, number))
    }
}

/// The element turning by `2π/k` (proper: a rotation; improper: `S_k`, a rotation by `2π/k`
/// followed by the mirror perpendicular to its axis) of order k, least index first, with its
/// order.
fn turn(g: &Group, k: usize, proper: bool) -> Option<(usize, usize)> {
    let c = (2.0 * PI / k as f64).cos();
    let trace = if proper { 1.0 + 2.0 * c } else { 2.0 * c - 1.0 };
    (0..g.order())
        .find(|&x| {
            g.is_proper(x) == proper
                && g.element_order(x) == k
                && (g.element(x).trace() - trace).abs() < TOL
        })
        .map(|x| (x, k))
}

/// The axis of a rotation, or of the improper rotation `m` (the axis of the rotation `−m`).
fn principal_axis(m: &Matrix3) -> Vector3<f64> {
    if m.determinant() > 0.0 {
        rotation_axis(m)
    } else {
        rotation_axis(&(-m))
    }
}

/// The three half-turns of a `D2` or `D2h`, assigned to (z, y, x) by closeness to the
/// coordinate axes (module documentation).
fn d2_axes(g: &Group) -> Option<[usize; 3]> {
    let halves: Vec<(usize, Vector3<f64>)> = (1..g.order())
        .filter(|&x| g.is_proper(x) && g.element_order(x) == 2)
        .map(|x| (x, rotation_axis(g.element(x))))
        .collect();
    if halves.len() != 3 {
        return None;
    }
    let mut left: Vec<(usize, Vector3<f64>)> = halves;
    let mut pick = |c: usize| {
        let best = (0..left.len()).fold(0, |best, i| {
            if left[i].1[c].abs() > left[best].1[c].abs() + TOL {
                i
            } else {
                best
            }
        });
        left.remove(best).0
    };
    let z = pick(2);
    let y = pick(1);
    let x = pick(0);
    Some([z, y, x])
}

#[cfg(test)]
mod tests {
    //! Labels of point groups that no group of this crate has as a subgroup (`Oh`, `Td`, `D3h`,
    //! `D4d`, `S8`, …): each group is generated from matrices, its irreps are split off its
    //! regular representation (which contains every irrep), and the labels are compared with
    //! the standard tables' list of irreps and their column of linear functions (x, y, z): the
    //! irreps in which the defining 3-D representation decomposes.

    use super::*;
    use crate::decompose::real_irreps;
    use nalgebra::{DMatrix, Rotation3};

    fn closure(gens: &[Matrix3]) -> Vec<Matrix3> {
        let mut elements = vec![Matrix3::identity()];
        let mut next = 0;
        while next < elements.len() {
            for g in gens {
                let p = g * elements[next];
                if !elements.iter().any(|e| (e - p).amax() < 1e-9) {
                    elements.push(p);
                }
            }
            next += 1;
        }
        elements
    }

    fn rz(k: usize) -> Matrix3 {
        Rotation3::from_axis_angle(&Vector3::z_axis(), 2.0 * PI / k as f64).into_inner()
    }

    fn group(gens: &[Matrix3]) -> Group {
        let mut g = Group::from_parts("G", closure(gens), Vec::new()).unwrap();
        let n = g.order();
        let regular: Vec<DMatrix<f64>> = (0..n)
            .map(|a| DMatrix::from_fn(n, n, |i, j| f64::from(u8::from(g.mul(a, j) == i))))
            .collect();
        let raw = real_irreps(&g, [regular]).unwrap();
        g.set_irreps(named_irreps(&g, raw));
        g
    }

    /// The irreps (with multiplicity) of the defining representation `g ↦ R_g`.
    fn linear_functions(g: &Group) -> Vec<String> {
        let mut out = Vec::new();
        for r in g.irreps() {
            let c = r.kind().commutant_dim() as f64;
            let m = (0..g.order())
                .map(|x| g.element(x).trace() * r.character(x))
                .sum::<f64>()
                / g.order() as f64
                / c;
            assert!((m - m.round()).abs() < 1e-9);
            out.extend(std::iter::repeat_n(
                r.name().to_string(),
                m.round() as usize,
            ));
        }
        out
    }

    #[test]
    fn labels_of_standard_point_groups() {
        let c3 = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        let c2x = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
        let sh = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        let inv = -Matrix3::identity();
        let s = |k: usize| sh * rz(k);
        let cases: Vec<(&str, Vec<Matrix3>, &str, &str)> = vec![
            (
                "Oh",
                vec![rz(4), c3, inv],
                "A1g A2g Eg T1g T2g A1u A2u Eu T1u T2u",
                "T1u",
            ),
            ("O", vec![rz(4), c3], "A1 A2 E T1 T2", "T1"),
            ("Td", vec![s(4), c3], "A1 A2 E T1 T2", "T2"),
            ("Th", vec![rz(2), c3, inv], "Ag Eg Tg Au Eu Tu", "Tu"),
            (
                "D3h",
                vec![rz(3), c2x, sh],
                "A1' A2' E' A1'' A2'' E''",
                "E' A2''",
            ),
            ("C3h", vec![rz(3), sh], "A' E' A'' E''", "E' A''"),
            (
                "D5h",
                vec![rz(5), c2x, sh],
                "A1' A2' E1' E2' A1'' A2'' E1'' E2''",
                "E1' A2''",
            ),
            (
                "D4h",
                vec![rz(4), c2x, inv],
                "A1g A2g B1g B2g Eg A1u A2u B1u B2u Eu",
                "A2u Eu",
            ),
            (
                "D6h",
                vec![rz(6), c2x, inv],
                "A1g A2g B1g B2g E1g E2g A1u A2u B1u B2u E1u E2u",
                "A2u E1u",
            ),
            ("D2d", vec![s(4), c2x], "A1 A2 B1 B2 E", "B2 E"),
            ("D4d", vec![s(8), c2x], "A1 A2 B1 B2 E1 E2 E3", "B2 E1"),
            ("S4", vec![s(4)], "A B E", "B E"),
            ("S8", vec![s(8)], "A B E1 E2 E3", "B E1"),
            ("C4h", vec![rz(4), inv], "Ag Bg Eg Au Bu Eu", "Au Eu"),
            (
                "C6h",
                vec![rz(6), inv],
                "Ag Bg E1g E2g Au Bu E1u E2u",
                "Au E1u",
            ),
            (
                "D2h",
                vec![rz(2), c2x, inv],
                "Ag B1g B2g B3g Au B1u B2u B3u",
                "B1u B2u B3u",
            ),
            ("D6", vec![rz(6), c2x], "A1 A2 B1 B2 E1 E2", "A2 E1"),
            ("Ci", vec![inv], "Ag Au", "Au Au Au"),
            ("Cs", vec![sh], "A' A''", "A' A' A''"),
        ];
        for (name, gens, labels, vector) in cases {
            let g = group(&gens);
            let all: Vec<usize> = (0..g.order()).collect();
            assert_eq!(g.point_group(&all).name(), name);
            let ours: Vec<&str> = g.irreps().iter().map(|r| r.name()).collect();
            assert_eq!(ours.join(" "), labels, "{name}");
            let mut lin = linear_functions(&g);
            let mut want: Vec<String> = vector.split(' ').map(str::to_string).collect();
            lin.sort();
            want.sort();
            assert_eq!(lin, want, "{name}: x, y, z");
        }
        // The rotation Rz(2π/5) of D5h is named as such: E1' has χ = 2 cos 72° there.
        let d5h = group(&[rz(5), c2x, sh]);
        let r5 = d5h.find(&rz(5)).unwrap();
        let e1 = d5h.irrep("E1'").unwrap();
        assert!((e1.character(r5) - 2.0 * (2.0 * PI / 5.0).cos()).abs() < 1e-9);
    }
}
