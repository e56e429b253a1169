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

/// Shard folders written before the balanced assignment (`sweep.json` without
/// `assignment`: run i in shard i mod N) still resume and merge that way.
#[test]
fn modulo_shard_folders_of_earlier_versions_resume_and_merge() {
    let whole = tempfile::tempdir().unwrap();
    ok(&sweep(whole.path(), &[]));
    let manifest: serde_json::Value = serde_json::from_str(&read(whole.path(), "sweep.json")).unwrap();
    let journal = read(whole.path(), "runs.csv");
    let (header, rows) = journal.split_once('\n').unwrap();
    let old = tempfile::tempdir().unwrap();
    let dirs: Vec<std::path::PathBuf> = (0..2).map(|k| old.path().join(format!("shard-{k}"))).collect();
    for (k, dir) in dirs.iter().enumerate() {
        std::fs::create_dir(dir).unwrap();
        let mut m = manifest.clone();
        m["shard"] = serde_json::json!({ "k": k, "n": 2 });
        std::fs::write(dir.join("sweep.json"), serde_json::to_string_pretty(&m).unwrap()).unwrap();
        // Run i in shard i mod 2, the first of them left to compute.
        let mine: Vec<&str> = rows.lines().filter(|r| r.split(',').next().unwrap().parse::<usize>().unwrap() % 2 == k).collect();
        std::fs::write(dir.join("runs.csv"), format!("{header}\n{}\n", mine[1..].join("\n"))).unwrap();
    }
    let resumed = ok(&sweep(&dirs[1], &["--shard", "1/2"]));
    assert_eq!(resumed["resumed_runs"], 5);
    assert_eq!(resumed["timing"]["runs_computed"], 1);
    // The other one is missing a run: the merge names it and its (modulo) shard.
    let out = sil_host().args(["merge", "--out"]).arg(old.path().join("m")).args(&dirs).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("1 of 12 runs are missing") && err.contains("shard 0/2)") && err.contains("shards with missing runs: 0."),
        "{err}"
    );
    let m = sil_host().args(["merge", "--allow-missing", "--json", "--out"]).arg(old.path().join("m")).args(&dirs).output().unwrap();
    assert_eq!(ok(&m)["results"]["missing"], 1);
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

