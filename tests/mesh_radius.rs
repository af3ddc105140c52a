//! The reference radius of a generated mesh as a parameter (`[mesh] radius = "R"`): the
//! balloon's limit curve in (p, R) against the closed form p R/(μH) = const, a path in R
//! against the mesh generated at that radius, held (fixed and sliding) boundaries that scale
//! with R and their loads against differences, and the values refused.

use memstab::analysis::run;
use memstab::model::check::check_derivatives;
use memstab::model::{Model, Request};
use memstab::results::CriticalKind;
use memstab::scene::Scene;
use memstab::study::mesh::MeshStudy;

/// The closed-form limit pressure of the k = 0.1 balloon, p R/(μH) at its maximum, and the
/// stretch there (scenes/balloon.toml).
const LIMIT_PR: f64 = 1.3551069;
const LIMIT_STRETCH: f64 = 1.4760699;

/// The bundled balloon at icosphere frequency 4 with its `[parameters]`, `[analysis]` and
/// `[start]` replaced by `tail`, and its mesh radius set to `radius` (TOML: a number or a
/// parameter's name in quotes).
fn balloon(radius: &str, tail: &str) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/balloon.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let params = text.find("[parameters.p]").unwrap();
    let text = format!("{}{tail}", &text[..params])
        .replacen("radius = 1.0", &format!("radius = {radius}"), 1)
        .replacen("frequency = 8", "frequency = 4", 1);
    assert!(text.contains(&format!("radius = {radius}")), "{text}");
    text
}

fn scene(text: &str) -> Scene {
    Scene::from_toml_str(text, "mesh-radius").unwrap()
}

/// The limit point followed in (p, R): by scaling, p R is the same at every point of the
/// curve (to the solver's tolerance: the mesh is the same one, scaled), and that constant is
/// the closed form's to the mesh's error; the stretch at the limit does not change either.
#[test]
fn the_balloons_limit_pressure_scales_as_one_over_the_radius() {
    let text = balloon(
        "\"R\"",
        r#"[parameters.p]
start = 0.4879036
min = 0.0
max = 4.0

[parameters.R]
start = 1.0
min = 0.5
max = 2.0

[analysis]
type = "critical-curve"
control = "p"
second = "R"
from = "limit"
steps = 200
path-steps = 400
max-step = 0.05

[start]
stretch = 1.05
"#,
    );
    let loaded = scene(&text);
    // The scene written back names the parameter again.
    let again = Scene::from_toml_str(&loaded.to_toml(), "again").unwrap();
    assert_eq!(again.mesh_radius, loaded.mesh_radius);
    assert_eq!(again.mesh, loaded.mesh);
    let mut study = MeshStudy::build(loaded).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the curve runs");
    let curve = result
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .expect("a curve");
    assert_eq!(curve.kind, CriticalKind::LimitPoint);
    let col = |name: &str| curve.parameters.iter().position(|p| p == name).unwrap();
    let (p, r) = (col("p"), col("R"));
    let s = curve.measures.iter().position(|m| m == "stretch").unwrap();
    let first = &curve.rows[0];
    let pr0 = first.parameters[p] * first.parameters[r];
    let (mut lo, mut hi, mut spread, mut stretch_spread) = (f64::MAX, 0.0f64, 0.0f64, 0.0f64);
    for row in &curve.rows {
        let radius = row.parameters[r];
        lo = lo.min(radius);
        hi = hi.max(radius);
        spread = spread.max((row.parameters[p] * radius / pr0 - 1.0).abs());
        stretch_spread = stretch_spread.max((row.measures[s] / first.measures[s] - 1.0).abs());
    }
    let closed = (pr0 / LIMIT_PR - 1.0).abs();
    let closed_stretch = (first.measures[s] / LIMIT_STRETCH - 1.0).abs();
    eprintln!(
        "{} points, R in [{lo}, {hi}], p R = {pr0}: spread {spread:e}, stretch spread \
         {stretch_spread:e}; closed form: {closed:e} (p R), {closed_stretch:e} (stretch)",
        curve.rows.len()
    );
    assert!(curve.rows.len() > 10, "{} points", curve.rows.len());
    // The curve runs from R = 1 to the bound R = 2.
    assert!(hi / lo > 1.9, "R covers [{lo}, {hi}]");
    // Measured: both about 2e-15.
    assert!(spread < 1e-12, "p R varies by {spread:e}");
    assert!(
        stretch_spread < 1e-12,
        "the stretch varies by {stretch_spread:e}"
    );
    // Frequency 4 (320 triangles): the mesh's error in the limit pressure is 1.5 %, in the
    // stretch at the limit 1.5e-5.
    assert!(closed < 0.02, "p R = {pr0} vs {LIMIT_PR}");
    assert!(
        closed_stretch < 1e-4,
        "{} vs {LIMIT_STRETCH}",
        first.measures[s]
    );
}

