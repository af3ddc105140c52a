//! Gmsh MSH 4.1 ascii, as [`crate::write`] writes it (see `write/gmsh.rs` and the Gmsh
//! reference manual, section "MSH file format").
//!
//! The file is a sequence of sections `$Name` … `$EndName`. Read are:
//! - `$MeshFormat` (required first): version 4.1, file-type 0 (ascii); binary MSH is refused
//!   because our writer never emits it.
//! - `$Nodes`: `numEntityBlocks numNodes minNodeTag maxNodeTag`, then per block
//!   `entityDim entityTag parametric numNodesInBlock`, the block's node tags one per line, then
//!   its coordinate lines `x y z` (plus the parametric coordinates when `parametric` is 1,
//!   which are dropped). Nodes are numbered in file order; tags are only looked up.
//! - `$Elements`: the same header, per block `entityDim entityTag elementType
//!   numElementsInBlock` and lines `elementTag n1 n2 …`. Blocks of 3-node triangles (type 2)
//!   are read; blocks of dimension 0 or 1 (points, lines on curves) are skipped; anything else
//!   is an error that names the element type.
//! - `$NodeData`: a field per section (string tag = name, real tag = time, integer tags = time
//!   step, components, count), then `nodeTag value…` lines. Only scalar fields named
//!   `set_<name>` are kept: they are the node sets (nodes not listed are not in the set).
//!
//! Every other section (`$Entities`, `$PhysicalNames`, `$ElementData`, comments …) is skipped
//! up to its `$End` line, as the manual asks of readers. Counts are checked against what
//! follows, so a wrong count surfaces as an error at the line where the data stop matching.

use super::{distinct, finite_node, Parts};
use crate::mesh::{Mesh, Vec3};
use std::collections::HashMap;
use std::str::FromStr;

/// Gmsh element type of the 3-node triangle.
const TRIANGLE: usize = 2;

/// Parses a whole `.msh` text.
pub(super) fn parse(text: &str) -> Result<Mesh, String> {
    let mut lines = Lines::new(text);
    let mut parts = Parts::default();
    // Node tag → node index, once `$Nodes` has been read.
    let mut tags: Option<HashMap<usize, usize>> = None;
    let mut seen_format = false;
    let mut seen_elements = false;
    while let Some((no, line)) = lines.next_nonblank() {
        let Some(name) = line.strip_prefix('$') else {
            return Err(format!(
                "line {no}: expected a section header such as $Nodes, got {}",
                quote(line)
            ));
        };
        if !seen_format && name != "MeshFormat" {
            return Err(format!(
                "line {no}: expected $MeshFormat first (is this a Gmsh .msh file?), got {}",
                quote(line)
            ));
        }
        match name {
            "MeshFormat" => {
                if seen_format {
                    return Err(format!("line {no}: a second $MeshFormat section"));
                }
                read_format(&mut lines)?;
                seen_format = true;
            }
            "Nodes" => {
                if tags.is_some() {
                    return Err(format!("line {no}: a second $Nodes section"));
                }
                tags = Some(read_nodes(&mut lines, &mut parts.nodes)?);
            }
            "Elements" => {
                let Some(tags) = &tags else {
                    return Err(format!("line {no}: $Elements before $Nodes"));
                };
                if seen_elements {
                    return Err(format!("line {no}: a second $Elements section"));
                }
                read_elements(&mut lines, tags, &mut parts.triangles)?;
                seen_elements = true;
            }
            "NodeData" => {
                let Some(tags) = &tags else {
                    return Err(format!("line {no}: $NodeData before $Nodes"));
                };
                read_node_data(&mut lines, no, tags, &mut parts)?;
            }
            _ => {
                skip_section(&mut lines, no, name)?;
                continue;
            }
        }
        lines.expect_end(name)?;
    }
    if !seen_format {
        return Err("the file is empty (expected $MeshFormat)".into());
    }
    if tags.is_none() {
        return Err("no $Nodes section".into());
    }
    if !seen_elements {
        return Err("no $Elements section".into());
    }
    parts.into_mesh()
}

