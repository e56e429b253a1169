//! Sensor models between the plant and the wire (HARDWARE.md "Sensors"):
//! 14-bit encoders (the elbow's sees `theta2 - theta1`), a 12-bit two-axis load
//! cell over +-25 N with white noise, the belt encoder at 1 mm/s. Noise is seeded
//! (ChaCha8), so a run is reproducible bit for bit.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use shared::wire::{self, SensorFrame};

/// The sensor models of one run.
#[derive(Debug, Clone)]
pub struct Sensors {
    rng: ChaCha8Rng,
    load_noise: Option<Normal<f64>>,
}

impl Sensors {
    /// Sensors with load-cell noise `load_noise_n` (N rms, >= 0) from `seed`.
    pub fn new(seed: u64, load_noise_n: f64) -> Self {
        let load_noise = if load_noise_n > 0.0 { Normal::new(0.0, load_noise_n).ok() } else { None };
        Self { rng: ChaCha8Rng::seed_from_u64(seed), load_noise }
    }

    /// The frame of period `seq` at `t_us`: state `x = [theta1, theta1_dot, theta2,
    /// theta2_dot]` (rad, rad/s), tip force `f = [f_t, f_n]` (N), belt speed (m/s).
    pub fn frame(&mut self, seq: u32, t_us: u64, x: &[f64; 4], f: [f64; 2], v_belt: f64) -> SensorFrame {
        let mut noise = || self.load_noise.map_or(0.0, |n| n.sample(&mut self.rng));
        let (n_t, n_n) = (noise(), noise());
        SensorFrame {
            t_us,
            seq,
            theta1_count: wire::encode_angle(x[0]),
            elbow_count: wire::encode_angle(x[2] - x[0]),
            f_t_code: wire::encode_force(f[0] + n_t),
            f_n_code: wire::encode_force(f[1] + n_n),
            belt_count: (v_belt * 1000.0).round().clamp(i16::MIN as f64, i16::MAX as f64) as i16,
            flags: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_frames_and_noise_has_the_set_rms() {
        let mut a = Sensors::new(7, 0.02);
        let mut b = Sensors::new(7, 0.02);
        let x = [0.1, 0.0, -0.3, 0.0];
        let mut sum2 = 0.0;
        let n = 20_000;
        for k in 0..n {
            let fa = a.frame(k, k as u64 * 1000, &x, [0.0, 10.0], -0.4);
            assert_eq!(fa, b.frame(k, k as u64 * 1000, &x, [0.0, 10.0], -0.4));
            let f_n = fa.f_n_code as f64 * 25.0 / 2048.0;
            sum2 += (f_n - 10.0).powi(2);
        }
        // Noise 20 mN rms plus quantisation (12.2 mN lsb, 3.5 mN rms) in quadrature.
        let rms = (sum2 / n as f64).sqrt();
        assert!((rms - (0.02f64.powi(2) + (25.0 / 2048.0f64).powi(2) / 12.0).sqrt()).abs() < 0.002, "rms {rms}");
    }
}
