//! Fourier modes about z and the irreps of an axial group (docs/theory.md §12.1).
//!
//! At wave number m a displacement field of a body of revolution is a combination of the
//! cos-type field (a cos mθ, b sin mθ, c cos mθ) in cylindrical components (u_r, u_θ, u_z) and
//! its partner, the sin-type field (a sin mθ, −b cos mθ, c sin mθ) (for m = 0: the
//! axisymmetric field and the twist u_θ(r)). An element that keeps the z-axis pointwise (a
//! rotation by φ about z, or a vertical mirror) acts on this pair by Rot(mφ) or by a
//! reflection (trace 0); its character is 2 cos(mφ) or 0. Decomposing that 2-D representation
//! by characters names the irreps a continuum mode of wave number m falls into.

use crate::group::Group;

impl Group {
    /// The irreps (name, multiplicity) that the pair of Fourier modes of wave number `m` about
    /// z spans in this group: for `C_nv`, A1 + A2 when m ≡ 0 (mod n), B1 + B2 when
    /// m ≡ n/2, else E_k with k ≡ ±m; for `C_n` the same with A, B (twice) and the complex-type
    /// E_k. `None` if an element does not keep the z-axis pointwise (not an axial group about z
    /// of rotations and vertical mirrors).
    pub fn fourier_irreps(&self, m: usize) -> Option<Vec<(String, usize)>> {
        let chi: Vec<f64> = self
            .elements()
            .iter()
            .map(|r| {
                let keeps_z = (r[(2, 2)] - 1.0).abs() < 1e-9
                    && r[(0, 2)].abs() < 1e-9
                    && r[(1, 2)].abs() < 1e-9;
                if !keeps_z {
                    return None;
                }
                let det = r[(0, 0)] * r[(1, 1)] - r[(0, 1)] * r[(1, 0)];
                Some(if det > 0.0 {
                    2.0 * (m as f64 * r[(1, 0)].atan2(r[(0, 0)])).cos()
                } else {
                    0.0
                })
            })
            .collect::<Option<_>>()?;
        let order = self.order() as f64;
        Some(
            self.irreps()
                .iter()
                .filter_map(|irrep| {
                    let dot = |a: &dyn Fn(usize) -> f64| {
                        (0..self.order())
                            .map(|g| a(g) * irrep.character(g))
                            .sum::<f64>()
                            / order
                    };
                    let n = dot(&|g| chi[g]) / dot(&|g| irrep.character(g));
                    let n = n.round() as usize;
                    (n > 0).then(|| (irrep.name().to_string(), n))
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use crate::Group;

    fn names(g: &Group, m: usize) -> Vec<(String, usize)> {
        g.fourier_irreps(m).expect("an axial group")
    }

    fn list(items: &[(&str, usize)]) -> Vec<(String, usize)> {
        items.iter().map(|(n, k)| (n.to_string(), *k)).collect()
    }

    /// The table of docs/theory.md §12.1, and its chiral counterparts.
    #[test]
    fn fourier_modes_fall_into_the_tabulated_irreps() {
        let c7v = Group::by_name("C7v").unwrap();
        assert_eq!(names(&c7v, 0), list(&[("A1", 1), ("A2", 1)]));
        assert_eq!(names(&c7v, 7), list(&[("A1", 1), ("A2", 1)]));
        for (m, k) in [
            (1, 1),
            (6, 1),
            (2, 2),
            (5, 2),
            (3, 3),
            (4, 3),
            (8, 1),
            (13, 1),
        ] {
            assert_eq!(names(&c7v, m), list(&[(&format!("E{k}"), 1)]), "m = {m}");
        }
        let c8v = Group::by_name("C8v").unwrap();
        assert_eq!(names(&c8v, 4), list(&[("B1", 1), ("B2", 1)]));
        assert_eq!(names(&c8v, 3), list(&[("E3", 1)]));
        let c2v = Group::by_name("C2v").unwrap();
        assert_eq!(names(&c2v, 1), list(&[("B1", 1), ("B2", 1)]));
        assert_eq!(names(&c2v, 2), list(&[("A1", 1), ("A2", 1)]));
        let c1v = Group::by_name("C1v").unwrap();
        assert_eq!(names(&c1v, 3), list(&[("A1", 1), ("A2", 1)]));
        let c7 = Group::by_name("C7").unwrap();
        assert_eq!(names(&c7, 7), list(&[("A", 2)]));
        assert_eq!(names(&c7, 4), list(&[("E3", 1)]));
        let c8 = Group::by_name("C8").unwrap();
        assert_eq!(names(&c8, 4), list(&[("B", 2)]));
        assert_eq!(names(&c8, 0), list(&[("A", 2)]));
        assert!(Group::by_name("Ih").unwrap().fourier_irreps(1).is_none());
    }
}
