//! `--seeds N` (issue 82): a sweep's cells over their sensor-noise seeds, through
//! the real binary. Seed 0 is the sweep of one seed, run for run; the other seeds
//! move the noise (so the runs differ); `cells.csv` counts each cell's seeds and
//! gives the Wilson interval of each fraction; the open loop refuses seeds
//! without jitter and, with it, marks the cells on a boundary.

use std::{collections::HashMap, path::Path, process::Command};

type Row = HashMap<String, String>;

fn sil_host() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sil-host"))
}

/// The sampled hybrid loop from x0d at the saturation edge (docs/results.md):
/// mu 0.9 and 0.95, two belt speeds, 3 s + 2 s per run.
const EDGE: &[&str] = &[
    "sweep",
    "--controller",
    "hybrid",
    "--ics",
    "d",
    "--mu",
    "0.9,0.95",
    "--mu-step",
    "0.05",
    "--v-belt=-0.6,-0.5",
    "--v-belt-step",
    "0.1",
    "--transient",
    "3",
    "--record",
    "2",
];

fn run(dir: &Path, args: &[&str]) -> serde_json::Value {
    let out = sil_host().args(args).arg("--json").arg("--out").arg(dir).output().unwrap();
    assert!(out.status.success(), "exit {:?}: {}", out.status.code(), String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("one JSON document")
}

fn rows(path: &Path) -> Vec<Row> {
    csv::Reader::from_path(path).unwrap().deserialize().map(|r| r.unwrap()).collect()
}

fn f(r: &Row, k: &str) -> f64 {
    r[k].parse().unwrap_or_else(|_| panic!("{k} = {:?}", r[k]))
}

/// Wilson's score interval, written out again (Wilson 1927): the cells' bounds must equal it.
fn wilson(k: f64, n: f64) -> (f64, f64) {
    let z = 1.959_963_984_540_054_f64;
    let p = k / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / d;
    (if k == 0.0 { 0.0 } else { (c - h).max(0.0) }, if k == n { 1.0 } else { (c + h).min(1.0) })
}

#[test]
fn seeds_give_each_cell_its_fractions_and_seed_zero_is_the_single_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let (one, many) = (dir.path().join("one"), dir.path().join("many"));
    let s1 = run(&one, EDGE);
    let s6 = run(&many, &[EDGE, &["--seeds", "6", "--jitter-f-n-ref", "0.05"]].concat());
    assert_eq!(s1["samples"]["seeds"], 1);
    assert!(s1["samples"]["note"].as_str().unwrap().starts_with("one sample per cell"), "{}", s1["samples"]);
    assert!(s1.get("ensemble").is_none() && !one.join("cells.csv").exists(), "one seed: no cells file");
    assert_eq!((s6["results"]["runs"].as_u64(), s6["samples"]["draws"].as_array().unwrap().len()), (Some(24), 6));
    // Seed 0 is the single sweep's runs, bit for bit.
    let (r1, r6) = (rows(&one.join("sweep.csv")), rows(&many.join("sweep.csv")));
    assert_eq!(r1.len(), 4);
    for r in &r1 {
        let twin = r6.iter().find(|x| x["index"] == r["index"]).unwrap();
        assert_eq!(r, twin, "seed 0 differs from the single sweep");
        assert_eq!(r["seed"], "0");
    }
    // Every f_n* draw within its bound, seed 0 nominal.
    for d in s6["samples"]["draws"].as_array().unwrap() {
        assert!(d["d_f_n_ref_n"].as_f64().unwrap().abs() <= 0.05, "{d}");
        assert_eq!(d["d_mu"], 0.0);
    }
    assert_eq!(s6["samples"]["draws"][0]["d_f_n_ref_n"], 0.0);
    // The other seeds move the noise: in every cell the seeds' trajectories differ.
    let cells = rows(&many.join("cells.csv"));
    assert_eq!(cells.len(), 4);
    for c in &cells {
        let of_cell: Vec<&Row> = r6.iter().filter(|r| r["mu"] == c["mu"] && r["v_belt"] == c["v_belt"]).collect();
        assert_eq!(of_cell.len(), 6);
        let maxima: std::collections::BTreeSet<String> = of_cell.iter().map(|r| r["theta1_dot_max"].clone()).collect();
        assert!(maxima.len() > 1, "six seeds, one trajectory: {c:?}");
        // The counts are the cell's rows', the bounds Wilson's, the flags the intervals'.
        let count = |o: &[&str]| of_cell.iter().filter(|r| o.contains(&r["outcome"].as_str())).count() as f64;
        for (name, outcomes) in [("lift_off", &["lift_off"][..]), ("safe_state", &["safe_state"]), ("contact", &["contact"])] {
            let k = count(outcomes);
            assert_eq!(f(c, name), k, "{name} {c:?}");
            let (lo, hi) = wilson(k, 6.0);
            assert!((f(c, &format!("{name}_lo")) - lo).abs() < 1e-12 && (f(c, &format!("{name}_hi")) - hi).abs() < 1e-12, "{c:?}");
        }
        let straddles = |name: &str| f(c, &format!("{name}_lo")) <= 0.5 && f(c, &format!("{name}_hi")) >= 0.5;
        assert_eq!(c["undecided"] == "true", straddles("lift_off") || straddles("contact"), "{c:?}");
        let k = f(c, "lift_off");
        assert_eq!(c["boundary"] == "true", k > 0.0 && k < 6.0);
    }
    // The summary pools the cells per mu; the map is shaded by the fraction.
    let per_mu = s6["ensemble"]["per_mu"].as_array().unwrap();
    assert_eq!(per_mu.len(), 2);
    assert_eq!(per_mu[0]["lift_off"]["n"], 12);
    let map = std::fs::read_to_string(many.join("map_newton_e0.2.svg")).unwrap();
    assert!(map.contains("Lift-off fraction over 6 seeds") && map.contains("undecided"), "the map is not the fractions'");
}

