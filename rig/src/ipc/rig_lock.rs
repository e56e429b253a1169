//! One plant and one firmware per rig, whatever the timing: each side takes an
//! exclusive lock on its role of the rig before it opens a service, so of runs
//! started together on one rig exactly one proceeds and every other is refused
//! ([`crate::record::RunError::RigInUse`], exit 2, naming the owner) before it
//! touches the winner's services (issue 39, 5: the node check alone was a race
//! that let two plants open the services together).
//!
//! The lock is an advisory `flock(2)` (std's [`std::fs::File::try_lock`]) on
//! `<private>/painleve-rig-<rig>.<role>.lock`, where `<private>` is the user's
//! own folder of mode 0700 ([`crate::private_files::runtime_dir`]:
//! `$XDG_RUNTIME_DIR/painleve` or `<temp>/painleve-<uid>`), so no other user can
//! plant a link at a lock's name, squat a rig's lock or name its holder (issue
//! 52, 4). The file is opened without following a link and must be a regular
//! file of ours. The kernel drops the lock when its holder exits, even by
//! SIGKILL, so a killed run never leaves a rig locked. The holder writes its pid
//! into the file, which a refused process reads for its message (the lock
//! itself decides, never the file), and removes the file when it lets go
//! (unlinked while still locked; a process that locked the unlinked file sees it
//! is no longer the path's and starts again). A file left by a killed holder is
//! only a name: every [`RigLock::acquire`] removes the lock files of dead pids
//! ([`remove_dead`]: a SIGKILLed run's, whose default rig name `painleve-<pid>`
//! no later run reuses), and the plant removes its killed firmware's
//! ([`RigLock::remove_stale`]).

use std::{
    fs::File,
    io::{Read, Seek, Write},
    os::unix::fs::MetadataExt,
    path::{Path, PathBuf},
};

use super::Role;
use crate::record::RunError;

/// The lock file of `role` of rig `rig`, in the user's private folder.
///
/// # Errors
/// [`RunError::PrivateFolder`] (exit 2) when the private folder is refused (a
/// link, another user's, open to others), [`RunError::Transport`] when it cannot
/// be made otherwise ([`crate::private_files::runtime_dir`]: the message says why;
/// [`RunError::private_folder`]).
pub fn lock_path(role: Role, rig: &str) -> Result<PathBuf, RunError> {
    let dir = crate::private_files::runtime_dir().map_err(|e| RunError::private_folder("the rig's lock folder", &e))?;
    Ok(dir.join(lock_name(role, rig)))
}

/// The lock file's name of `role` of rig `rig`.
fn lock_name(role: Role, rig: &str) -> String {
    format!("painleve-rig-{rig}.{}.lock", role_name(role))
}

/// The pid written in an open lock file, if any (read within
/// `tables::input::LOCK_OWNER`'s bound).
fn read_pid(file: &mut File) -> Option<i64> {
    let mut text = String::new();
    file.rewind().and_then(|()| Read::take(&mut *file, tables::input::LOCK_OWNER.bytes).read_to_string(&mut text)).ok()?;
    text.trim().parse().ok()
}

/// Whether `file` is still the one at `path` (not unlinked by a holder letting go).
fn is_at(file: &File, path: &Path) -> bool {
    std::fs::symlink_metadata(path).ok().zip(file.metadata().ok()).is_some_and(|(p, f)| p.ino() == f.ino() && p.dev() == f.dev())
}

