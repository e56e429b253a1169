//! `sil-host run`: a closed-loop SIL run of a scenario.
//!
//! Writes `trace.csv` (one row per control period), `summary.json` and
//! `trace.svg` (tip position against its reference, normal force, torques and
//! contact mode against time). A run that fails part way still writes every
//! period up to the failure and exits with code 1.

use std::{io::Write, time::Instant};

use serde::Serialize;

use crate::{
    cli::{ControllerArg, PaperX0, RunArgs},
    error::CliError,
    output::{OutputSet, progress_bar, write_csv},
    plot::{self, Panel, Series, colors},
    sil::{
        in_process::{self, LiftOffStats, PeriodRecord},
        scenario::Scenario,
    },
};

/// `summary.json` of a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// `ok` or `failed`.
    pub status: &'static str,
    /// The error, if the run failed part way.
    pub error: Option<String>,
    /// Scenario name.
    pub scenario: String,
    /// `hybrid` or `pid`.
    pub controller: String,
    /// `in-process` (the iceoryx2 transport arrives with the SIL issue).
    pub transport: &'static str,
    /// Control periods run.
    pub periods: usize,
    /// Lift-off statistics.
    #[serde(flatten)]
    pub lift_off: LiftOffStats,
    /// Deadline misses counted by the firmware.
    pub deadline_misses: usize,
    /// RMS of `z_t - z_t*` over the run, m.
    pub rms_tracking_error_m: f64,
    /// `z_t` at the end, m.
    pub final_z_t_m: f64,
    /// Wall-clock time of the loop, s.
    pub wall_s: f64,
    /// Simulated seconds per wall second.
    pub realtime_factor: f64,
    /// The scenario as run (after command-line overrides).
    pub scenario_used: Scenario,
}

fn load_scenario(args: &RunArgs) -> Result<Scenario, CliError> {
    let mut s = match &args.scenario {
        Some(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| CliError::BadInput(format!("cannot read scenario {}: {e}", path.display())))?;
            Scenario::from_toml(&text)?
        }
        None => Scenario::default_scenario(),
    };
    if let Some(c) = args.controller {
        s.controller.kind = match c {
            ControllerArg::Pid => "pid",
            ControllerArg::Hybrid => "hybrid",
        }
        .into();
    }
    if let Some(x0) = args.x0 {
        s.plant.x0 = match x0 {
            PaperX0::A => "a",
            PaperX0::D => "d",
            PaperX0::U => "u",
        }
        .into();
    }
    if let Some(z) = args.target_zt {
        s.controller.target_z_t = z;
    }
    if let Some(d) = args.duration {
        s.timing.duration_s = d;
    }
    if let Some(seed) = args.seed {
        s.sensors.seed = seed;
    }
    s.validate()?;
    Ok(s)
}

