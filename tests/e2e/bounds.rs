//! Issue 15, "Bounds on input": accepted-but-absurd values are refused with exit 2,
//! the key or flag named, nothing written.

use std::path::Path;

fn run(args: &[&str]) -> i32 {
    let mut full = vec!["sil-host"];
    full.extend_from_slice(args);
    sil_host::run(full)
}

fn scenario(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> String {
    let p = dir.join(name);
    std::fs::write(&p, edit(rig::scenario::DEFAULT_TOML.to_string())).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn absurd_flags_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [&[&str]; 6] = [
        &["simulate", "--mu", "1e300"],
        &["simulate", "--v-belt=-1e6"],
        &["simulate", "--x0-deg=1e308,0,-35.1,0"],
        &["simulate", "--x0-deg=0,1e9,-35.1,0"],
        &["simulate", "--rtol", "1e-300", "--atol", "1e-300"],
        &["poincare", "--mu", "11", "--v-belt=-0.5"],
    ];
    for (i, args) in cases.iter().enumerate() {
        let out = dir.path().join(format!("out{i}"));
        let mut a = args.to_vec();
        let o = out.to_string_lossy().into_owned();
        a.extend(["--out", &o]);
        assert_eq!(run(&a), 2, "{args:?}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
    // At the bounds they are accepted.
    let out = dir.path().join("ok");
    assert_eq!(run(&["simulate", "--mu", "10", "--v-belt=-5", "--duration", "0.01", "--out", out.to_str().unwrap()]), 0);
}

#[test]
fn absurd_scenarios_are_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let faults = |n: usize| (0..n).map(|_| "\n[[faults]]\nkind = \"drop_command\"\nat_s = 1.0\n").collect::<String>();
    let cases: Vec<(&str, String)> = vec![
        ("plant.mu", scenario(dir.path(), "mu.toml", |t| t.replace("mu = 0.6", "mu = 1e300"))),
        ("name", scenario(dir.path(), "name.toml", |t| t.replacen("name = \"", &format!("name = \"{}", "x".repeat(100)), 1))),
        ("faults", scenario(dir.path(), "many.toml", |t| t + &faults(1001))),
        ("faults[0]", scenario(dir.path(), "late.toml", |t| t + "\n[[faults]]\nkind = \"drop_command\"\nat_s = 100.0\n")),
        ("faults[0]", scenario(dir.path(), "long.toml", |t| t + "\n[[faults]]\nkind = \"drop_command\"\nat_s = 1.0\nduration_s = 1e308\n")),
        ("plant.rtol", scenario(dir.path(), "rtol.toml", |t| t.replace("rtol = 1e-9", "rtol = 1e-300"))),
    ];
    for (key, s) in &cases {
        let out = dir.path().join("out");
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_sil-host"))
            .args(["run", "--in-process", "--scenario", s, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{key}: {err}");
        let named = key.split('[').next().unwrap_or(key);
        assert!(err.contains(named), "{key} not named: {err}");
        assert!(!out.exists(), "{key}: nothing written");
    }
}
