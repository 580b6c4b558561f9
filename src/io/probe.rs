//! What the output driver makes of the grid layer, found out before the run reads a feature: the
//! layer is written once in memory (`/vsimem/`; in a temporary folder for a driver that cannot
//! write there) by the same driver with the same options and fields, and read back. Whatever
//! the format, this tells
//! - whether it keeps the cells at all (XLSX and ODS store no geometry; CSV stores it as WKT,
//!   which snakegrid asks for), and whether the creation options are acceptable;
//! - the names the driver gives the fields (a DBF cuts them to 10 characters, SQLite launders
//!   them), so that a source field that would take a computed field's name is written as
//!   `src_<name>` instead and the computed values keep their documented names (and, as
//!   ogr2ogr does, a source field whose name another took already, compared without case, as
//!   `<name>2`, `<name>3`, …: a GeoJSON layer may hold both `Name` and `NAME`, which a
//!   GeoPackage cannot);
//! - whether the driver can add a layer to a file it wrote, and delete one (GeoPackage can, KML
//!   cannot), which decides what `-update` and `-overwrite` may do with an existing file.
//!
//! Once the features are read, their ids are written the same way and read back, so that ids
//! the output would merge or change (a DBF drops trailing spaces, keeps at most 254 bytes and
//! recodes to its encoding) are refused before the layout.

use super::paths::file_list;
use super::readback::{can_read, read_back, Expected};
use super::session::Session;
use super::write::{self, computed_fields, Container, LayerSpec, OutputField, Row};
use crate::core::Error;
use crate::fields::OUTPUT_FIELDS;
use gdal::vector::{Defn, Feature, FieldValue, OGRFieldType};
use gdal::{Dataset, DatasetCapability, DatasetOptions, Driver, GdalOpenFlags};
use geo::{polygon, Polygon};
use std::ffi::{CString, OsStr};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The driver and options the output is written with.
pub(crate) struct Trial<'a> {
    pub session: &'a Session,
    pub driver: &'a Driver,
    pub dataset_options: &'a [String],
    pub layer_options: &'a [String],
    pub layer: &'a str,
    /// The destination's file name, so that the driver decides as it will for the real one
    /// (a `.shp` file, or a folder of Shapefiles).
    pub file_name: &'a OsStr,
}

/// The fields of the grid layer, as the probe found the driver names them.
pub(crate) struct Fields {
    /// The source fields, in order, as they are written.
    pub fields: Vec<OutputField>,
    /// Every field of the layer as the driver names it: the source fields, then the computed.
    pub stored: Vec<String>,
    /// The source fields written under another name, and why.
    pub notes: Vec<String>,
    /// The driver can add a layer to a file it wrote and delete one from it.
    pub layers_in_place: bool,
    /// How many files the driver wrote the dataset as (a Shapefile's `.shp`, `.shx`, `.dbf`,
    /// …): a dataset sent to standard output must be one.
    pub files: usize,
}

/// The name a source field called `name` is written under so as not to take a computed
/// field's: `src_<name>`, or, when another source field has that name already (the output of
/// an earlier run laid out again), the first of `src_<name>_2`, `src_<name>_3`, … that no source
/// field and no field written has (compared as the drivers do, without case).
fn renamed(name: &str, source: &[String], fields: &[OutputField]) -> String {
    let base = format!("src_{name}");
    let candidates = std::iter::once(base.clone()).chain((2..).map(|k| format!("{base}_{k}")));
    first_free(candidates, source.iter().map(String::as_str), fields)
}

/// The first of `candidates` (an endless run of names) that none of `names`, no field of
/// `fields` and no computed field has, compared as the drivers compare names: without case.
fn first_free<'n>(
    mut candidates: impl Iterator<Item = String>,
    names: impl Iterator<Item = &'n str> + Clone,
    fields: &[OutputField],
) -> String {
    let taken = |candidate: &str| {
        names.clone().any(|n| n.eq_ignore_ascii_case(candidate))
            || (fields.iter().map(|f| f.name.as_str()))
                .chain(computed_fields().map(|(c, _)| c))
                .any(|n| n.eq_ignore_ascii_case(candidate))
    };
    candidates
        .find(|candidate| !taken(candidate))
        .expect("an endless run of names has a free one")
}

/// Renames, as ogr2ogr does, each of `fields` whose name an earlier one has (compared without
/// case, as SQLite and DBF compare them) to the first of `<name>2`, `<name>3`, … that no field
/// and no computed field has; says which were renamed.
fn without_repeated_names(fields: &mut [OutputField]) -> Vec<bool> {
    let mut renamed = vec![false; fields.len()];
    for k in 0..fields.len() {
        let name = &fields[k].name;
        if !fields[..k]
            .iter()
            .any(|f| f.name.eq_ignore_ascii_case(name))
        {
            continue;
        }
        let candidates = (2..).map(|n| format!("{name}{n}"));
        let name = first_free(candidates, std::iter::empty(), fields);
        fields[k].name = name;
        renamed[k] = true;
    }
    renamed
}

