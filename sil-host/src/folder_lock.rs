//! One writer per output folder: every command that writes an `--out` folder
//! holds an exclusive lock on it for as long as it runs, so a second command
//! aimed at the same folder (two identical sweeps started together, a report
//! over a sweep still running) is refused before it writes anything, instead of
//! both interleaving their rows into one journal.
//!
//! The lock is an advisory `flock(2)` on the folder itself (std's
//! [`std::fs::File::try_lock`]): the kernel drops it when its holder exits, even
//! by SIGKILL, so a crashed command never leaves the folder locked and nothing
//! needs cleaning up. While it holds the lock, the command keeps a small file
//! `.sil-host.owner` in the folder (its pid and command line) for the refusal
//! message; it is removed on release, and one left by a killed command is only
//! read, never trusted, since the lock itself decides.
//!
//! Locks are re-entrant within one process: a command that locks its folder
//! and then writes its files through [`crate::output::OutputSet`] (which locks
//! the folder too) holds one lock. On a file system without `flock` (some
//! network file systems) the folder is used unlocked, with a warning on stderr.

use std::{
    collections::HashMap,
    fs::File,
    path::{Path, PathBuf},
    sync::{Mutex, OnceLock},
};

use crate::error::{CliError, io_err};

/// The file that names the lock's holder while it holds the lock.
pub const OWNER_FILE: &str = ".sil-host.owner";

/// The folders this process holds: the locked folder handle and how many
/// [`FolderLock`]s share it.
type Held = HashMap<PathBuf, (Option<File>, usize)>;

fn held() -> &'static Mutex<Held> {
    static HELD: OnceLock<Mutex<Held>> = OnceLock::new();
    HELD.get_or_init(|| Mutex::new(HashMap::new()))
}

/// An exclusive lock on an output folder, held until dropped.
#[derive(Debug)]
pub struct FolderLock {
    /// The folder, canonical (the key in this process's table).
    dir: PathBuf,
}

