//! ADC1's injected group reading the load cell (RM0090 13 "Analog-to-digital
//! converter"; STM32F405 datasheet DS8626 table 66 "ADC characteristics"):
//! two conversions started by TIM2's TRGO (input line 0, wired from the timer),
//! each taking the count the board twin's load-cell front end gives its
//! channel (`board_twin::adc::adc_count` through `board_twin::physics`).
//!
//! The board (docs/board.md, pin table): `f_t` on PA0 = ADC1 IN0, `f_n` on PA1
//! = ADC1 IN1; nothing else is wired to ADC1. Strict, at each trigger the
//! injected group is armed for and whenever ADON is set: a trigger that is not
//! TIM2's TRGO on its rising edge, a sequence that is not IN0 then IN1
//! (`JL = 1`: JSQ3 then JSQ4), a channel with nothing wired, a sampling time
//! under 15 cycles, a resolution or alignment other than 12-bit right, SCAN
//! off (the second conversion would not run), an ADC clock above the
//! datasheet's 36 MHz, a non-zero injected offset: each a [`BoardError`]
//! naming the register and its value.
//!
//! A missing conversion (the bench's `adc_counts` is `None`: a fault) sets no
//! JEOC. Not modelled: the conversion's duration (JEOC is set at the trigger),
//! the regular group, the analog watchdog, ADC2 and ADC3 (an access is an error).

use board_twin::bench::{Shared, lock};

use crate::device::{BoardError, RegisterModel, Result2};

const BASE: u32 = 0x4001_2000;
const SR: u32 = 0x00;
const CR1: u32 = 0x04;
const CR2: u32 = 0x08;
const SMPR1: u32 = 0x0C;
const SMPR2: u32 = 0x10;
const JOFR1: u32 = 0x14;
const JSQR: u32 = 0x38;
const JDR1: u32 = 0x3C;
const CCR: u32 = 0x304;
const CSR: u32 = 0x300;

const JEOC: u32 = 1 << 2;
const JSTRT: u32 = 1 << 3;
const SCAN: u32 = 1 << 8;
const ADON: u32 = 1 << 0;

/// The channel of each load-cell axis `[f_t, f_n]` (PA0 = IN0, PA1 = IN1).
pub const LOAD_CHANNELS: [u32; 2] = [0, 1];
/// JEXTSEL of TIM2's TRGO (RM0090 13.13.3, table 58... `0b0011`).
pub const JEXTSEL_TIM2_TRGO: u32 = 0b0011;
/// The ADC clock's maximum (DS8626 table 66: f_ADC 36 MHz at VDDA >= 2.4 V), Hz.
pub const ADC_MAX_HZ: u32 = 36_000_000;
/// The shortest sampling time the amplifiers' outputs are checked for, cycles.
pub const MIN_SAMPLING_CYCLES: u32 = 15;

/// ADC1 and the common registers.
pub struct Adc1 {
    regs: [u32; 0x50 / 4],
    ccr: u32,
    bench: Shared,
    /// Conversions run (tests count them).
    pub conversions: u64,
}

impl Adc1 {
    /// ADC1 at reset, converting what `bench` holds.
    pub fn new(bench: Shared) -> Self {
        Self { regs: [0; 0x50 / 4], ccr: 0, bench, conversions: 0 }
    }

    fn reg(&self, offset: u32) -> u32 {
        self.regs[(offset / 4) as usize]
    }

    fn err(&self, offset: u32, name: &str, why: String) -> BoardError {
        BoardError::new(format!("ADC1_{name} ({:#010x})", BASE + offset), if offset == CCR { self.ccr } else { self.reg(offset) }, why)
    }

