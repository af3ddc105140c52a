//! Rungs of critical points and their images on the other meshes, measured.

use super::{MeshRuns, Point, Unmatched, MATCH_TOLERANCE, PAIR_TOLERANCE, ROUND_OFF};
use crate::results::CriticalKind;
use crate::text::sci;
use serde::Serialize;

/// The multiplicity a rung of this point should reach: 2 for a wave number m ≥ 1 (the cos/sin
/// pair), 1 for m = 0, the point's own without a label. A limit point is a fold of the path,
/// never one partner of a double: its rung is itself.
fn expected(p: &Point) -> usize {
    if fold(p) {
        return p.multiplicity;
    }
    match p.m {
        Some(0) => 1,
        Some(_) => 2,
        None => p.multiplicity,
    }
    .max(p.multiplicity)
}

/// True for a limit point (a fold of the path in the control).
fn fold(p: &Point) -> bool {
    p.kind == CriticalKind::LimitPoint
}

/// Groups the points of one mesh that are not `taken` into rungs (indices, the first point
/// first).
fn rungs(points: &[Point], floor: f64, taken: &[bool]) -> Vec<Vec<usize>> {
    let mut used = taken.to_vec();
    let mut out = Vec::new();
    for i in 0..points.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let mut group = vec![i];
        let target = expected(&points[i]);
        let mut have = points[i].multiplicity;
        let v = points[i].value;
        while have < target {
            let next = (0..points.len())
                .filter(|&j| !used[j] && points[j].m == points[i].m && points[i].m.is_some())
                .filter(|&j| points[j].rising == points[i].rising)
                .filter(|&j| !fold(&points[j]))
                .filter(|&j| (points[j].value - v).abs() <= PAIR_TOLERANCE * v.abs() + floor)
                .min_by(|&a, &b| {
                    (points[a].value - v)
                        .abs()
                        .total_cmp(&(points[b].value - v).abs())
                });
            let Some(j) = next else { break };
            used[j] = true;
            have += points[j].multiplicity;
            group.push(j);
        }
        out.push(group);
    }
    out
}

/// What a rung's images must share with it: the wave number, whether it is a fold (folds are
/// the images of folds only), and the direction of the control where the path meets it (a
/// point met after a turn of the path lies on another piece of it).
#[derive(Debug, Clone, Copy)]
struct Likeness {
    m: Option<usize>,
    fold: bool,
    rising: bool,
}

impl Likeness {
    fn of(p: &Point) -> Self {
        Likeness {
            m: p.m,
            fold: fold(p),
            rising: p.rising,
        }
    }

    fn admits(&self, p: &Point) -> bool {
        p.m == self.m
            && p.rising == self.rising
            && match (self.fold, fold(p)) {
                (true, true) | (false, false) => true,
                (true, false) => false,
                // A mode of the pair that the mesh put in its trivial irrep: there the
                // bifurcation is not protected by the symmetry and the path folds instead.
                (false, true) => self.m.is_some_and(|m| m >= 1),
            }
    }
}

/// The images of a rung (like the rung's first point, value v, multiplicity `target`) among
/// the unused points.
fn images(
    points: &[Point],
    used: &mut [bool],
    like: Likeness,
    v: f64,
    target: usize,
    floor: f64,
) -> Vec<usize> {
    let mut found = Vec::new();
    let mut have = 0;
    while have < target {
        let next = (0..points.len())
            .filter(|&j| !used[j] && like.admits(&points[j]))
            .filter(|&j| (points[j].value - v).abs() <= MATCH_TOLERANCE * v.abs() + floor)
            .min_by(|&a, &b| {
                (points[a].value - v)
                    .abs()
                    .total_cmp(&(points[b].value - v).abs())
            });
        let Some(j) = next else { break };
        used[j] = true;
        have += points[j].multiplicity;
        found.push(j);
        if !like.fold && fold(&points[j]) {
            // The path turns there: the rest of the pair, if any, lies before it.
            break;
        }
    }
    found.sort_by(|&a, &b| points[a].value.total_cmp(&points[b].value));
    found
}

