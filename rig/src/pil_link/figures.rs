//! `summary.json`'s `pil` section of a run ([`PilFigures`]): the target, the
//! image's counts against the step's budget, and where its log went.

use super::{
    counts::{CORE_HZ, PilCounts, step_budget},
    defmt_log::LogLine,
    qemu::ICOUNT_SHIFT,
    target::PilTarget,
};
use crate::summary::PilFigures;

/// Where a board's log goes, for the summary and the human output: it is not on
/// the PIL link.
pub const BOARD_LOG_NOTE: &str = "not captured over a serial port: a board logs defmt over RTT to a debug probe (read it with `probe-rs attach --chip STM32F405RGTx <image ELF>`)";

impl PilFigures {
    /// The figures of a run's `counts` at `rate_hz` (Hz) over `target`; `log` is
    /// the image's defmt log when the link captured it, `exit` QEMU's exit status.
    pub fn new(target: &PilTarget, counts: &PilCounts, rate_hz: f64, log: Option<&[LogLine]>, exit: Option<String>) -> Self {
        let per_tick = counts.counts_per_tick();
        let step = counts.step.spread(per_tick);
        let budget = step_budget(rate_hz);
        let (image, shift, serial_port, baud) = match target {
            PilTarget::Qemu { image, .. } => (Some(image.display().to_string()), Some(ICOUNT_SHIFT), None, None),
            PilTarget::Serial { path, baud, .. } => (None, None, Some(path.display().to_string()), Some(*baud)),
        };
        Self {
            transport: target.transport(),
            serial_port,
            baud,
            image,
            qemu_icount_shift: shift,
            ticks_per_second: counts.ticks_per_second,
            step_clock: counts.clock,
            count_unit: counts.unit(),
            counts_per_tick: per_tick,
            step_counts: step,
            frame_counts: counts.frame.spread(per_tick),
            step_budget: budget,
            within_budget: step.worst <= budget,
            worst_step_period_share: step.worst / (CORE_HZ / rate_hz),
            qemu_exit: exit,
            defmt_log: match log {
                Some(_) => "defmt.log (decoded from QEMU's semihosting output)".into(),
                None => BOARD_LOG_NOTE.into(),
            },
            defmt_lines: log.map(<[LogLine]>::len),
            defmt_warnings: log.map(|l| l.iter().filter(|l| l.level == "warn" || l.level == "error").count()),
        }
    }
}
