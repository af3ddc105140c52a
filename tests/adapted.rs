//! Symmetry-adapted bases: block sizes from the character formula, orthonormality and
//! completeness, and a tangent at a symmetric state that is block diagonal with identical
//! partner blocks, its spectrum the union of the blocks' with multiplicity d_μ.

use memstab::adapted::{hermitian, AdaptedBasis, SparseBasis};
use memstab::effects::gas::GasPressure;
use memstab::effects::hydrostatic::{Fluid, FluidSide};
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::effects::Quantity;
use memstab::linalg::hermitian::hermitian_eigen;
use memstab::model::{Effect, FeModel, Model, Request};
use meshes::generators::{
    disc, icosphere, icosphere_oriented, truncated_sphere, DiscOptions, Down, IcosphereOptions,
    TruncatedSphereOptions,
};
use meshes::{GroupAction, SymmetricMesh};
use nalgebra::{DMatrix, DVector};
use symmetry::Invariant;

fn dense(b: &SparseBasis) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(b.unknowns(), b.dim());
    for (j, col) in b.columns().iter().enumerate() {
        for &(d, v) in col {
            m[(d, j)] = v;
        }
    }
    m
}

/// A model of the mesh with a membrane and a load that keeps `action`'s group.
fn model(sym: &SymmetricMesh, fixed: &[usize], fluid: bool) -> FeModel {
    let m = &sym.mesh;
    let membrane = Membrane::new(
        &m.nodes,
        &m.triangles,
        MooneyRivlin::new(1.0, 0.2, 1.0),
        1.1,
    )
    .unwrap();
    let load: Box<dyn Effect> = if fluid {
        Box::new(Fluid {
            filled: false,
            closing: None,
            density: Quantity::Value(1.0),
            gravity: Quantity::Value(1.0),
            level: Quantity::Value(0.2),
            side: if fixed.is_empty() {
                FluidSide::Behind
            } else {
                FluidSide::Front
            },
        })
    } else {
        Box::new(GasPressure {
            closing: None,
            pressure: Quantity::Value(0.3),
        })
    };
    FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        fixed,
        vec![Box::new(membrane), load],
        vec![],
    )
}