impl Trial<'_> {
    /// Makes the grid layer in memory with one blank feature of the `source` layer, renaming
    /// source fields until every computed field keeps its name and no two fields have one.
    pub(crate) fn fields(&self, source: &Defn) -> Result<Fields, Error> {
        let names: Vec<String> = source.fields().map(|f| f.name()).collect();
        let computed = |name: &str| computed_fields().any(|(c, _)| c.eq_ignore_ascii_case(name));
        let mut fields: Vec<OutputField> = (0..names.len())
            .map(|k| OutputField {
                source: k,
                name: names[k].clone(),
            })
            .collect();
        for k in 0..fields.len() {
            if computed(&names[k]) {
                let name = renamed(&names[k], &names, &fields);
                fields[k].name = name;
            }
        }
        let repeated = without_repeated_names(&mut fields);
        // Null (not unset) values, which even formats without a schema (GeoJSON) write, so that
        // every field reads back; a field the source declares NOT NULL (a GML layer's gml_id,
        // a constraint set in QGIS), which the output keeps as ogr2ogr does, gets a value of
        // its type instead.
        let mut blank =
            Feature::new(source).map_err(|e| self.session.io_error("cannot make a feature", e))?;
        for (k, field) in source.fields().enumerate() {
            let placeholder = match field.field_type() {
                _ if field.is_nullable() => None,
                OGRFieldType::OFTInteger | OGRFieldType::OFTInteger64 | OGRFieldType::OFTReal => {
                    Some("0")
                }
                OGRFieldType::OFTString => Some(""),
                OGRFieldType::OFTDate => Some("2000-01-01"),
                OGRFieldType::OFTTime => Some("00:00:00"),
                OGRFieldType::OFTDateTime => Some("2000-01-01T00:00:00"),
                _ => None,
            };
            match placeholder {
                Some(value) => blank.set_field_string(k, value),
                None => blank.set_field_null(k),
            }
            .map_err(|e| self.session.io_error("cannot make a feature", e))?;
        }
        // Each pass renames at least one more source field, so there are at most as many passes
        // as computed fields, plus the one that finds nothing more to rename.
        for _ in 0..=OUTPUT_FIELDS.len() {
            let (stored, layers_in_place, files) =
                self.try_layer(&fields, &[("", &blank)], None)?;
            let (kept, added) = stored.split_at(fields.len());
            let clash = computed_fields()
                .zip(added)
                .find(|((name, _), got)| got.as_str() != *name)
                .map(|((name, _), _)| name);
            let Some(clash) = clash else {
                let notes = fields
                    .iter()
                    .zip(kept)
                    .filter(|(field, _)| field.name != names[field.source])
                    .map(|(field, as_stored)| match repeated[field.source] {
                        true => format!(
                            "the source field {:?} is written as {as_stored:?}, as ogr2ogr \
                             writes it: another field has its name but for case, which most \
                             formats (GeoPackage, Shapefile) cannot tell apart",
                            names[field.source],
                        ),
                        false => format!(
                            "the source field {:?} is written as {as_stored:?}: the {} output \
                             would otherwise give it the name of the computed field",
                            names[field.source],
                            self.driver.short_name()
                        ),
                    })
                    .collect();
                return Ok(Fields {
                    fields,
                    stored,
                    notes,
                    layers_in_place,
                    files,
                });
            };
            // The source field that took the computed field's name, once the driver named it.
            let taker = kept
                .iter()
                .position(|k| k.eq_ignore_ascii_case(clash))
                .filter(|&k| fields[k].name == names[fields[k].source]);
            match taker {
                Some(k) => {
                    let name = renamed(&names[fields[k].source], &names, &fields);
                    fields[k].name = name;
                }
                None => {
                    return Err(Error::Io(format!(
                        "the {} driver does not keep the name of the computed field {clash:?}",
                        self.driver.short_name()
                    )))
                }
            }
        }
        Err(Error::Io(format!(
            "the {} driver keeps renaming the computed fields",
            self.driver.short_name()
        )))
    }

    /// Writes every `feature` of the source under its id (the field at `id_position` of
    /// `fields.stored`) in memory and reads it back, refusing the first id the output would
    /// change.
    pub(crate) fn ids(
        &self,
        fields: &Fields,
        features: &[(&str, &Feature)],
        id_position: usize,
    ) -> Result<(), Error> {
        self.try_layer(&fields.fields, features, Some(id_position))
            .map(|_| ())
    }

    /// Writes the layer with `fields` and `features` into a fresh folder of `/vsimem/`, reads it
    /// back (the ids too when `id_position` is given), and returns the names the driver gave
    /// every field, whether it can add and delete layers in the file it wrote, and how many
    /// files it wrote.
    ///
    /// A driver that fails in memory is tried again in a temporary folder on disk, and that
    /// trial's answer stands: some drivers claim GDAL's virtual I/O but cannot create a vector
    /// dataset there (netCDF: "Unable to create netCDF file", as if the destination's folder
    /// were missing), and what they do on disk is what the real output will meet.
    fn try_layer(
        &self,
        fields: &[OutputField],
        features: &[(&str, &Feature)],
        id_position: Option<usize>,
    ) -> Result<(Vec<String>, bool, usize), Error> {
        let memory = MemFolder::new();
        let result = self.try_layer_at(&memory.0, "in memory", fields, features, id_position);
        if result.is_ok() {
            return result;
        }
        match tempfile::tempdir() {
            Ok(disk) => self.try_layer_at(
                disk.path(),
                "in a temporary folder",
                fields,
                features,
                id_position,
            ),
            Err(_) => result,
        }
    }

    /// [`Self::try_layer`] in `folder`, whose path the messages replace by the destination's
    /// file name and say where (`place`) it was tried.
    fn try_layer_at(
        &self,
        folder: &Path,
        place: &str,
        fields: &[OutputField],
        features: &[(&str, &Feature)],
        id_position: Option<usize>,
    ) -> Result<(Vec<String>, bool, usize), Error> {
        // GDAL's warnings about the trial (unknown options, values cut) come again, about the
        // real output, when the run writes it.
        let warnings = self.session.warning_count();
        let result = self.try_layer_in(folder, fields, features, id_position);
        self.session.forget_warnings_after(warnings);
        // Messages name the destination, not the file that stood in for it.
        let shown = folder.join(self.file_name).display().to_string();
        let tried = format!("{} (tried {place})", self.file_name.to_string_lossy());
        result.map_err(|error| match error {
            Error::Io(message) => Error::Io(message.replace(&shown, &tried)),
            Error::InvalidInput { feature, message } => Error::InvalidInput {
                feature,
                message: message.replace(&shown, &tried),
            },
            other => other,
        })
    }

    fn try_layer_in(
        &self,
        folder: &Path,
        fields: &[OutputField],
        features: &[(&str, &Feature)],
        id_position: Option<usize>,
    ) -> Result<(Vec<String>, bool, usize), Error> {
        let path = folder.join(self.file_name);
        let square: Polygon<f64> =
            polygon![(x: 0.0, y: 0.0), (x: 1.0, y: 0.0), (x: 1.0, y: 1.0), (x: 0.0, y: 1.0)];
        let rows: Vec<Row> = features
            .iter()
            .map(|&(id, source)| Row {
                id,
                source,
                cell: &square,
                computed: computed_fields()
                    .map(|(_, kind)| match kind {
                        OGRFieldType::OFTInteger => FieldValue::IntegerValue(0),
                        _ => FieldValue::RealValue(0.0),
                    })
                    .collect(),
            })
            .collect();
        let spec = LayerSpec {
            name: self.layer,
            srs: None,
            options: self.layer_options,
            fields,
            metadata: &[],
        };
        let container = Container::New {
            driver: self.driver,
            options: self.dataset_options,
        };
        let written = write::write(self.session, &path, &container, &spec, &rows, &|_| true)?;
        let ids: Vec<&str> = features.iter().map(|(id, _)| *id).collect();
        let expected = Expected {
            driver: &self.driver.short_name(),
            layer: &written.layer,
            fields: &written.fields,
            ids: id_position.map(|position| (position, ids.as_slice())),
            features: rows.len(),
        };
        if can_read(self.driver) {
            read_back(self.session, &path, &expected)?;
        }
        let files = Dataset::open(&path).map_or(1, |dataset| file_list(&dataset).len().max(1));
        Ok((written.fields, layers_in_place(&path), files))
    }
}

