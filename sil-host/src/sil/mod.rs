//! The software-in-the-loop rig: scenarios, sensor models, and the loop that runs
//! the firmware's step against the plant, sampled and quantised as on hardware.

pub mod in_process;
pub mod scenario;
pub mod sensors;
