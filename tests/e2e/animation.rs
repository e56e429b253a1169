//! The report's animations (issue 55): the open-loop bounce from x0a and the
//! hybrid run from x0d as GIFs, decoded with the `gif` crate and checked against
//! the traces they are drawn from: the frame count and delay the report
//! documents, and the tip (the one vermilion mark of a frame) where the trace
//! puts it at the frame's time. Frames are saved as PNG under
//! `target/tmp/animation/`, to be looked at.

use std::path::Path;

use sil_host::animation::{self, Animation, Arm, Look, Strip, frame::TIP};
use sil_host::commands::report::animations::{self as report_animations, FPS};

use crate::common::{target_dir, workspace};

fn run(args: &[&str]) {
    let mut full = vec!["sil-host"];
    full.extend_from_slice(args);
    assert_eq!(sil_host::run(full), 0, "{args:?}");
}

/// The frames of the GIF at `path` as they are shown (each frame's rectangle
/// drawn over the picture so far, its transparent pixels leaving it), RGBA, and
/// each frame's delay (hundredths of a second); the size (px).
fn decode(path: &Path) -> (Vec<Vec<u8>>, Vec<u16>, (usize, usize)) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut d = options.read_info(std::fs::File::open(path).unwrap()).unwrap();
    let (w, h) = (usize::from(d.width()), usize::from(d.height()));
    let mut canvas = vec![0u8; 4 * w * h];
    let (mut frames, mut delays) = (Vec::new(), Vec::new());
    while let Some(f) = d.read_next_frame().unwrap() {
        for y in 0..usize::from(f.height) {
            for x in 0..usize::from(f.width) {
                let s = 4 * (y * usize::from(f.width) + x);
                if f.buffer[s + 3] != 0 {
                    let t = 4 * ((y + usize::from(f.top)) * w + x + usize::from(f.left));
                    canvas[t..t + 4].copy_from_slice(&f.buffer[s..s + 4]);
                }
            }
        }
        frames.push(canvas.clone());
        delays.push(f.delay);
    }
    (frames, delays, (w, h))
}

/// The centre of the pixels of colour `c` in an RGBA frame `w` px wide, and how many.
fn centre_of(frame: &[u8], w: usize, c: [u8; 3]) -> ((f64, f64), usize) {
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
    for (k, p) in frame.chunks_exact(4).enumerate() {
        if p[..3] == c {
            sx += (k % w) as f64;
            sy += (k / w) as f64;
            n += 1;
        }
    }
    ((sx / n.max(1) as f64, sy / n.max(1) as f64), n)
}

/// The trace's `t`, `theta1`, `theta2`.
fn angles(trace: &Path) -> Vec<[f64; 3]> {
    let mut r = csv::Reader::from_path(trace).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (t, a, b) = (col("t"), col("theta1"), col("theta2"));
    r.records().map(|row| row.unwrap()).map(|row| [t, a, b].map(|k| row[k].parse::<f64>().unwrap())).collect()
}

fn save_png(frame: &[u8], (w, h): (usize, usize), path: &Path) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let pixmap =
        resvg::tiny_skia::Pixmap::from_vec(frame.to_vec(), resvg::tiny_skia::IntSize::from_wh(w as u32, h as u32).unwrap()).unwrap();
    pixmap.save_png(path).unwrap();
}

