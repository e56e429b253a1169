//! Golden outputs: a fixed set of commands must write byte-identical files
//! (after dropping what depends on the wall clock, the machine or the output
//! path) to the ones recorded in `tests/golden/digests.txt`. It guards the
//! host-side redesign (a refactor): every step keeps these digests.
//!
//! `GOLDEN=update cargo test --release -p sil-host --features full --test e2e -- golden::` records them again
//! (only when an output is meant to change; say which and why in the commit).
//! On a mismatch the outputs are kept in `target/golden-actual/` for a diff
//! against the files of the previous binary.

use std::{
    collections::BTreeMap,
    path::{Path, PathBuf},
    process::Command,
};

use sha2::{Digest, Sha256};

use crate::common;

/// Keys (JSON) and columns (CSV) whose values depend on the wall clock, the
/// machine, the process or the output folder, not on the computation.
const VOLATILE: &[&str] = &[
    "wall_s",
    "median_point_wall_s",
    "cpu_s",
    "realtime_factor",
    "periods_per_s",
    "simulated_s_per_wall_s_per_core",
    "simulated_s_per_cpu_s",
    "paper_grid_projection_s",
    "ipc_rtt_us",
    "firmware_step_us",
    "period_jitter_us",
    "rig",
    "files",
    "out",
    "defmt_log",
    "image",
    "socket",
];

/// The commands (arguments after `sil-host`, before `--out DIR`).
fn cases() -> Vec<(String, Vec<String>)> {
    let root = common::workspace();
    let scenario = |s: &str| root.join("scenarios").join(format!("{s}.toml")).display().to_string();
    let mut cases: Vec<(String, Vec<String>)> = vec![
        ("simulate-x0a".into(), vec!["simulate".into(), "--x0".into(), "a".into()]),
        ("simulate-x0d".into(), vec!["simulate".into(), "--x0".into(), "d".into()]),
        ("admissible".into(), vec!["admissible".into()]),
        ("modes".into(), vec!["modes".into()]),
        (
            "sweep".into(),
            ["sweep", "--mu", "0.3,0.6", "--mu-step", "0.3", "--v-belt", "-1,-0.1", "--v-belt-step", "0.1"]
                .into_iter()
                .chain(["--impact-law", "newton,poisson"])
                .map(String::from)
                .collect(),
        ),
        ("poincare".into(), ["poincare", "--v-belt", "-0.9,-0.3", "--v-step", "0.3"].into_iter().map(String::from).collect()),
        ("zmax-all".into(), vec!["zmax".into(), "--all".into()]),
    ];
    for s in ["pid-x0d", "pid-x0u", "hybrid-x0d", "hybrid-x0u"] {
        cases.push((format!("run-in-process-{s}"), vec!["run".into(), "--in-process".into(), "--scenario".into(), scenario(s)]));
        cases.push((format!("run-iceoryx2-{s}"), vec!["run".into(), "--scenario".into(), scenario(s)]));
    }
    let image = common::qemu_image("pil").display().to_string();
    cases.push(("pil-default".into(), vec!["pil".into(), "--image".into(), image]));
    cases
}

/// `bytes` of file `name` without the volatile parts.
fn normalise(name: &str, bytes: &[u8]) -> Vec<u8> {
    if name.ends_with(".json") {
        let mut v: serde_json::Value = serde_json::from_slice(bytes).expect("valid JSON");
        strip(&mut v);
        serde_json::to_vec_pretty(&v).unwrap()
    } else if name.ends_with(".csv") {
        let text = String::from_utf8(bytes.to_vec()).expect("UTF-8 CSV");
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let keep: Vec<bool> = header.iter().map(|h| !VOLATILE.contains(h)).collect();
        let project = |l: &str| -> String {
            // Only headers with volatile columns need the split (their rows hold no quoted commas).
            if keep.iter().all(|k| *k) {
                l.to_string()
            } else {
                l.split(',').zip(&keep).filter(|(_, k)| **k).map(|(c, _)| c).collect::<Vec<_>>().join(",")
            }
        };
        let mut rows: Vec<String> = lines.map(project).collect();
        // runs.csv is appended in the order the threads finish.
        if name == "runs.csv" {
            rows.sort();
        }
        let mut out = project(&header.join(","));
        for r in rows {
            out.push('\n');
            out.push_str(&r);
        }
        out.into_bytes()
    } else {
        bytes.to_vec()
    }
}

fn strip(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| !VOLATILE.contains(&k.as_str()));
            m.values_mut().for_each(strip);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
        _ => {}
    }
}

fn digests(dir: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    for p in names {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let bytes = std::fs::read(&p).unwrap();
        let hash = Sha256::digest(normalise(&name, &bytes));
        out.insert(name, hash.iter().map(|b| format!("{b:02x}")).collect());
    }
    out
}

#[test]
fn outputs_match_the_recorded_digests() {
    let root = common::workspace();
    let actual_root = root.join("target/golden-actual");
    let _ = std::fs::remove_dir_all(&actual_root);
    let mut actual = BTreeMap::new();
    for (case, args) in cases() {
        let out = actual_root.join(&case);
        let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(&args).arg("--out").arg(&out).output().unwrap();
        assert!(o.status.success(), "{case}: {args:?} failed:\n{}", String::from_utf8_lossy(&o.stderr));
        for (file, hash) in digests(&out) {
            actual.insert(format!("{case}/{file}"), hash);
        }
    }
    let path = root.join("tests/golden/digests.txt");
    let text: String = actual.iter().map(|(k, v)| format!("{v}  {k}\n")).collect();
    if std::env::var("GOLDEN").as_deref() == Ok("update") {
        std::fs::write(&path, text).unwrap();
        return;
    }
    let recorded = std::fs::read_to_string(&path).expect("tests/golden/digests.txt (GOLDEN=update records it)");
    let recorded: BTreeMap<String, String> =
        recorded.lines().filter_map(|l| l.split_once("  ")).map(|(h, k)| (k.to_string(), h.to_string())).collect();
    let mut wrong = Vec::new();
    for k in recorded.keys().chain(actual.keys()).collect::<std::collections::BTreeSet<_>>() {
        match (recorded.get(k), actual.get(k)) {
            (Some(a), Some(b)) if a == b => {}
            (Some(_), Some(_)) => wrong.push(format!("changed: {k}")),
            (Some(_), None) => wrong.push(format!("missing: {k}")),
            (None, _) => wrong.push(format!("new: {k}")),
        }
    }
    assert!(wrong.is_empty(), "golden outputs differ (kept in {}):\n{}", actual_root.display(), wrong.join("\n"));
}
