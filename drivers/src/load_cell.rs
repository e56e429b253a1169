//! The two-axis tip load cell: two instrumentation amplifiers into ADC1, 12 bit,
//! conversions triggered by the control timer so the sample instant is the
//! period's start (docs/hardware.md "Reference board", "Sensors": +-25 N full
//! scale, 12-bit codes on the wire).
//!
//! embedded-hal 1.0 has no ADC trait, so the board implements [`LoadCellAdc`].

use core::fmt;

use shared::wire::{LOAD_CODE_MAX, LOAD_CODE_MIN, LOAD_FULL_SCALE_N};

/// One conversion's raw counts `[tangential, normal]` and their wire codes.
pub type CountsAndCodes = ([u16; 2], [i16; 2]);

/// Largest 12-bit right-aligned ADC count.
pub const ADC_MAX_COUNT: u16 = 4095;

/// The ADC behind the load cell, implemented by the board.
pub trait LoadCellAdc {
    /// The board's error (ADC overrun, a conversion missing this period, ...).
    type Error;

    /// The latest conversions `[tangential, normal]`, right-aligned counts in
    /// `0..=4095` (those of the current period's trigger).
    ///
    /// # Errors
    /// When the conversions are not this period's (overrun, missing end of
    /// conversion).
    fn read(&mut self) -> Result<[u16; 2], Self::Error>;
}

/// The load cell's axes, in the order of every `[_; 2]` here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Index 0: `f_t`, tangential to the belt.
    Tangential,
    /// Index 1: `f_n`, normal to the belt.
    Normal,
}

/// Why a [`Calibration`] was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationError {
    /// The zero is NaN, infinite, or outside `0..=4095` counts.
    BadZero(Axis),
    /// The gain is NaN, infinite, zero, or so large that a full-scale count
    /// difference (4095) overflows `f32`.
    BadGain(Axis),
}

impl fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CalibrationError::BadZero(a) => write!(f, "load cell {a:?}: zero must be finite and within 0..=4095 counts"),
            CalibrationError::BadGain(a) => write!(f, "load cell {a:?}: gain must be finite and non-zero"),
        }
    }
}

/// Per-axis calibration: force = `(count - zero_counts) * newtons_per_count`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// ADC count at zero force `[tangential, normal]`, in `0..=4095`.
    pub zero_counts: [f32; 2],
    /// Gain `[tangential, normal]`, N per count; non-zero (negative flips the axis).
    pub newtons_per_count: [f32; 2],
}

impl Default for Calibration {
    /// The nominal front end: zero at mid-scale (2048 counts) and +-25 N over
    /// +-2048 counts, i.e. one ADC count is one wire code (25/2048 N).
    fn default() -> Self {
        Self { zero_counts: [2048.0; 2], newtons_per_count: [LOAD_FULL_SCALE_N / 2048.0; 2] }
    }
}

impl Calibration {
    /// Checks the calibration, so that every force it gives is finite.
    ///
    /// # Errors
    /// [`CalibrationError::BadZero`], [`CalibrationError::BadGain`] (first bad axis).
    pub fn validate(&self) -> Result<(), CalibrationError> {
        for axis in [Axis::Tangential, Axis::Normal] {
            let (zero, gain) = self.axis(axis);
            if !(zero.is_finite() && (0.0..=ADC_MAX_COUNT as f32).contains(&zero)) {
                return Err(CalibrationError::BadZero(axis));
            }
            if gain == 0.0 || !(gain * ADC_MAX_COUNT as f32).is_finite() {
                return Err(CalibrationError::BadGain(axis));
            }
        }
        Ok(())
    }

    /// `(zero_counts, newtons_per_count)` of `axis`.
    fn axis(&self, axis: Axis) -> (f32, f32) {
        let ([zt, zn], [gt, gn]) = (self.zero_counts, self.newtons_per_count);
        match axis {
            Axis::Tangential => (zt, gt),
            Axis::Normal => (zn, gn),
        }
    }
}

/// Errors of [`LoadCell`] reads. `E` is the ADC's error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error<E> {
    /// The ADC failed (overrun, missing conversion).
    Adc(E),
    /// A count above 4095: not a 12-bit right-aligned conversion.
    CountOutOfRange {
        /// The axis that gave it.
        channel: Axis,
        /// The count.
        count: u16,
    },
}

impl<E: fmt::Debug> fmt::Display for Error<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Adc(e) => write!(f, "load cell: ADC error {e:?}"),
            Error::CountOutOfRange { channel, count } => write!(f, "load cell {channel:?}: count {count} above 4095"),
        }
    }
}

