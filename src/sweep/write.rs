//! Whole outputs: a file is written to a temporary file and renamed over
//! its destination ([`atomic_write`]); the output *set* of a sweep is
//! written into a staging directory next to its destination and renamed
//! into place only when every file is complete ([`publish_dir`]), so an
//! interrupted or failed sweep never leaves a partial set in view — neither
//! a half-written file nor new results beside an old `index.html`.
//!
//! A rename within one directory is atomic on POSIX file systems; on
//! Windows `std::fs::rename` replaces a destination file as well.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Distinguishes temporary files of one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A fresh temporary path next to `dest`: same directory, hidden name, same
/// extension (the PNG encoder picks its format from the extension).
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
pub fn atomic_write(dest: &Path, bytes: &[u8]) -> io::Result<()> {
    atomic_write_with(dest, |w| w.write_all(bytes))
}

/// Marker in the names of staging directories: `.<DIR>.dae-sweep-…`.
const STAGING_MARK: &str = ".dae-sweep-";

/// The name stem every staging directory of `dest` starts with:
/// `.<name of dest>.dae-sweep-`.
fn staging_prefix(dest: &Path) -> io::Result<String> {
    let name = dest.file_name().and_then(|n| n.to_str()).ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "`{}` does not end in a directory name (give e.g. out/s01, not . or ..)",
                dest.display()
            ),
        )
    })?;
    Ok(format!(".{name}{STAGING_MARK}"))
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
fn sibling(dest: &Path, kind: &str) -> io::Result<PathBuf> {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = format!("{}{kind}-{}-{n}", staging_prefix(dest)?, std::process::id());
    Ok(parent_of(dest).join(name))
}

/// Remove the staging and retired directories a killed run left beside
/// `dest` (`.<name>.dae-sweep-*`); returns what was removed. Only names of
/// that form are touched, never `dest` itself. Two sweeps writing to the
/// same destination at the same time are not supported: the later one
/// removes the other's staging directory.
pub fn clean_leftovers(dest: &Path) -> io::Result<Vec<PathBuf>> {
    let prefix = staging_prefix(dest)?;
    let parent = parent_of(dest);
    let mut removed = Vec::new();
    let entries = match fs::read_dir(parent) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(removed),
        Err(e) => return Err(e),
    };
    for entry in entries {
        let entry = entry?;
        let is_leftover = entry
            .file_name()
            .to_str()
            .is_some_and(|n| n.starts_with(&prefix));
        if is_leftover && entry.file_type()?.is_dir() {
            fs::remove_dir_all(entry.path())?;
            removed.push(entry.path());
        }
    }
    Ok(removed)
}

/// Produce the directory `dest` whole: `fill` writes every file into a
/// fresh staging directory `.<name>.dae-sweep-new-<pid>-<n>` beside `dest`
/// (same file system, so the renames below are renames, not copies).
///
/// * `fill` fails: the staging directory is removed, `dest` is untouched.
/// * `fill` succeeds and `dest` does not exist: the staging directory is
///   renamed to `dest` (one atomic rename).
/// * `dest` exists: it is renamed aside to `.<name>.dae-sweep-old-…`, the
///   staging directory renamed to `dest`, and the old one removed. Between
///   the two renames (microseconds) `dest` is absent, never partial; a
///   kill exactly there leaves both complete sets beside it under those
///   names. Whether `dest` may be replaced at all is the caller's decision
///   (see `sweep::write_outputs`).
///
/// Leftovers of killed runs (`.<name>.dae-sweep-*`) are removed first
/// ([`clean_leftovers`]); a run killed while filling leaves only its
/// staging directory, which the next run removes.
pub fn publish_dir<T, E, F>(dest: &Path, fill: F) -> Result<T, E>
where
    F: FnOnce(&Path) -> Result<T, E>,
    E: From<io::Error>,
{
    fs::create_dir_all(parent_of(dest))?;
    clean_leftovers(dest)?;
    let staging = sibling(dest, "new")?;
    fs::create_dir(&staging)?;
    let value = match fill(&staging) {
        Ok(v) => v,
        Err(e) => {
            // Whatever was written is discarded; the error is the fill's.
            let _ = fs::remove_dir_all(&staging);
            return Err(e);
        }
    };
    let swapped = replace_dir(&staging, dest);
    if swapped.is_err() {
        let _ = fs::remove_dir_all(&staging);
    }
    swapped?;
    Ok(value)
}

/// Move the complete `staging` directory to `dest`, retiring an existing
/// `dest` first (see [`publish_dir`]).
fn replace_dir(staging: &Path, dest: &Path) -> io::Result<()> {
    match fs::symlink_metadata(dest) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return fs::rename(staging, dest),
        Err(e) => return Err(e),
        Ok(m) if !m.is_dir() => {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!("`{}` exists and is not a directory", dest.display()),
            ))
        }
        Ok(_) => {}
    }
    let old = sibling(dest, "old")?;
    fs::rename(dest, &old)?;
    if let Err(e) = fs::rename(staging, dest) {
        // Put the previous set back; it was only moved.
        let _ = fs::rename(&old, dest);
        return Err(e);
    }
    // The new set is in place; a failure to delete the old one only leaves
    // a leftover that the next run removes.
    let _ = fs::remove_dir_all(&old);
    Ok(())
}
