//! The arm as Foxglove shows it (issue 55: "see it move"): from the rows of a
//! trace, the arm's frames (`foxglove.FrameTransforms` on `/tf`: `world`,
//! `base`, `link1`, `link2`, `tip`), a 3D scene (`foxglove.SceneUpdate` on
//! `/scene`: the links, the tip, the belt moving at `v_belt`, the contact force
//! as an arrow, the tip's recent path, a label) and a log (`foxglove.Log` on
//! `/log`: lift-offs, touchdowns, mode changes, deadline misses, the safe
//! state; `simulate`'s events), in Foxglove's own schemas through the Foxglove
//! SDK's types (the `foxglove` crate: protobuf, its published
//! `FileDescriptorSet`s).
//!
//! - [`ArmView`], [`EventLog`]: views of the CLI's tables
//!   ([`tables::mcap::McapView`]) that `trace.mcap` carries beside the tables'
//!   own JSON channels.
//! - [`LiveServer`], [`LiveTable`]: the same channels and bytes served live over the Foxglove
//!   WebSocket protocol (`sil-host run --live`), paced to real time or a rate.
//! - [`LAYOUT`]: the Foxglove layout that shows them (`docs/foxglove/layout.json`:
//!   a 3D panel, plots of `z_t`, `f_n` and the torques, the log).

pub mod geometry;
#[cfg(feature = "live")]
pub mod live;
pub mod log;
pub mod scene;
pub mod validate;
pub mod view;

pub use geometry::ArmGeometry;
#[cfg(feature = "live")]
pub use live::{CLOSING_STATUS, Closed, LiveError, LiveServer, LiveTable};
pub use view::{ArmView, EventLog, LOG_TOPIC, SCENE_TOPIC, TF_TOPIC, VIEW_PERIOD_S};

/// The Foxglove layout shipped with the project (`docs/foxglove/layout.json`):
/// a 3D panel following `/tf` and `/scene`, plots of `z_t` and `z_t_ref`,
/// `f_n` and `f_t`, the torques, and the log panel on `/log`. Import it in
/// Foxglove (Layouts > Import from file) and open a `trace.mcap`.
pub const LAYOUT: &str = include_str!("../../docs/foxglove/layout.json");

#[cfg(test)]
mod tests;
