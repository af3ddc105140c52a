//! Parsing: TOML text → [`Scene`], with one-line errors that name the key path.
//!
//! The document is parsed into a TOML table first (syntax errors, with line and column), then
//! section by section. Tagged sections (`[mesh]` by `generator`, `[[effect]]` and
//! `[[constraint]]` and `[analysis]` by `type`) are dispatched by hand on their tag, and each
//! plain struct is deserialised with `serde_path_to_error`, so every error carries its full
//! key path (`effect[1].pressure`); serde's messages are rephrased into the scene format's
//! words ("expected a number, got \"one\"").

use super::error::{num, Problem};
use super::*;
use crate::effects::REGISTRY;
use serde::de::{self, DeserializeOwned, Deserializer, Visitor};
use serde::Serializer;
use std::fmt;
use toml::{Table, Value};

/// The top-level keys, in the order they are read.
const SECTIONS: [&str; 10] = [
    "scene",
    "mesh",
    "material",
    "effect",
    "boundary",
    "parameters",
    "constraint",
    "analysis",
    "start",
    "refine",
];

pub(super) fn parse(text: &str, origin: &str) -> Result<Scene, SceneError> {
    let doc: Table = toml::from_str(text).map_err(|e| syntax_error(text, origin, &e))?;
    let mut scene = read(&doc).map_err(|p| p.into_error(origin))?;
    scene.origin = origin.to_string();
    super::validate::check(&mut scene).map_err(|p| p.into_error(origin))?;
    Ok(scene)
}

pub(super) fn parse_mesh(text: &str, origin: &str) -> Result<MeshSpec, SceneError> {
    let doc: Table = toml::from_str(text).map_err(|e| syntax_error(text, origin, &e))?;
    let spec = read_mesh(&Value::Table(doc)).map_err(|p| p.into_error(origin))?;
    super::validate::check_mesh_options(&spec).map_err(|p| p.into_error(origin))?;
    Ok(spec)
}

fn syntax_error(text: &str, origin: &str, e: &toml::de::Error) -> SceneError {
    let start = e.span().map_or(0, |s| s.start.min(text.len()));
    let start = (0..=start)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    let before = &text[..start];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    let mut message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
    let source = text.lines().nth(line - 1).unwrap_or("").trim();
    if !source.is_empty() {
        let quoted: String = source
            .chars()
            .take(60)
            .map(|c| if c.is_control() { '?' } else { c })
            .collect();
        let more = if source.chars().count() > 60 {
            "…"
        } else {
            ""
        };
        message = format!("{message} (in `{quoted}{more}`)");
    }
    SceneError::Syntax {
        origin: origin.to_string(),
        line,
        column,
        message,
    }
}