/// The images of one rung on one mesh at one resolution, measured.
#[derive(Debug, Clone, Serialize)]
pub struct Image {
    /// The resolution of the run.
    pub resolution: usize,
    /// Indices into that run's `critical`.
    pub points: Vec<usize>,
    /// Their irreps.
    pub irreps: Vec<String>,
    /// Their control values, ascending.
    pub values: Vec<f64>,
    /// Their multiplicities, summed.
    pub multiplicity: usize,
    /// Spread of the values of two or more points; 0 for one point in a d ≥ 2 irrep (double by
    /// construction); `null` otherwise (in every entry, so that readers need not test for it).
    pub gap: Option<f64>,
    /// Gap above round-off, for two or more points; `null` for one point (in every entry).
    pub split: Option<bool>,
    /// What the images say: `verdict`, its sentence, and `piece_gap`, the RMS distance of an
    /// imperfect fold's second piece where one was found (`null` otherwise, in every entry).
    #[serde(flatten)]
    pub verdict: Verdict,
    /// Each value's distance from the continuum's (value − continuum, in the order of
    /// `values`); empty without an axisymmetric mesh or without its image.
    pub distances: Vec<f64>,
}

/// What a rung's images on one mesh say.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// The measurement.
    pub kind: VerdictKind,
    /// Fewer images than the rung's multiplicity were found in range.
    pub missing: Option<Missing>,
    /// The images lie on the other side of a turn of the path than the rung
    /// (the matching's second pass).
    pub across_turn: bool,
    /// The images lie on a second piece, beside an imperfect fold, that the path does not
    /// reach (docs/theory.md §16.4).
    pub on_piece: bool,
    /// For an imperfect fold, the RMS distance of its second piece, where one was found.
    pub piece_gap: Option<f64>,
}

/// The measurement of a rung's images.
#[derive(Debug, Clone, PartialEq)]
pub enum VerdictKind {
    /// No image in range.
    NotFound,
    /// One point of a d ≥ 2 irrep: a multiple point by construction.
    Multiple {
        /// Its kind.
        kind: CriticalKind,
        /// Its irrep.
        irrep: String,
    },
    /// One simple point.
    Single(CriticalKind),
    /// One limit point as the image of a bifurcation: the mesh put a mode of the pair in its
    /// trivial irrep, where the bifurcation is imperfect.
    Imperfect {
        /// The point's irrep.
        irrep: String,
    },
    /// Two or more points at exactly the same value.
    NotSplitZero,
    /// Two or more points whose gap is within the localisation's uncertainty.
    NotSplitRoundOff {
        /// The uncertainty.
        precision: f64,
    },
    /// Two or more points whose gap exceeds the localisation's uncertainty.
    Split,
}

/// Which images were not found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Missing {
    /// The partner of a lone simple point.
    Partner,
    /// Some other image.
    Image,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.kind {
            VerdictKind::NotFound => f.write_str("not found")?,
            VerdictKind::Multiple { kind, irrep } => write!(f, "not split: {kind} in {irrep}")?,
            VerdictKind::Single(kind) => write!(f, "{kind}")?,
            VerdictKind::Imperfect { irrep } => {
                write!(f, "imperfect: a limit point in {irrep}, the path turns")?
            }
            VerdictKind::NotSplitZero => f.write_str("not split (gap 0)")?,
            VerdictKind::NotSplitRoundOff { precision } => {
                write!(f, "not split (gap at round-off, +-{})", sci(*precision))?
            }
            VerdictKind::Split => f.write_str("split")?,
        }
        match self.missing {
            // Its partner is the second piece's: on another path, named below.
            Some(Missing::Partner) if self.piece_gap.is_some() => {}
            Some(Missing::Partner) => f.write_str("; partner not found in range")?,
            Some(Missing::Image) => f.write_str("; an image not found in range")?,
            None => {}
        }
        if self.across_turn {
            f.write_str("; met on the other side of the path's turn")?;
        }
        if let Some(gap) = self.piece_gap {
            write!(
                f,
                "; its partner lies on a second piece beside it, at RMS distance {}",
                sci(gap)
            )?;
        }
        if self.on_piece {
            f.write_str("; on the second piece beside the imperfect fold")?;
        }
        Ok(())
    }
}

/// Two entries of its image: `verdict`, the sentence, and `piece_gap`, the measured
/// distance of a second piece (a number, not only words in the sentence).
impl Serialize for Verdict {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(2))?;
        map.serialize_entry("verdict", &self.to_string())?;
        map.serialize_entry("piece_gap", &self.piece_gap)?;
        map.end()
    }
}

