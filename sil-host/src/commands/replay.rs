//! `sil-host replay DIR`: a recorded run's frames through a firmware build
//! over any link of `run` and `pil`, every answer compared with the recorded one
//! bit for bit (docs/rig.md "Replay"). The reading, the comparison and the
//! verdict are the library's ([`experiments::replay`]); this command opens the
//! link, shows progress and prints.

use std::time::{Duration, Instant};

use experiments::replay::{self, Recording, ReplaySummary};
use rig::{FaultPlan, MonitorPolicy};

use crate::{
    cli::{ReplayArgs, ReplayLink},
    commands::Done,
    error::CliError,
    link_spec::LinkSpec,
    output::{OutputSet, StreamedTable, progress_bar},
};
use rig::frames::FrameRow;
use tables::TableFormat;

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
    let rec = Recording::read(&args.dir)?;
    let scenario = rec.scenario.with_overrides(&args.set)?;
    let setup = experiments::run::setup(scenario)?;
    // Frames of another rate, length or start than the scenario's would
    // replay as a divergence of the firmware: refused, naming the setting.
    rec.check_scenario(&setup)?;
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
    // `--out`: the replayed answers streamed as a run's frames table, the summary beside them.
    let mut out = args.out.as_deref().map(OutputSet::new).transpose()?;
    let mut table = out
        .as_mut()
        .map(|o| {
            StreamedTable::<FrameRow>::new(
                o,
                if args.format == TableFormat::Mcap { "trace" } else { "frames" },
                args.format,
                Duration::from_millis(200),
                Default::default(),
            )
        })
        .transpose()?;
    let bar = progress_bar(rec.rows.len() as u64, "replay", "periods", args.json);
    let stop = crate::cancel::stop_flag();
    let mut answers = |r: &FrameRow| table.as_mut().map_or((), |t| t.push(r));
    let comparison = replay::replay(&rec, link, &plan, args.all, &mut answers, &mut |replayed| {
        if replayed.is_multiple_of(500) {
            bar.set_position(replayed as u64);
        }
        !stop.load(std::sync::atomic::Ordering::Relaxed)
    });
    drop(open);
    bar.finish_and_clear();
    let overrides = args.set.iter().map(|o| format!("{}={}", o.key, o.text)).collect();
    let (summary, failure) = ReplaySummary::of(&rec, comparison, overrides, transport, started.elapsed().as_secs_f64());
    let mut files = Vec::new();
    if let (Some(mut out), Some(table)) = (out, table) {
        table.finish()?;
        out.write_json("summary.json", &summary)?;
        files = out.commit()?;
    }
    Ok(Done { result: summary, files, failure })
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

/// Runs `sil-host replay`: [`execute`], then prints the verdict (or the JSON
/// document with `--json`).
///
/// # Errors
/// As [`execute`]; a divergence is exit 1 after the verdict is printed.
pub fn run(args: &ReplayArgs) -> Result<(), CliError> {
    crate::commands::finish(execute(args)?, args.json, |s| s, |s, _| outln!("{s}"))
}
