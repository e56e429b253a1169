//! The accuracy contract (docs/architecture.md "The accuracy contract"): a
//! numerical change may move the last bits of the outputs only if every case stays
//! as close to its tight-tolerance reference as the code recorded in
//! `tests/accuracy/contract.json` did (no worse than twice, or [`compare::FLOOR`]
//! tolerances) and within a thousandth of the quantum of the sensor that measures
//! each column ([`compare::quantum`]), with the same events, and if the
//! paper-level results do not move (Table II to 5 decimals, `Z_t,sliding` within
//! 0.1 mm, the sweep's outcomes). The rule is the owner's decision of issue 43.
//!
//! Each case runs through the command line at the default tolerances (rtol 1e-9,
//! atol 1e-11) and as its reference at rtol 1e-12, atol 1e-14, with steps of at
//! most 0.1 ms (events are located to rounding in both: plant/src/segment/locate.rs). The
//! cap matters: where the samples (simulate's 1 ms trace) or the zero-order hold
//! (a closed loop's 0.2 and 0.8 ms segments) set the steps, a reference at a tighter
//! tolerance alone takes the very same steps, and would measure the run against
//! itself. The reference is recomputed by the same binary.
//!
//! `ACCURACY=record cargo test --release -p sil-host --features full --test e2e -- accuracy::` records the
//! contract again: only with a change that is meant to move it, said in the commit.

use std::{collections::BTreeMap, path::Path, process::Command};

use serde_json::{Value, json};

use crate::common;
mod compare;
mod path;

use compare::{Comparison, Table, breaches, kinds_before, quantum_breaches};

/// The reference's tolerances `(rtol, atol, max_step)`: three decades below the
/// default, and steps of at most 0.1 ms (none of the steps the samples or the
/// zero-order hold impose on the measured run: those are 0.2 ms or longer).
const REFERENCE_TOL: (&str, &str, &str) = ("1e-12", "1e-14", "1e-4");
/// The second reference's (a decade tighter again, steps of at most 70 us:
/// another step sequence), for the predictability horizon.
const REFERENCE_2_TOL: (&str, &str, &str) = ("1e-13", "1e-14", "7e-5");

/// `simulate` of an arm other than the paper's for 5 s at `mu` 0.6, `v_belt`
/// -0.5, from rest with its tip on the belt (the same joint angles for both arms:
/// `h / l` is the same).
fn other_arm(assignments: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = vec!["simulate".into()];
    for a in assignments {
        args.extend(["--set".to_string(), a.to_string()]);
    }
    args.extend([common::OTHER_ARM_X0, "--v-belt=-0.5", "--mu", "0.6", "--duration", "5"].map(String::from));
    args
}

/// A case: its name, the command line (after `sil-host`), and how to ask it for the
/// reference tolerances.
struct Case {
    name: &'static str,
    args: Vec<String>,
    /// How to ask for a reference's `(rtol, atol, max_step)`.
    tolerance: fn((&str, &str, &str)) -> Vec<String>,
    /// Arguments of the measured run only (empty: the default tolerances).
    measured: Vec<String>,
}

fn cases() -> Vec<Case> {
    let root = common::workspace();
    let strings = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let simulate_ref: fn((&str, &str, &str)) -> Vec<String> =
        |(r, a, h)| vec!["--rtol".into(), r.into(), "--atol".into(), a.into(), "--max-step".into(), h.into()];
    let run_ref: fn((&str, &str, &str)) -> Vec<String> = |(r, a, h)| {
        vec![
            "--set".into(),
            format!("plant.rtol={r}"),
            "--set".into(),
            format!("plant.atol={a}"),
            "--set".into(),
            format!("plant.max_step={h}"),
        ]
    };
    let mut cases = vec![
        Case { name: "simulate-x0a", args: strings(&["simulate", "--x0", "a"]), tolerance: simulate_ref, measured: vec![] },
        Case { name: "simulate-x0d", args: strings(&["simulate", "--x0", "d"]), tolerance: simulate_ref, measured: vec![] },
        // The bench's case (issue 16): 300 s of open-loop bouncing, a 1 ms trace.
        Case {
            name: "simulate-x0a-300s",
            args: strings(&["simulate", "--x0", "a", "--v-belt", "-0.5", "--duration", "300"]),
            tolerance: simulate_ref,
            measured: vec![],
        },
        // The same with 1 s samples: here the tolerance, not the samples, sets the steps.
        Case {
            name: "simulate-x0a-300s-1s-samples",
            args: strings(&["simulate", "--x0", "a", "--v-belt", "-0.5", "--duration", "300", "--sample-dt", "1"]),
            tolerance: simulate_ref,
            measured: vec![],
        },
        // Issue 67: the steps follow the arm's dynamics (plant::time_scale): a short,
        // light arm nine times faster than the paper's (535 rad/s, steps of at most
        // 0.22 ms; the paper's 2 ms left the contract at 0.34 s) and a long, heavy one
        // four times slower (15.7 rad/s, 7.7 ms), each bouncing then sliding.
        Case { name: "simulate-short-arm", args: other_arm(&common::SHORT_ARM), tolerance: simulate_ref, measured: vec![] },
        Case { name: "simulate-long-arm", args: other_arm(&common::LONG_ARM), tolerance: simulate_ref, measured: vec![] },
    ];
    for (name, s) in
        [("run-pid-x0d", "pid-x0d"), ("run-pid-x0u", "pid-x0u"), ("run-hybrid-x0d", "hybrid-x0d"), ("run-hybrid-x0u", "hybrid-x0u")]
    {
        let scenario = root.join("scenarios").join(format!("{s}.toml")).display().to_string();
        cases.push(Case {
            name,
            args: vec!["run".into(), "--in-process".into(), "--scenario".into(), scenario],
            tolerance: run_ref,
            measured: vec![],
        });
    }
    cases
}

