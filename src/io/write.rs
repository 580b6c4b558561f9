//! Writing the grid layer: one square per region, in input order, with every source field (same
//! type, subtype, width and precision; same name unless it collides with a computed field), then
//! the cell's column and row and the region's metrics, and the run's metrics and parameters as
//! layer metadata where the format keeps it.

use super::session::Session;
use crate::core::{Error, RegionCell};
use crate::fields::OUTPUT_FIELDS;
use gdal::cpl::CslStringList;
use gdal::spatial_ref::SpatialRef;
use gdal::vector::{
    Feature, FieldDefn, FieldValue, LayerAccess, LayerOptions, OGRFieldType, OGRwkbGeometryType,
    ToGdal,
};
use gdal::{Dataset, DatasetOptions, Driver, DriverManager, DriverType, GdalOpenFlags, Metadata};
use geo::Polygon;
use std::ffi::{c_int, CStr, CString};
use std::path::Path;

/// The fields added after the source's ([`OUTPUT_FIELDS`], the core's table), with the OGR type
/// each is written as; they always carry the computed values under exactly these names.
pub(crate) fn computed_fields() -> impl Iterator<Item = (&'static str, OGRFieldType::Type)> {
    OUTPUT_FIELDS.iter().map(|f| {
        let kind = if f.integer {
            OGRFieldType::OFTInteger
        } else {
            OGRFieldType::OFTReal
        };
        (f.name, kind)
    })
}

/// The values of the [`computed_fields`] for one cell, in the same order.
pub(crate) fn computed(cell: &RegionCell) -> Vec<FieldValue> {
    OUTPUT_FIELDS
        .iter()
        .map(|f| {
            let value = f.value(cell);
            if f.integer {
                // Columns and rows are i32 in the core.
                FieldValue::IntegerValue(value as i32)
            } else {
                FieldValue::RealValue(value)
            }
        })
        .collect()
}

/// The driver for `-f`, else the one the destination's extension names (refused when none
/// does), else, without an extension, GeoPackage; it must write vector data.
pub(crate) fn driver(format: Option<&str>, dst: &str) -> Result<Driver, Error> {
    let driver = match format {
        Some(name) => DriverManager::get_driver_by_name(name)
            .map_err(|_| Error::Io(format!("unknown format {name:?} (see ogrinfo --formats)")))?,
        None => match DriverManager::get_output_driver_for_dataset_name(dst, DriverType::Vector) {
            Some(d) => d,
            // A name GDAL knows no writer for is a format this GDAL lacks (Parquet, Arrow), not
            // a GeoPackage under a misleading name.
            None => match std::path::Path::new(dst).extension() {
                Some(extension) => {
                    return Err(Error::Io(format!(
                        "no vector format of this GDAL writes .{} files ({dst:?}); give -f \
                         (see ogrinfo --formats) or name the file .gpkg",
                        extension.to_string_lossy()
                    )))
                }
                None => DriverManager::get_driver_by_name("GPKG")
                    .map_err(|_| Error::Io("this GDAL has no GeoPackage driver; give -f".into()))?,
            },
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
    // Every driver that writes files does so through GDAL's virtual file layer; the others keep
    // the data in memory (Memory) or send it to a service, and would leave nothing at DST.
    if !says("DCAP_VIRTUALIO") {
        return Err(Error::Io(format!(
            "format {:?} does not write files (it keeps the layer in memory or sends it to a \
             service), so nothing would be left at {dst:?}; choose a file format (e.g. GPKG)",
            driver.short_name()
        )));
    }
    Ok(driver)
}

/// A source field as the output writes it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct OutputField {
    /// Its index in the source layer.
    pub source: usize,
    /// The name asked of the driver: the source's, or `src_<name>` when that collides with a
    /// computed field (see [`super::probe`]).
    pub name: String,
}

/// How the grid layer is made, the same in the probe and in the staged output.
pub(crate) struct LayerSpec<'a> {
    pub name: &'a str,
    pub srs: Option<&'a SpatialRef>,
    /// Layer creation options, NAME=VALUE (see [`super::options::layer_options`]).
    pub options: &'a [String],
    /// The source fields written, in order; the computed fields follow.
    pub fields: &'a [OutputField],
    /// Layer metadata items (key, value).
    pub metadata: &'a [(String, String)],
}

/// One feature of the grid layer.
pub(crate) struct Row<'a> {
    /// The region's id, for messages.
    pub id: &'a str,
    /// The source feature whose attributes it carries.
    pub source: &'a Feature<'a>,
    pub cell: &'a Polygon<f64>,
    /// The values of the [`computed_fields`].
    pub computed: Vec<FieldValue>,
}

