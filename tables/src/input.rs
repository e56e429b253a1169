//! Bounded inputs (issue 80, item 7): every file the host tools read (ELF
//! images, scenarios, summaries, recordings, backups, tables) is opened only if
//! it is a regular file, and read within a stated size bound, its [`Bound`].
//!
//! Before this module `board configure --elf /dev/zero` read until the kernel
//! killed it, a FIFO given as a file hung in `open`, and a `summary.json`
//! linked to `/dev/zero` was read until memory ran out. Here:
//!
//! 1. the path's metadata is read first (`std::fs::metadata`: links are
//!    followed, so a link to a regular file reads as that file): a FIFO, a
//!    character or block device, a directory or a socket is refused before
//!    `open` (which would block on a FIFO without a writer);
//! 2. its length is held to the bound of its kind ([`ELF_IMAGE`],
//!    [`SCENARIO`], ...; each constant gives its reason);
//! 3. the file is opened (without `O_NONBLOCK`) and its metadata read again
//!    from the open file: a file swapped for another kind between the two is
//!    refused too;
//! 4. it is read through [`BoundedReader`] (`Read::take(bound + 1)`), which
//!    fails once more than the bound has come: a file that grows while it is
//!    read, or whose length lies (`/proc` files say 0), is still bounded.
//!
//! The errors ([`InputError`]) name the file, what it was to be and its bound;
//! the command line maps them to exit 2 (`experiments::Error::BadInput`), the
//! Python package to `PainleveError` with exit code 2.

use std::{
    fmt,
    fs::File,
    io::{self, Read},
    path::{Path, PathBuf},
};

/// What a file is read as, and the most bytes it may hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bound {
    /// What the file is to be, as a message names it ("ELF image").
    pub what: &'static str,
    /// The largest length admitted, bytes.
    pub bytes: u64,
    /// Why this bound, as a message gives it.
    pub why: &'static str,
}

const KIB: u64 = 1 << 10;
const MIB: u64 = 1 << 20;
const GIB: u64 = 1 << 30;

/// An MCU image's ELF (`board configure --elf`, `pil --image`, the emulator's
/// `--elf`, `bench`): 64 MiB. What the board runs fits its 1 MiB of flash
/// (STM32F405RG; the images' budget is 64 KiB); the ELF adds its symbols, the
/// defmt table and the `mcu` profile's debug info (`debug = 2`), a few MiB.
pub const ELF_IMAGE: Bound =
    Bound { what: "ELF image", bytes: 64 * MIB, why: "the board's flash is 1 MiB; symbols and debug info make an image's ELF a few MiB" };

/// A scenario file (`--scenario`, a Python `Scenario.load`): 4 MiB. The
/// shipped ones are about 4 KiB; a long `[[faults]]` list stays well within.
pub const SCENARIO: Bound =
    Bound { what: "scenario", bytes: 4 * MIB, why: "a scenario is a few KiB of TOML (scenarios/*.toml: about 4 KiB)" };

/// A command's `summary.json` and its other JSON documents (`replay` reads a
/// run's scenario as run; the Python package's `load` every document of a
/// folder): 64 MiB. A run's summary is a few KiB; a sweep's or a report's
/// document lists its cases, some MiB at most.
pub const SUMMARY: Bound =
    Bound { what: "summary", bytes: 64 * MIB, why: "a run's summary.json is a few KiB, a sweep's or a report's document some MiB at most" };

/// A recording's frames table (`frames.csv`, `frames.arrow`, `trace.mcap`;
/// `replay`): 4 GiB, read whole into memory as rows. A row of `frames.csv` is
/// about 400 bytes: 4 GiB is some ten million periods, close to three hours
/// at 1 kHz.
pub const RECORDING: Bound =
    Bound { what: "recording", bytes: 4 * GIB, why: "about 10 million periods of ~400 B (nearly 3 h at 1 kHz), read whole into memory" };

/// A table read back whole (`trace.csv`, `trace.arrow`, `trace.mcap`, the
/// Python package's readers): 4 GiB. Its columns take as much memory again
/// as the file; two of that stay within the 24 GiB of the project's machines.
pub const TABLE: Bound =
    Bound { what: "table", bytes: 4 * GIB, why: "a table is read whole into memory, its columns as large as the file again" };

/// A sweep's manifest (`sweep.json`; `sweep` resuming, `merge`): 4 MiB. It
/// holds the sweep's spec, a few KiB.
pub const SWEEP_MANIFEST: Bound = Bound { what: "sweep manifest", bytes: 4 * MIB, why: "sweep.json holds a sweep's spec, a few KiB" };

