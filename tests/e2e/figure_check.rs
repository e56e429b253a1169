//! The check every figure must pass (issue 25), shared by `tests/e2e/figures.rs`
//! and `tests/e2e/report.rs`: each SVG is parsed (roxmltree), every text
//! element's box is measured with the font the figures are laid out with (DejaVu
//! Sans, `ab_glyph`), and the boxes must lie inside the canvas and overlap no
//! other; no tick reads `-0`; no text prints below 7 pt at the figure's print
//! size (its `width` in inches over its `viewBox` in px, issue 44); every legend
//! entry's swatch (its colour on the same kind of mark) occurs in the figure
//! outside the legend; each figure has its PDF beside it. Each figure is also
//! rendered to PNG with resvg (the same font) into `target/tmp/figures/`, to be
//! looked at.

use std::path::{Path, PathBuf};

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

/// A text element's ink box on the canvas, px.
#[derive(Debug, Clone)]
pub struct TextBox {
    /// The text.
    pub text: String,
    /// Left, top, right, bottom, px (y down).
    pub rect: [f64; 4],
    /// Its font size, px.
    pub font_px: f64,
}

fn fonts() -> (FontRef<'static>, FontRef<'static>) {
    (FontRef::try_from_slice(dejavu::sans::regular()).unwrap(), FontRef::try_from_slice(dejavu::sans::bold()).unwrap())
}

/// A length such as `0.76em`, `0.5ex` or `3` in px at font size `fs` (px). `ex`
/// is half an em, as resvg takes it.
fn length(s: &str, fs: f64) -> f64 {
    let s = s.trim();
    if let Some(v) = s.strip_suffix("em") {
        v.parse::<f64>().unwrap_or(0.0) * fs
    } else if let Some(v) = s.strip_suffix("ex") {
        v.parse::<f64>().unwrap_or(0.0) * fs * 0.5
    } else {
        s.trim_end_matches("px").parse::<f64>().unwrap_or(0.0)
    }
}

/// The ink box of `text` at font size `fs` px with its baseline origin at (0, 0):
/// left, top, right, bottom; and its advance width. `None` for text with no ink.
fn ink(font: &FontRef, text: &str, fs: f64) -> (Option<[f64; 4]>, f64) {
    let scale = PxScale::from((fs * font.height_unscaled() as f64 / font.units_per_em().unwrap() as f64) as f32);
    let f = font.as_scaled(scale);
    let mut caret = 0f32;
    let mut prev = None;
    let mut rect: Option<[f64; 4]> = None;
    for c in text.chars() {
        let id = f.glyph_id(c);
        if let Some(p) = prev {
            caret += f.kern(p, id);
        }
        let glyph = id.with_scale_and_position(scale, point(caret, 0.0));
        if let Some(o) = font.outline_glyph(glyph) {
            let b = o.px_bounds();
            let r = [b.min.x as f64, b.min.y as f64, b.max.x as f64, b.max.y as f64];
            rect = Some(match rect {
                None => r,
                Some(a) => [a[0].min(r[0]), a[1].min(r[1]), a[2].max(r[2]), a[3].max(r[3])],
            });
        }
        caret += f.h_advance(id);
        prev = Some(id);
    }
    (rect, caret as f64)
}

/// `rotate(a, cx, cy)` from a transform attribute.
fn rotation(t: &str) -> Option<(f64, f64, f64)> {
    let inner = t.trim().strip_prefix("rotate(")?.strip_suffix(')')?;
    let v: Vec<f64> = inner.split([',', ' ']).filter(|s| !s.is_empty()).map(|s| s.parse().unwrap_or(0.0)).collect();
    match v.as_slice() {
        [a] => Some((*a, 0.0, 0.0)),
        [a, x, y] => Some((*a, *x, *y)),
        _ => None,
    }
}

/// The code names a figure writes as symbols (`plot::symbols`): none may stand as
/// a word in its text.
pub const CODE_NAMES: [&str; 14] =
    ["theta1", "theta2", "theta1_dot", "theta2_dot", "mu", "mu_hat", "e_n", "z_t", "Z_t", "z_n", "f_n", "z_r_dot", "v_belt", "u1"];

/// The smallest text a figure may print, pt.
pub const MIN_TEXT_PT: f64 = 7.0;

