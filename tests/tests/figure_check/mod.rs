//! The check every figure must pass (issue 25), shared by `tests/tests/figures.rs`
//! and `tests/tests/report.rs`: each SVG is parsed (roxmltree), every text
//! element's box is measured with the font the figures are laid out with (DejaVu
//! Sans, `ab_glyph`), and the boxes must lie inside the canvas and overlap no
//! other; no tick reads `-0`. Each figure is also rendered to PNG with resvg (the
//! same font) into `target/tmp/figures/`, to be looked at.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

/// A text element's ink box on the canvas, px.
#[derive(Debug, Clone)]
pub struct TextBox {
    /// The text.
    pub text: String,
    /// Left, top, right, bottom, px (y down).
    pub rect: [f64; 4],
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

/// The canvas size and the ink box of every non-empty text element of `svg`.
///
/// # Panics
/// On an SVG that does not parse, or a text element that is not laid out by
/// plotters' SVG backend (nested `tspan`, a transform other than `rotate`).
pub fn text_boxes(svg: &str) -> ((f64, f64), Vec<TextBox>) {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    let root = doc.root_element();
    let dim = |a: &str| root.attribute(a).and_then(|v| v.trim_end_matches("px").parse::<f64>().ok()).expect("canvas size");
    let canvas = (dim("width"), dim("height"));
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
        boxes.push(TextBox { text, rect });
    }
    (canvas, boxes)
}

/// What is wrong with the figure `svg`: text outside the canvas, two texts that
/// overlap (by more than half a pixel both ways), a tick reading `-0`. Empty when
/// it passes.
pub fn problems(svg: &str) -> Vec<String> {
    let ((w, h), boxes) = text_boxes(svg);
    let mut out = Vec::new();
    let tol = 0.5;
    for b in &boxes {
        let [l, t, r, btm] = b.rect;
        if l < -tol || t < -tol || r > w + tol || btm > h + tol {
            out.push(format!("outside the {w} x {h} canvas: {:?} at [{l:.1}, {t:.1}, {r:.1}, {btm:.1}]", b.text));
        }
        let s = b.text.trim();
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

/// Renders `svg` to a PNG at `png` with resvg and the figures' font; the share
/// of its pixels that are not white.
pub fn render(svg: &str, png: &Path) -> f64 {
    let mut opt = resvg::usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_font_data(dejavu::sans::regular().to_vec());
    db.load_font_data(dejavu::sans::bold().to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    let tree = resvg::usvg::Tree::from_str(svg, &opt).expect("usvg parses the figure");
    let size = tree.size().to_int_size();
    let mut pixmap = resvg::tiny_skia::Pixmap::new(size.width(), size.height()).expect("a canvas of positive size");
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(&tree, resvg::tiny_skia::Transform::default(), &mut pixmap.as_mut());
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
        let ink = render(&svg, &out.join(rel).with_extension("png"));
        if ink < 0.005 {
            all.push(format!("{}: renders almost blank ({:.2} % ink)", rel.display(), 100.0 * ink));
        }
    }
    assert!(all.is_empty(), "{} problem(s) in the figures of {}:\n{}", all.len(), dir.display(), all.join("\n"));
    svgs.len()
}
