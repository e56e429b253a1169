//! `sil-host sweep` and `sil-host merge` through the real binary: known outcomes
//! of a tiny sweep, resume after an interruption (a run limit, a cut-off journal),
//! shards merged into the unsharded result, and the refusals.

use std::{path::Path, process::Command};

fn sil_host() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sil-host"))
}

/// A tiny open-loop sweep: mu 0.1 and 0.6, v_belt -0.6..-0.4 by 0.1, x0a and x0d,
/// 20 s transient + 5 s record (12 runs, well under a second).
const TINY: &[&str] =
    &["sweep", "--mu", "0.1,0.6", "--mu-step", "0.5", "--v-belt=-0.6,-0.4", "--v-belt-step", "0.1", "--transient", "20", "--record", "5"];

fn sweep(dir: &Path, extra: &[&str]) -> std::process::Output {
    sil_host().args(TINY).args(extra).arg("--json").arg("--out").arg(dir).output().unwrap()
}

fn ok(out: &std::process::Output) -> serde_json::Value {
    assert!(out.status.success(), "exit {:?}: {}", out.status.code(), String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("one JSON document on stdout")
}

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap()
}

/// With mu = 0.1, p > 0 on the whole belt (no Painlevé paradox: the admissible
/// region covers every configuration, docs/model.md experiment 2), so the arm settles to
/// steady sliding from both initial conditions: no bouncing, no lift-off in the
/// record window. At mu = 0.6 the arm bounces from x0a over this band.
#[test]
fn tiny_sweep_has_the_known_outcomes() {
    let dir = tempfile::tempdir().unwrap();
    let s = ok(&sweep(dir.path(), &[]));
    assert_eq!(s["status"], "complete");
    let case = &s["results"]["cases"][0];
    assert_eq!(case["impact_law"], "newton");
    let x0a = &case["ics"][0];
    assert_eq!(x0a["ic"], "x0a");
    assert_eq!(x0a["critical_mu"], 0.6);
    assert_eq!(x0a["per_mu"][0]["bouncing_points"], 0);
    assert_eq!(x0a["per_mu"][0]["indicator_points"], 0);
    assert_eq!(x0a["per_mu"][1]["bands"][0]["v_min"], -0.6);
    let mut rdr = csv::Reader::from_path(dir.path().join("sweep.csv")).unwrap();
    let rows: Vec<std::collections::HashMap<String, String>> = rdr.deserialize().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 12);
    for r in rows.iter().filter(|r| r["mu"] == "0.1") {
        assert_eq!(r["outcome"], "contact", "{r:?}");
        assert_eq!(r["lift_offs"], "0");
        assert_eq!(r["final_mode"], "sliding");
        // On the belt throughout the record window.
        assert!(r["tip_height_max"].parse::<f64>().unwrap().abs() < 1e-9, "{r:?}");
    }
    for r in rows.iter().filter(|r| r["mu"] == "0.6" && r["ic"] == "x0a") {
        assert_eq!(r["outcome"], "bouncing", "{r:?}");
        assert!(r["lift_offs"].parse::<u64>().unwrap() > 5);
        assert!(r["tip_height_max"].parse::<f64>().unwrap() > 1e-3);
    }
    for f in ["sweep.csv", "runs.csv", "sweep.json", "summary.json", "map_newton_e0.2.svg", "slices_newton_e0.2.svg"] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
    assert!(read(dir.path(), "map_newton_e0.2.svg").contains("bouncing"));
}