/// The canvas of `root` in px: its `viewBox` size, or its `width` and `height`.
fn canvas_px(root: roxmltree::Node) -> (f64, f64) {
    if let Some(vb) = root.attribute("viewBox") {
        let v: Vec<f64> = vb.split([' ', ',']).filter(|s| !s.is_empty()).map(|s| s.parse().expect("viewBox numbers")).collect();
        return (v[2], v[3]);
    }
    let dim = |a: &str| root.attribute(a).and_then(|v| v.trim_end_matches("px").parse::<f64>().ok()).expect("canvas size");
    (dim("width"), dim("height"))
}

/// Printed pt per canvas px of `svg`: its `width` in inches (`7in`) over its
/// canvas width; `None` when the figure gives no print size.
pub fn pt_per_px(svg: &str) -> Option<f64> {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    let root = doc.root_element();
    let inches: f64 = root.attribute("width")?.strip_suffix("in")?.parse().ok()?;
    Some(inches * 72.0 / canvas_px(root).0)
}

/// The canvas size and the ink box of every non-empty text element of `svg`.
///
/// # Panics
/// On an SVG that does not parse, or a text element that is not laid out by
/// plotters' SVG backend (nested `tspan`, a transform other than `rotate`).
pub fn text_boxes(svg: &str) -> ((f64, f64), Vec<TextBox>) {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    let root = doc.root_element();
    let canvas = canvas_px(root);
    let (regular, bold) = fonts();
    let mut boxes = Vec::new();
    for node in doc.descendants().filter(|n| n.has_tag_name("text")) {
        let text: String = node.descendants().filter(|n| n.is_text()).filter_map(|n| n.text()).collect::<String>().trim().to_string();
        if text.trim().is_empty() {
            continue;
        }
        let num = |a: &str| node.attribute(a).map_or(0.0, |v| v.parse::<f64>().unwrap_or(0.0));
        let fs = node.attribute("font-size").map_or(16.0, |v| length(v, 16.0));
        let font = if node.attribute("font-weight") == Some("bold") { &bold } else { &regular };
        let (ink_rect, advance) = ink(font, &text, fs);
        let Some(r) = ink_rect else { continue };
        let shift = match node.attribute("text-anchor") {
            Some("middle") => -advance / 2.0,
            Some("end") => -advance,
            _ => 0.0,
        };
        let x = num("x") + shift;
        let y = num("y") + node.attribute("dy").map_or(0.0, |d| length(d, fs));
        let mut corners = [(x + r[0], y + r[1]), (x + r[2], y + r[1]), (x + r[0], y + r[3]), (x + r[2], y + r[3])];
        if let Some(t) = node.attribute("transform") {
            let (a, cx, cy) = rotation(t).unwrap_or_else(|| panic!("unexpected transform {t}"));
            let (s, c) = a.to_radians().sin_cos();
            for p in &mut corners {
                let (dx, dy) = (p.0 - cx, p.1 - cy);
                *p = (cx + dx * c - dy * s, cy + dx * s + dy * c);
            }
        }
        let rect = corners
            .iter()
            .fold([f64::MAX, f64::MAX, f64::MIN, f64::MIN], |a, p| [a[0].min(p.0), a[1].min(p.1), a[2].max(p.0), a[3].max(p.1)]);
        boxes.push(TextBox { text, rect, font_px: fs });
    }
    (canvas, boxes)
}

/// What is wrong with the figure `svg`: text outside the canvas, two texts that
/// overlap (by more than half a pixel both ways), a tick reading `-0`, a code
/// name where its symbol belongs ([`CODE_NAMES`]), no print
/// size, text below [`MIN_TEXT_PT`] at it, a legend entry whose mark does not
/// occur ([`legend_problems`]). Empty when it passes.
pub fn problems(svg: &str) -> Vec<String> {
    let ((w, h), boxes) = text_boxes(svg);
    let mut out = legend_problems(svg);
    match pt_per_px(svg) {
        None => out.push("no print size (width in inches over a viewBox)".into()),
        Some(scale) => {
            for b in &boxes {
                let pt = b.font_px * scale;
                if pt < MIN_TEXT_PT - 1e-6 {
                    out.push(format!("{:?} prints at {pt:.2} pt, below {MIN_TEXT_PT} pt", b.text));
                }
            }
        }
    }
    let tol = 0.5;
    for b in &boxes {
        let [l, t, r, btm] = b.rect;
        if l < -tol || t < -tol || r > w + tol || btm > h + tol {
            out.push(format!("outside the {w} x {h} canvas: {:?} at [{l:.1}, {t:.1}, {r:.1}, {btm:.1}]", b.text));
        }
        let s = b.text.trim();
        for word in s.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
            if CODE_NAMES.contains(&word) {
                out.push(format!("{:?} writes the code name {word:?}, not its symbol", b.text));
            }
        }
        if s.starts_with('-') && s.parse::<f64>().is_ok_and(|v| v == 0.0) {
            out.push(format!("a tick reads {s:?}"));
        }
    }
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            let ox = a.rect[2].min(b.rect[2]) - a.rect[0].max(b.rect[0]);
            let oy = a.rect[3].min(b.rect[3]) - a.rect[1].max(b.rect[1]);
            if ox > tol && oy > tol {
                out.push(format!("{:?} overlaps {:?} ({ox:.1} x {oy:.1} px)", a.text, b.text));
            }
        }
    }
    out
}