/// Encodes a force (N) as a wire load-cell code, exactly as
/// `shared::wire::encode_force(force as f64)` does but in `f32` (the MCU has no
/// double-precision FPU): `round(force / 25 N * 2048)` half away from zero,
/// saturated to `[-2048, 2047]`, and 0 for a non-finite force.
///
/// Same codes for every `f32`: the division by 25 is the only rounding (times
/// 2048 is exact), its error is at most half an ulp of the result, while a
/// representable force that is not exactly on a half-code boundary lies at least
/// `81.92 ulp(force) > 64 ulp(force) >= ulp(result) / 2` from it; forces exactly
/// on a boundary, `(2k+1) 25 / 4096`, divide exactly. The bound to +-2 full
/// scales before the scaling only keeps huge forces from overflowing; they
/// saturate either way. (Checked in the tests, exhaustively over all `f32` in an
/// ignored one.)
pub fn encode_force_f32(force: f32) -> i16 {
    if !force.is_finite() {
        return 0;
    }
    // Bounded before the scaling so that no finite force overflows f32 (in f64
    // none does); beyond +-2 full scales the code saturates anyway.
    let full_scales = (force / LOAD_FULL_SCALE_N).clamp(-2.0, 2.0);
    let code = libm::roundf(full_scales * 2048.0);
    code.clamp(LOAD_CODE_MIN as f32, LOAD_CODE_MAX as f32) as i16
}

/// The load cell: an ADC and its validated calibration.
#[derive(Debug)]
pub struct LoadCell<ADC> {
    adc: ADC,
    cal: Calibration,
}

impl<ADC: LoadCellAdc> LoadCell<ADC> {
    /// A load cell on `adc` with calibration `cal`.
    ///
    /// # Errors
    /// [`CalibrationError`] from [`Calibration::validate`].
    pub fn new(adc: ADC, cal: Calibration) -> Result<Self, CalibrationError> {
        cal.validate()?;
        Ok(Self { adc, cal })
    }

    /// The calibration in use.
    pub fn calibration(&self) -> &Calibration {
        &self.cal
    }

    /// Gives the ADC back.
    pub fn release(self) -> ADC {
        self.adc
    }

    /// The forces `[f_t, f_n]`, N, of this period's conversion; always finite.
    ///
    /// # Errors
    /// [`Error::Adc`], [`Error::CountOutOfRange`] (first bad axis).
    pub fn read_newtons(&mut self) -> Result<[f32; 2], Error<ADC::Error>> {
        let [t, n] = self.adc.read().map_err(Error::Adc)?;
        Ok([self.force(Axis::Tangential, t)?, self.force(Axis::Normal, n)?])
    }

    /// The force of one axis, N.
    fn force(&self, axis: Axis, count: u16) -> Result<f32, Error<ADC::Error>> {
        if count > ADC_MAX_COUNT {
            return Err(Error::CountOutOfRange { channel: axis, count });
        }
        let (zero, gain) = self.cal.axis(axis);
        // Finite: |count - zero| <= 4095 and validate() bounded the gain for that.
        Ok((count as f32 - zero) * gain)
    }

    /// The wire codes `[f_t_code, f_n_code]` (codes of 25/2048 N, saturated to
    /// `[-2048, 2047]`) of this period's conversion, via [`encode_force_f32`].
    ///
    /// # Errors
    /// As [`LoadCell::read_newtons`].
    pub fn read_codes(&mut self) -> Result<[i16; 2], Error<ADC::Error>> {
        self.read_newtons().map(|f| f.map(encode_force_f32))
    }

    /// This period's raw conversions `[tangential, normal]`, counts in `0..=4095`
    /// (bring-up: tare and span), and their wire codes as [`LoadCell::read_codes`]
    /// gives them: one read of the ADC for both.
    ///
    /// # Errors
    /// As [`LoadCell::read_newtons`].
    pub fn read_counts_and_codes(&mut self) -> Result<CountsAndCodes, Error<ADC::Error>> {
        let [t, n] = self.adc.read().map_err(Error::Adc)?;
        let forces = [self.force(Axis::Tangential, t)?, self.force(Axis::Normal, n)?];
        Ok(([t, n], forces.map(encode_force_f32)))
    }

