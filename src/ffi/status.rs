//! Status codes, the calling thread's last error message, and the panic boundary that every
//! exported function goes through.

use crate::core::Error;
use std::any::Any;
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{self, AssertUnwindSafe};

/// What a fallible function did. `SNAKEGRID_OK` is 0, every failure is non-zero, and the
/// values never change between versions (new codes are only ever added at the end).
///
/// In C this is a `uint32_t`, so any value can be passed back to snakegrid_status_string().
/// cbindgen:rename-all=prefix:SNAKEGRID_
#[allow(non_camel_case_types, clippy::upper_case_acronyms)]
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Success: the out-parameters have been written.
    OK = 0,
    /// A required pointer argument was NULL.
    NULL_ARGUMENT = 1,
    /// A handle argument is not a live handle of the expected kind (freed, or another kind).
    INVALID_HANDLE = 2,
    /// An argument is malformed: text that is not UTF-8, an index out of range, an unknown job
    /// setting.
    INVALID_ARGUMENT = 3,
    /// The regions cannot be used: bad WKB, not a (multi)polygon, a duplicate id, no
    /// regions. The message names the region.
    INVALID_INPUT = 4,
    /// An unknown option name, or a value that does not parse or is out of range. The message
    /// names the option.
    INVALID_OPTION = 5,
    /// Reading or writing a dataset failed.
    IO_ERROR = 6,
    /// The progress callback asked to stop; nothing was produced.
    CANCELLED = 7,
    /// A bug in snakegrid (including a caught panic). Please report it with the message.
    INTERNAL_ERROR = 8,
    /// This build of the library cannot do it: snakegrid_run_job() in a build without GDAL
    /// (such as the one the QGIS plugin and the Python package ship). The message says which
    /// build can.
    UNSUPPORTED = 9,
}

impl Status {
    fn description(self) -> &'static CStr {
        match self {
            Status::OK => c"ok",
            Status::NULL_ARGUMENT => c"a required pointer argument is NULL",
            Status::INVALID_HANDLE => c"not a live handle of the expected kind",
            Status::INVALID_ARGUMENT => c"invalid argument",
            Status::INVALID_INPUT => c"invalid input regions",
            Status::INVALID_OPTION => c"invalid option",
            Status::IO_ERROR => c"dataset input/output error",
            Status::CANCELLED => c"cancelled by the progress callback",
            Status::INTERNAL_ERROR => c"internal error",
            Status::UNSUPPORTED => c"not supported by this build of the library",
        }
    }

    fn from_code(code: u32) -> Option<Status> {
        [
            Status::OK,
            Status::NULL_ARGUMENT,
            Status::INVALID_HANDLE,
            Status::INVALID_ARGUMENT,
            Status::INVALID_INPUT,
            Status::INVALID_OPTION,
            Status::IO_ERROR,
            Status::CANCELLED,
            Status::INTERNAL_ERROR,
            Status::UNSUPPORTED,
        ]
        .into_iter()
        .find(|s| *s as u32 == code)
    }
}

/// Why an exported function failed: the status to return and the message to keep.
#[derive(Debug)]
pub(crate) struct Failure {
    pub(crate) status: Status,
    pub(crate) message: String,
}

impl Failure {
    pub(crate) fn new(status: Status, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }

    pub(crate) fn null(argument: &str) -> Self {
        Failure::new(
            Status::NULL_ARGUMENT,
            format!("argument {argument} is NULL"),
        )
    }

    fn panic(payload: Box<dyn Any + Send>) -> Self {
        let what = payload
            .downcast_ref::<&str>()
            .copied()
            .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
            .unwrap_or("(no message)");
        Failure::new(
            Status::INTERNAL_ERROR,
            format!("internal error: panic: {what}"),
        )
    }
}

impl From<Error> for Failure {
    fn from(error: Error) -> Self {
        let status = match error {
            Error::InvalidInput { .. } => Status::INVALID_INPUT,
            Error::InvalidParameter(_) => Status::INVALID_OPTION,
            Error::Io(_) => Status::IO_ERROR,
            Error::Cancelled => Status::CANCELLED,
            Error::Internal(_) => Status::INTERNAL_ERROR,
        };
        Failure::new(status, error.to_string())
    }
}

/// Text for C: a Rust string cut at its first NUL, which C could not see past anyway.
pub(crate) fn c_string(text: &str) -> CString {
    let end = text.find('\0').unwrap_or(text.len());
    CString::new(&text[..end]).unwrap_or_default()
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: CString) {
    // During thread teardown the slot may be gone; there is nobody left to read it then.
    let _ = LAST_ERROR.try_with(|slot| *slot.borrow_mut() = message);
}

/// Runs the body of an exported function, turning a panic into a [`Failure`] so that no
/// unwinding crosses into C (where it would abort the host process, e.g. QGIS).
pub(crate) fn catch<R>(body: impl FnOnce() -> Result<R, Failure>) -> Result<R, Failure> {
    // AssertUnwindSafe: after a panic the handles the body touched may be half-updated, but
    // every mutation the API makes is a single assignment at the end of a successful body, so
    // a panic leaves them as they were.
    panic::catch_unwind(AssertUnwindSafe(body))
        .unwrap_or_else(|payload| Err(Failure::panic(payload)))
}

