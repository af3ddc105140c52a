//! Validation: the values and cross-references of a parsed scene ([`check`]), and the parts
//! that need the mesh ([`check_mesh`]). Each failure is one [`Problem`] naming the key path
//! and the value.

use super::error::{num, Problem};
use super::load::{key_path, RawConstraint};
use super::*;
use std::collections::BTreeSet;

/// Fails unless `x` is finite and > 0.
pub(super) fn positive(key: &str, x: f64) -> Result<(), Problem> {
    in_range(key, x, Range::Positive)
}

/// Fails unless `x` is finite and ≥ 0.
fn non_negative(key: &str, x: f64) -> Result<(), Problem> {
    in_range(key, x, Range::NonNegative)
}

/// Fails unless `x` is finite.
fn finite(key: &str, x: f64) -> Result<(), Problem> {
    in_range(key, x, Range::Finite)
}

/// Fails unless `x` lies in `range` ([`Range::check`]'s wording).
fn in_range(key: &str, x: f64, range: Range) -> Result<(), Problem> {
    range.check(x).map_err(|what| Problem::at(key, what))
}

/// Fails unless the integer `n` is at least `min`.
pub(super) fn at_least(key: &str, n: usize, min: usize) -> Result<(), Problem> {
    if n >= min {
        Ok(())
    } else {
        Err(Problem::at(key, format!("must be >= {min}, got {n}")))
    }
}

fn declared(parameters: &BTreeMap<String, Parameter>) -> String {
    if parameters.is_empty() {
        "no parameters are declared".into()
    } else {
        let names: Vec<&str> = parameters.keys().map(String::as_str).collect();
        format!("declared: {}", names.join(", "))
    }
}

/// Fails unless `name` is a declared parameter; `key` is where it was referenced.
pub(super) fn known_parameter(
    parameters: &BTreeMap<String, Parameter>,
    key: &str,
    name: &str,
) -> Result<(), Problem> {
    if parameters.contains_key(name) {
        Ok(())
    } else {
        Err(Problem::new(
            key,
            format!(
                "'{key}': unknown parameter \"{name}\" ({})",
                declared(parameters)
            ),
        ))
    }
}

/// Resolves the effect each constraint refers to and the parameter it governs.
pub(super) fn resolve_constraints(
    effects: &[Effect],
    parameters: &BTreeMap<String, Parameter>,
    raw: Vec<RawConstraint>,
) -> Result<Vec<Constraint>, Problem> {
    // A target that is neither a number nor "initial" must name a declared parameter.
    let known_target = |path: &str, t: &Target| match t {
        Target::Parameter(name) if !parameters.contains_key(name) => {
            let key = format!("{path}.value");
            Err(Problem::new(
                &key,
                format!(
                    "'{key}': expected a number or \"initial\", got \"{name}\" (or the name of \
                     a declared parameter; {})",
                    declared(parameters)
                ),
            ))
        }
        _ => Ok(()),
    };
    raw.into_iter()
        .map(|c| match c {
            RawConstraint::FluidVolume(r, path) => {
                known_target(&path, &r.value)?;
                let effect = pick_effect(effects, &path, "fluid-volume", "fluid", r.effect)?;
                let fluid = effects[effect]
                    .get::<FluidEffect>()
                    .expect("pick_effect returns a fluid effect");
                let level = governed(&path, "fluid-volume", effect, "level", &fluid.level)?;
                check_target(&path, &r.value, false)?;
                Ok(Constraint::FluidVolume(FluidVolumeConstraint {
                    effect,
                    value: r.value,
                    level,
                }))
            }
            RawConstraint::GasAmount(r, path) => {
                known_target(&path, &r.value)?;
                let effect = pick_effect(effects, &path, "gas-amount", "gas", r.effect)?;
                let gas = effects[effect]
                    .get::<GasEffect>()
                    .expect("pick_effect returns a gas effect");
                let pressure = governed(&path, "gas-amount", effect, "pressure", &gas.pressure)?;
                check_target(&path, &r.value, true)?;
                non_negative(&format!("{path}.ambient-pressure"), r.ambient_pressure)?;
                Ok(Constraint::GasAmount(GasAmountConstraint {
                    effect,
                    value: r.value,
                    ambient_pressure: r.ambient_pressure,
                    pressure,
                }))
            }
            RawConstraint::Fixed(f) => Ok(Constraint::Fixed(f)),
        })
        .collect()
}

