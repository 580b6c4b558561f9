//! A dataset-to-dataset run, described as the command line describes it ([`crate::job::Job`]), so that the
//! C API reads and writes through GDAL exactly as `snakegrid DST SRC [SRC_LAYER]` does.

use super::handle::{self, Handle, Out};
use super::status::{guard, guard_free, Failure, Status};
use crate::job::Job;
use std::ffi::c_char;

/// Where to read regions and where to write the grid map. Made by snakegrid_job_new(),
/// described by snakegrid_job_set(), snakegrid_job_set_overwrite() and
/// snakegrid_job_set_update(), run by snakegrid_run_job(), freed by snakegrid_job_free().
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
    group_field (-group), pin_col_field (-pin_col), pin_row_field (-pin_row), dst (DST), format (-f), layer_name (-nln), s_srs (-s_srs), target_srs (-t_srs), \
    json_report (-json), svg (-svg), hexjson (-hexjson), label_field (-label), lco (-lco), dsco (-dsco)";

/// Makes an empty job (no source, no destination, no overwrite, no update) and writes it to
/// `*out`.
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
/// - "group_field": field whose regions keep together, one block of cells per group on each
///   landmass (default: no groups; a null value is a group of its own region);
/// - "pin_col_field", "pin_row_field": fields holding each pinned region's cell, column and row
///   (whole numbers; null: free), both or neither; with pins, grid_col and grid_row are
///   numbered in the pins' frame (method.md §10);
/// - "dst": destination dataset path; required; "/vsistdout/" (with "format") sends the
///   dataset to the process's standard output once the run has succeeded, as one of
///   "json_report", "svg" or "hexjson" may instead;
/// - "format": GDAL driver short name (default: from the extension, refused when no
///   driver writes it; GPKG without one);
/// - "layer_name": output layer name (default: the source layer's);
/// - "s_srs": the source's CRS, any definition GDAL accepts, in place of the one it has;
/// - "target_srs": working CRS, any definition GDAL accepts (default: the source's if
///   projected, else a Lambert azimuthal equal-area CRS at its centre);
/// - "json_report": path of a machine-readable report to write;
/// - "svg": path of a picture of the source and the grid map to write;
/// - "hexjson": path of the layout as HexJSON to write (hexagonal cells only: parameter cell
///   hex);
/// - "label_field": short label field for the picture;
/// - "lco": one layer creation option of the output driver, NAME=VALUE; each call adds one
///   (as -lco does each time it is given), NULL clears them all;
/// - "dsco": one dataset creation option, NAME=VALUE; likewise.
///
/// Fails with SNAKEGRID_INVALID_ARGUMENT for another name, or an "lco" or "dsco" value that is
/// not NAME=VALUE. Thread safety: not concurrently with any other use of the same handle.
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
            "lco" => add_option(&mut job.layer_options, name, value)?,
            "dsco" => add_option(&mut job.dataset_options, name, value)?,
            _ => *optional_setting(job, name)? = value,
        }
        Ok(())
    })
}

/// Adds a creation option to `list` (`name`: the setting), or clears the list for NULL.
fn add_option(list: &mut Vec<String>, name: &str, value: Option<String>) -> Result<(), Failure> {
    match value {
        Some(option) => {
            crate::job::check_creation_option(name, &option)
                .map_err(|message| Failure::new(Status::INVALID_ARGUMENT, message))?;
            list.push(option);
        }
        None => list.clear(),
    }
    Ok(())
}

fn optional_setting<'a>(job: &'a mut Job, name: &str) -> Result<&'a mut Option<String>, Failure> {
    Ok(match name {
        "src_layer" => &mut job.src_layer,
        "where" => &mut job.where_clause,
        "id_field" => &mut job.id_field,
        "group_field" => &mut job.group_field,
        "pin_col_field" => &mut job.pin_col_field,
        "pin_row_field" => &mut job.pin_row_field,
        "format" => &mut job.format,
        "layer_name" => &mut job.layer_name,
        "s_srs" => &mut job.source_srs,
        "target_srs" => &mut job.target_srs,
        "json_report" => &mut job.json_report,
        "svg" => &mut job.svg,
        "hexjson" => &mut job.hexjson,
        "label_field" => &mut job.label_field,
        _ => {
            return Err(Failure::new(
                Status::INVALID_ARGUMENT,
                format!("unknown job setting {name:?}; the settings are {SETTINGS}"),
            ))
        }
    })
}

/// Whether what is at the outputs may be replaced (the command line's -overwrite): the layer of a
/// dataset that holds several (GeoPackage; the other layers are kept), else the whole file, never
/// a file that holds other layers; only once the run has succeeded. Off when the job is made.
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

/// Whether the layer is added to the existing destination dataset (the command line's
/// -update); the run then fails if the destination does not exist, cannot hold another layer,
/// or has a layer of that name (unless overwrite is on too, which replaces it). Off when the
/// job is made.
///
/// Thread safety: not concurrently with any other use of the same handle.
#[must_use]
#[no_mangle]
pub unsafe extern "C" fn snakegrid_job_set_update(job: *mut DatasetJob, update: bool) -> Status {
    guard("snakegrid_job_set_update", || {
        // SAFETY: a live handle nobody else uses meanwhile (header contract).
        unsafe { handle::get_mut(job, "job") }?.update = update;
        Ok(())
    })
}