/// Reads the sections (types and keys; the values are checked in `validate`).
fn read(doc: &Table) -> Result<Scene, Problem> {
    if let Some(key) = doc.keys().find(|k| !SECTIONS.contains(&k.as_str())) {
        return Err(Problem::new(
            &key_path("", key),
            format!(
                "unknown key '{}'; valid keys: {}",
                key_path("", key),
                SECTIONS.join(", ")
            ),
        ));
    }
    let section = |name: &str| -> Result<&Value, Problem> {
        doc.get(name)
            .ok_or_else(|| Problem::new(name, format!("missing section '{name}' ([{name}])")))
    };
    let info: SceneInfo = de(section("scene")?, "scene")?;
    let (mesh_value, mesh_radius) = radius_parameter(section("mesh")?, doc.get("parameters"))?;
    let mesh = read_mesh(&mesh_value)?;
    let material: Material = de(section("material")?, "material")?;
    let effects = match doc.get("effect") {
        None => Vec::new(),
        Some(v) => array_of_tables(v, "effect")?
            .iter()
            .enumerate()
            .map(|(i, t)| read_effect(t, &format!("effect[{i}]")))
            .collect::<Result<_, _>>()?,
    };
    let boundary: Boundary = match doc.get("boundary") {
        None => Boundary::default(),
        Some(v) => de(v, "boundary")?,
    };
    let mut parameters = BTreeMap::new();
    if let Some(v) = doc.get("parameters") {
        let table = v.as_table().ok_or_else(|| {
            Problem::new(
                "parameters",
                format!("'parameters': expected a table, got {}", show(v)),
            )
        })?;
        for (name, p) in table {
            let key = key_path("parameters", name);
            parameters.insert(name.clone(), de::<Parameter>(p, &key)?);
        }
    }
    let raw_constraints = match doc.get("constraint") {
        None => Vec::new(),
        Some(v) => array_of_tables(v, "constraint")?
            .iter()
            .enumerate()
            .map(|(i, t)| read_constraint(t, &format!("constraint[{i}]")))
            .collect::<Result<_, _>>()?,
    };
    let analysis = read_analysis(section("analysis")?)?;
    let start: Start = match doc.get("start") {
        None => Start::default(),
        Some(v) => de(v, "start")?,
    };
    let refine: Option<Refine> = match doc.get("refine") {
        None => None,
        Some(v) => Some(de(v, "refine")?),
    };
    let constraints = super::validate::resolve_constraints(&effects, &parameters, raw_constraints)?;
    Ok(Scene {
        origin: String::new(),
        info,
        mesh,
        mesh_radius,
        material,
        effects,
        boundary,
        parameters,
        constraints,
        analysis,
        start,
        refine,
    })
}

