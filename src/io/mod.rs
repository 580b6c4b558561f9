//! Reading regions from, and writing grid maps to, any vector dataset GDAL reads or writes.
//! The only module that uses GDAL. The command line and the C API's dataset entry point both
//! call [`run`], so they behave the same.
//!
//! - [`read`]: open the source, pick the layer, `-where`, features → regions;
//! - [`crs`]: the working CRS (automatic equal-area projection of geographic layers, `-t_srs`);
//! - [`write`]: the grid layer with the source attributes, cell and metric fields, metadata;
//! - [`output`]: staging folders, so an output appears whole or not at all;
//! - [`report`]: the JSON report, the layer metadata and the printed summary;
//! - [`svg`]: the side-by-side picture;
//! - [`session`]: GDAL's messages caught and a fixed date for the length of a run.

mod crs;
mod output;
mod paths;
mod read;
mod report;
mod session;
mod svg;
mod write;

pub use report::summary;
pub use write::{CELL_DISP, GRID_COL, GRID_ROW, NBR_KEPT, ORIENT_ERR};

use crate::core::{Error, GridMap, Params, Progress, Region};
pub use crate::job::Job;
use gdal::spatial_ref::SpatialRef;
use gdal::vector::LayerAccess;
use gdal::vector::{Feature, Layer};
use output::{Staged, Target};
use paths::SourceFiles;
use session::Session;
use std::path::{Path, PathBuf};

/// What a successful run produced.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub map: GridMap,
    /// Things the user should know, e.g. "projected from EPSG:4326 to ...".
    pub notes: Vec<String>,
    /// The source layer that was read.
    pub source_layer: String,
    /// The layer written (as the driver named it: a Shapefile's layer is its file name).
    pub layer: String,
    /// Short name of the GDAL driver that wrote the destination.
    pub format: String,
    /// The working CRS, which the cells and the output are in (`None`: the source had none).
    pub crs: Option<String>,
}

/// Share of the progress bar for reading (before) and writing (after) the layout.
const READ_SHARE: f64 = 0.05;
const WRITE_SHARE: f64 = 0.08;

/// Reads the source, runs the method, writes the destination (and the report and picture when
/// asked). On any error nothing is left at the destination.
pub fn run(job: &Job, params: &Params, progress: Progress) -> Result<Outcome, Error> {
    params.validate().map_err(Error::InvalidParameter)?;
    let session = Session::start();
    run_in(&session, job, params, progress)
}

fn run_in(
    session: &Session,
    job: &Job,
    params: &Params,
    progress: Progress,
) -> Result<Outcome, Error> {
    let step = |fraction: f64, message: &str| {
        if progress(fraction, message) {
            Ok(())
        } else {
            Err(Error::Cancelled)
        }
    };
    // Everything that can be refused without reading is refused before any work.
    let driver = write::driver(job.format.as_deref(), &job.dst)?;
    let dataset = read::open(session, &job.src)?;
    let source_files = SourceFiles::of(&dataset, &job.src);
    let outputs = outputs(job);
    for (what, path) in &outputs {
        source_files.refuse(what, Path::new(path))?;
    }
    distinct_outputs(&outputs)?;
    let target = Target::check(&job.dst, "destination", job.overwrite, true)?;
    let check_extra = |path: &Option<String>, what| {
        path.as_deref()
            .map(|p| Target::check(p, what, job.overwrite, false))
            .transpose()
    };
    let json_target = check_extra(&job.json_report, "JSON report")?;
    let svg_target = check_extra(&job.svg, "picture")?;

    let mut layer = read::layer(&dataset, job.src_layer.as_deref())?;
    let source_layer = layer.name();
    let Source {
        fields,
        id_field,
        label_field,
        source_srs,
        features,
        plan,
        regions,
        labels,
    } = Source::read(session, job, &mut layer)?;
    step(READ_SHARE, "laying out")?;

    let layout_share = 1.0 - READ_SHARE - WRITE_SHARE;
    let map = crate::core::generate(&regions, params, &|fraction, message| {
        progress(READ_SHARE + layout_share * fraction, message)
    })?;

    let staged = Staged::new(target)?;
    let layer_name = job.layer_name.as_deref().unwrap_or(&source_layer);
    let metadata = report::metadata(job, &source_layer, params, &map);
    let description = report::description(&map);
    let spec = write::LayerSpec {
        name: layer_name,
        source_fields: &fields,
        srs: plan.working.as_ref(),
        metadata: &metadata,
        description: &description,
    };
    let write_start = 1.0 - WRITE_SHARE;
    let written = write::write(
        session,
        &staged.path(),
        &driver,
        &spec,
        &features,
        &map,
        &|f| progress(write_start + WRITE_SHARE * f, "writing"),
    )?;
    let mut notes: Vec<String> = plan.note.into_iter().collect();
    notes.extend(map.notes.iter().cloned());
    notes.extend(written.notes);
    let outcome = Outcome {
        map,
        notes,
        source_layer,
        layer: written.layer,
        format: driver.short_name(),
        crs: plan.working.as_ref().map(crs::describe),
    };

    let json = json_target
        .map(|target| {
            let source = report::SourceInfo {
                dataset: &job.src,
                layer: &outcome.source_layer,
                where_clause: job.where_clause.as_deref(),
                id_field: id_field.map(|i| fields[i].as_str()),
                label_field: label_field.map(|i| fields[i].as_str()),
                features: features.len(),
            };
            let crs = report::CrsInfo {
                source: source_srs.as_ref().map(crs::describe),
                working: outcome.crs.clone(),
                working_projjson: plan
                    .working
                    .as_ref()
                    .and_then(|s| s.to_projjson().ok())
                    .and_then(|text| serde_json::from_str(&text).ok()),
                projected: plan.transform.is_some(),
            };
            let text = report::json(job, params, &outcome, source, crs, &labels)?;
            stage_text(target, &text)
        })
        .transpose()?;
    let picture = svg_target
        .map(|target| stage_text(target, &svg::render(&regions, &labels, &outcome.map)))
        .transpose()?;

    // Only now does anything appear at, or disappear from, the destinations.
    staged.commit(session, job.overwrite, &source_files)?;
    for extra in json.into_iter().chain(picture) {
        extra.commit(session, job.overwrite, &source_files)?;
    }
    // Too late to cancel: the outputs are in place.
    progress(1.0, "done");
    Ok(outcome)
}

