//! `scripts/sweep-slurm.sh` on a real Slurm: a one-node cluster on localhost
//! (`scripts/slurm-localhost.sh`: Debian's `slurm-wlm` and `munge`, as root), a
//! small sweep submitted as job arrays through the script's `submit`, and the
//! merge job's folder compared with the unsharded sweep's.
//!
//! It needs the packages and root, so it runs only with `PAINLEVE_SLURM=1` (CI's
//! `.ci/run` installs both and sets it); without it the test says so and passes.
//! With it, a missing package or user is a failure, not a skip.

use std::{
    collections::BTreeMap,
    path::{Path, PathBuf},
    process::{Command, Output},
    time::{Duration, Instant},
};

use crate::common;

/// A small open-loop sweep: mu 0.3 and 0.6, v_belt -0.6..-0.4 by 0.1, x0a and x0d,
/// 20 s + 5 s (12 runs, about a second of work): bouncing and contact rows both.
const SWEEP: &[&str] =
    &["--mu", "0.3,0.6", "--mu-step", "0.3", "--v-belt=-0.6,-0.4", "--v-belt-step", "0.1", "--transient", "20", "--record", "5"];

/// The sbatch options of every submission: one CPU per task (the cluster has two).
const SBATCH: &[&str] = &["--cpus-per-task=1", "--time=00:10:00"];

/// How long a job may take from submission to its end.
const JOB_TIMEOUT: Duration = Duration::from_secs(180);

fn sil_host() -> &'static str {
    env!("CARGO_BIN_EXE_sil-host")
}

fn text(o: &Output) -> String {
    format!("exit {:?}\nstdout:\n{}\nstderr:\n{}", o.status.code(), String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// The cluster of `scripts/slurm-localhost.sh`, stopped on drop.
struct Cluster {
    dir: tempfile::TempDir,
    conf: PathBuf,
}

impl Cluster {
    fn start() -> Self {
        let dir = tempfile::Builder::new().prefix("slurm-localhost").tempdir().unwrap();
        let o =
            Command::new("bash").arg(common::workspace().join("scripts/slurm-localhost.sh")).arg("start").arg(dir.path()).output().unwrap();
        assert!(o.status.success(), "the local cluster did not start:\n{}", text(&o));
        let conf = dir.path().join("slurm.conf");
        Self { dir, conf }
    }

    /// A Slurm client command talking to this cluster.
    fn client(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// `scripts/sweep-slurm.sh submit ARGS` from `cwd` with `env`: the array's and
    /// the merge's job ids.
    fn submit(&self, cwd: &Path, env: &[(&str, &str)], args: &[&str]) -> (u64, u64) {
        let mut c = self.client("bash");
        c.arg(common::workspace().join("scripts/sweep-slurm.sh")).arg("submit").args(args).current_dir(cwd);
        c.env("SIL_HOST", sil_host()).env_remove("SWEEP_SHARDS").env_remove("SWEEP_ARGS").env_remove("SWEEP_DIR");
        for (k, v) in env {
            c.env(k, v);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "submit {args:?}:\n{}", text(&o));
        let ids: Vec<u64> = String::from_utf8_lossy(&o.stdout).split_whitespace().map(|s| s.parse().unwrap()).collect();
        assert_eq!(ids.len(), 2, "ARRAY_ID MERGE_ID on stdout:\n{}", text(&o));
        (ids[0], ids[1])
    }

    /// `scontrol show job -o ID`: one line per job (an array: one per task), as
    /// key=value maps.
    fn jobs(&self, id: u64) -> Vec<BTreeMap<String, String>> {
        let o = self.client("scontrol").args(["show", "job", "-o", &id.to_string()]).output().unwrap();
        assert!(o.status.success(), "scontrol show job {id}:\n{}", text(&o));
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.split_whitespace().filter_map(|kv| kv.split_once('=')).map(|(k, v)| (k.to_string(), v.to_string())).collect())
            .collect()
    }

    /// Waits until every job of `id` has ended; their (task id or job id, state,
    /// exit code) sorted by task id.
    fn wait(&self, id: u64) -> Vec<(String, String, String)> {
        const ENDED: [&str; 9] =
            ["COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY", "BOOT_FAIL", "DEADLINE", "PREEMPTED"];
        let start = Instant::now();
        loop {
            let jobs = self.jobs(id);
            if !jobs.is_empty() && jobs.iter().all(|j| ENDED.contains(&j["JobState"].as_str())) {
                let mut out: Vec<(String, String, String)> = jobs
                    .iter()
                    .map(|j| {
                        let task = j.get("ArrayTaskId").unwrap_or(&j["JobId"]).clone();
                        (task, j["JobState"].clone(), j["ExitCode"].clone())
                    })
                    .collect();
                out.sort_by_key(|(t, _, _)| t.parse::<u64>().unwrap_or(u64::MAX));
                return out;
            }
            assert!(start.elapsed() < JOB_TIMEOUT, "job {id} still running after {JOB_TIMEOUT:?}: {jobs:?}\n{}", self.logs());
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    fn logs(&self) -> String {
        let tail = |f: &str| {
            let t = std::fs::read_to_string(self.dir.path().join(f)).unwrap_or_default();
            let lines: Vec<&str> = t.lines().collect();
            lines[lines.len().saturating_sub(15)..].join("\n")
        };
        format!("slurmctld.log:\n{}\nslurmd.log:\n{}", tail("slurmctld.log"), tail("slurmd.log"))
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash").arg(common::workspace().join("scripts/slurm-localhost.sh")).arg("stop").arg(self.dir.path()).output();
    }
}

/// The files of a sweep folder, those that do not depend on the invocation:
/// `summary.json` without `timing` and `files`, `runs.csv` sorted (completion order),
/// every other file (the figures' SVG and PDF) as its bytes.
fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if name.starts_with('.') || name.starts_with("slurm-") {
            continue;
        }
        let bytes = std::fs::read(&path).unwrap();
        if name != "summary.json" && name != "runs.csv" {
            out.insert(name, bytes);
            continue;
        }
        let mut t = String::from_utf8(bytes).unwrap_or_else(|e| panic!("{} is not UTF-8: {e}", path.display()));
        if name == "summary.json" {
            let mut v: serde_json::Value = serde_json::from_str(&t).unwrap();
            let m = v.as_object_mut().unwrap();
            m.remove("timing");
            m.remove("files");
            t = serde_json::to_string_pretty(&v).unwrap();
        } else if name == "runs.csv" {
            let mut lines: Vec<&str> = t.lines().collect();
            lines[1..].sort();
            t = lines.join("\n");
        }
        out.insert(name, t.into_bytes());
    }
    out
}

fn assert_same_sweep(merged: &Path, whole: &Path) {
    let (m, w) = (contents(merged), contents(whole));
    assert_eq!(m.keys().collect::<Vec<_>>(), w.keys().collect::<Vec<_>>(), "the same files");
    for (name, t) in &w {
        assert!(&m[name] == t, "{name} differs between {} and {}", merged.display(), whole.display());
    }
}

/// The shard (`k`, `n`) in a shard folder's manifest.
fn shard_of(dir: &Path) -> (u64, u64) {
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).unwrap()).unwrap();
    (m["shard"]["k"].as_u64().unwrap(), m["shard"]["n"].as_u64().unwrap())
}

