//! Writing the grid layer: one square per region, in input order, with every source field (same
//! name, type, subtype, width and precision), then the cell's column and row and the region's
//! metrics, and the run's metrics and parameters as layer metadata where the format keeps it.

use super::session::Session;
use crate::core::{Error, GridMap, RegionCell};
use gdal::spatial_ref::SpatialRef;
use gdal::vector::{
    Feature, FieldDefn, FieldValue, LayerAccess, LayerOptions, OGRFieldType, OGRwkbGeometryType,
    ToGdal,
};
use gdal::{Dataset, Driver, DriverManager, DriverType, Metadata};
use std::ffi::c_int;
use std::fs::OpenOptions;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The fields added after the source's, all at most 10 characters (the Shapefile limit).
/// Column of the region's cell, from the left (0 = leftmost used column).
pub const GRID_COL: &str = "grid_col";
/// Row of the region's cell, from the top (0 = topmost used row).
pub const GRID_ROW: &str = "grid_row";
/// Distance from the region's centroid to its cell, in cells (after the fit of method.md §8).
pub const CELL_DISP: &str = "cell_disp";
/// Share of the region's neighbours whose cells are still 8-neighbours.
pub const NBR_KEPT: &str = "nbr_kept";
/// Mean direction error towards its neighbours, degrees.
pub const ORIENT_ERR: &str = "orient_err";
const ADDED: [(&str, OGRFieldType::Type); 5] = [
    (GRID_COL, OGRFieldType::OFTInteger),
    (GRID_ROW, OGRFieldType::OFTInteger),
    (CELL_DISP, OGRFieldType::OFTReal),
    (NBR_KEPT, OGRFieldType::OFTReal),
    (ORIENT_ERR, OGRFieldType::OFTReal),
];

/// The values of the [`ADDED`] fields for one cell, in the same order.
fn computed(cell: &RegionCell) -> [FieldValue; 5] {
    let m = &cell.metrics;
    [
        FieldValue::IntegerValue(cell.col),
        FieldValue::IntegerValue(cell.row),
        FieldValue::RealValue(m.displacement),
        FieldValue::RealValue(m.neighbours_kept),
        FieldValue::RealValue(m.orientation_error),
    ]
}

/// The driver for `-f`, else the one the destination's extension names, else GeoPackage; it must
/// write vector data.
pub(crate) fn driver(format: Option<&str>, dst: &str) -> Result<Driver, Error> {
    let driver = match format {
        Some(name) => DriverManager::get_driver_by_name(name)
            .map_err(|_| Error::Io(format!("unknown format {name:?} (see ogrinfo --formats)")))?,
        None => match DriverManager::get_output_driver_for_dataset_name(dst, DriverType::Vector) {
            Some(d) => d,
            None => DriverManager::get_driver_by_name("GPKG")
                .map_err(|_| Error::Io("this GDAL has no GeoPackage driver; give -f".into()))?,
        },
    };
    let says = |key: &str| {
        driver
            .metadata_item(key, "")
            .is_some_and(|v| v.eq_ignore_ascii_case("YES"))
    };
    if !(says("DCAP_VECTOR") && says("DCAP_CREATE")) {
        return Err(Error::Io(format!(
            "format {:?} cannot create vector datasets",
            driver.short_name()
        )));
    }
    // Outputs are staged as files next to the destination, which a database cannot be.
    if driver.metadata_item("DMD_CONNECTION_PREFIX", "").is_some() {
        return Err(Error::Io(format!(
            "format {:?} writes to a database; write a file (e.g. GeoPackage) and load it with \
             ogr2ogr",
            driver.short_name()
        )));
    }
    Ok(driver)
}

/// What the written layer is, besides the cells.
pub(crate) struct LayerSpec<'a> {
    pub name: &'a str,
    /// The names of the source layer's fields, which every feature of `sources` has.
    pub source_fields: &'a [String],
    pub srs: Option<&'a SpatialRef>,
    /// Layer metadata items (key, value).
    pub metadata: &'a [(String, String)],
    /// One line for formats with a layer description (GeoPackage's gpkg_contents).
    pub description: &'a str,
}

/// The name of the layer written and notes (source fields replaced by the computed ones).
pub(crate) struct Written {
    pub layer: String,
    pub notes: Vec<String>,
}

