//! Complex-type (E_k) blocks of a chiral C7 disc solved two ways: the dense Hermitian block
//! and the sparse real block R = [[A, C], [−C, A]] (its inertia halved, its lowest eigenvalues
//! by shift-invert Lanczos kept orthogonal to the partners J v) give the same eigenvalues,
//! each once, the same negative counts and eigenvectors of the same block — at loaded states
//! of the ponding disc with negative eigenvalues in E_k, on a free disc whose rigid modes
//! lie in E1, and with rank-one terms inside a complex block. (Every block Lanczos includes the real A block; the check is the complex
//! ones.)

use memstab::adapted::AdaptedBasis;
use memstab::continuation::crossings::Spectrum;
use memstab::effects::membrane::{Membrane, MooneyRivlin};
use memstab::model::{FeModel, Model};
use memstab::scene::Scene;
use memstab::stability::{BlockEigen, Detail, Stability};
use memstab::study::mesh::MeshStudy;
use meshes::generators::{disc, DiscOptions};
use nalgebra::DVector;

/// The ponding scene on a C7 disc of `divisions`.
fn ponding_c7(divisions: usize) -> MeshStudy {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/ponding.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace(
        "divisions = 16 ",
        &format!("group = \"C7\"\ndivisions = {divisions} "),
    );
    MeshStudy::build(Scene::from_toml_str(&text, "ponding C7").unwrap()).unwrap()
}

/// The analysis of (u, params) with every block dense, every block by Lanczos, and by cost.
fn three_ways(
    model: &dyn Model,
    basis: &AdaptedBasis,
    u: &[f64],
    params: &[f64],
    detail: Detail,
) -> [Spectrum; 3] {
    let mut eval = model.new_evaluation();
    [BlockEigen::Dense, BlockEigen::Lanczos, BlockEigen::ByCost].map(|method| {
        let stability = Stability::new(model, basis).with_block_eigen(method);
        let mut local = stability.new_evaluation();
        let full = stability
            .analyse(u, params, &[], &mut eval, None, detail)
            .unwrap();
        // The evaluation around the representatives gives the same analysis.
        let near = stability
            .analyse(u, params, &[], &mut local, None, detail)
            .unwrap();
        assert_eq!(full.negatives(), near.negatives(), "{method:?}");
        for (a, b) in full.blocks.iter().zip(&near.blocks) {
            for (x, y) in a.eigenvalues.iter().zip(&b.eigenvalues) {
                assert!(
                    (x - y).abs() <= 1e-10 * full.scale,
                    "{method:?}: {x} vs {y}"
                );
            }
        }
        full
    })
}

/// Dense and sparse agree block by block: the Lanczos values are the lowest dense ones (each
/// double eigenvalue once), to 1e-10 relative to max|K_ij|; the counts, sizes and rigid
/// modes are equal; every Lanczos vector x of a complex block satisfies R x = λ x for its R.
fn agree(model: &dyn Model, basis: &AdaptedBasis, u: &[f64], params: &[f64], what: &str) {
    let lowest = 6;
    let [dense, lanczos, by_cost] = three_ways(model, basis, u, params, Detail::Vectors { lowest });
    let scale = dense.scale;
    let layout = model.layout();
    let mut eval = model.new_evaluation();
    model
        .evaluate(u, params, memstab::model::Request::ALL, &mut eval)
        .unwrap();
    for ((d, l), ib) in dense.blocks.iter().zip(&lanczos.blocks).zip(&basis.irreps) {
        let name = format!("{what}, {}", d.irrep);
        assert!(d.complete, "{name}: dense is complete");
        assert_eq!(d.size, l.size, "{name}");
        assert_eq!(d.negative, l.negative, "{name}");
        assert_eq!(d.rigid_modes, l.rigid_modes, "{name}");
        assert!(l.eigen_error.is_none(), "{name}: {:?}", l.eigen_error);
        assert!(l.eigenvalues.len() >= lowest.max(l.negative + 1), "{name}");
        for (a, b) in d.eigenvalues.iter().zip(&l.eigenvalues) {
            assert!(
                (a - b).abs() <= 1e-10 * scale,
                "{name}: dense {a} vs Lanczos {b}"
            );
        }
        if ib.complex {
            // The sparse path ran (its lowest values, not a dense fallback's whole spectrum).
            assert!(!l.complete, "{name}: solved by Lanczos");
            assert_eq!(2 * l.size, l.vectors.nrows(), "{name}: real coordinates");
            let r = ib.first().restrict_tangent(layout, &eval, &mut Vec::new());
            // (With rigid modes the vectors are those of R on their complement.)
            let checked = if l.rigid_modes == 0 {
                l.vectors.ncols()
            } else {
                0
            };
            for (k, lam) in l.eigenvalues.iter().enumerate().take(checked) {
                let x: DVector<f64> = l.vectors.column(k).into_owned();
                let res = (&r * &x - &x * *lam).amax() / x.amax();
                assert!(res <= 1e-8 * scale, "{name}: vector {k} residual {res:e}");
            }
        }
    }
    assert_eq!(dense.index, lanczos.index, "{what}");
    assert_eq!(dense.negatives(), by_cost.negatives(), "{what}");
    // The inertia alone gives the same counts.
    let [d0, l0, _] = three_ways(model, basis, u, params, Detail::Inertia);
    assert_eq!(d0.negatives(), dense.negatives(), "{what}");
    assert_eq!(l0.negatives(), dense.negatives(), "{what}");
}

