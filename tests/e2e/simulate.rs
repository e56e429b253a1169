//! End-to-end: `sil-host simulate` through the same entry point as the binary.

use std::path::Path;

use crate::common::{csv_rows, run, summary_of};

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|it| it.filter_map(|e| e.ok()).map(|e| e.file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn simulate_writes_trace_events_figure_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let code = run(&["simulate", "--x0", "a", "--duration", "2", "--out", out.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    assert_eq!(files_in(&out), vec!["events.csv", "summary.json", "trace.csv", "trace.html", "trace.pdf", "trace.svg"]);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "ok");
    assert_eq!(summary["initial_condition"]["name"], "x0a");
    assert_eq!(summary["initial_condition"]["projection"]["projected"], true);
    assert!((summary["simulated_s"].as_f64().unwrap() - 2.0).abs() < 1e-12);
    // x0a is in the Painlevé region: the run starts with an impact without collision, then bounces.
    assert_eq!(summary["impacts_without_collision"], 1);
    assert!(summary["touchdowns"].as_u64().unwrap() > 3);
    // The trace: one row per millisecond plus t = 0, never below the belt.
    let h = summary["params"]["h"].as_f64().unwrap();
    let mut rdr = csv::Reader::from_path(out.join("trace.csv")).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let zn = headers.iter().position(|c| c == "z_n").unwrap();
    let fnn = headers.iter().position(|c| c == "f_n").unwrap();
    let mode = headers.iter().position(|c| c == "mode").unwrap();
    let mut rows = 0;
    for rec in rdr.records() {
        let rec = rec.unwrap();
        let z_n: f64 = rec[zn].parse().unwrap();
        let f_n: f64 = rec[fnn].parse().unwrap();
        assert!(z_n >= -h - 1e-9, "below the belt: {z_n}");
        if &rec[mode] == "flight" {
            assert_eq!(f_n, 0.0);
        }
        rows += 1;
    }
    assert_eq!(rows, 2001);
    // Every touchdown in events.csv is at the belt with a reversal of the normal velocity.
    let mut rdr = csv::Reader::from_path(out.join("events.csv")).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let kind = headers.iter().position(|c| c == "kind").unwrap();
    let before = headers.iter().position(|c| c == "v_n_before").unwrap();
    let work = headers.iter().position(|c| c == "contact_work").unwrap();
    let mut touchdowns = 0;
    for rec in rdr.records() {
        let rec = rec.unwrap();
        if &rec[kind] == "touchdown" {
            touchdowns += 1;
            assert!(rec[before].parse::<f64>().unwrap() < 0.0);
        }
        assert!(rec[work].parse::<f64>().unwrap() <= 1e-12, "an impact created energy");
    }
    assert_eq!(touchdowns, summary["touchdowns"].as_u64().unwrap());
    let svg = std::fs::read_to_string(out.join("trace.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("zₙ"));
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad");
    let o = out.to_str().unwrap();
    for args in [
        vec!["simulate", "--mu", "nan", "--out", o],
        vec!["simulate", "--mu", "-0.5", "--out", o],
        vec!["simulate", "--e-n", "1.5", "--out", o],
        vec!["simulate", "--duration", "-1", "--out", o],
        vec!["simulate", "--rtol", "0", "--out", o],
        // Tip 1 cm inside the belt (theta1 = theta2 = 0: the hanging arm reaches 2 l = 0.42 m > H).
        vec!["simulate", "--x0-deg", "0,0,0,0", "--out", o],
        vec!["simulate", "--x0-deg", "1,2,3", "--out", o],
        vec!["simulate", "--no-such-flag", "--out", o],
        vec!["admissible", "--mu", "-1", "--out", o],
        vec!["modes", "--mu", "inf", "--out", o],
    ] {
        assert_eq!(run(&args), 2, "{args:?}");
        assert!(files_in(&out).is_empty(), "{args:?} wrote {:?}", files_in(&out));
    }
}

#[test]
fn a_failed_run_does_not_clobber_a_previous_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    assert_eq!(run(&["simulate", "--duration", "0.05", "--out", out.to_str().unwrap()]), 0);
    let before = std::fs::read(out.join("summary.json")).unwrap();
    assert_eq!(run(&["simulate", "--mu", "nan", "--out", out.to_str().unwrap()]), 2);
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), before);
    assert_eq!(files_in(out), vec!["events.csv", "summary.json", "trace.csv", "trace.html", "trace.pdf", "trace.svg"]);
}

