//! Files another local user cannot redirect (issue 52, 4 and 5).
//!
//! Two rules, for every file the rig and `sil-host` make:
//!
//! - **Locks and sockets live in a folder of our own** ([`runtime_dir`]): the
//!   user's `$XDG_RUNTIME_DIR/painleve` when `$XDG_RUNTIME_DIR` is set and is a
//!   folder of ours that only we can enter (mode 0700), else `<temp>/painleve-<uid>`
//!   (the temporary folder, `$TMPDIR` or `/tmp`). Either folder is made with mode
//!   0700 and refused, with a message saying why, if it is a symbolic link, not
//!   a folder, not ours, or open to others: nobody else can then plant a link,
//!   squat a lock or name a holder in it, whatever the file names (a rig's
//!   default name `painleve-<pid>` is predictable; in this folder that no longer
//!   matters).
//! - **No file is opened through a link** ([`open_lock`], [`create_new`]): lock
//!   files are opened with `O_NOFOLLOW` and refused unless they are regular files
//!   of ours; files that are written then renamed (`NAME.partial`) are made new
//!   (`O_CREAT | O_EXCL | O_NOFOLLOW`) after removing what a killed run left at
//!   that name: a link itself (never what it points to), or a regular file of
//!   ours. Anything else at the name is refused. A single file written whole
//!   or not at all by a writer without a folder lock ([`write_replacing`]: the
//!   Python package's `Result.write_page`, `write_mcap`) gets a temporary name of
//!   its own, made new, and renamed into place as the command line's outputs are.

use std::{
    ffi::OsStr,
    fs::{File, OpenOptions},
    io,
    os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt, PermissionsExt},
    path::{Path, PathBuf},
};

/// This process's effective user id.
pub fn euid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// The folder of this user's locks and sockets (made if missing, mode 0700):
/// `$XDG_RUNTIME_DIR/painleve` if `$XDG_RUNTIME_DIR` is a private folder of ours,
/// else `<temp>/painleve-<uid>`.
///
/// # Errors
/// An [`io::Error`] whose message names the folder and why it is refused: a
/// symbolic link, not a folder, owned by another user (uid named), open to
/// others (its mode named), or not creatable.
pub fn runtime_dir() -> io::Result<PathBuf> {
    runtime_dir_in(std::env::var_os("XDG_RUNTIME_DIR").as_deref(), &std::env::temp_dir())
}

/// [`runtime_dir`] with the runtime and temporary folders given.
///
/// # Errors
/// As [`runtime_dir`].
pub fn runtime_dir_in(xdg: Option<&OsStr>, temp: &Path) -> io::Result<PathBuf> {
    if let Some(xdg) = xdg.map(Path::new).filter(|p| p.is_absolute())
        && check_private(xdg).is_ok()
    {
        return private_dir(&xdg.join("painleve"));
    }
    private_dir(&temp.join(format!("painleve-{}", euid())))
}

/// Makes `dir` (mode 0700) if missing, then checks it is a private folder of ours.
///
/// # Errors
/// As [`runtime_dir`].
pub fn private_dir(dir: &Path) -> io::Result<PathBuf> {
    match std::fs::DirBuilder::new().mode(0o700).create(dir) {
        Ok(()) => {
            // The umask may have taken bits of 0700 away: set it whole.
            std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o700))
                .map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", dir.display())))?;
        }
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(io::Error::new(e.kind(), format!("cannot make the private folder {}: {e}", dir.display()))),
    }
    check_private(dir)?;
    Ok(dir.to_path_buf())
}

/// Checks that `dir` is a folder (not a link to one), ours, mode 0700.
fn check_private(dir: &Path) -> io::Result<()> {
    let refuse = |why: String| {
        Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!("{}: {why}; the rig keeps its locks only in a folder of yours that nobody else can enter", dir.display()),
        ))
    };
    let m = std::fs::symlink_metadata(dir).map_err(|e| io::Error::new(e.kind(), format!("{}: {e}", dir.display())))?;
    if m.file_type().is_symlink() {
        return refuse("a symbolic link (another user may have planted it: remove it)".into());
    }
    if !m.is_dir() {
        return refuse("not a folder".into());
    }
    if m.uid() != euid() {
        return refuse(format!("owned by uid {}, not by you (uid {}): another user's", m.uid(), euid()));
    }
    if m.mode() & 0o777 != 0o700 {
        return refuse(format!("mode {:o}, not 0700 (others can enter it): `chmod 700` it or remove it", m.mode() & 0o777));
    }
    Ok(())
}

