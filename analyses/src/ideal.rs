//! The paper's controllers in its own setting: continuous time, exact
//! measurements, no saturation (docs/model.md experiments 5 and 6), as torque laws the
//! plant evaluates inside its integration ([`Controller`](plant::Controller)), and a closed-loop run
//! of them ([`simulate`]).
//!
//! - [`IdealPid`]: paper eq. 8 on `q' = [theta1, theta2 - theta1]`, the reference
//!   `q'*` from inverse kinematics of `z* = [z_t*, -H]` on the initial elbow branch;
//!   its integrators are the plant's controller states `xi` (rad s).
//! - [`IdealHybrid`]: paper eqs. 9 to 11,
//!   `u = w + c + M J^-1 (-J_dot q_dot + i_x a_v) + J^T (-i_x f_t - i_y a_f)`, with
//!   the exact contact force of the plant's current phase; its force integral
//!   `int (f_n* - f_n) dt` (N s) is `xi_0`.
//!
//! The firmware runs the same laws sampled, in `f32` (`firmware::law`); the model
//! terms (`M`, `w`, `c`, `J`, `J_dot q_dot`, the contact forces) come from
//! `shared`, and the gains from the firmware's defaults (`firmware::Config`), so
//! the two settings differ only by sampling, quantisation and estimation (the
//! tests check that both laws give the same torque at the same state).
//!
//! Exact contact force in the hybrid law. In sliding the law's torque depends on
//! `f_t`, which depends on the torque (through `b`); the fixed point is
//! `f_n = a_f`, `f_t = -mu s a_f` (`s = sign z_r_dot`): with it
//! `b = -p a_f`, so the tip stays on the belt exactly while `p > 0` and `a_f > 0`
//! (the decoupling the paper designs for). In flight the exact force is zero. In
//! sticking the fixed point is degenerate (the law cancels whatever tangential
//! force there is), so the law there compensates the friction of slip in the
//! direction of `z_r_dot` (positive at rest), and its force integral uses the
//! plant's sticking force. The phase comes from the plant ([`Controller::torque_in`](plant::Controller::torque_in)).
//!
//! Consequence (a property of the ideal law, seen in the tests): the ideal hybrid
//! controller lifts off exactly where the tip reaches a configuration with `p = 0`
//! (the end of the admissible range of paper Table II). Beyond it, in contact
//! `b = -p a_f > 0` (the tip leaves) and in flight the law pushes it back with
//! `a_f`, with no time passing in between: the plant then stops with an
//! [`SimError::EventStorm`](plant::SimError::EventStorm) (lift-off and Zeno stop at one instant), or holds the
//! tip in its documented corner case. Runs that only need the first lift-off stop
//! there ([`IdealSetup::stop_at_lift_off`]); [`IdealRun::first_lift_off_s`] is set
//! either way.

mod laws;
mod reference;
mod run;

pub use self::laws::{HybridOutput, IdealHybrid, IdealLaw, IdealPid, LawFault};
pub use self::reference::{RefPoint, Reference};
pub use self::run::{IdealRun, IdealSample, IdealSetup, build, simulate};

#[cfg(test)]
mod tests;
