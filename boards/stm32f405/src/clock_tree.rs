//! Clock-tree bring-up of the STM32F405 (RM0090 rev 19, section 6 "RCC" and
//! section 3.5.1 "Relation between CPU clock frequency and flash read time"):
//! the 25 MHz crystal (HSE) through the main PLL to a 168 MHz core clock (both
//! from docs/hardware.md), then, by RM0090's limits, AHB at 168 MHz, APB1 at
//! 42 MHz, APB2 at 84 MHz, 48 MHz for USB, five flash wait states with prefetch and both caches on.
//!
//! The sequence is written once, over [`ClockControl`] (one method per step of
//! RM0090 6.3), so it runs on the host against a model of the RCC in the tests
//! and on the chip through the `stm32f4` PAC (`mcu::rcc`). Every wait for a ready
//! flag is bounded: a dead crystal is an error, not a hang.
//!
//! An emulator without an RCC model (QEMU's `netduinoplus2` maps the RCC as an
//! unimplemented device: reads return 0, writes are dropped) is recognised by
//! the HSI ready flag, which silicon sets out of reset: the bring-up is skipped
//! and reported as [`ClockOutcome::NoClockModel`] (the emulator's core clock is
//! fixed at 168 MHz already).

/// HSI, the internal RC oscillator the chip starts on, Hz (RM0090 6.2.2).
pub const HSI_HZ: u32 = 16_000_000;
/// The core clock this firmware is written for, Hz (docs/hardware.md).
pub const SYSCLK_HZ: u32 = 168_000_000;
/// APB1's clock after [`bring_up`] (AHB / 4), Hz; its timers run at twice it.
pub const PCLK1_HZ: u32 = SYSCLK_HZ / 4;
/// APB2's clock after [`bring_up`] (AHB / 2), Hz; its timers run at twice it.
pub const PCLK2_HZ: u32 = SYSCLK_HZ / 2;
/// Flash wait states at 168 MHz and 2.7 to 3.6 V (RM0090 table 10).
pub const FLASH_WAIT_STATES: u8 = 5;

/// The steps of the bring-up, one method each (RM0090 6.3.1 to 6.3.3, 3.9.1, 5.4.1).
pub trait ClockControl {
    /// CR.HSIRDY: the internal oscillator runs (always, on silicon out of reset).
    fn hsi_ready(&mut self) -> bool;
    /// Sets CR.HSEON: starts the crystal oscillator.
    fn start_hse(&mut self);
    /// CR.HSERDY.
    fn hse_ready(&mut self) -> bool;
    /// PWR clock on and the regulator in scale 1 (needed above 144 MHz).
    fn regulator_scale_1(&mut self);
    /// Writes PLLCFGR: source HSE and the dividers of `pll`.
    fn configure_pll(&mut self, pll: &PllConfig);
    /// Sets CR.PLLON.
    fn start_pll(&mut self);
    /// CR.PLLRDY.
    fn pll_ready(&mut self) -> bool;
    /// Writes ACR: `wait_states`, prefetch, instruction and data caches on.
    fn set_flash_latency(&mut self, wait_states: u8);
    /// ACR.LATENCY as read back.
    fn flash_latency(&mut self) -> u8;
    /// Writes CFGR: APB1 /4, APB2 /2, system clock from the PLL.
    fn switch_to_pll(&mut self);
    /// CFGR.SWS reads "PLL".
    fn runs_on_pll(&mut self) -> bool;
}

/// Main-PLL dividers: `f_vco = f_hse / m * n`, `sysclk = f_vco / p`,
/// `f_usb = f_vco / q` (RM0090 6.3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PllConfig {
    /// Input divider, 2..=63 (VCO input 1 to 2 MHz).
    pub m: u32,
    /// Multiplier, 50..=432 (VCO output 100 to 432 MHz).
    pub n: u32,
    /// System-clock divider: 2, 4, 6 or 8.
    pub p: u32,
    /// USB divider, 2..=15 (48 MHz wanted).
    pub q: u32,
}

/// Why the clocks could not be brought up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ClockError {
    /// No PLL setting gives 168 MHz and 48 MHz from this crystal (`hse_hz`).
    UnusableCrystal {
        /// The crystal, Hz.
        hse_hz: u32,
    },
    /// The crystal did not start (HSERDY never set).
    HseNotReady,
    /// The PLL did not lock (PLLRDY never set).
    PllNotReady,
    /// The flash latency did not read back as written.
    FlashLatency,
    /// The system clock did not switch to the PLL.
    SwitchFailed,
}