/// The ponding disc on C7 at densities below the first rung, between rungs and past several
/// E_k rungs (E1 twice, E2, E3 twice negative at ρ = 22).
#[test]
fn chiral_sparse_and_dense_blocks_agree_at_loaded_states() {
    let mut study = ponding_c7(10);
    let basis = AdaptedBasis::new(&study.action, study.model.layout()).unwrap();
    assert!(basis.irreps.iter().any(|b| b.complex));
    let u = memstab::bench::solve_start(&mut study, &[0.0]).unwrap();
    let mut seen_negative_e = false;
    for rho in [1.0, 7.0, 22.0] {
        agree(&study.model, &basis, &u, &[rho], &format!("rho = {rho}"));
        let [dense, ..] = three_ways(
            &study.model,
            &basis,
            &u,
            &[rho],
            Detail::Eigenvalues { lowest: 4 },
        );
        seen_negative_e |= dense
            .blocks
            .iter()
            .zip(&basis.irreps)
            .any(|(b, ib)| ib.complex && b.negative > 1);
    }
    assert!(seen_negative_e, "a state with negative E_k eigenvalues");
}

/// A free prestretched C7 disc (membrane only): its rigid modes lie in A (t_z, r_z) and E1
/// (t_x, t_y, r_x, r_y: two complex modes), deflated alike by the dense and the sparse
/// complex blocks.
#[test]
fn chiral_free_disc_deflates_rigid_modes_in_e1_alike() {
    let sym = disc(&DiscOptions {
        radius: 1.0,
        sectors: 7,
        divisions: 8,
        group: Some("C7".into()),
    })
    .unwrap();
    let m = &sym.mesh;
    let membrane = Membrane::new(
        &m.nodes,
        &m.triangles,
        MooneyRivlin::new(1.0, 0.2, 1.0),
        1.1,
    )
    .unwrap();
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![Box::new(membrane)],
        vec![],
    );
    let basis = AdaptedBasis::new(&sym.action, model.layout()).unwrap();
    let u = vec![0.0; model.layout().unknowns()];
    agree(&model, &basis, &u, &[], "free disc");
    let [dense, lanczos, _] =
        three_ways(&model, &basis, &u, &[], Detail::Eigenvalues { lowest: 4 });
    let e1 = basis.irreps.iter().position(|b| b.name == "E1").unwrap();
    assert_eq!(dense.blocks[e1].rigid_modes, 2);
    assert_eq!(lanczos.blocks[e1].rigid_modes, 2);
}

/// Rank-one terms in a complex block: an invariant potential on the E1 radial fields of the
/// C5 icosphere (vertex down, viewed as C5; docs/theory.md §14.6) hands its z-terms to the
/// solver as rank-one terms c a aᵀ with a in E1's isotypic component, which the sparse
/// complex block borders by a and J a (each with E = −2/c). At three values of λ the dense
/// and the sparse complex blocks agree (a border of a alone, E = −1/c, fails this).
#[test]
fn chiral_blocks_agree_with_rank_one_terms_in_them() {
    use memstab::effects::invariant::IrrepPotential;
    use meshes::generators::{icosphere_oriented, Down, IcosphereOptions};
    let sym = icosphere_oriented(
        &IcosphereOptions {
            radius: 1.0,
            frequency: 2,
        },
        Down::Vertex,
    )
    .unwrap();
    let m = &sym.mesh;
    let c5 = meshes::GroupAction::compute(m, symmetry::Group::by_name("C5").unwrap()).unwrap();
    let membrane = Membrane::new(
        &m.nodes,
        &m.triangles,
        MooneyRivlin::new(1.0, 0.2, 1.0),
        1.1,
    )
    .unwrap();
    let potential = IrrepPotential::new(&c5, &m.nodes, "E1", 0, [0.3, 0.2, 0.5]).unwrap();
    let model = FeModel::new(
        m.nodes.clone(),
        m.triangles.clone(),
        &[],
        vec![Box::new(membrane), Box::new(potential)],
        vec!["lambda".into()],
    );
    let basis = AdaptedBasis::new(&c5, model.layout()).unwrap();
    let e1 = basis.irreps.iter().position(|b| b.name == "E1").unwrap();
    assert!(basis.irreps[e1].complex);
    let u = vec![0.0; model.layout().unknowns()];
    let mut eval = model.new_evaluation();
    for lambda in [0.5, 1.0, 1.8] {
        model
            .evaluate(&u, &[lambda], memstab::model::Request::ALL, &mut eval)
            .unwrap();
        assert!(!eval.rank_one.is_empty(), "no rank-one terms at {lambda}");
        agree(&model, &basis, &u, &[lambda], &format!("lambda = {lambda}"));
    }
}