fn measure(
    points: &[Point],
    found: Vec<usize>,
    (target, folds): (usize, bool),
    resolution: usize,
) -> Image {
    let found_on = found.clone();
    let values: Vec<f64> = found.iter().map(|&j| points[j].value).collect();
    let irreps: Vec<String> = found.iter().map(|&j| points[j].irrep.clone()).collect();
    let multiplicity: usize = found.iter().map(|&j| points[j].multiplicity).sum();
    let (gap, split, kind) = match found.as_slice() {
        [] => (None, None, VerdictKind::NotFound),
        [j] if points[*j].multiplicity >= 2 => (
            Some(0.0),
            None,
            VerdictKind::Multiple {
                kind: points[*j].kind,
                irrep: points[*j].irrep.clone(),
            },
        ),
        [j] if fold(&points[*j]) && !folds => (
            None,
            None,
            VerdictKind::Imperfect {
                irrep: points[*j].irrep.clone(),
            },
        ),
        [j] => (None, None, VerdictKind::Single(points[*j].kind)),
        _ => {
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let gap = hi - lo;
            let scale = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            // Resolved when the gap exceeds twice the summed uncertainties of the two ends
            // (or, without them, ROUND_OFF of the value).
            let ends = |x: f64| {
                found
                    .iter()
                    .filter(|&&j| points[j].value == x)
                    .map(|&j| points[j].precision)
                    .next()
                    .flatten()
            };
            let precision = match (ends(lo), ends(hi)) {
                (Some(a), Some(b)) => a + b,
                _ => ROUND_OFF * scale,
            };
            if gap == 0.0 {
                (Some(gap), Some(false), VerdictKind::NotSplitZero)
            } else if gap <= 2.0 * precision {
                (
                    Some(gap),
                    Some(false),
                    VerdictKind::NotSplitRoundOff { precision },
                )
            } else {
                (Some(gap), Some(true), VerdictKind::Split)
            }
        }
    };
    let missing = (!found.is_empty() && multiplicity < target).then_some(
        if found.len() == 1 && multiplicity == 1 {
            Missing::Partner
        } else {
            Missing::Image
        },
    );
    Image {
        resolution,
        points: found,
        irreps,
        values,
        multiplicity,
        gap,
        split,
        verdict: Verdict {
            kind,
            missing,
            across_turn: false,
            on_piece: on_piece(points, &found_on),
            piece_gap: None,
        },
        distances: Vec::new(),
    }
}

/// Whether any of the points `found` lies on a second piece.
fn on_piece(points: &[Point], found: &[usize]) -> bool {
    found.iter().any(|&j| points[j].piece.is_some())
}

/// A rung's images on one mesh, at each resolution, and the observed order of the gap.
#[derive(Debug, Clone, Serialize)]
pub struct MeshImages {
    /// The mesh's label.
    pub mesh: String,
    /// One per resolution.
    pub levels: Vec<Image>,
    /// log2(gap_coarse / gap_fine) when both resolutions split the rung; for an imperfect
    /// fold, of its second piece's distance ([`Verdict::piece_gap`]) when both found one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
}

/// A rung of the reference mesh.
#[derive(Debug, Clone, Serialize)]
pub struct Rung {
    /// The wave number about z.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub m: Option<usize>,
    /// The kinds of its points on the reference mesh.
    pub kind: RungKind,
    /// Their irreps.
    pub irreps: Vec<String>,
    /// Their control values.
    pub values: Vec<f64>,
    /// Their multiplicities, summed.
    pub multiplicity: usize,
    /// The reference's resolution where the rung was found (its first, or the refined one).
    pub found_at: usize,
    /// The images on every mesh, the reference first.
    pub images: Vec<MeshImages>,
    /// The continuum's value: the image on the axisymmetric mesh (its finest run), when one
    /// is compared.
    pub continuum: Option<f64>,
    /// The continuum value's own error estimate: |value(2N) − value(N)| of the meridian's
    /// runs at N and 2N elements (the refined level, or its check run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub continuum_error: Option<f64>,
    /// Whether that estimate is not small (above a tenth) against the smallest nonzero
    /// |distance| of a 3-D image: the meridian is then too coarse to measure them against.
    pub continuum_coarse: bool,
    /// Observed orders of the distance from the continuum between the runs of one group at
    /// two resolutions.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub orders: Vec<DistanceOrder>,
    /// Whether the reference meets the rung as the control rises.
    #[serde(skip)]
    rising: bool,
}

