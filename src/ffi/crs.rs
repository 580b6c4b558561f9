//! The working-CRS rule of the library ([`crate::crs::working_crs`]) for hosts that project
//! layers themselves (QGIS, Python): which equal-area CRS a layer in longitude and latitude
//! should be laid out in, as named WKT2, so every face of snakegrid chooses the same one.

use super::handle::{self, Handle, Out};
use super::status::{c_string, guard, guard_free, Failure, Status};
use crate::crs::{working_crs, LonLatBox};
use std::ffi::{c_char, CString};

/// A chosen working CRS: its WKT2 definition, its name and a note for the user. Made by
/// snakegrid_working_crs(), freed by snakegrid_crs_free(); its strings live as long as it.
pub struct Crs {
    _opaque: [u8; 0],
}

/// What a CRS handle holds.
pub(crate) struct ChosenCrs {
    wkt: CString,
    name: CString,
    note: CString,
}

impl Handle for Crs {
    type Inner = ChosenCrs;
    const TAG: u64 = u64::from_be_bytes(*b"sgCRS\0\0\0");
    const NAME: &'static str = "snakegrid_crs";
}

/// Chooses the working CRS for a layer in longitude and latitude (degrees) from its regions'
/// extents: `boxes` holds `count` boxes of four numbers each, west, south, east, north (the
/// extent of each region, or one box for the whole layer; a layer across the antimeridian is
/// read right when each region has its own box). Writes a new handle to `*out`.
///
/// A layer spanning more than 180° of longitude gets Equal Earth, any other Lambert azimuthal
/// equal-area centred on it; a layer whose CRS is already projected needs no call (lay it out
/// in its own CRS), as the command line does.
///
/// Fails with SNAKEGRID_INVALID_INPUT when the numbers cannot be longitudes and latitudes (the
/// message gives the extent found) or `count` is 0.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_working_crs(
    boxes: *const f64,
    count: usize,
    out: *mut *mut Crs,
) -> Status {
    guard("snakegrid_working_crs", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        let values = count
            .checked_mul(4)
            .ok_or_else(|| Failure::new(Status::INVALID_ARGUMENT, "count is too large"))?;
        // SAFETY: `boxes` is NULL or valid for `4 * count` doubles (header contract).
        let numbers = unsafe { handle::slice(boxes, values, "boxes") }?;
        let boxes: Vec<LonLatBox> = numbers
            .chunks_exact(4)
            .map(|b| LonLatBox {
                west: b[0],
                south: b[1],
                east: b[2],
                north: b[3],
            })
            .collect();
        let chosen = working_crs(&boxes)?;
        out.write(handle::into_raw::<Crs>(ChosenCrs {
            wkt: c_string(&chosen.wkt),
            name: c_string(&chosen.name),
            note: c_string(&chosen.note),
        }));
        Ok(())
    })
}

/// Frees a CRS handle. NULL is ignored.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_crs_free(crs: *mut Crs) {
    // SAFETY: `crs` is NULL or a handle not used elsewhere meanwhile (header contract).
    guard_free("snakegrid_crs_free", || unsafe { handle::free(crs, "crs") })
}

/// The CRS as named WKT2 (ISO 19162:2019), which GDAL, PROJ and QGIS read; writes a string that
/// belongs to the handle to `*out`.
///
/// Thread safety: any number of threads may read one handle at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_crs_wkt(crs: *const Crs, out: *mut *const c_char) -> Status {
    // SAFETY: passed on (header contract).
    unsafe { read("snakegrid_crs_wkt", crs, out, |c| &c.wkt) }
}

/// The CRS's name (ASCII), e.g. "Lambert azimuthal equal-area at 37.0N 95.5W (snakegrid)". As
/// snakegrid_crs_wkt().
///
/// Thread safety: any number of threads may read one handle at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_crs_name(crs: *const Crs, out: *mut *const c_char) -> Status {
    // SAFETY: passed on (header contract).
    unsafe { read("snakegrid_crs_name", crs, out, |c| &c.name) }
}

/// What to tell the user about the choice (which projection, where, why). As
/// snakegrid_crs_wkt().
///
/// Thread safety: any number of threads may read one handle at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_crs_note(crs: *const Crs, out: *mut *const c_char) -> Status {
    // SAFETY: passed on (header contract).
    unsafe { read("snakegrid_crs_note", crs, out, |c| &c.note) }
}

/// The one body of the three accessors.
///
/// # Safety
/// `crs` NULL or a live handle; `out` NULL or writable.
unsafe fn read(
    function: &str,
    crs: *const Crs,
    out: *mut *const c_char,
    field: impl FnOnce(&ChosenCrs) -> &CString,
) -> Status {
    guard(function, || {
        // SAFETY: the caller's guarantees.
        let chosen = unsafe { handle::get(crs, "crs") }?;
        // SAFETY: the caller's guarantees.
        let out = unsafe { Out::new(out, "out") }?;
        out.write(field(chosen).as_ptr());
        Ok(())
    })
}
