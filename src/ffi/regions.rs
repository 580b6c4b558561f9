//! Regions given in memory, each as an id and a WKB (multi)polygon.

use super::handle::{self, Handle, Out};
use super::status::{guard, guard_free, Failure, Status};
use crate::core::{Error, Region};
use crate::input::{Admission, GeometryKind};
use std::ffi::c_char;
use std::ops::Deref;

/// The regions of one map, in a planar CRS (map units, e.g. metres). Made by
/// snakegrid_regions_new(), filled by snakegrid_regions_add(), freed by snakegrid_regions_free().
pub struct Regions {
    _opaque: [u8; 0],
}

/// What a regions handle holds: the regions, and the features admitted so far (for
/// snakegrid_regions_add_feature's checks).
#[derive(Default)]
pub(crate) struct RegionList {
    regions: Vec<Region>,
    admission: Admission,
}

impl RegionList {
    /// What the user should know of the features added by snakegrid_regions_add_feature():
    /// that curves were linearised.
    pub(crate) fn note(&self) -> Option<String> {
        self.admission.note()
    }

    /// Region `index`, or the error for an index past the last.
    fn region_mut(&mut self, index: usize) -> Result<&mut Region, Failure> {
        let count = self.regions.len();
        self.regions.get_mut(index).ok_or_else(|| {
            Failure::new(
                Status::INVALID_ARGUMENT,
                format!("index {index}: there are {count} regions"),
            )
        })
    }
}

impl Deref for RegionList {
    type Target = Vec<Region>;
    fn deref(&self) -> &Vec<Region> {
        &self.regions
    }
}

impl Handle for Regions {
    type Inner = RegionList;
    const TAG: u64 = u64::from_be_bytes(*b"sgREGION");
    const NAME: &'static str = "snakegrid_regions";
}

/// Makes an empty regions handle and writes it to `*out`.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_regions_new(out: *mut *mut Regions) -> Status {
    guard("snakegrid_regions_new", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        out.write(handle::into_raw::<Regions>(RegionList::default()));
        Ok(())
    })
}

/// Frees a regions handle. NULL is ignored.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_regions_free(regions: *mut Regions) {
    // SAFETY: `regions` is NULL or a handle not used elsewhere meanwhile (header contract).
    guard_free("snakegrid_regions_free", || unsafe {
        handle::free(regions, "regions")
    })
}

/// Adds one region: a unique, non-empty UTF-8 `id` and its geometry as `wkb_len` bytes of WKB,
/// a Polygon, a MultiPolygon or a GeometryCollection of only those, or a CurvePolygon or
/// MultiSurface (its arcs linearised in chords of at most 4 degrees, as GDAL does), in either
/// byte order (ISO or EWKB; Z and M are ignored). The bytes are copied; the caller keeps
/// ownership of `id` and `wkb`.
///
/// Fails with SNAKEGRID_INVALID_INPUT, naming the region, for malformed WKB or another geometry
/// type; the handle is then unchanged. The regions as a whole (unique ids, geometries with
/// area) are checked by snakegrid_run(). Thread safety: not concurrently with any other use of
/// the same handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_regions_add(
    regions: *mut Regions,
    id: *const c_char,
    wkb: *const u8,
    wkb_len: usize,
) -> Status {
    guard("snakegrid_regions_add", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        let list = unsafe { handle::get_mut(regions, "regions") }?;
        // SAFETY: NUL-terminated string or NULL (header contract).
        let id = unsafe { handle::text(id, "id") }?;
        // SAFETY: NULL or `wkb_len` readable bytes (header contract).
        let wkb = unsafe { handle::slice(wkb, wkb_len, "wkb") }?;
        let geometry = crate::wkb::to_multi_polygon(wkb)
            .map_err(|message| Failure::from(Error::input(Some(id), message)))?;
        list.regions.push(Region {
            id: id.to_owned(),
            geometry,
            group: None,
            pin: None,
        });
        Ok(())
    })
}

