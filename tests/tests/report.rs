//! `sil-host report`: every experiment runs and lands in one page.

use std::process::Command;

#[test]
fn the_quick_report_runs_every_experiment_and_links_every_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let results = dir.path().join("results.md");
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host-e2e"))
        .args(["report", "--json", "--out"])
        .arg(&out)
        .arg("--results")
        .arg(&results)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let index: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(index["failed"], 0);
    let steps = index["steps"].as_array().unwrap();
    let ids: Vec<&str> = steps.iter().map(|s| s["id"].as_str().unwrap()).collect();
    for id in ["modes", "admissible", "sweep-open-loop", "sweep-hybrid", "poincare", "zmax", "pid-x0u", "hybrid-x0d"] {
        assert!(ids.contains(&id), "{id} missing from {ids:?}");
    }
    let page = std::fs::read_to_string(out.join("report.md")).unwrap();
    // Every figure written is shown, and every link points at a file that exists.
    let mut figures = 0;
    for s in steps {
        for f in s["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap()) {
            assert!(out.join(f).is_file(), "{f}");
            if f.ends_with(".svg") {
                figures += 1;
                assert!(page.contains(&format!("![{f}]({f})")), "{f} not shown");
            }
        }
    }
    assert!(figures >= 10, "{figures} figures");
    // The controller comparison of the paper: the hybrid law slides from x0d, PID from x0u lifts off.
    let summary = |id: &str| steps.iter().find(|s| s["id"] == id).unwrap()["result"].clone();
    assert_eq!(summary("hybrid-x0d")["lift_offs"], 0);
    assert!(summary("pid-x0u")["lift_offs"].as_u64().unwrap() >= 1);
    // Numbers keep their digits: the integrator's tolerances are not rounded to 0.
    assert!(page.contains("| rtol, atol | 1e-9, 1e-11 |"), "tolerances not shown as 1e-9, 1e-11");
    assert!(!page.contains("| rtol, atol | 0, 0 |"));
    // The results page: the same tables, stamped, without figures.
    let results = std::fs::read_to_string(&results).unwrap();
    assert!(results.contains("commit `") && results.contains("UTC") && results.contains("CPUs"), "no stamp");
    assert!(results.contains("| hybrid-x0d |") || results.contains(" hybrid-x0d |"), "no run comparison");
    assert!(!results.contains("!["), "figures in the results page");
}