/// The observed order of a rung's distance from the continuum between two resolutions of one
/// group: ln(d_coarse / d_fine) / ln(n_fine / n_coarse), d the largest |distance| of the
/// images, n the resolution (divisions; the mesh size h ∝ 1/n).
#[derive(Debug, Clone, Serialize)]
pub struct DistanceOrder {
    /// The group.
    pub group: String,
    /// The coarse resolution.
    pub coarse: usize,
    /// The fine resolution.
    pub fine: usize,
    /// The order.
    pub order: f64,
}

/// The kinds of a rung's points: one kind, or several joined by `+`.
#[derive(Debug, Clone, PartialEq)]
pub struct RungKind(pub Vec<CriticalKind>);

impl std::fmt::Display for RungKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0.as_slice() {
            [first, rest @ ..] if rest.iter().all(|k| k == first) => write!(f, "{first}"),
            kinds => {
                let names: Vec<String> = kinds.iter().map(|k| k.to_string()).collect();
                f.write_str(&names.join(" + "))
            }
        }
    }
}

impl Serialize for RungKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Matches every mesh's points to the reference's rungs: those of its first resolution, then
/// (with `--refine`) those of its refined run that the first did not have.
pub(super) fn match_rungs(meshes: &[MeshRuns], floor: f64) -> (Vec<Rung>, Vec<Unmatched>) {
    // Used points per (mesh, level).
    let mut used: Vec<Vec<Vec<bool>>> = meshes
        .iter()
        .map(|m| {
            m.levels
                .iter()
                .map(|l| vec![false; l.critical.len()])
                .collect()
        })
        .collect();
    let mut out = Vec::new();
    for source in 0..meshes[0].levels.len() {
        let groups = rungs(&meshes[0].levels[source].critical, floor, &used[0][source]);
        for group in &groups {
            out.push(rung(meshes, &mut used, source, group, floor));
        }
    }
    across_turns(meshes, &mut used, &mut out, floor);
    let mut unmatched = Vec::new();
    for (k, mesh) in meshes.iter().enumerate() {
        for (l, level) in mesh.levels.iter().enumerate() {
            for (i, p) in level.critical.iter().enumerate() {
                if !used[k][l][i] {
                    unmatched.push(Unmatched {
                        mesh: mesh.label.clone(),
                        resolution: level.resolution,
                        point: i,
                        irrep: p.irrep.clone(),
                        value: p.value,
                        m: p.m,
                        rising: p.rising,
                    });
                }
            }
        }
    }
    (out, unmatched)
}

/// The rung `group` of the reference's level `source` with its images on every mesh.
fn rung(
    meshes: &[MeshRuns],
    used: &mut [Vec<Vec<bool>>],
    source: usize,
    group: &[usize],
    floor: f64,
) -> Rung {
    let reference = &meshes[0].levels[source].critical;
    let first = &reference[group[0]];
    let m = first.m;
    let multiplicity: usize = group.iter().map(|&i| reference[i].multiplicity).sum();
    let target = multiplicity.max(expected(first));
    let v = group.iter().map(|&i| reference[i].value).sum::<f64>() / group.len() as f64;
    let mut sorted = group.to_vec();
    sorted.sort_by(|&a, &b| reference[a].value.total_cmp(&reference[b].value));
    let mut all = Vec::new();
    for (k, mesh) in meshes.iter().enumerate() {
        let mut levels = Vec::new();
        for (l, level) in mesh.levels.iter().enumerate() {
            let found = if k == 0 && l == source {
                for &i in &sorted {
                    used[0][source][i] = true;
                }
                sorted.clone()
            } else {
                images(
                    &level.critical,
                    &mut used[k][l],
                    Likeness::of(first),
                    v,
                    target,
                    floor,
                )
            };
            let mut image = measure(
                &level.critical,
                found,
                (target, fold(first)),
                level.resolution,
            );
            if let VerdictKind::Imperfect { .. } = image.verdict.kind {
                let at = image.values[0];
                image.verdict.piece_gap = level.pieces.iter().find(|p| p.fold == at).map(|p| p.gap);
            }
            levels.push(image);
        }
        all.push(MeshImages {
            mesh: mesh.label.clone(),
            order: order_of(&levels),
            levels,
        });
    }
    Rung {
        m,
        kind: RungKind(sorted.iter().map(|&i| reference[i].kind).collect()),
        irreps: sorted.iter().map(|&i| reference[i].irrep.clone()).collect(),
        values: sorted.iter().map(|&i| reference[i].value).collect(),
        multiplicity,
        found_at: meshes[0].levels[source].resolution,
        images: all,
        continuum: None,
        continuum_error: None,
        continuum_coarse: false,
        orders: Vec::new(),
        rising: first.rising,
    }
}

