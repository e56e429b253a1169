//! `sil-host replay DIR`: a recorded run's frames through a firmware build,
//! every answer compared with the recorded one bit for bit (docs/rig.md
//! "Replay"). copper-rs re-simulates a task graph from its log and PX4 replays a
//! flight log through a new estimator; here the log is the run's `frames`
//! table ([`rig::frames::FrameRow`]: the frame the firmware read, the arm's
//! state the board links' sensors read, the answer), the firmware is any link
//! of `run` and `pil`, configured from the run's own scenario.
//!
//! The replay is open loop: each recorded frame goes out whatever the firmware
//! answered to the one before, so after a divergence the frames are no longer
//! what this firmware would have made its plant do; the first divergence is
//! the finding, the count after it (`--all`) a measure of its reach.

mod recording;

use std::time::Instant;

use rig::{FaultPlan, FirmwareLink, MonitorPolicy, frames::FrameRow, link::DropCommands};
use serde::Serialize;

use crate::{
    cli::{ReplayArgs, ReplayLink},
    commands::Done,
    error::CliError,
    link_spec::LinkSpec,
    output::progress_bar,
};

/// The signals compared in every period: the answer's kind, the command's
/// codes, status and overrun counter, and the telemetry's ten 32-bit floats
/// ([`FrameRow::signals`]).
const SIGNALS: &str = "the answer, the command's u1_code, u2_code, status and overruns, and the telemetry's z_t_ref, f_n_ref, q1, q2, qd1, qd2, f_t_meas, f_n_meas, u1_raw, u2_raw";

/// Where the replayed firmware first answered differently.
#[derive(Debug, Clone, Serialize)]
pub struct Divergence {
    /// The period `k` (the frame's `seq`).
    pub period: u32,
    /// Its sample time, s.
    pub t: f64,
    /// The first signal that differs ([`FrameRow::signals`]' names).
    pub signal: &'static str,
    /// The recorded value (a float as its 32-bit text and bits).
    pub recorded: String,
    /// The replayed value.
    pub replayed: String,
}

/// `replay`'s result (its `--json` document).
#[derive(Debug, Clone, Serialize)]
pub struct ReplaySummary {
    /// The run's folder.
    pub folder: String,
    /// The file the frames came from.
    pub frames: String,
    /// The recorded scenario's name.
    pub scenario: String,
    /// The `--set`s applied to it, as given.
    pub overrides: Vec<String>,
    /// The link the frames went over (`in-process`, `iceoryx2`, `twin`, `emulator`, `pil`).
    pub link: String,
    /// Periods recorded.
    pub periods_recorded: usize,
    /// Periods replayed (all of them, unless the link failed or the replay stopped at a divergence).
    pub periods_replayed: usize,
    /// Whether every replayed answer equals the recorded one, bit for bit, and every period was replayed.
    pub identical: bool,
    /// Periods whose answer differs (all of them counted only with `--all`).
    pub divergent_periods: usize,
    /// The first divergence, if any.
    pub first_divergence: Option<Divergence>,
    /// Why the link stopped part way, if it did.
    pub link_error: Option<String>,
    /// What is compared in each period.
    pub signals: &'static str,
    /// Wall-clock time of the replay (the link's start included), s.
    pub wall_s: f64,
}

