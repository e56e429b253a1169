//! The scenario files the documents start from, the scenario's key set
//! (docs/rig.md "The scenario file") and each key's documented range.

/// The repository's scenario files.
pub const FILES: [&str; 5] = [
    include_str!("../../../scenarios/default.toml"),
    include_str!("../../../scenarios/hybrid-x0d.toml"),
    include_str!("../../../scenarios/hybrid-x0u.toml"),
    include_str!("../../../scenarios/pid-x0d.toml"),
    include_str!("../../../scenarios/pid-x0u.toml"),
];

/// Three valid faults appended to the default scenario (the sixth base document).
pub(super) const FAULTS: &str = r#"
[[faults]]
kind = "late_command"
at_s = 3.0
duration_s = 0.005
delay_s = 0.0015

[[faults]]
kind = "stuck_sensor"
at_s = 1.0
signal = "f_n"

[[faults]]
kind = "stall"
at_s = 2.0
duration_s = 0.5
"#;

/// Every key of a scenario file, dotted (docs/rig.md "The scenario file"), and the
/// old `controller.hybrid_ki`.
pub const KEYS: &[&str] = &[
    "name",
    "plant.mu",
    "plant.v_belt",
    "plant.x0",
    "plant.impact_law",
    "plant.e_n",
    "plant.iwc",
    "plant.rtol",
    "plant.atol",
    "plant.m",
    "plant.l",
    "plant.sigma",
    "plant.k",
    "plant.h",
    "plant.alpha0",
    "plant.g",
    "controller.kind",
    "controller.target_z_t",
    "controller.move_time_s",
    "controller.f_n_ref",
    "controller.friction",
    "controller.mu_hat",
    "controller.hybrid_ki",
    "controller.pid.kp",
    "controller.pid.ki",
    "controller.pid.kd",
    "controller.hybrid.kp",
    "controller.hybrid.kd",
    "controller.hybrid.ki",
    "controller.model.m",
    "controller.model.l",
    "controller.model.sigma",
    "controller.model.k",
    "controller.model.h",
    "controller.model.alpha0",
    "controller.model.g",
    "timing.rate_hz",
    "timing.delta_s",
    "timing.duration_s",
    "sensors.seed",
    "sensors.load_noise_n",
    "sensors.encoder_bits",
    "rig.command_timeout_s",
    "rig.spin_us",
    "rig.peer_check_s",
    "rig.max_consecutive_timeouts",
    "rig.realtime_cpu",
    "rig.realtime_fifo_priority",
    "rig.connect_timeout_s",
    "plant",
    "controller",
    "controller.pid",
    "controller.hybrid",
    "controller.model",
    "timing",
    "sensors",
    "rig",
    "faults",
];

/// The tables of a scenario (where unknown keys go).
pub const TABLES: &[&str] =
    &["", "plant", "controller", "controller.pid", "controller.hybrid", "controller.model", "timing", "sensors", "rig"];

/// The keys of a `[[faults]]` entry.
pub const FAULT_KEYS: &[&str] = &["kind", "at_s", "duration_s", "delay_s", "signal"];

/// The documented range of a key (docs/rig.md), to draw values that are accepted.
#[derive(Debug, Clone, Copy)]
pub(super) enum Domain {
    /// A float in `[lo, hi]`.
    F(f64, f64),
    /// An integer in `[lo, hi]`.
    I(i64, i64),
    /// One of these words.
    E(&'static [&'static str]),
    /// Two floats in `[lo, hi]`.
    Pair(f64, f64),
}

use Domain::{E, F, I, Pair};

/// The keys with their documented ranges (`faults.K`: key `K` of a `[[faults]]` entry).
pub(super) const DOMAINS: &[(&str, Domain)] = &[
    ("name", E(&["x", "hybrid-x0d", "é\u{1F600}", "sixty-four characters, exactly: ................................."])),
    ("plant.mu", F(0.0, 10.0)),
    ("plant.v_belt", F(-5.0, 5.0)),
    ("plant.x0", E(&["a", "d", "u"])),
    ("plant.impact_law", E(&["newton", "poisson", "energetic"])),
    ("plant.e_n", F(0.0, 1.0)),
    ("plant.iwc", E(&["restitution", "plastic"])),
    ("plant.rtol", F(1e-14, 0.1)),
    ("plant.atol", F(1e-14, 0.1)),
    ("plant.m", F(1e-3, 100.0)),
    ("plant.l", F(0.19, 2.0)),
    ("plant.sigma", F(0.0, 10.0)),
    ("plant.k", F(0.0, 100.0)),
    ("plant.h", F(1e-3, 0.42)),
    ("plant.alpha0", F(-7.0, 7.0)),
    ("plant.g", F(1e-3, 100.0)),
    ("controller.kind", E(&["pid", "hybrid"])),
    ("controller.target_z_t", F(-0.42, 0.42)),
    ("controller.move_time_s", F(1e-300, 1e5)),
    ("controller.f_n_ref", F(0.0, 25.0)),
    ("controller.friction", E(&["commanded", "measured_normal", "measured", "none"])),
    ("controller.mu_hat", F(0.0, 10.0)),
    ("controller.hybrid_ki", F(0.0, 1e4)),
    ("controller.pid.kp", Pair(0.0, 1e4)),
    ("controller.pid.ki", Pair(0.0, 1e4)),
    ("controller.pid.kd", Pair(0.0, 1e3)),
    ("controller.hybrid.kp", F(0.0, 1e38)),
    ("controller.hybrid.kd", F(0.0, 1e4)),
    ("controller.hybrid.ki", F(0.0, 1e4)),
    ("controller.model.m", F(1e-50, 100.0)),
    ("controller.model.l", F(0.19, 2.0)),
    ("controller.model.sigma", F(0.0, 10.0)),
    ("controller.model.k", F(0.0, 100.0)),
    ("controller.model.h", F(1e-3, 0.42)),
    ("controller.model.alpha0", F(-7.0, 7.0)),
    ("controller.model.g", F(1e-3, 100.0)),
    ("timing.rate_hz", F(250.0, 10_000.0)),
    ("timing.delta_s", F(0.0, 1e-4)),
    ("timing.duration_s", F(1e-3, 1e5)),
    ("sensors.seed", I(0, i64::MAX)),
    ("sensors.load_noise_n", F(0.0, 25.0)),
    ("sensors.encoder_bits", I(10, 16)),
    ("rig.command_timeout_s", F(1e-3, 60.0)),
    ("rig.spin_us", F(0.0, 1e6)),
    ("rig.peer_check_s", F(1e-3, 60.0)),
    ("rig.max_consecutive_timeouts", I(1, 4_294_967_295)),
    ("rig.realtime_cpu", E(&["last", "none", "0", "3", "1023", " last"])),
    ("rig.realtime_fifo_priority", I(0, 99)),
    ("rig.connect_timeout_s", F(1e-3, 600.0)),
    ("faults.kind", E(&["late_command", "drop_command", "stall", "kill_firmware", "stuck_sensor", "nan_sensor", "out_of_range"])),
    ("faults.at_s", F(0.0, 12.0)),
    ("faults.duration_s", F(0.0, 60.0)),
    ("faults.delay_s", F(1e-6, 9.99)),
    ("faults.signal", E(&["theta1", "elbow", "f_t", "f_n", "belt"])),
];
