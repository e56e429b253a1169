//! Command-line interface of `sil-host` (clap): the program and its commands
//! ([`Cli`], [`Command`]); each command group's arguments in a file of its own
//! (the experiments' settings are [`experiments::settings`]), re-exported here.

mod bench;
mod board;
mod replay;
mod report;

use clap::{Parser, Subcommand};

pub use self::bench::BenchArgs;
pub use self::board::{AxisArg, BoardArgs, BoardCommand, BoardTwinArgs, FlashArg, JointArg};
pub use self::replay::{ReplayArgs, ReplayLink};
pub use self::report::{ReportArgs, ReportSize};
pub use experiments::settings::*;

/// `sil-host --version`: the package version, the commit it was built from
/// (`build.rs`: `git describe --always --dirty`, or `unknown` outside a git
/// checkout) and the optional features it was built with (`crate::features`).
pub const VERSION: &str =
    concat!(env!("CARGO_PKG_VERSION"), " (commit ", env!("SIL_HOST_COMMIT"), "; features: ", env!("SIL_HOST_FEATURES"), ")");

/// Plant simulator and rig for the Painlevé paradox on a two-link arm
/// (Marchese, Coraggio, Hogan, di Bernardo, ECC 2019).
///
/// Every command prints a human summary, or one JSON document with `--json`,
/// and writes its files under `--out DIR` (default `out/`). Every figure is an
/// SVG and a PDF of the same name, sized for a journal's column (3.5 in) or page
/// (7 in). Bad input exits with code 2 and writes nothing; a failure while
/// running exits with 1. A part this build lacks (`--version` lists its
/// features: board, live, formats, pdf) says which feature to build with (exit 2).
#[derive(Debug, Parser)]
#[command(name = "sil-host", version = VERSION, about, long_about)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open-loop simulation (u = 0) of the arm on the belt from one of the paper's
    /// initial conditions; writes trace.csv, events.csv, trace.svg, summary.json and
    /// trace.html (the arm animated on the belt beside the plots: one self-contained
    /// page, open it in a browser; docs/rig.md "The animated page").
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
    /// Writes trace.csv, summary.json, trace.svg and trace.html (the arm animated on
    /// the belt beside the plots, a time slider and play: one self-contained page, no
    /// network; long runs thinned to at most 5000 frames, as the page says; docs/rig.md
    /// "The animated page").
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
    ///   not over this link; the kill_firmware fault is not available. A law of one's own's
    ///   image: give the ELF that was flashed (--image), whose declaration binds the
    ///   scenario's [law] table and whose digest the image's Hello must carry.
    ///
    /// The worst and median step are reported against the budget, 5 % of the control
    /// period at 168 MHz (8400 at 1 kHz). Writes trace.csv, summary.json, trace.svg,
    /// trace.html (as run's), instructions.svg and (QEMU) defmt.log.
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
    /// first line, then serves in real time until Ctrl-C, SIGTERM or --serve-for. Its
    /// standard input takes the operator's hands, one a line: `weight normal|tangential
    /// NEWTONS` hangs a weight on the load cell, `weight off` takes it off, `reset`
    /// presses the reset button (the board restarts from its flash).
    #[command(allow_negative_numbers = true, name = "board-twin")]
    BoardTwin(BoardTwinArgs),
    /// Every speed and size figure against its target: the worst control step in PIL
    /// (instructions), the image's flash, the closed loop in-process and over
    /// iceoryx2, PIL periods per wall second, simulate 300 s with its trace, the
    /// closed-loop hybrid sweep (estimated), and optionally real time at 1 kHz
    /// (docs/measurements.md "Speed and scale"); --json for scripts.
    Bench(BenchArgs),
    /// Replays a recorded run through a firmware build (docs/rig.md "Replay"; copper-rs's
    /// resim and PX4's replay are the models): every sensor frame the run's firmware
    /// read, bit for bit (its folder's frames.csv, frames.arrow or trace.mcap), goes to
    /// the firmware of --link (this build in-process or over iceoryx2, another build's
    /// firmware process with --attach, the board twin, an `arm` ELF on the emulated
    /// board, a PIL image in QEMU), configured from the run's own scenario (--set
    /// changes it), and every answer is compared with the recorded one bit for bit:
    /// the command's torque codes, status and overrun counter, and the telemetry's
    /// 32-bit floats (references, estimates, measured forces, torques before
    /// quantisation). The frames are the recorded ones whatever the firmware answers
    /// (open loop, as a log replay). Prints "identical over N periods" or the first
    /// divergence: period, time, signal, both values.
    ///
    /// Exit codes: 0 identical; 1 a divergence (or the link failed part way); 2 bad
    /// input (not a run's folder, no frames recorded, a bad --set, no image).
    #[command(allow_negative_numbers = true)]
    Replay(ReplayArgs),
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
