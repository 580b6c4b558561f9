//! The working CRS: the method is planar, so a geographic layer is projected to the equal-area
//! CRS that [`crate::crs::working_crs`] chooses for it (or to `-t_srs`), and the run says so.

use super::session::Session;
use crate::core::Error;
use crate::crs::LonLatBox;
use gdal::spatial_ref::{AxisMappingStrategy, CoordTransform, SpatialRef};

/// Where the regions are laid out and how to get there from the source.
pub(crate) struct Plan {
    /// The CRS of the regions handed to the core and of the output; `None` when the source has
    /// none (its coordinates are taken as planar).
    pub working: Option<SpatialRef>,
    /// Source → working, when they differ.
    pub transform: Option<CoordTransform>,
    /// What the user should know about it.
    pub note: Option<String>,
    /// The central meridian of the working CRS the rule chose for a layer in longitude and
    /// latitude, when it splits the globe: regions are cut on the meridian opposite before they
    /// are projected ([`crate::crs::cut_at_seam`]).
    pub seam: Option<f64>,
}

/// Decides the working CRS: `-t_srs`, else the source's when it is projected, else the rule of
/// [`crate::crs::working_crs`] for the regions' lon/lat extents `boxes` (asked for only then).
pub(crate) fn plan(
    session: &Session,
    source: Option<&SpatialRef>,
    target: Option<&str>,
    boxes: impl FnOnce() -> Vec<LonLatBox>,
) -> Result<Plan, Error> {
    // GeoPackage stores "no CRS" as one of two placeholder CRSs, which GDAL reads back as real
    // ones ("Undefined geographic SRS" would otherwise send planar data to a projection).
    let placeholder = source
        .and_then(|s| s.name())
        .filter(|name| name.starts_with("Undefined") && name.ends_with("SRS"));
    let source = source.filter(|_| placeholder.is_none());
    match (source, target) {
        (None, None) => {
            let mut note = match placeholder {
                Some(name) => format!(
                    "the source has no CRS (only the placeholder {name:?}): its coordinates \
                     are taken as planar"
                ),
                None => "the source has no CRS: its coordinates are taken as planar".into(),
            };
            if crate::crs::looks_like_degrees(&boxes()) {
                note.push_str(
                    "; they lie within ±180 and ±90, as longitudes and latitudes would: if they \
                     are, -s_srs EPSG:4326 (or their own geographic CRS) projects them",
                );
            }
            Ok(Plan {
                working: None,
                transform: None,
                note: Some(note),
                seam: None,
            })
        }
        (None, Some(target)) => Err(Error::InvalidInput {
            feature: None,
            message: format!("the source has no CRS, so it cannot be projected to -t_srs {target}"),
        }),
        (Some(source), Some(target)) => {
            let working = parse(session, target)?;
            let mut note = format!(
                "projected from {} to {} (-t_srs)",
                describe(source),
                describe(&working)
            );
            if working.is_geographic() {
                note.push_str("; the working CRS is geographic, so cells are squares in degrees");
            }
            Ok(Plan {
                transform: Some(transform(session, source, &working)?),
                working: Some(working),
                note: Some(note),
                seam: None,
            })
        }
        (Some(source), None) if source.is_geographic() => {
            let chosen = crate::crs::working_crs(&boxes()).map_err(|e| match e {
                Error::InvalidInput { message, .. } => Error::input(
                    None,
                    format!("{message} (the source CRS is {})", describe(source)),
                ),
                other => other,
            })?;
            let working = parse(session, &chosen.wkt)?;
            Ok(Plan {
                transform: Some(transform(session, source, &working)?),
                note: Some(format!(
                    "the source CRS {} is geographic: {}",
                    describe(source),
                    chosen.note
                )),
                working: Some(working),
                seam: chosen.central_meridian,
            })
        }
        (Some(source), None) => {
            refuse_geocentric(source)?;
            let method = source.get_attr_value("PROJECTION", 0).ok().flatten();
            Ok(Plan {
                working: Some(source.clone()),
                transform: None,
                note: method.and_then(|m| crate::crs::projected_note(&m, &describe(source))),
                seam: None,
            })
        }
    }
}

/// A CRS from any definition GDAL accepts (EPSG code, WKT, PROJ string, file), with the
/// traditional GIS axis order (x = easting or longitude).
pub(crate) fn parse(session: &Session, definition: &str) -> Result<SpatialRef, Error> {
    let mut srs = SpatialRef::from_definition(definition).map_err(|_| {
        // The binding's error is only the failing method's code; GDAL's own message says why.
        let reason = session.take_error().unwrap_or_else(|| {
            "GDAL recognises no EPSG code, WKT, PROJ string or file in it".into()
        });
        Error::Io(format!("invalid CRS {definition:?}: {reason}"))
    })?;
    srs.set_axis_mapping_strategy(AxisMappingStrategy::TraditionalGisOrder);
    refuse_geocentric(&srs)?;
    Ok(srs)
}

/// A geocentric CRS (3D Cartesian axes through the Earth's centre) has no map plane to lay
/// cells out on; its polygons would be written flattened and meaningless.
fn refuse_geocentric(srs: &SpatialRef) -> Result<(), Error> {
    if !srs.is_geocentric() {
        return Ok(());
    }
    Err(Error::input(
        None,
        format!(
            "the CRS {} is geocentric (3D axes through the Earth's centre), which has no map \
             plane for the cells: give -t_srs a projected CRS",
            describe(srs)
        ),
    ))
}

/// The layer's CRS with the traditional GIS axis order, which GDAL 3 does not give EPSG:4326 by
/// default (it would swap latitude and longitude).
pub(crate) fn traditional(mut srs: SpatialRef) -> SpatialRef {
    srs.set_axis_mapping_strategy(AxisMappingStrategy::TraditionalGisOrder);
    srs
}

fn transform(
    session: &Session,
    from: &SpatialRef,
    to: &SpatialRef,
) -> Result<CoordTransform, Error> {
    CoordTransform::new(from, to).map_err(|e| {
        session.io_error(
            &format!(
                "cannot transform from {} to {}",
                describe(from),
                describe(to)
            ),
            e,
        )
    })
}

/// A short readable name: `EPSG:5070 (NAD83 / Conus Albers)`, else the CRS's name, else its
/// PROJ string.
pub(crate) fn describe(srs: &SpatialRef) -> String {
    let name = srs
        .name()
        .filter(|n| !n.is_empty() && n != "unknown" && n != "unnamed");
    let authority = srs.auth_name().zip(srs.auth_code().ok());
    match (authority, name) {
        (Some((auth, code)), Some(name)) => format!("{auth}:{code} ({name})"),
        (Some((auth, code)), None) => format!("{auth}:{code}"),
        (None, name) => srs
            .to_proj4()
            .ok()
            .map(|p| p.trim().to_owned())
            .filter(|p| !p.is_empty())
            .or(name)
            .unwrap_or_else(|| "an unnamed CRS".into()),
    }
}
