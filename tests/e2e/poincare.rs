//! `sil-host poincare` end to end on a few belt speeds (docs/model.md experiment 4):
//! the classes, the files and their agreement, exit codes.

use std::process::Command;

fn sil_host() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sil-host"))
}

/// At mu = 0.6 from x0a: steady sliding at -0.2 m/s, the period-2 orbit at
/// -0.37 m/s (after the period-doubling from period 3 at about -0.31 m/s going
/// down), chaos at -0.6 m/s (largest exponent about 0.5 per crossing).
#[test]
fn three_belt_speeds_give_equilibrium_period_two_and_chaos() {
    let dir = tempfile::tempdir().unwrap();
    let out =
        sil_host().args(["poincare", "--v-belt", "-0.6,-0.2", "--v-step", "0.23", "--json", "--out"]).arg(dir.path()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["grid_points"], 3);
    assert_eq!(summary["initial_condition"]["name"], "x0a");
    assert_eq!(summary["initial_condition"]["projection"]["projected"], true);

    let classes: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("classes.json")).unwrap()).unwrap();
    let classes = classes.as_array().unwrap();
    let v: Vec<f64> = classes.iter().map(|c| c["v_belt"].as_f64().unwrap()).collect();
    assert_eq!(v, [-0.6, -0.37, -0.2]);
    let (chaos, p2, eq) = (&classes[0], &classes[1], &classes[2]);
    assert_eq!(chaos["class"], "chaotic", "{chaos}");
    assert!(chaos["lyapunov"]["per_iteration"].as_f64().unwrap() > 0.2, "{chaos}");
    assert!(chaos["distinct_points"].as_u64().unwrap() > 100);
    assert_eq!(p2["class"], "periodic");
    assert_eq!(p2["period"], 2);
    assert!(p2["lyapunov"]["per_iteration"].as_f64().unwrap() < -0.1, "{p2}");
    assert_eq!(eq["class"], "equilibrium");
    assert_eq!(eq["final_mode"], "sliding");

    // section.csv: every point on the section, in the record window, and the
    // period-2 speed has exactly two distinct theta1 there.
    let mut rdr = csv::Reader::from_path(dir.path().join("section.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = rdr.records().map(Result::unwrap).collect();
    assert_eq!(rows.len() as u64, summary["section_points"].as_u64().unwrap());
    let mut p2_theta1: Vec<f64> = Vec::new();
    for r in &rows {
        let (v_belt, t, theta1_dot, kind) =
            (r[0].parse::<f64>().unwrap(), r[1].parse::<f64>().unwrap(), r[4].parse::<f64>().unwrap(), &r[7]);
        assert!((250.0..=300.0).contains(&t));
        if kind == "flow" {
            assert!(theta1_dot.abs() < 1e-9, "{r:?}");
        } else {
            assert!(theta1_dot >= 0.0);
        }
        if v_belt == -0.37 {
            p2_theta1.push(r[2].parse().unwrap());
        }
    }
    p2_theta1.sort_by(f64::total_cmp);
    p2_theta1.dedup_by(|a, b| (*a - *b).abs() < 1e-4);
    assert_eq!(p2_theta1.len(), 2, "{p2_theta1:?}");
    for f in ["classes.csv", "bifurcation.svg", "lyapunov.svg", "summary.json"] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
}

#[test]
fn bad_ranges_exit_with_2_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["poincare", "--v-belt", "-0.3,-0.5"][..],
        &["poincare", "--v-step", "0"],
        &["poincare", "--record", "-1"],
        &["poincare", "--mu", "NaN"],
        &["poincare", "--x0-deg", "0,0,0,0"],
    ] {
        let out = sil_host().args(args).arg("--out").arg(dir.path()).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written");
}

/// Issue 52, 8: Ctrl-C on `poincare` printed nothing and left the folder's owner
/// file. It now stops once the belt speeds under way finish, says so, writes
/// nothing, removes the owner file, and exits 130.
#[test]
fn an_interrupted_poincare_says_so_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p");
    let child = sil_host()
        .args(["poincare", "--v-belt=-0.9,-0.3", "--v-step", "0.002", "--threads", "1", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !out.join(".sil-host.owner").exists() {
        assert!(started.elapsed() < std::time::Duration::from_secs(30), "poincare never started");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted: poincare stopped after") && err.contains("of 301 belt speeds"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(left.is_empty(), "nothing written, no owner file left: {left:?}");
}
