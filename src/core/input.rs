//! What a layer's features must be to become regions, and what every face says when one is
//! not: the command line (through GDAL), the C API and the QGIS plugin all admit features here,
//! so a null id or a line among the polygons gets the same message everywhere.

use super::Error;
use geo::{Geometry, MultiPolygon};
use std::collections::HashMap;

/// The largest angle one chord of a linearised arc spans: GDAL's default (`OGR_ARC_STEPSIZE`),
/// so that a curved layer read here and one linearised by `ogr2ogr -nlt CONVERT_TO_LINEAR`
/// differ by less than the outline's tolerance.
pub const ARC_STEP_DEGREES: f64 = 4.0;

/// What a reader found as a feature's geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryKind<'a> {
    /// No geometry at all.
    Null,
    /// A geometry without points.
    Empty,
    /// A polygon or multipolygon, or a collection of nothing else ([`polygons_of`]): what the
    /// method takes.
    Polygonal,
    /// A curved polygon (its type name, e.g. "CURVEPOLYGON"): taken, its arcs linearised by
    /// the reader (chords of at most [`ARC_STEP_DEGREES`]).
    Curved(&'a str),
    /// Any other geometry type (its name, e.g. "POINT").
    Other(&'a str),
}

/// The features admitted so far, to refuse a second use of an id and to tell of curves.
#[derive(Clone, Debug, Default)]
pub struct Admission {
    /// Each id and the feature that used it first.
    seen: HashMap<String, String>,
    /// The first feature with a curved geometry, its type, and how many there are.
    curved: Option<(String, String, usize)>,
}

impl Admission {
    /// Admits one feature, called `feature` in messages until its id is known ("FID 3"), with
    /// its `id` (`None`: null) and what its geometry is; returns the id. Refuses a null, empty or
    /// repeated id and a geometry that is not polygonal, naming the feature.
    pub fn admit(
        &mut self,
        feature: &str,
        id: Option<&str>,
        geometry: GeometryKind,
    ) -> Result<String, Error> {
        let id = id.ok_or_else(|| Error::input(Some(feature), "the id is null"))?;
        if id.is_empty() {
            return Err(Error::input(Some(feature), "the id is empty"));
        }
        if let Some(first) = self.seen.get(id) {
            return Err(Error::input(
                Some(id),
                format!("the id is not unique ({first} and {feature} share it)"),
            ));
        }
        let problem = match geometry {
            GeometryKind::Polygonal | GeometryKind::Curved(_) => None,
            GeometryKind::Null => Some("the geometry is null".to_owned()),
            GeometryKind::Empty => Some("the geometry is empty".to_owned()),
            GeometryKind::Other(name) if name.starts_with("GEOMETRYCOLLECTION") => Some(format!(
                "the geometry is a {name} that holds more than polygons"
            )),
            GeometryKind::Other(name) => Some(format!(
                "the geometry is a {name}, not a polygon or multipolygon"
            )),
        };
        if let Some(problem) = problem {
            return Err(Error::input(Some(id), problem));
        }
        if let GeometryKind::Curved(name) = geometry {
            let first = (id.to_owned(), name.to_owned(), 0);
            self.curved.get_or_insert(first).2 += 1;
        }
        self.seen.insert(id.to_owned(), feature.to_owned());
        Ok(id.to_owned())
    }

    /// What the user should know of the features admitted: that curves were linearised.
    pub fn note(&self) -> Option<String> {
        let (id, name, count) = self.curved.as_ref()?;
        let others = match count - 1 {
            0 => String::new(),
            1 => " and 1 other".to_owned(),
            n => format!(" and {n} others"),
        };
        Some(format!(
            "feature {id}{others}: curved geometry ({name}) linearised, each arc cut into \
             chords of at most {} degrees",
            ARC_STEP_DEGREES
        ))
    }
}

/// The polygons of a region's geometry: a polygon, a multipolygon, or a geometry collection
/// that holds only those (at any depth), as some tools write a region drawn in parts; `None`
/// for anything else. A collection's empty polygons are dropped; `None` when nothing is left.
pub fn polygons_of(geometry: Geometry<f64>) -> Option<MultiPolygon<f64>> {
    let polygons = match geometry {
        Geometry::Polygon(p) => vec![p],
        Geometry::MultiPolygon(m) => m.0,
        Geometry::GeometryCollection(c) => {
            let mut polygons = Vec::new();
            for member in c.0 {
                polygons.extend(polygons_of(member)?.0);
            }
            polygons.retain(|p| !p.exterior().0.is_empty());
            if polygons.is_empty() {
                return None;
            }
            polygons
        }
        _ => return None,
    };
    Some(MultiPolygon(polygons))
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{wkt, GeometryCollection};

    #[test]
    fn a_collection_of_polygons_is_a_multipolygon_and_a_mixed_one_is_not() {
        let a = wkt!(POLYGON((0. 0.,1. 0.,1. 1.,0. 0.)));
        let b = wkt!(MULTIPOLYGON(((2. 0.,3. 0.,3. 1.,2. 0.)),((4. 0.,5. 0.,5. 1.,4. 0.))));
        let nested = GeometryCollection(vec![
            Geometry::Polygon(a.clone()),
            Geometry::GeometryCollection(GeometryCollection(vec![Geometry::MultiPolygon(b)])),
        ]);
        // One polygon and, one level down, two: three (a hand count).
        assert_eq!(
            polygons_of(Geometry::GeometryCollection(nested))
                .unwrap()
                .0
                .len(),
            3
        );
        let mixed = GeometryCollection(vec![
            Geometry::Polygon(a.clone()),
            Geometry::LineString(wkt!(LINESTRING(0. 0.,1. 1.))),
        ]);
        assert_eq!(polygons_of(Geometry::GeometryCollection(mixed)), None);
        let empty = GeometryCollection::<f64>(vec![]);
        assert_eq!(polygons_of(Geometry::GeometryCollection(empty)), None);
        assert_eq!(polygons_of(Geometry::Polygon(a)).unwrap().0.len(), 1);
        assert_eq!(polygons_of(Geometry::Point(wkt!(POINT(0. 0.)))), None);
    }

    #[test]
    fn every_refusal_names_the_feature() {
        let mut admission = Admission::default();
        let polygon = GeometryKind::Polygonal;
        assert_eq!(admission.admit("FID 1", Some("a"), polygon).unwrap(), "a");
        let refused = [
            ("FID 2", None, polygon, "feature FID 2: the id is null"),
            ("FID 3", Some(""), polygon, "feature FID 3: the id is empty"),
            (
                "FID 4",
                Some("a"),
                polygon,
                "feature a: the id is not unique (FID 1 and FID 4 share it)",
            ),
            (
                "FID 5",
                Some("b"),
                GeometryKind::Null,
                "feature b: the geometry is null",
            ),
            (
                "FID 6",
                Some("c"),
                GeometryKind::Empty,
                "feature c: the geometry is empty",
            ),
            (
                "FID 7",
                Some("d"),
                GeometryKind::Other("POINT"),
                "feature d: the geometry is a POINT",
            ),
        ];
        for (feature, id, kind, message) in refused {
            let err = admission.admit(feature, id, kind).unwrap_err().to_string();
            assert!(err.contains(message), "{err}");
        }
        // A refused feature does not take its id.
        assert_eq!(admission.admit("FID 9", Some("b"), polygon).unwrap(), "b");
    }

    #[test]
    fn curved_features_are_taken_and_told_of_once() {
        let mut admission = Admission::default();
        assert_eq!(admission.note(), None);
        let curved = GeometryKind::Curved("CURVEPOLYGON");
        admission.admit("FID 1", Some("a"), curved).unwrap();
        let note = admission.note().unwrap();
        assert!(
            note.starts_with("feature a: curved geometry (CURVEPOLYGON)"),
            "{note}"
        );
        admission
            .admit("FID 2", Some("b"), GeometryKind::Polygonal)
            .unwrap();
        admission
            .admit("FID 3", Some("c"), GeometryKind::Curved("MULTISURFACE"))
            .unwrap();
        admission.admit("FID 4", Some("d"), curved).unwrap();
        let note = admission.note().unwrap();
        assert!(note.starts_with("feature a and 2 others: curved"), "{note}");
    }
}
