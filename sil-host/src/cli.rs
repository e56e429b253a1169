//! Command-line interface of `sil-host` (clap).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// Plant simulator and rig for the Painlevé paradox on a two-link arm
/// (Marchese, Coraggio, Hogan, di Bernardo, ECC 2019).
///
/// Every command prints a human summary, or one JSON document with `--json`,
/// and writes its files under `--out DIR` (default `out/`). Bad input exits
/// with code 2 and writes nothing; a failure while running exits with 1.
#[derive(Debug, Parser)]
#[command(name = "sil-host", version, about, long_about)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open-loop simulation (u = 0) of the arm on the belt from one of the paper's
    /// initial conditions; writes trace.csv, events.csv, trace.svg, summary.json.
    #[command(allow_negative_numbers = true)]
    Simulate(SimulateArgs),
    /// Admissible configurations (docs/model.md experiment 2, paper Table II): the ranges
    /// of z_t on the belt where p > 0, for elbow up and elbow down.
    #[command(allow_negative_numbers = true)]
    Admissible(AdmissibleArgs),
    /// Mode map (docs/model.md experiment 1, paper Fig. 2): the contact mode over a grid
    /// of (theta1, theta1_dot) with the tip on the belt, with the curves b = 0 and p = 0.
    #[command(allow_negative_numbers = true)]
    Modes(ModesArgs),
    /// One-parameter bifurcation diagram (docs/model.md experiment 4, paper Fig. 4): open
    /// loop (u = 0) from x0a at mu = 0.6 over a fine grid of v_belt; after a transient,
    /// theta1 at every upward crossing of theta1_dot = 0 (located inside the
    /// integration steps), and each v_belt classified as equilibrium, periodic (with
    /// its period) or chaotic (largest Lyapunov exponent of the section map).
    /// Writes section.csv, classes.csv, classes.json, summary.json, bifurcation.svg,
    /// lyapunov.svg.
    ///
    /// Classification: a period p is accepted when every section point (theta1,
    /// theta2) is within --tol of the point p crossings later over the whole record
    /// (at least 3 periods recorded); otherwise chaotic when the largest Lyapunov
    /// exponent per crossing, less twice its standard error, exceeds
    /// --chaos-threshold (two nearby trajectories of the section map, renormalised
    /// every crossing), else aperiodic. No crossings: equilibrium (steady sliding
    /// or sticking); fewer than 6: settling.
    #[command(allow_negative_numbers = true)]
    Poincare(PoincareArgs),
    /// Closed-loop SIL run of a scenario: the firmware in its own process (spawned,
    /// or attached with --attach) against the plant, over iceoryx2 shared memory, in
    /// lockstep (default) or paced by the wall clock (--realtime); sampled at the
    /// control rate with quantised sensors and torques and a zero-order hold.
    /// Writes trace.csv, summary.json and trace.svg.
    ///
    /// Exit codes: 0 ok; 1 the run stopped early (firmware in its safe state, firmware
    /// process dead or stalled, plant failure; everything up to then is written);
    /// 2 bad input (nothing written).
    #[command(allow_negative_numbers = true)]
    Run(RunArgs),
    /// The firmware process of the SIL rig: the firmware step answering sensor frames
    /// over iceoryx2. `sil-host run` spawns it; start it by hand with the same
    /// scenario and `--rig NAME`, then `sil-host run --attach NAME`.
    ///
    /// Exit codes: 0 the plant ended the run; 3 the plant died (the firmware latched
    /// its safe state, zero torque); 1 transport failure; 2 bad input.
    #[command(allow_negative_numbers = true)]
    Firmware(FirmwareArgs),
    /// Z_t,sliding (docs/model.md experiments 5 and 6): the largest tangential target z_t*
    /// the tip reaches with no lift-off, by bisection on z_t*, for the PID or the
    /// hybrid controller from x0d or x0u, with the paper's ideal controllers
    /// (--ideal: continuous time, exact measurements) or the sampled firmware
    /// (in-process, 1 kHz, quantised sensors and torques). --all: the eight cases
    /// in parallel. A target is reached when, over the whole run, the tip never
    /// leaves the belt (no lift-off, not even between samples, no impact without
    /// collision), the run ends normally, and |z_t - z_t*| <= --settle-tol over the
    /// last --settle-window s. Writes zmax.csv, trials.csv, summary.json and one
    /// figure per case (the run at the limit).
    #[command(allow_negative_numbers = true)]
    Zmax(ZmaxArgs),
    /// Sensitivity study (issue 14): the paper's headline results (critical mu, the
    /// bouncing band at mu = 0.6 from x0a, whether x0d bounces, Z_t,sliding for the
    /// four paper cases ideal and sampled, whether the hybrid closed loop bounces)
    /// recomputed under each open choice, one at a time from the defaults: impact law
    /// and e_n, the IWC rule, the hybrid law's friction term, the move time, the
    /// lift-off criterion, and for the sampled firmware the rate, the encoder bits,
    /// the load-cell noise and the mu_hat mismatch. Writes sensitivity.csv (choice,
    /// value, result), summary.json and one figure per headline result. --size quick
    /// takes a few minutes on 2 cores; --size paper uses the paper's resolution.
    #[command(allow_negative_numbers = true)]
    Sensitivity(SensitivityArgs),
    /// Processor in the loop: the MCU image (thumbv7em-none-eabihf, the one that would
    /// be flashed) closes the loop with the plant over its USART1 (postcard, CRC-32 and
    /// COBS frames), in lockstep with the same scenarios and outputs as `run`. Two modes:
    ///
    /// - QEMU (default): the image (--image) runs in QEMU's netduinoplus2 (an STM32F405,
    ///   --qemu) under -icount shift=0, the frames through semihosting and two host
    ///   FIFOs (--qemu-link semihosting, real time and faster) or its USART1 on a local
    ///   socket (--qemu-link usart, about 0.4x real time at 1 kHz). Step counts are
    ///   instructions (emulated SysTick); the image's defmt log is decoded and shown
    ///   (and written to defmt.log). Build the image first: `cargo build-pil` (its QEMU
    ///   build, profile qemu; docs/board.md). Needs qemu-system-arm.
    ///
    /// - Hardware in the loop (--serial PATH): the image runs on a board flashed with it
    ///   (`cargo pil`),
    ///   its USART1 (2 Mbaud, --baud) wired to the serial device PATH (a USB-serial
    ///   adapter), raw 8N1, no flow control. Step counts are what the image reports
    ///   (DWT cycles on silicon); its defmt log goes over RTT to a debug probe (probe-rs),
    ///   not over this link; the kill_firmware fault is not available.
    ///
    /// The worst and median step are reported against the budget, 5 % of the control
    /// period at 168 MHz (8400 at 1 kHz). Writes trace.csv, summary.json, trace.svg,
    /// instructions.svg and (QEMU) defmt.log.
    ///
    /// Exit codes: 0 ok; 1 the run stopped early (safe state, QEMU or the board dead or
    /// hung, plant failure; everything up to then is written); 2 bad input, no image,
    /// or no such serial device.
    #[command(allow_negative_numbers = true)]
    Pil(PilArgs),
    /// Bring-up of a board running the `arm` image, over its USART1 (docs/board.md
    /// "Bring-up", step by step; ODrive's odrivetool is the model): status and raw
    /// readings, the guided calibration (encoders' zeros at the jig's pose, each
    /// joint's direction checked by a low-torque jog, the load cell's tare and span),
    /// the firmware configuration of a scenario, the save to flash, enable and
    /// disable. One request, one reply, in the PIL framing (postcard, CRC-32C, COBS).
    ///
    /// Exit codes: 0 done; 1 the board refused or a check failed (said why);
    /// 2 bad input, no such port, or no answer.
    #[command(allow_negative_numbers = true)]
    Board(BoardArgs),
    /// The board twin (the `arm` image's application on the simulated reference
    /// board, the arm hanging free over a lowered belt) serving the bring-up protocol
    /// on a pseudo-terminal, so that every `sil-host board` command runs without a
    /// board (CI). Prints the port's path (and the pose the jig would hold) on its
    /// first line, then serves in real time until Ctrl-C, SIGTERM or --duration.
    #[command(allow_negative_numbers = true, name = "board-twin")]
    BoardTwin(BoardTwinArgs),
    /// Every speed and size figure against its target: the worst control step in PIL
    /// (instructions), the image's flash, the closed loop in-process and over
    /// iceoryx2, PIL periods per wall second, simulate 300 s with its trace, the
    /// closed-loop hybrid sweep (estimated), and optionally real time at 1 kHz
    /// (docs/measurements.md "Speed and scale"); --json for scripts.
    Bench(BenchArgs),
    /// Two-parameter brute-force bifurcation diagram (docs/model.md experiments 3 and 7,
    /// paper Figs. 3 and 9): a grid in (mu, v_belt), and optionally in the impact law
    /// and e_n, from the paper's and random initial conditions; per run a transient,
    /// then the record window where the paper's indicator max theta1_dot, the
    /// lift-offs and the highest tip position are measured. Runs in parallel on all
    /// cores; each finished run is appended to DIR/runs.csv at once, so an
    /// interrupted sweep (Ctrl-C, kill) resumes when started again with the same
    /// arguments and --out. Writes sweep.csv (rows by run index), summary.json,
    /// map_*.svg and slices_*.svg.
    ///
    /// Exit codes: 0 done (or --limit reached); 1 interrupted or failed (what was
    /// computed is kept); 2 bad input, or --out holds a different sweep.
    #[command(allow_negative_numbers = true)]
    Sweep(SweepArgs),
    /// Joins the folders of a sharded sweep (`sweep --shard K/N`) into one: checks
    /// they belong to the same sweep and that no run is missing or given twice with
    /// different results, and writes the same outputs as an unsharded sweep.
    ///
    /// Exit codes: 0 merged; 2 folders of different sweeps, runs missing (unless
    /// --allow-missing) or conflicting.
    Merge(MergeArgs),
    /// Every experiment of docs/model.md at a size that finishes in minutes, in one page:
    /// `report.md` with every figure and table (and `report.json`), each experiment's
    /// files in a folder of its own. Run it from the repository root.
    ///
    /// Exit codes: 0 ok; 1 an experiment failed (the page says which; the rest is
    /// written); 2 bad input.
    Report(ReportArgs),
}

