//! The arguments of the closed-loop runs of a scenario: `run` (and its link),
//! `firmware` (the firmware process) and `pil` (and its QEMU link).

use std::path::PathBuf;

use super::common::{LiveArgs, OutputArgs, ScenarioArgs, StrictArgs};

/// The link of `sil-host run --link`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum RunLink {
    /// The firmware process over iceoryx2 shared memory.
    Iceoryx2,
    /// The firmware step in the plant's process.
    InProcess,
    /// The arm application on the board twin, in the plant's process.
    Twin,
    /// The unmodified `arm` ELF on the emulated reference board (register level), in the plant's process.
    Emulator,
}

impl RunLink {
    /// What runs on a link without a board, in words (`the in-process link`), for
    /// the messages about the board tables (`experiments::scenario::BOARD_TABLES`).
    pub fn without_board(self) -> &'static str {
        match self {
            Self::Iceoryx2 => "the iceoryx2 link (the firmware process)",
            Self::InProcess => "the in-process link",
            Self::Twin => "the board twin",
            Self::Emulator => "the emulated board",
        }
    }
}

/// `sil-host run`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct RunArgs {
    /// The scenario.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub scenario: ScenarioArgs,
    /// Link the firmware step directly into this process (no IPC). Same scenario
    /// and seed give the same trace, bit for bit, as the lockstep iceoryx2 run.
    /// Short for `--link in-process`.
    #[cfg_attr(feature = "clap", arg(long, conflicts_with_all = ["realtime", "attach"]))]
    pub in_process: bool,
    /// How the plant reaches the firmware: `iceoryx2` (the default: the firmware
    /// process in lockstep), `in-process` (the step linked in), or `twin` (the
    /// `arm` image's application on the board twin: bus-level device models of
    /// the reference board, with the scenario's `[board]` and `[calibration]`;
    /// docs/board.md "The board twin"), or `emulator` (the unmodified `arm` ELF,
    /// the bytes flashed, on the emulated STM32F405 whose SPI1, ADC1, timers and
    /// pins drive the same device models; docs/board.md "The emulated image").
    #[cfg_attr(feature = "clap", arg(long, value_enum, value_name = "LINK", conflicts_with = "in_process"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::option"))]
    pub link: Option<RunLink>,
    /// With --link emulator: the `arm` ELF to run (default
    /// target/thumbv7em-none-eabihf/mcu/arm, built by `cargo build -p
    /// board-stm32f405 --profile mcu --target thumbv7em-none-eabihf --bin arm`).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PATH"))]
    pub elf: Option<std::path::PathBuf>,
    /// Pace the periods by the wall clock (1 kHz: 1 ms per period) instead of
    /// lockstep; reports period jitter and the firmware's step time.
    #[cfg_attr(feature = "clap", arg(long))]
    pub realtime: bool,
    /// Attach to a firmware process started by hand (`sil-host firmware --rig NAME`)
    /// instead of spawning one.
    #[cfg_attr(feature = "clap", arg(long, value_name = "NAME", conflicts_with = "rig"))]
    pub attach: Option<String>,
    /// Name of the rig (its iceoryx2 services) when spawning; default painleve-<pid>.
    #[cfg_attr(feature = "clap", arg(long, value_name = "NAME"))]
    pub rig: Option<String>,
    /// Wait for N monitors (subscribers of painleve/RIG/ground_truth, such as
    /// examples/python/monitor.py) before period 0, up to rig.connect_timeout_s;
    /// in lockstep the plant then also waits for a monitor whose buffer is full,
    /// so every monitor receives every sample (docs/rig.md, "Monitors").
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u16).range(0..=8), conflicts_with = "in_process"))]
    pub monitors: u16,
    /// With --monitors in lockstep: how long one sample waits for a full monitor
    /// before that monitor is given up (not waited for again), s, in (0, 600].
    #[cfg_attr(feature = "clap", arg(long, value_name = "S", default_value_t = 2.0, requires = "monitors"))]
    pub monitor_timeout: f64,
    /// Format of the trace: `csv` (trace.csv), `arrow` (trace.arrow: an Arrow IPC
    /// file, as simulate's, written a record batch at a time as the run goes, so a
    /// killed run keeps its batches; pandas.read_feather, polars.read_ipc,
    /// painleve.load; painleve.load also reads a killed run's, cut before its footer) or
    /// `mcap` (trace.mcap, for Foxglove and ROS 2 tools: channels /state, /contact,
    /// /torques, /firmware of protobuf messages with their schemas (FileDescriptorSets), and the arm in
    /// Foxglove's own schemas: /tf (FrameTransforms), /scene (SceneUpdate), /log
    /// (Log); log times in ns of simulated time; a zstd chunk per 100 periods, so a
    /// killed run keeps its chunks; docs/rig.md "Outputs", "Foxglove").
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "csv"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub format: tables::TableFormat,
    /// Do not write trace.html (the arm animated beside the trace's plots; docs/rig.md
    /// "The animated page"). Gathering it costs about 0.6 s of CPU per million samples
    /// (a 1000 s `run --in-process`: 4.4 s against 3.8 s; 6 MB more peak memory).
    #[cfg_attr(feature = "clap", arg(long))]
    pub no_page: bool,
    /// The run shown live in Foxglove.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub live: LiveArgs,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}

