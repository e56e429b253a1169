//! The arm image: the controller on the arm (docs/hardware.md "Reference board").
//!
//! TIM2's update interrupt at the control rate runs one period: the sensors
//! are sampled at the tick (encoders over SPI1, the load cell's conversions
//! that the tick itself started, the belt's quadrature count), the firmware
//! steps through `firmware::board::handle`, the torques are written to the
//! PWM, and the independent watchdog is fed. The safe state disables the
//! drivers. A reset (or a watchdog reset) comes up with them disabled until the
//! enable button (PC13 to ground, held 20 ms) resets the firmware; they are
//! enabled at the next command that is not the safe state.
//!
//! The step's cycles (DWT `CYCCNT` on silicon) are reported per window of
//! `step_stats::WINDOW` periods, worst and median, with the tick's interval
//! spread and the stack's high-water mark: in the defmt log and as telemetry
//! on USART1 TX (`board_stm32f405::telemetry::ArmTelemetry`, PIL framing).
//!
//! Under QEMU (feature `qemu`) the image runs `QEMU_PERIODS` periods and exits;
//! QEMU models no encoder, load cell or belt: the frames are invalid and the
//! firmware goes to its safe state (bad frames) with the drivers disabled.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "`arm` is the Cortex-M4F image for the arm: `cargo run -p board-stm32f405 --release --target thumbv7em-none-eabihf --bin arm` (docs/board.md)"
    );
}

#[cfg(target_os = "none")]
mod image {
    use core::cell::{Cell, RefCell};

    use board_stm32f405::{
        calibration,
        clock_tree::ClockOutcome,
        mcu::{
            self, adc,
            cycles::CycleClock,
            exit,
            gpio::{self, GpioPin},
            iwdg, rcc, spi, stack,
            timers::{self, BeltCounter, PwmChannel},
            usart,
        },
        pins,
        step_stats::StepStats,
        telemetry::ArmTelemetry,
        timing::{TIM2_CLOCK_HZ, TickTimer},
    };
    use cortex_m::interrupt::Mutex;
    use cortex_m_rt::entry;
    use drivers::{
        as5047p::As5047p,
        belt::BeltEncoder,
        frame::{self, Readings},
        load_cell::LoadCell,
        motor::{Motor, MotorStage},
    };
    use firmware::{
        Config, Event, Firmware, Outcome, SafeReason, TickClock,
        board::{self, Board},
        pil::{self, MAX_FRAME},
    };
    use shared::wire::{frame_flags, status};
    use stm32f4::stm32f405::{Interrupt, interrupt};

    /// Periods the QEMU build runs before it exits (3 windows).
    const QEMU_PERIODS: u32 = 3 * board_stm32f405::step_stats::WINDOW;
    /// Periods the button must read pressed (20 ms at 1 kHz).
    const BUTTON_PERIODS: u16 = 20;
    /// QEMU's timer clock for TIM2 to TIM5, Hz: the emulator has no RCC and
    /// clocks its timers at a fixed rate (measured: docs/board.md).
    const QEMU_TIMER_HZ: u32 = board_stm32f405::timing::QEMU_TIMER_HZ;

    type Encoder = As5047p<spi::Spi1Device>;
    type Motors = MotorStage<PwmChannel, GpioPin, PwmChannel, GpioPin, GpioPin, GpioPin>;

    /// Everything the control interrupt owns.
    struct Arm {
        board: ArmBoard,
        firmware: Option<Firmware>,
    }

    struct ArmBoard {
        clock: CycleClock,
        theta1: Encoder,
        elbow: Encoder,
        load: LoadCell<adc::LoadCellAdc>,
        belt: BeltEncoder<BeltCounter>,
        motors: Motors,
        button_low: u16,
        button_released: bool,
        reset_pending: bool,
        enable_requested: bool,
        period_us: u64,
        seq: u32,
        tick_mark: u32,
        now_us: u64,
        interval: [u32; 2],
        handler_worst: u32,
        stats: StepStats,
        invalid_logged: u16,
        safe_logged: bool,
    }

    static ARM: Mutex<RefCell<Option<Arm>>> = Mutex::new(RefCell::new(None));
    static REPORT: Mutex<Cell<Option<ArmTelemetry>>> = Mutex::new(Cell::new(None));

