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
