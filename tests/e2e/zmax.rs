//! End-to-end: `sil-host zmax` (Z_t,sliding, docs/model.md experiments 5 and 6).

fn run(args: &[&str]) -> i32 {
    let mut full = vec!["sil-host"];
    full.extend_from_slice(args);
    sil_host::run(full)
}

/// A coarse search of both hybrid cases from x0d: files, JSON, and the ideal
/// limit at the end of the admissible range (p = 0), reported in the same row.
#[test]
fn zmax_writes_its_table_figures_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let args = ["zmax", "--controller", "hybrid", "--x0", "d", "--tol", "0.005", "--duration", "3", "--settle-window", "0.5", "--out", out];
    assert_eq!(run(&args), 0);
    assert_eq!(run(&[&args[..], &["--ideal"]].concat()), 0);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap()).unwrap();
    let row = &summary["results"][0];
    assert_eq!((row["controller"].as_str(), row["x0"].as_str(), row["setting"].as_str()), (Some("hybrid"), Some("d"), Some("ideal")));
    assert_eq!(row["outcome"], "found");
    let (z, fail, end) =
        (row["z_t_sliding_m"].as_f64().unwrap(), row["first_failing_m"].as_f64().unwrap(), row["p_zero_end_m"].as_f64().unwrap());
    assert!(z <= end && end < fail + 1e-4 && fail - z <= 0.005, "{z} {fail} {end}");
    assert!(row["why_failing"].as_str().unwrap().contains("t = "), "{row}");
    let trials = summary["trials"].as_array().unwrap();
    assert_eq!(trials.len() as u64, row["trials"].as_u64().unwrap());
    let csv = std::fs::read_to_string(dir.path().join("zmax.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "header and one row");
    assert!(dir.path().join("zmax-hybrid-x0d-ideal.svg").exists() && dir.path().join("zmax-hybrid-x0d-sampled.svg").exists());
}

#[test]
fn zmax_bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    for bad in [
        &["zmax", "--tol", "0", "--out", o][..],
        &["zmax", "--bracket", "0.1,0.05", "--out", o],
        &["zmax", "--bracket", "0.0,0.5", "--out", o],
        &["zmax", "--duration", "1", "--out", o],
        &["zmax", "--settle-tol", "nan", "--out", o],
    ] {
        assert_eq!(run(bad), 2, "{bad:?}");
    }
    assert!(!out.exists());
}