    impl ArmBoard {
        /// Samples every sensor now (the tick): the frame of period `seq`.
        fn sample(&mut self) -> shared::wire::SensorFrame {
            let readings = Readings {
                theta1_raw: self.theta1.sample().ok(),
                elbow_raw: self.elbow.sample().ok(),
                load_codes: match self.load.read_codes() {
                    Ok([t, n]) => [Some(t), Some(n)],
                    Err(_) => [None, None],
                },
                belt_mm_s: self.belt.speed_mm_s().ok(),
                driver_fault: self.motors.fault_asserted().ok(),
            };
            let f = frame::assemble(self.seq as u64 * self.period_us, self.seq, readings, &calibration::ENCODERS);
            let invalid = f.flags & frame_flags::ANY_INVALID;
            if invalid != self.invalid_logged {
                if invalid == 0 {
                    defmt::info!("period {=u32}: every sensor reads again", self.seq);
                } else {
                    defmt::warn!(
                        "period {=u32}: invalid readings (frame flags {=u16:#x}: theta1 {=bool}, elbow {=bool}, f_t {=bool}, f_n {=bool}, belt {=bool}, driver fault {=bool})",
                        self.seq,
                        invalid,
                        invalid & frame_flags::THETA1_INVALID != 0,
                        invalid & frame_flags::ELBOW_INVALID != 0,
                        invalid & frame_flags::F_T_INVALID != 0,
                        invalid & frame_flags::F_N_INVALID != 0,
                        invalid & frame_flags::BELT_INVALID != 0,
                        invalid & frame_flags::DRIVER_FAULT != 0
                    );
                }
                self.invalid_logged = invalid;
            }
            f
        }

        /// A press: low for [`BUTTON_PERIODS`] after having been seen released
        /// (a button stuck low, or a pin QEMU does not model, never presses).
        fn button_pressed(&mut self) -> bool {
            if gpio::read(&pins::ENABLE_BUTTON) {
                self.button_low = 0;
                self.button_released = true;
                return false;
            }
            if !self.button_released {
                return false;
            }
            self.button_low = self.button_low.saturating_add(1);
            if self.button_low == BUTTON_PERIODS {
                self.button_released = false;
                return true;
            }
            false
        }
    }

    impl Board for ArmBoard {
        type Error = core::convert::Infallible;

        fn next_event(&mut self) -> Result<Event, Self::Error> {
            if core::mem::take(&mut self.reset_pending) {
                return Ok(Event::Reset);
            }
            let frame = self.sample();
            // The step starts now: the tick plus the sampling.
            let us = self.clock.ticks().wrapping_sub(self.tick_mark) / (self.clock.ticks_per_second() / 1_000_000);
            self.now_us = frame.t_us + u64::from(us);
            Ok(Event::Frame(frame))
        }

        fn now_us(&self) -> u64 {
            self.now_us
        }

        fn apply(&mut self, outcome: &Outcome, fw: Option<&Firmware>) -> Result<(), Self::Error> {
            match outcome {
                Outcome::Command(c) => {
                    if c.status & status::SAFE_STATE != 0 {
                        if self.motors.disable().is_err() {
                            defmt::error!("the drivers did not disable");
                        }
                        self.enable_requested = false;
                        if !self.safe_logged {
                            let reason = SafeReason::from_status(c.status).map_or(0, |r| r as u8);
                            defmt::error!(
                                "period {=u32}: safe state (reason {=u8}: 1 deadline misses, 2 bad frames, 3 non-finite, 4 singular, 5 unreachable, 6 peer lost, 7 sensor fault): drivers disabled; press the enable button to reset",
                                c.seq,
                                reason
                            );
                            self.safe_logged = true;
                        }
                    } else if core::mem::take(&mut self.enable_requested) {
                        match self.motors.enable() {
                            Ok(()) => defmt::info!("period {=u32}: drivers enabled", c.seq),
                            Err(_) => defmt::error!("period {=u32}: the drivers refuse to enable (fault line asserted)", c.seq),
                        }
                    }
                    // Disabled drivers get zero duty whatever the codes.
                    let _ = self.motors.apply([c.u1_code, c.u2_code]);
                    iwdg::feed();
                    if let Some(step) = self.stats.record(c.step_ticks) {
                        let report = ArmTelemetry {
                            seq: c.seq,
                            status: c.status,
                            overruns: fw.map_or(0, Firmware::overruns),
                            drivers_enabled: self.motors.is_enabled(),
                            clock: self.clock.kind(),
                            step,
                            tick_interval: self.interval,
                            handler_worst: self.handler_worst,
                            // Filled in by the idle loop: scanning the stack takes too long here.
                            stack_high_water_bytes: 0,
                        };
                        defmt::info!(
                            "period {=u32}: step ticks median {=u32} worst {=u32} over {=u32}; tick interval {=u32}..{=u32} ticks; handler worst {=u32} ticks; overruns {=u32}; drivers {=str}",
                            c.seq,
                            step.median,
                            step.worst,
                            step.steps,
                            self.interval[0],
                            self.interval[1],
                            self.handler_worst,
                            report.overruns,
                            if report.drivers_enabled { "enabled" } else { "disabled" }
                        );
                        cortex_m::interrupt::free(|cs| REPORT.borrow(cs).set(Some(report)));
                        self.interval = [u32::MAX, 0];
                        self.handler_worst = 0;
                    }
                }
                Outcome::Reset => {
                    defmt::info!("enable button: firmware reset; the drivers enable at the next command");
                    self.enable_requested = true;
                    self.safe_logged = false;
                }
                _ => {}
            }
            Ok(())
        }
    }