/// A `[[constraint]]` as written, before its effect is resolved.
#[derive(Debug, Clone)]
pub(super) enum RawConstraint {
    FluidVolume(RawFluidVolume, String),
    GasAmount(RawGasAmount, String),
    Fixed(FixedConstraint),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub(super) struct RawFluidVolume {
    #[serde(default)]
    pub effect: Option<usize>,
    pub value: Target,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub(super) struct RawGasAmount {
    #[serde(default)]
    pub effect: Option<usize>,
    pub value: Target,
    pub ambient_pressure: f64,
}

/// `[mesh] radius = "R"`: the mesh table with the radius set to R's start value (where the
/// mesh is generated; 1 if R declares no usable start, which the checks then report) and the
/// parameter. Only the generated surfaces scale; the axisymmetric generator refuses it.
fn radius_parameter(
    mesh: &Value,
    parameters: Option<&Value>,
) -> Result<(Value, Option<Quantity>), Problem> {
    let Some(name) = mesh.get("radius").and_then(Value::as_str) else {
        return Ok((mesh.clone(), None));
    };
    let generator = mesh.get("generator").and_then(Value::as_str).unwrap_or("");
    if !matches!(generator, "disc" | "icosphere" | "truncated-sphere") {
        return Err(Problem::at(
            "mesh.radius",
            format!(
                "= \"{name}\": a parameter radius needs a generated surface (disc, icosphere, \
                 truncated-sphere), not generator \"{generator}\"; give a number"
            ),
        ));
    }
    let start = parameters
        .and_then(|p| p.get(name))
        .and_then(|p| p.get("start"))
        .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        .unwrap_or(1.0);
    let mut table = mesh.as_table().cloned().unwrap_or_default();
    table.insert("radius".into(), Value::Float(start));
    Ok((
        Value::Table(table),
        Some(Quantity::Parameter(name.to_string())),
    ))
}

fn read_mesh(v: &Value) -> Result<MeshSpec, Problem> {
    let (generator, rest) = tagged(v, "mesh", "generator", Generator::NAMES)?;
    let generator = Generator::from_name(&generator).expect("a listed generator");
    let others = |own: &[&str]| -> Vec<&'static str> {
        Generator::ALL
            .iter()
            .flat_map(|g| g.options())
            .copied()
            .filter(|o| !own.contains(o))
            .collect()
    };
    // An option of another generator gets a message that says so.
    let explain = |own: &[&str], p: Problem| -> Problem {
        match p.key.strip_prefix("mesh.") {
            Some(opt) if p.message.starts_with("unknown key") && others(own).contains(&opt) => {
                Problem::at(
                    &p.key,
                    format!(
                        "is not an option of generator \"{generator}\" (its options: {})",
                        own.join(", ")
                    ),
                )
            }
            _ => p,
        }
    };
    let own = generator.options();
    match generator {
        Generator::Disc => de(&rest, "mesh").map(MeshSpec::Disc),
        Generator::Icosphere => de(&rest, "mesh").map(MeshSpec::Icosphere),
        Generator::TruncatedSphere => de(&rest, "mesh").map(MeshSpec::TruncatedSphere),
        Generator::File => de(&rest, "mesh").map(MeshSpec::File),
        Generator::Axisymmetric => de(&rest, "mesh").map(MeshSpec::Axisymmetric),
    }
    .map_err(|p| explain(own, p))
    .map_err(with_tag("generator"))
}

fn read_effect(v: &Value, path: &str) -> Result<Effect, Problem> {
    let names: Vec<&str> = REGISTRY.iter().map(|e| e.kind).collect();
    let (kind, rest) = tagged(v, path, "type", &names)?;
    let entry = REGISTRY
        .iter()
        .find(|e| e.kind == kind)
        .expect("the tag was checked against the registry");
    de_with(&rest, path, entry.read)
        .map(|spec| Effect::new(entry.kind, spec))
        .map_err(with_tag("type"))
}

fn read_constraint(v: &Value, path: &str) -> Result<RawConstraint, Problem> {
    let (kind, rest) = tagged(v, path, "type", ConstraintKind::NAMES)?;
    let path = path.to_string();
    match ConstraintKind::from_name(&kind).expect("a listed constraint") {
        ConstraintKind::FluidVolume => {
            de(&rest, &path).map(|c| RawConstraint::FluidVolume(c, path))
        }
        ConstraintKind::GasAmount => de(&rest, &path).map(|c| RawConstraint::GasAmount(c, path)),
        ConstraintKind::Fixed => de(&rest, &path).map(RawConstraint::Fixed),
    }
    .map_err(with_tag("type"))
}

fn read_analysis(v: &Value) -> Result<Analysis, Problem> {
    let (kind, rest) = tagged(v, "analysis", "type", &analysis_types())?;
    let Value::Table(rest) = rest else {
        unreachable!("a tagged section is a table")
    };
    Analysis::read(&kind, &rest).map_err(with_tag("type"))
}

/// The value of `key` as an array of tables (`[[key]]`).
fn array_of_tables<'a>(v: &'a Value, key: &str) -> Result<&'a Vec<Value>, Problem> {
    match v {
        Value::Array(items) => {
            if let Some((i, item)) = items.iter().enumerate().find(|(_, t)| !t.is_table()) {
                let path = format!("{key}[{i}]");
                return Err(Problem::new(
                    &path,
                    format!("'{path}': expected a table, got {}", show(item)),
                ));
            }
            Ok(items)
        }
        other => Err(Problem::new(
            key,
            format!(
                "'{key}': expected an array of tables ([[{key}]]), got {}",
                show(other)
            ),
        )),
    }
}

/// Splits a tagged table: the tag's value (one of `allowed`) and the table without it.
fn tagged(v: &Value, path: &str, tag: &str, allowed: &[&str]) -> Result<(String, Value), Problem> {
    let table = v.as_table().ok_or_else(|| {
        Problem::new(path, format!("'{path}': expected a table, got {}", show(v)))
    })?;
    let tag_path = key_path(path, tag);
    let value = table
        .get(tag)
        .ok_or_else(|| Problem::new(&tag_path, format!("missing field '{tag_path}'")))?;
    let name = value.as_str().ok_or_else(|| {
        Problem::new(
            &tag_path,
            format!("'{tag_path}': expected a string, got {}", show(value)),
        )
    })?;
    if !allowed.contains(&name) {
        return Err(Problem::new(
            &tag_path,
            format!(
                "'{tag_path}': unknown value \"{name}\"; expected one of: {}",
                allowed.join(", ")
            ),
        ));
    }
    let mut rest = table.clone();
    rest.remove(tag);
    Ok((name.to_string(), Value::Table(rest)))
}

