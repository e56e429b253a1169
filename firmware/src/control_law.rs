//! A control law as the firmware runs it (issue 70): the [`ControlLaw`] trait,
//! what a law reads each period ([`LawInput`], [`LawContext`]), what it returns
//! ([`LawOutput`]) and what it declares to the protection ([`Declares`]); the
//! paper's two laws as its implementations ([`PidLaw`], paper eq. 8;
//! [`HybridLaw`], eqs. 9 to 11 with every friction term) and [`PaperLaws`], the
//! two chosen by the configuration's `controller` (the images and the rig as
//! built today).
//!
//! The step ([`crate::controller::Firmware::step`]) owns everything around the law: the
//! frame's decoding and checks, the estimate, the reference, lift-off
//! detection, the sensor, runaway and wiring checks, saturation and the
//! torques' encoding, the chatter check, deadlines and the safe state. Which of
//! the checks that depend on the law apply is decided by what the law
//! declares ([`Declares`]), never by its name: the tracking check runs for a
//! law that declares its tracking dynamics, whichever law it is.
//!
//! A law runs in the control handler: it must not allocate, must not panic on
//! data and must stay within the step's budget (5 % of the period at 168 MHz,
//! docs/hardware.md "Budgets"). An error ([`LawError`]) latches the safe state
//! at once; non-finite torques or a non-finite disturbance bound are
//! [`crate::controller::SafeReason::NonFinite`] at that period, checked by the step after
//! every law, whatever the law returns or declares.
//!
//! **The boundary is sealed** (issue 80): a law supplies [`ControlLaw::step`]
//! and its declarations, never the protected body around it. The one hook
//! that chooses where that body is compiled ([`ControlLaw::control`]) takes a
//! parameter of a type private to this crate ([`Sealed`], as the standard
//! library seals `Error::type_id`), so no crate outside `firmware` can
//! override it or call it, and [`crate::controller::Firmware`]'s body is private to the
//! crate. Overriding it does not compile:
//!
//! ```compile_fail,E0603
//! use firmware::{config::Config, ControlLaw, Declares, LawContext, LawInput, LawOutput, LawSpec};
//! use firmware::{decode::Measurement, law::LawError, Firmware, SafeReason};
//!
//! #[derive(Debug, Clone)]
//! struct Escape;
//!
//! impl ControlLaw for Escape {
//!     const SPEC: LawSpec = LawSpec::PAPER;
//!     fn fresh(_: &Config) -> Self { Escape }
//!     fn declares(_: &Config) -> Declares { Declares { tracking: None, on_belt: false, uses_reference_acceleration: false } }
//!     fn step(&mut self, _: &LawContext<'_>, _: &LawInput) -> Result<LawOutput, LawError> {
//!         Ok(LawOutput { u: [2.0, 2.0], disturbance: 0.0 })
//!     }
//!     // The protected body replaced by a law's own: the hook's last parameter is
//!     // of a type no crate outside `firmware` can name (error E0603: private).
//!     fn control(
//!         _: &mut Firmware<Self>,
//!         _: u32,
//!         _: &Measurement,
//!         _: firmware::control_law::Sealed,
//!     ) -> Result<([f32; 2], u32), SafeReason> {
//!         Ok(([2.0, 2.0], 0))
//!     }
//! }
//! ```
//!
//! nor does calling the body directly:
//!
//! ```compile_fail,E0624
//! use firmware::{decode::Measurement, Firmware};
//! fn skip(fw: &mut Firmware<firmware::PaperLaws>, m: &Measurement) {
//!     let _ = fw.control(1, m);
//! }
//! ```
//!
//! while the same law without the override is an ordinary law:
//!
//! ```
//! use firmware::{config::Config, ControlLaw, Declares, LawContext, LawInput, LawOutput, LawSpec};
//! use firmware::law::LawError;
//!
//! #[derive(Debug, Clone)]
//! struct Escape;
//!
//! impl ControlLaw for Escape {
//!     const SPEC: LawSpec = LawSpec::PAPER;
//!     fn fresh(_: &Config) -> Self { Escape }
//!     fn declares(_: &Config) -> Declares { Declares { tracking: None, on_belt: false, uses_reference_acceleration: false } }
//!     fn step(&mut self, _: &LawContext<'_>, _: &LawInput) -> Result<LawOutput, LawError> {
//!         Ok(LawOutput { u: [2.0, 2.0], disturbance: 0.0 })
//!     }
//! }
//! let fw = firmware::Firmware::<Escape>::with_law(Config::default()).unwrap();
//! assert!(fw.safe_state().is_none());
//! ```

