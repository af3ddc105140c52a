//! `cusps.csv`, `cusp_curve.json` and `cusp_curve.svg`: the cusps of a limit curve followed
//! in a third parameter ([`CuspCurveReport`]).

use super::figure::{self, finish, Entry, Line, Mark, Plot, Sample, Symbol};
use super::scales::Scales;
use super::svg::xml_chars;
use super::{write_whole, Num, OutputError};
use crate::results::{CuspCurveReport, Extremum};
use plotters::style::RGBColor;
use std::io;
use std::path::{Path, PathBuf};

/// Writes `cusps.csv`, `cusp_curve.json`, `cusp_curve.svg` and `cusp_curve.png` into `dir`;
/// returns their paths.
///
/// `cusps.csv` has a row per cusp of every slice:
/// `<third>,refined,cusp,extremum,arclength,<each parameter>,<each measure>` (`cusp` its
/// number along the slice's curve, from 1). `cusp_curve.json` is the whole report: the
/// slices with their fold lines and cusps, and the ends of pairs of cusps. `cusp_curve.svg`
/// draws every slice's fold line in (second, control), its cusps marked, and each end's
/// estimate.
///
/// # Errors
/// [`OutputError::Invalid`] for a non-finite number in a cusp (nothing is written), else as
/// the other writers.
pub fn write_cusp_curve(
    dir: &Path,
    report: &CuspCurveReport,
    scales: &Scales,
    caption: &str,
) -> Result<Vec<PathBuf>, OutputError> {
    let csv = dir.join("cusps.csv");
    let json = dir.join("cusp_curve.json");
    let svg_path = dir.join("cusp_curve.svg");
    for sl in &report.slices {
        let bad = sl
            .cusps
            .iter()
            .flat_map(|e| e.parameters.iter().chain(&e.measures).chain([&e.arclength]))
            .chain(sl.line.iter().flatten())
            .any(|v| !v.is_finite());
        if bad || !sl.third.is_finite() {
            return Err(OutputError::invalid(
                &csv,
                format!(
                    "the slice at {} = {} holds a non-finite number",
                    report.third, sl.third
                ),
            ));
        }
    }
    let column = |name: &str| report.parameters.iter().position(|p| p == name);
    let (Some(c), Some(s)) = (column(&report.control), column(&report.second)) else {
        return Err(OutputError::invalid(
            &svg_path,
            "the control or the second parameter is not a parameter of the report".to_string(),
        ));
    };
    let svg = render(report, (c, s), scales, caption)
        .map_err(|e| OutputError::invalid(&svg_path, format!("plotting failed: {e}")))?;
    write_whole(&csv, |w| {
        let header: Vec<&str> = [
            report.third.as_str(),
            "refined",
            "cusp",
            "extremum",
            "arclength",
        ]
        .into_iter()
        .chain(report.parameters.iter().map(String::as_str))
        .chain(report.measures.iter().map(String::as_str))
        .collect();
        writeln!(w, "{}", header.join(","))?;
        for sl in &report.slices {
            for (i, e) in sl.cusps.iter().enumerate() {
                let extremum = e.extremum.map_or_else(String::new, |x| x.to_string());
                write!(
                    w,
                    "{},{},{},{extremum},{}",
                    Num(sl.third),
                    sl.refined,
                    i + 1,
                    Num(e.arclength)
                )?;
                for &v in e.parameters.iter().chain(&e.measures) {
                    write!(w, ",{}", Num(v))?;
                }
                writeln!(w)?;
            }
        }
        Ok(())
    })?;
    write_whole(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, report).map_err(io::Error::other)?;
        writeln!(w)
    })?;
    write_whole(&svg_path, |w| w.write_all(xml_chars(&svg).as_bytes()))?;
    let png = super::write_png_beside(&svg_path)?;
    Ok(vec![csv, json, svg_path, png])
}

/// A colour from blue (t = 0) to red (t = 1).
fn ramp(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let mix = |a: f64, b: f64| (a + (b - a) * t).round() as u8;
    RGBColor(mix(31.0, 200.0), mix(87.0, 40.0), mix(180.0, 40.0))
}

/// Every good slice's fold line in (second, control), its cusps marked; the ends' nearest
/// pairs ringed.
fn render(
    report: &CuspCurveReport,
    (c, s): (usize, usize),
    scales: &Scales,
    caption: &str,
) -> Result<String, Box<dyn std::error::Error>> {
    let (xs, ys) = (
        scales.or_name(&report.second),
        scales.or_name(&report.control),
    );
    let at = |p: &[f64]| (p[s] * xs.factor, p[c] * ys.factor);
    let title = format!(
        "cusps of the limit curve in ({}, {}) as {} varies",
        report.second, report.control, report.third
    );
    let mut plot = Plot::new(title, caption, &xs.label, &ys.label);
    let good: Vec<_> = report
        .slices
        .iter()
        .filter(|sl| sl.failure.is_none())
        .collect();
    let (lo, hi) = good
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), sl| {
            (a.min(sl.third), b.max(sl.third))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    // Only the part of each fold line near the cusps is of interest: the box of every cusp,
    // widened; without cusps, the whole lines.
    let cusps: Vec<(f64, f64)> = good
        .iter()
        .flat_map(|sl| sl.cusps.iter().map(|e| at(&e.parameters)))
        .collect();
    if cusps.len() >= 2 {
        let xr = figure::padded(cusps.iter().map(|p| p.0));
        let yr = figure::padded(cusps.iter().map(|p| p.1));
        let (wx, wy) = (xr.end - xr.start, yr.end - yr.start);
        plot.ranges = Some((xr.start - wx..xr.end + wx, yr.start - wy..yr.end + wy));
    }
    for (i, sl) in good.iter().enumerate() {
        let colour = ramp((sl.third - lo) / span);
        let points = sl
            .line
            .iter()
            .map(|p| (p[1] * xs.factor, p[0] * ys.factor))
            .filter(|p| match &plot.ranges {
                Some((x, y)) => x.contains(&p.0) && y.contains(&p.1),
                None => true,
            })
            .collect();
        plot.lines.push(Line::new(
            points,
            colour,
            if sl.refined { 1 } else { 2 },
            None,
        ));
        if i == 0 || i + 1 == good.len() {
            plot.legend.push(Entry::new(
                format!(
                    "fold line at {} = {}",
                    report.third,
                    figure::tick(sl.third, span)
                ),
                Sample::Line(colour, 2, None),
            ));
        }
        for e in &sl.cusps {
            let (symbol, kind) = match e.extremum {
                Some(Extremum::Maximum) => (
                    Symbol::Disc(RGBColor(200, 30, 30)),
                    format!("cusp, maximum of {}", report.second),
                ),
                _ => (
                    Symbol::Square(RGBColor(20, 140, 60)),
                    format!("cusp, minimum of {}", report.second),
                ),
            };
            plot.marks.push(Mark {
                at: at(&e.parameters),
                symbol,
                kind,
                label: String::new(),
            });
        }
    }
    if good.len() > 2 {
        plot.legend.push(Entry::new(
            format!(
                "{} slices between, coloured by {} (thin: added near an end)",
                good.len() - 2,
                report.third
            ),
            Sample::Note,
        ));
    }
    for e in &report.ends {
        let text = match e.estimate {
            Some(x) => format!(
                "{} ends at {} = {}",
                e.kind,
                report.third,
                figure::tick(x, span)
            ),
            None => format!("{} ends between the slices", e.kind),
        };
        plot.legend.push(Entry::new(text, Sample::Note));
    }
    let (svg, layout) = figure::render(&plot)?;
    Ok(finish(&svg, &layout))
}
