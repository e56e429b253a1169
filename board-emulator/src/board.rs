//! [`EmulatedBoard`]: the unmodified `arm` ELF on the emulated reference
//! board, driven by the simulated arm one control period at a time, as
//! `board_twin::BoardTwin` drives the application: before each tick the board's
//! physics (`board_twin::BoardPhysics`, the same models) set what the devices
//! sense; the machine runs through the tick (TIM2's interrupt: SPI frames to
//! the encoders, the ADC's conversions, the step, the PWM); after it the
//! torques come from TIM3's duty, the direction pins and the enable pin.
//!
//! Time: the machine's clock is the board's. Period `k`'s tick is TIM2's
//! update at `t0 + k Ts`; [`EmulatedBoard::tick`] runs the machine to
//! `t0 + (k + 0.9) Ts`, past the handler and before the next tick, so that
//! what the host sets between two calls is what the next tick samples.

use arm_app::monitor::Monitor;
use board_twin::{ArmState, BoardDescription, BoardPhysics, BusFaults, as5047p::As5047pModel, bench::lock};
use rsemu::core::{space::MemAttrs, value::Width};

use std::sync::Arc;

use crate::{
    accelerator::Acr,
    adc1::Adc1,
    checks::{self, peek},
    core_clock::Mode,
    device::{BoardError, RegisterModel},
    dma2::{Dma2, DmaFaults},
    image::{ArmImage, FLASH_BASE, RECORD_SECTOR},
    machine::{BoardMachine, BuildError, input, out},
    spi1::{Spi1, SpiFaults},
    usart1::Usart1,
};

mod probe;

/// Why the emulated board stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EmuError {
    /// The machine could not be built.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// The board description is invalid.
    #[error("{0}")]
    Board(String),
    /// The image configured a part as the board cannot work with, or used a
    /// register the models do not implement.
    #[error("the image misconfigures the board: {0}")]
    Misconfigured(BoardError),
    /// The image touched an address nothing answers (a bus fault on the part).
    #[error("the image accessed {address:#010x}, where the emulated board has nothing (a bus fault); pc {pc:#010x}")]
    BusFault {
        /// The address.
        address: u32,
        /// The core's program counter when the run stopped.
        pc: u32,
    },
    /// The core locked up (a fault in a fault handler).
    #[error("the core locked up at pc {pc:#010x}")]
    LockedUp {
        /// The program counter.
        pc: u32,
    },
    /// The image did not start its control tick.
    #[error("the image did not start its control tick within {ms} ms of machine time (pc {pc:#010x})")]
    NoTick {
        /// How long was waited.
        ms: u64,
        /// Where the core was.
        pc: u32,
    },
    /// The independent watchdog reset the image.
    #[error("the independent watchdog reset the image (RCC_CSR.IWDGRSTF) before period {period}")]
    WatchdogReset {
        /// The period.
        period: u64,
    },
    /// rsemu refused to go on.
    #[error("the emulator stopped: {0}")]
    Emulator(String),
}

/// The emulated board.
pub struct EmulatedBoard {
    m: BoardMachine,
    physics: BoardPhysics,
    image: ArmImage,
    period_ns: u64,
    /// TIM2's next update (the next tick), ns of machine time.
    next_tick_ns: u64,
    ticks: u64,
    belt: crate::belt::Quadrature,
    rtt: Vec<u8>,
    /// The image's ticks (monitor block) after the last period, to see a reset.
    last_image_ticks: Option<u32>,
    /// SPI1's faults for the next tick ([`EmulatedBoard::set_spi_faults`]).
    pending_spi: SpiFaults,
    /// The image's monitor block as the last run left it (read once a run).
    monitor: Option<Monitor>,
}

/// A fault at the register level that the host injects into the machine
/// (issue 38, "faults at the register level"), beside the devices' faults
/// (`board_twin::BusFaults`) and SPI1's ([`SpiFaults`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegisterFault {
    /// TIM2's update interrupt is lost (DIER.UIE cleared behind the image's
    /// back): no more ticks, no more watchdog feeds; the IWDG must reset the MCU.
    TickLost,
}

/// How far into a period a tick's run goes (a fraction of the period): past
/// the handler (tens of microseconds), a scheduler round (50 us at most: TIM3's
/// 20 kHz) before the next tick.
const RUN_TO: f64 = 0.9;

