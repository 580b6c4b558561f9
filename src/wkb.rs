//! Well-Known Binary in and out, for callers that hand regions over as bytes (the C API) rather
//! than as `geo` types. Parsing and writing are the georust `wkb` crate's; this module only
//! decides what a region may be: a Polygon, a MultiPolygon or a GeometryCollection of them
//! ([`crate::input::polygons_of`]), or a curved surface, linearised ([`curved`]); read in 2D
//! (Z and M are dropped, as the method is planar).

pub mod curved;

use crate::input::{polygons_of, GeometryKind};
use geo::{MultiPolygon, Polygon};
use geo_traits::to_geo::{ToGeoGeometry, ToGeoMultiPolygon, ToGeoPolygon};
use geo_traits::GeometryTrait;
use wkb::reader::Wkb;
use wkb::writer::{write_multi_polygon, write_polygon, WriteOptions};
use wkb::Endianness;

/// Reads one region's geometry. Either byte order, ISO or extended (EWKB) flavour; the whole
/// buffer must be one geometry. The error says what is wrong, not which region: the caller
/// knows that.
pub fn to_multi_polygon(bytes: &[u8]) -> Result<MultiPolygon<f64>, String> {
    match type_code(bytes) {
        Some(code) if curved::curved_name(code).is_some() => curved::to_multi_polygon(bytes),
        // A collection the straight reader refuses may hold curved polygons.
        Some(code) if curved::base_code(code) == 7 => {
            straight(bytes).or_else(|e| curved::to_multi_polygon(bytes).map_err(|_| e))
        }
        _ => straight(bytes),
    }
}

/// The WKB type code in the header of `bytes`, in their byte order.
fn type_code(bytes: &[u8]) -> Option<u32> {
    match bytes {
        [0, a, b, c, d, ..] => Some(u32::from_be_bytes([*a, *b, *c, *d])),
        [1, a, b, c, d, ..] => Some(u32::from_le_bytes([*a, *b, *c, *d])),
        _ => None,
    }
}

/// Reads a geometry without curves, with the `wkb` crate.
fn straight(bytes: &[u8]) -> Result<MultiPolygon<f64>, String> {
    let geometry = Wkb::try_new(bytes).map_err(|e| {
        let text = e.to_string();
        // The crate measures against the part of the buffer left at the ring it reads, so its
        // "buffer length is 4" misled about a buffer of 13 bytes whose ring count was 2³¹.
        if text.contains("Invalid buffer length") {
            format!(
                "invalid WKB: its {} bytes end before the rings and points its counts declare \
                 (cut short, or a count is wrong)",
                bytes.len()
            )
        } else {
            format!("invalid WKB: {text}")
        }
    })?;
    // The reader stops at the end of the first geometry; anything after it means the caller
    // passed the wrong length or several geometries.
    let used = geometry.buf().len();
    if used != bytes.len() {
        return Err(format!(
            "invalid WKB: {} bytes after the geometry's end (it takes {used} of {})",
            bytes.len() - used,
            bytes.len()
        ));
    }
    match geometry.as_type() {
        geo_traits::GeometryType::Polygon(p) => Ok(MultiPolygon(vec![p.to_polygon()])),
        geo_traits::GeometryType::MultiPolygon(mp) => Ok(mp.to_multi_polygon()),
        geo_traits::GeometryType::GeometryCollection(_) => (geometry.try_to_geometry())
            .and_then(polygons_of)
            .ok_or_else(|| "expected a GeometryCollection of polygons only".to_owned()),
        _ => Err(format!(
            "expected a Polygon, MultiPolygon or GeometryCollection of them, got a {:?}",
            geometry.geometry_type()
        )),
    }
}

