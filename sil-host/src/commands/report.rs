//! `sil-host report`: every experiment of docs/model.md at a size that finishes in
//! minutes, gathered in one Markdown page (`report.md`) with every figure and
//! table, so a researcher sees the whole reproduction at once.
//!
//! Each experiment runs as its own `sil-host` command (this executable, with
//! `--json --out DIR/<id>`), exactly as a user would type it: the page gives the
//! command line of each, and its files stay next to the page. A failed
//! experiment does not stop the others; the page says what failed and why, and
//! the command exits 1 at the end.

use std::{
    fmt::Write as _,
    path::{Path, PathBuf},
    process::{Command, Stdio},
    time::Instant,
};

use serde::Serialize;
use serde_json::Value;

use crate::{
    cli::{ReportArgs, ReportSize},
    error::CliError,
    output::{OutputSet, progress_bar},
};

/// One command of an experiment.
#[derive(Debug, Clone)]
struct Step {
    /// Sub-folder of the report (and the step's name).
    id: &'static str,
    /// Arguments after `sil-host` (without `--out` and `--json`).
    args: Vec<String>,
}

/// One section of the report: an experiment of docs/model.md with its commands.
#[derive(Debug, Clone)]
struct Section {
    /// What the paper shows, and where.
    title: &'static str,
    /// docs/model.md experiment and paper figure or table.
    source: &'static str,
    /// The commands that reproduce it.
    steps: Vec<Step>,
}

fn step(id: &'static str, args: &[&str]) -> Step {
    Step { id, args: args.iter().map(|s| (*s).to_string()).collect() }
}

