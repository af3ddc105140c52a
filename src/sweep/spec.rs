//! The sweep file and its expansion: a base scene, a grid over scene keys and fixed
//! overrides, made into one scene per grid point, every one validated (and its mesh built)
//! before anything is written.

use super::{Expanded, SweepError, Task};
use crate::results::sweep::SweptValue;
use crate::scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

/// The most grid points a sweep may have.
pub const MAX_POINTS: usize = 100_000;

/// The scene keys that name files: a relative path is made absolute (against the directory of
/// the file it came from), since a task's scene lives in its run directory.
const FILE_KEYS: [&str; 3] = ["mesh.path", "start.from", "analysis.from-run"];

/// One step of a key path: a table key, or an index into an array of tables.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// Parses a dotted scene key (`material.k`, `effect[0].density`, `parameters.h.max`).
fn parse_key(key: &str) -> Result<Vec<Step>, String> {
    let mut steps = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        let valid = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_';
        if name.is_empty() || !name.chars().all(valid) {
            return Err(format!(
                "'{key}' is not a scene key (dotted names such as material.k or effect[0].density)"
            ));
        }
        steps.push(Step::Key(name.to_string()));
        while !rest.is_empty() {
            let index = rest
                .strip_prefix('[')
                .and_then(|r| r.split_once(']'))
                .and_then(|(i, r)| i.parse::<usize>().ok().map(|i| (i, r)));
            let Some((i, r)) = index else {
                return Err(format!(
                    "'{key}' is not a scene key (an index is written [N], as in effect[0])"
                ));
            };
            steps.push(Step::Index(i));
            rest = r;
        }
    }
    Ok(steps)
}

/// Sets `key` (parsed into `steps`) to `value` in `table`, creating missing tables on the way.
fn set(
    table: &mut toml::Table,
    key: &str,
    steps: &[Step],
    value: toml::Value,
) -> Result<(), String> {
    let mut at = table;
    for (n, step) in steps.iter().enumerate() {
        let last = n + 1 == steps.len();
        let Step::Key(name) = step else {
            unreachable!("a key path starts with a key and indices follow keys");
        };
        // The indices after this key, then the next key.
        let indices: Vec<usize> = steps[n + 1..]
            .iter()
            .map_while(|s| match s {
                Step::Index(i) => Some(*i),
                Step::Key(_) => None,
            })
            .collect();
        if last {
            at.insert(name.clone(), value);
            return Ok(());
        }
        if indices.is_empty() {
            let entry = at
                .entry(name.clone())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            at = entry.as_table_mut().ok_or_else(|| {
                format!("'{key}': the base scene's '{name}' is a value, not a table")
            })?;
            continue;
        }
        let mut value_at = at
            .get_mut(name)
            .ok_or_else(|| format!("'{key}': the base scene has no '{name}' to index"))?;
        let end = n + 1 + indices.len() == steps.len();
        for (j, &i) in indices.iter().enumerate() {
            let array = value_at
                .as_array_mut()
                .ok_or_else(|| format!("'{key}': the base scene's '{name}' is not a list"))?;
            let len = array.len();
            let slot = array.get_mut(i).ok_or_else(|| {
                format!("'{key}': the base scene's '{name}' has {len} entries (indices from 0)")
            })?;
            if end && j + 1 == indices.len() {
                *slot = value;
                return Ok(());
            }
            value_at = slot;
        }
        // Continue into the table the indices reached; the loop skips the index steps.
        return set(
            value_at.as_table_mut().ok_or_else(|| {
                format!("'{key}': the base scene's '{name}' entry is not a table")
            })?,
            key,
            &steps[n + 1 + indices.len()..],
            value,
        );
    }
    Ok(())
}

