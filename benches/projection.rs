//! The symmetry projection on the f = 16 balloon (Ih, 7686 unknowns): building the adapted
//! basis of every irrep (`AdaptedBasis::new`, once per mesh and group) and restricting one
//! tangent to every block (`restrict_tangent` of `first()` of each irrep, per matrix).
//!
//! `cargo bench --bench projection`

use memstab::adapted::AdaptedBasis;
use memstab::bench::{balloon_scene, solve_start};
use memstab::model::{Model, Request};
use memstab::study::mesh::MeshStudy;

fn main() {
    divan::main();
}

#[divan::bench(args = [8, 16], sample_count = 5)]
fn adapted_basis(bencher: divan::Bencher, frequency: usize) {
    let study = MeshStudy::build(balloon_scene(frequency).unwrap()).unwrap();
    bencher.bench_local(|| AdaptedBasis::new(&study.action, study.model.layout()).unwrap());
}

#[divan::bench(args = [8, 16], sample_count = 10)]
fn restrict_all_blocks(bencher: divan::Bencher, frequency: usize) {
    let mut study = MeshStudy::build(balloon_scene(frequency).unwrap()).unwrap();
    let params = study.start.clone();
    let u = solve_start(&mut study, &params).unwrap();
    let mut eval = study.model.new_evaluation();
    study
        .model
        .evaluate(&u, &params, Request::ALL, &mut eval)
        .unwrap();
    let basis = AdaptedBasis::new(&study.action, study.model.layout()).unwrap();
    let mut work = Vec::new();
    bencher.bench_local(|| {
        basis
            .irreps
            .iter()
            .map(|ib| {
                ib.first()
                    .restrict_tangent(study.model.layout(), &eval, &mut work)
                    .nrows()
            })
            .sum::<usize>()
    });
}
