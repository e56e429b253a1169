//! Where the PIL image runs and how long the link waits for it: QEMU on an
//! image, the bytes over one of two paths ([`QemuLink`]), or a serial port to a
//! board ([`PilTarget`]); the link's options ([`PilOptions`]), the faults each
//! target can inject, and where the image is by default.

use std::{
    ops::RangeInclusive,
    path::{Path, PathBuf},
};

use crate::{faults::LinkKind, record::RunError, scenario::Scenario};

/// Baud rate of the reference board's PIL link (USART1 at 2 Mbaud).
pub const DEFAULT_BAUD: u32 = 2_000_000;

/// Baud rates a serial link may be opened at: from the slowest common rate to
/// what fast USB-serial adapters reach.
pub const BAUD_RANGE: RangeInclusive<u32> = 9_600..=12_000_000;

/// How the bytes reach an image under QEMU. The frames, their checks and the
/// image's instruction counts are the same over both (`tests/e2e/pil.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum QemuLink {
    /// Two host FIFOs the image reads and writes through semihosting, a whole
    /// frame per call: the fast path (real time at 1 kHz and beyond).
    #[default]
    Semihosting,
    /// The emulated USART1 on a Unix socket (`-chardev socket`): one byte per
    /// emulator main-loop turn, about 0.4x real time at 1 kHz; it runs the
    /// board's USART driver.
    Usart,
}

/// Where the image runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PilTarget {
    /// Spawn QEMU's `netduinoplus2` on an image.
    Qemu {
        /// The PIL image (ELF for thumbv7em-none-eabihf).
        image: PathBuf,
        /// The QEMU executable (`qemu-system-arm`).
        qemu: PathBuf,
        /// How the bytes reach the image.
        link: QemuLink,
    },
    /// Whatever answers at the other end of a serial device: a board flashed with
    /// the PIL image (hardware in the loop), or QEMU's `-serial pty`.
    Serial {
        /// The device (`/dev/ttyUSB0`, `/dev/ttyACM0`, a pseudo-terminal).
        path: PathBuf,
        /// Line rate, baud (8N1, no flow control); see [`BAUD_RANGE`].
        baud: u32,
        /// The ELF flashed on the board, for its law's declaration
        /// (`PAINLEVE_LAW_SPEC`): what the scenario's `[law]` table binds to,
        /// held to the digest the image says in its Hello. `None`: the paper's
        /// laws.
        elf: Option<PathBuf>,
    },
}

impl PilTarget {
    /// How the bytes travel: `qemu-semihosting`, `qemu-socket` (the emulated
    /// USART) or `serial` (`summary.json`'s `pil.transport`).
    pub fn transport(&self) -> &'static str {
        match self {
            Self::Qemu { link: QemuLink::Semihosting, .. } => "qemu-semihosting",
            Self::Qemu { link: QemuLink::Usart, .. } => "qemu-socket",
            Self::Serial { .. } => "serial",
        }
    }
}

/// Where the image runs and how long to wait for it.
#[derive(Debug, Clone)]
pub struct PilOptions {
    /// QEMU on an image, or a serial port.
    pub target: PilTarget,
    /// Wall time the image gets to connect, boot (or answer Hello) and accept
    /// the configuration, s; positive.
    pub boot_timeout_s: f64,
    /// Wall time the image gets to answer one frame before it counts as hung, s; positive.
    pub answer_timeout_s: f64,
    /// Keep every period's tick counts
    /// ([`PilCounts::step_ticks`](super::PilCounts::step_ticks), 8 bytes a
    /// period: short runs that compare them period by period); off, the counts
    /// are summarised in fixed memory only.
    pub keep_ticks: bool,
}

impl PilOptions {
    /// QEMU on `image` over the semihosting FIFOs, with `qemu-system-arm` from
    /// `PATH` and 20 s / 5 s timeouts.
    pub fn new(image: impl Into<PathBuf>) -> Self {
        Self::for_target(PilTarget::Qemu { image: image.into(), qemu: "qemu-system-arm".into(), link: QemuLink::Semihosting })
    }

    /// The serial device `path` at `baud`, a board running the paper's laws'
    /// PIL image, with 20 s / 5 s timeouts.
    pub fn serial(path: impl Into<PathBuf>, baud: u32) -> Self {
        Self::for_target(PilTarget::Serial { path: path.into(), baud, elf: None })
    }

    /// `target` with 20 s / 5 s timeouts.
    pub fn for_target(target: PilTarget) -> Self {
        Self { target, boot_timeout_s: 20.0, answer_timeout_s: 5.0, keep_ticks: false }
    }
}

/// Refuses the faults `target` cannot inject ([`LinkKind::check`]).
///
/// # Errors
/// [`RunError::Unsupported`] naming the fault and why.
pub fn check_faults(s: &Scenario, target: &PilTarget) -> Result<(), RunError> {
    let kind = match target {
        PilTarget::Qemu { .. } => LinkKind::PilQemu,
        PilTarget::Serial { .. } => LinkKind::PilSerial,
    };
    kind.check(&s.faults)
}

/// The default place of the PIL image: the `mcu` profile's output next to this
/// executable's target folder (`target/thumbv7em-none-eabihf/qemu/pil`), else in
/// the workspace this `sil-host` was built from.
pub fn default_image() -> PathBuf {
    crate::image_path::beside_this_executable(Path::new("thumbv7em-none-eabihf/qemu/pil"))
}

/// Why a file cannot be the PIL image ([`check_image`]).
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// Not a regular file within `tables::input::ELF_IMAGE`'s bound.
    #[error(transparent)]
    Input(#[from] tables::input::InputError),
    /// Not an ELF, or one for another machine: what it is.
    #[error("{0}")]
    NotArm(String),
}

/// Refuses at once an image QEMU's Cortex-M4 cannot run (issue 52, 8: a damaged
/// file exited 1 and one of another machine waited 20 s for a boot that never
/// came): it must be a regular file within `tables::input::ELF_IMAGE`'s bound
/// (issue 80) and read as an ELF whose header says 32-bit little-endian ARM.
///
/// # Errors
/// [`ImageError`]: the input error naming the file and the bound, or what the
/// file is instead.
pub fn check_image(image: &Path) -> Result<(), ImageError> {
    use object::Object;
    let bytes = tables::input::read(image, tables::input::ELF_IMAGE)?;
    let elf = object::File::parse(&*bytes).map_err(|e| ImageError::NotArm(format!("not an ELF image ({e})")))?;
    if elf.architecture() != object::Architecture::Arm || !elf.is_little_endian() || elf.is_64() {
        return Err(ImageError::NotArm(format!(
            "an ELF for {:?} ({}-bit, {}-endian), not 32-bit little-endian ARM",
            elf.architecture(),
            if elf.is_64() { 64 } else { 32 },
            if elf.is_little_endian() { "little" } else { "big" }
        )));
    }
    Ok(())
}

/// How to build the image (for error messages).
pub const BUILD_HINT: &str = "cargo build-pil (= cargo build -p board-stm32f405 --profile qemu --target thumbv7em-none-eabihf --no-default-features --features qemu --bin pil)";