#[test]
fn an_interrupted_sweep_resumes_to_the_same_rows() {
    let whole = tempfile::tempdir().unwrap();
    ok(&sweep(whole.path(), &[]));
    // Interrupted by a run limit, then resumed.
    let parts = tempfile::tempdir().unwrap();
    let first = ok(&sweep(parts.path(), &["--limit", "5"]));
    assert_eq!(first["status"], "incomplete");
    assert_eq!(first["results"]["runs"], 5);
    let resumed = ok(&sweep(parts.path(), &[]));
    assert_eq!(resumed["resumed_runs"], 5);
    assert_eq!(resumed["timing"]["runs_computed"], 7);
    assert_eq!(read(parts.path(), "sweep.csv"), read(whole.path(), "sweep.csv"));
    assert_eq!(resumed["results"], ok(&sweep(whole.path(), &[]))["results"]);
    // Killed in the middle of writing a row: the cut-off line is dropped and rerun.
    let cut = tempfile::tempdir().unwrap();
    ok(&sweep(cut.path(), &["--limit", "4"]));
    let journal = read(cut.path(), "runs.csv");
    std::fs::write(cut.path().join("runs.csv"), &journal[..journal.len() - 20]).unwrap();
    let again = ok(&sweep(cut.path(), &[]));
    assert_eq!(again["resumed_runs"], 3);
    assert_eq!(read(cut.path(), "sweep.csv"), read(whole.path(), "sweep.csv"));
    assert_eq!(read(cut.path(), "runs.csv").lines().count(), 13, "header and 12 rows, none twice");
}

#[test]
fn resuming_with_other_arguments_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    ok(&sweep(dir.path(), &["--limit", "2"]));
    let out = sweep(dir.path(), &["--e-n", "0.5"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("different sweep") && err.contains("e_n"), "{err}");
    let out = sweep(dir.path(), &["--shard", "0/2"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("shard"));
}

#[test]
fn merged_shards_equal_the_unsharded_sweep() {
    let whole = tempfile::tempdir().unwrap();
    let w = ok(&sweep(whole.path(), &[]));
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let sa = ok(&sweep(a.path(), &["--shard", "0/2"]));
    ok(&sweep(b.path(), &["--shard", "1/2"]));
    assert_eq!(sa["results"]["runs"], 6);
    let merged = tempfile::tempdir().unwrap();
    let m = sil_host().args(["merge", "--json", "--out"]).arg(merged.path()).arg(a.path()).arg(b.path()).output().unwrap();
    let m = ok(&m);
    assert_eq!(m["status"], "complete");
    assert_eq!(m["results"], w["results"]);
    assert_eq!(read(merged.path(), "sweep.csv"), read(whole.path(), "sweep.csv"));
    // The merged folder is a complete sweep: running the sweep there computes nothing.
    let again = ok(&sweep(merged.path(), &[]));
    assert_eq!(again["timing"]["runs_computed"], 0);

    // One shard only: the missing runs are named, nothing is written.
    let lone = tempfile::tempdir().unwrap();
    let out = sil_host().args(["merge", "--out"]).arg(lone.path().join("m")).arg(a.path()).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("6 of 12 runs are missing") && err.contains("shard 1/2"), "{err}");
    assert!(!lone.path().join("m").exists());
    // Shards of different sweeps are refused.
    let other = tempfile::tempdir().unwrap();
    ok(&sweep(other.path(), &["--shard", "1/2", "--threshold", "1e-3"]));
    let out = sil_host().args(["merge", "--out"]).arg(lone.path().join("m")).arg(a.path()).arg(other.path()).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("threshold"));
}

