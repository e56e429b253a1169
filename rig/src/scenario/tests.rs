//! Reading and validating scenarios: errors that name the key, overrides, the
//! legacy key, the limits of the firmware's `f32`.

use firmware::ControllerKind;
use plant::initial::PaperX0;

use super::*;
use crate::overrides::Override;

#[test]
fn the_embedded_default_parses_and_matches_the_issue() {
    let s = Scenario::from_toml(DEFAULT_TOML).unwrap();
    assert_eq!((s.plant.mu, s.plant.v_belt, s.plant.x0), (0.6, -0.4, PaperX0::D));
    assert_eq!((s.controller.kind, s.controller.target_z_t, s.controller.f_n_ref), (ControllerKind::Hybrid, 0.10, 10.0));
    assert_eq!((s.timing.rate_hz, s.timing.duration_s), (1000.0, 10.0));
}

#[test]
fn errors_name_the_bad_key_and_value() {
    let bad_key = DEFAULT_TOML.replace("mu = 0.6\n", "mu = 0.6\nmuu = 1\n");
    let e = Scenario::from_toml(&bad_key).unwrap_err().to_string();
    assert!(e.contains("muu"), "{e}");
    let bad_value = DEFAULT_TOML.replace("rate_hz = 1000.0", "rate_hz = 50.0");
    let e = Scenario::from_toml(&bad_value).unwrap_err().to_string();
    assert!(e.contains("timing.rate_hz") && e.contains("50"), "{e}");
    let bad_type = DEFAULT_TOML.replace("e_n = 0.2", "e_n = \"high\"");
    let e = Scenario::from_toml(&bad_type).unwrap_err().to_string();
    assert!(e.contains("e_n"), "{e}");
    let bad_fault = format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"stuck_sensor\"\nat_s = 1.0\n");
    let e = Scenario::from_toml(&bad_fault).unwrap_err().to_string();
    assert!(e.contains("faults[0]") && e.contains("signal"), "{e}");
    let bad_fault_kind = format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"gremlins\"\nat_s = 1.0\n");
    let e = Scenario::from_toml(&bad_fault_kind).unwrap_err().to_string();
    assert!(e.contains("gremlins"), "{e}");
    let bad_kind = DEFAULT_TOML.replace("kind = \"hybrid\"", "kind = \"lqr\"");
    assert!(Scenario::from_toml(&bad_kind).unwrap_err().to_string().contains("controller.kind"));
    let bad_cpu = DEFAULT_TOML.replace("realtime_cpu = \"last\"", "realtime_cpu = \"first\"");
    let e = Scenario::from_toml(&bad_cpu).unwrap_err().to_string();
    assert!(e.contains("rig.realtime_cpu") && e.contains("first"), "{e}");
    let bad_prio = DEFAULT_TOML.replace("realtime_fifo_priority = 10", "realtime_fifo_priority = 100");
    let e = Scenario::from_toml(&bad_prio).unwrap_err().to_string();
    assert!(e.contains("rig.realtime_fifo_priority") && e.contains("100"), "{e}");
}

