//! A control law of one's own on the arm: an impedance controller (N. Hogan,
//! "Impedance Control: An Approach to Manipulation", ASME J. Dyn. Sys., Meas.,
//! Control 107, 1985), as a [`firmware::ControlLaw`]. Copy this crate, change
//! [`Impedance`], and the rig runs your law where it runs the paper's: in
//! process, as its own firmware process over iceoryx2 (`sil-host run
//! --attach`), on the emulated board and in PIL (README.md).
//!
//! The law makes the tip behave as a spring and a damper about a point that
//! follows the reference along the belt and sits `f_n* / k_n` below its
//! surface, so that at rest on the belt the spring presses with `f_n*`. The
//! arm's own torques (gravity, the elbow's spring and damping, the centripetal
//! terms; paper eq. 1) are compensated with the firmware's model of the arm:
//!
//! ```text
//! F_t = k_t (z_t* - z_t) + d_t (z_t_dot* - z_t_dot)
//! F_n = k_n (-H - f_n*/k_n - z_n) - d_n z_n_dot
//! u'  = w(q, q_dot) + c(q, q_dot) + J^T [F_t, F_n]      (generalised torques, N m)
//! u   = [u'_1 + u'_2, u'_2]                              (motor torques, N m)
//! ```
//!
//! It promises no tracking dynamics (the closed loop's tangential error obeys
//! the arm's configuration-dependent inertia, not a fixed polynomial), so the
//! firmware's tracking check is off for it ([`firmware::Declares`]); every
//! other protection (frames, sensors, runaway, wiring, lift-off, deadlines,
//! non-finite torques, the safe state) acts on it as on the paper's laws.

#![no_std]

use firmware::{Config, ControlLaw, Declares, LawContext, LawInput, LawOutput, LawSpec, ParamSpec, law::LawError};

/// Index of `k_t` in the law's parameters.
pub const K_T: usize = 0;
/// Index of `d_t`.
pub const D_T: usize = 1;
/// Index of `k_n`.
pub const K_N: usize = 2;
/// Index of `d_n`.
pub const D_N: usize = 3;

/// The impedance controller: stateless (no integrator), four parameters.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Impedance;

impl ControlLaw for Impedance {
    const SPEC: LawSpec = LawSpec {
        name: "impedance",
        source: "N. Hogan, Impedance Control, ASME JDSMC 107, 1985",
        params: &[
            // Tangential stiffness and damping: about 45 rad/s and critical
            // damping for the tip's apparent mass of about 1 kg.
            ParamSpec { name: "k_t", unit: "N/m", min: 0.0, max: 20_000.0, default: 2_000.0 },
            ParamSpec { name: "d_t", unit: "N s/m", min: 0.0, max: 1_000.0, default: 90.0 },
            // Normal stiffness (the virtual point sits f_n*/k_n below the belt) and damping.
            ParamSpec { name: "k_n", unit: "N/m", min: 10.0, max: 20_000.0, default: 1_000.0 },
            ParamSpec { name: "d_n", unit: "N s/m", min: 0.0, max: 1_000.0, default: 60.0 },
        ],
    };

    fn fresh(_cfg: &Config) -> Self {
        Self
    }

    fn declares(_cfg: &Config) -> Declares {
        Declares { tracking: None, on_belt: true, uses_reference_acceleration: false }
    }

    fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError> {
        let p = ctx.params();
        let (k_t, d_t, k_n, d_n) = (p[K_T], p[D_T], p[K_N], p[D_N]);
        let (z, z_dot, j) = (input.kin.z, input.kin.z_dot, input.kin.jac);
        let r = &input.reference;
        // The virtual tip force, N.
        let f_t = k_t * (r.pos - z[0]) + d_t * (r.vel - z_dot[0]);
        let f_n = k_n * (-ctx.arm.params.h - input.f_n_ref / k_n - z[1]) - d_n * z_dot[1];
        // The arm's own torques, compensated (paper eq. 1: M q_ddot + w + c = u' + J^T f).
        let wc = ctx.arm.w_sin(input.trig.s1, input.trig.s2, &input.q, &input.qd) + ctx.arm.c_sin(input.trig.s12(), &input.qd);
        let u0 = wc[0] + j[(0, 0)] * f_t + j[(1, 0)] * f_n;
        let u1 = wc[1] + j[(0, 1)] * f_t + j[(1, 1)] * f_n;
        Ok(LawOutput { u: [u0 + u1, u1], disturbance: 0.0 })
    }
}