/// Runs `sil-host args` into `out`.
fn sil_host(args: &[String], out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).arg("--out").arg(out).output().unwrap();
    assert!(o.status.success(), "{args:?} failed:\n{}", String::from_utf8_lossy(&o.stderr));
}

fn read_table(path: &Path) -> Option<Table> {
    std::fs::read_to_string(path).ok().map(|t| Table::parse(&t))
}

/// Run-length form of a kind sequence: `[["touchdown", 3], ...]`.
fn run_lengths(kinds: &[String]) -> Value {
    let mut out: Vec<(String, usize)> = Vec::new();
    for k in kinds {
        match out.last_mut() {
            Some((last, n)) if last == k => *n += 1,
            _ => out.push((k.clone(), 1)),
        }
    }
    json!(out)
}

fn envelope_json(env: &BTreeMap<String, Vec<f64>>) -> Value {
    // Three significant digits: the rule compares within a factor of 2.
    let round = |v: f64| if v == 0.0 { 0.0 } else { format!("{v:.3e}").parse::<f64>().unwrap() };
    Value::Object(env.iter().map(|(k, v)| (k.clone(), json!(v.iter().map(|&x| round(x)).collect::<Vec<_>>()))).collect())
}

fn envelope_of(v: &Value) -> BTreeMap<String, Vec<f64>> {
    v.as_object()
        .map(|m| m.iter().map(|(k, v)| (k.clone(), v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect())).collect())
        .unwrap_or_default()
}

/// One case measured now: its trace's and events' comparisons with the reference,
/// and where the two references depart from each other.
struct Measured {
    trace: Comparison,
    events: Option<(Table, Table)>,
    /// The predictability horizon, s: the two references' departure (see `compare`).
    predictable_s: f64,
    /// The path horizon against the reference and the two references' against each
    /// other, s (issue 81, [`path`]: the events and the angles at the whole seconds, the
    /// same whatever the sampling; infinite where they never part).
    path_horizon_s: f64,
    path_predictable_s: f64,
}

fn measure(case: &Case, dir: &Path) -> Measured {
    let d = dir.join(case.name);
    let (default_dir, reference_dir, reference_2_dir) = (d.join("default"), d.join("reference"), d.join("reference-2"));
    let with = |extra: Vec<String>| case.args.iter().cloned().chain(extra).collect::<Vec<_>>();
    sil_host(&with(case.measured.clone()), &default_dir);
    sil_host(&with((case.tolerance)(REFERENCE_TOL)), &reference_dir);
    sil_host(&with((case.tolerance)(REFERENCE_2_TOL)), &reference_2_dir);
    let reference = read_table(&reference_dir.join("trace.csv")).expect("reference trace.csv");
    let trace = Comparison::of(&read_table(&default_dir.join("trace.csv")).expect("trace.csv"), &reference);
    let references = Comparison::of(&reference, &read_table(&reference_2_dir.join("trace.csv")).expect("second reference trace.csv"));
    let predictable_s = if references.departed.is_some() { references.horizon_s } else { f64::INFINITY };
    let events = read_table(&default_dir.join("events.csv")).zip(read_table(&reference_dir.join("events.csv")));
    let (run, reference, reference_2) = (path::read(&default_dir), path::read(&reference_dir), path::read(&reference_2_dir));
    let (path_horizon_s, path_predictable_s) = (path::horizon(&run, &reference).0, path::horizon(&reference, &reference_2).0);
    Measured { trace, events, predictable_s, path_horizon_s, path_predictable_s }
}