    /// Replaces the calibration (bring-up).
    ///
    /// # Errors
    /// [`CalibrationError`] from [`Calibration::validate`]; the old one stays.
    pub fn set_calibration(&mut self, cal: Calibration) -> Result<(), CalibrationError> {
        cal.validate()?;
        self.cal = cal;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use shared::wire::encode_force;

    /// A fake ADC returning one scripted result.
    struct FakeAdc(Result<[u16; 2], &'static str>);

    impl LoadCellAdc for FakeAdc {
        type Error = &'static str;
        fn read(&mut self) -> Result<[u16; 2], &'static str> {
            self.0
        }
    }

    fn cell(r: Result<[u16; 2], &'static str>) -> LoadCell<FakeAdc> {
        LoadCell::new(FakeAdc(r), Calibration::default()).unwrap()
    }

    #[test]
    fn default_calibration_is_one_code_per_count() {
        assert_eq!(cell(Ok([2048, 2048])).read_newtons(), Ok([0.0, 0.0]));
        assert_eq!(cell(Ok([2048 + 819, 2048 - 100])).read_codes(), Ok([819, -100]));
        let f = cell(Ok([2048 + 1024, 0])).read_newtons().unwrap();
        assert_eq!(f, [12.5, -25.0]);
    }

    #[test]
    fn codes_clamp_at_full_scale() {
        assert_eq!(cell(Ok([4095, 0])).read_codes(), Ok([2047, -2048]));
        // A steeper front end saturates earlier, at the wire's ends.
        let cal = Calibration { zero_counts: [2048.0; 2], newtons_per_count: [0.1, -0.1] };
        let mut lc = LoadCell::new(FakeAdc(Ok([4095, 4095])), cal).unwrap();
        assert_eq!(lc.read_codes(), Ok([LOAD_CODE_MAX, LOAD_CODE_MIN]));
    }

    #[test]
    fn adc_errors_and_out_of_range_counts_are_errors() {
        assert_eq!(cell(Err("overrun")).read_codes(), Err(Error::Adc("overrun")));
        assert_eq!(cell(Ok([4096, 0])).read_newtons(), Err(Error::CountOutOfRange { channel: Axis::Tangential, count: 4096 }));
        assert_eq!(cell(Ok([0, u16::MAX])).read_codes(), Err(Error::CountOutOfRange { channel: Axis::Normal, count: u16::MAX }));
    }

    #[test]
    fn calibration_is_validated() {
        let ok = Calibration::default();
        assert_eq!(ok.validate(), Ok(()));
        let with = |z: [f32; 2], g: [f32; 2]| Calibration { zero_counts: z, newtons_per_count: g }.validate();
        assert_eq!(with([f32::NAN, 0.0], [1.0; 2]), Err(CalibrationError::BadZero(Axis::Tangential)));
        assert_eq!(with([0.0, 4095.5], [1.0; 2]), Err(CalibrationError::BadZero(Axis::Normal)));
        assert_eq!(with([0.0, -1.0], [1.0; 2]), Err(CalibrationError::BadZero(Axis::Normal)));
        assert_eq!(with([0.0, 4095.0], [1.0, 0.0]), Err(CalibrationError::BadGain(Axis::Normal)));
        assert_eq!(with([0.0; 2], [f32::INFINITY, 1.0]), Err(CalibrationError::BadGain(Axis::Tangential)));
        assert_eq!(with([0.0; 2], [1.0, f32::NAN]), Err(CalibrationError::BadGain(Axis::Normal)));
        assert_eq!(with([0.0; 2], [1.0, f32::MAX / 1000.0]), Err(CalibrationError::BadGain(Axis::Normal)));
        assert!(LoadCell::new(FakeAdc(Ok([0, 0])), Calibration { zero_counts: [0.0; 2], newtons_per_count: [0.0; 2] }).is_err());
    }

    #[test]
    fn f32_encoding_matches_the_wire_near_every_half_code_boundary() {
        for k in -2100..2100 {
            let boundary = (2 * k + 1) as f32 * LOAD_FULL_SCALE_N / 4096.0;
            let mut f = boundary;
            for _ in 0..16 {
                f = f.next_down();
            }
            for _ in 0..33 {
                assert_eq!(encode_force_f32(f), encode_force(f as f64), "force {f:e}");
                f = f.next_up();
            }
        }
        for f in [0.0, -0.0, f32::MAX, f32::MIN, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e-45] {
            assert_eq!(encode_force_f32(f), encode_force(f as f64), "force {f:e}");
        }
    }

    /// Every `f32` (4 x 10^9 of them): `cargo test -p drivers --release -- --ignored`.
    #[test]
    #[ignore = "exhaustive, about a minute in release"]
    fn f32_encoding_matches_the_wire_for_every_f32() {
        for bits in 0..=u32::MAX {
            let f = f32::from_bits(bits);
            assert_eq!(encode_force_f32(f), encode_force(f as f64), "force {f:e}");
        }
    }

    proptest! {
        #[test]
        fn f32_encoding_matches_the_wire_in_range(f in -60.0f32..60.0) {
            prop_assert_eq!(encode_force_f32(f), encode_force(f as f64));
        }

        #[test]
        fn f32_encoding_matches_the_wire(bits in any::<u32>()) {
            let f = f32::from_bits(bits);
            prop_assert_eq!(encode_force_f32(f), encode_force(f as f64));
        }

        #[test]
        fn any_count_gives_finite_forces(counts in any::<[u16; 2]>(), z in 0.0f32..=4095.0, g in -1e30f32..1e30) {
            prop_assume!(g != 0.0);
            let cal = Calibration { zero_counts: [z; 2], newtons_per_count: [g; 2] };
            let mut lc = LoadCell::new(FakeAdc(Ok(counts)), cal).unwrap();
            match lc.read_newtons() {
                Ok(f) => prop_assert!(f.iter().all(|x| x.is_finite())),
                Err(e) => prop_assert!(matches!(e, Error::CountOutOfRange { .. }), "{:?}", e),
            }
        }
    }
}
