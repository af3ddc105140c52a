//! `type = "diagram"`: the global bifurcation diagram of a scene. The path with its
//! branches, as `type = "path"` with `[analysis.branches]` follows them (to the diagram's
//! depth; each branch once, group images merged and connections to known points recorded,
//! docs/theory.md §14.8), then beside every fold of the path the second piece of an
//! imperfect bifurcation, if there is one ([`super::partner`], docs/theory.md §16.4).

use super::partner::{near_misses, partners, Follow};
use super::path::Path;
use super::{after_finished, AfterError, Analysis, Context, Observer, RunError};
use crate::continuation::{interrupt, PathOptions};
use crate::output::{self, Described, Drawing, FinishedRun, OutputError};
use crate::results::partner::Partner;
use crate::results::{Outcome, RunResult, StopReason};
use crate::scene::{DiagramAnalysis, Scene};
use crate::study::Study;
use crate::text::sig_digits;
use std::path::Path as FilePath;

/// `type = "diagram"`.
pub struct Diagram(pub DiagramAnalysis);

impl Diagram {
    fn path(&self) -> Path {
        Path(self.0.path())
    }

    /// The diagram beyond its path, from the path in `cx`'s record: the branches of its
    /// bifurcation points (to the diagram's depth), then the second piece beside each fold.
    fn global(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<(), RunError> {
        let options = self.path().branch_options(study, None);
        let critical = cx.record.critical.clone();
        cx.record.branches = Some(
            study
                .branches(&critical, options)
                .map_err(RunError::Branches)?,
        );
        if self.0.partners && !interrupt::requested() {
            let opts = self.options(study);
            let follow = Follow {
                steps: self.0.partner_steps,
                save_every: self.0.settings.save_every,
                limits: self.path().limits(study),
            };
            let mut found = partners(
                study,
                &opts,
                cx.record.path(),
                cx.record.critical(),
                &mut cx.crossings,
                &follow,
                &|_| true,
            );
            if self.0.near_misses && !interrupt::requested() {
                let first = found.iter().filter(|p| p.piece.is_some()).count() + 1;
                found.extend(near_misses(
                    study,
                    &opts,
                    cx.record.path(),
                    &mut cx.crossings,
                    &follow,
                    first,
                ));
            }
            cx.record.outcome = Some(Outcome::new(found));
        }
        Ok(())
    }
}

/// What `memstab diagram RUN_DIR` changes of the diagram's settings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// The branches' depth, points and largest step (as `memstab branch`'s).
    pub branches: super::branch::Overrides,
    /// Seek the second piece beside every fold.
    pub partners: Option<bool>,
    /// Points of each second piece.
    pub partner_steps: Option<usize>,
}

/// The diagram's settings for the scene of a finished path: its own keys when it is a
/// diagram, else the path's with the diagram's defaults (the depth and steps of its
/// `[analysis.branches]` where it has them); then `overrides`. A value out of range is an
/// error naming the flag.
pub fn settings_for(
    analysis: &crate::scene::Analysis,
    overrides: &Overrides,
) -> Result<DiagramAnalysis, String> {
    let mut d = match (
        analysis.get::<DiagramAnalysis>(),
        analysis.get::<crate::scene::PathAnalysis>(),
    ) {
        (Some(d), _) => d.clone(),
        (None, Some(p)) => DiagramAnalysis::of_path(p),
        (None, None) => {
            return Err(format!(
                "the run's scene is a {} analysis: a diagram starts from a path (type = \"path\" or \"diagram\")",
                analysis.kind()
            ))
        }
    };
    let branches = &overrides.branches;
    branches.check()?;
    if let Some(depth) = branches.depth {
        d.depth = depth;
    }
    if let Some(s) = branches.steps {
        d.branch_steps = s;
    }
    match overrides.partner_steps {
        Some(0) => return Err("--partner-steps 0: must be >= 1".into()),
        Some(s) => d.partner_steps = s,
        None => {}
    }
    if let Some(m) = branches.max_step {
        d.branch_max_step = Some(m);
    }
    if let Some(p) = overrides.partners {
        d.partners = p;
    }
    Ok(d)
}

/// The diagram of the finished path `run` of `study` (`memstab diagram RUN_DIR`): the run
/// read back, and what a `type = "diagram"` run adds to its path — the branches and the
/// second pieces — computed from it with `settings` ([`settings_for`]). The result's path is
/// the run's own.
///
/// # Errors
/// As [`after_finished`].
pub fn from_run(
    study: &mut dyn Study,
    run: &FinishedRun,
    settings: DiagramAnalysis,
    observer: &mut dyn Observer,
) -> Result<RunResult, AfterError> {
    let diagram = Diagram(settings);
    let opts = diagram.options(study);
    let stop = StopReason::Recorded(run.stop.clone());
    after_finished(study, run, &opts, observer, |study, cx| {
        diagram.global(study, cx).map(|()| stop)
    })
}

