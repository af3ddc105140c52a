//! What the states of a run say of their validity (docs/theory.md §8.10), once for every
//! model: a study measures a state ([`Study::state_check`]: its wrinkled elements and largest
//! principal stretch) and its contact ([`Study::penetrations`]: each node's penetration of a
//! penalty plane and the element size); this module turns the measures into a run's
//! [`Checks`] and a state's flags, so that the 3-D mesh and the meridian raise `stretch` and
//! `contact-jump` alike.

use super::Study;
use crate::results::validity::{Checks, ContactChange, Flag, StateCheck};
use crate::results::{Bracket, CriticalPoint, RunResult, StateKind};

/// The checks' frame of a study: the material's stated range, the elements, the energy.
fn frame<S: Study + ?Sized>(study: &S) -> Checks {
    let material = &study.scene().material;
    Checks {
        max_stretch: material.max_stretch,
        triangles: study.about().mesh.elements,
        relaxed: material.relaxed_stiffness().is_some(),
        ..Checks::default()
    }
}

/// The flags of the state (u, Λ): `wrinkled` under the plain energy, `stretch` beyond the
/// material's range.
pub fn state_flags<S: Study + ?Sized>(study: &S, u: &[f64], params: &[f64]) -> Vec<Flag> {
    frame(study).state_flags(&study.state_check(u, params), None)
}

/// How the contact set changed within critical point `cp`'s localisation bracket: the nodes
/// in contact (penetration > 0) at one end and not at the other, the deepest penetration at
/// the point over the element size there; `None` without a contact effect or a bracket.
pub fn contact_change<S: Study + ?Sized>(study: &S, cp: &CriticalPoint) -> Option<ContactChange> {
    contact_within(study, (&cp.state, &cp.parameters), cp.bracket.as_ref()?)
}

/// How the contact set changed within `bracket` about the state `at` (u, Λ), as
/// [`contact_change`] for a critical point's.
fn contact_within<S: Study + ?Sized>(
    study: &S,
    (u, params): (&[f64], &[f64]),
    bracket: &Bracket,
) -> Option<ContactChange> {
    let (at, h) = study.penetrations(u, params)?;
    let [(u0, p0), (u1, p1)] = &bracket.ends;
    let (before, _) = study.penetrations(u0, p0)?;
    let (after, _) = study.penetrations(u1, p1)?;
    let changed = before
        .iter()
        .zip(&after)
        .filter(|(a, b)| (**a > 0.0) != (**b > 0.0))
        .count();
    let deepest = at.iter().copied().fold(0.0, f64::max);
    Some(ContactChange {
        changed,
        penetration: if h > 0.0 { deepest / h } else { 0.0 },
        bracket: bracket.width,
    })
}

/// What the states of a finished run say of their validity: every row's (from every point's
/// kept state; none for a branch, which keeps none), turning point's and critical point's,
/// with the contact's change in each critical point's bracket.
pub fn checks<S: Study + ?Sized>(study: &S, result: &RunResult) -> Checks {
    let report = &result.report;
    let rows = if result.points.len() == report.rows.len() {
        result
            .points
            .iter()
            .map(|p| study.state_check(&study.expand(&p.q), &p.parameters))
            .collect()
    } else {
        Vec::new()
    };
    // A turning point at a corner of the path has the corner's bracket: the contact's change
    // within it, as a critical point's.
    let turning: Vec<StateCheck> = result
        .states
        .iter()
        .filter(|s| matches!(s.kind, StateKind::Turning(_)))
        .zip(
            report
                .turning_points
                .iter()
                .map(Some)
                .chain(std::iter::repeat(None)),
        )
        .map(|(s, t)| StateCheck {
            contact: t
                .and_then(|t| t.corner.as_ref())
                .and_then(|b| contact_within(study, (&s.u, &s.params), b)),
            ..study.state_check(&s.u, &s.params)
        })
        .collect();
    let turning = if turning.len() == report.turning_points.len() {
        turning
    } else {
        Vec::new()
    };
    let critical = report
        .critical
        .iter()
        .map(|cp| StateCheck {
            contact: contact_change(study, cp),
            ..study.state_check(&cp.state, &cp.parameters)
        })
        .collect();
    Checks {
        rows,
        turning,
        critical,
        ..frame(study)
    }
}