/// The open loop has no noise: seeds need jitter (exit 2 and the flags to give),
/// and a jitter of mu across the critical mu puts its cells on a boundary. At mu
/// 0.4 (the critical mu from x0a on the paper's grid at v_belt -0.5, e_n 0.2)
/// jittered by +-0.05 some seeds bounce and some do not; at 0.1 none does.
#[test]
fn open_loop_seeds_need_jitter_and_mark_the_boundary() {
    let dir = tempfile::tempdir().unwrap();
    let base = ["sweep", "--ics", "a", "--mu", "0.1,0.4", "--mu-step", "0.3", "--v-belt=-0.5", "--transient", "20", "--record", "5"];
    let out = sil_host().args(base).args(["--seeds", "4", "--out"]).arg(dir.path().join("x")).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--jitter-mu"), "{}", String::from_utf8_lossy(&out.stderr));
    let out = sil_host()
        .args(base)
        .args(["--seeds", "4", "--jitter-f-n-ref", "0.1", "--jitter-mu", "0.01", "--out"])
        .arg(dir.path().join("y"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "f_n* jitter in open loop");
    let out_dir = dir.path().join("z");
    let s = run(&out_dir, &[&base[..], &["--seeds", "12", "--jitter-mu", "0.05"]].concat());
    assert!(s["samples"]["note"].as_str().unwrap().contains("no noise"), "{}", s["samples"]);
    let cells = rows(&out_dir.join("cells.csv"));
    let at = |mu: &str| cells.iter().find(|c| c["mu"] == mu).unwrap().clone();
    assert_eq!((at("0.1")["lift_off"].as_str(), at("0.1")["boundary"].as_str()), ("0", "false"));
    assert_eq!(at("0.4")["boundary"], "true", "{:?}", at("0.4"));
}
