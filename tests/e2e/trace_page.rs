//! End-to-end: `trace.html` in a real browser. Headless Chromium (Debian's
//! `chromium`) opens the page a `sil-host run` and a `sil-host simulate` wrote,
//! at chosen times (`?t=SECONDS`), and screenshots it; the tip's marker (pure
//! magenta, a colour nothing else on the page has) must be within a few pixels
//! of where the trace puts the tip at that time: `z_t`, `z_n` read from
//! `trace.csv`, mapped to pixels by the page's documented world-to-pixel mapping
//! (the arm canvas's `data-px-per-m`, `data-base-x`, `data-base-y`, read from the
//! page's DOM after its script ran, `--dump-dom`). The page's own idea of where
//! the tip is (`tipPixel()`) is not used. The base joint's marker (pure cyan)
//! checks the mapping's origin the same way.
//!
//! Chromium missing: the test is skipped with a message, or fails when
//! `PAINLEVE_REQUIRE_CHROMIUM=1` (CI, `.ci/run`). Every browser is killed after
//! [`BROWSER_TIMEOUT`]. Chromium's stderr (D-Bus noise when run as root) is not a failure.

use std::{
    path::{Path, PathBuf},
    process::{Command, Stdio},
    time::{Duration, Instant},
};

/// The longest one browser may take to load the page and answer.
const BROWSER_TIMEOUT: Duration = Duration::from_secs(90);
/// The browser window, CSS px (at a device scale factor of 1: screen pixels).
const WINDOW: (u32, u32) = (1280, 960);
/// How far the marker's centre may be from the trace's tip, px.
const TOLERANCE_PX: f64 = 3.0;

/// Chromium's executable, or `None` (skip) when it is missing and not required.
fn chromium() -> Option<PathBuf> {
    let found = ["/usr/bin/chromium", "/usr/bin/chromium-browser"].into_iter().map(PathBuf::from).find(|p| p.is_file());
    if found.is_none() {
        let why = "headless Chromium is missing (/usr/bin/chromium): apt-get install -y chromium";
        assert!(std::env::var("PAINLEVE_REQUIRE_CHROMIUM").as_deref() != Ok("1"), "{why} (PAINLEVE_REQUIRE_CHROMIUM=1)");
        eprintln!("skipped: {why}");
    }
    found
}

/// Runs `sil-host` with `args` (the real binary) and checks it succeeded.
fn sil_host(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).output().unwrap();
    assert!(o.status.success(), "sil-host {args:?}: {}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
}

/// Runs Chromium headless on `url` with `extra` flags (a fresh profile in
/// `scratch`), killed after [`BROWSER_TIMEOUT`]; its standard output.
fn browse(chromium: &Path, scratch: &Path, extra: &[String], url: &str) -> String {
    let profile = tempfile::tempdir_in(scratch).unwrap();
    let stdout = tempfile::NamedTempFile::new_in(scratch).unwrap().into_temp_path();
    let mut child = Command::new(chromium)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run"])
        .args(["--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars"])
        .args(["--force-device-scale-factor=1", "--run-all-compositor-stages-before-draw", "--virtual-time-budget=3000"])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .args(extra)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout).unwrap())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {}: {e}", chromium.display()));
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > BROWSER_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("Chromium did not finish {url} within {} s (killed): {extra:?}", BROWSER_TIMEOUT.as_secs());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "Chromium failed on {url} ({status}): {extra:?}");
    std::fs::read_to_string(&stdout).unwrap()
}

/// The page's world-to-pixel mapping as its script published it on the arm
/// canvas: `(px per m, base x, base y, the frame's time)`.
fn mapping(dom: &str) -> (f64, f64, f64, f64) {
    let start = dom.find("<canvas id=\"arm\"").unwrap_or_else(|| panic!("no arm canvas in the DOM:\n{}", &dom[..dom.len().min(2000)]));
    let tag = &dom[start..start + dom[start..].find('>').unwrap()];
    let attr = |name: &str| -> f64 {
        let at = tag.find(&format!("{name}=\"")).unwrap_or_else(|| panic!("{name} missing on the arm canvas: {tag}")) + name.len() + 2;
        tag[at..at + tag[at..].find('"').unwrap()].parse().unwrap_or_else(|e| panic!("{name} in {tag}: {e}"))
    };
    (attr("data-px-per-m"), attr("data-base-x"), attr("data-base-y"), attr("data-frame-t"))
}

/// An RGB screenshot: width, height and the pixels row by row.
struct Image {
    w: usize,
    h: usize,
    rgb: Vec<[u8; 3]>,
}

