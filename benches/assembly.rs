//! Element assembly: `model.evaluate` (residual, sparse tangent and loads) of the k = 0.1
//! balloon on the f = 16 icosphere (5120 triangles, 7686 unknowns) at its start state.
//!
//! `cargo bench --bench assembly`

use memstab::bench::{balloon_scene, solve_start};
use memstab::model::{Model, Request};
use memstab::study::mesh::MeshStudy;

fn main() {
    divan::main();
}

#[divan::bench(args = [8, 16], sample_count = 30)]
fn evaluate_all(bencher: divan::Bencher, frequency: usize) {
    let mut study = MeshStudy::build(balloon_scene(frequency).unwrap()).unwrap();
    let params = study.start.clone();
    let u = solve_start(&mut study, &params).unwrap();
    let mut eval = study.model.new_evaluation();
    bencher.bench_local(|| {
        study
            .model
            .evaluate(&u, &params, Request::ALL, &mut eval)
            .unwrap();
    });
}

#[divan::bench(args = [16], sample_count = 30)]
fn evaluate_residual_only(bencher: divan::Bencher, frequency: usize) {
    let mut study = MeshStudy::build(balloon_scene(frequency).unwrap()).unwrap();
    let params = study.start.clone();
    let u = solve_start(&mut study, &params).unwrap();
    let mut eval = study.model.new_evaluation();
    bencher.bench_local(|| {
        study
            .model
            .evaluate(&u, &params, Request::RESIDUAL, &mut eval)
            .unwrap();
    });
}
