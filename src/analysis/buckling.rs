//! The `linear-buckling` analysis: the start state held while the control sweeps
//! `[min, max]` in `samples` steps. At every sample the tangent at the held state is split by
//! irrep; where a block's negative count changes between samples its eigenvalue crossing is
//! localised in the control and classified (a singular trivial block of a held state is a
//! symmetric bifurcation: the state cannot fold). The lowest eigenvalue of every block at
//! every sample goes into the report's [`Spectra`] (what `path.svg` plots for this analysis).

use super::equilibrium::path_options;
use super::{Analysis, Context, RunError};
use crate::continuation::crossings::End;
use crate::continuation::crossings::Spectrum;
use crate::continuation::events::Event;
use crate::continuation::PathOptions;
use crate::results::{
    Spectra, SpectrumIrrep, SpectrumRow, StateKind, StopReason, SPECTRUM_EIGENVALUES,
};
use crate::scene::AnalysisSpec as _;
use crate::scene::LinearBucklingAnalysis;
use crate::study::Study;

/// `type = "linear-buckling"`.
pub struct Buckling(pub LinearBucklingAnalysis);

impl Analysis for Buckling {
    fn options(&self, study: &dyn Study) -> PathOptions {
        let settings = self.0.settings();
        path_options(study, &settings, Some((f64::NEG_INFINITY, f64::INFINITY)))
    }

    fn held(&self) -> bool {
        true
    }

    fn run(&self, study: &dyn Study, cx: &mut Context<'_>) -> Result<StopReason, RunError> {
        let (u, params) = (cx.start.u.clone(), cx.start.params.clone());
        Ok(sweep(study, cx, &u, &params, self.0.samples))
    }
}

/// Sweeps the control over its range at the held state `u` (solved at `params_start`).
fn sweep(
    study: &dyn Study,
    cx: &mut Context<'_>,
    u: &[f64],
    params_start: &[f64],
    samples: usize,
) -> StopReason {
    let Some(control) = study.control() else {
        return StopReason::NoControl;
    };
    let c = control.index;
    let (lo, hi) = (
        Some(control.min).filter(|v| v.is_finite()).unwrap_or(0.0),
        Some(control.max).filter(|v| v.is_finite()).unwrap_or(1.0),
    );
    let record = &mut cx.record;
    let observer = &mut *cx.observer;
    let mut crossings = cx.crossings.take();
    let at = |value: f64| {
        let mut p = params_start.to_vec();
        p[c] = value;
        p
    };
    let mut previous: Option<(Spectrum, f64)> = None;
    let mut sampled: Vec<(usize, f64, Option<Sample>)> = Vec::with_capacity(samples + 1);
    let mut stop = StopReason::Swept {
        min: lo,
        max: hi,
        samples,
    };
    for i in 0..=samples {
        if i > 0 && crate::continuation::interrupt::requested() {
            stop = StopReason::Interrupted;
            break;
        }
        let value = lo + (hi - lo) * (i as f64 / samples as f64);
        if i > 0 {
            // A sample is the sweep's step (the test hook counts it).
            crate::continuation::interrupt::step_accepted();
        }
        observer.progress(i, value);
        let params = at(value);
        observer.state(u, &params);
        let spectrum = crossings.as_mut().and_then(|x| x.spectrum(u, &params));
        sampled.push((i, value, spectrum.as_ref().map(Sample::of)));
        let index = spectrum.as_ref().map(|s| s.index);
        record.row(study, i, value - lo, u, params.clone(), 0, index);
        if let (Some((a, va)), Some(b), Some(x)) = (&previous, &spectrum, crossings.as_mut()) {
            if a.negatives() != b.negatives() {
                let va = *va;
                let pa = at(va);
                let ends = (
                    End {
                        spectrum: a,
                        u,
                        params: &pa,
                    },
                    End {
                        spectrum: b,
                        u,
                        params: &params,
                    },
                );
                for event in x.localise(ends.0, ends.1, i - 1, value - va, false, |s| {
                    Some((u.to_vec(), at(va + s)))
                }) {
                    match event {
                        Event::Critical(cp) => record.add_critical(cp),
                        Event::Warning(w) => record.warnings.push(w),
                        Event::Turning(_) | Event::Stop(_) => {}
                    }
                }
            }
        }
        previous = spectrum.map(|s| (s, value));
    }
    record.spectra = spectra_of(sampled);
    record.irreps = record
        .spectra
        .irreps
        .iter()
        .map(|i| i.name.clone())
        .collect();
    for (row, s) in record.rows.iter_mut().zip(&record.spectra.rows) {
        row.negative = s.negative.iter().copied().collect();
    }
    record.state(0, StateKind::Held, u.to_vec(), &at(lo));
    stop
}

/// What the report keeps of one sample's spectrum: per block, its irrep, its lowest
/// eigenvalues relative to the scale (the finite ones, up to [`SPECTRUM_EIGENVALUES`]) and
/// its negative count.
struct Sample {
    scale: f64,
    blocks: Vec<(SpectrumIrrep, Vec<f64>, usize)>,
}

impl Sample {
    fn of(s: &Spectrum) -> Self {
        Self {
            scale: s.scale,
            blocks: s
                .blocks
                .iter()
                .map(|b| {
                    let irrep = SpectrumIrrep {
                        name: b.irrep.clone(),
                        dim: b.dim,
                        size: b.size,
                        eigenvalues: !b.eigenvalues.is_empty(),
                    };
                    let lowest: Vec<f64> = b
                        .eigenvalues
                        .iter()
                        .map(|l| l / s.scale)
                        .take_while(|l| l.is_finite())
                        .take(SPECTRUM_EIGENVALUES)
                        .collect();
                    (irrep, lowest, b.negative)
                })
                .collect(),
        }
    }
}

/// The report's [`Spectra`] from the samples `(step, control, sample)` of a sweep: the irreps
/// of the first analysed sample, a row per sample (all `None` where it was not analysed).
fn spectra_of(sampled: Vec<(usize, f64, Option<Sample>)>) -> Spectra {
    let Some(first) = sampled.iter().find_map(|s| s.2.as_ref()) else {
        return Spectra::default();
    };
    let mut irreps: Vec<SpectrumIrrep> = first.blocks.iter().map(|b| b.0.clone()).collect();
    let n = irreps.len();
    let rows: Vec<SpectrumRow> = sampled
        .into_iter()
        .map(|(step, control, sample)| {
            let sample = sample.filter(|s| s.blocks.len() == n && s.scale.is_finite());
            SpectrumRow {
                step,
                control,
                scale: sample.as_ref().map_or(0.0, |s| s.scale),
                lowest: sample.as_ref().map_or_else(
                    || vec![None; n],
                    |s| s.blocks.iter().map(|b| b.1.first().copied()).collect(),
                ),
                eigenvalues: sample.as_ref().map_or_else(
                    || vec![Vec::new(); n],
                    |s| s.blocks.iter().map(|b| b.1.clone()).collect(),
                ),
                negative: sample.as_ref().map_or_else(
                    || vec![None; n],
                    |s| s.blocks.iter().map(|b| Some(b.2)).collect(),
                ),
            }
        })
        .collect();
    // A block counts as having eigenvalues if any sample computed them.
    for (mu, irrep) in irreps.iter_mut().enumerate() {
        irrep.eigenvalues = rows.iter().any(|r| r.lowest[mu].is_some());
    }
    Spectra { irreps, rows }
}
