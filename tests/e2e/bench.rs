//! End-to-end: `sil-host bench` (issue 16). Every figure names its target; what
//! cannot be measured is skipped with the command that fixes it; the image sizes
//! agree with `scripts/budgets.py` (an independent reader of the same ELF); bad
//! input exits 2. Speeds themselves are measured, not asserted (docs/rig.md).

use std::{path::Path, process::Command};

/// Runs the binary: exit code, stdout, stderr.
fn bench(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).arg("bench").args(args).output().unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn figures(stdout: &str) -> Vec<serde_json::Value> {
    serde_json::from_str::<serde_json::Value>(stdout).unwrap().as_array().unwrap().clone()
}

#[test]
fn missing_images_are_skipped_with_the_command_that_builds_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let (code, out, err) = bench(&["--only", "flash,step", "--target-dir", d, "--json", "--check"]);
    assert_eq!(code, 0, "skipped figures do not fail --check: {err}");
    let f = figures(&out);
    let ids: Vec<_> = f.iter().map(|f| f["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["flash_pil_mcu", "flash_pil_release", "control_step_hybrid", "control_step_pid"]);
    for f in &f {
        assert_eq!(f["status"], "skipped", "{f}");
        assert!(f["value"].is_null());
        let why = f["reason"].as_str().unwrap();
        assert!(why.contains("cargo build"), "{why}");
    }
}

#[test]
fn unknown_groups_and_bad_numbers_exit_2_naming_them() {
    let (code, _, err) = bench(&["--only", "flash,warp"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("warp") && err.contains("in-process") && err.contains("sweep"), "{err}");
    for (args, needle) in [
        (&["--repeat", "0"][..], "--repeat"),
        (&["--duration", "nan"][..], "--duration"),
        (&["--pil-s", "0"][..], "--pil-s"),
        (&["--only", "realtime"][..], "--realtime-s"),
    ] {
        let (code, _, err) = bench(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn the_loop_and_simulate_figures_are_measured_against_their_targets() {
    let (code, out, err) = bench(&["--only", "in-process,simulate", "--repeat", "2", "--duration", "0.5", "--json"]);
    assert_eq!(code, 0, "{err}");
    let f = figures(&out);
    assert_eq!(f.len(), 5);
    let (loop_, sim, arrow, sparse, ratio) = (&f[0], &f[1], &f[2], &f[3], &f[4]);
    assert_eq!(
        (loop_["id"].as_str(), loop_["unit"].as_str(), loop_["goal"].as_str()),
        (Some("in_process"), Some("periods/s"), Some("at_least"))
    );
    assert_eq!(loop_["target"], 1_000_000.0);
    let runs: Vec<f64> = loop_["runs"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(runs.len(), 2);
    assert!(runs.iter().all(|r| *r > 1_000.0), "{runs:?}");
    let v = loop_["value"].as_f64().unwrap();
    assert!(runs.contains(&v), "the value is one of the runs (the median): {v} of {runs:?}");
    let met = v >= 1_000_000.0;
    assert_eq!(loop_["status"], if met { "met" } else { "not_met" });
    assert_eq!((sim["id"].as_str(), sim["unit"].as_str(), sim["target"].as_f64()), (Some("simulate_300s"), Some("s"), Some(0.1)));
    assert!(sim["value"].as_f64().unwrap() > 0.0);
    assert_eq!(
        (arrow["id"].as_str(), arrow["unit"].as_str(), arrow["target"].as_f64()),
        (Some("simulate_300s_arrow"), Some("s"), Some(0.05))
    );
    assert!(arrow["value"].as_f64().unwrap() > 0.0);
    assert!(arrow["detail"].to_string().contains("trace.arrow"), "{}", arrow["detail"]);
    assert_eq!(
        (sparse["id"].as_str(), sparse["unit"].as_str(), sparse["target"].as_f64()),
        (Some("simulate_300s_sparse"), Some("s"), Some(0.02))
    );
    assert!(sparse["value"].as_f64().unwrap() > 0.0);
    // Issue 81: the 1 s samples' cost over the 1 ms trace's, the two medians' ratio.
    assert_eq!(
        (ratio["id"].as_str(), ratio["unit"].as_str(), ratio["target"].as_f64()),
        (Some("simulate_300s_sparse_ratio"), Some("ratio"), Some(0.25))
    );
    let r = ratio["value"].as_f64().unwrap();
    assert_eq!(r.to_bits(), (sparse["value"].as_f64().unwrap() / sim["value"].as_f64().unwrap()).to_bits(), "{r}");
    assert_eq!(ratio["status"], if r <= 0.25 { "met" } else { "not_met" });
}

/// `scripts/budgets.py`'s flash figure of one image.
fn budgets_flash(elf: &Path) -> Option<u64> {
    let o =
        Command::new("python3").arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts/budgets.py")).arg(elf).arg("--json").output().ok()?;
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).ok()?;
    v["flash_bytes"].as_u64()
}

#[test]
fn the_flash_figures_agree_with_the_budget_script() {
    // scripts/test.sh builds the images before the tests; a bare `cargo test` may not have.
    let target = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../target"));
    let (code, out, err) = bench(&["--only", "flash", "--target-dir", target.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let mut compared = 0;
    for (f, profile) in figures(&out).iter().zip(["mcu", "release"]) {
        let elf = target.join("thumbv7em-none-eabihf").join(profile).join("pil");
        match (f["value"].as_f64(), budgets_flash(&elf)) {
            (Some(v), Some(b)) => {
                assert_eq!(v, b as f64, "{profile}: bench {v}, budgets.py {b}");
                compared += 1;
            }
            (None, _) => assert!(!elf.exists(), "{profile}: {f}"),
            (Some(_), None) => panic!("budgets.py could not read {}", elf.display()),
        }
    }
    if std::env::var_os("PAINLEVE_REQUIRE_IMAGES").is_some() {
        assert_eq!(compared, 2, "PAINLEVE_REQUIRE_IMAGES: both images must be built");
    }
}
