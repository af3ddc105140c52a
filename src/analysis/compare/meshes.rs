//! The meshes of a comparison: how they are named, and the scene on each.

use super::CompareError;
use crate::scene::{Generator, MeshSpec, Scene};
use crate::text::one_line;

/// How a mesh is named.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum MeshArg {
    /// A group name for the scene's generator.
    Group(String),
    /// `GENERATOR:KEY=VALUE,…`.
    Full {
        generator: String,
        options: Vec<(String, String)>,
    },
}

/// One mesh of a comparison: its label (as written) and what it means.
#[derive(Debug, Clone)]
pub struct MeshChoice {
    /// The label, as written.
    pub label: String,
    pub(super) arg: MeshArg,
}

/// Most samples a sweep keeps when `--max` stretches it.
const MAX_SAMPLES: usize = 100_000;

/// A generator that builds meshes (every one but `file`).
pub(super) fn generated(name: &str) -> Option<Generator> {
    Generator::from_name(name).filter(|g| *g != Generator::File)
}

/// The meshes of comma-separated lists (`C8v,C2v,disc:sectors=8,divisions=12,group=C1v`); a
/// `KEY=VALUE` item continues the full override before it. Errors name the list as
/// `--meshes '…'`.
pub fn parse_meshes(values: &[String]) -> Result<Vec<MeshChoice>, CompareError> {
    let mut out: Vec<MeshChoice> = Vec::new();
    for value in values {
        let mut continuing = false;
        for raw in value.split(',') {
            let item = raw.trim();
            if item.is_empty() {
                return Err(CompareError::Input(format!(
                    "--meshes '{value}': an empty mesh name"
                )));
            }
            if let Some((generator, rest)) = item.split_once(':') {
                let generator = generator.trim().to_string();
                let mut options = Vec::new();
                if !rest.trim().is_empty() {
                    options.push(key_value(rest, value)?);
                }
                out.push(MeshChoice {
                    label: item.to_string(),
                    arg: MeshArg::Full { generator, options },
                });
                continuing = true;
            } else if item.contains('=') {
                let last = out.last_mut().filter(|_| continuing);
                let Some(MeshChoice {
                    label,
                    arg: MeshArg::Full { options, .. },
                }) = last
                else {
                    return Err(CompareError::Input(format!(
                        "--meshes '{value}': '{item}' names no generator; write a full \
                         override as GENERATOR:KEY=VALUE,..., e.g. disc:divisions=12,group=C2v"
                    )));
                };
                options.push(key_value(item, value)?);
                label.push(',');
                label.push_str(item);
            } else if generated(item).is_some() {
                out.push(MeshChoice {
                    label: item.to_string(),
                    arg: MeshArg::Full {
                        generator: item.to_string(),
                        options: Vec::new(),
                    },
                });
                continuing = true;
            } else {
                out.push(MeshChoice {
                    label: item.to_string(),
                    arg: MeshArg::Group(item.to_string()),
                });
                continuing = false;
            }
        }
    }
    for (i, t) in out.iter().enumerate() {
        if out[..i].iter().any(|o| o.label == t.label) {
            return Err(CompareError::Input(format!(
                "--meshes: '{}' is given twice",
                t.label
            )));
        }
    }
    if out.is_empty() {
        return Err(CompareError::Input("--meshes: no mesh given".into()));
    }
    Ok(out)
}

fn key_value(item: &str, value: &str) -> Result<(String, String), CompareError> {
    match item.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() && !v.trim().is_empty() => {
            Ok((k.trim().replace('_', "-"), v.trim().to_string()))
        }
        _ => Err(CompareError::Input(format!(
            "--meshes '{value}': '{item}' is not KEY=VALUE"
        ))),
    }
}

/// A typed option value as TOML: an integer, a float, a boolean, else a string.
fn toml_value(v: &str) -> toml::Value {
    if let Ok(i) = v.parse::<i64>() {
        toml::Value::Integer(i)
    } else if let Ok(f) = v.parse::<f64>() {
        toml::Value::Float(f)
    } else if let Ok(b) = v.parse::<bool>() {
        toml::Value::Boolean(b)
    } else {
        toml::Value::String(v.to_string())
    }
}

