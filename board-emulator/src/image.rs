//! The `arm` ELF as a debug probe sees it (probe-rs's flashing path): its
//! loadable segments, placed in the STM32F405's flash from `0x0800_0000`
//! (memory.x), and the symbols the emulator reads in RAM: the monitor block
//! (`arm_app::monitor`), defmt's RTT control block, the stack's bounds.

use std::path::{Path, PathBuf};

use object::{Object, ObjectSegment, ObjectSymbol};

/// Where the flash starts (RM0090 2.3.1, memory.x).
pub const FLASH_BASE: u32 = 0x0800_0000;
/// The settings record's sector (sector 4, `arm_app::record`).
pub const RECORD_SECTOR: u32 = 0x0801_0000;
/// The flash the reference board's STM32F405RG has, bytes (1 MiB).
pub const FLASH_BYTES: u32 = 1 << 20;

/// Why an image was not taken.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ImageError {
    /// The file could not be read: missing, not a regular file, or over its
    /// bound (`tables::input::ELF_IMAGE`).
    #[error("{message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the file (and the bound).
        message: String,
    },
    /// Not a 32-bit little-endian ARM ELF, or a broken one.
    #[error("{path} is not an ARM ELF image: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A loadable segment outside the flash below the settings sector.
    #[error("{path}: a loadable segment at {address:#010x} ({size} bytes) is outside the image's flash [0x08000000, 0x08010000)")]
    Placement {
        /// The file.
        path: PathBuf,
        /// The segment's load address.
        address: u64,
        /// Its size, bytes.
        size: u64,
    },
    /// A symbol the emulator needs is missing (an image of another kind).
    #[error("{path}: no symbol `{symbol}`: this is not the `arm` image of this workspace")]
    Symbol {
        /// The file.
        path: PathBuf,
        /// The symbol.
        symbol: &'static str,
    },
}

/// The image: what goes into flash, and where its RAM symbols are.
#[derive(Debug, Clone)]
pub struct ArmImage {
    /// The file it came from.
    pub path: PathBuf,
    /// The flash's content from [`FLASH_BASE`] up to the image's end (`0xFF` in gaps).
    pub flash: Vec<u8>,
    /// `PAINLEVE_MONITOR`'s address (`arm_app::monitor::Monitor`).
    pub monitor: u32,
    /// `_SEGGER_RTT`'s address (defmt's RTT control block), if linked.
    pub rtt: Option<u32>,
    /// The stack's region `[low, top)` (the painted-stack probe's: with flip-link
    /// the stack sits at RAM's start, below the static data).
    pub stack: (u32, u32),
}

impl ArmImage {
    /// Reads the ELF at `path`.
    ///
    /// # Errors
    /// [`ImageError`]: unreadable, not an ARM ELF, a segment outside the image's
    /// flash, a missing symbol.
    pub fn load(path: &Path) -> Result<Self, ImageError> {
        let bytes = tables::input::read(path, tables::input::ELF_IMAGE)
            .map_err(|e| ImageError::Read { path: path.into(), message: e.to_string() })?;
        Self::parse(path, &bytes)
    }