fn decode(png_path: &Path) -> Image {
    let bytes = std::fs::read(png_path).unwrap();
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    let (w, h) = (info.width as usize, info.height as usize);
    let rgb = (0..w * h).map(|i| [buf[i * channels], buf[i * channels + 1], buf[i * channels + 2]]).collect();
    Image { w, h, rgb }
}

/// The centre (px, from the top left) of the pixels `like` picks, how many
/// there are and the size of their bounding box.
fn blob(img: &Image, like: impl Fn([u8; 3]) -> bool) -> (f64, f64, usize, (usize, usize)) {
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (usize::MAX, 0, usize::MAX, 0);
    for y in 0..img.h {
        for x in 0..img.w {
            if like(img.rgb[y * img.w + x]) {
                // A pixel's centre is at +0.5 of its index in CSS coordinates.
                sx += x as f64 + 0.5;
                sy += y as f64 + 0.5;
                n += 1;
                (x_lo, x_hi, y_lo, y_hi) = (x_lo.min(x), x_hi.max(x), y_lo.min(y), y_hi.max(y));
            }
        }
    }
    assert!(n > 0, "no pixel of the marker's colour in the screenshot");
    (sx / n as f64, sy / n as f64, n, (x_hi - x_lo + 1, y_hi - y_lo + 1))
}

const MAGENTA: fn([u8; 3]) -> bool = |[r, g, b]| r >= 235 && g <= 30 && b >= 235;
const CYAN: fn([u8; 3]) -> bool = |[r, g, b]| r <= 30 && g >= 235 && b >= 235;

/// The row of `trace.csv` at time `t`: `(t, z_t, z_n)`.
fn trace_at(csv_path: &Path, t: f64) -> (f64, f64, f64) {
    let mut rdr = csv::Reader::from_path(csv_path).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let col = |name: &str| headers.iter().position(|c| c == name).unwrap_or_else(|| panic!("no column {name}"));
    let (ct, czt, czn) = (col("t"), col("z_t"), col("z_n"));
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            let f = |i: usize| r[i].parse::<f64>().unwrap();
            (f(ct), f(czt), f(czn))
        })
        .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
        .unwrap()
}

/// What one screenshot at time `t` showed: the expected tip pixel (from the
/// trace), the marker's centre, and the base check.
struct Shot {
    expected: (f64, f64),
    marker: (f64, f64),
}

/// Opens `dir/trace.html` at time `t` and checks the tip and base markers
/// against `dir/trace.csv` at that time; `png` keeps the screenshot.
fn check_at(chromium: &Path, scratch: &Path, dir: &Path, t: f64, png: &Path) -> Shot {
    let url = format!("file://{}?t={t}", dir.join("trace.html").canonicalize().unwrap().display());
    let dom = browse(chromium, scratch, &["--dump-dom".to_string()], &url);
    let (s, base_x, base_y, frame_t) = mapping(&dom);
    let (row_t, z_t, z_n) = trace_at(&dir.join("trace.csv"), t);
    assert!((row_t - t).abs() < 1e-9, "the trace has a sample at {t} s (nearest {row_t})");
    assert!((frame_t - t).abs() < 1e-5, "the page shows the frame at {t} s, not {frame_t}");
    assert!(s > 100.0 && s.is_finite(), "a sane scale: {s} px/m");
    browse(chromium, scratch, &[format!("--screenshot={}", png.display())], &url);
    let img = decode(png);
    assert_eq!((img.w, img.h), (WINDOW.0 as usize, WINDOW.1 as usize), "the screenshot is the window");
    let (bx, by, _, _) = blob(&img, CYAN);
    assert!((bx - base_x).hypot(by - base_y) <= 2.0, "base marker at ({bx:.1}, {by:.1}), the mapping says ({base_x:.1}, {base_y:.1})");
    let expected = (base_x + s * z_t, base_y - s * z_n);
    let (mx, my, n, (w, h)) = blob(&img, MAGENTA);
    assert!(w <= 16 && h <= 16 && n >= 40, "one round tip marker (6 px radius): {n} px in a {w} x {h} box");
    let off = (mx - expected.0).hypot(my - expected.1);
    assert!(
        off <= TOLERANCE_PX,
        "t = {t} s: the tip marker is at ({mx:.1}, {my:.1}) px, the trace's tip (z_t {z_t:.5} m, z_n {z_n:.5} m) maps to \
         ({:.1}, {:.1}) px: {off:.1} px off",
        expected.0,
        expected.1
    );
    eprintln!("t = {t} s: the tip marker is {off:.2} px from the trace's tip ({n} px of magenta)");
    Shot { expected, marker: (mx, my) }
}

