//! End-to-end: `sil-host run` (closed loop, in-process: the iceoryx2 transport is
//! in `sil_rig.rs`) and the shipped scenarios.

fn run(args: &[&str]) -> i32 {
    let mut full = vec!["sil-host"];
    full.extend_from_slice(args);
    sil_host::run(full)
}

#[test]
fn shipped_scenarios_parse_and_the_default_run_tracks() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        let s = rig::scenario::Scenario::from_toml(&std::fs::read_to_string(&path).unwrap()).unwrap();
        names.push(s.name);
    }
    names.sort();
    assert_eq!(names, ["hybrid-x0d", "hybrid-x0d", "hybrid-x0u", "pid-x0d", "pid-x0u"]);
    let dir = tempfile::tempdir().unwrap();
    assert_eq!(run(&["run", "--in-process", "--duration", "3", "--out", dir.path().to_str().unwrap()]), 0);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["transport"], "in-process");
    assert_eq!(summary["periods"], 3000);
    assert_eq!(summary["lift_offs"], 0);
    assert!(summary["rms_tracking_error_m"].as_f64().unwrap() < 1e-3);
    assert!((summary["final_z_t_m"].as_f64().unwrap() - 0.10).abs() < 2e-3);
}

#[test]
fn a_bad_scenario_exits_2_naming_the_key_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, rig::scenario::DEFAULT_TOML.replace("delta_s = 0.0002", "delta_s = 0.5")).unwrap();
    let out = dir.path().join("out");
    assert_eq!(run(&["run", "--scenario", bad.to_str().unwrap(), "--out", out.to_str().unwrap()]), 2);
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().count() == 0);
    let err = rig::scenario::Scenario::from_toml(&std::fs::read_to_string(&bad).unwrap()).unwrap_err().to_string();
    assert!(err.contains("timing.delta_s") && err.contains("0.5"), "{err}");
    assert_eq!(run(&["run", "--target-zt", "nan", "--out", out.to_str().unwrap()]), 2);
}

/// Issue 66 (5): `--duration` acts before the scenario's check, as `--set
/// timing.duration_s` does: a fault a file places past its own 10 s is reached
/// by `--duration 15` (it was refused, exit 2), and still refused without it.
#[test]
fn duration_reaches_a_fault_past_the_files_own_end() {
    let dir = tempfile::tempdir().unwrap();
    let late = dir.path().join("late.toml");
    let fault = "\n[[faults]]\nkind = \"nan_sensor\"\nsignal = \"belt\"\nat_s = 12.0\nduration_s = 0.001\n";
    std::fs::write(&late, format!("{}{fault}", rig::scenario::DEFAULT_TOML)).unwrap();
    let scenario = late.to_str().unwrap();
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    assert_eq!(run(&["run", "--in-process", "--scenario", scenario, "--out", &out("refused")]), 2);
    let (by_flag, by_set) = (out("flag"), out("set"));
    assert_eq!(run(&["run", "--in-process", "--scenario", scenario, "--duration", "15", "--no-page", "--out", &by_flag]), 0);
    assert_eq!(run(&["run", "--in-process", "--scenario", scenario, "--set", "timing.duration_s=15", "--no-page", "--out", &by_set]), 0);
    let summary = |o: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(std::path::Path::new(o).join("summary.json")).unwrap()).unwrap()
    };
    let (f, s) = (summary(&by_flag), summary(&by_set));
    assert_eq!(f["periods"], 15_000);
    assert_eq!(f["scenario_used"], s["scenario_used"], "the flag and the --set run the same scenario");
    assert_eq!(f["scenario_used"]["faults"][0]["at_s"], 12.0);
    let trace = |o: &str| std::fs::read(std::path::Path::new(o).join("trace.csv")).unwrap();
    assert!(trace(&by_flag) == trace(&by_set), "the same trace");
}
