//! The protected step: the frame's decoding and checks, the estimate, lift-off
//! detection, the law, saturation and the torques' encoding, the checks around
//! the law, deadlines and the safe state (docs/architecture.md, issue 80: the
//! body no law can replace).

use nalgebra::Vector2;
use shared::{
    Arm, ElbowBranch,
    kinematics::{JointTrig, tip_position_trig},
    time::{Duration, Instant},
    wire::{self, ActuatorCommand, SensorFrame, status},
};

use crate::{
    belt_check::{self},
    consistency::{ConsistencyRule, InnovationRule},
    control_law::{ControlLaw, LawContext, LawInput},
    decode::{self, EncoderScale, FrameFault, Measurement},
    estimator::{self},
    law::{self, TipKinematics},
    liftoff::LiftOffRule,
    reference::{Quintic, RefPoint},
    runaway::Runaway,
    tick_clock::TickClock,
    tracking::Expectation,
    wiring::WiringInput,
};

use super::{Firmware, SafeReason, Started, Telemetry};

/// `1 / x`, out of line and cold: the rate of an interval after skipped periods,
/// rare. Inline, the compiler computed the division (14 cycles) every step, the
/// usual one too, to select it without a branch.
#[cold]
#[inline(never)]
fn reciprocal(x: f32) -> f32 {
    1.0 / x
}

// Where the step's code is compiled (issue 70; docs/measurements.md "The step
// behind a trait"). `Firmware<L>` is generic, so its methods are compiled in the
// crate that builds the image, where they inline into each other before link-time
// optimisation. The step as it was before the trait calls two non-generic
// functions of this crate, the frame's check and the body, which fat LTO then
// inlines whole (the body with the last-call bonus): the paper's laws keep that
// shape through `paper_laws::paper_control` and these free functions, which
// are not generic in the law. With the generic body compiled in the image's crate the step took
// 8 to 11 % more instructions, and with the frame's check inlined early LTO took
// the body's call as cold (threshold 45) and left it out of line.

/// Decodes `frame` and checks its sequence against the last one's, `last_seq`
/// (`None` before the first): the measurement and whether periods were skipped.
/// Not generic (compiled here, whatever the law): see the notes above.
fn checked(scale: &EncoderScale, last_seq: Option<u32>, frame: &SensorFrame) -> Result<(Measurement, bool), FrameFault> {
    let m = decode::decode_with(frame, scale)?;
    match last_seq {
        Some(last) if frame.seq <= last => Err(FrameFault::Stale),
        Some(last) => Ok((m, frame.seq > last.wrapping_add(1))),
        None => Ok((m, false)),
    }
}