/// A value as a table cell and a number.
pub(super) fn swept(value: &toml::Value) -> SweptValue {
    let number = match value {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    };
    let text = match value {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    SweptValue { text, number }
}

/// The leaves of `table` under `prefix` as dotted keys: a grid's lists (`lists`) or a set's
/// values.
fn flatten(
    section: &str,
    prefix: &str,
    table: &toml::Table,
    lists: bool,
    out: &mut Vec<(String, toml::Value)>,
) -> Result<(), String> {
    for (k, v) in table {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(t) => flatten(section, &key, t, lists, out)?,
            toml::Value::Array(_) => out.push((key, v.clone())),
            other if !lists => out.push((key, other.clone())),
            other => {
                return Err(format!(
                "{section}.{key} = {other}: a grid key takes a list of values, e.g. {key} = [1, 2]"
            ))
            }
        }
    }
    Ok(())
}

/// The absolute form of a relative file value of `key` (one of [`FILE_KEYS`]) in `table`,
/// against `dir`.
fn absolute_files(table: &mut toml::Table, dir: &Path) {
    for key in FILE_KEYS {
        let steps = parse_key(key).expect("the file keys parse");
        let mut at: Option<&mut toml::Value> = None;
        let mut tab: &mut toml::Table = table;
        for (n, s) in steps.iter().enumerate() {
            let Step::Key(name) = s else { break };
            if n + 1 == steps.len() {
                at = tab.get_mut(name);
                break;
            }
            match tab.get_mut(name).and_then(toml::Value::as_table_mut) {
                Some(t) => tab = t,
                None => break,
            }
        }
        if let Some(toml::Value::String(s)) = at {
            let p = Path::new(s.as_str());
            if p.is_relative() {
                let joined = dir.join(p);
                let abs = std::path::absolute(&joined).unwrap_or(joined);
                if let Some(text) = abs.to_str() {
                    *s = text.to_string();
                }
            }
        }
    }
}

fn input(origin: &str, message: impl std::fmt::Display) -> SweepError {
    SweepError::Input(crate::text::one_line(&format!("{origin}: {message}")))
}

/// A file's text, read as a scene file is (a regular file, of at most the scene size limit).
fn read_text(path: &Path, what: &str) -> Result<String, SweepError> {
    let origin = path.display().to_string();
    if let Some(kind) = crate::scene::not_regular(path) {
        return Err(input(
            &origin,
            format!("the {what} is {kind}, not a regular file"),
        ));
    }
    let limit = crate::limits::Limits::from_env()
        .map_err(|e| SweepError::Input(e.to_string()))?
        .scene_bytes;
    let bytes = std::fs::metadata(path)
        .map_err(|e| input(&origin, format!("cannot read the {what}: {e}")))?
        .len();
    if bytes > limit {
        return Err(input(
            &origin,
            format!("the {what} is larger than {}", crate::limits::bytes(limit)),
        ));
    }
    crate::output::read_regular_string(path)
        .map_err(|e| input(&origin, format!("cannot read the {what}: {e}")))
}

