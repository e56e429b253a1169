//! The firmware's life outside the step: made for a configuration and a law,
//! reset, put in and read out of the safe state, told of missed periods.

use shared::{
    Arm,
    model::ArmTerms,
    time::Instant,
    wire::{ActuatorCommand, status},
};

use crate::{
    belt_check::BeltMonitor,
    chatter::ChatterMonitor,
    config::{Config, ConfigError},
    consistency::{ConsistencyMonitor, FrictionSignMonitor, InnovationMonitor},
    control_law::ControlLaw,
    decode::EncoderScale,
    estimator::AngleTracker,
    liftoff::LiftOffDetector,
    paper_laws::PaperLaws,
    runaway::{RunawayMonitor, RunawayRule},
    tracking::{TrackingMonitor, TrackingRule},
    wiring::{WiringMonitor, WiringRule},
};

use super::{Firmware, SafeReason, Telemetry};

impl Firmware<PaperLaws> {
    /// A firmware instance with configuration `cfg`, running the paper's law
    /// the configuration's `controller` names ([`PaperLaws`]).
    ///
    /// # Errors
    /// [`ConfigError`] naming the first invalid setting.
    pub fn new(cfg: Config) -> Result<Self, ConfigError> {
        Self::with_law(cfg)
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

    pub(super) fn enter_safe(&mut self, reason: SafeReason) {
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
}

/// Latches `reason` in `safe` unless a reason is latched already.
fn enter_safe(safe: &mut Option<SafeReason>, reason: SafeReason) {
    if safe.is_none() {
        *safe = Some(reason);
    }
}
