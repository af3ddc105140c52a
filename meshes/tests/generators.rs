//! Tests of the mesh generators: counts, verified symmetry (and no hidden symmetry), geometry
//! and convergence, and rejection of bad input.

use meshes::generators::{
    disc, icosphere, icosphere_oriented, truncated_sphere, DiscOptions, Down, IcosphereOptions,
    TruncatedSphereOptions,
};
use meshes::{Mesh, MeshError, SymmetricMesh, Vec3};
use std::f64::consts::PI;
use symmetry::{Group, Invariant, Matrix3};

fn disc_with(sectors: usize, divisions: usize, group: Option<&str>) -> SymmetricMesh {
    disc(&DiscOptions {
        radius: 1.0,
        sectors,
        divisions,
        group: group.map(str::to_string),
    })
    .unwrap_or_else(|e| panic!("disc N={sectors} d={divisions} {group:?}: {e}"))
}

fn cap(pattern: &str, divisions: usize) -> SymmetricMesh {
    truncated_sphere(&TruncatedSphereOptions {
        divisions,
        ..TruncatedSphereOptions::for_pattern(pattern)
    })
    .unwrap_or_else(|e| panic!("truncated sphere {pattern} d={divisions}: {e}"))
}

fn sphere(frequency: usize) -> SymmetricMesh {
    icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency,
    })
    .unwrap()
}

/// Verifies the mesh and its group; returns the verification's closedness.
fn verified(m: &SymmetricMesh) -> bool {
    let v = m
        .verify()
        .unwrap_or_else(|e| panic!("{} mesh does not verify: {e}", m.group().name()));
    assert!(v.max_position_error <= 1e-13, "{v:?}");
    v.closed
}

fn assert_no_hidden(m: &SymmetricMesh) {
    let hidden = m.hidden_symmetries();
    assert!(
        hidden.is_empty(),
        "{} mesh has hidden symmetries {hidden:?}",
        m.group().name()
    );
}