/// Reads, validates and expands the sweep file `path` (docs/scenes.md, "Sweeps"): every grid
/// point's scene parsed and validated and its mesh built. Bad input is one line naming the
/// sweep file and the key and value at fault.
pub fn expand(path: &Path) -> Result<Expanded, SweepError> {
    let origin = path.display().to_string();
    let text = read_text(path, "sweep file")?;
    let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        input(&origin, format!("TOML syntax error: {}", e.message()))
    })?;
    for key in doc.keys() {
        if !matches!(key.as_str(), "sweep" | "grid" | "set") {
            return Err(input(
                &origin,
                format!("unknown section '{key}' (a sweep file has [sweep], [grid] and [set])"),
            ));
        }
    }
    let head = doc
        .get("sweep")
        .and_then(toml::Value::as_table)
        .ok_or_else(|| {
            input(
                &origin,
                "no [sweep] table (its 'scene' names the base scene)",
            )
        })?;
    for (key, value) in head {
        if !matches!(key.as_str(), "scene" | "name") {
            return Err(input(
                &origin,
                format!("unknown key 'sweep.{key}' = {value} (known: scene, name)"),
            ));
        }
    }
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let scene_rel = match head.get("scene") {
        Some(toml::Value::String(s)) if !s.is_empty() => s.clone(),
        Some(other) => {
            return Err(input(
                &origin,
                format!("sweep.scene = {other}: give the base scene's file name"),
            ))
        }
        None => {
            return Err(input(
                &origin,
                "sweep.scene: missing (the base scene's file)",
            ))
        }
    };
    let scene_path: PathBuf = dir.join(&scene_rel);
    let name = match head.get("name") {
        Some(toml::Value::String(s)) if !s.is_empty() && !s.contains(['\n', '\r']) => s.clone(),
        Some(other) => {
            return Err(input(
                &origin,
                format!("sweep.name = {other}: give a one-line name"),
            ))
        }
        None => path
            .file_stem()
            .map_or_else(|| "sweep".into(), |s| s.to_string_lossy().into_owned()),
    };
    // The base scene must stand on its own.
    Scene::load(&scene_path).map_err(|e| {
        input(
            &origin,
            format!(
                "sweep.scene = \"{scene_rel}\": {}",
                crate::text::one_line(&e.to_string())
            ),
        )
    })?;
    let mut base: toml::Table = read_text(&scene_path, "base scene")?
        .parse()
        .map_err(|e: toml::de::Error| input(&origin, format!("sweep.scene: {}", e.message())))?;
    absolute_files(&mut base, scene_path.parent().unwrap_or(Path::new("")));

    let section = |name: &str| -> Result<toml::Table, SweepError> {
        match doc.get(name) {
            None => Ok(toml::Table::new()),
            Some(toml::Value::Table(t)) => Ok(t.clone()),
            Some(other) => Err(input(
                &origin,
                format!("{name} = {other}: expected a table [{name}]"),
            )),
        }
    };
    let mut grid = Vec::new();
    flatten("grid", "", &section("grid")?, true, &mut grid).map_err(|m| input(&origin, m))?;
    let mut fixed = Vec::new();
    flatten("set", "", &section("set")?, false, &mut fixed).map_err(|m| input(&origin, m))?;
    if grid.is_empty() {
        return Err(input(
            &origin,
            "[grid] is empty: give at least one key and its values",
        ));
    }
    let mut keys = Vec::new();
    let mut lists: Vec<Vec<toml::Value>> = Vec::new();
    let mut total: usize = 1;
    for (key, list) in &grid {
        let steps = parse_key(key).map_err(|m| input(&origin, format!("grid: {m}")))?;
        let values = list.as_array().cloned().unwrap_or_default();
        if values.is_empty() {
            return Err(input(
                &origin,
                format!("grid.{key} = []: give at least one value"),
            ));
        }
        let texts: Vec<String> = values.iter().map(|v| swept(v).text).collect();
        if let Some((_, t)) = texts
            .iter()
            .enumerate()
            .find(|(i, t)| texts[..*i].contains(t))
        {
            return Err(input(
                &origin,
                format!("grid.{key}: the value {t} is listed twice"),
            ));
        }
        if fixed.iter().any(|(k, _)| k == key) {
            return Err(input(
                &origin,
                format!("'{key}' is both in [grid] and in [set]"),
            ));
        }
        total = total.saturating_mul(values.len());
        keys.push((key.clone(), steps));
        lists.push(values);
    }
    if total > MAX_POINTS {
        return Err(input(
            &origin,
            format!("[grid] has {total} points, more than {MAX_POINTS}; split the sweep"),
        ));
    }
    let mut fixed_steps = Vec::new();
    for (key, value) in &fixed {
        let steps = parse_key(key).map_err(|m| input(&origin, format!("set: {m}")))?;
        fixed_steps.push((key.clone(), steps, value.clone()));
    }
    let width = total.to_string().len().max(4);
    let mut tasks = Vec::with_capacity(total);
    for n in 0..total {
        // The last key varies fastest.
        let mut choice = vec![0; lists.len()];
        let mut rest = n;
        for k in (0..lists.len()).rev() {
            choice[k] = rest % lists[k].len();
            rest /= lists[k].len();
        }
        let mut table = base.clone();
        for (key, steps, value) in &fixed_steps {
            set(&mut table, key, steps, value.clone())
                .map_err(|m| input(&origin, format!("set {m}")))?;
        }
        let mut values = Vec::new();
        for (k, (key, steps)) in keys.iter().enumerate() {
            let v = lists[k][choice[k]].clone();
            values.push(swept(&v));
            set(&mut table, key, steps, v).map_err(|m| input(&origin, format!("grid {m}")))?;
        }
        absolute_files(&mut table, &dir);
        let id = n + 1;
        let point: Vec<String> = keys
            .iter()
            .zip(&values)
            .map(|((k, _), v)| format!("{k} = {}", v.text))
            .collect();
        let body = toml::to_string(&table)
            .map_err(|e| SweepError::Failure(format!("grid point {id}: {e}")))?;
        let scene_text = format!(
            "# Grid point {id} of the sweep '{name}': {}\n{body}",
            point.join(", ")
        );
        let blame = |e: &SceneError| -> String {
            let at = e.key().unwrap_or("");
            let hit = |k: &str| {
                !at.is_empty()
                    && (at == k
                        || at.starts_with(&format!("{k}."))
                        || at.starts_with(&format!("{k}["))
                        || k.starts_with(&format!("{at}.")))
            };
            if let Some((k, _)) = keys.iter().find(|(k, _)| hit(k)) {
                let v = &values[keys.iter().position(|(x, _)| x == k).unwrap_or(0)];
                format!("grid '{k}' = {}", v.text)
            } else if let Some((k, _, v)) = fixed_steps.iter().find(|(k, _, _)| hit(k)) {
                format!("set '{k}' = {v}")
            } else {
                format!("grid point {id} ({})", point.join(", "))
            }
        };
        let scene = Scene::from_toml_str(&body, "").map_err(|e| {
            input(
                &origin,
                format!("{}: {}", blame(&e), crate::text::one_line(&e.to_string())),
            )
        })?;
        scene.build_mesh().map_err(|e| {
            input(
                &origin,
                format!("{}: {}", blame(&e), crate::text::one_line(&e.to_string())),
            )
        })?;
        tasks.push(Task {
            id,
            dir: format!("run_{id:0width$}"),
            values,
            scene: scene_text,
        });
    }
    Ok(Expanded {
        version: env!("CARGO_PKG_VERSION").to_string(),
        name,
        origin,
        scene: scene_path.display().to_string(),
        keys: keys.into_iter().map(|(k, _)| k).collect(),
        tasks,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_parse_and_set() {
        let mut t: toml::Table =
            "[material]\nk = 0.1\n[[effect]]\ntype = \"gas\"\npressure = \"p\"\n"
                .parse()
                .unwrap();
        let steps = parse_key("effect[0].pressure").unwrap();
        set(
            &mut t,
            "effect[0].pressure",
            &steps,
            toml::Value::Float(1.5),
        )
        .unwrap();
        assert_eq!(t["effect"][0]["pressure"].as_float(), Some(1.5));
        let steps = parse_key("material.k").unwrap();
        set(&mut t, "material.k", &steps, toml::Value::Float(0.2)).unwrap();
        assert_eq!(t["material"]["k"].as_float(), Some(0.2));
        let steps = parse_key("refine.levels").unwrap();
        set(&mut t, "refine.levels", &steps, toml::Value::Integer(1)).unwrap();
        assert_eq!(t["refine"]["levels"].as_integer(), Some(1));
        let steps = parse_key("effect[3].pressure").unwrap();
        let e = set(
            &mut t,
            "effect[3].pressure",
            &steps,
            toml::Value::Float(1.0),
        )
        .unwrap_err();
        assert!(e.contains("has 1 entries"), "{e}");
        assert!(parse_key("material..k").is_err());
        assert!(parse_key("effect[x]").is_err());
    }
}
