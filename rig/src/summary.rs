//! The typed summary of a closed-loop run (`summary.json` of `sil-host run` and
//! `sil-host pil`): what every run reports, and the PIL figures of the image.

use serde::Serialize;

use firmware::pil::StepClock;
use plant::Validity;

use super::{
    realtime::RealtimeSetup,
    record::{LiftOffStats, PeriodRecord, RunError},
    scenario::Scenario,
    stats::RunStats,
};

// Their home is `stats` (the accumulators that make them); here for `summary.json`'s readers.
pub use super::stats::{Percentiles, Spread, percentiles};

/// `summary.json` of a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// `ok` or `failed`.
    pub status: &'static str,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
    /// Scenario name.
    pub scenario: String,
    /// `hybrid` or `pid`; a law of one's own's name (the scenario's `[law]`
    /// table, [`crate::scenario::Scenario::controller_name`]).
    pub controller: String,
    /// The control law that ran, in words, as every view names it (trace.html, the
    /// MCAP's `/log` and `painleve.run` record, Python's `Result.law`): `hybrid`,
    /// `pid`, ``law `impedance` (k_t = 2500, the rest at their defaults)``
    /// ([`crate::scenario::Scenario::law_in_words`]); `Python <name>` for
    /// `painleve.run_controller`'s callable.
    pub law: String,
    /// `iceoryx2` or `in-process`; `pil-qemu` or `pil-serial` for `sil-host pil`.
    pub transport: &'static str,
    /// `lockstep` or `realtime` (`in-process` runs are lockstep).
    pub timing: &'static str,
    /// The rig's name (its iceoryx2 services); `null` in-process.
    pub rig: Option<String>,
    /// Control periods run.
    pub periods: usize,
    /// Lift-off statistics.
    #[serde(flatten)]
    pub lift_off: LiftOffStats,
    /// The plant's validity counters (energy-creating impacts, fallbacks, cone
    /// violations, Zeno stops, integrator failures; `plant::Validity`).
    pub validity: Validity,
    /// The plant's energy ledger (docs/plant.md "The energy ledger"): the works of
    /// the motors, the damping, the belt and the contact, what they leave unexplained.
    pub ledger: plant::Ledger,
    /// Deadline misses seen by the plant (no command, lost, or late past `t_k + Ts`).
    pub deadline_misses: usize,
    /// Deadline misses the firmware counted itself (its overrun counter at the end).
    pub firmware_overruns: u32,
    /// RMS of `z_t - z_t*` over the run, m.
    pub rms_tracking_error_m: f64,
    /// `z_t` at the end, m.
    pub final_z_t_m: f64,
    /// Wall-clock time of the loop, s.
    pub wall_s: f64,
    /// Simulated seconds per wall second.
    pub realtime_factor: f64,
    /// Control periods per wall-clock second.
    pub periods_per_s: f64,
    /// iceoryx2 runs: frame published to command received, us.
    pub ipc_rtt_us: Option<Percentiles>,
    /// iceoryx2 runs: the firmware's step time as it measured it, us.
    pub firmware_step_us: Option<Percentiles>,
    /// Real-time runs: frame publication minus its ideal wall time, us.
    pub period_jitter_us: Option<Percentiles>,
    /// iceoryx2 runs: commands that arrived after their period was given up.
    pub late_answers: u64,
    /// Real-time iceoryx2 runs: the plant loop's CPU and `SCHED_FIFO` priority,
    /// and what the kernel refused (`rig.realtime_cpu`, `rig.realtime_fifo_priority`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub realtime_setup: Option<RealtimeSetup>,
    /// PIL runs: the image's instruction counts and log (`sil-host pil`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pil: Option<PilFigures>,
    /// Runs with `--monitors`: what the plant did for monitors (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monitors: Option<MonitorSummary>,
    /// The scenario as run (after command-line overrides).
    pub scenario_used: Scenario,
    /// The plant's parameters as run: paper Table I, `mu`, `v_belt` (SI, radians;
    /// [`crate::setup::plant_params`]).
    pub plant_params: shared::Params<f64>,
    /// The firmware's configuration as run ([`crate::setup::firmware_config`]): its
    /// model of the arm (`params`, `mu` = `mu_hat`), the PID gains (paper eq. 8),
    /// the hybrid gains (eqs. 9 to 11, `K'_I` resolved), references and limits.
    pub firmware_config: firmware::Config,
    /// The firmware's own announcement of what it runs (the handshake before
    /// period 0, [`crate::handshake`]): equal to `firmware_config` or the run
    /// would have been refused; `null` for PIL runs (the image checks its
    /// protocol version instead).
    pub firmware_announcement: Option<crate::handshake::Announced>,
}

impl RunSummary {
    /// The figures every run has, from its `records` (the trace as recorded, up to
    /// the failure if there was one) and its wall-clock time `wall_s` (s); the
    /// transport's own figures (round trip, jitter, step time, PIL counts) empty.
    /// [`RunSummary::from_stats`] of [`RunStats::of`] the records.
    pub fn from_records(
        scenario: &Scenario,
        records: &[PeriodRecord],
        failure: Option<&RunError>,
        transport: &'static str,
        timing: &'static str,
        wall_s: f64,
        validity: Validity,
    ) -> Self {
        Self::from_stats(scenario, &RunStats::of(records), failure, transport, timing, wall_s, validity)
    }