/// The case as recorded: the horizon, the envelopes, the events' kinds before it.
fn record_case(m: &Measured) -> Value {
    let h = m.trace.horizon_s;
    let mut v = json!({
        "horizon_s": h,
        "departed": m.trace.departed,
        "predictable_s": if m.predictable_s.is_finite() { json!(m.predictable_s) } else { Value::Null },
        "trace": envelope_json(&m.trace.envelope(h)),
        "trace_absolute": envelope_json(&m.trace.absolute_envelope(h)),
        "path_horizon_s": finite_or_null(m.path_horizon_s),
        "path_predictable_s": finite_or_null(m.path_predictable_s),
    });
    if let Some((events, reference)) = &m.events {
        v["events"] = envelope_json(&Comparison::of(events, reference).envelope(h));
        v["event_kinds"] = run_lengths(&kinds_before(reference, h));
    }
    v
}

fn finite_or_null(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// Where the case breaks its recorded contract: on the recorded horizon, cut at
/// today's predictability horizon (the references' departure) when that is earlier;
/// and on the path (issue 81): the run follows its reference's path (the events'
/// kinds and times to 1 us, the angles at the whole seconds to a thousandth of a count)
/// at least as far as recorded, or as far as today's two references agree.
fn check_case(name: &str, m: &Measured, recorded: &Value) -> Vec<String> {
    let mut path_wrong = Vec::new();
    let recorded_path = recorded["path_horizon_s"].as_f64().unwrap_or(f64::INFINITY);
    let owed = recorded_path.min(m.path_predictable_s);
    if m.path_horizon_s < owed - 1e-9 {
        path_wrong.push(format!(
            "{name}: the path leaves its reference at {} s, before the recorded {recorded_path} s and the references' {} s",
            m.path_horizon_s, m.path_predictable_s
        ));
    }
    let h = recorded["horizon_s"].as_f64().expect("horizon_s");
    let judged = m.predictable_s.min(h);
    // The checkpoints at or before the judged span.
    let checkpoints =
        (1..=compare::CHECKPOINTS).take_while(|k| h * *k as f64 / compare::CHECKPOINTS as f64 <= judged * (1.0 + 1e-12)).count();
    let mut wrong: Vec<String> = breaches(&envelope_of(&recorded["trace"]), &m.trace.envelope(h), checkpoints)
        .into_iter()
        .map(|b| format!("{name}: trace.csv {b}"))
        .collect();
    // The sensors' bound holds before the horizon: the horizon's own sample is where
    // the run has departed (by 1000 tolerances, more than a thousandth of the
    // encoders' quantum), and with 1 s samples it is where the references part too.
    let before_horizon = h * (1.0 - 1e-9);
    wrong.extend(
        quantum_breaches(&m.trace.absolute_envelope(before_horizon), checkpoints).into_iter().map(|b| format!("{name}: trace.csv {b}")),
    );
    if let Some((events, reference)) = &m.events {
        let now = Comparison::of(events, reference).envelope(h);
        wrong.extend(breaches(&envelope_of(&recorded["events"]), &now, checkpoints).into_iter().map(|b| format!("{name}: events.csv {b}")));
        let (kinds, reference_kinds) = (kinds_before(events, judged), kinds_before(reference, judged));
        if kinds != reference_kinds {
            wrong.push(format!(
                "{name}: the events before {judged} s differ from the reference's ({} against {})",
                kinds.len(),
                reference_kinds.len()
            ));
        }
        // The reference's kinds start as recorded (all of them when judged to the recorded horizon).
        let recorded_kinds = kinds_of(&recorded["event_kinds"]);
        let prefix = recorded_kinds.len() >= reference_kinds.len() && recorded_kinds[..reference_kinds.len()] == reference_kinds[..];
        if !prefix || (judged >= h && reference_kinds.len() != recorded_kinds.len()) {
            wrong.push(format!("{name}: the reference's events before {judged} s are not the recorded ones"));
        }
    }
    wrong.extend(path_wrong);
    wrong
}

/// The kinds of a run-length form, expanded.
fn kinds_of(v: &Value) -> Vec<String> {
    v.as_array()
        .map(|a| {
            a.iter()
                .flat_map(|p| std::iter::repeat_n(p[0].as_str().unwrap_or("").to_string(), p[1].as_u64().unwrap_or(0) as usize))
                .collect()
        })
        .unwrap_or_default()
}

/// The paper-level results: Table II to 5 decimals, `Z_t,sliding` of the eight
/// cases, the small sweep's outcomes and the critical `mu` on its grid.
fn paper_level(dir: &Path) -> Value {
    let read = |p: &Path| -> Value { serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap() };
    let admissible = dir.join("admissible");
    sil_host(&["admissible".into()], &admissible);
    let a = read(&admissible.join("admissible.json"));
    let round5 = |v: &Value| -> Value {
        json!(
            v.as_array()
                .unwrap()
                .iter()
                .map(|iv| iv.as_array().unwrap().iter().map(|x| format!("{:.5}", x.as_f64().unwrap())).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        )
    };
    let table_ii = json!({
        "elbow_up": round5(&a["z_r_dot_positive"]["elbow_up"]),
        "elbow_down": round5(&a["z_r_dot_positive"]["elbow_down"]),
    });
    let zmax = dir.join("zmax");
    sil_host(&["zmax".into(), "--all".into()], &zmax);
    let z = read(&zmax.join("summary.json"));
    let z_t_sliding: serde_json::Map<String, Value> = z["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let key = format!("{}-x0{}-{}", r["controller"].as_str().unwrap(), r["x0"].as_str().unwrap(), r["setting"].as_str().unwrap());
            (key, json!({"outcome": r["outcome"], "z_t_sliding_m": r["z_t_sliding_m"]}))
        })
        .collect();
    let sweep = dir.join("sweep");
    let sweep_args = ["sweep", "--mu", "0.1,1", "--mu-step", "0.1", "--v-belt", "-1,-0.1", "--v-belt-step", "0.1"];
    sil_host(&sweep_args.iter().map(|s| s.to_string()).collect::<Vec<_>>(), &sweep);
    let runs = read_table(&sweep.join("runs.csv")).expect("runs.csv");
    let col = |n: &str| runs.column(n).unwrap_or_else(|| panic!("runs.csv has {n}"));
    let (mu, v, ic, outcome) = (col("mu"), col("v_belt"), col("ic"), col("outcome"));
    let mut outcomes: Vec<String> = runs.rows.iter().map(|r| format!("{} {} {} {}", r[ic], r[mu], r[v], r[outcome])).collect();
    outcomes.sort();
    let critical_mu = |x0: &str| -> Value {
        let bouncing = runs
            .rows
            .iter()
            .filter(|r| r[ic] == x0 && r[col("theta1_dot_over_threshold")] == "true")
            .filter_map(|r| r[mu].parse::<f64>().ok());
        bouncing.fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x)))).map_or(Value::Null, |m| json!(m))
    };
    json!({
        "table_ii_m": table_ii,
        "z_t_sliding": z_t_sliding,
        "sweep": {"args": sweep_args, "critical_mu_x0a": critical_mu("x0a"), "critical_mu_x0d": critical_mu("x0d"), "outcomes": outcomes},
    })
}

