//! The layers of the crate (docs/architecture.md) are one-way: every module imports only
//! modules of its own layer or of layers below it, read from the `crate::` paths of every
//! source file (comments excluded); the writers import no model, analysis or study; and the
//! analysis types' keys are named only in the scene and in the analyses.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The layers, bottom up (docs/architecture.md): a module may use its own layer and those
/// below.
const LAYERS: &[&[&str]] = &[
    &["text", "limits", "reference"],
    &["linalg", "results"],
    &["model"],
    &["continuation"],
    &["effects", "axisym"],
    &["scene"],
    &["adapted", "stability", "output"],
    &["study"],
    &["analysis"],
    &["bench", "demo", "sweep"],
];

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a source file belongs to (`src/analysis/curve.rs` → `analysis`).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// The code of a line without its comment (a `//` outside a string literal).
fn code(line: &str) -> &str {
    let mut in_string = false;
    let bytes = line.as_bytes();
    for i in 0..bytes.len() {
        match bytes[i] {
            b'"' if i == 0 || bytes[i - 1] != b'\\' => in_string = !in_string,
            b'/' if !in_string && bytes.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
    }
    line
}

/// Every (file, line, module imported) of the crate's own `crate::x` paths, by the importing
/// top-level module.
fn imports() -> BTreeMap<String, Vec<(PathBuf, usize, String)>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut out: BTreeMap<String, Vec<(PathBuf, usize, String)>> = BTreeMap::new();
    for file in files {
        let module = module_of(&src, &file);
        let text = std::fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            let line = code(line);
            let mut rest = line;
            while let Some(at) = rest.find("crate::") {
                let after = &rest[at + "crate::".len()..];
                let name: String = after
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                let qualified = at >= 2 && &rest[at - 2..at] == "::";
                if !qualified && !name.is_empty() {
                    out.entry(module.clone())
                        .or_default()
                        .push((file.clone(), n + 1, name));
                }
                rest = after;
            }
        }
    }
    out
}

#[test]
fn every_module_imports_only_its_own_layer_or_those_below() {
    let mut wrong = Vec::new();
    for (module, uses) in imports() {
        if matches!(module.as_str(), "lib" | "main" | "cli") {
            continue;
        }
        let Some(own) = layer(&module) else {
            panic!("module {module} is in no layer of docs/architecture.md");
        };
        for (file, line, used) in uses {
            let Some(theirs) = layer(&used) else {
                panic!("{}:{line}: crate::{used} is in no layer", file.display());
            };
            if theirs > own {
                wrong.push(format!(
                    "{}:{line}: {module} (layer {own}) uses {used} (layer {theirs})",
                    file.display()
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports of a higher layer:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_writers_import_no_model_analysis_or_study() {
    let uses = imports();
    let bad: Vec<String> = uses
        .get("output")
        .into_iter()
        .flatten()
        .filter(|(_, _, used)| matches!(used.as_str(), "model" | "analysis" | "study"))
        .map(|(file, line, used)| format!("{}:{line}: crate::{used}", file.display()))
        .collect();
    assert!(bad.is_empty(), "writers that reach into a model: {bad:?}");
}

/// The analysis types' keys (`src/scene/analyses/`) are named only by the scene and by the
/// analyses that run them: no study, writer, benchmark or command dispatches on them (the
/// analyses write and summarise their own results through their trait).
#[test]
fn the_analysis_types_are_named_only_in_the_scene_and_the_analyses() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut keys = Vec::new();
    sources(&src.join("scene").join("analyses"), &mut keys);
    let types: Vec<String> = keys
        .iter()
        .flat_map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            text.lines()
                .filter_map(|l| l.strip_prefix("pub struct "))
                .map(|l| l.split([' ', '{', '(']).next().unwrap().to_string())
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(
        types.iter().any(|t| t == "PathAnalysis") && types.len() >= 6,
        "the analysis types were not found: {types:?}"
    );
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut found = Vec::new();
    for file in files {
        let rel = file
            .strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .to_string();
        if rel.starts_with("scene") || rel.starts_with("analysis") {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if let Some(t) = types.iter().find(|t| code(line).contains(t.as_str())) {
                found.push(format!("{rel}:{} ({t})", n + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "analysis types named outside the scene and the analyses: {found:?}"
    );
}
