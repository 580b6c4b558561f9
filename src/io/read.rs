//! Reading the regions of one layer: open any OGR source, pick the layer, apply `-where`, and
//! turn each feature into a [`Region`], refusing (and naming) what the method cannot use.

use super::session::Session;
use crate::core::{Error, Progress, Region};
use crate::crs::LonLatBox;
use crate::input::{Admission, GeometryKind};
use gdal::spatial_ref::CoordTransform;
use gdal::vector::{Feature, FieldValue, Geometry, Layer, LayerAccess, OGRwkbGeometryType};
use gdal::{Dataset, DatasetOptions, GdalOpenFlags};
use geo::{CoordsIter, MultiPolygon};
use std::cell::Cell;
use std::path::Path;
use std::time::{Duration, Instant};

/// Whether to go on reading, as the host says when asked (its progress, at the bar's start):
/// reading 10⁷ vertices takes 0.6 s, a cancel is to be heard within 0.2 s, and a host as slow
/// to ask as QGIS's Python is not to be asked once per feature of a layer of 85,000. The time
/// decides only when the host is asked, never what is read.
pub(crate) struct Going<'p> {
    progress: Progress<'p>,
    /// When the host was last asked; `None` before the first feature, which asks.
    asked: Cell<Option<Instant>>,
}

/// How often [`Going`] asks the host.
const ASKED_EVERY: Duration = Duration::from_millis(20);

impl<'p> Going<'p> {
    pub(crate) fn new(progress: Progress<'p>) -> Self {
        Going {
            progress,
            asked: Cell::new(None),
        }
    }

    /// `Err(Cancelled)` once the host, when asked, says to stop.
    fn on(&self) -> Result<(), Error> {
        if (self.asked.get()).is_some_and(|asked| asked.elapsed() < ASKED_EVERY) {
            return Ok(());
        }
        self.asked.set(Some(Instant::now()));
        match (self.progress)(0.0, "reading") {
            true => Ok(()),
            false => Err(Error::Cancelled),
        }
    }
}

pub(crate) fn open(session: &Session, src: &str) -> Result<Dataset, Error> {
    super::paths::refuse_special_file("source", Path::new(src))?;
    let options = DatasetOptions {
        // Verbose errors make GDAL say why (no such file, not recognised) instead of nothing.
        open_flags: GdalOpenFlags::GDAL_OF_VECTOR
            | GdalOpenFlags::GDAL_OF_READONLY
            | GdalOpenFlags::GDAL_OF_VERBOSE_ERROR,
        ..Default::default()
    };
    Dataset::open_ex(src, options).map_err(|e| {
        if !src.contains(':') && !Path::new(src).exists() {
            Error::Io(format!(
                "cannot open source {src:?}: no such file or directory"
            ))
        } else {
            session.io_error(&format!("cannot open source {src:?}"), e)
        }
    })
}

/// The named layer, or the first, with a note when the first was taken from several: GDAL's
/// tools would take them all, and the user may have meant another.
pub(crate) fn layer<'d>(
    dataset: &'d Dataset,
    name: Option<&str>,
) -> Result<(Layer<'d>, Option<String>), Error> {
    let all = || dataset.layers().map(|l| l.name()).collect::<Vec<String>>();
    let names = || {
        let all = all();
        if all.is_empty() {
            "it has no layers".to_owned()
        } else {
            format!("its layers: {}", all.join(", "))
        }
    };
    let layer = match name {
        Some(name) => dataset.layer_by_name(name).map_err(|_| {
            Error::input(
                None,
                format!("the source has no layer named {name:?} ({})", names()),
            )
        }),
        None => dataset
            .layer(0)
            .map_err(|_| Error::input(None, "the source has no layers")),
    }?;
    // An attribute table would otherwise fail on its first feature, as if that one lacked a
    // geometry.
    if layer.defn().geom_fields().next().is_none() {
        return Err(Error::input(
            None,
            format!(
                "the source layer {:?} has no geometry column: it is a table, not regions ({})",
                layer.name(),
                names()
            ),
        ));
    }
    let note = (name.is_none() && dataset.layer_count() > 1).then(|| {
        format!(
            "the source has {} layers ({}): laid out the first, {:?}; name another after the \
             source to lay it out instead",
            dataset.layer_count(),
            all().join(", "),
            layer.name()
        )
    });
    Ok((layer, note))
}