/// Issue 27: a NUL or ESC in the name made `trace.svg` ill-formed XML and reached
/// the terminal raw. Refused, and the refusal shows it escaped.
#[test]
fn control_characters_in_the_name_are_refused_and_shown_escaped() {
    for bad in ["a\u{0}b", "run\u{1b}[2J", "tab\there", "line\nbreak", "del\u{7f}"] {
        let toml = DEFAULT_TOML.replacen("name = \"hybrid-x0d\"", &format!("name = {}", toml::Value::from(bad)), 1);
        assert_ne!(toml, DEFAULT_TOML, "the default scenario names itself `hybrid-x0d`");
        let e = Scenario::from_toml(&toml).unwrap_err().to_string();
        assert!(e.contains("name") && e.contains("control character"), "{e}");
        assert!(!e.chars().any(char::is_control), "the message carries no control character: {e:?}");
    }
    // Issue 39: U+FFFE and U+FFFF (noncharacters, not XML 1.0 characters) made
    // `trace.svg` ill-formed too.
    for bad in ["a\u{FFFE}b", "end\u{FFFF}", "x\u{FDD0}", "plane1\u{1FFFF}"] {
        let toml = DEFAULT_TOML.replacen("name = \"hybrid-x0d\"", &format!("name = {}", toml::Value::from(bad)), 1);
        let e = Scenario::from_toml(&toml).unwrap_err().to_string();
        assert!(e.contains("name") && e.contains("noncharacter"), "{e}");
    }
    // Issue 52, 8: U+202E (right-to-left override) showed the name's end reversed;
    // every format character (category Cf) is refused, shown escaped.
    for bad in ["run\u{202E}dcba", "a\u{2066}b", "zero\u{200B}width", "bom\u{FEFF}", "tag\u{E0041}", "soft\u{AD}"] {
        let toml = DEFAULT_TOML.replacen("name = \"hybrid-x0d\"", &format!("name = {}", toml::Value::from(bad)), 1);
        let e = Scenario::from_toml(&toml).unwrap_err().to_string();
        assert!(e.contains("name") && e.contains("format character"), "{e}");
        assert!(!e.contains(bad), "the name is shown escaped: {e:?}");
    }
    let fine = DEFAULT_TOML.replacen("name = \"hybrid-x0d\"", "name = \"Zürich run — 2 \u{FFFD}\"", 1);
    assert_eq!(Scenario::from_toml(&fine).unwrap().name, "Zürich run — 2 \u{FFFD}");
}

fn set(arg: &str) -> Override {
    arg.parse().unwrap()
}

/// Issue 52, 6: a scenario file's array with extra elements ran with them
/// dropped, while `--set` refused the same values. Every array is strict: a wrong
/// length or a wrong-typed element is an error naming the key.
#[test]
fn arrays_of_a_wrong_length_or_type_are_refused_naming_the_key() {
    let cases = [
        ("[controller.pid]", "kp = [200.0, 0.0, \"x\"]", "controller.pid.kp"),
        ("[controller.pid]", "kp = [200.0, 0.0, 1.0]", "controller.pid.kp"),
        ("[controller.pid]", "ki = [1.0]", "controller.pid.ki"),
        ("[controller.pid]", "kd = [1.0, \"x\"]", "controller.pid.kd"),
        ("[board.load_cell]", "zero_counts = [2048.0, 2048.0, \"junk\", {a=1}]", "board.load_cell.zero_counts"),
        ("[board.load_cell]", "zero_counts = [2048.0]", "board.load_cell.zero_counts"),
    ];
    for (table, line, key) in cases {
        // In a file: the default scenario's own text with the key's line replaced
        // (its other lines as they are), the board's table added.
        let field = key.rsplit_once('.').unwrap().1;
        let kept: Vec<&str> = DEFAULT_TOML.lines().filter(|l| !l.starts_with(&format!("{field} ="))).collect();
        let mut file = kept.join("\n") + "\n";
        if file.contains(&format!("\n{table}")) {
            let header = file.lines().find(|l| l.starts_with(table)).unwrap().to_string();
            file = file.replacen(&header, &format!("{header}\n{line}"), 1);
        } else {
            file += &format!("\n{table}\n{line}\n");
        }
        let e = Scenario::from_toml(&file).expect_err(line).to_string();
        assert!(e.contains(key), "{line}: {e}");
        if line.matches(',').count() >= 2 {
            assert!(e.contains("more than the key takes") || e.contains("where the key takes 2"), "{line}: {e}");
        }
        // The same value by `--set`.
        let value = line.split_once(" = ").unwrap().1;
        let e = Scenario::default_scenario().with_overrides(&[set(&format!("{key}={value}"))]).unwrap_err();
        assert!(e.to_string().contains(key), "--set {key}={value}: {e}");
    }
    // The right lengths still read, from a file and from the default.
    let file = DEFAULT_TOML.to_string() + "\n[board.load_cell]\nzero_counts = [2000.0, 2100.0]\n";
    assert_eq!(Scenario::from_toml(&file).unwrap().board.load_cell.zero_counts, [2000.0, 2100.0]);
    assert_eq!(Scenario::from_toml(DEFAULT_TOML).unwrap().controller.pid.kp, [200.0, 0.0]);
}

