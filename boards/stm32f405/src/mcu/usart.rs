//! USART1 on PA9 / PA10 (RM0090 30): 8N1 at 2 Mbaud from APB2 at 84 MHz, polled
//! with bounded waits, the line the PIL wire and the arm's telemetry use.
//! QEMU's `netduinoplus2` wires it to its first serial port (`-serial`).

use stm32f4::stm32f405 as pac;

use super::gpio;
use crate::pins;

/// The link's rate, baud (docs/hardware.md).
pub const BAUD: u32 = 2_000_000;

fn usart() -> &'static pac::usart1::RegisterBlock {
    // SAFETY: USART1 belongs to one context of each image (the PIL loop, the
    // arm's idle loop).
    unsafe { &*pac::USART1::ptr() }
}

/// Sets USART1 and its pins up; `rx_interrupt` enables the receive interrupt
/// line (it only wakes the core from WFI: the handler is never run with
/// interrupts masked).
pub fn init(rx: bool) {
    gpio::configure(&pins::USART1_TX);
    if rx {
        gpio::configure(&pins::USART1_RX);
    }
    let u = usart();
    // 84 MHz / 2 Mbaud = 42: mantissa 2, fraction 10 (oversampling by 16).
    u.brr().write(|w| unsafe { w.bits((crate::clock_tree::PCLK2_HZ / BAUD) as u16) });
    u.cr1().write(|w| w.ue().set_bit().te().set_bit().re().bit(rx).rxneie().bit(rx));
}

/// A received byte, if one is waiting.
pub fn try_read() -> Option<u8> {
    let u = usart();
    let sr = u.sr().read();
    // An overrun (ORE) is cleared by the read below; the framing layer drops the
    // damaged frame.
    (sr.rxne().bit_is_set() || sr.ore().bit_is_set()).then(|| u.dr().read().dr().bits() as u8)
}

/// Whether a byte can be written now.
pub fn can_write() -> bool {
    usart().sr().read().txe().bit_is_set()
}

/// Writes one byte; waits for room (one byte is 5 us at 2 Mbaud; bounded).
pub fn write(byte: u8) {
    for _ in 0..100_000 {
        if can_write() {
            break;
        }
    }
    usart().dr().write(|w| unsafe { w.dr().bits(u16::from(byte)) });
}

/// Writes all of `bytes`.
pub fn write_all(bytes: &[u8]) {
    bytes.iter().for_each(|&b| write(b));
}
