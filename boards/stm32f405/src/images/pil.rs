//! The processor-in-the-loop image: the firmware against the PC's plant over
//! USART1 at 2 Mbaud (wire: `firmware::pil`). Under QEMU (`netduinoplus2`,
//! feature `qemu`) the plant's `sil-host pil` starts it; on a board with a
//! USB-serial adapter on PA9/PA10, `sil-host pil --serial PATH` runs it
//! (hardware in the loop).
//!
//! The plant owns time (lockstep): the image waits for each frame. The step's
//! ticks are the DWT cycle counter on silicon and SysTick at 168 MHz under QEMU
//! (where `-icount shift=0` retires an instruction per virtual ns: 5.95 per
//! tick); `Hello` says which, and the end-of-run log line names them. Each answer
//! carries the step's ticks and the frame's (decode plus step, from its last byte).
//! At `End` the image logs its figures and the stack's high-water mark; under
//! QEMU it then exits, on a board it waits for the next run.
//!
//! Under QEMU the same frames can bypass the emulated USART: when QEMU's
//! semihosting command line is `pil-fifo PREFIX`, the image reads and writes the
//! host FIFOs `PREFIX.down` and `PREFIX.up` through semihosting (one trap per
//! chunk instead of one emulator main-loop turn per byte: QEMU's USART model
//! takes a byte only once the last was read). `sil-host pil` does this by default
//! (docs/board.md, "PIL in real time").

use crate::mcu::{self, cycles::CycleClock, exit, log_time, stack, usart};
use firmware::{
    ControlLaw, Event, Firmware, Outcome, TickClock,
    board::{self, Board},
    config::ConfigError,
    pil::{self, Downlink, FrameBuffer, MAX_FRAME, Push, Uplink},
};
use shared::time::{Duration, Instant};
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
    link: Link,
    clock: CycleClock,
    rx: FrameBuffer,
    hello: Uplink,
    /// Start of the current frame's interval (its last byte), ticks.
    frame_mark: u32,
    now: Instant,
    fig: Figures,
}

impl PilBoard {
    fn send(&mut self, msg: &Uplink) {
        let mut buf = [0u8; MAX_FRAME];
        match pil::encode(msg, &mut buf) {
            Ok(frame) => self.link.write_all(frame),
            Err(_) => defmt::error!("uplink message does not fit a frame"),
        }
    }

    /// Waits for the next received byte (USART1, or the downlink FIFO under QEMU).
    #[inline(never)]
    fn read_byte(&mut self) -> u8 {
        #[cfg(feature = "qemu")]
        if let Link::Fifo(f) = &mut self.link {
            return f.read_byte();
        }
        usart_read_byte()
    }
}

/// Where the frames travel: USART1 (a board, or QEMU's emulated USART), or
/// under QEMU the host's FIFOs through semihosting.
// One per image and no heap to box it in: the FIFO's buffer stays inline.
#[allow(clippy::large_enum_variant)]
enum Link {
    Usart,
    #[cfg(feature = "qemu")]
    Fifo(fifo::Fifo),
}

impl Link {
    /// The link QEMU's semihosting command line asks for, else USART1.
    fn choose() -> Self {
        #[cfg(feature = "qemu")]
        if let Some(f) = fifo::Fifo::from_cmdline() {
            return Self::Fifo(f);
        }
        Self::Usart
    }

    fn write_all(&mut self, bytes: &[u8]) {
        match self {
            Self::Usart => usart::write_all(bytes),
            #[cfg(feature = "qemu")]
            Self::Fifo(f) => f.write_all(bytes),
        }
    }
}