/// Adds one feature of a layer as the command line reads it, with the same checks and messages:
/// `feature` names it until its id is known (e.g. "FID 3"), `id` is its id (NULL: a null id),
/// `wkb` its geometry as `wkb_len` bytes (NULL: a null geometry). A null or empty id, an id
/// already added by this function, and a geometry that is not a (non-empty) Polygon,
/// MultiPolygon or GeometryCollection of them, or a curved polygon (linearised, and the run's
/// notes say so), are refused with SNAKEGRID_INVALID_INPUT and the
/// command line's message, e.g. "feature FID 3: the id is null" or "feature p1: the geometry is
/// a POINT, not a polygon or multipolygon"; the handle is then unchanged. Hosts that read layers themselves (QGIS,
/// Python) use this so that users see what the command line would say.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_regions_add_feature(
    regions: *mut Regions,
    feature: *const c_char,
    id: *const c_char,
    wkb: *const u8,
    wkb_len: usize,
) -> Status {
    guard("snakegrid_regions_add_feature", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        let list = unsafe { handle::get_mut(regions, "regions") }?;
        // SAFETY: NUL-terminated strings or NULL (header contract).
        let (feature, id) = unsafe {
            (
                handle::text(feature, "feature")?,
                handle::optional_text(id, "id")?,
            )
        };
        let wkb = if wkb.is_null() {
            None
        } else {
            // SAFETY: `wkb_len` readable bytes (header contract).
            Some(unsafe { handle::slice(wkb, wkb_len, "wkb") }?)
        };
        let named =
            |message: String| Failure::from(Error::input(Some(id.unwrap_or(feature)), message));
        let kind = match wkb {
            None => GeometryKind::Null,
            Some(bytes) => crate::wkb::geometry_kind(bytes).map_err(named)?,
        };
        // Admitted on a copy, so that a refused feature leaves the handle as it was.
        let mut admission = list.admission.clone();
        let id = admission.admit(feature, id, kind)?;
        let geometry = crate::wkb::to_multi_polygon(wkb.unwrap_or_default()).map_err(named)?;
        list.admission = admission;
        list.regions.push(Region {
            id,
            geometry,
            group: None,
            pin: None,
        });
        Ok(())
    })
}

/// Sets the group of region `index` (0 for the first added, in the order of addition), whose
/// regions keep together in one block of cells per landmass (method.md §10; the parameter
/// group_gap sets whether blocks of different groups may touch): a UTF-8 name, copied; a blank
/// name, like a null value in a layer, makes the region a group of its own. `group` NULL clears
/// it: a map where no region has a group is laid out without groups. Only the names' equality
/// counts: renaming every group moves no cell.
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for an index past the last region; the handle is then
/// unchanged. Thread safety: not concurrently with any other use of the same
/// handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_regions_set_group(
    regions: *mut Regions,
    index: usize,
    group: *const c_char,
) -> Status {
    guard("snakegrid_regions_set_group", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        let list = unsafe { handle::get_mut(regions, "regions") }?;
        // SAFETY: NUL-terminated string or NULL (header contract).
        let group = unsafe { handle::optional_text(group, "group") }?;
        let region = list.region_mut(index)?;
        region.group = group.map(str::to_owned);
        Ok(())
    })
}

/// Pins region `index` (0 for the first added) to the cell at column `col`, row `row` (method.md
/// §10): offset coordinates as the grid layer numbers them, rows from the top (for hexagons the
/// odd rows (pointy) or columns (flat) sit half a cell further). Whole numbers given as doubles,
/// so that a host passes a layer's integer or real values as they are; both NaN unpins the
/// region. With pins, every cell is numbered in the pins' frame and the pinned regions keep
/// theirs.
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for an index past the last region, a value that is not
/// a whole number, or only one of the two NaN; the handle is then unchanged. Two regions on one
/// cell are refused by snakegrid_run, naming both. Thread safety: not concurrently with any
/// other use of the same handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_regions_set_pin(
    regions: *mut Regions,
    index: usize,
    col: f64,
    row: f64,
) -> Status {
    guard("snakegrid_regions_set_pin", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        let list = unsafe { handle::get_mut(regions, "regions") }?;
        let region = list.region_mut(index)?;
        let pin = crate::pins::pin_of(Some(col), Some(row)).map_err(|message| {
            Failure::new(
                Status::INVALID_ARGUMENT,
                format!("feature {}: {message}", region.id),
            )
        })?;
        region.pin = pin;
        Ok(())
    })
}