/// The index of the effect of type `kind` a constraint at `path` refers to: `given`, or the
/// only one of that type.
fn pick_effect(
    effects: &[Effect],
    path: &str,
    constraint: &str,
    kind: &str,
    given: Option<usize>,
) -> Result<usize, Problem> {
    let candidates: Vec<usize> = (0..effects.len())
        .filter(|&i| effects[i].kind() == kind)
        .collect();
    let listing = || {
        candidates
            .iter()
            .map(|i| format!("effect[{i}]"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match given {
        Some(i) => {
            let key = format!("{path}.effect");
            match effects.get(i) {
                Some(e) if e.kind() == kind => Ok(i),
                Some(e) => Err(Problem::at(
                    &key,
                    format!(
                        "= {i} refers to a {} effect; a {constraint} constraint needs a {kind} \
                         effect{}",
                        e.kind(),
                        if candidates.is_empty() {
                            String::new()
                        } else {
                            format!(" ({})", listing())
                        }
                    ),
                )),
                None => Err(Problem::at(
                    &key,
                    format!(
                        "= {i} is out of range: the scene has {} effects (indices from 0)",
                        effects.len()
                    ),
                )),
            }
        }
        None => match candidates.as_slice() {
            [i] => Ok(*i),
            [] => Err(Problem::new(
                path,
                format!("'{path}' ({constraint}) needs a {kind} effect; the scene has none"),
            )),
            _ => Err(Problem::new(
                &format!("{path}.effect"),
                format!(
                    "'{path}.effect' is required: the scene has several {kind} effects ({})",
                    listing()
                ),
            )),
        },
    }
}

/// The parameter named by the quantity `key` of effect `effect`, which a constraint governs.
fn governed(
    path: &str,
    constraint: &str,
    effect: usize,
    key: &str,
    q: &Quantity,
) -> Result<String, Problem> {
    match q {
        Quantity::Parameter(name) => Ok(name.clone()),
        Quantity::Value(v) => Err(Problem::new(
            path,
            format!(
                "'{path}' ({constraint}) needs 'effect[{effect}].{key}' to be a parameter, got {}",
                num(*v)
            ),
        )),
    }
}

fn check_target(path: &str, t: &Target, must_be_positive: bool) -> Result<(), Problem> {
    match *t {
        Target::Initial | Target::Parameter(_) => Ok(()),
        Target::Value(v) if must_be_positive => positive(&format!("{path}.value"), v),
        Target::Value(v) => finite(&format!("{path}.value"), v),
    }
}

/// Checks the values and cross-references of a parsed scene; normalises plane normals.
pub(super) fn check(scene: &mut Scene) -> Result<(), Problem> {
    if scene.info.name.trim().is_empty() {
        return Err(Problem::at("scene.name", "must not be empty, got \"\""));
    }
    check_mesh_options(&scene.mesh)?;
    check_mesh_radius(scene)?;
    check_material(&scene.material, &scene.parameters)?;
    for (i, effect) in scene.effects.iter_mut().enumerate() {
        check_effect(i, effect, &scene.parameters)?;
    }
    let mut names = BTreeSet::new();
    for (i, name) in scene.boundary.fixed.iter().enumerate() {
        if !names.insert(name) {
            return Err(Problem::at(
                &format!("boundary.fixed[{i}]"),
                format!("lists \"{name}\" a second time"),
            ));
        }
    }
    check_slides(&mut scene.boundary)?;
    check_start(scene)?;
    if let Some(r) = &scene.refine {
        if !(1..=2).contains(&r.levels) {
            return Err(Problem::at(
                "refine.levels",
                format!(
                    "must be 1 (the mesh at twice the divisions) or 2 (at twice and four times), got {}",
                    r.levels
                ),
            ));
        }
    }
    for (name, p) in &scene.parameters {
        check_parameter_name(name)?;
        check_parameter(&key_path("parameters", name), p)?;
    }
    check_parameter_ranges(scene)?;
    check_constraints(scene)?;
    scene.analysis.check(scene)?;
    check_parameter_use(scene)?;
    check_flat_unstretched(scene)?;
    positive("start.stretch", scene.start.stretch)?;
    let held = held_sets(scene);
    if scene.start.stretch != 1.0 && !held.is_empty() {
        return Err(Problem::at(
            "start.stretch",
            format!(
                "= {} would move the fixed or sliding nodes ({}); a clamped membrane starts taut \
                 from material.prestretch and keeps stretch = 1",
                num(scene.start.stretch),
                held.join(", ")
            ),
        ));
    }
    check_enclosure(scene)
}

/// A unit vector from `v` (`key` names it in the message).
fn unit(key: &str, v: [f64; 3]) -> Result<[f64; 3], Problem> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if !(len.is_finite() && len > 0.0) {
        return Err(Problem::at(
            key,
            format!(
                "must be a finite non-zero vector, got [{}, {}, {}]",
                num(v[0]),
                num(v[1]),
                num(v[2])
            ),
        ));
    }
    Ok([v[0] / len, v[1] / len, v[2] / len])
}

/// `[[boundary.slide]]`: normals normalised, each set once and not also fixed.
fn check_slides(boundary: &mut Boundary) -> Result<(), Problem> {
    let mut seen = BTreeSet::new();
    for (i, slide) in boundary.slide.iter_mut().enumerate() {
        let key = format!("boundary.slide[{i}]");
        slide.normal = unit(&format!("{key}.normal"), slide.normal)?;
        if boundary.fixed.contains(&slide.set) {
            return Err(Problem::at(
                &format!("{key}.set"),
                format!(
                    "= \"{}\" is also in boundary.fixed; a node set is fixed or slides",
                    slide.set
                ),
            ));
        }
        if !seen.insert(slide.set.clone()) {
            return Err(Problem::at(
                &format!("{key}.set"),
                format!("= \"{}\" slides a second time", slide.set),
            ));
        }
    }
    Ok(())
}

/// `[start]`: `from` with `point`; `hold-translation` a direction, for a free body only.
fn check_start(scene: &mut Scene) -> Result<(), Problem> {
    let start = &mut scene.start;
    match (&start.from, start.point) {
        (Some(f), None) => {
            return Err(Problem::at(
                "start.from",
                format!(
                    "= \"{}\" needs start.point, the path point (row 'step') to start from",
                    f.display()
                ),
            ))
        }
        (None, Some(n)) => {
            return Err(Problem::at(
                "start.point",
                format!("= {n} needs start.from, the path.json of the run it belongs to"),
            ))
        }
        _ => {}
    }
    if let Some(d) = start.hold_translation {
        start.hold_translation = Some(unit("start.hold-translation", d)?);
        let held = !scene.boundary.fixed.is_empty() || !scene.boundary.slide.is_empty();
        if held {
            return Err(Problem::at(
                "start.hold-translation",
                "is a start for a free body; this scene fixes or slides node sets".to_string(),
            ));
        }
        if start.from.is_some() {
            return Err(Problem::at(
                "start.hold-translation",
                "and start.from exclude each other: a saved state needs no homotopy".to_string(),
            ));
        }
    }
    Ok(())
}

/// A gas amount sharing its enclosure with a fluid needs the fluid's amount: a fluid-volume
/// constraint with a number or a parameter (docs/theory.md §3.5). A filled enclosure has no
/// room for gas.
fn check_enclosure(scene: &Scene) -> Result<(), Problem> {
    let gas = scene
        .effects
        .iter()
        .position(|e| e.get::<GasAmountEffect>().is_some())
        .map(|i| format!("effect[{i}] (gas-amount)"))
        .or_else(|| {
            scene
                .constraints
                .iter()
                .position(|c| matches!(c, Constraint::GasAmount(_)))
                .map(|i| format!("constraint[{i}] (gas-amount)"))
        });
    let inside: Vec<(usize, &FluidEffect)> = scene
        .effects
        .iter()
        .enumerate()
        .filter_map(|(i, e)| {
            e.get::<FluidEffect>()
                .filter(|f| f.side == FluidSide::Inside)
                .map(|f| (i, f))
        })
        .collect();
    let Some(gas) = gas else {
        return Ok(());
    };
    if let Some((i, _)) = inside.iter().find(|(_, f)| f.filled) {
        return Err(Problem::at(
            &format!("effect[{i}].filled"),
            format!("= true leaves no room for the gas of {gas}"),
        ));
    }
    if inside.len() > 1 {
        return Err(Problem::new(
            &format!("effect[{}]", inside[1].0),
            format!(
                "'effect[{}]': {gas} shares the enclosure with one fluid only, this is a second",
                inside[1].0
            ),
        ));
    }
    let Some(&(i, _)) = inside.first() else {
        return Ok(());
    };
    let held = scene.constraints.iter().find_map(|c| match c {
        Constraint::FluidVolume(v) if v.effect == i => Some(&v.value),
        _ => None,
    });
    match held {
        Some(Target::Value(_) | Target::Parameter(_)) => Ok(()),
        Some(Target::Initial) | None => Err(Problem::new(
            &format!("effect[{i}]"),
            format!(
                "'effect[{i}]' (fluid inside) shares the enclosure with {gas}: the gas fills \
                 V - V_f, so the fluid's volume must be known from the start; hold it with a \
                 [[constraint]] type = \"fluid-volume\" whose value is a number or a parameter \
                 (not \"initial\")"
            ),
        )),
    }
}

/// The node sets the boundary holds: the fixed ones and the sliding ones.
fn held_sets(scene: &Scene) -> Vec<&str> {
    scene
        .boundary
        .fixed
        .iter()
        .map(String::as_str)
        .chain(scene.boundary.slide.iter().map(|s| s.set.as_str()))
        .collect()
}

/// `[mesh] radius = "R"`: a declared parameter with positive values (held nodes scale with
/// it, docs/theory.md §2.8).
fn check_mesh_radius(scene: &Scene) -> Result<(), Problem> {
    match &scene.mesh_radius {
        Some(q) => check_quantity("mesh.radius", q, Range::Positive, &scene.parameters),
        None => Ok(()),
    }
}

/// The range of a generated mesh's radius: beyond it a triangle's area (a product of two
/// lengths, normed through their squares) or an enclosed volume leaves the floating-point
/// numbers, and the reference triangles are degenerate.
pub const RADIUS_RANGE: (f64, f64) = (1e-75, 1e75);

pub(super) fn check_mesh_options(mesh: &MeshSpec) -> Result<(), Problem> {
    let radius_rule = |r: f64| {
        positive("mesh.radius", r)?;
        let (lo, hi) = RADIUS_RANGE;
        if r < lo || r > hi {
            return Err(Problem::at(
                "mesh.radius",
                format!(
                    "must lie within [{}, {}]: at {} the mesh's elements are degenerate in floating point (their areas and volumes over- or underflow)",
                    num(lo),
                    num(hi),
                    num(r)
                ),
            ));
        }
        Ok(())
    };
    match mesh {
        MeshSpec::Disc(d) => {
            radius_rule(d.radius)?;
            at_least("mesh.sectors", d.sectors, 3)?;
            at_least("mesh.divisions", d.divisions, 1)?;
        }
        MeshSpec::Icosphere(i) => {
            radius_rule(i.radius)?;
            at_least("mesh.frequency", i.frequency, 1)?;
        }
        MeshSpec::TruncatedSphere(t) => {
            radius_rule(t.radius)?;
            let c = t.cut_height;
            if !(c.is_finite() && c > -t.radius && c < t.radius) {
                return Err(Problem::at(
                    "mesh.cut-height",
                    format!(
                        "must lie strictly between -radius and radius ({}, {}), got {}",
                        num(-t.radius),
                        num(t.radius),
                        num(c)
                    ),
                ));
            }
            if let Some(d) = t.divisions {
                at_least("mesh.divisions", d, 1)?;
            }
        }
        MeshSpec::Axisymmetric(a) => {
            radius_rule(a.radius)?;
            at_least("mesh.elements", a.elements, 1)?;
            if a.elements > 4096 {
                return Err(Problem::at(
                    "mesh.elements",
                    format!("must be <= 4096, got {}", a.elements),
                ));
            }
            if a.modes > 200 {
                return Err(Problem::at(
                    "mesh.modes",
                    format!("must be <= 200, got {}", a.modes),
                ));
            }
            let c = a.cut_height;
            if a.shape == AxisymShape::TruncatedSphere
                && !(c.is_finite() && c > -a.radius && c < a.radius)
            {
                return Err(Problem::at(
                    "mesh.cut-height",
                    format!(
                        "must lie strictly between -radius and radius ({}, {}), got {}",
                        num(-a.radius),
                        num(a.radius),
                        num(c)
                    ),
                ));
            }
        }
        MeshSpec::File(f) => {
            if f.path.as_os_str().is_empty() {
                return Err(Problem::at("mesh.path", "must name a mesh file, got \"\""));
            }
            // The name only: building a large group here would take the time the limits
            // (checked when the study is built) are there to refuse.
            if symmetry::Group::order_of(&f.group).is_none() {
                let e = symmetry::GroupError::UnknownName(f.group.clone());
                return Err(Problem::at("mesh.group", format!("= \"{}\": {e}", f.group)));
            }
        }
    }
    Ok(())
}

fn check_material(m: &Material, parameters: &BTreeMap<String, Parameter>) -> Result<(), Problem> {
    for (key, q, range) in m.ruled_quantities() {
        check_quantity(&format!("material.{key}"), q, range, parameters)?;
    }
    if let Some(max) = m.max_stretch {
        if !(max.is_finite() && max > 1.0) {
            return Err(Problem::at(
                "material.max-stretch",
                format!("must be a finite number > 1, got {}", num(max)),
            ));
        }
    }
    if let Some(eps) = m.wrinkling_stiffness {
        let key = "material.wrinkling-stiffness";
        if m.wrinkling != super::Wrinkling::Relaxed {
            return Err(Problem::at(
                key,
                format!("= {}: needs wrinkling = \"relaxed\"", num(eps)),
            ));
        }
        if !(eps.is_finite() && (0.0..=1.0).contains(&eps)) {
            return Err(Problem::at(
                key,
                format!("must be between 0 and 1, got {}", num(eps)),
            ));
        }
    }
    if let Some(width) = m.wrinkling_width {
        let key = "material.wrinkling-width";
        if m.wrinkling != super::Wrinkling::Relaxed {
            return Err(Problem::at(
                key,
                format!("= {}: needs wrinkling = \"relaxed\"", num(width)),
            ));
        }
        if !(width.is_finite() && (0.0..=0.1).contains(&width)) {
            return Err(Problem::at(
                key,
                format!("must be between 0 and 0.1, got {}", num(width)),
            ));
        }
    }
    Ok(())
}

/// A quantity names a declared parameter, or its value lies in its range.
fn check_quantity(
    key_path: &str,
    q: &Quantity,
    range: Range,
    parameters: &BTreeMap<String, Parameter>,
) -> Result<(), Problem> {
    match q {
        Quantity::Parameter(name) => known_parameter(parameters, key_path, name),
        Quantity::Value(v) => in_range(key_path, *v, range),
    }
}

fn check_effect(
    i: usize,
    effect: &mut Effect,
    parameters: &BTreeMap<String, Parameter>,
) -> Result<(), Problem> {
    let path = format!("effect[{i}]");
    for (key, q, range) in effect.ruled_quantities() {
        check_quantity(&format!("{path}.{key}"), q, range, parameters)?;
    }
    effect
        .spec_mut()
        .check()
        .map_err(|r| Problem::at(&format!("{path}.{}", r.key), r.what))
}

/// The columns of `path.csv` besides the parameters: no parameter may take their names.
const COLUMNS: [&str; 12] = [
    "step",
    "arclength",
    "iterations",
    "index",
    "max_displacement",
    "min_z",
    "max_z",
    "volume",
    "stretch",
    "fluid_volume",
    "wrinkled_area",
    "slack_area",
];

/// A parameter's name is an identifier (a letter or `_`, then letters, digits, `_` or `-`,
/// at most 64 characters) and not a column of `path.csv`.
fn check_parameter_name(name: &str) -> Result<(), Problem> {
    let key = key_path("parameters", name);
    let shown: String = name.chars().take(64).collect();
    let mut chars = name.chars();
    let identifier = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        && name.len() <= 64;
    if !identifier {
        return Err(Problem::new(
            "parameters",
            format!(
                "'parameters': the name {shown:?} is not an identifier (a letter or '_', then \
                 letters, digits, '_' or '-'; at most 64 characters)"
            ),
        ));
    }
    if COLUMNS.contains(&name) || name.starts_with("fluid_volume_") {
        return Err(Problem::new(
            &key,
            format!("'{key}': \"{name}\" is a column of path.csv; choose another name"),
        ));
    }
    Ok(())
}

/// A parameter that feeds a quantity with a range (a density ≥ 0, an amount of gas > 0)
/// keeps its start and bounds in that range.
fn check_parameter_ranges(scene: &Scene) -> Result<(), Problem> {
    for (key, q, range) in scene.quantities() {
        let Some(name) = q.parameter() else { continue };
        let Some(p) = scene.parameters.get(name) else {
            continue;
        };
        let pkey = key_path("parameters", name);
        let check = |field: &str, v: f64| -> Result<(), Problem> {
            let (ok, what) = match range {
                Range::Finite => (true, ""),
                Range::NonNegative => (v >= 0.0, ">= 0"),
                Range::Positive => (v > 0.0, "> 0"),
            };
            if ok {
                return Ok(());
            }
            Err(Problem::at(
                &format!("{pkey}.{field}"),
                format!("must be {what} (it is {key}), got {}", num(v)),
            ))
        };
        check("start", p.start)?;
        if let Some(min) = p.min {
            check("min", min)?;
        }
    }
    Ok(())
}

/// A flat disc (3-D or a meridian) without pre-stretch under a load normal to it (gas or
/// fluid): its tangent is singular at the flat start, which carries no such load — refused
/// on both models alike, unless the start is a saved state.
fn check_flat_unstretched(scene: &Scene) -> Result<(), Problem> {
    let flat = match &scene.mesh {
        MeshSpec::Disc(_) => true,
        MeshSpec::Axisymmetric(a) => a.shape == AxisymShape::Disc,
        _ => false,
    };
    let normal = scene.effects.iter().any(|e| e.spec().presses_normally());
    if !flat || !normal || scene.start.from.is_some() {
        return Ok(());
    }
    let stretch = scene.start_value(&scene.material.prestretch);
    if stretch != 1.0 {
        return Ok(());
    }
    let value = match &scene.material.prestretch {
        Quantity::Value(_) => "1".to_string(),
        Quantity::Parameter(n) => format!("\"{n}\" (start 1)"),
    };
    Err(Problem::new(
        "material.prestretch",
        format!(
            "'material.prestretch' = {value} on a flat disc: without pre-stretch a flat \
             membrane has no stiffness against the pressure normal to it (its tangent is \
             singular at the flat start); give a pre-stretch > 1 (e.g. 1.1)"
        ),
    ))
}

/// The largest magnitude of a parameter's bound: beyond it the arithmetic of a sweep or a
/// step over the range (its width times a fraction, squared in a norm) overflows.
pub const MAX_BOUND: f64 = 1e150;

fn check_parameter(key: &str, p: &Parameter) -> Result<(), Problem> {
    finite(&format!("{key}.start"), p.start)?;
    if let Some(min) = p.min {
        finite(&format!("{key}.min"), min)?;
    }
    if let Some(max) = p.max {
        finite(&format!("{key}.max"), max)?;
    }
    if let (Some(min), Some(max)) = (p.min, p.max) {
        if !(max - min).is_finite() {
            return Err(Problem::at(
                &format!("{key}.max"),
                format!(
                    "- min overflows ({} - {}): the range must have a finite width",
                    num(max),
                    num(min)
                ),
            ));
        }
    }
    for (field, bound) in [("min", p.min), ("max", p.max)] {
        let Some(b) = bound else { continue };
        let k = format!("{key}.{field}");
        if b.abs() > MAX_BOUND {
            return Err(Problem::at(
                &k,
                format!(
                    "must lie within [-{m}, {m}] (the arithmetic over the range overflows beyond), got {}",
                    num(b),
                    m = num(MAX_BOUND)
                ),
            ));
        }
    }
    if let (Some(min), Some(max)) = (p.min, p.max) {
        if min >= max {
            return Err(Problem::at(
                &format!("{key}.min"),
                format!("must be < max = {}, got {}", num(max), num(min)),
            ));
        }
    }
    let below = p.min.is_some_and(|m| p.start < m);
    let above = p.max.is_some_and(|m| p.start > m);
    if below || above {
        let show = |b: Option<f64>, inf: &str| b.map_or_else(|| inf.to_string(), num);
        return Err(Problem::at(
            &format!("{key}.start"),
            format!(
                "must lie within [min, max] = [{}, {}], got {}",
                show(p.min, "-inf"),
                show(p.max, "inf"),
                num(p.start)
            ),
        ));
    }
    Ok(())
}

fn check_constraints(scene: &Scene) -> Result<(), Problem> {
    let mut governed: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, c) in scene.constraints.iter().enumerate() {
        let path = format!("constraint[{i}]");
        let name = c.parameter();
        let key = match c {
            Constraint::Fixed(_) => format!("{path}.parameter"),
            _ => path.clone(),
        };
        known_parameter(&scene.parameters, &key, name)?;
        let target = match c {
            Constraint::FluidVolume(v) => v.value.parameter(),
            Constraint::GasAmount(g) => g.value.parameter(),
            Constraint::Fixed(_) => None,
        };
        if let Some(t) = target {
            let key = format!("{path}.value");
            if t == name {
                return Err(Problem::at(
                    &key,
                    format!("= \"{t}\" is the parameter this constraint governs"),
                ));
            }
        }
        if let Some(j) = governed.insert(name, i) {
            return Err(Problem::new(
                &key,
                format!(
                    "'{key}' ({}) governs parameter \"{name}\", which constraint[{j}] \
                     ({}) already governs",
                    c.kind(),
                    scene.constraints[j].kind()
                ),
            ));
        }
    }
    Ok(())
}

/// A declared parameter that no constraint governs (a path's free parameter).
pub(super) fn free_parameter(scene: &Scene, key: &str, name: &str) -> Result<(), Problem> {
    known_parameter(&scene.parameters, key, name)?;
    if let Some((i, c)) = scene
        .constraints
        .iter()
        .enumerate()
        .find(|(_, c)| c.parameter() == name)
    {
        return Err(Problem::at(
            key,
            format!(
                "= \"{name}\" is governed by constraint[{i}] ({}); it must be free",
                c.kind()
            ),
        ));
    }
    Ok(())
}

/// Every declared parameter is used by an effect; on a path, every parameter but the control
/// is governed by a constraint.
fn check_parameter_use(scene: &Scene) -> Result<(), Problem> {
    let used: BTreeSet<&str> = scene
        .quantities()
        .into_iter()
        .filter_map(|(_, q, _)| q.parameter())
        .chain(scene.constraints.iter().filter_map(|c| match c {
            Constraint::FluidVolume(v) => v.value.parameter(),
            Constraint::GasAmount(g) => g.value.parameter(),
            Constraint::Fixed(_) => None,
        }))
        .collect();
    for name in scene.parameters.keys() {
        let key = key_path("parameters", name);
        if !used.contains(name.as_str()) {
            return Err(Problem::at(
                &key,
                format!(
                    "is declared but no quantity uses it (give a quantity of the material or an effect as \"{name}\")"
                ),
            ));
        }
        let Some(free) = scene.analysis.spec().free() else {
            continue;
        };
        if !free.contains(&name.as_str()) && scene.governing(name).is_none() {
            let free = match free.as_slice() {
                [control] => format!("the control (\"{control}\")"),
                _ => format!("a free parameter (\"{}\")", free.join("\", \"")),
            };
            return Err(Problem::at(
                &key,
                format!(
                    "is neither {free} nor governed by a constraint; \
                     hold it with [[constraint]] type = \"fixed\", parameter = \"{name}\""
                ),
            ));
        }
    }
    Ok(())
}

/// The checks that need the mesh (see [`Scene::check_mesh`]).
pub(super) fn check_mesh(scene: &Scene, sym: &SymmetricMesh) -> Result<(), Problem> {
    let mesh = &sym.mesh;
    // "the disc mesh", "the mesh in 'disc.msh'".
    let the_mesh = scene.mesh.describe();
    let sets = scene
        .boundary
        .fixed
        .iter()
        .enumerate()
        .map(|(i, n)| (format!("boundary.fixed[{i}]"), n))
        .chain(
            scene
                .boundary
                .slide
                .iter()
                .enumerate()
                .map(|(i, s)| (format!("boundary.slide[{i}].set"), &s.set)),
        );
    for (key, name) in sets {
        if !mesh.boundaries.contains_key(name) {
            let available: Vec<&str> = mesh.boundaries.keys().map(String::as_str).collect();
            let has = if available.is_empty() {
                format!("{the_mesh} has no node sets")
            } else {
                format!("{the_mesh} has: {}", available.join(", "))
            };
            return Err(Problem::new(
                &key,
                format!("'{key}': unknown node set \"{name}\" ({has})"),
            ));
        }
    }
    let topology = mesh
        .topology()
        .map_err(|e| Problem::new("mesh", format!("'mesh' ({}): {e}", scene.mesh.generator())))?;
    let mut fixed: BTreeSet<usize> = scene.fixed_nodes(sym).into_iter().collect();
    if !mesh.nodes.is_empty() && fixed.len() == mesh.nodes.len() {
        let names: Vec<String> = scene
            .boundary
            .fixed
            .iter()
            .map(|n| format!("\"{n}\""))
            .collect();
        return Err(Problem::new(
            "boundary.fixed",
            format!(
                "'boundary.fixed' = [{}] fixes every one of the {} nodes of {the_mesh}: no unknown is left to solve for; fix only the supported nodes",
                names.join(", "),
                mesh.nodes.len()
            ),
        ));
    }
    fixed.extend(scene.sliding_nodes(sym).into_iter().map(|(i, _)| i));
    let rim: BTreeSet<usize> = topology.boundary_loops.iter().flatten().copied().collect();
    let loose = rim.difference(&fixed).count();
    for (i, effect) in scene.effects.iter().enumerate() {
        let path = format!("effect[{i}]");
        if effect.encloses() && !topology.closed && loose > 0 {
            return Err(Problem::new(
                &path,
                format!(
                    "'{path}' ({}) needs a closed membrane or a fixed rim, but {loose} of the {} \
                     rim nodes of {the_mesh} are not in boundary.fixed (or boundary.slide)",
                    effect.kind(),
                    rim.len()
                ),
            ));
        }
        effect
            .spec()
            .check_mesh(topology.closed, &the_mesh)
            .map_err(|r| Problem::at(&format!("{path}.{}", r.key), r.what))?;
    }
    scene.analysis.spec().check_mesh(topology.closed, &the_mesh)
}
