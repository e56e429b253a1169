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

/// The nominal gain of the reference front end, N per count: +-25 N over
/// +-2048 counts (docs/hardware.md "Full scales and signs": 81.92 counts per N),
/// one ADC count one wire code.
pub const NOMINAL_NEWTONS_PER_COUNT: f32 = LOAD_FULL_SCALE_N / 2048.0;

/// How far a gain may lie from [`NOMINAL_NEWTONS_PER_COUNT`], as a factor either
/// way: a gain in `[nominal / 4, 4 nominal]` (0.00305 to 0.0488 N per count) is
/// taken. Why: the front end's amplifiers are set so that the load cell's +-25 N
/// fill the ADC's 4096 counts; a gain 4 times the nominal one would put 25 N at
/// 512 counts (the 12-bit ADC used as a 9-bit one, 50 mN a count: the force
/// loop's noise floor), a gain a quarter of it would clip the ADC at 6.25 N,
/// below the reference force `f_n*` of 10 N. Beyond these the front end is
/// mis-built or mis-spanned (a weight on the wrong axis, a span of the noise),
/// and the force loop would be blind (a gain of 1e-45 reads every force as 0)
/// or deafened. The sign is positive: the count increases with the force in its
/// positive direction on the reference board (docs/hardware.md); a load cell of
/// the wrong sign is a wiring fault to fix, not to calibrate away.
pub const GAIN_FACTOR: f32 = 4.0;

/// Why a [`Calibration`] was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationError {
    /// The zero is NaN, infinite, or outside `0..=4095` counts.
    BadZero(Axis),
    /// The gain is NaN, infinite, not positive, or outside
    /// `[nominal / GAIN_FACTOR, nominal * GAIN_FACTOR]` ([`GAIN_FACTOR`]).
    BadGain(Axis),
}

impl CalibrationError {
    /// The axis whose value is refused.
    pub fn axis(self) -> Axis {
        match self {
            Self::BadZero(a) | Self::BadGain(a) => a,
        }
    }
}

impl Axis {
    /// The axis's index in every `[_; 2]` (0 tangential, 1 normal).
    pub fn index(self) -> usize {
        match self {
            Self::Tangential => 0,
            Self::Normal => 1,
        }
    }
}

impl fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CalibrationError::BadZero(a) => write!(f, "load cell {a:?}: zero must be finite and within 0..=4095 counts"),
            CalibrationError::BadGain(a) => write!(
                f,
                "load cell {a:?}: gain must be positive, within a factor 4 of the nominal 25/2048 N per count \
                 (0.00305 to 0.0488 N per count)"
            ),
        }
    }
}

/// Per-axis calibration: force = `(count - zero_counts) * newtons_per_count`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// ADC count at zero force `[tangential, normal]`, in `0..=4095`.
    pub zero_counts: [f32; 2],
    /// Gain `[tangential, normal]`, N per count; positive, within a factor
    /// [`GAIN_FACTOR`] of [`NOMINAL_NEWTONS_PER_COUNT`].
    pub newtons_per_count: [f32; 2],
}

impl Default for Calibration {
    /// The nominal front end: zero at mid-scale (2048 counts) and +-25 N over
    /// +-2048 counts, i.e. one ADC count is one wire code (25/2048 N).
    fn default() -> Self {
        Self { zero_counts: [2048.0; 2], newtons_per_count: [NOMINAL_NEWTONS_PER_COUNT; 2] }
    }
}

impl Calibration {
    /// Checks the calibration: every force it gives is finite, and the front end
    /// is one the reference board's can be (zero within the ADC, gain positive and
    /// within a factor [`GAIN_FACTOR`] of the nominal one). The one rule of the
    /// firmware, the bring-up's `Restore` and the flash record, the backup files
    /// and the scenario files' `[calibration]`.
    ///
    /// # Errors
    /// [`CalibrationError::BadZero`], [`CalibrationError::BadGain`] (first bad axis).
    pub fn validate(&self) -> Result<(), CalibrationError> {
        for axis in [Axis::Tangential, Axis::Normal] {
            let (zero, gain) = self.axis(axis);
            if !(zero.is_finite() && (0.0..=ADC_MAX_COUNT as f32).contains(&zero)) {
                return Err(CalibrationError::BadZero(axis));
            }
            let (lo, hi) = (NOMINAL_NEWTONS_PER_COUNT / GAIN_FACTOR, NOMINAL_NEWTONS_PER_COUNT * GAIN_FACTOR);
            if !(lo..=hi).contains(&gain) {
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
        let cal = Calibration { zero_counts: [2048.0; 2], newtons_per_count: [0.04; 2] };
        let mut lc = LoadCell::new(FakeAdc(Ok([4095, 0])), cal).unwrap();
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
        let n = NOMINAL_NEWTONS_PER_COUNT;
        let with = |z: [f32; 2], g: [f32; 2]| Calibration { zero_counts: z, newtons_per_count: g }.validate();
        assert_eq!(with([f32::NAN, 0.0], [n; 2]), Err(CalibrationError::BadZero(Axis::Tangential)));
        assert_eq!(with([0.0, 4095.5], [n; 2]), Err(CalibrationError::BadZero(Axis::Normal)));
        assert_eq!(with([0.0, -1.0], [n; 2]), Err(CalibrationError::BadZero(Axis::Normal)));
        assert_eq!(with([0.0, 4095.0], [n, 0.0]), Err(CalibrationError::BadGain(Axis::Normal)));
        assert_eq!(with([0.0; 2], [f32::INFINITY, n]), Err(CalibrationError::BadGain(Axis::Tangential)));
        assert_eq!(with([0.0; 2], [n, f32::NAN]), Err(CalibrationError::BadGain(Axis::Normal)));
        assert_eq!(with([0.0; 2], [n, f32::MAX / 1000.0]), Err(CalibrationError::BadGain(Axis::Normal)));
        // The audit's blind front end (issue 52): 1e-45 N per count reads every force as 0.
        assert_eq!(with([2048.0; 2], [1e-45, n]), Err(CalibrationError::BadGain(Axis::Tangential)));
        // A negative gain: a load cell of the wrong sign.
        assert_eq!(with([2048.0; 2], [n, -n]), Err(CalibrationError::BadGain(Axis::Normal)));
        // The range's ends are taken, just beyond them is not.
        assert_eq!(with([2048.0; 2], [n / GAIN_FACTOR, n * GAIN_FACTOR]), Ok(()));
        assert_eq!(with([2048.0; 2], [(n / GAIN_FACTOR).next_down(), n]), Err(CalibrationError::BadGain(Axis::Tangential)));
        assert_eq!(with([2048.0; 2], [n, (n * GAIN_FACTOR).next_up()]), Err(CalibrationError::BadGain(Axis::Normal)));
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
        fn any_count_gives_finite_forces(counts in any::<[u16; 2]>(), z in 0.0f32..=4095.0, g in 0.25f32..=4.0) {
            let g = g * NOMINAL_NEWTONS_PER_COUNT;
            let cal = Calibration { zero_counts: [z; 2], newtons_per_count: [g; 2] };
            let mut lc = LoadCell::new(FakeAdc(Ok(counts)), cal).unwrap();
            match lc.read_newtons() {
                Ok(f) => prop_assert!(f.iter().all(|x| x.is_finite())),
                Err(e) => prop_assert!(matches!(e, Error::CountOutOfRange { .. }), "{:?}", e),
            }
        }
    }
}
