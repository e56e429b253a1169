//! End-to-end: every parameter open (issue 14). The arm's parameters (paper
//! Table I) and the gains (paper eqs. 8 to 11) as scenario keys and `--set`
//! overrides: they reach the plant, the firmware and the ideal laws, agree with
//! the same values given another way, and bad keys or values exit 2 naming them.

use std::{path::Path, process::Command};

use plant::{Hold, NoObserver, Plant, SimConfig, initial};
use rig::{InProcessLink, Scenario, run_loop, setup};
use shared::Params;

/// Runs the binary; returns the exit code and standard error.
fn sil_host(args: &[&str]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sil-host")).args(args).output().unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&read(path)).unwrap()
}

/// The default scenario with `m = 0.24` (twice the paper's) in the file.
fn heavy_scenario_text() -> String {
    rig::scenario::DEFAULT_TOML.replacen("m = 0.12 ", "m = 0.24 ", 1)
}

#[test]
fn a_heavier_arm_changes_the_run_and_the_file_key_equals_set() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("heavy.toml");
    std::fs::write(&file, heavy_scenario_text()).unwrap();
    let out = |name: &str| dir.path().join(name);
    let base = ["run", "--in-process", "--duration", "1"];
    let go = |extra: &[&str], name: &str| {
        let o = out(name);
        let mut args: Vec<&str> = base.to_vec();
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", o.to_str().unwrap()]);
        let (code, err) = sil_host(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
    };
    go(&[], "default");
    go(&["--scenario", file.to_str().unwrap()], "file");
    go(&["--set", "plant.m=0.24"], "set");
    let trace = |name: &str| read(&out(name).join("trace.csv"));
    assert_ne!(trace("default"), trace("file"), "m = 0.24 must change the trajectory");
    assert_eq!(trace("file"), trace("set"), "the file key and --set must give the same run");

    // The summary records what was used, on both sides of the wire.
    let s = json(&out("set").join("summary.json"));
    assert_eq!(s["plant_params"]["m"], 0.24);
    assert!((s["firmware_config"]["params"]["m"].as_f64().unwrap() - 0.24).abs() < 1e-6);
    assert_eq!(s["firmware_config"]["pid"]["kp"][0], 200.0);
    assert_eq!(s["firmware_config"]["hybrid"]["ki"], 650.0);
    assert_eq!(s["scenario_used"]["plant"]["m"], 0.24);

    // An independent path: the scenario built in code, run through the library.
    let mut scenario = Scenario::default_scenario();
    scenario.plant.m = 0.24;
    scenario.timing.duration_s = 1.0;
    let setup = rig::RunSetup::new(scenario).unwrap();
    let mut link = InProcessLink::new(&setup).unwrap();
    let (records, failure) = run_loop(&setup, &mut link, &mut ());
    assert!(failure.is_none());
    let last = records.last().unwrap();
    let final_z_t = s["final_z_t_m"].as_f64().unwrap();
    assert_eq!(final_z_t, last.z_t, "the library run and the command's must agree");
}

#[test]
fn the_firmware_models_the_plant_unless_told_otherwise() {
    let mut s = Scenario::from_toml(&heavy_scenario_text()).unwrap();
    let cfg = setup::firmware_config(&s);
    assert_eq!(cfg.params, Params::<f64> { m: 0.24, mu: s.controller.mu_hat, ..Params::paper() }.cast::<f32>());
    // A deliberate mismatch: the firmware keeps the paper's mass.
    let with_model = heavy_scenario_text().replace("# [controller.model]", "[controller.model]").replace("# m = 0.12", "m = 0.12");
    s = Scenario::from_toml(&with_model).unwrap();
    assert_eq!(s.plant.m, 0.24);
    assert_eq!(setup::firmware_config(&s).params.m, 0.12);
    assert_eq!(setup::plant_params(&s).m, 0.24);
    // The gains and the PIL configuration message carry them.
    let s = Scenario::from_toml_with(
        rig::scenario::DEFAULT_TOML,
        &["controller.pid.kp=[150, 1]", "controller.hybrid.kd=700", "controller.hybrid.ki=300", "plant.g=9.7"].map(|a| a.parse().unwrap()),
    )
    .unwrap();
    let cfg = setup::firmware_config(&s);
    assert_eq!((cfg.pid.kp, cfg.hybrid.kd, cfg.hybrid.ki, cfg.params.g), ([150.0, 1.0], 700.0, 300.0, 9.7));
    let mut buf = [0u8; firmware::pil::MAX_FRAME];
    let msg = firmware::pil::Downlink::Configure(cfg);
    let frame = firmware::pil::encode(&msg, &mut buf).unwrap().to_vec();
    let mut scratch = frame.clone();
    let back: firmware::pil::Downlink = firmware::pil::decode(&mut scratch[..frame.len() - 1]).unwrap();
    assert_eq!(back, msg);
}