fn check(name: &str, action: &GroupAction, model: &FeModel) {
    let layout = model.layout();
    let n = layout.unknowns();
    let basis = AdaptedBasis::new(action, layout).unwrap_or_else(|e| panic!("{name}: {e}"));
    // Sizes: Σ_μ d_μ m_μ = N, each from the character formula (checked inside `new`).
    let total: usize = basis.irreps.iter().map(|b| b.dim * b.multiplicity).sum();
    assert_eq!(total, n, "{name}: blocks do not cover the unknowns");
    // All columns together: an orthonormal basis of R^N.
    let all: Vec<DMatrix<f64>> = basis
        .irreps
        .iter()
        .flat_map(|b| b.partners(layout).iter().map(dense).collect::<Vec<_>>())
        .collect();
    let q = DMatrix::from_columns(
        &all.iter()
            .flat_map(|m| m.column_iter().map(|c| c.into_owned()))
            .collect::<Vec<DVector<f64>>>(),
    );
    let orth = (q.transpose() * &q - DMatrix::identity(n, n)).amax();
    assert!(orth < 1e-12, "{name}: columns not orthonormal ({orth:e})");
    // A symmetric state: a random combination of the fixed-point columns.
    let fixed_point = &basis.irreps[0].first();
    let qa = DVector::from_fn(fixed_point.dim(), |i, _| 0.02 * ((i as f64 * 0.7).sin()));
    let mut u = vec![0.0; n];
    fixed_point.expand(&qa, &mut u);
    let mut eval = model.new_evaluation();
    model.evaluate(&u, &[], Request::ALL, &mut eval).unwrap();
    // Rigid motions restricted from the orbit representatives equal the explicit restriction.
    let x = model.positions(&u, &[]);
    for k in 0..6 {
        let mut motion = [0.0; 6];
        motion[k] = 1.0;
        let field = &model.rigid_modes(&[motion], &x)[0];
        for b in &basis.irreps {
            let fast = b.first().restrict_rigid(&motion, &x, layout);
            let slow = b.first().restrict(field);
            assert!(
                (&fast - &slow).amax() < 1e-12 * slow.amax().max(1.0),
                "{name}: rigid motion {k} in {}",
                b.name
            );
        }
    }
    let k = model.pattern().to_dense(&eval.tangent);
    let k = DMatrix::from_fn(n, n, |i, j| k[(i, j)]);
    let kt = q.transpose() * &k * &q;
    let scale = k.amax();
    // Block diagonal: everything outside the (μ, a) diagonal blocks is round-off.
    let mut offset = 0;
    let mut spans = Vec::new();
    for b in &basis.irreps {
        // A complex-type irrep's one basis spans its whole isotypic component.
        let (copies, size) = if b.complex {
            (1, 2 * b.multiplicity)
        } else {
            (b.dim, b.multiplicity)
        };
        for _ in 0..copies {
            spans.push((offset, size));
            offset += size;
        }
    }
    let mut off = kt.clone();
    for &(o, m) in &spans {
        off.view_mut((o, o), (m, m)).fill(0.0);
    }
    assert!(
        off.amax() < 1e-12 * scale,
        "{name}: off-block residual {:e}",
        off.amax() / scale
    );
    // Partner blocks equal the first one.
    let mut o = 0;
    let mut work = Vec::new();
    for b in &basis.irreps {
        let k0 = b.first().restrict_tangent(layout, &eval, &mut work);
        if b.complex {
            // [[A, C], [−C, A]]: the J structure of a complex-type block.
            let m = b.multiplicity;
            let (a, c) = (k0.view((0, 0), (m, m)), k0.view((0, m), (m, m)));
            assert!(
                (k0.view((m, m), (m, m)) - a).amax() < 1e-12 * scale,
                "{name}: {}",
                b.name
            );
            assert!(
                (k0.view((m, 0), (m, m)) + c).amax() < 1e-12 * scale,
                "{name}: {}",
                b.name
            );
            assert!(
                (c + c.transpose()).amax() < 1e-12 * scale,
                "{name}: {}",
                b.name
            );
            // The orbit-local R (from K's columns at the representatives) is the explicit
            // column-by-column Bᵀ K B, and its sparse form the same matrix without the
            // rank-one terms.
            let slow = b
                .first()
                .restrict_tangent_to(b.first(), layout, &eval, &mut work);
            let slow = (&slow + slow.transpose()) * 0.5;
            assert!(
                (&k0 - &slow).amax() < 1e-12 * scale,
                "{name}: orbit-local {} differs from the explicit block by {:e}",
                b.name,
                (&k0 - &slow).amax() / scale
            );
            let (pattern, values) = b
                .first()
                .restrict_tangent_sparse(layout, &eval)
                .expect("a complex-type block has an orbit-local form");
            let sparse = pattern.to_dense(&values);
            let mut rank_one = DMatrix::zeros(2 * m, 2 * m);
            for (cr, av) in &eval.rank_one {
                let ar = b.first().restrict(av);
                rank_one += &ar * ar.transpose() * *cr;
            }
            let sparse = DMatrix::from_fn(2 * m, 2 * m, |i, j| sparse[(i, j)]) + rank_one;
            assert!(
                (&k0 - &sparse).amax() < 1e-12 * scale,
                "{name}: sparse {} differs from the dense block by {:e}",
                b.name,
                (&k0 - &sparse).amax() / scale
            );
            o += 2 * m;
            continue;
        }
        // The sparse block (its triangles computed on and below the diagonal of orbits and
        // mirrored) is the dense one without the rank-one terms.
        let m = b.multiplicity;
        let (pattern, values) = b
            .first()
            .restrict_tangent_sparse(layout, &eval)
            .expect("a block built from the action has an orbit-local form");
        let sparse = pattern.to_dense(&values);
        let mut sparse = DMatrix::from_fn(m, m, |i, j| sparse[(i, j)]);
        for (cr, av) in &eval.rank_one {
            let ar = b.first().restrict(av);
            sparse += &ar * ar.transpose() * *cr;
        }
        assert!(
            (&k0 - &sparse).amax() < 1e-12 * scale,
            "{name}: sparse {} differs from the dense block by {:e}",
            b.name,
            (&k0 - &sparse).amax() / scale
        );
        assert!(
            (&sparse - sparse.transpose()).amax() == 0.0,
            "{name}: sparse {} is not symmetric",
            b.name
        );
        for a in 0..b.dim {
            let ka = kt.view(
                (o + a * b.multiplicity, o + a * b.multiplicity),
                (b.multiplicity, b.multiplicity),
            );
            assert!(
                (ka - &k0).amax() < 1e-12 * scale,
                "{name}: partner {a} of {} differs",
                b.name
            );
        }
        o += b.dim * b.multiplicity;
    }
    // Spectrum of K = union of the blocks' spectra with multiplicity d_μ.
    let mut from_blocks: Vec<f64> = basis
        .irreps
        .iter()
        .filter(|b| b.multiplicity > 0)
        .flat_map(|b| {
            let k0 = b.first().restrict_tangent(layout, &eval, &mut Vec::new());
            // A complex-type block: the m eigenvalues of the Hermitian block, each d = 2 times.
            let ev: Vec<f64> = if b.complex {
                hermitian_eigen(&hermitian(&k0), false).0
            } else {
                k0.symmetric_eigenvalues().iter().copied().collect()
            };
            std::iter::repeat_n(ev, b.dim).flatten().collect::<Vec<_>>()
        })
        .collect();
    let mut full: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
    from_blocks.sort_by(f64::total_cmp);
    full.sort_by(f64::total_cmp);
    let diff = from_blocks
        .iter()
        .zip(&full)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-10 * scale, "{name}: spectra differ by {diff:e}");
}