/// Where the paper-level results moved from the recorded ones.
fn check_paper(now: &Value, recorded: &Value) -> Vec<String> {
    let mut wrong = Vec::new();
    if now["table_ii_m"] != recorded["table_ii_m"] {
        wrong.push(format!("Table II moved: {} (recorded {})", now["table_ii_m"], recorded["table_ii_m"]));
    }
    for (key, r) in recorded["z_t_sliding"].as_object().unwrap() {
        let n = &now["z_t_sliding"][key];
        let (a, b) = (n["z_t_sliding_m"].as_f64(), r["z_t_sliding_m"].as_f64());
        let close = match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-4,
            (None, None) => true,
            _ => false,
        };
        if n["outcome"] != r["outcome"] || !close {
            wrong.push(format!("Z_t,sliding {key}: {n} (recorded {r}; within 0.1 mm)"));
        }
    }
    for key in ["critical_mu_x0a", "critical_mu_x0d"] {
        if now["sweep"][key] != recorded["sweep"][key] {
            wrong.push(format!("{key} on the sweep's grid: {} (recorded {})", now["sweep"][key], recorded["sweep"][key]));
        }
    }
    let (a, b) = (now["sweep"]["outcomes"].as_array().unwrap(), recorded["sweep"]["outcomes"].as_array().unwrap());
    let flipped: Vec<String> = a.iter().zip(b).filter(|(x, y)| x != y).map(|(x, y)| format!("{y} -> {x}")).collect();
    if !flipped.is_empty() || a.len() != b.len() {
        wrong.push(format!("sweep outcomes moved ({} of {}): {}", flipped.len(), b.len(), flipped.join("; ")));
    }
    wrong
}