/// The observed order of a rung's images on one mesh: of the gap ([`gap_order`]), or of an
/// imperfect fold's second piece's distance ([`piece_gap_order`]).
fn order_of(levels: &[Image]) -> Option<f64> {
    gap_order(levels).or_else(|| piece_gap_order(levels))
}

/// log2(gap_coarse / gap_fine) of an imperfect fold's second piece, when both resolutions
/// found one.
fn piece_gap_order(levels: &[Image]) -> Option<f64> {
    match levels {
        [a, b] => match (a.verdict.piece_gap, b.verdict.piece_gap) {
            (Some(ga), Some(gb)) if ga > 0.0 && gb > 0.0 => Some((ga / gb).log2()),
            _ => None,
        },
        _ => None,
    }
}

/// log2(gap_coarse / gap_fine) when both resolutions split the rung.
fn gap_order(levels: &[Image]) -> Option<f64> {
    match levels {
        [a, b] => match (a.split, b.split, a.gap, b.gap) {
            (Some(true), Some(true), Some(ga), Some(gb)) => Some((ga / gb).log2()),
            _ => None,
        },
        _ => None,
    }
}

/// The second pass over the rungs of wave number m that are not folds, for every run in which
/// the first found no image: a bifurcation that the reference meets just after a turn of the
/// path may come just before it on a mesh, when the mesh's error at that fold, e = |F_mesh −
/// F_ref|, exceeds the point's distance from the fold. So a rung within e of a reference fold
/// F_ref takes as its images the points no rung took with its m on the other piece of the path,
/// nearest in value, provided they lie within e of the mesh's image F_mesh of that fold; they
/// are marked `across_turn`. Folds keep to their piece, and unlabelled modes (an icosphere's)
/// get no second pass.
fn across_turns(meshes: &[MeshRuns], used: &mut [Vec<Vec<bool>>], rungs: &mut [Rung], floor: f64) {
    // Every fold rung: its reference value and its image per (mesh, level), if found.
    let folds: Vec<(f64, Vec<Vec<Option<f64>>>)> = rungs
        .iter()
        .filter(|r| r.kind.0.iter().all(|k| *k == CriticalKind::LimitPoint))
        .map(|r| {
            let images = r
                .images
                .iter()
                .map(|im| {
                    im.levels
                        .iter()
                        .map(|l| l.values.first().copied())
                        .collect()
                })
                .collect();
            (r.values[0], images)
        })
        .collect();
    for rung in rungs.iter_mut() {
        if rung.m.is_none() || rung.kind.0.contains(&CriticalKind::LimitPoint) {
            continue;
        }
        let like = Likeness {
            m: rung.m,
            fold: false,
            rising: !rung.rising,
        };
        let v = rung.values.iter().sum::<f64>() / rung.values.len() as f64;
        for (k, mesh) in meshes.iter().enumerate().skip(1) {
            let images_k = &mut rung.images[k];
            for (l, level) in mesh.levels.iter().enumerate() {
                if !images_k.levels[l].points.is_empty() {
                    continue;
                }
                // The folds near which the mesh's error may have reordered the rung.
                let near: Vec<(f64, f64)> = folds
                    .iter()
                    .filter_map(|(f_ref, im)| {
                        let f_mesh = im[k].get(l).copied().flatten()?;
                        let e = (f_mesh - f_ref).abs();
                        ((v - f_ref).abs() <= e).then_some((f_mesh, e))
                    })
                    .collect();
                if near.is_empty() {
                    continue;
                }
                let before = used[k][l].clone();
                let found = images(
                    &level.critical,
                    &mut used[k][l],
                    like,
                    v,
                    rung.multiplicity,
                    floor,
                );
                let by_its_fold = |j: &usize| {
                    let p = level.critical[*j].value;
                    near.iter().any(|(f, e)| (p - f).abs() <= *e)
                };
                if found.is_empty() || !found.iter().all(by_its_fold) {
                    used[k][l] = before;
                    continue;
                }
                let mut image = measure(
                    &level.critical,
                    found,
                    (rung.multiplicity, false),
                    level.resolution,
                );
                image.verdict.across_turn = true;
                images_k.levels[l] = image;
            }
            images_k.order = order_of(&images_k.levels);
        }
    }
}

