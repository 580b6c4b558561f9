//! Reading regions from, and writing grid maps to, any vector dataset GDAL reads or writes.
//! The only module that uses GDAL. The command line and the C API's dataset entry point both
//! call [`run`], so they behave the same.
//!
//! - [`read`]: open the source, pick the layer, `-where`, features → regions;
//! - [`crs`]: the working CRS (`-s_srs`, `-t_srs`, the automatic equal-area projection);
//! - [`options`]: creation options, the user's (`-dsco`, `-lco`) and snakegrid's own;
//! - [`probe`]: what the output driver makes of the layer, tried in memory before the run (on
//!   disk for a driver that cannot write in memory);
//! - [`destination`]: what may happen to what is already at an output (`-update`, `-overwrite`);
//! - [`write`]: the grid layer with the source attributes, cell and metric fields, metadata;
//! - [`readback`]: an output read back to prove it holds what it claims;
//! - [`staging`]: the folders outputs are written in, locked while a run lives;
//! - [`commit`]: every output moved into place together, or none;
//! - [`report`]: the JSON report, the layer metadata and the printed summary;
//! - [`svg`]: the side-by-side picture;
//! - [`session`]: GDAL's messages caught and a fixed date for the length of a run.

mod commit;
mod crs;
mod destination;
mod options;
mod paths;
mod probe;
mod read;
mod readback;
mod report;
mod session;
mod staging;
mod stdout;
mod svg;
mod write;

pub use stdout::{sends_to_stdout, STDOUT};

pub use report::summary;

use crate::core::params::CellShape;
use crate::core::{hexjson, Error, GridMap, Params, Progress, Region};
pub use crate::job::Job;
use commit::Staged;
use destination::{Destination, Mode, Plan};
use gdal::spatial_ref::SpatialRef;
use gdal::vector::LayerAccess;
use gdal::vector::{Feature, Layer};
use gdal::Driver;
use geo::CoordsIter;
use paths::SourceFiles;
use session::Session;
use staging::Staging;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use write::{Container, Row};

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

/// The progress bar's shares of reading (before) and writing (after) the layout: each stage's
/// expected time against the layout's ([`crate::expected_seconds`]), so that the bar
/// follows the clock both on dense boundaries, where starting and reading are a sixth of the run
/// (the US states at 10⁶ vertices), and on many regions, where they are a twentieth.
#[derive(Clone, Copy)]
struct BarShares {
    read: f64,
    write: f64,
}

impl BarShares {
    /// Starting GDAL and reading: 55 ms, 0.06 µs a vertex and 5 µs a feature; writing: 10 ms
    /// and 12 µs a feature (the US counties and states, as given and densified to 10⁶ vertices,
    /// BENCHMARKS.md "Progress").
    fn of(regions: &[Region], params: &Params) -> BarShares {
        let features = regions.len() as f64;
        let vertices: usize = regions.iter().map(|r| r.geometry.coords_count()).sum();
        let read = 0.055 + 0.06e-6 * vertices as f64 + 5e-6 * features;
        let write = 0.01 + 12e-6 * features;
        let total = read + crate::expected_seconds(regions, params) + write;
        BarShares {
            read: read / total,
            write: write / total,
        }
    }
}

