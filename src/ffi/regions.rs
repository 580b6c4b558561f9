//! Regions given in memory, each as an id and a WKB (multi)polygon.

use super::handle::{self, Handle, Out};
use super::status::{guard, guard_free, Failure, Status};
use crate::core::{Error, Region};
use std::ffi::c_char;

/// The regions of one map, in a planar CRS (map units, e.g. metres). Made by
/// snakegrid_regions_new(), filled by snakegrid_regions_add(), freed by snakegrid_regions_free().
pub struct Regions {
    _opaque: [u8; 0],
}

impl Handle for Regions {
    type Inner = Vec<Region>;
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
        out.write(handle::into_raw::<Regions>(Vec::new()));
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
/// a Polygon or MultiPolygon in either byte order (ISO or EWKB; Z and M are ignored). The bytes
/// are copied; the caller keeps ownership of `id` and `wkb`.
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
        list.push(Region {
            id: id.to_owned(),
            geometry,
        });
        Ok(())
    })
}
