//! Files of an output directory: an exclusive lock per directory, and
//! atomic replacement of whole files.
//!
//! * [`lock_dir`]: one writer per output directory. Two runs into the same
//!   `--out` at once appended every record twice; the second now fails at
//!   once, naming the directory. The lock is an advisory lock (`flock`) on
//!   [`LOCK_FILE`] held for the life of the [`DirLock`]; the system
//!   releases it when the process ends, however it ends, so a stale lock
//!   file never blocks a later run.
//! * [`write_file`] and [`replace_with`]: the new content goes to a
//!   temporary file in the same directory, which is synced and renamed over
//!   the target. A reader sees the old file or the new one, never a partial
//!   one: a disk that fills up while `run.json` is written leaves the old
//!   `run.json` (or none), not a truncated one that breaks every later run,
//!   and a figure that cannot be written leaves no 0-byte PNG.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Name of the lock file inside a locked output directory.
pub const LOCK_FILE: &str = ".sornav-sim.lock";

/// Why an output file or directory could not be used.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Another process holds the directory's lock.
    #[error(
        "{dir} is in use by another sornav-sim run (lock {lock} held); wait for it to finish or use another --out"
    )]
    Busy {
        /// The output directory.
        dir: PathBuf,
        /// Its lock file.
        lock: PathBuf,
    },
    /// A file could not be created, written, synced or renamed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's error.
        #[source]
        source: std::io::Error,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The exclusive lock of an output directory, released when dropped.
#[derive(Debug)]
pub struct DirLock {
    _file: File,
}

/// Takes the exclusive lock of `dir` (which must exist) without waiting.
///
/// # Errors
/// [`OutputError::Busy`] when another process (or another [`DirLock`] of
/// this one) holds it, [`OutputError::Io`] when the lock file cannot be
/// opened or locked.
pub fn lock_dir(dir: &Path) -> Result<DirLock, OutputError> {
    let path = dir.join(LOCK_FILE);
    let file = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(io(&path))?;
    match file.try_lock() {
        Ok(()) => Ok(DirLock { _file: file }),
        Err(TryLockError::WouldBlock) => Err(OutputError::Busy {
            dir: dir.to_path_buf(),
            lock: path,
        }),
        Err(TryLockError::Error(e)) => Err(io(&path)(e)),
    }
}

/// A temporary path next to `path`, with its extension (so that encoders
/// that choose the format by extension, such as plotters', still do);
/// removed when dropped unless persisted.
fn temp_beside(path: &Path) -> Result<tempfile::TempPath, OutputError> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(&suffix)
        .tempfile_in(dir)
        .map(tempfile::NamedTempFile::into_temp_path)
        .map_err(io(path))
}

/// Replaces `path` with `bytes` atomically (temporary file, sync, rename).
///
/// # Errors
/// [`OutputError::Io`]; `path` is then unchanged and no temporary file is
/// left.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    replace_with(path, |tmp| {
        let mut f = File::create(tmp).map_err(io(tmp))?;
        f.write_all(bytes).map_err(io(tmp))?;
        f.sync_all().map_err(io(tmp))
    })
}

/// Replaces `path` atomically with what `write` writes to the temporary
/// path it is given (which has `path`'s extension). The temporary file is
/// synced before the rename.
///
/// # Errors
/// `write`'s error, or [`OutputError::Io`] (converted into `E`) when the
/// temporary file cannot be created, synced or renamed; `path` is then
/// unchanged and no temporary file is left.
pub fn replace_with<E: From<OutputError>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let tmp = temp_beside(path)?;
    write(&tmp)?;
    File::open(&tmp)
        .and_then(|f| f.sync_all())
        .map_err(io(path))?;
    tmp.persist(path).map_err(|e| io(path)(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sornav-output-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_second_lock_on_the_same_directory_is_refused_until_the_first_is_dropped() {
        let dir = temp_dir("lock");
        let first = lock_dir(&dir).unwrap();
        match lock_dir(&dir) {
            Err(e @ OutputError::Busy { .. }) => {
                assert!(e.to_string().contains("in use"), "{e}");
            }
            other => panic!("expected Busy, got {other:?}"),
        }
        drop(first);
        let again = lock_dir(&dir).unwrap();
        drop(again);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn a_failed_replacement_keeps_the_old_file_and_leaves_no_temporary() {
        let dir = temp_dir("replace");
        let path = dir.join("run.json");
        write_file(&path, b"old").unwrap();
        let failed: Result<(), OutputError> = replace_with(&path, |tmp| {
            std::fs::write(tmp, b"partial").unwrap();
            Err(OutputError::Io {
                path: tmp.to_path_buf(),
                source: std::io::Error::other("disk full"),
            })
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        write_file(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, [std::ffi::OsString::from("run.json")]);
        // the temporary path keeps the extension
        replace_with(&dir.join("fig.png"), |tmp| {
            assert_eq!(tmp.extension().unwrap(), "png");
            std::fs::write(tmp, b"png").map_err(io(tmp))
        })
        .unwrap();
        let _ = std::fs::remove_dir_all(dir);
    }
}
