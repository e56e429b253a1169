//! End-to-end (issue 14): impacts that never create energy, the IWC rule as a
//! parameter, honest lift-off and Zeno counts, the belt at rest, and the validity
//! counters in every simulating command's output, through the binary's entry point.

use std::path::Path;

fn run(args: &[&str]) -> i32 {
    let mut full = vec!["sil-host"];
    full.extend_from_slice(args);
    sil_host::run(full)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

const VALIDITY_KEYS: [&str; 6] =
    ["energy_gains", "newton_fallbacks", "poisson_fallbacks", "cone_violations", "zeno_stops", "integrator_failures"];

fn assert_validity(v: &serde_json::Value, what: &str) {
    for k in VALIDITY_KEYS {
        assert!(v[k].is_u64(), "{what}: validity.{k} missing in {v}");
    }
}

/// The example: Newton with friction took an unforced arm on a belt at rest
/// from 0.60 J to 2.4 MJ. Now the impact falls back to the energetic law, counted,
/// and the energy never rises; `--strict` passes since nothing violates the model.
#[test]
fn the_energy_creating_newton_example_is_resolved_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("kane");
    let code = run(&[
        "simulate",
        "--x0-deg=-48.684496279623254,2.823333459779312,7.4835841707377675,-1.0371273914840837",
        "--mu",
        "0.7572516523185144",
        "--v-belt",
        "0.0",
        "--e-n",
        "0.5",
        "--impact-law",
        "newton",
        "--duration",
        "1",
        "--strict",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let s = json(&out.join("summary.json"));
    assert_validity(&s["validity"], "simulate");
    assert_eq!(s["validity"]["energy_gains"], 0);
    assert!(s["validity"]["newton_fallbacks"].as_u64().unwrap() >= 1);
    let mut rdr = csv::Reader::from_path(out.join("trace.csv")).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let col = headers.iter().position(|c| c == "energy").unwrap();
    let energies: Vec<f64> = rdr.records().map(|r| r.unwrap()[col].parse().unwrap()).collect();
    let e0 = energies[0];
    assert!(
        energies.iter().all(|&e| e <= e0 + 1e-9),
        "the energy rose above {e0} J: max {:?}",
        energies.iter().cloned().fold(f64::MIN, f64::max)
    );
    let events = std::fs::read_to_string(out.join("events.csv")).unwrap();
    assert!(events.contains("newton_fallback"), "the fallback is in the event log");
}

/// The failing belt-at-rest run completes.
#[test]
fn the_belt_at_rest_example_completes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rest");
    let code = run(&[
        "simulate",
        "--x0-deg=33.07292848745343,49.62172726136302,-16.333220434168876,-58.18208540238367",
        "--mu",
        "0.5913955784533411",
        "--v-belt",
        "0.0",
        "--e-n",
        "0.055244538844798186",
        "--impact-law",
        "newton",
        "--duration",
        "1",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let s = json(&out.join("summary.json"));
    assert_eq!(s["status"], "ok");
    assert_eq!(s["simulated_s"], 1.0);
    assert_eq!(s["validity"]["integrator_failures"], 0);
}

/// x0a starts with an impact without collision. Under the restitution rule the tip
/// is thrown off the belt at once; under the plastic rule it is left on the belt
/// with `v_n = 0`, so the first event after the IWC differs.
#[test]
fn the_iwc_rule_changes_what_follows_the_impact_without_collision() {
    let dir = tempfile::tempdir().unwrap();
    let mut first_mode = Vec::new();
    for rule in ["restitution", "plastic"] {
        let out = dir.path().join(rule);
        let code = run(&["simulate", "--x0", "a", "--duration", "0.2", "--iwc", rule, "--json", "--out", out.to_str().unwrap()]);
        assert_eq!(code, 0, "{rule}");
        let s = json(&out.join("summary.json"));
        assert_eq!(s["sim"]["iwc"], rule);
        assert_eq!(s["impacts_without_collision"], 1, "{rule}");
        let mut rdr = csv::Reader::from_path(out.join("events.csv")).unwrap();
        let headers = rdr.headers().unwrap().clone();
        let (kind, mode, v_n) = (
            headers.iter().position(|c| c == "kind").unwrap(),
            headers.iter().position(|c| c == "mode_after").unwrap(),
            headers.iter().position(|c| c == "v_n_after").unwrap(),
        );
        let iwc = rdr.records().map(|r| r.unwrap()).find(|r| &r[kind] == "impact_without_collision").unwrap();
        let v: f64 = iwc[v_n].parse().unwrap();
        if rule == "plastic" {
            assert!(v.abs() < 1e-9, "plastic: v_n = 0 after the IWC, got {v}");
        } else {
            assert!(v > 1e-4, "restitution: the tip leaves the belt, v_n = {v}");
        }
        first_mode.push(iwc[mode].to_string());
    }
    assert_eq!(first_mode[0], "flight");
    assert_ne!(first_mode[1], "flight");
    // A bad rule is a clear error naming the choices (exit 2).
    assert_eq!(run(&["simulate", "--iwc", "sticky", "--out", dir.path().join("bad").to_str().unwrap()]), 2);
}

/// The e_n = 0 sweep point: persistent bouncing that was labelled
/// `oscillating` with 0 lift-offs (departures after plastic touchdowns were not
/// counted) is `bouncing` with lift-offs, and almost no touchdown is a Zeno stop.
/// The sweep rows carry the validity columns and the IWC rule.
#[test]
fn plastic_touchdowns_count_as_lift_offs_in_a_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let code = run(&[
        "sweep",
        "--mu",
        "0.6,0.6",
        "--v-belt=-0.55,-0.55",
        "--ics",
        "a",
        "--e-n",
        "0",
        "--transient",
        "20",
        "--record",
        "20",
        "--strict",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let mut rdr = csv::Reader::from_path(out.join("sweep.csv")).unwrap();
    let headers = rdr.headers().unwrap().clone();
    for k in VALIDITY_KEYS.iter().chain(&["iwc"]) {
        assert!(headers.iter().any(|h| h == *k), "sweep.csv has {k}");
    }
    let row = rdr.records().next().unwrap().unwrap();
    let get = |k: &str| row[headers.iter().position(|h| h == k).unwrap()].to_string();
    assert_eq!(get("outcome"), "bouncing");
    let (lift_offs, touchdowns): (u64, u64) = (get("lift_offs").parse().unwrap(), get("touchdowns").parse().unwrap());
    assert!(touchdowns > 20 && lift_offs + 1 >= touchdowns, "lift-offs {lift_offs}, touchdowns {touchdowns}");
    let zeno: u64 = get("zeno_stops").parse().unwrap();
    assert!(zeno * 10 < touchdowns, "rounding residues are not Zeno stops: {zeno} of {touchdowns}");
    let s = json(&out.join("summary.json"));
    assert_validity(&s["results"]["validity"], "sweep");
    assert_eq!(s["results"]["invalid"].as_array().unwrap().len(), 0);
}

/// The IWC rule and the energetic law are sweep dimensions like the impact law.
#[test]
fn the_iwc_rule_and_the_energetic_law_are_sweep_dimensions() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let code = run(&[
        "sweep",
        "--mu",
        "0.6,0.6",
        "--v-belt=-0.6,-0.5",
        "--v-belt-step",
        "0.1",
        "--ics",
        "a",
        "--impact-law",
        "newton,energetic",
        "--iwc",
        "restitution,plastic",
        "--transient",
        "2",
        "--record",
        "2",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let s = json(&out.join("summary.json"));
    assert_eq!(s["results"]["runs"], 8, "2 rules x 2 laws x 2 speeds");
    let cases: Vec<(String, String)> = s["results"]["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["iwc"].as_str().unwrap().to_string(), c["impact_law"].as_str().unwrap().to_string()))
        .collect();
    assert_eq!(cases.len(), 4);
    assert!(cases.contains(&("plastic".into(), "energetic".into())));
    assert_eq!(s["spec"]["format"], analyses::sweep::FORMAT);
}

/// `run` and `zmax` summaries carry the validity counters too.
#[test]
fn closed_loop_summaries_carry_validity() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let code = run(&["run", "--in-process", "--duration", "0.5", "--strict", "--json", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert_validity(&json(&out.join("summary.json"))["validity"], "run");
    let out = dir.path().join("zmax");
    let code = run(&[
        "zmax",
        "--controller",
        "hybrid",
        "--x0",
        "d",
        "--ideal",
        "--duration",
        "3",
        "--bracket=0.0,0.05",
        "--tol",
        "0.02",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let s = json(&out.join("summary.json"));
    assert_validity(&s["validity"], "zmax");
    assert_eq!(s["base_scenario"]["plant"]["iwc"], "restitution");
    // zmax takes the IWC rule too, in one place only.
    let plastic = dir.path().join("zmax-plastic");
    let args = ["zmax", "--controller", "hybrid", "--x0", "d", "--ideal", "--duration", "3", "--bracket=0.0,0.05", "--tol", "0.02"];
    let mut a = args.to_vec();
    a.extend(["--iwc", "plastic", "--json", "--out", plastic.to_str().unwrap()]);
    assert_eq!(run(&a), 0);
    assert_eq!(json(&plastic.join("summary.json"))["base_scenario"]["plant"]["iwc"], "plastic");
    let both = dir.path().join("zmax-both");
    let mut a = args.to_vec();
    a.extend(["--iwc", "plastic", "--set", "plant.iwc=plastic", "--out", both.to_str().unwrap()]);
    assert_eq!(run(&a), 2);
    assert!(!both.exists());
    for t in s["trials"].as_array().unwrap() {
        assert_validity(&t["validity"], "zmax trial");
    }
}
