//! The arguments of `replay` (a recorded run's frames through a firmware build).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

/// The firmware build a replay feeds: the links of `run` and `pil`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReplayLink {
    /// The firmware step linked into this executable (this build's firmware).
    InProcess,
    /// The firmware process over iceoryx2: spawned from this executable, or
    /// another build's started by hand (--attach).
    Iceoryx2,
    /// The `arm` application on the board twin's bus-level models.
    Twin,
    /// The flashed `arm` ELF (--elf) on the emulated reference board.
    Emulator,
    /// The PIL image (--image) in QEMU.
    Pil,
}

/// `sil-host replay`.
#[derive(Debug, Clone, Args)]
pub struct ReplayArgs {
    /// The run's folder (`sil-host run` or `pil` --out): its summary.json (the
    /// scenario as run) and its frames (frames.csv, frames.arrow, or trace.mcap's
    /// /wire channels).
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
    /// The firmware build to feed the recorded frames to.
    #[arg(long, value_enum, default_value_t = ReplayLink::InProcess, value_name = "LINK")]
    pub link: ReplayLink,
    /// With --link emulator: the `arm` ELF (default: the mcu profile's
    /// target/thumbv7em-none-eabihf/mcu/arm).
    #[arg(long, value_name = "PATH")]
    pub elf: Option<PathBuf>,
    /// With --link pil: the PIL image (default: `cargo build-pil`'s output).
    #[arg(long, value_name = "ELF")]
    pub image: Option<PathBuf>,
    /// With --link pil: QEMU's executable.
    #[arg(long, default_value = "qemu-system-arm", value_name = "EXE")]
    pub qemu: PathBuf,
    /// With --link iceoryx2: attach to a firmware process started by hand
    /// (`sil-host firmware --rig NAME` of any build, with the run's scenario)
    /// instead of spawning this executable's.
    #[arg(long, value_name = "NAME")]
    pub attach: Option<String>,
    /// Change the recorded scenario before the replay (repeatable; the keys of
    /// `run --set`): the firmware is configured from the result, the frames stay
    /// the recorded ones. A changed gain shows where the commands first move.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<rig::overrides::Override>,
    /// Keep comparing after the first divergence and count the periods that
    /// differ (default: stop at the first).
    #[arg(long)]
    pub all: bool,
    /// Write the replayed answers (the recorded frames, this build's answers) as a run's folder DIR:
    /// frames.csv, .arrow or trace.mcap's /wire channels (--format), and summary.json (the comparison).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// With --out: the frames' format, as `run --format` (csv, arrow, mcap).
    #[arg(long, value_enum, default_value = "csv", requires = "out")]
    pub format: tables::TableFormat,
    /// Print one JSON document instead of the text.
    #[arg(long)]
    pub json: bool,
}