/// The encoders' chip selects in their ports' `IDR` (docs/board.md "Pin map"):
/// theta1's PA4 (GPIOA), the elbow's PB0 (GPIOB).
const CS_PINS: [u32; 2] = [1 << 4, 1 << 0];

impl EmulatedBoard {
    /// The board `board` running `image`, its settings sector holding
    /// `record_sector` (the bytes of `board_twin::FlashModel`: a record saved,
    /// erased, or damaged), its load cell's noise as the twin's (`seed`,
    /// `load_noise_n`), the control period `period_ns`, the core run in `mode`.
    /// Nothing runs yet. `period_ns` is the period expected until the image
    /// starts its tick; from then on the board runs the period TIM2 is
    /// programmed for ([`EmulatedBoard::period_ns`]: the image's configuration
    /// in force, `arm_app::rate`), and follows the image when it changes it.
    ///
    /// # Errors
    /// [`EmuError::Board`] for a bad description, [`EmuError::Build`].
    pub fn new(
        image: ArmImage,
        board: BoardDescription,
        record_sector: &[u8],
        period_ns: u64,
        seed: u64,
        load_noise_n: f64,
        mode: crate::core_clock::Mode,
    ) -> Result<Self, EmuError> {
        let physics = BoardPhysics::new(board, seed, load_noise_n).map_err(EmuError::Board)?;
        let bench = physics.bench().clone();
        let mut flash = image.flash.clone();
        let record_at = (RECORD_SECTOR - FLASH_BASE) as usize;
        flash.resize(record_at, 0xFF);
        // Up to the record's end: the rest of the sector is erased anyway.
        let used = record_sector.iter().rposition(|&b| b != 0xFF).map_or(0, |i| i + 1);
        flash.extend_from_slice(&record_sector[..used.div_ceil(4) * 4]);
        let models: Vec<(&'static str, Box<dyn RegisterModel>)> = vec![
            ("spi1", Box::new(Spi1::new([As5047pModel::new(bench.clone(), 0), As5047pModel::new(bench.clone(), 1)]))),
            ("adc1", Box::new(Adc1::new(bench))),
            ("usart1", Box::new(Usart1::default())),
        ];
        let m = BoardMachine::build(flash, models, mode)?;
        Ok(Self {
            m,
            physics,
            image,
            period_ns,
            next_tick_ns: 0,
            ticks: 0,
            belt: crate::belt::Quadrature::default(),
            rtt: Vec::new(),
            last_image_ticks: None,
            pending_spi: SpiFaults::default(),
            monitor: None,
        })
    }

    /// Powers the board up with the arm at `arm` and runs the image until its
    /// control tick runs: start-up (clocks, pins, the settings record, the
    /// encoders' check), then TIM2's first update. Returns the machine time of
    /// the next tick, ns.
    ///
    /// # Errors
    /// [`EmuError::NoTick`] when no tick comes within 200 ms; the board's errors.
    pub fn boot(&mut self, arm: &ArmState) -> Result<u64, EmuError> {
        self.physics.sense(arm, &BusFaults::default(), false);
        self.drive_pins();
        let step = 1_000_000;
        let t0 = self.m.now_ns();
        for ms in 1..=200u64 {
            self.run_to(t0 + ms * step)?;
            if self.monitor().is_some() {
                // The image's rate: TIM2 as its configuration programmed it.
                if let Some(p) = self.timer_period_ns() {
                    self.period_ns = p;
                }
                // The tick's phase from TIM2's counter: the last update was CNT
                // timer counts ago.
                let psc = peek(&self.m.machine, 0x4000_0028) + 1;
                let cnt = peek(&self.m.machine, 0x4000_0024);
                let since = u64::from(cnt) * u64::from(psc) * 1_000_000_000 / u64::from(checks::APB1_TIMER_HZ);
                let last = self.m.now_ns() - since;
                if self.m.core.mode() == Mode::Counted {
                    let acr = Acr::from_bits(peek(&self.m.machine, 0x4002_3C00));
                    self.m.core.set_accelerator(acr, Arc::from(self.image.flash.as_slice()));
                }
                // The last update's control step may still be to come (the
                // acquisition's frames, then the pended control interrupt:
                // tens of microseconds, a good part of a 100 us period): run
                // past it as a tick does, so the monitor's count is that
                // update's and the next tick adds exactly one.
                self.run_to(last + (RUN_TO * self.period_ns as f64) as u64)?;
                self.next_tick_ns = last + self.period_ns;
                self.last_image_ticks = self.monitor().map(|m| m.ticks);
                self.check_configuration()?;
                return Ok(self.next_tick_ns);
            }
        }
        Err(EmuError::NoTick { ms: 200, pc: self.m.core.cpu.pc() })
    }