/// Whether the dataset at `path`, opened for update, can take another layer and lose one.
fn layers_in_place(path: &Path) -> bool {
    let options = DatasetOptions {
        open_flags: GdalOpenFlags::GDAL_OF_VECTOR | GdalOpenFlags::GDAL_OF_UPDATE,
        ..Default::default()
    };
    Dataset::open_ex(path, options).is_ok_and(|dataset| {
        dataset.has_capability(DatasetCapability::CREATE_LAYER)
            && dataset.has_capability(DatasetCapability::DELETE_LAYER)
    })
}

/// A folder of GDAL's in-memory file system, removed with everything in it when dropped.
struct MemFolder(PathBuf);

/// Makes the folders of concurrent runs (the C API may run several) distinct.
static PROBES: AtomicUsize = AtomicUsize::new(0);

impl MemFolder {
    fn new() -> MemFolder {
        let folder = MemFolder(PathBuf::from(format!(
            "/vsimem/snakegrid-probe-{}-{}",
            std::process::id(),
            PROBES.fetch_add(1, Ordering::Relaxed)
        )));
        // Drivers that write a folder of files (CSV, Shapefile) want it to exist, as a
        // staging folder does.
        if let Some(path) = folder.c_path() {
            // SAFETY: a NUL-terminated path that outlives the call.
            unsafe { gdal_sys::VSIMkdir(path.as_ptr(), 0o755) };
        }
        folder
    }

    fn c_path(&self) -> Option<CString> {
        CString::new(self.0.to_string_lossy().as_bytes()).ok()
    }
}

impl Drop for MemFolder {
    fn drop(&mut self) {
        if let Some(path) = self.c_path() {
            // SAFETY: a NUL-terminated path that outlives the call; VSIRmdirRecursive only
            // removes what is under it in GDAL's in-memory file system.
            unsafe { gdal_sys::VSIRmdirRecursive(path.as_ptr()) };
        }
    }
}
