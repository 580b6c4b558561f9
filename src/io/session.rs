//! GDAL state for the duration of one run, restored afterwards so that a host application (the C
//! API inside QGIS) keeps its own:
//! - GDAL's messages are caught instead of printed: errors become our one-line [`Error`]s,
//!   warnings become notes of the run;
//! - formats that store "now" (GeoPackage's `last_change` and metadata timestamps) store a fixed
//!   date, and a File Geodatabase's GUIDs are made from its contents, so two runs give the same
//!   bytes;
//! - the SQLite-based formats (GeoPackage, SQLite) do not sync to the disk at each commit of
//!   their journal (28 times for one GeoPackage layer): every run writes into a staged copy
//!   that is nobody's until it is synced once and moved into place (`commit`), so those syncs
//!   protected nothing, and on a network drive each costs milliseconds.
//!
//! All are per thread in GDAL (an error-handler stack and thread-local configuration options),
//! and a run calls GDAL from one thread only (the core's worker threads never do).

use crate::core::Error;
use gdal::errors::GdalError;
use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr};
use std::marker::PhantomData;

/// The date written wherever a format stores the time of writing.
pub(crate) const FIXED_DATE: &str = "2000-01-01T00:00:00Z";

/// The configuration options a session sets on its thread, with their values.
const OPTIONS: [(&str, &str); 3] = [
    ("OGR_CURRENT_DATE", FIXED_DATE),
    ("OGR_SQLITE_SYNCHRONOUS", "OFF"),
    // A File Geodatabase's tables hold a random GUID per item (the layer, the dataset):
    // without this no two runs write the same folder.
    ("OPENFILEGDB_REPRODUCIBLE_UUID", "YES"),
];

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

/// Open while a run talks to GDAL; dropping it restores GDAL's previous handler and options.
/// Not `Send`: the handler it pushed belongs to this thread.
pub(crate) struct Session {
    /// Per option of [`OPTIONS`], its thread-local value before the session ("": none).
    previous: Vec<String>,
    _this_thread: PhantomData<*const ()>,
}

impl Session {
    pub(crate) fn start() -> Session {
        CAUGHT.with(|caught| *caught.borrow_mut() = Caught::default());
        // SAFETY: `catch` has the signature GDAL expects and never unwinds; the matching
        // CPLPopErrorHandler runs in `drop`, on this same thread (the session is not `Send`).
        unsafe { gdal_sys::CPLPushErrorHandler(Some(catch)) };
        let previous = (OPTIONS.iter())
            .map(|&(option, value)| {
                let previous =
                    gdal::config::get_thread_local_config_option(option, "").unwrap_or_default();
                // Cannot fail: the strings are free of NUL bytes.
                let _ = gdal::config::set_thread_local_config_option(option, value);
                previous
            })
            .collect();
        Session {
            previous,
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
        for (&(option, _), previous) in OPTIONS.iter().zip(&self.previous) {
            let _ = if previous.is_empty() {
                gdal::config::clear_thread_local_config_option(option)
            } else {
                gdal::config::set_thread_local_config_option(option, previous)
            };
        }
        // SAFETY: pops the handler `start` pushed on this thread.
        unsafe { gdal_sys::CPLPopErrorHandler() };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gdal::config::{
        clear_thread_local_config_option, get_thread_local_config_option,
        set_thread_local_config_option,
    };

    #[test]
    fn a_session_sets_its_options_on_its_thread_and_gives_the_host_its_own_back() {
        // The host (QGIS, through the C API) has its own value for one option, none for the other.
        set_thread_local_config_option("OGR_SQLITE_SYNCHRONOUS", "NORMAL").unwrap();
        clear_thread_local_config_option("OGR_CURRENT_DATE").unwrap();
        let value = |option| get_thread_local_config_option(option, "").unwrap();
        {
            let _session = Session::start();
            assert_eq!(value("OGR_SQLITE_SYNCHRONOUS"), "OFF");
            assert_eq!(value("OGR_CURRENT_DATE"), FIXED_DATE);
            // Other threads (the host's) are untouched.
            let elsewhere = std::thread::spawn(move || {
                get_thread_local_config_option("OGR_SQLITE_SYNCHRONOUS", "").unwrap()
            });
            assert_eq!(elsewhere.join().unwrap(), "");
        }
        assert_eq!(value("OGR_SQLITE_SYNCHRONOUS"), "NORMAL");
        assert_eq!(value("OGR_CURRENT_DATE"), "");
        clear_thread_local_config_option("OGR_SQLITE_SYNCHRONOUS").unwrap();
    }
}
