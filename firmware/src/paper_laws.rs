//! The paper's two control laws as [`ControlLaw`]s: the joint-space PID
//! ([`PidLaw`], paper eq. 8) and the hybrid force/motion law ([`HybridLaw`], eqs.
//! 9 to 11 with every friction term), and [`PaperLaws`], the two chosen by the
//! configuration's `controller`: what the `arm` and PIL images, the firmware
//! process and the in-process rig run.

use crate::{
    config::{Config, ControllerKind},
    control_law::{ControlLaw, Declares, LawContext, LawInput, LawOutput, Sealed, TrackingDynamics},
    law::{self, HybridInput, HybridState, LawError, PidState},
    law_spec::LawSpec,
};

/// The joint-space PID (paper eq. 8, [`law::pid`]): no tracking promise on
/// `z_t` (it tracks joint angles), no reference acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PidLaw {
    state: PidState,
}

impl ControlLaw for PidLaw {
    const SPEC: LawSpec = LawSpec::PAPER;

    fn fresh(_cfg: &Config) -> Self {
        Self::default()
    }

    #[inline(always)]
    fn declares(_cfg: &Config) -> Declares {
        Declares { tracking: None, on_belt: false, uses_reference_acceleration: false }
    }

    #[inline(always)]
    fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError> {
        let u = law::pid(
            ctx.arm,
            &ctx.cfg.pid,
            ctx.branch,
            &input.reference,
            input.q,
            input.qd,
            &mut self.state,
            input.dt,
            ctx.cfg.torque_limit,
        )?;
        Ok(LawOutput { u, disturbance: 0.0 })
    }
}

/// The hybrid force/motion law (paper eqs. 9 to 11, [`law::hybrid_at`]) with
/// the configuration's friction term: it promises `z_t`'s tracking dynamics of
/// its gains `K'_P`, `K'_D`, `K'_I` and reads the reference's acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HybridLaw {
    state: HybridState,
}

impl ControlLaw for HybridLaw {
    const SPEC: LawSpec = LawSpec::PAPER;

    fn fresh(_cfg: &Config) -> Self {
        Self::default()
    }

    #[inline(always)]
    fn declares(cfg: &Config) -> Declares {
        let h = &cfg.hybrid;
        Declares { tracking: Some(TrackingDynamics { kp: h.kp, kd: h.kd, ki: h.ki }), on_belt: true, uses_reference_acceleration: true }
    }

    #[inline(always)]
    fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError> {
        let cfg = ctx.cfg;
        let measured = HybridInput { q: input.q, qd: input.qd, f_t: input.f_t, f_n: input.f_n, v_belt: input.v_belt };
        let (u, signals) = law::hybrid_at(
            ctx.terms,
            cfg.params.mu,
            &cfg.hybrid,
            cfg.friction,
            &input.reference,
            input.f_n_ref,
            &measured,
            &input.trig,
            &input.kin,
            &mut self.state,
            input.dt,
            ctx.mu_gain,
            input.saturated,
        )?;
        Ok(LawOutput { u, disturbance: signals.disturbance })
    }
}

/// The paper's two laws, the configuration's `controller` choosing
/// ([`ControllerKind`]): what the `arm` and PIL images, the firmware process
/// and the in-process rig run. Both states are kept, as before the trait, so
/// a configuration's law is the same bits whichever way it is built.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PaperLaws {
    pid: PidLaw,
    hybrid: HybridLaw,
}

impl ControlLaw for PaperLaws {
    const SPEC: LawSpec = LawSpec::PAPER;

    #[inline(always)]
    fn control(
        fw: &mut crate::controller::Firmware<Self>,
        seq: u32,
        m: &crate::decode::Measurement,
        _: Sealed,
    ) -> Result<([f32; 2], u32), crate::controller::SafeReason> {
        paper_control(fw, seq, m)
    }

    fn fresh(_cfg: &Config) -> Self {
        Self::default()
    }

    #[inline(always)]
    fn declares(cfg: &Config) -> Declares {
        match cfg.controller {
            ControllerKind::Pid => PidLaw::declares(cfg),
            ControllerKind::Hybrid => HybridLaw::declares(cfg),
        }
    }

    #[inline(always)]
    fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError> {
        match ctx.cfg.controller {
            ControllerKind::Pid => self.pid.step(ctx, input),
            ControllerKind::Hybrid => self.hybrid.step(ctx, input),
        }
    }
}

/// [`crate::controller::Firmware`]'s body for the paper's laws ([`PaperLaws`]'s
/// [`ControlLaw::control`]): one non-generic function of this crate, which the
/// image's link-time optimisation inlines whole into the step (`crate::controller`'s
/// notes on where the step's code is compiled).
fn paper_control(
    fw: &mut crate::controller::Firmware<PaperLaws>,
    seq: u32,
    m: &crate::decode::Measurement,
) -> Result<([f32; 2], u32), crate::controller::SafeReason> {
    fw.control(seq, m)
}