/// Writes the grid layer to a new dataset at `path`: `sources[k]` gives the attributes of
/// `map.cells[k]`. `progress` gets the fraction written and returns false to cancel.
pub(crate) fn write(
    session: &Session,
    path: &Path,
    driver: &Driver,
    spec: &LayerSpec,
    sources: &[Feature],
    map: &GridMap,
    progress: &dyn Fn(f64) -> bool,
) -> Result<Written, Error> {
    let fail = |what: &str, e| session.io_error(&format!("cannot {what} {:?}", path.display()), e);
    let mut dataset = driver
        .create_vector_only(path)
        .map_err(|e| fail("create", e))?;
    // One transaction where the format has them: much faster for GeoPackage, all or nothing.
    let in_transaction = match dataset.start_transaction() {
        Ok(mut transaction) => {
            let written = fill(
                session,
                &mut transaction,
                driver,
                spec,
                sources,
                map,
                progress,
            )?;
            transaction.commit().map_err(|e| fail("write", e))?;
            Some(written)
        }
        Err(_) => None,
    };
    let written = match in_transaction {
        Some(written) => written,
        None => fill(session, &mut dataset, driver, spec, sources, map, progress)?,
    };
    // Closing flushes; a failure here (disk full) must fail the run.
    dataset.close().map_err(|e| fail("write", e))?;
    if driver.short_name() == "ESRI Shapefile" {
        fix_dbf_dates(path)?;
    }
    Ok(written)
}

fn fill(
    session: &Session,
    dataset: &mut Dataset,
    driver: &Driver,
    spec: &LayerSpec,
    sources: &[Feature],
    map: &GridMap,
    progress: &dyn Fn(f64) -> bool,
) -> Result<Written, Error> {
    let fail = |what: &str, e| session.io_error(what, e);
    let source_fields = spec.source_fields;
    let replaced = |name: &str| {
        ADDED
            .iter()
            .any(|(added, _)| added.eq_ignore_ascii_case(name))
    };
    let mut notes: Vec<String> = source_fields
        .iter()
        .filter(|name| replaced(name))
        .map(|name| format!("the source field {name:?} was replaced by the computed value"))
        .collect();

    let taken: Vec<&str> = source_fields
        .iter()
        .map(String::as_str)
        .chain(ADDED.iter().map(|(name, _)| *name))
        .collect();
    let mut options: Vec<String> = ["FID", "GEOMETRY_NAME"]
        .into_iter()
        .filter_map(|option| column_option(driver, option, &taken))
        .collect();
    if creation_option(driver, "DESCRIPTION").is_some() {
        options.push(format!("DESCRIPTION={}", spec.description));
    }
    let option_refs: Vec<&str> = options.iter().map(String::as_str).collect();
    let mut layer = dataset
        .create_layer(LayerOptions {
            name: spec.name,
            srs: spec.srs,
            ty: OGRwkbGeometryType::wkbPolygon,
            options: Some(&option_refs),
        })
        .map_err(|e| fail(&format!("cannot create layer {:?}", spec.name), e))?;

    // Source field k goes to output field map[k] (−1: replaced by a computed field).
    let mut field_map: Vec<c_int> = Vec::with_capacity(source_fields.len());
    let mut next: c_int = 0;
    if let Some(first) = sources.first() {
        for (k, name) in source_fields.iter().enumerate() {
            if replaced(name) {
                field_map.push(-1);
                continue;
            }
            copy_field_definition(&layer, first, k)
                .map_err(|e| fail(&format!("cannot create field {name:?}"), e))?;
            field_map.push(next);
            next += 1;
        }
    }
    let mut added = Vec::with_capacity(ADDED.len());
    for (name, kind) in ADDED {
        FieldDefn::new(name, kind)
            .and_then(|d| d.add_to_layer(&layer))
            .map_err(|e| fail(&format!("cannot create field {name:?}"), e))?;
        added.push(next as usize);
        next += 1;
    }
    if layer.defn().fields().count() != next as usize {
        return Err(Error::Io(format!(
            "the {} driver did not create every field",
            driver.short_name()
        )));
    }
    for (key, value) in spec.metadata {
        layer
            .set_metadata_item(key, value, "")
            .map_err(|e| fail(&format!("cannot set layer metadata {key}"), e))?;
    }

    let total = map.cells.len().max(1) as f64;
    for (k, (cell, source)) in map.cells.iter().zip(sources).enumerate() {
        let mut feature =
            Feature::new(layer.defn()).map_err(|e| fail("cannot make a feature", e))?;
        copy_field_values(&mut feature, source, &field_map)
            .map_err(|e| fail(&format!("cannot copy the attributes of {:?}", cell.id), e))?;
        let square = cell
            .cell
            .to_gdal()
            .map_err(|e| fail("cannot make a cell", e))?;
        feature
            .set_geometry(square)
            .and_then(|_| {
                added
                    .iter()
                    .zip(computed(cell))
                    .try_for_each(|(&index, value)| feature.set_field(index, &value))
            })
            .and_then(|_| feature.create(&layer))
            .map_err(|e| fail(&format!("cannot write the cell of {:?}", cell.id), e))?;
        if !progress((k + 1) as f64 / total) {
            return Err(Error::Cancelled);
        }
    }
    notes.extend(session.warnings());
    Ok(Written {
        layer: layer.name(),
        notes,
    })
}

