//! What the image measured of itself: the tick counts of each answered frame
//! (the step's own and the whole frame's), in fixed memory, with their unit
//! (instructions under QEMU, cycles on silicon) and the step's budget they are
//! judged against.

use firmware::pil::StepClock;

use super::qemu::ICOUNT_SHIFT;
use crate::{envelope::Envelope, stats::CountDistribution, summary::CountUnit};

/// Core clock of the reference board, Hz (docs/hardware.md: 168 MHz): the clock the
/// step budget is counted in.
pub const CORE_HZ: f64 = 168e6;

/// Budget of a control step at the default 1 kHz rate: 5 % of 1 ms at 168 MHz
/// (docs/hardware.md "Budgets"), 8400 cycles, or instructions under QEMU (each at
/// least one cycle). Other rates: [`step_budget`].
pub const STEP_BUDGET_INSTRUCTIONS: f64 = 8_400.0;

/// Budget of a control step at `rate_hz` (Hz): 5 % of the control period at
/// 168 MHz, in cycles on silicon and in instructions under QEMU (a lower bound
/// of cycles); [`STEP_BUDGET_INSTRUCTIONS`] at 1 kHz, 840 at 10 kHz. Not finite
/// for a rate that is not positive.
pub fn step_budget(rate_hz: f64) -> f64 {
    // 168e6 / 1000 / 20 is exactly 8400 (0.05 * ... would round).
    CORE_HZ / rate_hz / 20.0
}

/// What the image measured, one sample per answered frame, in its tick unit:
/// exact distributions and decimated series against time in fixed memory, and
/// every sample only when asked
/// ([`PilOptions::keep_ticks`](super::PilOptions::keep_ticks)).
#[derive(Debug, Clone)]
pub struct PilCounts {
    /// Answered frames.
    pub answers: u64,
    /// `step_ticks` of each command ([`firmware::Firmware::step`]'s own time): their distribution.
    pub step: CountDistribution,
    /// The frame's time (decoding: COBS, CRC, postcard; plus the step): its distribution.
    pub frame: CountDistribution,
    /// `step_ticks` against the frame's sample time `t_k` (s), decimated ([`Envelope`]) for figures.
    pub step_series: Envelope,
    /// Frame ticks against `t_k` (s), decimated for figures.
    pub frame_series: Envelope,
    /// Every `step_ticks`, in period order; empty unless
    /// [`PilOptions::keep_ticks`](super::PilOptions::keep_ticks).
    pub step_ticks: Vec<u32>,
    /// Every frame's ticks, in period order; empty unless
    /// [`PilOptions::keep_ticks`](super::PilOptions::keep_ticks).
    pub frame_ticks: Vec<u32>,
    pub(super) keep_ticks: bool,
    /// The image's tick rate (its `Hello`), Hz.
    pub ticks_per_second: u32,
    /// What its ticks count (its `Hello`): emulated SysTick or DWT cycles
    /// (`EmulatedSysTick` until the Hello arrives).
    pub clock: StepClock,
}

impl Default for PilCounts {
    fn default() -> Self {
        Self {
            answers: 0,
            step: CountDistribution::default(),
            frame: CountDistribution::default(),
            step_series: Envelope::new(),
            frame_series: Envelope::new(),
            step_ticks: Vec::new(),
            frame_ticks: Vec::new(),
            keep_ticks: false,
            ticks_per_second: 0,
            clock: StepClock::EmulatedSysTick,
        }
    }
}

impl PilCounts {
    /// Adds one answer's counts, of the frame sampled at `t` (s).
    pub fn record(&mut self, t: f64, step_ticks: u32, frame_ticks: u32) {
        self.answers += 1;
        self.step.record(step_ticks);
        self.frame.record(frame_ticks);
        self.step_series.push(t, f64::from(step_ticks));
        self.frame_series.push(t, f64::from(frame_ticks));
        if self.keep_ticks {
            self.step_ticks.push(step_ticks);
            self.frame_ticks.push(frame_ticks);
        }
    }

    /// Instructions retired per tick under `-icount shift=ICOUNT_SHIFT`: QEMU's
    /// SysTick runs at the core clock of *virtual* time, and virtual time is
    /// `2^shift` ns per instruction. Meaningful for [`StepClock::EmulatedSysTick`] only.
    pub fn instructions_per_tick(&self) -> f64 {
        1e9 / (self.ticks_per_second.max(1) as f64 * (1u64 << ICOUNT_SHIFT) as f64)
    }

    /// The unit of the counts: instructions (emulated) or cycles (silicon).
    pub fn unit(&self) -> CountUnit {
        CountUnit::of(self.clock)
    }

    /// Counts of [`Self::unit`] per tick: [`Self::instructions_per_tick`] under
    /// QEMU, 1 for DWT cycles (one tick is one cycle).
    pub fn counts_per_tick(&self) -> f64 {
        match self.clock {
            StepClock::EmulatedSysTick => self.instructions_per_tick(),
            StepClock::DwtCycles | StepClock::Simulated => 1.0,
        }
    }
}