/// What kind of geometry `bytes` hold, for the input checks every face shares
/// ([`crate::input::Admission`]); the names are the OGC ones GDAL prints ("POINT").
pub fn geometry_kind(bytes: &[u8]) -> Result<GeometryKind<'static>, String> {
    let code = type_code(bytes);
    if let Ok(geometry) = to_multi_polygon(bytes) {
        let empty = geometry.0.iter().all(|p| p.exterior().0.is_empty());
        // Curved: a curved type, or a collection only the curves' reader takes, that holds an
        // arc (a MultiSurface of plain polygons is not).
        let curved = code
            .and_then(|code| {
                curved::curved_name(code).or_else(|| {
                    (curved::base_code(code) == 7 && straight(bytes).is_err())
                        .then_some("GEOMETRYCOLLECTION")
                })
            })
            .filter(|_| curved::read(bytes).is_ok_and(|(_, arcs)| arcs > 0));
        return Ok(match curved {
            _ if empty => GeometryKind::Empty,
            Some(name) => GeometryKind::Curved(name),
            None => GeometryKind::Polygonal,
        });
    }
    // Not a polygon the reader takes: name the type from the header (byte order, then the type
    // code, ISO with Z/M in the thousands or EWKB with flags in the high bits), as a reader of
    // points would.
    let Some(code) = code else {
        return Err(to_multi_polygon(bytes).unwrap_err());
    };
    let name = match curved::base_code(code) {
        1 => "POINT",
        2 => "LINESTRING",
        4 => "MULTIPOINT",
        5 => "MULTILINESTRING",
        7 => "GEOMETRYCOLLECTION",
        8 => "CIRCULARSTRING",
        9 => "COMPOUNDCURVE",
        11 => "MULTICURVE",
        15 => "POLYHEDRALSURFACE",
        16 => "TIN",
        17 => "TRIANGLE",
        _ => return Err(to_multi_polygon(bytes).unwrap_err()),
    };
    // A point or line that does not even parse is still named by its type.
    Ok(GeometryKind::Other(name))
}

/// Writes a polygon (a grid cell) as little-endian 2D ISO WKB.
pub fn from_polygon(polygon: &Polygon<f64>) -> Vec<u8> {
    let mut out = Vec::new();
    let options = WriteOptions {
        endianness: Endianness::LittleEndian,
    };
    // Writing into a Vec cannot fail for lack of space, and a geo-types polygon is always 2D,
    // the only other error the writer knows.
    write_polygon(&mut out, polygon, &options).expect("a 2D polygon always writes to a Vec");
    out
}

