//! USART1, the bring-up and telemetry line (RM0090 30 "Universal synchronous
//! asynchronous receiver transmitter"): the image's bytes out, the host's bytes
//! in, and its receive interrupt (`irq`, wired to the NVIC's line 37).
//!
//! Strict, at every byte sent or received: the line is 8N1 at 2 Mbaud from
//! PCLK2 = 84 MHz (docs/hardware.md), so `UE`, 8 data bits (`M = 0`), no
//! parity, one stop bit, a `BRR` within 2 % of 2 Mbaud (oversampling by 16:
//! `BRR = 42` gives it exactly), `TE` to send and `RE` to receive; otherwise a
//! [`BoardError`] naming the register and its value.
//!
//! The line paces itself to the image: the next byte from the host enters DR
//! when the last was read, so the receiver never overruns (a real 2 Mbaud line
//! delivers a byte every 5 us). Bytes sent leave at once (`TXE` and `TC` always
//! set). Not modelled: the character time, break, LIN, IrDA, smartcard, DMA.

use std::collections::VecDeque;

use crate::device::{BoardError, RegisterModel, Result2};

const BASE: u32 = 0x4001_1000;
const SR: u32 = 0x00;
const DR: u32 = 0x04;
const BRR: u32 = 0x08;
const CR1: u32 = 0x0C;
const CR2: u32 = 0x10;
const CR3: u32 = 0x14;
const GTPR: u32 = 0x18;

const RXNE: u32 = 1 << 5;
const TC: u32 = 1 << 6;
const TXE: u32 = 1 << 7;

const RE: u32 = 1 << 2;
const TE: u32 = 1 << 3;
const RXNEIE: u32 = 1 << 5;
const TCIE: u32 = 1 << 6;
const TXEIE: u32 = 1 << 7;
const PCE: u32 = 1 << 10;
const M: u32 = 1 << 12;
const UE: u32 = 1 << 13;
const OVER8: u32 = 1 << 15;

/// The line's rate (docs/hardware.md), baud.
pub const BAUD: u32 = 2_000_000;

/// USART1 with the host's side of the line.
#[derive(Debug, Default)]
pub struct Usart1 {
    cr1: u32,
    cr2: u32,
    cr3: u32,
    brr: u32,
    gtpr: u32,
    /// The byte in DR, not yet read (`RXNE`).
    rx_dr: Option<u8>,
    /// Bytes the host sent, waiting to enter DR.
    pub rx: VecDeque<u8>,
    /// Bytes the image sent, not yet taken by the host.
    pub tx: Vec<u8>,
}

impl Usart1 {
    /// The line's configuration as the board needs it, or why not.
    fn check(&self, receiving: bool) -> Result2<()> {
        let cr1 = |why: String| Err(BoardError::new(format!("USART1_CR1 ({:#010x})", BASE + CR1), self.cr1, why));
        if self.cr1 & UE == 0 {
            return cr1("UE = 0: the USART is disabled".into());
        }
        if self.cr1 & M != 0 || self.cr1 & PCE != 0 {
            return cr1("9 data bits or parity: the line is 8N1".into());
        }
        let enable = if receiving { RE } else { TE };
        if self.cr1 & enable == 0 {
            return cr1(format!(
                "{} = 0: the {} is off",
                if receiving { "RE" } else { "TE" },
                if receiving { "receiver" } else { "transmitter" }
            ));
        }
        if (self.cr2 >> 12) & 0b11 != 0 {
            return Err(BoardError::new(format!("USART1_CR2 ({:#010x})", BASE + CR2), self.cr2, "stop bits other than 1: the line is 8N1"));
        }
        let over = if self.cr1 & OVER8 != 0 { 8.0 } else { 16.0 };
        let div = f64::from(self.brr >> 4) + f64::from(self.brr & 0xF) / over;
        let baud = f64::from(crate::spi1::APB2_HZ) / (over * div.max(1.0 / 16.0));
        if (baud / f64::from(BAUD) - 1.0).abs() > 0.02 {
            return Err(BoardError::new(
                format!("USART1_BRR ({:#010x})", BASE + BRR),
                self.brr,
                format!("{:.0} baud at PCLK2 84 MHz: the line runs at 2 Mbaud (within 2 %)", baud),
            ));
        }
        Ok(())
    }

    fn sr(&self) -> u32 {
        TXE | TC | if self.rx_dr.is_some() { RXNE } else { 0 }
    }