    fn parse(path: &Path, bytes: &[u8]) -> Result<Self, ImageError> {
        let format = |message: String| ImageError::Format { path: path.into(), message };
        let elf = object::File::parse(bytes).map_err(|e| format(e.to_string()))?;
        if elf.architecture() != object::Architecture::Arm || !elf.is_little_endian() {
            return Err(format(format!("architecture {:?}", elf.architecture())));
        }
        let mut flash = Vec::new();
        for seg in elf.segments() {
            let data = seg.data().map_err(|e| format(e.to_string()))?;
            if data.is_empty() {
                continue;
            }
            // Load addresses (LMA): .data's initial values sit in flash too.
            let (addr, size) = (seg.address(), data.len() as u64);
            let lma = load_address(&elf, addr).unwrap_or(addr);
            let end = lma + size;
            if lma < u64::from(FLASH_BASE) || end > u64::from(RECORD_SECTOR) {
                return Err(ImageError::Placement { path: path.into(), address: lma, size });
            }
            let (from, to) = ((lma - u64::from(FLASH_BASE)) as usize, (end - u64::from(FLASH_BASE)) as usize);
            if flash.len() < to {
                flash.resize(to, 0xFF);
            }
            flash[from..to].copy_from_slice(data);
        }
        if flash.is_empty() {
            return Err(format("no loadable segment".into()));
        }
        let symbol = |name: &'static str| {
            elf.symbols()
                .find(|s| s.name() == Ok(name))
                .map(|s| s.address() as u32)
                .ok_or(ImageError::Symbol { path: path.into(), symbol: name })
        };
        let monitor = symbol("PAINLEVE_MONITOR")?;
        let rtt = symbol("_SEGGER_RTT").ok();
        let top = symbol("_stack_start")?;
        let sdata = symbol("__sdata")?;
        let euninit = symbol("__euninit")?;
        const RAM_START: u32 = 0x2000_0000;
        let low = if top <= sdata { RAM_START } else { euninit };
        Ok(Self { path: path.into(), flash, monitor, rtt, stack: (low, top) })
    }
}

impl ArmImage {
    /// Which bytes these are: the CRC-32 (CRC-32/ISO-HDLC, zlib's `crc32`) of
    /// [`ArmImage::flash`], the flash from `FLASH_BASE` to the image's end as it is
    /// loaded (`0xFF` in gaps). Two files with the same loaded bytes have the same
    /// value whatever their paths and debug info; the images carry no GNU build id
    /// (rust-lld adds none for the MCU target).
    #[must_use]
    pub fn crc32(&self) -> u32 {
        crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&self.flash)
    }

    /// One line naming the image for a run's log: its path (made absolute where
    /// it can be), its bytes of flash and their [`ArmImage::crc32`], e.g.
    /// `/w/target/thumbv7em-none-eabihf/mcu/arm (64 748 B of flash, CRC-32 0x1a2b3c4d)`.
    #[must_use]
    pub fn describe(&self) -> String {
        let path = std::path::absolute(&self.path).unwrap_or_else(|_| self.path.clone());
        format!("{} ({} B of flash, CRC-32 0x{:08x})", path.display(), self.flash.len(), self.crc32())
    }
}

/// The load address of the segment whose virtual address is `vaddr` (ELF
/// program headers: `p_paddr` is the LMA).
fn load_address(elf: &object::File<'_>, vaddr: u64) -> Option<u64> {
    match elf {
        object::File::Elf32(e) => {
            use object::read::elf::ProgramHeader;
            let endian = e.endian();
            e.elf_program_headers()
                .iter()
                .find(|p| u64::from(p.p_vaddr(endian)) == vaddr && p.p_type(endian) == object::elf::PT_LOAD)
                .map(|p| u64::from(p.p_paddr(endian)))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_images_id_is_zlibs_crc32_of_its_flash_bytes_and_ignores_its_path() {
        // CRC-32/ISO-HDLC's check value (the CRC RevEng catalogue): "123456789".
        let image = |path: &str| ArmImage { path: path.into(), flash: b"123456789".to_vec(), monitor: 0, rtt: None, stack: (0, 0) };
        assert_eq!(image("a/arm").crc32(), 0xCBF4_3926);
        assert_eq!(image("a/arm").crc32(), image("/elsewhere/copy").crc32());
        let mut other = image("a/arm");
        other.flash[0] ^= 1;
        assert_ne!(other.crc32(), image("a/arm").crc32());
        let line = image("a/arm").describe();
        assert!(line.ends_with("a/arm (9 B of flash, CRC-32 0xcbf43926)") && line.starts_with('/'), "{line}");
    }

    #[test]
    fn a_file_that_is_not_an_elf_is_refused_by_name() {
        let e = ArmImage::parse(Path::new("x.bin"), b"\x7fELF-no").unwrap_err();
        assert!(matches!(e, ImageError::Format { .. }), "{e}");
        assert!(e.to_string().contains("x.bin"));
    }
}
