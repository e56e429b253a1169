//! The emulated reference board as an rsemu machine: rsemu's STM32F407
//! description (the F405's die and memory map: the Cortex-M4F core with its
//! NVIC and DWT, RCC, flash and its interface, SRAM, TIM1 to TIM14, GPIO, IWDG)
//! from its catalog, with our own parts added in the machine's language: SPI1,
//! ADC1 and USART1 ([`crate::spi1`], [`crate::adc1`], [`crate::usart1`]), the
//! board's side of the pins ([`crate::device::PinsDevice`]), and the wires
//! between them as the board's copper runs (docs/board.md "Pin map"). Every
//! access to an address nothing answers is logged (`log-unassigned`) and is a
//! bus fault in the image, as on the part.

use std::sync::Arc;

use rsemu::{
    core::clock::GlobalTime,
    machine::{Machine, catalog},
};

use crate::{
    core_clock::{self, Core, Mode},
    device::{self, ErrorLog, Hub, PIN_LINES},
};

/// The board's wires from our parts to rsemu's, in its machine language.
const BOARD: &str = r#"
  # ---- the painleve reference board (board-emulator/src/machine.rs) ----
  object spi1   "painleve.regs" { role = "spi1" }
  object adc1   "painleve.regs" { role = "adc1" }
  object usart1 "painleve.regs" { role = "usart1" }
  object dma2   "painleve.regs" { role = "dma2" }
  object board  "painleve.pins" { }
  map mem apb2-base + 0x3000 size 0x400 = spi1
  map mem apb2-base + 0x2000 size 0x400 = adc1
  map mem apb2-base + 0x1000 size 0x400 = usart1
  map mem ahb1-base + 0x6400 size 0x400 = dma2
  wire spi1.irq   -> cpu.irq35      # SPI1
  wire adc1.irq   -> cpu.irq18      # ADC
  wire usart1.irq -> cpu.irq37      # USART1
  wire dma2.irq   -> cpu.irq56      # DMA2_Stream0: SPI1_RX's frame ends
  wire tim2.trgo  -> adc1.in0       # the control tick starts the injected conversions
  wire gpioa.p4   -> spi1.in0       # PA4: the theta1 encoder's CSn
  wire gpiob.p0   -> spi1.in1       # PB0: the elbow encoder's CSn
  wire gpiob.p12  -> board.in0      # PB12: motor 1's direction
  wire gpiob.p13  -> board.in1      # PB13: motor 2's direction
  wire gpiob.p14  -> board.in2      # PB14: the drivers' enable
  wire board.out0 -> gpiob.in15     # PB15: the drivers' nFAULT (pulled up)
  wire board.out1 -> gpioc.in13     # PC13: the enable button (pulled up)
  wire board.out2 -> tim4.ti1       # PB6: the belt encoder's A
  wire board.out3 -> tim4.ti2       # PB7: the belt encoder's B
}
"#;

/// The objects of rsemu's STM32F407 description the image never uses, left
/// out of the machine: each lazily advanced device costs every scheduler round
/// a synchronisation (a fifth of the run's time with all fourteen timers). An
/// access to one is then an access where the board has nothing: an error with
/// its address, as for any other unused address. Besides the unused timers and
/// watchdog and the RTC: the evaluation board's I2C1 with its EEPROM, NFC tag
/// and secure element, the SD slot, USART2's console, the keypad on GPIOE and
/// the RNG (the reference board has none of them: docs/hardware.md).
pub const LEFT_OUT: [&str; 21] = [
    "tim1", "tim5", "tim6", "tim7", "tim8", "tim9", "tim10", "tim11", "tim12", "tim13", "tim14", "wwdg", "rtc", "i2c1", "eeprom", "nfc",
    "atecc", "sdio", "usart2", "keypad", "rng",
];

/// The event wheel's granule, in bits of rsemu's `GlobalTime` (2^-64 s): 2^-20 s,
/// about 0.95 us. rsemu's default (32 bits: 0.23 ns) made each scheduler round,
/// a few microseconds of the board's time, sweep the wheel's 256 level-0 slots and
/// a hundred of level 1's: 14 000 host instructions a round, 166 rounds a period,
/// a seventh of the emulated board's run (callgrind, issue 85). The granule only
/// buckets the queue: events come due by their exact time and sequence whatever
/// it is (rsemu's `EventQueue`: an event in the current granule waits in the
/// ordered `due` heap until its instant), so every trace is the same bits (the
/// emulator's tests against the board twin).
pub const GRANULE_SHIFT: u32 = 44;