/// A path in R at the fixed pressure p = 0.9 from R = 1, and at its last point an
/// equilibrium of the mesh generated at that radius (a number): the same positions, volume
/// and stretch to the solver's tolerance.
#[test]
fn a_path_in_the_radius_is_the_mesh_generated_at_each_radius() {
    let text = balloon(
        "\"R\"",
        r#"[parameters.p]
start = 0.9

[parameters.R]
start = 1.0
min = 0.5
max = 1.3

[[constraint]]
type = "fixed"
parameter = "p"

[analysis]
type = "path"
control = "R"
direction = "increase"
steps = 60
max-step = 0.05

[start]
stretch = 1.1
"#,
    );
    let mut study = MeshStudy::build(scene(&text)).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the path runs");
    let last = result.states.last().expect("the last state");
    let r_col = study.parameters.iter().position(|p| p == "R").unwrap();
    let radius = last.params[r_col];
    assert!(
        radius > 1.25 && radius <= 1.3 + 0.05,
        "the path ends at R = {radius}"
    );
    let row = result.report.rows.last().unwrap();
    let names = &result.report.measures;
    let at = |name: &str| names.iter().position(|m| m == name).unwrap();
    let stretch = row.measures[at("stretch")];
    let x = study.model.positions(&last.u, &last.params);
    // The same balloon generated at that radius, found by its own start solve.
    let fixed = balloon(
        &format!("{radius:?}"),
        &format!(
            "[parameters.p]\nstart = 0.9\n\n[analysis]\ntype = \"equilibrium\"\n\n[start]\nstretch = {stretch:?}\n"
        ),
    );
    let mut other = MeshStudy::build(scene(&fixed)).unwrap();
    let alone = run(&mut other, |_, _| {}).expect("the equilibrium solves");
    let last_alone = alone.states.last().unwrap();
    let y = other.model.positions(&last_alone.u, &last_alone.params);
    let gap = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    let own = alone.report.rows.last().unwrap();
    let volume = (row.measures[at("volume")] / own.measures[at("volume")] - 1.0).abs();
    let stretches = (stretch / own.measures[at("stretch")] - 1.0).abs();
    let moved = (row.measures[at("max_displacement")] - own.measures[at("max_displacement")]).abs();
    eprintln!(
        "R = {radius}: positions within {gap:e}, volume {volume:e}, stretch {stretches:e}, \
         max_displacement {moved:e}"
    );
    // Measured: all within 1e-15.
    assert!(gap < 1e-11 * radius, "positions differ by {gap:e}");
    assert!(volume < 1e-11 && stretches < 1e-11 && moved < 1e-11);
}

fn memstab(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .output()
        .expect("the memstab binary runs")
}

