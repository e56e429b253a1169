//! Sensor models between the plant and the wire (docs/hardware.md "Sensors"):
//! 14-bit encoders (the elbow's sees `theta2 - theta1`), a 12-bit two-axis load
//! cell over +-25 N with white noise, the reference board's belt encoder (its
//! counter differenced over each period, `drivers::belt::SampledBelt`: the belt
//! sensor's one model, the board links' too, docs/hardware.md "The belt sensor's
//! model"). Noise is seeded (ChaCha8), so a run is reproducible bit for bit.

use drivers::belt::{BeltError, SampledBelt};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use shared::wire::{self, SensorFrame, frame_flags};

use super::faults::{FaultKind, FaultPlan, Signal};

/// A model of the sensors between the plant and the wire: one frame per period.
pub trait SensorModel {
    /// The frame of period `seq` at `t_us` (us): state `x = [theta1, theta1_dot,
    /// theta2, theta2_dot]` (rad, rad/s), tip force `f = [f_t, f_n]` (N), the
    /// belt's travel since period 0's sample `belt_travel_m` (m: `v_belt t_k`,
    /// as the board links' belt counter sees it). Called once per period, in order.
    fn frame(&mut self, seq: u32, t_us: u64, x: &[f64; 4], f: [f64; 2], belt_travel_m: f64) -> SensorFrame;

    /// The joint encoders' resolution, bits a turn (their counts wrap at `2^bits`).
    fn encoder_bits(&self) -> u8 {
        wire::ENCODER_BITS
    }
}

/// The sensor models of one run (docs/hardware.md "Sensors").
#[derive(Debug, Clone)]
pub struct Sensors {
    rng: ChaCha8Rng,
    load_noise: Option<Normal<f64>>,
    /// Joint encoder resolution, bits per revolution.
    encoder_bits: u8,
    /// The belt encoder (the reference board's at the run's period), or why
    /// that period has none.
    belt: Result<SampledBelt, BeltError>,
}

/// The sensor faults of a scenario wrapped around any sensor model (the way
/// smoltcp's `FaultInjector` wraps a device): the inner model makes the frame,
/// then this period's faults corrupt it. A stuck sensor repeats its previous
/// count, a NaN one sends count 0 with its invalid bit in `flags`, an
/// out-of-range one sends a count outside its range, a spiking encoder its
/// count plus the spike's (wrapped at the encoder's `2^bits`). A drifting load
/// cell and a belt encoder's gain act on what the inner model senses (the
/// force plus the offset, the belt speed times the gain), so that the
/// quantisation is the sensor's own, as on the board. The inner model runs the
/// same with or without faults (its noise stream is drawn identically), so a
/// fault changes nothing else.
#[derive(Debug, Clone)]
pub struct SensorFaults<S> {
    inner: S,
    plan: FaultPlan,
    last: SensorFrame,
    /// The belt counter's travel under a `belt_gain` fault.
    belt_gained: drivers::belt::GainedTravel,
}

impl<S: SensorModel> SensorFaults<S> {
    /// `inner` with the sensor faults of `plan`.
    pub fn new(inner: S, plan: FaultPlan) -> Self {
        Self { inner, plan, last: SensorFrame::default(), belt_gained: drivers::belt::GainedTravel::default() }
    }

    /// The run's faults (all of them: the link's act elsewhere).
    pub fn plan(&self) -> &FaultPlan {
        &self.plan
    }
}

