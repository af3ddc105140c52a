//! Character tables against GAP, an independent source.
//!
//! `tests/data/gap_character_tables.json` was written by `scripts/gap_character_tables.g`
//! (GAP 4.12 with ctbllib): class sizes, element orders and every irreducible character as
//! exact cyclotomic coefficients. The tables agree if some bijection of classes that keeps
//! class sizes and element orders makes the two sets of rows equal.

use serde_json::Value;
use std::f64::consts::PI;
use symmetry::Group;

struct Table {
    sizes: Vec<usize>,
    orders: Vec<usize>,
    rows: Vec<Vec<f64>>,
}

fn gap_table(name: &str) -> Table {
    let text = include_str!("data/gap_character_tables.json");
    let all: Value = serde_json::from_str(text).expect("valid JSON");
    let t = &all[name];
    let ints = |v: &Value| -> Vec<usize> {
        v.as_array()
            .expect("array")
            .iter()
            .map(|x| x.as_u64().expect("integer") as usize)
            .collect()
    };
    // A cyclotomic with coefficients c_k in the basis E(n)^k: value Σ c_k exp(2πik/n).
    let value = |coeffs: &Value| -> f64 {
        let c = coeffs.as_array().expect("coefficients");
        let n = c.len() as f64;
        let (re, im) = c.iter().enumerate().fold((0.0, 0.0), |(re, im), (k, ck)| {
            let ck = ck.as_i64().expect("integer coefficient") as f64;
            let a = 2.0 * PI * k as f64 / n;
            (re + ck * a.cos(), im + ck * a.sin())
        });
        assert!(im.abs() < 1e-12, "{name}: a non-real character value");
        re
    };
    Table {
        sizes: ints(&t["class_sizes"]),
        orders: ints(&t["element_orders"]),
        rows: t["irreps"]
            .as_array()
            .expect("irreps")
            .iter()
            .map(|row| row.as_array().expect("row").iter().map(value).collect())
            .collect(),
    }
}

fn our_table(g: &Group) -> Table {
    Table {
        sizes: g.classes().iter().map(Vec::len).collect(),
        orders: g.classes().iter().map(|c| g.element_order(c[0])).collect(),
        rows: g
            .irreps()
            .iter()
            .map(|r| g.classes().iter().map(|c| r.character(c[0])).collect())
            .collect(),
    }
}

/// Rows of `a` with columns permuted by `perm` equal the rows of `b` as a set.
fn rows_match(a: &Table, b: &Table, perm: &[usize]) -> bool {
    let mut used = vec![false; b.rows.len()];
    a.rows.iter().all(|ra| {
        let hit = b.rows.iter().enumerate().position(|(k, rb)| {
            !used[k]
                && perm
                    .iter()
                    .enumerate()
                    .all(|(i, &j)| (ra[i] - rb[j]).abs() < 1e-9)
        });
        hit.map(|k| used[k] = true).is_some()
    })
}

/// Backtracking search for a class bijection (size- and order-preserving) that matches rows.
fn find_bijection(a: &Table, b: &Table, perm: &mut Vec<usize>, used: &mut [bool]) -> bool {
    let i = perm.len();
    if i == a.sizes.len() {
        return rows_match(a, b, perm);
    }
    for j in 0..b.sizes.len() {
        if used[j] || a.sizes[i] != b.sizes[j] || a.orders[i] != b.orders[j] {
            continue;
        }
        // Prune: column i must agree with column j as multisets of values.
        let mut ca: Vec<f64> = a.rows.iter().map(|r| r[i]).collect();
        let mut cb: Vec<f64> = b.rows.iter().map(|r| r[j]).collect();
        ca.sort_by(f64::total_cmp);
        cb.sort_by(f64::total_cmp);
        if ca.iter().zip(&cb).any(|(x, y)| (x - y).abs() > 1e-9) {
            continue;
        }
        used[j] = true;
        perm.push(j);
        if find_bijection(a, b, perm, used) {
            return true;
        }
        perm.pop();
        used[j] = false;
    }
    false
}

fn assert_matches_gap(g: &Group, gap_name: &str) {
    let ours = our_table(g);
    let gap = gap_table(gap_name);
    assert_eq!(
        ours.rows.len(),
        gap.rows.len(),
        "{}: number of irreps",
        g.name()
    );
    let mut s1 = ours.sizes.clone();
    let mut s2 = gap.sizes.clone();
    s1.sort_unstable();
    s2.sort_unstable();
    assert_eq!(s1, s2, "{}: class sizes", g.name());
    let mut used = vec![false; gap.sizes.len()];
    assert!(
        find_bijection(&ours, &gap, &mut Vec::new(), &mut used),
        "{}: no class bijection makes the character tables agree with GAP",
        g.name()
    );
}

#[test]
fn c7v_matches_gap_dihedral_group_14() {
    assert_matches_gap(&Group::by_name("C7v").unwrap(), "C7v");
}

#[test]
fn c8v_matches_gap_dihedral_group_16() {
    assert_matches_gap(&Group::by_name("C8v").unwrap(), "C8v");
}

#[test]
fn c12v_and_c2v_match_gap() {
    assert_matches_gap(&Group::cyclic_v(12), "C12v");
    assert_matches_gap(&Group::cyclic_v(2), "C2v");
}

#[test]
fn icosahedral_groups_match_gap() {
    assert_matches_gap(&Group::icosahedral(), "I");
    assert_matches_gap(&Group::icosahedral_full(), "Ih");
}

#[test]
fn a_wrong_table_is_detected() {
    // The comparison can fail: C8v is not C7v, and a table with one character altered
    // does not match.
    let c8v = our_table(&Group::cyclic_v(8));
    let gap = gap_table("C7v");
    assert_ne!(c8v.rows.len(), gap.rows.len());
    let ih = Group::icosahedral_full();
    let mut ours = our_table(&ih);
    ours.rows[3][2] += 1.0;
    let gap = gap_table("Ih");
    let mut used = vec![false; gap.sizes.len()];
    assert!(!find_bijection(&ours, &gap, &mut Vec::new(), &mut used));
}