#[test]
fn discs_of_every_symmetry() {
    for (sectors, divisions, group) in [
        (7, 3, None),
        (8, 3, None),
        (8, 3, Some("C2v")),
        (6, 3, Some("C1v")),
        (6, 3, Some("C3v")),
        // The trivial group: its one block is the identity basis, K as assembled.
        (6, 3, Some("C1")),
    ] {
        let sym = disc(&DiscOptions {
            radius: 1.0,
            sectors,
            divisions,
            group: group.map(String::from),
        })
        .unwrap();
        let fixed = sym.mesh.boundaries["rim"].clone();
        let model = model(&sym, &fixed, true);
        check(
            &format!("disc {:?}", sym.group().name()),
            &sym.action,
            &model,
        );
    }
}

#[test]
fn icospheres_in_ih_and_resting_on_a_vertex() {
    let sym = icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 2,
    })
    .unwrap();
    check("icosphere Ih", &sym.action, &model(&sym, &[], false));
    for down in [Down::Vertex, Down::Face, Down::Edge] {
        let sym = icosphere_oriented(
            &IcosphereOptions {
                radius: 1.0,
                frequency: 2,
            },
            down,
        )
        .unwrap();
        let action = sym
            .action
            .restrict(&[Invariant::Direction(-nalgebra::Vector3::z())])
            .unwrap();
        check(
            &format!("icosphere {:?} down, {}", down, action.group().name()),
            &action,
            &model(&sym, &[], true),
        );
    }
}

#[test]
fn truncated_spheres() {
    for pattern in ["C8v", "C2v", "C1v"] {
        let sym = truncated_sphere(&TruncatedSphereOptions {
            divisions: 3,
            ..TruncatedSphereOptions::for_pattern(pattern)
        })
        .unwrap();
        let fixed = sym.mesh.boundaries["cut"].clone();
        check(
            &format!("truncated sphere {pattern}"),
            &sym.action,
            &model(&sym, &fixed, true),
        );
    }
}