/// Writes a multipolygon (the moved outline) as little-endian 2D ISO WKB.
pub fn from_multi_polygon(polygons: &MultiPolygon<f64>) -> Vec<u8> {
    let mut out = Vec::new();
    let options = WriteOptions {
        endianness: Endianness::LittleEndian,
    };
    // As for from_polygon.
    write_multi_polygon(&mut out, polygons, &options)
        .expect("a 2D multipolygon always writes to a Vec");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{polygon, Area, MapCoords};

    fn square() -> Polygon<f64> {
        polygon![(x: 0.0, y: 0.0), (x: 2.0, y: 0.0), (x: 2.0, y: 2.0), (x: 0.0, y: 2.0)]
    }

    #[test]
    fn a_polygon_round_trips() {
        let bytes = from_polygon(&square());
        assert_eq!(bytes[0], 1, "little endian");
        assert_eq!(&bytes[1..5], &3u32.to_le_bytes(), "ISO Polygon");
        let back = to_multi_polygon(&bytes).unwrap();
        assert_eq!(back, MultiPolygon(vec![square()]));
    }

    #[test]
    fn a_multipolygon_is_read_whole() {
        let mut bytes = vec![1u8];
        bytes.extend(6u32.to_le_bytes());
        bytes.extend(2u32.to_le_bytes());
        bytes.extend(from_polygon(&square()));
        bytes.extend(from_polygon(&square()));
        let back = to_multi_polygon(&bytes).unwrap();
        assert_eq!(back.0.len(), 2);
        assert_eq!(back.unsigned_area(), 8.0);
    }

    #[test]
    fn z_and_m_are_dropped() {
        // Big-endian Polygon ZM (ISO code 3003): one ring of four points.
        let mut bytes = vec![0u8];
        bytes.extend(3003u32.to_be_bytes());
        bytes.extend(1u32.to_be_bytes());
        bytes.extend(4u32.to_be_bytes());
        for (x, y) in [(0.0f64, 0.0f64), (1.0, 0.0), (0.0, 1.0), (0.0, 0.0)] {
            for v in [x, y, 7.0, 9.0] {
                bytes.extend(v.to_be_bytes());
            }
        }
        let back = to_multi_polygon(&bytes).unwrap();
        assert_eq!(back.unsigned_area(), 0.5);
    }

    #[test]
    fn other_types_truncations_and_trailing_bytes_are_refused() {
        let mut point = vec![1u8];
        point.extend(1u32.to_le_bytes());
        point.extend(1.0f64.to_le_bytes());
        point.extend(2.0f64.to_le_bytes());
        let err = to_multi_polygon(&point).unwrap_err();
        assert!(err.contains("got a Point"), "{err}");

        let bytes = from_polygon(&square());
        for len in 0..bytes.len() {
            let err = to_multi_polygon(&bytes[..len]).unwrap_err();
            assert!(err.starts_with("invalid WKB"), "{len}: {err}");
        }
        // A polygon claiming 2³¹ − 1 rings in 13 bytes: the crate's message gave a length of 4.
        let huge = [
            1, 3, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f, 0xff, 0xff, 0xff, 0x7f,
        ];
        let err = to_multi_polygon(&huge).unwrap_err();
        assert!(err.contains("its 13 bytes end before"), "{err}");
        let mut longer = bytes.clone();
        longer.push(0);
        let err = to_multi_polygon(&longer).unwrap_err();
        assert!(err.contains("1 bytes after"), "{err}");
    }

    #[test]
    fn a_multipolygon_round_trips() {
        let two = MultiPolygon(vec![
            square(),
            square().map_coords(|c| c + (5.0, 0.0).into()),
        ]);
        assert_eq!(to_multi_polygon(&from_multi_polygon(&two)).unwrap(), two);
    }

    #[test]
    fn the_kind_of_a_geometry_is_named_as_gdal_names_it() {
        assert_eq!(
            geometry_kind(&from_polygon(&square())),
            Ok(GeometryKind::Polygonal)
        );
        let mut point = vec![1u8];
        point.extend(1u32.to_le_bytes());
        point.extend(1.0f64.to_le_bytes());
        point.extend(2.0f64.to_le_bytes());
        assert_eq!(geometry_kind(&point), Ok(GeometryKind::Other("POINT")));
        let curved = curved::big_endian_circle_z();
        assert_eq!(
            geometry_kind(&curved),
            Ok(GeometryKind::Curved("CURVEPOLYGON"))
        );
        // A collection holding it is curved too, and read whole.
        let mut collection = vec![1u8];
        collection.extend(7u32.to_le_bytes());
        collection.extend(2u32.to_le_bytes());
        collection.extend(&curved);
        collection.extend(from_polygon(&square()));
        assert_eq!(
            geometry_kind(&collection),
            Ok(GeometryKind::Curved("GEOMETRYCOLLECTION"))
        );
        assert_eq!(to_multi_polygon(&collection).unwrap().0.len(), 2);
        // A MultiSurface of plain polygons (as GML readers hand them over) is no curve.
        let mut plain = vec![1u8];
        plain.extend(12u32.to_le_bytes());
        plain.extend(1u32.to_le_bytes());
        plain.extend(from_polygon(&square()));
        assert_eq!(geometry_kind(&plain), Ok(GeometryKind::Polygonal));
        assert_eq!(
            to_multi_polygon(&plain).unwrap(),
            MultiPolygon(vec![square()])
        );
        // Cut short, it is an error; a curve that bounds nothing is named.
        let err = geometry_kind(&curved[..20]).unwrap_err();
        assert!(err.starts_with("invalid WKB"), "{err}");
        let mut arc = vec![1u8];
        arc.extend(8u32.to_le_bytes());
        arc.extend(0u32.to_le_bytes());
        assert_eq!(
            geometry_kind(&arc),
            Ok(GeometryKind::Other("CIRCULARSTRING"))
        );
        let mut empty = vec![1u8];
        empty.extend(3u32.to_le_bytes());
        empty.extend(0u32.to_le_bytes());
        assert_eq!(geometry_kind(&empty), Ok(GeometryKind::Empty));
        assert!(geometry_kind(&[9, 9]).is_err());
    }
}
