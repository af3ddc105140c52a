//! The assembly of several effects (summed per triangle, then scattered once in parallel
//! ranges) against a plain dense scatter of every effect's terms, one effect at a time: with
//! load slots (one parameter named twice), a node effect between triangle effects, moving
//! held coordinates, a subset, and buffers reused across requests.

use super::*;
use crate::model::{Effect, FeModel, Model};
use symmetry::Invariant;

/// Made-up terms of triangle `t` at `x` (the scatter does not care whether they are
/// derivatives of one another): distinct, position-dependent, with a symmetric Hessian.
fn tri_terms(seed: f64, t: usize, x: &[Vec3; 3], p: &[f64]) -> TriangleTerms {
    let w = |i: usize| (seed * (1.0 + i as f64) + 0.37 * t as f64).sin();
    let s: f64 = x.iter().map(|v| v.x + 2.0 * v.y - v.z).sum();
    let mut terms = TriangleTerms::default();
    terms.local.value = p[0] * w(100) * s;
    for a in 0..9 {
        terms.local.grad[a] = p[1] * w(a) * (1.0 + s * s);
        for b in 0..9 {
            terms.local.hess[a][b] = p[0] * w(10 + a.min(b) * 9 + a.max(b)) + s;
        }
        for (l, load) in terms.loads.iter_mut().enumerate() {
            load[a] = w(200 + 9 * l + a) * s;
        }
    }
    terms
}

fn node_terms(i: usize, x: &Vec3, p: &[f64]) -> NodeTerms {
    let w = |k: usize| (0.7 * (1.0 + k as f64) + 0.29 * i as f64).cos();
    let mut terms = NodeTerms {
        value: p[2] * x.norm(),
        ..NodeTerms::default()
    };
    for a in 0..3 {
        terms.grad[a] = w(a) * x[a];
        terms.loads[0][a] = w(3 + a);
        for b in 0..3 {
            terms.hess[a][b] = p[1] * w(6 + a.min(b) * 3 + a.max(b)) + x.z;
        }
    }
    terms
}

/// A triangle effect with the made-up terms of `seed` and the load slots `loads`.
struct TriEffect {
    seed: f64,
    loads: [Option<usize>; 3],
}

/// A node effect whose one load slot names parameter 1.
struct NodeEffect;

impl Effect for TriEffect {
    fn name(&self) -> &str {
        "triangles"
    }
    fn keeps(&self) -> Vec<Invariant> {
        Vec::new()
    }
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        Vec::new()
    }
    fn assemble(&self, x: &[Vec3], p: &[f64], out: &mut Assembler<'_>) -> Result<(), ModelError> {
        out.add_triangles(x, self.loads, |t, xt, terms| {
            *terms = tri_terms(self.seed, t, xt, p);
            Ok(())
        })
    }
}

impl Effect for NodeEffect {
    fn name(&self) -> &str {
        "nodes"
    }
    fn keeps(&self) -> Vec<Invariant> {
        Vec::new()
    }
    fn rigid_motions(&self) -> Vec<[f64; 6]> {
        Vec::new()
    }
    fn assemble(&self, x: &[Vec3], p: &[f64], out: &mut Assembler<'_>) -> Result<(), ModelError> {
        out.add_nodes(x, [Some(1)], |i, xi, terms| {
            *terms = node_terms(i, xi, p);
            Ok(())
        })
    }
}

const SEEDS: [(f64, [Option<usize>; 3]); 2] = [
    (0.3, [Some(0), Some(1), Some(0)]),
    (1.1, [None, Some(2), None]),
];

/// A bumpy 6 × 6 grid of nodes (two triangles per cell), nodes 0..6 fixed and two sliding.
fn model() -> FeModel {
    let n = 6;
    let reference = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f64, (k / n) as f64);
            Vec3::new(1.0 + i, 1.0 + j, 0.1 * (i * j).sin())
        })
        .collect();
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let k = j * n + i;
            triangles.push([k, k + 1, k + n + 1]);
            triangles.push([k, k + n + 1, k + n]);
        }
    }
    let effects: Vec<Box<dyn Effect>> = vec![
        Box::new(TriEffect {
            seed: SEEDS[0].0,
            loads: SEEDS[0].1,
        }),
        Box::new(NodeEffect),
        Box::new(TriEffect {
            seed: SEEDS[1].0,
            loads: SEEDS[1].1,
        }),
    ];
    let names = ["a", "b", "radius"].map(String::from).to_vec();
    let fixed: Vec<usize> = (0..n).collect();
    FeModel::new(reference, triangles, &fixed, effects, names)
        .with_sliding(&[(n * n - 1, Vec3::z()), (n * n - 2, Vec3::z())])
        .with_scaled_holding(2, 1.5)
}

/// Π, F, dense K and the loads by a plain scatter of one effect at a time.
struct Dense {
    energy: f64,
    residual: Vec<f64>,
    tangent: Vec<Vec<f64>>,
    loads: Vec<Vec<f64>>,
}