    /// The injected group as the load cell needs it, or why not.
    fn check(&self) -> Result2<()> {
        let cr2 = self.reg(CR2);
        let jexten = (cr2 >> 20) & 0b11;
        let jextsel = (cr2 >> 16) & 0b1111;
        if jexten != 0b01 || jextsel != JEXTSEL_TIM2_TRGO {
            return Err(self.err(
                CR2,
                "CR2",
                format!(
                    "injected trigger JEXTSEL {jextsel:#06b} on edge JEXTEN {jexten:#04b}: the load cell is sampled at the period's start, on TIM2's TRGO (JEXTSEL 0b0011) rising (JEXTEN 0b01; docs/hardware.md)"
                ),
            ));
        }
        if cr2 & (1 << 11) != 0 {
            return Err(self.err(CR2, "CR2", "left-aligned data (ALIGN = 1): the drivers read right-aligned 12-bit counts".into()));
        }
        let cr1 = self.reg(CR1);
        if (cr1 >> 24) & 0b11 != 0 {
            return Err(self.err(
                CR1,
                "CR1",
                format!("resolution code {}: the load cell is read at 12 bits (RES = 0)", (cr1 >> 24) & 0b11),
            ));
        }
        if cr1 & SCAN == 0 {
            return Err(self.err(CR1, "CR1", "SCAN = 0: only the first injected channel would convert".into()));
        }
        let jsqr = self.reg(JSQR);
        let jl = (jsqr >> 20) & 0b11;
        let seq: Vec<u32> = (3 - jl..4).map(|i| (jsqr >> (5 * i)) & 0x1F).collect();
        if seq != LOAD_CHANNELS {
            return Err(self.err(
                JSQR,
                "JSQR",
                format!(
                    "injected sequence {seq:?} (JL = {jl}): the load cell's f_t is on IN0 (PA0) and f_n on IN1 (PA1), converted in that order (docs/board.md)"
                ),
            ));
        }
        for ch in LOAD_CHANNELS {
            let smp = (self.reg(SMPR2) >> (3 * ch)) & 0b111;
            let cycles = [3, 15, 28, 56, 84, 112, 144, 480][smp as usize];
            if cycles < MIN_SAMPLING_CYCLES {
                return Err(self.err(
                    SMPR2,
                    "SMPR2",
                    format!("channel {ch} samples for {cycles} cycles: the amplifiers' outputs need at least {MIN_SAMPLING_CYCLES}"),
                ));
            }
        }
        for j in 0..4 {
            if self.reg(JOFR1 + 4 * j) != 0 {
                return Err(self.err(
                    JOFR1 + 4 * j,
                    &format!("JOFR{}", j + 1),
                    "an injected offset: the tare is the firmware's, the counts must be raw".into(),
                ));
            }
        }
        let pre = 2 * (((self.ccr >> 16) & 0b11) + 1);
        let f_adc = crate::spi1::APB2_HZ / pre;
        if f_adc > ADC_MAX_HZ {
            return Err(self.err(
                CCR,
                "CCR",
                format!("ADCCLK = APB2 84 MHz / {pre} = {:.1} MHz: above the datasheet's 36 MHz", f64::from(f_adc) / 1e6),
            ));
        }
        Ok(())
    }

    /// TIM2's TRGO rose: the injected group converts, if armed for it.
    fn trigger(&mut self) -> Result2<()> {
        let cr2 = self.reg(CR2);
        if cr2 & ADON == 0 {
            return Ok(());
        }
        self.check()?;
        let Some(counts) = lock(&self.bench).adc_counts else {
            // The conversion is lost (a fault): no JEOC this period.
            return Ok(());
        };
        self.regs[(JDR1 / 4) as usize] = u32::from(counts[0]);
        self.regs[(JDR1 / 4 + 1) as usize] = u32::from(counts[1]);
        self.regs[0] |= JEOC | JSTRT;
        self.conversions += 1;
        Ok(())
    }
}

impl RegisterModel for Adc1 {
    fn read(&mut self, offset: u32) -> Result2<u32> {
        match offset {
            SR..=0x4C => Ok(self.reg(offset)),
            CSR => Ok(self.reg(SR)),
            CCR => Ok(self.ccr),
            _ => Err(unmodelled(offset)),
        }
    }

    fn write(&mut self, offset: u32, value: u32) -> Result2<()> {
        match offset {
            // rc_w0 flags: writing 0 clears, 1 keeps.
            SR => {
                self.regs[0] &= value | !0x3F;
                Ok(())
            }
            CR1 | SMPR1 | SMPR2 | JSQR | 0x14..=0x34 => {
                self.regs[(offset / 4) as usize] = value;
                Ok(())
            }
            CR2 => {
                self.regs[(CR2 / 4) as usize] = value & !((1 << 22) | (1 << 30));
                if value & (1 << 22) != 0 {
                    return Err(self.err(CR2, "CR2", "JSWSTART: the load cell's conversions start on TIM2's TRGO, not by software".into()));
                }
                if value & ADON != 0 { self.check() } else { Ok(()) }
            }
            CCR => {
                self.ccr = value;
                Ok(())
            }
            _ => Err(unmodelled(offset)),
        }
    }

