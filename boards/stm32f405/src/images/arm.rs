//! The arm image: the controller on the arm (docs/hardware.md "Reference board").
//!
//! This file only creates the peripherals and hands them to the arm application
//! (`arm_app::ArmApp`, hardware-independent, the same code the board twin runs
//! on the host). TIM2's update, at the rate of the saved configuration
//! (`arm_app::rate`: 100 to 4 000 us), starts the period's acquisition: the load
//! cell's injected conversions on its trigger, and the two AS5047P frames on SPI1
//! through DMA2 (SPI1_TX stream 3, SPI1_RX stream 0, the chip select released and
//! the next frame started in the RX stream's completion). When the frames are in
//! memory the acquisition pends the control interrupt (CAN2_TX's vector), whose
//! `tick` reads that memory only (no peripheral flag is polled), steps the firmware
//! through `firmware::board::handle`, writes the torques to the PWM and feeds the
//! independent watchdog. Priorities: USART1 (0x00) above TIM2 and DMA2 (0x20) above
//! the control interrupt (0x40); the idle loop (the notices' defmt lines, the
//! window's report, the reset's fresh firmware, the bring-up's requests) borrows
//! the application under PRIMASK or BASEPRI at the control's priority. The safe
//! state disables the drivers. A reset (or a watchdog reset) comes up with them
//! disabled until the enable button (PC13 to ground, held 20 ms at any rate:
//! `arm_app::BUTTON_PRESS_S`) resets the firmware; they are enabled at the next
//! command that is not the safe state.
//!
//! The step's cycles (DWT `CYCCNT` on silicon) are reported per window of
//! `step_stats::WINDOW` periods, worst and median, with the tick's interval
//! spread and the stack's high-water mark: in the defmt log and as telemetry
//! on USART1 TX (`board_stm32f405::telemetry::ArmTelemetry`, PIL framing).
//!
//! Under QEMU (feature `qemu`) the image runs `QEMU_PERIODS` periods and exits;
//! QEMU models no encoder, load cell or belt: the frames are invalid and the
//! firmware goes to its safe state (bad frames) with the drivers disabled.

use core::cell::RefCell;

use crate::{
    calibration,
    clock_tree::ClockOutcome,
    mcu::{
        self, acquisition, adc,
        cycles::CycleClock,
        exit,
        flash::SettingsFlash,
        gpio::{self, GpioPin},
        iwdg::{self, Iwdg},
        log_time,
        notices::{defer, log, log_notices},
        rcc, spi, stack,
        timers::{self, BeltCounter, PwmChannel},
        usart,
    },
    pins,
    timing::{TIM2_CLOCK_HZ, TickTimer},
};
use arm_app::{
    ArmApp, ArmCalibration, ArmIo, ArmParts, Notice, StartError,
    bringup::{Reply, Request},
};
use cortex_m::interrupt::Mutex;
use drivers::motor::{Motor, MotorStage};
use firmware::{
    Config, ControlLaw,
    pil::{self, FrameBuffer, MAX_FRAME, Push},
};
use heapless::Deque;
use stm32f4::stm32f405::Interrupt;

/// Periods the QEMU build runs before it exits (3 windows).
const QEMU_PERIODS: u32 = 3 * arm_app::step_stats::WINDOW;
/// QEMU's timer clock for TIM2 to TIM5, Hz: the emulator has no RCC and
/// clocks its timers at a fixed rate (measured: docs/board.md).
const QEMU_TIMER_HZ: u32 = crate::timing::QEMU_TIMER_HZ;

/// The reference board's parts, as the arm application sees them.
pub struct Stm32f405;

impl ArmIo for Stm32f405 {
    type Spi = spi::Spi1Device;
    type Encoders = acquisition::DmaEncoders;
    type Adc = adc::LoadCellAdc;
    type Counter = BeltCounter;
    type Pwm = PwmChannel;
    type Out = GpioPin;
    type In = GpioPin;
    type Watchdog = Iwdg;
    type Clock = CycleClock;
    type Flash = SettingsFlash;
}