/// Reads the source, runs the method, writes the destination (and the report and picture when
/// asked). On any error or cancellation every existing output is left as it was, and nothing
/// new is left behind.
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
    // Everything that can be refused without reading a feature is refused before any work.
    for (path, what, name) in [
        (&job.src, "source", "SRC"),
        (&job.dst, "destination", "DST"),
    ] {
        if path.is_empty() {
            return Err(Error::InvalidParameter(format!(
                "no {what} dataset is given ({name}; \"{}\" of a C API job)",
                name.to_ascii_lowercase()
            )));
        }
    }
    for (flag, list) in [
        ("-dsco", &job.dataset_options),
        ("-lco", &job.layer_options),
    ] {
        for option in list {
            crate::job::check_creation_option(flag, option).map_err(Error::InvalidParameter)?;
        }
    }
    if job.hexjson.is_some() && params.cell == CellShape::Square {
        return Err(Error::InvalidParameter(hexjson::NEEDS_HEXAGONS.into()));
    }
    let driver = write::driver(job.format.as_deref(), &job.dst)?;
    let format = driver.short_name();
    // An output at /vsistdout/ is made in a temporary folder, and sent once the run succeeds.
    let asked = job;
    let (mut redirected, stream) = stdout::redirect(job, &driver)?;
    redirected.dst = paths::through_link(&redirected.dst);
    for path in [
        &mut redirected.json_report,
        &mut redirected.svg,
        &mut redirected.hexjson,
    ] {
        *path = path.as_deref().map(paths::through_link);
    }
    let job = &redirected;
    let dataset = read::open(session, &job.src)?;
    let source_files = SourceFiles::of(&dataset, &job.src);
    let outputs = outputs(job);
    for (what, path) in &outputs {
        source_files.refuse(what, Path::new(path))?;
    }
    on_disk(&outputs)?;
    distinct_outputs(&outputs)?;
    let file_name = Path::new(&job.dst)
        .file_name()
        .ok_or_else(|| Error::Io(format!("the destination {:?} is not a file name", job.dst)))?;

    let (mut layer, layer_note) = read::layer(&dataset, job.src_layer.as_deref())?;
    let source_layer = layer.name();
    let layer_name = job
        .layer_name
        .clone()
        .unwrap_or_else(|| source_layer.clone());
    if layer_name.trim().is_empty() {
        return Err(Error::InvalidParameter(
            "the output layer's name is empty: give -nln a name".into(),
        ));
    }
    let source_names: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
    let taken: Vec<&str> = (source_names.iter().map(String::as_str))
        .chain(write::computed_fields().map(|(name, _)| name))
        .collect();
    let layer_options = |description: &str| {
        options::layer_options(&driver, &job.layer_options, &taken, description)
    };
    let trial_options = layer_options("snakegrid grid map");
    let dataset_options = options::dataset_options(&driver, &job.dataset_options);
    let trial = probe::Trial {
        session,
        driver: &driver,
        dataset_options: &dataset_options,
        layer_options: &trial_options,
        layer: &layer_name,
        file_name,
    };
    let fields = trial.fields(layer.defn())?;
    if stream.as_ref().is_some_and(|s| s.is_destination()) && fields.files > 1 {
        return Err(Error::Io(format!(
            "the {format} format writes a dataset of {} files, which cannot go to standard \
             output ({STDOUT}) as one stream; give a format of one file (e.g. -f GeoJSON, \
             -f FlatGeobuf, -f CSV)",
            fields.files
        )));
    }
    let mode = Mode::of(job.update, job.overwrite);
    let destination = Destination::dataset(
        session,
        &job.dst,
        mode,
        &driver,
        &layer_name,
        fields.layers_in_place,
    )?;
    let extra = |path: &Option<String>, what| {
        path.as_deref()
            .map(|p| Destination::file(p, what, mode))
            .transpose()
    };
    let json_destination = extra(&job.json_report, "JSON report")?;
    let svg_destination = extra(&job.svg, "picture")?;
    let hexjson_destination = extra(&job.hexjson, "HexJSON")?;

    // Staging folders (after removing those that killed runs left), so that a run that cannot
    // write beside an output fails now rather than after the layout.
    let all = std::iter::once(&destination)
        .chain(&json_destination)
        .chain(&svg_destination)
        .chain(&hexjson_destination);
    let folders: BTreeSet<PathBuf> = all.map(|d| staging::folder_of(&d.path)).collect();
    let mut notes: Vec<String> = folders.iter().flat_map(|f| staging::sweep(f)).collect();
    notes.extend(layer_note);
    let dst_staging = Staging::new(&destination.path, "destination")?;
    let stage = |d: Option<Destination>, what| {
        d.map(|d| Staging::new(&d.path, what).map(|s| (d, s)))
            .transpose()
    };
    let json_staging = stage(json_destination, "JSON report")?;
    let svg_staging = stage(svg_destination, "picture")?;
    let hexjson_staging = stage(hexjson_destination, "HexJSON")?;

    step(0.0, "reading")?;
    let Source {
        id_field,
        label_field,
        source_srs,
        features,
        plan,
        regions,
        labels,
        notes: source_notes,
    } = Source::read(session, job, &mut layer, &read::Going::new(progress))?;
    // The ids as the output would store them, before the layout.
    let id_position = id_field.and_then(|i| fields.fields.iter().position(|f| f.source == i));
    let ids: Vec<&str> = regions.iter().map(|r| r.id.as_str()).collect();
    if let Some(position) = id_position {
        let pairs: Vec<(&str, &Feature)> = ids.iter().copied().zip(&features).collect();
        trial.ids(&fields, &pairs, position)?;
    }
    let shares = BarShares::of(&regions, params);
    step(shares.read, "checking geometry")?;

    let layout_share = 1.0 - shares.read - shares.write;
    let map = crate::core::generate(&regions, params, &|fraction, message| {
        progress(shares.read + layout_share * fraction, message)
    })?;

    let grid = StagedGrid {
        session,
        job,
        driver: &driver,
        destination: &destination,
        staging: &dst_staging,
        layer: &layer_name,
        source_layer: &source_layer,
        srs: plan.working.as_ref(),
        fields: &fields,
        dataset_options: &dataset_options,
        layer_options: &layer_options,
        ids: id_position.map(|position| (position, ids.as_slice())),
        write_share: shares.write,
    };
    let (layer_written, grid_notes) = grid.write(params, &map, &features, progress)?;

    let mut all_notes: Vec<String> = source_notes;
    all_notes.extend(map.notes.iter().cloned());
    all_notes.extend(repaired_once_projected(
        &map,
        &features,
        plan.transform.is_some(),
    ));
    all_notes.append(&mut notes);
    all_notes.extend(fields.notes);
    for note in grid_notes {
        if !all_notes.contains(&note) {
            all_notes.push(note);
        }
    }
    let outcome = Outcome {
        map,
        notes: all_notes,
        source_layer,
        layer: layer_written,
        format,
        crs: plan.working.as_ref().map(crs::describe),
    };

    let mut staged = vec![Staged {
        what: "destination",
        destination: destination.path,
        staging: dst_staging,
        displaced: destination.displaced,
    }];
    if let Some((json, staging)) = json_staging {
        let source = report::SourceInfo {
            dataset: &job.src,
            layer: &outcome.source_layer,
            where_clause: job.where_clause.as_deref(),
            id_field: id_field.map(|i| source_names[i].as_str()),
            group_field: job.group_field.as_deref(),
            pin_col_field: job.pin_col_field.as_deref(),
            pin_row_field: job.pin_row_field.as_deref(),
            label_field: label_field.map(|i| source_names[i].as_str()),
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
        // The report names the outputs as asked (/vsistdout/ too).
        let text = report::json(asked, params, &outcome, source, crs, &labels)?;
        staged.push(stage_text("JSON report", json, staging, &text)?);
    }
    if let Some((svg, staging)) = svg_staging {
        let picture = svg::render(&regions, &labels, &outcome.map);
        staged.push(stage_text("picture", svg, staging, &picture)?);
    }
    if let Some((hexjson, staging)) = hexjson_staging {
        let fields = features.iter().map(hexjson_fields).collect();
        let text = hexjson::of_map(&outcome.map, &labels, fields)
            .ok_or_else(|| Error::Internal(hexjson::NEEDS_HEXAGONS.into()))?;
        staged.push(stage_text("HexJSON", hexjson, staging, &text)?);
    }

    // The last chance to cancel; only now does anything appear at, or disappear from, the
    // destinations.
    step(1.0, "moving the outputs into place")?;
    commit::commit(staged, job.overwrite, &source_files)?;
    // Too late to cancel: the outputs are in place.
    if let Some(stream) = stream {
        stream.send()?;
    }
    progress(1.0, "done");
    Ok(outcome)
}

