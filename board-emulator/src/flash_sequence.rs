//! The flash interface's programming sequence, checked: rsemu's `st.flash`
//! models what the part does (the keys, `LOCK`, `BSY`, the error flags); this
//! wrapper of its register window reports, into the board's [`ErrorLog`], every
//! sequence the reference board cannot take, naming the register and the value,
//! as the other models do.
//!
//! From RM0090 rev 21 §3.5.1 ("Unlocking the Flash control register": "any
//! wrong sequence will return a bus error and lock up the FLASH_CR register
//! until the next reset"), §3.6 (erase and program: `BSY` clear before a new
//! operation, `PSIZE` for the supply), §3.9.5 to §3.9.7 (the registers), and
//! the board: a 3.3 V supply without `VPP` (x64 parallelism needs `VPP`,
//! RM0090 table 7), the code in sectors 0 to 3, the record in sector 4
//! (docs/hardware.md), so an erase of any other sector, or a mass erase,
//! would erase the image.
//!
//! Caught:
//! - `FLASH_KEYR`: a value other than `KEY1` then `KEY2`, or a key written
//!   while `FLASH_CR` is already unlocked;
//! - `FLASH_CR` written while locked (the part ignores the write);
//! - an erase started (`STRT`) with `BSY` set, without `SER`, with `MER`, of a
//!   sector other than the record's, or at x64 parallelism; programming (`PG`)
//!   at x64 parallelism;
//! - `FLASH_SR` read with an error flag set (`OPERR`, `WRPERR`, `PGAERR`,
//!   `PGPERR`, `PGSERR`): rsemu found the part would refuse an operation (for
//!   example a program into cells not erased, or a write to the array without
//!   `PG`).
//!
//! Not caught here: a program into another sector than the record's with the
//! sequence right (the array's write port is rsemu's own region).

use std::sync::{Arc, Mutex, PoisonError};

use rsemu::core::space::{AccessConstraints, MemAttrs, MemOps, MemResult};

use crate::device::{BoardError, ErrorLog};

/// The flash interface's base (RM0090 §2.3).
pub const FLASH_IF: u32 = 0x4002_3C00;
/// `FLASH_KEYR`'s unlock keys (RM0090 §3.5.1).
pub const KEYS: [u32; 2] = [0x4567_0123, 0xCDEF_89AB];
/// The sector the board's record lives in (docs/hardware.md).
pub const RECORD_SECTOR_NUMBER: u32 = 4;

const KEYR: u64 = 0x04;
const SR: u64 = 0x0C;
const CR: u64 = 0x10;
const CR_LOCK: u32 = 1 << 31;
const CR_STRT: u32 = 1 << 16;
const CR_PG: u32 = 1 << 0;
const CR_SER: u32 = 1 << 1;
const CR_MER: u32 = 1 << 2;
const SR_BSY: u32 = 1 << 16;
/// `OPERR`, `WRPERR`, `PGAERR`, `PGPERR`, `PGSERR` (RM0090 §3.9.5).
const SR_ERRORS: [(u32, &str); 5] = [
    (1 << 1, "OPERR (operation error)"),
    (1 << 4, "WRPERR (write protection error)"),
    (1 << 5, "PGAERR (programming alignment error)"),
    (1 << 6, "PGPERR (programming parallelism error)"),
    (1 << 7, "PGSERR (programming sequence error: an array write without PG, or into cells not erased)"),
];

fn name(offset: u64) -> String {
    let r = match offset {
        KEYR => "FLASH_KEYR",
        SR => "FLASH_SR",
        CR => "FLASH_CR",
        _ => "FLASH",
    };
    format!("{r} ({:#010x})", u64::from(FLASH_IF) + offset)
}

/// The checking window: the wrapped `st.flash` register window.
#[derive(Debug)]
pub struct FlashSequence {
    inner: Arc<dyn MemOps>,
    errors: ErrorLog,
    /// The next key expected while `LOCK` is set (0: `KEY1`, 1: `KEY2`).
    key: Mutex<usize>,
}

impl FlashSequence {
    /// Wraps `inner` (`st.flash`'s `regs` window), reporting into `errors`.
    pub fn new(inner: Arc<dyn MemOps>, errors: ErrorLog) -> Self {
        Self { inner, errors, key: Mutex::new(0) }
    }