fn rot_z(angle: f64) -> Matrix3 {
    let (s, c) = angle.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Independent of `hidden_symmetries`: the elements of `C_Nv` about z (the pattern's group,
/// which contains every symmetry of a slightly perturbed pattern) that map the mesh onto
/// itself, as (rotations k with angle 2πk/N, mirrors j at angle πj/N from x).
fn symmetries_in_cnv(mesh: &Mesh, n: usize) -> (Vec<usize>, Vec<usize>) {
    let rotations = (0..n)
        .filter(|&k| {
            // The rotation by 2πk/N generates the cyclic group of order N / gcd(k, N).
            let g = Group::cyclic(n / gcd(k, n));
            assert!(g.find(&rot_z(2.0 * PI * k as f64 / n as f64)).is_some());
            SymmetricMesh::new(mesh.clone(), g).is_ok()
        })
        .collect();
    let mirrors = (0..n)
        .filter(|&j| {
            let g = Group::cyclic_v(1).conjugated(&rot_z(PI * j as f64 / n as f64), "C1v");
            SymmetricMesh::new(mesh.clone(), g).is_ok()
        })
        .collect();
    (rotations, mirrors)
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// Asserts that within `C_Nv` exactly the rotations and mirrors of `C_M` / `C_Mv` are
/// symmetries.
fn assert_exactly(mesh: &Mesh, n: usize, m: usize, mirrors: bool) {
    let (rot, mir) = symmetries_in_cnv(mesh, n);
    let step = n / m;
    let want_rot: Vec<usize> = (0..n).step_by(step).collect();
    // Mirror j (angle πj/N) belongs to C_Mv iff πj/N is a multiple of π/M.
    let want_mir: Vec<usize> = if mirrors {
        (0..n).step_by(step).collect()
    } else {
        Vec::new()
    };
    assert_eq!(rot, want_rot, "rotations of C{m} in C{n}v");
    assert_eq!(mir, want_mir, "mirrors of C{m}v in C{n}v");
}

fn min_angle_deg(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .flat_map(|t| {
            (0..3).map(move |k| {
                let (a, b, c) = (
                    mesh.nodes[t[k]],
                    mesh.nodes[t[(k + 1) % 3]],
                    mesh.nodes[t[(k + 2) % 3]],
                );
                (b - a).angle(&(c - a)).to_degrees()
            })
        })
        .fold(f64::INFINITY, f64::min)
}

/// Observed order of convergence log2(e_h / e_{h/2}).
fn order(coarse: f64, fine: f64) -> f64 {
    (coarse / fine).log2()
}

fn invalid(result: Result<SymmetricMesh, MeshError>) -> String {
    match result {
        Err(MeshError::Invalid(m)) => m,
        Err(e @ MeshError::Option { .. }) => e.to_string(),
        Err(e) => panic!("expected MeshError::Invalid or Option, got {e}"),
        Ok(_) => panic!("expected an error"),
    }
}

// ---------------------------------------------------------------------------------------------
// Disc

#[test]
fn disc_counts() {
    let m = disc(&DiscOptions::default()).unwrap();
    assert_eq!(m.mesh.triangles.len(), 1792);
    assert_eq!(m.mesh.nodes.len(), 7 * 16 * 17 / 2 + 1);
    assert_eq!(m.group().name(), "C7v");
    for (n, d, group) in [
        (7, 16, Some("C7")),
        (8, 15, None),
        (8, 5, Some("C2v")),
        (4, 6, Some("C2")),
        (5, 1, Some("C5v")),
        (5, 2, Some("C1v")),
        (3, 2, Some("C1")),
        (6, 3, Some("C3v")),
    ] {
        let m = disc_with(n, d, group);
        assert_eq!(m.mesh.triangles.len(), n * d * d, "N={n} d={d} {group:?}");
        assert_eq!(m.mesh.nodes.len(), n * d * (d + 1) / 2 + 1, "N={n} d={d}");
        let topo = m.mesh.topology().unwrap();
        assert_eq!(topo.euler, 1);
        assert_eq!(topo.boundary_loops.len(), 1);
    }
}

#[test]
fn disc_is_flat_counterclockwise_with_rim() {
    for group in [None, Some("C7"), Some("C1v")] {
        let m = disc(&DiscOptions {
            radius: 2.5,
            group: group.map(str::to_string),
            ..Default::default()
        })
        .unwrap();
        assert!(m.mesh.nodes.iter().all(|x| x.z == 0.0));
        for t in 0..m.mesh.triangles.len() {
            assert!(
                m.mesh.area_vector(t).z > 0.0,
                "triangle {t} is not counter-clockwise"
            );
        }
        let rim = &m.mesh.boundaries["rim"];
        assert_eq!(rim.len(), 7 * 16);
        for &i in rim {
            assert!((m.mesh.nodes[i].norm() - 2.5).abs() < 1e-14);
        }
        let loop_nodes = &m.mesh.topology().unwrap().boundary_loops[0];
        let mut sorted = loop_nodes.clone();
        sorted.sort_unstable();
        assert_eq!(&sorted, rim);
        // The centre stays at the origin.
        assert!(m.mesh.nodes.iter().any(|x| x.norm() == 0.0));
    }
}

#[test]
fn disc_symmetry_is_exactly_the_declared_group() {
    for (n, d, group, m, mirrors) in [
        (7, 16, None, 7, true),
        (7, 16, Some("C7"), 7, false),
        (8, 15, Some("C8v"), 8, true),
        (8, 6, Some("C2v"), 2, true),
        (4, 6, Some("C2v"), 2, true),
        (6, 5, Some("C3v"), 3, true),
        (6, 5, Some("C3"), 3, false),
        (7, 8, Some("C1v"), 1, true),
        (8, 8, Some("C1v"), 1, true),
        (7, 6, Some("C1"), 1, false),
        (8, 4, Some("C4"), 4, false),
        (7, 2, Some("C1v"), 1, true),
        (6, 2, Some("C3"), 3, false),
        (4, 2, Some("C2v"), 2, true),
        (3, 1, Some("C3v"), 3, true),
    ] {
        let mesh = disc_with(n, d, group);
        assert!(!verified(&mesh), "a disc is open");
        assert_eq!(mesh.group().order(), if mirrors { 2 * m } else { m });
        assert_no_hidden(&mesh);
        assert_exactly(&mesh.mesh, n, m, mirrors);
    }
}

#[test]
fn symmetry_check_detects_the_pattern_symmetry() {
    // The independent check sees all of C7v on the plain pattern, even declared as C1v.
    let plain = disc(&DiscOptions::default()).unwrap();
    assert_exactly(&plain.mesh, 7, 7, true);
    let as_c1v = SymmetricMesh::new(plain.mesh, Group::cyclic_v(1)).unwrap();
    assert_exactly(&as_c1v.mesh, 7, 7, true);
    // The perturbed C1v disc has only its mirror.
    let broken = disc_with(7, 16, Some("C1v"));
    assert!(SymmetricMesh::new(broken.mesh, Group::cyclic_v(7)).is_err());
}

/// A flat mesh at z = 0: the search must try candidates with and without z → −z.
#[test]
fn hidden_symmetries_sees_the_rotations_of_a_flat_disc() {
    let plain = disc(&DiscOptions::default()).unwrap();
    let as_c1v = SymmetricMesh::new(plain.mesh, Group::cyclic_v(1)).unwrap();
    assert_eq!(as_c1v.hidden_symmetries().len(), 12);
}

#[test]
fn disc_area_converges_quadratically() {
    for group in ["C7v", "C1"] {
        let err = |d: usize| (disc_with(7, d, Some(group)).mesh.area() - PI).abs();
        let (e8, e16, e32) = (err(8), err(16), err(32));
        assert!(e16 < 0.02, "{e16}");
        for (a, b) in [(e8, e16), (e16, e32)] {
            let p = order(a, b);
            assert!((1.8..2.2).contains(&p), "{group}: observed order {p}");
        }
    }
}

#[test]
fn disc_elements_are_well_shaped() {
    for (n, group) in [
        (7, None),
        (7, Some("C1")),
        (8, Some("C2v")),
        (8, Some("C1v")),
    ] {
        for d in [if group.is_none() { 1 } else { 2 }, 3, 16] {
            let m = disc_with(n, d, group);
            let a = min_angle_deg(&m.mesh);
            assert!(a > 30.0, "N={n} d={d} {group:?}: min angle {a}");
        }
    }
}

#[test]
fn disc_rejects_bad_input() {
    let with = |f: &dyn Fn(&mut DiscOptions)| {
        let mut o = DiscOptions::default();
        f(&mut o);
        invalid(disc(&o))
    };
    let msg = with(&|o| o.sectors = 0);
    assert!(msg.contains("sectors") && msg.contains('0'), "{msg}");
    let msg = with(&|o| o.sectors = 2);
    assert!(msg.contains("sectors") && msg.contains('2'), "{msg}");
    let msg = with(&|o| o.divisions = 0);
    assert!(msg.contains("divisions") && msg.contains('0'), "{msg}");
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let msg = with(&|o| o.radius = r);
        assert!(
            msg.contains("radius") && msg.contains(&format!("{r}")),
            "{msg}"
        );
    }
    for g in [
        "C3v", "C2", "C14v", "D7", "C", "Cv", "C0v", "C-1", "c7v", "C7vv", "", "Ih",
    ] {
        let msg = with(&|o| o.group = Some(g.to_string()));
        assert!(
            msg.contains("group") && msg.contains(&format!("'{g}'")),
            "{msg}"
        );
    }
    for g in ["C1v", "C7"] {
        let msg = with(&|o| {
            o.divisions = 1;
            o.group = Some(g.to_string());
        });
        assert!(msg.contains("divisions = 1"), "{msg}");
    }
    let msg = with(&|o| {
        o.sectors = usize::MAX;
        o.divisions = usize::MAX;
    });
    assert!(msg.contains("triangles"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// Icosphere

#[test]
fn icosphere_counts() {
    for f in [1, 2, 3, 16] {
        let m = sphere(f);
        assert_eq!(m.mesh.triangles.len(), 20 * f * f, "f={f}");
        assert_eq!(m.mesh.nodes.len(), 10 * f * f + 2, "f={f}");
        assert_eq!(m.group().name(), "Ih");
        assert_eq!(m.group().order(), 120);
        assert_eq!(m.mesh.topology().unwrap().euler, 2);
    }
    let m = sphere(16);
    assert_eq!((m.mesh.triangles.len(), m.mesh.nodes.len()), (5120, 2562));
    let d = icosphere(&IcosphereOptions::default()).unwrap();
    assert_eq!((d.mesh.triangles.len(), d.mesh.nodes.len()), (320, 162));
}

#[test]
fn icosphere_verifies_closed_on_sphere() {
    for f in [1, 2, 3, 5, 16] {
        let m = icosphere(&IcosphereOptions {
            radius: 0.7,
            frequency: f,
        })
        .unwrap();
        assert!(verified(&m), "f={f}: an icosphere is closed");
        assert_no_hidden(&m);
        assert!(m.mesh.boundaries.is_empty());
        assert!(m.mesh.volume() > 0.0);
        for x in &m.mesh.nodes {
            assert!((x.norm() - 0.7).abs() < 1e-14);
        }
        // Outward: every area vector points away from the centre.
        for t in 0..m.mesh.triangles.len() {
            let c = m.mesh.triangles[t]
                .iter()
                .map(|&i| m.mesh.nodes[i])
                .sum::<Vec3>();
            assert!(m.mesh.area_vector(t).dot(&c) > 0.0);
        }
        let a = min_angle_deg(&m.mesh);
        assert!(a > 50.0, "f={f}: min angle {a}");
    }
}

#[test]
fn icosphere_volume_converges_quadratically() {
    let err = |f: usize| (4.0 * PI / 3.0 - sphere(f).mesh.volume()).abs();
    let (e8, e16, e32) = (err(8), err(16), err(32));
    for (a, b) in [(e8, e16), (e16, e32)] {
        let p = order(a, b);
        assert!((1.9..2.1).contains(&p), "observed order {p}");
    }
}

#[test]
fn icosphere_oriented_keeps_the_expected_subgroup() {
    let minus_z = Vec3::new(0.0, 0.0, -1.0);
    for (down, name) in [
        (Down::Vertex, "C5v"),
        (Down::Face, "C3v"),
        (Down::Edge, "C2v"),
    ] {
        let opts = IcosphereOptions {
            radius: 1.0,
            frequency: 6,
        };
        let m = icosphere_oriented(&opts, down).unwrap();
        // At f = 6 vertices, face centres and edge midpoints are all nodes: one is at −z.
        assert!(m.mesh.nodes.iter().any(|x| (x - minus_z).norm() < 1e-14));
        assert!(verified(&m));
        assert_eq!(m.group().name(), "Ih");
        let sub = m.action.restrict(&[Invariant::Direction(minus_z)]).unwrap();
        assert_eq!(sub.group().name(), name);
        // The restricted action still verifies, and the plane y = 0 is one of its mirrors.
        let restricted = SymmetricMesh {
            mesh: m.mesh.clone(),
            action: sub,
        };
        restricted.verify().unwrap();
        let mirror_y = Matrix3::from_diagonal(&Vec3::new(1.0, -1.0, 1.0));
        assert!(restricted.group().find(&mirror_y).is_some(), "{name}");
    }
}

#[test]
fn icosphere_rejects_bad_input() {
    let msg = invalid(icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: 0,
    }));
    assert!(msg.contains("frequency") && msg.contains('0'), "{msg}");
    for r in [0.0, -2.0, f64::NAN] {
        let msg = invalid(icosphere(&IcosphereOptions {
            radius: r,
            frequency: 2,
        }));
        assert!(
            msg.contains("radius") && msg.contains(&format!("{r}")),
            "{msg}"
        );
    }
    let msg = invalid(icosphere(&IcosphereOptions {
        radius: 1.0,
        frequency: usize::MAX,
    }));
    assert!(msg.contains("frequency"), "{msg}");
    let msg = invalid(icosphere_oriented(
        &IcosphereOptions {
            radius: -1.0,
            frequency: 2,
        },
        Down::Face,
    ));
    assert!(msg.contains("radius"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// Truncated sphere

#[test]
fn truncated_sphere_default_counts() {
    let m = truncated_sphere(&TruncatedSphereOptions::default()).unwrap();
    assert_eq!(m.group().name(), "C8v");
    assert_eq!(m.mesh.triangles.len(), 6728);
    assert_eq!(m.mesh.nodes.len(), 4 * 29 * 30 + 1);
    for (pattern, reference) in [("C8v", 6656), ("C2v", 5472), ("C1v", 5520)] {
        let o = TruncatedSphereOptions::for_pattern(pattern);
        let m = truncated_sphere(&o).unwrap();
        let n = m.mesh.triangles.len();
        assert_eq!(n, 8 * o.divisions * o.divisions);
        let rel = (n as f64 / reference as f64 - 1.0).abs();
        assert!(
            rel < 0.05,
            "{pattern}: {n} elements vs reference {reference}"
        );
        assert_eq!(m.group().name(), pattern);
    }
}

#[test]
fn truncated_sphere_symmetry_and_geometry() {
    for (pattern, m_order, mirrors) in [("C8v", 8, true), ("C2v", 2, true), ("C1v", 1, true)] {
        let o = TruncatedSphereOptions::for_pattern(pattern);
        let m = truncated_sphere(&o).unwrap();
        assert!(!verified(&m), "a truncated sphere is open");
        assert_no_hidden(&m);
        assert_exactly(&m.mesh, 8, m_order, mirrors);
        let topo = m.mesh.topology().unwrap();
        assert_eq!((topo.euler, topo.boundary_loops.len()), (1, 1));
        let cut = &m.mesh.boundaries["cut"];
        assert_eq!(cut.len(), 8 * o.divisions);
        let mut boundary = topo.boundary_loops[0].clone();
        boundary.sort_unstable();
        assert_eq!(&boundary, cut);
        for &i in cut {
            let x = m.mesh.nodes[i];
            assert_eq!(x.z, -0.5, "{pattern}: cut node {i} off the plane");
            assert!((x.norm() - 1.0).abs() < 1e-14);
        }
        for x in &m.mesh.nodes {
            assert!((x.norm() - 1.0).abs() < 1e-14);
            assert!(x.z >= -0.5);
        }
        assert!(
            m.mesh.nodes.iter().any(|x| (x - Vec3::z()).norm() == 0.0),
            "pole"
        );
        // Outward orientation.
        for t in 0..m.mesh.triangles.len() {
            let c = m.mesh.triangles[t]
                .iter()
                .map(|&i| m.mesh.nodes[i])
                .sum::<Vec3>();
            assert!(m.mesh.area_vector(t).dot(&c) > 0.0);
        }
        let a = min_angle_deg(&m.mesh);
        eprintln!("{pattern}: min angle {a:.1}");
        assert!(a > 15.0, "{pattern}: min angle {a}");
    }
}

#[test]
fn truncated_sphere_chiral_and_other_patterns() {
    for (pattern, m_order, mirrors) in [("C4v", 4, true), ("C8", 8, false), ("C2", 2, false)] {
        let m = cap(pattern, 10);
        verified(&m);
        assert_no_hidden(&m);
        assert_exactly(&m.mesh, 8, m_order, mirrors);
    }
}

#[test]
fn truncated_sphere_area_converges_quadratically() {
    for (pattern, c) in [("C8v", -0.5), ("C1v", -0.5), ("C2v", 0.3)] {
        let exact = 2.0 * PI * (1.0 - c);
        let err = |d: usize| {
            let o = TruncatedSphereOptions {
                cut_height: c,
                divisions: d,
                ..TruncatedSphereOptions::for_pattern(pattern)
            };
            (exact - truncated_sphere(&o).unwrap().mesh.area()).abs()
        };
        let (e8, e16, e32) = (err(8), err(16), err(32));
        for (a, b) in [(e8, e16), (e16, e32)] {
            let p = order(a, b);
            assert!(
                (1.8..2.2).contains(&p),
                "{pattern} c={c}: observed order {p}"
            );
        }
    }
}

#[test]
fn truncated_sphere_shapes_over_cut_heights() {
    for c in [-0.9, -0.5, 0.0, 0.5, 0.9] {
        for pattern in ["C8v", "C1v"] {
            let m = truncated_sphere(&TruncatedSphereOptions {
                radius: 2.0,
                cut_height: 2.0 * c,
                pattern: pattern.into(),
                divisions: 12,
            })
            .unwrap();
            verified(&m);
            assert_no_hidden(&m);
            let a = min_angle_deg(&m.mesh);
            eprintln!("c={c} {pattern}: min angle {a:.1}");
            assert!(a > 15.0, "c={c} {pattern}: min angle {a}");
        }
    }
}

#[test]
fn truncated_sphere_rejects_bad_input() {
    let with = |f: &dyn Fn(&mut TruncatedSphereOptions)| {
        let mut o = TruncatedSphereOptions::default();
        f(&mut o);
        invalid(truncated_sphere(&o))
    };
    for c in [-1.0, -1.5, 1.0, 2.0, f64::NAN] {
        let msg = with(&|o| o.cut_height = c);
        assert!(
            msg.contains("cut_height") && msg.contains(&format!("{c}")),
            "{msg}"
        );
    }
    for p in ["C3v", "C16v", "D8", "c8v", "", "Ih"] {
        let msg = with(&|o| o.pattern = p.to_string());
        assert!(
            msg.contains("pattern") && msg.contains(&format!("'{p}'")),
            "{msg}"
        );
    }
    for r in [0.0, -1.0, f64::NAN] {
        let msg = with(&|o| o.radius = r);
        assert!(
            msg.contains("radius") && msg.contains(&format!("{r}")),
            "{msg}"
        );
    }
    let msg = with(&|o| o.divisions = 0);
    assert!(msg.contains("divisions") && msg.contains('0'), "{msg}");
    let msg = with(&|o| {
        o.divisions = 1;
        o.pattern = "C2v".into();
    });
    assert!(msg.contains("divisions = 1"), "{msg}");
    assert!(truncated_sphere(&TruncatedSphereOptions {
        divisions: 1,
        ..Default::default()
    })
    .is_ok());
}

#[test]
fn generation_and_verification_are_fast() {
    use std::time::Instant;
    let t = Instant::now();
    let ico = sphere(32);
    let cap = truncated_sphere(&TruncatedSphereOptions::default()).unwrap();
    let generate = t.elapsed().as_secs_f64();
    let t = Instant::now();
    ico.verify().unwrap();
    cap.verify().unwrap();
    let verify = t.elapsed().as_secs_f64();
    eprintln!("generate f=32 icosphere + default cap: {generate:.3} s, verify: {verify:.3} s");
    // Generous bounds (debug builds and loaded machines); release is far below.
    assert!(generate < 10.0 && verify < 60.0);
}
