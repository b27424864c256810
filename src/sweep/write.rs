//! Whole outputs: a file is written to a temporary file and renamed over
//! its destination ([`atomic_write`]); the output *set* of a sweep is
//! written into a staging directory next to its destination and swapped
//! into place only when every file is complete ([`publish_dir`]), so an
//! interrupted or failed sweep never leaves a partial set in view — neither
//! a half-written file nor new results beside an old `index.html`.
//!
//! The rules, each with the defect it answers (issue 27):
//!
//! * **One writer per destination.** [`OutputLock`] is an exclusive
//!   `flock` on `.<name>.dae-lock` beside the destination, taken before any
//!   work and held until the set is published; a second sweep into the same
//!   `--out` is refused at once with [`PublishError::Busy`] naming the
//!   holder's process id (it does not wait: a sweep can take hours, and a
//!   refusal is what a script can act on). The kernel releases the lock
//!   when its holder dies, however it dies.
//! * **One atomic replacement.** On Linux the complete staging directory
//!   and the previous set are exchanged by one `renameat2(…,
//!   RENAME_EXCHANGE)` (through `rustix`): at every instant the
//!   destination holds the previous or the new complete set. Where the
//!   call is not available (other systems, or a file system that refuses
//!   it with `EINVAL`) the fallback is two renames — the old set aside,
//!   the new one in — between which (microseconds) the destination is
//!   absent, never partial, and a kill there leaves both complete sets
//!   beside it under `.<name>.dae-sweep-*` names.
//! * **Stale staging directories are removed, live ones never.** A
//!   staging or retired directory carries its creator's process id
//!   (`.<name>.dae-sweep-new-<pid>-<n>`); it is removed only under the
//!   lock and only if that process no longer exists.
//! * **Interrupts.** [`interrupt`] (called by the `dae` binary's SIGINT
//!   handler) removes the staging directories of this process and exits
//!   with 130 before the exchange; once the new set is in place the
//!   interrupt is ignored and the command finishes with its own code.
//! * **A mount point as destination is refused before any work**
//!   ([`PublishError::MountPoint`]): no rename can replace it.
//!
//! Write failures (a full disk, permissions) are errors of the fill and
//! leave the previous set in place.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Distinguishes temporary files of one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A fresh temporary path next to `dest`: same directory, hidden name, same
/// extension (the PNG encoder picks its format from the extension).
///
/// ```
/// use std::path::Path;
/// let tmp = dae::sweep::write::temp_path_for(Path::new("out/a.png"));
/// assert_eq!(tmp.parent(), Some(Path::new("out")));
/// assert!(tmp.to_str().unwrap().ends_with(".png"));
/// ```
pub fn temp_path_for(dest: &Path) -> PathBuf {
    let dir = dest.parent().unwrap_or_else(|| Path::new(""));
    let name = dest.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = match dest.extension().and_then(|e| e.to_str()) {
        Some(ext) => format!(".{name}.tmp-{}-{n}.{ext}", std::process::id()),
        None => format!(".{name}.tmp-{}-{n}", std::process::id()),
    };
    dir.join(tmp)
}