/// Runs `sil-host run`.
///
/// # Errors
/// Bad scenario or overrides (exit 2, nothing written); a failure part way (exit 1,
/// everything up to it written); I/O or plotting failures.
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let scenario = load_scenario(args)?;
    // Check the plant and firmware set-up before touching the output folder.
    in_process::plant_for(&scenario).map_err(CliError::Sim)?;
    firmware::Firmware::new(in_process::firmware_config(&scenario))
        .map_err(|e| CliError::BadInput(format!("firmware configuration: {e}")))?;
    let mut out = OutputSet::new(&args.output.out)?;
    let n = (scenario.timing.duration_s * scenario.timing.rate_hz).round() as u64;
    let progress = progress_bar(n, "SIL run", "periods", args.output.json);
    let started = Instant::now();
    let (records, failure) = in_process::run(&scenario, |k, _| {
        if k % 500 == 0 {
            progress.set_position(k as u64);
        }
    });
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();

    write_csv(&mut out, "trace.csv", &records)?;
    let svg = out.stage("trace.svg");
    draw(&svg, &scenario, &records)?;
    let rms = if records.is_empty() {
        0.0
    } else {
        (records.iter().map(|r| (r.z_t - r.z_t_ref).powi(2)).sum::<f64>() / records.len() as f64).sqrt()
    };
    let simulated = records.len() as f64 / scenario.timing.rate_hz;
    let summary = RunSummary {
        status: if failure.is_some() { "failed" } else { "ok" },
        error: failure.as_ref().map(|e| e.to_string()),
        scenario: scenario.name.clone(),
        controller: scenario.controller.kind.clone(),
        transport: "in-process",
        periods: records.len(),
        lift_off: in_process::lift_off_stats(&records),
        deadline_misses: records.iter().filter(|r| r.deadline_miss).count(),
        rms_tracking_error_m: rms,
        final_z_t_m: records.last().map_or(f64::NAN, |r| r.z_t),
        wall_s,
        realtime_factor: simulated / wall_s.max(1e-9),
        scenario_used: scenario.clone(),
    };
    let json = serde_json::to_string_pretty(&summary).map_err(|e| CliError::Io { path: out.path("summary.json"), source: e.into() })?;
    out.write_bytes("summary.json", json.as_bytes())?;
    let written = out.commit()?;
    if args.output.json {
        println!("{json}");
    } else {
        let mut o = std::io::stdout().lock();
        let l = &summary.lift_off;
        let _ = writeln!(
            o,
            "SIL run `{}` ({}, {}): {} periods in {:.2} s wall ({:.0}x real time)",
            summary.scenario, summary.controller, summary.transport, summary.periods, wall_s, summary.realtime_factor
        );
        let _ = writeln!(
            o,
            "lift-offs {} (detected {}, missed {}, false alarms {}, max latency {} periods) | deadline misses {}",
            l.lift_offs, l.lift_offs_detected, l.missed_lift_offs, l.false_alarms, l.max_detection_latency_periods, summary.deadline_misses
        );
        let _ = writeln!(
            o,
            "tracking: rms error {:.3} mm, final z_t {:.5} m (target {:.5} m)",
            rms * 1e3,
            summary.final_z_t_m,
            scenario.controller.target_z_t
        );
        if let Some(e) = &summary.error {
            let _ = writeln!(o, "FAILED: {e}");
        }
        let _ = writeln!(o, "wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
    }
    match failure {
        Some(e) => Err(CliError::Run(e)),
        None => Ok(()),
    }
}

fn draw(path: &std::path::Path, s: &Scenario, records: &[PeriodRecord]) -> Result<(), CliError> {
    let t_end = records.last().map_or(1.0, |r| r.t).max(1e-9);
    let col = |f: fn(&PeriodRecord) -> f64| records.iter().map(|r| (r.t, f(r))).collect::<Vec<_>>();
    let panels = [
        Panel {
            y_label: "z_t (m)",
            series: vec![
                Series { label: "z_t", points: col(|r| r.z_t), color: colors::BLUE, step: false },
                Series { label: "z_t*", points: col(|r| r.z_t_ref), color: colors::GREY, step: false },
            ],
            y_range: None,
        },
        Panel {
            y_label: "f_n (N)",
            series: vec![Series { label: "f_n", points: col(|r| r.f_n), color: colors::GREEN, step: false }],
            y_range: None,
        },
        Panel {
            y_label: "torque (N m)",
            series: vec![
                Series { label: "u1", points: col(|r| r.u1_cmd), color: colors::ORANGE, step: true },
                Series { label: "u2", points: col(|r| r.u2_cmd), color: colors::RED, step: true },
            ],
            y_range: None,
        },
        Panel {
            y_label: "mode (0 flight, 1 sliding, 2 sticking)",
            series: vec![Series {
                label: "mode",
                points: col(|r| match r.mode {
                    "sliding" => 1.0,
                    "sticking" => 2.0,
                    _ => 0.0,
                }),
                color: colors::PURPLE,
                step: true,
            }],
            y_range: Some((-0.2, 2.2)),
        },
    ];
    let title = format!("SIL run {}: {} from x0{}, z_t* = {} m", s.name, s.controller.kind, s.plant.x0, s.controller.target_z_t);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