/// The chiral discs (C7, and C4 on eight sectors): complex-type E_k blocks that cover the
/// unknowns with the rest, orthonormal, block diagonal with the J structure, and the spectrum
/// of K the union of the Hermitian blocks' with multiplicity 2.
#[test]
fn chiral_discs_have_hermitian_blocks() {
    for (sectors, group) in [(7, "C7"), (8, "C4")] {
        let sym = disc(&DiscOptions {
            radius: 1.0,
            sectors,
            divisions: 3,
            group: Some(group.into()),
        })
        .unwrap();
        let fixed = sym.mesh.boundaries["rim"].clone();
        let model = model(&sym, &fixed, true);
        let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
        assert!(basis.irreps.iter().any(|b| b.complex), "{group}");
        check(&format!("chiral disc {group}"), &sym.action, &model);
    }
}

/// On a C7v disc viewed as C7, the Hermitian block of E_k has exactly the spectrum of the
/// C7v E_k block, and C7's A block the union of A1's and A2's: with the rim fixed, and with
/// it sliding in its plane z = 0 (the candidates of a complex block projected onto the plane,
/// as a real block's are).
#[test]
fn c7_blocks_of_a_c7v_mesh_are_the_c7v_blocks() {
    let sym = disc(&DiscOptions {
        radius: 1.0,
        sectors: 7,
        divisions: 4,
        group: None,
    })
    .unwrap();
    let rim = sym.mesh.boundaries["rim"].clone();
    let sliding: Vec<(usize, memstab::model::Vec3)> = rim
        .iter()
        .map(|&i| (i, memstab::model::Vec3::z()))
        .collect();
    c7_blocks_are_the_c7v_blocks(&sym, &model(&sym, &rim, true));
    c7_blocks_are_the_c7v_blocks(&sym, &model(&sym, &[], true).with_sliding(&sliding));
}

fn c7_blocks_are_the_c7v_blocks(sym: &SymmetricMesh, model: &FeModel) {
    let layout = model.layout();
    let c7 = GroupAction::compute(&sym.mesh, symmetry::Group::by_name("C7").unwrap()).unwrap();
    let full = AdaptedBasis::new(&sym.action, layout).unwrap();
    let sub = AdaptedBasis::new(&c7, layout).unwrap();
    // A symmetric (C7v) state that is not flat.
    let fp = full.irreps[0].first();
    let qa = DVector::from_fn(fp.dim(), |i, _| 0.02 * ((i as f64 * 0.7).sin()));
    let mut u = vec![0.0; layout.unknowns()];
    fp.expand(&qa, &mut u);
    let mut eval = model.new_evaluation();
    model.evaluate(&u, &[], Request::ALL, &mut eval).unwrap();
    let scale = eval.tangent.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let spectrum = |b: &memstab::adapted::IrrepBasis| -> Vec<f64> {
        let k = b.first().restrict_tangent(layout, &eval, &mut Vec::new());
        let mut v: Vec<f64> = if b.complex {
            hermitian_eigen(&hermitian(&k), false).0
        } else {
            k.symmetric_eigenvalues().iter().copied().collect()
        };
        v.sort_by(f64::total_cmp);
        v
    };
    let of = |basis: &AdaptedBasis, names: &[&str]| -> Vec<f64> {
        let mut v: Vec<f64> = basis
            .irreps
            .iter()
            .filter(|b| names.contains(&b.name.as_str()))
            .flat_map(spectrum)
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let names: Vec<String> = sub.irreps.iter().map(|b| b.name.clone()).collect();
    assert_eq!(names, ["A", "E1", "E2", "E3"]);
    for (c7_irrep, c7v_irreps) in [
        ("A", &["A1", "A2"][..]),
        ("E1", &["E1"][..]),
        ("E2", &["E2"][..]),
        ("E3", &["E3"][..]),
    ] {
        let (x, y) = (of(&sub, &[c7_irrep]), of(&full, c7v_irreps));
        assert_eq!(x.len(), y.len(), "{c7_irrep}");
        assert!(!x.is_empty());
        let diff = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            diff < 1e-11 * scale,
            "{c7_irrep}: spectra differ by {diff:e}"
        );
    }
}