/// The index of field `name` (exact, else the only case-insensitive match).
pub(crate) fn field_index(fields: &[String], name: &str) -> Option<usize> {
    fields.iter().position(|f| f == name).or_else(|| {
        let mut matches = fields
            .iter()
            .enumerate()
            .filter(|(_, f)| f.eq_ignore_ascii_case(name));
        match (matches.next(), matches.next()) {
            (Some((i, _)), None) => Some(i),
            _ => None,
        }
    })
}

/// A required field, or an error that lists the layer's fields.
pub(crate) fn require_field(fields: &[String], name: &str, option: &str) -> Result<usize, Error> {
    field_index(fields, name).ok_or_else(|| {
        Error::input(
            None,
            format!(
                "{option} {name:?}: the source layer has no such field (its fields: {})",
                if fields.is_empty() {
                    "none".to_owned()
                } else {
                    fields.join(", ")
                }
            ),
        )
    })
}

/// Every feature that passes `-where`, in the layer's order. They are kept for the writer,
/// which copies their attributes.
pub(crate) fn features<'l>(
    session: &Session,
    layer: &'l mut Layer,
    where_clause: Option<&str>,
    going: &Going,
) -> Result<Vec<Feature<'l>>, Error> {
    let what = match where_clause {
        Some(expression) => format!("invalid -where expression {expression:?}"),
        None => "cannot read the source layer".to_owned(),
    };
    if let Some(expression) = where_clause {
        layer
            .set_attribute_filter(expression)
            .map_err(|e| session.io_error(&what, e))?;
    }
    // Some drivers (GeoPackage) check a filter only when reading, and a read error ends the
    // iteration like the end of the layer would: either must fail the run, not shorten it.
    session.take_error();
    let mut features: Vec<Feature<'l>> = Vec::new();
    for feature in layer.features() {
        going.on()?;
        features.push(feature);
    }
    if let Some(reason) = session.take_error() {
        return Err(Error::Io(format!("{what}: {reason}")));
    }
    if features.is_empty() {
        return Err(Error::input(
            None,
            match where_clause {
                Some(_) => "no feature passes the -where filter",
                None => "the source layer has no features",
            },
        ));
    }
    Ok(features)
}

/// One feature that passed the checks, before projection.
pub(crate) struct Checked {
    pub id: String,
    pub label: String,
    /// Its group (`-group`); `None` when null or not asked for.
    pub group: Option<String>,
    /// Its pin (`-pin_col`, `-pin_row`); `None` when both are null or not asked for.
    pub pin: Option<(i32, i32)>,
    /// Polygon or multipolygon, flattened to 2D.
    pub geometry: Geometry,
}

/// The fields a feature's settings come from, as indices into the layer's fields.
pub(crate) struct SettingFields {
    pub id: Option<usize>,
    pub label: Option<usize>,
    pub group: Option<usize>,
    /// The pin's column and row fields.
    pub pin: Option<(usize, usize)>,
}