/// A radius parameter that starts or may go at or below 0, on a membrane closed by a plate
/// off the plane z = 0 (which would have to move with it), or of the axisymmetric generator:
/// exit code 2, one line naming the key, nothing written.
#[test]
fn bad_radius_parameters_are_refused_without_writing() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("never");
    let path_tail = |r: &str| {
        format!(
            "[parameters.p]\nstart = 0.4879036\n\n[parameters.R]\n{r}\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"R\"\n\n[analysis]\ntype = \"path\"\ncontrol = \"p\"\nsteps = 3\n"
        )
    };
    let axisym = std::fs::read_to_string(format!(
        "{}/scenes/axisymmetric/balloon.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let axisym_radius = axisym
        .lines()
        .find(|l| l.trim_start().starts_with("radius"))
        .expect("the axisymmetric balloon gives its radius")
        .to_string();
    let cases = [
        (
            "start.toml",
            balloon("\"R\"", &path_tail("start = -1.0")),
            vec!["mesh.radius", "-1"],
        ),
        (
            "min.toml",
            balloon("\"R\"", &path_tail("start = 1.0\nmin = 0.0")),
            vec!["parameters.R.min", "mesh.radius"],
        ),
        (
            "plate.toml",
            held_scene(
                false,
                0.3,
                "[[effect]]\ntype = \"gas\"\npressure = \"p\"\n\n[parameters.p]\nstart = \
                 0.5\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"p\"\n",
            ),
            vec!["mesh.radius", "plate", "z = 0"],
        ),
        (
            "axisym.toml",
            axisym.replacen(&axisym_radius, "radius = \"R\"", 1),
            vec!["mesh.radius", "axisymmetric"],
        ),
    ];
    for (name, text, needles) in cases {
        let file = tmp.path().join(name);
        std::fs::write(&file, text).unwrap();
        let out = memstab(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{name}: not one line: {err}"
        );
        for needle in needles {
            assert!(err.contains(needle), "{name}: '{needle}' not in: {err}");
        }
        assert!(!dir.exists(), "{name}: {} was created", dir.display());
    }
}

/// A clamped disc (`membrane` = its effects and constraints) or a truncated sphere cut at
/// z = `cut` whose edge slides on planes z = const, with the reference radius the parameter R
/// (start 1.1) as the path's control.
fn held_scene(disc: bool, cut: f64, effects: &str) -> String {
    let mesh = if disc {
        "generator = \"disc\"\nradius = \"R\"\nsectors = 7\ndivisions = 3".to_string()
    } else {
        format!(
            "generator = \"truncated-sphere\"\nradius = \"R\"\ncut-height = {cut:?}\npattern = \
             \"C8v\"\ndivisions = 3"
        )
    };
    let boundary = if disc {
        "[boundary]\nfixed = [\"rim\"]\n"
    } else {
        "[boundary]\n\n[[boundary.slide]]\nset = \"cut\"\nnormal = [0.0, 0.0, 1.0]\n"
    };
    format!(
        "[scene]\nname = \"held\"\n\n[mesh]\n{mesh}\n\n[material]\nmodel = \
         \"mooney-rivlin\"\nmu = 100.0\nk = 0.1\nthickness = 0.01\nprestretch = 1.1\n\n\
         {effects}\n{boundary}\n[parameters.R]\nstart = 1.1\nmin = 0.5\nmax = 2.0\n\n\
         [analysis]\ntype = \"path\"\ncontrol = \"R\"\nsteps = 3\n"
    )
}

/// Deterministic pseudo-random numbers in [−1, 1].
fn noise(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed.wrapping_mul(6364136223846793005) | 1;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

/// Held boundaries with a radius parameter, on a clamped disc (gas below, a pond above; or a
/// fixed amount of gas, whose tangent has a rank-one term) and on truncated spheres whose cut
/// edge slides on the floor (a fluid with its volume held and spin; a gas with its amount
/// held): at R ≠ R0 a fixed node sits at (R/R0) X̂ and a sliding one in the plane through
/// (R/R0) X̂; ∂F/∂R — whose part from the moving held coordinates is K_{u,held} ∂x/∂R — and
/// every constraint's ∂g/∂R agree with central differences in R, at states off equilibrium
/// and with every other derivative checked too.
#[test]
fn held_boundaries_scale_with_the_radius_and_their_loads_are_derivatives() {
    let gas_pond = "[[effect]]\ntype = \"gas\"\npressure = \"p\"\n\n[[effect]]\ntype = \
                    \"fluid\"\nside = \"above\"\ndensity = 0.5\ngravity = 1.0\nlevel = 0.05\n\n\
                    [parameters.p]\nstart = 0.4\n\n[[constraint]]\ntype = \"gas-amount\"\n\
                    value = \"initial\"\nambient-pressure = 1.0\n";
    let amount = "[[effect]]\ntype = \"gas-amount\"\namount = 2.5\nambient-pressure = 1.0\n";
    let squeeze = "[[effect]]\ntype = \"plane\"\nnormal = [-1.0, 0.0, 0.0]\noffset = -0.9\n\
                   penalty = 1000.0\nexponent = 3\n\n[[effect]]\ntype = \"spin\"\ndensity = \
                   0.2\nomega2 = \"w2\"\n\n[parameters.w2]\nstart = 5.0\n\n[[constraint]]\ntype = \"fixed\"\n\
                   parameter = \"w2\"\n";
    let spinning = "[[effect]]\ntype = \"fluid\"\nside = \"inside\"\nfilled = true\ndensity = \
                    0.2\ngravity = 1.0\nlevel = \"h\"\n\n[[effect]]\ntype = \"spin\"\ndensity \
                    = 0.2\nomega2 = \"w2\"\n\n[parameters.h]\nstart = 3.0\n\n[parameters.w2]\n\
                    start = 5.0\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"w2\"\n\n\
                    [[constraint]]\ntype = \"fluid-volume\"\nvalue = \"initial\"\n";
    // (scene, whether its held nodes move with R: not those in the plane z = 0).
    let cases = [
        (
            "clamped disc, gas and pond",
            held_scene(true, 0.0, gas_pond),
            true,
        ),
        (
            "clamped disc, gas amount",
            held_scene(true, 0.0, amount),
            true,
        ),
        (
            "cap sliding on z = -0.3",
            held_scene(false, -0.3, squeeze),
            true,
        ),
        (
            "cap sliding on z = 0, fluid",
            held_scene(false, 0.0, spinning),
            false,
        ),
    ];
    for (k, (file, text, moves)) in cases.into_iter().enumerate() {
        let r0 = 1.1;
        let mut study = MeshStudy::build(scene(&text)).unwrap();
        let r = study.parameters.iter().position(|p| p == "R").unwrap();
        let mut params: Vec<f64> = study.start.clone();
        params[r] = 1.15 * r0;
        let n = study.model.unknowns();
        let scale = 0.05 * r0;
        let mut u: Vec<f64> = noise(k as u64 + 1, n).iter().map(|v| scale * v).collect();
        // A bulge of the flat disc, so that the gas under it has a volume.
        if file.contains("disc") {
            for (i, xh) in study.model.reference().iter().enumerate() {
                if let Some(dz) = study.model.layout().dof(i, 2) {
                    u[dz] += 0.3 * r0 * (1.0 - (xh.x * xh.x + xh.y * xh.y) / (r0 * r0));
                }
            }
        }
        let d = noise(k as u64 + 77, n);
        // Targets "initial" from the unloaded start, so that g is not of the state itself.
        study.set_targets(&vec![0.0; n], &study.start.clone());
        let model = &study.model;
        // Where the held nodes are.
        let x = model.positions(&u, &params);
        let layout = model.layout();
        let (mut fixed, mut sliding, mut worst) = (0, 0, 0.0f64);
        for (i, xi) in x.iter().enumerate() {
            let xh = model.reference()[i];
            if layout.dof(i, 0).is_none() {
                fixed += 1;
                worst = worst.max((xi - xh * 1.15).norm());
            } else if let Some(nn) = layout.slide_normal(i) {
                sliding += 1;
                let normal_part = nn.dot(&(xi - xh * 1.15));
                let u_normal = (0..3)
                    .map(|c| nn[c] * u[layout.dof(i, c).unwrap()])
                    .sum::<f64>();
                worst = worst.max((normal_part - u_normal).abs());
            }
        }
        assert!(fixed + sliding > 0, "{file}: no held node");
        let at_start = model.positions(&u, &study.start);
        let moved = x.iter().zip(&at_start).filter(|(a, b)| a != b).count();
        assert_eq!(moved > 0, moves, "{file}: {moved} nodes moved with R");
        assert!(
            worst < 1e-14,
            "{file}: held nodes off (R/R0) X̂ by {worst:e}"
        );
        let e = check_derivatives(model, &u, &params, &d, 1e-6).unwrap();
        eprintln!("{file} ({fixed} fixed, {sliding} sliding): {e:?}");
        assert!(e.residual < 1e-7, "{file}: {e:?}");
        assert!(e.tangent < 1e-6, "{file}: {e:?}");
        assert!(e.loads < 1e-7, "{file}: {e:?}");
        // The load of R is not only the membrane's own: the held coordinates' part is there.
        let mut eval = model.new_evaluation();
        model
            .evaluate(&u, &params, Request::ALL, &mut eval)
            .unwrap();
        let load_norm = eval.loads[r].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(load_norm > 0.0, "{file}: no load in R");
        // Every constraint's derivatives in R and along d.
        for c in &study.constraints {
            let at = |p: &[f64], u: &[f64]| c.evaluate(layout, &model.positions(u, p), p);
            let v = at(&params, &u);
            let h = 1e-6 * r0;
            let (mut pp, mut pm) = (params.clone(), params.clone());
            pp[r] += h;
            pm[r] -= h;
            let fd_r = (at(&pp, &u).value - at(&pm, &u).value) / (2.0 * h);
            let shifted =
                |s: f64| -> Vec<f64> { u.iter().zip(&d).map(|(a, b)| a + s * b).collect() };
            let fd_u =
                (at(&params, &shifted(1e-6)).value - at(&params, &shifted(-1e-6)).value) / 2e-6;
            let exact_u: f64 = v.grad_u.iter().zip(&d).map(|(g, di)| g * di).sum();
            let size = v
                .grad_u
                .iter()
                .map(|g| g.abs())
                .sum::<f64>()
                .max(v.value.abs());
            eprintln!(
                "  {}: dg/dR {} vs differences {fd_r}; along d {exact_u} vs {fd_u}",
                c.name(),
                v.grad_params[r]
            );
            assert_eq!(
                fd_r.abs() > 1e-3 * size,
                moves,
                "{file}: {}: dg/dR",
                c.name()
            );
            assert!(
                (v.grad_params[r] - fd_r).abs() < 1e-7 * size,
                "{file}: {} dg/dR {} vs {fd_r}",
                c.name(),
                v.grad_params[r]
            );
            assert!((exact_u - fd_u).abs() < 1e-7 * size, "{file}: {}", c.name());
        }
    }
}

/// A clamped disc under gas whose reference radius is `radius` (a number or "R"), with the
/// parameters, constraints and analysis `tail`.
fn clamped_disc(radius: &str, tail: &str) -> String {
    format!(
        "[scene]\nname = \"clamped-disc\"\n\n[mesh]\ngenerator = \"disc\"\nradius = {radius}\n\
         sectors = 7\ndivisions = 4\n\n[material]\nmodel = \"mooney-rivlin\"\nmu = 100.0\nk = \
         0.0\nthickness = 0.01\nprestretch = 1.05\n\n[[effect]]\ntype = \"gas\"\npressure = \
         \"p\"\n\n[boundary]\nfixed = [\"rim\"]\n\n{tail}"
    )
}

/// The clamped disc under gas: its rim held at (R/R0) X̂, the disc scaled to R is the disc
/// generated at R, so by the balloon's scaling argument (docs/theory.md §2.8) its limit
/// pressure times R is one constant along the limit point followed in (p, R). And a path in R
/// at a fixed pressure ends where the disc generated at that radius is in equilibrium.
#[test]
fn a_clamped_discs_limit_pressure_scales_as_one_over_the_radius() {
    let curve_tail = "[parameters.p]\nstart = 0.0\nmin = 0.0\nmax = 10.0\n\n[parameters.R]\n\
                      start = 1.0\nmin = 0.6\nmax = 1.8\n\n[analysis]\ntype = \
                      \"critical-curve\"\ncontrol = \"p\"\nsecond = \"R\"\nfrom = \"limit\"\n\
                      steps = 60\npath-steps = 300\nmax-step = 0.1\n";
    let mut study = MeshStudy::build(scene(&clamped_disc("\"R\"", curve_tail))).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the curve runs");
    let curve = result
        .outcome::<memstab::results::CurveReport>()
        .cloned()
        .expect("a curve");
    assert_eq!(curve.kind, CriticalKind::LimitPoint);
    let col = |name: &str| curve.parameters.iter().position(|p| p == name).unwrap();
    let (p, r) = (col("p"), col("R"));
    let pr0 = curve.rows[0].parameters[p] * curve.rows[0].parameters[r];
    let (mut lo, mut hi, mut spread) = (f64::MAX, 0.0f64, 0.0f64);
    for row in &curve.rows {
        let radius = row.parameters[r];
        lo = lo.min(radius);
        hi = hi.max(radius);
        spread = spread.max((row.parameters[p] * radius / pr0 - 1.0).abs());
    }
    eprintln!(
        "{} points, R in [{lo}, {hi}], p R = {pr0}: spread {spread:e}",
        curve.rows.len()
    );
    assert!(
        curve.rows.len() > 5 && hi / lo > 1.5,
        "R covers [{lo}, {hi}]"
    );
    assert!(spread < 1e-9, "p R varies by {spread:e}");

    let path_tail = "[parameters.p]\nstart = 1.0\n\n[parameters.R]\nstart = 1.0\nmin = 0.5\n\
                     max = 1.3\n\n[[constraint]]\ntype = \"fixed\"\nparameter = \"p\"\n\n\
                     [analysis]\ntype = \"path\"\ncontrol = \"R\"\ndirection = \"increase\"\n\
                     steps = 60\nmax-step = 0.05\n";
    let mut study = MeshStudy::build(scene(&clamped_disc("\"R\"", path_tail))).unwrap();
    let result = run(&mut study, |_, _| {}).expect("the path runs");
    let last = result.states.last().expect("the last state");
    let radius = last.params[study.parameters.iter().position(|p| p == "R").unwrap()];
    assert!(radius > 1.25, "the path ends at R = {radius}");
    let x = study.model.positions(&last.u, &last.params);
    let fixed = clamped_disc(
        &format!("{radius:?}"),
        "[parameters.p]\nstart = 1.0\n\n[analysis]\ntype = \"equilibrium\"\n",
    );
    let mut other = MeshStudy::build(scene(&fixed)).unwrap();
    let alone = run(&mut other, |_, _| {}).expect("the equilibrium solves");
    let own = alone.states.last().unwrap();
    let y = other.model.positions(&own.u, &own.params);
    let gap = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    let rise = y.iter().map(|v| v.z).fold(0.0, f64::max);
    eprintln!("R = {radius}: positions within {gap:e} (the centre rises {rise})");
    assert!(rise > 0.1 * radius, "the disc barely inflates: {rise}");
    assert!(gap < 1e-10 * radius, "positions differ by {gap:e}");
}