/// Opens (creating it, mode 0600, if missing) the lock file `path` for reading
/// and writing, without following a link, and checks it is a regular file of ours.
///
/// # Errors
/// The open's error (a link at `path`: "a symbolic link is at its name, not
/// followed"), or [`io::ErrorKind::PermissionDenied`] naming the file's owner or kind.
pub fn open_lock(path: &Path) -> io::Result<File> {
    open_lock_with(path, true)
}

/// [`open_lock`] of a lock file that exists (none is made).
///
/// # Errors
/// As [`open_lock`]; [`io::ErrorKind::NotFound`] when there is none.
pub fn open_existing_lock(path: &Path) -> io::Result<File> {
    open_lock_with(path, false)
}

fn open_lock_with(path: &Path, create: bool) -> io::Result<File> {
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(create)
        .truncate(false)
        .mode(0o600)
        .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
        .open(path)
        .map_err(said_link)?;
    let m = file.metadata()?;
    if !m.is_file() {
        return Err(io::Error::new(io::ErrorKind::PermissionDenied, "not a regular file"));
    }
    if m.uid() != euid() {
        return Err(io::Error::new(io::ErrorKind::PermissionDenied, format!("owned by uid {}, not by you (uid {})", m.uid(), euid())));
    }
    Ok(file)
}

/// Creates `path` new for writing (`O_CREAT | O_EXCL | O_NOFOLLOW`, mode 0666
/// less the umask, as [`File::create`]), after removing what a killed run may
/// have left at that name: a symbolic link (the link itself, never its target)
/// or a regular file of ours.
///
/// # Errors
/// [`io::ErrorKind::AlreadyExists`] when something else is at `path` (a folder,
/// another user's file) or when a file appeared there between the removal and
/// the creation (a planted one: refused, not followed); the OS's error otherwise.
pub fn create_new(path: &Path) -> io::Result<File> {
    clear_stale(path)?;
    OpenOptions::new().write(true).create_new(true).custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC).open(path).map_err(said_link)
}

/// `ELOOP` from `O_NOFOLLOW` (a link at the name) in words.
fn said_link(e: io::Error) -> io::Error {
    if e.raw_os_error() == Some(libc::ELOOP) {
        io::Error::new(
            io::ErrorKind::PermissionDenied,
            "a symbolic link is at its name (not followed: another user may have planted it; remove it)",
        )
    } else {
        e
    }
}

/// [`create_new`], then writes `bytes` whole.
///
/// # Errors
/// As [`create_new`], and the write's error.
pub fn write_new(path: &Path, bytes: &[u8]) -> io::Result<()> {
    use io::Write;
    create_new(path)?.write_all(bytes)
}

/// Writes the file `path` whole or not at all, never through a link, as
/// `sil-host` writes its outputs (`sil-host/src/output.rs`): `write` fills a new
/// file under a temporary name in `path`'s folder, which is then renamed to `path`.
///
/// - The temporary file (`.NAME.XXXXXX.partial`, `XXXXXX` random) is made with
///   `O_CREAT | O_EXCL` by [`tempfile`]: no link, planted or left, satisfies it, and
///   two writers of the same `path` (threads, processes) never share one. Its mode
///   is 0666 less the umask, as [`File::create`]'s.
/// - The rename replaces what is at `path`: a previous file, or a link (the link
///   itself, never its target, which is left as it was). A reader of `path` sees
///   the old file or the whole new one, never part of it.
/// - When `write` fails, or the rename does (a folder at `path`), the temporary
///   file is removed and `path` is left as it was. A process killed outright
///   while writing leaves its `.NAME.XXXXXX.partial` (never a partial `path`).
///
/// `write` gets the temporary file's path (for its error messages) and the file,
/// which it closes (drops) when done; nothing is flushed to the disk (`fsync`),
/// as for the command line's outputs.
///
/// # Errors
/// `write`'s error, or an [`io::Error`] (into `E`) whose message names `path`: the
/// temporary file cannot be made (no such folder, no permission, `path` without a
/// file name) or renamed to `path` (a folder there).
pub fn write_replacing<E: From<io::Error>>(path: &Path, write: impl FnOnce(&Path, File) -> Result<(), E>) -> Result<(), E> {
    let named = |e: io::Error| io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()));
    let name = path.file_name().ok_or_else(|| named(io::Error::new(io::ErrorKind::InvalidInput, "not a file name")))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(".");
    let (file, tmp) = tempfile::Builder::new()
        .prefix(&prefix)
        .suffix(".partial")
        .permissions(std::fs::Permissions::from_mode(0o666))
        .tempfile_in(dir)
        .map_err(named)?
        .into_parts();
    // On an error below, `tmp` is dropped: the temporary file is removed.
    write(&tmp, file)?;
    tmp.persist(path).map_err(|e| named(e.error))?;
    Ok(())
}

