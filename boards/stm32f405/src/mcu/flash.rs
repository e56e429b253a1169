//! The settings record's sector (`arm_app::record`): sector 4 of the
//! STM32F405's flash, 64 KiB at `0x0801_0000`, just above the images' 64 KiB
//! budget (memory.x gives the images 64 KiB, so the linker refuses an image that
//! would reach it). Behind embedded-storage's `NorFlash`, addressed from the
//! sector's start. RM0090 3.5 "Erase and program operations": unlock with the
//! two keys, sector erase (SER, SNB, STRT), word programming (PG, PSIZE x32 at
//! 2.7 to 3.6 V), BSY polled, errors read from SR and cleared, locked again.
//!
//! A sector erase stalls the core (code runs from the same bank) for up to
//! 1.1 s at x32 (DS8626 "Flash memory programming"): the watchdog's timeout is
//! stretched around it ([`super::iwdg::stretched`]) and no tick runs meanwhile;
//! the bring-up's save is refused unless the drivers are disabled.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash, check_erase, check_read, check_write,
};
use stm32f4::stm32f405 as pac;

/// The sector's address.
pub const SECTOR_ADDR: u32 = 0x0801_0000;
/// The sector's size, bytes.
pub const SECTOR_BYTES: usize = 64 * 1024;
/// Sector 4's number (RM0090 table 5).
const SECTOR: u8 = 4;
/// The watchdog's timeout during an erase, us: twice the worst erase.
const ERASE_WATCHDOG_US: u32 = 2_200_000;
/// Polls of BSY before giving up on a word (a word takes 16 us at most) or an
/// erase (the erase stalls the core: BSY reads clear after it).
const BUSY_POLLS: u32 = 10_000_000;

/// A flash operation that failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlashError {
    /// Out of the sector, or misaligned.
    Access(NorFlashErrorKind),
    /// SR reported an error (its bits: PGSERR, PGPERR, PGAERR, WRPERR, OPERR).
    Status(u32),
    /// BSY never cleared.
    Busy,
}

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            Self::Access(k) => *k,
            _ => NorFlashErrorKind::Other,
        }
    }
}

/// Sector 4, owned by the arm application (one owner: the arm image creates
/// it once).
#[derive(Debug, Default)]
pub struct SettingsFlash(());

fn regs() -> &'static pac::flash::RegisterBlock {
    // SAFETY: the flash interface is used by this module only, from the idle
    // loop inside a critical section.
    unsafe { &*pac::FLASH::ptr() }
}

const SR_ERRORS: u32 = 0b1111_0010; // PGSERR | PGPERR | PGAERR | WRPERR | OPERR

fn wait_ready() -> Result<(), FlashError> {
    let f = regs();
    for _ in 0..BUSY_POLLS {
        if f.sr().read().bsy().bit_is_clear() {
            let sr = f.sr().read().bits();
            // Clear every flag (write 1 to clear).
            f.sr().write(|w| unsafe { w.bits(sr) });
            return if sr & SR_ERRORS == 0 { Ok(()) } else { Err(FlashError::Status(sr & SR_ERRORS)) };
        }
    }
    Err(FlashError::Busy)
}

fn unlocked<T>(op: impl FnOnce(&pac::flash::RegisterBlock) -> Result<T, FlashError>) -> Result<T, FlashError> {
    let f = regs();
    wait_ready()?;
    if f.cr().read().lock().bit_is_set() {
        f.keyr().write(|w| unsafe { w.bits(0x4567_0123) });
        f.keyr().write(|w| unsafe { w.bits(0xCDEF_89AB) });
    }
    let out = op(f);
    f.cr().write(|w| w.lock().set_bit());
    out
}

impl ErrorType for SettingsFlash {
    type Error = FlashError;
}

impl ReadNorFlash for SettingsFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, out: &mut [u8]) -> Result<(), FlashError> {
        check_read(self, offset, out.len()).map_err(FlashError::Access)?;
        for (i, b) in out.iter_mut().enumerate() {
            // SAFETY: inside sector 4 (checked above), memory-mapped flash.
            *b = unsafe { core::ptr::read_volatile((SECTOR_ADDR + offset + i as u32) as *const u8) };
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        SECTOR_BYTES
    }
}

impl NorFlash for SettingsFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = SECTOR_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        check_erase(self, from, to).map_err(FlashError::Access)?;
        if from == to {
            return Ok(());
        }
        super::iwdg::stretched(ERASE_WATCHDOG_US, || {
            unlocked(|f| {
                // LOCK written 0 (no effect): `write` starts from CR's reset value,
                // which has LOCK set, and writing LOCK 1 locks CR at once (RM0090
                // 3.9.7) so that STRT and PG would be ignored and the save fail on
                // silicon (found by the emulated image, issue 38).
                f.cr().write(|w| unsafe { w.psize().bits(0b10).ser().set_bit().snb().bits(SECTOR) }.lock().clear_bit());
                f.cr().modify(|_, w| w.strt().set_bit());
                let r = wait_ready();
                f.cr().modify(|_, w| w.ser().clear_bit());
                r
            })
        })
    }

    fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), FlashError> {
        check_write(self, offset, data.len()).map_err(FlashError::Access)?;
        unlocked(|f| {
            // LOCK written 0, as in `erase`.
            f.cr().write(|w| unsafe { w.psize().bits(0b10) }.pg().set_bit().lock().clear_bit());
            let mut r = Ok(());
            for (i, word) in data.chunks_exact(4).enumerate() {
                let addr = SECTOR_ADDR + offset + 4 * i as u32;
                // SAFETY: a word inside sector 4 (checked above), PG set.
                unsafe { core::ptr::write_volatile(addr as *mut u32, u32::from_le_bytes([word[0], word[1], word[2], word[3]])) };
                r = wait_ready();
                if r.is_err() {
                    break;
                }
            }
            f.cr().modify(|_, w| w.pg().clear_bit());
            r
        })
    }
}
