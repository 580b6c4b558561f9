//! GDAL state for the duration of one run, restored afterwards so that a host application (the C
//! API inside QGIS) keeps its own:
//! - GDAL's messages are caught instead of printed: errors become our one-line [`Error`]s,
//!   warnings become notes of the run;
//! - formats that store "now" (GeoPackage's `last_change` and metadata timestamps) store a fixed
//!   date, so two runs give the same bytes.
//!
//! Both are per thread in GDAL (an error-handler stack and a thread-local configuration option),
//! and a run calls GDAL from one thread only (the core's worker threads never do).

use crate::core::Error;
use gdal::errors::GdalError;
use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr};
use std::marker::PhantomData;

/// The date written wherever a format stores the time of writing.
pub(crate) const FIXED_DATE: &str = "2000-01-01T00:00:00Z";
const DATE_OPTION: &str = "OGR_CURRENT_DATE";

/// What GDAL said on this thread since the session started.
#[derive(Default)]
struct Caught {
    warnings: Vec<String>,
    last_error: Option<String>,
}

thread_local! {
    static CAUGHT: RefCell<Caught> = RefCell::new(Caught::default());
}

/// GDAL's error handler while a session is open. It must never unwind into C: every step here
/// is infallible (`try_` borrows, lossy UTF-8), and a message arriving while the cell is busy or
/// the thread is exiting is dropped.
unsafe extern "C" fn catch(class: gdal_sys::CPLErr::Type, _number: c_int, message: *const c_char) {
    if message.is_null() {
        return;
    }
    // SAFETY: GDAL passes a NUL-terminated string that stays valid during this call; it is
    // copied before returning.
    let text = unsafe { CStr::from_ptr(message) }
        .to_string_lossy()
        .trim()
        .to_owned();
    let _ = CAUGHT.try_with(|caught| {
        if let Ok(mut caught) = caught.try_borrow_mut() {
            match class {
                gdal_sys::CPLErr::CE_Warning if !caught.warnings.contains(&text) => {
                    caught.warnings.push(text)
                }
                gdal_sys::CPLErr::CE_Failure | gdal_sys::CPLErr::CE_Fatal => {
                    caught.last_error = Some(text)
                }
                _ => {}
            }
        }
    });
}

/// Open while a run talks to GDAL; dropping it restores GDAL's previous handler and date. Not
/// `Send`: the handler it pushed belongs to this thread.
pub(crate) struct Session {
    previous_date: String,
    _this_thread: PhantomData<*const ()>,
}

impl Session {
    pub(crate) fn start() -> Session {
        CAUGHT.with(|caught| *caught.borrow_mut() = Caught::default());
        // SAFETY: `catch` has the signature GDAL expects and never unwinds; the matching
        // CPLPopErrorHandler runs in `drop`, on this same thread (the session is not `Send`).
        unsafe { gdal_sys::CPLPushErrorHandler(Some(catch)) };
        let previous_date =
            gdal::config::get_thread_local_config_option(DATE_OPTION, "").unwrap_or_default();
        // Cannot fail: both strings are free of NUL bytes.
        let _ = gdal::config::set_thread_local_config_option(DATE_OPTION, FIXED_DATE);
        Session {
            previous_date,
            _this_thread: PhantomData,
        }
    }

    /// GDAL's warnings so far, each once, in the order they came.
    pub(crate) fn warnings(&self) -> Vec<String> {
        CAUGHT.with(|caught| caught.borrow().warnings.clone())
    }

    /// How many warnings GDAL has given so far.
    pub(crate) fn warning_count(&self) -> usize {
        CAUGHT.with(|caught| caught.borrow().warnings.len())
    }

    /// Forgets the warnings after the first `kept`: those of a trial that the real run will
    /// give again, about its own files.
    pub(crate) fn forget_warnings_after(&self, kept: usize) {
        CAUGHT.with(|caught| caught.borrow_mut().warnings.truncate(kept));
    }

    /// The last error GDAL reported since the previous call, if any.
    pub(crate) fn take_error(&self) -> Option<String> {
        CAUGHT.with(|caught| caught.borrow_mut().last_error.take())
    }

    /// `context: reason`, the reason taken from the GDAL error or else from the last error GDAL
    /// reported (many bindings return only a code).
    pub(crate) fn io_error(&self, context: &str, error: GdalError) -> Error {
        let from_error = match &error {
            GdalError::CplError { msg, .. } | GdalError::NullPointer { msg, .. } => msg.trim(),
            _ => "",
        };
        let reason = if !from_error.is_empty() {
            from_error.to_owned()
        } else if let Some(last) = self.take_error() {
            last
        } else {
            error.to_string()
        };
        Error::Io(format!("{context}: {reason}"))
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        let _ = if self.previous_date.is_empty() {
            gdal::config::clear_thread_local_config_option(DATE_OPTION)
        } else {
            gdal::config::set_thread_local_config_option(DATE_OPTION, &self.previous_date)
        };
        // SAFETY: pops the handler `start` pushed on this thread.
        unsafe { gdal_sys::CPLPopErrorHandler() };
    }
}