use nalgebra::Vector2;
use shared::{Arm, ElbowBranch, kinematics::JointTrig, model::ArmTerms};

use crate::{
    config::{Config, ConfigError},
    law::{LawError, TipKinematics},
    law_spec::LawSpec,
    reference::RefPoint,
};

mod seal {
    /// The seal of [`super::ControlLaw::control`]: public, so it may appear in
    /// a public trait's signature, but in a private module, so no crate outside
    /// `firmware` can name it (the standard library's `Error::type_id` is sealed
    /// the same way). Constructed only by the step.
    #[derive(Debug, Clone, Copy)]
    pub struct Sealed(pub(crate) ());
}

pub(crate) use seal::Sealed;

/// What a law declares to the protection around it, once per configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Declares {
    /// The tracking dynamics it promises for `e = z_t - z_t*` while sliding,
    /// `e'' + kd e' + kp e + ki int e = d` (`kp` 1/s², `kd` 1/s, `ki` 1/s³), which
    /// the tracking check ([`crate::tracking`]) holds it to; `None`: the law
    /// does not track `z_t` and the check is off.
    pub tracking: Option<TrackingDynamics>,
    /// Whether it holds the tip on the belt, pressing with a force of its own
    /// (`false`: it may lift off by design, as the paper's PID from `x0u`). For
    /// a law that promises no [`Declares::tracking`], the lift-off the firmware
    /// declares (its own detector and confirmation, [`crate::liftoff`]) is then
    /// a stop at once, [`crate::controller::SafeReason::LiftOff`]: without a tracking
    /// promise it is the first sign of a tip whipped off the belt by a reversed
    /// or dead motor, which the wiring check (its observer's 40 Hz bandwidth)
    /// sees 10 to 20 ms later, past 30 mm where the law holds 1 to 2 N m against
    /// the arm (issue 70; the FMEA over the envelope under the template's
    /// impedance law, `examples/law-template/tests/protection.rs`). A law
    /// beyond its `Z_t,sliding` (the paradox's bounce) is stopped by it too, as
    /// the hybrid law is on a board. With [`Declares::tracking`] the tracking
    /// check holds the promise instead (lift-off for 2 ms, the error's bound:
    /// [`crate::tracking`]).
    pub on_belt: bool,
    /// Whether it reads the reference's acceleration (`RefPoint::acc`); the
    /// step leaves it 0 otherwise (and saves its arithmetic).
    pub uses_reference_acceleration: bool,
}

/// The closed-loop tracking error's dynamics a law promises ([`Declares::tracking`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingDynamics {
    /// Stiffness, 1/s².
    pub kp: f32,
    /// Damping, 1/s.
    pub kd: f32,
    /// Integral gain, 1/s³ (0: none).
    pub ki: f32,
}

/// What the step hands a law, derived once per configuration: the arm's model
/// (the firmware's own `f32` parameters, `mu = mu_hat`), its folded factors and
/// the friction estimate's gain per period.
#[derive(Debug, Clone, Copy)]
pub struct LawContext<'a> {
    /// The whole configuration (gains, references, limits).
    pub cfg: &'a Config,
    /// The arm's model.
    pub arm: &'a Arm<f32>,
    /// Its constant factors, folded once.
    pub terms: &'a ArmTerms<f32>,
    /// The elbow's branch the run started on (the inverse kinematics' side).
    pub branch: ElbowBranch,
    /// The friction estimate's filter gain per period (`mu_estimate::gain(dt)`).
    pub mu_gain: f32,
}

impl LawContext<'_> {
    /// The law's own parameters (`cfg.law.values`), in the order and units of
    /// its [`ControlLaw::SPEC`], each within its declared range.
    #[inline(always)]
    pub fn params(&self) -> &[f32; crate::law_spec::LAW_PARAMS] {
        &self.cfg.law.values
    }
}