    /// Sets the devices from `arm` and `faults` (load-cell noise when `noisy`),
    /// runs the machine through the next tick, and returns the joint torques
    /// `[u1, u2]` (N m) the drivers make until the next tick.
    ///
    /// # Errors
    /// The board's errors ([`EmuError`]), the watchdog's reset among them.
    pub fn tick(&mut self, arm: &ArmState, faults: &BusFaults, spi: SpiFaults, noisy: bool) -> Result<[f64; 2], EmuError> {
        self.physics.sense(arm, faults, noisy);
        self.drive_pins();
        let pending = std::mem::take(&mut self.pending_spi);
        let spi = SpiFaults { overrun: spi.overrun || pending.overrun, mode_fault: spi.mode_fault || pending.mode_fault };
        if let Some(w) = self.m.hub.window("spi1") {
            w.with(|m| {
                if let Some(s) = as_spi(m) {
                    s.faults = spi;
                }
            });
        }
        // The acquisition's faults (the twin's `BusFaults::acquisition`) on
        // DMA2's next transfer; a stuck chip select in GPIO's IDR (theta1's
        // PA4, the elbow's PB0: the image reads the pin back after each
        // release), the acquisition's `StuckChipSelect` being theta1's.
        use arm_app::AcquisitionFault as F;
        let dma = match faults.acquisition {
            Some(F::TransferError) => DmaFaults { transfer_error: true, ..DmaFaults::default() },
            Some(F::FifoError) => DmaFaults { fifo_error: true, ..DmaFaults::default() },
            Some(F::DirectModeError) => DmaFaults { direct_mode_error: true, ..DmaFaults::default() },
            Some(F::Timeout) => DmaFaults { stall: true, ..DmaFaults::default() },
            Some(F::StuckChipSelect) | None => DmaFaults::default(),
        };
        let cs =
            [faults.encoders[0].chip_select_stuck || faults.acquisition == Some(F::StuckChipSelect), faults.encoders[1].chip_select_stuck];
        self.m.stuck_low.set(if cs[0] { CS_PINS[0] } else { 0 }, if cs[1] { CS_PINS[1] } else { 0 });
        if let Some(w) = self.m.hub.window("dma2") {
            w.with(|m| {
                if let Some(d) = (m as &mut dyn std::any::Any).downcast_mut::<Dma2>() {
                    d.faults = dma;
                }
            });
        }
        let target = lock(self.physics.bench()).belt_count;
        let next_tick = self.next_tick_ns * u64::from(checks::SYSCLK_HZ) / 1_000_000_000;
        self.belt.drive_to(&mut self.m, target, next_tick).map_err(|e| match e {
            crate::belt::BeltError::Emulator(m) => EmuError::Emulator(m),
            too_fast => EmuError::Board(too_fast.to_string()),
        })?;
        let to = self.next_tick_ns + (RUN_TO * self.period_ns as f64) as u64;
        self.run_to(to)?;
        // A reset: RCC_CSR's watchdog flag (until the image takes it at boot),
        // or the monitor block's ticks going back (the image zeroes it at start-up).
        let ticks = self.monitor().map(|m| m.ticks);
        let went_back = match (self.last_image_ticks, ticks) {
            (Some(last), Some(now)) => now < last,
            (Some(_), None) => true,
            _ => false,
        };
        if went_back || peek(&self.m.machine, 0x4002_3874) & (1 << 29) != 0 {
            self.last_image_ticks = None;
            return Err(EmuError::WatchdogReset { period: self.ticks });
        }
        self.last_image_ticks = ticks;
        if let Some(p) = self.timer_period_ns()
            && p != self.period_ns
        {
            // The image retimed its tick in this period (a `Configure` of
            // another rate, served by its idle loop: TIM2 restarted with the new
            // reload): the next tick from TIM2's counter, as at boot.
            self.period_ns = p;
            let psc = peek(&self.m.machine, 0x4000_0028) + 1;
            let cnt = peek(&self.m.machine, 0x4000_0024);
            let since = u64::from(cnt) * u64::from(psc) * 1_000_000_000 / u64::from(checks::APB1_TIMER_HZ);
            self.next_tick_ns = self.m.now_ns() - since;
        }
        self.next_tick_ns += self.period_ns;
        self.ticks += 1;
        if self.ticks % 1000 == 1 {
            self.check_configuration()?;
        }
        Ok(self.torques())
    }

