//! The second pieces of one run's imperfect folds (docs/theory.md §16.4): a fold whose mode
//! has a wave number m ≥ 1 is the image of a bifurcation the mesh does not protect; the
//! solutions beyond it — where the reference mesh meets the pair's further points — lie on a
//! piece the path never reaches. Each is found and followed ([`crate::analysis::partner`]),
//! and its critical points join the run's, so that the matching finds them as images.

use super::{point_of, wave_number, Piece, Point};
use crate::analysis::partner::{partners_of_run, Follow};
use crate::results::{CriticalKind, RunResult};
use crate::study::mesh::MeshStudy;

/// The second pieces beside the folds among `critical` (the run's points as compared) whose
/// mode has a wave number m ≥ 1, each followed for the scene's step budget, and the critical
/// points on them, labelled as the run's (`label_modes`) and marked with their piece.
pub(super) fn second_pieces(
    study: &MeshStudy,
    result: &RunResult,
    critical: &[Point],
    label_modes: bool,
) -> (Vec<Piece>, Vec<Point>) {
    let imperfect = |k: usize| {
        critical
            .get(k)
            .is_some_and(|p| p.kind == CriticalKind::LimitPoint && p.m.is_some_and(|m| m >= 1))
    };
    if !(0..critical.len()).any(imperfect) {
        return (Vec::new(), Vec::new());
    }
    let follow = Follow {
        steps: study.scene.analysis.budget().unwrap_or(100),
        save_every: usize::MAX,
        limits: Vec::new(),
    };
    let found = partners_of_run(study, result, follow, &imperfect);
    let mut pieces = Vec::new();
    let mut points = Vec::new();
    for partner in &found {
        let Some(piece) = &partner.piece else {
            continue;
        };
        let report = &piece.run.report;
        let control = report.parameters.iter().position(|p| *p == report.control);
        pieces.push(Piece {
            fold: partner.value,
            m: critical[partner.fold - 1].m,
            gap: piece.gap,
            points: report.rows.len(),
            stop: report.stop.clone(),
        });
        for (k, cp) in report.critical.iter().enumerate() {
            let m = label_modes.then(|| wave_number(study, &cp.mode));
            let mut p = point_of(report, control, k, cp.irrep.clone(), m, None);
            p.piece = Some(pieces.len());
            points.push(p);
        }
    }
    (pieces, points)
}
