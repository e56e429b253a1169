//! The map of contact modes over `(theta1, theta1_dot)` with the tip on the belt
//! (docs/model.md experiment 1, paper Fig. 2), computed by [`analyses::modes`]:
//! the settings' check and the computation, `modes.csv`'s rows and the JSON summary.

use crate::{arm::parse_range, error::Error, settings::ModesArgs};
use analyses::modes::*;

pub mod summary;

/// Checks the options and computes the mode map (what `sil-host modes` writes),
/// without writing anything.
///
/// # Errors
/// [`crate::error::Error::Analysis`] / [`crate::error::Error::Analysis`] (exit 2) for bad ranges, `mu`
/// or `v_belt`, [`Error::Analysis`] (exit 2) for a bad grid size.
pub fn compute(args: &ModesArgs) -> Result<ModeMap, Error> {
    let t1 = parse_range("theta1-deg", &args.theta1_deg)?;
    let t1d = parse_range("theta1-dot", &args.theta1_dot)?;
    let params = crate::arm::arm_params(&args.set, "modes", &[], args.mu, args.v_belt)?;
    Ok(compute_for(params, args.branch, args.theta2_sign, t1, t1d, args.grid)?)
}

/// The branch the map follows, in words (the figures' and the summary's label).
pub fn branch_label(map: &ModeMap) -> String {
    let root = if map.sign.sign(map.branch) > 0.0 { "+" } else { "-" };
    match map.sign {
        Theta2Sign::Auto => format!("elbow {}, theta2 = {root}acos(H/l - cos theta1)", map.branch.name()),
        _ => format!("theta2 = {root}acos(H/l - cos theta1), both elbow branches"),
    }
}
