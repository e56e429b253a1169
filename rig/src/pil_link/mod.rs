//! The processor-in-the-loop bridge: the MCU image (`boards/stm32f405/src/bin/pil.rs`)
//! runs in QEMU's `netduinoplus2` (an STM32F405) or on a board, and this link
//! joins its USART1 to the rig's lockstep loop, so the plant, the scenarios and
//! the outputs are those of the SIL rig.
//!
//! Two transports carry the same byte stream ([`PilTarget`]):
//! - **QEMU** (PIL): `qemu-system-arm -machine netduinoplus2 -icount shift=0 ...
//!   -kernel IMAGE`, the bytes through one of two paths ([`QemuLink`]):
//!   - **semihosting FIFOs** (the default): the link makes two named pipes
//!     `PREFIX.down` and `PREFIX.up` and passes `pil-fifo PREFIX` as QEMU's
//!     semihosting command line; the image reads and writes them with
//!     semihosting calls, a whole frame per call (a median 7 600 periods per
//!     wall second on a shared 2-core machine, against 290 through the USART;
//!     docs/measurements.md);
//!   - **the emulated USART1**: the link listens on a Unix socket and QEMU's
//!     `-chardev socket,path=SOCK -serial chardev:plant` joins it to USART1.
//!     QEMU's USART model takes a byte only once the image has read the last
//!     one, one emulator main-loop turn and two thread hand-overs per byte: 300
//!     to 450 periods per wall second. It exercises the board's USART driver.
//!
//!   Either way the image's defmt log arrives on QEMU's standard output
//!   (semihosting) and is decoded here with `defmt-decoder` from the image's own ELF.
//! - **A serial port** (hardware in the loop): the board's USART1 at 2 Mbaud
//!   through a USB-serial adapter (docs/hardware.md "Reference board"), raw 8N1,
//!   no flow control. Nothing is spawned and no log is captured: a board logs
//!   defmt over RTT to a debug probe (probe-rs).
//!
//! Over either, one protocol implementation speaks [`firmware::pil`] (postcard,
//! CRC-32, COBS): a lone `0x00` (it ends any partial frame left on the line),
//! [`Downlink::Hello`](firmware::pil::Downlink::Hello) until the image says
//! [`Uplink::Hello`](firmware::pil::Uplink::Hello) (a board may have
//! booted long before the port was opened), the protocol version check, the
//! configuration, then each period's frame and its answer.
//!
//! Lockstep: the plant owns time and the image's step starts at the frame's
//! sample time, so the command's `t_sent_us` (the image's own clock) decides when
//! it takes effect, as in-process. Wall time only guards against a hung or dead
//! image: no answer within the answer timeout, QEMU exiting, its socket closing
//! or the serial port going away end the run with
//! [`RunError::FirmwareLost`](crate::record::RunError::FirmwareLost),
//! never a hang.

mod counts;
mod defmt_log;
mod figures;
mod link;
mod pipe;
mod qemu;
mod rate;
mod target;

pub use counts::{CORE_HZ, PilCounts, STEP_BUDGET_INSTRUCTIONS, step_budget};
pub use defmt_log::{LogLine, LogSink, decode_log};
pub use figures::BOARD_LOG_NOTE;
pub use link::PilLink;
pub use pipe::open_port;
pub use qemu::ICOUNT_SHIFT;
pub use rate::{PilRate, measure_default_rate, measure_rate};
pub use target::{
    BAUD_RANGE, BUILD_HINT, DEFAULT_BAUD, ImageError, PilOptions, PilTarget, QemuLink, check_faults, check_image, default_image,
};

#[cfg(test)]
mod tests;