/// `$MeshFormat`: `4.1 0 8`.
fn read_format(lines: &mut Lines<'_>) -> Result<(), String> {
    let (no, line) = lines.expect("the format line 'version file-type data-size'")?;
    let words: Vec<&str> = line.split_ascii_whitespace().collect();
    let [version, file_type, _data_size] = words.as_slice() else {
        return Err(format!(
            "line {no}: expected 'version file-type data-size' (4.1 0 8), got {}",
            quote(line)
        ));
    };
    if *version != "4.1" {
        return Err(format!(
            "line {no}: MSH version {version} is not supported; only 4.1 is read"
        ));
    }
    match *file_type {
        "0" => Ok(()),
        "1" => Err(format!(
            "line {no}: binary MSH is not supported; only ascii (file-type 0) is read"
        )),
        other => Err(format!(
            "line {no}: file-type {other} is neither 0 (ascii) nor 1 (binary)"
        )),
    }
}

/// `$Nodes`: appends the coordinates to `nodes` and returns the tag of each node.
fn read_nodes(
    lines: &mut Lines<'_>,
    nodes: &mut Vec<Vec3>,
) -> Result<HashMap<usize, usize>, String> {
    let [blocks, total, _, _] =
        lines.numbers::<usize, 4>("the $Nodes header 'numEntityBlocks numNodes minTag maxTag'")?;
    let mut tags = HashMap::new();
    for _ in 0..blocks {
        let (no, [dim, _, parametric, count]) = lines.numbers_at::<usize, 4>(
            "a node block header 'entityDim entityTag parametric numNodesInBlock'",
        )?;
        if dim > 3 || parametric > 1 {
            return Err(format!(
                "line {no}: a node block needs entityDim 0 to 3 and parametric 0 or 1, got \
                 {dim} and {parametric}"
            ));
        }
        // Parametric nodes carry `dim` parametric coordinates after x y z.
        let extra = parametric * dim;
        let first = nodes.len();
        let mut block_tags = Vec::new();
        for _ in 0..count {
            let (no, [tag]) = lines.numbers_at::<usize, 1>("a node tag")?;
            block_tags.push((no, tag));
        }
        for k in 0..count {
            let (no, line) = lines.expect("a coordinate line 'x y z'")?;
            let values = parse_all::<f64>(line)
                .filter(|v| v.len() == 3 + extra)
                .ok_or_else(|| {
                    format!(
                        "line {no}: expected {} numbers for node {} of the block ('x y z'{}), \
                         got {}",
                        3 + extra,
                        k + 1,
                        if extra > 0 {
                            " and parametric coordinates"
                        } else {
                            ""
                        },
                        quote(line)
                    )
                })?;
            let x = Vec3::new(values[0], values[1], values[2]);
            finite_node(&x, &format!("line {no}"))?;
            nodes.push(x);
        }
        for (k, (no, tag)) in block_tags.into_iter().enumerate() {
            if tags.insert(tag, first + k).is_some() {
                return Err(format!("line {no}: node tag {tag} is used twice"));
            }
        }
    }
    if nodes.len() != total {
        return Err(format!(
            "line {}: the $Nodes header announces {total} nodes, the blocks hold {}",
            lines.no,
            nodes.len()
        ));
    }
    Ok(tags)
}

