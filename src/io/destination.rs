//! What a run may do with what is already at an output's path, as ogr2ogr's `-update` and
//! `-overwrite` say, decided before any feature is read:
//! - nothing there: a new file (`-update` is refused: it adds a layer to a dataset that exists);
//! - something there, neither option: refused;
//! - a file of the output's format that holds several layers, where GDAL can add and delete one
//!   (GeoPackage, SQLite): `-update` adds the layer (refused when the file has a layer of that
//!   name), `-overwrite` adds or replaces it; both work on a copy of the file that the commit
//!   renames over the original, so that every other layer, style, metadata and relation is kept
//!   and the original is untouched until the new file is complete (the cost: a full copy);
//! - any other file (a single-layer format: Shapefile, GeoJSON, FlatGeobuf, CSV; a file GDAL
//!   cannot open): `-overwrite` replaces it whole, with its sidecars, but never a dataset that
//!   holds another layer or a raster, which would be lost;
//! - a folder: refused, whatever the options (its other files would be at stake).

use super::paths::{file_list, SQLITE_JOURNALS};
use super::session::Session;
use crate::core::Error;
use gdal::vector::LayerAccess;
use gdal::{Dataset, DatasetOptions, Driver, GdalOpenFlags, Metadata};
use std::fs;
use std::path::{Path, PathBuf};

/// What the user allowed to happen to existing outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mode {
    /// Neither option: every output must be new.
    Create,
    /// `-update`: add the layer to the existing destination dataset.
    Update,
    /// `-overwrite`: replace the layer, or what cannot hold more than it.
    Overwrite,
}

impl Mode {
    pub(crate) fn of(update: bool, overwrite: bool) -> Mode {
        match (update, overwrite) {
            (_, true) => Mode::Overwrite,
            (true, false) => Mode::Update,
            (false, false) => Mode::Create,
        }
    }
}

/// How the destination dataset is written.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Plan {
    /// A new dataset, which replaces whatever [`Destination::displaced`] lists.
    New,
    /// A copy of the existing file with the layer added, or put in place of the layer named.
    /// `alone`: the file holds no other layer and no raster, so nothing else's metadata can
    /// change with the new layer's.
    InPlace {
        replace: Option<String>,
        alone: bool,
    },
}

/// An output path checked before any work.
#[derive(Debug)]
pub(crate) struct Destination {
    pub path: PathBuf,
    pub plan: Plan,
    /// The files the output replaces when it is committed.
    pub displaced: Vec<PathBuf>,
}

impl Destination {
    /// Checks the destination dataset of a run: `driver` writes it, with a layer named `layer`;
    /// `layers_in_place`: the driver can add a layer to a file it wrote and delete one from it.
    pub(crate) fn dataset(
        session: &Session,
        path: &str,
        mode: Mode,
        driver: &Driver,
        layer: &str,
        layers_in_place: bool,
    ) -> Result<Destination, Error> {
        let path = PathBuf::from(path);
        let shown = path.display();
        let Some(existing) = existing(&path, "destination", mode)? else {
            if mode == Mode::Update {
                return Err(Error::Io(format!(
                    "the destination {shown:?} does not exist: -update adds a layer to an \
                     existing dataset"
                )));
            }
            return Ok(Destination {
                path,
                plan: Plan::New,
                displaced: Vec::new(),
            });
        };
        // A write-ahead log or rollback journal holds what the database file does not yet
        // (SQLite's shared-memory index, -shm, holds none of the data). Checked before GDAL
        // opens the file: SQLite may apply or remove a journal when a connection closes.
        let journal = existing
            .iter()
            .skip(1)
            .find(|file| !file.to_string_lossy().ends_with("-shm"));
        if let Some(journal) = journal {
            return Err(Error::Io(format!(
                "the destination {shown:?} is in use ({:?} exists: another program has it open, \
                 or did not close it): close it first, as snakegrid replaces the file with a \
                 new or updated copy",
                journal.display()
            )));
        }
        let options = DatasetOptions {
            open_flags: GdalOpenFlags::GDAL_OF_VECTOR
                | GdalOpenFlags::GDAL_OF_RASTER
                | GdalOpenFlags::GDAL_OF_READONLY,
            ..Default::default()
        };
        let opened = Dataset::open_ex(&path, options).ok();
        // A file that is not a dataset is no error of the run's.
        session.take_error();
        let Some(old) = opened else {
            if mode == Mode::Update {
                return Err(Error::Io(format!(
                    "the destination {shown:?} is not a dataset GDAL can open, so -update \
                     cannot add a layer to it"
                )));
            }
            return Ok(Destination {
                displaced: existing,
                path,
                plan: Plan::New,
            });
        };
        let format = old.driver().short_name();
        let output = driver.short_name();
        let layers: Vec<String> = old.layers().map(|l| l.name()).collect();
        let mut files = own_files(&path, &file_list(&old));
        if format == "ESRI Shapefile" {
            // Deduplicated with the rest below.
            files.extend(shapefile_indexes(&path));
        }
        let single_file = files.iter().all(|f| f.file_name() == path.file_name());
        if format == output && single_file && layers_in_place {
            let same = layers.iter().find(|l| l.eq_ignore_ascii_case(layer));
            if let (Mode::Update, Some(same)) = (mode, same) {
                return Err(Error::Io(format!(
                    "the destination {shown:?} already has a layer {same:?} (use -overwrite to \
                     replace it, or -nln to choose another name)"
                )));
            }
            let alone = layers.iter().all(|l| Some(l) == same) && !has_rasters(&old);
            return Ok(Destination {
                plan: Plan::InPlace {
                    replace: same.cloned(),
                    alone,
                },
                displaced: vec![path.clone()],
                path,
            });
        }
        if mode == Mode::Update {
            return Err(Error::Io(if format == output {
                format!(
                    "the {output} format cannot add a layer to the existing {shown:?} \
                     (-update); use -overwrite to replace it"
                )
            } else {
                format!(
                    "the destination {shown:?} is a {format} dataset, so -update cannot add a \
                     {output} layer to it"
                )
            }));
        }
        let rasters = has_rasters(&old);
        // What replacing the whole file would lose: a file of the output's own single-layer
        // format holds just the layer being replaced; any other, every layer of another name.
        let others: Vec<&String> = if format == output && layers.len() <= 1 {
            Vec::new()
        } else {
            layers
                .iter()
                .filter(|l| !l.eq_ignore_ascii_case(layer))
                .collect()
        };
        if rasters || !others.is_empty() {
            let mut held: Vec<String> = others.iter().map(|l| format!("layer {l:?}")).collect();
            if rasters {
                held.push("raster data".to_owned());
            }
            return Err(Error::Io(format!(
                "the destination {shown:?} is a {format} dataset that holds {}, which -overwrite \
                 would lose: a {output} output replaces the whole file; write to another file",
                held.join(", ")
            )));
        }
        let mut displaced = existing;
        for file in files {
            if !displaced.contains(&file) {
                displaced.push(file);
            }
        }
        Ok(Destination {
            path,
            plan: Plan::New,
            displaced,
        })
    }

