//! The two entry points, in memory ([`crate::generate`]) and dataset to dataset
//! ([`crate::io::run`]), and the progress callback that both pass to the core.

use super::handle::{self, Out};
use super::job::DatasetJob;
use super::options::Options;
use super::regions::Regions;
use super::result::{Output, RunResult};
use super::status::{c_string, guard, Failure, Status};
use crate::core::Progress;
use std::ffi::{c_char, c_int, c_void};
use std::sync::{Mutex, PoisonError};

/// Progress callback: `fraction` done (0 to 1, never decreasing), a short `message` (valid only
/// during the call) and the `user_data` given to the run. Return 0 to go on, non-zero to cancel:
/// the run then stops soon after with SNAKEGRID_CANCELLED and the callback is not called again.
///
/// It may be called from threads other than the caller's (the candidates run in parallel),
/// but never from two threads at once, and only until the run returns. It must not throw (C++)
/// or longjmp out, and must not free the handles the run is using.
pub type ProgressCallback = Option<
    unsafe extern "C" fn(fraction: f64, message: *const c_char, user_data: *mut c_void) -> c_int,
>;

/// A C callback as the core's [`Progress`]: calls are serialised, fractions never go back
/// (worker threads may report out of order), and a request to cancel is remembered so that
/// every later report answers "stop" without calling C again.
struct CallbackProgress {
    callback: unsafe extern "C" fn(f64, *const c_char, *mut c_void) -> c_int,
    user_data: *mut c_void,
    /// Held during each call.
    state: Mutex<Reported>,
}

#[derive(Default)]
struct Reported {
    /// The largest fraction passed to the callback so far.
    fraction: f64,
    /// The callback has asked to cancel.
    cancelled: bool,
}

// SAFETY: the core reports progress from worker threads. The header requires the callback and
// its user_data to be usable from any thread, and the mutex makes the calls one at a time, so
// sharing the raw pointer between threads adds no data race on the Rust side.
unsafe impl Sync for CallbackProgress {}

impl CallbackProgress {
    fn report(&self, fraction: f64, message: &str) -> bool {
        let mut state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        if !state.cancelled {
            state.fraction = state.fraction.max(fraction.clamp(0.0, 1.0));
            let message = c_string(message);
            // SAFETY: a C function pointer given by the caller for this run, called with a
            // NUL-terminated message that outlives the call and the caller's own user_data.
            state.cancelled =
                unsafe { (self.callback)(state.fraction, message.as_ptr(), self.user_data) } != 0;
        }
        !state.cancelled
    }
}

/// Runs `body` with the core's view of an optional C callback.
fn with_progress<R>(
    callback: ProgressCallback,
    user_data: *mut c_void,
    body: impl FnOnce(Progress) -> R,
) -> R {
    match callback {
        Some(callback) => {
            let adapter = CallbackProgress {
                callback,
                user_data,
                state: Mutex::default(),
            };
            body(&|fraction, message| adapter.report(fraction, message))
        }
        None => body(&|_, _| true),
    }
}

/// Makes a grid map of the regions in memory with the given options and writes a new result
/// handle to `*result` (free it with snakegrid_result_free()). `progress` and `user_data` may be
/// NULL.
///
/// Fails with SNAKEGRID_INVALID_INPUT (no regions, a duplicate or empty id, a region without
/// area; the message names the region), SNAKEGRID_INVALID_OPTION, SNAKEGRID_CANCELLED, or SNAKEGRID_INTERNAL_ERROR. Thread safety: the
/// regions and options are only read, so several runs may share them, from any threads, as
/// long as no thread modifies or frees them meanwhile.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_run(
    regions: *const Regions,
    options: *const Options,
    progress: ProgressCallback,
    user_data: *mut c_void,
    result: *mut *mut RunResult,
) -> Status {
    guard("snakegrid_run", || {
        // SAFETY: live handles not modified meanwhile, `result` NULL or writable (header
        // contract).
        let (list, params, out) = unsafe {
            (
                handle::get(regions, "regions")?,
                handle::get(options, "options")?,
                Out::new(result, "result")?,
            )
        };
        let map = with_progress(progress, user_data, |p| crate::generate(list, params, p))?;
        // In memory there is no I/O to report on: the notes are the admission's (curves
        // linearised) and the core's (repaired polygons).
        let notes: Vec<String> = list.note().into_iter().chain(map.notes.clone()).collect();
        out.write(handle::into_raw::<RunResult>(Output::new(map, &notes)));
        Ok(())
    })
}