    impl Arm {
        /// One control period (in TIM2's interrupt).
        fn tick(&mut self) {
            let b = &mut self.board;
            let interval = b.clock.ticks().wrapping_sub(b.tick_mark);
            b.tick_mark = b.clock.mark();
            if b.seq > 0 {
                b.interval = [b.interval[0].min(interval), b.interval[1].max(interval)];
            }
            if b.button_pressed() {
                b.reset_pending = true;
            }
            let clock = b.clock;
            loop {
                let Ok(event) = b.next_event();
                let _ = board::handle(&mut self.firmware, event, b, &clock);
                if matches!(event, Event::Frame(_)) {
                    break;
                }
            }
            b.seq = b.seq.wrapping_add(1);
            b.handler_worst = b.handler_worst.max(b.clock.ticks().wrapping_sub(b.tick_mark));
        }
    }

    #[interrupt]
    fn TIM2() {
        if !timers::take_tick() {
            return;
        }
        cortex_m::interrupt::free(|cs| {
            if let Some(arm) = ARM.borrow(cs).borrow_mut().as_mut() {
                arm.tick();
            }
        });
    }

    #[entry]
    fn main() -> ! {
        let Some(mut core) = cortex_m::Peripherals::take() else {
            defmt::error!("core peripherals already taken");
            exit::exit(2);
        };
        let (clocks, clock) = mcu::start(&mut core);
        let watchdog_reset = rcc::take_watchdog_reset_flag();
        // The drivers first: disabled, before anything can fail.
        let m1 = Motor::new(PwmChannel(0), GpioPin(pins::DIR_U1));
        let m2 = Motor::new(PwmChannel(1), GpioPin(pins::DIR_U2));
        for p in [pins::DIR_U1, pins::DIR_U2, pins::DRIVER_ENABLE, pins::DRIVER_FAULT, pins::ENABLE_BUTTON] {
            gpio::configure(&p);
        }
        let timer_hz = match clocks {
            ClockOutcome::Pll { .. } => TIM2_CLOCK_HZ,
            ClockOutcome::NoClockModel => QEMU_TIMER_HZ,
        };
        timers::start_pwm(timer_hz);
        let Ok(motors) = MotorStage::new(m1, m2, GpioPin(pins::DRIVER_ENABLE), GpioPin(pins::DRIVER_FAULT)) else {
            defmt::error!("the motor stage did not come up disabled");
            exit::exit(3);
        };
        if watchdog_reset {
            defmt::warn!("reset by the watchdog (a step hung): drivers disabled until the enable button");
        }
        let cfg = Config::default();
        let Ok(fw) = Firmware::new(cfg) else {
            defmt::error!("invalid firmware configuration");
            exit::exit(2);
        };
        let tick = match TickTimer::for_period(timer_hz, cfg.period) {
            Ok(t) => t,
            Err(e) => {
                defmt::error!("control rate: {}", e);
                exit::exit(2);
            }
        };
        spi::init();
        adc::init();
        timers::start_belt_encoder();
        usart::init(false);
        let mut theta1 = As5047p::new(spi::Spi1Device::new(pins::CS_THETA1));
        let mut elbow = As5047p::new(spi::Spi1Device::new(pins::CS_ELBOW));
        for (name, enc) in [("theta1", &mut theta1), ("elbow", &mut elbow)] {
            match enc.check_ready() {
                Ok(d) => defmt::info!("encoder {=str}: ready, AGC {=u8}", name, d.agc),
                Err(e) => defmt::error!("encoder {=str}: not ready ({=str}): its readings will be invalid", name, encoder_error(&e)),
            }
        }
        let Ok(load) = LoadCell::new(adc::LoadCellAdc, calibration::LOAD_CELL) else {
            defmt::error!("invalid load-cell calibration");
            exit::exit(2);
        };
        let Ok(belt) = BeltEncoder::new(BeltCounter, calibration::BELT_METRES_PER_COUNT, cfg.period.as_secs_f32()) else {
            defmt::error!("invalid belt calibration");
            exit::exit(2);
        };
        let period_us = cfg.period.as_us();
        let board = ArmBoard {
            clock,
            theta1,
            elbow,
            load,
            belt,
            motors,
            button_low: 0,
            button_released: false,
            reset_pending: false,
            enable_requested: false,
            period_us,
            seq: 0,
            tick_mark: clock.mark(),
            now_us: 0,
            interval: [u32::MAX, 0],
            handler_worst: 0,
            stats: StepStats::default(),
            invalid_logged: 0,
            safe_logged: false,
        };
        cortex_m::interrupt::free(|cs| ARM.borrow(cs).replace(Some(Arm { board, firmware: Some(fw) })));
        defmt::info!(
            "arm image up: {=u64} us control period (TIM2 psc {=u16} arr {=u16} from {=u32} Hz), step clock {=str}, drivers disabled until the enable button",
            period_us,
            tick.psc,
            tick.arr,
            timer_hz,
            match clock.kind() {
                pil::StepClock::DwtCycles => "DWT cycles",
                pil::StepClock::EmulatedSysTick => "SysTick (emulated: instructions)",
            }
        );
        iwdg::start(5 * period_us as u32);
        timers::start_tick(tick);
        // SAFETY: the handler's state is in place; nothing else uses TIM2's line.
        unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::TIM2) };
        // Idle: send each window's telemetry (the interrupt preempts this).
        loop {
            cortex_m::asm::wfi();
            if let Some(mut report) = cortex_m::interrupt::free(|cs| REPORT.borrow(cs).take()) {
                report.stack_high_water_bytes = stack::high_water_bytes();
                defmt::info!("stack high-water mark {=u32} bytes", report.stack_high_water_bytes);
                let mut buf = [0u8; MAX_FRAME];
                if let Ok(frame) = pil::encode(&report, &mut buf) {
                    usart::write_all(frame);
                }
            }
            // The periods run so far and whether the drivers are on, from the board itself.
            let (periods, drivers) = cortex_m::interrupt::free(|cs| {
                ARM.borrow(cs).borrow().as_ref().map_or((0, false), |a| (a.board.seq, a.board.motors.is_enabled()))
            });
            if exit::UNDER_QEMU && periods >= QEMU_PERIODS {
                cortex_m::peripheral::NVIC::mask(Interrupt::TIM2);
                defmt::info!(
                    "qemu run over: {=u32} periods, drivers {=str}, stack high-water mark {=u32} of {=u32} bytes",
                    periods,
                    if drivers { "enabled" } else { "disabled" },
                    stack::high_water_bytes(),
                    stack::size_bytes()
                );
                exit::exit(0);
            }
        }
    }

    fn encoder_error<E>(e: &drivers::as5047p::Error<E>) -> &'static str {
        use drivers::as5047p::Error;
        match e {
            Error::Bus(_) => "SPI bus error",
            Error::Parity { .. } => "parity error",
            Error::ErrorFlag { .. } => "error flag",
            Error::NotReady => "offset compensation not finished, or no chip on the bus",
            Error::Magnet { .. } => "magnetic field out of range",
            Error::CordicOverflow => "CORDIC overflow",
        }
    }
}
