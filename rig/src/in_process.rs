//! The in-process transport: the firmware step linked directly into the plant's
//! process, no IPC (`sil-host run --in-process`). The firmware's clock is the
//! frame's: its step takes no simulated time.

use firmware::board::FrozenClock;
use shared::wire::{GroundTruth, SensorFrame};

use plant::PlantEvent;

use super::{
    firmware_side::FirmwareSide,
    record::{PeriodRecord, RunError},
    rig::{Exchange, FirmwareLink, run_loop, run_loop_observed},
    scenario::Scenario,
};

/// The firmware step called directly.
#[derive(Debug, Clone)]
pub struct InProcessLink {
    side: FirmwareSide,
}

impl InProcessLink {
    /// The link for a scenario.
    ///
    /// # Errors
    /// [`RunError::Firmware`] for an invalid configuration; [`RunError::Unsupported`]
    /// when the scenario injects a fault that needs the firmware in its own process.
    pub fn new(s: &Scenario) -> Result<Self, RunError> {
        if let Some(f) = s.faults.iter().find(|f| f.needs_ipc()) {
            return Err(RunError::Unsupported(format!(
                "fault {:?} acts on the firmware process: run over iceoryx2 (without --in-process)",
                f.kind
            )));
        }
        Ok(Self { side: FirmwareSide::new(s)? })
    }
}

impl FirmwareLink for InProcessLink {
    fn transport(&self) -> &'static str {
        "in-process"
    }

    fn exchange(&mut self, frame: &SensorFrame, _truth: &GroundTruth) -> Result<Exchange, RunError> {
        let (command, telemetry) = self.side.answer(frame, frame.t_us, &FrozenClock);
        Ok(Exchange::Answered { command, telemetry, at_stamp: false })
    }
}

/// Runs the scenario in-process; `on_period(k, n)` is called after each period.
/// Returns every period's record, and the error if the run stopped early.
pub fn run(s: &Scenario, mut on_period: impl FnMut(usize, usize)) -> (Vec<PeriodRecord>, Option<RunError>) {
    run_recording(
        s,
        |k, n| {
            on_period(k, n);
            true
        },
        |_| {},
    )
}

/// As [`run`], handing every plant event to `on_events` (see
/// [`super::rig::run_loop_observed`]).
pub fn run_observed(
    s: &Scenario,
    on_period: impl FnMut(usize, usize) -> bool,
    on_events: impl FnMut(&[PlantEvent]),
) -> (Vec<PeriodRecord>, Option<RunError>) {
    match InProcessLink::new(s) {
        Ok(mut link) => run_loop_observed(s, &mut link, on_period, |_| {}, on_events),
        Err(e) => (Vec::new(), Some(e)),
    }
}

/// As [`run`], handing every sensor frame to `on_frame` as it goes on the wire
/// (a recording of what crossed the wire).
pub fn run_recording(
    s: &Scenario,
    on_period: impl FnMut(usize, usize) -> bool,
    on_frame: impl FnMut(&SensorFrame),
) -> (Vec<PeriodRecord>, Option<RunError>) {
    match InProcessLink::new(s) {
        Ok(mut link) => run_loop(s, &mut link, on_period, on_frame),
        Err(e) => (Vec::new(), Some(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::lift_off_stats;

    #[test]
    fn default_scenario_tracks_without_lift_off_and_is_reproducible() {
        let mut s = Scenario::default_scenario();
        s.timing.duration_s = 4.0;
        let (a, err) = run(&s, |_, _| {});
        assert!(err.is_none(), "{err:?}");
        let (b, _) = run(&s, |_, _| {});
        assert_eq!(a, b, "same scenario and seed: identical records");
        let st = lift_off_stats(&a);
        assert_eq!(st.lift_offs, 0, "{st:?}");
        assert_eq!(st.false_alarms, 0, "{st:?}");
        assert!(a.iter().all(|r| !r.deadline_miss && !r.firmware_deadline_miss));
        let last = a.last().unwrap();
        assert!((last.z_t - 0.10).abs() < 1e-3, "final z_t {}", last.z_t);
        let settled: Vec<_> = a.iter().filter(|r| r.t > 2.5).collect();
        assert!(settled.iter().all(|r| (r.f_n - 10.0).abs() < 0.5), "f_n held near 10 N");
    }
}
