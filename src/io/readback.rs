//! Reading a written layer back to prove that it is what it claims: every feature, every field
//! under the name it was given, a polygon for every cell and every region's id as it was. The
//! probe does it in memory before the run, the run once more on the staged output before the
//! commit, as a last guard against a driver that changes what it stores.

use super::session::Session;
use crate::core::Error;
use gdal::vector::{LayerAccess, OGRFieldType, OGRwkbGeometryType};
use gdal::{Dataset, DatasetOptions, Driver, GdalOpenFlags, Metadata};
use std::path::Path;

/// What a written layer must hold.
pub(crate) struct Expected<'a> {
    /// The driver that wrote it, for messages.
    pub driver: &'a str,
    /// The layer's name, as the driver gave it.
    pub layer: &'a str,
    /// Its fields as the driver named them; a driver may add its own (CSV's `WKT`).
    pub fields: &'a [String],
    /// The id field (a position in `fields`) and each feature's id, in order; `None` when the
    /// ids are feature ids, which a format may renumber.
    pub ids: Option<(usize, &'a [&'a str])>,
    pub features: usize,
}

/// Whether GDAL can read what `driver` writes; a few formats are written only (PGDUMP's SQL).
pub(crate) fn can_read(driver: &Driver) -> bool {
    driver
        .metadata_item("DCAP_OPEN", "")
        .is_some_and(|v| v.eq_ignore_ascii_case("YES"))
}

/// Reads the layer at `path` back and compares it with `expected`; returns the layer's name as
/// it reads back (a CSV or Shapefile layer is named after its file, whatever it was created as).
pub(crate) fn read_back(
    session: &Session,
    path: &Path,
    expected: &Expected,
) -> Result<String, Error> {
    let shown = path.display();
    let driver = expected.driver;
    let options = DatasetOptions {
        open_flags: GdalOpenFlags::GDAL_OF_VECTOR | GdalOpenFlags::GDAL_OF_READONLY,
        ..Default::default()
    };
    let unreadable = || {
        let reason = session
            .take_error()
            .map(|reason| format!(" ({reason})"))
            .unwrap_or_default();
        Error::Io(format!(
            "GDAL cannot read back the {driver} output {shown:?}{reason}, so what it holds \
             cannot be checked"
        ))
    };
    let dataset = Dataset::open_ex(path, options).map_err(|_| unreadable())?;
    let only = || match dataset.layer_count() {
        1 => dataset.layer(0),
        _ => Err(gdal::errors::GdalError::BadArgument(format!(
            "it has no layer {:?}",
            expected.layer
        ))),
    };
    let mut layer = dataset
        .layer_by_name(expected.layer)
        .or_else(|_| only())
        .map_err(|_| unreadable())?;
    let names: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
    let types: Vec<u32> = layer.defn().fields().map(|f| f.field_type()).collect();
    // Every expected field, by its name, exact or else in another case (LIBKML reads `name`
    // back as its placemarks' `Name`, in its own place); a format may add fields (CSV's `WKT`).
    let mut found = Vec::with_capacity(expected.fields.len());
    for name in expected.fields {
        let index = names
            .iter()
            .position(|n| n == name)
            .or_else(|| names.iter().position(|n| n.eq_ignore_ascii_case(name)));
        match index {
            Some(index) => found.push(index),
            None => {
                return Err(Error::Io(format!(
                    "the {driver} output {shown:?} reads back without the field {name:?} (its \
                     fields: {})",
                    names.join(", ")
                )))
            }
        }
    }
    let mut count = 0;
    let mut stored_ids = Vec::new();
    for (k, feature) in layer.features().enumerate() {
        count += 1;
        let polygon = feature
            .geometry()
            // SAFETY: only reads the wrapped pointer, which `Feature::geometry` has just set;
            // the binding hands out a null geometry as a wrapper of a null pointer.
            .filter(|g| !unsafe { g.c_geometry() }.is_null())
            .map(|g| gdal::vector::geometry_type_flatten(g.geometry_type()))
            .is_some_and(|t| {
                t == OGRwkbGeometryType::wkbPolygon || t == OGRwkbGeometryType::wkbMultiPolygon
            });
        if !polygon {
            return Err(Error::Io(format!(
                "the {driver} output {shown:?} does not keep the cells' polygons (feature \
                 number {} reads back without one)",
                k + 1
            )));
        }
        if let Some((position, _)) = expected.ids {
            stored_ids.push(feature.field_as_string(found[position]).ok().flatten());
        }
    }
    if let Some((position, ids)) = expected.ids {
        let numeric = matches!(
            types[found[position]],
            OGRFieldType::OFTInteger | OGRFieldType::OFTInteger64 | OGRFieldType::OFTReal
        );
        compare_ids(driver, ids, &stored_ids, numeric)?;
    }
    if count != expected.features {
        return Err(Error::Io(format!(
            "the {driver} output {shown:?} reads back {count} features, not {}",
            expected.features
        )));
    }
    Ok(layer.name())
}

