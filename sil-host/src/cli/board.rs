//! The arguments of `board` (a board's bring-up, step by step) and `board-twin`
//! (the simulated board serving it).

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};

use experiments::settings::ScenarioArgs;

/// `sil-host board`.
#[derive(Debug, Clone, Args)]
pub struct BoardArgs {
    /// The board's serial port: a USB-serial adapter on USART1 (PA9/PA10), or the
    /// path `sil-host board-twin --pty` printed.
    #[arg(long, value_name = "PATH")]
    pub port: PathBuf,
    /// The line rate, baud (8N1, no flow control).
    #[arg(long, default_value_t = rig::pil_link::DEFAULT_BAUD, value_name = "BAUD")]
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
    /// The raw readings every --interval-ms on one line of at most 80 columns
    /// (rewritten in place on a terminal; one line per reading into a pipe or a file;
    /// --json: one document per reading), until Ctrl-C or --count: the period, the
    /// drivers, the joints (degrees once the zeros are set), the load cell (newtons
    /// once tared and spanned or skipped, else ADC counts), the belt's count, the
    /// fault line when asserted, the status in short.
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
    /// gain = force / (count - tare). Needs the tare first (`calibrate`). With
    /// --skip, keeps the nominal gain instead and the record says the span was
    /// skipped; `save` needs each axis spanned or skipped.
    Span {
        /// The axis: tangential (f_t) or normal (f_n).
        #[arg(long, value_enum)]
        axis: AxisArg,
        /// The force, N (|F| <= 25).
        #[arg(long, required_unless_present = "skip", conflicts_with = "skip", allow_hyphen_values = true)]
        newtons: Option<f64>,
        /// Keep the axis's nominal gain (no known weight at hand).
        #[arg(long)]
        skip: bool,
    },
    /// Sends the firmware configuration of a scenario (controller, gains, rate,
    /// limits); the firmware validates it. The rate (`timing.rate_hz`) is any the
    /// image runs, 250 Hz to 10 kHz (control periods of 100 to 4000 us): the
    /// board's control tick follows it at once, and the period it runs is read
    /// back and printed; a rate outside is refused, exit 2, nothing sent. The
    /// runaway limits must be on (`controller.runaway_limits = false` is refused,
    /// exit 2: a board never runs without them). Echoes each setting it changed
    /// (`KEY = OLD -> NEW`); unsaved until `save`. A law of one's own
    /// (docs/board.md "Your own law"): give the image that was flashed with
    /// `--elf`; the scenario's `[law]` table is bound to the law it declares,
    /// which must be the law the board reports (its declaration's digest),
    /// else exit 2, nothing sent.
    Configure {
        /// The scenario.
        #[command(flatten)]
        scenario: ScenarioArgs,
        /// The ELF flashed on the board, for its law's declaration
        /// (`PAINLEVE_LAW_SPEC`; an ELF without one is refused); the paper's
        /// laws without --elf. A regular file of at most 64 MiB.
        #[arg(long, value_name = "ELF")]
        elf: Option<std::path::PathBuf>,
    },
    /// Saves the calibration and configuration in force to flash (version and
    /// CRC-32C); they are loaded at every reset. Until saved the drivers stay
    /// locked out. Refused (exit 1, naming what is missing) unless the
    /// calibration is complete: zeros set, both directions checked, tared, each
    /// axis spanned or skipped; and when nothing is unsaved (the settings in force
    /// are the record already: a reset since a `configure` reloaded the record and
    /// discarded it).
    Save,
    /// Lifts the reduced torque limit a new calibration runs at (both joints'
    /// directions must have been checked).
    LiftTorqueLimit,
    /// Enables the drivers: resets the firmware, which closes the loop; then reads
    /// the state back until the drivers are on, and watches them for 50 of the
    /// board's periods. Exit 1 naming why when they are not on, or went off within
    /// the watch (locked out, their fault line, the firmware's safe state and its
    /// reason).
    Enable,
    /// Disables the drivers now.
    Disable,
    /// Writes the board's calibration and firmware configuration in force to FILE,
    /// as TOML (read over the line: what `save` would store; docs/board.md "Backup
    /// and restore"). Refuses to overwrite FILE without --force.
    Backup {
        /// The backup file to write (TOML).
        file: PathBuf,
        /// Overwrite FILE if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Restores a backup FILE: the calibration and configuration together. The
    /// file is checked here (TOML, format version, the bring-up protocol, every
    /// key known and typed, every value by the firmware's own rules: exit 2 naming
    /// the key, nothing sent); the firmware checks it again as it checks its flash
    /// record at reset, and takes it whole or refuses it (exit 1; the board
    /// unchanged). Drivers disabled only. The
    /// restored settings are not saved: `save`, then `lift-torque-limit` if the
    /// calibration changed, before `enable`.
    Restore {
        /// The backup file to read (TOML, from `backup`).
        file: PathBuf,
    },
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
    /// Serve on a new pseudo-terminal (the only transport). Standard input takes
    /// the operator's actions, one a line: `weight normal|tangential NEWTONS`,
    /// `weight off`, `reset` (the reset button), `belt up` (the belt raised to the
    /// tip: the arm at the scenario's initial pose on the running belt, held while
    /// the drivers are off) and `belt down`.
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
    /// Serve the unmodified `arm` ELF on the emulated board instead of the twin's
    /// application (docs/board.md "The emulated image"): the bring-up protocol
    /// then runs through the image's own USART1, flash and timers.
    #[arg(long)]
    pub emulated: bool,
    /// With --emulated: the `arm` ELF (default target/thumbv7em-none-eabihf/mcu/arm).
    #[arg(long, value_name = "PATH", requires = "emulated")]
    pub elf: Option<std::path::PathBuf>,
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
