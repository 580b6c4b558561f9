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
    /// Field whose regions keep together (`-group`, method.md §10); no groups when `None`.
    pub group_field: Option<String>,
    /// Fields holding each pinned region's cell, column and row (`-pin_col`, `-pin_row`,
    /// method.md §10): whole numbers, null for a free region. Both or neither.
    pub pin_col_field: Option<String>,
    pub pin_row_field: Option<String>,
    /// Destination dataset path.
    pub dst: String,
    /// GDAL driver short name (`-f`); guessed from the extension (refused when no
    /// driver writes it), else GeoPackage, when `None`.
    pub format: Option<String>,
    /// Output layer name (`-nln`); the source layer's name when `None`.
    pub layer_name: Option<String>,
    /// Replace what is at the outputs (`-overwrite`), only once the run has succeeded: the layer
    /// of a dataset that holds several (GeoPackage), else the whole file.
    pub overwrite: bool,
    /// Add the layer to the existing destination dataset (`-update`); refused when it has a
    /// layer of that name, unless `overwrite`.
    pub update: bool,
    /// The source's CRS (`-s_srs`), any definition GDAL accepts, in place of the one it has.
    pub source_srs: Option<String>,
    /// Working CRS (`-t_srs`): any definition GDAL accepts. A geographic source is projected to
    /// the equal-area CRS of [`crate::crs::working_crs`] when `None`.
    pub target_srs: Option<String>,
    /// Machine-readable report (`-json FILE`).
    pub json_report: Option<String>,
    /// Picture of the source and the grid map side by side (`-svg FILE`).
    pub svg: Option<String>,
    /// The layout as HexJSON, for hexagonal cells (`-hexjson FILE`).
    pub hexjson: Option<String>,
    /// Short label field for the picture (`-label`).
    pub label_field: Option<String>,
    /// Dataset creation options, NAME=VALUE (`-dsco`).
    pub dataset_options: Vec<String>,
    /// Layer creation options, NAME=VALUE (`-lco`); they take precedence over snakegrid's own.
    pub layer_options: Vec<String>,
}

/// Checks that `text` is `NAME=VALUE`, as `-lco` and `-dsco` take it; `flag` names the option
/// (`-lco`, or the C API's `lco`) in the message.
pub fn check_creation_option(flag: &str, text: &str) -> Result<(), String> {
    match text.split_once('=') {
        Some((name, _)) if !name.trim().is_empty() => Ok(()),
        _ => Err(format!(
            "{flag} {text:?}: a creation option is written NAME=VALUE"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_creation_option_is_name_equals_value() {
        assert!(check_creation_option("-lco", "SPATIAL_INDEX=NO").is_ok());
        assert!(check_creation_option("-lco", "DESCRIPTION=").is_ok());
        let error = check_creation_option("-dsco", "VERSION").unwrap_err();
        assert_eq!(
            error,
            "-dsco \"VERSION\": a creation option is written NAME=VALUE"
        );
        assert!(check_creation_option("lco", "=YES").is_err());
    }
}