/// The boundary of every function that returns a status: runs the body, records the message
/// of a failure (prefixed with the function's name) or clears it on success, and returns the
/// status.
pub(crate) fn guard(function: &str, body: impl FnOnce() -> Result<(), Failure>) -> Status {
    match catch(body) {
        Ok(()) => {
            set_last_error(CString::default());
            Status::OK
        }
        Err(failure) => {
            set_last_error(c_string(&format!("{function}: {}", failure.message)));
            failure.status
        }
    }
}

/// The boundary of the `_free` functions, which return nothing: a failure (a pointer that is
/// not a live handle) is recorded, success leaves the last message alone so that cleanup code
/// does not erase the error it is cleaning up after.
pub(crate) fn guard_free(function: &str, body: impl FnOnce() -> Result<(), Failure>) {
    if let Err(failure) = catch(body) {
        set_last_error(c_string(&format!("{function}: {}", failure.message)));
    }
}

/// The message of the last failed call on the calling thread, naming the function and the
/// problem (for bad input, the region; for options, the option). Empty ("") when the last call
/// that returns a snakegrid_status succeeded. Functions that return no status (the `_free`
/// functions, snakegrid_version, snakegrid_status_string, this one) do not clear it.
///
/// Never NULL. The string belongs to the library and stays valid until the next call on the
/// same thread that returns a snakegrid_status. Thread safety: safe from any thread; each thread
/// has its own message.
#[no_mangle]
pub extern "C" fn snakegrid_last_error_message() -> *const c_char {
    catch(|| {
        Ok(LAST_ERROR
            .try_with(|slot| slot.borrow().as_ptr())
            .unwrap_or(c"".as_ptr()))
    })
    .unwrap_or(c"".as_ptr())
}

/// A short, static description of a status code ("unknown status" for values this version
/// does not define).
///
/// Never NULL; the string is static. Thread safety: safe from any thread.
#[no_mangle]
pub extern "C" fn snakegrid_status_string(status: u32) -> *const c_char {
    catch(|| {
        Ok(Status::from_code(status)
            .map_or(c"unknown status", Status::description)
            .as_ptr())
    })
    .unwrap_or(c"unknown status".as_ptr())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn last_message() -> String {
        // SAFETY: the function returns a NUL-terminated string owned by this thread's slot.
        unsafe { CStr::from_ptr(snakegrid_last_error_message()) }
            .to_str()
            .unwrap()
            .to_owned()
    }

    #[test]
    fn a_panic_becomes_an_internal_error_with_its_message() {
        let status = guard("snakegrid_test", || panic!("the core is not written yet"));
        assert_eq!(status, Status::INTERNAL_ERROR);
        assert_eq!(
            last_message(),
            "snakegrid_test: internal error: panic: the core is not written yet"
        );
        let status = guard("snakegrid_test", || panic!("{} formatted", 1));
        assert_eq!(status, Status::INTERNAL_ERROR);
        assert!(last_message().ends_with("panic: 1 formatted"));
    }

    #[test]
    fn success_clears_the_message_and_cleanup_keeps_it() {
        guard("snakegrid_test", || Err(Failure::null("out")));
        assert_eq!(last_message(), "snakegrid_test: argument out is NULL");
        guard_free("snakegrid_test_free", || Ok(()));
        assert_eq!(last_message(), "snakegrid_test: argument out is NULL");
        guard_free("snakegrid_test_free", || panic!("in a destructor"));
        assert!(last_message().starts_with("snakegrid_test_free: internal error"));
        assert_eq!(guard("snakegrid_test", || Ok(())), Status::OK);
        assert_eq!(last_message(), "");
    }

    #[test]
    fn core_errors_keep_their_kind_and_the_feature() {
        let failure = Failure::from(Error::input(Some("06"), "the polygon has no area"));
        assert_eq!(failure.status, Status::INVALID_INPUT);
        assert_eq!(failure.message, "feature 06: the polygon has no area");
        assert_eq!(Failure::from(Error::Cancelled).status, Status::CANCELLED);
        assert_eq!(
            Failure::from(Error::Io("x".into())).status,
            Status::IO_ERROR
        );
        assert_eq!(
            Failure::from(Error::InvalidParameter("x".into())).status,
            Status::INVALID_OPTION
        );
    }

    #[test]
    fn every_status_has_a_description_and_unknown_codes_are_safe() {
        for code in 0..=9 {
            let status = Status::from_code(code).unwrap();
            assert_eq!(status as u32, code);
            // SAFETY: static NUL-terminated strings.
            let text = unsafe { CStr::from_ptr(snakegrid_status_string(code)) };
            assert_ne!(text, c"unknown status");
        }
        assert_eq!(Status::from_code(10), None);
        // SAFETY: as above.
        assert_eq!(
            unsafe { CStr::from_ptr(snakegrid_status_string(u32::MAX)) },
            c"unknown status"
        );
    }

    #[test]
    fn messages_are_cut_at_a_nul() {
        assert_eq!(c_string("ab\0cd"), CString::new("ab").unwrap());
    }
}