impl FolderLock {
    /// Creates the folder `dir` (and its parents) if needed and locks it.
    ///
    /// # Errors
    /// [`CliError::FolderInUse`] (exit 2) when another process holds the folder,
    /// with the holder as its owner file names it; [`CliError::BadInput`] (exit
    /// 2) when `dir` is a file; [`CliError::Io`] when the folder cannot be
    /// created or opened.
    pub fn acquire(dir: &Path) -> Result<Self, CliError> {
        if dir.exists() && !dir.is_dir() {
            // Bad input (exit 2), nothing written: the user named a file.
            return Err(CliError::bad_input(format!(
                "--out {}: a file, not a folder; name a folder (it is made if missing)",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let canonical = dir.canonicalize().map_err(io_err(dir))?;
        let mut table = held().lock().unwrap_or_else(|p| p.into_inner());
        if let Some((_, count)) = table.get_mut(&canonical) {
            *count += 1;
            return Ok(Self { dir: canonical });
        }
        let handle = File::open(&canonical).map_err(io_err(dir))?;
        let handle = match handle.try_lock() {
            Ok(()) => {
                remove_stale_partials(&canonical);
                let owner = format!("pid {}: {}\n", std::process::id(), command_line());
                // Informative only: a failure to write it does not stop the command.
                // Made new, never through a link (rig::private_files).
                let _ = rig::private_files::write_new(&canonical.join(OWNER_FILE), owner.as_bytes());
                Some(handle)
            }
            Err(std::fs::TryLockError::WouldBlock) => {
                let owner = tables::input::read_to_string(&canonical.join(OWNER_FILE), tables::input::LOCK_OWNER)
                    .ok()
                    .map(|s| s.trim().to_string())
                    .filter(|s| !s.is_empty())
                    .unwrap_or_else(|| "another process".into());
                return Err(CliError::FolderInUse { path: dir.to_path_buf(), owner });
            }
            Err(std::fs::TryLockError::Error(e)) => {
                eprintln!(
                    "warning: cannot lock {} ({e}): this file system has no flock, so a second command writing into it would not be refused",
                    dir.display()
                );
                None
            }
        };
        table.insert(canonical.clone(), (handle, 1));
        Ok(Self { dir: canonical })
    }

    /// The locked folder (canonical).
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// Removes what a killed command (SIGKILL, a power cut) left in `dir`, which
/// this process has just locked, so no other command is writing there: its
/// staged files `.NAME.partial` (never kept by design: a finished command renames
/// them) and its owner file. Streamed `NAME.partial` files (rows flushed before
/// the kill) are kept. Said on stderr.
fn remove_stale_partials(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if (name.starts_with('.') && name.ends_with(".partial") || name == OWNER_FILE) && std::fs::remove_file(e.path()).is_ok() {
            removed.push(name);
        }
    }
    if !removed.is_empty() {
        removed.sort();
        eprintln!("{}: removed what an interrupted command left: {}", dir.display(), removed.join(", "));
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let mut table = held().lock().unwrap_or_else(|p| p.into_inner());
        let last = match table.get_mut(&self.dir) {
            Some((_, count)) => {
                *count -= 1;
                *count == 0
            }
            None => false,
        };
        if last {
            // Remove the owner file while still holding the lock, then close the
            // handle, which releases it.
            if let Some((handle, _)) = table.remove(&self.dir) {
                if handle.is_some() {
                    let _ = std::fs::remove_file(self.dir.join(OWNER_FILE));
                }
                drop(handle);
            }
        }
    }
}

/// This process's command line, for the owner file (arguments joined by spaces).
fn command_line() -> String {
    let args: Vec<String> = std::env::args().collect();
    let line = args.join(" ");
    // One line, printable: control characters would garble the refusal message.
    line.chars().map(|c| if c.is_control() { '?' } else { c }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_locked_once_per_process_and_released_on_the_last_drop() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a/b");
        let first = FolderLock::acquire(&out).unwrap();
        assert!(out.join(OWNER_FILE).exists());
        let again = FolderLock::acquire(&out).unwrap();
        // Another open file description of the folder is refused while either is held.
        let other = File::open(&out).unwrap();
        assert!(matches!(other.try_lock(), Err(std::fs::TryLockError::WouldBlock)));
        drop(first);
        assert!(matches!(other.try_lock(), Err(std::fs::TryLockError::WouldBlock)), "still held by the second");
        assert!(out.join(OWNER_FILE).exists());
        drop(again);
        assert!(!out.join(OWNER_FILE).exists(), "the owner file goes with the lock");
        other.try_lock().expect("released with the last holder");
    }

    #[test]
    fn a_folder_held_elsewhere_is_refused_with_its_owner() {
        let dir = tempfile::tempdir().unwrap();
        // Another holder: a separate open file description of the same folder,
        // as another process would have (flock locks belong to the description).
        let other = File::open(dir.path()).unwrap();
        other.try_lock().unwrap();
        std::fs::write(dir.path().join(OWNER_FILE), "pid 4242: sil-host sweep --out x\n").unwrap();
        let err = FolderLock::acquire(dir.path()).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        let msg = err.to_string();
        assert!(msg.contains("pid 4242") && msg.contains("in use"), "{msg}");
        // The refused command removed nothing of the holder's.
        assert!(dir.path().join(OWNER_FILE).exists());
    }

    #[test]
    fn an_out_that_names_a_file_is_bad_input_and_the_file_is_left() {
        // Issue 39: it exited 1 (an I/O error) where bad input is 2.
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("results.txt");
        std::fs::write(&file, "mine").unwrap();
        let err = FolderLock::acquire(&file).unwrap_err();
        assert_eq!(err.exit_code(), 2, "{err}");
        assert!(err.to_string().contains("a file, not a folder"), "{err}");
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    }
}
