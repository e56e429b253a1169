//! Each experiment's settings, as both fronts take them: with the `clap`
//! feature they are `clap::Args` (the `sil-host` command's flags, and the
//! `painleve` functions' keyword arguments, parsed by the same definitions, so
//! the defaults, ranges and messages are one); one file per group of
//! experiments (`common`: what several share).

mod closed_loop;
mod common;
mod open_loop;
mod sensitivity;
mod sweep;
mod zmax;

pub use self::closed_loop::{FirmwareArgs, PilArgs, QemuLinkArg, RunArgs, RunLink};
pub use self::common::{LiveArgs, OutputArgs, ScenarioArgs, StrictArgs};
pub use self::open_loop::{AdmissibleArgs, ModesArgs, PoincareArgs, SimulateArgs};
pub use self::sensitivity::SensitivityArgs;
pub use self::sweep::{MergeArgs, SweepArgs};
pub use self::zmax::ZmaxArgs;