/// A mark's colour (`#RRGGBB`, upper case) and kind: `line` (a polyline, line or
/// path, by its stroke), `dot` (a circle), `box` (a rect) or `triangle` (a
/// polygon), by its fill, else its stroke.
fn mark(node: roxmltree::Node) -> Option<(String, &'static str)> {
    let kind = match node.tag_name().name() {
        "polyline" | "line" | "path" => "line",
        "circle" => "dot",
        "rect" => "box",
        "polygon" => "triangle",
        _ => return None,
    };
    let paint = |a: &str| node.attribute(a).filter(|v| *v != "none").map(str::to_uppercase);
    let color = if kind == "line" { paint("stroke") } else { paint("fill").or_else(|| paint("stroke")) }?;
    Some((color, kind))
}

/// The legend entries of `svg` whose swatch occurs nowhere else in it. An entry is
/// a text anchored at its start with the marks drawn just before it (plotters
/// writes elements in drawing order) lying within 24 px to its left and 12 px of
/// its middle: its swatch. The swatch's first filled mark (else its first mark)
/// gives the colour and kind to find among the figure's other marks.
pub fn legend_problems(svg: &str) -> Vec<String> {
    legend_entries(svg)
        .into_iter()
        .filter(|e| !e.found)
        .map(|e| format!("the legend entry {:?} ({} {}) occurs nowhere in the figure", e.label, e.kind, e.color))
        .collect()
}

/// A legend entry of a figure ([`legend_entries`]).
#[derive(Debug, Clone)]
pub struct LegendEntry {
    /// Its label.
    pub label: String,
    /// Its swatch's colour, `#RRGGBB`.
    pub color: String,
    /// Its swatch's kind of mark ([`mark`]).
    pub kind: &'static str,
    /// Whether that mark occurs outside the legend.
    pub found: bool,
}

/// The legend entries of `svg`, as [`legend_problems`] finds them.
pub fn legend_entries(svg: &str) -> Vec<LegendEntry> {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    let elements: Vec<roxmltree::Node> = doc.root_element().children().filter(|n| n.is_element()).collect();
    let num = |n: &roxmltree::Node, a: &str| n.attribute(a).and_then(|v| v.parse::<f64>().ok());
    // A mark's box: left, top, right, bottom (px).
    let bounds = |n: &roxmltree::Node| -> Option<[f64; 4]> {
        match n.tag_name().name() {
            "polyline" | "polygon" => {
                let pts: Vec<f64> =
                    n.attribute("points")?.split([' ', ',']).filter(|s| !s.is_empty()).filter_map(|s| s.parse().ok()).collect();
                let (xs, ys): (Vec<f64>, Vec<f64>) = pts.chunks(2).map(|p| (p[0], p[1])).unzip();
                Some([
                    xs.iter().copied().fold(f64::MAX, f64::min),
                    ys.iter().copied().fold(f64::MAX, f64::min),
                    xs.iter().copied().fold(f64::MIN, f64::max),
                    ys.iter().copied().fold(f64::MIN, f64::max),
                ])
            }
            "circle" => {
                let (x, y, r) = (num(n, "cx")?, num(n, "cy")?, num(n, "r")?);
                Some([x - r, y - r, x + r, y + r])
            }
            "rect" => {
                let (x, y) = (num(n, "x")?, num(n, "y")?);
                Some([x, y, x + num(n, "width")?, y + num(n, "height")?])
            }
            _ => None,
        }
    };
    let mut swatch_of: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, t) in elements.iter().enumerate().filter(|(_, n)| n.has_tag_name("text")) {
        if t.attribute("text-anchor").is_some_and(|a| a != "start") || t.attribute("transform").is_some() {
            continue;
        }
        let (Some(x), Some(y)) = (num(t, "x"), num(t, "y")) else { continue };
        let fs = t.attribute("font-size").and_then(|v| v.parse::<f64>().ok()).unwrap_or(16.0);
        // The text's middle: plotters anchors it at its middle (`dy="0.5ex"`) or its top.
        let mid = if t.attribute("dy") == Some("0.5ex") { y } else { y + 0.5 * fs };
        let mut swatch = Vec::new();
        for k in (0..i).rev() {
            let Some(b) = bounds(&elements[k]) else { break };
            let near = b[2] <= x + 0.5 && b[2] >= x - 24.0 && b[0] >= x - 40.0 && (0.5 * (b[1] + b[3]) - mid).abs() <= 12.0;
            if !near {
                break;
            }
            swatch.push(k);
        }
        if !swatch.is_empty() {
            let label: String = t.descendants().filter(|n| n.is_text()).filter_map(|n| n.text()).collect::<String>().trim().to_string();
            swatch.reverse();
            swatch_of.push((label, swatch));
        }
    }
    let in_swatches: std::collections::HashSet<usize> = swatch_of.iter().flat_map(|(_, s)| s.iter().copied()).collect();
    let mut out = Vec::new();
    for (label, swatch) in swatch_of {
        let marks: Vec<(String, &str)> = swatch.iter().filter_map(|&k| mark(elements[k])).collect();
        let filled = swatch.iter().find(|&&k| elements[k].attribute("fill").is_some_and(|f| f != "none")).and_then(|&k| mark(elements[k]));
        let Some((color, kind)) = filled.or_else(|| marks.first().cloned()) else { continue };
        let found = elements
            .iter()
            .enumerate()
            .filter(|(k, _)| !in_swatches.contains(k))
            .filter_map(|(_, n)| mark(*n))
            .any(|(c, kd)| c == color && (kd == kind || (kind == "box" && kd == "triangle")));
        out.push(LegendEntry { label, color, kind, found });
    }
    out
}