/// The grid layer of a run as it is written in the destination's staging folder.
struct StagedGrid<'a> {
    session: &'a Session,
    job: &'a Job,
    driver: &'a Driver,
    destination: &'a Destination,
    staging: &'a Staging,
    layer: &'a str,
    source_layer: &'a str,
    srs: Option<&'a SpatialRef>,
    /// The fields as the probe found the driver names them.
    fields: &'a probe::Fields,
    /// The dataset creation options of a new dataset ([`options::dataset_options`]).
    dataset_options: &'a [String],
    /// The layer creation options, given the layer's description.
    layer_options: &'a dyn Fn(&str) -> Vec<String>,
    /// The id field's position among the fields, and every region's id in input order.
    ids: Option<(usize, &'a [&'a str])>,
    /// The progress bar's share of the writing, at its end ([`BarShares`]).
    write_share: f64,
}

impl StagedGrid<'_> {
    /// Writes `map`'s cells with the attributes of `features` (in the same order) into the
    /// staging folder, as a new dataset or into a copy of the existing one, and reads it back as
    /// a last guard. Returns the layer's name as written and what the user should know.
    fn write(
        &self,
        params: &Params,
        map: &GridMap,
        features: &[Feature],
        progress: Progress,
    ) -> Result<(String, Vec<String>), Error> {
        let (session, job, destination) = (self.session, self.job, self.destination);
        let format = self.driver.short_name();
        let mut notes = Vec::new();
        // Layer metadata set in an existing GeoPackage makes GDAL rewrite the metadata of
        // every other layer (their timestamps change), so a layer added beside others keeps
        // its metrics in its description only.
        let metadata = match destination.plan {
            Plan::New | Plan::InPlace { alone: true, .. } => {
                let id_field =
                    (self.ids).map(|(position, _)| self.fields.stored[position].as_str());
                report::metadata(job, self.source_layer, id_field, params, map)
            }
            Plan::InPlace { alone: false, .. } => {
                notes.push(format!(
                    "the run's parameters and metrics are not written to the metadata tables of \
                     the existing {:?}, which would change the other layers' metadata: the \
                     layer's description has the metrics, -json the rest",
                    destination.path.display()
                ));
                Vec::new()
            }
        };
        let options = (self.layer_options)(&report::description(map));
        let spec = write::LayerSpec {
            name: self.layer,
            srs: self.srs,
            options: &options,
            fields: &self.fields.fields,
            metadata: &metadata,
        };
        let staged_path = self.staging.path();
        let container = match &destination.plan {
            Plan::New => Container::New {
                driver: self.driver,
                options: self.dataset_options,
            },
            Plan::InPlace { replace, .. } => {
                std::fs::copy(&destination.path, &staged_path).map_err(|e| {
                    Error::Io(format!(
                        "cannot copy the destination {:?} to update it: {e}",
                        destination.path.display()
                    ))
                })?;
                if !job.dataset_options.is_empty() {
                    notes.push(format!(
                        "-dsco is ignored: the layer is added to the existing {:?}",
                        destination.path.display()
                    ));
                }
                Container::Existing {
                    replace: replace.as_deref(),
                }
            }
        };
        let rows: Vec<Row> = map
            .cells
            .iter()
            .zip(features)
            .map(|(cell, source)| Row {
                id: &cell.id,
                source,
                cell: &cell.cell,
                computed: write::computed(cell),
            })
            .collect();
        let write_start = 1.0 - self.write_share;
        let written = write::write(session, &staged_path, &container, &spec, &rows, &|f| {
            progress(write_start + self.write_share * f, "writing")
        })?;
        // The last guard: the staged layer holds every cell, field and id as the probe found.
        if written.fields != self.fields.stored {
            return Err(Error::Io(format!(
                "the {format} driver named the fields {} when writing, but {} when tried",
                written.fields.join(", "),
                self.fields.stored.join(", ")
            )));
        }
        let expected = readback::Expected {
            driver: &format,
            layer: &written.layer,
            fields: &self.fields.stored,
            ids: self.ids,
            features: rows.len(),
        };
        let layer = if readback::can_read(self.driver) {
            readback::read_back(session, &staged_path, &expected)?
        } else {
            notes.push(format!(
                "GDAL cannot read the {format} format, so what it stored (the ids among it) \
                 could not be checked"
            ));
            written.layer
        };
        // GDAL's warnings, naming the destination rather than its staged copy.
        let staged_name = staged_path.display().to_string();
        notes.extend(
            written
                .notes
                .into_iter()
                .map(|note| note.replace(&staged_name, &job.dst)),
        );
        Ok((layer, notes))
    }
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
    let (mut layer, layer_note) = read::layer(&dataset, job.src_layer.as_deref())?;
    let source = Source::read(&session, job, &mut layer, &read::Going::new(&|_, _| true))?;
    Ok(SourceRegions {
        regions: source.regions,
        labels: source.labels,
        notes: layer_note.into_iter().chain(source.notes).collect(),
    })
}

