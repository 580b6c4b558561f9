//! Method parameters by name. Every setter goes through [`Params::set`], the parser the command
//! line uses, so names, accepted values and range checks are the same everywhere.

use super::handle::{self, Handle, Out};
use super::status::{c_string, catch, guard, guard_free, Failure, Status};
use crate::core::params::{Bound, Kind, PARAMETERS};
use crate::core::Params;
use std::ffi::{c_char, CString};
use std::sync::OnceLock;

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
#[must_use]
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
#[must_use]
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
#[must_use]
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
#[must_use]
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
#[must_use]
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

/// What kind of value an option takes (snakegrid_option::kind).
/// cbindgen:rename-all=prefix:SNAKEGRID_OPTION_
#[allow(non_camel_case_types, clippy::upper_case_acronyms)]
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OptionKind {
    /// A finite number.
    REAL = 0,
    /// A whole number >= 0 of `integer_bits` bits.
    INTEGER = 1,
    /// "true" or "false".
    BOOL = 2,
    /// One of the names in `choices`.
    CHOICE = 3,
    /// Comma-separated numbers, `list_min` to `list_max` of them, each in the range.
    REAL_LIST = 4,
    /// Comma-separated x:y pairs, `list_min` to `list_max` of them, each number in the range.
    PAIR_LIST = 5,
}

/// One row of the parameter table, as every face of snakegrid shows it. Every string is static
/// (it lives as long as the library is loaded) and UTF-8.
#[repr(C)]
pub struct COptionInfo {
    /// The name snakegrid_options_set() takes.
    pub name: *const c_char,
    pub kind: OptionKind,
    /// The default, as text that snakegrid_options_set() reads back.
    pub default_value: *const c_char,
    /// The option may be "none" (unset).
    pub optional: bool,
    /// The range (of each element, for lists): `minimum` applies when `has_minimum`, and is
    /// excluded when `minimum_open`; likewise the maximum.
    pub has_minimum: bool,
    pub minimum: f64,
    pub minimum_open: bool,
    pub has_maximum: bool,
    pub maximum: f64,
    pub maximum_open: bool,
    /// The range as text, e.g. "(0, 1]" or "nodal or element".
    pub range: *const c_char,
    /// Width of an INTEGER option (32 or 64); 0 for other kinds.
    pub integer_bits: u32,
    /// How many elements a list takes; 0 and 0 for other kinds.
    pub list_min: usize,
    pub list_max: usize,
    /// The names of a CHOICE option, separated by '|'; "" for other kinds.
    pub choices: *const c_char,
    /// Unit of the value ("cells", "cells²", ...; "" for none).
    pub unit: *const c_char,
    /// The step of the method it belongs to ("Snake", "Outline", ...), and a heading for it.
    pub group: *const c_char,
    pub group_title: *const c_char,
    /// Best left alone by most users.
    pub advanced: bool,
    /// One line, and a paragraph.
    pub summary: *const c_char,
    pub help: *const c_char,
}

/// The strings of one table row, made once so that the pointers handed out stay valid.
struct RowTexts {
    name: CString,
    default_value: CString,
    range: CString,
    choices: CString,
    unit: CString,
    group: CString,
    group_title: CString,
    summary: CString,
    help: CString,
}

fn row_texts() -> &'static [RowTexts] {
    static TEXTS: OnceLock<Vec<RowTexts>> = OnceLock::new();
    TEXTS.get_or_init(|| {
        PARAMETERS
            .iter()
            .map(|p| RowTexts {
                name: c_string(p.name),
                default_value: c_string(&p.default_text()),
                range: c_string(&p.range_text()),
                choices: c_string(&match p.kind {
                    Kind::Choice(names) => names.join("|"),
                    _ => String::new(),
                }),
                unit: c_string(p.unit),
                group: c_string(p.group.as_str()),
                group_title: c_string(p.group.title()),
                summary: c_string(p.summary),
                help: c_string(p.help),
            })
            .collect()
    })
}

/// The number of options (rows of the parameter table).
///
/// Never fails. Thread safety: safe from any thread.
#[no_mangle]
pub extern "C" fn snakegrid_option_count() -> usize {
    catch(|| Ok(PARAMETERS.len())).unwrap_or(0)
}

/// Describes option `index` (0 to snakegrid_option_count() - 1, in the table's order: grouped
/// by the step of the method) into `*out`.
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for an index out of range.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_option_info(index: usize, out: *mut COptionInfo) -> Status {
    guard("snakegrid_option_info", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        let (p, texts) = PARAMETERS
            .get(index)
            .zip(row_texts().get(index))
            .ok_or_else(|| {
                Failure::new(
                    Status::INVALID_ARGUMENT,
                    format!(
                        "index {index} is out of range (there are {} options)",
                        PARAMETERS.len()
                    ),
                )
            })?;
        let (kind, integer_bits, (list_min, list_max)) = match p.kind {
            Kind::Real => (OptionKind::REAL, 0, (0, 0)),
            Kind::Integer { bits } => (OptionKind::INTEGER, bits, (0, 0)),
            Kind::Bool => (OptionKind::BOOL, 0, (0, 0)),
            Kind::Choice(_) => (OptionKind::CHOICE, 0, (0, 0)),
            Kind::RealList { min, max } => (OptionKind::REAL_LIST, 0, (min, max)),
            Kind::PairList { min, max } => (OptionKind::PAIR_LIST, 0, (min, max)),
        };
        let bound = |b: Option<Bound>| match b {
            Some(b) => (true, b.value, b.open),
            None => (false, 0.0, false),
        };
        let (has_minimum, minimum, minimum_open) = bound(p.min);
        let (has_maximum, maximum, maximum_open) = bound(p.max);
        out.write(COptionInfo {
            name: texts.name.as_ptr(),
            kind,
            default_value: texts.default_value.as_ptr(),
            optional: p.optional,
            has_minimum,
            minimum,
            minimum_open,
            has_maximum,
            maximum,
            maximum_open,
            range: texts.range.as_ptr(),
            integer_bits,
            list_min,
            list_max,
            choices: texts.choices.as_ptr(),
            unit: texts.unit.as_ptr(),
            group: texts.group.as_ptr(),
            group_title: texts.group_title.as_ptr(),
            advanced: p.advanced,
            summary: texts.summary.as_ptr(),
            help: texts.help.as_ptr(),
        });
        Ok(())
    })
}