/// The application with law `L`, once made ([`run`]; an [`AppSlot`] holds
/// it): the image's static `ARM` ([`crate::arm_image!`]). A reference, not the
/// application itself: `None` is then all zeros and the static takes no flash
/// (in `.data`, the application's `None`, a tag inside a 2.7 KiB structure,
/// took its size of flash for its initial value; issue 56).
pub type AppCell<L> = Mutex<RefCell<Option<&'static mut ArmApp<Stm32f405, L>>>>;
/// Where the application lives: the image's static `APP`, in cortex-m-rt's
/// `.uninit` (neither copied from flash nor zeroed), written once by [`run`]
/// before `ARM` refers to it and any interrupt is enabled.
pub type AppSlot<L> = core::mem::MaybeUninit<ArmApp<Stm32f405, L>>;

/// An empty [`AppCell`] (the image's `ARM` before [`run`]).
pub const fn app_cell<L: ControlLaw>() -> AppCell<L> {
    Mutex::new(RefCell::new(None))
}
/// Bytes received on USART1, filled by its interrupt, emptied by the idle loop.
static RX: Mutex<RefCell<Deque<u8, RX_BYTES>>> = Mutex::new(RefCell::new(Deque::new()));
/// Room for two whole requests.
const RX_BYTES: usize = 2 * MAX_FRAME;
/// Priorities (lower is more urgent): a received byte must be taken within
/// a character time (5 us at 2 Mbaud), shorter than a step: USART1 preempts
/// TIM2 (its handler moves one byte: tens of cycles).
const USART1_PRIORITY: u8 = 0x00;
/// The acquisition's interrupts (TIM2's update and deadline, DMA2 stream
/// 0's frame ends): short, above the control, so a late step never delays
/// the next period's frames.
const ACQUISITION_PRIORITY: u8 = 0x20;
/// The control step (`acquisition::CONTROL_INTERRUPT`, pended when the
/// period's acquisition is over), below every other interrupt: USART1's
/// bytes, the next period's tick and frames preempt it (a step takes tens of
/// microseconds: 10 characters at 2 Mbaud). It takes no critical section
/// around the step (issue 56): the application (`ARM`) is its own at this
/// priority (see [`control_section`]).
const CONTROL_PRIORITY: u8 = 0x40;

/// The control interrupt's access to `ARM` without masking the interrupts
/// above it. Sound by priority, as a ceiling: `ARM` is borrowed by the
/// control interrupt and by thread mode, there only inside
/// `cortex_m::interrupt::free` (PRIMASK set) or [`below_control`] (BASEPRI
/// at `CONTROL_PRIORITY`), where the control interrupt cannot run; no
/// interrupt above the control's touches it (USART1 fills `RX`, TIM2 and
/// DMA2 the acquisition's own state), and the control interrupt never
/// preempts itself. The RefCell's flag still checks it.
///
/// # Safety
/// From the control interrupt only.
unsafe fn control_section() -> cortex_m::interrupt::CriticalSection {
    // SAFETY: the caller is the control interrupt (see above).
    unsafe { cortex_m::interrupt::CriticalSection::new() }
}

/// TIM2's handler: the tick (update: the period's frames start) and the
/// acquisition's deadline (compare 1).
pub fn on_tim2() {
    let (update, deadline) = timers::take_tick_events();
    if deadline {
        acquisition::on_deadline();
    }
    if update {
        acquisition::on_tick();
    }
}

/// DMA2 stream 0's handler (SPI1_RX): a frame is over, or a stream failed.
pub fn on_dma2_stream0() {
    acquisition::on_rx_stream();
}

/// The control interrupt's handler (CAN2_TX's vector), the step of `arm`'s
/// application, pended by the acquisition once both encoders and the load
/// cell are in memory: reads memory and computes, preemptible by the
/// interrupts above it (`CONTROL_PRIORITY`).
///
/// # Safety
/// From the control interrupt only ([`control_section`]).
#[inline(always)]
pub unsafe fn on_control<L: ControlLaw>(arm: &AppCell<L>) {
    acquisition::publish();
    // The defmt log's timestamp (mcu::log_time): this tick's time.
    log_time::tick();
    // SAFETY: this is the control interrupt (the caller's promise).
    let cs = unsafe { control_section() };
    if let Some(arm) = arm.borrow(&cs).borrow_mut().as_mut() {
        arm.tick(&mut defer);
        if let Some(m) = arm.monitor() {
            // SAFETY: written here only; read by a debugger or the
            // emulator, never by the image.
            unsafe { core::ptr::write_volatile(&raw mut PAINLEVE_MONITOR, m) };
        }
    }
}