/// How big the report's experiments are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReportSize {
    /// Coarse grids and short windows: minutes on a 2-core machine.
    Quick,
    /// The paper's grids and windows (hours on a 2-core machine).
    Paper,
}

/// `sil-host report`.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Size of the experiments.
    #[arg(long, value_enum, default_value = "quick")]
    pub size: ReportSize,
    /// Also write the page's tables (no figures), stamped with date, commit and
    /// machine, to this Markdown file (the repository keeps them in docs/results.md).
    #[arg(long, value_name = "FILE.md")]
    pub results: Option<PathBuf>,
    /// Exit status on model violations in any experiment.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Output folder and JSON switch (`--out` defaults to `out/`; the page is `report.md` there).
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host bench`.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Figure groups to measure, comma-separated (default: all but cycles and
    /// realtime): step (worst control step in PIL, instructions), cycles (its
    /// Cortex-M4 cycle estimate and the highest rate it allows, scripts/cycles.py,
    /// about 2 min), flash (the PIL image's size),
    /// in-process, lockstep (iceoryx2), twin (the board twin's closed loop), pil
    /// (PIL periods per wall second), simulate
    /// (300 s with its 1 ms trace), sweep (closed-loop hybrid grid, estimated),
    /// realtime (needs --realtime-s).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub only: Vec<String>,
    /// Simulated seconds per in-process and lockstep run (1 kHz: 1000 periods per second).
    #[arg(long, default_value_t = 10.0)]
    pub duration: f64,
    /// Runs per wall-clock figure (the median is reported; PIL: at most 3 hybrid runs, then one PID).
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
    /// Simulated seconds per PIL run.
    #[arg(long, default_value_t = 2.0)]
    pub pil_s: f64,
    /// The PIL image (ELF); default: `cargo build-pil`'s output in the target folder.
    #[arg(long, value_name = "ELF")]
    pub image: Option<PathBuf>,
    /// QEMU's executable.
    #[arg(long, default_value = "qemu-system-arm", value_name = "EXE")]
    pub qemu: PathBuf,
    /// The cargo target folder holding the MCU images (default: the one this
    /// executable was built in).
    #[arg(long, value_name = "DIR")]
    pub target_dir: Option<PathBuf>,
    /// Runs of the closed-loop sweep to time (one balanced shard, scaled to the
    /// grid); the grid's size or more runs it whole (1810 runs).
    #[arg(long, default_value_t = 40, value_name = "N")]
    pub sweep_runs: usize,
    /// Length of the real-time run, s (0: none).
    #[arg(long, default_value_t = 0.0)]
    pub realtime_s: f64,
    /// Exit 1 when a measured figure misses its target (skipped ones do not count).
    #[arg(long)]
    pub check: bool,
    /// Print one JSON document (an array of figures) instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// `sil-host sensitivity`.
#[derive(Debug, Clone, Args)]
pub struct SensitivityArgs {
    /// Size of the study: `quick` (coarse grids, short windows, Z_t,sliding to 4 mm)
    /// or `paper` (experiment 3's grid, 250 s + 50 s, Z_t,sliding to 1 mm).
    #[arg(long, value_enum, default_value = "quick")]
    pub size: analyses::sensitivity::Size,
    /// Base scenario (the arm's parameters, gains, f_n*, mu, v_belt for Z_t,sliding;
    /// the sampled firmware's settings); default: the embedded default scenario.
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Change one key of the base scenario (repeatable; as for `run`). Refused: the
    /// keys the study varies or sets per run.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host zmax`.
