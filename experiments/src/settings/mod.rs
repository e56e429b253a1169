//! Each experiment's settings, as both fronts take them: with the `clap`
//! feature they are `clap::Args` (the `sil-host` command's flags) and serde
//! documents (the `painleve` functions' keyword arguments, laid over the
//! defaults clap gives: `painleve`'s `settings`), with the same typed values
//! ([`NumberList`], choices by the names clap shows), so the defaults, values
//! and messages are one; one file per group of experiments (`common`: what
//! several share; `values`: the typed values).

mod closed_loop;
mod common;
mod ensemble;
mod open_loop;
mod sensitivity;
mod sweep;
mod values;
mod zmax;

pub use self::closed_loop::{FirmwareArgs, PilArgs, QemuLinkArg, RunArgs, RunLink};
pub use self::common::{LiveArgs, OutputArgs, ScenarioArgs, StrictArgs};
pub use self::ensemble::EnsembleArgs;
pub use self::open_loop::{AdmissibleArgs, ModesArgs, PoincareArgs, SimulateArgs};
pub use self::sensitivity::SensitivityArgs;
pub use self::sweep::{MergeArgs, SweepArgs};
pub use self::values::NumberList;
pub use self::zmax::ZmaxArgs;