/// Removes a link or a regular file of ours at `path`; nothing there is fine.
fn clear_stale(path: &Path) -> io::Result<()> {
    let m = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e),
    };
    let ours = m.file_type().is_symlink() || (m.is_file() && m.uid() == euid());
    if !ours {
        let what = if m.is_file() { format!("a file of uid {}, not yours", m.uid()) } else { "not a regular file".into() };
        return Err(io::Error::new(io::ErrorKind::AlreadyExists, format!("{what} is in the way; remove it")));
    }
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// Removes the files in `dir` named `<prefix><pid>-...` whose process `pid` is
/// dead (a SIGKILLed PIL run's FIFOs and socket, `painleve-pil-<pid>-<n>.up`);
/// returns their names.
pub fn remove_dead_pid_files(dir: &Path, prefix: &str) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let pid = name.strip_prefix(prefix).and_then(|r| r.split_once('-')).and_then(|(p, _)| p.parse::<i64>().ok());
        if pid.is_some_and(|p| !pid_alive(p)) && std::fs::remove_file(e.path()).is_ok() {
            removed.push(name);
        }
    }
    removed
}

/// Whether process `pid` exists (it may be another user's).
pub fn pid_alive(pid: i64) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else { return false };
    if pid <= 0 {
        return false;
    }
    // SAFETY: signal 0 only checks that the process exists.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    #[test]
    fn a_partial_file_is_never_written_through_a_planted_link() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("elsewhere");
        std::fs::write(&target, "theirs").unwrap();
        let partial = dir.path().join("trace.csv.partial");
        symlink(&target, &partial).unwrap();
        write_new(&partial, b"ours").unwrap();
        // The link was replaced by a new file; its target is untouched.
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "theirs");
        assert!(!std::fs::symlink_metadata(&partial).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(&partial).unwrap(), "ours");
        // A dangling link too (the target would have been created).
        let missing = dir.path().join("made-by-link");
        std::fs::remove_file(&partial).unwrap();
        symlink(&missing, &partial).unwrap();
        write_new(&partial, b"again").unwrap();
        assert!(!missing.exists());
        // A stale file of ours is replaced; a folder in the way is refused.
        write_new(&partial, b"third").unwrap();
        assert_eq!(std::fs::read_to_string(&partial).unwrap(), "third");
        let folder = dir.path().join("x.partial");
        std::fs::create_dir(&folder).unwrap();
        assert_eq!(create_new(&folder).unwrap_err().kind(), io::ErrorKind::AlreadyExists);
    }

    /// Issue 80, 8: a single file written through a link planted at its name
    /// (`painleve`'s `Result.write_page`), and half-written on a failure.
    #[test]
    fn a_replaced_file_is_never_written_through_a_link_nor_left_half_written() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim");
        std::fs::write(&victim, "theirs").unwrap();
        let out = dir.path().join("trace.html");
        symlink(&victim, &out).unwrap();
        write_replacing::<io::Error>(&out, |_, mut f| f.write_all(b"ours")).unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "theirs");
        assert!(std::fs::symlink_metadata(&out).unwrap().is_file(), "the link is replaced by a file");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "ours");
        // A dangling link: nothing made at its target.
        let absent = dir.path().join("absent");
        std::fs::remove_file(&out).unwrap();
        symlink(&absent, &out).unwrap();
        write_replacing::<io::Error>(&out, |_, mut f| f.write_all(b"again")).unwrap();
        assert!(!absent.exists());
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "again");
        // A write that fails half way: the previous file stays, no temporary file is left.
        let e = write_replacing(&out, |tmp, mut f| {
            f.write_all(b"half")?;
            assert!(tmp.file_name().unwrap().to_str().unwrap().starts_with(".trace.html."), "{}", tmp.display());
            Err(io::Error::other("failed"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "failed");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "again");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        // A folder at the name, or a missing folder: an error naming the path, nothing left.
        let folder = dir.path().join("folder");
        std::fs::create_dir(&folder).unwrap();
        let e = write_replacing::<io::Error>(&folder, |_, mut f| f.write_all(b"x")).unwrap_err().to_string();
        assert!(e.contains("cannot write") && e.contains("folder"), "{e}");
        let missing = dir.path().join("no/such/file");
        let e = write_replacing::<io::Error>(&missing, |_, _| Ok(())).unwrap_err().to_string();
        assert!(e.contains("no/such/file"), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
        assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
    }

    #[test]
    fn a_lock_file_is_not_opened_through_a_link() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("victim");
        std::fs::write(&target, "keep").unwrap();
        let lock = dir.path().join("r.lock");
        symlink(&target, &lock).unwrap();
        let e = open_lock(&lock).unwrap_err().to_string();
        assert!(e.contains("a symbolic link is at its name"), "{e}");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    }

    #[test]
    fn the_private_folder_is_made_0700_and_refused_when_not_private() {
        let temp = tempfile::tempdir().unwrap();
        let dir = runtime_dir_in(None, temp.path()).unwrap();
        assert_eq!(dir, temp.path().join(format!("painleve-{}", euid())));
        assert_eq!(std::fs::metadata(&dir).unwrap().mode() & 0o777, 0o700);
        // Open to others: refused, naming the mode.
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o777)).unwrap();
        let e = runtime_dir_in(None, temp.path()).unwrap_err().to_string();
        assert!(e.contains("mode 777"), "{e}");
        std::fs::remove_dir(&dir).unwrap();
        // A link planted at its name: refused, and nothing made through it.
        let elsewhere = temp.path().join("planted");
        std::fs::DirBuilder::new().mode(0o700).create(&elsewhere).unwrap();
        symlink(&elsewhere, &dir).unwrap();
        let e = runtime_dir_in(None, temp.path()).unwrap_err().to_string();
        assert!(e.contains("symbolic link"), "{e}");
        // $XDG_RUNTIME_DIR when private; the temporary folder's otherwise.
        let xdg = temp.path().join("xdg");
        std::fs::DirBuilder::new().mode(0o700).create(&xdg).unwrap();
        assert_eq!(runtime_dir_in(Some(xdg.as_os_str()), temp.path()).unwrap(), xdg.join("painleve"));
        std::fs::set_permissions(&xdg, std::fs::Permissions::from_mode(0o755)).unwrap();
        std::fs::remove_file(&dir).unwrap();
        assert_eq!(runtime_dir_in(Some(xdg.as_os_str()), temp.path()).unwrap(), dir);
    }

    #[test]
    fn another_users_folder_is_refused() {
        // Only root can give a folder away (as another user would own it).
        if euid() != 0 {
            eprintln!("skipped: needs root to chown a folder to nobody");
            return;
        }
        let temp = tempfile::tempdir().unwrap();
        let dir = temp.path().join(format!("painleve-{}", euid()));
        std::fs::DirBuilder::new().mode(0o700).create(&dir).unwrap();
        std::os::unix::fs::chown(&dir, Some(65534), Some(65534)).unwrap();
        let e = runtime_dir_in(None, temp.path()).unwrap_err().to_string();
        assert!(e.contains("owned by uid 65534") && e.contains("another user's"), "{e}");
        // A lock file of another user's, in a folder of ours: refused too.
        let lock = temp.path().join("r.lock");
        std::fs::write(&lock, "65534").unwrap();
        std::os::unix::fs::chown(&lock, Some(65534), Some(65534)).unwrap();
        let e = open_lock(&lock).unwrap_err().to_string();
        assert!(e.contains("owned by uid 65534"), "{e}");
    }

    #[test]
    fn a_dead_runs_pid_files_are_removed_and_a_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let me = std::process::id();
        for name in [format!("painleve-pil-{dead}-0.up"), format!("painleve-pil-{me}-0.up"), "painleve-pil-x-0.up".into(), "other".into()] {
            std::fs::write(dir.path().join(name), "").unwrap();
        }
        assert_eq!(remove_dead_pid_files(dir.path(), "painleve-pil-"), [format!("painleve-pil-{dead}-0.up")]);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
    }

    #[test]
    fn a_dead_pid_is_dead() {
        assert!(pid_alive(i64::from(std::process::id())));
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = i64::from(child.id());
        child.wait().unwrap();
        assert!(!pid_alive(pid));
        assert!(!pid_alive(0) && !pid_alive(-1) && !pid_alive(i64::MAX));
    }
}