/// Issue 24's example (elbow up, below the critical `mu`, Newton with `e_n = 0.5`):
/// the first impact's normal impulse reverses the slip through `Q_12`. With the
/// friction impulse taken against the slip *before* the impact, friction then
/// pointed along the slip after it, and the run never settled (2 490 touchdowns in
/// 300 s, 829 energetic fallbacks, 415 touchdowns in the last 50 s). An event-driven
/// and a Moreau-Jean implementation written elsewhere both settle into sliding after
/// a few dozen touchdowns; so must every law here, with no fallback for Newton, and
/// every Newton impulse must oppose the slip it leaves (or stick).
#[test]
fn a_newton_impact_whose_slip_reverses_settles_into_sliding() {
    for law in ["newton", "poisson", "energetic"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        let code = run(&[
            "simulate",
            "--x0-deg=-6.4753421,0,36.4863482,0",
            "--mu",
            "0.2463681",
            "--v-belt=-0.5902458",
            "--impact-law",
            law,
            "--e-n",
            "0.5",
            "--duration",
            "300",
            "--out",
            out.to_str().unwrap(),
            "--json",
        ]);
        assert_eq!(code, 0, "{law}");
        let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["final_mode"], "sliding", "{law}");
        let counters = &summary["counters"];
        let touchdowns = counters["touchdowns"].as_u64().unwrap();
        assert!((1..100).contains(&touchdowns), "{law}: {touchdowns} touchdowns");
        assert_eq!(counters["newton_fallbacks"], 0, "{law}");
        assert_eq!(summary["validity"]["integrator_failures"], 0, "{law}");
        assert_eq!(summary["status"], "ok", "{law}");
        let mut rdr = csv::Reader::from_path(out.join("events.csv")).unwrap();
        let headers = rdr.headers().unwrap().clone();
        let col = |name: &str| headers.iter().position(|c| c == name).unwrap();
        let (t, kind, vr_after, pt, resolution) = (col("t"), col("kind"), col("v_r_after"), col("impulse_t"), col("resolution"));
        let mut last_touchdown = 0.0_f64;
        for rec in rdr.records() {
            let rec = rec.unwrap();
            if &rec[kind] != "touchdown" {
                continue;
            }
            last_touchdown = rec[t].parse().unwrap();
            if law == "newton" {
                let (v, p): (f64, f64) = (rec[vr_after].parse().unwrap(), rec[pt].parse().unwrap());
                assert!(
                    p * v <= 1e-12 || &rec[resolution] == "newton_sticking",
                    "friction along the slip after the impact: P_t {p}, v_r+ {v}"
                );
            }
        }
        assert!(last_touchdown < 250.0, "{law}: still bouncing at {last_touchdown} s");
    }
}

/// Issue 24: a `mu` scan across the bouncing band of a perturbed arm (found by a
/// search: Table I's `m` +11 %, `l` +4 %, `sigma` +19 %, `k` -16 %, `alpha0` -17 %,
/// `h` set so that `x0a` is on the belt; Poisson, `e_n = 0.1`, `v_belt` -0.984 m/s)
/// completes every run under both IWC rules, the dynamic jams counted. Before the
/// jam was resolved where the step size collapses, `mu` 0.41 and 0.42 failed
/// ("step size 1.4e-13 s too small") under both rules, with `f_n` only 40 to 450 N.
#[test]
fn a_mu_scan_across_a_bouncing_band_of_a_perturbed_arm_completes_with_its_jams_counted() {
    let dir = tempfile::tempdir().unwrap();
    let arm = [
        "plant.m=0.13288317384683318",
        "plant.l=0.21762723339408532",
        "plant.sigma=0.005932199636113795",
        "plant.k=1.0920241576528966",
        "plant.h=0.3912149518771235",
        "plant.alpha0=0.19777060647993205",
    ];
    for iwc in ["plastic", "restitution"] {
        let (mut jams, mut bouncing, mut settled) = (0, 0, 0);
        for k in 0..=10 {
            let mu = format!("{:.2}", 0.36 + 0.01 * f64::from(k));
            let out = dir.path().join(format!("{iwc}-{mu}"));
            let mut args = vec!["simulate", "--x0", "a", "--mu", &mu, "--v-belt=-0.9839901853524298", "--duration", "130"];
            args.extend(["--iwc", iwc, "--impact-law", "poisson", "--e-n", "0.1", "--sample-dt", "0.01", "--out", out.to_str().unwrap()]);
            for a in &arm {
                args.extend(["--set", a]);
            }
            assert_eq!(run(&args), 0, "{iwc}, mu {mu}");
            let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
            assert_eq!(s["status"], "ok", "{iwc}, mu {mu}");
            assert_eq!(s["validity"]["integrator_failures"], 0, "{iwc}, mu {mu}");
            assert!((s["simulated_s"].as_f64().unwrap() - 130.0).abs() < 1e-9);
            let c = &s["counters"];
            jams += c["jams"].as_u64().unwrap();
            let touchdowns = c["touchdowns"].as_u64().unwrap();
            if touchdowns > 500 {
                bouncing += 1;
            }
            if touchdowns < 20 && s["final_mode"] == "sliding" {
                settled += 1;
            }
        }
        assert!(bouncing >= 2 && settled >= 1, "{iwc}: the scan crosses the band: {bouncing} bouncing, {settled} settled");
        assert!(jams >= 10, "{iwc}: the corner is met and counted: {jams} jams");
    }
}

