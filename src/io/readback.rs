//! Reading a written layer back to prove that it is what it claims: every feature, every field
//! under the name it was given, a polygon for every cell and every region's id as it was. The
//! probe does it in memory before the run, the run once more on the staged output before the
//! commit, as a last guard against a driver that changes what it stores.

use super::session::Session;
use crate::core::Error;
use gdal::vector::{LayerAccess, OGRwkbGeometryType};
use gdal::{Dataset, DatasetOptions, GdalOpenFlags};
use std::path::Path;

/// What a written layer must hold.
pub(crate) struct Expected<'a> {
    /// The driver that wrote it, for messages.
    pub driver: &'a str,
    /// The layer's name, as the driver gave it.
    pub layer: &'a str,
    /// Its fields as the driver named them, in order; a driver may add its own (CSV's `WKT`).
    pub fields: &'a [String],
    /// The id field (a position in `fields`) and each feature's id, in order; `None` when the
    /// ids are feature ids, which a format may renumber.
    pub ids: Option<(usize, &'a [&'a str])>,
    pub features: usize,
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
    let dataset = Dataset::open_ex(path, options)
        .map_err(|e| session.io_error(&format!("cannot read back {shown:?}"), e))?;
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
        .map_err(|e| session.io_error(&format!("cannot read back {shown:?}"), e))?;
    let names: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
    // Each expected field in order, extra ones allowed between them.
    let mut found = Vec::with_capacity(expected.fields.len());
    let mut rest = names.iter().enumerate();
    for name in expected.fields {
        match rest.find(|(_, n)| *n == name) {
            Some((index, _)) => found.push(index),
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
    for (k, feature) in layer.features().enumerate() {
        count += 1;
        let wanted = expected.ids.and_then(|(_, ids)| ids.get(k).copied());
        let name = wanted.map_or_else(|| format!("number {}", k + 1), str::to_owned);
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
                "the {driver} output {shown:?} does not keep the cells' polygons (the cell of \
                 feature {name} reads back without one)"
            )));
        }
        if let (Some((position, _)), Some(id)) = (expected.ids, wanted) {
            let stored = feature.field_as_string(found[position]).ok().flatten();
            if stored.as_deref() != Some(id) {
                return Err(Error::input(
                    Some(id),
                    id_change(driver, id, stored.as_deref()),
                ));
            }
        }
    }
    if count != expected.features {
        return Err(Error::Io(format!(
            "the {driver} output {shown:?} reads back {count} features, not {}",
            expected.features
        )));
    }
    Ok(layer.name())
}

/// Why an id would not survive the output, from what the driver made of it.
fn id_change(driver: &str, id: &str, stored: Option<&str>) -> String {
    let Some(stored) = stored else {
        return format!("the {driver} output would store no id for it");
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
    use super::id_change;

    #[test]
    fn an_id_change_says_what_the_format_did() {
        let dbf = "ESRI Shapefile";
        assert!(id_change(dbf, "a  ", Some("a")).contains("drops trailing spaces"));
        let long = "x".repeat(300);
        assert!(id_change(dbf, &long, Some(&long[..254]))
            .contains("keeps only the first 254 of its 300 bytes"));
        assert!(id_change(dbf, "北京", Some("??")).contains("cannot encode"));
        assert!(id_change(dbf, "a", None).contains("no id"));
    }
}
