//! The processor-in-the-loop image for the STM32F405 (QEMU's `netduinoplus2`):
//! the firmware that would be flashed, with a board that reads framed sensor
//! frames from USART1 and writes framed commands back (wire: `firmware::pil`).
//!
//! The plant owns time (lockstep): the image waits for each frame instead of
//! pacing itself by SysTick. SysTick runs free (reload `0xFF_FFFF`, core clock)
//! and is restarted when a frame's last byte arrives, so each answer carries the
//! step's own time (`step_ticks`) and the frame's (decode plus step,
//! `frame_ticks`) in core-clock ticks; under QEMU's `-icount shift=0` those are
//! a deterministic function of the instructions retired (README "PIL"). defmt
//! logs go out over semihosting (QEMU's standard output), and the image exits
//! through semihosting when the bridge ends the run.
//!
//! Build: `cargo build -p firmware --profile mcu --target thumbv7em-none-eabihf
//! --bin pil`; run: `sil-host pil`. On the host this binary only says what it is for.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("`pil` is the Cortex-M4F PIL image: build it with --target thumbv7em-none-eabihf and run it with `sil-host pil` (README)");
}

#[cfg(target_os = "none")]
#[path = "../mcu_mmio.rs"]
mod mmio;

#[cfg(target_os = "none")]
mod image {
    use super::mmio;
    use cortex_m::peripheral::{SYST, syst::SystClkSource};
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use firmware::{
        Firmware, TickClock,
        pil::{self, Downlink, FrameBuffer, MAX_FRAME, Push, Uplink},
    };

    /// Core clock, Hz: the STM32F405 at 168 MHz (HARDWARE.md), SysTick's source.
    const CORE_HZ: u32 = 168_000_000;
    /// SysTick reload: the full 24-bit range (free running).
    const RELOAD: u32 = 0x00FF_FFFF;

    /// STM32F405 registers (RM0090): RCC, GPIOA and USART1, which QEMU's
    /// netduinoplus2 wires to its first serial port (`-serial`).
    mod reg {
        pub const RCC_AHB1ENR: usize = 0x4002_3830;
        pub const RCC_APB2ENR: usize = 0x4002_3844;
        pub const GPIOA_MODER: usize = 0x4002_0000;
        pub const GPIOA_AFRH: usize = 0x4002_0024;
        pub const USART1_SR: usize = 0x4001_1000;
        pub const USART1_DR: usize = 0x4001_1004;
        pub const USART1_BRR: usize = 0x4001_1008;
        pub const USART1_CR1: usize = 0x4001_100C;
        /// SR: received data ready.
        pub const SR_RXNE: u32 = 1 << 5;
        /// SR: transmit data register empty.
        pub const SR_TXE: u32 = 1 << 7;
        /// CR1: USART enable, transmitter enable, receiver enable.
        pub const CR1_UE_TE_RE: u32 = (1 << 13) | (1 << 3) | (1 << 2);
        /// CR1: interrupt when a byte is received.
        pub const CR1_RXNEIE: u32 = 1 << 5;
    }

    fn read(addr: usize) -> u32 {
        // SAFETY: `addr` is one of the memory-mapped registers of `reg`, aligned.
        unsafe { core::ptr::read_volatile(addr as *const u32) }
    }

    fn write(addr: usize, value: u32) {
        // SAFETY: as `read`; this image is the only user of these peripherals.
        unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
    }

    /// USART1 on PA9 (TX) / PA10 (RX), polled: 8N1 at 2 Mbaud from APB2 at 84 MHz
    /// (a 1 kHz loop moves about 80 bytes per period). QEMU ignores the clocks
    /// and the pins; on silicon the clock tree must be at 168 MHz first.
    struct Usart1;

    impl Usart1 {
        fn init() -> Self {
            write(reg::RCC_AHB1ENR, read(reg::RCC_AHB1ENR) | 1); // GPIOA clock
            write(reg::RCC_APB2ENR, read(reg::RCC_APB2ENR) | (1 << 4)); // USART1 clock
            write(reg::GPIOA_MODER, (read(reg::GPIOA_MODER) & !(0b1111 << 18)) | (0b1010 << 18)); // PA9, PA10: AF
            write(reg::GPIOA_AFRH, (read(reg::GPIOA_AFRH) & !(0xFF << 4)) | (0x77 << 4)); // AF7 = USART1
            write(reg::USART1_BRR, 84_000_000 / 2_000_000);
            write(reg::USART1_CR1, reg::CR1_UE_TE_RE | reg::CR1_RXNEIE);
            cortex_m::interrupt::disable();
            // SAFETY: interrupts are masked (PRIMASK) and no handler is needed:
            // the enabled line only wakes the core from WFI.
            unsafe { cortex_m::peripheral::NVIC::unmask(Usart1Irq) };
            Self
        }

        /// Waits for the next received byte, asleep (WFI) until USART1's
        /// interrupt is pending: interrupts stay masked (PRIMASK), so it only
        /// wakes the core. Under QEMU a sleeping core lets the emulator deliver
        /// the socket's bytes at once; polling would hold it up.
        fn read_byte(&mut self) -> u8 {
            loop {
                cortex_m::peripheral::NVIC::unpend(Usart1Irq);
                if read(reg::USART1_SR) & reg::SR_RXNE != 0 {
                    return read(reg::USART1_DR) as u8;
                }
                cortex_m::asm::wfi();
            }
        }

        fn write_all(&mut self, bytes: &[u8]) {
            for &b in bytes {
                while read(reg::USART1_SR) & reg::SR_TXE == 0 {}
                write(reg::USART1_DR, b as u32);
            }
        }

