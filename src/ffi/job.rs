//! A dataset-to-dataset run, described as the command line describes it ([`crate::job::Job`]), so that the
//! C API reads and writes through GDAL exactly as `snakegrid DST SRC [SRC_LAYER]` does.

use super::handle::{self, Handle, Out};
use super::status::{guard, guard_free, Failure, Status};
use crate::job::Job;
use std::ffi::c_char;

/// Where to read regions and where to write the grid map. Made by snakegrid_job_new(),
/// described by snakegrid_job_set() and snakegrid_job_set_overwrite(), run by
/// snakegrid_run_job(), freed by snakegrid_job_free().
pub struct DatasetJob {
    _opaque: [u8; 0],
}

impl Handle for DatasetJob {
    type Inner = Job;
    const TAG: u64 = u64::from_be_bytes(*b"sgJOB\0\0\0");
    const NAME: &'static str = "snakegrid_job";
}

/// The settings snakegrid_job_set() knows, each with the command-line option it mirrors.
const SETTINGS: &str = "src (SRC), src_layer (SRC_LAYER), where (-where), id_field (-id), \
    dst (DST), format (-f), layer_name (-nln), target_srs (-t_srs), json_report (-json), \
    svg (-svg), label_field (-label)";

/// Makes an empty job (no source, no destination, no overwrite) and writes it to `*out`.
///
/// Thread safety: safe from any thread.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_job_new(out: *mut *mut DatasetJob) -> Status {
    guard("snakegrid_job_new", || {
        // SAFETY: `out` is NULL or writable (header contract).
        let out = unsafe { Out::new(out, "out") }?;
        out.write(handle::into_raw::<DatasetJob>(Job::default()));
        Ok(())
    })
}

/// Frees a job handle. NULL is ignored.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[no_mangle]
pub unsafe extern "C" fn snakegrid_job_free(job: *mut DatasetJob) {
    // SAFETY: `job` is NULL or a handle not used elsewhere meanwhile (header contract).
    guard_free("snakegrid_job_free", || unsafe { handle::free(job, "job") })
}

/// Sets one text setting of a job; `value` NULL clears it (the command line's default). The
/// settings, with the command-line option each mirrors:
/// - "src": source dataset (file, folder or connection string); required;
/// - "src_layer": source layer name (default: the first layer);
/// - "where": OGR SQL attribute filter;
/// - "id_field": field holding the unique region id (default: the feature id);
/// - "dst": destination dataset path; required;
/// - "format": GDAL driver short name (default: from the extension, else GPKG);
/// - "layer_name": output layer name (default: the source layer's);
/// - "target_srs": working CRS, any definition GDAL accepts (default: the source's if
///   projected, else a Lambert azimuthal equal-area CRS at its centre);
/// - "json_report": path of a machine-readable report to write;
/// - "svg": path of a picture of the source and the grid map to write;
/// - "label_field": short label field for the picture.
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for another name. Thread safety: not concurrently with
/// any other use of the same handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_job_set(
    job: *mut DatasetJob,
    name: *const c_char,
    value: *const c_char,
) -> Status {
    guard("snakegrid_job_set", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        let job = unsafe { handle::get_mut(job, "job") }?;
        // SAFETY: NUL-terminated strings or NULL (header contract).
        let (name, value) = unsafe {
            (
                handle::text(name, "name")?,
                handle::optional_text(value, "value")?,
            )
        };
        let value = value.map(str::to_owned);
        match name {
            "src" => job.src = value.unwrap_or_default(),
            "dst" => job.dst = value.unwrap_or_default(),
            _ => *optional_setting(job, name)? = value,
        }
        Ok(())
    })
}

fn optional_setting<'a>(job: &'a mut Job, name: &str) -> Result<&'a mut Option<String>, Failure> {
    Ok(match name {
        "src_layer" => &mut job.src_layer,
        "where" => &mut job.where_clause,
        "id_field" => &mut job.id_field,
        "format" => &mut job.format,
        "layer_name" => &mut job.layer_name,
        "target_srs" => &mut job.target_srs,
        "json_report" => &mut job.json_report,
        "svg" => &mut job.svg,
        "label_field" => &mut job.label_field,
        _ => {
            return Err(Failure::new(
                Status::INVALID_ARGUMENT,
                format!("unknown job setting {name:?}; the settings are {SETTINGS}"),
            ))
        }
    })
}

/// Whether an existing destination may be replaced (the command line's -overwrite); it is
/// replaced only once the run has succeeded. Off when the job is made.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_job_set_overwrite(
    job: *mut DatasetJob,
    overwrite: bool,
) -> Status {
    guard("snakegrid_job_set_overwrite", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        unsafe { handle::get_mut(job, "job") }?.overwrite = overwrite;
        Ok(())
    })
}