/// `sil-host firmware`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct FirmwareArgs {
    /// The rig to serve (the plant's `--rig` or `--attach` name).
    #[cfg_attr(feature = "clap", arg(long, value_name = "NAME"))]
    pub rig: String,
    /// Real-time mode: the firmware's clock is the wall clock (the plant runs with --realtime).
    #[cfg_attr(feature = "clap", arg(long))]
    pub realtime: bool,
    /// The scenario (the firmware's configuration and the faults on its side).
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub scenario: ScenarioArgs,
}

/// `sil-host pil`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct PilArgs {
    /// The scenario (as for `run`).
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub scenario: ScenarioArgs,
    /// QEMU mode: the PIL image (ELF); default: `cargo build-pil`'s output,
    /// target/thumbv7em-none-eabihf/qemu/pil. With --serial: the ELF flashed on
    /// the board, for its control law's declaration (a law of one's own: the
    /// scenario's `[law]` table binds to it, and the image's Hello must carry
    /// its digest); without it, the paper's laws.
    #[cfg_attr(feature = "clap", arg(long, value_name = "ELF"))]
    pub image: Option<PathBuf>,
    /// QEMU mode: the QEMU executable.
    #[cfg_attr(feature = "clap", arg(long, default_value = "qemu-system-arm", value_name = "EXE"))]
    pub qemu: PathBuf,
    /// QEMU mode: how the frames reach the image. `semihosting` (default): two
    /// host FIFOs the image reads and writes through semihosting, a frame per
    /// call (faster than real time at 1 kHz). `usart`: the emulated USART1 on a
    /// socket, the board's own driver, one byte per emulator main-loop turn
    /// (about 0.4x real time). The same frames, trace and instruction counts.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = QemuLinkArg::Semihosting, value_name = "LINK", conflicts_with = "serial"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub qemu_link: QemuLinkArg,
    /// Hardware in the loop: the serial device of a board running the PIL image
    /// (e.g. /dev/ttyUSB0), instead of spawning QEMU. It must exist.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PATH", conflicts_with = "qemu"))]
    pub serial: Option<PathBuf>,
    /// With --serial: the line rate, baud (8N1, no flow control), 9600 to 12000000;
    /// the reference board's USART1 runs at 2 Mbaud.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 2_000_000, value_name = "BAUD", requires = "serial"))]
    pub baud: u32,
    /// Wall time the image gets to answer one frame before the run stops as hung, s.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 5.0))]
    pub answer_timeout: f64,
    /// QEMU mode: do not echo the image's defmt log while it runs (it is still
    /// written to defmt.log).
    #[cfg_attr(feature = "clap", arg(long))]
    pub quiet: bool,
    /// Format of the trace: `csv` (trace.csv), `arrow` (trace.arrow: an Arrow IPC
    /// file, as simulate's, written a record batch at a time as the run goes, so a
    /// killed run keeps its batches; pandas.read_feather, polars.read_ipc,
    /// painleve.load; painleve.load also reads a killed run's, cut before its footer) or
    /// `mcap` (trace.mcap, for Foxglove and ROS 2 tools: channels /state, /contact,
    /// /torques, /firmware of protobuf messages with their schemas (FileDescriptorSets), and the arm in
    /// Foxglove's own schemas: /tf (FrameTransforms), /scene (SceneUpdate), /log
    /// (Log); log times in ns of simulated time; a zstd chunk per 100 periods, so a
    /// killed run keeps its chunks; docs/rig.md "Outputs", "Foxglove").
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "csv"))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice"))]
    pub format: tables::TableFormat,
    /// Do not write trace.html (the arm animated beside the trace's plots; docs/rig.md
    /// "The animated page"). Gathering it costs about 0.6 s of CPU per million samples
    /// (a 1000 s `run --in-process`: 4.4 s against 3.8 s; 6 MB more peak memory).
    #[cfg_attr(feature = "clap", arg(long))]
    pub no_page: bool,
    /// The run shown live in Foxglove.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub live: LiveArgs,
    /// Exit status on model violations.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub strict: StrictArgs,
    /// Output options.
    #[cfg_attr(feature = "clap", command(flatten))]
    #[cfg_attr(feature = "clap", serde(flatten))]
    pub output: OutputArgs,
}

/// `sil-host pil --qemu-link` ([`rig::pil_link::QemuLink`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum QemuLinkArg {
    /// Host FIFOs through semihosting, a frame per call.
    Semihosting,
    /// The emulated USART1 on a Unix socket, a byte per emulator main-loop turn.
    Usart,
}

impl From<QemuLinkArg> for rig::pil_link::QemuLink {
    fn from(a: QemuLinkArg) -> Self {
        match a {
            QemuLinkArg::Semihosting => Self::Semihosting,
            QemuLinkArg::Usart => Self::Usart,
        }
    }
}