/// `$Elements`: appends the triangles to `triangles`; skips blocks of points and lines.
fn read_elements(
    lines: &mut Lines<'_>,
    tags: &HashMap<usize, usize>,
    triangles: &mut Vec<[usize; 3]>,
) -> Result<(), String> {
    let [blocks, total, _, _] = lines
        .numbers::<usize, 4>("the $Elements header 'numEntityBlocks numElements minTag maxTag'")?;
    let mut read = 0usize;
    for _ in 0..blocks {
        let (no, [dim, _, kind, count]) = lines.numbers_at::<usize, 4>(
            "an element block header 'entityDim entityTag elementType numElementsInBlock'",
        )?;
        read = read.saturating_add(count);
        if kind != TRIANGLE {
            if dim >= 2 {
                return Err(format!(
                    "line {no}: element type {kind}{} in a {dim}-D block; only 3-node triangles \
                     (type 2) are read",
                    element_name(kind)
                ));
            }
            for _ in 0..count {
                lines.expect("an element line")?;
            }
            continue;
        }
        for _ in 0..count {
            let (no, [_, a, b, c]) =
                lines.numbers_at::<usize, 4>("a triangle line 'elementTag n1 n2 n3'")?;
            let mut tri = [0; 3];
            for (slot, tag) in tri.iter_mut().zip([a, b, c]) {
                *slot = *tags
                    .get(&tag)
                    .ok_or_else(|| format!("line {no}: node tag {tag} is not in $Nodes"))?;
            }
            distinct(&tri, &format!("line {no}"))?;
            triangles.push(tri);
        }
    }
    if read != total {
        return Err(format!(
            "line {}: the $Elements header announces {total} elements, the blocks hold {read}",
            lines.no
        ));
    }
    Ok(())
}

/// `$NodeData` (opened at line `start`): keeps the field if it is a node set.
fn read_node_data(
    lines: &mut Lines<'_>,
    start: usize,
    tags: &HashMap<usize, usize>,
    parts: &mut Parts,
) -> Result<(), String> {
    let [strings] = lines.numbers::<usize, 1>("the number of string tags")?;
    let mut name = None;
    for _ in 0..strings {
        let (_, line) = lines.expect("a string tag")?;
        name.get_or_insert_with(|| line.trim().trim_matches('"').to_string());
    }
    let [reals] = lines.numbers::<usize, 1>("the number of real tags")?;
    for _ in 0..reals {
        lines.numbers::<f64, 1>("a real tag")?;
    }
    let (no, [integers]) = lines.numbers_at::<usize, 1>("the number of integer tags")?;
    if integers < 3 {
        return Err(format!(
            "line {no}: $NodeData needs 3 integer tags (time step, components, count), got \
             {integers}"
        ));
    }
    lines.numbers::<i64, 1>("the time step")?;
    let [components] = lines.numbers::<usize, 1>("the number of components")?;
    let [count] = lines.numbers::<usize, 1>("the number of values")?;
    for _ in 3..integers {
        lines.numbers::<i64, 1>("an integer tag")?;
    }
    let name = name.unwrap_or_default();
    let place = format!("$NodeData at line {start}");
    let is_set = name.starts_with(super::NODE_SET_PREFIX);
    if is_set && components != 1 {
        return Err(format!(
            "{place}: node set field \"{name}\" has {components} components, expected 1"
        ));
    }
    let mut values = vec![0.0; if is_set { tags.len() } else { 0 }];
    let mut listed = vec![false; values.len()];
    for _ in 0..count {
        let (no, line) = lines.expect("a value line 'nodeTag value…'")?;
        let words = parse_all::<f64>(line)
            .filter(|v| v.len() == 1 + components)
            .ok_or_else(|| {
                format!(
                    "line {no}: expected a node tag and {components} value(s), got {}",
                    quote(line)
                )
            })?;
        if !is_set {
            continue;
        }
        let tag = words[0];
        let node = (tag >= 0.0 && tag.fract() == 0.0)
            .then(|| tags.get(&(tag as usize)))
            .flatten()
            .copied()
            .ok_or_else(|| format!("line {no}: node tag {tag} is not in $Nodes"))?;
        if std::mem::replace(&mut listed[node], true) {
            return Err(format!("line {no}: node tag {tag} is listed twice"));
        }
        values[node] = words[1];
    }
    parts.add_point_field(&name, &place, values)
}