/// The dataset the grid layer is written into.
pub(crate) enum Container<'a> {
    /// A new dataset made by `driver` with these dataset creation options.
    New {
        driver: &'a Driver,
        options: &'a [String],
    },
    /// The dataset already at the path (a staged copy of the destination), opened for update;
    /// its layer named `replace`, if any, is deleted first.
    Existing { replace: Option<&'a str> },
}

/// What was written.
pub(crate) struct Written {
    /// The layer's name, as the driver gave it (a Shapefile's layer is its file name).
    pub layer: String,
    /// Every field of the layer as the driver named it, in order.
    pub fields: Vec<String>,
    /// GDAL's warnings while writing.
    pub notes: Vec<String>,
}

/// Writes the grid layer, one feature per row, into the dataset at `path`. `progress` gets the
/// fraction written and returns false to cancel.
pub(crate) fn write(
    session: &Session,
    path: &Path,
    container: &Container,
    spec: &LayerSpec,
    rows: &[Row],
    progress: &dyn Fn(f64) -> bool,
) -> Result<Written, Error> {
    let fail = |what: &str, e| session.io_error(&format!("cannot {what} {:?}", path.display()), e);
    let mut dataset = match container {
        Container::New { driver, options } => {
            create_vector(driver, path, options).map_err(|e| fail("create", e))?
        }
        Container::Existing { replace } => {
            let options = DatasetOptions {
                open_flags: GdalOpenFlags::GDAL_OF_VECTOR | GdalOpenFlags::GDAL_OF_UPDATE,
                ..Default::default()
            };
            let mut dataset = Dataset::open_ex(path, options).map_err(|e| fail("update", e))?;
            let old = replace.and_then(|name| {
                dataset
                    .layers()
                    .position(|layer| layer.name().eq_ignore_ascii_case(name))
            });
            if let Some(index) = old {
                dataset
                    .delete_layer(index)
                    .map_err(|e| fail(&format!("replace layer {:?} of", spec.name), e))?;
            }
            dataset
        }
    };
    // One transaction where the format has them: much faster for GeoPackage, all or nothing.
    let in_transaction = match dataset.start_transaction() {
        Ok(mut transaction) => {
            let written = fill(session, &mut transaction, spec, rows, progress)?;
            transaction.commit().map_err(|e| fail("write", e))?;
            Some(written)
        }
        Err(_) => None,
    };
    let mut written = match in_transaction {
        Some(written) => written,
        None => fill(session, &mut dataset, spec, rows, progress)?,
    };
    // Closing flushes; a failure here (disk full) must fail the run.
    dataset.close().map_err(|e| fail("write", e))?;
    written.notes.extend(session.warnings());
    Ok(written)
}

/// A new vector dataset with dataset creation options: the binding makes one either without
/// options, or with options and a raster band type (which some drivers refuse: OpenFileGDB,
/// MVT).
fn create_vector(
    driver: &Driver,
    path: &Path,
    options: &[String],
) -> gdal::errors::Result<Dataset> {
    let mut list = CslStringList::new();
    for option in options {
        list.add_string(option)?;
    }
    let name = CString::new(path.to_string_lossy().as_bytes())?;
    // SAFETY: the driver handle is valid while `driver` lives; the name and the option list are
    // NUL-terminated and outlive the call, which copies what it keeps. A non-null result is a
    // new dataset that nothing else owns, so the binding may own and close it.
    let dataset = unsafe {
        gdal_sys::GDALCreate(
            driver.c_driver(),
            name.as_ptr(),
            0,
            0,
            0,
            gdal_sys::GDALDataType::GDT_Unknown,
            list.as_ptr(),
        )
    };
    if dataset.is_null() {
        return Err(gdal::errors::GdalError::NullPointer {
            method_name: "GDALCreate",
            msg: String::new(),
        });
    }
    // SAFETY: see above.
    Ok(unsafe { Dataset::from_c_dataset(dataset) })
}

