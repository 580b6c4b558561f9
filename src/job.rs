//! What a dataset-to-dataset run is asked to do: a plain description, shared by the command line
//! and the C API's dataset job, which [`crate::io::run`] carries out (with the `gdal` feature).

/// One dataset-to-dataset run, as `snakegrid [options] DST SRC [SRC_LAYER]` describes it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Job {
    /// Source dataset: file, folder or connection string.
    pub src: String,
    /// Source layer name; the first layer when `None`.
    pub src_layer: Option<String>,
    /// OGR SQL attribute filter (`-where`).
    pub where_clause: Option<String>,
    /// Field holding the unique region id (`-id`); the feature id when `None`.
    pub id_field: Option<String>,
    /// Destination dataset path.
    pub dst: String,
    /// GDAL driver short name (`-f`); guessed from the extension, else GeoPackage, when `None`.
    pub format: Option<String>,
    /// Output layer name (`-nln`); the source layer's name when `None`.
    pub layer_name: Option<String>,
    /// Replace an existing destination (`-overwrite`), only once the run has succeeded.
    pub overwrite: bool,
    /// Working CRS (`-t_srs`): any definition GDAL accepts. A geographic source is projected to
    /// a Lambert azimuthal equal-area CRS at its centre when `None`.
    pub target_srs: Option<String>,
    /// Machine-readable report (`-json FILE`).
    pub json_report: Option<String>,
    /// Picture of the source and the grid map side by side (`-svg FILE`).
    pub svg: Option<String>,
    /// Short label field for the picture (`-label`).
    pub label_field: Option<String>,
}
