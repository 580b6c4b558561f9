//! Outputs appear whole or not at all. Each is written into a fresh hidden folder next to its
//! destination (same file system, so the final move is a rename) and moved into place only after
//! the whole run succeeded; on any failure or cancellation the folder is removed with everything
//! in it. Formats that write several files (a Shapefile's .shp, .shx, .dbf, .prj, .cpg) or a
//! folder are handled alike: whatever the driver wrote in the staging folder is moved.
//!
//! Without `-overwrite` an existing destination is an error found before any work; with it, the
//! old destination is removed (through its GDAL driver when it is a dataset, so sidecar files go
//! too) only once the new one is complete.

use super::paths::SourceFiles;
use super::session::Session;
use crate::core::Error;
use gdal::{Dataset, DatasetOptions, DriverManager, GdalOpenFlags};
use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// What is at a destination before the run.
enum Existing {
    Nothing,
    /// A dataset GDAL opens, removed by its driver (short name).
    Dataset(String),
    File,
}

/// A destination checked before any work.
pub(crate) struct Target {
    path: PathBuf,
    what: &'static str,
    existing: Existing,
}

impl Target {
    /// Checks `path` for an output described as `what` ("destination", "JSON report", ...).
    /// `dataset`: the output is a GDAL dataset (so an existing one is removed by its driver).
    pub(crate) fn check(
        path: &str,
        what: &'static str,
        overwrite: bool,
        dataset: bool,
    ) -> Result<Target, Error> {
        let path = PathBuf::from(path);
        if path.file_name().is_none() {
            return Err(Error::Io(format!(
                "{what} {:?} is not a file name",
                path.display()
            )));
        }
        let Ok(metadata) = fs::symlink_metadata(&path) else {
            return Ok(Target {
                path,
                what,
                existing: Existing::Nothing,
            });
        };
        if !overwrite {
            return Err(Error::Io(format!(
                "{what} {:?} already exists (use -overwrite to replace it)",
                path.display()
            )));
        }
        let opened = dataset
            .then(|| {
                let options = DatasetOptions {
                    open_flags: GdalOpenFlags::GDAL_OF_VECTOR | GdalOpenFlags::GDAL_OF_READONLY,
                    ..Default::default()
                };
                Dataset::open_ex(&path, options).ok()
            })
            .flatten();
        let existing = match opened {
            Some(old) => Existing::Dataset(old.driver().short_name()),
            None if !metadata.is_dir() => Existing::File,
            None => {
                return Err(Error::Io(format!(
                    "{what} {:?} is a folder that is not a dataset; not replacing it",
                    path.display()
                )))
            }
        };
        Ok(Target {
            path,
            what,
            existing,
        })
    }
}

/// An output being written in its staging folder; dropping it without [`Staged::commit`]
/// removes everything written.
pub(crate) struct Staged {
    target: Target,
    dir: PathBuf,
}

/// Makes staging folder names unique among the runs of one process (the C API may run several).
static STAGING: AtomicUsize = AtomicUsize::new(0);

impl Staged {
    pub(crate) fn new(target: Target) -> Result<Staged, Error> {
        let name = target
            .path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let dir = parent(&target.path).join(format!(
            ".{name}.snakegrid-{}-{}.tmp",
            std::process::id(),
            STAGING.fetch_add(1, Ordering::Relaxed)
        ));
        fs::create_dir(&dir).map_err(|e| {
            Error::Io(format!(
                "cannot write next to {} {:?}: {e}",
                target.what,
                target.path.display()
            ))
        })?;
        Ok(Staged { target, dir })
    }

    /// Where to write the output: the destination's file name inside the staging folder.
    pub(crate) fn path(&self) -> PathBuf {
        self.dir
            .join(self.target.path.file_name().unwrap_or_default())
    }

    fn entries(&self) -> Result<Vec<OsString>, Error> {
        let listing = fs::read_dir(&self.dir)
            .map_err(|e| Error::Io(format!("cannot list {:?}: {e}", self.dir.display())))?;
        let mut names = listing
            .map(|entry| entry.map(|e| e.file_name()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| Error::Io(format!("cannot list {:?}: {e}", self.dir.display())))?;
        names.sort();
        Ok(names)
    }

    /// Moves the output into place, first removing what was at the destination (only present
    /// with `-overwrite`, see [`Target::check`]).
    /// Every file it moves is checked once more against the `source` files first: a driver may
    /// write sidecars that the checks before the run could not foresee.
    pub(crate) fn commit(
        self,
        session: &Session,
        overwrite: bool,
        source: &SourceFiles,
    ) -> Result<(), Error> {
        let entries = self.entries()?;
        let folder = parent(&self.target.path);
        let shown = self.target.path.display();
        for name in &entries {
            source.refuse(self.target.what, &folder.join(name))?;
        }
        match &self.target.existing {
            Existing::Nothing => {}
            Existing::Dataset(driver) => DriverManager::get_driver_by_name(driver)
                .and_then(|d| d.delete(&self.target.path))
                .map_err(|e| {
                    session.io_error(
                        &format!("cannot remove the old {} {shown:?}", self.target.what),
                        e,
                    )
                })?,
            Existing::File => fs::remove_file(&self.target.path).map_err(|e| {
                Error::Io(format!(
                    "cannot remove the old {} {shown:?}: {e}",
                    self.target.what
                ))
            })?,
        }
        // A sidecar of the new output may collide with a stray file the old dataset did not list.
        if !overwrite {
            if let Some(taken) = entries.iter().find(|name| folder.join(name).exists()) {
                return Err(Error::Io(format!(
                    "{:?} already exists (use -overwrite to replace it)",
                    folder.join(taken).display()
                )));
            }
        }
        for name in &entries {
            fs::rename(self.dir.join(name), folder.join(name)).map_err(|e| {
                Error::Io(format!(
                    "cannot move the {} into place at {shown:?}: {e}",
                    self.target.what
                ))
            })?;
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        // Empty after a commit; holds the partial output after a failure.
        let _ = fs::remove_dir_all(&self.dir);
    }
}

/// The folder of `path` ("." for a bare file name).
fn parent(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}