/// Issue 27: a fault in the run's last half period was accepted and never acted.
/// The load applies the run's own rule (`Fault::periods`).
#[test]
fn a_fault_that_cannot_act_is_refused_at_load() {
    let fault = |at_s: f64| format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"drop_command\"\nat_s = {at_s}\n");
    // The default runs 10 s at 1 kHz: periods 0 to 9999, the last at 9.999 s.
    assert!(Scenario::from_toml(&fault(9.999)).is_ok());
    for never in [9.9993, 9.9995, 10.0, 11.0] {
        let e = Scenario::from_toml(&fault(never)).unwrap_err().to_string();
        assert!(e.contains("faults[0]") && e.contains("never act") && e.contains("last period is 9999"), "{never}: {e}");
    }
}

/// docs/rig.md "Overrides": `--set faults=[...]` replaces the file's faults and
/// is validated as in a file.
#[test]
fn faults_can_be_set_and_are_validated() {
    let s = Scenario::from_toml_with(DEFAULT_TOML, &[set("faults=[{kind=\"stall\",at_s=0.5,duration_s=0.05}]")]).unwrap();
    assert_eq!(s.faults.len(), 1);
    let with_two = format!("{DEFAULT_TOML}\n[[faults]]\nkind = \"stall\"\nat_s = 1.0\n[[faults]]\nkind = \"stall\"\nat_s = 2.0\n");
    assert_eq!(Scenario::from_toml_with(&with_two, &[set("faults=[]")]).unwrap().faults.len(), 0);
    let e = Scenario::from_toml_with(DEFAULT_TOML, &[set("faults=[{kind=\"gremlin\",at_s=0.5}]")]).unwrap_err().to_string();
    assert!(e.contains("faults[0].kind") && e.contains("gremlin") && e.contains("--set"), "{e}");
}

#[test]
fn overrides_reach_the_scenario_and_errors_name_the_key() {
    let s = Scenario::from_toml_with(DEFAULT_TOML, &[set("plant.m=0.24"), set("controller.pid.kp=[150,1]")]).unwrap();
    assert_eq!((s.plant.m, s.controller.pid.kp), (0.24, [150.0, 1.0]));
    assert_eq!(s, Scenario::default_scenario().with_overrides(&[set("plant.m=0.24"), set("controller.pid.kp=[150,1]")]).unwrap());
    let err = |args: &[&str]| {
        let o: Vec<Override> = args.iter().map(|a| set(a)).collect();
        Scenario::from_toml_with(DEFAULT_TOML, &o).unwrap_err().to_string()
    };
    let e = err(&["plant.m=-1"]);
    assert!(e.contains("`plant.m` = -1") && e.contains("> 0"), "{e}");
    let e = err(&["plant.m=nan"]);
    assert!(e.contains("`plant.m` = NaN"), "{e}");
    let e = err(&["plant.mass=1"]);
    assert!(e.contains("mass") && e.contains("plant.mass=1"), "{e}");
    let e = err(&["controller.pid.kp=[1]"]);
    assert!(e.contains("controller.pid.kp"), "{e}");
    let e = err(&["controller.hybrid.kd=-3"]);
    assert!(e.contains("controller.hybrid.kd") && e.contains("-3"), "{e}");
    let e = err(&["plant.m=1", "plant.m=2"]);
    assert!(e.contains("twice"), "{e}");
    let e = err(&["plant.m.x=1"]);
    assert!(e.contains("`plant.m` is not a table"), "{e}");
    let e = err(&["controller.model.l=0.1"]);
    assert!(e.contains("controller.model.h"), "{e}");
}

