//! The working-CRS rule of the library ([`crate::crs::working_crs`]) for hosts that project
//! layers themselves (QGIS, Python): which equal-area CRS a layer in longitude and latitude
//! should be laid out in, as named WKT2, so every face of snakegrid chooses the same one.

use super::handle::{self, Handle, Out};
use super::status::{c_string, guard, guard_free, Failure, Status};
use crate::crs::{cut_at_seam, looks_like_degrees, projected_note, working_crs, LonLatBox};
use geo::MultiPolygon;
use std::cell::RefCell;
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
    central_meridian: Option<f64>,
}

impl Handle for Crs {
    type Inner = ChosenCrs;
    const TAG: u64 = u64::from_be_bytes(*b"sgCRS\0\0\0");
    const NAME: &'static str = "snakegrid_crs";
}

/// Chooses the working CRS for a layer in longitude and latitude (degrees) from its regions'
/// extents: `boxes` holds `count` boxes of four numbers each, west, south, east, north (best
/// the boxes snakegrid_lon_lat_boxes() gives for each region; the extent of each region, or
/// one box for the whole layer, also do, but a region drawn across the antimeridian then spans
/// the globe). Writes a new handle to `*out`.
///
/// A layer spanning more than 180° of longitude gets Equal Earth, or Lambert azimuthal
/// equal-area centred on a pole when it lies within 45° of that pole; any other Lambert
/// azimuthal equal-area centred on it; a layer whose CRS is already projected needs no call (lay it out
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
        // SAFETY: as the header's contract for `boxes` and `count`.
        let boxes = unsafe { lon_lat_boxes(boxes, count) }?;
        let chosen = working_crs(&boxes)?;
        out.write(handle::into_raw::<Crs>(ChosenCrs {
            wkt: c_string(&chosen.wkt),
            name: c_string(&chosen.name),
            note: c_string(&chosen.note),
            central_meridian: chosen.central_meridian,
        }));
        Ok(())
    })
}

/// `count` boxes of four numbers each (west, south, east, north) from `boxes`.
///
/// # Safety
/// `boxes` NULL or valid for `4 * count` doubles.
unsafe fn lon_lat_boxes(boxes: *const f64, count: usize) -> Result<Vec<LonLatBox>, Failure> {
    let values = count
        .checked_mul(4)
        .ok_or_else(|| Failure::new(Status::INVALID_ARGUMENT, "count is too large"))?;
    // SAFETY: the caller's guarantee.
    let numbers = unsafe { handle::slice(boxes, values, "boxes") }?;
    Ok(numbers
        .chunks_exact(4)
        .map(|b| LonLatBox {
            west: b[0],
            south: b[1],
            east: b[2],
            north: b[3],
        })
        .collect())
}

thread_local! {
    static PROJECTED_NOTE: RefCell<CString> = RefCell::new(CString::default());
}

/// What to tell the user about laying a layer out in its own projected CRS, as the command line
/// tells it: a Mercator projection draws areas larger towards the poles, and the regions' areas
/// set the cell size and the landmasses' budgets. `projection` is the CRS's projection method as
/// GDAL, PROJ or QGIS name it ("Mercator_1SP", "Popular Visualisation Pseudo Mercator", "merc");
/// `crs` names the CRS in the message (e.g. "EPSG:3857"). Writes the note to `*out`, or NULL
/// when there is nothing to tell; the note stays valid until the next call of this function on
/// the same thread.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_projected_crs_note(
    projection: *const c_char,
    crs: *const c_char,
    out: *mut *const c_char,
) -> Status {
    guard("snakegrid_projected_crs_note", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        // SAFETY: NUL-terminated strings or NULL (header contract).
        let projection = unsafe { handle::text(projection, "projection") }?;
        // SAFETY: as `projection`.
        let crs = unsafe { handle::text(crs, "crs") }?;
        out.write(match projected_note(projection, crs) {
            Some(note) => PROJECTED_NOTE.with(|slot| {
                *slot.borrow_mut() = c_string(&note);
                slot.borrow().as_ptr()
            }),
            None => std::ptr::null(),
        });
        Ok(())
    })
}

/// Whether a layer without a CRS, whose regions have the extents `boxes` (as
/// snakegrid_working_crs() takes them), could be in longitude and latitude: every coordinate
/// within ±180 and ±90, and the layer wider than a hundredth of a degree. The command line then
/// adds to its note that the layer may want a geographic CRS; a host says it its own way (QGIS:
/// set the layer's CRS). Writes the answer to `*out`.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_looks_like_degrees(
    boxes: *const f64,
    count: usize,
    out: *mut bool,
) -> Status {
    guard("snakegrid_looks_like_degrees", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        // SAFETY: as the header's contract for `boxes` and `count`.
        let boxes = unsafe { lon_lat_boxes(boxes, count) }?;
        out.write(looks_like_degrees(&boxes));
        Ok(())
    })
}

