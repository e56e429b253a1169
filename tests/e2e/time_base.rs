//! One time base for both sides of the wire (shared::time): at rates whose
//! period is not a whole number of microseconds (6 and 7 kHz), the plant and the
//! firmware use the same period, agree on every deadline, and the frames' stamps
//! stay on plant time.

use firmware::Firmware;
use rig::{
    faults::{Fault, FaultKind},
    in_process,
    scenario::Scenario,
    setup::firmware_config,
};
use shared::Period;

/// The default scenario at `rate_hz` (with a sampling delay inside its period),
/// `late_command` windows delaying steps by `period + j` us for j in -2..=2, one
/// period each, two periods apart (fewer than the firmware's limit in a row).
fn scenario(rate_hz: f64) -> (Scenario, Period) {
    let mut s = Scenario::default_scenario();
    s.timing.rate_hz = rate_hz;
    s.timing.delta_s = 5e-5;
    s.timing.duration_s = 0.05;
    let period = s.timing.period();
    let p = period.as_secs_f64();
    s.faults = (-2i32..=2)
        .enumerate()
        .map(|(i, j)| Fault {
            delay_s: (period.as_us() as i64 + i64::from(j)) as f64 * 1e-6,
            ..Fault::new(FaultKind::LateCommand, (20 + 4 * i) as f64 * p, 0.0)
        })
        .collect();
    s.validate().unwrap();
    (s, period)
}

#[test]
fn both_sides_agree_on_every_deadline_and_no_stamp_drifts_at_6_and_7_khz() {
    for (rate, us) in [(6000.0, 167), (7000.0, 143)] {
        let (s, period) = scenario(rate);
        assert_eq!(period.as_us(), us, "{rate} Hz rounds once to {us} us");
        // The firmware is configured with the very same period.
        let cfg = firmware_config(&s);
        assert_eq!(cfg.period, period);
        Firmware::new(cfg).unwrap();

        let (records, failure) = in_process::run(&s, &mut ());
        assert!(failure.is_none(), "{rate} Hz: {failure:?}");
        assert_eq!(records.len() as u64, s.timing.periods());
        let mut misses = 0;
        for (k, r) in records.iter().enumerate() {
            // Plant time is k whole periods: the frame stamp k * period us, no drift.
            let stamp_s = period.sample(k as u64).as_secs_f64();
            assert!((r.t - stamp_s).abs() <= 1e-12, "{rate} Hz period {k}: t = {} s, stamp {stamp_s} s", r.t);
            // Both sides judge the same deadline.
            assert_eq!(
                r.deadline_miss, r.firmware_deadline_miss,
                "{rate} Hz period {k}: plant {} firmware {}",
                r.deadline_miss, r.firmware_deadline_miss
            );
            misses += usize::from(r.deadline_miss);
        }
        // Steps started period - 2, - 1 us late make it; period, + 1, + 2 us late miss.
        assert_eq!(misses, 3, "{rate} Hz");
    }
}