/// Writes what [`from_run`] found into `out`: `branches.json`, a directory per branch and
/// `diagram.svg` ([`output::write_branches`]), then `diagram.json`, a directory per second
/// piece and `partners.svg`; returns the branches' files and the others, each with what it
/// holds.
///
/// # Errors
/// The first file that could not be written.
pub fn write_from_run(
    drawing: &dyn Drawing,
    scene: &Scene,
    result: &RunResult,
    out: &FilePath,
) -> Result<(output::BranchesWritten, Vec<Described>), OutputError> {
    let empty = crate::results::Branches::default();
    let branches = result.branches.as_ref().unwrap_or(&empty);
    let primary = crate::results::PrimaryPath::of(&result.report);
    let written =
        output::write_branches(drawing, scene, branches, &primary, out).map_err(|e| e.error)?;
    Ok((written, write_pieces(result, drawing, scene, out)?))
}

/// `diagram.json`, `partners.svg` and a directory per second piece of `result`.
fn write_pieces(
    result: &RunResult,
    drawing: &dyn Drawing,
    scene: &Scene,
    out: &FilePath,
) -> Result<Vec<Described>, OutputError> {
    let none = Vec::new();
    let found = result.outcome::<Vec<Partner>>().unwrap_or(&none);
    let files = output::write_partners(
        drawing,
        scene,
        out,
        found,
        result.branches.as_ref(),
        &result.report,
    )?;
    Ok(files
        .into_iter()
        .map(|(path, what)| Described { path, what })
        .collect())
}

/// The lines of a diagram's summary beyond its path and branches: the second pieces.
pub fn summary(result: &RunResult) -> Vec<String> {
    partner_summary(result)
}

impl Analysis for Diagram {
    fn options(&self, study: &dyn Study) -> PathOptions {
        self.path().options_of(study)
    }

    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let mut path = self.0.path();
        path.branches = None;
        let stop = Path(path).run(study, cx)?;
        self.global(study, cx)?;
        Ok(stop)
    }

    /// `diagram.json`, `partners.svg` and a directory per second piece.
    fn write(
        &self,
        result: &RunResult,
        drawing: &dyn Drawing,
        scene: &Scene,
        out: &FilePath,
    ) -> Result<Vec<Described>, OutputError> {
        write_pieces(result, drawing, scene, out)
    }

    fn summary(&self, result: &RunResult) -> Vec<String> {
        partner_summary(result)
    }
}

/// The summary's lines on the second pieces of a diagram's result.
fn partner_summary(result: &RunResult) -> Vec<String> {
    let Some(found) = result.outcome::<Vec<Partner>>() else {
        return Vec::new();
    };
    let control = &result.report.control;
    let mut lines = vec![format!(
        "second pieces: {} of the path's {} folds have one beside them; {} beside its {} dips",
        found
            .iter()
            .filter(|p| p.dip.is_none() && p.piece.is_some())
            .count(),
        found.iter().filter(|p| p.dip.is_none()).count(),
        found
            .iter()
            .filter(|p| p.dip.is_some() && p.piece.is_some())
            .count(),
        found.iter().filter(|p| p.dip.is_some()).count(),
    )];
    for p in found {
        let at = match p.dip {
            Some(step) => format!(
                "  dip at step {step}, {control} = {}",
                sig_digits(p.value, 6)
            ),
            None => format!(
                "  fold {} at {control} = {}",
                p.fold,
                sig_digits(p.value, 6)
            ),
        };
        let Some(piece) = &p.piece else {
            lines.push(format!(
                "{at}: {}",
                p.note.as_deref().unwrap_or("no second piece")
            ));
            continue;
        };
        let r = &piece.run.report;
        let c = r.parameters.iter().position(|n| n == control);
        let points: Vec<String> = r
            .critical
            .iter()
            .map(|cp| {
                format!(
                    "{} {} at {}",
                    cp.kind.short(),
                    cp.irrep,
                    sig_digits(c.map_or(0.0, |c| cp.parameters[c]), 6)
                )
            })
            .collect();
        let critical = if points.is_empty() {
            "no critical point".to_string()
        } else {
            points.join(", ")
        };
        let (to, followed) = if p.dip.is_some() {
            ("the path's state at its first", "points towards the dip")
        } else {
            ("the fold's state at the same", "points beyond the fold")
        };
        lines.push(format!(
            "{at}: a second piece, not reached by the path, at an RMS distance {} from \
                 {to} {control} (the gap); {}: {} {followed}, {critical}; stopped: {}",
            sig_digits(piece.gap, 4),
            piece.run.directory,
            r.rows.len(),
            r.stop
        ));
    }
    lines
}