/// The objects of rsemu's description the board replaces with its own model:
/// DMA2 ([`crate::dma2`], strict, reaching SPI1's model).
pub const REPLACED: [&str; 1] = ["dma2"];

/// The description without the objects of [`LEFT_OUT`] and [`REPLACED`]: their
/// `object` blocks (one line, or the lines to the block's closing brace) and
/// every `map` and `wire` line naming one.
fn without_unused(text: &str) -> String {
    let names = |line: &str| -> bool {
        let t = line.trim_start();
        if !(t.starts_with("object ") || t.starts_with("map ") || t.starts_with("wire ")) {
            return false;
        }
        let code = t.split('#').next().unwrap_or("");
        code.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-' || c == '_')).any(|w| LEFT_OUT.contains(&w) || REPLACED.contains(&w))
    };
    let braces = |line: &str| -> i64 {
        let code = line.split('#').next().unwrap_or("");
        code.matches('{').count() as i64 - code.matches('}').count() as i64
    };
    let mut out = String::with_capacity(text.len());
    // The depth of the object block being left out (0: none).
    let mut skipping = 0;
    for line in text.lines() {
        if skipping > 0 {
            skipping += braces(line);
            continue;
        }
        if names(line) {
            skipping = braces(line).max(0);
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// The interrupt lines `text` wires to the core (`wire ... -> cpu.irqN`, the
/// objects left out already gone): the only lines a device of the machine can
/// assert.
fn wired_irqs(text: &str) -> Vec<u16> {
    text.lines()
        .filter_map(|l| l.split('#').next())
        .filter(|l| l.trim_start().starts_with("wire "))
        .filter_map(|l| l.split("-> cpu.irq").nth(1))
        .filter_map(|rest| rest.trim_start().split(|c: char| !c.is_ascii_digit()).next()?.parse().ok())
        .collect()
}

/// The pins device's output lines.
pub mod out {
    /// The drivers' nFAULT (high: no fault).
    pub const FAULT: usize = 0;
    /// The enable button (high: released).
    pub const BUTTON: usize = 1;
    /// The belt encoder's A.
    pub const BELT_A: usize = 2;
    /// The belt encoder's B.
    pub const BELT_B: usize = 3;
}

/// The pins device's input lines.
pub mod input {
    /// Motor 1's direction pin.
    pub const DIR1: usize = 0;
    /// Motor 2's direction pin.
    pub const DIR2: usize = 1;
    /// The drivers' enable pin.
    pub const ENABLE: usize = 2;
}

/// Why the machine was not built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the emulated board could not be built: {0}")]
pub struct BuildError(pub String);

/// The machine and the handles the host drives it by.
pub struct BoardMachine {
    /// rsemu's machine.
    pub machine: Machine,
    /// The core, wrapped (sleep skipping, the handler's instructions).
    pub core: Arc<Core>,
    /// Our parts, by role.
    pub hub: Arc<Hub>,
    /// What the parts found wrong.
    pub errors: ErrorLog,
    /// The GPIO pins the host makes read low in `IDR` (a stuck chip select).
    pub stuck_low: crate::widen::StuckLow,
}

impl BoardMachine {
    /// Builds the board with `flash` as the flash's content from `0x0800_0000`
    /// and `models` offered under their roles (`spi1`, `adc1`, `usart1`), the
    /// core run in `mode`.
    ///
    /// # Errors
    /// [`BuildError`] with rsemu's message.
    pub fn build(flash: Vec<u8>, models: Vec<(&'static str, Box<dyn device::RegisterModel>)>, mode: Mode) -> Result<Self, BuildError> {
        let e = |x: rsemu::core::error::Error| BuildError(x.to_string());
        let entry = catalog::machine("stm32f407").ok_or_else(|| BuildError("rsemu has no stm32f407 machine in this build".into()))?;
        let mut text = entry.source.to_string();
        text = text.replacen("space mem    { width = 32 }", "space mem    { width = 32, log-unassigned = true }", 1);
        let end = text.rfind('}').ok_or_else(|| BuildError("the stm32f407 description has no closing brace".into()))?;
        text.truncate(end);
        let mut text = without_unused(&text);
        text.push_str(BOARD);
        let errors = ErrorLog::default();
        let mut idle = [false; PIN_LINES];
        idle[out::FAULT] = true;
        idle[out::BUTTON] = true;
        let hub = Arc::new(Hub::new(errors.clone(), idle));
        hub.offer("dma2", Box::new(crate::dma2::Dma2::new(Arc::downgrade(&hub))));
        for (role, m) in models {
            hub.offer(role, m);
        }
        let mut reg = catalog::registry().map_err(e)?;
        let mut opts = catalog::build_options().map_err(e)?;
        let slot = core_clock::bind(&mut opts.bindings, mode);
        crate::widen::widen_class(&mut opts.bindings, "st.iwdg");
        crate::widen::check_flash_class(&mut opts.bindings, "st.flash", errors.clone());
        let stuck_low = crate::widen::StuckLow::default();
        crate::widen::stuck_low_class(&mut opts.bindings, "st.gpio", stuck_low.clone());
        if mode == Mode::Functional {
            // The core alone runnable on its crystal: rsemu then arms live
            // positions (the belt's edges need them). DMA1 is unused; DMA2 is
            // the board's own model (`crate::dma2`), which moves a frame at once.
            crate::widen::not_runnable_class(&mut opts.bindings, "st.dma");
        }
        device::install(&mut reg, &mut opts.bindings, &mut opts.classes, Arc::clone(&hub)).map_err(e)?;
        opts.realize.media.insert("firmware", flash);
        opts.realize.scheduler.granule_shift = GRANULE_SHIFT;
        let machine = rsemu::machine::build("painleve-f405.machine", &text, &reg, &opts).map_err(e)?;
        let core =
            slot.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone().ok_or_else(|| BuildError("no core was built".into()))?;
        core.set_wired_irqs(wired_irqs(&text));
        if !stuck_low.wraps_both_ports() {
            return Err(BuildError("GPIOA and GPIOB were not told apart by their MODER reset values (crate::widen::StuckLow)".into()));
        }
        Ok(Self { machine, core, hub, errors, stuck_low })
    }

    /// The machine's time, ns.
    pub fn now_ns(&self) -> u64 {
        self.machine.now().as_nanos()
    }

    /// Runs the machine to `ns` of machine time, cutting the scheduler's
    /// round there (rsemu's `step_until`: for host events between rounds).
    ///
    /// # Errors
    /// rsemu's, in words.
    pub fn step_until(&mut self, ns: u64) -> Result<(), String> {
        self.machine.step_until(GlobalTime::from_nanos(ns)).map_err(|e| e.to_string())
    }

    /// Runs the machine until `ns` of machine time.
    ///
    /// # Errors
    /// rsemu's, in words.
    pub fn run_until(&mut self, ns: u64) -> Result<(), String> {
        self.machine.run_until(GlobalTime::from_nanos(ns)).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wired_lines_are_the_descriptions_cpu_irq_wires_without_the_objects_left_out() {
        let entry = rsemu::machine::catalog::machine("stm32f407").expect("rsemu's stm32f407");
        let full = wired_irqs(entry.source);
        let kept = wired_irqs(&(without_unused(entry.source) + BOARD));
        // USART2 (38), SDIO (49) and the RNG (80) are left out; the board's own SPI1,
        // ADC, USART1 and DMA2 stream 0 are wired.
        for line in [38, 49, 80] {
            assert!(full.contains(&line) && !kept.contains(&line), "{line}: {full:?} {kept:?}");
        }
        for line in [35, 18, 37, 56, 28, 30] {
            assert!(kept.contains(&line), "{line}: {kept:?}");
        }
        assert_eq!(wired_irqs("  wire tim2.irq -> cpu.irq28  # TIM2\n# wire x.irq -> cpu.irq3\nmap mem 0 = cpu.irq9"), [28]);
    }
}
