//! The in-process loop: the firmware step linked directly, no IPC. Period `k`:
//! the sensors are sampled at `t_k = k Ts` into a frame, the firmware computes a
//! command, the previous command stays applied until `t_k + delta`, then the new
//! one (zero-order hold) until `t_{k+1}` (HARDWARE.md "Control loop").

use firmware::{
    Config, ControllerKind, Firmware,
    board::FrozenClock,
    config::{FrictionCompensation, HybridGains},
};
use serde::Serialize;
use shared::{ContactMode, Params, wire};

use super::{scenario::Scenario, sensors::Sensors};
use crate::{
    initial,
    plant::{Plant, SimConfig, SimError},
};

/// One control period of a run (a row of `trace.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeriodRecord {
    /// Sample time `t_k`, s.
    pub t: f64,
    /// True state at `t_k` (rad, rad/s).
    pub theta1: f64,
    /// `theta1_dot`, rad/s.
    pub theta1_dot: f64,
    /// `theta2`, rad.
    pub theta2: f64,
    /// `theta2_dot`, rad/s.
    pub theta2_dot: f64,
    /// Tip `z_t`, m.
    pub z_t: f64,
    /// Tip `z_n`, m.
    pub z_n: f64,
    /// Reference `z_t*` (the firmware's), m.
    pub z_t_ref: f64,
    /// True tangential contact force at `t_k`, N.
    pub f_t: f64,
    /// True normal contact force at `t_k`, N.
    pub f_n: f64,
    /// True contact mode at `t_k`.
    pub mode: &'static str,
    /// Commanded motor torques of period `k`, N m (after quantisation).
    pub u1_cmd: f64,
    /// Commanded `u2`, N m.
    pub u2_cmd: f64,
    /// Torques applied at `t_k` (the previous command), N m.
    pub u1_applied: f64,
    /// Applied `u2`, N m.
    pub u2_applied: f64,
    /// True lift-off (the tip in flight at `t_k`).
    pub lift_off_true: bool,
    /// Lift-off as the firmware reports it.
    pub lift_off_detected: bool,
    /// Deadline miss in this period.
    pub deadline_miss: bool,
    /// The firmware's status word.
    pub status: u32,
}

/// The firmware configuration a scenario asks for.
pub fn firmware_config(s: &Scenario) -> Config {
    let c = &s.controller;
    let mut params = Params::<f32>::paper();
    params.mu = c.mu_hat as f32;
    params.v_belt = s.plant.v_belt as f32;
    let base = Config::default();
    Config {
        params,
        controller: if c.kind == "pid" { ControllerKind::Pid } else { ControllerKind::Hybrid },
        period_s: (1.0 / s.timing.rate_hz) as f32,
        target_z_t: c.target_z_t as f32,
        move_time_s: c.move_time_s as f32,
        f_n_ref: c.f_n_ref as f32,
        hybrid: HybridGains { ki: c.hybrid_ki as f32, ..base.hybrid },
        friction: match c.friction.as_str() {
            "measured" => FrictionCompensation::Measured,
            "measured_normal" => FrictionCompensation::ModelMeasuredNormal,
            "none" => FrictionCompensation::None,
            _ => FrictionCompensation::ModelCommandedNormal,
        },
        ..base
    }
}

/// The plant a scenario asks for, at `t = 0`.
///
/// # Errors
/// [`SimError`] for bad parameters or initial conditions.
pub fn plant_for(s: &Scenario) -> Result<Plant, SimError> {
    let params = Params::new(s.plant.mu, s.plant.v_belt)?;
    let sim =
        SimConfig { rtol: s.plant.rtol, atol: s.plant.atol, impact_law: s.plant.impact_law, e_n: s.plant.e_n, ..SimConfig::default() };
    let ic = match s.plant.x0.as_str() {
        "a" => initial::X0A,
        "u" => initial::X0U,
        _ => initial::X0D,
    };
    Plant::new(params, sim, initial::deg_to_state(ic.deg), 0.0, [0.0, 0.0])
}

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The plant failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The firmware configuration is invalid.
    #[error("firmware configuration: {0}")]
    Firmware(#[from] firmware::config::ConfigError),
}

/// Runs the scenario in-process; `on_period(k, n)` is called after each period
/// (for progress bars). Returns every period's record; on a plant failure the
/// records so far come back with the error.
pub fn run(s: &Scenario, on_period: impl FnMut(usize, usize)) -> (Vec<PeriodRecord>, Option<RunError>) {
    run_recording(s, on_period, |_| {})
}