#[derive(Debug, Clone, Args)]
pub struct ZmaxArgs {
    /// Controller (ignored with --all).
    #[arg(long, value_enum, default_value = "hybrid")]
    pub controller: firmware::ControllerKind,
    /// Initial condition (ignored with --all).
    #[arg(long, value_enum, default_value = "d")]
    pub x0: plant::initial::PaperX0,
    /// The paper's ideal controllers (continuous time, exact measurements, no
    /// saturation) instead of the sampled firmware (ignored with --all).
    #[arg(long)]
    pub ideal: bool,
    /// All eight cases (pid/hybrid x x0d/x0u x ideal/sampled), in parallel, as a table.
    #[arg(long)]
    pub all: bool,
    /// Bisection tolerance on z_t*, m.
    #[arg(long, default_value_t = 1e-3)]
    pub tol: f64,
    /// Targets searched, m: LO,HI. Default: from the initial tip position
    /// (z_t* = start) to 1 mm short of the end of the reachable belt.
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true)]
    pub bracket: Option<String>,
    /// Run length of a trial, s (the move takes the scenario's move_time_s, 2 s).
    #[arg(long, default_value_t = 10.0)]
    pub duration: f64,
    /// Largest |z_t - z_t*| over the settle window for the target to count as reached, m.
    #[arg(long, default_value_t = 1e-3)]
    pub settle_tol: f64,
    /// The last part of the run where the tip must be within --settle-tol, s.
    #[arg(long, default_value_t = 1.0)]
    pub settle_window: f64,
    /// Impact-without-collision rule of the base scenario (`plant.iwc`): `restitution`
    /// or `plastic`; default: the scenario's.
    #[arg(long, value_enum)]
    pub iwc: Option<plant::impact::IwcRule>,
    /// Lift-off criterion, m: 0 counts any departure from the belt (located exactly);
    /// a gap > 0 counts a lift-off only when the tip rises more than this above the
    /// belt at a sample (0 to 0.1 m).
    #[arg(long, default_value_t = 0.0)]
    pub lift_off_gap: f64,
    /// Base scenario of the sampled setting (rate, sensors, the arm's parameters,
    /// mu, v_belt, gains, f_n*, move time, ...); its controller, initial condition,
    /// target and run length are set per trial, and K'_I when it does not give
    /// controller.hybrid.ki (the paper's: 650 from x0d, 0 from x0u). The ideal
    /// setting takes the plant's parameters, the gains, f_n*, the move time and the
    /// plant settings from it. Default: the embedded default scenario.
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Change one key of the base scenario, e.g. `--set plant.m=0.24
    /// --set controller.hybrid.kp=800 --set controller.hybrid.ki=300` (repeatable;
    /// KEY=VALUE as for `run`). The ideal and the sampled trials use the plant's
    /// parameters and the gains it gives; without `controller.hybrid.ki` K'_I is
    /// the paper's per initial condition. Refused: the keys each trial sets
    /// (controller.kind, plant.x0, controller.target_z_t, timing.duration_s).
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The scenario of a run and its command-line overrides.
#[derive(Debug, Clone, Args)]
pub struct ScenarioArgs {
    /// Scenario file (TOML, see scenarios/), `-` for standard input; default: the
    /// embedded default scenario (hybrid from x0d, mu 0.6, v_belt -0.4 m/s, f_n* 10 N,
    /// z_t* 0.10 m over 2 s, 10 s, 1 kHz).
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Override the controller.
    #[arg(long, value_enum)]
    pub controller: Option<firmware::ControllerKind>,
    /// Override the initial condition.
    #[arg(long, value_enum)]
    pub x0: Option<plant::initial::PaperX0>,
    /// Override the tangential target z_t*, m.
    #[arg(long)]
    pub target_zt: Option<f64>,
    /// Override the run length, s.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Override the sensor-noise seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Override the impact-without-collision rule (scenario `plant.iwc`):
    /// `restitution` (the tip is thrown off the belt) or `plastic` (left stuck, v_n = 0).
    #[arg(long, value_enum)]
    pub iwc: Option<plant::impact::IwcRule>,
    /// Change one scenario key, e.g. `--set plant.m=0.24 --set controller.pid.kp=[150,0]`
    /// (repeatable). KEY is the scenario file's dotted key path (docs/rig.md), VALUE a
    /// TOML value (a bare word such as `pid` is a string). Applied to the file before
    /// it is read, so a bad key or value is an error naming it (exit 2). A key also
    /// set by a flag here (`--x0` and `plant.x0`, ...) is refused.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
}

/// `--strict`, on every command that simulates.
#[derive(Debug, Clone, Copy, Args)]
pub struct StrictArgs {
    /// Exit 1 if any result violates the model (an energy-creating impact, a
    /// friction-cone violation, an integrator failure); everything is still written
    /// and the violations are listed. Without it they are reported, and exit is 0.
    #[arg(long)]
    pub strict: bool,
}

/// `sil-host firmware`.
#[derive(Debug, Clone, Args)]
pub struct FirmwareArgs {
    /// The rig to serve (the plant's `--rig` or `--attach` name).
    #[arg(long, value_name = "NAME")]
    pub rig: String,
    /// Real-time mode: the firmware's clock is the wall clock (the plant runs with --realtime).
    #[arg(long)]
    pub realtime: bool,
    /// The scenario (the firmware's configuration and the faults on its side).
    #[command(flatten)]
    pub scenario: ScenarioArgs,
}

/// The link of `sil-host run --link`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RunLink {
    /// The firmware process over iceoryx2 shared memory.
    Iceoryx2,
    /// The firmware step in the plant's process.
    InProcess,
    /// The arm application on the board twin, in the plant's process.
    Twin,
}

