//! The board's physics around its MCU, for any MCU model (the twin's
//! application on device models, or the `arm` ELF in an emulator): before a
//! tick, what the devices sense from the simulated arm (the magnets' angles
//! through each encoder's mounting, the forces through the load cell's front
//! end and its seeded noise, the belt's travel, the faults on the bus); after
//! it, the joint torques the motor stage makes from the outputs the MCU left
//! on its pins ([`crate::motor_stage::joint_torques`]).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::{
    adc::adc_count,
    bench::{Bench, EncoderFaults, Shared},
    motor_stage::joint_torques,
};
use board_description::{BoardDescription, ENCODER_COUNTS, EncoderMounting};

/// What the arm is doing at a tick, as the board's devices sense it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmState {
    /// `[theta1, theta1_dot, theta2, theta2_dot]`, rad and rad/s (paper eq. 1).
    pub x: [f64; 4],
    /// Tip force `[f_t, f_n]` on the load cell, N.
    pub f: [f64; 2],
    /// The belt's travel since its counter read 0, m.
    pub belt_travel_m: f64,
}

/// Faults on the bus this tick (docs/hardware.md "Faults"), and the sensors'
/// and the board's faults the devices make (docs/rig.md "Faults").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BusFaults {
    /// Each encoder's bus and magnet, `[theta1, elbow]`.
    pub encoders: [EncoderFaults; 2],
    /// The ADC's conversion is missing.
    pub missing_conversion: bool,
    /// A load-cell channel's reading stays where it was `[f_t, f_n]` (a seized
    /// amplifier output, a sample-and-hold that no longer samples).
    pub adc_stuck: [bool; 2],
    /// The belt's counter stops counting (a broken encoder wire).
    pub belt_stuck: bool,
    /// The drivers assert nFAULT.
    pub driver_fault: bool,
    /// The period's acquisition of the encoders fails this way (the `arm`
    /// image's DMA: docs/board.md "The encoders by DMA"); no frame reaches the
    /// encoders.
    pub acquisition: Option<arm_app::AcquisitionFault>,
    /// How far each encoder's chip reads off `[theta1, elbow]` (by chip select), counts
    /// (a spike: EMI, a bad sample).
    pub encoder_spike: [i32; 2],
    /// The load cell's offsets `[f_t, f_n]`, N, added to the force its front end
    /// senses (an amplifier's drift); `None`: none.
    pub load_offsets_n: Option<[f64; 2]>,
    /// The belt encoder's gain on the travel from this tick (its count carries
    /// on from where it was, `gain` counts per count of travel); `None`: the
    /// counter reads the belt's travel.
    pub belt_gain: Option<f64>,
    /// The board's truth this tick when a fault changed it (a motor or an
    /// encoder rewired, weakened or slipped mid-run); `None`: the description's.
    pub board: Option<BoardDescription>,
}

/// The board's devices as the arm drives them: the shared bench, the board's
/// description, the load cell's noise.
#[derive(Debug)]
pub struct BoardPhysics {
    bench: Shared,
    board: BoardDescription,
    rng: ChaCha8Rng,
    noise: Option<Normal<f64>>,
    /// The amplifiers' last counts (a stuck channel keeps its own).
    last_adc: [u16; 2],
    /// The board's truth at the last tick (the description, or a fault's).
    now: BoardDescription,
    /// The travel the belt counter reads under a gain fault (the one model,
    /// `drivers::belt::GainedTravel`).
    belt_gained: drivers::belt::GainedTravel,
}

impl BoardPhysics {
    /// The devices of `board` on a fresh bench, with load-cell noise of
    /// `load_noise_n` N rms (white, seeded by `seed`, drawn `[f_t, f_n]` per
    /// tick as the wire-level sensor model draws it). At power-up the ADC has
    /// converted nothing yet (both counts 0).
    ///
    /// # Errors
    /// The description's own check ([`BoardDescription::check`]), in words.
    pub fn new(board: BoardDescription, seed: u64, load_noise_n: f64) -> Result<Self, String> {
        board.check()?;
        let bench: Shared = std::sync::Arc::new(std::sync::Mutex::new(Bench::default()));
        crate::bench::lock(&bench).adc_counts = Some([0; 2]);
        let noise = (load_noise_n > 0.0).then(|| Normal::new(0.0, load_noise_n).ok()).flatten();
        Ok(Self {
            bench,
            board,
            rng: ChaCha8Rng::seed_from_u64(seed),
            noise,
            last_adc: [0; 2],
            now: board,
            belt_gained: drivers::belt::GainedTravel::default(),
        })
    }

    /// The bench the device models hold.
    pub fn bench(&self) -> &Shared {
        &self.bench
    }

    /// The board description.
    pub fn board(&self) -> &BoardDescription {
        &self.board
    }

