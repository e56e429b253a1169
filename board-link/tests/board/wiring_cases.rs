//! The wiring faults of issue 52 and the random admissible scenarios they are
//! tried on, shared by the twin's tests (`twin.rs`: 200 scenarios per fault and
//! law) and the flashed image's (`emulator.rs`: a sample).

use board_twin::BoardDescription;
use rig::scenario::{DEFAULT_TOML, Scenario};

/// A reproducible uniform source in [0, 1) (xorshift64).
pub struct Uniform(u64);

impl Uniform {
    /// The source seeded with `seed` (any value but 0), its first draws skipped.
    pub fn new(seed: u64) -> Self {
        let mut r = Self(seed.max(1));
        for _ in 0..5 {
            r.next();
        }
        r
    }

    /// The next draw.
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Random admissible scenario `i` under `kind` (`pid` or `hybrid`), `duration`
/// seconds: the paper's arm and gains from `x0d` or `x0u`, `mu` 0.3 to 0.8 (and
/// `mu_hat = mu`), `v_belt` -1 to -0.1 m/s, `f_n*` 3 to 10 N, `z_t*` -0.05 to
/// 0.14 m (below the hybrid law's `Z_t,sliding`, 0.148 m from `x0d`), any seed.
pub fn random_admissible(i: u64, kind: &str, duration: f64) -> Scenario {
    let mut r = Uniform(0x9E37_79B9_7F4A_7C15 ^ (i * 7919 + 1));
    for _ in 0..5 {
        r.next();
    }
    let x0 = if r.next() < 0.5 { "d" } else { "u" };
    let sets = [
        format!("controller.kind={kind}"),
        format!("plant.x0={x0}"),
        format!("plant.mu={}", 0.3 + 0.5 * r.next()),
        format!("plant.v_belt={}", -1.0 + 0.9 * r.next()),
        format!("controller.f_n_ref={}", 3.0 + 7.0 * r.next()),
        format!("controller.target_z_t={}", -0.05 + 0.19 * r.next()),
        format!("sensors.seed={}", 100 + i),
        format!("timing.duration_s={duration}"),
    ];
    let overrides: Vec<_> = sets.iter().map(|a| a.parse().unwrap()).collect();
    let mut s = Scenario::from_toml_with(DEFAULT_TOML, &overrides).unwrap();
    s.controller.mu_hat = s.plant.mu;
    s
}

/// A wiring fault: its name, and how it changes the board's truth.
pub type WiringFault = (&'static str, fn(&mut BoardDescription));

/// The wiring faults of issue 52, as changes of the board's truth.
pub const WIRING_FAULTS: [WiringFault; 8] = [
    ("motor 1 reversed", |b| b.motor1.reversed = true),
    ("motor 2 reversed", |b| b.motor2.reversed = true),
    ("theta1 encoder reversed", |b| b.theta1_encoder.reversed = true),
    ("elbow encoder reversed", |b| b.elbow_encoder.reversed = true),
    ("encoders swapped", |b| b.encoders_swapped = true),
    ("load cell's normal axis reversed", |b| b.load_cell.counts_per_newton[1] *= -1.0),
    ("load cell's tangential axis reversed", |b| b.load_cell.counts_per_newton[0] *= -1.0),
    ("load cell reversed", |b| {
        b.load_cell.counts_per_newton[0] *= -1.0;
        b.load_cell.counts_per_newton[1] *= -1.0;
    }),
];

/// Whether the paper's `kind` law leaves `fault` without any input to act on:
/// the PID (paper eq. 8) uses no force, and its joint-2 gains are 0 (`u2 = 0`).
pub fn unused_by(kind: &str, fault: &str) -> bool {
    kind == "pid" && (fault.starts_with("load cell") || fault == "motor 2 reversed")
}