    /// The control period the board runs, ns: TIM2's update period as the
    /// image programmed it once its tick started (else the period given to
    /// [`EmulatedBoard::new`]).
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// TIM2's update period, ns: `(PSC + 1) (ARR + 1)` counts of APB1's timer
    /// clock (RM0090 18.3.1, 84 MHz), `None` while TIM2 is stopped.
    fn timer_period_ns(&self) -> Option<u64> {
        let m = &self.m.machine;
        if peek(m, 0x4000_0000) & 1 == 0 {
            return None;
        }
        let counts = (u64::from(peek(m, 0x4000_0028)) + 1) * (u64::from(peek(m, 0x4000_002C)) + 1);
        Some(counts * 1_000_000_000 / u64::from(checks::APB1_TIMER_HZ))
    }

    /// The torques from TIM3's duty, the direction pins and the enable pin.
    fn torques(&mut self) -> [f64; 2] {
        let mm = &self.m.machine;
        let arr = peek(mm, 0x4000_042C);
        let max_duty = (arr + 1).min(u32::from(u16::MAX)) as u16;
        let duty = [peek(mm, 0x4000_0434), peek(mm, 0x4000_0438)].map(|c| c.min(u32::from(max_duty)) as u16);
        let pins = self.m.hub.pins();
        let level = |l| pins.as_ref().is_some_and(|p| p.level(l));
        {
            let mut b = lock(self.physics.bench());
            b.outputs.duty = duty;
            b.outputs.dir_high = [level(input::DIR1), level(input::DIR2)];
            b.outputs.enable = level(input::ENABLE);
        }
        self.physics.torques(max_duty)
    }

    /// Drives the fault line and the button from the bench.
    fn drive_pins(&self) {
        let (fault, held) = {
            let b = lock(self.physics.bench());
            (b.driver_fault, b.button_held)
        };
        if let Some(p) = self.m.hub.pins() {
            p.drive(out::FAULT, !fault);
            p.drive(out::BUTTON, !held);
        }
    }

    fn run_to(&mut self, ns: u64) -> Result<(), EmuError> {
        // The counted core runs no live positions: its scheduler's rounds end
        // on their own grid and events (TIM3's 20 kHz update among them, up to
        // 50 us apart), and a whole round past `ns` would run into the next
        // tick at a 100 us period. Cut there (issue 56). The functional core
        // keeps whole rounds: alone runnable, with live positions, its runs end
        // before the next tick at 10 kHz (the link's one-tick-a-period check).
        match self.m.core.mode() {
            Mode::Functional => self.m.run_until(ns),
            Mode::Counted => self.m.step_until(ns),
        }
        .map_err(EmuError::Emulator)?;
        self.drain_rtt();
        self.monitor = self.read_monitor();
        if let Some(e) = self.m.errors.first() {
            return Err(EmuError::Misconfigured(e));
        }
        let (faults, address) = self.m.core.cpu.bus_faults();
        if faults > 0 {
            return Err(EmuError::BusFault { address, pc: self.m.core.cpu.pc() });
        }
        if self.m.core.cpu.is_locked_up() {
            return Err(EmuError::LockedUp { pc: self.m.core.cpu.pc() });
        }
        Ok(())
    }

    fn check_configuration(&self) -> Result<(), EmuError> {
        let m = &self.m.machine;
        let period_s = self.period_ns as f64 * 1e-9;
        checks::clock_tree(m)
            .and_then(|()| checks::pins(m))
            .and_then(|()| checks::timers(m, 1.0 / period_s))
            .and_then(|()| checks::watchdog(m, period_s))
            .map_err(EmuError::Misconfigured)
    }