/// Produce `dest` through a temporary file: `produce` creates and fills the
/// file at the path it is given; on success the file is renamed over
/// `dest`; on failure it is removed and `dest` is untouched.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// let dest = dir.path().join("a.txt");
/// dae::sweep::write::atomic_write_via(&dest, |tmp| std::fs::write(tmp, "x"))?;
/// assert_eq!(std::fs::read_to_string(&dest)?, "x");
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn atomic_write_via<E, F>(dest: &Path, produce: F) -> Result<(), E>
where
    F: FnOnce(&Path) -> Result<(), E>,
    E: From<io::Error>,
{
    let tmp = temp_path_for(dest);
    let result = produce(&tmp).and_then(|()| fs::rename(&tmp, dest).map_err(E::from));
    if result.is_err() {
        // The temporary file may or may not exist; nothing else to do.
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Write `dest` through a temporary file with a caller-supplied writer
/// body: `fill` writes into the open temporary file (it may fail half-way);
/// the data is flushed to disk before the rename.
///
/// ```
/// use std::io::Write;
/// let dir = tempfile::tempdir()?;
/// let dest = dir.path().join("a.txt");
/// dae::sweep::write::atomic_write_with(&dest, |w| w.write_all(b"x"))?;
/// assert_eq!(std::fs::read(&dest)?, b"x");
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn atomic_write_with<F>(dest: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    atomic_write_via(dest, |tmp: &Path| {
        let mut file = File::create(tmp)?;
        fill(&mut file)?;
        file.flush()?;
        file.sync_all()
    })
}

/// Write `bytes` to `dest` whole: after this returns, `dest` holds either
/// its previous content (on error) or exactly `bytes`.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// let dest = dir.path().join("a.txt");
/// dae::sweep::write::atomic_write(&dest, b"whole")?;
/// assert_eq!(std::fs::read(&dest)?, b"whole");
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn atomic_write(dest: &Path, bytes: &[u8]) -> io::Result<()> {
    atomic_write_with(dest, |w| w.write_all(bytes))
}

/// Why an output set could not be published (see the module
/// documentation for the rules).
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    /// Another process holds the lock on this destination.
    #[error(
        "{} is being written by another dae process{}; a destination takes one sweep at a time, \
         so wait for it to finish or give another --out (lock: {})",
        dir.display(),
        holder.map_or_else(String::new, |p| format!(" (pid {p})")),
        lock.display()
    )]
    Busy {
        /// The destination.
        dir: PathBuf,
        /// The lock file.
        lock: PathBuf,
        /// The holder's process id, as it wrote it into the lock file.
        holder: Option<u32>,
    },
    /// The destination is a mount point: no rename can replace it.
    #[error(
        "{} is a mount point: a sweep replaces its output directory by a rename, which a mount \
         point refuses; give a directory inside it, e.g. {}",
        dir.display(),
        dir.join("out").display()
    )]
    MountPoint {
        /// The destination.
        dir: PathBuf,
    },
    /// The destination's path does not end in a name (`.`, `..`, `/`).
    #[error("`{}` does not end in a directory name (give e.g. out/s01, not . or ..)", dir.display())]
    NoName {
        /// The destination.
        dir: PathBuf,
    },
    /// An existing destination that is not a directory.
    #[error("{} exists and is not a directory", dir.display())]
    NotADirectory {
        /// The destination.
        dir: PathBuf,
    },
    /// A file system operation failed.
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        /// What was being done (`create`, `lock`, `replace`, …).
        action: &'static str,
        /// On what.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
}

impl PublishError {
    fn io<'a>(action: &'static str, path: &'a Path) -> impl FnOnce(io::Error) -> PublishError + 'a {
        move |source| PublishError::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Marker in the names of staging directories: `.<DIR>.dae-sweep-…`.
const STAGING_MARK: &str = ".dae-sweep-";

/// The name of `dest`'s last component.
fn dest_name(dest: &Path) -> Result<&str, PublishError> {
    dest.file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| PublishError::NoName {
            dir: dest.to_path_buf(),
        })
}

/// The name stem every staging directory of `dest` starts with:
/// `.<name of dest>.dae-sweep-`.
fn staging_prefix(dest: &Path) -> Result<String, PublishError> {
    Ok(format!(".{}{STAGING_MARK}", dest_name(dest)?))
}

/// The directory holding `dest` (`.` for a bare name).
fn parent_of(dest: &Path) -> &Path {
    match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// A fresh path beside `dest` for a staging (`new`) or retired (`old`)
/// directory: `.<name>.dae-sweep-<kind>-<pid>-<n>`.
fn sibling(dest: &Path, kind: &str) -> Result<PathBuf, PublishError> {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = format!("{}{kind}-{}-{n}", staging_prefix(dest)?, std::process::id());
    Ok(parent_of(dest).join(name))
}

/// The process id in a staging directory's name
/// (`.<name>.dae-sweep-<kind>-<pid>-<n>`).
fn staging_pid(name: &str, prefix: &str) -> Option<u32> {
    let rest = name.strip_prefix(prefix)?;
    let mut parts = rest.split('-');
    let _kind = parts.next()?;
    parts.next()?.parse().ok()
}

/// Whether process `pid` exists (signal 0). `true` where this cannot be
/// told, so that a directory is never removed on a guess.
#[cfg(unix)]
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    // Beyond i32 (Linux allows at most 2^22) or 0: no such process.
    let Some(p) = i32::try_from(pid)
        .ok()
        .and_then(rustix::process::Pid::from_raw)
    else {
        return false;
    };
    match rustix::process::test_kill_process(p) {
        Ok(()) => true,
        Err(e) => e != rustix::io::Errno::SRCH,
    }
}

/// Whether process `pid` exists; without a way to tell, `true`.
#[cfg(not(unix))]
fn process_alive(pid: u32) -> bool {
    let _ = pid;
    true
}

/// Remove the staging and retired directories that dead processes left
/// beside `dest` (`.<name>.dae-sweep-*-<pid>-*` whose `pid` no longer
/// exists, or this process's own); returns what was removed. Only names of
/// that form are touched, never `dest` itself, and never a directory of a
/// live process. [`publish_dir`] calls it under the destination's lock.
///
/// ```
/// let dir = tempfile::tempdir()?;
/// let dest = dir.path().join("out");
/// // No process has id 4 000 000 000 (Linux allows at most 2^22).
/// let dead = dir.path().join(".out.dae-sweep-new-4000000000-0");
/// std::fs::create_dir(&dead)?;
/// let removed = dae::sweep::write::clean_leftovers(&dest)?;
/// assert_eq!(removed, [dead]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn clean_leftovers(dest: &Path) -> Result<Vec<PathBuf>, PublishError> {
    let prefix = staging_prefix(dest)?;
    let parent = parent_of(dest);
    let mut removed = Vec::new();
    let entries = match fs::read_dir(parent) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(removed),
        Err(e) => return Err(PublishError::io("read", parent)(e)),
    };
    let mine = std::process::id();
    for entry in entries {
        let entry = entry.map_err(PublishError::io("read", parent))?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some(pid) = staging_pid(name, &prefix) else {
            continue;
        };
        let is_dir = entry
            .file_type()
            .map_err(PublishError::io("read", &entry.path()))?
            .is_dir();
        let ours_or_dead = (pid == mine && !is_active(&entry.path())) || !process_alive(pid);
        if is_dir && ours_or_dead {
            let path = entry.path();
            fs::remove_dir_all(&path).map_err(PublishError::io("remove", &path))?;
            removed.push(path);
        }
    }
    Ok(removed)
}

