//! Figures fit for a paper (issue 25): the check over every figure
//! (`figure_check`) catches what it must, and the figures of the quick commands
//! pass it. `tests/tests/report.rs` runs the same check over every figure the
//! report writes.

mod figure_check;

use std::process::Command;

/// An SVG of plotters' shape holding `texts`: `(x, y, anchor, text)` at 16 px.
fn svg_of(w: u32, h: u32, texts: &[(f64, f64, &str, &str)]) -> String {
    let mut s = format!(r#"<svg width="{w}" height="{h}" viewBox="0 0 {w} {h}" xmlns="http://www.w3.org/2000/svg">"#);
    for (x, y, anchor, t) in texts {
        s += &format!(
            r##"<text x="{x}" y="{y}" dy="0.76em" text-anchor="{anchor}" font-family="sans-serif" font-size="16" fill="#000000">{t}</text>"##
        );
    }
    s + "</svg>"
}

#[test]
fn the_check_finds_overlapping_texts_text_off_the_canvas_and_minus_zero() {
    let good = svg_of(400, 100, &[(10.0, 10.0, "start", "z_t (m)"), (10.0, 40.0, "start", "f_n (N)"), (390.0, 10.0, "end", "0.10")]);
    assert_eq!(figure_check::problems(&good), Vec::<String>::new());
    // Two labels on one line, the second starting inside the first.
    let overlap = svg_of(400, 100, &[(10.0, 10.0, "start", "lift_off_only"), (60.0, 12.0, "start", "contact")]);
    assert_eq!(figure_check::problems(&overlap).len(), 1, "{:?}", figure_check::problems(&overlap));
    // A legend entry cut at the right edge (the sweep map's "inval").
    let cut = svg_of(400, 100, &[(360.0, 10.0, "start", "invalid")]);
    assert!(figure_check::problems(&cut)[0].contains("outside"), "{:?}", figure_check::problems(&cut));
    // A centred title wider than the canvas.
    let wide = svg_of(200, 100, &[(100.0, 10.0, "middle", "Outcome over (v_belt, mu), hybrid (firmware, sampled)")]);
    assert!(figure_check::problems(&wide).iter().any(|p| p.contains("outside")));
    let minus = svg_of(400, 100, &[(10.0, 10.0, "start", "-0.0")]);
    assert!(figure_check::problems(&minus)[0].contains("-0.0"));
    // A y-axis description rotated about its anchor stays inside when it fits.
    let rotated = r#"<svg width="100" height="300" xmlns="http://www.w3.org/2000/svg"><text x="20" y="150" dy="0.76em" text-anchor="middle" font-family="sans-serif" font-size="16" transform="rotate(270, 20, 150)">theta1_dot (rad/s)</text></svg>"#;
    let ((_, _), boxes) = figure_check::text_boxes(rotated);
    let r = boxes[0].rect;
    assert!(r[3] - r[1] > r[2] - r[0], "a rotated text is taller than wide: {r:?}");
    assert!(figure_check::problems(rotated).is_empty());
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
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host-e2e")).args(args).arg("--out").arg(dir.path().join(sub)).output().unwrap();
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
}