/// A sweep's journal (`runs.csv`; `sweep` resuming, `merge`): 1 GiB. A run's
/// row is about 200 bytes: some five million runs, past any sweep of the
/// paper's figures (10^4 to 10^5 runs).
pub const SWEEP_JOURNAL: Bound =
    Bound { what: "sweep journal", bytes: GIB, why: "a run's row is about 200 B: some 5 million runs, read whole" };

/// A board's backup (`board backup` writes it, `board restore` reads it):
/// 1 MiB. A backup is the calibration and the configuration, about 2 KiB of
/// TOML.
pub const BACKUP: Bound =
    Bound { what: "board backup", bytes: MIB, why: "a backup is the board's calibration and configuration, about 2 KiB" };

/// A lock's owner file (`.sil-host.owner`, a rig's lock file): 4 MiB, a pid
/// and a command line (Linux caps a command line's arguments at 2 MiB).
pub const LOCK_OWNER: Bound =
    Bound { what: "lock owner file", bytes: 4 * MIB, why: "a pid and a command line (Linux caps the arguments at 2 MiB)" };

/// A text file of a command's folder read whole as text (the Python
/// package's `load`: `defmt.log`, `report.md`): 1 GiB. A PIL run's defmt
/// log is a line per logged event, a few MiB for an hour.
pub const LOG: Bound =
    Bound { what: "log", bytes: GIB, why: "a command's logs and notes are MiB (a PIL run's defmt.log: a line per logged event)" };

/// A small system file read for a stamp (`/proc/cpuinfo`,
/// `/proc/sys/kernel/hostname`): 1 MiB. Their length reads 0, so only
/// [`BoundedReader`] bounds them.
pub const SYSTEM_FILE: Bound =
    Bound { what: "system file", bytes: MIB, why: "/proc's text files are a few KiB (cpuinfo: about 1.5 KiB per CPU)" };

/// A figure read back for printing (`figures`' SVG to PDF): 256 MiB. The
/// figures are decimated; the largest SVG measured is a few MiB.
pub const FIGURE: Bound = Bound { what: "figure", bytes: 256 * MIB, why: "the figures are decimated: their SVGs are a few MiB at most" };

/// A length as a message gives it: in the largest binary unit that divides it.
struct Bytes(u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.0;
        for (unit, size) in [("GiB", GIB), ("MiB", MIB), ("KiB", KIB)] {
            if n >= size && n.is_multiple_of(size) {
                return write!(f, "{} {unit}", n / size);
            }
        }
        write!(f, "{n} bytes")
    }
}

impl fmt::Display for Bound {
    /// "at most 64 MiB (the board's flash is 1 MiB; ...)".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "at most {} ({})", Bytes(self.bytes), self.why)
    }
}

/// Why an input file is not read.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// Its metadata or its bytes cannot be read (no such file, no permission, an I/O error).
    #[error("cannot read the {} {}: {source}", bound.what, path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What it was to be.
        bound: Bound,
        /// The OS error.
        source: io::Error,
    },
    /// It is not a regular file: a FIFO, a device, a directory or a socket.
    #[error(
        "cannot read the {0} {1}: it is {kind}, not a regular file: the {0} is read from a regular file of {bound}",
        bound.what,
        path.display()
    )]
    NotAFile {
        /// The file.
        path: PathBuf,
        /// What it was to be, and its bound.
        bound: Bound,
        /// What it is ("a FIFO", "a character device", ...).
        kind: &'static str,
    },
    /// It is longer than its bound: `length` as its metadata says, or `None`
    /// when it said less and more came while it was read.
    #[error(
        "cannot read the {0} {1}: it is {2}, over the {0}'s bound: {bound}",
        bound.what,
        path.display(),
        length.map_or_else(|| format!("longer than {} bytes as read", bound.bytes), |n| format!("{n} bytes"))
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What it was to be, and its bound.
        bound: Bound,
        /// Its length by its metadata, if that is what gave it away.
        length: Option<u64>,
    },
}

impl InputError {
    /// The file.
    pub fn path(&self) -> &Path {
        match self {
            Self::Unreadable { path, .. } | Self::NotAFile { path, .. } | Self::TooLarge { path, .. } => path,
        }
    }

    /// Whether the file is not there (the callers for which an absent file is
    /// no error, such as a sweep's journal before its first run, ask).
    pub fn is_not_found(&self) -> bool {
        matches!(self, Self::Unreadable { source, .. } if source.kind() == io::ErrorKind::NotFound)
    }
}