    /// Checks a plain file output (the JSON report, the picture), described as `what`.
    pub(crate) fn file(path: &str, what: &str, mode: Mode) -> Result<Destination, Error> {
        let path = PathBuf::from(path);
        // -update concerns the destination dataset only.
        let mode = if mode == Mode::Update {
            Mode::Create
        } else {
            mode
        };
        let displaced = existing(&path, what, mode)?.unwrap_or_default();
        Ok(Destination {
            path,
            plan: Plan::New,
            displaced,
        })
    }
}

/// What is at `path` (the path and the SQLite journals beside it), `None` when nothing is;
/// refuses a path without a file name, a folder, and anything at all in [`Mode::Create`].
fn existing(path: &Path, what: &str, mode: Mode) -> Result<Option<Vec<PathBuf>>, Error> {
    let shown = path.display();
    if path.file_name().is_none() {
        return Err(Error::Io(format!(
            "the {what} {shown:?} is not a file name"
        )));
    }
    let Ok(metadata) = fs::symlink_metadata(path) else {
        return Ok(None);
    };
    super::paths::refuse_special_file(what, path)?;
    if metadata.is_dir() {
        return Err(Error::Io(format!(
            "the {what} {shown:?} is a folder: snakegrid does not replace or update folders, \
             whose other files would be at stake; name a file (e.g. a .gpkg, or a .shp inside \
             the folder)"
        )));
    }
    if mode == Mode::Create {
        return Err(Error::Io(format!(
            "the {what} {shown:?} already exists (use -overwrite to replace it)"
        )));
    }
    let mut files = vec![path.to_path_buf()];
    for suffix in SQLITE_JOURNALS {
        let mut name = path.as_os_str().to_owned();
        name.push(suffix);
        let name = PathBuf::from(name);
        if fs::symlink_metadata(&name).is_ok() {
            files.push(name);
        }
    }
    Ok(Some(files))
}

/// Files beside the Shapefile `path` that describe its old data but that GDAL does not list:
/// other programs' spatial indexes and code page. Left beside a new Shapefile, the indexes are
/// corrupt and the code page misreads its text.
fn shapefile_indexes(path: &Path) -> Vec<PathBuf> {
    const SIDECARS: [&str; 10] = [
        "sbn", "sbx", "fbn", "fbx", "ain", "aih", "atx", "ixs", "mxs", "cpg",
    ];
    let Some(stem) = path.file_stem() else {
        return Vec::new();
    };
    let Ok(entries) = fs::read_dir(super::staging::folder_of(path)) else {
        return Vec::new();
    };
    let stem = stem.to_string_lossy().to_lowercase();
    let mut found: Vec<PathBuf> = entries
        .filter_map(|entry| entry.ok())
        .map(|entry| entry.file_name().to_string_lossy().into_owned())
        .filter(|name| {
            let lower = name.to_lowercase();
            SIDECARS
                .iter()
                .any(|extension| lower == format!("{stem}.{extension}"))
        })
        .map(|name| path.with_file_name(name))
        .collect();
    found.sort();
    found
}

/// The files of a dataset at `path` that belong to it alone: those GDAL lists in the same folder
/// whose names start as `path`'s does (`grid.shp` → `grid.dbf`, `grid.shp.xml`). A dataset may
/// list files it only refers to (a VRT's sources), which are not its to lose.
fn own_files(path: &Path, listed: &[String]) -> Vec<PathBuf> {
    let folder = |p: &Path| {
        let parent = match p.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent,
            _ => Path::new("."),
        };
        fs::canonicalize(parent).ok()
    };
    let home = folder(path);
    let stem = path
        .file_stem()
        .map(|s| format!("{}.", s.to_string_lossy()))
        .unwrap_or_default();
    listed
        .iter()
        .map(Path::new)
        .filter(|file| home.is_some() && folder(file) == home)
        .filter_map(|file| file.file_name())
        .filter(|name| Some(*name) == path.file_name() || name.to_string_lossy().starts_with(&stem))
        // Spelled as the destination is, so that the two compare.
        .map(|name| path.with_file_name(name))
        .collect()
}

/// Whether `dataset` holds rasters, itself or as subdatasets (a GeoPackage's tile tables).
fn has_rasters(dataset: &Dataset) -> bool {
    dataset.raster_count() > 0
        || dataset
            .metadata_domain("SUBDATASETS")
            .is_some_and(|items| !items.is_empty())
}