/// Ids, labels, groups, pins and polygonal geometries of `features`: each is admitted by the
/// rules every face shares ([`Admission`]: null, empty or repeated ids, null, empty or
/// non-polygonal geometries, each refused naming the feature); pins that are not whole numbers
/// or given by halves are refused too ([`crate::pins::pin_of`]). Curved polygons come back
/// linearised, with the admission's note saying so.
pub(crate) fn check(
    features: &[Feature],
    fields: &SettingFields,
    going: &Going,
) -> Result<(Vec<Checked>, Option<String>), Error> {
    let (id_field, label_field, group_field) = (fields.id, fields.label, fields.group);
    let mut admission = Admission::default();
    let checked = features
        .iter()
        .enumerate()
        .map(|(k, feature)| {
            going.on()?;
            let fid = match feature.fid() {
                Some(fid) => format!("FID {fid}"),
                None => format!("number {}", k + 1),
            };
            let id = match id_field {
                Some(i) => feature.field_as_string(i).ok().flatten(),
                None => Some(feature.fid().map(|fid| fid.to_string()).ok_or_else(|| {
                    Error::input(
                        Some(&fid),
                        "the feature has no FID; name an id field with -id",
                    )
                })?),
            };
            let geometry = usable(feature.geometry());
            let name = geometry.map(|g| g.geometry_name()).unwrap_or_default();
            let kind = kind(geometry, &name);
            let id = admission.admit(&fid, id.as_deref(), kind)?;
            let mut geometry = geometry
                .map(flat_copy)
                .ok_or_else(|| Error::Internal("an admitted geometry is null".into()))?;
            if let GeometryKind::Curved(_) = kind {
                // Linearised as every face does it, before any projection.
                geometry = (geometry.wkb().ok())
                    .ok_or_else(|| "GDAL cannot write it as WKB".to_owned())
                    .and_then(|bytes| crate::wkb::to_multi_polygon(&bytes))
                    .and_then(|linear| {
                        Geometry::from_wkb(&crate::wkb::from_multi_polygon(&linear))
                            .map_err(|e| e.to_string())
                    })
                    .map_err(|m| Error::input(Some(&id), m))?;
            }
            let label = label_field
                .and_then(|i| feature.field_as_string(i).ok().flatten())
                .filter(|l| !l.trim().is_empty())
                .unwrap_or_else(|| id.clone());
            let group = group_field.and_then(|i| feature.field_as_string(i).ok().flatten());
            let pin = match fields.pin {
                Some((col, row)) => {
                    let value = |i| number(feature, i).map_err(|m| Error::input(Some(&id), m));
                    crate::pins::pin_of(value(col)?, value(row)?)
                        .map_err(|m| Error::input(Some(&id), m))?
                }
                None => None,
            };
            Ok(Checked {
                id,
                label,
                group,
                pin,
                geometry,
            })
        })
        .collect::<Result<Vec<Checked>, Error>>()?;
    Ok((checked, admission.note()))
}

/// Field `index` of `feature` as a number: `None` when null or blank; a text field's value
/// parsed (a CSV source has only text).
fn number(feature: &Feature, index: usize) -> Result<Option<f64>, String> {
    match feature.field(index) {
        Ok(None) => Ok(None),
        Ok(Some(FieldValue::IntegerValue(v))) => Ok(Some(f64::from(v))),
        Ok(Some(FieldValue::Integer64Value(v))) => Ok(Some(v as f64)),
        Ok(Some(FieldValue::RealValue(v))) => Ok(Some(v)),
        Ok(Some(FieldValue::StringValue(text))) if text.trim().is_empty() => Ok(None),
        Ok(Some(FieldValue::StringValue(text))) => (text.trim().parse::<f64>().map(Some))
            .map_err(|_| format!("the pin value {text:?} is not a number")),
        Ok(Some(_)) | Err(_) => Err("the pin field holds no number".into()),
    }
}

/// The feature's geometry, `None` when it has none.
fn usable(geometry: Option<&Geometry>) -> Option<&Geometry> {
    // The binding hands out a null geometry as a wrapper of a null pointer, which every other
    // call would pass to GDAL.
    // SAFETY: only reads the wrapped pointer, which `Feature::geometry` has just set.
    geometry.filter(|g| !unsafe { g.c_geometry() }.is_null())
}

/// What `geometry` (whose type name is `name`) is, for [`Admission`].
fn kind<'n>(geometry: Option<&Geometry>, name: &'n str) -> GeometryKind<'n> {
    let Some(geometry) = geometry else {
        return GeometryKind::Null;
    };
    if geometry.is_empty() {
        return GeometryKind::Empty;
    }
    match gdal::vector::geometry_type_flatten(geometry.geometry_type()) {
        OGRwkbGeometryType::wkbPolygon | OGRwkbGeometryType::wkbMultiPolygon => {
            GeometryKind::Polygonal
        }
        // A collection, or a curved type, is judged as every face judges its WKB: a collection
        // may hold curved polygons, a MultiSurface only plain ones.
        OGRwkbGeometryType::wkbGeometryCollection
        | OGRwkbGeometryType::wkbCurvePolygon
        | OGRwkbGeometryType::wkbMultiSurface => (geometry.wkb().ok())
            .and_then(|bytes| crate::wkb::geometry_kind(&bytes).ok())
            .filter(|kind| matches!(kind, GeometryKind::Polygonal | GeometryKind::Curved(_)))
            .unwrap_or(GeometryKind::Other(name)),
        _ => GeometryKind::Other(name),
    }
}