/// Regression (the `scenario` fuzzing harness, docs/fuzzing.md): values the
/// firmware's f32 cannot hold were accepted, then refused by the firmware at the
/// start of a run (or of every zmax and sweep trial); they are refused here,
/// naming the key. Accepted values give a configuration the firmware accepts.
#[test]
fn values_beyond_the_firmwares_f32_are_refused_naming_the_key() {
    let h_onto_2l = format!("plant.h={:?}", (2.0f64 * 0.21).next_down());
    let z_onto_2l = format!("controller.target_z_t={:?}", (2.0f64 * 0.21).next_down());
    for (arg, key) in [
        ("controller.hybrid.kp=1e39", "controller.hybrid.kp"),
        ("controller.pid.ki=[1e39, 0]", "controller.pid.ki"),
        ("plant.m=1e-50", "plant.m"),
        ("plant.alpha0=-1e39", "plant.alpha0"),
        ("controller.model.g=1e-46", "controller.model.g"),
        ("controller.move_time_s=1e-300", "controller.move_time_s"),
        (h_onto_2l.as_str(), "plant.h"),
        (z_onto_2l.as_str(), "controller.target_z_t"),
    ] {
        let e = Scenario::from_toml_with(DEFAULT_TOML, &[set(arg)]).unwrap_err().to_string();
        assert!(e.contains(&format!("`{key}`")), "{arg}: {e}");
    }
    for arg in ["controller.hybrid.kp=3.4e38", "plant.m=1e-44", "controller.move_time_s=1e-44", "controller.model.l=0.19"] {
        let s = Scenario::from_toml_with(DEFAULT_TOML, &[set(arg)]).unwrap_or_else(|e| panic!("{arg}: {e}"));
        firmware::Firmware::new(crate::setup::firmware_config(&s)).unwrap_or_else(|e| panic!("{arg}: {e}"));
    }
}

/// Regression (the `scenario` fuzzing harness): the TOML reader's nesting limit
/// said only "recursion limit", neither where nor what; the error says what.
#[test]
fn nesting_beyond_the_toml_readers_limit_is_said() {
    let deep = format!("{}\n[zz{}]\na = 1\n", DEFAULT_TOML, ".x".repeat(90));
    let e = Scenario::from_toml(&deep).unwrap_err().to_string();
    assert!(e.starts_with("the scenario is not valid TOML: keys, tables or arrays nested 80 levels"), "{e}");
}

#[test]
fn the_legacy_hybrid_ki_key_is_read_as_hybrid_ki() {
    let old = DEFAULT_TOML.replace("[controller]\n", "[controller]\nhybrid_ki = 321.0\n");
    assert_eq!(Scenario::from_toml(&old).unwrap().controller.hybrid.ki, Some(321.0));
    let both = old.replace("kd = 900.0 ", "ki = 1.0\nkd = 900.0 ");
    assert!(Scenario::from_toml(&both).is_err());
    // An override of the new key wins over the file's old one.
    assert_eq!(Scenario::from_toml_with(&old, &[set("controller.hybrid.ki=5")]).unwrap().controller.hybrid.ki, Some(5.0));
    assert_eq!(Scenario::from_toml_with(DEFAULT_TOML, &[set("controller.hybrid_ki=7")]).unwrap().controller.hybrid.ki, Some(7.0));
}

#[test]
fn realtime_cpu_accepts_last_none_and_numbers() {
    let pin = |v: &str| RigSection { realtime_cpu: v.into(), ..RigSection::default() }.realtime_pin();
    assert_eq!(pin("last"), Ok(CpuPin::Last));
    assert_eq!(pin("none"), Ok(CpuPin::None));
    assert_eq!(pin("3"), Ok(CpuPin::Cpu(3)));
    assert!(pin("-1").is_err() && pin("1024").is_err() && pin("").is_err());
}