/// Staging directories and locks of this process, for [`interrupt`].
struct Active {
    staging: Vec<PathBuf>,
    locks: Vec<PathBuf>,
    /// A set was exchanged into place: an interrupt now is ignored.
    published: bool,
}

static ACTIVE: Mutex<Active> = Mutex::new(Active {
    staging: Vec::new(),
    locks: Vec::new(),
    published: false,
});

fn active() -> std::sync::MutexGuard<'static, Active> {
    // A panic while holding it leaves plain data; use it as it is.
    ACTIVE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn is_active(path: &Path) -> bool {
    active().staging.iter().any(|p| p == path)
}

/// What an interrupt (SIGINT) does: before a set is published, remove this
/// process's staging directories and lock files, and return `true` (the
/// caller exits with 130; the previous set is untouched); after, return
/// `false` (the new set is in place; the command finishes normally). Waits
/// for an exchange in progress to complete, so it never interrupts one.
///
/// ```
/// // Nothing staged in this process: an interrupt may end it.
/// assert!(dae::sweep::write::interrupt());
/// ```
pub fn interrupt() -> bool {
    let mut a = active();
    if a.published {
        return false;
    }
    for dir in a.staging.drain(..) {
        // A worker may still be adding files: try again a few times.
        for _ in 0..5 {
            if fs::remove_dir_all(&dir).is_ok() || !dir.exists() {
                break;
            }
        }
    }
    for lock in a.locks.drain(..) {
        let _ = fs::remove_file(lock);
    }
    // Keep the mutex until the process exits, so that no exchange starts.
    std::mem::forget(a);
    true
}

/// An exclusive lock on an output destination, held from before the work
/// until the set is published (see the module documentation). Dropping it
/// releases the lock and removes the lock file.
///
/// ```
/// use dae::sweep::write::OutputLock;
/// let dir = tempfile::tempdir()?;
/// let dest = dir.path().join("s01");
/// let lock = OutputLock::acquire(&dest)?;
/// assert_eq!(lock.dest(), dest);
/// drop(lock);
/// assert!(OutputLock::acquire(&dest).is_ok());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct OutputLock {
    dest: PathBuf,
    path: PathBuf,
    /// Holds the `flock`; closing it releases the lock.
    _file: File,
}

