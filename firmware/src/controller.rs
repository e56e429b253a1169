//! The per-period step: decode and check the frame, estimate, detect lift-off,
//! run the control law, saturate and encode, monitor deadlines, and hold the
//! safe state.

use nalgebra::Vector2;
use shared::{
    Arm, ElbowBranch,
    kinematics::{JointTrig, tip_position_trig},
    model::ArmTerms,
    time::{Duration, Instant},
    wire::{self, ActuatorCommand, SensorFrame, status},
};

use crate::{
    TickClock,
    belt_check::{self, BeltMonitor},
    chatter::ChatterMonitor,
    config::{Config, ConfigError},
    consistency::{ConsistencyMonitor, ConsistencyRule, FrictionSignMonitor, InnovationMonitor, InnovationRule},
    control_law::{ControlLaw, LawContext, LawInput, PaperLaws},
    decode::{self, EncoderScale, FrameFault, Measurement},
    estimator::{self, AngleTracker},
    law::{self, TipKinematics},
    liftoff::{LiftOffDetector, LiftOffRule},
    reference::{Quintic, RefPoint},
    runaway::{Runaway, RunawayMonitor, RunawayRule},
    tracking::{Expectation, TrackingMonitor, TrackingRule},
    wiring::{WiringInput, WiringMonitor, WiringRule},
};

mod safe_reason;
mod telemetry;

pub use safe_reason::SafeReason;
pub use telemetry::Telemetry;

/// `1 / x`, out of line and cold: the rate of an interval after skipped periods,
/// rare. Inline, the compiler computed the division (14 cycles) every step, the
/// usual one too, to select it without a branch.
#[cold]
#[inline(never)]
fn reciprocal(x: f32) -> f32 {
    1.0 / x
}

#[derive(Debug, Clone, Copy)]
struct Started {
    seq0: u32,
    last_seq: u32,
    trackers: [AngleTracker; 2],
    quintic: Quintic,
    force_ramp: Quintic,
    branch: ElbowBranch,
    /// Sines and cosines of the trackers' angles as the last step left them: the
    /// next step's prediction starts from those angles (two `sin_cos` saved).
    trig: JointTrig<f32>,
}

/// The firmware's state across periods, running control law `L` (by default
/// the paper's two, [`PaperLaws`]). Fixed size, no heap.
#[derive(Debug, Clone)]
pub struct Firmware<L: ControlLaw = PaperLaws> {
    cfg: Config,
    arm: Arm<f32>,
    /// The arm's constant factors, folded once per configuration (not every step).
    terms: ArmTerms<f32>,
    /// The encoders' count range and angle per count, derived once.
    scale: EncoderScale,
    started: Option<Started>,
    liftoff: LiftOffDetector,
    consistency: ConsistencyMonitor,
    innovation: InnovationMonitor,
    friction_sign: FrictionSignMonitor,
    /// The belt speed reading's plausibility ([`crate::belt_check`]).
    belt: BeltMonitor,
    /// The friction sign check's confirmation at this rate, periods.
    friction_confirm: u16,
    runaway: RunawayMonitor,
    /// The runaway limits at this rate, derived once.
    runaway_rule: RunawayRule,
    wiring: WiringMonitor,
    /// The wiring check at this rate, derived once.
    wiring_rule: WiringRule,
    tracking: TrackingMonitor,
    /// A law that chatters ([`crate::chatter`]).
    chatter: ChatterMonitor,
    /// The hybrid law's tracking check at this rate and gains, derived once.
    tracking_rule: TrackingRule,
    /// The hybrid law's last disturbance bound `D`, m/s^2 ([`crate::tracking`]).
    disturbance: f32,
    /// The control law and its state.
    law: L,
    last_codes: [i16; 2],
    applied: [f32; 2],
    last_saturated: bool,
    consecutive_bad: u16,
    consecutive_misses: u16,
    overruns: u32,
    safe: Option<SafeReason>,
    telemetry: Telemetry,
    /// The period in seconds, `f32`, derived once from `cfg.period`.
    dt: f32,
    /// `1 / dt`, 1/s: the rate of a step that follows its predecessor (no gap).
    rate: f32,
    /// The friction estimate's filter gain per period, `mu_estimate::gain(dt)`.
    mu_gain: f32,
    /// `1 / move_time_s`, 1/s, for the first frame's move.
    move_rate: f32,
    /// The force ramp's duration (`force_ramp_s`, at least 1 ns), s, and its inverse, 1/s.
    ramp: (f32, f32),
    /// The observer's gains for `cfg` (at angle 0): the first frame's trackers
    /// start from it, so no step pays for the `expf` of the gains.
    tracker: AngleTracker,
}

