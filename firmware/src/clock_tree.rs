//! Clock-tree bring-up of the STM32F405 (RM0090 rev 19, section 6 "RCC" and
//! section 3.5.1 "Relation between CPU clock frequency and flash read time"):
//! the external crystal (HSE) through the main PLL to a 168 MHz core clock
//! (HARDWARE.md), AHB at 168 MHz, APB1 at 42 MHz, APB2 at 84 MHz, 48 MHz for
//! USB, five flash wait states with prefetch and both caches on.
//!
//! The register sequence is behind [`Registers`], so it runs on the host against
//! a model of the RCC in the tests; the MCU images pass volatile access to the
//! chip's registers (`src/mcu_mmio.rs`: this crate forbids `unsafe`). Every wait for
//! a ready flag is bounded: a dead crystal is an error, not a hang.
//!
//! An emulator without an RCC model (QEMU's `netduinoplus2` maps the RCC as an
//! unimplemented device: reads return 0, writes are dropped) is recognised by
//! the HSI ready flag, which silicon sets out of reset: the bring-up is skipped
//! and reported as [`ClockOutcome::NoClockModel`] (the emulator's core clock is
//! fixed at 168 MHz already).

/// HSI, the internal RC oscillator the chip starts on, Hz (RM0090 6.2.2).
pub const HSI_HZ: u32 = 16_000_000;
/// The core clock this firmware is written for, Hz (HARDWARE.md).
pub const SYSCLK_HZ: u32 = 168_000_000;
/// The Netduino Plus 2's crystal (QEMU's `netduinoplus2` board), Hz.
pub const NETDUINO_PLUS_2_HSE_HZ: u32 = 25_000_000;

/// RCC and flash-interface register addresses and bits (RM0090 6.3, 3.9).
pub mod reg {
    /// RCC clock control register.
    pub const RCC_CR: u32 = 0x4002_3800;
    /// RCC PLL configuration register.
    pub const RCC_PLLCFGR: u32 = 0x4002_3804;
    /// RCC clock configuration register.
    pub const RCC_CFGR: u32 = 0x4002_3808;
    /// RCC APB1 peripheral clock enable register.
    pub const RCC_APB1ENR: u32 = 0x4002_3840;
    /// PWR power control register.
    pub const PWR_CR: u32 = 0x4000_7000;
    /// Flash access control register.
    pub const FLASH_ACR: u32 = 0x4002_3C00;

    /// CR: HSI ready.
    pub const CR_HSIRDY: u32 = 1 << 1;
    /// CR: HSE on.
    pub const CR_HSEON: u32 = 1 << 16;
    /// CR: HSE ready.
    pub const CR_HSERDY: u32 = 1 << 17;
    /// CR: main PLL on.
    pub const CR_PLLON: u32 = 1 << 24;
    /// CR: main PLL ready.
    pub const CR_PLLRDY: u32 = 1 << 25;
    /// PLLCFGR: the PLL's source is HSE.
    pub const PLLCFGR_SRC_HSE: u32 = 1 << 22;
    /// APB1ENR: power interface clock.
    pub const APB1ENR_PWREN: u32 = 1 << 28;
    /// PWR_CR: regulator in scale 1 (needed above 144 MHz).
    pub const PWR_CR_VOS: u32 = 1 << 14;
    /// ACR: prefetch, instruction cache, data cache.
    pub const ACR_PRFTEN_ICEN_DCEN: u32 = (1 << 8) | (1 << 9) | (1 << 10);
    /// ACR: the latency field.
    pub const ACR_LATENCY_MASK: u32 = 0xF;
    /// CFGR: system clock switch field (bits 0..1), 0b10 = PLL.
    pub const CFGR_SW_PLL: u32 = 0b10;
    /// CFGR: system clock switch status field (bits 2..3).
    pub const CFGR_SWS_MASK: u32 = 0b11 << 2;
    /// CFGR: APB1 prescaler /4 (bits 10..12 = 0b101).
    pub const CFGR_PPRE1_DIV4: u32 = 0b101 << 10;
    /// CFGR: APB2 prescaler /2 (bits 13..15 = 0b100).
    pub const CFGR_PPRE2_DIV2: u32 = 0b100 << 13;
}

