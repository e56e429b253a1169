//! The arguments of `bench` (every speed and size figure against its target).

use std::path::PathBuf;

use clap::Args;

/// `sil-host bench`.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Figure groups to measure, comma-separated (default: all but cycles and
    /// realtime): step (worst control step in PIL, instructions), cycles (its
    /// Cortex-M4 cycle estimate and the highest rate it allows, scripts/cycles.py,
    /// about 2 min), flash (the PIL image's size),
    /// in-process, lockstep (iceoryx2), twin (the board twin's closed loop),
    /// emulator (the flashed `arm` image on the emulated board: its control
    /// handler's cycles, counted, at 1 kHz, 10 kHz and over random scenarios),
    /// pil (PIL periods per wall second), simulate
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