#[test]
fn sigterm_stops_simulate_with_its_outputs_written_and_nothing_left_over() {
    // Issue 39: an interrupted simulate left `.partial` files and a stale owner
    // file (SIGTERM killed it). Now it stops at its next chunk, writes what it
    // simulated (status `stopped`), cleans up, and exits 143.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["simulate", "--duration", "3000", "--out", out.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Event-driven: the signal comes once rows are being written.
    let partial = out.join(".trace.csv.partial");
    let start = std::time::Instant::now();
    while std::fs::metadata(&partial).map_or(0, |m| m.len()) == 0 {
        assert!(start.elapsed() < std::time::Duration::from_secs(60), "simulate never started writing");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(143), "{err}");
    assert!(err.contains("stopped by a signal"), "{err}");
    assert_eq!(files_in(&out), vec!["events.csv", "summary.json", "trace.csv", "trace.html", "trace.pdf", "trace.svg"]);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "stopped");
    assert!(summary["simulated_s"].as_f64().unwrap() < 3000.0);
}

#[test]
fn what_a_killed_command_left_is_removed_by_the_next_one() {
    // SIGKILL leaves its staged files and owner file: the next command on the
    // folder (which now holds its lock) removes them and says so.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir_all(&out).unwrap();
    for f in [".trace.csv.partial", ".events.csv.partial", ".sil-host.owner"] {
        std::fs::write(out.join(f), "left by a killed run").unwrap();
    }
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sil-host"))
        .args(["simulate", "--duration", "1", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("removed what an interrupted command left"));
    assert_eq!(files_in(&out), vec!["events.csv", "summary.json", "trace.csv", "trace.html", "trace.pdf", "trace.svg"]);
}

#[test]
fn with_no_friction_a_tip_at_rest_is_never_a_cone_violation() {
    // Issue 39: the fuzzer's reproducer at mu = 0 was flagged INVALID for a
    // friction-cone violation; with no friction there is no cone to leave (the
    // tip comes to rest at an equilibrium, its slip acceleration zero to rounding).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mu0");
    let code = run(&[
        "simulate",
        "--x0-deg=-4.241873513684681,6.759357711486936,-38.74046096645096,-8.50371822885448",
        "--mu",
        "0.0",
        "--v-belt",
        "0.0",
        "--impact-law",
        "energetic",
        "--e-n",
        "1.0",
        "--duration",
        "20.880",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["validity"]["cone_violations"], 0, "{}", summary["validity"]);
    assert_eq!(summary["status"], "ok");
    // The run reached the rest the violation was flagged at (t = 19.81 s).
    assert!(summary["counters"]["touchdowns"].as_u64().unwrap() > 1000);
}

/// Issue 40: the singular-point rule is a setting of every run: `--singular slide`
/// is written in the summary's `sim` (the default, `leave`, is not), the counters
/// name the singular points and bridges, and a value that is no rule is refused.
#[test]
fn the_singular_rule_is_a_setting_and_its_counters_are_in_every_summary() {
    let dir = tempfile::tempdir().unwrap();
    for (rule, written) in [(None, false), (Some("slide"), true)] {
        let out = dir.path().join(format!("{rule:?}"));
        let mut args = vec!["simulate", "--duration", "1", "--out", out.to_str().unwrap()];
        if let Some(r) = rule {
            args.extend(["--singular", r]);
        }
        assert_eq!(run(&args), 0);
        let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(s["sim"].get("singular").is_some(), written, "{rule:?}: {}", s["sim"]);
        for key in ["singular_points", "bridges", "bridged_s"] {
            assert_eq!(s["counters"][key].as_f64(), Some(0.0), "{key}");
        }
    }
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sil-host")).args(["simulate", "--singular", "stay"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("leave"), "the choices are named");
}

/// Issue 53's arm, start and belt (`--mu 0.422`, Newton `e_n` 0.2).
const ISSUE53: [&str; 18] = [
    "--set",
    "plant.m=0.15",
    "--set",
    "plant.l=0.23",
    "--set",
    "plant.sigma=0.008",
    "--set",
    "plant.k=1.0",
    "--set",
    "plant.h=0.40",
    "--set",
    "plant.alpha0=0.20",
    "--x0-deg=34.53531701873741,0.0,23.744016380660902,0.0",
    "--v-belt=-0.5",
    "--mu",
    "0.422",
    "--duration",
    "300",
];

/// Issue 53: the energy jump with status ok. Both reproducers (plastic at 10 ms,
/// restitution at 100 ms) and the four other runs bounce to 300 s, as a
/// Moreau-Jean time-stepper and a SciPy event-driven simulator do: no rise of the
/// energy between two samples beyond the orbit's own (0.033 J), the energy at the
/// end the bouncing orbit's (above -0.59 J; the rest state the jump ended in has
/// -0.6078 J), the ledger closed and in the summary.
#[test]
fn the_issue53_reproducers_keep_bouncing_with_the_energy_ledger_closed() {
    let dir = tempfile::tempdir().unwrap();
    for iwc in ["plastic", "restitution"] {
        for dt in ["0.1", "0.01", "0.001"] {
            let out = dir.path().join(format!("{iwc}-{dt}"));
            let mut args = vec!["simulate", "--iwc", iwc, "--sample-dt", dt, "--out", out.to_str().unwrap()];
            args.extend(ISSUE53);
            assert_eq!(run(&args), 0, "{iwc} {dt}");
            let s = summary_of(&out);
            assert_eq!(s["status"], "ok");
            let rows = csv_rows(&out.join("trace.csv"));
            let energy = rows[0].iter().position(|c| c == "energy").unwrap();
            let e: Vec<f64> = rows[1..].iter().map(|r| r[energy].parse().unwrap()).collect();
            let rise = e.windows(2).map(|w| w[1] - w[0]).fold(f64::NEG_INFINITY, f64::max);
            assert!(rise < 0.2, "{iwc} {dt}: the energy rose by {rise} J between two samples");
            assert!(*e.last().unwrap() > -0.59, "{iwc} {dt}: E(300) = {} J: left the bouncing orbit", e.last().unwrap());
            let l = &s["ledger"];
            assert_eq!(l["violations"], 0, "{iwc} {dt}: {l}");
            assert!(l["residual_j"].as_f64().unwrap().abs() < 1e-6, "{iwc} {dt}: {l}");
            assert!(s["counters"]["singular_points"].as_u64().unwrap() > 100, "{iwc} {dt}: the orbit passes the singular point");
        }
    }
}

/// Issue 53: the open loop's path does not depend on the sample period nor on the
/// duration. From `x0a` at `mu` 0.6, `v_belt` -0.5 (where the 0.1 s trace used to
/// leave the 0.001 s one at t = 0.4 s): the events are the same bytes, a row of the
/// 0.1 s trace is the row of the 0.001 s trace at the same instant (the same bytes
/// where the two instants `k 0.1` and `100 k 0.001` are the same double, within
/// what their rounding moves elsewhere), and a 100 s run is the first 100 s of a 300 s run.
/// Issue 67: the same for the accuracy contract's two other arms, whose steps the
/// arm's dynamics cap (`plant::time_scale`) at 0.22 ms and 7.7 ms.
#[test]
fn the_open_loop_path_depends_on_neither_the_sample_period_nor_the_duration() {
    let paper = ["--x0", "a"];
    let other = |sets: [&'static str; 6]| {
        let mut args = vec![crate::common::OTHER_ARM_X0];
        for set in sets {
            args.extend(["--set", set]);
        }
        args
    };
    let short = other(crate::common::SHORT_ARM);
    let long = other(crate::common::LONG_ARM);
    path_is_independent_of_sampling_and_duration("paper", &paper, "30", ("100", "300"), 100);
    path_is_independent_of_sampling_and_duration("short", &short, "10", ("4", "10"), 40);
    path_is_independent_of_sampling_and_duration("long", &long, "10", ("4", "10"), 10);
}

/// The checks of [`the_open_loop_path_depends_on_neither_the_sample_period_nor_the_duration`]
/// for one arm (`arm`: its `simulate` arguments), over `duration` s (at 1 ms and 0.1
/// s samples) and the `prefix` pair of durations (0.01 s samples), with more than
/// `min_events` events.
fn path_is_independent_of_sampling_and_duration(name: &str, arm: &[&str], duration: &str, prefix: (&str, &str), min_events: usize) {
    let dir = tempfile::tempdir().unwrap();
    let simulate = |run_name: &str, dt: &str, duration: &str| {
        let out = dir.path().join(run_name);
        let mut args = vec!["simulate", "--mu", "0.6", "--v-belt=-0.5", "--sample-dt", dt, "--duration", duration];
        args.extend(arm);
        args.extend(["--out", out.to_str().unwrap()]);
        assert_eq!(run(&args), 0, "{name} {run_name}");
        (csv_rows(&out.join("trace.csv")), std::fs::read_to_string(out.join("events.csv")).unwrap())
    };
    let (fine, fine_events) = simulate("fine", "0.001", duration);
    let (coarse, coarse_events) = simulate("coarse", "0.1", duration);
    assert_eq!(fine_events, coarse_events, "{name}: the events do not depend on the sample period");
    assert!(fine_events.lines().count() > min_events, "{name}: {} events", fine_events.lines().count());
    let (mut same_instant, mut worst) = (0, 0.0f64);
    for (k, row) in coarse.iter().enumerate().skip(1) {
        let other = &fine[(k - 1) * 100 + 1];
        if row[0] == other[0] {
            assert_eq!(row, other, "{name}: the same instant, the same row");
            same_instant += 1;
        } else {
            for (a, b) in row[1..10].iter().zip(&other[1..10]) {
                worst = worst.max((a.parse::<f64>().unwrap() - b.parse::<f64>().unwrap()).abs());
            }
        }
    }
    assert!(same_instant > coarse.len() / 2, "{name}: {same_instant} rows at bit-equal instants");
    assert!(worst < 1e-9, "{name}: rows at instants a rounding apart differ by {worst}");
    let (long, long_events) = simulate("long", "0.01", prefix.1);
    let (short, short_events) = simulate("short", "0.01", prefix.0);
    assert_eq!(short[..], long[..short.len()], "{name}: a {} s run is the first {} s of a {} s run", prefix.0, prefix.0, prefix.1);
    assert!(long_events.starts_with(&short_events), "{name}");
}

/// Issue 53: a near-singular Newton touchdown can take much energy from the belt
/// within the rigid model (this arm gains 9.4 J in one touchdown at 0.457 s, its
/// contact work -6.0 J): the ledger accounts for it, names it (the belt's 15.4 J in
/// one event) and closes, and the run is valid.
#[test]
fn the_ledger_names_the_largest_energy_one_event_took_from_the_belt() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("touchdown");
    let mut args = vec!["simulate", "--mu", "0.41", "--v-belt=-0.5", "--duration", "1", "--out", out.to_str().unwrap()];
    args.extend(["--x0-deg=34.53531701873741,0.0,23.744016380660902,0.0"]);
    for set in ["plant.m=0.1788", "plant.l=0.2238", "plant.sigma=0.0063", "plant.k=1.0518", "plant.h=0.4167", "plant.alpha0=0.177"] {
        args.extend(["--set", set]);
    }
    assert_eq!(run(&args), 0);
    let s = summary_of(&out);
    let l = &s["ledger"];
    let largest = l["largest_event_belt_j"].as_f64().unwrap();
    assert!((15.0..16.0).contains(&largest), "{l}");
    assert_eq!(l["violations"], 0);
    assert!(l["residual_j"].as_f64().unwrap().abs() < 1e-6, "{l}");
    assert_eq!(s["validity"]["energy_gains"], 0, "the impact is admissible in the belt's frame");
}

// Issue 67, item 5 ("Smaller").

/// Runs the binary (for what it prints); returns the exit code, standard output
/// and standard error.
fn sil_host_output(args: &[&str]) -> (i32, String, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).output().unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Issue 67's light, short arm with links of `l` m: its `--set` overrides, the
/// base height `H` putting the tip of its start ([`SHORT_ARM_X0`]) on the belt.
fn short_arm(l: f64) -> Vec<String> {
    let h = l * (27.696865482139f64.to_radians().cos() + 18.573779305261f64.to_radians().cos());
    ["plant.m=0.02".to_string(), format!("plant.l={l:?}"), "plant.sigma=0.0003".into(), "plant.k=1.5".into()]
        .into_iter()
        .chain([format!("plant.h={h:?}"), "plant.alpha0=0.2".into()])
        .flat_map(|s| ["--set".to_string(), s])
        .collect()
}

/// The start of issue 67's short arm, deg and deg/s.
const SHORT_ARM_X0: &str = crate::common::OTHER_ARM_X0;

/// (a) The open-loop commands take an arm too short for the default scenario's
/// closed-loop target (`controller.target_z_t` = 0.10 m, at or beyond the reach
/// `2 l` for `l <= 0.05` m), which they never use: `simulate` ran issue 67's arm
/// (`l` = 0.06 m) and refused every arm with `l <= 0.05` m. A closed-loop `run`
/// uses the target and still refuses it, naming the key and the reach.
#[test]
fn a_short_arm_runs_open_loop_and_its_unreachable_target_is_refused_closed_loop() {
    let dir = tempfile::tempdir().unwrap();
    for l in [0.06, 0.05, 0.04] {
        let out = dir.path().join(format!("simulate-{l}"));
        let arm = short_arm(l);
        let mut args: Vec<&str> = vec!["simulate", SHORT_ARM_X0, "--v-belt=-0.5", "--mu", "0.6", "--duration", "0.5", "--no-page"];
        args.extend(arm.iter().map(String::as_str));
        args.extend(["--out", out.to_str().unwrap()]);
        assert_eq!(run(&args), 0, "l = {l}");
        let s = summary_of(&out);
        assert_eq!((s["status"].as_str(), s["params"]["l"].as_f64()), (Some("ok"), Some(l)), "l = {l}");
        assert!(s["simulated_s"].as_f64().unwrap() == 0.5 && s["touchdowns"].as_u64().unwrap() >= 1, "l = {l}: {s}");
    }
    let arm = short_arm(0.05);
    let arm: Vec<&str> = arm.iter().map(String::as_str).collect();
    let poincare = dir.path().join("poincare");
    let mut args = vec!["poincare", SHORT_ARM_X0, "--v-belt=-0.5,-0.4", "--v-step", "0.1", "--transient", "1", "--record", "1"];
    args.extend(&arm);
    args.extend(["--out", poincare.to_str().unwrap()]);
    assert_eq!(run(&args), 0, "poincare");
    let sweep = dir.path().join("sweep");
    let mut args = vec!["sweep", "--mu", "0.6", "--v-belt=-0.5", "--ics", "a", "--transient", "1", "--record", "1"];
    args.extend(&arm);
    args.extend(["--out", sweep.to_str().unwrap()]);
    assert_eq!(run(&args), 0, "sweep");
    for (what, set) in [("modes", vec!["modes", "--grid", "20"]), ("admissible", vec!["admissible"])] {
        let out = dir.path().join(what);
        let mut args = set;
        args.extend(["--set", "plant.l=0.05", "--set", "plant.h=0.09", "--out", out.to_str().unwrap()]);
        assert_eq!(run(&args), 0, "{what}");
    }
    // Closed loop the target is used: refused before anything is written.
    let out = dir.path().join("run");
    let mut args = vec!["run", "--in-process", "--duration", "0.1"];
    args.extend(&arm);
    args.extend(["--out", out.to_str().unwrap()]);
    let (code, _, err) = sil_host_output(&args);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("controller.target_z_t") && err.contains("0.1") && err.contains("2 l = 0.1 m"), "{err}");
    assert!(!err.contains("panicked") && !out.exists(), "{err}");
    // The arm itself is still checked: the belt out of its reach.
    let (code, _, err) = sil_host_output(&["simulate", "--set", "plant.l=0.05", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("plant.h") && err.contains("2 l = 0.1 m") && !out.exists(), "{err}");
}

/// The times of the departures from the belt in `events.csv`: a lift-off or a
/// singular point into flight, and an impact (a touchdown's bounce, an impact
/// without collision, a jam) that leaves the tip faster than the Zeno rule's
/// velocity, 1e-4 m/s (`analyses::lift_offs`'s test counts them so).
fn departures(events: &Path) -> Vec<f64> {
    let rows = csv_rows(events);
    let col = |name: &str| rows[0].iter().position(|c| c == name).unwrap();
    let (t, kind, mode, v_n) = (col("t"), col("kind"), col("mode_after"), col("v_n_after"));
    rows[1..]
        .iter()
        .filter(|r| match r[kind].as_str() {
            "lift_off" | "singular_point" => r[mode] == "flight",
            "touchdown" | "impact_without_collision" | "jam" => r[v_n].parse::<f64>().unwrap() > 1e-4,
            _ => false,
        })
        .map(|r| r[t].parse().unwrap())
        .collect()
}

/// (b) `lift_offs` has one meaning everywhere, every departure from the belt: on
/// the bounce from `x0a` (`mu` 0.6, `v_belt` -0.5: its impact without collision
/// at `t = 0`, then rebounds) `simulate`'s count over 5 s is `sweep`'s over its
/// transient (1 s) and record window (4 s), each window's the departures of
/// `events.csv` in it; `counters.lift_offs` is the same count and the plant's own
/// count, without the bounces, is `counters.lift_offs_from_contact` (1: before
/// issue 67 `simulate` wrote that as `lift_offs`).
#[test]
fn simulate_and_sweep_count_the_same_lift_offs() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("simulate");
    let args = ["simulate", "--x0", "a", "--mu", "0.6", "--v-belt=-0.5", "--duration", "5", "--sample-dt", "0.01", "--no-page"];
    let mut args = args.to_vec();
    args.extend(["--out", sim.to_str().unwrap()]);
    assert_eq!(run(&args), 0);
    let s = summary_of(&sim);
    let sweep = dir.path().join("sweep");
    let args = ["sweep", "--mu", "0.6", "--v-belt=-0.5", "--ics", "a", "--transient", "1", "--record", "4"];
    let mut args = args.to_vec();
    args.extend(["--out", sweep.to_str().unwrap()]);
    assert_eq!(run(&args), 0);
    let rows = csv_rows(&sweep.join("sweep.csv"));
    assert_eq!(rows.len(), 2, "one run");
    let cell = |name: &str| -> u64 { rows[1][rows[0].iter().position(|c| c == name).unwrap()].parse().unwrap() };
    let (transient, record) = (cell("lift_offs_transient"), cell("lift_offs"));
    let lift_offs = s["lift_offs"].as_u64().unwrap();
    assert!(lift_offs > 20, "it bounces: {lift_offs}");
    assert_eq!(lift_offs, transient + record, "simulate {lift_offs}, sweep {transient} + {record}");
    let c = &s["counters"];
    assert_eq!(c["lift_offs"].as_u64(), Some(lift_offs));
    assert_eq!(c["lift_offs_from_contact"].as_u64(), Some(1), "the impact without collision at t = 0: {c}");
    assert_eq!(c["lift_offs_from_contact"].as_u64().unwrap() + c["bounces"].as_u64().unwrap(), lift_offs, "{c}");
    let t = departures(&sim.join("events.csv"));
    assert_eq!(t.len() as u64, lift_offs, "every departure in events.csv");
    assert_eq!(t.iter().filter(|t| **t <= 1.0).count() as u64, transient, "sweep's transient");
    assert_eq!(t.iter().filter(|t| **t > 1.0).count() as u64, record, "sweep's record window");
}