/// Sets every rung's continuum value (its image on the mesh `continuum`, the finest run that
/// has one), each image's distances from it, and the observed orders of the distance between
/// the resolutions of one group (the axisymmetric mesh itself excluded).
pub(super) fn measure_distances(meshes: &[MeshRuns], rungs: &mut [Rung], continuum: usize) {
    for rung in rungs.iter_mut() {
        let c = rung.images[continuum]
            .levels
            .iter()
            .rev()
            .find(|l| !l.values.is_empty())
            .map(|l| l.values.iter().sum::<f64>() / l.values.len() as f64);
        rung.continuum = c;
        let Some(c) = c else { continue };
        let mean = |l: &Image| l.values.iter().sum::<f64>() / l.values.len() as f64;
        rung.continuum_error = match (&rung.images[continuum].levels[..], &meshes[continuum].check)
        {
            // Refined: the two levels' values.
            ([a, b, ..], _) if !a.values.is_empty() && !b.values.is_empty() => {
                Some((mean(b) - mean(a)).abs())
            }
            // The check run's point with the rung's m nearest the continuum value (20 %).
            (_, Some(check)) => check
                .critical
                .iter()
                .filter(|p| p.m == rung.m && (p.value - c).abs() <= 0.2 * c.abs())
                .map(|p| (p.value - c).abs())
                .min_by(f64::total_cmp),
            _ => None,
        };
        // (group, resolution, largest |distance|) of every 3-D run with images.
        let mut runs: Vec<(String, usize, f64)> = Vec::new();
        for (k, im) in rung.images.iter_mut().enumerate() {
            for (l, level) in im.levels.iter_mut().enumerate() {
                level.distances = level.values.iter().map(|v| v - c).collect();
                let d = level.distances.iter().fold(0.0f64, |a, d| a.max(d.abs()));
                if k != continuum && !level.distances.is_empty() {
                    runs.push((meshes[k].levels[l].group.clone(), level.resolution, d));
                }
            }
        }
        let nearest = runs
            .iter()
            .map(|r| r.2)
            .filter(|&d| d > 0.0)
            .min_by(f64::total_cmp);
        rung.continuum_coarse = matches!(
            (rung.continuum_error, nearest),
            (Some(e), Some(d)) if e > 0.1 * d
        );
        runs.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)));
        runs.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
        rung.orders = runs
            .windows(2)
            .filter(|w| w[0].0 == w[1].0 && w[0].2 > 0.0 && w[1].2 > 0.0)
            .map(|w| DistanceOrder {
                group: w[0].0.clone(),
                coarse: w[0].1,
                fine: w[1].1,
                order: (w[0].2 / w[1].2).ln() / (w[1].1 as f64 / w[0].1 as f64).ln(),
            })
            .collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(kind: CriticalKind, irrep: &str, value: f64, m: usize) -> Point {
        Point {
            kind,
            irrep: irrep.into(),
            multiplicity: 1,
            value,
            m: Some(m),
            residual_eigenvalue: 1e-13,
            precision: None,
            isotropy: "C1v".into(),
            rising: true,
            flags: Vec::new(),
            piece: None,
        }
    }

    #[test]
    fn a_fold_pair_is_two_rungs_not_a_split_double() {
        // A maximum and a minimum of the control close together, both in A1 with the same
        // wave number: two folds, each its own rung — never the two halves of a double.
        let folds = [
            point(CriticalKind::LimitPoint, "A1", 2.000, 1),
            point(CriticalKind::LimitPoint, "A1", 2.001, 1),
        ];
        let groups = rungs(&folds, 0.0, &[false, false]);
        assert_eq!(groups, vec![vec![0], vec![1]]);
        // The halves of a split double still pair: A1 + A2 bifurcations of one wave number.
        let split = [
            point(CriticalKind::SymmetricBifurcation, "A1", 2.000, 1),
            point(CriticalKind::SimpleBifurcation, "A2", 2.001, 1),
        ];
        assert_eq!(rungs(&split, 0.0, &[false, false]), vec![vec![0, 1]]);
        // Nor is a bifurcation the image of a fold.
        let mut used = vec![false, false];
        let found = images(&split, &mut used, Likeness::of(&folds[0]), 2.0, 1, 0.0);
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn a_fold_of_a_mode_with_a_wave_number_is_the_imperfect_image_of_its_bifurcation() {
        // On a mesh that puts the cos mode of an m = 2 pair in its trivial irrep the
        // bifurcation is imperfect: the path folds near it (arriving while the control rises)
        // and turns back; the fold's partner, a minimum met on the way back, is on another
        // piece of the path.
        let double = point(CriticalKind::SimpleBifurcation, "A2", 16.76, 2);
        let mut min = point(CriticalKind::LimitPoint, "A1", 16.70, 2);
        min.rising = false;
        let other = [point(CriticalKind::LimitPoint, "A1", 16.70, 2), min];
        let mut used = vec![false, false];
        let found = images(&other, &mut used, Likeness::of(&double), 16.76, 2, 0.0);
        assert_eq!(found, vec![0]);
        let image = measure(&other, found, (2, false), 12);
        assert_eq!(
            image.verdict.to_string(),
            "imperfect: a limit point in A1, the path turns; partner not found in range"
        );
        // A fold of the axisymmetric states (m = 0) is never the image of a bifurcation.
        let mut used = vec![false];
        let m0 = point(CriticalKind::SymmetricBifurcation, "A1", 16.76, 0);
        let fold0 = [point(CriticalKind::LimitPoint, "A1", 16.70, 0)];
        assert!(images(&fold0, &mut used, Likeness::of(&m0), 16.76, 1, 0.0).is_empty());
    }

    #[test]
    fn an_imperfect_folds_second_piece_is_named_with_its_distance_and_order() {
        // The reference's m = 2 double; on the other mesh, at two resolutions, the imperfect
        // fold with a second piece beside it (RMS distances 0.08 and 0.02: order 2), and an
        // m = 1 pair met on that piece.
        let double = point(CriticalKind::MultipleBifurcation(2), "E2", 16.76, 2);
        let e1 = point(CriticalKind::MultipleBifurcation(2), "E1", 18.10, 1);
        let on_piece = |irrep: &str, v: f64| {
            let mut p = point(CriticalKind::SimpleBifurcation, irrep, v, 1);
            p.piece = Some(1);
            p
        };
        let mut reference = runs("C8v", vec![double.clone(), e1.clone()]);
        reference.levels[0].critical[0].multiplicity = 2;
        reference.levels[0].critical[1].multiplicity = 2;
        reference.levels.push(reference.levels[0].clone());
        let mut other = runs(
            "C2v",
            vec![
                point(CriticalKind::LimitPoint, "A1", 16.70, 2),
                on_piece("B1", 18.08),
                on_piece("B2", 18.12),
            ],
        );
        other.levels.push(other.levels[0].clone());
        for (level, gap) in other.levels.iter_mut().zip([0.08, 0.02]) {
            level.pieces.push(super::super::Piece {
                fold: 16.70,
                m: Some(2),
                gap,
                points: 10,
                stop: crate::results::StopReason::Bounds,
            });
        }
        let (rungs, _) = match_rungs(&[reference, other], 0.0);
        let m2 = &rungs[0].images[1];
        assert_eq!(m2.levels[0].verdict.piece_gap, Some(0.08));
        let verdict = m2.levels[0].verdict.to_string();
        assert!(
            verdict.ends_with(
                "its partner lies on a second piece beside it, at RMS distance 8.000e-2"
            ),
            "{verdict}"
        );
        assert!(!verdict.contains("not found"), "{verdict}");
        assert_eq!(m2.order, Some(2.0));
        let m1 = &rungs[1].images[1].levels[0];
        assert_eq!(m1.points.len(), 2);
        assert!(m1.verdict.on_piece);
        assert!(m1
            .verdict
            .to_string()
            .ends_with("on the second piece beside the imperfect fold"));
        // The fold itself lies on the path.
        assert!(!m2.levels[0].verdict.on_piece);
    }

    #[test]
    fn a_point_met_after_a_turn_is_not_the_image_of_one_met_before() {
        // A rung met while the control rises; on the other mesh the path turns at a fold
        // before it and meets a point of the same m, nearer the rung's value than the
        // tolerance, on its way back.
        let rung = point(CriticalKind::SimpleBifurcation, "A2", 16.76, 2);
        let mut back = point(CriticalKind::SimpleBifurcation, "A2", 16.60, 2);
        back.rising = false;
        let ahead = point(CriticalKind::SimpleBifurcation, "A1", 16.90, 2);
        let other = [back.clone(), ahead];
        let mut used = vec![false, false];
        let found = images(&other, &mut used, Likeness::of(&rung), 16.76, 2, 0.0);
        assert_eq!(
            found,
            vec![1],
            "only the point on the rising piece is an image"
        );
        // Nor do such two points of one mesh form a rung together.
        let mesh = [rung, back];
        assert_eq!(rungs(&mesh, 0.0, &[false, false]), vec![vec![0], vec![1]]);
    }

    fn runs(label: &str, critical: Vec<Point>) -> MeshRuns {
        MeshRuns {
            label: label.into(),
            generator: "disc".into(),
            levels: vec![super::super::Level {
                mesh: label.into(),
                resolution: 8,
                nodes: 0,
                triangles: 0,
                group: label.into(),
                order: 1,
                unknowns: 0,
                symmetric_unknowns: 0,
                stop: crate::results::StopReason::Bounds,
                note: None,
                warnings: Vec::new(),
                seconds: 0.0,
                critical,
                flagged: Vec::new(),
                turning: Vec::new(),
                events: Vec::new(),
                pieces: Vec::new(),
            }],
            check: None,
        }
    }

    #[test]
    fn a_bifurcation_the_mesh_error_moves_across_a_nearby_fold_is_matched_across_the_turn() {
        // The reference folds at 18.774 and meets the m = 4 double just after the turn; the
        // mesh, 0.6 off at the fold, meets its m = 4 pair 0.03 before its own fold. On a mesh
        // without an image of the fold, a point of the reference's m = 1 met after the turn
        // is left unmatched.
        let fold = |v: f64| point(CriticalKind::LimitPoint, "A1", v, 0);
        let mut m4 = point(CriticalKind::MultipleBifurcation(2), "m=4", 18.769, 4);
        m4.multiplicity = 2;
        m4.rising = false;
        let m1 = point(CriticalKind::MultipleBifurcation(2), "m=1", 17.723, 1);
        let reference = runs("axisymmetric", vec![m1.clone(), fold(18.774), m4]);
        let b = |irrep: &str, v: f64| point(CriticalKind::SimpleBifurcation, irrep, v, 4);
        let mut far = point(CriticalKind::SimpleBifurcation, "B1", 16.33, 1);
        far.rising = false;
        let mesh = runs("C8v", vec![b("B2", 19.346), b("B1", 19.350), fold(19.377)]);
        let other = runs("C2v", vec![far]);
        let (rungs, unmatched) = match_rungs(&[reference, mesh, other], 0.0);
        let rung = rungs.iter().find(|r| r.m == Some(4)).unwrap();
        let image = &rung.images[1].levels[0];
        assert_eq!(image.values, vec![19.346, 19.350]);
        assert!(image.verdict.across_turn);
        assert!(image
            .verdict
            .to_string()
            .ends_with("met on the other side of the path's turn"));
        let one = rungs.iter().find(|r| r.m == Some(1)).unwrap();
        assert!(one.images[2].levels[0].points.is_empty());
        assert_eq!(unmatched.len(), 1, "{unmatched:?}");
        assert_eq!(unmatched[0].mesh, "C2v");
    }
}
