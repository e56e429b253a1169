//! The paper's analyses, on the plant ([`plant`]) and the rig ([`rig`]): each
//! takes typed settings and returns a typed result; the command line
//! (`sil-host`) prints, plots and writes them.
//!
//! - [`corner_search`]: the search for runs that do not complete on perturbed arms (issue 40);
//! - [`admissible`]: the admissible configurations of the tip on the belt
//!   (docs/model.md, experiment 2; paper Table II);
//! - [`modes`]: the map of contact modes (experiment 1; paper Fig. 2);
//! - [`ideal`]: the paper's continuous-time controllers with exact measurements;
//! - [`lift_offs`]: what every output's `lift_offs` counts (every departure from the belt);
//! - [`zmax`]: Z_t,sliding, the largest target reached without lift-off
//!   (experiments 5 and 6);
//! - [`sweep`]: the brute-force two-parameter bifurcation diagram (experiments 3 and 7);
//! - [`poincare`]: the one-parameter bifurcation diagram on a Poincaré section
//!   (experiment 4).
#![warn(missing_docs)]

pub mod admissible;
pub mod corner_search;
pub mod error;
pub mod ideal;
pub mod lift_offs;
pub mod modes;
pub mod paper;
pub mod poincare;
pub mod sensitivity;
pub mod sweep;
pub mod zmax;

pub use error::AnalysisError;