/// A source layer read, checked and projected.
struct Source<'l> {
    id_field: Option<usize>,
    label_field: Option<usize>,
    source_srs: Option<SpatialRef>,
    features: Vec<Feature<'l>>,
    plan: crs::Plan,
    regions: Vec<Region>,
    labels: Vec<String>,
    /// What the user should know about how the source was read (its CRS).
    notes: Vec<String>,
}

impl<'l> Source<'l> {
    /// `going` says whether to go on, asked as the features are read.
    fn read(
        session: &Session,
        job: &Job,
        layer: &'l mut Layer,
        going: &read::Going,
    ) -> Result<Source<'l>, Error> {
        let fields: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
        let id_field = job
            .id_field
            .as_deref()
            .map(|name| read::require_field(&fields, name, "-id"))
            .transpose()?;
        let group_field = job
            .group_field
            .as_deref()
            .map(|name| read::require_field(&fields, name, "-group"))
            .transpose()?;
        let label_field = match job.label_field.as_deref() {
            Some(name) => Some(read::require_field(&fields, name, "-label")?),
            None => ["abbr", "name"]
                .iter()
                .find_map(|name| read::field_index(&fields, name)),
        };
        let mut notes = Vec::new();
        let source_srs = match job.source_srs.as_deref() {
            Some(definition) => {
                let assigned = crs::parse(session, definition)?;
                notes.push(format!(
                    "the source is taken to be in {} (-s_srs)",
                    crs::describe(&assigned)
                ));
                Some(assigned)
            }
            None => layer.spatial_ref().map(crs::traditional),
        };
        let features = read::features(session, layer, job.where_clause.as_deref(), going)?;
        let pin = match (job.pin_col_field.as_deref(), job.pin_row_field.as_deref()) {
            (Some(col), Some(row)) => Some((
                read::require_field(&fields, col, "-pin_col")?,
                read::require_field(&fields, row, "-pin_row")?,
            )),
            (None, None) => None,
            _ => {
                return Err(Error::InvalidParameter(
                    "-pin_col and -pin_row go together: name both fields or neither".into(),
                ))
            }
        };
        let setting_fields = read::SettingFields {
            id: id_field,
            label: label_field,
            group: group_field,
            pin,
        };
        let (checked, admission_note) = read::check(&features, &setting_fields, going)?;
        notes.extend(admission_note);
        // Read as drawn only when the working-CRS rule needs the extents.
        let drawn = std::cell::OnceCell::new();
        let drawn_once = || drawn.get_or_init(|| read::drawn(&checked));
        let plan = crs::plan(
            session,
            source_srs.as_ref(),
            job.target_srs.as_deref(),
            || read::boxes(drawn_once()),
        )?;
        let seam = plan.seam.map(|central| (central, drawn_once().as_slice()));
        let regions = read::regions(session, &checked, plan.transform.as_ref(), seam, going)?;
        let labels = checked.into_iter().map(|c| c.label).collect();
        notes.extend(plan.note.clone());
        Ok(Source {
            id_field,
            label_field,
            source_srs,
            features,
            plan,
            regions,
            labels,
            notes,
        })
    }
}

