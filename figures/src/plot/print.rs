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
/// `path` with the extension `pdf`: one page of the printed size, vector, its text
/// as text in the embedded DejaVu Sans.
///
/// # Errors
/// plotters' error, an I/O error on either file, or svg2pdf's, as text.
pub fn finish(root: DrawingArea<SVGBackend<'_>, Shift>, path: &Path, width: PrintWidth) -> Result<(), String> {
    let (w, h) = root.dim_in_pixel();
    root.present().map_err(|e| e.to_string())?;
    drop(root);
    let svg = std::fs::read_to_string(path).map_err(|e| format!("reading back {}: {e}", path.display()))?;
    let svg = with_print_size(&svg, (w, h), width)?;
    std::fs::write(path, &svg).map_err(|e| format!("writing {}: {e}", path.display()))?;
    let pdf = to_pdf(&svg)?;
    let pdf_path = pdf_path(path);
    std::fs::write(&pdf_path, pdf).map_err(|e| format!("writing {}: {e}", pdf_path.display()))
}

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

/// The PDF of `svg`: its fonts from the figures' DejaVu Sans, 96 user units to
/// the inch (CSS's, which usvg takes the inch sizes in).
///
/// # Errors
/// usvg's or svg2pdf's error, as text.
pub fn to_pdf(svg: &str) -> Result<Vec<u8>, String> {
    let mut opt = svg2pdf::usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_font_data(super::font::bytes().to_vec());
    db.load_font_data(dejavu::sans::bold().to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    let tree = svg2pdf::usvg::Tree::from_str(svg, &opt).map_err(|e| format!("usvg: {e}"))?;
    let page = svg2pdf::PageOptions { dpi: 96.0 };
    let pdf = svg2pdf::to_pdf(&tree, svg2pdf::ConversionOptions::default(), page).map_err(|e| format!("svg2pdf: {e}"))?;
    Ok(with_sorted_resources(pdf))
}

/// `pdf` with the entries of each resource dictionary (`/xo3 12 0 R` lines) in
/// the order of their names, outside streams: svg2pdf 0.13 writes them in a
/// `HashMap`'s order, which differs from run to run, and the same figure must give
/// the same bytes (runs over different links are byte-identical). Sorting lines
/// within a run of lines keeps every byte offset of the file, so its
/// cross-reference table stays right.
fn with_sorted_resources(pdf: Vec<u8>) -> Vec<u8> {
    // A resource entry: spaces, `/`, lower-case letters, digits, ` N 0 R`.
    fn entry(line: &[u8]) -> Option<(&[u8], u64)> {
        let s = std::str::from_utf8(line).ok()?;
        let t = s.trim_start_matches(' ');
        let (name, rest) = t.strip_prefix('/')?.split_once(' ')?;
        let (obj, r) = rest.split_once(' ')?;
        (s.len() > t.len() && r == "0 R" && obj.bytes().all(|b| b.is_ascii_digit())).then_some(())?;
        let letters = name.trim_end_matches(|c: char| c.is_ascii_digit());
        (!letters.is_empty() && letters.bytes().all(|b| b.is_ascii_lowercase()) && letters.len() < name.len()).then_some(())?;
        Some((letters.as_bytes(), name[letters.len()..].parse().ok()?))
    }
    let mut out = Vec::with_capacity(pdf.len());
    let mut run: Vec<&[u8]> = Vec::new();
    let mut in_stream = false;
    let flush = |run: &mut Vec<&[u8]>, out: &mut Vec<u8>| {
        run.sort_by_key(|l| entry(l.strip_suffix(b"\n").unwrap_or(l)));
        for l in run.drain(..) {
            out.extend_from_slice(l);
        }
    };
    for line in pdf.split_inclusive(|&b| b == b'\n') {
        let text = line.strip_suffix(b"\n").unwrap_or(line);
        if in_stream {
            in_stream = !text.starts_with(b"endstream");
        } else if entry(text).is_some() {
            run.push(line);
            continue;
        } else {
            in_stream = text == b"stream";
        }
        flush(&mut run, &mut out);
        out.extend_from_slice(line);
    }
    flush(&mut run, &mut out);
    out
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

    /// A figure's PDF is one page of its printed size with its font embedded.
    #[test]
    fn a_figure_prints_at_its_size_with_its_font() {
        let svg = r#"<svg width="1008" height="288" viewBox="0 0 1008 288" xmlns="http://www.w3.org/2000/svg"><text x="10" y="20" font-family="sans-serif" font-size="14.5">θ̇₁ (rad/s), μ = 0.6</text></svg>"#;
        let sized = with_print_size(svg, (1008, 288), PrintWidth::TwoColumn).unwrap();
        assert!(sized.starts_with(r#"<svg width="7in" height="2.0000in" viewBox="0 0 1008 288""#), "{sized}");
        assert!(with_print_size(svg, (1000, 288), PrintWidth::TwoColumn).is_err());
        let pdf = to_pdf(&sized).unwrap();
        let text = String::from_utf8_lossy(&pdf);
        assert!(text.starts_with("%PDF-"));
        assert!(text.contains("/MediaBox [0 0 504 144]"), "a 7 x 2 in page");
        assert!(text.contains("/FontFile2"), "the font is embedded");
        assert!(text.contains("DejaVuSans"), "the font is the figures'");
    }

    /// The same figure gives the same PDF bytes every time (svg2pdf's resource
    /// dictionaries come in a hash map's order), and the sorting keeps its length.
    #[test]
    fn the_same_figure_gives_the_same_pdf() {
        let mut svg = String::from(r#"<svg width="3.5in" height="1in" viewBox="0 0 504 144" xmlns="http://www.w3.org/2000/svg">"#);
        for k in 0..30 {
            svg += &format!(
                r##"<polyline fill="none" opacity="0.{}" stroke="#0072B2" points="{k},0 {k},100"/><text x="{k}" y="120" font-size="14.5" opacity="0.{}">{k}</text>"##,
                k % 9 + 1,
                (k + 3) % 9 + 1
            );
        }
        svg += "</svg>";
        let first = to_pdf(&svg).unwrap();
        for _ in 0..8 {
            assert!(to_pdf(&svg).unwrap() == first, "the bytes differ between conversions");
        }
        let raw = svg2pdf::to_pdf(
            &svg2pdf::usvg::Tree::from_str(&svg, &{
                let mut o = svg2pdf::usvg::Options::default();
                o.fontdb_mut().load_font_data(super::super::font::bytes().to_vec());
                o
            })
            .unwrap(),
            svg2pdf::ConversionOptions::default(),
            svg2pdf::PageOptions { dpi: 96.0 },
        )
        .unwrap();
        assert_eq!(with_sorted_resources(raw.clone()).len(), raw.len());
        let sorted = String::from_utf8_lossy(&first);
        let gs: Vec<u64> =
            sorted.lines().filter_map(|l| l.trim().strip_prefix("/gs")).filter_map(|l| l.split(' ').next()?.parse().ok()).collect();
        assert!(gs.len() > 5 && gs.is_sorted(), "{gs:?}");
    }
}