impl Firmware {
    /// A firmware instance with configuration `cfg`, running the paper's law
    /// the configuration's `controller` names ([`PaperLaws`]).
    ///
    /// # Errors
    /// [`ConfigError`] naming the first invalid setting.
    pub fn new(cfg: Config) -> Result<Self, ConfigError> {
        Self::with_law(cfg)
    }
}

// Where the step's code is compiled (issue 70; docs/measurements.md "The step
// behind a trait"). `Firmware<L>` is generic, so its methods are compiled in the
// crate that builds the image, where they inline into each other before link-time
// optimisation. The step as it was before the trait calls two non-generic
// functions of this crate, the frame's check and the body, which fat LTO then
// inlines whole (the body with the last-call bonus): the paper's laws keep that
// shape through `control_law::paper_control` and these free functions, which
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

/// Latches `reason` in `safe` unless a reason is latched already.
fn enter_safe(safe: &mut Option<SafeReason>, reason: SafeReason) {
    if safe.is_none() {
        *safe = Some(reason);
    }
}

impl<L: ControlLaw> Firmware<L> {
    /// A firmware instance with configuration `cfg` running law `L`: the
    /// firmware's own checks of `cfg`, then that `cfg.law` is for `L` with
    /// every value in the range `L` declares ([`crate::LawSpec::check`]), then
    /// the law's own ([`ControlLaw::validate`]). A malformed [`ControlLaw::SPEC`]
    /// does not compile.
    ///
    /// # Errors
    /// [`ConfigError`] naming the first invalid setting.
    pub fn with_law(cfg: Config) -> Result<Self, ConfigError> {
        const {
            assert!(
                L::SPEC.is_valid(),
                "ControlLaw::SPEC: a name of up to 16 ASCII letters, digits, - or _; at most 8 parameters, each named once, min <= default <= max, finite"
            )
        };
        cfg.validate()?;
        L::SPEC.check(&cfg.law)?;
        L::validate(&cfg)?;
        Ok(Self::fresh(cfg))
    }

    /// A fresh state for an already validated configuration. The tracking
    /// check's rule is derived from the dynamics the law declares (the hybrid
    /// gains when it declares none: the check is then off, the rule unused).
    fn fresh(cfg: Config) -> Self {
        let ts = cfg.period.as_secs_f32();
        let d = L::declares(&cfg).tracking.unwrap_or(crate::control_law::TrackingDynamics {
            kp: cfg.hybrid.kp,
            kd: cfg.hybrid.kd,
            ki: cfg.hybrid.ki,
        });
        Self::fresh_with(cfg, TrackingRule::at_period(ts, d.kp, d.kd, d.ki))
    }