/// The regions whose polygons the core repaired but which are valid as drawn in the source's
/// CRS (GEOS's validity, asked of the source features as read): projecting moves every vertex
/// and keeps every edge straight, so a ring that passes close by itself can cross itself once
/// projected (Natural Earth's Sudan and Mozambique in Equal Earth). The repair notes give the
/// crossings in the working CRS and read as if the source were at fault; this says it is not.
/// `None` when the layer was not projected or no such region was repaired.
fn repaired_once_projected(map: &GridMap, features: &[Feature], projected: bool) -> Option<String> {
    if !projected {
        return None;
    }
    let valid_as_drawn: Vec<&str> = (map.cells.iter().zip(features))
        .filter(|(cell, feature)| {
            cell.repair.is_some() && feature.geometry().is_some_and(|g| g.is_valid())
        })
        .map(|(cell, _)| cell.id.as_str())
        .collect();
    let (first, count) = (valid_as_drawn.first()?, valid_as_drawn.len());
    let named = match count {
        1 => format!("feature {first} is"),
        2..=10 => format!("features {} are", valid_as_drawn.join(", ")),
        _ => format!(
            "features {} and {} more are",
            valid_as_drawn[..10].join(", "),
            count - 10
        ),
    };
    Some(format!(
        "{named} valid as drawn in the source's CRS: a ring crosses itself only once projected \
         to the working CRS (edges that pass close by each other), so the repair, and the \
         crossing its note gives, are in the working CRS; there is nothing to fix in the source"
    ))
}