#[test]
fn bad_arguments_exit_with_2() {
    let dir = tempfile::tempdir().unwrap();
    for args in [&["--shard", "2/2"][..], &["--mu-step", "0.3"], &["--e-n", "1.5"], &["--ics", "q"], &["--scenario", "x.toml"]] {
        let out = sweep(&dir.path().join("x"), args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
    assert!(!dir.path().join("x").exists(), "nothing written");
}

/// Closed loop (experiment 7's set-up): the hybrid controller from x0d at mu 0.6,
/// v_belt -0.4 m/s holds the tip on the belt (experiment 6): no lift-off.
#[test]
fn closed_loop_hybrid_keeps_the_tip_on_the_belt() {
    let dir = tempfile::tempdir().unwrap();
    let out = sil_host()
        .args([
            "sweep",
            "--controller",
            "hybrid",
            "--ics",
            "d",
            "--mu",
            "0.6",
            "--v-belt=-0.4",
            "--transient",
            "3",
            "--record",
            "1",
            "--json",
        ])
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let s = ok(&out);
    assert_eq!(s["spec"]["scenario"]["controller"]["kind"], "hybrid");
    let mut rdr = csv::Reader::from_path(dir.path().join("sweep.csv")).unwrap();
    let rows: Vec<std::collections::HashMap<String, String>> = rdr.deserialize().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["lift_offs"], "0", "{:?}", rows[0]);
    assert_ne!(rows[0]["outcome"], "bouncing");
    assert_eq!(s["results"]["cases"][0]["ics"][0]["critical_mu"], serde_json::Value::Null);
}

/// The paper's continuous-time hybrid law (--ideal) from x0d and x0u at mu 0.6
/// holds the tip on the belt across belt speeds (experiment 6's set-up): no
/// lift-off, no bouncing band.
#[test]
fn closed_loop_ideal_hybrid_keeps_the_tip_on_the_belt() {
    let dir = tempfile::tempdir().unwrap();
    let out = sil_host()
        .args(["sweep", "--controller", "hybrid", "--ideal", "--ics", "d,u", "--mu", "0.6", "--v-belt=-0.6,-0.2", "--v-belt-step", "0.2"])
        .args(["--transient", "3", "--record", "1", "--json", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let s = ok(&out);
    assert_eq!(s["spec"]["ideal"], true);
    assert_eq!(s["results"]["runs"], 6);
    assert_eq!(s["results"]["outcomes"]["contact"], 6, "{}", s["results"]);
}

/// `scripts/sweep-slurm.sh` under a stand-in for Slurm: each array task runs as
/// Slurm would start it (its environment variables), a fake `sbatch` records the
/// merge job the first task queues and runs its `--wrap` command; the merged
/// folder must equal the unsharded sweep.
#[test]
fn the_slurm_job_array_script_shards_and_merges_to_the_unsharded_sweep() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/sweep-slurm.sh");
    let whole = tempfile::tempdir().unwrap();
    ok(&sweep(whole.path(), &[]));
    let work = tempfile::tempdir().unwrap();
    let bin = work.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    let log = work.path().join("sbatch.log");
    let fake = bin.join("sbatch");
    // The merge job: record the arguments, then run the --wrap command (afterok is
    // met: the test runs it after both tasks succeeded).
    std::fs::write(
        &fake,
        format!(
            "#!/usr/bin/env bash\necho \"$@\" >> {log}\nfor a in \"$@\"; do case $a in --wrap) w=1;; *) [ -n \"$w\" ] && cmd=$a && w=;; esac; done\necho \"$cmd\" > {wrap}\n",
            log = log.display(),
            wrap = work.path().join("wrap.sh").display()
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let sweep_args = TINY[1..].join(" ");
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    for k in 0..2 {
        let out = Command::new("bash")
            .arg(&script)
            .current_dir(work.path())
            .env("PATH", &path)
            .env("SIL_HOST", env!("CARGO_BIN_EXE_sil-host"))
            .env("SWEEP_ARGS", &sweep_args)
            .env("SWEEP_DIR", "out")
            .env("SLURM_ARRAY_TASK_ID", k.to_string())
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .env("SLURM_ARRAY_TASK_MIN", "0")
            .env("SLURM_ARRAY_JOB_ID", "4242")
            .env("SLURM_CPUS_PER_TASK", "1")
            .output()
            .unwrap();
        assert!(out.status.success(), "task {k}: {}", String::from_utf8_lossy(&out.stderr));
    }
    // Exactly one merge job, queued by the first task, after the whole array.
    let queued = std::fs::read_to_string(&log).unwrap();
    assert_eq!(queued.lines().count(), 1, "{queued}");
    assert!(queued.contains("--dependency=afterok:4242"), "{queued}");
    let wrap = std::fs::read_to_string(work.path().join("wrap.sh")).unwrap();
    let merge = Command::new("bash").arg("-c").arg(wrap.trim()).current_dir(work.path()).output().unwrap();
    assert!(merge.status.success(), "merge: {}", String::from_utf8_lossy(&merge.stderr));
    assert_eq!(read(&work.path().join("out/merged"), "sweep.csv"), read(whole.path(), "sweep.csv"));
    // Outside Slurm the script refuses to run.
    let bare = Command::new("bash").arg(&script).env_remove("SLURM_ARRAY_TASK_ID").output().unwrap();
    assert_eq!(bare.status.code(), Some(2));
}