#[test]
fn sharded_sweep_on_a_real_slurm_merges_to_the_unsharded_sweep() {
    if std::env::var("PAINLEVE_SLURM").as_deref() != Ok("1") {
        eprintln!("skipped: set PAINLEVE_SLURM=1 to run it (needs slurm-wlm, munge and root; CI does)");
        return;
    }
    let work = tempfile::tempdir().unwrap();
    let whole = work.path().join("whole");
    let o = Command::new(sil_host()).arg("sweep").args(SWEEP).args(["--json", "--out"]).arg(&whole).output().unwrap();
    assert!(o.status.success(), "the unsharded sweep:\n{}", text(&o));
    let cluster = Cluster::start();
    let sweep_args = SWEEP.join(" ");

    // 1. An array that does not start at 0: three tasks are shards 0/3, 1/3, 2/3;
    // the merge job, queued with the array, joins them.
    let a = work.path().join("a");
    let (array, merge) =
        cluster.submit(work.path(), &[("SWEEP_DIR", "a"), ("SWEEP_ARGS", &sweep_args)], &[SBATCH, &["--array=1-3"]].concat());
    let tasks = cluster.wait(array);
    assert_eq!(tasks.len(), 3, "{tasks:?}");
    assert!(tasks.iter().all(|(_, s, c)| s == "COMPLETED" && c == "0:0"), "{tasks:?}");
    let m = cluster.wait(merge);
    assert_eq!((m[0].1.as_str(), m[0].2.as_str()), ("COMPLETED", "0:0"), "merge job:\n{}", read_merge_log(&a, merge));
    let shards: Vec<(u64, u64)> = (0..3).map(|k| shard_of(&a.join(format!("shard-{k}")))).collect();
    assert_eq!(shards, [(0, 3), (1, 3), (2, 3)]);
    assert_same_sweep(&a.join("merged"), &whole);

    // 2. A stepped array whose first task fails (its folder's path is taken by a
    // file): the merge job runs all the same, fails, and names the missing shard
    // and the command that re-runs it.
    let b = work.path().join("b");
    std::fs::create_dir(&b).unwrap();
    std::fs::write(b.join("shard-0"), "in the way").unwrap();
    let (array, merge) = cluster.submit(work.path(), &[("SWEEP_DIR", "b")], &[SBATCH, &["--array=0-4:2", "--"], SWEEP].concat());
    let tasks = cluster.wait(array);
    let states: Vec<(&str, &str)> = tasks.iter().map(|(t, s, _)| (t.as_str(), s.as_str())).collect();
    assert_eq!(states, [("0", "FAILED"), ("2", "COMPLETED"), ("4", "COMPLETED")]);
    let m = cluster.wait(merge);
    let log = read_merge_log(&b, merge);
    assert_eq!((m[0].1.as_str(), m[0].2.as_str()), ("FAILED", "2:0"), "merge job:\n{log}");
    assert!(log.contains("no folder for shards 0 of 3"), "{log}");
    assert!(log.contains("shards with missing runs: 0"), "{log}");
    assert!(log.contains("SWEEP_SHARDS=3") && log.contains("submit --array=0 "), "{log}");
    assert!(!b.join("merged").exists(), "nothing merged");
    assert_eq!((shard_of(&b.join("shard-1")), shard_of(&b.join("shard-2"))), ((1, 3), (2, 3)));

    // 3. The re-run the merge job asked for: shard 0 alone (the task id is the
    // shard), and a merge of all three.
    std::fs::remove_file(b.join("shard-0")).unwrap();
    let (array, merge) = cluster.submit(
        work.path(),
        &[("SWEEP_DIR", "b"), ("SWEEP_SHARDS", "3"), ("SWEEP_ARGS", &sweep_args)],
        &[SBATCH, &["--array=0"]].concat(),
    );
    assert_eq!(cluster.wait(array)[0].1, "COMPLETED");
    let m = cluster.wait(merge);
    assert_eq!((m[0].1.as_str(), m[0].2.as_str()), ("COMPLETED", "0:0"), "merge job:\n{}", read_merge_log(&b, merge));
    assert_eq!(shard_of(&b.join("shard-0")), (0, 3));
    assert_same_sweep(&b.join("merged"), &whole);

    // 4. Pre-emption: a task requeued part way (as PreemptMode=REQUEUE does) starts
    // again (after the cluster's cred_expire, 10 s), resumes its folder, and the
    // merge job waits for it. A longer sweep: 2 x 276 runs of 300 s, a few seconds each.
    let c = work.path().join("c");
    let long = ["--mu", "0.5,1.0", "--mu-step", "0.1", "--v-belt=-1,-0.1", "--v-belt-step", "0.02"];
    let (array, merge) = cluster.submit(work.path(), &[("SWEEP_DIR", "c")], &[SBATCH, &["--array=0-1", "--"], &long].concat());
    let journal = c.join("shard-0/runs.csv");
    let start = Instant::now();
    while std::fs::read_to_string(&journal).map_or(0, |t| t.lines().count()) < 6 {
        assert!(start.elapsed() < JOB_TIMEOUT, "task 0 wrote no runs:\n{}", cluster.logs());
        std::thread::sleep(Duration::from_millis(50));
    }
    let o = cluster.client("scontrol").args(["requeue", &format!("{array}_0")]).output().unwrap();
    assert!(o.status.success(), "requeue:\n{}", text(&o));
    let tasks = cluster.wait(array);
    assert!(tasks.iter().all(|(_, s, c)| s == "COMPLETED" && c == "0:0"), "{tasks:?}");
    let m = cluster.wait(merge);
    assert_eq!((m[0].1.as_str(), m[0].2.as_str()), ("COMPLETED", "0:0"), "merge job:\n{}", read_merge_log(&c, merge));
    let task0 = cluster.jobs(array).into_iter().find(|j| j.get("ArrayTaskId").map(String::as_str) == Some("0")).unwrap();
    assert_eq!(task0["Restarts"], "1");
    // The second start resumed the first's runs (the task's log is rewritten on requeue).
    let log = std::fs::read_to_string(work.path().join(format!("slurm-{array}_0.out"))).unwrap();
    assert!(log.contains("(restart 1)"), "{log}");
    // "sweep of 276 runs (shard 0/2 of 552) in DIR: 12 done already, computing 264 on 1 threads"
    let line = log.lines().find(|l| l.contains("done already")).unwrap_or_else(|| panic!("{log}"));
    let done: u64 = line.rsplit_once(": ").and_then(|(_, r)| r.split_whitespace().next()).and_then(|n| n.parse().ok()).unwrap();
    let total = 276;
    assert!(log.contains(&format!("sweep of {total} runs")), "{log}");
    assert!(done > 0 && done < total, "resumed {done} of {total}:\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(c.join("merged/summary.json")).unwrap()).unwrap();
    assert_eq!((summary["status"].as_str(), summary["results"]["runs"].as_u64()), (Some("complete"), Some(552)));
}

fn read_merge_log(dir: &Path, job: u64) -> String {
    std::fs::read_to_string(dir.join(format!("slurm-merge-{job}.out"))).unwrap_or_else(|e| format!("(no merge log: {e})"))
}