    fn word(&self, offset: u64) -> u32 {
        let mut w = [0u8; 4];
        let _ = self.inner.read(offset, &mut w, MemAttrs::DEBUG);
        u32::from_le_bytes(w)
    }

    fn check_write(&self, offset: u64, value: u32) -> Option<BoardError> {
        let cr = self.word(CR);
        let locked = cr & CR_LOCK != 0;
        match offset {
            KEYR => {
                let mut key = self.key.lock().unwrap_or_else(PoisonError::into_inner);
                if !locked {
                    return Some(BoardError::new(
                        name(offset),
                        value,
                        "a key written while FLASH_CR is unlocked: a wrong sequence, a bus error that locks FLASH_CR until reset (RM0090 3.5.1); unlock only when LOCK reads 1",
                    ));
                }
                if value != KEYS[*key] {
                    *key = 0;
                    return Some(BoardError::new(
                        name(offset),
                        value,
                        format!(
                            "not the unlock sequence KEY1 {:#010x} then KEY2 {:#010x} (expected {}): a bus error that locks FLASH_CR until reset (RM0090 3.5.1)",
                            KEYS[0],
                            KEYS[1],
                            if *key == 0 { "KEY1" } else { "KEY2" }
                        ),
                    ));
                }
                *key = (*key + 1) % 2;
                None
            }
            CR if locked => Some(BoardError::new(
                name(offset),
                value,
                "written while locked (LOCK reads 1): the part ignores it; unlock with KEY1, KEY2 into FLASH_KEYR first (RM0090 3.5.1)",
            )),
            CR => {
                let psize = (value >> 8) & 0b11;
                let sector = (value >> 3) & 0xF;
                let starting = value & CR_STRT != 0 && cr & CR_STRT == 0;
                if (starting || value & CR_PG != 0) && self.word(SR) & SR_BSY != 0 {
                    return Some(BoardError::new(
                        name(offset),
                        value,
                        "an operation started while FLASH_SR.BSY is set: poll BSY clear first (RM0090 3.6.3)",
                    ));
                }
                if (starting || value & CR_PG != 0) && psize == 0b11 {
                    return Some(BoardError::new(
                        name(offset),
                        value,
                        "PSIZE x64 needs an external VPP, which the board does not have: x32 (PSIZE 0b10) at 3.3 V (RM0090 table 7)",
                    ));
                }
                if starting && value & CR_MER != 0 {
                    return Some(BoardError::new(
                        name(offset),
                        value,
                        "a mass erase: it would erase the image (the record is sector 4 alone, docs/hardware.md)",
                    ));
                }
                if starting && value & CR_SER == 0 {
                    return Some(BoardError::new(name(offset), value, "STRT without SER or MER: no erase is selected (RM0090 3.6.3)"));
                }
                if starting && sector != RECORD_SECTOR_NUMBER {
                    return Some(BoardError::new(
                        name(offset),
                        value,
                        format!(
                            "erases sector {sector}: the image lives in sectors 0 to 3, the record in sector {RECORD_SECTOR_NUMBER} (docs/hardware.md)"
                        ),
                    ));
                }
                None
            }
            _ => None,
        }
    }
}

impl MemOps for FlashSequence {
    fn read(&self, offset: u64, dst: &mut [u8], attrs: MemAttrs) -> MemResult {
        self.inner.read(offset, dst, attrs)?;
        if offset == SR && dst.len() == 4 && !attrs.debug {
            let sr = u32::from_le_bytes([dst[0], dst[1], dst[2], dst[3]]);
            let set: Vec<&str> = SR_ERRORS.iter().filter(|(b, _)| sr & b != 0).map(|(_, n)| *n).collect();
            if !set.is_empty() {
                self.errors.push(BoardError::new(name(offset), sr, format!("the part refused an operation: {}", set.join(", "))));
            }
        }
        Ok(())
    }

    fn write(&self, offset: u64, src: &[u8], attrs: MemAttrs) -> MemResult {
        if !attrs.debug {
            let mut w = [0u8; 4];
            let n = src.len().min(4);
            w[..n].copy_from_slice(&src[..n]);
            if let Some(e) = self.check_write(offset & !3, u32::from_le_bytes(w)) {
                self.errors.push(e);
            }
        }
        self.inner.write(offset, src, attrs)
    }

    fn constraints(&self) -> AccessConstraints {
        self.inner.constraints()
    }
}