    /// The reset button (NRST) pressed and released: every device returns to
    /// its reset state but the flash, whose array survives (rsemu's `Warm`
    /// reset), the core's NVIC and system control block with them (a system
    /// reset: `core_clock::Core`'s reset); the image starts again from its
    /// vector table, loads its record from the emulated flash, and is booted
    /// as [`EmulatedBoard::boot`] does.
    /// SRAM keeps its content on the part; the monitor block's magic is
    /// cleared first so that the boot waits for the new image's first tick.
    ///
    /// # Errors
    /// As [`EmulatedBoard::boot`].
    pub fn reset(&mut self, arm: &ArmState) -> Result<u64, EmuError> {
        if let Some(space) = self.m.machine.space("mem") {
            let _ = space.write(u64::from(self.image.monitor), Width::U32, 0, MemAttrs::DEBUG);
        }
        self.m.machine.reset(rsemu::core::device::ResetKind::Warm);
        self.monitor = None;
        self.last_image_ticks = None;
        self.boot(arm)
    }

    /// SPI1's faults for the next tick only.
    pub fn set_spi_faults(&mut self, faults: SpiFaults) {
        self.pending_spi = faults;
    }

    /// Injects `fault` now.
    pub fn inject(&mut self, fault: RegisterFault) {
        let Some(space) = self.m.machine.space("mem") else { return };
        match fault {
            // A bus master's write (not a debugger's): TIM2_DIER = 0.
            RegisterFault::TickLost => {
                let _ = space.write(0x4000_000C, Width::U32, 0, MemAttrs::default());
            }
        }
    }

    /// Runs the machine for `ns` without touching the devices (a stalled or
    /// resetting image), then, when the image ticks again, realigns the next
    /// tick. Returns whether it ticks.
    ///
    /// # Errors
    /// The board's errors but a watchdog reset (which is what this waits through).
    pub fn run_for(&mut self, ns: u64) -> Result<bool, EmuError> {
        let to = self.m.now_ns() + ns;
        self.run_to(to)?;
        self.last_image_ticks = self.monitor().map(|m| m.ticks);
        if self.last_image_ticks.is_none() {
            return Ok(false);
        }
        let psc = peek(&self.m.machine, 0x4000_0028) + 1;
        let cnt = peek(&self.m.machine, 0x4000_0024);
        let since = u64::from(cnt) * u64::from(psc) * 1_000_000_000 / u64::from(checks::APB1_TIMER_HZ);
        self.next_tick_ns = self.m.now_ns() - since + self.period_ns;
        Ok(peek(&self.m.machine, 0x4000_000C) & 1 != 0)
    }

    /// Holds the enable button (`true`) or lets it go, from the next tick on.
    pub fn hold_button(&mut self, held: bool) {
        self.physics.hold_button(held);
    }

    /// The machine's time, ns.
    pub fn now_ns(&self) -> u64 {
        self.m.now_ns()
    }

    /// Runs the machine to `ns`, cutting the scheduler's round there (a debugger's step).
    ///
    /// # Errors
    /// rsemu's, in words.
    pub fn step_to(&mut self, ns: u64) -> Result<(), String> {
        self.m.step_until(ns)?;
        self.monitor = self.read_monitor();
        Ok(())
    }

    /// The rsemu machine (a debugger's reads: `checks::peek`).
    pub fn machine(&self) -> &rsemu::machine::Machine {
        &self.m.machine
    }

    /// Every configuration or sequence error the board's models found so far
    /// (the run stops at the first: [`EmuError::Misconfigured`]).
    pub fn board_errors(&self) -> Vec<BoardError> {
        self.m.errors.all()
    }

    /// The wrapped core.
    pub fn core(&self) -> &crate::core_clock::Core {
        &self.m.core
    }

    /// Periods run since boot.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// The board description.
    pub fn board(&self) -> &BoardDescription {
        self.physics.board()
    }
}

fn as_spi(m: &mut dyn RegisterModel) -> Option<&mut Spi1> {
    (m as &mut dyn std::any::Any).downcast_mut()
}
