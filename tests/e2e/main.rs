//! The end-to-end tests, one test binary: each module runs the real `sil-host`
//! executable (`CARGO_BIN_EXE_sil-host`) or the libraries across crates, as a
//! user would. `common` builds the MCU images for QEMU once per run and decodes
//! their defmt logs; `figure_check` checks every figure a command writes. The soak
//! test is a binary of its own (`tests/soak.rs`): it compares the machine's
//! iceoryx2 files before and after, so nothing else may run beside it. So is the
//! memory test (`tests/memory.rs`): a child's peak RSS counts the process it was
//! forked from, which must be small.

mod accuracy;
mod aliases;
mod animation;
mod arm_image;
mod arrow_tables;
mod bench;
mod binary;
mod board;
mod bounds;
mod closed_loop;
mod closed_loop_friction;
mod common;
mod ensemble;
mod figure_check;
mod figures;
mod foxglove_view;
mod friction_loop;
mod friction_unknown;
mod golden;
mod input_bounds;
mod law_template;
mod model_f32_f64;
mod monitors;
mod params;
mod pil;
mod pil_vs_library;
mod poincare;
mod published_ledger;
mod python_monitor;
mod replay;
mod report;
mod results_page;
mod run;
mod sil_rig;
mod simulate;
mod slurm;
mod sweep;
mod time_base;
mod trace_page;
mod validity;
mod zmax;
