//! The font every figure draws its text with, embedded in the binary.
//!
//! plotters draws text through `ab_glyph` from fonts registered by name, so
//! the figures need no system font library (fontconfig, freetype) and look
//! the same on every machine. DejaVu Sans (`assets/fonts/DejaVuSans.ttf`,
//! licence beside it) is registered as the `sans-serif` family, the one
//! every figure names; bold text falls back to its regular face.

use crate::sweep::plot::PlotError;
use std::sync::OnceLock;

/// DejaVu Sans 2.37, unmodified.
const DEJAVU_SANS: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// The family name the figures use.
const FAMILY: &str = "sans-serif";

/// Register the embedded font with plotters (once per process; later calls
/// return the first call's outcome). Every drawing entry point calls it.
pub(crate) fn register() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, DEJAVU_SANS)
            .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font {
            family: FAMILY,
            file: "assets/fonts/DejaVuSans.ttf",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::prelude::*;

    #[test]
    fn the_embedded_font_lays_out_text() {
        register().expect("the embedded font parses");
        let style: TextStyle = (FAMILY, 20).into_font().into();
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, (200, 50)).into_drawing_area();
        let (w, h) = root.estimate_text_size("radau5(rcd0)", &style).unwrap();
        // Twelve glyphs at 20 px: a real font's advances, not zero.
        assert!((80..200).contains(&w), "width {w}");
        assert!(h > 10, "height {h}");
        // A bold request falls back to the regular face instead of failing.
        let bold: TextStyle = (FAMILY, 20).into_font().style(FontStyle::Bold).into();
        assert!(root.estimate_text_size("x", &bold).is_ok());
    }
}
