//! Figures fit for a paper (issue 25): the check over every figure
//! (`figure_check`) catches what it must, and the figures of the quick commands
//! pass it. `tests/e2e/report.rs` runs the same check over every figure the
//! report writes.

use crate::figure_check;

use std::process::Command;

/// An SVG of the figures' shape (2 px per printed pt: 144 px to the inch) holding
/// `texts`: `(x, y, anchor, text)` at 16 px (8 pt in print).
fn svg_of(w: u32, h: u32, texts: &[(f64, f64, &str, &str)]) -> String {
    let (wi, hi) = (w as f64 / 144.0, h as f64 / 144.0);
    let mut s = format!(r#"<svg width="{wi}in" height="{hi}in" viewBox="0 0 {w} {h}" xmlns="http://www.w3.org/2000/svg">"#);
    for (x, y, anchor, t) in texts {
        s += &format!(
            r##"<text x="{x}" y="{y}" dy="0.76em" text-anchor="{anchor}" font-family="sans-serif" font-size="16" fill="#000000">{t}</text>"##
        );
    }
    s + "</svg>"
}

#[test]
fn the_check_finds_overlapping_texts_text_off_the_canvas_and_minus_zero() {
    let good = svg_of(400, 100, &[(10.0, 10.0, "start", "zₜ (m)"), (10.0, 40.0, "start", "fₙ (N)"), (390.0, 10.0, "end", "0.10")]);
    assert_eq!(figure_check::problems(&good), Vec::<String>::new());
    // Two labels on one line, the second starting inside the first.
    let overlap = svg_of(400, 100, &[(10.0, 10.0, "start", "lift-off only"), (60.0, 12.0, "start", "contact")]);
    assert_eq!(figure_check::problems(&overlap).len(), 1, "{:?}", figure_check::problems(&overlap));
    // A legend entry cut at the right edge (the sweep map's "inval").
    let cut = svg_of(400, 100, &[(360.0, 10.0, "start", "invalid")]);
    assert!(figure_check::problems(&cut)[0].contains("outside"), "{:?}", figure_check::problems(&cut));
    // A centred title wider than the canvas.
    let wide = svg_of(200, 100, &[(100.0, 10.0, "middle", "Outcome over (v_belt, mu), hybrid (firmware, sampled)")]);
    assert!(figure_check::problems(&wide).iter().any(|p| p.contains("outside")));
    let code = svg_of(400, 100, &[(10.0, 10.0, "start", "theta1_dot (rad/s), mu = 0.6")]);
    assert_eq!(figure_check::problems(&code).len(), 2, "{:?}", figure_check::problems(&code));
    let minus = svg_of(400, 100, &[(10.0, 10.0, "start", "-0.0")]);
    assert!(figure_check::problems(&minus)[0].contains("-0.0"));
    // A y-axis description rotated about its anchor stays inside when it fits.
    let rotated = r#"<svg width="0.6944in" height="2.0833in" viewBox="0 0 100 300" xmlns="http://www.w3.org/2000/svg"><text x="20" y="150" dy="0.76em" text-anchor="middle" font-family="sans-serif" font-size="16" transform="rotate(270, 20, 150)">θ̇₁ (rad/s)</text></svg>"#;
    let ((_, _), boxes) = figure_check::text_boxes(rotated);
    let r = boxes[0].rect;
    assert!(r[3] - r[1] > r[2] - r[0], "a rotated text is taller than wide: {r:?}");
    assert!(figure_check::problems(rotated).is_empty());
}

/// The print-size rules (issue 44): a figure states its printed size, no text
/// prints below 7 pt at it, and every legend entry's mark occurs in the figure.
#[test]
fn the_check_finds_small_print_no_print_size_and_legend_entries_with_nothing_drawn() {
    // 16 px on a 1008 px canvas printed 7 in wide: 8 pt; printed 3.5 in wide: 4 pt.
    let good = svg_of(1008, 200, &[(10.0, 10.0, "start", "θ̇₁ (rad/s)")]);
    assert_eq!(figure_check::problems(&good), Vec::<String>::new());
    let small = good.replace(r#"width="7in""#, r#"width="3.5in""#);
    assert!(figure_check::problems(&small).iter().any(|p| p.contains("prints at 4.00 pt")), "{:?}", figure_check::problems(&small));
    let no_size = good.replace(r#"width="7in""#, r#"width="1008""#);
    assert!(figure_check::problems(&no_size).iter().any(|p| p.contains("no print size")));
    // A legend: a blue line swatch and a vermillion dot swatch, each before its label.
    let legend = |data: &str| {
        format!(
            r##"<svg width="7in" height="1.3889in" viewBox="0 0 1008 200" xmlns="http://www.w3.org/2000/svg">{data}<polyline fill="none" stroke="#0072B2" stroke-width="2" points="900,20 922,20 "/><text x="928" y="20" dy="0.5ex" text-anchor="start" font-family="sans-serif" font-size="14.5" fill="#000000">zₜ</text><circle cx="911" cy="44" r="4" fill="#D55E00" stroke="none"/><text x="928" y="44" dy="0.5ex" text-anchor="start" font-family="sans-serif" font-size="14.5" fill="#000000">impact</text></svg>"##
        )
    };
    let line = r##"<polyline fill="none" stroke="#0072B2" stroke-width="1" points="10,100 500,150 "/>"##;
    let dot = r##"<circle cx="300" cy="150" r="3" fill="#D55E00" stroke="none"/>"##;
    assert_eq!(figure_check::legend_problems(&legend(&format!("{line}{dot}"))), Vec::<String>::new());
    let missing = figure_check::legend_problems(&legend(line));
    assert_eq!(missing.len(), 1, "{missing:?}");
    assert!(missing[0].contains("\"impact\""), "{missing:?}");
    // The same colour on another kind of mark is not the entry's mark.
    let wrong_kind =
        figure_check::legend_problems(&legend(&format!("{line}{}", r##"<polyline fill="none" stroke="#D55E00" points="1,1 2,2 "/>"##)));
    assert_eq!(wrong_kind.len(), 1, "{wrong_kind:?}");
}

#[test]
fn the_check_measures_text_with_the_figures_font() {
    // DejaVu Sans at 16 px: "0" advances 10.2 px (1303/2048 em); ten of them span about 100 px of ink.
    let ((_, _), boxes) = figure_check::text_boxes(&svg_of(400, 100, &[(0.0, 0.0, "start", "0000000000")]));
    let width = boxes[0].rect[2] - boxes[0].rect[0];
    assert!((width - 100.0).abs() < 3.0, "ink width {width}");
}

#[test]
fn the_figures_of_the_quick_commands_pass_the_check() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str], sub: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).arg("--out").arg(dir.path().join(sub)).output().unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    };
    run(&["modes", "--grid", "60"], "modes");
    run(&["admissible"], "admissible");
    run(&["simulate", "--duration", "2"], "simulate");
    run(&["run", "--in-process", "--duration", "1"], "run");
    run(
        &[
            "sweep",
            "--mu",
            "0.3,0.6",
            "--mu-step",
            "0.3",
            "--v-belt",
            "-0.6,-0.3",
            "--v-belt-step",
            "0.1",
            "--transient",
            "0.5",
            "--record",
            "0.5",
        ],
        "sweep",
    );
    run(&["poincare", "--v-belt", "-0.7,-0.6", "--v-step", "0.05", "--transient", "2", "--record", "2"], "poincare");
    let n = figure_check::check_all(dir.path(), "quick");
    assert!(n >= 8, "{n} figures");
    // The legend check reads the real legends: the closed-loop trace's entries are found, with their marks.
    let trace = std::fs::read_to_string(dir.path().join("run/trace.svg")).unwrap();
    let labels: Vec<String> = figure_check::legend_entries(&trace).into_iter().filter(|e| e.found).map(|e| e.label).collect();
    for l in ["zₜ", "zₜ*", "fₙ", "τ₁", "τ₂"] {
        assert!(labels.iter().any(|x| x == l), "{l} among {labels:?}");
    }
    let map = std::fs::read_to_string(dir.path().join("sweep/map_newton_e0.2.svg")).unwrap();
    assert!(figure_check::legend_entries(&map).iter().any(|e| e.label.starts_with("bouncing") && e.kind == "box"));
}