/// What a law reads each period: the estimate, the reference, the measured
/// forces, the period. SI units, radians. Held by value (the step builds it in
/// registers: a reference to the kinematics made the step keep them in memory,
/// 48 instructions more per step).
#[derive(Debug, Clone, Copy)]
pub struct LawInput {
    /// Estimated `[theta1, theta2]`, rad.
    pub q: Vector2<f32>,
    /// Estimated `[theta1_dot, theta2_dot]`, rad/s.
    pub qd: Vector2<f32>,
    /// Sines and cosines of `q`.
    pub trig: JointTrig<f32>,
    /// The tip's estimated position, velocity and Jacobian at `q`, `qd` (paper eq. 1).
    pub kin: TipKinematics,
    /// The tangential reference `z_t*`, its velocity and (if declared) acceleration.
    pub reference: RefPoint,
    /// The normal-force reference `f_n*` after its ramp, N.
    pub f_n_ref: f32,
    /// Measured tangential force `f_t`, N.
    pub f_t: f32,
    /// Measured normal force `f_n`, N.
    pub f_n: f32,
    /// Measured belt speed `v_belt`, m/s.
    pub v_belt: f32,
    /// The control period, s.
    pub dt: f32,
    /// Whether a motor saturated in the previous period (for anti-windup).
    pub saturated: bool,
}

/// What a law returns each period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawOutput {
    /// Motor torques `[u1, u2]`, N m, before saturation (the step saturates at
    /// `torque_limit` and encodes).
    pub u: [f32; 2],
    /// The bound `D` on the tangential acceleration the law cannot see in a
    /// slide, m/s² ([`crate::tracking`]), for the tracking check; 0 for a law
    /// that claims none.
    pub disturbance: f32,
}

/// A control law the firmware runs: no heap, no panic on data.
pub trait ControlLaw: Clone + core::fmt::Debug {
    /// What the law declares about its own configuration: its name, source and
    /// parameters (names, units, ranges, defaults; [`LawSpec`]), which a
    /// configuration's `law` must match ([`crate::controller::Firmware::with_law`]) and the
    /// plant maps a scenario's `[law]` table onto. The paper's laws:
    /// [`LawSpec::PAPER`].
    const SPEC: LawSpec;

    /// The law's fresh state for configuration `cfg` (integrators at zero):
    /// at the firmware's start and at every reset.
    fn fresh(cfg: &Config) -> Self;

    /// What the law declares for `cfg` ([`Declares`]).
    fn declares(cfg: &Config) -> Declares;

    /// Refuses a configuration the law cannot run, with the setting and the
    /// reason ([`ConfigError`]); called after the firmware's own checks.
    ///
    /// # Errors
    /// The first setting out of the law's range.
    fn validate(cfg: &Config) -> Result<(), ConfigError> {
        let _ = cfg;
        Ok(())
    }

    /// The step's body for a trusted frame with this law: by default the
    /// generic one, compiled where the image is built. The paper's laws
    /// override it with a function compiled in `firmware`, so their step is
    /// the code it was before the trait (a generic body compiled in the image's
    /// crate cost the step 8 to 11 % more instructions at `opt-level = "s"`;
    /// `crate::controller`'s notes). A law of one's own keeps the default: its
    /// step's cost is what `scripts/cycles.py` measures for its image.
    ///
    /// Sealed: its last parameter, [`Sealed`], is a type no crate outside
    /// `firmware` can name, so no other crate can override or call it (the
    /// module's notes; issue 80).
    #[doc(hidden)]
    #[inline(always)]
    fn control(
        fw: &mut crate::controller::Firmware<Self>,
        seq: u32,
        m: &crate::decode::Measurement,
        _: Sealed,
    ) -> Result<([f32; 2], u32), crate::controller::SafeReason> {
        fw.control(seq, m)
    }

    /// One period: the motor torques for `input`.
    ///
    /// # Errors
    /// [`LawError`]: the firmware latches its safe state at once.
    fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError>;
}

/// Defines `PAINLEVE_LAW_SPEC`, the symbol an MCU image carries its law's
/// declaration in ([`LawSpec::encoded`]), for the host to read from the ELF
/// (`rig::law::LawDescription::from_elf`) and bind a scenario's `[law]` table
/// with before it configures the image. The image must reference it (the
/// linker drops unreferenced data): the images' entry points pass it to
/// `core::hint::black_box`.
#[macro_export]
macro_rules! law_spec_symbol {
    ($law:ty) => {
        /// The law's declaration in postcard's encoding (`firmware::law_spec`).
        #[unsafe(no_mangle)]
        #[used]
        pub static PAINLEVE_LAW_SPEC: [u8; <$law as $crate::ControlLaw>::SPEC.encoded_len()] = <$law as $crate::ControlLaw>::SPEC.encoded();
    };
}
