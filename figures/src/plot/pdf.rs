//! A figure's PDF (the feature `pdf`): svg2pdf's conversion of the printed SVG
//! ([`super::print::finish`]), its text as text in the embedded, subset DejaVu
//! Sans, with bytes that do not vary from run to run.

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
    use crate::plot::PrintWidth;

    /// A figure's PDF is one page of its printed size with its font embedded.
    #[test]
    fn a_figure_prints_at_its_size_with_its_font() {
        let svg = r#"<svg width="7in" height="2.0000in" viewBox="0 0 1008 288" xmlns="http://www.w3.org/2000/svg"><text x="10" y="20" font-family="sans-serif" font-size="14.5">θ̇₁ (rad/s), μ = 0.6</text></svg>"#;
        assert_eq!(PrintWidth::TwoColumn.inches(), 7.0);
        let pdf = to_pdf(svg).unwrap();
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
