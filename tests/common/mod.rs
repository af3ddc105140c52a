//! Helpers shared by integration tests: reading our SVG output, following a path, and the
//! bundled balloon's variants with their closed form; the checks of every figure (`figures`).

pub mod figures;
pub mod identity;

/// The `<polyline>`s of an SVG: stroke colour and points.
#[allow(dead_code)]
pub fn polylines(svg: &str) -> Vec<(String, Vec<(i64, i64)>)> {
    svg.split("<polyline")
        .skip(1)
        .map(|p| {
            let attr = |name: &str| {
                let start = p.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
                p[start..start + p[start..].find('"').unwrap()].to_string()
            };
            let points = attr("points")
                .split_whitespace()
                .map(|xy| {
                    let (x, y) = xy.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            (attr("stroke"), points)
        })
        .collect()
}

/// The contents of the SVG's `<text>` elements, trimmed.
#[allow(dead_code)]
pub fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

/// Follows `problem` from (q0, λ0) (solved at its control first) until `stop` holds at a
/// point, the control leaves `opts.bounds` or `opts.max_steps` steps were taken: the
/// library's driver ([`Continuation`]) with its turning-point detection ([`trace`]).
#[allow(dead_code)]
pub fn follow<P: memstab::continuation::Problem>(
    problem: P,
    q0: &nalgebra::DVector<f64>,
    lambda0: &nalgebra::DVector<f64>,
    opts: &memstab::continuation::PathOptions,
    mut stop: impl FnMut(&memstab::continuation::PathPoint) -> bool,
) -> Result<memstab::continuation::events::Branch, memstab::continuation::SolveError> {
    use memstab::continuation::events::trace;
    use memstab::continuation::Continuation;
    use memstab::results::StopReason;
    let mut driver = Continuation::start(problem, q0, lambda0, opts.clone())?;
    Ok(trace(
        &mut driver,
        opts.max_steps,
        |_, p| stop(p).then_some(StopReason::Condition),
        &mut [],
        |_, _| {},
    ))
}

/// The sphere's fold line in closed form: ∂p/∂λ = 0 of
/// p R/(μH) = 2/(1+k)(λ⁻¹ − λ⁻⁷)(1 + kλ²) gives k(λ) = (λ⁶ − 7)/(λ⁸ + 5λ²).
#[allow(dead_code)]
pub fn fold_k(l: f64) -> f64 {
    (l.powi(6) - 7.0) / (l.powi(8) + 5.0 * l * l)
}

/// The bundled balloon (scenes/balloon.toml) at icosphere frequency `frequency` with its
/// material's k = "k" and the text from `[analysis]` up to `[start]` replaced by `middle`
/// (which declares `[parameters.k]` and the analysis).
#[allow(dead_code)]
pub fn balloon_with_k(frequency: usize, middle: &str) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/scenes/balloon.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let analysis = text.find("[analysis]").unwrap();
    let start = text.find("[start]").unwrap();
    let text = format!("{}{middle}{}", &text[..analysis], &text[start..])
        .replacen("k = 0.1\n", "k = \"k\"\n", 1)
        .replacen("frequency = 8", &format!("frequency = {frequency}"), 1);
    assert!(text.contains("k = \"k\""), "{text}");
    text
}

/// A balloon under a pressure p (effect 0) that also holds a reservoir of gas (effect 1) at
/// the over-pressure q, its amount (P + q)V the parameter n held by a `gas-amount`
/// constraint (P = 0.1); `mesh` is the body of its `[mesh]` table, `analysis` its
/// `[analysis]` table and any constraint that needs.
#[allow(dead_code)]
pub fn reservoir_balloon(name: &str, mesh: &str, analysis: &str) -> String {
    format!(
        r#"[scene]
name = "{name}"

[mesh]
{mesh}

[material]
model = "mooney-rivlin"
mu = 100.0
k = 0.1
thickness = 0.01

[[effect]]
type = "gas"
pressure = "p"

[[effect]]
type = "gas"
pressure = "q"

[parameters.p]
start = 0.19
min = 0.0
max = 3.0

[parameters.q]
start = 0.3

[parameters.n]
start = 1.94
min = 0.5
max = 3.0

[[constraint]]
type = "gas-amount"
effect = 1
value = "n"
ambient-pressure = 0.1

{analysis}

[start]
stretch = 1.05
"#
    )
}

/// The reservoir balloon's path in p at its amount n held.
#[allow(dead_code)]
pub const RESERVOIR_PATH: &str = "[[constraint]]\ntype = \"fixed\"\nparameter = \"n\"\n\n\
                                  [analysis]\ntype = \"path\"\ncontrol = \"p\"\nsteps = 400\n\
                                  max-step = 0.1\nstop-stretch = 2.6\n";

/// The reservoir balloon's limit point at amount n in closed form, (p, λ): the maximum over
/// the stretch λ ∈ [1.2, 3] (after the sphere's own maximum) of p_s(λ) − n/(V₀λ³) + P
/// (V₀ = 4π/3, p_s the k = 0.1 sphere's pressure), by golden section.
#[allow(dead_code)]
pub fn reservoir_limit(n: f64) -> (f64, f64) {
    let v0 = 4.0 * std::f64::consts::PI / 3.0;
    let p = |l: f64| memstab::reference::sphere_pressure(0.1, l) - n / (v0 * l.powi(3)) + 0.1;
    let (mut a, mut b) = (1.2f64, 3.0f64);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if p(c) > p(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let l = 0.5 * (a + b);
    (p(l), l)
}

/// Runs an axisymmetric scene (`[mesh] generator = "axisymmetric"`) through the one study
/// seam (`MeridianStudy` and `analysis::run`): its report.
#[allow(dead_code)]
pub fn meridian_report(scene: memstab::scene::Scene) -> memstab::results::PathReport {
    let mut study = memstab::study::meridian::MeridianStudy::build(scene).unwrap();
    memstab::analysis::run(&mut study, |_, _| {})
        .unwrap()
        .report
}

/// The wave number m of a critical point of the meridian (its block `m<m>`).
#[allow(dead_code)]
pub fn wave_number(c: &memstab::results::CriticalPoint) -> usize {
    memstab::axisym::blocks::wave_number(&c.irrep)
        .unwrap_or_else(|| panic!("not a block of the meridian: {}", c.irrep))
}

/// Runs the memstab binary with `args`.
pub fn memstab(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_memstab"))
        .args(args)
        .output()
        .expect("the memstab binary runs")
}

/// A process's output as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}