/// What [`bring_up`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ClockOutcome {
    /// The core runs at [`SYSCLK_HZ`] from the PLL.
    Pll {
        /// The dividers used.
        m: u32,
        /// Multiplier.
        n: u32,
    },
    /// No clock model (an emulator: the RCC reads 0): nothing was done.
    NoClockModel,
}

impl PllConfig {
    /// Dividers for [`SYSCLK_HZ`] and 48 MHz USB from a crystal of `hse_hz`
    /// (4 to 26 MHz, RM0090 6.2.1), with the VCO input at 1 MHz or, when the
    /// crystal allows, 2 MHz (less jitter).
    ///
    /// # Errors
    /// [`ClockError::UnusableCrystal`] when no integer dividers fit.
    pub fn for_168mhz(hse_hz: u32) -> Result<Self, ClockError> {
        let bad = ClockError::UnusableCrystal { hse_hz };
        if !(4_000_000..=26_000_000).contains(&hse_hz) {
            return Err(bad);
        }
        for vco_in in [2_000_000u32, 1_000_000] {
            if !hse_hz.is_multiple_of(vco_in) {
                continue;
            }
            let m = hse_hz / vco_in;
            // 336 MHz VCO: /2 for 168 MHz, /7 for 48 MHz.
            let n = 336_000_000 / vco_in;
            let cfg = Self { m, n, p: 2, q: 7 };
            if cfg.valid() {
                return Ok(cfg);
            }
        }
        Err(bad)
    }

    fn valid(&self) -> bool {
        (2..=63).contains(&self.m) && (50..=432).contains(&self.n) && matches!(self.p, 2 | 4 | 6 | 8) && (2..=15).contains(&self.q)
    }
}