/// What a file type is, as a message names it; `None` for a regular file.
fn kind_of(t: std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    if t.is_file() {
        None
    } else if t.is_dir() {
        Some("a directory")
    } else if t.is_fifo() {
        Some("a FIFO")
    } else if t.is_char_device() {
        Some("a character device")
    } else if t.is_block_device() {
        Some("a block device")
    } else if t.is_socket() {
        Some("a socket")
    } else {
        Some("not a file")
    }
}

/// Checks `meta` against `bound`: a regular file within it.
fn check(path: &Path, bound: Bound, meta: &std::fs::Metadata) -> Result<(), InputError> {
    if let Some(kind) = kind_of(meta.file_type()) {
        return Err(InputError::NotAFile { path: path.to_path_buf(), bound, kind });
    }
    if meta.len() > bound.bytes {
        return Err(InputError::TooLarge { path: path.to_path_buf(), bound, length: Some(meta.len()) });
    }
    Ok(())
}

/// Opens `path` for reading as a file of kind `bound`: a regular file (links
/// followed) no longer than `bound.bytes`, checked before it is opened and
/// again on the open file. For a reader that seeks (Arrow's); read it through
/// [`reader`] otherwise.
///
/// # Errors
/// [`InputError::Unreadable`] (no such file, no permission), [`InputError::NotAFile`]
/// (a FIFO, a device, a directory, a socket), [`InputError::TooLarge`].
pub fn open(path: &Path, bound: Bound) -> Result<File, InputError> {
    let unreadable = |source| InputError::Unreadable { path: path.to_path_buf(), bound, source };
    check(path, bound, &std::fs::metadata(path).map_err(unreadable)?)?;
    let file = File::open(path).map_err(unreadable)?;
    check(path, bound, &file.metadata().map_err(unreadable)?)?;
    Ok(file)
}

/// `path` opened as [`open`] does, read through a [`BoundedReader`].
///
/// # Errors
/// As [`open`].
pub fn reader(path: &Path, bound: Bound) -> Result<BoundedReader<File>, InputError> {
    Ok(BoundedReader::new(open(path, bound)?, path, bound))
}

/// The bytes of `path`, a file of kind `bound`.
///
/// # Errors
/// As [`open`]; [`InputError::TooLarge`] also when more than `bound.bytes`
/// came while it was read; [`InputError::Unreadable`] for a read error.
pub fn read(path: &Path, bound: Bound) -> Result<Vec<u8>, InputError> {
    let mut r = reader(path, bound)?;
    let mut bytes = Vec::new();
    r.read_to_end(&mut bytes).map_err(|e| r.error(e))?;
    Ok(bytes)
}

/// The text of `path`, a file of kind `bound`.
///
/// # Errors
/// As [`read`]; [`InputError::Unreadable`] for text that is not UTF-8.
pub fn read_to_string(path: &Path, bound: Bound) -> Result<String, InputError> {
    let mut r = reader(path, bound)?;
    let mut text = String::new();
    r.read_to_string(&mut text).map_err(|e| r.error(e))?;
    Ok(text)
}

/// All of `source` (standard input, an open file) as text, read as a file of
/// kind `bound` named `name`: at most `bound.bytes`.
///
/// # Errors
/// [`InputError::TooLarge`] past the bound; [`InputError::Unreadable`] for a
/// read error or text that is not UTF-8.
pub fn read_stream_to_string(source: impl Read, name: &Path, bound: Bound) -> Result<String, InputError> {
    let mut r = BoundedReader::new(source, name, bound);
    let mut text = String::new();
    r.read_to_string(&mut text).map_err(|e| r.error(e))?;
    Ok(text)
}

/// A reader that fails once more than its bound has come (`Read::take(bound + 1)`
/// underneath): the error is an [`io::Error`] holding the [`InputError::TooLarge`],
/// whose message names the file and the bound.
#[derive(Debug)]
pub struct BoundedReader<R> {
    inner: io::Take<R>,
    path: PathBuf,
    bound: Bound,
}

impl<R: Read> BoundedReader<R> {
    /// `inner`, the file `path` of kind `bound`, bounded.
    pub fn new(inner: R, path: &Path, bound: Bound) -> Self {
        Self { inner: inner.take(bound.bytes.saturating_add(1)), path: path.to_path_buf(), bound }
    }

    /// The [`InputError`] of an I/O error this reader gave: the
    /// [`InputError::TooLarge`] it holds, or the OS error as
    /// [`InputError::Unreadable`].
    pub fn error(&self, e: io::Error) -> InputError {
        into_input_error(e, &self.path, self.bound)
    }
}

