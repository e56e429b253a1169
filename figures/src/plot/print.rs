//! Figures at a journal's print size: every figure is drawn for one column
//! (3.5 in) or the full page width (7 in), at 2 SVG px per printed point, and its
//! file says so (`width="7in"` over a `viewBox` in px), so that a viewer, LaTeX or
//! a journal's system prints it at the size its text was designed for: no text
//! below [`MIN_TEXT_PT`]. Each figure is also written as a PDF beside its SVG
//! (svg2pdf: vector, the text as text in the embedded, subset DejaVu Sans).
//!
//! Sources: the column widths are the common two-column journal layout (IEEE and
//! IFAC: 3.5 in per column, 7.16 in across; Elsevier: 90 mm and 190 mm); 7 pt is
//! the smallest text those journals' artwork guides accept.

use std::path::{Path, PathBuf};

use plotters::{coord::Shift, prelude::*};

/// SVG px per printed point (pt, 1/72 in): a two-column figure is 1008 px wide.
pub const PX_PER_PT: f64 = 2.0;

/// The smallest text a figure may print, pt.
pub const MIN_TEXT_PT: f64 = 7.0;

/// plotters writes a font of size `s` as an SVG `font-size` of `s / 1.24` px.
pub const PLOTTERS_FONT_SCALE: f64 = 1.24;

/// The width a figure is designed for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PrintWidth {
    /// One column of a two-column page, 3.5 in.
    OneColumn,
    /// The full width of a two-column page, 7 in.
    TwoColumn,
}

impl PrintWidth {
    /// The printed width, inches.
    pub const fn inches(self) -> f64 {
        match self {
            Self::OneColumn => 3.5,
            Self::TwoColumn => 7.0,
        }
    }

    /// The canvas width, SVG px ([`PX_PER_PT`] per point): 504 or 1008.
    pub const fn px(self) -> u32 {
        match self {
            Self::OneColumn => 504,
            Self::TwoColumn => 1008,
        }
    }
}

/// The printed size, pt, of text plotters draws at font size `px`.
pub fn printed_pt(px: f64) -> f64 {
    px / PLOTTERS_FONT_SCALE / PX_PER_PT
}

/// Presents `root` (plotters writes the SVG at `path`), then sets the file's
/// printed size (`width` inches across, the height in the same scale, over a
/// `viewBox` of the canvas in px) and writes the same figure as a PDF at
/// `path` with the extension `pdf` ([`WRITES_PDF`]: with the feature `pdf`): one
/// page of the printed size, vector, its text as text in the embedded DejaVu Sans
/// (`super::pdf`).
///
/// # Errors
/// plotters' error, an I/O error on either file, or svg2pdf's, as text.
pub fn finish(root: DrawingArea<SVGBackend<'_>, Shift>, path: &Path, width: PrintWidth) -> Result<(), String> {
    let (w, h) = root.dim_in_pixel();
    root.present().map_err(|e| e.to_string())?;
    drop(root);
    let svg = tables::input::read_to_string(path, tables::input::FIGURE).map_err(|e| format!("reading back: {e}"))?;
    let svg = with_print_size(&svg, (w, h), width)?;
    std::fs::write(path, &svg).map_err(|e| format!("writing {}: {e}", path.display()))?;
    #[cfg(feature = "pdf")]
    {
        let pdf = super::pdf::to_pdf(&svg)?;
        let pdf_path = pdf_path(path);
        std::fs::write(&pdf_path, pdf).map_err(|e| format!("writing {}: {e}", pdf_path.display()))?;
    }
    Ok(())
}

/// Whether [`finish`] writes each figure's PDF beside its SVG: this build has the
/// feature `pdf` (svg2pdf). Without it the figures are SVG only.
pub const WRITES_PDF: bool = cfg!(feature = "pdf");

/// Where the PDF of the figure at `svg` goes: beside it with the extension `pdf`;
/// for a file staged by `sil-host`'s `OutputSet::stage_figure`
/// (`.name.svg.partial`), the PDF's staged name (`.name.pdf.partial`).
pub fn pdf_path(svg: &Path) -> PathBuf {
    let name = svg.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    match name.strip_suffix(".svg.partial") {
        Some(stem) => svg.with_file_name(format!("{stem}.pdf.partial")),
        None => svg.with_extension("pdf"),
    }
}

/// `svg` (plotters' output, its root `<svg width="W" height="H" viewBox="0 0 W
/// H"`) with the width and height in inches for `width`.
///
/// # Errors
/// When the root element is not plotters' (the size cannot be set).
fn with_print_size(svg: &str, (w, h): (u32, u32), width: PrintWidth) -> Result<String, String> {
    let from = format!(r#"<svg width="{w}" height="{h}" "#);
    if !svg.starts_with(&from) {
        return Err(format!("the SVG does not start with {from:?}"));
    }
    let scale = width.inches() / w as f64;
    let to = format!(r#"<svg width="{}in" height="{:.4}in" "#, width.inches(), h as f64 * scale);
    Ok(format!("{to}{}", &svg[from.len()..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The smallest text prints at 7 pt or more; the widths are the journals'.
    #[test]
    fn the_smallest_text_prints_at_seven_points() {
        use super::super::font::TEXT_PX;
        assert!(printed_pt(TEXT_PX) >= MIN_TEXT_PT);
        assert!(printed_pt(TEXT_PX - 1.0) < MIN_TEXT_PT, "18 is the smallest size that prints at 7 pt");
        for w in [PrintWidth::OneColumn, PrintWidth::TwoColumn] {
            assert_eq!(w.px() as f64, w.inches() * 72.0 * PX_PER_PT);
        }
    }

    /// The printed size is set over plotters' viewBox, and a root that is not
    /// plotters' is refused.
    #[test]
    fn a_figure_gets_its_printed_size() {
        let svg = r#"<svg width="1008" height="288" viewBox="0 0 1008 288" xmlns="http://www.w3.org/2000/svg"></svg>"#;
        let sized = with_print_size(svg, (1008, 288), PrintWidth::TwoColumn).unwrap();
        assert!(sized.starts_with(r#"<svg width="7in" height="2.0000in" viewBox="0 0 1008 288""#), "{sized}");
        assert!(with_print_size(svg, (1000, 288), PrintWidth::TwoColumn).is_err());
    }
}
