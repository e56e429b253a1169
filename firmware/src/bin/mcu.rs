//! The Cortex-M4F image (STM32F405, e.g. QEMU's `netduinoplus2`) with the replay
//! board: it replays the sensor frames recorded from a plant run
//! (`firmware/replay/frames.bin`, consecutive 24-byte little-endian
//! `SensorFrame` records written by `sil-host`'s `record_replay_frames` example),
//! one per SysTick period (1 kHz), runs [`firmware::Firmware::step`] on each, logs
//! every command with defmt over semihosting, and exits through semihosting.
//!
//! Build and run in QEMU: `cargo run -p firmware --release --target
//! thumbv7em-none-eabihf --bin mcu` (the runner is `scripts/qemu-run.sh`). On the
//! host this binary only says what it is for.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("`mcu` is the Cortex-M4F image: build it with --target thumbv7em-none-eabihf (see README)");
}

#[cfg(target_os = "none")]
#[path = "../mcu_mmio.rs"]
mod mmio;

#[cfg(target_os = "none")]
mod image {
    use super::mmio;
    use core::cell::Cell;

    use cortex_m::peripheral::{SYST, syst::SystClkSource};
    use cortex_m_rt::entry;
    use defmt_semihosting as _;
    use firmware::{Board, Config, Firmware, TickClock};
    use shared::wire::{ActuatorCommand, SensorFrame};

    /// Core clock assumed for SysTick: the STM32F405's 168 MHz (HARDWARE.md). QEMU's
    /// netduinoplus2 model clocks SysTick from its own virtual clock; the period is
    /// then 1 ms of QEMU time (and a fixed instruction count under `-icount`).
    const CORE_HZ: u32 = 168_000_000;
    /// Control rate, Hz.
    const RATE_HZ: u32 = 1_000;
    /// SysTick reload for one control period.
    const RELOAD: u32 = CORE_HZ / RATE_HZ - 1;

    /// The recorded frames (24-byte little-endian records).
    static FRAMES: &[u8] = include_bytes!("../../replay/frames.bin");

    /// Parses record `i` field by field (no transmute: the layout is the wire's).
    fn frame_at(i: usize) -> Option<SensorFrame> {
        let b = FRAMES.get(i * 24..i * 24 + 24)?;
        let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]);
        let i16_at = |o: usize| i16::from_le_bytes([b[o], b[o + 1]]);
        Some(SensorFrame {
            t_us: u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
            seq: u32::from_le_bytes([b[8], b[9], b[10], b[11]]),
            theta1_count: u16_at(12),
            elbow_count: u16_at(14),
            f_t_code: i16_at(16),
            f_n_code: i16_at(18),
            belt_count: i16_at(20),
            flags: u16_at(22),
        })
    }

    /// An up-counting tick clock from SysTick (which counts down from `RELOAD`):
    /// `ticks = periods * (RELOAD + 1) + (RELOAD - current)`, at the core clock.
    struct SysTickClock {
        periods: Cell<u32>,
    }

    impl TickClock for SysTickClock {
        fn ticks(&self) -> u32 {
            let current = SYST::get_current();
            self.periods.get().wrapping_mul(RELOAD + 1).wrapping_add(RELOAD - current.min(RELOAD))
        }
        fn ticks_per_second(&self) -> u32 {
            CORE_HZ
        }
    }

    /// The replay board: frames from flash, commands to the defmt log, time from SysTick.
    struct ReplayBoard<'a> {
        next: usize,
        clock: &'a SysTickClock,
        syst: SYST,
    }

    impl Board for ReplayBoard<'_> {
        type Error = core::convert::Infallible;

        fn next_frame(&mut self) -> Result<Option<SensorFrame>, Self::Error> {
            let frame = frame_at(self.next);
            if frame.is_some() {
                // The frame of period k arrives at the tick that starts period k.
                while !self.syst.has_wrapped() {
                    cortex_m::asm::nop();
                }
                self.clock.periods.set(self.clock.periods.get().wrapping_add(1));
                self.next += 1;
            }
            Ok(frame)
        }

        fn send(&mut self, c: &ActuatorCommand) -> Result<(), Self::Error> {
            defmt::info!(
                "cmd seq={=u32} u1={=i16} u2={=i16} status={=u32} ticks={=u32}",
                c.seq,
                c.u1_code,
                c.u2_code,
                c.status,
                c.step_ticks
            );
            Ok(())
        }

        fn now_us(&self) -> u64 {
            // Replay: the step starts at the sample time of the frame it answers.
            0
        }
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
        let clock = SysTickClock { periods: Cell::new(0) };
        let mut board = ReplayBoard { next: 0, clock: &clock, syst: cp.SYST };
        let mut fw = match Firmware::new(Config::default()) {
            Ok(fw) => fw,
            Err(_) => {
                defmt::error!("invalid firmware configuration");
                semihosting::process::exit(2);
            }
        };
        defmt::info!("replay: {=usize} frames", FRAMES.len() / 24);
        let mut worst = 0u32;
        while let Ok(Some(frame)) = board.next_frame() {
            let cmd = fw.step(frame.t_us, &frame, &clock);
            worst = worst.max(cmd.step_ticks);
            let _ = board.send(&cmd);
        }
        defmt::info!("done: worst step {=u32} ticks", worst);
        semihosting::process::exit(0);
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
