//! The page's text: the HTML skeleton, its style and script (`assets/`, written
//! by hand, no library), and the run's data as one JSON document inside it.

use serde_json::{Value, json};

use super::{
    curves::Curves,
    events::Events,
    frames::{Frame, Frames},
    info::PageInfo,
    view,
};

const SKELETON: &str = include_str!("assets/page.html");
const STYLE: &str = include_str!("assets/page.css");
const SCRIPT: &str = include_str!("assets/page.js");

/// The whole page of `info`'s run from its `frames` and `curves`.
pub(super) fn page(info: PageInfo, frames: Frames, curves: &Curves, events: &Events) -> String {
    let samples = frames.samples();
    let (frames, step) = frames.finish();
    let data = data(&info, &frames, step, samples, curves, events);
    let json = script_json(&data);
    fill(SKELETON, &[("TITLE", &escape(&info.title)), ("STYLE", STYLE), ("SCRIPT", SCRIPT), ("DATA", &json)])
}

/// `skeleton` with each of its `{{NAME}}` placeholders replaced by the value of
/// `NAME` in `values` (an unknown name left as it is), in one pass over the
/// skeleton alone: a value that holds a placeholder's text (a scenario named
/// `{{DATA}}`) is never filled in itself.
fn fill(skeleton: &str, values: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(skeleton.len() + values.iter().map(|(_, v)| v.len()).sum::<usize>());
    let mut rest = skeleton;
    while let Some(open) = rest.find("{{") {
        out.push_str(&rest[..open]);
        let after = &rest[open + 2..];
        match after.find("}}").and_then(|close| values.iter().find(|(name, _)| *name == &after[..close]).map(|(_, v)| (close, v))) {
            Some((close, value)) => {
                out.push_str(value);
                rest = &after[close + 2..];
            }
            None => {
                out.push_str("{{");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// `data` as JSON text that is safe inside a `<script>` element: `<`, `>` and
/// `&` (which can only occur inside its strings) written as `\u003c`, `\u003e`,
/// `\u0026`, so no text of the run (a scenario's name such as `<!--<script>`,
/// which would put the HTML parser in the script's "double escaped" state and
/// let the page's own `</script>` through, or `</script>` itself) can end or
/// change the element; U+2028 and U+2029 as `\u2028`, `\u2029`, which older
/// JavaScript parsers take as line ends. The same JSON value: `JSON.parse` reads
/// the escapes back.
fn script_json(data: &Value) -> String {
    let text = data.to_string();
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// The page's JSON document (what `assets/page.js` reads).
fn data(info: &PageInfo, frames: &[Frame], step: f64, samples: u64, curves: &Curves, events: &Events) -> Value {
    let joints: Vec<_> = frames.iter().map(|f| view::joints(info.l, f.theta)).collect();
    let col = |f: &dyn Fn(usize) -> f64| (0..frames.len()).map(|i| f(i) as f32).collect::<Vec<f32>>();
    let f_max = frames.iter().map(|f| f.force[0].hypot(f.force[1])).filter(|f| f.is_finite()).fold(0.0, f64::max);
    let n_per_m = view::force_scale(f_max);
    let span = match (frames.first(), frames.last()) {
        (Some(a), Some(b)) => b.t - a.t,
        _ => 0.0,
    };
    let sample_dt = if samples > 1 { span / (samples - 1) as f64 } else { 0.0 };
    let world = view::world_box(info.l, info.h, joints.iter().flat_map(|(e, t)| [*e, *t]));
    json!({
        "title": info.title,
        "facts": info.facts,
        "closed_loop": info.closed_loop,
        "l": info.l,
        "h": info.h,
        "v_belt": info.v_belt,
        "view": world,
        "belt_depth": view::BELT_DEPTH_M,
        "force_n_per_m": n_per_m,
        "frames": {
            "step_s": step,
            "t": col(&|i| frames[i].t),
            "elbow_x": col(&|i| joints[i].0[0]),
            "elbow_y": col(&|i| joints[i].0[1]),
            "tip_x": col(&|i| joints[i].1[0]),
            "tip_y": col(&|i| joints[i].1[1]),
            "f_t": col(&|i| frames[i].force[0]),
            "f_n": col(&|i| frames[i].force[1]),
            "mode": frames.iter().map(|f| f.mode).collect::<Vec<u8>>(),
            "z_t_ref": col(&|i| frames[i].z_t_ref),
            "u1": col(&|i| frames[i].u[0]),
            "u2": col(&|i| frames[i].u[1]),
        },
        "modes": crate::plot::MODE_NAMES,
        "panels": curves.panels(),
        "events": events.json(),
        "notes": notes(frames.len(), step, samples, sample_dt, curves.samples_per_bucket(), n_per_m, events),
        "generator": format!("sil-host {}", env!("CARGO_PKG_VERSION")),
    })
}

/// What the page says about its decimation, scales and units.
fn notes(frames: usize, step: f64, samples: u64, sample_dt: f64, per_bucket: u64, n_per_m: f64, events: &Events) -> Vec<String> {
    let ms = |s: f64| format!("{:.3}", s * 1e3).trim_end_matches('0').trim_end_matches('.').to_string();
    let animation = if samples == 0 {
        "Animation: none, the run has no samples (it stopped before its first).".to_string()
    } else if step <= sample_dt * (1.0 + 1e-9) || frames as u64 >= samples {
        format!("Animation: every sample is a frame ({frames} frames, a sample every {} ms of simulated time).", ms(sample_dt))
    } else {
        format!(
            "Animation: a frame every {} ms of simulated time ({frames} frames, {:.0} per simulated second) from {samples} samples \
             (one every {} ms). The frame shown is the one nearest the chosen time.",
            ms(step),
            1.0 / step,
            ms(sample_dt)
        )
    };
    let plots = if per_bucket <= 1 {
        format!("Plots: every sample ({samples}).")
    } else {
        format!(
            "Plots: the lowest and the highest value of every {per_bucket} consecutive samples ({samples} samples in all), \
             finer than a pixel of the whole run: no extreme is lost; zoomed in (the plots menu) they show the same points, \
             the trace file has every sample."
        )
    };
    vec![
        animation,
        plots,
        events.note(),
        format!(
            "Arm view: the two links drawn from θ₁ and θ₂ (from the downward vertical) by the plant's forward kinematics; \
             the base joint (cyan) at the origin, the tip (magenta); the belt's surface at zₙ = −H, its stripes moving at the \
             belt speed; the contact force (fₜ, fₙ) on the tip as an arrow, 1 cm of the view = {} N.",
            n_per_m / 100.0
        ),
        "Units: SI (s, m, N, N m); zₜ along the belt, zₙ upward, the base joint at (0, 0).".to_string(),
        "World to pixel: a point (zₜ, zₙ) is drawn at (base_x + s·zₜ, base_y − s·zₙ) CSS px, with s, base_x and base_y \
         the arm canvas's data-px-per-m, data-base-x and data-base-y (from the page's top left)."
            .to_string(),
        "Open a time with ?t=SECONDS in the address; keys: space plays or pauses, the arrows step a frame; \
         click or drag on the plots to move the cursor; the plots menu shows the whole run or 10 s, 1 s or 0.1 s around \
         the cursor."
            .to_string(),
    ]
}

/// `text` with `&`, `<`, `>` and `"` escaped for HTML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace_page::{PageSample, TracePage};

    fn page_of(seconds: f64) -> String {
        let info = PageInfo {
            title: "test </script> & <b>".into(),
            facts: vec![("scenario".into(), "x</script>".into())],
            l: 0.21,
            h: 0.3775,
            v_belt: -0.4,
            closed_loop: true,
        };
        let mut page = TracePage::new(info);
        let n = (seconds * 1e3).round() as i64;
        for k in 0..=n {
            let t = k as f64 * 1e-3;
            page.push(&PageSample {
                t,
                theta: [0.4 + 0.1 * t.sin(), -0.3],
                z: [0.1, -0.37],
                force: [-6.0, 10.0],
                mode: "sliding",
                z_t_ref: 0.1,
                u: [0.1, 0.2],
                safe_state: false,
            });
        }
        page.html()
    }

    /// The page is one file: no address outside it, its data parses, nothing in
    /// the data closes its script element.
    #[test]
    fn the_page_is_self_contained_and_its_data_parses() {
        let html = page_of(2.0);
        for bad in ["http:", "https:", "//cdn", "<link", " src=", "import ", "fetch("] {
            assert!(!html.contains(bad), "{bad} in the page");
        }
        assert!(html.contains("<title>test &lt;/script&gt; &amp; &lt;b&gt;</title>"));
        let start = html.find("id=\"trace-data\">").unwrap() + "id=\"trace-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        let data: Value = serde_json::from_str(&html[start..end]).unwrap();
        assert_eq!(data["facts"][0][1], "x</script>");
        assert_eq!(data["frames"]["t"].as_array().unwrap().len(), 201);
        assert_eq!(data["force_n_per_m"], 200.0, "|f| = 11.7 N fits 8 cm at 200 N/m");
        let notes = data["notes"].as_array().unwrap();
        assert!(notes[0].as_str().unwrap().contains("a frame every 10 ms"), "{}", notes[0]);
        assert!(notes[1].as_str().unwrap().contains("every sample (2001)"), "{}", notes[1]);
    }

    /// A scenario name (or any text of the run) with what HTML reads inside a
    /// script element (`<!--<script>`, `</script>`, `&`, U+2028/U+2029) gives
    /// data with no `<`, `>` or `&` and those two characters escaped, which
    /// parses back to the same strings; the page holds exactly two script
    /// elements, the data's ending at the first `</script>`.
    #[test]
    fn the_data_escapes_what_html_reads_in_a_script() {
        let name = "<!--<script> a\u{2028}b\u{2029}c & </script> --> {{DATA}} {{SCRIPT}}";
        let info = PageInfo {
            title: name.into(),
            facts: vec![("scenario".into(), name.into())],
            l: 0.21,
            h: 0.3775,
            v_belt: -0.4,
            closed_loop: true,
        };
        let html = TracePage::new(info).html();
        let start = html.find("id=\"trace-data\">").unwrap() + "id=\"trace-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        let json = &html[start..end];
        for bad in ['<', '>', '&', '\u{2028}', '\u{2029}'] {
            assert!(!json.contains(bad), "{bad:?} in the data");
        }
        let data: Value = serde_json::from_str(json).unwrap();
        assert_eq!(data["facts"][0][1], name, "the name reads back whole");
        assert_eq!(data["title"], name);
        assert_eq!(html.matches("<script").count(), 2, "the data's element and the script's");
        assert_eq!(html.matches("</script>").count(), 2);
        assert!(html[end..].starts_with("</script>\n<script>"), "the data's element ends where it should");
        assert!(html.contains("<title>&lt;!--&lt;script&gt;"), "the title, escaped, placeholders left as text");
        assert!(html.contains("{{DATA}} {{SCRIPT}}</title>"), "a placeholder in the name is not filled");
    }

    /// A run without samples still gives a page that says so.
    #[test]
    fn an_empty_run_gives_a_page_that_says_so() {
        let html = page_of(-1.0);
        assert!(html.contains("the run has no samples"), "the note");
        assert!(html.contains("\"t\":[]"), "no frames");
    }

    /// A long run's page stays small, and says how it was thinned.
    #[test]
    fn a_long_run_gives_a_bounded_page_that_says_so() {
        let html = page_of(300.0);
        assert!(html.len() < 2_500_000, "{} bytes", html.len());
        assert!(html.contains("a frame every 80 ms"));
        assert!(html.contains("of every 256 consecutive samples"), "300 001 samples in at most 2048 buckets");
    }
}
