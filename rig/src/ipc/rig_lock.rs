//! One plant and one firmware per rig, whatever the timing: each side takes an
//! exclusive lock on its role of the rig before it opens a service, so of runs
//! started together on one rig exactly one proceeds and every other is refused
//! ([`crate::record::RunError::RigInUse`], exit 2, naming the owner) before it
//! touches the winner's services (issue 39, 5: the node check alone was a race
//! that let two plants open the services together).
//!
//! The lock is an advisory `flock(2)` (std's [`std::fs::File::try_lock`]) on
//! `<temp>/painleve-rig-<rig>.<role>.lock`: the kernel drops it when its holder
//! exits, even by SIGKILL, so a killed run never leaves a rig locked. The holder
//! writes its pid into the file, which a refused process reads for its message
//! (the lock itself decides, never the file), and removes the file when it lets
//! go (unlinked while still locked; a process that locked the unlinked file
//! sees it is no longer the path's and starts again). A file left by a killed
//! holder is only a name: the next holder takes it, and the plant removes its
//! killed firmware's ([`RigLock::remove_stale`]).

use std::{
    fs::{File, OpenOptions},
    io::{Read, Seek, Write},
    os::unix::fs::MetadataExt,
    path::PathBuf,
};

use super::Role;
use crate::record::RunError;

/// The lock file of `role` of rig `rig`.
pub fn lock_path(role: Role, rig: &str) -> PathBuf {
    std::env::temp_dir().join(format!("painleve-rig-{rig}.{}.lock", role_name(role)))
}

fn role_name(role: Role) -> &'static str {
    match role {
        Role::Plant => "plant",
        Role::Firmware => "firmware",
    }
}

/// An exclusive hold of one role of a rig, released when dropped (or when the
/// process exits, however).
#[derive(Debug)]
pub struct RigLock {
    file: File,
    path: PathBuf,
}

impl Drop for RigLock {
    fn drop(&mut self) {
        // Unlinked while still held; closing the file then releases the lock.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

impl RigLock {
    /// Takes `role` of rig `rig` (a name [`super::check_rig_name`] accepts).
    ///
    /// # Errors
    /// [`RunError::RigInUse`] when another process holds it (its pid, -1 if it
    /// has not written it yet); [`RunError::Transport`] when the lock file cannot
    /// be made (the temporary folder not writable).
    pub fn acquire(role: Role, rig: &str) -> Result<Self, RunError> {
        let path = lock_path(role, rig);
        let io = |e: std::io::Error| RunError::Transport(format!("the rig's lock {}: {e}", path.display()));
        loop {
            let mut file = OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(io)?;
            match file.try_lock() {
                Ok(()) => {
                    // Still the path's file? (Its holder may have unlinked it between
                    // our open and our lock: then start again on the new one.)
                    let same = std::fs::metadata(&path)
                        .ok()
                        .zip(file.metadata().ok())
                        .is_some_and(|(p, f)| p.ino() == f.ino() && p.dev() == f.dev());
                    if !same {
                        continue;
                    }
                    // Informative only: the refusal message's pid.
                    let _ = file.set_len(0).and_then(|()| file.rewind()).and_then(|()| write!(file, "{}", std::process::id()));
                    return Ok(Self { file, path });
                }
                Err(std::fs::TryLockError::WouldBlock) => {
                    // The holder writes its pid just after it locks: read again for a
                    // moment if it has not yet (the lock already decided).
                    let mut pid = -1;
                    for _ in 0..100 {
                        let mut text = String::new();
                        let _ = file.rewind().and_then(|()| file.read_to_string(&mut text));
                        if let Ok(p) = text.trim().parse::<i64>() {
                            pid = p;
                            break;
                        }
                        std::thread::sleep(std::time::Duration::from_millis(2));
                    }
                    return Err(RunError::RigInUse { rig: rig.to_string(), role: role_name(role), pid });
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(io(e)),
            }
        }
    }

    /// Removes the lock file of `role` of `rig` if its holder is gone (a killed
    /// firmware's): taken, then let go.
    pub fn remove_stale(role: Role, rig: &str) {
        if lock_path(role, rig).exists() {
            drop(Self::acquire(role, rig));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_role_is_held_once_and_freed_when_dropped() {
        let rig = format!("unit-lock-{}", std::process::id());
        let a = RigLock::acquire(Role::Plant, &rig).unwrap();
        // The other role is independent.
        let f = RigLock::acquire(Role::Firmware, &rig).unwrap();
        // A second hold of the same role (another open file description: as
        // another process would) is refused naming this process.
        match RigLock::acquire(Role::Plant, &rig) {
            Err(RunError::RigInUse { role: "plant", pid, .. }) => assert_eq!(pid, i64::from(std::process::id())),
            other => panic!("{other:?}"),
        }
        drop(a);
        let b = RigLock::acquire(Role::Plant, &rig).unwrap();
        drop(f);
        drop(b);
        // Nothing is left once both are let go.
        assert!(!lock_path(Role::Plant, &rig).exists() && !lock_path(Role::Firmware, &rig).exists());
    }
}
