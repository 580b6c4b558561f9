//! Creation options: the user's `-dsco` and `-lco` (NAME=VALUE, as ogr2ogr takes them), the layer
//! options snakegrid sets itself where the driver has them, and the option lists that GDAL drivers
//! publish as XML.

use super::session::FIXED_DATE;
use gdal::{Driver, Metadata};

/// The name of a `NAME=VALUE` option, for comparing with the driver's names.
fn name_of(option: &str) -> &str {
    option
        .split_once('=')
        .map_or(option, |(name, _)| name)
        .trim()
}

/// One `<Option>` of a driver's layer creation option list.
struct DriverOption {
    default: Option<String>,
    /// The values a `string-select` option takes.
    values: Vec<String>,
}

/// The metadata item in which a driver lists its layer creation options.
const LAYER_OPTIONS: &str = "DS_LAYER_CREATIONOPTIONLIST";
/// The metadata item in which a driver lists its dataset creation options.
const DATASET_OPTIONS: &str = "DMD_CREATIONOPTIONLIST";

/// Option `name` of the driver's layer creation option list.
fn layer_option(driver: &Driver, name: &str) -> Option<DriverOption> {
    driver_option(driver, LAYER_OPTIONS, name)
}

/// Option `name` of the driver's option list `list` ([`LAYER_OPTIONS`], [`DATASET_OPTIONS`]).
fn driver_option(driver: &Driver, list: &str, name: &str) -> Option<DriverOption> {
    let xml = driver.metadata_item(list, "")?;
    let document = roxmltree::Document::parse(&xml).ok()?;
    let option = document.descendants().find(|node| {
        node.has_tag_name("Option")
            && node
                .attribute("name")
                .is_some_and(|n| n.eq_ignore_ascii_case(name))
    })?;
    Some(DriverOption {
        default: option.attribute("default").map(str::to_owned),
        values: option
            .children()
            .filter(|child| child.has_tag_name("Value"))
            .filter_map(|value| value.text())
            .map(|text| text.trim().to_owned())
            .collect(),
    })
}

/// Whether the driver has layer creation option `name`.
pub(crate) fn has_layer_option(driver: &Driver, name: &str) -> bool {
    layer_option(driver, name).is_some()
}

/// The layer creation options of the grid layer: the user's `-lco` first, then those snakegrid
/// sets where the driver has them and the user did not set them:
/// - `FID` and `GEOMETRY_NAME`, renamed when the driver's default column name is one of
///   `fields` (a source field `fid` written to GeoPackage would otherwise be taken as the FID);
/// - `DESCRIPTION`: `description`, the run's metrics (GeoPackage's `gpkg_contents`);
/// - `DBF_DATE_LAST_UPDATE`: the fixed date of every run, so that a Shapefile's DBF header does
///   not change from one day to the next;
/// - `GEOMETRY=AS_WKT`: formats that write geometry only on request (CSV) write the cells as WKT.
pub(crate) fn layer_options(
    driver: &Driver,
    user: &[String],
    fields: &[&str],
    description: &str,
) -> Vec<String> {
    let mut options = user.to_vec();
    let unset = |options: &[String], name: &str| {
        has_layer_option(driver, name)
            && !options
                .iter()
                .any(|o| name_of(o).eq_ignore_ascii_case(name))
    };
    for column in ["FID", "GEOMETRY_NAME"] {
        if unset(&options, column) {
            options.extend(column_option(driver, column, fields));
        }
    }
    if unset(&options, "DESCRIPTION") {
        options.push(format!("DESCRIPTION={description}"));
    }
    if unset(&options, "DBF_DATE_LAST_UPDATE") {
        // FIXED_DATE is an ISO 8601 date-time; the DBF header takes YYYY-MM-DD.
        let day = FIXED_DATE.split('T').next().unwrap_or(FIXED_DATE);
        options.push(format!("DBF_DATE_LAST_UPDATE={day}"));
    }
    if unset(&options, "GEOMETRY")
        && layer_option(driver, "GEOMETRY").is_some_and(|o| o.values.iter().any(|v| v == "AS_WKT"))
    {
        options.push("GEOMETRY=AS_WKT".to_owned());
    }
    options
}

/// The dataset creation options of a new output: the user's `-dsco` first, then those snakegrid
/// sets where the driver has them and the user did not set them:
/// - `WRITE_GDAL_HISTORY=NO` (netCDF): the history attribute holds the time of writing and the
///   staging file's path, so that no two runs would write the same file.
pub(crate) fn dataset_options(driver: &Driver, user: &[String]) -> Vec<String> {
    let mut options = user.to_vec();
    let set = |name: &str| (options.iter()).any(|o| name_of(o).eq_ignore_ascii_case(name));
    if !set("WRITE_GDAL_HISTORY")
        && driver_option(driver, DATASET_OPTIONS, "WRITE_GDAL_HISTORY").is_some()
    {
        options.push("WRITE_GDAL_HISTORY=NO".to_owned());
    }
    options
}

/// `OPTION=name` for a column the driver creates itself (FID, geometry) when its default name
/// would clash with a field; `None` (keep the driver's default) when there is no clash.
fn column_option(driver: &Driver, option: &str, taken: &[&str]) -> Option<String> {
    let default = layer_option(driver, option)?
        .default
        .filter(|d| !d.is_empty())?;
    let clashes = |name: &str| taken.iter().any(|t| t.eq_ignore_ascii_case(name));
    if !clashes(&default) {
        return None;
    }
    let free = (1..)
        .map(|n| format!("{default}_{n}"))
        .find(|name| !clashes(name))?;
    Some(format!("{option}={free}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use gdal::DriverManager;

    #[test]
    fn snakegrid_sets_only_the_options_the_driver_has_and_the_user_left_alone() {
        let gpkg = DriverManager::get_driver_by_name("GPKG").unwrap();
        let options = layer_options(&gpkg, &[], &["fid", "name"], "metrics");
        assert_eq!(options, ["FID=fid_1", "DESCRIPTION=metrics"]);
        let user = ["fid=cell".to_owned()];
        assert_eq!(
            layer_options(&gpkg, &user, &["fid"], "m"),
            ["fid=cell", "DESCRIPTION=m"]
        );
        let shapefile = DriverManager::get_driver_by_name("ESRI Shapefile").unwrap();
        assert_eq!(
            layer_options(&shapefile, &[], &["name"], "m"),
            ["DBF_DATE_LAST_UPDATE=2000-01-01"]
        );
        let csv = DriverManager::get_driver_by_name("CSV").unwrap();
        assert_eq!(layer_options(&csv, &[], &[], "m"), ["GEOMETRY=AS_WKT"]);
        let user = ["GEOMETRY=AS_XY".to_owned()];
        assert_eq!(layer_options(&csv, &user, &[], "m"), user);
    }

    #[test]
    fn new_datasets_write_no_history_unless_asked() {
        let netcdf = DriverManager::get_driver_by_name("netCDF").unwrap();
        assert_eq!(dataset_options(&netcdf, &[]), ["WRITE_GDAL_HISTORY=NO"]);
        let user = ["write_gdal_history=YES".to_owned()];
        assert_eq!(dataset_options(&netcdf, &user), user);
        let gpkg = DriverManager::get_driver_by_name("GPKG").unwrap();
        assert!(dataset_options(&gpkg, &[]).is_empty());
    }
}