/// Adds the tag key to the "valid keys" hint of a problem found in a tagged table.
fn with_tag(tag: &'static str) -> impl Fn(Problem) -> Problem {
    move |mut p| {
        p.message = p
            .message
            .replacen("; valid keys: ", &format!("; valid keys: {tag}, "), 1);
        p
    }
}

/// `prefix.key` (or `key` at the top), quoting keys that are not bare.
pub(super) fn key_path(prefix: &str, key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    let key = if bare {
        key.to_string()
    } else {
        format!("{key:?}")
    };
    if prefix.is_empty() {
        key
    } else {
        format!("{prefix}.{key}")
    }
}

/// A path segment below a section.
enum Seg {
    Key(String),
    Index(usize),
}

fn join(prefix: &str, segs: &[Seg]) -> String {
    let mut path = prefix.to_string();
    for s in segs {
        match s {
            Seg::Key(k) => path = key_path(&path, k),
            Seg::Index(i) => path.push_str(&format!("[{i}]")),
        }
    }
    path
}

/// Deserialises `v` (found at key path `prefix`) into `T`, turning serde's error into a
/// one-line problem with the full key path.
pub(super) fn de<T: DeserializeOwned>(v: &Value, prefix: &str) -> Result<T, Problem> {
    de_with(v, prefix, serde_path_to_error::deserialize::<_, T>)
}

/// Reads the table `v` at `prefix` with `read` (a deserializer that tracks the path to the
/// offending key), rephrasing its error as a [`Problem`].
fn de_with<T>(
    v: &Value,
    prefix: &str,
    read: impl FnOnce(Value) -> Result<T, serde_path_to_error::Error<toml::de::Error>>,
) -> Result<T, Problem> {
    // Every section is a table; serde would read an array positionally into a struct.
    if !v.is_table() {
        return Err(Problem::new(
            prefix,
            format!("'{prefix}': expected a table, got {}", show(v)),
        ));
    }
    read(v.clone()).map_err(|e| {
        let segs: Vec<Seg> = e
            .path()
            .iter()
            .filter_map(|s| match s {
                serde_path_to_error::Segment::Seq { index } => Some(Seg::Index(*index)),
                serde_path_to_error::Segment::Map { key } => Some(Seg::Key(key.clone())),
                serde_path_to_error::Segment::Enum { .. }
                | serde_path_to_error::Segment::Unknown => None,
            })
            .collect();
        let found = lookup(v, &segs);
        let message = e.into_inner().message().to_string();
        rephrase(prefix, &segs, found, &message)
    })
}

fn lookup<'a>(v: &'a Value, segs: &[Seg]) -> Option<&'a Value> {
    let mut cur = v;
    for s in segs {
        cur = match (s, cur) {
            (Seg::Key(k), Value::Table(t)) => t.get(k)?,
            (Seg::Index(i), Value::Array(a)) => a.get(*i)?,
            _ => return None,
        };
    }
    Some(cur)
}

/// The text between the first pair of backticks in `s`.
fn ticked(s: &str) -> Option<&str> {
    let a = s.find('`')?;
    let b = s[a + 1..].find('`')?;
    Some(&s[a + 1..a + 1 + b])
}

/// `expected one of `a`, `b`` → `a, b`.
fn untick(s: &str) -> String {
    s.replace('`', "")
}

