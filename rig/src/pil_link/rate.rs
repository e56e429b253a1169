//! How fast a PIL run goes in wall time: a whole scenario run over the link,
//! nothing written, timed from spawning QEMU (or opening the port) to the last
//! record (`sil-host pil`'s periods per wall second, `sil-host bench`'s PIL figure).

use std::{path::Path, time::Instant};

use serde::Serialize;

use super::{
    link::PilLink,
    target::{PilOptions, PilTarget, QemuLink},
};
use crate::{
    period_loop::{RunObserver, stream_loop},
    record::{PeriodRecord, RunError},
    scenario::Scenario,
    setup::RunSetup,
};

/// What [`measure_rate`] measured: how fast a PIL run goes in wall time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PilRate {
    /// `summary.json`'s `pil.transport` of the run: `qemu-semihosting`, `qemu-socket` or `serial`.
    pub transport: &'static str,
    /// Periods run (all of the scenario's).
    pub periods: usize,
    /// Wall time from spawning QEMU (or opening the port) to the image configured, s.
    pub start_s: f64,
    /// Wall time of the periods, from the first frame sent to the last record, s.
    pub loop_s: f64,
    /// `periods / loop_s`: periods per wall second (1000 is real time at 1 kHz).
    pub periods_per_s: f64,
}

/// Runs the whole scenario `s` in PIL over `opts` (lockstep, nothing written,
/// the image's log dropped) and measures its speed in wall time: the figure
/// `sil-host pil` prints as periods per wall second, without the files. For the
/// default scenario (10 000 periods at 1 kHz) see [`measure_default_rate`].
///
/// # Errors
/// As [`PilLink::start`]; the run's own failure ([`RunError::FirmwareLost`] and
/// the rest) when it stopped before its end.
pub fn measure_rate(setup: &RunSetup, opts: &PilOptions) -> Result<PilRate, RunError> {
    /// Notes when each record is made.
    struct LastRecord(Option<Instant>);
    impl RunObserver for LastRecord {
        fn on_record(&mut self, _record: &PeriodRecord) {
            self.0 = Some(Instant::now());
        }
    }
    let t0 = Instant::now();
    let mut link = PilLink::start(setup, opts, None)?;
    let started = Instant::now();
    let mut last = LastRecord(None);
    let (periods, failure) = stream_loop(setup, &mut link, &mut last);
    if let Some(e) = failure {
        return Err(e);
    }
    let loop_s = last.0.map_or(0.0, |t| (t - started).as_secs_f64());
    Ok(PilRate {
        transport: opts.target.transport(),
        periods,
        start_s: (started - t0).as_secs_f64(),
        loop_s,
        periods_per_s: if loop_s > 0.0 { periods as f64 / loop_s } else { 0.0 },
    })
}

/// [`measure_rate`] on the default scenario (hybrid from x0d, 1 kHz) cut to
/// `periods` periods (10 000: the whole default run), the image at `image` in
/// `qemu-system-arm` from `PATH` over `link`. `sil-host bench`'s PIL figure:
/// `measure_default_rate(&default_image(), 10_000, QemuLink::Semihosting)`.
///
/// # Errors
/// As [`measure_rate`]; [`RunError::Transport`] for `periods` 0.
pub fn measure_default_rate(image: &Path, periods: u32, link: QemuLink) -> Result<PilRate, RunError> {
    if periods == 0 {
        return Err(RunError::Transport("a PIL rate needs at least one period".into()));
    }
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = f64::from(periods) / s.timing.rate_hz;
    let target = PilTarget::Qemu { image: image.to_path_buf(), qemu: "qemu-system-arm".into(), link };
    measure_rate(&RunSetup::new(s)?, &PilOptions::for_target(target))
}