/// `sil-host run`.
#[derive(Debug, Clone, Args)]
pub struct RunArgs {
    /// The scenario.
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Link the firmware step directly into this process (no IPC). Same scenario
    /// and seed give the same trace, bit for bit, as the lockstep iceoryx2 run.
    /// Short for `--link in-process`.
    #[arg(long, conflicts_with_all = ["realtime", "attach"])]
    pub in_process: bool,
    /// How the plant reaches the firmware: `iceoryx2` (the default: the firmware
    /// process in lockstep), `in-process` (the step linked in), or `twin` (the
    /// `arm` image's application on the board twin: bus-level device models of
    /// the reference board, with the scenario's `[board]` and `[calibration]`;
    /// docs/board.md "The board twin").
    #[arg(long, value_enum, value_name = "LINK", conflicts_with = "in_process")]
    pub link: Option<RunLink>,
    /// Pace the periods by the wall clock (1 kHz: 1 ms per period) instead of
    /// lockstep; reports period jitter and the firmware's step time.
    #[arg(long)]
    pub realtime: bool,
    /// Attach to a firmware process started by hand (`sil-host firmware --rig NAME`)
    /// instead of spawning one.
    #[arg(long, value_name = "NAME", conflicts_with = "rig")]
    pub attach: Option<String>,
    /// Name of the rig (its iceoryx2 services) when spawning; default painleve-<pid>.
    #[arg(long, value_name = "NAME")]
    pub rig: Option<String>,
    /// Wait for N monitors (subscribers of painleve/RIG/ground_truth, such as
    /// examples/python/monitor.py) before period 0, up to rig.connect_timeout_s;
    /// in lockstep the plant then also waits for a monitor whose buffer is full,
    /// so every monitor receives every sample (docs/rig.md, "Monitors").
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u16).range(0..=8), conflicts_with = "in_process")]
    pub monitors: u16,
    /// With --monitors in lockstep: how long one sample waits for a full monitor
    /// before that monitor is given up (not waited for again), s, in (0, 600].
    #[arg(long, value_name = "S", default_value_t = 2.0, requires = "monitors")]
    pub monitor_timeout: f64,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host pil --qemu-link` ([`rig::pil_link::QemuLink`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
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

/// `sil-host board`.
#[derive(Debug, Clone, Args)]
pub struct BoardArgs {
    /// The board's serial port: a USB-serial adapter on USART1 (PA9/PA10), or the
    /// path `sil-host board-twin --pty` printed.
    #[arg(long, value_name = "PATH")]
    pub port: PathBuf,
    /// The line rate, baud (8N1, no flow control).
    #[arg(long, default_value_t = rig::bringup_line::DEFAULT_BAUD, value_name = "BAUD")]
    pub baud: u32,
    /// Print one JSON document instead of the human summary.
    #[arg(long, global = true)]
    pub json: bool,
    /// What to do.
    #[command(subcommand)]
    pub command: BoardCommand,
}

/// The `sil-host board` steps, in the order of docs/board.md "Bring-up".
#[derive(Debug, Clone, Subcommand)]
pub enum BoardCommand {
    /// The firmware's state, its raw readings (encoder counts and field strength,
    /// ADC codes, belt count, fault line), its calibration and last telemetry.
    Status,
    /// Status and raw readings every --interval-ms, until Ctrl-C or --count.
    Watch {
        /// Milliseconds between two readings.
        #[arg(long, default_value_t = 200)]
        interval_ms: u64,
        /// Readings to take (default: until Ctrl-C).
        #[arg(long)]
        count: Option<u64>,
    },
    /// The guided calibration, drivers disabled, the arm free and held at the
    /// calibration pose by its jig: the encoders' zeros set at the pose, then each
    /// joint jogged both ways at low torque (it must move its torque's way, by 0.7 to
    /// 30 degrees, or the command stops and says which joint and why), then the load
    /// cell's tare (nothing on it). Then: `span` with a known weight, `configure`,
    /// `save`.
    Calibrate {
        /// The calibration pose, degrees: theta1 (from straight down, positive
        /// counter-clockwise) and the elbow's angle theta2 - theta1, as the jig's
        /// drawing gives them (the twin prints its pose).
        #[arg(long, value_name = "THETA1,ELBOW", value_delimiter = ',', required = true, allow_hyphen_values = true)]
        pose_deg: Vec<f64>,
        /// An encoder that counts against its joint (repeatable): theta1 or elbow.
        #[arg(long, value_name = "JOINT")]
        reversed: Vec<JointArg>,
        /// The jog's torque, N m (at most 0.5).
        #[arg(long, default_value_t = 0.1)]
        jog_nm: f64,
        /// Skip the load cell's tare.
        #[arg(long)]
        no_tare: bool,
    },
    /// The load cell's span: with a known force on one axis now (a weight: m g),
    /// gain = force / (count - tare).
    Span {
        /// The axis: tangential (f_t) or normal (f_n).
        #[arg(long, value_enum)]
        axis: AxisArg,
        /// The force, N.
        #[arg(long)]
        newtons: f64,
    },
    /// Sends the firmware configuration of a scenario (controller, gains, rate,
    /// limits); the firmware validates it. The rate must be the image's.
    Configure {
        /// The scenario.
        #[command(flatten)]
        scenario: ScenarioArgs,
    },
    /// Saves the calibration and configuration in force to flash (version and
    /// CRC-32C); they are loaded at every reset. Until saved the drivers stay locked out.
    Save,
    /// Lifts the reduced torque limit a new calibration runs at (both joints'
    /// directions must have been checked).
    LiftTorqueLimit,
    /// Enables the drivers: resets the firmware, which closes the loop.
    Enable,
    /// Disables the drivers now.
    Disable,
}

/// A joint, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum JointArg {
    /// The base joint.
    Theta1,
    /// The elbow.
    Elbow,
}

/// A load-cell axis, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AxisArg {
    /// f_t.
    Tangential,
    /// f_n.
    Normal,
}

/// `sil-host board-twin`.
#[derive(Debug, Clone, Args)]
pub struct BoardTwinArgs {
    /// Serve on a new pseudo-terminal (the only transport).
    #[arg(long, required = true)]
    pub pty: bool,
    /// The scenario: its `[board]` (the board's physical truth: mountings, wiring),
    /// its firmware configuration and `[calibration]` (the image's compiled-in
    /// fallback, and the saved record with --flash saved).
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// The settings sector at power-up: erased (a new board), saved (the scenario's
    /// settings), or corrupt (a record with a damaged byte).
    #[arg(long, value_enum, default_value_t = FlashArg::Erased)]
    pub flash: FlashArg,
    /// Hold the drivers' fault line (nFAULT) asserted.
    #[arg(long)]
    pub fault_line: bool,
    /// Stop after this many seconds of wall time (default: until Ctrl-C or SIGTERM).
    #[arg(long, value_name = "S")]
    pub serve_for: Option<f64>,
    /// Print the first line as JSON (port, pose).
    #[arg(long)]
    pub json: bool,
}

/// The twin's settings sector at power-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FlashArg {
    /// Nothing stored.
    Erased,
    /// The scenario's settings stored.
    Saved,
    /// The scenario's settings stored, one byte damaged.
    Corrupt,
}

/// `sil-host pil`.
#[derive(Debug, Clone, Args)]
pub struct PilArgs {
    /// The scenario (as for `run`).
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// QEMU mode: the PIL image (ELF); default: `cargo build-pil`'s output,
    /// target/thumbv7em-none-eabihf/qemu/pil.
    #[arg(long, value_name = "ELF")]
    pub image: Option<PathBuf>,
    /// QEMU mode: the QEMU executable.
    #[arg(long, default_value = "qemu-system-arm", value_name = "EXE")]
    pub qemu: PathBuf,
    /// QEMU mode: how the frames reach the image. `semihosting` (default): two
    /// host FIFOs the image reads and writes through semihosting, a frame per
    /// call (faster than real time at 1 kHz). `usart`: the emulated USART1 on a
    /// socket, the board's own driver, one byte per emulator main-loop turn
    /// (about 0.4x real time). The same frames, trace and instruction counts.
    #[arg(long, value_enum, default_value_t = QemuLinkArg::Semihosting, value_name = "LINK", conflicts_with = "serial")]
    pub qemu_link: QemuLinkArg,
    /// Hardware in the loop: the serial device of a board running the PIL image
    /// (e.g. /dev/ttyUSB0), instead of spawning QEMU. It must exist.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["image", "qemu"])]
    pub serial: Option<PathBuf>,
    /// With --serial: the line rate, baud (8N1, no flow control), 9600 to 12000000;
    /// the reference board's USART1 runs at 2 Mbaud.
    #[arg(long, default_value_t = 2_000_000, value_name = "BAUD", requires = "serial")]
    pub baud: u32,
    /// Wall time the image gets to answer one frame before the run stops as hung, s.
    #[arg(long, default_value_t = 5.0)]
    pub answer_timeout: f64,
    /// QEMU mode: do not echo the image's defmt log while it runs (it is still
    /// written to defmt.log).
    #[arg(long)]
    pub quiet: bool,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Options shared by every command's output.
#[derive(Debug, Clone, Args)]
pub struct OutputArgs {
    /// Folder for the files the command writes (created if missing).
    #[arg(long, default_value = "out", value_name = "DIR")]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}

/// `sil-host simulate`.
#[derive(Debug, Clone, Args)]
pub struct SimulateArgs {
    /// Initial condition: one of the paper's (projected onto the belt).
    #[arg(long, value_enum, default_value = "a", conflicts_with = "x0_deg")]
    pub x0: plant::initial::PaperX0,
    /// Initial condition in degrees and degrees per second: th1,th1dot,th2,th2dot.
    /// A tip up to 1 mm inside the belt is projected onto it; deeper is an error.
    #[arg(long, value_name = "TH1,TH1DOT,TH2,TH2DOT", allow_hyphen_values = true)]
    pub x0_deg: Option<String>,
    /// Friction coefficient mu (>= 0).
    #[arg(long, default_value_t = 0.6)]
    pub mu: f64,
    /// Belt speed v_belt, m/s.
    #[arg(long, default_value_t = -0.4, allow_hyphen_values = true)]
    pub v_belt: f64,
    /// Impact law at touchdown and for impacts without collision.
    #[arg(long, value_enum, default_value = "newton")]
    pub impact_law: plant::impact::ImpactLaw,
    /// Restitution coefficient e_n in [0, 1] (of the velocity for Newton, of the impulse
    /// for Poisson, of the normal work for energetic).
    #[arg(long, default_value_t = 0.2)]
    pub e_n: f64,
    /// Simulated time, s.
    #[arg(long, default_value_t = 10.0)]
    pub duration: f64,
    /// Sampling period of trace.csv, s (events are written at their exact times in events.csv).
    #[arg(long, default_value_t = 1e-3)]
    pub sample_dt: f64,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-9)]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[arg(long, default_value_t = 1e-11)]
    pub atol: f64,
    /// Impact-without-collision rule: `restitution` (the law's restitution throws the
    /// tip off the belt) or `plastic` (the tip is left stuck tangentially, v_n = 0).
    #[arg(long, value_enum, default_value = "restitution")]
    pub iwc: plant::impact::IwcRule,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.m=0.24 --set plant.h=0.35`: KEYS plant.m, plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g. Repeatable;
    /// the defaults are the paper's. Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host admissible`.