/// Refuses the first id of `ids` that `stored` (the ids read back) does not hold as it is. A
/// format may store the features in another order (FlatGeobuf sorts them along its spatial
/// index); what it stored in the place of a missing id is the best guess of what became of it.
/// In a `numeric` field an id is its number: a Shapefile writes a real 1 as
/// "1.000000000000000", which still names the region.
fn compare_ids(
    driver: &str,
    ids: &[&str],
    stored: &[Option<String>],
    numeric: bool,
) -> Result<(), Error> {
    let key = |id: &str| -> String {
        match id.trim().parse::<f64>() {
            Ok(number) if numeric && number.is_finite() => number.to_string(),
            _ => id.to_owned(),
        }
    };
    let stored: Vec<Option<&str>> = stored.iter().map(Option::as_deref).collect();
    let same = |s: Option<&str>, id: &str| s.is_some_and(|s| s == id || key(s) == key(id));
    if stored.len() == ids.len() && stored.iter().zip(ids).all(|(s, id)| same(*s, id)) {
        return Ok(());
    }
    let mut sorted_ids: Vec<String> = ids.iter().map(|id| key(id)).collect();
    let mut sorted_stored: Vec<String> = stored.iter().flatten().map(|s| key(s)).collect();
    sorted_ids.sort_unstable();
    sorted_stored.sort_unstable();
    if sorted_ids == sorted_stored {
        return Ok(());
    }
    let missing = ids
        .iter()
        .position(|id| sorted_stored.binary_search(&key(id)).is_err())
        .unwrap_or(0);
    let id = ids.get(missing).copied().unwrap_or_default();
    let instead = stored.get(missing).copied().flatten().filter(|s| *s != id);
    Err(Error::input(Some(id), id_change(driver, id, instead)))
}

/// Why an id would not survive the output, from what the driver made of it.
fn id_change(driver: &str, id: &str, stored: Option<&str>) -> String {
    let Some(stored) = stored else {
        return format!("the {driver} output does not keep this id as it is");
    };
    let how = if stored == id.trim_end() {
        "drops trailing spaces".to_owned()
    } else if id.starts_with(stored) {
        format!(
            "keeps only the first {} of its {} bytes",
            stored.len(),
            id.len()
        )
    } else {
        "cannot encode some of its characters".to_owned()
    };
    format!(
        "the {driver} output {how}, so the id would be stored as {stored:?}, which no longer \
         names this region; choose another -id field or output format"
    )
}

#[cfg(test)]
mod tests {
    use super::{compare_ids, id_change};

    #[test]
    fn ids_may_come_back_in_another_order_but_not_changed() {
        let some = |v: &[&str]| v.iter().map(|s| Some(s.to_string())).collect::<Vec<_>>();
        assert!(compare_ids(
            "FlatGeobuf",
            &["a", "b", "c"],
            &some(&["c", "a", "b"]),
            false
        )
        .is_ok());
        let error =
            compare_ids("ESRI Shapefile", &["a", "a  "], &some(&["a", "a"]), false).unwrap_err();
        assert_eq!(
            error.to_string(),
            "feature a  : the ESRI Shapefile output drops trailing spaces, so the id would be \
             stored as \"a\", which no longer names this region; choose another -id field or \
             output format"
        );
        let error = compare_ids("GPKG", &["a", "b"], &some(&["a"]), false).unwrap_err();
        assert!(error.to_string().starts_with("feature b: "), "{error}");
    }

    #[test]
    fn a_number_is_the_same_id_however_the_format_writes_it() {
        let some = |v: &[&str]| v.iter().map(|s| Some(s.to_string())).collect::<Vec<_>>();
        // A Shapefile's real field: 15 decimals.
        let dbf = some(&["1.000000000000000", "2.500000000000000"]);
        assert!(compare_ids("ESRI Shapefile", &["1", "2.5"], &dbf, true).is_ok());
        // The same digits in a text field are another id.
        assert!(compare_ids("ESRI Shapefile", &["1", "2.5"], &dbf, false).is_err());
        // A number that changed is refused, in a numeric field too.
        let error = compare_ids("ESRI Shapefile", &["1", "3"], &dbf, true).unwrap_err();
        assert!(error.to_string().starts_with("feature 3: "), "{error}");
    }

    #[test]
    fn an_id_change_says_what_the_format_did() {
        let dbf = "ESRI Shapefile";
        assert!(id_change(dbf, "a  ", Some("a")).contains("drops trailing spaces"));
        let long = "x".repeat(300);
        assert!(id_change(dbf, &long, Some(&long[..254]))
            .contains("keeps only the first 254 of its 300 bytes"));
        assert!(id_change(dbf, "北京", Some("??")).contains("cannot encode"));
        assert!(id_change(dbf, "a", None).contains("does not keep this id"));
    }
}
