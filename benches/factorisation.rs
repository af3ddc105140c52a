//! One sparse factorisation: `SymmetricFactorization::factorize` (numeric LBLᵀ, the symbolic
//! analysis done once outside the loop) of the full tangent K − σI of the f = 16 balloon at
//! its start state (7686 unknowns). The small negative shift σ = −1e-3 max|K_ij| keeps the
//! six rigid-body modes of the free sphere from making K singular.
//!
//! `cargo bench --bench factorisation`

use memstab::bench::{balloon_scene, solve_start};
use memstab::linalg::SymmetricFactorization;
use memstab::model::{Model, Request};
use memstab::study::mesh::MeshStudy;

fn main() {
    divan::main();
}

fn shifted_tangent(frequency: usize) -> (MeshStudy, Vec<f64>) {
    let mut study = MeshStudy::build(balloon_scene(frequency).unwrap()).unwrap();
    let params = study.start.clone();
    let u = solve_start(&mut study, &params).unwrap();
    let mut eval = study.model.new_evaluation();
    study
        .model
        .evaluate(&u, &params, Request::ALL, &mut eval)
        .unwrap();
    let pattern = study.model.pattern();
    let scale = eval.tangent.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut values = eval.tangent.clone();
    for i in 0..pattern.n() {
        values[pattern.position(i, i).unwrap()] += 1e-3 * scale;
    }
    (study, values)
}

#[divan::bench(args = [8, 16], sample_count = 20)]
fn factorize(bencher: divan::Bencher, frequency: usize) {
    let (study, values) = shifted_tangent(frequency);
    let mut f = SymmetricFactorization::new(study.model.pattern()).unwrap();
    bencher.bench_local(|| f.factorize(&values).unwrap());
}

#[divan::bench(args = [16], sample_count = 5)]
fn symbolic_and_factorize(bencher: divan::Bencher, frequency: usize) {
    let (study, values) = shifted_tangent(frequency);
    bencher.bench_local(|| {
        let mut f = SymmetricFactorization::new(study.model.pattern()).unwrap();
        f.factorize(&values).unwrap();
        f
    });
}