/// Memory-mapped register access, 32-bit.
pub trait Registers {
    /// Reads the register at `addr`.
    fn read(&mut self, addr: u32) -> u32;
    /// Writes `value` to the register at `addr`.
    fn write(&mut self, addr: u32, value: u32);
    /// Sets `bits` in the register at `addr` (read, modify, write).
    fn set_bits(&mut self, addr: u32, bits: u32) {
        let v = self.read(addr);
        self.write(addr, v | bits);
    }
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

    /// The PLLCFGR word (source HSE).
    pub fn pllcfgr(&self) -> u32 {
        self.m | (self.n << 6) | (((self.p / 2) - 1) << 16) | reg::PLLCFGR_SRC_HSE | (self.q << 24)
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
pub fn bring_up<R: Registers>(regs: &mut R, hse_hz: u32, max_polls: u32) -> Result<ClockOutcome, ClockError> {
    if regs.read(reg::RCC_CR) & reg::CR_HSIRDY == 0 {
        return Ok(ClockOutcome::NoClockModel);
    }
    let pll = PllConfig::for_168mhz(hse_hz)?;
    let wait = |regs: &mut R, addr: u32, mask: u32, want: u32, err: ClockError| {
        for _ in 0..max_polls {
            if regs.read(addr) & mask == want {
                return Ok(());
            }
        }
        Err(err)
    };
    regs.set_bits(reg::RCC_CR, reg::CR_HSEON);
    wait(regs, reg::RCC_CR, reg::CR_HSERDY, reg::CR_HSERDY, ClockError::HseNotReady)?;
    // Scale 1 regulator for 168 MHz (the reset value, written to be sure).
    regs.set_bits(reg::RCC_APB1ENR, reg::APB1ENR_PWREN);
    regs.set_bits(reg::PWR_CR, reg::PWR_CR_VOS);
    regs.write(reg::RCC_PLLCFGR, pll.pllcfgr());
    regs.set_bits(reg::RCC_CR, reg::CR_PLLON);
    wait(regs, reg::RCC_CR, reg::CR_PLLRDY, reg::CR_PLLRDY, ClockError::PllNotReady)?;
    // Five wait states at 168 MHz and 3.3 V, before the switch (RM0090 table 10).
    regs.write(reg::FLASH_ACR, 5 | reg::ACR_PRFTEN_ICEN_DCEN);
    wait(regs, reg::FLASH_ACR, reg::ACR_LATENCY_MASK, 5, ClockError::FlashLatency)?;
    regs.write(reg::RCC_CFGR, reg::CFGR_PPRE1_DIV4 | reg::CFGR_PPRE2_DIV2 | reg::CFGR_SW_PLL);
    wait(regs, reg::RCC_CFGR, reg::CFGR_SWS_MASK, reg::CFGR_SW_PLL << 2, ClockError::SwitchFailed)?;
    Ok(ClockOutcome::Pll { m: pll.m, n: pll.n })
}

/// The MCU images' start-up: [`bring_up`] from the Netduino Plus 2's crystal
/// ([`NETDUINO_PLUS_2_HSE_HZ`]), the outcome logged. On failure the image never
/// runs the control loop at the wrong rate (its SysTick figures assume 168 MHz):
/// it logs why and sleeps forever, commanding no torque.
#[cfg(target_os = "none")]
pub fn bring_up_or_halt<R: Registers>(regs: &mut R) {
    match bring_up(regs, NETDUINO_PLUS_2_HSE_HZ, 200_000) {
        Ok(ClockOutcome::Pll { m, n }) => defmt::info!("core clock 168 MHz from the 25 MHz crystal (PLL m={=u32} n={=u32})", m, n),
        Ok(ClockOutcome::NoClockModel) => defmt::info!("no RCC model (emulator): core clock as emulated"),
        Err(e) => {
            defmt::error!("clock bring-up failed: {}; not running the control loop", e);
            loop {
                cortex_m::asm::wfi();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A model of the RCC: writes stick, HSE and the PLL become ready after a few
    /// polls when `crystal` (and a valid PLL setting) is there, SWS follows SW.
    struct RccModel {
        regs: BTreeMap<u32, u32>,
        crystal: bool,
        polls: u32,
        writes: Vec<(u32, u32)>,
    }

    impl RccModel {
        fn silicon(crystal: bool) -> Self {
            // Reset values: HSI on and ready (RM0090 6.3.1), VOS scale 1.
            let regs = BTreeMap::from([(reg::RCC_CR, 0x0000_0083), (reg::PWR_CR, reg::PWR_CR_VOS)]);
            Self { regs, crystal, polls: 0, writes: Vec::new() }
        }
    }

    impl Registers for RccModel {
        fn read(&mut self, addr: u32) -> u32 {
            self.polls += 1;
            let mut v = *self.regs.get(&addr).unwrap_or(&0);
            if addr == reg::RCC_CR && self.polls > 3 {
                if v & reg::CR_HSEON != 0 && self.crystal {
                    v |= reg::CR_HSERDY;
                }
                if v & reg::CR_PLLON != 0 && v & reg::CR_HSERDY != 0 {
                    v |= reg::CR_PLLRDY;
                }
                self.regs.insert(addr, v);
            }
            if addr == reg::RCC_CFGR {
                v = (v & !reg::CFGR_SWS_MASK) | ((v & 0b11) << 2);
            }
            v
        }
        fn write(&mut self, addr: u32, value: u32) {
            self.writes.push((addr, value));
            self.regs.insert(addr, value);
        }
    }

    #[test]
    fn the_paper_target_clock_comes_from_the_netduino_crystal() {
        // 25 MHz / 25 * 336 / 2 = 168 MHz, / 7 = 48 MHz.
        let c = PllConfig::for_168mhz(NETDUINO_PLUS_2_HSE_HZ).unwrap();
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
        let out = bring_up(&mut rcc, NETDUINO_PLUS_2_HSE_HZ, 1000).unwrap();
        assert_eq!(out, ClockOutcome::Pll { m: 25, n: 336 });
        let at = |addr: u32| rcc.writes.iter().position(|w| w.0 == addr).unwrap();
        assert!(at(reg::FLASH_ACR) < at(reg::RCC_CFGR), "wait states before the faster clock");
        assert_eq!(rcc.regs[&reg::FLASH_ACR] & 0xF, 5);
        assert_eq!(rcc.regs[&reg::RCC_PLLCFGR], PllConfig { m: 25, n: 336, p: 2, q: 7 }.pllcfgr());
        assert_eq!(rcc.regs[&reg::RCC_CFGR] & 0b11, reg::CFGR_SW_PLL);
    }

    #[test]
    fn a_dead_crystal_is_an_error_after_a_bounded_wait_not_a_hang() {
        let mut rcc = RccModel::silicon(false);
        assert_eq!(bring_up(&mut rcc, NETDUINO_PLUS_2_HSE_HZ, 1000), Err(ClockError::HseNotReady));
        assert!(rcc.polls <= 1002);
        // Never switched: the core stays on HSI.
        assert!(!rcc.regs.contains_key(&reg::RCC_CFGR));
    }

    #[test]
    fn an_emulator_without_an_rcc_model_is_left_alone() {
        struct Unimplemented(u32);
        impl Registers for Unimplemented {
            fn read(&mut self, _: u32) -> u32 {
                0
            }
            fn write(&mut self, _: u32, _: u32) {
                self.0 += 1;
            }
        }
        let mut none = Unimplemented(0);
        assert_eq!(bring_up(&mut none, NETDUINO_PLUS_2_HSE_HZ, 1000), Ok(ClockOutcome::NoClockModel));
        assert_eq!(none.0, 0);
    }
}