/// The paper's scenario files: `./scenarios`, else the repository's at build time.
fn scenario_dir() -> Option<PathBuf> {
    [PathBuf::from("scenarios"), Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")].into_iter().find(|p| p.is_dir())
}

/// The experiments, at the size asked for.
fn sections(size: ReportSize, scenarios: &Path) -> Vec<Section> {
    let quick = size == ReportSize::Quick;
    let mut v = vec![
        Section {
            title: "Contact modes on the belt",
            source: "docs/model.md experiment 1, paper Fig. 2",
            steps: vec![step("modes", &["modes", "--mu", "0.6", "--grid", if quick { "200" } else { "400" }])],
        },
        Section {
            title: "Admissible configurations",
            source: "docs/model.md experiment 2, paper Table II",
            steps: vec![step("admissible", &["admissible", "--mu", "0.6"])],
        },
        Section {
            title: "Open-loop bouncing from x0a",
            source: "docs/model.md experiments 3 and 4 (one run of the open-loop system, u = 0)",
            steps: vec![step("simulate", &["simulate", "--x0", "a", "--mu", "0.6", "--v-belt", "-0.4", "--duration", "10"])],
        },
    ];
    v.push(Section {
        title: "Open-loop two-parameter bifurcation diagram",
        source: "docs/model.md experiment 3, paper Fig. 3: persistent bouncing over (v_belt, mu), u = 0, from x0a and x0d, for e_n = 0, 0.2 and 0.5 (how the band moves with the impact law)",
        steps: vec![step(
            "sweep-open-loop",
            &if quick {
                vec!["sweep", "--v-belt-step", "0.01", "--transient", "100", "--record", "30", "--e-n", "0,0.2,0.5"]
            } else {
                vec!["sweep", "--e-n", "0,0.2,0.5"]
            },
        )],
    });
    v.push(Section {
        title: "Closed-loop bifurcation diagram (hybrid force/motion control)",
        source: "docs/model.md experiment 7, paper Fig. 9: experiment 3's sweep from x0d with the sampled hybrid firmware in the loop",
        steps: vec![step(
            "sweep-hybrid",
            &if quick {
                vec!["sweep", "--controller", "hybrid", "--ics", "d", "--v-belt-step", "0.05", "--transient", "20", "--record", "10"]
            } else {
                vec!["sweep", "--controller", "hybrid", "--ics", "d"]
            },
        )],
    });
    v.push(Section {
        title: "One-parameter bifurcation diagram (Poincaré section)",
        source: "docs/model.md experiment 4, paper Fig. 4: mu = 0.6 from x0a, theta1 where theta1_dot crosses 0 upwards",
        steps: vec![step(
            "poincare",
            &if quick {
                vec!["poincare", "--mu", "0.6", "--v-step", "0.004", "--transient", "150", "--record", "50"]
            } else {
                vec!["poincare", "--mu", "0.6"]
            },
        )],
    });
    v.push(Section {
        title: "Z_t,sliding: how far each controller drives the tip with no lift-off",
        source: "docs/model.md experiments 5 and 6 (the paper's continuous-time setting, --ideal, and our sampled firmware)",
        steps: vec![step("zmax", &["zmax", "--all"])],
    });
    v.push(Section {
        title: "PID and hybrid force/motion control in the SIL loop",
        source: "docs/model.md experiments 5 and 6 (paper Figs. 6 to 8): the firmware sampled at 1 kHz with docs/hardware.md's sensors",
        steps: ["pid-x0d", "pid-x0u", "hybrid-x0d", "hybrid-x0u"]
            .into_iter()
            .map(|name| Step {
                id: name,
                args: vec![
                    "run".into(),
                    "--in-process".into(),
                    "--scenario".into(),
                    scenarios.join(format!("{name}.toml")).to_string_lossy().into_owned(),
                ],
            })
            .collect(),
    });
    v
}

/// What one step produced.
#[derive(Debug, Clone, Serialize)]
struct StepResult {
    id: String,
    command: String,
    exit_code: Option<i32>,
    wall_s: f64,
    /// The command's JSON document, if it printed one.
    summary: Option<Value>,
    /// The end of its standard error when it failed.
    error: Option<String>,
    /// Files it wrote, relative to the report folder.
    files: Vec<String>,
}

/// `report.json`: the index of the page.
#[derive(Debug, Clone, Serialize)]
struct ReportIndex {
    size: &'static str,
    wall_s: f64,
    failed: usize,
    steps: Vec<StepResult>,
}

/// Runs `sil-host report`.
///
/// # Errors
/// [`CliError::BadInput`] when this executable cannot be found or the scenario
/// folder is missing; [`CliError::Io`] when the report cannot be written;
/// [`CliError::BadInput`]-free failure of an experiment is reported in the page
/// and turns into exit code 1 after everything is written.
pub fn run(args: &ReportArgs) -> Result<(), CliError> {
    let exe = std::env::current_exe().map_err(|e| CliError::BadInput(format!("cannot find this executable: {e}")))?;
    let scenarios = scenario_dir()
        .ok_or_else(|| CliError::BadInput("cannot find the scenarios/ folder: run `sil-host report` from the repository root".into()))?;
    let sections = sections(args.size, &scenarios);
    let mut out = OutputSet::new(&args.output.out)?;
    let n: usize = sections.iter().map(|s| s.steps.len()).sum();
    let progress = progress_bar(n as u64, "report", "experiments", args.output.json);
    let started = Instant::now();
    let mut results: Vec<Vec<StepResult>> = Vec::new();
    for section in &sections {
        let mut rs = Vec::new();
        for st in &section.steps {
            progress.set_message(st.id);
            rs.push(run_step(&exe, out.dir(), st));
            progress.inc(1);
        }
        results.push(rs);
    }
    progress.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();
    let failed = results.iter().flatten().filter(|r| r.exit_code != Some(0)).count();
    let size = match args.size {
        ReportSize::Quick => "quick",
        ReportSize::Paper => "paper",
    };
    let page = render_page(&sections, &results, size, wall_s);
    out.write_bytes("report.md", page.as_bytes())?;
    let index = ReportIndex { size, wall_s, failed, steps: results.into_iter().flatten().collect() };
    let json = serde_json::to_string_pretty(&index).map_err(|e| CliError::Io { path: out.path("report.json"), source: e.into() })?;
    out.write_bytes("report.json", json.as_bytes())?;
    let dir = out.dir().to_path_buf();
    out.commit()?;
    if args.output.json {
        println!("{json}");
    } else {
        println!(
            "report: {} experiments in {wall_s:.1} s wall, {failed} failed; open {}",
            index.steps.len(),
            dir.join("report.md").display()
        );
    }
    if failed > 0 {
        return Err(CliError::PartFailed(format!("{failed} experiment(s) failed; see {}", dir.join("report.md").display())));
    }
    Ok(())
}

fn run_step(exe: &Path, root: &Path, st: &Step) -> StepResult {
    let dir = root.join(st.id);
    let command = format!("sil-host {} --out {}", st.args.join(" "), dir.display());
    let t = Instant::now();
    let output = Command::new(exe).args(&st.args).arg("--out").arg(&dir).arg("--json").stdin(Stdio::null()).output();
    let wall_s = t.elapsed().as_secs_f64();
    let (exit_code, summary, error) = match output {
        Ok(o) => {
            let summary = serde_json::from_slice::<Value>(&o.stdout).ok();
            let error = (!o.status.success()).then(|| tail(&String::from_utf8_lossy(&o.stderr), 20));
            (o.status.code(), summary, error)
        }
        Err(e) => (None, None, Some(format!("cannot start {}: {e}", exe.display()))),
    };
    StepResult { id: st.id.into(), command, exit_code, wall_s, summary, error, files: files_in(root, &dir) }
}

fn tail(s: &str, lines: usize) -> String {
    let v: Vec<&str> = s.lines().collect();
    v[v.len().saturating_sub(lines)..].join("\n")
}

/// Files of `dir`, relative to `root`, sorted (hidden and partial files left out).
fn files_in(root: &Path, dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && !p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')))
        .filter_map(|p| p.strip_prefix(root).ok().map(PathBuf::from))
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn render_page(sections: &[Section], results: &[Vec<StepResult>], size: &str, wall_s: f64) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Reproduction of Marchese, Coraggio, Hogan, di Bernardo (ECC 2019)\n");
    let _ = writeln!(
        md,
        "Every experiment of docs/model.md from our own simulation (`sil-host report`, size `{size}`, {wall_s:.0} s of wall time). \
         Each section gives the command that made it; its files are in the folder of the same name.\n"
    );
    let _ = writeln!(md, "| experiment | source | status | wall time |\n|---|---|---|---|");
    for (s, rs) in sections.iter().zip(results) {
        for r in rs {
            let status = if r.exit_code == Some(0) { "ok".to_string() } else { format!("**failed** (exit {:?})", r.exit_code) };
            let _ = writeln!(md, "| {} ({}) | {} | {} | {:.1} s |", s.title, r.id, s.source, status, r.wall_s);
        }
    }
    for (s, rs) in sections.iter().zip(results) {
        let _ = writeln!(md, "\n## {}\n\n*{}*\n", s.title, s.source);
        if rs.len() > 1 {
            comparison_table(&mut md, rs);
        }
        for r in rs {
            if rs.len() > 1 {
                let _ = writeln!(md, "\n### {}\n", r.id);
            }
            let _ = writeln!(md, "```\n{}\n```\n", r.command);
            if let Some(e) = &r.error {
                let _ = writeln!(md, "**Failed** (exit code {:?}):\n\n```\n{e}\n```\n", r.exit_code);
            }
            if let Some(v) = &r.summary {
                scalar_table(&mut md, v);
                nested_tables(&mut md, v);
                sweep_bands(&mut md, v);
            }
            for f in r.files.iter().filter(|f| f.ends_with(".svg")) {
                let _ = writeln!(md, "![{f}]({f})\n");
            }
            let data: Vec<&String> = r.files.iter().filter(|f| !f.ends_with(".svg")).collect();
            if !data.is_empty() {
                let links: Vec<String> = data.iter().map(|f| format!("[{f}]({f})")).collect();
                let _ = writeln!(md, "Data: {}\n", links.join(", "));
            }
        }
    }
    md
}

/// The top-level numbers, strings and booleans of a command's JSON document.
fn scalar_table(md: &mut String, v: &Value) {
    let Some(map) = v.as_object() else { return };
    let rows: Vec<(String, String)> = map.iter().filter_map(|(k, v)| scalar(v).map(|s| (k.clone(), s))).collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(md, "| quantity | value |\n|---|---|");
    for (k, s) in rows {
        let _ = writeln!(md, "| `{k}` | {s} |");
    }
    md.push('\n');
}

/// Rows shown of a table from a JSON array (the files hold the rest).
const MAX_ROWS: usize = 60;

/// The top-level objects of scalars (one-row tables) and arrays of objects
/// (tables, one row per element) of a command's JSON document.
fn nested_tables(md: &mut String, v: &Value) {
    let Some(map) = v.as_object() else { return };
    for (key, value) in map {
        let rows: Vec<&serde_json::Map<String, Value>> = match value {
            Value::Object(o) if !o.is_empty() && o.values().all(|x| scalar(x).is_some() || x.is_null()) => vec![o],
            Value::Array(a) if !a.is_empty() && a.iter().all(Value::is_object) => a.iter().filter_map(Value::as_object).collect(),
            _ => continue,
        };
        let mut columns: Vec<&String> = Vec::new();
        for r in &rows {
            for (k, x) in r.iter() {
                if (scalar(x).is_some() || x.is_null()) && !columns.contains(&k) {
                    columns.push(k);
                }
            }
        }
        if columns.is_empty() {
            continue;
        }
        let _ = writeln!(md, "`{key}`:\n");
        let _ =
            writeln!(md, "| {} |\n|{}", columns.iter().map(|c| c.as_str()).collect::<Vec<_>>().join(" | "), "---|".repeat(columns.len()));
        for r in rows.iter().take(MAX_ROWS) {
            let cells: Vec<String> = columns.iter().map(|c| r.get(*c).and_then(scalar).unwrap_or_else(|| "-".into())).collect();
            let _ = writeln!(md, "| {} |", cells.join(" | "));
        }
        if rows.len() > MAX_ROWS {
            let _ = writeln!(md, "\n({} more rows in the files)", rows.len() - MAX_ROWS);
        }
        md.push('\n');
    }
}

/// A sweep's summary (`results.cases`): per impact law, `e_n` and initial
/// condition, the critical `mu` and the belt-speed bands of persistent bouncing for
/// each `mu`, so the page shows how the band moves with the impact law.
fn sweep_bands(md: &mut String, v: &Value) {
    let Some(cases) = v.pointer("/results/cases").and_then(Value::as_array) else { return };
    let _ = writeln!(md, "Persistent bouncing, by impact law and `e_n`:\n");
    let _ = writeln!(md, "| impact law | e_n | initial condition | critical mu | bands of v_belt (m/s) per mu |\n|---|---|---|---|---|");
    for case in cases {
        let law = case.get("impact_law").and_then(scalar).unwrap_or_default();
        let e_n = case.get("e_n").and_then(scalar).unwrap_or_default();
        for ic in case.get("ics").and_then(Value::as_array).into_iter().flatten() {
            let name = ic.get("ic").and_then(scalar).unwrap_or_default();
            let critical = ic.get("critical_mu").and_then(scalar).unwrap_or_else(|| "none".into());
            let per_mu: Vec<String> = ic
                .get("per_mu")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .filter_map(|m| {
                    let bands: Vec<String> = m
                        .get("bands")?
                        .as_array()?
                        .iter()
                        .filter_map(|b| Some(format!("[{}, {}]", scalar(b.get("v_min")?)?, scalar(b.get("v_max")?)?)))
                        .collect();
                    (!bands.is_empty()).then(|| format!("{}: {}", m.get("mu").and_then(scalar).unwrap_or_default(), bands.join(" ")))
                })
                .collect();
            let bands = if per_mu.is_empty() { "none".to_string() } else { per_mu.join("; ") };
            let _ = writeln!(md, "| {law} | {e_n} | {name} | {critical} | {bands} |");
        }
    }
    md.push('\n');
}

/// The runs of a section side by side: the scalar fields they share.
fn comparison_table(md: &mut String, rs: &[StepResult]) {
    let objects: Vec<&serde_json::Map<String, Value>> = rs.iter().filter_map(|r| r.summary.as_ref()?.as_object()).collect();
    let Some(first) = objects.first() else { return };
    let keys: Vec<&String> =
        first.keys().filter(|k| objects.iter().all(|o| o.get(*k).and_then(scalar).is_some()) && *k != "scenario").collect();
    let _ = write!(md, "| quantity |");
    for r in rs.iter().filter(|r| r.summary.is_some()) {
        let _ = write!(md, " {} |", r.id);
    }
    let _ = writeln!(md, "\n|---|{}", "---|".repeat(objects.len()));
    for k in keys {
        let _ = write!(md, "| `{k}` |");
        for o in &objects {
            let _ = write!(md, " {} |", o.get(k).and_then(scalar).unwrap_or_default());
        }
        md.push('\n');
    }
    md.push('\n');
}

fn scalar(v: &Value) -> Option<String> {
    match v {
        Value::Number(n) => Some(match n.as_f64() {
            Some(x) if n.is_f64() => format!("{x:.6}").trim_end_matches('0').trim_end_matches('.').to_string(),
            _ => n.to_string(),
        }),
        Value::String(s) if s.len() <= 200 => Some(s.replace('|', "\\|")),
        Value::Bool(b) => Some(b.to_string()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_show_scalars_and_escape_pipes() {
        let v: Value = serde_json::json!({"mu": 0.6, "n": 3, "what": "a|b", "list": [1, 2], "ok": true});
        let mut md = String::new();
        scalar_table(&mut md, &v);
        assert!(md.contains("| `mu` | 0.6 |") && md.contains("| `n` | 3 |") && md.contains("a\\|b") && md.contains("| `ok` | true |"));
        assert!(!md.contains("list"), "arrays are not scalars");
    }

    #[test]
    fn arrays_of_objects_and_objects_of_scalars_become_tables() {
        let v: Value = serde_json::json!({
            "counts": {"periodic": 3, "chaotic": 2},
            "bands": [{"class": "periodic", "period": 2}, {"class": "chaotic", "period": null}],
            "deep": {"a": {"b": 1}},
        });
        let mut md = String::new();
        nested_tables(&mut md, &v);
        assert!(md.contains("| chaotic | periodic |") && md.contains("| 2 | 3 |"), "{md}");
        assert!(md.contains("| class | period |") && md.contains("| periodic | 2 |") && md.contains("| chaotic | - |"), "{md}");
        assert!(!md.contains("deep"), "objects of objects are left to the files: {md}");
    }

    #[test]
    fn sweep_bands_show_critical_mu_and_bands_per_case() {
        let v: Value = serde_json::json!({"results": {"cases": [
            {"impact_law": "newton", "e_n": 0.5, "ics": [{"ic": "x0a", "critical_mu": 0.4, "per_mu": [
                {"mu": 0.3, "bands": []},
                {"mu": 0.4, "bands": [{"v_min": -0.96, "v_max": -0.31, "points": 66}]}
            ]}]},
            {"impact_law": "newton", "e_n": 0.0, "ics": [{"ic": "x0a", "critical_mu": null, "per_mu": [{"mu": 0.4, "bands": []}]}]}
        ]}});
        let mut md = String::new();
        sweep_bands(&mut md, &v);
        assert!(md.contains("| newton | 0.5 | x0a | 0.4 | 0.4: [-0.96, -0.31] |"), "{md}");
        assert!(md.contains("| newton | 0 | x0a | none | none |"), "{md}");
    }

    #[test]
    fn comparison_table_keeps_shared_scalar_keys() {
        let r = |id: &str, v: Value| StepResult {
            id: id.into(),
            command: String::new(),
            exit_code: Some(0),
            wall_s: 0.0,
            summary: Some(v),
            error: None,
            files: vec![],
        };
        let rs = [r("a", serde_json::json!({"x": 1, "y": 2})), r("b", serde_json::json!({"x": 3, "z": 4}))];
        let mut md = String::new();
        comparison_table(&mut md, &rs);
        assert!(md.contains("| `x` | 1 | 3 |"), "{md}");
        assert!(!md.contains("`y`") && !md.contains("`z`"), "{md}");
    }
}
