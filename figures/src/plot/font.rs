//! The figures' font: DejaVu Sans (the `dejavu` crate, Bitstream Vera licence),
//! registered with plotters under the family `sans-serif`, so that plotters lays
//! text out with real glyph advances (its `ab_glyph` backend) instead of a guess.
//!
//! The SVG files still name the generic family `sans-serif`: DejaVu Sans is among
//! the widest common sans-serif faces, so text laid out for it fits in the space
//! given when a viewer substitutes Helvetica, Arial or Liberation Sans. The test
//! over every figure (`tests/e2e/figure_check.rs`) measures text with the same
//! font.

use std::sync::Once;

use plotters::style::{FontStyle, register_font};

/// The family every figure uses.
pub const FAMILY: &str = "sans-serif";

/// plotters' font size of the smallest text a figure draws (tick labels, legend
/// labels, notes): 18, which prints at 7.26 pt on a figure's print width
/// ([`super::print::printed_pt`]), above the 7 pt floor.
pub const TEXT_PX: f64 = 18.0;
/// plotters' font size of axis descriptions (7.7 pt in print).
pub const DESC_PX: f64 = 19.0;
/// plotters' font size of a chart's caption above it (8.1 pt in print).
pub const CAPTION_PX: f64 = 20.0;
/// plotters' font size of a figure's title (8.9 pt in print).
pub const TITLE_PX: f64 = 22.0;

/// The bytes of the font the figures are laid out with (DejaVu Sans 2.37, TrueType).
pub fn bytes() -> &'static [u8] {
    dejavu::sans::regular()
}

/// Registers the font with plotters, once per process. Idempotent; called by
/// [`super::svg_canvas`] before any figure is drawn.
pub fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType file shipped in the crate: registration
        // cannot fail; if it did, text would fail to draw with a plot error.
        let _ = register_font(FAMILY, FontStyle::Normal, bytes());
        let _ = register_font(FAMILY, FontStyle::Bold, dejavu::sans::bold());
    });
}