/// Two times of a closed-loop run and one of an open-loop bounce: the tip is
/// where the trace says at each, and the two times' tips are far enough apart
/// that the check tells them apart.
#[test]
fn the_pages_arm_is_where_the_trace_puts_it() {
    let Some(chromium) = chromium() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scratch = dir.path();
    let run = scratch.join("run");
    sil_host(&["run", "--in-process", "--duration", "2.5", "--out", run.to_str().unwrap()]);
    let html = std::fs::read_to_string(run.join("trace.html")).unwrap();
    for bad in ["http://", "https://", "<link", " src=", "@import", "fetch("] {
        assert!(!html.contains(bad), "trace.html is self-contained: {bad} in it");
    }
    // Early in the move and after it: z_t* goes from the start to 0.10 m over 2 s.
    let shots: Vec<Shot> =
        [0.25, 2.2].iter().map(|&t| check_at(&chromium, scratch, &run, t, &scratch.join(format!("run-{t}.png")))).collect();
    let apart = (shots[0].expected.0 - shots[1].expected.0).hypot(shots[0].expected.1 - shots[1].expected.1);
    assert!(apart > 4.0 * TOLERANCE_PX, "the two times' tips are {apart:.1} px apart: too close to tell apart");
    let wrong = (shots[0].marker.0 - shots[1].expected.0).hypot(shots[0].marker.1 - shots[1].expected.1);
    assert!(wrong > TOLERANCE_PX, "the check tells the times apart");

    // An open-loop bounce from x0a: the tip in flight.
    let sim = scratch.join("simulate");
    sil_host(&["simulate", "--x0", "a", "--duration", "0.6", "--out", sim.to_str().unwrap()]);
    check_at(&chromium, scratch, &sim, 0.35, &scratch.join("simulate.png"));
    if let Ok(keep) = std::env::var("PAINLEVE_KEEP_SCREENSHOTS") {
        for f in ["run-0.25.png", "run-2.2.png", "simulate.png"] {
            std::fs::copy(scratch.join(f), Path::new(&keep).join(f)).unwrap();
        }
    }
}

/// Every table format gets the page; `--no-page` leaves it out.
#[test]
fn every_format_writes_the_page_and_no_page_leaves_it_out() {
    let dir = tempfile::tempdir().unwrap();
    for command in ["run", "simulate"] {
        let out = dir.path().join(format!("{command}-no-page"));
        let extra: &[&str] = if command == "run" { &["--in-process"] } else { &[] };
        sil_host(&[&[command, "--duration", "0.2", "--no-page", "--out", out.to_str().unwrap()], extra].concat());
        assert!(out.join("summary.json").is_file() && !out.join("trace.html").exists(), "{command} --no-page");
    }
    for format in ["arrow", "mcap"] {
        let out = dir.path().join(format);
        sil_host(&["run", "--in-process", "--duration", "0.3", "--format", format, "--out", out.to_str().unwrap()]);
        let html = std::fs::read_to_string(out.join("trace.html")).unwrap();
        assert!(html.contains("id=\"trace-data\"") && html.contains("\"frames\""), "{format}: the page holds its data");
        let sim = dir.path().join(format!("sim-{format}"));
        sil_host(&["simulate", "--duration", "0.2", "--format", format, "--out", sim.to_str().unwrap()]);
        assert!(sim.join("trace.html").is_file(), "simulate --format {format} writes trace.html");
    }
}

/// Issue 66 (5): a scenario named with what HTML reads inside a script element
/// (`<!--<script>`: the parser's "double escaped" state, in which the page's own
/// `</script>` no longer ends the data) gives a page whose data holds no `<`,
/// `>` or `&` and reads back to the name; the page has its two script elements.
#[test]
fn a_scenario_name_cannot_break_the_pages_script() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let name = "<!--<script>&\u{2028}";
    let set = format!("name={}", serde_json::to_string(name).unwrap());
    sil_host(&["run", "--in-process", "--duration", "0.05", "--set", &set, "--out", out.to_str().unwrap()]);
    let html = std::fs::read_to_string(out.join("trace.html")).unwrap();
    let start = html.find("id=\"trace-data\">").unwrap() + "id=\"trace-data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    let json = &html[start..end];
    assert!(!json.contains(['<', '>', '&', '\u{2028}']), "the data holds none of them: {json:.200}");
    let data: serde_json::Value = serde_json::from_str(json).unwrap();
    let facts = data["facts"].as_array().unwrap();
    assert!(facts.iter().any(|f| f[0] == "scenario" && f[1] == name), "the name reads back: {facts:?}");
    assert_eq!((html.matches("<script").count(), html.matches("</script>").count()), (2, 2));
}