/// Runs `f` on the application from thread mode with the control interrupt
/// masked (BASEPRI at `CONTROL_PRIORITY`, RM0090 / ARMv7-M B1.5.7) and the
/// interrupts above it not: the long work of the idle loop (the next
/// reset's fresh firmware, about 3 000 cycles) delays neither USART1's
/// bytes nor the acquisition's frames. `None` before the application.
fn below_control<L: ControlLaw, R>(arm: &AppCell<L>, f: impl FnOnce(&mut ArmApp<Stm32f405, L>) -> R) -> Option<R> {
    let old = cortex_m::register::basepri::read();
    // Raising BASEPRI only masks more (BASEPRI_MAX never lowers it).
    cortex_m::register::basepri_max::write(CONTROL_PRIORITY);
    // SAFETY: the control interrupt is masked now, and nothing above it
    // touches ARM (`control_section`'s argument).
    let cs = unsafe { cortex_m::interrupt::CriticalSection::new() };
    let r = arm.borrow(&cs).borrow_mut().as_deref_mut().map(f);
    // SAFETY: back to what it was (thread mode runs at BASEPRI 0).
    unsafe { cortex_m::register::basepri::write(old) };
    r
}

/// The monitor block (`arm_app::monitor`): the last tick's command and
/// telemetry, for probe-rs's live watch and the emulator's lockstep link.
#[unsafe(no_mangle)]
#[used]
static mut PAINLEVE_MONITOR: arm_app::monitor::Monitor = arm_app::monitor::Monitor {
    magic: 0,
    version: 0,
    ticks: 0,
    drivers_enabled: 0,
    command: shared::wire::ActuatorCommand {
        seq: 0,
        t_sent_us: 0,
        u1_code: 0,
        u2_code: 0,
        status: 0,
        step_ticks: 0,
        overruns: 0,
        reserved: 0,
    },
    telemetry: shared::wire::FirmwareTelemetry {
        seq: 0,
        status: 0,
        z_t_ref: 0.0,
        f_n_ref: 0.0,
        q: [0.0; 2],
        qd: [0.0; 2],
        f: [0.0; 2],
        u_raw: [0.0; 2],
    },
};

/// USART1's handler: the bring-up's bytes into `RX`.
pub fn on_usart1() {
    cortex_m::interrupt::free(|cs| {
        let mut rx = RX.borrow(cs).borrow_mut();
        while let Some(b) = usart::try_read() {
            // A full buffer drops the byte: the frame's CRC fails and the
            // host asks again.
            let _ = rx.push_back(b);
        }
    });
}

/// Serves the bring-up requests received so far (docs/board.md "Bring-up"):
/// each request between two ticks, its reply on USART1 TX.
fn serve_requests<L: ControlLaw>(arm: &AppCell<L>, frames: &mut FrameBuffer, timer_hz: u32) {
    while let Some(b) = cortex_m::interrupt::free(|cs| RX.borrow(cs).borrow_mut().pop_front()) {
        let Push::Frame(f) = frames.push(b) else { continue };
        let Ok(request) = pil::decode::<Request>(f) else {
            defmt::warn!("bring-up: a frame that does not decode was dropped");
            continue;
        };
        // A new rate (`Configure`, `Restore`): TIM2 follows it before the next tick.
        let mut reply = cortex_m::interrupt::free(|cs| {
            arm.borrow(cs).borrow_mut().as_mut().map(|a| {
                let reply = a.serve(request);
                // (`Status` reports the tick's period; TIM2's update that
                // loaded it, cleared, left its interrupt pending: dropped.)
                if a.retime(|p| timers::retime(p, timer_hz, acquisition::DEADLINE_US)).is_some() {
                    cortex_m::peripheral::NVIC::unpend(Interrupt::TIM2);
                }
                reply
            })
        });
        // The stack's scan takes too long for the tick: done here.
        if let Some(Reply::Telemetry(Some(t))) = reply.as_mut() {
            t.stack_high_water_bytes = stack::high_water_bytes();
        }
        let mut buf = [0u8; MAX_FRAME];
        if let Some(reply) = reply
            && let Ok(frame) = pil::encode(&reply, &mut buf)
        {
            usart::write_all(frame);
        }
    }
}

