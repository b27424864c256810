//! Whole-file writes: every output of `dae sweep` is first written to a
//! temporary file in the destination directory and then renamed over the
//! destination, so an interrupted or failed sweep never leaves a
//! half-written results file, and an older complete file stays intact until
//! the new one is complete.
//!
//! A rename within one directory is atomic on POSIX file systems; on
//! Windows `std::fs::rename` replaces the destination as well.

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
