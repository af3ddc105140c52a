//! PNG images of the SVG figures, rendered by the binary itself (resvg) with the bundled
//! DejaVu Sans (`assets/fonts`, see its README for the licence), so that a user without a
//! browser or Python gets a picture and a machine without system fonts still gets its text.

use super::{write_whole, OutputError};
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};

/// The font every PNG's text is set in.
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Pixels per SVG pixel: twice the SVG's size, for print.
pub const PNG_SCALE: f32 = 2.0;

/// `svg` rendered as a PNG image at [`PNG_SCALE`] times its size on white.
///
/// # Errors
/// A message if the SVG does not parse or the image cannot be made.
pub fn render_png(svg: &str) -> Result<Vec<u8>, String> {
    let mut options = usvg::Options::default();
    {
        let fonts = options.fontdb_mut();
        fonts.load_font_data(FONT.to_vec());
        for set in [
            usvg::fontdb::Database::set_sans_serif_family,
            usvg::fontdb::Database::set_serif_family,
            usvg::fontdb::Database::set_monospace_family,
        ] {
            set(fonts, "DejaVu Sans");
        }
    }
    options.font_family = "DejaVu Sans".to_string();
    let tree = usvg::Tree::from_str(svg, &options).map_err(|e| e.to_string())?;
    let size = tree.size();
    let (w, h) = (
        (size.width() * PNG_SCALE).ceil() as u32,
        (size.height() * PNG_SCALE).ceil() as u32,
    );
    let mut pixmap =
        tiny_skia::Pixmap::new(w, h).ok_or_else(|| format!("an image of {w} × {h} pixels"))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        tiny_skia::Transform::from_scale(PNG_SCALE, PNG_SCALE),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(|e| e.to_string())
}

/// Writes the PNG of the SVG file `svg` beside it (same name, `.png`) and returns its path.
///
/// # Errors
/// [`OutputError::Io`] if the SVG cannot be read or the PNG written; [`OutputError::Invalid`]
/// if it cannot be rendered (nothing is written).
pub fn write_png_beside(svg: &Path) -> Result<PathBuf, OutputError> {
    let png = svg.with_extension("png");
    let text = std::fs::read_to_string(svg).map_err(|source| OutputError::Io {
        path: svg.to_path_buf(),
        source,
    })?;
    let bytes = render_png(&text)
        .map_err(|e| OutputError::invalid(&png, format!("cannot render {}: {e}", svg.display())))?;
    write_whole(&png, |w| w.write_all(&bytes))?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text is drawn with the bundled font: a text-only SVG gets dark pixels.
    #[test]
    fn text_renders_without_system_fonts() {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="120" height="40"><text x="5" y="28" font-family="sans-serif" font-size="24">p R/μH</text></svg>"#;
        let png = render_png(svg).unwrap();
        let image = tiny_skia::Pixmap::decode_png(&png).unwrap();
        assert_eq!((image.width(), image.height()), (240, 80));
        let dark = image
            .pixels()
            .iter()
            .filter(|p| p.red() < 100 && p.alpha() > 200)
            .count();
        assert!(dark > 200, "{dark} dark pixels");
    }
}