impl<S: SensorModel> SensorModel for SensorFaults<S> {
    fn frame(&mut self, seq: u32, t_us: u64, x: &[f64; 4], f: [f64; 2], belt_travel_m: f64) -> SensorFrame {
        let k = u64::from(seq);
        let f = self.plan.load_offsets_n(k).map_or(f, |o| [f[0] + o[0], f[1] + o[1]]);
        // The counter's travel under a gain fault: the twin's model (`drivers::belt::GainedTravel`).
        let belt_travel_m = self.belt_gained.read(belt_travel_m, self.plan.belt_gain(k));
        let mut frame = self.inner.frame(seq, t_us, x, f, belt_travel_m);
        let wrap = 1i64 << self.inner.encoder_bits();
        let spike = |count: u16, signal| (i64::from(count) + i64::from(self.plan.spike_counts(signal, k))).rem_euclid(wrap) as u16;
        frame.theta1_count = spike(frame.theta1_count, Signal::Theta1);
        frame.elbow_count = spike(frame.elbow_count, Signal::Elbow);
        for (kind, signal) in self.plan.sensor_faults(k) {
            let last = &self.last;
            match (kind, signal) {
                (FaultKind::StuckSensor, Signal::Theta1) => frame.theta1_count = last.theta1_count,
                (FaultKind::StuckSensor, Signal::Elbow) => frame.elbow_count = last.elbow_count,
                (FaultKind::StuckSensor, Signal::FT) => frame.f_t_code = last.f_t_code,
                (FaultKind::StuckSensor, Signal::FN) => frame.f_n_code = last.f_n_code,
                (FaultKind::StuckSensor, Signal::Belt) => frame.belt_count = last.belt_count,
                (FaultKind::NanSensor, s) => {
                    let (bit, zero): (u16, fn(&mut SensorFrame)) = match s {
                        Signal::Theta1 => (frame_flags::THETA1_INVALID, |f| f.theta1_count = 0),
                        Signal::Elbow => (frame_flags::ELBOW_INVALID, |f| f.elbow_count = 0),
                        Signal::FT => (frame_flags::F_T_INVALID, |f| f.f_t_code = 0),
                        Signal::FN => (frame_flags::F_N_INVALID, |f| f.f_n_code = 0),
                        Signal::Belt => (frame_flags::BELT_INVALID, |f| f.belt_count = 0),
                    };
                    frame.flags |= bit;
                    zero(&mut frame);
                }
                (FaultKind::OutOfRange, Signal::Theta1) => frame.theta1_count = u16::MAX,
                (FaultKind::OutOfRange, Signal::Elbow) => frame.elbow_count = u16::MAX,
                (FaultKind::OutOfRange, Signal::FT) => frame.f_t_code = i16::MAX,
                (FaultKind::OutOfRange, Signal::FN) => frame.f_n_code = i16::MAX,
                (FaultKind::OutOfRange, Signal::Belt) => frame.belt_count = i16::MIN,
                _ => {}
            }
        }
        self.last = frame;
        frame
    }
}

impl Sensors {
    /// Sensors sampled every `period` with load-cell noise `load_noise_n` (N
    /// rms, >= 0) from `seed`, the reference board's 14-bit encoders and its
    /// belt encoder (the default `[board]` and `[calibration]`: 1e6 counts per
    /// metre read at 1e-6 m per count, so one count of change over the period is
    /// 1 mm/s at 1 kHz, 10 mm/s at 10 kHz; the scenario's own tables describe a
    /// board, which this model does not have). A period whose scale the
    /// reference encoder cannot carry (`drivers::belt::scale`: outside 10 us to
    /// 6.5 ms; the scenarios' 250 Hz to 10 kHz all can) reads the belt invalid
    /// in every frame.
    pub fn new(seed: u64, load_noise_n: f64, period: shared::Period) -> Self {
        let load_noise = if load_noise_n > 0.0 { Normal::new(0.0, load_noise_n).ok() } else { None };
        let belt = SampledBelt::new(
            board_description::BoardDescription::default().belt_counts_per_metre,
            crate::calibration::CalibrationSection::default().belt_metres_per_count,
            period.as_secs_f32(),
        );
        Self { rng: ChaCha8Rng::seed_from_u64(seed), load_noise, encoder_bits: wire::ENCODER_BITS, belt }
    }

    /// The same with `bits`-bit joint encoders (10 to 16, `wire::ENCODER_BITS_RANGE`).
    pub fn with_encoder_bits(self, bits: u8) -> Self {
        Self { encoder_bits: bits, ..self }
    }
}

impl SensorModel for Sensors {
    fn encoder_bits(&self) -> u8 {
        self.encoder_bits
    }

