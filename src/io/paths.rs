//! What a run must never write to: every file of the source dataset as GDAL lists it, compared
//! by where the file system puts a path, not by how it is spelled. `a.shp`, `./a.shp`,
//! `dir/../a.shp` and a symbolic link to it are all the same file; `a.dbf` is part of `a.shp`.

use crate::core::Error;
use gdal::Dataset;
use std::ffi::CStr;
use std::path::{Component, Path, PathBuf};

/// The files SQLite keeps beside a database while it is open or after a crash.
pub(crate) const SQLITE_JOURNALS: [&str; 3] = ["-wal", "-shm", "-journal"];

/// The files of a source dataset, canonical.
pub(crate) struct SourceFiles {
    files: Vec<PathBuf>,
    /// The source as the user named it, for messages.
    shown: String,
}

impl SourceFiles {
    /// Every file GDAL says `dataset` is made of (a Shapefile's `.shp` and all its sidecars, a
    /// GeoPackage), with the journal files SQLite keeps beside a database (`-wal`, `-shm`,
    /// `-journal`), and for a dataset inside an archive (`/vsizip/a.zip/...`) the archive.
    pub(crate) fn of(dataset: &Dataset, src: &str) -> SourceFiles {
        let mut listed = file_list(dataset);
        if listed.is_empty() {
            listed.push(src.to_owned());
        }
        let mut files = Vec::new();
        for name in listed {
            let path = match archive_of(&name) {
                Some(archive) => archive,
                None => PathBuf::from(&name),
            };
            for suffix in std::iter::once("").chain(SQLITE_JOURNALS) {
                let mut with = path.clone().into_os_string();
                with.push(suffix);
                files.extend(canonical(Path::new(&with)));
            }
        }
        files.sort();
        files.dedup();
        SourceFiles {
            files,
            shown: src.to_owned(),
        }
    }

    /// No files at all, for tests of what writes outputs.
    #[cfg(test)]
    pub(crate) fn none() -> SourceFiles {
        SourceFiles {
            files: Vec::new(),
            shown: String::new(),
        }
    }

    /// Refuses `path` (an output described as `what`) when writing it could touch a file of the
    /// source: it is one of them, or a folder that holds one.
    pub(crate) fn refuse(&self, what: &str, path: &Path) -> Result<(), Error> {
        let targets = canonical(path);
        for target in &targets {
            if let Some(file) = self.files.iter().find(|f| f.starts_with(target)) {
                let relation = if file == target {
                    "is a file of"
                } else {
                    "is a folder that holds a file of"
                };
                return Err(Error::Io(format!(
                    "the {what} {:?} {relation} the source {:?} ({}): refusing to write over \
                     the source",
                    path.display(),
                    self.shown,
                    file.display()
                )));
            }
        }
        Ok(())
    }
}

/// The ways the file system can name `path`: the real folder it is in plus its name (which is
/// what a new file there would be), and where it finally leads when it exists (through symbolic
/// links). Empty only when the folder cannot be resolved either.
pub(crate) fn canonical(path: &Path) -> Vec<PathBuf> {
    let mut ways = Vec::new();
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match (folder.canonicalize(), path.file_name()) {
        (Ok(real), Some(name)) => ways.push(real.join(name)),
        _ => ways.push(lexical(path)),
    }
    if let Ok(real) = path.canonicalize() {
        if !ways.contains(&real) {
            ways.push(real);
        }
    }
    ways
}

/// The file an output path names: through a symbolic link to an existing file, the file it
/// leads to, so that the output replaces that file and the link stays (as `ogr2ogr` writes
/// through a link); otherwise the path itself. The run's outputs are staged beside their final
/// path and renamed over it, and a rename over a link replaces the link.
pub(crate) fn through_link(path: &str) -> String {
    let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    match Path::new(path).canonicalize() {
        Ok(real) if is_link && real.is_file() => real.to_string_lossy().into_owned(),
        _ => path.to_string(),
    }
}

/// `path` with `.` and `..` resolved by spelling only, for paths the file system cannot resolve.
fn lexical(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// The archive of a path inside one of GDAL's archive file systems (`/vsizip/a.zip/b.shp` →
/// `a.zip`, `/vsigzip/a.gpkg.gz` → `a.gpkg.gz`): the longest leading part that is a file.
fn archive_of(name: &str) -> Option<PathBuf> {
    let inner = ["/vsizip/", "/vsitar/", "/vsigzip/", "/vsi7z/"]
        .iter()
        .find_map(|prefix| name.strip_prefix(prefix))?;
    // `{...}` quotes an archive path that holds the archive file system's own separators.
    let inner = inner.trim_start_matches('{').replace('}', "");
    let mut candidate = PathBuf::from(inner);
    loop {
        if candidate.is_file() {
            return Some(candidate);
        }
        if !candidate.pop() {
            return None;
        }
    }
}

/// Refuses a `path` that is a FIFO, a socket or a device: opening one waits for a writer or
/// reads a stream, so a run would hang before any check (a symbolic link is judged by its
/// target). A path that does not exist is left to the caller.
pub(crate) fn refuse_special_file(what: &str, path: &Path) -> Result<(), Error> {
    use std::os::unix::fs::FileTypeExt;
    let Ok(kind) = std::fs::metadata(path).map(|m| m.file_type()) else {
        return Ok(());
    };
    let special = if kind.is_fifo() {
        "a named pipe (FIFO)"
    } else if kind.is_socket() {
        "a socket"
    } else if kind.is_char_device() || kind.is_block_device() {
        "a device"
    } else {
        return Ok(());
    };
    Err(Error::Io(format!(
        "the {what} {:?} is {special}, not a file or folder: snakegrid reads and writes \
         datasets in files",
        path.display()
    )))
}

/// GDALGetFileList: the files the driver says make up the dataset.
pub(crate) fn file_list(dataset: &Dataset) -> Vec<String> {
    // SAFETY: the dataset handle is valid while `dataset` lives; GDALGetFileList returns a new
    // NULL-terminated list of NUL-terminated strings (or NULL), which is read and then freed
    // with CSLDestroy, as GDAL documents.
    unsafe {
        let list = gdal_sys::GDALGetFileList(dataset.c_dataset());
        let mut names = Vec::new();
        if !list.is_null() {
            let mut k = 0;
            while !(*list.add(k)).is_null() {
                names.push(CStr::from_ptr(*list.add(k)).to_string_lossy().into_owned());
                k += 1;
            }
            gdal_sys::CSLDestroy(list);
        }
        names
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_of_one_file_are_one_path() {
        let dir = std::env::temp_dir().join(format!("snakegrid-paths-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let file = dir.join("a.gpkg");
        std::fs::write(&file, b"x").unwrap();
        let link = dir.join("link.gpkg");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&file, &link).unwrap();
        let real = file.canonicalize().unwrap();
        assert!(canonical(&dir.join("sub/../a.gpkg")).contains(&real));
        assert!(canonical(&dir.join("./a.gpkg")).contains(&real));
        assert!(canonical(&link).contains(&real));
        // A file that does not exist yet: its folder resolved, its name kept.
        assert_eq!(
            canonical(&dir.join("sub/../new.gpkg")),
            vec![dir.canonicalize().unwrap().join("new.gpkg")]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_archive_path_names_its_archive() {
        let dir = std::env::temp_dir().join(format!("snakegrid-zip-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let zip = dir.join("a.zip");
        std::fs::write(&zip, b"x").unwrap();
        let inside = format!("/vsizip/{}/layers/b.shp", zip.display());
        assert_eq!(archive_of(&inside), Some(zip.clone()));
        assert_eq!(archive_of("plain.shp"), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