/// (c) `initial_condition.used_deg` is the state the run starts from, before any
/// impulse: from `x0a` the angles projected onto the belt and the rates as given
/// (0), where it held the rates after the impact without collision at `t = 0`
/// (199.94, -322.20 deg/s at `v_belt` -0.5), now `after_startup_deg` (the trace's
/// first row). A run started from `used_deg` resolves `t = 0` the same way.
#[test]
fn used_deg_is_the_projected_start_before_any_impulse() {
    let dir = tempfile::tempdir().unwrap();
    let simulate = |name: &str, x0: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["simulate", "--mu", "0.6", "--v-belt=-0.5", "--duration", "0.2", "--no-page"];
        args.extend(x0);
        args.extend(["--out", out.to_str().unwrap()]);
        assert_eq!(run(&args), 0, "{name}");
        (summary_of(&out), csv_rows(&out.join("trace.csv")))
    };
    let deg = |v: &serde_json::Value| -> [f64; 4] { std::array::from_fn(|i| v[i].as_f64().unwrap()) };
    let (s, trace) = simulate("x0a", &["--x0", "a"]);
    let ic = &s["initial_condition"];
    let (used, after) = (deg(&ic["used_deg"]), deg(&ic["after_startup_deg"]));
    assert_eq!(ic["projection"]["projected"], true);
    assert_eq!(ic["startup_events"], serde_json::json!(["impact_without_collision"]));
    assert!((used[0] - 32.0043).abs() < 1e-4 && (used[2] - 18.2662).abs() < 1e-4, "{used:?}");
    assert_eq!([used[1], used[3]], [0.0, 0.0], "the rates as given, before the impulse: {used:?}");
    assert_eq!([after[0], after[2]], [used[0], used[2]], "an impulse moves no angle");
    assert!((after[1] - 199.94).abs() < 0.01 && (after[3] + 322.20).abs() < 0.01, "{after:?}");
    let first: Vec<f64> = trace[1][1..5].iter().map(|c| c.parse::<f64>().unwrap().to_degrees()).collect();
    assert_eq!(first, after, "after_startup_deg is the trace's first row");
    // The projected start is on the belt ...
    let params = shared::Params::<f64> { mu: 0.6, v_belt: -0.5, ..shared::Params::paper() };
    let x = plant::initial::deg_to_state(used);
    assert!(plant::initial::describe_projection(&params, x).height_above_belt.abs() < 1e-12);
    // ... and, given as a custom start, is resolved as x0a was: the same impact
    // without collision at t = 0, the same state after it.
    let given = format!("--x0-deg={}", used.map(|v| format!("{v:?}")).join(","));
    let (custom, _) = simulate("custom", &[given.as_str()]);
    let ic = &custom["initial_condition"];
    assert_eq!(ic["startup_events"], serde_json::json!(["impact_without_collision"]));
    for (a, b) in deg(&ic["used_deg"]).iter().zip(used) {
        assert!((a - b).abs() < 1e-9, "{:?} against {used:?}", ic["used_deg"]);
    }
    for (a, b) in deg(&ic["after_startup_deg"]).iter().zip(after) {
        assert!((a - b).abs() < 1e-6 * (1.0 + b.abs()), "{:?} against {after:?}", ic["after_startup_deg"]);
    }
}