    fn input(&mut self, line: u32, high: bool) -> Result2<()> {
        if line == 0 && high { self.trigger() } else { Ok(()) }
    }

    fn peek(&self, offset: u32) -> u32 {
        match offset {
            SR..=0x4C => self.reg(offset),
            CCR => self.ccr,
            _ => 0,
        }
    }

    fn reset(&mut self) {
        *self = Self { conversions: self.conversions, ..Self::new(self.bench.clone()) };
    }
}

fn unmodelled(offset: u32) -> BoardError {
    BoardError::new(
        format!("ADC +{offset:#x} ({:#010x})", BASE + offset),
        0,
        "a register the ADC1 model does not implement (ADC1's and the common CCR/CSR only; nothing is wired to ADC2 or ADC3)",
    )
}

#[cfg(test)]
mod tests {
    use board_twin::bench::Bench;

    use super::*;

    /// The image's configuration (`mcu/adc.rs`), in its order.
    fn configured() -> Adc1 {
        let bench: Shared = std::sync::Arc::new(std::sync::Mutex::new(Bench::default()));
        lock(&bench).adc_counts = Some([1000, 3000]);
        let mut a = Adc1::new(bench);
        a.write(CCR, 0b01 << 16).unwrap();
        a.write(JSQR, (1 << 20) | (1 << 15)).unwrap(); // JL 1: JSQ3 = IN0, JSQ4 = IN1
        a.write(SMPR2, 0b001 | (0b001 << 3)).unwrap();
        a.write(CR1, SCAN).unwrap();
        a.write(CR2, (JEXTSEL_TIM2_TRGO << 16) | (0b01 << 20) | ADON).unwrap();
        a
    }

    #[test]
    fn tim2s_trgo_converts_f_t_then_f_n_into_jdr1_and_jdr2() {
        let mut a = configured();
        assert_eq!(a.read(SR).unwrap() & JEOC, 0);
        a.input(0, true).unwrap();
        assert_ne!(a.read(SR).unwrap() & JEOC, 0);
        assert_eq!((a.read(JDR1).unwrap(), a.read(JDR1 + 4).unwrap()), (1000, 3000));
        // A missing conversion (a fault) sets no JEOC.
        a.write(SR, 0).unwrap();
        lock(&a.bench).adc_counts = None;
        a.input(0, false).unwrap();
        a.input(0, true).unwrap();
        assert_eq!(a.read(SR).unwrap() & JEOC, 0);
    }

    #[test]
    fn a_wrong_channel_trigger_sampling_time_or_clock_is_an_error_naming_the_register() {
        let cases: [(u32, u32, &str, &str); 6] = [
            (JSQR, (1 << 20) | (5 << 10) | (1 << 15), "ADC1_JSQR", "IN0 (PA0)"),
            (JSQR, (1 << 20) | (1 << 10), "ADC1_JSQR", "in that order"),
            (SMPR2, 0, "ADC1_SMPR2", "3 cycles"),
            (CR1, 0, "ADC1_CR1", "SCAN"),
            (CCR, 0, "ADC1_CCR", "42.0 MHz"),
            (CR2, (0b0100 << 16) | (0b01 << 20) | ADON, "ADC1_CR2", "TIM2's TRGO"),
        ];
        for (reg, value, name, why) in cases {
            let mut a = configured();
            let r = a.write(reg, value).and_then(|()| a.input(0, true));
            let e = r.unwrap_err();
            assert!(e.register.starts_with(name) && e.why.contains(why), "{name} = {value:#x}: {e}");
        }
    }

    #[test]
    fn a_software_start_is_refused_and_adc2_is_not_there() {
        let mut a = configured();
        assert!(a.write(CR2, ADON | (1 << 22)).unwrap_err().why.contains("JSWSTART"));
        assert!(a.read(0x100).unwrap_err().why.contains("ADC2"));
    }
}
