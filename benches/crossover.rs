//! Where dense block eigenvalues stop paying: the lowest eigenvalues of every irrep block of
//! the spinning cap (`memstab::bench::SPINNING_CAP_TOML`) on a C1v mesh, at ω² = 0.3, by a
//! dense solve of each block (`BlockEigen::Dense`: every eigenvalue) against shift-invert
//! Lanczos on the block's bordered sparse factorisation (`BlockEigen::Lanczos`: the lowest
//! 10, certified by inertia), and what the cost model chooses by default
//! (`BlockEigen::ByCost`, `stability::lanczos_is_cheaper`). The C1v blocks have about 345,
//! 805 and 1 830 columns at 8, 12 and 18 divisions.
//!
//! `cargo bench --bench crossover`

use memstab::adapted::AdaptedBasis;
use memstab::bench::{solve_start, spinning_cap_scene};
use memstab::model::Model;
use memstab::stability::{BlockEigen, Detail, Stability};
use memstab::study::mesh::MeshStudy;

fn main() {
    divan::main();
}

/// The C1v cap with `divisions`, its start state at ω² = 0.3 and its adapted basis.
fn cap(divisions: usize) -> (MeshStudy, Vec<f64>, Vec<f64>, AdaptedBasis) {
    let mut study = MeshStudy::build(spinning_cap_scene("C1v", divisions, 1).unwrap()).unwrap();
    let params = vec![0.3];
    let u = solve_start(&mut study, &params).unwrap();
    let basis = AdaptedBasis::new(&study.action, study.model.layout()).unwrap();
    (study, u, params, basis)
}

fn lowest_eigenvalues(bencher: divan::Bencher, divisions: usize, method: Option<BlockEigen>) {
    let (study, u, params, basis) = cap(divisions);
    let mut stability = Stability::new(&study.model, &basis);
    if let Some(method) = method {
        stability = stability.with_block_eigen(method);
    }
    let mut eval = study.model.new_evaluation();
    let detail = Detail::Eigenvalues { lowest: 10 };
    bencher.bench_local(|| {
        stability
            .analyse(&u, &params, &study.constraints, &mut eval, None, detail)
            .unwrap()
    });
}

#[divan::bench(args = [8, 12, 18], sample_count = 5)]
fn dense(bencher: divan::Bencher, divisions: usize) {
    lowest_eigenvalues(bencher, divisions, Some(BlockEigen::Dense));
}

#[divan::bench(args = [8, 12, 18], sample_count = 5)]
fn lanczos(bencher: divan::Bencher, divisions: usize) {
    lowest_eigenvalues(bencher, divisions, Some(BlockEigen::Lanczos));
}

#[divan::bench(args = [8, 12, 18], sample_count = 5)]
fn by_cost(bencher: divan::Bencher, divisions: usize) {
    lowest_eigenvalues(bencher, divisions, None);
}