/// (d) The default impact-without-collision rule throws the tip off the belt
/// where a Moreau-Jean time-stepper (Siconos) leaves it on: `--iwc`'s help says
/// to compare with one under `--iwc plastic` (`simulate`, `poincare`; `sweep`'s
/// list of rules names `plastic` as that rule).
#[test]
fn the_iwc_help_says_to_compare_with_moreau_jean_codes_under_plastic() {
    for command in ["simulate", "poincare", "sweep"] {
        let (code, help, err) = sil_host_output(&[command, "--help"]);
        assert_eq!(code, 0, "{command}: {err}");
        let at = help.find("--iwc <IWC>").unwrap_or_else(|| panic!("{command}: no --iwc in {help}"));
        let entry = &help[at..];
        let entry = &entry[..entry[2..].find("\n      --").map_or(entry.len(), |e| e + 2)];
        let words = entry.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(words.contains("Moreau-Jean") && words.contains("Siconos"), "{command}: {words}");
        if command == "sweep" {
            assert!(words.contains("`plastic` (left stuck, v_n = 0; the rule to compare with a Moreau-Jean"), "{words}");
        } else {
            assert!(words.contains("run with `--iwc plastic`") && words.contains("v_n = 0.018 m/s"), "{command}: {words}");
        }
    }
}