/// M of `C<M>` / `C<M>v`, if the name has that form.
fn axial_order(name: &str) -> Option<usize> {
    let rest = name.strip_prefix('C')?;
    let digits = rest.strip_suffix('v').unwrap_or(rest);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok().filter(|&m: &usize| m >= 1)
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The sector count shared by the group names: the scene's if every M divides it, else the
/// smallest multiple of lcm(M…) that is at least the scene's.
pub(super) fn common_sectors(scene_sectors: usize, typed: &[MeshChoice]) -> usize {
    let orders: Vec<usize> = typed
        .iter()
        .filter_map(|t| match &t.arg {
            MeshArg::Group(g) => axial_order(g),
            MeshArg::Full { .. } => None,
        })
        .collect();
    if orders.iter().all(|m| scene_sectors.is_multiple_of(*m)) {
        return scene_sectors;
    }
    let l = orders
        .iter()
        .fold(1usize, |l, &m| (l / gcd(l, m)).saturating_mul(m))
        .max(1);
    scene_sectors.div_ceil(l).saturating_mul(l)
}

/// The resolution of a mesh spec: divisions, or an icosphere's frequency.
pub(super) fn resolution(spec: &MeshSpec) -> usize {
    match spec {
        MeshSpec::Disc(d) => d.divisions,
        MeshSpec::Icosphere(i) => i.frequency,
        MeshSpec::TruncatedSphere(t) => t.divisions_or_default(),
        MeshSpec::Axisymmetric(a) => a.elements,
        MeshSpec::File(_) => 0,
    }
}

/// The mesh options as one line, e.g. `disc sectors=8 divisions=6 group=C8v`.
pub(super) fn describe(spec: &MeshSpec) -> String {
    match spec {
        MeshSpec::Disc(d) => format!(
            "disc sectors={} divisions={} group={}",
            d.sectors,
            d.divisions,
            d.group
                .clone()
                .unwrap_or_else(|| format!("C{}v", d.sectors))
        ),
        MeshSpec::Icosphere(i) => format!(
            "icosphere frequency={}{}",
            i.frequency,
            i.down.map_or_else(String::new, |d| format!(
                " down={}",
                format!("{d:?}").to_lowercase()
            ))
        ),
        MeshSpec::TruncatedSphere(t) => format!(
            "truncated-sphere pattern={} divisions={} cut-height={}",
            t.pattern,
            t.divisions_or_default(),
            t.cut_height
        ),
        MeshSpec::File(f) => format!("file {} group={}", f.path.display(), f.group),
        MeshSpec::Axisymmetric(a) => format!(
            "axisymmetric shape={} elements={} modes={}",
            match a.shape {
                crate::scene::AxisymShape::Disc => "disc",
                crate::scene::AxisymShape::TruncatedSphere => "truncated-sphere",
                crate::scene::AxisymShape::Sphere => "sphere",
            },
            a.elements,
            a.modes
        ),
    }
}

/// The `[mesh]` table of the meridian of a 3-D mesh: the surface of revolution the generator
/// builds, its geometry keys carried over (radius, a cut's height); the meridian's own keys
/// (elements, modes) take their defaults unless the override sets them.
fn meridian_of(spec: &MeshSpec) -> Result<toml::Table, String> {
    let (shape, radius, cut) = match spec {
        MeshSpec::Disc(d) => ("disc", d.radius, None),
        MeshSpec::TruncatedSphere(t) => ("truncated-sphere", t.radius, Some(t.cut_height)),
        MeshSpec::Icosphere(i) => ("sphere", i.radius, None),
        MeshSpec::Axisymmetric(_) => unreachable!("only a 3-D mesh is made a meridian"),
        MeshSpec::File(f) => {
            return Err(format!(
                "the scene's mesh is the file '{}', whose surface of revolution is not known; \
                 give the meridian's shape, e.g. axisymmetric:shape=disc,radius=1.1",
                f.path.display()
            ))
        }
    };
    let mut mesh = toml::Table::new();
    mesh.insert("generator".into(), "axisymmetric".into());
    mesh.insert("shape".into(), shape.into());
    mesh.insert("radius".into(), toml::Value::Float(radius));
    if let Some(c) = cut {
        mesh.insert("cut-height".into(), toml::Value::Float(c));
    }
    Ok(mesh)
}

/// The settings shared by every variant.
pub(super) struct Common {
    pub(super) control: String,
    pub(super) max: Option<f64>,
    pub(super) samples: Option<usize>,
    pub(super) divisions: Option<usize>,
    pub(super) sectors: usize,
}

/// The scene with the typed mesh and the common settings, validated again as a whole.
pub(super) fn variant(
    scene: &Scene,
    typed: &MeshChoice,
    common: &Common,
) -> Result<Scene, CompareError> {
    let bad = |what: String| CompareError::Input(format!("mesh '{}': {what}", typed.label));
    let mut mesh = toml::Table::try_from(&scene.mesh)
        .map_err(|e| CompareError::Failure(format!("the scene's mesh does not serialise: {e}")))?;
    let own = scene.mesh.generator();
    let mut explicit_resolution = false;
    match &typed.arg {
        MeshArg::Group(name) => match &scene.mesh {
            MeshSpec::Disc(_) => {
                mesh.insert("group".into(), toml::Value::String(name.clone()));
                mesh.insert(
                    "sectors".into(),
                    toml::Value::Integer(common.sectors as i64),
                );
            }
            MeshSpec::TruncatedSphere(_) => {
                mesh.insert("pattern".into(), toml::Value::String(name.clone()));
            }
            // The same file, declared with another group.
            MeshSpec::File(_) => {
                mesh.insert("group".into(), toml::Value::String(name.clone()));
            }
            MeshSpec::Axisymmetric(_) => return Err(bad(crate::scene::AXISYMMETRIC_ONLY.into())),
            MeshSpec::Icosphere(_) => {
                return Err(bad(
                    "an icosphere has no group option; name it by a full override, e.g. \
                     icosphere:frequency=4,down=vertex"
                        .into(),
                ))
            }
        },
        MeshArg::Full { generator, options } => {
            let Some(chosen) = generated(generator) else {
                let known: Vec<&str> = Generator::ALL
                    .iter()
                    .filter_map(|g| generated(g.name()).map(|g| g.name()))
                    .collect();
                return Err(bad(format!(
                    "unknown generator '{generator}' ({})",
                    known.join(", ")
                )));
            };
            let full = options.iter().any(|(k, _)| k == "shape");
            if chosen == Generator::Axisymmetric && own != Generator::Axisymmetric && !full {
                mesh = meridian_of(&scene.mesh).map_err(bad)?;
            } else if chosen != own {
                mesh = toml::Table::new();
                mesh.insert("generator".into(), toml::Value::String(generator.clone()));
            }
            for (k, v) in options {
                if k == "generator" {
                    return Err(bad("the generator goes before the ':'".into()));
                }
                explicit_resolution |= Some(k.as_str()) == chosen.resolution_key();
                mesh.insert(k.clone(), toml_value(v));
            }
        }
    }
    let generator = mesh
        .get("generator")
        .and_then(|g| g.as_str())
        .and_then(Generator::from_name)
        .unwrap_or(own);
    // `--divisions` is the 3-D meshes' resolution; a meridian keeps its elements.
    let three_d = generator != Generator::Axisymmetric;
    if let (Some(d), false, true, Some(key)) = (
        common.divisions,
        explicit_resolution,
        three_d,
        generator.resolution_key(),
    ) {
        mesh.insert(key.into(), toml::Value::Integer(d as i64));
    }
    let mut base = scene.clone();
    if let Some(max) = common.max {
        if let Some(p) = base.parameters.get_mut(&common.control) {
            let old = (p.min, p.max);
            p.max = Some(max);
            // Keep the sample spacing of a linear-buckling sweep.
            if let (true, Some(samples), (Some(lo), Some(hi)), None) = (
                base.analysis.holds_state(),
                base.analysis.budget(),
                old,
                common.samples,
            ) {
                if hi > lo && max > lo {
                    let samples = ((samples as f64) * (max - lo) / (hi - lo)).ceil();
                    if samples.is_nan() || samples > MAX_SAMPLES as f64 {
                        return Err(CompareError::Input(format!(
                            "--max {}: the sweep would keep its spacing with {samples:e} \
                             samples, more than {MAX_SAMPLES}; give --samples",
                            crate::text::num(max)
                        )));
                    }
                    base.analysis.set_budget(samples.max(1.0) as usize);
                }
            }
        }
    }
    if let Some(n) = common.samples {
        base.analysis.set_budget(n);
    }
    let mut table = toml::Table::try_from(&base)
        .map_err(|e| CompareError::Failure(format!("the scene does not serialise: {e}")))?;
    table.insert("mesh".into(), toml::Value::Table(mesh));
    let text = toml::to_string(&table)
        .map_err(|e| CompareError::Failure(format!("the scene does not serialise: {e}")))?;
    let origin = format!("{} with mesh '{}'", scene.origin, typed.label);
    Scene::from_toml_str(&text, &origin).map_err(|e| CompareError::Input(one_line(&e.to_string())))
}