/// As [`run`], handing every sensor frame to `on_frame` as it goes on the wire
/// (the firmware's replay board plays such a recording).
pub fn run_recording(
    s: &Scenario,
    mut on_period: impl FnMut(usize, usize),
    mut on_frame: impl FnMut(&shared::wire::SensorFrame),
) -> (Vec<PeriodRecord>, Option<RunError>) {
    let mut records = Vec::new();
    let mut plant = match plant_for(s) {
        Ok(p) => p,
        Err(e) => return (records, Some(e.into())),
    };
    let mut fw = match Firmware::new(firmware_config(s)) {
        Ok(f) => f,
        Err(e) => return (records, Some(e.into())),
    };
    let mut sensors = Sensors::new(s.sensors.seed, s.sensors.load_noise_n);
    let ts = 1.0 / s.timing.rate_hz;
    let delta = s.timing.delta_s;
    let n = (s.timing.duration_s * s.timing.rate_hz).round() as usize;
    records.reserve(n);
    let mut applied = [0.0f64; 2];
    let mut f_now = plant.contact_force(applied);
    for k in 0..n {
        let t_k = k as f64 * ts;
        let x = plant.state();
        let t_us = (t_k * 1e6).round() as u64;
        let frame = sensors.frame(k as u32, t_us, &x, f_now, s.plant.v_belt);
        on_frame(&frame);
        let cmd = fw.step(t_us, &frame, &FrozenClock);
        let u_new = [wire::decode_torque(cmd.u1_code) as f64, wire::decode_torque(cmd.u2_code) as f64];
        let z = plant.tip();
        records.push(PeriodRecord {
            t: t_k,
            theta1: x[0],
            theta1_dot: x[1],
            theta2: x[2],
            theta2_dot: x[3],
            z_t: z[0],
            z_n: z[1],
            z_t_ref: fw.telemetry().reference[0] as f64,
            f_t: f_now[0],
            f_n: f_now[1],
            mode: plant.mode().name(),
            u1_cmd: u_new[0],
            u2_cmd: u_new[1],
            u1_applied: applied[0],
            u2_applied: applied[1],
            lift_off_true: plant.mode() == ContactMode::Flight,
            lift_off_detected: cmd.status & wire::status::LIFT_OFF != 0,
            deadline_miss: cmd.status & wire::status::DEADLINE_MISS != 0,
            status: cmd.status,
        });
        // Zero-order hold: the previous command until t_k + delta, then the new one.
        let step = plant.advance(applied, delta).and_then(|_| plant.advance(u_new, (k + 1) as f64 * ts - plant.time()));
        match step {
            Ok(r) => f_now = r.f,
            Err(e) => return (records, Some(e.into())),
        }
        applied = u_new;
        on_period(k + 1, n);
    }
    (records, None)
}

/// Lift-off detection statistics of a run (HARDWARE.md "Lift-off detection").
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LiftOffStats {
    /// True lift-offs (contact to flight transitions at the samples).
    pub lift_offs: u32,
    /// True lift-offs the firmware detected before the tip was back in contact.
    pub lift_offs_detected: u32,
    /// True lift-offs it did not detect.
    pub missed_lift_offs: u32,
    /// Detections with the tip in contact throughout.
    pub false_alarms: u32,
    /// Largest detection latency, periods.
    pub max_detection_latency_periods: u32,
}

/// Matches true and detected lift-offs period by period: a true flight episode is
/// detected if the firmware declares lift-off during it or within 5 periods after
/// it ends (a short hop may end before the confirmation); a detection episode that
/// overlaps no true flight (nor starts within 5 periods after one) is a false alarm.
pub fn lift_off_stats(records: &[PeriodRecord]) -> LiftOffStats {
    const GRACE: usize = 5;
    let mut st = LiftOffStats::default();
    let n = records.len();
    let mut k = 0;
    while k < n {
        if records[k].lift_off_true && (k == 0 || !records[k - 1].lift_off_true) {
            st.lift_offs += 1;
            let start = k;
            let mut end = k;
            while end + 1 < n && records[end + 1].lift_off_true {
                end += 1;
            }
            match (start..n.min(end + 1 + GRACE)).find(|&j| records[j].lift_off_detected) {
                Some(j) => {
                    st.lift_offs_detected += 1;
                    st.max_detection_latency_periods = st.max_detection_latency_periods.max((j - start) as u32);
                }
                None => st.missed_lift_offs += 1,
            }
            k = end + 1;
        } else {
            k += 1;
        }
    }
    let mut k = 0;
    while k < n {
        if records[k].lift_off_detected && (k == 0 || !records[k - 1].lift_off_detected) {
            let start = k;
            let mut end = k;
            while end + 1 < n && records[end + 1].lift_off_detected {
                end += 1;
            }
            let lo = start.saturating_sub(GRACE);
            if !(lo..=end).any(|j| records[j].lift_off_true) {
                st.false_alarms += 1;
            }
            k = end + 1;
        } else {
            k += 1;
        }
    }
    st
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let last = a.last().unwrap();
        assert!((last.z_t - 0.10).abs() < 1e-3, "final z_t {}", last.z_t);
        let settled: Vec<_> = a.iter().filter(|r| r.t > 2.5).collect();
        assert!(settled.iter().all(|r| (r.f_n - 10.0).abs() < 0.5), "f_n held near 10 N");
    }

    #[test]
    fn stats_match_hand_made_sequences() {
        let base = PeriodRecord {
            t: 0.0,
            theta1: 0.0,
            theta1_dot: 0.0,
            theta2: 0.0,
            theta2_dot: 0.0,
            z_t: 0.0,
            z_n: 0.0,
            z_t_ref: 0.0,
            f_t: 0.0,
            f_n: 0.0,
            mode: "sliding",
            u1_cmd: 0.0,
            u2_cmd: 0.0,
            u1_applied: 0.0,
            u2_applied: 0.0,
            lift_off_true: false,
            lift_off_detected: false,
            deadline_miss: false,
            status: 0,
        };
        let seq = |truth: &str, det: &str| -> Vec<PeriodRecord> {
            truth
                .chars()
                .zip(det.chars())
                .map(|(t, d)| PeriodRecord { lift_off_true: t == '1', lift_off_detected: d == '1', ..base })
                .collect()
        };
        // One hop detected 2 periods late, one missed, one false alarm.
        let r = seq("0011110000000000011000000000000000", "0000111100000000000000000000011000");
        let st = lift_off_stats(&r);
        assert_eq!((st.lift_offs, st.lift_offs_detected, st.missed_lift_offs, st.false_alarms), (2, 1, 1, 1));
        assert_eq!(st.max_detection_latency_periods, 2);
    }
}