/// The arm image's main with law `L`: brings the board up, makes the
/// application in `slot`, hands it to `arm` (the control interrupt's), starts
/// the tick and serves the bring-up in the idle loop; never returns (under
/// QEMU it exits after `QEMU_PERIODS`). Called from the image's entry point
/// ([`crate::arm_image!`]). The compiled-in configuration, when the flash
/// holds no settings record, is the defaults with `L`'s declared parameters.
///
/// # Safety
/// Once, from the entry point, with `arm` and `slot` the image's own statics,
/// no interrupt enabled yet.
pub unsafe fn run<L: ControlLaw>(arm: &'static AppCell<L>, slot: *mut AppSlot<L>) -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        defmt::error!("core peripherals already taken");
        exit::exit(2);
    };
    let (clocks, clock) = mcu::start(&mut core);
    let watchdog_reset = rcc::take_watchdog_reset_flag();
    // The drivers first: disabled (the enable pin an output, low), before
    // anything can fail. Then the PWM at 20 kHz with zero duty, and only then
    // the motors, which read their full-scale duty (TIM3's ARR + 1) once:
    // made before `start_pwm` they read the reset value of ARR (or 0 with
    // TIM3's clock off), and every duty was wrong (found by the emulated
    // image, issue 38: no torque at all there, 15.6 times too much on silicon).
    for p in [pins::DIR_U1, pins::DIR_U2, pins::DRIVER_ENABLE, pins::DRIVER_FAULT, pins::ENABLE_BUTTON] {
        gpio::configure(&p);
    }
    let timer_hz = match clocks {
        ClockOutcome::Pll { .. } => TIM2_CLOCK_HZ,
        ClockOutcome::NoClockModel => QEMU_TIMER_HZ,
    };
    timers::start_pwm(timer_hz);
    let m1 = Motor::new(PwmChannel(0), GpioPin(pins::DIR_U1));
    let m2 = Motor::new(PwmChannel(1), GpioPin(pins::DIR_U2));
    let Ok(motors) = MotorStage::new(m1, m2, GpioPin(pins::DRIVER_ENABLE), GpioPin(pins::DRIVER_FAULT)) else {
        defmt::error!("the motor stage did not come up disabled");
        exit::exit(3);
    };
    if watchdog_reset {
        defmt::warn!("reset by the watchdog (a step hung): drivers disabled until the enable button");
    }
    let cfg = Config { law: L::SPEC.defaults(), ..Config::default() };
    spi::init();
    acquisition::init();
    adc::init();
    timers::start_belt_encoder();
    usart::init(true);
    let parts = ArmParts::<Stm32f405> {
        theta1: spi::Spi1Device::new(pins::CS_THETA1, acquisition::busy),
        elbow: spi::Spi1Device::new(pins::CS_ELBOW, acquisition::busy),
        encoders: acquisition::DmaEncoders,
        adc: adc::LoadCellAdc,
        belt: BeltCounter,
        motors,
        button: GpioPin(pins::ENABLE_BUTTON),
        watchdog: Iwdg,
        clock,
        flash: SettingsFlash::default(),
    };
    let cal = ArmCalibration {
        encoders: calibration::ENCODERS,
        load_cell: calibration::LOAD_CELL,
        belt_metres_per_count: calibration::BELT_METRES_PER_COUNT,
    };
    let app = match ArmApp::<Stm32f405, L>::new(parts, cfg, &cal, &mut log) {
        Ok(app) => app,
        Err(StartError::Config(_)) => {
            defmt::error!("invalid firmware configuration");
            exit::exit(2);
        }
        Err(StartError::LoadCell(_)) => {
            defmt::error!("invalid load-cell calibration");
            exit::exit(2);
        }
        Err(StartError::Belt(_)) => {
            defmt::error!("invalid belt calibration");
            exit::exit(2);
        }
        Err(StartError::ProtectionOff) => {
            defmt::error!("the compiled-in configuration turns the runaway limits off, which a board never runs");
            exit::exit(2);
        }
    };
    // The control rate is the configuration's in force (the settings
    // record's, else the compiled-in fallback's): TIM2's reload from it.
    let period = app.config().period;
    let tick = match TickTimer::for_period(timer_hz, period) {
        Ok(t) if period.as_us() >= crate::timing::MIN_PERIOD_US && period.as_us() <= crate::timing::MAX_PERIOD_US => t,
        Ok(_) => {
            defmt::error!("control rate: {=u64} us is outside the image's 100 to 4000 us (250 Hz to 10 kHz)", period.as_us());
            exit::exit(2);
        }
        Err(e) => {
            defmt::error!("control rate: {}", e);
            exit::exit(2);
        }
    };
    let period_us = period.as_us();
    log_time::set_period_us(period_us as u32);
    // SAFETY: once, here, before any interrupt is enabled: nothing else
    // refers to the slot (`arm` is None until this line's end).
    let app = unsafe { (*slot).write(app) };
    cortex_m::interrupt::free(|cs| arm.borrow(cs).replace(Some(app)));
    defmt::info!(
        "arm image up: {=u64} us control period (TIM2 psc {=u16} arr {=u16} from {=u32} Hz), step clock {=str}, drivers disabled until the enable button",
        period_us,
        tick.psc,
        tick.arr,
        timer_hz,
        match clock.kind() {
            pil::StepClock::DwtCycles => "DWT cycles",
            pil::StepClock::EmulatedSysTick => "SysTick (emulated: instructions)",
            pil::StepClock::Simulated => "none (simulated)",
        }
    );
    iwdg::start(5 * period_us as u32);
    // SAFETY: the handlers' state is in place; nothing else uses these lines.
    unsafe {
        core.NVIC.set_priority(Interrupt::USART1, USART1_PRIORITY);
        core.NVIC.set_priority(Interrupt::TIM2, ACQUISITION_PRIORITY);
        core.NVIC.set_priority(Interrupt::DMA2_STREAM0, ACQUISITION_PRIORITY);
        core.NVIC.set_priority(acquisition::CONTROL_INTERRUPT, CONTROL_PRIORITY);
        cortex_m::peripheral::NVIC::unmask(Interrupt::USART1);
        cortex_m::peripheral::NVIC::unmask(Interrupt::DMA2_STREAM0);
        cortex_m::peripheral::NVIC::unmask(acquisition::CONTROL_INTERRUPT);
        cortex_m::peripheral::NVIC::unmask(Interrupt::TIM2);
    }
    timers::start_tick(tick, timer_hz, acquisition::DEADLINE_US);
    let mut frames = FrameBuffer::default();
    // Idle: serve the bring-up requests (the interrupts preempt this).
    loop {
        cortex_m::asm::wfi();
        log_notices();
        // The control interrupt's work that can wait (issue 56): the
        // window's summary, the next reset's fresh firmware.
        if let Some(Some(report)) = below_control(arm, ArmApp::idle) {
            log(Notice::Window(report));
        }
        serve_requests(arm, &mut frames, timer_hz);
        // The periods run so far and whether the drivers are on, from the application itself.
        let (periods, drivers) =
            cortex_m::interrupt::free(|cs| arm.borrow(cs).borrow().as_ref().map_or((0, false), |a| (a.periods(), a.drivers_enabled())));
        if exit::UNDER_QEMU && periods >= QEMU_PERIODS {
            cortex_m::peripheral::NVIC::mask(Interrupt::TIM2);
            cortex_m::peripheral::NVIC::mask(acquisition::CONTROL_INTERRUPT);
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
