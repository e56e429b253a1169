//! The `arm` image's notices in its defmt log (issue 56): what the application tells
//! the operator ([`arm_app::Notice`]), logged at start-up directly ([`log`]) and from
//! the control interrupt through a queue ([`defer`]) that the idle loop empties
//! ([`log_notices`]), so a defmt line never costs the handler its thousands of cycles.

use core::cell::RefCell;

use arm_app::{Notice, Settings, record::RecordFault};
use cortex_m::interrupt::Mutex;
use heapless::Deque;
use shared::wire::frame_flags;

/// The notices of the control interrupt, waiting for the idle loop to log
/// them (issue 56): a defmt line costs the handler thousands of cycles (the
/// window's report, once every `step_stats::WINDOW` periods, about 11 000
/// with the flash's wait states, most of the 1 kHz handler's worst case).
/// Logged in order, at the same stamp (`log_time`: the period's, as long as
/// the idle loop runs before the next tick's control step).
static NOTICES: Mutex<RefCell<Deque<Notice, NOTICE_QUEUE>>> = Mutex::new(RefCell::new(Deque::new()));
/// Notices a period can raise, with room to spare: a window's report, the
/// invalid readings, an acquisition fault, the safe state and the drivers'.
const NOTICE_QUEUE: usize = 8;
/// Notices dropped because the queue was full (the idle loop starved by
/// the interrupts), told with the next ones logged.
static NOTICES_DROPPED: Mutex<core::cell::Cell<u32>> = Mutex::new(core::cell::Cell::new(0));

/// The control interrupt's notice sink: queued for [`log_notices`]. Out
/// of line: one copy for the tick's call sites.
#[inline(never)]
pub fn defer(n: Notice) {
    cortex_m::interrupt::free(|cs| {
        if NOTICES.borrow(cs).borrow_mut().push_back(n).is_err() {
            let d = NOTICES_DROPPED.borrow(cs);
            d.set(d.get().saturating_add(1));
        }
    });
}

/// The idle loop: logs the notices the control interrupt queued ([`defer`]).
pub fn log_notices() {
    loop {
        let (n, dropped) =
            cortex_m::interrupt::free(|cs| (NOTICES.borrow(cs).borrow_mut().pop_front(), NOTICES_DROPPED.borrow(cs).replace(0)));
        if dropped > 0 {
            defmt::warn!("{=u32} notices dropped (the idle loop fell behind the control interrupt)", dropped);
        }
        let Some(n) = n else { return };
        log(n);
    }
}

/// What the application tells the operator, in the defmt log (at start-up
/// directly, from the control interrupt through [`defer`]); a window's
/// report also goes to the idle loop, which sends it on USART1. Out of
/// line: called from start-up and the idle loop, one copy (the image's
/// 64 KiB under the qemu profile's semihosting).
#[inline(never)]
pub fn log(n: Notice) {
    match n {
        Notice::EncoderReady { joint, agc } => defmt::info!("encoder {=str}: ready, AGC {=u8}", joint.name(), agc),
        Notice::EncoderNotReady { joint, fault } => {
            defmt::error!("encoder {=str}: not ready ({=str}): its readings will be invalid", joint.name(), fault.describe())
        }
        Notice::ReadingsBack { seq } => defmt::info!("period {=u32}: every sensor reads again", seq),
        Notice::AcquisitionFault { seq, fault } => {
            defmt::warn!("period {=u32}: the encoders' acquisition failed: {=str}", seq, fault.describe())
        }
        Notice::InvalidReadings { seq, flags } => defmt::warn!(
            "period {=u32}: invalid readings (frame flags {=u16:#x}: theta1 {=bool}, elbow {=bool}, f_t {=bool}, f_n {=bool}, belt {=bool}, driver fault {=bool})",
            seq,
            flags,
            flags & frame_flags::THETA1_INVALID != 0,
            flags & frame_flags::ELBOW_INVALID != 0,
            flags & frame_flags::F_T_INVALID != 0,
            flags & frame_flags::F_N_INVALID != 0,
            flags & frame_flags::BELT_INVALID != 0,
            flags & frame_flags::DRIVER_FAULT != 0
        ),
        // The reason's own name, interned by defmt (no flash for the text; issue 69:
        // the line listed every reason, and missed the two newest).
        Notice::SafeState { seq, reason } => defmt::error!(
            "period {=u32}: safe state, reason {=u8} ({=istr}; firmware::SafeReason): drivers disabled; press the enable button to reset",
            seq,
            reason,
            safe_reason_name(reason)
        ),
        Notice::DriversDidNotDisable => defmt::error!("the drivers did not disable"),
        Notice::DriversEnabled { seq } => defmt::info!("period {=u32}: drivers enabled", seq),
        Notice::DriversRefused { seq } => defmt::error!("period {=u32}: the drivers refuse to enable (fault line asserted)", seq),
        Notice::FirmwareReset => defmt::info!("enable button: firmware reset; the drivers enable at the next command"),
        Notice::Jogged(j) => defmt::info!(
            "jog of {=str} at code {=i16}: moved {=i32} / {=i32} counts, {=str}; drivers disabled",
            j.joint.name(),
            j.code,
            j.moved_counts[0],
            j.moved_counts[1],
            if j.verdict.is_ok() { "direction right" } else { "refused" }
        ),
        Notice::Window(report) => {
            defmt::info!(
                "period {=u32}: step ticks median {=u32} worst {=u32} over {=u32}; tick interval {=u32}..{=u32} ticks; handler worst {=u32} ticks; overruns {=u32}; drivers {=str}",
                report.seq,
                report.step.median,
                report.step.worst,
                report.step.steps,
                report.tick_interval[0],
                report.tick_interval[1],
                report.handler_worst,
                report.overruns,
                if report.drivers_enabled { "enabled" } else { "disabled" }
            );
        }
        Notice::Settings(s) => match s {
            Settings::Saved => defmt::info!("settings: loaded from flash"),
            Settings::Corrupt(RecordFault::Version(v)) => {
                defmt::error!("settings: record of format version {=u16}: {=str}", v, s.describe())
            }
            _ => defmt::error!("settings: {=str}", s.describe()),
        },
        Notice::LockedOut(s) => defmt::warn!("enable button ignored: {=str}", s.describe()),
    }
}

/// The name of safe-state reason `code` (`firmware::SafeReason`'s discriminants),
/// as an interned defmt string.
fn safe_reason_name(code: u8) -> defmt::Str {
    match code {
        1 => defmt::intern!("deadline misses"),
        2 => defmt::intern!("bad frames"),
        3 => defmt::intern!("non-finite"),
        4 => defmt::intern!("singular"),
        5 => defmt::intern!("unreachable"),
        6 => defmt::intern!("peer lost"),
        7 => defmt::intern!("sensor fault"),
        8 => defmt::intern!("runaway"),
        9 => defmt::intern!("overload"),
        10 => defmt::intern!("miswired"),
        11 => defmt::intern!("tracking"),
        12 => defmt::intern!("lift-off"),
        13 => defmt::intern!("acquisition"),
        14 => defmt::intern!("saturated"),
        15 => defmt::intern!("unstable"),
        _ => defmt::intern!("unknown"),
    }
}