#[test]
fn k_prime_i_defaults_to_the_papers_by_initial_condition() {
    let s = Scenario::default_scenario();
    assert_eq!(s.controller.hybrid.ki, None);
    assert_eq!(setup::firmware_config(&s).hybrid.ki, 650.0);
    let mut u = s.clone();
    u.plant.x0 = plant::initial::PaperX0::U;
    assert_eq!(setup::firmware_config(&u).hybrid.ki, 0.0);
    let set = Scenario::from_toml_with(rig::scenario::DEFAULT_TOML, &["controller.hybrid.ki=300".parse().unwrap()]).unwrap();
    let mut set_u = set.clone();
    set_u.plant.x0 = plant::initial::PaperX0::U;
    assert_eq!(setup::firmware_config(&set_u).hybrid.ki, 300.0);
    // The old key still works.
    let old = rig::scenario::DEFAULT_TOML.replace("mu_hat = 0.6 ", "hybrid_ki = 123.0\nmu_hat = 0.6 ");
    assert_eq!(Scenario::from_toml(&old).unwrap().controller.hybrid.ki, Some(123.0));
}

#[test]
fn simulate_with_set_equals_the_plant_built_directly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let (code, err) = sil_host(&[
        "simulate",
        "--x0",
        "d",
        "--duration",
        "0.5",
        "--set",
        "plant.m=0.24",
        "--set",
        "plant.k=2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let params = Params::<f64> { m: 0.24, k: 2.0, ..Params::paper() };
    assert_eq!(json(&out.join("summary.json"))["params"]["m"], 0.24);
    let mut plant = Plant::new(params, SimConfig::default(), initial::deg_to_state(initial::X0D.deg), 0.0, [0.0; 2]).unwrap();
    for k in 1..=500 {
        plant.advance(&Hold([0.0, 0.0]), k as f64 * 1e-3 - plant.time(), &mut NoObserver).unwrap();
    }
    let text = read(&out.join("trace.csv"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let last: Vec<&str> = lines.last().unwrap().split(',').collect();
    let col = |name: &str| last[header.iter().position(|h| *h == name).unwrap()].parse::<f64>().unwrap();
    let x = plant.state();
    assert!((col("t") - 0.5).abs() < 1e-12);
    assert!((col("theta1") - x[0]).abs() < 1e-9 && (col("theta2") - x[2]).abs() < 1e-9, "{} {}", col("theta1"), x[0]);
    // And it differs from the paper's arm.
    let paper = dir.path().join("paper");
    assert_eq!(sil_host(&["simulate", "--x0", "d", "--duration", "0.5", "--out", paper.to_str().unwrap()]).0, 0);
    assert_ne!(read(&paper.join("trace.csv")), text);
}

#[test]
fn bad_keys_and_values_exit_2_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (&["run", "--in-process", "--set", "plant.mass=1"], &["plant.mass"]),
        (&["run", "--in-process", "--set", "plant.m=-1"], &["plant.m", "-1", "out of range"]),
        (&["run", "--in-process", "--set", "plant.m=nan"], &["plant.m", "NaN"]),
        (&["run", "--in-process", "--set", "controller.pid.kp=[1]"], &["controller.pid.kp"]),
        (&["run", "--in-process", "--set", "controller.hybrid.kp=-5"], &["controller.hybrid.kp", "-5"]),
        (&["run", "--in-process", "--set", "plant.h=0.5"], &["plant.h", "0.5"]),
        (&["run", "--in-process", "--set", "plant.m"], &["KEY=VALUE"]),
        (&["run", "--in-process", "--x0", "u", "--set", "plant.x0=d"], &["plant.x0", "--x0"]),
        (&["pil", "--set", "plant.l=abc"], &["plant.l"]),
        (&["simulate", "--set", "plant.mu=0.3"], &["plant.mu", "--mu"]),
        (&["simulate", "--set", "controller.pid.kp=[1,0]"], &["controller.pid.kp"]),
        (&["simulate", "--set", "plant.g=0"], &["plant.g", "0"]),
        (&["admissible", "--set", "plant.m=0.2"], &["plant.m", "plant.l, plant.h"]),
        (&["modes", "--set", "plant.sigma=-1"], &["plant.sigma", "-1"]),
        (&["poincare", "--set", "plant.alpha0=inf"], &["plant.alpha0", "inf"]),
        (&["sweep", "--set", "controller.hybrid.kp=1"], &["controller.hybrid.kp"]),
        (&["sweep", "--controller", "hybrid", "--set", "plant.mu=1"], &["plant.mu", "--mu"]),
        (&["zmax", "--set", "controller.target_z_t=0.1"], &["controller.target_z_t"]),
        (&["zmax", "--set", "controller.pid.kd=[-1,0]"], &["controller.pid.kd", "-1"]),
    ];
    for (args, needles) in cases {
        let mut full: Vec<&str> = args.to_vec();
        full.extend_from_slice(&["--out", o]);
        let (code, err) = sil_host(&full);
        assert_eq!(code, 2, "{full:?}: {err}");
        for n in *needles {
            assert!(err.contains(n), "{full:?}: `{n}` not in: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{full:?} wrote {}", out.display());
    }
}

#[test]
fn the_open_loop_analyses_take_the_arm_keys() {
    let dir = tempfile::tempdir().unwrap();
    let o = |n: &str| dir.path().join(n);
    let ok = |args: &[&str]| {
        let (code, err) = sil_host(args);
        assert_eq!(code, 0, "{args:?}: {err}");
    };
    ok(&["admissible", "--out", o("a0").to_str().unwrap()]);
    ok(&["admissible", "--set", "plant.l=0.25", "--out", o("a1").to_str().unwrap()]);
    let (a0, a1) = (json(&o("a0").join("admissible.json")), json(&o("a1").join("admissible.json")));
    assert_eq!(a1["params"]["l"], 0.25);
    assert_ne!(a0["z_r_dot_positive"], a1["z_r_dot_positive"]);
    let direct = analyses::admissible::compute_for(Params { l: 0.25, ..Params::paper() }, analyses::admissible::SCAN_STEPS).unwrap();
    let up: Vec<[f64; 2]> =
        direct.intervals(shared::ElbowBranch::Up, shared::SlipDirection::Positive).iter().map(|i| [i.lo, i.hi]).collect();
    assert_eq!(a1["z_r_dot_positive"]["elbow_up"], serde_json::json!(up));
    ok(&["modes", "--grid", "20", "--set", "plant.g=5", "--json", "--out", o("m").to_str().unwrap()]);
    ok(&[
        "sweep",
        "--mu",
        "0.6",
        "--v-belt",
        "-0.4",
        "--ics",
        "d",
        "--transient",
        "1",
        "--record",
        "1",
        "--set",
        "plant.m=0.2",
        "--out",
        o("s").to_str().unwrap(),
    ]);
    assert_eq!(json(&o("s").join("sweep.json"))["spec"]["params"]["m"], 0.2);
    // Resuming with other parameters is another sweep: refused.
    let (code, _) = sil_host(&[
        "sweep",
        "--mu",
        "0.6",
        "--v-belt",
        "-0.4",
        "--ics",
        "d",
        "--transient",
        "1",
        "--record",
        "1",
        "--set",
        "plant.m=0.3",
        "--out",
        o("s").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
}

#[test]
fn the_ideal_laws_use_the_opened_gains() {
    use analyses::zmax::{Combination, Criteria, Setting, ideal_setup};
    let base = Scenario::from_toml_with(
        rig::scenario::DEFAULT_TOML,
        &["controller.pid.kp=[150, 0]", "controller.hybrid.kp=400", "plant.m=0.2"].map(|a| a.parse().unwrap()),
    )
    .unwrap();
    let c =
        Criteria { duration_s: 3.0, move_time_s: 2.0, reach_tol_m: 5e-3, settle_tol_m: 1e-3, settle_window_s: 1.0, lift_off_gap_m: 0.0 };
    let pid = ideal_setup(
        &base,
        Combination { controller: firmware::ControllerKind::Pid, x0: plant::initial::PaperX0::D, setting: Setting::Ideal },
        0.05,
        &c,
    );
    assert_eq!((pid.pid.kp, pid.hybrid_kp, pid.params.m), ([150.0, 0.0], 400.0, 0.2));
    let u = ideal_setup(
        &base,
        Combination { controller: firmware::ControllerKind::Hybrid, x0: plant::initial::PaperX0::U, setting: Setting::Ideal },
        0.05,
        &c,
    );
    assert_eq!(u.hybrid_ki, 0.0);
    // The gains change the ideal run.
    let paper = ideal_setup(
        &Scenario::default_scenario(),
        Combination { controller: firmware::ControllerKind::Pid, x0: plant::initial::PaperX0::D, setting: Setting::Ideal },
        0.05,
        &c,
    );
    let a = analyses::ideal::simulate(&pid, |_| {}).unwrap();
    let b = analyses::ideal::simulate(&paper, |_| {}).unwrap();
    assert_ne!(a.samples.last().unwrap().u1, b.samples.last().unwrap().u1);
}