#[test]
fn the_bounce_and_the_hybrid_run_are_drawn_where_their_traces_put_the_tip() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = workspace().join("scenarios/hybrid-x0d.toml");
    let runs: [(&str, Vec<&str>, usize); 2] = [
        // The report's commands (sil-host/src/commands/report/sections.rs) and the
        // frames its page documents: 2 s slowed down 4 times, 5 s in real time, at 25 fps.
        ("simulate", vec!["simulate", "--x0", "a", "--mu", "0.6", "--v-belt", "-0.4", "--duration", "10"], 200),
        ("hybrid-x0d", vec!["run", "--in-process", "--scenario", scenario.to_str().unwrap()], 125),
    ];
    let arm = Arm { l: 0.21, h: 0.3775, v_belt: -0.4 };
    for (id, args, frames) in runs {
        let out = dir.path().join(id);
        run(&[&args[..], &["--out", out.to_str().unwrap(), "--json"]].concat());
        let written = report_animations::write(id, &out, arm, format!("{id} (test)")).unwrap().expect("the step is animated");
        let (t0, _, slow_down, _) = report_animations::plan(id).unwrap();
        let gif = out.join(report_animations::FILE);
        assert_eq!((written.frames, written.delay_cs), (frames, 4), "{id}");
        assert!(written.bytes < 1 << 20, "{id}: {} bytes, over the 1 MiB a tracked file may have", written.bytes);
        let (shown, delays, size) = decode(&gif);
        assert_eq!(size, (640, 480));
        assert_eq!(shown.len(), frames, "{id}: frames in the file");
        assert!(delays.iter().all(|d| *d == 4), "{id}: every frame 4 cs (25 fps): {delays:?}");
        let trace = angles(&out.join("trace.csv"));
        let tip_at = |t: f64| {
            let row = trace.iter().min_by(|a, b| (a[0] - t).abs().total_cmp(&(b[0] - t).abs())).unwrap();
            let (l, q1, q2) = (arm.l, row[1], row[2]);
            written.scene.px(l * (q1.sin() + q2.sin()), -l * (q1.cos() + q2.cos()))
        };
        let mut moved = 0.0f64;
        for k in [0, frames / 3, frames / 2, frames - 1] {
            let t = t0 + k as f64 / (f64::from(FPS) * slow_down);
            let ((x, y), n) = centre_of(&shown[k], size.0, [TIP.0, TIP.1, TIP.2]);
            assert!(n > 50, "{id} frame {k}: the tip's dot has {n} px");
            let (ex, ey) = tip_at(t);
            assert!(
                (x - ex).hypot(y - ey) < 3.0,
                "{id} frame {k} (t = {t} s): tip drawn at ({x:.1}, {y:.1}), the trace puts it at ({ex:.1}, {ey:.1})"
            );
            let (px, py) = tip_at(t - 0.25);
            moved = moved.max((px - ex).hypot(py - ey));
            save_png(&shown[k], size, &target_dir().join(format!("tmp/animation/{id}-{k}.png")));
        }
        assert!(moved > 6.0, "{id}: the tip moves, so a frame drawn at the wrong time would show");
    }
}

#[test]
fn bad_animations_are_refused_with_a_reason() {
    let trace = animation::ArmTrace {
        t: vec![0.0, 1.0],
        theta1: vec![0.1; 2],
        theta2: vec![0.2; 2],
        z_t: vec![0.0; 2],
        z_n: vec![-0.3; 2],
        f_t: vec![0.0; 2],
        f_n: vec![0.0; 2],
        mode: vec!["flight".into(); 2],
        ..Default::default()
    };
    let arm = Arm { l: 0.21, h: 0.3775, v_belt: -0.4 };
    let dir = tempfile::tempdir().unwrap();
    let look = Look { title: "t".into(), strip: Strip::Height, slow_down: 1.0 };
    for (a, why) in [
        (Animation { t0: 0.0, t1: 1.0, fps: 0, look: look.clone() }, "frames per second"),
        (Animation { t0: 0.0, t1: 2.0, fps: 25, look: look.clone() }, "outside the trace"),
        (Animation { t0: 0.0, t1: 1.0, fps: 25, look: Look { slow_down: -1.0, ..look.clone() } }, "slow-down"),
    ] {
        let e = animation::write_gif(&dir.path().join("a.gif"), &trace, arm, &a).unwrap_err().to_string();
        assert!(e.contains(why), "{e}");
    }
}