impl<L: ControlLaw> Firmware<L> {
    /// One control period.
    ///
    /// `now` is when the step starts, on the clock of `frame.t_us`; `clock`
    /// measures the step's own execution. The command answers `frame.seq`. It is a
    /// deadline miss when the command leaves later than `frame.t_us + Ts`
    /// (`now - t_us` plus the step's own time); `deadline_miss_limit`
    /// consecutive misses latch the safe state.
    ///
    /// Bad frames (counts out of range, a repeated or older sequence number) are
    /// never trusted: the previous command is held and `BAD_FRAME` reported;
    /// `bad_frame_limit` consecutive ones latch the safe state. A law failure
    /// (unreachable reference, singular arm, NaN) latches it at once. In the safe
    /// state the command is zero torque with `SAFE_STATE` and the reason code set,
    /// until [`Firmware::reset`].
    // Never inlined: the step's code (and its instruction count, a CI gate) must not
    // depend on the board loop it is called from (docs/board.md "The control step's cost").
    #[inline(never)]
    pub fn step<C: TickClock>(&mut self, now: Instant, frame: &SensorFrame, clock: &C) -> ActuatorCommand {
        let start = clock.ticks();
        let mut flags = 0u32;
        let codes = match self.checked(frame) {
            Err(fault) => {
                flags |= fault.status_bits();
                self.consecutive_bad = self.consecutive_bad.saturating_add(1);
                if self.consecutive_bad >= self.cfg.bad_frame_limit {
                    self.enter_safe(SafeReason::BadFrames);
                }
                self.last_codes
            }
            Ok((m, gap)) => {
                self.consecutive_bad = 0;
                if gap {
                    flags |= status::SEQUENCE_GAP;
                }
                match L::control(self, frame.seq, &m, crate::control_law::Sealed(())) {
                    Ok((u, f)) => {
                        flags |= f;
                        let (u1, s1) = wire::encode_torque(u[0]);
                        let (u2, s2) = wire::encode_torque(u[1]);
                        self.last_saturated = flags & (status::SATURATED_U1 | status::SATURATED_U2) != 0 || s1 || s2;
                        [u1, u2]
                    }
                    Err(reason) => {
                        self.enter_safe(reason);
                        [0, 0]
                    }
                }
            }
        };
        // Deadline: the command leaves at now + the step's own time; leaving at
        // t_k + Ts or later it cannot act in period k (the plant's rule too).
        let elapsed_ticks = clock.ticks().wrapping_sub(start);
        let elapsed = Duration::from_us(elapsed_ticks as u64 * 1_000_000 / clock.ticks_per_second().max(1) as u64);
        let period_us = self.cfg.period.as_us();
        // Saturating: a clock near u64::MAX (or a frame stamped far in the past)
        // must read as late, never wrap round to on time.
        if now.saturating_since(frame.sampled_at()).saturating_add(elapsed).as_us() >= period_us {
            flags |= status::DEADLINE_MISS;
            self.overruns = self.overruns.saturating_add(1);
            self.consecutive_misses = self.consecutive_misses.saturating_add(1);
            if self.consecutive_misses >= self.cfg.deadline_miss_limit {
                self.enter_safe(SafeReason::DeadlineMisses);
            }
        } else {
            self.consecutive_misses = 0;
        }
        let codes = match self.safe {
            Some(reason) => {
                flags |= status::SAFE_STATE | ((reason as u32) << status::REASON_SHIFT);
                [0, 0]
            }
            None => codes,
        };
        self.last_codes = codes;
        self.applied = [wire::decode_torque(codes[0]), wire::decode_torque(codes[1])];
        ActuatorCommand {
            t_sent_us: now.saturating_add(elapsed).as_us(),
            seq: frame.seq,
            u1_code: codes[0],
            u2_code: codes[1],
            status: flags,
            step_ticks: elapsed_ticks,
            overruns: self.overruns,
            reserved: 0,
        }
    }

    /// Decodes the frame and checks its sequence; returns the measurement and
    /// whether periods were skipped.
    fn checked(&self, frame: &SensorFrame) -> Result<(Measurement, bool), FrameFault> {
        checked(&self.scale, self.started.as_ref().map(|s| s.last_seq), frame)
    }

