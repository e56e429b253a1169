//! The processor-in-the-loop image: the firmware against the PC's plant over
//! USART1 at 2 Mbaud (wire: `firmware::pil`). Under QEMU (`netduinoplus2`,
//! feature `qemu`) the plant's `sil-host pil` starts it; on a board with a
//! USB-serial adapter on PA9/PA10, `sil-host pil --serial PATH` runs it
//! (hardware in the loop).
//!
//! The plant owns time (lockstep): the image waits for each frame. The step's
//! ticks are the DWT cycle counter on silicon and SysTick under QEMU (where
//! `-icount shift=0` makes them instructions); `Hello` says which. Each answer
//! carries the step's ticks and the frame's (decode plus step, from its last byte).
//! At `End` the image logs its figures and the stack's high-water mark; under
//! QEMU it then exits, on a board it waits for the next run.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("`pil` is the Cortex-M4F PIL image: build it with --target thumbv7em-none-eabihf (docs/board.md)");
}

#[cfg(target_os = "none")]
mod image {
    use board_stm32f405::mcu::{self, cycles::CycleClock, exit, stack, usart};
    use cortex_m_rt::entry;
    use firmware::{
        Event, Firmware, Outcome, TickClock,
        board::{self, Board},
        config::ConfigError,
        pil::{self, Downlink, FrameBuffer, MAX_FRAME, Push, Uplink},
    };
    use stm32f4::stm32f405::Interrupt;

    /// Running figures of a run.
    #[derive(Default)]
    struct Figures {
        frames: u32,
        garbled: u32,
        worst_step: u32,
        worst_frame: u32,
    }

    /// The board of the PIL image: frames from USART1, answers back.
    struct PilBoard {
        clock: CycleClock,
        rx: FrameBuffer,
        hello: Uplink,
        /// Start of the current frame's interval (its last byte), ticks.
        frame_mark: u32,
        now_us: u64,
        fig: Figures,
    }

    impl PilBoard {
        fn send(&mut self, msg: &Uplink) {
            let mut buf = [0u8; MAX_FRAME];
            match pil::encode(msg, &mut buf) {
                Ok(frame) => usart::write_all(frame),
                Err(_) => defmt::error!("uplink message does not fit a frame"),
            }
        }

        /// Waits for the next received byte, asleep until USART1's interrupt is
        /// pending: interrupts stay masked (PRIMASK), so it only wakes the core.
        /// Under QEMU a sleeping core lets the emulator deliver bytes at once.
        fn read_byte(&mut self) -> u8 {
            loop {
                cortex_m::peripheral::NVIC::unpend(Interrupt::USART1);
                if let Some(b) = usart::try_read() {
                    return b;
                }
                cortex_m::asm::wfi();
            }
        }
    }

    impl Board for PilBoard {
        type Error = core::convert::Infallible;

        fn next_event(&mut self) -> Result<Event, Self::Error> {
            loop {
                let byte = self.read_byte();
                let frame = match self.rx.push(byte) {
                    Push::Pending => continue,
                    Push::Overflow => {
                        self.fig.garbled += 1;
                        defmt::warn!("frame longer than {=usize} bytes dropped", MAX_FRAME);
                        self.send(&Uplink::Garbled);
                        continue;
                    }
                    Push::Frame(f) => f,
                };
                self.frame_mark = self.clock.mark();
                let msg = pil::decode::<Downlink>(frame);
                match msg {
                    Err(_) => {
                        self.fig.garbled += 1;
                        defmt::warn!("garbled frame dropped (COBS, CRC or message)");
                        self.send(&Uplink::Garbled);
                    }
                    Ok(Downlink::Hello) => {
                        let hello = self.hello;
                        self.send(&hello);
                    }
                    Ok(Downlink::Configure(cfg)) => return Ok(Event::Configure(cfg)),
                    Ok(Downlink::Frame { frame, start_delay_us }) => {
                        self.now_us = frame.t_us.saturating_add(u64::from(start_delay_us));
                        return Ok(Event::Frame(frame));
                    }
                    Ok(Downlink::End) => return Ok(Event::End),
                }
            }
        }

        fn now_us(&self) -> u64 {
            self.now_us
        }

        fn apply(&mut self, outcome: &Outcome, fw: Option<&Firmware>) -> Result<(), Self::Error> {
            match (outcome, fw) {
                (Outcome::Command(command), Some(fw)) => {
                    let telemetry = fw.telemetry_message(command);
                    let frame_ticks = self.clock.ticks().wrapping_sub(self.frame_mark);
                    self.fig.frames += 1;
                    self.fig.worst_step = self.fig.worst_step.max(command.step_ticks);
                    self.fig.worst_frame = self.fig.worst_frame.max(frame_ticks);
                    self.send(&Uplink::Answer { command: *command, telemetry, frame_ticks });
                }
                (Outcome::Configured, Some(fw)) => {
                    let cfg = fw.config();
                    let pid = matches!(cfg.controller, firmware::ControllerKind::Pid);
                    defmt::info!("configured: {=str} controller, period {=u64} us", if pid { "pid" } else { "hybrid" }, cfg.period.as_us());
                    self.fig = Figures::default();
                    self.send(&Uplink::Configured);
                }
                (Outcome::Rejected(e), _) => {
                    match e {
                        ConfigError::OutOfRange { name, value, .. } => {
                            defmt::error!("configuration rejected: {=str} = {=f32}", name, value)
                        }
                        ConfigError::Params(_) => defmt::error!("configuration rejected: arm parameters"),
                    }
                    self.send(&Uplink::Rejected);
                }
                (Outcome::NotConfigured { .. }, _) => {
                    defmt::error!("a frame before the configuration");
                    self.send(&Uplink::Rejected);
                }
                (Outcome::Ended, _) => defmt::info!(
                    "end of run: {=u32} frames, worst step {=u32} ticks, worst frame {=u32} ticks, {=u32} garbled, stack high-water mark {=u32} of {=u32} bytes",
                    self.fig.frames,
                    self.fig.worst_step,
                    self.fig.worst_frame,
                    self.fig.garbled,
                    stack::high_water_bytes(),
                    stack::size_bytes()
                ),
                _ => {}
            }
            Ok(())
        }
    }

    #[entry]
    fn main() -> ! {
        let Some(mut core) = cortex_m::Peripherals::take() else {
            defmt::error!("core peripherals already taken");
            exit::exit(2);
        };
        let (_, clock) = mcu::start(&mut core);
        usart::init(true);
        cortex_m::interrupt::disable();
        // SAFETY: interrupts are masked (PRIMASK) and no handler is needed: the
        // enabled line only wakes the core from WFI.
        unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::USART1) };
        let hello = Uplink::Hello { protocol: pil::PROTOCOL_VERSION, ticks_per_second: clock.ticks_per_second(), clock: clock.kind() };
        let mut board = PilBoard { clock, rx: FrameBuffer::default(), hello, frame_mark: 0, now_us: 0, fig: Figures::default() };
        defmt::info!("PIL image up: protocol {=u16}, waiting for the plant on USART1", pil::PROTOCOL_VERSION);
        board.send(&hello);
        let mut fw: Option<Firmware> = None;
        loop {
            let Ok(()) = board::run(&mut fw, &mut board, &clock);
            if exit::UNDER_QEMU {
                exit::exit(0);
            }
            fw = None;
        }
    }
}
