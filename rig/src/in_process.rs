//! The in-process transport: the firmware step linked directly into the plant's
//! process, no IPC (`sil-host run --in-process`). The firmware's clock is the
//! frame's: its step takes no simulated time.

use crate::faults::LinkKind;
use firmware::{ControlLaw, PaperLaws, board::FrozenClock};
use shared::wire::{GroundTruth, SensorFrame};

use super::{
    firmware_side::FirmwareSide,
    link::{Exchange, FirmwareLink},
    period_loop::{RunObserver, run_loop},
    record::{PeriodRecord, RunError},
    scenario::Scenario,
    setup::RunSetup,
};

/// The firmware step, running law `L` (the paper's laws by default), called directly.
#[derive(Debug, Clone)]
pub struct InProcessLink<L: ControlLaw = PaperLaws> {
    side: FirmwareSide<L>,
    announced: crate::handshake::Announced,
}

impl InProcessLink {
    /// The link for a scenario, with the paper's laws ([`InProcessLink::for_law`]).
    ///
    /// # Errors
    /// As [`InProcessLink::for_law`].
    pub fn new(setup: &RunSetup) -> Result<Self, RunError> {
        Self::for_law(setup)
    }
}

impl<L: ControlLaw> InProcessLink<L> {
    /// The link for a scenario, the firmware running law `L`.
    ///
    /// # Errors
    /// [`RunError::Firmware`] for an invalid configuration; [`RunError::Law`]
    /// for a `[law]` table that does not fit `L`; [`RunError::Unsupported`]
    /// when the scenario injects a fault that needs the firmware in its own process.
    pub fn for_law(setup: &RunSetup) -> Result<Self, RunError> {
        LinkKind::InProcess.check(&setup.scenario().faults)?;
        let side = FirmwareSide::<L>::for_law(setup)?;
        let announced = crate::handshake::of_config(side.firmware().config(), &L::SPEC)?;
        Ok(Self { side, announced })
    }
}

impl<L: ControlLaw> FirmwareLink for InProcessLink<L> {
    fn transport(&self) -> &'static str {
        "in-process"
    }

    fn announcement(&self) -> Option<&crate::handshake::Announced> {
        Some(&self.announced)
    }

    fn exchange(&mut self, frame: &SensorFrame, _truth: &GroundTruth) -> Result<Exchange, RunError> {
        let (command, telemetry) = self.side.answer(frame, frame.sampled_at(), &FrozenClock);
        Ok(Exchange::Answered { command, telemetry, at_stamp: false })
    }
}

/// Runs the scenario in-process ([`run_loop`] over an [`InProcessLink`]),
/// telling `run` what happens. Returns every period's record, and the error if
/// the run stopped early.
pub fn run(s: &Scenario, run: &mut dyn RunObserver) -> (Vec<PeriodRecord>, Option<RunError>) {
    run_law::<PaperLaws>(s, run)
}

/// [`run`] with the control law `L` (a law of one's own, docs/board.md "Your
/// own law"): the scenario's `[law]` table bound to what `L` declares.
pub fn run_law<L: ControlLaw>(s: &Scenario, run: &mut dyn RunObserver) -> (Vec<PeriodRecord>, Option<RunError>) {
    let setup = match RunSetup::new(s.clone()) {
        Ok(setup) => setup,
        Err(e) => return (Vec::new(), Some(e)),
    };
    match InProcessLink::<L>::for_law(&setup) {
        Ok(mut link) => run_loop(&setup, &mut link, run),
        Err(e) => (Vec::new(), Some(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::lift_off_stats;

    /// Issue 52, 8: `timing.delta_s = 1e-20` (in range: [0, one period)) failed
    /// with "time step ... must be finite": the delay is below the clock's
    /// resolution at every sample, so it acts as none; the run is the run without
    /// a delay, bit for bit.
    #[test]
    fn a_delay_below_the_clocks_resolution_acts_as_none() {
        let mut s = Scenario::default_scenario();
        s.timing.duration_s = 0.5;
        s.timing.delta_s = 0.0;
        let (none, err) = run(&s, &mut ());
        assert!(err.is_none(), "{err:?}");
        for tiny in [1e-20, 1e-300, f64::from_bits(1)] {
            s.timing.delta_s = tiny;
            s.validate().unwrap();
            let (r, err) = run(&s, &mut ());
            assert!(err.is_none(), "delta_s {tiny:e}: {err:?}");
            assert_eq!(format!("{r:?}"), format!("{none:?}"), "delta_s {tiny:e}");
        }
    }

    #[test]
    fn default_scenario_tracks_without_lift_off_and_is_reproducible() {
        let mut s = Scenario::default_scenario();
        s.timing.duration_s = 4.0;
        let (a, err) = run(&s, &mut ());
        assert!(err.is_none(), "{err:?}");
        let (b, _) = run(&s, &mut ());
        assert_eq!(a, b, "same scenario and seed: identical records");
        let st = lift_off_stats(&a);
        assert_eq!(st.lift_offs, 0, "{st:?}");
        assert_eq!(st.false_alarms, 0, "{st:?}");
        assert!(a.iter().all(|r| !r.deadline_miss && !r.firmware_deadline_miss));
        let last = a.last().unwrap();
        assert!((last.z_t - 0.10).abs() < 1e-3, "final z_t {}", last.z_t);
        // The streamed statistics are those of the whole list, to the bit.
        let st = crate::stats::RunStats::of(&a);
        let direct = (a.iter().map(|r| (r.z_t - r.z_t_ref).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
        assert_eq!(st.rms_tracking_error().to_bits(), direct.to_bits());
        assert_eq!((st.periods(), st.deadline_misses(), st.final_z_t(), st.last_t()), (a.len(), 0, last.z_t, Some(last.t)));
        let settled: Vec<_> = a.iter().filter(|r| r.t > 2.5).collect();
        assert!(settled.iter().all(|r| (r.f_n - 10.0).abs() < 0.5), "f_n held near 10 N");
    }
}