fn fill(
    session: &Session,
    dataset: &mut Dataset,
    spec: &LayerSpec,
    rows: &[Row],
    progress: &dyn Fn(f64) -> bool,
) -> Result<Written, Error> {
    let fail = |what: &str, e| session.io_error(what, e);
    let first = rows
        .first()
        .ok_or_else(|| Error::Internal("a grid layer without features".into()))?;
    let option_refs: Vec<&str> = spec.options.iter().map(String::as_str).collect();
    let (driver_name, declared) = {
        let driver = dataset.driver();
        let declared = driver.metadata_item("DMD_CREATIONFIELDDATATYPES", "");
        (driver.short_name(), declared)
    };
    let mut layer = dataset
        .create_layer(LayerOptions {
            name: spec.name,
            srs: spec.srs,
            ty: OGRwkbGeometryType::wkbPolygon,
            options: Some(&option_refs),
        })
        .map_err(|e| fail(&format!("cannot create layer {:?}", spec.name), e))?;
    // Spreadsheets (XLSX, ODS) make a layer without geometry, where every cell would be lost.
    if layer.defn().geom_fields().count() == 0 {
        return Err(Error::Io(format!(
            "format {:?} cannot store geometries, so the cells would be lost; write e.g. \
             GeoPackage, Shapefile, GeoJSON, FlatGeobuf, or CSV (which holds them as WKT)",
            dataset.driver().short_name()
        )));
    }

    // Fields the driver makes with every layer (KML's Name and Description) come first.
    let builtin = layer.defn().fields().count();
    // Source field k goes to output field field_map[k] (−1: not written).
    let mut field_map: Vec<c_int> = vec![-1; first.source.field_count()];
    // The source list fields the format lacks: written as JSON text, where field_map says.
    let mut as_json: Vec<usize> = Vec::new();
    let mut notes = Vec::new();
    for (position, field) in spec.fields.iter().enumerate() {
        let lacked = list_type(first.source, field.source).filter(|kind| {
            declared
                .as_deref()
                .is_some_and(|d| !d.split(' ').any(|t| t == kind))
        });
        if let Some(kind) = &lacked {
            as_json.push(field.source);
            notes.push(format!(
                "the source field {:?} ({kind}) is written as JSON text: the {driver_name} \
                 format has no {kind} fields",
                field.name
            ));
        }
        create_field(&layer, first.source, field, lacked.is_some())
            .map_err(|e| fail(&format!("cannot create field {:?}", field.name), e))?;
        if let Some(slot) = field_map.get_mut(field.source) {
            *slot = c_int::try_from(builtin + position)
                .map_err(|_| Error::Io("too many fields for the output".into()))?;
        }
    }
    for (name, kind) in computed_fields() {
        FieldDefn::new(name, kind)
            .and_then(|d| d.add_to_layer(&layer))
            .map_err(|e| fail(&format!("cannot create field {name:?}"), e))?;
    }
    let fields: Vec<String> = layer
        .defn()
        .fields()
        .skip(builtin)
        .map(|f| f.name())
        .collect();
    if fields.len() != spec.fields.len() + OUTPUT_FIELDS.len() {
        return Err(Error::Io(format!(
            "the {} driver did not create every field",
            dataset.driver().short_name()
        )));
    }
    for (key, value) in spec.metadata {
        layer
            .set_metadata_item(key, value, "")
            .map_err(|e| fail(&format!("cannot set layer metadata {key}"), e))?;
    }

    let total = rows.len() as f64;
    for (k, row) in rows.iter().enumerate() {
        let mut feature =
            Feature::new(layer.defn()).map_err(|e| fail("cannot make a feature", e))?;
        copy_field_values(&mut feature, row.source, &field_map)
            .and_then(|_| {
                as_json.iter().try_for_each(|&source| {
                    match list_as_json(row.source, source) {
                        // A list field the format lacks was written: its output index is ≥ 0.
                        Some(json) => {
                            let output = usize::try_from(field_map[source]).map_err(|_| {
                                gdal::errors::GdalError::BadArgument("an unwritten field".into())
                            })?;
                            feature.set_field_string(output, &json)
                        }
                        None => Ok(()),
                    }
                })
            })
            .map_err(|e| fail(&format!("cannot copy the attributes of {:?}", row.id), e))?;
        let square = row
            .cell
            .to_gdal()
            .map_err(|e| fail("cannot make a cell", e))?;
        feature
            .set_geometry(square)
            .and_then(|_| {
                row.computed.iter().enumerate().try_for_each(|(j, value)| {
                    feature.set_field(builtin + spec.fields.len() + j, value)
                })
            })
            .and_then(|_| feature.create(&layer))
            .map_err(|e| fail(&format!("cannot write the cell of {:?}", row.id), e))?;
        if !progress((k + 1) as f64 / total) {
            return Err(Error::Cancelled);
        }
    }
    Ok(Written {
        layer: layer.name(),
        fields,
        notes,
    })
}

/// The type name of source field `index` of `source` when it holds a list ("StringList", …).
fn list_type(source: &Feature, index: usize) -> Option<String> {
    let index = c_int::try_from(index).ok()?;
    // SAFETY: `source` is a live feature; OGR_F_GetFieldDefnRef returns NULL for an index
    // outside its definition (checked), else a definition its own definition holds.
    let kind = unsafe {
        let definition = gdal_sys::OGR_F_GetFieldDefnRef(source.c_feature(), index);
        if definition.is_null() {
            return None;
        }
        gdal_sys::OGR_Fld_GetType(definition)
    };
    matches!(
        kind,
        OGRFieldType::OFTIntegerList
            | OGRFieldType::OFTInteger64List
            | OGRFieldType::OFTRealList
            | OGRFieldType::OFTStringList
    )
    .then(|| gdal::vector::field_type_to_name(kind))
}