/// Brings the core clock to [`SYSCLK_HZ`] from a crystal of `hse_hz`, polling
/// each ready flag at most `max_polls` times (at 16 MHz on HSI, 100 000 polls are
/// a few tens of milliseconds; a crystal starts within 2 ms).
///
/// # Errors
/// [`ClockError`]: the crystal is unusable or dead, the PLL did not lock, the
/// flash latency or the clock switch did not take. The core then still runs on
/// HSI at 16 MHz, and the image must not run the control loop (its timing
/// assumes 168 MHz).
pub fn bring_up<R: ClockControl>(rcc: &mut R, hse_hz: u32, max_polls: u32) -> Result<ClockOutcome, ClockError> {
    if !rcc.hsi_ready() {
        return Ok(ClockOutcome::NoClockModel);
    }
    let pll = PllConfig::for_168mhz(hse_hz)?;
    let wait = |rcc: &mut R, ready: fn(&mut R) -> bool, err: ClockError| {
        for _ in 0..max_polls {
            if ready(rcc) {
                return Ok(());
            }
        }
        Err(err)
    };
    rcc.start_hse();
    wait(rcc, R::hse_ready, ClockError::HseNotReady)?;
    rcc.regulator_scale_1();
    rcc.configure_pll(&pll);
    rcc.start_pll();
    wait(rcc, R::pll_ready, ClockError::PllNotReady)?;
    // The wait states before the faster clock (RM0090 3.5.1).
    rcc.set_flash_latency(FLASH_WAIT_STATES);
    wait(rcc, |r| r.flash_latency() == FLASH_WAIT_STATES, ClockError::FlashLatency)?;
    rcc.switch_to_pll();
    wait(rcc, R::runs_on_pll, ClockError::SwitchFailed)?;
    Ok(ClockOutcome::Pll { m: pll.m, n: pll.n })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model of the RCC: HSE and the PLL become ready a few polls after they
    /// are started when `crystal` is there; every step is logged in order.
    struct RccModel {
        hsi: bool,
        crystal: bool,
        polls: u32,
        log: Vec<&'static str>,
        hse_on: bool,
        pll_on: bool,
        pll: Option<PllConfig>,
        latency: u8,
        on_pll: bool,
    }

    impl RccModel {
        fn silicon(crystal: bool) -> Self {
            Self { hsi: true, crystal, polls: 0, log: Vec::new(), hse_on: false, pll_on: false, pll: None, latency: 0, on_pll: false }
        }
        fn at(&self, step: &str) -> usize {
            self.log.iter().position(|s| *s == step).unwrap()
        }
    }

    impl ClockControl for RccModel {
        fn hsi_ready(&mut self) -> bool {
            self.hsi
        }
        fn start_hse(&mut self) {
            self.log.push("hse");
            self.hse_on = true;
        }
        fn hse_ready(&mut self) -> bool {
            self.polls += 1;
            self.hse_on && self.crystal && self.polls > 3
        }
        fn regulator_scale_1(&mut self) {
            self.log.push("vos");
        }
        fn configure_pll(&mut self, pll: &PllConfig) {
            self.log.push("pllcfgr");
            self.pll = Some(*pll);
        }
        fn start_pll(&mut self) {
            self.log.push("pll");
            self.pll_on = true;
        }
        fn pll_ready(&mut self) -> bool {
            self.polls += 1;
            self.pll_on && self.pll.is_some()
        }
        fn set_flash_latency(&mut self, wait_states: u8) {
            self.log.push("latency");
            self.latency = wait_states;
        }
        fn flash_latency(&mut self) -> u8 {
            self.latency
        }
        fn switch_to_pll(&mut self) {
            self.log.push("switch");
            self.on_pll = self.pll_on;
        }
        fn runs_on_pll(&mut self) -> bool {
            self.on_pll
        }
    }

    #[test]
    fn the_paper_target_clock_comes_from_the_netduino_crystal() {
        // 25 MHz / 25 * 336 / 2 = 168 MHz, / 7 = 48 MHz.
        let c = PllConfig::for_168mhz(crate::pins::HSE_HZ).unwrap();
        assert_eq!(c, PllConfig { m: 25, n: 336, p: 2, q: 7 });
        // An 8 MHz crystal (STM32F4-Discovery) gets the 2 MHz VCO input.
        assert_eq!(PllConfig::for_168mhz(8_000_000).unwrap(), PllConfig { m: 4, n: 168, p: 2, q: 7 });
        for hse in [4_000_000u32, 8_000_000, 12_000_000, 16_000_000, 24_000_000, 25_000_000, 26_000_000] {
            let c = PllConfig::for_168mhz(hse).unwrap();
            assert_eq!(u64::from(hse) / u64::from(c.m) * u64::from(c.n) / u64::from(c.p), u64::from(SYSCLK_HZ), "{hse}");
            assert_eq!(u64::from(hse) / u64::from(c.m) * u64::from(c.n) / u64::from(c.q), 48_000_000, "{hse}");
        }
        assert!(PllConfig::for_168mhz(3_000_000).is_err());
        assert!(PllConfig::for_168mhz(12_345_678).is_err());
    }

    #[test]
    fn bring_up_sets_latency_before_switching_and_reaches_the_pll() {
        let mut rcc = RccModel::silicon(true);
        let out = bring_up(&mut rcc, 25_000_000, 1000).unwrap();
        assert_eq!(out, ClockOutcome::Pll { m: 25, n: 336 });
        assert_eq!(rcc.log, ["hse", "vos", "pllcfgr", "pll", "latency", "switch"]);
        assert!(rcc.at("latency") < rcc.at("switch"), "wait states before the faster clock");
        assert_eq!(rcc.latency, 5);
        assert_eq!(rcc.pll, Some(PllConfig { m: 25, n: 336, p: 2, q: 7 }));
        assert!(rcc.on_pll);
    }

    #[test]
    fn a_dead_crystal_is_an_error_after_a_bounded_wait_not_a_hang() {
        let mut rcc = RccModel::silicon(false);
        assert_eq!(bring_up(&mut rcc, 25_000_000, 1000), Err(ClockError::HseNotReady));
        assert!(rcc.polls <= 1000);
        // Never switched: the core stays on HSI.
        assert_eq!(rcc.log, ["hse"]);
    }

    #[test]
    fn an_emulator_without_an_rcc_model_is_left_alone() {
        let mut rcc = RccModel::silicon(true);
        rcc.hsi = false;
        assert_eq!(bring_up(&mut rcc, 25_000_000, 1000), Ok(ClockOutcome::NoClockModel));
        assert!(rcc.log.is_empty());
    }
}