/// Writes `text` as the output `what` in its staging folder.
fn stage_text(
    what: &'static str,
    destination: Destination,
    staging: Staging,
    text: &str,
) -> Result<Staged, Error> {
    std::fs::write(staging.path(), text)
        .map_err(|e| Error::Io(format!("cannot write {:?}: {e}", staging.path().display())))?;
    Ok(Staged {
        what,
        destination: destination.path,
        staging,
        displaced: destination.displaced,
    })
}

/// The outputs a job writes, each with what it is called in messages.
fn outputs(job: &Job) -> Vec<(&'static str, &str)> {
    let extras = [
        ("JSON report", &job.json_report),
        ("picture", &job.svg),
        ("HexJSON", &job.hexjson),
    ];
    std::iter::once(("destination", job.dst.as_str()))
        .chain(
            extras
                .into_iter()
                .filter_map(|(what, path)| Some((what, path.as_deref()?))),
        )
        .collect()
}

/// Refuses an output in one of GDAL's virtual file systems (`/vsizip/`, `/vsimem/`, …), which
/// the run cannot make beside and then rename into place: the message says so, where the
/// folder checks would call it a folder that does not exist. Standard output (`/vsistdout/`)
/// is made in a temporary folder and sent once complete ([`stdout`]).
fn on_disk(outputs: &[(&str, &str)]) -> Result<(), Error> {
    match (outputs.iter()).find(|(_, path)| path.starts_with("/vsi")) {
        Some((what, path)) => Err(Error::Io(format!(
            "the {what} {path:?} is in one of GDAL's virtual file systems, which snakegrid does \
             not write to: every output is made beside its path and renamed into place once \
             complete, so that a failed run leaves nothing half-written; write a file, or to \
             standard output ({STDOUT}, with -f)"
        ))),
        None => Ok(()),
    }
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

/// A feature's string and number fields, as HexJSON carries them (it keeps the short strings).
fn hexjson_fields(feature: &Feature) -> Vec<(String, serde_json::Value)> {
    use gdal::vector::FieldValue;
    (feature.fields())
        .filter_map(|(name, value)| {
            let value = match value? {
                FieldValue::StringValue(s) => serde_json::Value::from(s),
                FieldValue::IntegerValue(v) => v.into(),
                FieldValue::Integer64Value(v) => v.into(),
                FieldValue::RealValue(v) => serde_json::Number::from_f64(v)?.into(),
                _ => return None,
            };
            Some((name, value))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{Coord, LineString, MultiPolygon, Polygon};

    /// `count` regions side by side, each a square whose boundary has `vertices` vertices.
    fn squares(count: usize, vertices: usize) -> Vec<Region> {
        (0..count)
            .map(|k| {
                let side = vertices / 4;
                let x0 = k as f64;
                let t = |i: usize| i as f64 / side as f64;
                let ring: Vec<Coord<f64>> = (0..side)
                    .map(|i| Coord {
                        x: x0 + t(i),
                        y: 0.0,
                    })
                    .chain((0..side).map(|i| Coord {
                        x: x0 + 1.0,
                        y: t(i),
                    }))
                    .chain((0..side).map(|i| Coord {
                        x: x0 + 1.0 - t(i),
                        y: 1.0,
                    }))
                    .chain((0..side).map(|i| Coord {
                        x: x0,
                        y: 1.0 - t(i),
                    }))
                    .collect();
                Region {
                    id: k.to_string(),
                    geometry: MultiPolygon(vec![Polygon::new(LineString(ring), vec![])]),
                    group: None,
                    pin: None,
                }
            })
            .collect()
    }

    #[test]
    fn reading_takes_more_of_the_bar_the_denser_the_boundaries() {
        let params = Params::default();
        let plain = BarShares::of(&squares(1000, 40), &params);
        let dense = BarShares::of(&squares(1000, 4000), &params);
        for shares in [plain, dense] {
            assert!(shares.read > 0.0 && shares.write > 0.0);
            assert!(shares.read + shares.write < 1.0);
        }
        assert!(dense.read > plain.read, "{} {}", plain.read, dense.read);
        // Writing follows the regions alone, so its share falls as the rest grows.
        assert!(dense.write < plain.write, "{} {}", plain.write, dense.write);
    }
}
