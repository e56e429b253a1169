//! Target `firmware-step`: [`firmware::Firmware::step`] under arbitrary frames and times.
//!
//! A case is a valid configuration (the default, or one of `scenarios/*.toml` through
//! `rig::setup::firmware_config`, with some settings redrawn within their ranges) and
//! a script of up to [`MAX_OPS`] operations: steps, resets and a lost peer. A step's
//! frame has plausible counts (an arm near the belt, so the laws run), random counts
//! within range, arbitrary bits or edge values (0, the range ends, `MIN`/`MAX`) in
//! every field, any flags; its sequence number goes on, repeats, goes back, jumps or
//! wraps near `u32::MAX`; its stamp `t_us` goes on, back, jumps or sits near
//! `u64::MAX`; the step starts on time, late, before the frame or at any `now_us`,
//! and the step's own clock reads any ticks at any rate (0 Hz included).
//!
//! The wire's `SensorFrame` holds integers only (counts and codes): "NaN" reaches
//! the firmware as a sensor's invalid flag, which the cases set.
//!
//! The property ([`check`]) runs the firmware beside a small model of its frame
//! checks, deadline monitor and safe state (`firmware/src/controller/step.rs`) and asserts
//! for every command: no panic; it echoes the frame's `seq`; torque codes within the
//! 12-bit range `[-2048, 2047]` and, decoded, finite and within the configured
//! `torque_limit` (plus half a code); only defined status bits; `BAD_FRAME`,
//! `STALE_FRAME` and `SEQUENCE_GAP` exactly when the frame is out of range, flagged
//! invalid, stale or after a gap; a bad frame holds the previous command;
//! `DEADLINE_MISS` exactly when `now_us - t_us` plus the step's time reaches the
//! period, the overrun counter counting exactly these and never decreasing;
//! `t_sent_us`, `step_ticks` and `reserved` as documented; `bad_frame_limit`
//! consecutive bad frames or `deadline_miss_limit` consecutive misses latch the safe
//! state, a law or sensor fault only on a trusted frame; once latched, every command
//! is zero torque with `SAFE_STATE` and the first reason, until a reset.
//!
//! The files: `knobs` (the configuration of a case), `case` (the script),
//! `generators` (the proptest strategies), `frames` (a step's frame from the
//! script), `model` (the model of the firmware and the check of one command) and
//! `runner` (a case run on the firmware beside the model).

mod case;
mod frames;
mod generators;
mod knobs;
mod model;
mod runner;

pub use case::{Case, Clock, Counts, EDGE_I16, EDGE_U16, MAX_OPS, Op, SeqMove, Start, TimeMove};
pub use frames::out_of_range;
pub use generators::strategy;
pub use knobs::Knobs;
pub use model::{DEFINED_STATUS_BITS, ModelState, Observed, check_step};
pub use runner::{Coverage, check, check_covering};