#[test]
fn every_case_stays_as_close_to_its_reference_as_recorded_and_the_paper_results_hold() {
    let root = common::workspace();
    let dir = root.join("target/accuracy");
    let _ = std::fs::remove_dir_all(&dir);
    let measured: Vec<(&'static str, Measured)> = cases().iter().map(|c| (c.name, measure(c, &dir))).collect();
    let paper = paper_level(&dir);
    let path = root.join("tests/accuracy/contract.json");
    if std::env::var("ACCURACY").as_deref() == Ok("record") {
        let cases: serde_json::Map<String, Value> = measured.iter().map(|(n, m)| (n.to_string(), record_case(m))).collect();
        let contract = json!({
            "rule": "(a) every step passes the integrator's error test at the run's tolerances and no step is forced past a discontinuity of the right-hand side (the hold's switch, an event); (b) per case and column, up to each of 20 checkpoints over [0, horizon_s] cut at the references' predictability horizon, the scaled error |x - x_ref| / (1e-11 + 1e-9 |x_ref|) stays below max(2 x recorded, 1000) and, for a column a sensor measures, the error stays below a thousandth of that sensor's quantum (theta1, theta2: 2 pi / 2^14 rad; f_t, f_n: 25/2048 N; trace_absolute records it); (c) the events' kinds before horizon_s equal the reference's and the recorded ones, and the paper-level results equal (Table II to 5 decimals, Z_t,sliding within 0.1 mm with the same outcome, the sweep's outcomes and critical mu); (d) the path (issue 81: the events' kinds and times to 1 us, the angles at the whole seconds to 1e-3 of an encoder count, whatever the sampling) follows the reference's at least to min(path_horizon_s, today's path_predictable_s)",
            "reference": {"rtol": REFERENCE_TOL.0, "atol": REFERENCE_TOL.1, "max_step": REFERENCE_TOL.2},
            "second_reference": {"rtol": REFERENCE_2_TOL.0, "atol": REFERENCE_2_TOL.1, "max_step": REFERENCE_2_TOL.2},
            "cases": cases,
            "paper": paper,
        });
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, serde_json::to_string_pretty(&contract).unwrap() + "\n").unwrap();
        return;
    }
    let recorded: Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("tests/accuracy/contract.json (ACCURACY=record records it)")).unwrap();
    let mut wrong = Vec::new();
    for (name, m) in &measured {
        // A reference that is the measured run itself (the same steps) measures nothing.
        if m.trace.envelope(m.trace.horizon_s).values().all(|e| e.iter().all(|&x| x == 0.0)) {
            wrong.push(format!("{name}: the trace equals its reference to the bit: the reference takes the run's own steps"));
        }
        match recorded["cases"].get(*name) {
            Some(r) => wrong.extend(check_case(name, m, r)),
            None => wrong.push(format!("{name}: not in the contract")),
        }
    }
    wrong.extend(check_paper(&paper, &recorded["paper"]));
    assert!(wrong.is_empty(), "the accuracy contract is broken (outputs in {}):\n{}", dir.display(), wrong.join("\n"));
    // Kept only for a broken contract (0.25 GB, the 300 s trace most of it).
    let _ = std::fs::remove_dir_all(&dir);
}

/// The contract can fail. A looser tolerance no longer shows it (issue 53): with
/// every open-loop step capped at 2 ms, DOP853's local error is far below even
/// rtol 1e-4 in flight, so the cap, not the tolerance, sets the steps, and a run
/// at rtol 1e-4 keeps the contract (measured). A model 1e-7 off (the arm's mass
/// 0.12 kg -> 0.120000012 kg, an error a hundred tolerances would leave after a
/// second) breaks it on the bouncing case.
#[test]
fn a_run_1e_7_off_breaks_the_contract() {
    let root = common::workspace();
    let recorded: Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("tests/accuracy/contract.json")).expect("contract.json")).unwrap();
    let case = cases().into_iter().find(|c| c.name == "simulate-x0a").unwrap();
    let loose = Case { measured: ["--set", "plant.m=0.120000012"].map(String::from).to_vec(), ..case };
    let dir = root.join("target/accuracy-loose");
    let m = measure(&loose, &dir);
    let wrong = check_case(loose.name, &m, &recorded["cases"][loose.name]);
    assert!(!wrong.is_empty(), "a model 1e-7 off kept the contract (outputs in {})", dir.display());
    // The path's check sees it too (issue 81): its touchdowns move by more than 1 us
    // before the recorded path horizon.
    assert!(wrong.iter().any(|w| w.contains("the path leaves its reference")), "{wrong:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