        /// Frames and sends `msg`.
        fn send(&mut self, msg: &Uplink) {
            let mut buf = [0u8; MAX_FRAME];
            match pil::encode(msg, &mut buf) {
                Ok(frame) => self.write_all(frame),
                Err(_) => defmt::error!("uplink message does not fit a frame"),
            }
        }
    }

    /// USART1's interrupt line (RM0090 table 61: position 37).
    #[derive(Clone, Copy)]
    struct Usart1Irq;

    // SAFETY: 37 is USART1's position in the STM32F405's vector table.
    unsafe impl cortex_m::interrupt::InterruptNumber for Usart1Irq {
        fn number(self) -> u16 {
            37
        }
    }

    /// Core-clock ticks since the last [`FreeTicks::restart`] (SysTick counts down
    /// from `RELOAD`; a step is far shorter than its 0.1 s wrap).
    struct FreeTicks;

    impl FreeTicks {
        fn restart() {
            // SAFETY: a write of any value to the current-value register clears it
            // (SysTick then reloads); SysTick is ours alone.
            unsafe { (*SYST::PTR).cvr.write(0) };
        }
    }

    impl TickClock for FreeTicks {
        fn ticks(&self) -> u32 {
            // Right after the restart the counter reads 0 until it reloads.
            match SYST::get_current() {
                0 => 0,
                current => RELOAD - current.min(RELOAD),
            }
        }
        fn ticks_per_second(&self) -> u32 {
            CORE_HZ
        }
    }

    /// Running figures of the step times, ticks.
    #[derive(Default)]
    struct Figures {
        frames: u32,
        garbled: u32,
        worst_step: u32,
        worst_frame: u32,
    }

    #[entry]
    fn main() -> ! {
        let Some(mut cp) = cortex_m::Peripherals::take() else {
            defmt::error!("core peripherals already taken");
            semihosting::process::exit(2);
        };
        firmware::clock_tree::bring_up_or_halt(&mut mmio::Mmio);
        cp.SYST.set_clock_source(SystClkSource::Core);
        cp.SYST.set_reload(RELOAD);
        cp.SYST.clear_current();
        cp.SYST.enable_counter();
        let mut usart = Usart1::init();
        let clock = FreeTicks;
        let mut rx = FrameBuffer::default();
        let mut fw: Option<Firmware> = None;
        let mut fig = Figures::default();
        defmt::info!("PIL image up: protocol {=u16}, waiting for the plant on USART1", pil::PROTOCOL_VERSION);
        let hello = Uplink::Hello { protocol: pil::PROTOCOL_VERSION, ticks_per_second: CORE_HZ, clock: pil::StepClock::EmulatedSysTick };
        usart.send(&hello);
        loop {
            let byte = usart.read_byte();
            let frame = match rx.push(byte) {
                Push::Pending => continue,
                Push::Overflow => {
                    fig.garbled += 1;
                    defmt::warn!("frame longer than {=usize} bytes dropped", MAX_FRAME);
                    usart.send(&Uplink::Garbled);
                    continue;
                }
                Push::Frame(f) => f,
            };
            FreeTicks::restart();
            let msg = match pil::decode::<Downlink>(frame) {
                Ok(m) => m,
                Err(_) => {
                    fig.garbled += 1;
                    defmt::warn!("garbled frame dropped (COBS, CRC or message)");
                    usart.send(&Uplink::Garbled);
                    continue;
                }
            };
            match (msg, fw.as_mut()) {
                (Downlink::Configure(cfg), _) => match Firmware::new(cfg) {
                    Ok(f) => {
                        let pid = matches!(cfg.controller, firmware::ControllerKind::Pid);
                        defmt::info!("configured: {=str} controller, period {=f32} s", if pid { "pid" } else { "hybrid" }, cfg.period_s);
                        fw = Some(f);
                        usart.send(&Uplink::Configured);
                    }
                    Err(e) => {
                        match e {
                            firmware::config::ConfigError::OutOfRange { name, value, .. } => {
                                defmt::error!("configuration rejected: {=str} = {=f32}", name, value)
                            }
                            firmware::config::ConfigError::Params(_) => defmt::error!("configuration rejected: arm parameters"),
                        }
                        usart.send(&Uplink::Rejected);
                    }
                },
                (Downlink::Frame { frame, start_delay_us }, Some(f)) => {
                    let now_us = frame.t_us.saturating_add(start_delay_us as u64);
                    let command = f.step(now_us, &frame, &clock);
                    let telemetry = f.telemetry_message(&command);
                    let frame_ticks = clock.ticks();
                    fig.frames += 1;
                    fig.worst_step = fig.worst_step.max(command.step_ticks);
                    fig.worst_frame = fig.worst_frame.max(frame_ticks);
                    usart.send(&Uplink::Answer { command, telemetry, frame_ticks });
                }
                (Downlink::Frame { .. }, None) => {
                    defmt::error!("a frame before the configuration");
                    usart.send(&Uplink::Rejected);
                }
                (Downlink::Hello, _) => usart.send(&hello),
                (Downlink::End, _) => {
                    defmt::info!(
                        "end of run: {=u32} frames, worst step {=u32} ticks, worst frame {=u32} ticks, {=u32} garbled",
                        fig.frames,
                        fig.worst_step,
                        fig.worst_frame,
                        fig.garbled
                    );
                    semihosting::process::exit(0);
                }
            }
        }
    }

    /// Logs where it panicked (line only: formatting the message would pull
    /// `core::fmt` into the image) and halts QEMU with a failure status.
    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        let line = info.location().map_or(0, |l| l.line());
        defmt::error!("panic at line {=u32}", line);
        semihosting::process::exit(101);
    }
}