/// Renders `svg` to a PNG at `png` with resvg and the figures' font; the share
/// of its pixels that are not white.
pub fn render(svg: &str, png: &Path) -> f64 {
    let mut opt = resvg::usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_font_data(dejavu::sans::regular().to_vec());
    db.load_font_data(dejavu::sans::bold().to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    let tree = resvg::usvg::Tree::from_str(svg, &opt).expect("usvg parses the figure");
    // At one pixel per canvas px (a print size in inches would give 96 per inch).
    let (w, h) = canvas_px(roxmltree::Document::parse(svg).expect("the SVG parses").root_element());
    let scale = (w / tree.size().width() as f64) as f32;
    let mut pixmap = resvg::tiny_skia::Pixmap::new(w.ceil() as u32, h.ceil() as u32).expect("a canvas of positive size");
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(&tree, resvg::tiny_skia::Transform::from_scale(scale, scale), &mut pixmap.as_mut());
    if let Some(dir) = png.parent() {
        std::fs::create_dir_all(dir).unwrap();
    }
    pixmap.save_png(png).expect("the PNG is written");
    let px = pixmap.pixels();
    px.iter().filter(|p| p.red() < 250 || p.green() < 250 || p.blue() < 250).count() as f64 / px.len() as f64
}

/// Every `.svg` under `dir`, sorted.
pub fn svgs_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "svg") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Checks every figure under `dir` and renders each to
/// `target/tmp/figures/<name>/<relative path>.png`; panics listing every problem.
pub fn check_all(dir: &Path, name: &str) -> usize {
    let svgs = svgs_under(dir);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("figures").join(name);
    let mut all = Vec::new();
    for svg_path in &svgs {
        let rel = svg_path.strip_prefix(dir).unwrap();
        let svg = std::fs::read_to_string(svg_path).unwrap();
        for p in problems(&svg) {
            all.push(format!("{}: {p}", rel.display()));
        }
        match std::fs::read(svg_path.with_extension("pdf")) {
            Ok(pdf) if pdf.starts_with(b"%PDF-") && pdf.windows(10).any(|w| w == b"/FontFile2") => {}
            Ok(_) => all.push(format!("{}: its PDF is not a PDF with its font embedded", rel.display())),
            Err(e) => all.push(format!("{}: no PDF beside it ({e})", rel.display())),
        }
        let ink = render(&svg, &out.join(rel).with_extension("png"));
        if ink < 0.005 {
            all.push(format!("{}: renders almost blank ({:.2} % ink)", rel.display(), 100.0 * ink));
        }
    }
    assert!(all.is_empty(), "{} problem(s) in the figures of {}:\n{}", all.len(), dir.display(), all.join("\n"));
    svgs.len()
}
