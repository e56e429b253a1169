//! The step's tick counter: the DWT cycle counter on silicon; SysTick at the
//! core clock where the DWT is not modelled (QEMU's `netduinoplus2`, whose
//! `CYCCNT` reads 0: there, under `-icount shift=0`, ticks follow retired
//! instructions, not cycles). [`CycleClock::mark`] starts an interval at an
//! event (the control tick, a frame's arrival); `ticks()` counts from there.

use cortex_m::peripheral::{DCB, DWT, SYST, syst::SystClkSource};
use firmware::{TickClock, pil::StepClock};

use crate::clock_tree::SYSCLK_HZ;

/// SysTick's reload in the emulator: the full 24 bits (0.1 s at 168 MHz).
const RELOAD: u32 = 0x00FF_FFFF;

/// The counter in use.
#[derive(Debug, Clone, Copy)]
pub struct CycleClock {
    kind: StepClock,
}

impl CycleClock {
    /// Enables the DWT cycle counter (trace first, RM0090 / ARMv7-M C1.8) and
    /// keeps it if it counts; else runs SysTick free at the core clock.
    pub fn start(dcb: &mut DCB, dwt: &mut DWT, syst: &mut SYST) -> Self {
        dcb.enable_trace();
        DWT::unlock();
        dwt.enable_cycle_counter();
        let before = DWT::cycle_count();
        cortex_m::asm::delay(64);
        if DWT::cycle_count() != before {
            return Self { kind: StepClock::DwtCycles };
        }
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();
        Self { kind: StepClock::EmulatedSysTick }
    }

    /// What the ticks are.
    pub fn kind(&self) -> StepClock {
        self.kind
    }

    /// Starts an interval: SysTick restarts from its reload (its 0.1 s wrap
    /// bounds an interval); the DWT runs on (its differences wrap in 25 s).
    pub fn mark(&self) -> u32 {
        match self.kind {
            StepClock::DwtCycles | StepClock::Simulated => DWT::cycle_count(),
            StepClock::EmulatedSysTick => {
                // SAFETY: a write of any value clears the current-value register
                // (it then reloads); SysTick belongs to this clock.
                unsafe { (*SYST::PTR).cvr.write(0) };
                0
            }
        }
    }
}

impl TickClock for CycleClock {
    fn ticks(&self) -> u32 {
        match self.kind {
            StepClock::DwtCycles | StepClock::Simulated => DWT::cycle_count(),
            // Right after the restart the counter reads 0 until it reloads.
            StepClock::EmulatedSysTick => match SYST::get_current() {
                0 => 0,
                current => RELOAD - current.min(RELOAD),
            },
        }
    }
    fn ticks_per_second(&self) -> u32 {
        SYSCLK_HZ
    }
}

impl arm_app::IntervalClock for CycleClock {
    fn mark(&self) -> u32 {
        CycleClock::mark(self)
    }
    fn kind(&self) -> StepClock {
        CycleClock::kind(self)
    }
}