/// Replays `args.dir` over `args.link`; prints nothing.
///
/// # Errors
/// Bad input (exit 2): not a run's folder, no frames, a file that is not a
/// regular file within its bound, a recording cut off or of another scenario
/// than the one replayed (naming the setting), a bad `--set`, an option of
/// another link, a missing image; the link's refusals to start. The replay's
/// verdict is the returned [`Done`]'s failure: [`CliError::Diverged`] (exit 1)
/// at a divergence, the link's error when it failed part way.
pub fn execute(args: &ReplayArgs) -> Result<Done<ReplaySummary>, CliError> {
    check_link_options(args)?;
    let rec = recording::read(&args.dir)?;
    let scenario = rec.scenario.with_overrides(&args.set)?;
    let setup = experiments::run::setup(scenario)?;
    // Frames of another rate, length or start than the scenario's would
    // replay as a divergence of the firmware: refused, naming the setting.
    recording::check_scenario(&rec, &setup)?;
    let spec = match args.link {
        ReplayLink::InProcess => LinkSpec::InProcess,
        ReplayLink::Iceoryx2 => {
            let rig = args.attach.clone().unwrap_or_else(rig::ipc::default_rig_name);
            rig::ipc::check_rig_name(&rig).map_err(CliError::bad_input)?;
            LinkSpec::Iceoryx2 { rig, attach: args.attach.is_some(), realtime: false, monitors: MonitorPolicy::default() }
        }
        ReplayLink::Twin => LinkSpec::Twin,
        #[cfg(feature = "board")]
        ReplayLink::Emulator => LinkSpec::Emulator { elf: args.elf.clone().unwrap_or_else(board_link::emulator_link::default_image) },
        #[cfg(not(feature = "board"))]
        ReplayLink::Emulator => LinkSpec::Emulator { elf: args.elf.clone().unwrap_or_default() },
        ReplayLink::Pil => {
            let target = super::pil::qemu_target(args.image.clone(), args.qemu.clone(), rig::pil_link::QemuLink::default())?;
            rig::pil_link::check_faults(setup.scenario(), &target).map_err(|e| CliError::bad_input(e.to_string()))?;
            LinkSpec::Pil { options: rig::pil_link::PilOptions::for_target(target), on_log: None }
        }
    };
    let started = Instant::now();
    let mut open = spec.open(&setup)?;
    let link = open.link();
    let transport = link.transport().to_string();
    let plan = FaultPlan::new(&setup.scenario().faults, setup.scenario().timing.period());
    let progress = progress_bar(rec.rows.len() as u64, "replay", "periods", args.json);
    let stop = crate::cancel::stop_flag();
    let (mut replayed, mut divergent, mut first, mut link_error) = (0usize, 0usize, None, None);
    for row in &rec.rows {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            link_error = Some(CliError::interrupted(format!("interrupted after {replayed} periods")));
            break;
        }
        let (frame, truth) = (row.frame(), row.truth());
        // As the period loop drives a link: the faults that act on the firmware
        // itself first, then the exchange through the `drop_command` wrapper.
        link.before_period(u64::from(row.seq));
        let mut wire = DropCommands { inner: &mut *link, plan: &plan };
        match wire.exchange(&frame, &truth) {
            Ok(exchange) => {
                replayed += 1;
                let got = FrameRow::of(&frame, &truth, &exchange);
                if let Some((signal, recorded, replayed_value)) = row.first_difference(&got) {
                    divergent += 1;
                    first.get_or_insert(Divergence {
                        period: row.seq,
                        t: row.t,
                        signal,
                        recorded: recorded.to_string(),
                        replayed: replayed_value.to_string(),
                    });
                    if !args.all {
                        break;
                    }
                }
            }
            Err(e) => {
                link_error = Some(CliError::from(e));
                break;
            }
        }
        if replayed.is_multiple_of(500) {
            progress.set_position(replayed as u64);
        }
    }
    link.finish(replayed as u32);
    drop(open);
    progress.finish_and_clear();
    let summary = ReplaySummary {
        folder: args.dir.display().to_string(),
        frames: rec.source.display().to_string(),
        scenario: rec.scenario.name.clone(),
        overrides: args.set.iter().map(|o| format!("{}={}", o.key, o.text)).collect(),
        link: transport,
        periods_recorded: rec.rows.len(),
        periods_replayed: replayed,
        identical: first.is_none() && link_error.is_none() && replayed == rec.rows.len(),
        divergent_periods: divergent,
        first_divergence: first,
        link_error: link_error.as_ref().map(ToString::to_string),
        signals: SIGNALS,
        wall_s: started.elapsed().as_secs_f64(),
    };
    let failure = link_error.or_else(|| summary.first_divergence.as_ref().map(|d| CliError::Diverged(verdict(&summary, d))));
    Ok(Done { result: summary, files: Vec::new(), failure })
}

/// Refuses an option of another link (exit 2) rather than ignoring it.
fn check_link_options(args: &ReplayArgs) -> Result<(), CliError> {
    let given = [
        ("--elf", args.elf.is_some(), ReplayLink::Emulator),
        ("--image", args.image.is_some(), ReplayLink::Pil),
        ("--attach", args.attach.is_some(), ReplayLink::Iceoryx2),
    ];
    for (flag, is_given, link) in given {
        if is_given && args.link != link {
            let name = clap::ValueEnum::to_possible_value(&link).map(|v| v.get_name().to_string()).unwrap_or_default();
            return Err(CliError::bad_input(format!("{flag} goes with --link {name}")));
        }
    }
    if matches!(args.link, ReplayLink::Twin | ReplayLink::Emulator) {
        crate::features::require(cfg!(feature = "board"), "board", "replay --link twin/emulator")?;
    }
    Ok(())
}

/// The one-line verdict of a divergence.
fn verdict(s: &ReplaySummary, d: &Divergence) -> String {
    let reach = if s.periods_replayed == s.periods_recorded {
        format!("{} of {} periods differ", s.divergent_periods, s.periods_recorded)
    } else {
        "stopped there (--all counts every period that differs)".to_string()
    };
    format!(
        "the replay diverged from the recording at period {} (t = {} s): {} recorded {}, replayed {}; {reach}",
        d.period, d.t, d.signal, d.recorded, d.replayed
    )
}

/// Runs `sil-host replay`: [`execute`], then prints the verdict (or the JSON
/// document with `--json`).
///
/// # Errors
/// As [`execute`]; a divergence is exit 1 after the verdict is printed.
pub fn run(args: &ReplayArgs) -> Result<(), CliError> {
    crate::commands::finish(execute(args)?, args.json, |s| s, |s, _| print(s))
}

/// The human verdict.
fn print(s: &ReplaySummary) {
    let set = if s.overrides.is_empty() { String::new() } else { format!(", with --set {}", s.overrides.join(" --set ")) };
    outln!("replay of {} ({}; scenario {}{set}) over the {} link, {:.3} s:", s.folder, s.frames, s.scenario, s.link, s.wall_s);
    if s.identical {
        outln!("  identical over {} periods: every answer bit for bit ({})", s.periods_replayed, s.signals);
        return;
    }
    if let Some(d) = &s.first_divergence {
        outln!("  DIVERGED at period {} (t = {} s): {} recorded {}, replayed {}", d.period, d.t, d.signal, d.recorded, d.replayed);
        outln!(
            "  {} of {} periods replayed, {} differ{}",
            s.periods_replayed,
            s.periods_recorded,
            s.divergent_periods,
            if s.periods_replayed < s.periods_recorded && s.link_error.is_none() {
                " (stopped at the first: --all compares every period)"
            } else {
                ""
            }
        );
    }
    if let Some(e) = &s.link_error {
        outln!("  the link stopped after {} of {} periods: {e}", s.periods_replayed, s.periods_recorded);
    }
}
