//! Issue 81: the accuracy contract restated on the path, in quantities that do not
//! depend on how densely a run is sampled (docs/architecture.md "The contract on the
//! path"): the events' kinds in order and their times, and the angles in encoder
//! counts at the whole seconds (rows of any trace whose period divides 1 s). A run's
//! **path horizon** against a reference is the first event whose kind differs or whose
//! time differs by more than [`EVENT_TIME_S`], or the first whole second whose angles
//! differ by more than [`COUNT_FRACTION`] of an encoder count, whichever comes first.
//!
//! The sampled norm it replaces put one path's departure at 2.939 s with a 1 ms trace
//! and at 5.0 s with 1 s samples (the norm's error peaks at a zero crossing of
//! `theta1_dot`, where the tolerance falls to `atol`); here both samplings report one
//! horizon, and `rtol` moves it only where the tolerance, not the step cap, sets the
//! steps.

use std::{path::Path, process::Command};

use crate::common;

/// The tolerance on an event's time, s: an angle error of a thousandth of a count
/// (3.8e-7 rad) moves a touchdown by about that at the bouncing's rates of about 0.4 rad/s.
pub const EVENT_TIME_S: f64 = 1e-6;
/// The tolerance on the angles at the whole seconds, in encoder counts (14 bits).
pub const COUNT_FRACTION: f64 = 1e-3;
/// One encoder count, rad (docs/hardware.md: 14-bit absolute encoders).
const COUNT: f64 = 2.0 * std::f64::consts::PI / 16384.0;

/// A run's path: its events `(t, kind)` and its angles at the whole seconds.
pub struct PathOf {
    events: Vec<(f64, String)>,
    seconds: Vec<(i64, [f64; 2])>,
}

/// Reads a folder's `events.csv` and its trace's whole-second rows; a folder with no
/// events table (`run`'s) has the changes of its trace's `mode` column for events (at the
/// loop's 1 ms samples, the same in a run and its reference until they part).
pub fn read(dir: &Path) -> PathOf {
    let trace = common::csv_rows(&dir.join("trace.csv"));
    let (tt, a1, a2) = (col(&trace[0], "t"), col(&trace[0], "theta1"), col(&trace[0], "theta2"));
    let num = |r: &Vec<String>, i: usize| r[i].parse::<f64>().unwrap();
    let events = if dir.join("events.csv").is_file() {
        let events = common::csv_rows(&dir.join("events.csv"));
        let (t, kind) = (col(&events[0], "t"), col(&events[0], "kind"));
        events[1..].iter().map(|r| (num(r, t), r[kind].clone())).collect()
    } else {
        let mode = col(&trace[0], "mode");
        trace[2..]
            .iter()
            .zip(&trace[1..])
            .filter(|(r, before)| r[mode] != before[mode])
            .map(|(r, _)| (num(r, tt), format!("mode {}", r[mode])))
            .collect()
    };
    PathOf {
        events,
        seconds: trace[1..]
            .iter()
            .filter(|r| (num(r, tt) - num(r, tt).round()).abs() < 1e-9 && num(r, tt) >= 1.0)
            .map(|r| (num(r, tt).round() as i64, [num(r, a1), num(r, a2)]))
            .collect(),
    }
}

fn col(header: &[String], name: &str) -> usize {
    header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
}

/// The path horizon of `a` against `b`, s (infinite when they agree throughout), and
/// what ended it.
pub fn horizon(a: &PathOf, b: &PathOf) -> (f64, String) {
    let by_event = a
        .events
        .iter()
        .zip(&b.events)
        .find(|((ta, ka), (tb, kb))| ka != kb || (ta - tb).abs() > EVENT_TIME_S)
        .map(|((ta, ka), (tb, kb))| (ta.min(*tb), format!("{ka} at {ta:.9} s against {kb} at {tb:.9} s")));
    let by_angle = a.seconds.iter().find_map(|(s, x)| {
        let (_, y) = b.seconds.iter().find(|(t, _)| t == s)?;
        let counts = (x[0] - y[0]).abs().max((x[1] - y[1]).abs()) / COUNT;
        (counts > COUNT_FRACTION).then(|| (*s as f64, format!("{counts:.2e} counts at {s} s")))
    });
    match (by_event, by_angle) {
        (Some(e), Some(a)) => {
            if a.0 < e.0 {
                a
            } else {
                e
            }
        }
        (Some(x), None) | (None, Some(x)) => x,
        (None, None) => (f64::INFINITY, "none".into()),
    }
}

fn simulate(dir: &Path, name: &str, args: &[&str]) -> PathOf {
    let out = dir.join(name);
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).arg("simulate").args(args).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    read(&out)
}