/// Runs a job: reads the regions from the source dataset, makes the grid map, writes the
/// destination (and the report and picture when asked), all through GDAL exactly as the
/// command line does, and writes a new result handle to `*result`. `progress` and `user_data`
/// may be NULL. On failure or cancellation every existing output is left as it was and nothing
/// new is left behind.
///
/// Fails with SNAKEGRID_UNSUPPORTED in a build without GDAL; otherwise with SNAKEGRID_IO_ERROR
/// (the source cannot be read; the destination cannot be written, exists without overwrite or
/// update, or is a format that would not keep the grid), SNAKEGRID_INVALID_INPUT (including an
/// id the output format would change), SNAKEGRID_CANCELLED or SNAKEGRID_INTERNAL_ERROR. Thread
/// safety: as snakegrid_run(); two jobs with the same
/// destination must not run at once.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_run_job(
    job: *const DatasetJob,
    options: *const Options,
    progress: ProgressCallback,
    user_data: *mut c_void,
    result: *mut *mut RunResult,
) -> Status {
    guard("snakegrid_run_job", || {
        // SAFETY: live handles not modified meanwhile, `result` NULL or writable (header
        // contract).
        let (job, params, out) = unsafe {
            (
                handle::get(job, "job")?,
                handle::get(options, "options")?,
                Out::new(result, "result")?,
            )
        };
        let (map, notes) = with_progress(progress, user_data, |p| run_dataset(job, params, p))?;
        out.write(handle::into_raw::<RunResult>(Output::new(map, &notes)));
        Ok(())
    })
}

/// The dataset run of the command line, in a build with GDAL.
#[cfg(feature = "gdal")]
fn run_dataset(
    job: &crate::job::Job,
    params: &crate::Params,
    progress: crate::Progress,
) -> Result<(crate::GridMap, Vec<String>), Failure> {
    let outcome = crate::io::run(job, params, progress)?;
    Ok((outcome.map, outcome.notes))
}

/// A build without GDAL reads and writes no datasets; the in-memory entry point still works.
#[cfg(not(feature = "gdal"))]
fn run_dataset(
    _job: &crate::job::Job,
    _params: &crate::Params,
    _progress: crate::Progress,
) -> Result<(crate::GridMap, Vec<String>), Failure> {
    Err(Failure::new(
        Status::UNSUPPORTED,
        "this build of libsnakegrid has no GDAL, so it reads and writes no datasets: read the \
         regions yourself and pass them to snakegrid_run(), or use a build with GDAL (the \
         default cargo build, the command line)",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffi::job::{snakegrid_job_free, snakegrid_job_new, snakegrid_job_set};
    use crate::ffi::options::{snakegrid_options_free, snakegrid_options_new};
    use crate::ffi::status::snakegrid_last_error_message;
    use std::ffi::CStr;
    use std::ptr::null_mut;

    /// The dataset entry point of this build: it reads the layer (with GDAL) or says which build
    /// can, and either way it names a missing source or the missing GDAL.
    #[test]
    fn the_dataset_entry_point_answers_in_every_build() {
        let (mut job, mut options, mut result) = (null_mut(), null_mut(), null_mut());
        // SAFETY: fresh out-pointers, strings NUL-terminated, handles freed at the end.
        unsafe {
            assert_eq!(snakegrid_job_new(&mut job), Status::OK);
            assert_eq!(snakegrid_options_new(&mut options), Status::OK);
            for (key, value) in [(c"src", c"/no/such/source.gpkg"), (c"dst", c"/tmp/x.gpkg")] {
                assert_eq!(
                    snakegrid_job_set(job, key.as_ptr(), value.as_ptr()),
                    Status::OK
                );
            }
            let status = snakegrid_run_job(job, options, None, null_mut(), &mut result);
            let message = CStr::from_ptr(snakegrid_last_error_message()).to_string_lossy();
            if cfg!(feature = "gdal") {
                assert_eq!(status, Status::IO_ERROR, "{message}");
                assert!(message.contains("no such file"), "{message}");
            } else {
                assert_eq!(status, Status::UNSUPPORTED, "{message}");
                assert!(message.contains("has no GDAL"), "{message}");
            }
            assert!(result.is_null());
            snakegrid_job_free(job);
            snakegrid_options_free(options);
        }
    }

    /// A job without its source or destination says which is missing: it said "cannot open
    /// source \"\"".
    #[cfg(feature = "gdal")]
    #[test]
    fn a_job_without_its_datasets_names_the_missing_one() {
        let (mut job, mut options, mut result) = (null_mut(), null_mut(), null_mut());
        // SAFETY: fresh out-pointers, strings NUL-terminated, handles freed at the end.
        unsafe {
            assert_eq!(snakegrid_job_new(&mut job), Status::OK);
            assert_eq!(snakegrid_options_new(&mut options), Status::OK);
            for (set, missing) in [
                (None, "no source dataset"),
                (Some(c"src"), "no destination"),
            ] {
                if let Some(key) = set {
                    let value = c"/no/such/source.gpkg";
                    assert_eq!(
                        snakegrid_job_set(job, key.as_ptr(), value.as_ptr()),
                        Status::OK
                    );
                }
                let status = snakegrid_run_job(job, options, None, null_mut(), &mut result);
                let message = CStr::from_ptr(snakegrid_last_error_message()).to_string_lossy();
                assert_eq!(status, Status::INVALID_OPTION, "{message}");
                assert!(message.contains(missing), "{message}");
                assert!(result.is_null());
            }
            snakegrid_job_free(job);
            snakegrid_options_free(options);
        }
    }
}