/// `scripts/sweep-slurm.sh` under a stand-in for Slurm (the real one:
/// tests/e2e/slurm.rs, with PAINLEVE_SLURM=1): `submit` through a fake `sbatch`
/// that records its arguments, then the array's tasks and the merge job run as
/// Slurm would start them. The merged folder must equal the unsharded sweep; a
/// merge without one shard's folder fails naming it and the command to re-run it.
#[test]
fn the_slurm_script_submits_the_array_and_the_merge_and_merges_to_the_unsharded_sweep() {
    let whole = tempfile::tempdir().unwrap();
    ok(&sweep(whole.path(), &[]));
    let work = tempfile::tempdir().unwrap();
    let bin = fake_sbatch(work.path());
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let out = Command::new("bash")
        .arg(slurm_script())
        .args(["submit", "--array=1-3", "-p", "short", "--"])
        .args(&TINY[1..])
        .current_dir(work.path())
        .env("PATH", &path)
        .env("SIL_HOST", env!("CARGO_BIN_EXE_sil-host"))
        .env("SWEEP_DIR", "out")
        .env_remove("SWEEP_ARGS")
        .env_remove("SWEEP_SHARDS")
        .output()
        .unwrap();
    assert!(out.status.success(), "submit: {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "101 102");
    let calls = sbatch_calls(work.path());
    assert_eq!(calls.len(), 2, "{calls:?}");
    let (array, merge) = (&calls[0], &calls[1]);
    // The array: the user's options, the array, then the script's task arguments.
    let script_at = array.iter().position(|a| a.ends_with("sweep-slurm.sh")).unwrap();
    assert_eq!(array[..script_at], ["--parsable", "-p", "short", "--array=1-3"]);
    assert_eq!(array[script_at + 1..script_at + 3], ["task", "array:1-3"]);
    // The merge: after the array whatever its outcome (its job id without the cluster name).
    assert!(merge.contains(&"--dependency=afterany:101".to_string()) && merge.contains(&"-p".to_string()), "{merge:?}");
    assert!(!merge.iter().any(|a| a.starts_with("--array")), "{merge:?}");
    let merge_at = merge.iter().position(|a| a.ends_with("sweep-slurm.sh")).unwrap();
    assert_eq!(merge[merge_at + 1..merge_at + 3], ["merge", "3"]);

    // Slurm runs the tasks (ids 1, 2, 3: shards 0, 1, 2 of 3), then the merge.
    for id in 1..=3 {
        let o = Command::new("bash")
            .args(&array[script_at..])
            .current_dir(work.path())
            .env("SLURM_ARRAY_TASK_ID", id.to_string())
            .env("SLURM_ARRAY_JOB_ID", "101")
            .env("SLURM_CPUS_PER_TASK", "1")
            .output()
            .unwrap();
        assert!(o.status.success(), "task {id}: {}", String::from_utf8_lossy(&o.stderr));
        let m: serde_json::Value = serde_json::from_str(&read(&work.path().join(format!("out/shard-{}", id - 1)), "sweep.json")).unwrap();
        assert_eq!((m["shard"]["k"].as_u64(), m["shard"]["n"].as_u64()), (Some(id - 1), Some(3)));
        assert_eq!(m["shard"]["assignment"], "balanced");
    }
    let o = Command::new("bash").args(&merge[merge_at..]).current_dir(work.path()).output().unwrap();
    assert!(o.status.success(), "merge: {}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read(&work.path().join("out/merged"), "sweep.csv"), read(whole.path(), "sweep.csv"));

    // Shard 1's folder lost: the merge fails, naming it and the re-run.
    std::fs::remove_dir_all(work.path().join("out/merged")).unwrap();
    std::fs::remove_dir_all(work.path().join("out/shard-1")).unwrap();
    let o = Command::new("bash").args(&merge[merge_at..]).current_dir(work.path()).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no folder for shards 1 of 3"), "{err}");
    assert!(err.contains("shards with missing runs: 1."), "{err}");
    assert!(err.contains("SWEEP_SHARDS=3 ") && err.contains(" submit --array=1 "), "{err}");
    assert!(!work.path().join("out/merged").exists());
}

/// Which shard an array task computes, for the array forms: its position among the
/// array's task ids (any form, through `submit`), the task id itself (`SWEEP_SHARDS`),
/// or Slurm's variables for a plain `sbatch --array=A-B[:S]`; a clear refusal
/// (exit 2) when it cannot be told.
#[test]
fn the_slurm_script_takes_the_shard_from_the_array() {
    let work = tempfile::tempdir().unwrap();
    // A stand-in for sil-host that prints its arguments.
    let fake = work.path().join("sil-host");
    std::fs::write(&fake, "#!/usr/bin/env bash\necho \"$@\"\n").unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let task = |sharding: Option<&str>, id: u32, vars: &[(&str, &str)]| {
        let mut c = Command::new("bash");
        c.arg(slurm_script());
        if let Some(s) = sharding {
            c.args(["task", s]).arg(&fake).arg("out").arg("--mu=0.5");
        } else {
            c.env("SIL_HOST", &fake).env("SWEEP_DIR", "out").env("SWEEP_ARGS", "--mu=0.5");
        }
        c.env("SLURM_ARRAY_TASK_ID", id.to_string()).env("SLURM_CPUS_PER_TASK", "2").env_remove("SWEEP_SHARDS");
        for (k, v) in vars {
            c.env(k, v);
        }
        c.output().unwrap()
    };
    let shard = |o: std::process::Output| -> String {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let args = String::from_utf8_lossy(&o.stdout).trim().to_string();
        assert!(args.starts_with("sweep --mu=0.5 --shard ") && args.contains("--threads 2"), "{args}");
        args.split_whitespace().nth(3).unwrap().to_string()
    };
    for (sharding, id, want) in [
        ("array:1-16", 1, "0/16"),
        ("array:1-16", 16, "15/16"),
        ("array:0-30:2", 30, "15/16"),
        ("array:0-30:2%4", 6, "3/16"),
        ("array:1,5,9", 9, "2/3"),
        ("array:7,1-3", 7, "3/4"),
        ("shards:16", 3, "3/16"),
    ] {
        assert_eq!(shard(task(Some(sharding), id, &[])), want, "{sharding} task {id}");
    }
    let range =
        [("SLURM_ARRAY_TASK_MIN", "0"), ("SLURM_ARRAY_TASK_STEP", "2"), ("SLURM_ARRAY_TASK_COUNT", "16"), ("SLURM_ARRAY_TASK_MAX", "30")];
    assert_eq!(shard(task(None, 4, &range)), "2/16");
    // A list array seen through Slurm's variables only (1,4,9: min 1, step 1, 3 tasks).
    let list =
        [("SLURM_ARRAY_TASK_MIN", "1"), ("SLURM_ARRAY_TASK_STEP", "1"), ("SLURM_ARRAY_TASK_COUNT", "3"), ("SLURM_ARRAY_TASK_MAX", "9")];
    for (sharding, id, vars, says) in [
        (None, 4, &list[..], "not one range"),
        (None, 4, &[][..], "not all set"),
        (Some("array:1-3"), 4, &[][..], "not in --array"),
        (Some("array:1-x"), 1, &[][..], "cannot read 1-x"),
        (Some("shards:3"), 3, &[][..], "not a shard"),
    ] {
        let o = task(sharding, id, vars);
        assert_eq!(o.status.code(), Some(2), "{sharding:?} {id}");
        assert!(String::from_utf8_lossy(&o.stderr).contains(says), "{sharding:?}: {}", String::from_utf8_lossy(&o.stderr));
    }
    // Outside Slurm, and bad submissions: refused before anything is queued.
    let bare = Command::new("bash").arg(slurm_script()).env_remove("SLURM_ARRAY_TASK_ID").output().unwrap();
    assert_eq!(bare.status.code(), Some(2));
    let bin = fake_sbatch(work.path());
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    for (args, env, says) in [
        (&["submit", "-p", "short"][..], None, "needs --array"),
        (&["submit", "--array=0-3", "--", "--e-n", "1.5"], None, "e-n"),
        (&["submit", "--array=2-5"], Some("4"), "within 0-3"),
    ] {
        let mut c = Command::new("bash");
        c.arg(slurm_script()).args(args).current_dir(work.path()).env("PATH", &path);
        c.env("SIL_HOST", env!("CARGO_BIN_EXE_sil-host")).env("SWEEP_DIR", work.path().join("refused")).env_remove("SWEEP_ARGS");
        match env {
            Some(n) => c.env("SWEEP_SHARDS", n),
            None => c.env_remove("SWEEP_SHARDS"),
        };
        let o = c.output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(String::from_utf8_lossy(&o.stderr).contains(says), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    }
    assert!(sbatch_calls(work.path()).is_empty(), "nothing submitted");
}

fn slurm_script() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/sweep-slurm.sh")
}

/// A fake `sbatch` in `dir/bin`: writes its arguments, one a line, to
/// `dir/sbatch-N.args` and answers `--parsable` with job id 100 + N (and a cluster name).
fn fake_sbatch(dir: &Path) -> std::path::PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let fake = bin.join("sbatch");
    std::fs::write(
        &fake,
        format!(
            "#!/usr/bin/env bash\nn=$(ls {d} | grep -c '^sbatch-.*\\.args$')\nn=$((n + 1))\nprintf '%s\\n' \"$@\" > {d}/sbatch-$n.args\necho \"$((100 + n));cluster\"\n",
            d = dir.display()
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    bin
}

/// The recorded `sbatch` calls, in order.
fn sbatch_calls(dir: &Path) -> Vec<Vec<String>> {
    (1..)
        .map(|n| dir.join(format!("sbatch-{n}.args")))
        .take_while(|p| p.exists())
        .map(|p| std::fs::read_to_string(p).unwrap().lines().map(String::from).collect())
        .collect()
}

/// Waits until process `pid` holds `dir` (its owner file names it), up to 60 s on a
/// loaded machine: driven by the event, not a sleep.
fn wait_until_locked(dir: &Path, pid: u32) {
    let start = std::time::Instant::now();
    let owner = dir.join(sil_host::folder_lock::OWNER_FILE);
    while !std::fs::read_to_string(&owner).is_ok_and(|s| s.starts_with(&format!("pid {pid}:"))) {
        assert!(start.elapsed() < std::time::Duration::from_secs(60), "process {pid} never locked {}", dir.display());
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// Issue 27: two sweeps into one folder interleaved their rows and destroyed it.
/// A sweep holding its folder (stopped with SIGSTOP while it holds it, so the
/// test does not depend on how long it runs) refuses a second sweep, a merge, a
/// report and a run into that folder with exit 2 and the owner's pid; continued,
/// it finishes unharmed, to the rows of a sweep run alone.
#[test]
fn a_second_command_into_a_held_folder_is_refused_and_the_first_finishes_unharmed() {
    let alone = tempfile::tempdir().unwrap();
    ok(&sweep(alone.path(), &[]));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shared");
    let first =
        sil_host().args(TINY).args(["--json", "--threads", "1", "--out"]).arg(&out).stdout(std::process::Stdio::piped()).spawn().unwrap();
    wait_until_locked(&out, first.id());
    // SAFETY: signals to our own child.
    assert_eq!(unsafe { libc::kill(first.id() as i32, libc::SIGSTOP) }, 0);
    let shard = tempfile::tempdir().unwrap();
    ok(&sweep(shard.path(), &["--shard", "0/2"]));
    let o = shard.path().to_str().unwrap();
    let refused: [(&str, Vec<&str>); 4] = [
        ("sweep", TINY.to_vec()),
        ("merge", vec!["merge", "--allow-missing", o]),
        ("report", vec!["report"]),
        ("run", vec!["run", "--in-process", "--duration", "0.1"]),
    ];
    for (what, args) in refused {
        let second = sil_host().args(&args).arg("--out").arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&second.stderr);
        assert_eq!(second.status.code(), Some(2), "{what}: {err}");
        assert!(err.contains("is in use by pid") && err.contains(&format!("pid {}", first.id())), "{what}: {err}");
        assert!(!out.join("summary.json").exists() && !out.join("trace.csv").exists(), "{what} wrote nothing");
    }
    assert_eq!(unsafe { libc::kill(first.id() as i32, libc::SIGCONT) }, 0);
    let s = ok(&first.wait_with_output().unwrap());
    assert_eq!(s["status"], "complete");
    assert_eq!(read(&out, "sweep.csv"), read(alone.path(), "sweep.csv"));
    assert_eq!(read(&out, "runs.csv").lines().count(), 13, "header and 12 rows, none twice");
    assert!(!out.join(sil_host::folder_lock::OWNER_FILE).exists(), "the owner file goes with the lock");
}

/// The audit's trial: two identical sweeps started together into one new folder.
/// Whichever takes the folder first computes the grid; the other is refused (exit
/// 2) or, started after the first finished, finds the sweep complete (exit 0). The
/// folder always ends as a sweep run alone.
#[test]
fn two_sweeps_started_together_leave_one_whole_sweep() {
    let alone = tempfile::tempdir().unwrap();
    ok(&sweep(alone.path(), &[]));
    for trial in 0..3 {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("together");
        let start = || {
            sil_host()
                .args(TINY)
                .arg("--out")
                .arg(&out)
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (start(), start());
        let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
        let codes = (a.status.code(), b.status.code());
        let why = format!("trial {trial}: {codes:?}: {} | {}", String::from_utf8_lossy(&a.stderr), String::from_utf8_lossy(&b.stderr));
        assert!(matches!(codes, (Some(0), Some(0)) | (Some(0), Some(2)) | (Some(2), Some(0))), "{why}");
        assert_eq!(read(&out, "sweep.csv"), read(alone.path(), "sweep.csv"), "{why}");
        assert_eq!(read(&out, "runs.csv").lines().count(), 13, "{why}");
    }
}
