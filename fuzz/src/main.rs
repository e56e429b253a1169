//! `fuzz`: runs the harnesses of `painleve-fuzz` (docs/fuzzing.md).
//!
//! ```sh
//! cargo run --release -p painleve-fuzz -- firmware-step --cases 1000000 --seed 7
//! cargo run --release -p painleve-fuzz -- all --cases 20000 --json
//! cargo run --release -p painleve-fuzz -- scenario --seed 7 --case 4711   # replay one case
//! ```
//!
//! Exit codes: 0 every case passed, 1 a case failed (the shrunk input, the seed
//! and the replay command are printed), 2 bad command line.

use std::{io::IsTerminal, process::ExitCode};

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use painleve_fuzz::{Report, Target, on_harness_thread, quiet_panics};

/// Seeded, reproducible fuzzing of the firmware step, the PIL decoder and the scenario parser.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Cli {
    /// What to fuzz.
    target: Which,
    /// Cases per target.
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(1..))]
    cases: u64,
    /// Seed of the run: case K of seed S is the same input on every machine.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Run only case K of the seed (replays a failure); `--cases` is ignored.
    #[arg(long, value_name = "K")]
    case: Option<u64>,
    /// Print the input of case K (`--case`) without running it (a case that aborts
    /// the process, such as a stack overflow, cannot report itself).
    #[arg(long, requires = "case")]
    show: bool,
    /// One line of JSON on standard output: cases, seconds, cases/s, failures per target.
    #[arg(long)]
    json: bool,
}

/// A target on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Which {
    /// `firmware::Firmware::step` under hostile frames and times.
    FirmwareStep,
    /// `firmware::pil::decode` under mutated and random frames.
    PilDecode,
    /// `rig::scenario::Scenario::from_toml_with` under hostile documents and `--set`s.
    Scenario,
    /// The three, one after the other.
    All,
}

impl Which {
    fn targets(self) -> Vec<Target> {
        match self {
            Self::FirmwareStep => vec![Target::FirmwareStep],
            Self::PilDecode => vec![Target::PilDecode],
            Self::Scenario => vec![Target::Scenario],
            Self::All => Target::ALL.to_vec(),
        }
    }
}

fn progress_bar(target: Target, count: u64, json: bool) -> ProgressBar {
    if json || count < 2 || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(count).with_prefix(target.name());
    let style = ProgressStyle::with_template("{prefix:>13} [{bar:30}] {human_pos}/{human_len} {per_sec} eta {eta}")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    bar.set_style(style);
    bar
}

fn json_line(reports: &[Report]) -> String {
    let targets: Vec<serde_json::Value> = reports
        .iter()
        .map(|r| {
            let failure = r.failure.as_ref().map(|f| {
                serde_json::json!({
                    "case": f.case,
                    "message": f.message,
                    "input": f.input,
                    "replay": replay(r),
                })
            });
            serde_json::json!({
                "target": r.target,
                "seed": r.seed,
                "cases": r.cases,
                "seconds": r.seconds,
                "cases_per_s": r.cases_per_second(),
                "failures": usize::from(r.failure.is_some()),
                "failure": failure,
            })
        })
        .collect();
    let cases: u64 = reports.iter().map(|r| r.cases).sum();
    let seconds: f64 = reports.iter().map(|r| r.seconds).sum();
    let failures = reports.iter().filter(|r| r.failure.is_some()).count();
    serde_json::json!({
        "cases": cases,
        "seconds": seconds,
        "cases_per_s": if seconds > 0.0 { cases as f64 / seconds } else { 0.0 },
        "failures": failures,
        "targets": targets,
    })
    .to_string()
}

fn replay(r: &Report) -> String {
    let case = r.failure.as_ref().map_or(0, |f| f.case);
    format!("cargo run --release -p painleve-fuzz -- {} --seed {} --case {case}", r.target, r.seed)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let (true, Some(k)) = (cli.show, cli.case) {
        for target in cli.target.targets() {
            println!("{} case {k} of seed {}:\n{}", target.name(), cli.seed, target.show(cli.seed, k));
        }
        return ExitCode::SUCCESS;
    }
    quiet_panics();
    let mut reports = Vec::new();
    for target in cli.target.targets() {
        let (first, count) = cli.case.map_or((0, cli.cases), |k| (k, 1));
        let bar = progress_bar(target, count, cli.json);
        let b = bar.clone();
        let seed = cli.seed;
        let report = on_harness_thread(move || target.run(seed, first, count, &mut |done| b.set_position(done)));
        bar.finish_and_clear();
        if !cli.json {
            println!(
                "{}: {} cases in {:.2} s ({:.0} cases/s), seed {}: {}",
                target.name(),
                report.cases,
                report.seconds,
                report.cases_per_second(),
                report.seed,
                if report.failure.is_some() { "FAILED" } else { "ok" }
            );
            if let Some(f) = &report.failure {
                eprintln!(
                    "\n{} failed at case {} (seed {}), after {} shrinking steps:",
                    target.name(),
                    f.case,
                    report.seed,
                    f.shrink_steps
                );
                eprintln!("  {}", f.message.replace('\n', "\n  "));
                eprintln!("minimal input:\n{}", f.input);
                eprintln!("replay: {}\n", replay(&report));
            }
        }
        reports.push(report);
    }
    if cli.json {
        println!("{}", json_line(&reports));
    }
    if reports.iter().any(|r| r.failure.is_some()) { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}
