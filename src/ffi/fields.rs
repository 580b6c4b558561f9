//! The fields a grid layer adds after the source's ([`crate::fields::OUTPUT_FIELDS`]), for hosts
//! that write layers themselves: their names, types and meaning, and each region's values.

use super::handle::Out;
use super::result::RunResult;
use super::status::{c_string, catch, guard, Failure, Status};
use crate::fields::OUTPUT_FIELDS;
use std::ffi::{c_char, CString};
use std::sync::OnceLock;

/// One added field of a grid layer. Its strings are static.
#[repr(C)]
pub struct CField {
    /// The field's name, at most 10 characters (it fits a Shapefile).
    pub name: *const c_char,
    /// A whole number (write an integer field), else a real.
    pub integer: bool,
    /// What it holds.
    pub description: *const c_char,
}

fn texts() -> &'static [(CString, CString)] {
    static TEXTS: OnceLock<Vec<(CString, CString)>> = OnceLock::new();
    TEXTS.get_or_init(|| {
        OUTPUT_FIELDS
            .iter()
            .map(|f| (c_string(f.name), c_string(f.description)))
            .collect()
    })
}

/// The number of fields a grid layer adds after the source's.
///
/// Never fails. Thread safety: safe from any thread.
#[no_mangle]
pub extern "C" fn snakegrid_field_count() -> usize {
    catch(|| Ok(OUTPUT_FIELDS.len())).unwrap_or(0)
}

/// Describes added field `index` (0 to snakegrid_field_count() - 1, in the order a layer has
/// them) into `*out`. Fails with SNAKEGRID_INVALID_ARGUMENT for an index out of range.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_field_info(index: usize, out: *mut CField) -> Status {
    guard("snakegrid_field_info", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        let (field, (name, description)) = field(index)?;
        out.write(CField {
            name: name.as_ptr(),
            integer: field.integer,
            description: description.as_ptr(),
        });
        Ok(())
    })
}

/// The value of added field `field` for region `index` of a result, written to `*out` (an
/// integer field's value is a whole number). Fails with SNAKEGRID_INVALID_ARGUMENT for either
/// index out of range.
///
/// Thread safety: any number of threads may read one result at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_result_field(
    result: *const RunResult,
    index: usize,
    field_index: usize,
    out: *mut f64,
) -> Status {
    // SAFETY: passed on (header contract).
    unsafe {
        super::result::read("snakegrid_result_field", result, out, |o| {
            let (added, _) = field(field_index)?;
            Ok(added.value(o.cell(index)?))
        })
    }
}

fn field(
    index: usize,
) -> Result<
    (
        &'static crate::fields::OutputField,
        &'static (CString, CString),
    ),
    Failure,
> {
    OUTPUT_FIELDS
        .get(index)
        .zip(texts().get(index))
        .ok_or_else(|| {
            Failure::new(
                Status::INVALID_ARGUMENT,
                format!(
                    "field index {index} is out of range (there are {} fields)",
                    OUTPUT_FIELDS.len()
                ),
            )
        })
}