    /// The figures every run has, from its streamed statistics `stats` (every
    /// period recorded, up to the failure if there was one) and its wall-clock
    /// time `wall_s` (s); the transport's own figures (round trip, jitter, step
    /// time, PIL counts) empty.
    pub fn from_stats(
        scenario: &Scenario,
        stats: &RunStats,
        failure: Option<&RunError>,
        transport: &'static str,
        timing: &'static str,
        wall_s: f64,
        validity: Validity,
    ) -> Self {
        let periods = stats.periods();
        let simulated = periods as f64 * scenario.timing.period().as_secs_f64();
        Self {
            status: if failure.is_some() { "failed" } else { "ok" },
            error: failure.map(|e| e.to_string()),
            scenario: scenario.name.clone(),
            controller: scenario.controller_name().to_string(),
            law: scenario.law_in_words(),
            transport,
            timing,
            rig: None,
            periods,
            lift_off: stats.lift_off(),
            validity,
            ledger: plant::Ledger::default(),
            deadline_misses: stats.deadline_misses(),
            firmware_overruns: stats.max_overruns(),
            rms_tracking_error_m: stats.rms_tracking_error(),
            final_z_t_m: stats.final_z_t(),
            wall_s,
            realtime_factor: simulated / wall_s.max(1e-9),
            periods_per_s: periods as f64 / wall_s.max(1e-9),
            ipc_rtt_us: None,
            firmware_step_us: None,
            period_jitter_us: None,
            late_answers: 0,
            realtime_setup: None,
            pil: None,
            monitors: None,
            scenario_used: scenario.clone(),
            plant_params: crate::setup::plant_params(scenario),
            firmware_config: crate::setup::firmware_config(scenario),
            firmware_announcement: None,
        }
    }
}

/// The `monitors` part of `summary.json` (`sil-host run --monitors N`; docs/rig.md,
/// "Monitors").
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MonitorSummary {
    /// Monitors (subscribers of `ground_truth`) the plant waited for before period 0.
    pub waited_for: usize,
    /// Whether the plant waited for a monitor whose buffer was full (lockstep)
    /// rather than discarding the sample for it (real time).
    pub lossless: bool,
    /// How long one sample waited for a full monitor before it was given up, s.
    pub timeout_s: f64,
    /// Monitors given up (dead, stopped or too slow); they then lost samples.
    pub given_up: u32,
    /// Samples not delivered to given-up monitors (one per monitor per sample).
    pub samples_dropped: u64,
}

/// RMS of `z_t - z_t*` over `records`, m (0 when empty; [`RunStats::rms_tracking_error`]).
pub fn rms_tracking_error(records: &[PeriodRecord]) -> f64 {
    RunStats::of(records).rms_tracking_error()
}

/// The PIL part of `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct PilFigures {
    /// How the bytes travelled: `qemu-semihosting` (QEMU spawned here, host FIFOs
    /// through semihosting), `qemu-socket` (QEMU spawned here, its emulated USART1
    /// on a Unix socket) or `serial`.
    pub transport: &'static str,
    /// Serial runs: the device.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub serial_port: Option<String>,
    /// Serial runs: the line rate, baud (8N1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baud: Option<u32>,
    /// The image that ran under QEMU; `null` over a serial port (it is in the board's flash).
    pub image: Option<String>,
    /// QEMU's `-icount` shift (one instruction per `2^shift` ns of virtual time);
    /// `null` over a serial port.
    pub qemu_icount_shift: Option<u32>,
    /// The image's tick rate (its core clock), Hz.
    pub ticks_per_second: u32,
    /// What the image's tick counter is (its Hello): `EmulatedSysTick` or `DwtCycles`.
    pub step_clock: firmware::pil::StepClock,
    /// Unit of `step_counts`, `frame_counts` and `step_budget`: `instructions`
    /// (emulated SysTick under `-icount`) or `cycles` (DWT on silicon).
    pub count_unit: CountUnit,
    /// `count_unit`s per tick: `1e9 / (ticks_per_second 2^shift)` instructions
    /// under QEMU, 1 cycle on silicon.
    pub counts_per_tick: f64,
    /// `Firmware::step` (sensor decode to command encode), in `count_unit`:
    /// median, 99th percentile, worst.
    pub step_counts: Spread,
    /// A frame's last byte to its answer ready to send (COBS, CRC and postcard
    /// decoding plus the step), in `count_unit`.
    pub frame_counts: Spread,
    /// The budget of a step in `count_unit` (docs/hardware.md: 5 % of the control
    /// period at 168 MHz; 8400 at 1 kHz).
    pub step_budget: f64,
    /// Whether the worst step is within the budget.
    pub within_budget: bool,
    /// Worst step as a share of the control period at 168 MHz (for instructions:
    /// if each took one cycle, a lower bound on silicon: docs/rig.md).
    pub worst_step_period_share: f64,
    /// QEMU's exit status at the end (`exit status: 0` when the image ended the
    /// run); `null` over a serial port.
    pub qemu_exit: Option<String>,
    /// Where the image's defmt log is: `defmt.log`, or why it is not captured.
    pub defmt_log: String,
    /// Lines of the image's defmt log; `null` when it is not captured.
    pub defmt_lines: Option<usize>,
    /// Of which at `warn` or `error` level; `null` when it is not captured.
    pub defmt_warnings: Option<usize>,
}

/// What the step counts of a run are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CountUnit {
    /// Instructions retired (QEMU under `-icount`; a lower bound of cycles).
    Instructions,
    /// Core clock cycles (silicon).
    Cycles,
}

impl CountUnit {
    /// The unit of an image's tick counter.
    pub fn of(clock: StepClock) -> Self {
        match clock {
            StepClock::EmulatedSysTick => Self::Instructions,
            StepClock::DwtCycles | StepClock::Simulated => Self::Cycles,
        }
    }

    /// `instructions` or `cycles`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Instructions => "instructions",
            Self::Cycles => "cycles",
        }
    }
}