fn rephrase(prefix: &str, segs: &[Seg], found: Option<&Value>, message: &str) -> Problem {
    let path = join(prefix, segs);
    if let Some(rest) = message.strip_prefix("unknown field ") {
        let field = ticked(rest).unwrap_or(rest);
        // serde_path_to_error may or may not have pushed the key itself.
        let full = match segs.last() {
            Some(Seg::Key(k)) if k == field => path.clone(),
            _ => key_path(&path, field),
        };
        let hint = match rest.split_once(", ") {
            Some((_, "there are no fields")) => String::new(),
            Some((_, expected)) => format!(
                "; valid keys: {}",
                untick(expected)
                    .trim_start_matches("expected ")
                    .trim_start_matches("one of ")
                    .replace(" or ", ", ")
            ),
            None => String::new(),
        };
        return Problem::new(&full, format!("unknown key '{full}'{hint}"));
    }
    if let Some(rest) = message.strip_prefix("missing field ") {
        let field = ticked(rest).unwrap_or(rest);
        let full = key_path(&path, field);
        return Problem::new(&full, format!("missing field '{full}'"));
    }
    if let Some(rest) = message.strip_prefix("unknown variant ") {
        let variant = ticked(rest).unwrap_or(rest);
        let expected = rest
            .split_once(", expected ")
            .map(|(_, e)| untick(e).replace("one of ", ""))
            .unwrap_or_default();
        return Problem::new(
            &path,
            format!("'{path}': unknown value \"{variant}\"; expected one of: {expected}"),
        );
    }
    for kind in ["invalid type: ", "invalid value: ", "invalid length "] {
        if let Some(rest) = message.strip_prefix(kind) {
            let (unexpected, expected) = rest.split_once(", expected ").unwrap_or((rest, "?"));
            let got = found.map_or_else(|| untick(unexpected), show);
            return Problem::new(
                &path,
                format!("'{path}': expected {}, got {got}", plain_expected(expected)),
            );
        }
    }
    if path.is_empty() {
        Problem::new("", message.to_string())
    } else {
        Problem::new(&path, format!("'{path}': {message}"))
    }
}

/// serde's name for an expected type in the scene format's words.
fn plain_expected(expected: &str) -> String {
    match expected {
        "f64" | "f32" => "a number".into(),
        "usize" | "u64" | "u32" | "u16" | "u8" => "a non-negative integer".into(),
        "i64" | "i32" | "isize" => "an integer".into(),
        "a boolean" | "bool" => "true or false".into(),
        "a string" | "path string" => "a string".into(),
        "a sequence" => "an array".into(),
        "a map" => "a table".into(),
        e if e.starts_with("struct ") => "a table".into(),
        e if e.starts_with("enum ") || e.starts_with("variant ") || e == "string only" => {
            "a string".into()
        }
        e if e.starts_with("an array of length ") => {
            format!("an array of {} numbers", &e["an array of length ".len()..])
        }
        e => untick(e),
    }
}

/// A TOML value as it appears in messages.
pub(super) fn show(v: &Value) -> String {
    match v {
        Value::String(s) => format!("{s:?}"),
        Value::Integer(i) => i.to_string(),
        Value::Float(f) => {
            let s = num(*f);
            if f.is_finite() && !s.contains(['.', 'e']) {
                format!("{s}.0")
            } else {
                s
            }
        }
        Value::Boolean(b) => b.to_string(),
        Value::Datetime(d) => d.to_string(),
        Value::Array(a) if a.iter().any(Value::is_table) => "an array of tables".into(),
        Value::Array(a) => {
            let text = v.to_string();
            if text.chars().count() <= 40 {
                text
            } else {
                format!("an array of {} values", a.len())
            }
        }
        Value::Table(_) => "a table".into(),
    }
}

impl<'de> Deserialize<'de> for Target {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Target;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, \"initial\" or a parameter name")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Target, E> {
                Ok(Target::Value(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Target, E> {
                Ok(Target::Value(v as f64))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Target, E> {
                Ok(Target::Value(v))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Target, E> {
                if v == "initial" {
                    Ok(Target::Initial)
                } else {
                    Ok(Target::Parameter(v.to_string()))
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl Serialize for Target {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Target::Initial => s.serialize_str("initial"),
            Target::Value(v) => s.serialize_f64(*v),
            Target::Parameter(name) => s.serialize_str(name),
        }
    }
}