    /// Quantised encoders and load cell with seeded noise, the belt encoder's
    /// speed in mm/s (`drivers::belt::SampledBelt` of the travel: 0 in the first
    /// frame). A non-finite reading, or a belt beyond +-5 m/s over the period,
    /// is sent as count 0 with its invalid bit set in `flags` (as a board's
    /// `drivers::frame::assemble` does).
    fn frame(&mut self, seq: u32, t_us: u64, x: &[f64; 4], f: [f64; 2], belt_travel_m: f64) -> SensorFrame {
        let mut noise = || self.load_noise.map_or(0.0, |n| n.sample(&mut self.rng));
        let (n_t, n_n) = (noise(), noise());
        let mut flags = 0;
        let mut check = |v: f64, bit: u16| {
            if !v.is_finite() {
                flags |= bit;
            }
        };
        check(x[0], frame_flags::THETA1_INVALID);
        check(x[2] - x[0], frame_flags::ELBOW_INVALID);
        check(f[0], frame_flags::F_T_INVALID);
        check(f[1], frame_flags::F_N_INVALID);
        check(belt_travel_m, frame_flags::BELT_INVALID);
        // The encoder samples every period, a bad one too (its counter reads on).
        let belt = self.belt.as_mut().map_err(|e| *e).and_then(|b| b.speed_mm_s(belt_travel_m));
        if belt.is_err() {
            flags |= frame_flags::BELT_INVALID;
        }
        // `encode_*` map a non-finite value to 0; the flag says it was not a reading.
        SensorFrame {
            t_us,
            seq,
            theta1_count: wire::encode_angle_bits(x[0], self.encoder_bits),
            elbow_count: wire::encode_angle_bits(x[2] - x[0], self.encoder_bits),
            f_t_code: wire::encode_force(f[0] + n_t),
            f_n_code: wire::encode_force(f[1] + n_n),
            belt_count: if flags & frame_flags::BELT_INVALID == 0 { belt.unwrap_or(0) } else { 0 },
            flags,
        }
    }
}