/// The [`InputError`] of an I/O error `e` on `path`: the one it holds (a
/// [`BoundedReader`]'s), or `e` as [`InputError::Unreadable`].
pub fn into_input_error(e: io::Error, path: &Path, bound: Bound) -> InputError {
    match e.downcast::<InputError>() {
        Ok(input) => input,
        Err(source) => InputError::Unreadable { path: path.to_path_buf(), bound, source },
    }
}

impl<R: Read> Read for BoundedReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        // `take(bound + 1)`: a limit of 0 left means byte bound + 1 came.
        if self.inner.limit() == 0 && n > 0 {
            return Err(io::Error::new(
                io::ErrorKind::FileTooLarge,
                InputError::TooLarge { path: self.path.clone(), bound: self.bound, length: None },
            ));
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    const SMALL: Bound = Bound { what: "test file", bytes: 16, why: "a test" };

    #[test]
    fn a_regular_file_within_its_bound_reads_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        std::fs::write(&path, b"0123456789abcdef").unwrap();
        assert_eq!(read(&path, SMALL).unwrap(), b"0123456789abcdef");
        assert_eq!(read_to_string(&path, SMALL).unwrap(), "0123456789abcdef");
        // Through a link: the file it names.
        let link = dir.path().join("l");
        std::os::unix::fs::symlink(&path, &link).unwrap();
        assert_eq!(read(&link, SMALL).unwrap().len(), 16);
    }

    #[test]
    fn a_file_over_its_bound_is_refused_naming_the_bound() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        std::fs::write(&path, [b'x'; 17]).unwrap();
        let e = read(&path, SMALL).unwrap_err();
        assert!(matches!(e, InputError::TooLarge { length: Some(17), .. }), "{e:?}");
        assert_eq!(
            e.to_string(),
            format!("cannot read the test file {}: it is 17 bytes, over the test file's bound: at most 16 bytes (a test)", path.display())
        );
        // A 10 GB sparse file: refused from its metadata, nothing read.
        let big = dir.path().join("big");
        File::create(&big).unwrap().set_len(10_000_000_000).unwrap();
        let started = Instant::now();
        let e = read(&big, ELF_IMAGE).unwrap_err();
        assert!(started.elapsed() < Duration::from_secs(1));
        assert!(e.to_string().contains("over the ELF image's bound: at most 64 MiB"), "{e}");
    }

    #[test]
    fn devices_fifos_and_directories_are_refused_before_they_are_opened() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
        let mut cases = vec![(PathBuf::from("/dev/zero"), "a character device"), (dir.path().to_path_buf(), "a directory")];
        if made {
            // Opening a FIFO without a writer blocks: refused before `open`.
            cases.push((fifo, "a FIFO"));
        }
        for (path, kind) in cases {
            let e = read(&path, SCENARIO).unwrap_err();
            assert!(matches!(e, InputError::NotAFile { .. }), "{e:?}");
            assert!(
                e.to_string()
                    .contains(&format!(": it is {kind}, not a regular file: the scenario is read from a regular file of at most 4 MiB")),
                "{e}"
            );
            assert!(e.to_string().contains("at most 4 MiB"), "{e}");
        }
        assert!(read(&dir.path().join("none"), SCENARIO).unwrap_err().is_not_found());
    }

    /// A file whose length lies (`/proc` files say 0) or that grows while read:
    /// the reader stops one byte past the bound.
    #[test]
    fn a_stream_longer_than_its_bound_fails_as_it_is_read() {
        let e = read_stream_to_string(io::repeat(b'a'), Path::new("-"), SMALL).unwrap_err();
        assert!(matches!(e, InputError::TooLarge { length: None, .. }), "{e:?}");
        assert!(e.to_string().contains("longer than 16 bytes as read"), "{e}");
        assert_eq!(read_stream_to_string(&b"0123456789abcdef"[..], Path::new("-"), SMALL).unwrap().len(), 16);
        // A /proc file: length 0, text within the bound.
        assert!(read_to_string(Path::new("/proc/self/status"), SYSTEM_FILE).unwrap().contains("Name:"));
    }

    #[test]
    fn the_bounds_are_given_in_their_units() {
        assert_eq!(Bytes(64 * MIB).to_string(), "64 MiB");
        assert_eq!(Bytes(4 * GIB).to_string(), "4 GiB");
        assert_eq!(Bytes(1000).to_string(), "1000 bytes");
    }
}