fn dense(model: &FeModel, u: &[f64], p: &[f64]) -> Dense {
    let layout = model.layout();
    let n = layout.unknowns();
    let x = model.positions(u, p);
    let mut d = Dense {
        energy: 0.0,
        residual: vec![0.0; n],
        tangent: vec![vec![0.0; n]; n],
        loads: vec![vec![0.0; n]; p.len()],
    };
    let dof = |i: usize, k: usize| layout.dof(i, k);
    // The rate of every node along the held motion (a finite difference is exact: linear).
    let mut q = p.to_vec();
    q[2] += 1.0;
    let rate: Vec<Vec3> = model
        .positions(u, &q)
        .iter()
        .zip(&x)
        .map(|(a, b)| a - b)
        .collect();
    for (seed, slots) in SEEDS {
        for (t, tri) in layout.triangles().iter().enumerate() {
            let terms = tri_terms(seed, t, &[x[tri[0]], x[tri[1]], x[tri[2]]], p);
            d.energy += terms.local.value;
            for a in 0..9 {
                let Some(r) = dof(tri[a / 3], a % 3) else {
                    continue;
                };
                d.residual[r] += terms.local.grad[a];
                for (s, par) in slots.iter().enumerate() {
                    if let Some(par) = par {
                        d.loads[*par][r] += terms.loads[s][a];
                    }
                }
                for b in 0..9 {
                    let h = terms.local.hess[a][b];
                    d.loads[2][r] += h * rate[tri[b / 3]][b % 3];
                    if let Some(c) = dof(tri[b / 3], b % 3) {
                        d.tangent[r][c] += h;
                    }
                }
            }
        }
    }
    for (i, xi) in x.iter().enumerate() {
        let terms = node_terms(i, xi, p);
        d.energy += terms.value;
        for a in 0..3 {
            let Some(r) = dof(i, a) else { continue };
            d.residual[r] += terms.grad[a];
            d.loads[1][r] += terms.loads[0][a];
            for (b, h) in terms.hess[a].iter().enumerate() {
                d.loads[2][r] += h * rate[i][b];
                d.tangent[r][dof(i, b).expect("a free node")] += h;
            }
        }
    }
    d
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
}

/// Compares `e` with the dense scatter at the unknowns `rows` (F, loads, K's columns).
fn compare(model: &FeModel, e: &Evaluation, d: &Dense, rows: &[usize], whole: bool) {
    let k = model.pattern().to_dense(&e.tangent);
    if whole {
        assert!(close(e.energy, d.energy), "{} vs {}", e.energy, d.energy);
    }
    for &r in rows {
        assert!(close(e.residual[r], d.residual[r]), "residual {r}");
        for (p, (l, m)) in e.loads.iter().zip(&d.loads).enumerate() {
            assert!(close(l[r], m[r]), "load {p} at {r}: {} vs {}", l[r], m[r]);
        }
        for c in 0..model.unknowns() {
            assert!(close(k[(c, r)], d.tangent[c][r]), "K[{c}, {r}]");
        }
    }
}

#[test]
fn fused_parallel_scatter_equals_a_plain_scatter_of_every_effect() {
    let model = model();
    let n = model.unknowns();
    let all: Vec<usize> = (0..n).collect();
    let u: Vec<f64> = (0..n).map(|i| 0.01 * (i as f64).sin()).collect();
    let (p1, p2) = ([1.3, 0.7, 1.6], [0.9, 1.4, 1.2]);
    let (d1, d2) = (dense(&model, &u, &p1), dense(&model, &u, &p2));
    let mut e = model.new_evaluation();
    model.evaluate(&u, &p1, Request::ALL, &mut e).unwrap();
    compare(&model, &e, &d1, &all, true);
    // Reused: a residual request, then everything at other parameters.
    model.evaluate(&u, &p1, Request::RESIDUAL, &mut e).unwrap();
    assert!(e
        .residual
        .iter()
        .zip(&d1.residual)
        .all(|(a, b)| close(*a, *b)));
    model.evaluate(&u, &p2, Request::ALL, &mut e).unwrap();
    compare(&model, &e, &d2, &all, true);

    // A subset: exact at its nodes' unknowns, untouched zeros elsewhere in K.
    let nodes = [7, 8, 20, 35];
    let subset = std::sync::Arc::new(Subset::around(model.layout(), &nodes));
    let mut s = model.new_evaluation().restricted_to(subset);
    for (p, d) in [(&p1, &d1), (&p2, &d2), (&p1, &d1)] {
        model.evaluate(&u, p, Request::ALL, &mut s).unwrap();
        let layout = model.layout();
        let rows: Vec<usize> = nodes
            .iter()
            .flat_map(|&i| (0..3).filter_map(move |k| layout.dof(i, k)))
            .collect();
        compare(&model, &s, d, &rows, false);
    }
    let written = s.tangent.iter().filter(|v| **v != 0.0).count();
    assert!(
        written < e.tangent.len() / 2,
        "{written} of {}",
        e.tangent.len()
    );
}

#[test]
fn scatter_ranges_cover_every_unknown_and_list_every_triangle_touching_them() {
    let model = model();
    let layout = model.layout();
    for ranges in [1, 3, 1000] {
        let plan = ScatterPlan::new(
            &layout.tri_dofs,
            0..layout.triangles().len(),
            layout.pattern().col_ptr(),
            ranges,
        );
        assert_eq!(plan.bounds[0], 0);
        assert_eq!(*plan.bounds.last().unwrap() as usize, layout.unknowns());
        assert!(plan.bounds.windows(2).all(|w| w[0] < w[1]));
        for r in 0..plan.ranges() {
            let (lo, hi) = (plan.bounds[r], plan.bounds[r + 1]);
            let members = &plan.members[plan.start[r]..plan.start[r + 1]];
            assert!(members.windows(2).all(|w| w[0] < w[1]));
            for (t, dofs) in layout.tri_dofs.iter().enumerate() {
                let touches = dofs.iter().any(|&d| d != NONE && (lo..hi).contains(&d));
                assert_eq!(
                    touches,
                    members.contains(&(t as u32)),
                    "range {r}, triangle {t}"
                );
            }
        }
    }
}