/// Skips an unknown section opened at line `start` up to its `$End` line.
fn skip_section(lines: &mut Lines<'_>, start: usize, name: &str) -> Result<(), String> {
    let end = format!("$End{name}");
    while let Some((_, line)) = lines.next_line() {
        if line.trim() == end {
            return Ok(());
        }
    }
    Err(format!(
        "the section ${name} opened at line {start} has no {end}"
    ))
}

/// A few element types by name, for messages.
fn element_name(kind: usize) -> &'static str {
    match kind {
        1 => " (2-node line)",
        3 => " (4-node quadrangle)",
        4 => " (4-node tetrahedron)",
        5 => " (8-node hexahedron)",
        6 => " (6-node prism)",
        7 => " (5-node pyramid)",
        9 => " (6-node triangle)",
        10 => " (9-node quadrangle)",
        15 => " (1-node point)",
        16 => " (8-node quadrangle)",
        _ => "",
    }
}

/// All words of `line` parsed as `T`, or `None` if one does not parse.
fn parse_all<T: FromStr>(line: &str) -> Option<Vec<T>> {
    line.split_ascii_whitespace()
        .map(|w| w.parse().ok())
        .collect()
}

/// A line as it appears in messages: quoted, cut at 60 characters.
fn quote(line: &str) -> String {
    let line = line.trim();
    if line.is_empty() {
        return "an empty line".into();
    }
    let short: String = line.chars().take(60).collect();
    if short.len() < line.len() {
        format!("'{short}…'")
    } else {
        format!("'{short}'")
    }
}

/// The lines of the file with their 1-based numbers.
struct Lines<'a> {
    inner: std::str::Lines<'a>,
    /// Number of the last line returned (0 before the first).
    no: usize,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Self {
        Self {
            inner: text.lines(),
            no: 0,
        }
    }

    fn next_line(&mut self) -> Option<(usize, &'a str)> {
        let line = self.inner.next()?;
        self.no += 1;
        Some((self.no, line))
    }

    fn next_nonblank(&mut self) -> Option<(usize, &'a str)> {
        loop {
            let (no, line) = self.next_line()?;
            if !line.trim().is_empty() {
                return Some((no, line.trim()));
            }
        }
    }

    /// The next non-blank line, which must exist; `what` names it in the error.
    fn expect(&mut self, what: &str) -> Result<(usize, &'a str), String> {
        self.next_nonblank()
            .ok_or_else(|| format!("line {}: the file ends where {what} was expected", self.no))
    }

    /// The next line as exactly `N` numbers of type `T`, with its number.
    fn numbers_at<T: FromStr + Copy + Default, const N: usize>(
        &mut self,
        what: &str,
    ) -> Result<(usize, [T; N]), String> {
        let (no, line) = self.expect(what)?;
        let mut out = [T::default(); N];
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let ok = words.len() == N
            && words
                .iter()
                .zip(out.iter_mut())
                .all(|(w, slot)| w.parse().map(|v| *slot = v).is_ok());
        if ok {
            Ok((no, out))
        } else {
            Err(format!("line {no}: expected {what}, got {}", quote(line)))
        }
    }

    /// The next line as exactly `N` numbers of type `T`.
    fn numbers<T: FromStr + Copy + Default, const N: usize>(
        &mut self,
        what: &str,
    ) -> Result<[T; N], String> {
        self.numbers_at(what).map(|(_, v)| v)
    }

    /// The next line must close section `name`.
    fn expect_end(&mut self, name: &str) -> Result<(), String> {
        let end = format!("$End{name}");
        match self.next_nonblank() {
            Some((_, line)) if line == end => Ok(()),
            Some((no, line)) => Err(format!(
                "line {no}: expected {end}, got {} (does a count in ${name} not match the data?)",
                quote(line)
            )),
            None => Err(format!(
                "line {}: the file ends inside ${name} (expected {end})",
                self.no
            )),
        }
    }
}