/// Creates on `layer` a field defined exactly as field `index` of `source`: the safe API can only
/// make a field from a name and a basic type, which would lose subtypes (boolean, int16,
/// float32, JSON, UUID), widths, precisions, defaults and nullability.
fn copy_field_definition<L: LayerAccess>(
    layer: &L,
    source: &Feature,
    index: usize,
) -> gdal::errors::Result<()> {
    let index = c_int::try_from(index)?;
    // SAFETY: `source` is a live feature, which holds a reference to its definition, so the
    // definition and its field `index` (< the source's field count) are valid during the call;
    // OGR_L_CreateField copies the field definition it is given and keeps no pointer to it.
    let result = unsafe {
        let definition = gdal_sys::OGR_F_GetDefnRef(source.c_feature());
        let field = gdal_sys::OGR_FD_GetFieldDefn(definition, index);
        gdal_sys::OGR_L_CreateField(layer.c_layer(), field, 1)
    };
    ogr_result(result, "OGR_L_CreateField")
}

/// Copies every attribute of `source` into `target` as `map` says: the safe API reads and writes
/// no binary or time values, and converting through it could change date-time precision.
fn copy_field_values(
    target: &mut Feature,
    source: &Feature,
    map: &[c_int],
) -> gdal::errors::Result<()> {
    if map.len() != source.field_count() {
        return Err(gdal::errors::GdalError::BadArgument(
            "field map does not match the source".into(),
        ));
    }
    // SAFETY: both features are live; `map` has one entry per field of `source` (checked above),
    // each −1 or the index of a field of `target` whose definition was copied from that source
    // field. OGR_F_SetFromWithMap copies the values and keeps no pointer to either feature.
    let result = unsafe {
        gdal_sys::OGR_F_SetFromWithMap(target.c_feature(), source.c_feature(), 1, map.as_ptr())
    };
    ogr_result(result, "OGR_F_SetFromWithMap")
}

fn ogr_result(
    result: gdal_sys::OGRErr::Type,
    method_name: &'static str,
) -> gdal::errors::Result<()> {
    if result == gdal_sys::OGRErr::OGRERR_NONE {
        Ok(())
    } else {
        Err(gdal::errors::GdalError::OgrError {
            err: result,
            method_name,
        })
    }
}

/// The `<Option .../>` element of layer creation option `name` in the driver's list.
fn creation_option(driver: &Driver, name: &str) -> Option<String> {
    let list = driver
        .metadata_item("DS_LAYER_CREATIONOPTIONLIST", "")?
        .replace('\'', "\"");
    let start = list.find(&format!("<Option name=\"{name}\""))?;
    let end = list[start..].find('>')? + start;
    Some(list[start..=end].to_owned())
}

/// `OPTION=name` for a column the driver creates itself (FID, geometry) when its default name
/// would clash with a field: e.g. a source field `fid` written to GeoPackage would otherwise be
/// taken as the FID column. `None` (keep the driver's default) when there is no clash.
fn column_option(driver: &Driver, option: &str, taken: &[&str]) -> Option<String> {
    let element = creation_option(driver, option)?;
    let default = element
        .split("default=\"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .filter(|d| !d.is_empty())?;
    let clashes = |name: &str| taken.iter().any(|t| t.eq_ignore_ascii_case(name));
    if !clashes(default) {
        return None;
    }
    let free = (1..)
        .map(|n| format!("{default}_{n}"))
        .find(|name| !clashes(name))?;
    Some(format!("{option}={free}"))
}

/// [`FIXED_DATE`](super::session::FIXED_DATE) (2000-01-01) as a DBF header stores it.
const DBF_DATE: [u8; 3] = [100, 1, 1];

/// A DBF header stores the date it was written (bytes 1–3: years since 1900, month, day), the
/// one thing that would make two Shapefiles of the same run differ from one day to the next. It
/// gets the same fixed date as every other format.
/// `path` is the staged output: a .shp file (sidecars beside it) or a folder of Shapefiles.
fn fix_dbf_dates(path: &Path) -> Result<(), Error> {
    let folder = if path.is_dir() {
        path.to_path_buf()
    } else {
        path.parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."))
    };
    let listing = std::fs::read_dir(&folder)
        .map_err(|e| Error::Io(format!("cannot list {:?}: {e}", folder.display())))?;
    for entry in listing.flatten() {
        let file = entry.path();
        if !file
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("dbf"))
        {
            continue;
        }
        OpenOptions::new()
            .write(true)
            .open(&file)
            .and_then(|mut f| {
                f.seek(SeekFrom::Start(1))?;
                f.write_all(&DBF_DATE)
            })
            .map_err(|e| Error::Io(format!("cannot write {:?}: {e}", file.display())))?;
    }
    Ok(())
}