/// The `(kind, t)` of every row of `events.csv`, times bit for bit.
fn events_of(csv_path: &Path) -> Vec<(String, f64)> {
    let mut rdr = csv::Reader::from_path(csv_path).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let col = |name: &str| headers.iter().position(|c| c == name).unwrap_or_else(|| panic!("no column {name}"));
    let (ct, ck) = (col("t"), col("kind"));
    rdr.records().map(|r| r.unwrap()).map(|r| (r[ck].to_string(), r[ct].parse::<f64>().unwrap())).collect()
}

/// The `(data-kind, data-t)` of every item of the page's event list, from the DOM
/// its script built.
fn listed_events(dom: &str) -> Vec<(String, f64)> {
    let list = &dom[dom.find("<ol id=\"event-list\"").expect("the event list in the DOM")..];
    let list = &list[..list.find("</ol>").unwrap()];
    list.split("<li ")
        .skip(1)
        .map(|li| {
            let tag = &li[..li.find('>').unwrap()];
            let attr = |name: &str| {
                let at = tag.find(&format!("{name}=\"")).unwrap_or_else(|| panic!("{name} missing: {tag}")) + name.len() + 2;
                tag[at..at + tag[at..].find('"').unwrap()].to_string()
            };
            (attr("data-kind"), attr("data-t").parse::<f64>().unwrap())
        })
        .collect()
}

/// The page's data (`#trace-data`) from the dumped DOM.
fn page_data(dom: &str) -> serde_json::Value {
    let start = dom.find("id=\"trace-data\">").unwrap() + "id=\"trace-data\">".len();
    let end = start + dom[start..].find("</script>").unwrap();
    serde_json::from_str(&dom[start..end]).unwrap()
}

/// Pixels of the touchdown colour (#0072b2) within `r` px of `(x, y)`.
fn ring_pixels(img: &Image, (x, y): (f64, f64), r: f64) -> usize {
    let like = |[cr, cg, cb]: [u8; 3]| cr <= 20 && (100..=130).contains(&cg) && (165..=200).contains(&cb);
    let mut n = 0;
    for py in (y - r).max(0.0) as usize..((y + r) as usize).min(img.h) {
        for px in (x - r).max(0.0) as usize..((x + r) as usize).min(img.w) {
            if like(img.rgb[py * img.w + px]) {
                n += 1;
            }
        }
    }
    n
}