impl OutputLock {
    /// Take the lock on `dest` without waiting: `.<name>.dae-lock` in
    /// `dest`'s parent (created, with the parent, if missing). Refuses a
    /// `dest` that is a mount point or not a directory, and one another
    /// process is writing ([`PublishError::Busy`]). Then removes the
    /// leftovers of dead processes ([`clean_leftovers`]).
    pub fn acquire(dest: &Path) -> Result<OutputLock, PublishError> {
        let name = dest_name(dest)?;
        let parent = parent_of(dest);
        fs::create_dir_all(parent).map_err(PublishError::io("create", parent))?;
        check_destination(dest)?;
        let path = parent.join(format!(".{name}.dae-lock"));
        // The holder removes the lock file on release; a file opened just
        // before that removal is locked in vain, so the lock counts only if
        // the path still names the locked file.
        for _ in 0..100 {
            let mut file = fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(PublishError::io("create", &path))?;
            if !try_lock(&file).map_err(PublishError::io("lock", &path))? {
                let mut text = String::new();
                let _ = io::Read::read_to_string(&mut file, &mut text);
                return Err(PublishError::Busy {
                    dir: dest.to_path_buf(),
                    lock: path,
                    holder: text.trim().parse().ok(),
                });
            }
            if same_file(&file, &path) {
                file.set_len(0).map_err(PublishError::io("write", &path))?;
                write!(file, "{}", std::process::id()).map_err(PublishError::io("write", &path))?;
                active().locks.push(path.clone());
                let lock = OutputLock {
                    dest: dest.to_path_buf(),
                    path,
                    _file: file,
                };
                clean_leftovers(dest)?;
                return Ok(lock);
            }
        }
        Err(PublishError::Io {
            action: "lock",
            path,
            source: io::Error::other("the lock file kept being replaced"),
        })
    }

    /// The destination this lock guards.
    pub fn dest(&self) -> &Path {
        &self.dest
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Removed while still locked (the file closes after this).
        let _ = fs::remove_file(&self.path);
        active().locks.retain(|p| p != &self.path);
    }
}

/// `flock(LOCK_EX | LOCK_NB)`: `Ok(false)` when another holds it.
#[cfg(unix)]
fn try_lock(file: &File) -> io::Result<bool> {
    use rustix::fs::{flock, FlockOperation};
    match flock(file, FlockOperation::NonBlockingLockExclusive) {
        Ok(()) => Ok(true),
        Err(e) if e == rustix::io::Errno::WOULDBLOCK => Ok(false),
        Err(e) => Err(e.into()),
    }
}

/// Without `flock`, no lock: one sweep per destination is the user's care.
#[cfg(not(unix))]
fn try_lock(_file: &File) -> io::Result<bool> {
    Ok(true)
}

/// Whether the open `file` is the file `path` names now.
#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> bool {
    path.exists()
}

/// Refuse, before any work, a `dest` that exists and is not a directory or
/// is a mount point.
fn check_destination(dest: &Path) -> Result<(), PublishError> {
    match fs::symlink_metadata(dest) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(PublishError::io("read", dest)(e)),
        Ok(m) if !m.is_dir() => Err(PublishError::NotADirectory {
            dir: dest.to_path_buf(),
        }),
        Ok(_) if is_mount_point(dest) => Err(PublishError::MountPoint {
            dir: dest.to_path_buf(),
        }),
        Ok(_) => Ok(()),
    }
}

/// Whether the directory `dir` is a mount point: on another device than
/// its parent, or (a bind mount within one device) listed as a mount point
/// in `/proc/self/mountinfo`.
///
/// ```
/// use std::path::Path;
/// assert!(dae::sweep::write::is_mount_point(Path::new("/")));
/// let dir = tempfile::tempdir()?;
/// assert!(!dae::sweep::write::is_mount_point(&dir.path().join("sub")));
/// # Ok::<(), std::io::Error>(())
/// ```
pub fn is_mount_point(dir: &Path) -> bool {
    let Ok(full) = fs::canonicalize(dir) else {
        return false;
    };
    let Some(parent) = full.parent() else {
        // The root.
        return true;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(a), Ok(b)) = (fs::metadata(&full), fs::metadata(parent)) {
            if a.dev() != b.dev() {
                return true;
            }
        }
    }
    listed_mount_point(&full)
}

/// Whether `/proc/self/mountinfo` lists `full` (canonical) as a mount
/// point; `false` where there is no such file.
fn listed_mount_point(full: &Path) -> bool {
    let Ok(info) = fs::read_to_string("/proc/self/mountinfo") else {
        return false;
    };
    let Some(want) = full.to_str() else {
        return false;
    };
    info.lines()
        .filter_map(|line| line.split(' ').nth(4))
        .any(|point| unescape_mountinfo(point) == want)
}

