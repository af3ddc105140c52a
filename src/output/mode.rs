//! `critical_NN_mode.svg` and `.png`: a critical state's mode seen from above — its
//! component along the deformed surface's normal, over the deformed mesh projected on the
//! (x, y) plane at equal scales, with a colour bar.

use super::figure::{finish, Layout};
use super::svg::xml_chars;
use super::{write_whole, OutputError};
use meshes::Vec3;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::error::Error;
use std::path::{Path, PathBuf};

/// Width and height of a mode figure in pixels.
const SIZE: (u32, u32) = (760, 680);

/// The mode's normal component at every node, divided by its largest modulus (all zero for
/// a mode without normal component).
pub fn normal_component(mode: &[[f64; 3]], normals: &[[f64; 3]]) -> Vec<f64> {
    let w: Vec<f64> = mode
        .iter()
        .zip(normals)
        .map(|(m, n)| {
            let v = m[0] * n[0] + m[1] * n[1] + m[2] * n[2];
            if v.is_finite() {
                v
            } else {
                0.0
            }
        })
        .collect();
    let max = w.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if max > 0.0 {
        w.iter().map(|v| v / max).collect()
    } else {
        w
    }
}

/// The diverging colour of `t` in [-1, 1]: blue below zero, white at zero, red above.
pub fn diverging(t: f64) -> RGBColor {
    let t = t.clamp(-1.0, 1.0);
    let mix = |to: (f64, f64, f64), s: f64| {
        let c = |w: f64| (255.0 + (w - 255.0) * s).round() as u8;
        RGBColor(c(to.0), c(to.1), c(to.2))
    };
    if t < 0.0 {
        mix((33.0, 102.0, 172.0), -t)
    } else {
        mix((178.0, 24.0, 43.0), t)
    }
}

/// Writes `<stem>_mode.svg` and `<stem>_mode.png` into `dir`: the normal component of `mode`
/// (one vector per node) over the surface `positions` with `triangles`, seen from above (the
/// triangles drawn from the lowest to the highest, so that the top of a closed surface
/// shows), under `title` with `caption` below; returns their paths.
///
/// # Errors
/// [`OutputError::Invalid`] when the lengths disagree, a position is not finite or there is
/// no triangle (nothing is written); else as the other writers.
pub fn write_mode(
    dir: &Path,
    stem: &str,
    (positions, triangles): (&[Vec3], &[[usize; 3]]),
    mode: &[[f64; 3]],
    title: &str,
    caption: &str,
) -> Result<Vec<PathBuf>, OutputError> {
    let svg_path = dir.join(format!("{stem}_mode.svg"));
    let bad = |m: String| Err(OutputError::invalid(&svg_path, m));
    if mode.len() != positions.len() {
        return bad(format!(
            "a mode of {} nodes for a mesh of {}",
            mode.len(),
            positions.len()
        ));
    }
    if triangles.is_empty() || triangles.iter().flatten().any(|&i| i >= positions.len()) {
        return bad("the mesh has no triangles or a node out of range".to_string());
    }
    if positions.iter().any(|x| x.iter().any(|c| !c.is_finite())) {
        return bad("a node's position is not finite".to_string());
    }
    let w = normal_component(mode, &super::run::node_normals(positions, triangles));
    let svg = render(positions, triangles, &w, title, caption)
        .map_err(|e| OutputError::invalid(&svg_path, format!("plotting failed: {e}")))?;
    let layout = Layout {
        width: SIZE.0,
        height: SIZE.1,
        caption: caption.to_string(),
        ..Layout::default()
    };
    let svg = finish(&svg, &layout);
    write_whole(&svg_path, |f| f.write_all(xml_chars(&svg).as_bytes()))?;
    let png = super::write_png_beside(&svg_path)?;
    Ok(vec![svg_path, png])
}