/// Source field `index` of `source`, a list, as a JSON array (`["a","b"]`, `[1,2]`), as a
/// GeoPackage stores one; `None` when it is null.
fn list_as_json(source: &Feature, index: usize) -> Option<String> {
    let json = match source.field(index).ok()?? {
        FieldValue::StringListValue(v) => serde_json::to_string(&v),
        FieldValue::IntegerListValue(v) => serde_json::to_string(&v),
        FieldValue::Integer64ListValue(v) => serde_json::to_string(&v),
        FieldValue::RealListValue(v) => serde_json::to_string(&v),
        _ => return None,
    };
    json.ok()
}

/// Creates `field` on `layer`: the source's definition as it is, or a copy of it under the new
/// name, or (`as_json`) a copy of type String holding JSON.
fn create_field<L: LayerAccess>(
    layer: &L,
    source: &Feature,
    field: &OutputField,
    as_json: bool,
) -> gdal::errors::Result<()> {
    let index = c_int::try_from(field.source)?;
    if index >= c_int::try_from(source.field_count())? {
        return Err(gdal::errors::GdalError::BadArgument(format!(
            "the source has no field {index}"
        )));
    }
    let name = CString::new(field.name.as_str())?;
    // SAFETY: `source` is a live feature, which holds a reference to its definition, so the
    // definition and its field `index` (checked against the field count above) are valid during
    // the call. A renamed copy is made with OGR_Fld_Create, given every property the source
    // field has, passed to OGR_L_CreateField (which copies the definition it is given and keeps
    // no pointer to it) and destroyed here.
    let result = unsafe {
        let definition = gdal_sys::OGR_F_GetDefnRef(source.c_feature());
        let original = gdal_sys::OGR_FD_GetFieldDefn(definition, index);
        let same_name = CStr::from_ptr(gdal_sys::OGR_Fld_GetNameRef(original)) == name.as_c_str();
        if same_name && !as_json {
            gdal_sys::OGR_L_CreateField(layer.c_layer(), original, 1)
        } else {
            let copy = renamed_copy(original, &name);
            if as_json {
                gdal_sys::OGR_Fld_SetType(copy, OGRFieldType::OFTString);
                gdal_sys::OGR_Fld_SetSubType(copy, gdal_sys::OGRFieldSubType::OFSTJSON);
            }
            let result = gdal_sys::OGR_L_CreateField(layer.c_layer(), copy, 1);
            gdal_sys::OGR_Fld_Destroy(copy);
            result
        }
    };
    ogr_result(result, "OGR_L_CreateField")
}

/// A new field definition named `name` with every property of `original`; the caller destroys
/// it.
///
/// # Safety
/// `original` must be a valid field definition for the duration of the call.
unsafe fn renamed_copy(original: gdal_sys::OGRFieldDefnH, name: &CStr) -> gdal_sys::OGRFieldDefnH {
    // SAFETY: `original` is valid (the caller's contract); the strings it hands out are copied
    // by the setters before this function returns.
    unsafe {
        let copy = gdal_sys::OGR_Fld_Create(name.as_ptr(), gdal_sys::OGR_Fld_GetType(original));
        gdal_sys::OGR_Fld_SetSubType(copy, gdal_sys::OGR_Fld_GetSubType(original));
        gdal_sys::OGR_Fld_SetWidth(copy, gdal_sys::OGR_Fld_GetWidth(original));
        gdal_sys::OGR_Fld_SetPrecision(copy, gdal_sys::OGR_Fld_GetPrecision(original));
        gdal_sys::OGR_Fld_SetJustify(copy, gdal_sys::OGR_Fld_GetJustify(original));
        gdal_sys::OGR_Fld_SetNullable(copy, gdal_sys::OGR_Fld_IsNullable(original));
        gdal_sys::OGR_Fld_SetUnique(copy, gdal_sys::OGR_Fld_IsUnique(original));
        gdal_sys::OGR_Fld_SetDefault(copy, gdal_sys::OGR_Fld_GetDefault(original));
        gdal_sys::OGR_Fld_SetDomainName(copy, gdal_sys::OGR_Fld_GetDomainName(original));
        gdal_sys::OGR_Fld_SetAlternativeName(
            copy,
            gdal_sys::OGR_Fld_GetAlternativeNameRef(original),
        );
        copy
    }
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