    /// Sets what the devices sense from `arm` and `faults` (with load-cell noise
    /// when `noisy`): the magnets' chip counts, the ADC's conversions, the belt's
    /// count (held while stuck, scaled by a gain), the fault line; the board's
    /// truth is `faults.board` when a fault changed it, the description's otherwise.
    pub fn sense(&mut self, arm: &ArmState, faults: &BusFaults, noisy: bool) {
        let (n_t, n_n) = match (noisy, self.noise) {
            (true, Some(n)) => (n.sample(&mut self.rng), n.sample(&mut self.rng)),
            _ => (0.0, 0.0),
        };
        self.now = faults.board.unwrap_or(self.board);
        let mut b = crate::bench::lock(&self.bench);
        let d = &self.now;
        let counts = [magnet_counts(arm.x[0], &d.theta1_encoder), magnet_counts(arm.x[2] - arm.x[0], &d.elbow_encoder)];
        b.magnet_counts = if d.encoders_swapped { [counts[1], counts[0]] } else { counts };
        for (chip, spike) in b.magnet_counts.iter_mut().zip(faults.encoder_spike) {
            if spike != 0 {
                *chip += f64::from(spike);
            }
        }
        b.encoder_faults = faults.encoders;
        let lc = &d.load_cell;
        let f = faults.load_offsets_n.map_or(arm.f, |o| [arm.f[0] + o[0], arm.f[1] + o[1]]);
        let fresh = [
            adc_count(lc.zero_counts[0], lc.counts_per_newton[0], f[0] + n_t),
            adc_count(lc.zero_counts[1], lc.counts_per_newton[1], f[1] + n_n),
        ];
        let held = self.last_adc;
        let counts = [0, 1].map(|i| if faults.adc_stuck[i] { held[i] } else { fresh[i] });
        self.last_adc = counts;
        b.adc_counts = (!faults.missing_conversion).then_some(counts);
        if !faults.belt_stuck {
            let read = self.belt_gained.read(arm.belt_travel_m, faults.belt_gain);
            b.belt_count = drivers::belt::count_at(read, d.belt_counts_per_metre);
        }
        b.driver_fault = faults.driver_fault;
        b.acquisition = faults.acquisition;
    }

    /// The joint torques `[u1, u2]` (N m) the drivers make from the outputs on
    /// the bench now, through the motors of the last [`BoardPhysics::sense`]'s
    /// board, with full-scale duty `max_duty` counts (the twin's description; an
    /// emulated TIM3's ARR + 1).
    pub fn torques(&self, max_duty: u16) -> [f64; 2] {
        joint_torques(&self.bench, &BoardDescription { pwm_max_duty: max_duty, ..self.now })
    }

    /// Holds the enable button down (`true`) or lets it go.
    pub fn hold_button(&self, held: bool) {
        crate::bench::lock(&self.bench).button_held = held;
    }
}

/// The magnet's angle of a joint at `angle` (rad) through `mounting`, chip counts.
fn magnet_counts(angle: f64, mounting: &EncoderMounting) -> f64 {
    let counts = angle / std::f64::consts::TAU * ENCODER_COUNTS;
    let signed = if mounting.reversed { -counts } else { counts };
    signed + mounting.zero_count
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The belt's counter under a gain: from the onset it counts `gain` times the
    /// travel, carrying on from its count; after, the travel again, from where
    /// the gain left it. No gain: the travel's count, as ever.
    #[test]
    fn a_belt_gain_scales_the_counts_from_its_onset_and_the_counter_carries_on() {
        let mut p = BoardPhysics::new(BoardDescription::default(), 1, 0.0).unwrap();
        let mut counts = Vec::new();
        for k in 0..8u32 {
            let arm = ArmState { x: [0.0; 4], f: [0.0; 2], belt_travel_m: -4e-4 * f64::from(k) };
            let belt_gain = (2..5).contains(&k).then_some(-0.5);
            p.sense(&arm, &BusFaults { belt_gain, ..BusFaults::default() }, false);
            counts.push(i32::from(crate::bench::lock(p.bench()).belt_count as i16));
        }
        assert_eq!(counts, [0, -400, -200, 0, 200, -200, -600, -1000]);
    }

    /// A spike adds its counts to the chip's magnet; a drift its newtons to the
    /// force; a board fault's truth replaces the description's for the tick.
    #[test]
    fn spikes_offsets_and_a_board_fault_act_on_the_devices() {
        let mut p = BoardPhysics::new(BoardDescription::default(), 1, 0.0).unwrap();
        let arm = ArmState { x: [0.5, 0.0, 0.2, 0.0], f: [1.0, 5.0], belt_travel_m: 0.0 };
        p.sense(&arm, &BusFaults::default(), false);
        let (magnets, adc) = {
            let b = crate::bench::lock(p.bench());
            (b.magnet_counts, b.adc_counts.unwrap())
        };
        let faults = BusFaults { encoder_spike: [0, -7], load_offsets_n: Some([0.0, 25.0 / 2048.0 * 3.0]), ..BusFaults::default() };
        p.sense(&arm, &faults, false);
        let b = crate::bench::lock(p.bench());
        assert_eq!(b.magnet_counts, [magnets[0], magnets[1] - 7.0]);
        assert_eq!(b.adc_counts.unwrap(), [adc[0], adc[1] + 3]);
        drop(b);
        let mut reversed = BoardDescription::default();
        reversed.theta1_encoder.reversed = true;
        p.sense(&arm, &BusFaults { board: Some(reversed), ..BusFaults::default() }, false);
        assert_eq!(crate::bench::lock(p.bench()).magnet_counts[0], -magnets[0]);
        assert_eq!(p.board(), &BoardDescription::default(), "the description stays");
    }
}