#[derive(Debug, Clone, Args)]
pub struct AdmissibleArgs {
    /// Friction coefficient mu (>= 0).
    #[arg(long, default_value_t = 0.6, allow_hyphen_values = true)]
    pub mu: f64,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.l=0.25 --set plant.h=0.35`: KEYS plant.l, plant.h. Repeatable;
    /// the defaults are the paper's. Only these change where p > 0 (m scales p; the rest do not enter it). Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host modes`.
#[derive(Debug, Clone, Args)]
pub struct ModesArgs {
    /// Friction coefficient mu (>= 0).
    #[arg(long, default_value_t = 0.6, allow_hyphen_values = true)]
    pub mu: f64,
    /// Belt speed v_belt, m/s (sets the sign of z_r_dot, hence which p applies).
    #[arg(long, default_value_t = -0.4, allow_hyphen_values = true)]
    pub v_belt: f64,
    /// Elbow branch for theta2 (the tip is put on the belt on this branch).
    #[arg(long, value_enum, default_value = "down")]
    pub branch: shared::ElbowBranch,
    /// theta1 range in degrees: MIN,MAX.
    #[arg(long, default_value = "-90,90", value_name = "MIN,MAX", allow_hyphen_values = true)]
    pub theta1_deg: String,
    /// theta1_dot range in rad/s: MIN,MAX.
    #[arg(long, default_value = "-10,10", value_name = "MIN,MAX", allow_hyphen_values = true)]
    pub theta1_dot: String,
    /// Grid points along each axis.
    #[arg(long, default_value_t = 400)]
    pub grid: usize,
    /// Which root of cos(theta2) = H/l - cos(theta1) to use. `auto`: the one on
    /// `--branch` (minus for down, plus for up); points whose configuration is then
    /// not on `--branch` are unreachable (theta1 < -25.98 deg for down, > 25.98 deg for up).
    /// `plus`/`minus`: that root over the whole theta1 range, `--branch` ignored; the
    /// elbow branch then changes at the straight arm (`plus` holds x0a, `minus` x0u
    /// and x0d) and is written per point in modes.csv. Default `plus`: the root through
    /// the paper's x0a, which crosses the Painlevé region (paper Fig. 2).
    #[arg(long, value_enum, default_value = "plus")]
    pub theta2_sign: analyses::modes::Theta2Sign,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.m=0.24 --set plant.h=0.35`: KEYS plant.m, plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g. Repeatable;
    /// the defaults are the paper's. Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host poincare`.
#[derive(Debug, Clone, Args)]
pub struct PoincareArgs {
    /// Friction coefficient mu (>= 0).
    #[arg(long, default_value_t = 0.6)]
    pub mu: f64,
    /// Initial condition: one of the paper's (projected onto the belt).
    #[arg(long, value_enum, default_value = "a", conflicts_with = "x0_deg")]
    pub x0: plant::initial::PaperX0,
    /// Initial condition in degrees and degrees per second: th1,th1dot,th2,th2dot.
    #[arg(long, value_name = "TH1,TH1DOT,TH2,TH2DOT", allow_hyphen_values = true)]
    pub x0_deg: Option<String>,
    /// Belt-speed range, m/s: MIN,MAX (both ends included), or one speed. The default covers
    /// the band where the open loop from x0a keeps bouncing at mu = 0.6 (found
    /// with this command over [-1, -0.1] in steps of 0.02, then 0.002: from about
    /// -0.864 to -0.310 m/s, with steady sliding interleaved between -0.864 and
    /// -0.782), with steady sliding at both ends.
    #[arg(long, default_value = "-0.90,-0.30", value_name = "MIN,MAX|V", allow_hyphen_values = true)]
    pub v_belt: String,
    /// Grid step of v_belt, m/s.
    #[arg(long, default_value_t = 0.002)]
    pub v_step: f64,
    /// Transient discarded before recording, s.
    #[arg(long, default_value_t = 250.0)]
    pub transient: f64,
    /// Record window, s.
    #[arg(long, default_value_t = 50.0)]
    pub record: f64,
    /// Tolerance on section points (theta1 and theta2, rad) for the period and the
    /// count of distinct points.
    #[arg(long, default_value_t = 1e-4)]
    pub tol: f64,
    /// Largest period looked for.
    #[arg(long, default_value_t = 32)]
    pub max_period: usize,
    /// Hysteresis of the section, rad/s: an upward crossing counts only after
    /// theta1_dot went below minus this (steady sliding has theta1_dot = 0 to
    /// about 1e-11 rad/s of rounding noise, which must not count as motion).
    #[arg(long, default_value_t = 1e-6)]
    pub section_depth: f64,
    /// An aperiodic motion is chaotic when its largest Lyapunov exponent per
    /// section crossing, less twice its standard error, exceeds this.
    #[arg(long, default_value_t = 0.01)]
    pub chaos_threshold: f64,
    /// Crossings averaged in the Lyapunov estimate (0: no estimate).
    #[arg(long, default_value_t = 200)]
    pub lyap_iterations: usize,
    /// Crossings discarded first in the Lyapunov estimate.
    #[arg(long, default_value_t = 20)]
    pub lyap_skip: usize,
    /// Separation of the two trajectories after each renormalisation (state norm,
    /// rad and rad/s).
    #[arg(long, default_value_t = 1e-7)]
    pub lyap_d0: f64,
    /// Impact law at touchdown and for impacts without collision.
    #[arg(long, value_enum, default_value = "newton")]
    pub impact_law: plant::impact::ImpactLaw,
    /// Restitution coefficient e_n in [0, 1].
    #[arg(long, default_value_t = 0.2)]
    pub e_n: f64,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-9)]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[arg(long, default_value_t = 1e-11)]
    pub atol: f64,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Impact-without-collision rule: `restitution` (the law's restitution throws the
    /// tip off the belt) or `plastic` (the tip is left stuck tangentially, v_n = 0).
    #[arg(long, value_enum, default_value = "restitution")]
    pub iwc: plant::impact::IwcRule,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Change one of the arm's parameters (paper Table I; SI units, radians), e.g.
    /// `--set plant.m=0.24 --set plant.h=0.35`: KEYS plant.m, plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g. Repeatable;
    /// the defaults are the paper's. Keys set by a flag of this command
    /// (`plant.mu`: --mu, ...) are refused: a key is set in one place.
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Output options.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `sil-host sweep`.
#[derive(Debug, Clone, Args)]
pub struct SweepArgs {
    /// Friction coefficients: MIN,MAX (or one value), spaced by --mu-step.
    #[arg(long, default_value = "0.1,1", value_name = "MIN,MAX", allow_hyphen_values = true)]
    pub mu: String,
    /// Spacing of --mu.
    #[arg(long, default_value_t = 0.1)]
    pub mu_step: f64,
    /// Belt speeds, m/s: MIN,MAX (or one value), spaced by --v-belt-step.
    #[arg(long, default_value = "-1,-0.1", value_name = "MIN,MAX", allow_hyphen_values = true)]
    pub v_belt: String,
    /// Spacing of --v-belt, m/s.
    #[arg(long, default_value_t = 0.005)]
    pub v_belt_step: f64,
    /// The paper's initial conditions to use (projected onto the belt at the same
    /// z_t and elbow branch): any of a, d, u, comma-separated; `none` for only random ones.
    #[arg(long, value_delimiter = ',', default_value = "a,d", value_name = "LIST")]
    pub ics: Vec<String>,
    /// Random initial conditions in contact, added to --ics: the tip on the belt at
    /// z_t uniform within 90 % of the reach, a random elbow branch, at rest; the same
    /// ones at every grid point.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub random_ics: usize,
    /// Seed of the random initial conditions.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Transient before the record window, s.
    #[arg(long, default_value_t = 250.0)]
    pub transient: f64,
    /// Record window, s.
    #[arg(long, default_value_t = 50.0)]
    pub record: f64,
    /// What drives the arm: `none` (open loop, u = 0; experiment 3), or the firmware's
    /// `hybrid` (experiment 7) or `pid` controller run in-process, sampled as on the
    /// MCU, with the scenario's references (experiment 6's by default).
    #[arg(long, value_enum, default_value = "none")]
    pub controller: analyses::sweep::SweepController,
    /// Closed loop: the paper's continuous-time controller with exact measurements
    /// instead of the sampled firmware.
    #[arg(long)]
    pub ideal: bool,
    /// Closed loop: scenario whose controller, timing and sensor sections are used
    /// (default: the embedded default, experiment 6's hybrid references). Its plant
    /// section is replaced per run (except the arm's parameters); mu_hat is set to
    /// each run's mu, and, unless it gives controller.hybrid.ki, K'_I to 0 from
    /// elbow-up initial conditions and 650 otherwise (the paper's gains).
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Impact laws, comma-separated (each is a sweep dimension).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "newton")]
    pub impact_law: Vec<plant::impact::ImpactLaw>,
    /// Restitution coefficients e_n in [0, 1], comma-separated (each is a sweep dimension).
    #[arg(long, value_delimiter = ',', default_value = "0.2")]
    pub e_n: Vec<f64>,
    /// Impact-without-collision rules, comma-separated (each is a sweep dimension):
    /// `restitution` (the tip is thrown off the belt), `plastic` (left stuck, v_n = 0).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "restitution")]
    pub iwc: Vec<plant::impact::IwcRule>,
    /// Persistent bouncing is flagged when max theta1_dot over the record window
    /// exceeds this, rad/s. The paper's threshold is 0; an arm at rest shows
    /// theta1_dot ~ 5e-15 rad/s from rounding, hence the small default.
    #[arg(long, default_value_t = analyses::sweep::DEFAULT_THRESHOLD)]
    pub threshold: f64,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-9)]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[arg(long, default_value_t = 1e-11)]
    pub atol: f64,
    /// Change one key, e.g. `--set plant.m=0.24` (repeatable; KEY=VALUE as for
    /// `run`). Open loop: only the arm's parameters (paper Table I: plant.m,
    /// plant.l, plant.sigma, plant.k, plant.h, plant.alpha0, plant.g). Closed loop:
    /// any key of the scenario except those the sweep sets per run (plant.mu,
    /// plant.v_belt, plant.x0, plant.impact_law, plant.e_n, plant.rtol, plant.atol,
    /// controller.kind, controller.mu_hat, timing.duration_s). Part of the sweep's
    /// identity (sweep.json).
    #[arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true)]
    pub set: Vec<rig::overrides::Override>,
    /// Compute only shard K of N (0 <= K < N), for a cluster job array; join the
    /// shards' folders with `sil-host merge`. The runs are dealt to the shards so
    /// that each gets an equal share of every initial condition and `mu`
    /// (docs/analyses.md, "Cluster").
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Compute at most N more runs, then write the outputs and stop (exit 0); run
    /// again to continue. For timing a subset, or sweeping in installments.
    #[arg(long, value_name = "N")]
    pub limit: Option<usize>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Exit status on model violations.
    #[command(flatten)]
    pub strict: StrictArgs,
    /// Folder of the sweep (created if missing; an existing sweep there is resumed).
    #[arg(long, default_value = "out/sweep", value_name = "DIR")]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}

/// `sil-host merge`.
#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// The shards' folders.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Write the outputs even if runs are missing (they are listed in the summary).
    #[arg(long)]
    pub allow_missing: bool,
    /// Folder of the merged sweep (a complete sweep folder, like an unsharded run's).
    #[arg(long, default_value = "out/sweep-merged", value_name = "DIR")]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}