    /// Estimation, lift-off detection and the control law for a trusted frame;
    /// returns the motor torques (N m, saturated) and status bits. Reached
    /// through [`ControlLaw::control`] (see there why); private to the crate,
    /// so no law can skip it (issue 80).
    #[inline(always)]
    pub(crate) fn control(&mut self, seq: u32, m: &Measurement) -> Result<([f32; 2], u32), SafeReason> {
        // Borrowed, not copied: the configuration is most of the firmware's state.
        let cfg = &self.cfg;
        let ts = self.dt;
        let p = &cfg.params;
        // Both in (-pi, pi] (decoded): their sum needs no remainder (the same bits).
        let theta2 = decode::wrap_sum(m.theta1 + m.elbow);
        let mut innovation = [0.0f32; 2];
        // The joint accelerations the model did not explain over the interval, rad/s^2.
        let mut missed_accel = [0.0f32; 2];
        // The motor torques the model expected to accelerate the joints over the
        // interval, `[v0 + v1, v1]` of `M q_ddot = u - w - c + J^T f`, N m.
        let mut net = [0.0f32; 2];
        // Initialise on the first trusted frame: the reference starts where the tip is.
        // The sines and cosines of the estimate, when the first frame has them already.
        let mut first_trig = None;
        let s: &mut Started = match &mut self.started {
            Some(s) => {
                let gap = seq.wrapping_sub(s.last_seq);
                let dt = gap as f32 * ts;
                // Model-based prediction: the joint acceleration under the torque we
                // commanded and the force we measured (both held over the interval).
                let q = Vector2::new(s.trackers[0].angle, s.trackers[1].angle);
                let qd = Vector2::new(s.trackers[0].rate, s.trackers[1].rate);
                let u = Arm::generalised_torque(&Vector2::new(self.applied[0], self.applied[1]));
                let (qdd, v) = estimator::predicted_acceleration(&self.terms, &s.trig, &q, &qd, &u, &Vector2::new(m.f_t, m.f_n));
                net = [v[0] + v[1], v[1]];
                let qdd = if crate::finite::finite_both(qdd[0], qdd[1]) { qdd } else { Vector2::zeros() };
                innovation = [
                    s.trackers[0].update_with_acceleration(m.theta1, dt, qdd[0]),
                    s.trackers[1].update_with_acceleration(theta2, dt, qdd[1]),
                ];
                // 1 / dt without the division when no period was skipped (the same bits:
                // `1 as f32 * ts` is `ts`).
                let per_s = if gap == 1 { self.rate } else { reciprocal(dt) };
                missed_accel = [s.trackers[0].rate_correction(innovation[0]) * per_s, s.trackers[1].rate_correction(innovation[1]) * per_s];
                s.last_seq = seq;
                s
            }
            None => {
                let q = Vector2::new(m.theta1, theta2);
                let trig = JointTrig::new(&q);
                let z = tip_position_trig(p.l, &trig);
                let s = Started {
                    seq0: seq,
                    last_seq: seq,
                    trackers: [self.tracker.restarted_at(m.theta1), self.tracker.restarted_at(theta2)],
                    quintic: Quintic::with_rate(z[0], cfg.target_z_t, cfg.move_time_s, self.move_rate),
                    force_ramp: Quintic::with_rate(law::clamp(m.f_n, 0.0, cfg.f_n_ref), cfg.f_n_ref, self.ramp.0, self.ramp.1),
                    branch: cfg.branch.unwrap_or(ElbowBranch::of(&q)),
                    trig,
                };
                // The trackers start at the measured angles: the estimate's sines and
                // cosines are these (no second sin_cos on the first frame).
                first_trig = Some(trig);
                self.started.insert(s)
            }
        };
        let q = Vector2::new(s.trackers[0].angle, s.trackers[1].angle);
        let qd = Vector2::new(s.trackers[0].rate, s.trackers[1].rate);
        // One sin_cos per angle for the tip estimate, the hybrid law and the next
        // step's prediction.
        let trig = match first_trig {
            Some(t) => t,
            None => JointTrig::of(&q),
        };
        s.trig = trig;
        let kin = TipKinematics::of(p.l, &trig, &qd);
        let (z, z_dot) = (kin.z, kin.z_dot);
        let height = z[1] + p.h;
        let rule = LiftOffRule {
            lift_off_force: cfg.lift_off_force,
            lift_off_height: cfg.lift_off_height,
            confirm: cfg.lift_off_confirm,
            touchdown_force: cfg.touchdown_force,
        };
        let lifted = self.liftoff.update(&rule, m.f_n, height);
        // The raw angles (quantisation only, no observer lag) against the load cell.
        // Their cosines from the estimate's sines and cosines (a few milliradians away).
        let measured_height = trig.tip_normal_near(p.l, &q, &Vector2::new(m.theta1, theta2)) + p.h;
        let consistency_rule = ConsistencyRule {
            contact_force: cfg.sensor_contact_force,
            height_tolerance: cfg.sensor_height_tolerance,
            confirm: cfg.sensor_fault_confirm,
        };
        let innovation_rule =
            InnovationRule { threshold: cfg.innovation_threshold, confirm: cfg.innovation_confirm, settle: cfg.innovation_settle };
        // A load cell at full scale under-reads: the prediction made with it is wrong.
        let full_scale = wire::LOAD_FULL_SCALE_N * (wire::LOAD_CODE_MAX - 1) as f32 / -(wire::LOAD_CODE_MIN as f32);
        let load_saturated = m.f_n.abs() >= full_scale || m.f_t.abs() >= full_scale;
        // Friction against the slip: the slip is the observer's, whose prediction
        // is wrong at full scale (as after an impact): it is then no evidence.
        // The belt's reading against the last ([`crate::belt_check`]): from the run's
        // fourth period (its first reads 0, its second may read part of a period; the
        // reference's time below, the same subtraction).
        let k_run = seq.wrapping_sub(s.seq0);
        let belt_jumped = self.belt.update(m.v_belt) & (k_run >= belt_check::FIRST_PERIOD);
        let inconsistent = belt_jumped
            | self.consistency.update(&consistency_rule, m.f_n, measured_height)
            | self.friction_sign.update(
                cfg.sensor_contact_force,
                m.f_t,
                m.f_n,
                z_dot[0] - m.v_belt,
                lifted || load_saturated,
                self.friction_confirm,
            );
        let unexplained = self.innovation.update(&innovation_rule, innovation, lifted, load_saturated);
        if inconsistent || unexplained {
            return Err(SafeReason::SensorFault);
        }
        if cfg.runaway_limits {
            match self.runaway.update(&self.runaway_rule, [qd[0], qd[1]], load_saturated, m.f_n) {
                Some(Runaway::Speed) => return Err(SafeReason::Runaway),
                Some(Runaway::Overload) => return Err(SafeReason::Overload),
                None => {}
            }
            let input = WiringInput {
                unexplained: missed_accel,
                c21: trig.c21(),
                applied: self.applied,
                net,
                lifted,
                height,
                height_rate: z_dot[1],
                load_saturated,
            };
            let mass = [self.terms.m11, self.terms.half_ml2, self.terms.m22];
            if self.wiring.update_folded(&self.wiring_rule, mass, &input).is_some() {
                return Err(SafeReason::Miswired);
            }
        }
        let t_run = k_run as f32 * ts;
        // The PID uses no reference acceleration: not computed under it.
        // What the law declares, derived from the configuration where it is used
        // (the paper's laws: one comparison of `controller`, shared by both uses
        // and the law's own dispatch).
        let declares = L::declares(cfg);
        let reference: RefPoint = s.quintic.at_with(t_run, declares.uses_reference_acceleration);
        if cfg.runaway_limits && declares.tracking.is_some() {
            match self.tracking.update(&self.tracking_rule, z[0] - reference.pos, lifted, self.disturbance, self.last_saturated) {
                Some(Expectation::Tracking) => return Err(SafeReason::Tracking),
                Some(Expectation::Saturated) => return Err(SafeReason::Saturated),
                Some(Expectation::Unstable) => return Err(SafeReason::Unstable),
                Some(Expectation::LiftOff) => return Err(SafeReason::LiftOff),
                None => {}
            }
        } else if cfg.runaway_limits && declares.on_belt && lifted {
            // A law that holds the tip on the belt and promises no tracking
            // dynamics: the lift-off the firmware declares breaks its promise.
            return Err(SafeReason::LiftOff);
        }
        let f_n_ref = s.force_ramp.pos_at(t_run);
        let mut flags = m.flags;
        if lifted {
            flags |= status::LIFT_OFF;
        }
        if reference.moving {
            flags |= status::REFERENCE_MOVING;
        }
        let ctx = LawContext { cfg, arm: &self.arm, terms: &self.terms, branch: s.branch, mu_gain: self.mu_gain };
        let input = LawInput {
            q,
            qd,
            trig,
            kin,
            reference,
            f_n_ref,
            f_t: m.f_t,
            f_n: m.f_n,
            v_belt: m.v_belt,
            dt: ts,
            saturated: self.last_saturated,
        };
        let out = self.law.step(&ctx, &input)?;
        // A law's non-finite torques or disturbance bound are its failure,
        // whatever it returns or declares (issue 80: the paper's laws check
        // their own too; a NaN bound would blind the tracking check).
        if !crate::finite::finite_all3(out.u[0], out.u[1], out.disturbance) {
            return Err(SafeReason::NonFinite);
        }
        self.disturbance = out.disturbance;
        let u_raw = out.u;
        let (u, sat) = law::saturate(u_raw, cfg.torque_limit);
        if cfg.runaway_limits && self.chatter.update(u, cfg.torque_limit) {
            // A command that chatters while a joint already moves against its
            // motor is a miswired arm, not the law's own failure (issue 80).
            return Err(if self.wiring.suspects() { SafeReason::Miswired } else { SafeReason::Unstable });
        }
        if sat[0] {
            flags |= status::SATURATED_U1;
        }
        if sat[1] {
            flags |= status::SATURATED_U2;
        }
        self.telemetry = Telemetry { q: [q[0], q[1]], qd: [qd[0], qd[1]], z_t_ref: reference.pos, f_n_ref, f: [m.f_t, m.f_n], u_raw };
        Ok((u, flags))
    }
}
