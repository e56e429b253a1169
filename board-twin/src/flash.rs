//! The settings record's flash sector (sector 4 of the STM32F405: 64 KiB,
//! RM0090 3 "Embedded flash memory"), as the NOR flash it is: an erase sets a
//! whole sector to `0xFF`; programming can only clear bits (RM0090 3.5.4: a
//! word programmed again over non-erased bits is ANDed here, as the cells do);
//! writes are whole words (x32 parallelism at 2.7 to 3.6 V: 4 bytes). The bytes
//! are shared with the test's side ([`FlashModel::bytes`]) so that a test can
//! damage the record between two resets.

use std::{cell::RefCell, rc::Rc};

use arm_app::record::{self, RecordFault, Stored};
use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash, check_erase, check_read, check_write,
};

/// The sector's size, bytes (sector 4: 64 KiB).
pub const SECTOR_BYTES: usize = 64 * 1024;

/// The sector's bytes, shared between the model and its owner.
pub type FlashBytes = Rc<RefCell<Vec<u8>>>;

/// A flash access out of range or misaligned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlashError(pub NorFlashErrorKind);

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

/// One erasable sector of NOR flash.
#[derive(Debug, Clone)]
pub struct FlashModel {
    bytes: FlashBytes,
}

impl FlashModel {
    /// An erased sector (a board fresh from the factory).
    pub fn erased() -> Self {
        Self { bytes: Rc::new(RefCell::new(vec![0xFF; SECTOR_BYTES])) }
    }

    /// A sector holding the settings record of `stored` (a board brought up),
    /// written as the image's `Save` writes it.
    ///
    /// # Errors
    /// [`RecordFault`] when the record does not fit.
    pub fn saved(stored: &Stored) -> Result<Self, RecordFault> {
        let flash = Self::erased();
        record::save(&mut flash.clone(), stored)?;
        Ok(flash)
    }

    /// The sector of a board that was brought up: the record of calibration
    /// `cal` with every step done (`CalibrationRecord::brought_up`) and the
    /// firmware's `config`.
    ///
    /// # Errors
    /// As [`FlashModel::saved`].
    pub fn brought_up(cal: &arm_app::ArmCalibration, config: firmware::Config) -> Result<Self, RecordFault> {
        Self::saved(&Stored { calibration: arm_app::bringup::CalibrationRecord::brought_up(cal), config })
    }

    /// The sector's bytes (read them, or damage them).
    pub fn bytes(&self) -> FlashBytes {
        self.bytes.clone()
    }
}

impl ErrorType for FlashModel {
    type Error = FlashError;
}

impl ReadNorFlash for FlashModel {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, out: &mut [u8]) -> Result<(), FlashError> {
        check_read(self, offset, out.len()).map_err(FlashError)?;
        let start = offset as usize;
        out.copy_from_slice(&self.bytes.borrow()[start..start + out.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        SECTOR_BYTES
    }
}

impl NorFlash for FlashModel {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = SECTOR_BYTES;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        check_erase(self, from, to).map_err(FlashError)?;
        self.bytes.borrow_mut()[from as usize..to as usize].fill(0xFF);
        Ok(())
    }

    fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), FlashError> {
        check_write(self, offset, data.len()).map_err(FlashError)?;
        let start = offset as usize;
        let mut bytes = self.bytes.borrow_mut();
        for (cell, &b) in bytes[start..start + data.len()].iter_mut().zip(data) {
            *cell &= b;
        }
        Ok(())
    }
}