    /// Moves the host's next byte into DR if DR is free and the receiver is on.
    ///
    /// # Errors
    /// [`BoardError`] when a byte waits and the receiver is misconfigured.
    pub fn deliver(&mut self) -> Result2<()> {
        if self.rx_dr.is_none() && !self.rx.is_empty() && self.cr1 & UE != 0 {
            self.check(true)?;
            self.rx_dr = self.rx.pop_front();
        }
        Ok(())
    }
}

impl RegisterModel for Usart1 {
    fn read(&mut self, offset: u32) -> Result2<u32> {
        match offset {
            SR => Ok(self.sr()),
            DR => {
                let b = self.rx_dr.take().map_or(0, u32::from);
                self.deliver()?;
                Ok(b)
            }
            BRR => Ok(self.brr),
            CR1 => Ok(self.cr1),
            CR2 => Ok(self.cr2),
            CR3 => Ok(self.cr3),
            GTPR => Ok(self.gtpr),
            _ => Err(unmodelled(offset)),
        }
    }

    fn write(&mut self, offset: u32, value: u32) -> Result2<()> {
        match offset {
            SR => Ok(()),
            DR => {
                self.check(false)?;
                self.tx.push(value as u8);
                Ok(())
            }
            BRR => {
                self.brr = value & 0xFFFF;
                Ok(())
            }
            CR1 => {
                self.cr1 = value & 0xBFFF;
                self.deliver()
            }
            CR2 => {
                self.cr2 = value & 0x7F7F;
                Ok(())
            }
            CR3 => {
                self.cr3 = value & 0xFFF;
                Ok(())
            }
            GTPR => {
                self.gtpr = value & 0xFFFF;
                Ok(())
            }
            _ => Err(unmodelled(offset)),
        }
    }

    fn peek(&self, offset: u32) -> u32 {
        match offset {
            SR => self.sr(),
            DR => self.rx_dr.map_or(0, u32::from),
            BRR => self.brr,
            CR1 => self.cr1,
            CR2 => self.cr2,
            CR3 => self.cr3,
            GTPR => self.gtpr,
            _ => 0,
        }
    }

    fn irq(&self) -> bool {
        (self.cr1 & RXNEIE != 0 && self.rx_dr.is_some()) || (self.cr1 & (TXEIE | TCIE) != 0)
    }

    fn reset(&mut self) {
        // The host's queues are the line's, not the MCU's.
        *self = Self { rx: std::mem::take(&mut self.rx), tx: std::mem::take(&mut self.tx), ..Self::default() };
    }
}

fn unmodelled(offset: u32) -> BoardError {
    BoardError::new(
        format!("USART1 +{offset:#x} ({:#010x})", BASE + offset),
        0,
        "a register the USART1 model does not implement (SR, DR, BRR, CR1 to CR3, GTPR only)",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_carries_bytes_both_ways_at_2_mbaud_8n1() {
        let mut u = Usart1::default();
        u.write(BRR, 42).unwrap();
        u.write(CR1, UE | TE | RE | RXNEIE).unwrap();
        u.write(DR, 0x55).unwrap();
        assert_eq!(u.tx, [0x55]);
        u.rx.extend([1, 2]);
        u.deliver().unwrap();
        assert!(u.irq(), "RXNE with RXNEIE raises the interrupt");
        assert_eq!((u.read(DR).unwrap(), u.read(DR).unwrap()), (1, 2));
        assert!(!u.irq());
    }

    #[test]
    fn another_rate_or_frame_format_is_an_error_naming_the_register() {
        for (reg, value, name) in [(BRR, 56, "USART1_BRR"), (CR1, UE | TE | RE | M, "USART1_CR1"), (CR1, UE | RE, "USART1_CR1")] {
            let mut u = Usart1::default();
            u.write(BRR, 42).unwrap();
            u.write(CR1, UE | TE | RE).unwrap();
            u.write(reg, value).unwrap();
            let e = u.write(DR, 0x55).unwrap_err();
            assert!(e.register.starts_with(name) && e.value == value, "{name}: {e}");
        }
        let mut u = Usart1::default();
        u.write(BRR, 56).unwrap();
        u.write(CR1, UE | TE | RE).unwrap();
        assert!(u.write(DR, 1).unwrap_err().why.contains("1500000 baud"));
    }
}