/// `frame` with the belt speed `v_belt` (m/s) stated directly rather than
/// measured: `belt_count` is `v_belt` in mm/s (the wire's resolution), rounded
/// half away from zero and clamped to `i16`; a non-finite speed is count 0 with
/// `BELT_INVALID` set in `flags`. Not the belt sensor's model ([`Sensors`]): for
/// a frame whose readings a caller states one by one (Python's `Firmware.step`
/// with a dict).
pub fn with_stated_belt_speed(frame: SensorFrame, v_belt: f64) -> SensorFrame {
    let (belt_count, flags) = if v_belt.is_finite() {
        ((v_belt * 1000.0).round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16, frame.flags & !frame_flags::BELT_INVALID)
    } else {
        (0, frame.flags | frame_flags::BELT_INVALID)
    };
    SensorFrame { belt_count, flags, ..frame }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_frames_and_noise_has_the_set_rms() {
        let mut a = Sensors::new(7, 0.02, shared::Period::MILLISECOND);
        let mut b = Sensors::new(7, 0.02, shared::Period::MILLISECOND);
        let x = [0.1, 0.0, -0.3, 0.0];
        let mut sum2 = 0.0;
        let n = 20_000;
        for k in 0..n {
            let fa = a.frame(k, k as u64 * 1000, &x, [0.0, 10.0], 0.0);
            assert_eq!(fa, b.frame(k, k as u64 * 1000, &x, [0.0, 10.0], 0.0));
            let f_n = fa.f_n_code as f64 * 25.0 / 2048.0;
            sum2 += (f_n - 10.0).powi(2);
        }
        // Noise 20 mN rms plus quantisation (12.2 mN lsb, 3.5 mN rms) in quadrature.
        let rms = (sum2 / n as f64).sqrt();
        assert!((rms - (0.02f64.powi(2) + (25.0 / 2048.0f64).powi(2) / 12.0).sqrt()).abs() < 0.002, "rms {rms}");
    }

    /// The encoder resolution is the sensor model's: counts stay below `2^bits` and
    /// decode (at the same resolution, as the firmware does) to within half a count;
    /// the default is the reference board's 14 bits.
    #[test]
    fn encoder_resolution_sets_the_counts() {
        let x = [0.3217, 0.0, -0.2711, 0.0];
        let default = Sensors::new(1, 0.0, shared::Period::MILLISECOND).frame(0, 0, &x, [0.0, 5.0], 0.0);
        assert_eq!(default, Sensors::new(1, 0.0, shared::Period::MILLISECOND).with_encoder_bits(14).frame(0, 0, &x, [0.0, 5.0], 0.0));
        for bits in 10..=16u8 {
            let f = Sensors::new(1, 0.0, shared::Period::MILLISECOND).with_encoder_bits(bits).frame(0, 0, &x, [0.0, 5.0], 0.0);
            let lsb = std::f64::consts::TAU / f64::from(1u32 << bits);
            assert!(u32::from(f.theta1_count) < 1u32 << bits);
            let m = firmware::decode::decode_bits(&f, bits).unwrap();
            assert!((f64::from(m.theta1) - x[0]).abs() <= 0.5 * lsb + 1e-6, "{bits} bits");
            assert!((f64::from(m.elbow) - (x[2] - x[0])).abs() <= 0.5 * lsb + 1e-6, "{bits} bits");
        }
    }

    /// The belt reading is the belt encoder's (`drivers::belt::SampledBelt`):
    /// 0 in the first frame, then the counts of each period at the rate's scale
    /// (1 mm/s per count at 1 kHz, 10 at 10 kHz) with the count's jitter, the
    /// belt's sign; beyond 5 m/s over a period, or a non-finite travel, the
    /// reading is invalid.
    #[test]
    fn the_belt_is_read_by_the_encoder_model() {
        let x = [0.1, 0.0, -0.3, 0.0];
        for (us, lsb) in [(1000u32, 1i16), (100, 10)] {
            let period = shared::Period::from_us(us).unwrap();
            let mut s = Sensors::new(1, 0.0, period);
            let ts = period.as_secs_f64();
            let belt: Vec<i16> = (0..200u32).map(|k| s.frame(k, 0, &x, [0.0, 5.0], -0.4 * (f64::from(k) * ts)).belt_count).collect();
            assert_eq!(belt[0], 0, "{us} us: no earlier count in period 0");
            assert!(belt[1..].iter().all(|&v| v % lsb == 0 && (-400 - lsb..=-400 + lsb).contains(&v)), "{us} us: {belt:?}");
            assert!(belt[1..].iter().any(|&v| v != -400), "{us} us: the count's jitter shows: {belt:?}");
        }
        let mut s = Sensors::new(1, 0.0, shared::Period::MILLISECOND);
        assert_eq!(s.frame(0, 0, &x, [0.0, 5.0], 0.0).flags, 0);
        let fast = s.frame(1, 1000, &x, [0.0, 5.0], 6e-3);
        assert_eq!((fast.belt_count, fast.flags), (0, frame_flags::BELT_INVALID));
        let nan = s.frame(2, 2000, &x, [0.0, 5.0], f64::NAN);
        assert_eq!((nan.belt_count, nan.flags), (0, frame_flags::BELT_INVALID));
        // A stated speed is the wire's mm/s, no encoder.
        let f = with_stated_belt_speed(nan, -0.4004);
        assert_eq!((f.belt_count, f.flags), (-400, 0));
        assert_eq!(with_stated_belt_speed(f, f64::NAN).flags, frame_flags::BELT_INVALID);
    }

    /// The fault wrapper changes only the faulted signal in its window and nothing
    /// when there is no fault (same noise, same frames as the bare model).
    #[test]
    fn faults_wrap_any_sensor_model() {
        use crate::faults::Fault;
        let x = [0.1, 0.0, -0.3, 0.0];
        let frames = |faults: &[Fault]| -> Vec<SensorFrame> {
            let mut s =
                SensorFaults::new(Sensors::new(3, 0.02, shared::Period::MILLISECOND), FaultPlan::new(faults, shared::Period::MILLISECOND));
            (0..10u32).map(|k| s.frame(k, u64::from(k) * 1000, &[x[0] + 1e-3 * f64::from(k), 0.0, x[2], 0.0], [0.0, 10.0], 0.0)).collect()
        };
        let mut bare = Sensors::new(3, 0.02, shared::Period::MILLISECOND);
        let plain: Vec<_> = (0..10u32)
            .map(|k| bare.frame(k, u64::from(k) * 1000, &[x[0] + 1e-3 * f64::from(k), 0.0, x[2], 0.0], [0.0, 10.0], 0.0))
            .collect();
        assert_eq!(frames(&[]), plain);
        let stuck = Fault { signal: Some(Signal::Theta1), ..Fault::new(FaultKind::StuckSensor, 0.005, 0.003) };
        let got = frames(&[stuck]);
        for k in 0..10 {
            let faulted = (5..8).contains(&k);
            let want_theta1 = if faulted { plain[4].theta1_count } else { plain[k].theta1_count };
            assert_eq!(got[k].theta1_count, want_theta1, "period {k}");
            assert_eq!((got[k].f_n_code, got[k].elbow_count), (plain[k].f_n_code, plain[k].elbow_count), "period {k}");
        }
        let nan = Fault { signal: Some(Signal::FN), ..Fault::new(FaultKind::NanSensor, 0.002, 0.0) };
        let got = frames(&[nan]);
        assert_eq!(got[2].flags & frame_flags::F_N_INVALID, frame_flags::F_N_INVALID);
        assert_eq!(got[3], plain[3]);
        // A spike: the count off by `counts` (wrapped at 2^14) for `periods` periods.
        let spike = Fault {
            signal: Some(Signal::Elbow),
            counts: Some(-100),
            spike_periods: Some(2),
            ..Fault::new(FaultKind::EncoderSpike, 0.003, 0.0)
        };
        let got = frames(&[spike]);
        for k in 0..10 {
            let off = if (3..5).contains(&k) { -100 } else { 0 };
            assert_eq!(i64::from(got[k].elbow_count), (i64::from(plain[k].elbow_count) + off).rem_euclid(16384), "period {k}");
            assert_eq!(got[k].theta1_count, plain[k].theta1_count);
        }
        // A drift of 0.5 N/s on f_n from 2 ms: 0.5 mN at period 3, 3.5 mN at 9 (the code's lsb is 12.2 mN, noise 20 mN).
        let drift = Fault { signal: Some(Signal::FN), rate_n_per_s: Some(0.5), ..Fault::new(FaultKind::LoadCellDrift, 0.002, 1.0) };
        let plan = FaultPlan::new(&[drift], shared::Period::MILLISECOND);
        assert_eq!(plan.load_offsets_n(1), None);
        assert_eq!(plan.load_offsets_n(2), Some([0.0, 0.0]));
        assert!((plan.load_offsets_n(9).unwrap()[1] - 0.0035).abs() < 1e-12);
        let got = frames(&[Fault { rate_n_per_s: Some(-0.5), ..drift }]);
        assert_eq!(got[..2], plain[..2]);
        // A belt gain: the speed read times the gain over its periods (-0.4 m/s:
        // -400 mm/s, one count of the encoder's jitter either way), the
        // counter carrying on from where it left it after.
        let travel = |k: u32| -0.4 * f64::from(k) * 1e-3;
        let belt_frames = |faults: &[Fault]| -> Vec<i16> {
            let mut s =
                SensorFaults::new(Sensors::new(3, 0.02, shared::Period::MILLISECOND), FaultPlan::new(faults, shared::Period::MILLISECOND));
            (0..10u32).map(|k| s.frame(k, u64::from(k) * 1000, &[x[0], 0.0, x[2], 0.0], [0.0, 10.0], travel(k)).belt_count).collect()
        };
        let plain = belt_frames(&[]);
        assert_eq!(plain[0], 0, "no earlier count at period 0");
        assert!(plain[1..].iter().all(|b| (b + 400).abs() <= 1), "{plain:?}");
        for gain in [0.5, 2.0, -1.0] {
            let got = belt_frames(&[Fault { gain: Some(gain), ..Fault::new(FaultKind::BeltGain, 0.004, 0.002) }]);
            for k in 0..10 {
                let want = if (4..6).contains(&k) {
                    gain * -400.0
                } else if k == 0 {
                    0.0
                } else {
                    -400.0
                };
                assert!((f64::from(got[k]) - want).abs() <= 1.0, "gain {gain}, period {k}: {got:?}");
            }
        }
    }
}
