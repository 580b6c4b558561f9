//! Staging folders. Each output of a run is written into a fresh hidden folder beside its
//! destination, `.NAME.snakegrid-XXXXXX.tmp` (made by `tempfile`; beside it so that moving the
//! output into place is a rename on one file system), and removed with everything in it when the
//! run ends, whether it failed, was cancelled or succeeded (then it is empty but for what the
//! output replaced).
//!
//! A run that is killed outright (SIGKILL, a power cut) cannot clean up. So each run holds an
//! advisory lock on its staging folders for as long as it lives, which the kernel releases when
//! the process ends however it ends, and every run removes the staging folders beside its
//! outputs whose lock it can take and that are older than [`STALE_AFTER`] (the age guards
//! against file systems whose locks are only local, and against a run that has just made its
//! folder and not yet locked it).

use crate::core::Error;
use std::ffi::OsStr;
use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};
use tempfile::TempDir;

/// A staging folder this old, whose lock is free, was left by a run that was killed.
pub(crate) const STALE_AFTER: Duration = Duration::from_secs(10 * 60);

const MARK: &str = ".snakegrid-";
const SUFFIX: &str = ".tmp";

/// The staging folder of one output, locked while it lives, removed when dropped.
pub(crate) struct Staging {
    /// The destination's file name, which the output has inside the folder too.
    name: PathBuf,
    dir: TempDir,
    /// Holds the advisory lock on `dir`.
    _lock: File,
}

impl Staging {
    /// A new locked staging folder beside `destination` (an output described as `what`).
    pub(crate) fn new(destination: &Path, what: &str) -> Result<Staging, Error> {
        let name = PathBuf::from(destination.file_name().unwrap_or_default());
        let cannot = |e: std::io::Error| {
            Error::Io(format!(
                "cannot write next to the {what} {:?}: {e}",
                destination.display()
            ))
        };
        let folder = folder_of(destination);
        if !folder.is_dir() {
            return Err(Error::Io(format!(
                "the folder {:?} of the {what} {:?} does not exist",
                folder.display(),
                destination.display()
            )));
        }
        let prefix = format!(".{}{MARK}", name.display());
        let dir = tempfile::Builder::new()
            .prefix(&prefix)
            .suffix(SUFFIX)
            .tempdir_in(&folder)
            .map_err(cannot)?;
        let lock = File::open(dir.path()).map_err(cannot)?;
        lock.try_lock().map_err(|e| cannot(e.into()))?;
        Ok(Staging {
            name,
            dir,
            _lock: lock,
        })
    }

    /// The folder itself.
    pub(crate) fn dir(&self) -> &Path {
        self.dir.path()
    }

    /// Where the output is written: the destination's file name inside the folder.
    pub(crate) fn path(&self) -> PathBuf {
        self.dir.path().join(&self.name)
    }

    /// Leaves the folder on disk (it holds files a failed commit could not put back) and returns
    /// its path.
    pub(crate) fn keep(self) -> PathBuf {
        self.dir.keep()
    }
}

/// The folder of `path` ("." for a bare file name).
pub(crate) fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Whether `name` is what [`Staging::new`] names its folders.
fn is_staging_name(name: &OsStr) -> bool {
    let name = name.to_string_lossy();
    name.starts_with('.') && name.ends_with(SUFFIX) && name.contains(MARK)
}

/// Removes the staging folders in `folder` that no live run holds and that are older than
/// [`STALE_AFTER`]; returns a note for each one removed.
pub(crate) fn sweep(folder: &Path) -> Vec<String> {
    let Ok(listing) = fs::read_dir(folder) else {
        return Vec::new();
    };
    let mut notes = Vec::new();
    for entry in listing.flatten() {
        let path = entry.path();
        if !is_staging_name(&entry.file_name()) || !is_stale(&path) {
            continue;
        }
        // The lock is free only when no run holds it: its owner has ended.
        let Ok(lock) = File::open(&path) else {
            continue;
        };
        if lock.try_lock().is_ok() && fs::remove_dir_all(&path).is_ok() {
            notes.push(format!(
                "removed the staging folder {:?}, left by a run that was interrupted",
                path.display()
            ));
        }
    }
    notes
}

/// A real folder (not a link to one) last changed more than [`STALE_AFTER`] ago.
fn is_stale(path: &Path) -> bool {
    fs::symlink_metadata(path)
        .ok()
        .filter(|m| m.is_dir())
        .and_then(|m| m.modified().ok())
        .and_then(|changed| SystemTime::now().duration_since(changed).ok())
        .is_some_and(|age| age > STALE_AFTER)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sets the modification time of `path` to `age` ago.
    fn age(path: &Path, age: Duration) {
        let file = File::open(path).unwrap();
        file.set_modified(SystemTime::now() - age).unwrap();
    }

    #[test]
    fn a_sweep_removes_only_old_staging_folders_no_run_holds() {
        let scratch = tempfile::tempdir().unwrap();
        let destination = scratch.path().join("grid.gpkg");
        let held = Staging::new(&destination, "destination").unwrap();
        let held_dir = held.dir().to_path_buf();
        let old = scratch.path().join(".grid.gpkg.snakegrid-abc123.tmp");
        let young = scratch.path().join(".other.svg.snakegrid-def456.tmp");
        let unrelated = scratch.path().join(".keep.tmp");
        for dir in [&old, &young, &unrelated] {
            fs::create_dir(dir).unwrap();
            fs::write(dir.join("partial"), b"x").unwrap();
        }
        let long_ago = STALE_AFTER + Duration::from_secs(60);
        for dir in [&old, &unrelated, &held_dir] {
            age(dir, long_ago);
        }
        age(&young, STALE_AFTER / 2);

        let notes = sweep(scratch.path());
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].contains(".grid.gpkg.snakegrid-abc123.tmp"));
        assert!(!old.exists());
        assert!(young.exists() && unrelated.exists());
        assert!(held_dir.exists(), "a folder a live run holds stays");
        drop(held);
        assert!(!held_dir.exists(), "dropping the staging removes it");
    }
}