thread_local! {
    static BOXES: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
    static CUT: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// The boxes of one region in longitude and latitude (WKB Polygon or MultiPolygon, `wkb_len`
/// bytes) for snakegrid_working_crs(): one box per polygon, four numbers each (west, south,
/// east, north), with a ring that steps across ±180° (as d3's world-atlas draws Russia and
/// Fiji) taken across it, so its box may run past 180. Writes the numbers to `*boxes` and the
/// number of boxes to `*count`; the numbers stay valid until the next call of this function
/// on the same thread.
///
/// Fails with SNAKEGRID_INVALID_INPUT when the bytes are not a Polygon or MultiPolygon.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_lon_lat_boxes(
    wkb: *const u8,
    wkb_len: usize,
    boxes: *mut *const f64,
    count: *mut usize,
) -> Status {
    guard("snakegrid_lon_lat_boxes", || {
        // SAFETY: `boxes` and `count` are NULL or writable (header contract).
        let (boxes, count) = unsafe { (Out::new(boxes, "boxes")?, Out::new(count, "count")?) };
        // SAFETY: NULL or `wkb_len` readable bytes (header contract).
        let region = unsafe { region(wkb, wkb_len) }?;
        let found = crate::crs::lon_lat_boxes(&region);
        count.write(found.len());
        boxes.write(BOXES.with(|slot| {
            let mut numbers = slot.borrow_mut();
            numbers.clear();
            numbers.extend(
                found
                    .iter()
                    .flat_map(|b| [b.west, b.south, b.east, b.north]),
            );
            numbers.as_ptr()
        }));
        Ok(())
    })
}

/// One region in longitude and latitude (WKB, as snakegrid_lon_lat_boxes()) made ready to be
/// projected to the working CRS `crs`, which splits the globe on the meridian opposite its
/// centre: rings that step across ±180° are carried across, and a region across that meridian
/// is cut there, its pieces on either edge of the map. Projected as drawn, such a region would
/// become a band round the globe. A working CRS centred on a pole splits nothing and changes no
/// region. Writes a little-endian WKB MultiPolygon to `*out` and its
/// length to `*out_len`, valid until the next call of this function on the same thread; or
/// NULL and 0 when the region needs no change (nearly every region), so project it as it is.
///
/// Fails with SNAKEGRID_INVALID_INPUT when the bytes are not a Polygon or MultiPolygon.
///
/// Thread safety: any number of threads may read one handle at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_crs_cut(
    crs: *const Crs,
    wkb: *const u8,
    wkb_len: usize,
    out: *mut *const u8,
    out_len: *mut usize,
) -> Status {
    guard("snakegrid_crs_cut", || {
        // SAFETY: a live handle or NULL (header contract).
        let chosen = unsafe { handle::get(crs, "crs") }?;
        // SAFETY: `out` and `out_len` are NULL or writable (header contract).
        let (out, out_len) = unsafe { (Out::new(out, "out")?, Out::new(out_len, "out_len")?) };
        // SAFETY: NULL or `wkb_len` readable bytes (header contract).
        let region = unsafe { region(wkb, wkb_len) }?;
        let cut = (chosen.central_meridian).and_then(|central| cut_at_seam(&region, central));
        match cut {
            Some(cut) => CUT.with(|slot| {
                let mut bytes = slot.borrow_mut();
                *bytes = crate::wkb::from_multi_polygon(&cut);
                out_len.write(bytes.len());
                out.write(bytes.as_ptr());
            }),
            None => {
                out_len.write(0);
                out.write(std::ptr::null());
            }
        }
        Ok(())
    })
}

/// The region in `wkb_len` bytes at `wkb`, a WKB Polygon or MultiPolygon.
///
/// # Safety
/// `wkb` NULL or valid for `wkb_len` bytes.
unsafe fn region(wkb: *const u8, wkb_len: usize) -> Result<MultiPolygon<f64>, Failure> {
    // SAFETY: the caller's guarantee.
    let wkb = unsafe { handle::slice(wkb, wkb_len, "wkb") }?;
    crate::wkb::to_multi_polygon(wkb)
        .map_err(|message| Failure::from(crate::core::Error::input(None, message)))
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