/// One arm's path horizons (s): the predictability horizon (the two references), the
/// default's with a 1 ms trace and with 1 s samples, the default's path under the cap at
/// rtol 1e-4, and the uncapped ones at rtol 1e-4, 1e-9 and 1e-12.
struct Horizons {
    predictable: f64,
    dense: f64,
    sparse: f64,
    capped_loose: f64,
    uncapped: [f64; 3],
}

fn horizons(dir: &Path, name: &str, base: &[&str]) -> Horizons {
    let run = |what: &str, extra: &[&str]| {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        simulate(dir, &format!("{name}-{what}"), &args)
    };
    let reference = run("ref", &["--rtol", "1e-12", "--atol", "1e-14", "--max-step", "1e-4"]);
    let reference_2 = run("ref2", &["--rtol", "1e-13", "--atol", "1e-14", "--max-step", "7e-5"]);
    let against = |p: PathOf, what: &str| {
        let (h, why) = horizon(&p, &reference);
        println!("{name}, {what}: {h} s ({why})");
        h
    };
    let (predictable, why) = horizon(&reference, &reference_2);
    println!("{name}: predictability horizon {predictable} s ({why})");
    let uncapped = |rtol: &str, atol: &str| {
        against(run(&format!("nocap-{rtol}"), &["--max-step", "1e3", "--rtol", rtol, "--atol", atol]), &format!("uncapped rtol {rtol}"))
    };
    Horizons {
        predictable,
        dense: against(run("1ms", &[]), "default, 1 ms trace"),
        sparse: against(run("1s", &["--sample-dt", "1"]), "default, 1 s samples"),
        capped_loose: against(run("cap-1e-4", &["--rtol", "1e-4"]), "capped rtol 1e-4"),
        uncapped: [uncapped("1e-4", "1e-11"), uncapped("1e-9", "1e-11"), uncapped("1e-12", "1e-14")],
    }
}

/// On three arms (the paper's, bouncing from `x0a` at `v_belt` -0.5 for 10 s, whose
/// horizons lie before 6 s; issue 67's short, fast arm and a random one for 5 s, which
/// the references follow throughout): the path horizon at the default options is one
/// whether the trace is sampled every 1 ms or every 1 s; under the step cap `rtol` 1e-4
/// gives the default's path (the cap, not the tolerance, sets the steps); without the
/// cap (`--max-step 1e3`) `rtol` is a working knob: the horizon grows as it tightens
/// (1e-4, 1e-9, 1e-12) towards the references'. On the paper's arm the default lies
/// within 0.5 s of the predictability horizon and holds further than rtol 1e-9
/// uncapped (the cap's reason, measured); on the other two the default and the uncapped
/// tolerances from 1e-9 hold throughout (no cap needed there).
#[test]
fn the_path_horizon_is_the_samplings_and_rtol_moves_it_only_without_the_cap() {
    let dir = tempfile::tempdir().unwrap();
    let random_th2 = (1.6 - 40f64.to_radians().cos()).acos().to_degrees();
    let random_x0 = format!("--x0-deg=40,0,{random_th2},0");
    let short: Vec<&str> = common::SHORT_ARM
        .iter()
        .flat_map(|s| ["--set", *s])
        .chain([common::OTHER_ARM_X0, "--v-belt=-0.5", "--mu", "0.6", "--duration", "5"])
        .collect();
    let random: Vec<&str> = ["plant.m=0.2", "plant.l=0.3", "plant.sigma=0.004", "plant.k=0.8", "plant.h=0.48", "plant.alpha0=0.1"]
        .iter()
        .flat_map(|s| ["--set", *s])
        .chain([random_x0.as_str(), "--v-belt=-0.3", "--mu", "0.5", "--duration", "5"])
        .collect();
    for (name, base) in [("paper", vec!["--x0", "a", "--v-belt", "-0.5", "--duration", "10"]), ("short", short), ("random", random)] {
        let h = horizons(dir.path(), name, &base);
        assert_eq!(h.dense.to_bits(), h.sparse.to_bits(), "{name}: one path, two horizons: {} and {}", h.dense, h.sparse);
        assert_eq!(h.capped_loose.to_bits(), h.dense.to_bits(), "{name}: under the cap rtol 1e-4 is the default's path");
        let [h4, h9, h12] = h.uncapped;
        assert!(h4 < h9 && h9 <= h12, "{name}: rtol does not move the uncapped path: {h4}, {h9}, {h12}");
        if name == "paper" {
            assert!(h.predictable.is_finite() && h.predictable > 3.0, "{}", h.predictable);
            assert!(h.dense > h.predictable - 0.5, "the default departs at {} s, {} s predictable", h.dense, h.predictable);
            assert!(h9 < h.dense, "uncapped at the default rtol ({h9} s) holds as far as the cap ({} s): the cap is not needed", h.dense);
        } else {
            assert!(h.predictable.is_infinite() && h.dense.is_infinite() && h9.is_infinite(), "{name}: {} {} {h9}", h.predictable, h.dense);
        }
    }
}