/// Undo mountinfo's octal escapes (`\040` for a space, …).
fn unescape_mountinfo(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let octal = bytes.get(i + 1..i + 4).and_then(|d| {
            std::str::from_utf8(d)
                .ok()
                .and_then(|d| u8::from_str_radix(d, 8).ok())
        });
        match (bytes[i], octal) {
            (b'\\', Some(b)) => {
                out.push(b);
                i += 4;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Produce the directory `dest` whole: `fill` writes every file into a
/// fresh staging directory `.<name>.dae-sweep-new-<pid>-<n>` beside `dest`
/// (same file system, so the replacement is a rename, not a copy).
///
/// * `fill` fails: the staging directory is removed, `dest` is untouched.
/// * `fill` succeeds and `dest` does not exist: the staging directory is
///   renamed to `dest`.
/// * `dest` exists: the two are exchanged atomically (the module
///   documentation has the fallback where that is not available), and the
///   previous set, now under the staging name, is removed.
///
/// The destination's [`OutputLock`] is taken here unless `lock` is given
/// (the command line takes it before the work, so that a second sweep is
/// refused before it runs). Whether `dest` may be replaced at all is the
/// caller's decision (see `sweep::write_outputs`).
///
/// ```
/// let root = tempfile::tempdir()?;
/// let dest = root.path().join("out");
/// let n = dae::sweep::write::publish_dir(&dest, None, |staging| {
///     std::fs::write(staging.join("results.csv"), "t\n")?;
///     Ok::<_, Box<dyn std::error::Error>>(1)
/// })?;
/// assert_eq!(n, 1);
/// assert!(dest.join("results.csv").is_file());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn publish_dir<T, E, F>(dest: &Path, lock: Option<&OutputLock>, fill: F) -> Result<T, E>
where
    F: FnOnce(&Path) -> Result<T, E>,
    E: From<PublishError>,
{
    // Held until the set is published (dropped at the end).
    let _own = match lock {
        Some(l) if l.dest() == dest => None,
        _ => Some(OutputLock::acquire(dest)?),
    };
    let staging = sibling(dest, "new")?;
    {
        let mut a = active();
        fs::create_dir(&staging).map_err(PublishError::io("create", &staging))?;
        a.staging.push(staging.clone());
    }
    let forget = |staging: &Path| active().staging.retain(|p| p != staging);
    let value = match fill(&staging) {
        Ok(v) => v,
        Err(e) => {
            // Whatever was written is discarded; the error is the fill's.
            let _ = fs::remove_dir_all(&staging);
            forget(&staging);
            return Err(e);
        }
    };
    let swapped = {
        let mut a = active();
        let r = replace_dir(&staging, dest);
        if r.is_ok() {
            a.published = true;
        }
        a.staging.retain(|p| p != &staging);
        r
    };
    // Either the previous set (exchanged) or the unused staging directory.
    let _ = fs::remove_dir_all(&staging);
    swapped?;
    Ok(value)
}

/// Move the complete `staging` directory to `dest`: a rename when `dest`
/// is absent, otherwise an exchange (afterwards `staging` names the
/// previous set).
fn replace_dir(staging: &Path, dest: &Path) -> Result<(), PublishError> {
    match fs::symlink_metadata(dest) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return fs::rename(staging, dest).map_err(PublishError::io("create", dest))
        }
        Err(e) => return Err(PublishError::io("read", dest)(e)),
        Ok(m) if !m.is_dir() => {
            return Err(PublishError::NotADirectory {
                dir: dest.to_path_buf(),
            })
        }
        Ok(_) => {}
    }
    if exchange(staging, dest).map_err(PublishError::io("replace", dest))? {
        return Ok(());
    }
    // The fallback: two renames.
    let old = sibling(dest, "old")?;
    fs::rename(dest, &old).map_err(PublishError::io("replace", dest))?;
    if let Err(e) = fs::rename(staging, dest) {
        // Put the previous set back; it was only moved.
        let _ = fs::rename(&old, dest);
        return Err(PublishError::io("replace", dest)(e));
    }
    // `staging` is now free: the caller removes what is there, so move the
    // retired set there (a failure only leaves a leftover for the next run).
    let _ = fs::rename(&old, staging);
    Ok(())
}

/// `renameat2(a, b, RENAME_EXCHANGE)`: `Ok(false)` where the system or
/// the file system does not offer it (then the caller falls back).
#[cfg(any(target_os = "linux", target_os = "android"))]
fn exchange(a: &Path, b: &Path) -> io::Result<bool> {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    use rustix::io::Errno;
    match renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE) {
        Ok(()) => Ok(true),
        Err(e) if e == Errno::INVAL || e == Errno::NOSYS || e == Errno::NOTSUP => Ok(false),
        Err(e) => Err(e.into()),
    }
}

/// No atomic exchange here: the caller falls back to two renames.
#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn exchange(_a: &Path, _b: &Path) -> io::Result<bool> {
    Ok(false)
}
