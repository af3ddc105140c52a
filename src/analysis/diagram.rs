//! `type = "diagram"`: the global bifurcation diagram of a scene. The path with its
//! branches, as `type = "path"` with `[analysis.branches]` follows them (to the diagram's
//! depth; each branch once, group images merged and connections to known points recorded,
//! docs/theory.md §14.8), then beside every fold of the path the second piece of an
//! imperfect bifurcation, if there is one ([`super::partner`], docs/theory.md §16.4).

use super::partner::{partners, Follow};
use super::path::Path;
use super::{Analysis, Context, RunError};
use crate::continuation::{interrupt, PathOptions};
use crate::output::{self, Described, Drawing, OutputError};
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
}

impl Analysis for Diagram {
    fn options(&self, study: &dyn Study) -> PathOptions {
        self.path().options_of(study)
    }

    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let stop = self.path().run(study, cx)?;
        if self.0.partners && !interrupt::requested() {
            let opts = self.options(study);
            let follow = Follow {
                steps: self.0.partner_steps,
                save_every: self.0.settings.save_every,
                limits: self.path().limits(study),
            };
            let found = partners(
                study,
                &opts,
                cx.record.path(),
                cx.record.critical(),
                &mut cx.crossings,
                &follow,
                &|_| true,
            );
            cx.record.outcome = Some(Outcome::new(found));
        }
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

    fn summary(&self, result: &RunResult) -> Vec<String> {
        let Some(found) = result.outcome::<Vec<Partner>>() else {
            return Vec::new();
        };
        let control = &result.report.control;
        let mut lines = vec![format!(
            "second pieces: {} of the path's {} folds have one beside them",
            found.iter().filter(|p| p.piece.is_some()).count(),
            found.len()
        )];
        for p in found {
            let at = format!(
                "  fold {} at {control} = {}",
                p.fold,
                sig_digits(p.value, 6)
            );
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
            lines.push(format!(
                "{at}: a second piece, not reached by the path, at an RMS distance {} from \
                 the fold's state at the same {control} (the gap); {}: {} points beyond the \
                 fold, {critical}; stopped: {}",
                sig_digits(piece.gap, 4),
                piece.run.directory,
                r.rows.len(),
                r.stop
            ));
        }
        lines
    }
}