/// The figure: the triangles in plan view at equal scales, coloured by the mean of their
/// corners' values `w`, and the colour bar at the right.
fn render(
    x: &[Vec3],
    triangles: &[[usize; 3]],
    w: &[f64],
    title: &str,
    caption: &str,
) -> Result<String, Box<dyn Error>> {
    let (lo, hi) = x.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    // The plan's box: square, left of the colour bar, below the title, above the caption.
    let (left, top, side) = (40.0, 60.0, 540.0);
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let scale = side / span;
    let centre = ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0);
    let px = |p: &Vec3| {
        (
            (left + side / 2.0 + (p[0] - centre.0) * scale).round() as i32,
            (top + side / 2.0 - (p[1] - centre.1) * scale).round() as i32,
        )
    };
    let mut order: Vec<usize> = (0..triangles.len()).collect();
    let height = |t: &[usize; 3]| t.iter().map(|&i| x[i][2]).sum::<f64>();
    order.sort_by(|&a, &b| height(&triangles[a]).total_cmp(&height(&triangles[b])));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let font = |size: u32, h: HPos| {
            ("sans-serif", size)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(h, VPos::Center))
        };
        root.draw(&Text::new(
            title.to_string(),
            (SIZE.0 as i32 / 2, 24),
            font(18, HPos::Center),
        ))?;
        for &k in &order {
            let t = &triangles[k];
            let mean = t.iter().map(|&i| w[i]).sum::<f64>() / 3.0;
            let c = diverging(mean);
            let pts: Vec<(i32, i32)> = t.iter().map(|&i| px(&x[i])).collect();
            root.draw(&Polygon::new(pts.clone(), c.filled()))?;
            // A hairline of the same colour closes the gaps between neighbours.
            let mut closed = pts;
            closed.push(closed[0]);
            root.draw(&PathElement::new(closed, c.stroke_width(1)))?;
        }
        // The colour bar: −1 at the bottom, +1 at the top.
        let (bx, by, bw, bh) = (620, 90, 24, 480);
        let steps = 96;
        for k in 0..steps {
            let t = 1.0 - 2.0 * (f64::from(k) + 0.5) / f64::from(steps);
            let y0 = by + bh * k / steps;
            let y1 = by + bh * (k + 1) / steps;
            root.draw(&Rectangle::new(
                [(bx, y0), (bx + bw, y1)],
                diverging(t).filled(),
            ))?;
        }
        root.draw(&Rectangle::new(
            [(bx, by), (bx + bw, by + bh)],
            BLACK.stroke_width(1),
        ))?;
        for (t, text) in [
            (1.0, "+1"),
            (0.5, "0.5"),
            (0.0, "0"),
            (-0.5, "−0.5"),
            (-1.0, "−1"),
        ] {
            let y = by + ((1.0 - t) / 2.0 * f64::from(bh)).round() as i32;
            root.draw(&PathElement::new(
                [(bx + bw, y), (bx + bw + 5, y)],
                BLACK.stroke_width(1),
            ))?;
            root.draw(&Text::new(text, (bx + bw + 8, y), font(13, HPos::Left)))?;
        }
        root.draw(&Text::new(
            "normal component / max",
            (bx + bw / 2, by - 22),
            font(13, HPos::Center),
        ))?;
        root.draw(&Text::new(
            "seen from above (x right, y up), equal scales",
            (left as i32, (top + side) as i32 + 22),
            font(13, HPos::Left),
        ))?;
        super::figure::draw_caption(&root, caption, SIZE)?;
        root.present()?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_component_of_a_flat_square_is_the_z_component_scaled() {
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let t = [[0, 1, 2], [0, 2, 3]];
        let n = super::super::run::node_normals(&x, &t);
        for v in &n {
            assert!((v[2] - 1.0).abs() < 1e-12 && v[0].abs() < 1e-12);
        }
        let mode = [
            [5.0, 0.0, 1.0],
            [0.0, 3.0, -2.0],
            [0.0, 0.0, 0.5],
            [9.0, 9.0, 0.0],
        ];
        let w = normal_component(&mode, &n);
        assert_eq!(w, vec![0.5, -1.0, 0.25, 0.0]);
        assert_eq!(diverging(0.0), RGBColor(255, 255, 255));
        assert_eq!(diverging(1.0), RGBColor(178, 24, 43));
        assert_eq!(diverging(-1.0), RGBColor(33, 102, 172));
    }

    #[test]
    fn a_mode_of_the_wrong_length_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let e = write_mode(
            dir.path(),
            "critical_01",
            (&x, &[[0, 1, 2]]),
            &[[0.0; 3]],
            "t",
            "c",
        );
        assert!(e.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let files = write_mode(
            dir.path(),
            "critical_01",
            (&x, &[[0, 1, 2]]),
            &[[0.0, 0.0, 1.0]; 3],
            "t",
            "c",
        )
        .unwrap();
        assert!(files.iter().all(|f| f.exists()));
    }
}