/// The regions of a job's source layer, as the method receives them, and what the user should
/// know about how they were read (e.g. the automatic projection).
#[derive(Clone, Debug)]
pub struct SourceRegions {
    pub regions: Vec<Region>,
    /// The short label of each region (`-label`, else `abbr`, else `name`, else its id).
    pub labels: Vec<String>,
    pub notes: Vec<String>,
}

/// Reads and projects the regions of `job`'s source exactly as [`run`] does, without running
/// the method or writing anything.
pub fn read_regions(job: &Job) -> Result<SourceRegions, Error> {
    let session = Session::start();
    let dataset = read::open(&session, &job.src)?;
    let mut layer = read::layer(&dataset, job.src_layer.as_deref())?;
    let source = Source::read(&session, job, &mut layer)?;
    Ok(SourceRegions {
        regions: source.regions,
        labels: source.labels,
        notes: source.plan.note.into_iter().collect(),
    })
}

/// A source layer read, checked and projected.
struct Source<'l> {
    fields: Vec<String>,
    id_field: Option<usize>,
    label_field: Option<usize>,
    source_srs: Option<SpatialRef>,
    features: Vec<Feature<'l>>,
    plan: crs::Plan,
    regions: Vec<Region>,
    labels: Vec<String>,
}

impl<'l> Source<'l> {
    fn read(session: &Session, job: &Job, layer: &'l mut Layer) -> Result<Source<'l>, Error> {
        let fields: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
        let id_field = job
            .id_field
            .as_deref()
            .map(|name| read::require_field(&fields, name, "-id"))
            .transpose()?;
        let label_field = match job.label_field.as_deref() {
            Some(name) => Some(read::require_field(&fields, name, "-label")?),
            None => ["abbr", "name"]
                .iter()
                .find_map(|name| read::field_index(&fields, name)),
        };
        let source_srs = layer.spatial_ref().map(crs::traditional);
        let features = read::features(session, layer, job.where_clause.as_deref())?;
        let checked = read::check(&features, id_field, label_field)?;
        let plan = crs::plan(
            session,
            source_srs.as_ref(),
            job.target_srs.as_deref(),
            || read::boxes(&checked),
        )?;
        let regions = read::regions(session, &checked, plan.transform.as_ref())?;
        let labels = checked.into_iter().map(|c| c.label).collect();
        Ok(Source {
            fields,
            id_field,
            label_field,
            source_srs,
            features,
            plan,
            regions,
            labels,
        })
    }
}

/// Writes `text` to a staged copy of `target`.
fn stage_text(target: Target, text: &str) -> Result<Staged, Error> {
    let staged = Staged::new(target)?;
    std::fs::write(staged.path(), text)
        .map_err(|e| Error::Io(format!("cannot write {:?}: {e}", staged.path().display())))?;
    Ok(staged)
}

/// The outputs a job writes, each with what it is called in messages.
fn outputs(job: &Job) -> Vec<(&'static str, &str)> {
    let extras = [("JSON report", &job.json_report), ("picture", &job.svg)];
    std::iter::once(("destination", job.dst.as_str()))
        .chain(
            extras
                .into_iter()
                .filter_map(|(what, path)| Some((what, path.as_deref()?))),
        )
        .collect()
}

/// Refuses a run two of whose outputs are one file, however spelled.
fn distinct_outputs(outputs: &[(&str, &str)]) -> Result<(), Error> {
    let resolved: Vec<Vec<PathBuf>> = outputs
        .iter()
        .map(|(_, path)| paths::canonical(Path::new(path)))
        .collect();
    for (k, (what, path)) in outputs.iter().enumerate() {
        for (other, (other_what, other_path)) in outputs.iter().enumerate().skip(k + 1) {
            if resolved[k].iter().any(|p| resolved[other].contains(p)) {
                return Err(Error::Io(format!(
                    "the {what} {path:?} and the {other_what} {other_path:?} are the same file"
                )));
            }
        }
    }
    Ok(())
}