/// Waits for the next byte of USART1, asleep until its interrupt is
/// pending: interrupts stay masked (PRIMASK), so it only wakes the core.
/// Under QEMU a sleeping core lets the emulator deliver bytes at once.
fn usart_read_byte() -> u8 {
    loop {
        cortex_m::peripheral::NVIC::unpend(Interrupt::USART1);
        if let Some(b) = usart::try_read() {
            return b;
        }
        cortex_m::asm::wfi();
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
                    // The defmt log's timestamp (mcu::log_time): this frame's period.
                    log_time::set_tick(frame.seq);
                    self.now = frame.sampled_at().saturating_add(Duration::from_us(u64::from(start_delay_us)));
                    return Ok(Event::Frame(frame));
                }
                Ok(Downlink::End) => return Ok(Event::End),
            }
        }
    }

    fn now(&self) -> Instant {
        self.now
    }

    fn apply<M: ControlLaw>(&mut self, outcome: &Outcome, fw: Option<&Firmware<M>>) -> Result<(), Self::Error> {
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
                log_time::set_period_us(cfg.period.as_us() as u32);
                if cfg.law.name.is_paper() {
                    let pid = matches!(cfg.controller, firmware::ControllerKind::Pid);
                    defmt::info!("configured: {=str} controller, period {=u64} us", if pid { "pid" } else { "hybrid" }, cfg.period.as_us());
                } else {
                    defmt::info!("configured: law {=[u8]:a}, period {=u64} us", cfg.law.name.as_bytes(), cfg.period.as_us());
                }
                self.fig = Figures::default();
                self.send(&Uplink::Configured);
            }
            (Outcome::Rejected(e), _) => {
                match e {
                    ConfigError::OutOfRange { name, value, .. } => {
                        defmt::error!("configuration rejected: {=str} = {=f32}", name, value)
                    }
                    ConfigError::Params(_) => defmt::error!("configuration rejected: arm parameters"),
                    ConfigError::WrongLaw { built, .. } => {
                        defmt::error!("configuration rejected: for another law than this image's {=[u8]:a}", built.as_bytes())
                    }
                    ConfigError::LawParam { name, value, .. } => {
                        defmt::error!("configuration rejected: law parameter {=str} = {=f32}", name, value)
                    }
                }
                self.send(&Uplink::Rejected);
            }
            (Outcome::NotConfigured { .. }, _) => {
                defmt::error!("a frame before the configuration");
                self.send(&Uplink::Rejected);
            }
            // The ticks named by their clock (issue 69: the host says
            // instructions, the log said "ticks" of no clock), in the format
            // string (interned by defmt: no flash).
            (Outcome::Ended, _) => defmt::info!(
                "end of run: {=u32} frames, worst step {=u32} ticks, worst frame {=u32} ticks (step clock ticks: SysTick at 168 MHz under QEMU, 5.95 instructions each at -icount shift=0; DWT cycles on silicon), {=u32} garbled, stack high-water mark {=u32} of {=u32} bytes",
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

/// The PIL byte stream through two host FIFOs by semihosting (QEMU only):
/// the same COBS frames as on USART1, a chunk per trap.
#[cfg(feature = "qemu")]
mod fifo {
    use crate::mcu::exit;
    use firmware::pil::MAX_FRAME;
    use semihosting::{
        fd::{AsFd, OwnedFd},
        sys::arm_compat::{OpenMode, sys_get_cmdline_uninit, sys_open, sys_read_orig, sys_write_orig},
    };

    /// The semihosting command line that asks for this link: `pil-fifo PREFIX`.
    const ASK: &[u8] = b"pil-fifo ";

    pub struct Fifo {
        down: OwnedFd,
        up: OwnedFd,
        buf: [u8; MAX_FRAME],
        at: usize,
        len: usize,
    }

    impl Fifo {
        /// Opens `PREFIX.down` (to read) and `PREFIX.up` (to write) when QEMU's
        /// semihosting command line is `pil-fifo PREFIX`; `None` otherwise (no
        /// such line, a path too long or FIFOs that do not open: USART1 then).
        pub fn from_cmdline() -> Option<Self> {
            let mut line = [core::mem::MaybeUninit::<u8>::uninit(); 240];
            let line = sys_get_cmdline_uninit(&mut line).ok()?;
            let prefix = line.strip_prefix(ASK)?;
            let open = |ext: &[u8], mode: OpenMode| {
                let mut path = [0u8; 256];
                let n = prefix.len() + ext.len();
                if n >= path.len() {
                    return None;
                }
                path[..prefix.len()].copy_from_slice(prefix);
                path[prefix.len()..n].copy_from_slice(ext);
                let path = core::ffi::CStr::from_bytes_until_nul(&path).ok()?;
                sys_open(path, mode).ok()
            };
            let up = open(b".up", OpenMode::WRONLY_TRUNC_BINARY)?;
            let down = open(b".down", OpenMode::RDONLY_BINARY)?;
            Some(Self { down, up, buf: [0; MAX_FRAME], at: 0, len: 0 })
        }

        /// The next byte, waiting for the host (the emulator blocks in the
        /// read: virtual time stands still). The plant gone (end of file) or a
        /// failed read ends the image: nobody is left to answer.
        pub fn read_byte(&mut self) -> u8 {
            if self.at == self.len {
                let not_read = match sys_read_orig(self.down.as_fd(), &mut self.buf) {
                    Ok(n) => n,
                    Err(_) => self.buf.len(),
                };
                let got = self.buf.len().saturating_sub(not_read);
                if got == 0 {
                    defmt::warn!("the plant closed the PIL FIFO: exiting");
                    exit::exit(3);
                }
                (self.at, self.len) = (0, got);
            }
            self.at += 1;
            self.buf[self.at - 1]
        }

        /// Writes a whole frame (one trap for all of it).
        pub fn write_all(&mut self, mut bytes: &[u8]) {
            while !bytes.is_empty() {
                match sys_write_orig(self.up.as_fd(), bytes) {
                    Ok(not_written) if not_written < bytes.len() => bytes = &bytes[bytes.len() - not_written..],
                    _ => {
                        defmt::warn!("the plant closed the PIL FIFO: exiting");
                        exit::exit(3);
                    }
                }
            }
        }
    }
}

/// The PIL image's main loop with control law `L`: never returns (under QEMU
/// it exits at the end of a run). Called from an image's entry point
/// ([`crate::pil_image!`]).
pub fn run<L: ControlLaw>() -> ! {
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
    let hello = Uplink::Hello {
        protocol: pil::PROTOCOL_VERSION,
        ticks_per_second: clock.ticks_per_second(),
        clock: clock.kind(),
        law_digest: const { L::SPEC.digest() },
    };
    let link = Link::choose();
    let mut board =
        PilBoard { link, clock, rx: FrameBuffer::default(), hello, frame_mark: 0, now: Instant::from_us(0), fig: Figures::default() };
    let on = match board.link {
        Link::Usart => "USART1",
        #[cfg(feature = "qemu")]
        Link::Fifo(_) => "QEMU's semihosting FIFOs",
    };
    defmt::info!("PIL image up: protocol {=u16}, waiting for the plant on {=str}", pil::PROTOCOL_VERSION, on);
    board.send(&hello);
    let mut fw: Option<Firmware<L>> = None;
    loop {
        let Ok(()) = board::run(&mut fw, &mut board, &clock);
        if exit::UNDER_QEMU {
            exit::exit(0);
        }
        fw = None;
    }
}
