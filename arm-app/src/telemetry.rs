//! The arm image's telemetry: one message per window of [`crate::step_stats::WINDOW`]
//! periods, on USART1's TX line in the PIL wire's framing (postcard, CRC-32,
//! COBS: `firmware::pil::encode`), so a USB-serial adapter and the same decoder
//! read it. The defmt log carries the same figures.

use firmware::pil::StepClock;
use serde::{Deserialize, Serialize};

use crate::step_stats::WindowSummary;

/// One window's report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArmTelemetry {
    /// The last period of the window.
    pub seq: u32,
    /// The last command's status word (`shared::wire::status`).
    pub status: u32,
    /// Deadline overruns since the last reset (the firmware's counter).
    pub overruns: u32,
    /// Whether the motor drivers are enabled.
    pub drivers_enabled: bool,
    /// What the step's ticks are (cycles on silicon).
    pub clock: StepClock,
    /// The step's execution time over the window, ticks.
    pub step: WindowSummary,
    /// The shortest and longest interval between two control ticks in the
    /// window, ticks (their spread is the tick's jitter plus the handler's latency).
    pub tick_interval: [u32; 2],
    /// The longest control interrupt of the window (sampling, step, outputs), ticks.
    pub handler_worst: u32,
    /// The stack's high-water mark, bytes.
    pub stack_high_water_bytes: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::pil::{FrameBuffer, MAX_FRAME, Push, decode, encode};

    #[test]
    fn telemetry_round_trips_through_the_pil_framing() {
        let t = ArmTelemetry {
            seq: 123_456,
            status: 1 | (7 << 24),
            overruns: 2,
            drivers_enabled: false,
            clock: StepClock::DwtCycles,
            step: WindowSummary { steps: 1000, worst: 6123, median: 4016 },
            tick_interval: [167_900, 168_100],
            handler_worst: 9000,
            stack_high_water_bytes: 2048,
        };
        let mut buf = [0u8; MAX_FRAME];
        let wire = encode(&t, &mut buf).unwrap().to_vec();
        assert!(wire.len() < 64, "{} bytes: 0.3 ms at 2 Mbaud", wire.len());
        let mut fb = FrameBuffer::default();
        let mut got = None;
        for b in wire {
            if let Push::Frame(f) = fb.push(b) {
                got = Some(decode::<ArmTelemetry>(f).unwrap());
            }
        }
        assert_eq!(got, Some(t));
    }
}
