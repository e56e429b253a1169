//! Firmware configuration: controller choice, gains, references, limits.

/// Which control law runs (MODEL.md experiments 5 and 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ControllerKind {
    /// Joint-space PID (paper eq. 8).
    Pid,
    /// Hybrid force/motion control (paper eqs. 9 to 11).
    Hybrid,
}

/// Firmware configuration (defaults: HARDWARE.md and MODEL.md experiment 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Control law.
    pub controller: ControllerKind,
    /// Control period `Ts`, s (HARDWARE.md: 1 ms; 0.1 ms to 4 ms allowed).
    pub period_s: f32,
    /// Tangential target `z_t*`, m.
    pub target_z_t: f32,
    /// Duration of the quintic move to the target, s.
    pub move_time_s: f32,
    /// Normal force reference `f_n*`, N.
    pub f_n_ref: f32,
}

impl Default for Config {
    fn default() -> Self {
        Self { controller: ControllerKind::Hybrid, period_s: 1e-3, target_z_t: 0.10, move_time_s: 2.0, f_n_ref: 10.0 }
    }
}