/// A copy of `geometry` flattened to 2D.
fn flat_copy(geometry: &Geometry) -> Geometry {
    let mut copy = geometry.clone();
    copy.flatten_to_2d();
    copy
}

/// Every checked geometry as drawn, for the working-CRS rule on a layer in longitude and
/// latitude; `None` where the bytes cannot be read as polygons (refused in [`regions`]).
pub(crate) fn drawn(checked: &[Checked]) -> Vec<Option<MultiPolygon<f64>>> {
    use rayon::prelude::*;
    let bytes: Vec<Option<Vec<u8>>> = checked.iter().map(|c| c.geometry.wkb().ok()).collect();
    bytes
        .into_par_iter()
        .map(|b| b.and_then(|b| crate::wkb::to_multi_polygon(&b).ok()))
        .collect()
}

/// The lon/lat extents of the parts of the geometries `drawn`, for the working CRS
/// ([`crate::crs::lon_lat_boxes`]).
pub(crate) fn boxes(drawn: &[Option<MultiPolygon<f64>>]) -> Vec<LonLatBox> {
    drawn
        .iter()
        .flatten()
        .flat_map(crate::crs::lon_lat_boxes)
        .collect()
}

/// The regions in the working CRS, in the order of `checked`. GDAL hands each geometry over as
/// WKB in one call and the bytes are parsed on every core: the binding's own conversion asks
/// GDAL for one vertex at a time, on one core, a tenth of a second at 10⁶ vertices
/// (BENCHMARKS.md "Dense boundaries").
///
/// With `seam` (the working CRS's central meridian and the geometries as drawn, when the
/// working-CRS rule chose it), a region across the meridian opposite, or drawn stepping across
/// ±180°, is cut there first ([`crate::crs::cut_at_seam`]).
pub(crate) fn regions(
    session: &Session,
    checked: &[Checked],
    transform: Option<&CoordTransform>,
    seam: Option<(f64, &[Option<MultiPolygon<f64>>])>,
    going: &Going,
) -> Result<Vec<Region>, Error> {
    use rayon::prelude::*;
    let cannot_read = |id: &str| Error::input(Some(id), "the geometry cannot be read as polygons");
    let cuts: Vec<Option<MultiPolygon<f64>>> = match seam {
        Some((central, drawn)) => drawn
            .par_iter()
            .map(|g| g.as_ref().and_then(|g| crate::crs::cut_at_seam(g, central)))
            .collect(),
        None => Vec::new(),
    };
    let read = checked
        .iter()
        .enumerate()
        .map(|(k, c)| {
            going.on()?;
            let cut = match cuts.get(k) {
                Some(Some(cut)) => Some(
                    Geometry::from_wkb(&crate::wkb::from_multi_polygon(cut))
                        .map_err(|_| cannot_read(&c.id))?,
                ),
                _ => None,
            };
            let projected;
            let geometry = match transform {
                Some(t) => {
                    projected =
                        cut.as_ref().unwrap_or(&c.geometry).transform(t).map_err(
                            |e| match session.io_error("cannot project the geometry", e) {
                                Error::Io(message) => Error::input(Some(&c.id), message),
                                other => other,
                            },
                        )?;
                    &projected
                }
                None => &c.geometry,
            };
            let bytes = geometry.wkb().map_err(|_| cannot_read(&c.id))?;
            let region = Region {
                id: c.id.clone(),
                geometry: MultiPolygon(Vec::new()),
                group: c.group.clone(),
                pin: c.pin,
            };
            Ok((region, bytes))
        })
        // A feature GDAL cannot project is reported in its turn, after any earlier one whose
        // bytes turn out bad below.
        .collect::<Vec<Result<(Region, Vec<u8>), Error>>>();
    crate::core::first_error_in_order(read.into_par_iter().map(|read| {
        let (mut region, bytes) = read?;
        region.geometry =
            crate::wkb::to_multi_polygon(&bytes).map_err(|_| cannot_read(&region.id))?;
        if (region.geometry.coords_iter()).any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(Error::input(
                Some(&region.id),
                "the geometry has a NaN or infinite coordinate",
            ));
        }
        Ok(region)
    }))
}