    /// [`Self::fresh`] with the tracking check's rule already derived for `cfg`
    /// (its filters' coefficients take a few thousand cycles of `expf`: a
    /// reset, which the board runs in its control handler at the enable
    /// button, keeps them instead; at 10 kHz they would take a period).
    fn fresh_with(cfg: Config, tracking_rule: TrackingRule) -> Self {
        Self {
            cfg,
            arm: Arm::new(cfg.params),
            terms: ArmTerms::of(&cfg.params),
            scale: EncoderScale::of_bits(cfg.encoder_bits),
            started: None,
            liftoff: LiftOffDetector::default(),
            consistency: ConsistencyMonitor::default(),
            innovation: InnovationMonitor::default(),
            friction_sign: FrictionSignMonitor::default(),
            belt: BeltMonitor::default(),
            friction_confirm: FrictionSignMonitor::confirm_periods(cfg.period.as_secs_f32()),
            runaway: RunawayMonitor::default(),
            runaway_rule: RunawayRule::at_period(cfg.period.as_secs_f32()),
            wiring: WiringMonitor::default(),
            wiring_rule: WiringRule::at_period(cfg.period.as_secs_f32()),
            tracking: TrackingMonitor::default(),
            chatter: ChatterMonitor::default(),
            tracking_rule,
            disturbance: 0.0,
            law: L::fresh(&cfg),
            last_codes: [0, 0],
            applied: [0.0, 0.0],
            last_saturated: false,
            consecutive_bad: 0,
            consecutive_misses: 0,
            overruns: 0,
            safe: None,
            telemetry: Telemetry::default(),
            dt: cfg.period.as_secs_f32(),
            rate: 1.0 / cfg.period.as_secs_f32(),
            mu_gain: crate::mu_estimate::gain(cfg.period.as_secs_f32()),
            move_rate: 1.0 / cfg.move_time_s,
            ramp: (cfg.force_ramp_s.max(1e-9), 1.0 / cfg.force_ramp_s.max(1e-9)),
            tracker: AngleTracker::new(0.0, cfg.observer_bandwidth, cfg.period.as_secs_f32()),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// The safe state's reason, if the firmware is in it.
    pub fn safe_state(&self) -> Option<SafeReason> {
        self.safe
    }

    /// Deadline overruns since the last reset.
    pub fn overruns(&self) -> u32 {
        self.overruns
    }

    /// What the last step computed.
    pub fn telemetry(&self) -> &Telemetry {
        &self.telemetry
    }

    /// Leaves the safe state and starts afresh at the next frame (new reference
    /// from the tip's position then, integrators and counters cleared). The only
    /// way out of the safe state.
    pub fn reset(&mut self) {
        *self = Self::fresh_with(self.cfg, self.tracking_rule);
    }

    fn enter_safe(&mut self, reason: SafeReason) {
        enter_safe(&mut self.safe, reason);
    }

    /// Latches the safe state (zero torque) for a reason found outside the step,
    /// such as [`SafeReason::PeerLost`] when the board sees its peer die. A state
    /// already latched keeps its first reason. Left only by [`Firmware::reset`].
    pub fn enter_safe_state(&mut self, reason: SafeReason) {
        self.enter_safe(reason);
    }

    /// Counts `periods` control ticks that passed without a step: the board woke
    /// (a stalled process, a core held by something else) to frames it never
    /// answered and dropped as stale, answering only the newest. Each is an
    /// overrun and a consecutive deadline miss, as if its step had run late, so
    /// the firmware's count equals what its peer saw; `deadline_miss_limit`
    /// consecutive misses latch [`SafeReason::DeadlineMisses`]. The next step on
    /// time clears the consecutive count, as usual. Saturating.
    pub fn missed_periods(&mut self, periods: u32) {
        if periods == 0 {
            return;
        }
        self.overruns = self.overruns.saturating_add(periods);
        self.consecutive_misses = self.consecutive_misses.saturating_add(u16::try_from(periods).unwrap_or(u16::MAX));
        if self.consecutive_misses >= self.cfg.deadline_miss_limit {
            self.enter_safe(SafeReason::DeadlineMisses);
        }
    }

    /// The zero-torque command the safe state sends for frame `seq` at `now` (on
    /// the clock of [`SensorFrame::t_us`]) without a frame to step on (the board's
    /// loop uses it when its peer is lost).
    pub fn safe_command(&self, seq: u32, now: Instant) -> ActuatorCommand {
        let reason = self.safe.map_or(0, |r| r as u32);
        ActuatorCommand {
            t_sent_us: now.as_us(),
            seq,
            u1_code: 0,
            u2_code: 0,
            status: status::SAFE_STATE | (reason << status::REASON_SHIFT),
            step_ticks: 0,
            overruns: self.overruns,
            reserved: 0,
        }
    }
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
                let qdd = if crate::finite_both(qdd[0], qdd[1]) { qdd } else { Vector2::zeros() };
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
        if !crate::finite_all3(out.u[0], out.u[1], out.disturbance) {
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