/// Issue 69 (1): the open-loop bounce from x0a (the paper's phenomenon) is in the
/// page: every event of `events.csv` is in the page's list with its kind and its
/// time bit for bit (every touchdown among them, counted from the DOM), the frame
/// after a touchdown names it in its readout and rings the contact, and a frame
/// with no impact since the previous one has no ring.
#[test]
fn the_page_marks_every_event_of_the_bounce() {
    let Some(chromium) = chromium() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scratch = dir.path();
    let sim = scratch.join("x0a");
    sil_host(&["simulate", "--x0", "a", "--out", sim.to_str().unwrap()]);
    let events = events_of(&sim.join("events.csv"));
    let touchdowns: Vec<f64> = events.iter().filter(|(k, _)| k == "touchdown").map(|(_, t)| *t).collect();
    assert!(touchdowns.len() >= 20, "the bounce has its touchdowns: {}", touchdowns.len());
    let url = |t: &str| format!("file://{}?t={t}", sim.join("trace.html").canonicalize().unwrap().display());

    let dom = browse(&chromium, scratch, &["--dump-dom".to_string()], &url("1.05"));
    let listed = listed_events(&dom);
    assert_eq!(listed.iter().filter(|(k, _)| k == "touchdown").count(), touchdowns.len(), "every touchdown is listed");
    assert_eq!(listed.len(), events.len(), "every event is listed");
    // trace.svg marks the same impacts (touchdowns and impacts without collision) and says how many.
    let impacts = listed.iter().filter(|(k, _)| k == "touchdown" || k == "impact_without_collision").count();
    let svg = std::fs::read_to_string(sim.join("trace.svg")).unwrap();
    assert!(svg.contains(&format!("{impacts} impacts between the samples")), "trace.svg counts the page's {impacts} impacts");
    for ((k, t), (lk, lt)) in events.iter().zip(&listed) {
        assert!(k == lk && t.to_bits() == lt.to_bits(), "events.csv has {k} at {t} s, the page {lk} at {lt} s");
    }

    // The first frame at or after the second touchdown: its readout names it.
    let data = page_data(&dom);
    let frames: Vec<f64> = data["frames"]["t"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let td = touchdowns[1];
    let i = frames.iter().position(|&f| f >= td).expect("a frame after the touchdown");
    let dom = browse(&chromium, scratch, &["--dump-dom".to_string()], &url(&frames[i].to_string()));
    let readout = &dom[dom.find("<figcaption id=\"readout\"").unwrap()..];
    let readout = &readout[..readout.find("</figcaption>").unwrap()];
    assert!(readout.contains("touchdown at"), "the frame after a touchdown names it: {readout}");
    let (s, base_x, base_y, _) = mapping(&dom);
    let tip_at = |t: f64| {
        let (_, z_t, z_n) = trace_at(&sim.join("trace.csv"), t);
        (base_x + s * z_t, base_y - s * z_n)
    };
    let png = scratch.join("impact.png");
    browse(&chromium, scratch, &[format!("--screenshot={}", png.display())], &url(&frames[i].to_string()));
    let ring = ring_pixels(&decode(&png), tip_at(frames[i]), 22.0);
    assert!(ring >= 40, "a ring around the contact in the frame after the touchdown: {ring} px of its colour");

    // A frame in flight with no event since the previous frame: no ring.
    let h = data["h"].as_f64().unwrap();
    let quiet = (1..frames.len())
        .find(|&j| {
            frames[j] > 0.2
                && !events.iter().any(|(_, t)| *t > frames[j - 1] - 1e-6 && *t <= frames[j] + 1e-6)
                && trace_at(&sim.join("trace.csv"), frames[j]).2 > -h + 1e-3
        })
        .expect("a frame in flight with no event");
    let png = scratch.join("quiet.png");
    browse(&chromium, scratch, &[format!("--screenshot={}", png.display())], &url(&frames[quiet].to_string()));
    let ring = ring_pixels(&decode(&png), tip_at(frames[quiet]), 22.0);
    assert!(ring < 5, "no ring without an impact (t = {} s): {ring} px of its colour", frames[quiet]);
}

/// Issue 69 (1), over random open-loop runs (not only the x0a bounce): the
/// page's events are `events.csv`'s, every one, each kind and time bit for bit.
/// Reads the page's data (no browser): the list the script builds is this data.
#[test]
fn every_event_of_random_runs_is_in_the_page() {
    let dir = tempfile::tempdir().unwrap();
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut impacts = 0;
    for k in 0..8 {
        let out = dir.path().join(format!("run{k}"));
        let x0 = ["a", "d", "u"][(next() * 3.0) as usize];
        let law = ["newton", "poisson", "energetic"][(next() * 3.0) as usize];
        let (mu, v_belt, e_n) = (0.2 + 0.8 * next(), -1.0 + 0.9 * next(), 0.8 * next());
        let (mu, v_belt, e_n) = (format!("{mu:.3}"), format!("{v_belt:.3}"), format!("{e_n:.2}"));
        let args = ["simulate", "--x0", x0, "--mu", &mu, "--v-belt", &v_belt, "--e-n", &e_n, "--impact-law", law, "--duration", "3"];
        sil_host(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
        let events = events_of(&out.join("events.csv"));
        let data = page_data(&std::fs::read_to_string(out.join("trace.html")).unwrap());
        let e = &data["events"];
        let kinds: Vec<&str> = e["kinds"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
        let listed: Vec<(String, f64)> = e["t"]
            .as_array()
            .unwrap()
            .iter()
            .zip(e["kind"].as_array().unwrap())
            .map(|(t, i)| (kinds[i.as_u64().unwrap() as usize].to_string(), t.as_f64().unwrap()))
            .collect();
        assert_eq!(listed.len(), events.len(), "{args:?}: every event in the page");
        for ((a, ta), (b, tb)) in events.iter().zip(&listed) {
            assert!(a == b && ta.to_bits() == tb.to_bits(), "{args:?}: events.csv {a} at {ta}, the page {b} at {tb}");
        }
        assert_eq!(e["left_out"], 0, "{args:?}");
        impacts += events.iter().filter(|(k, _)| k == "touchdown" || k == "impact_without_collision").count();
    }
    assert!(impacts > 0, "the random runs have impacts to mark");
}
