//! Method parameters by name. Every setter goes through [`Params::set`], the parser the command
//! line uses, so names, accepted values and range checks are the same everywhere.

use super::handle::{self, Handle, Out};
use super::status::{guard, guard_free, Failure, Status};
use crate::core::Params;
use std::ffi::c_char;

/// The method's parameters for one run, all at their defaults when made (the command line's
/// defaults). Made by snakegrid_options_new(), freed by snakegrid_options_free().
pub struct Options {
    _opaque: [u8; 0],
}

impl Handle for Options {
    type Inner = Params;
    const TAG: u64 = u64::from_be_bytes(*b"sgOPTION");
    const NAME: &'static str = "snakegrid_options";
}

/// Makes an options handle with every parameter at its default and writes it to `*out`.
///
/// Thread safety: safe from any thread.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_options_new(out: *mut *mut Options) -> Status {
    guard("snakegrid_options_new", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        out.write(handle::into_raw::<Options>(Params::default()));
        Ok(())
    })
}

/// Frees an options handle. NULL is ignored.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_options_free(options: *mut Options) {
    // SAFETY: `options` is NULL or a handle not used elsewhere meanwhile (header contract).
    guard_free("snakegrid_options_free", || unsafe {
        handle::free(options, "options")
    })
}

/// Sets the parameter `name` from text, parsed as the command line parses it: numbers ("0.15", "30"), booleans ("true"/"false", "yes"/"no", "1"/"0"), "element" or
/// "nodal", comma-separated lists ("0.02,0.04"), shifts as x:y pairs ("0:0,0.5:0.5"), and
/// "none" to clear an optional value. docs/c-api.md lists the names, defaults and ranges.
///
/// Fails with SNAKEGRID_INVALID_OPTION for an unknown name or a value that does not parse or is
/// out of range; the handle is then unchanged.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_options_set(
    options: *mut Options,
    name: *const c_char,
    value: *const c_char,
) -> Status {
    guard("snakegrid_options_set", || {
        // SAFETY: NUL-terminated string or NULL (header contract).
        let value = unsafe { handle::text(value, "value") }?;
        // SAFETY: as the function's other arguments.
        unsafe { set(options, name, value) }
    })
}

/// Sets a numeric parameter. As snakegrid_options_set(); NaN and infinities are refused, and an
/// integer parameter refuses a fractional value.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_options_set_double(
    options: *mut Options,
    name: *const c_char,
    value: f64,
) -> Status {
    // Debug formatting is the shortest text that parses back to the same double.
    // SAFETY: the arguments are passed on unchanged (header contract).
    guard("snakegrid_options_set_double", || unsafe {
        set(options, name, &format!("{value:?}"))
    })
}

/// Sets an integer (or numeric) parameter. As snakegrid_options_set().
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_options_set_int(
    options: *mut Options,
    name: *const c_char,
    value: i64,
) -> Status {
    // SAFETY: the arguments are passed on unchanged (header contract).
    guard("snakegrid_options_set_int", || unsafe {
        set(options, name, &value.to_string())
    })
}

/// Sets a boolean parameter. As snakegrid_options_set().
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_options_set_bool(
    options: *mut Options,
    name: *const c_char,
    value: bool,
) -> Status {
    // SAFETY: the arguments are passed on unchanged (header contract).
    guard("snakegrid_options_set_bool", || unsafe {
        set(options, name, if value { "true" } else { "false" })
    })
}

/// The one setter behind the four exports.
///
/// # Safety
/// `options` NULL or a live handle nobody else uses meanwhile; `name` NULL or NUL-terminated.
unsafe fn set(options: *mut Options, name: *const c_char, value: &str) -> Result<(), Failure> {
    // SAFETY: the caller's guarantees.
    let params = unsafe { handle::get_mut(options, "options") }?;
    // SAFETY: the caller's guarantees.
    let name = unsafe { handle::text(name, "name") }?;
    params
        .set(name, value)
        .map_err(|message| Failure::new(Status::INVALID_OPTION, message))
}