/// Removes the rig lock files in `dir` whose writer's pid is dead and that nobody
/// holds (a SIGKILLed run's); returns their names. A file being taken (no pid
/// yet) or held is left alone.
pub fn remove_dead(dir: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if !(name.starts_with("painleve-rig-") && name.ends_with(".lock")) {
            continue;
        }
        let path = e.path();
        let Ok(mut file) = crate::private_files::open_existing_lock(&path) else { continue };
        if read_pid(&mut file).is_none_or(crate::private_files::pid_alive) {
            continue;
        }
        // Dead: take it (a live holder would refuse us), check it is still the
        // path's, then unlink it while held.
        if file.try_lock().is_ok() && is_at(&file, &path) && std::fs::remove_file(&path).is_ok() {
            removed.push(name);
        }
    }
    removed
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
        let path = lock_path(role, rig)?;
        if let Some(dir) = path.parent() {
            remove_dead(dir);
        }
        let io = |e: std::io::Error| RunError::Transport(format!("the rig's lock {}: {e}", path.display()));
        'open: loop {
            let mut file = crate::private_files::open_lock(&path).map_err(io)?;
            match file.try_lock() {
                Ok(()) => {
                    // Still the path's file? (Its holder may have unlinked it between
                    // our open and our lock: then start again on the new one.)
                    if !is_at(&file, &path) {
                        continue;
                    }
                    // Informative only: the refusal message's pid.
                    let _ = file.set_len(0).and_then(|()| file.rewind()).and_then(|()| write!(file, "{}", std::process::id()));
                    return Ok(Self { file, path });
                }
                Err(std::fs::TryLockError::WouldBlock) => {
                    // The holder writes its pid just after it locks: read again for a
                    // moment if it has not yet (the lock already decided). A file
                    // unlinked meanwhile was being let go (its holder leaving, or a
                    // dead run's removed by [`remove_dead`]): start again.
                    let mut pid = -1;
                    for _ in 0..100 {
                        if file.metadata().is_ok_and(|m| m.nlink() == 0) {
                            continue 'open;
                        }
                        if let Some(p) = read_pid(&mut file) {
                            pid = p;
                            if crate::private_files::pid_alive(p) {
                                break;
                            }
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
        if lock_path(role, rig).is_ok_and(|p| p.exists()) {
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
        assert!(!lock_path(Role::Plant, &rig).unwrap().exists() && !lock_path(Role::Firmware, &rig).unwrap().exists());
    }

    #[test]
    fn a_dead_runs_lock_is_removed_by_the_next_and_a_live_ones_kept() {
        let dir = lock_path(Role::Plant, "x").unwrap().parent().unwrap().to_path_buf();
        // A SIGKILLed run's: its pid written, no holder.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let stale = dir.join(lock_name(Role::Plant, &format!("painleve-{dead}")));
        std::fs::write(&stale, dead.to_string()).unwrap();
        // A live holder's (this process, holding it), and one being taken (no pid yet).
        let live_rig = format!("unit-live-{}", std::process::id());
        let live = RigLock::acquire(Role::Firmware, &live_rig).unwrap();
        let fresh = dir.join(lock_name(Role::Plant, &format!("unit-fresh-{}", std::process::id())));
        std::fs::write(&fresh, "").unwrap();
        let next = RigLock::acquire(Role::Plant, &format!("unit-next-{}", std::process::id())).unwrap();
        assert!(!stale.exists(), "the dead run's lock was removed");
        assert!(live.path.exists() && fresh.exists(), "the live and the fresh locks are kept");
        drop((next, live));
        std::fs::remove_file(&fresh).unwrap();
    }

    #[test]
    fn a_link_planted_at_a_locks_name_is_refused_and_not_written_through() {
        let rig = format!("unit-link-{}", std::process::id());
        let path = lock_path(Role::Plant, &rig).unwrap();
        let victim = tempfile::NamedTempFile::new().unwrap();
        std::fs::write(victim.path(), "keep").unwrap();
        std::os::unix::fs::symlink(victim.path(), &path).unwrap();
        let e = RigLock::acquire(Role::Plant, &rig).unwrap_err().to_string();
        std::fs::remove_file(&path).unwrap();
        assert!(e.contains("a symbolic link is at its name"), "{e}");
        assert_eq!(std::fs::read_to_string(victim.path()).unwrap(), "keep");
    }
}
