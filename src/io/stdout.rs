//! Standard output as an output, spelled `/vsistdout/` as ogr2ogr spells it
//! (`snakegrid -f GeoJSON /vsistdout/ SRC | jq …`, or `-json /vsistdout/`). The output is made
//! in a temporary folder like any other, staged and moved into place there, and only once the
//! whole run has succeeded are its bytes copied to standard output: a failed or cancelled run
//! writes nothing there.

use super::Error;
use crate::job::Job;
use gdal::{Driver, Metadata};
use std::path::PathBuf;

/// The path that names standard output.
pub const STDOUT: &str = "/vsistdout/";

/// Whether one of `job`'s outputs is standard output, so that the command line's summary goes
/// to standard error instead.
pub fn sends_to_stdout(job: &Job) -> bool {
    [
        Some(&job.dst),
        job.json_report.as_ref(),
        job.svg.as_ref(),
        job.hexjson.as_ref(),
    ]
    .into_iter()
    .any(|path| path.is_some_and(|p| p == STDOUT))
}

/// An output made in a temporary folder, to be sent to standard output.
pub(crate) struct Stream {
    /// Removed, with everything in it, when the stream is dropped.
    _folder: tempfile::TempDir,
    what: &'static str,
    path: PathBuf,
}

/// `job` with its output at [`STDOUT`] (at most one of the destination, `-json`, `-svg` and
/// `-hexjson`) made in a temporary folder instead, and that output's [`Stream`]; `job` as it is
/// when none goes to standard output. `driver` is the destination's.
pub(crate) fn redirect(job: &Job, driver: &Driver) -> Result<(Job, Option<Stream>), Error> {
    let destination_name = format!("grid.{}", driver_extension(driver));
    let outputs = [
        ("destination", Some(&job.dst), destination_name.as_str()),
        ("JSON report", job.json_report.as_ref(), "report.json"),
        ("picture", job.svg.as_ref(), "picture.svg"),
        ("HexJSON", job.hexjson.as_ref(), "layout.hexjson"),
    ];
    let mut to_stdout = (0..outputs.len()).filter(|&k| outputs[k].1.is_some_and(|p| p == STDOUT));
    let Some(k) = to_stdout.next() else {
        return Ok((job.clone(), None));
    };
    let (what, _, name) = outputs[k];
    if let Some(other) = to_stdout.next() {
        return Err(Error::InvalidParameter(format!(
            "the {what} and the {} both go to standard output ({STDOUT}); only one can",
            outputs[other].0
        )));
    }
    if k == 0 {
        if job.format.is_none() {
            return Err(Error::InvalidParameter(format!(
                "standard output ({STDOUT}) has no extension to tell the format: give -f \
                 (e.g. -f GeoJSON)"
            )));
        }
        if job.update {
            return Err(Error::InvalidParameter(format!(
                "-update adds a layer to an existing dataset, and standard output ({STDOUT}) \
                 holds none"
            )));
        }
    }
    let folder = tempfile::Builder::new()
        .prefix("snakegrid-stdout-")
        .tempdir()
        .map_err(|e| Error::Io(format!("cannot make a temporary folder for {STDOUT}: {e}")))?;
    let made = folder.path().join(name);
    let made_text = made.to_string_lossy().into_owned();
    let mut work = job.clone();
    match k {
        0 => work.dst = made_text,
        1 => work.json_report = Some(made_text),
        2 => work.svg = Some(made_text),
        _ => work.hexjson = Some(made_text),
    }
    let stream = Stream {
        _folder: folder,
        what,
        path: made,
    };
    Ok((work, Some(stream)))
}

impl Stream {
    /// Whether it is the destination dataset (which must be one file).
    pub(crate) fn is_destination(&self) -> bool {
        self.what == "destination"
    }

    /// Copies the finished output to standard output.
    pub(crate) fn send(self) -> Result<(), Error> {
        use std::io::Write;
        let cannot = |e: std::io::Error| {
            Error::Io(format!(
                "cannot write the {} to standard output: {e}",
                self.what
            ))
        };
        let mut file = std::fs::File::open(&self.path).map_err(cannot)?;
        let mut out = std::io::stdout().lock();
        std::io::copy(&mut file, &mut out).map_err(cannot)?;
        out.flush().map_err(cannot)
    }
}

/// The file extension the driver writes (`geojson`, `gpkg`, `csv`), or `out`.
fn driver_extension(driver: &Driver) -> String {
    let listed = (driver.metadata_item("DMD_EXTENSION", ""))
        .or_else(|| driver.metadata_item("DMD_EXTENSIONS", ""))
        .unwrap_or_default();
    listed
        .split_whitespace()
        .next()
        .filter(|e| e.chars().all(|c| c.is_ascii_alphanumeric()))
        .unwrap_or("out")
        .to_owned()
}
