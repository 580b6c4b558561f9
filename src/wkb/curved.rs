//! Curved surfaces (ISO SQL/MM's CurvePolygon and MultiSurface, with rings that are circular
//! arcs, compound curves or straight lines) read as polygons: every arc is cut into chords of
//! at most [`ARC_STEP_DEGREES`]. The georust `wkb` crate reads no curves, hence this small
//! reader.
//!
//! Two regions sharing an arc draw it in opposite directions; each arc is cut from its end
//! that comes first in (x, y) order, with its circle taken from its points in that order, so
//! both regions get the very same vertices and stay neighbours vertex for vertex.

use crate::input::ARC_STEP_DEGREES;
use geo::{Coord, LineString, MultiPolygon, Polygon};
use std::cmp::Ordering;

/// The WKB type codes this reader knows (the last three digits of an ISO code).
const LINE_STRING: u32 = 2;
const POLYGON: u32 = 3;
const MULTI_POLYGON: u32 = 6;
const COLLECTION: u32 = 7;
const CIRCULAR_STRING: u32 = 8;
const COMPOUND_CURVE: u32 = 9;
const CURVE_POLYGON: u32 = 10;
const MULTI_SURFACE: u32 = 12;

/// Whether the WKB type `code` (ISO, or extended with flags in the high bits) is a curved
/// type, and its OGC name.
pub fn curved_name(code: u32) -> Option<&'static str> {
    match base_code(code) {
        CIRCULAR_STRING => Some("CIRCULARSTRING"),
        COMPOUND_CURVE => Some("COMPOUNDCURVE"),
        CURVE_POLYGON => Some("CURVEPOLYGON"),
        11 => Some("MULTICURVE"),
        MULTI_SURFACE => Some("MULTISURFACE"),
        _ => None,
    }
}

/// The polygons of a curved surface, or of a collection holding one, linearised; Z and M are
/// dropped. `Err` says what the bytes hold instead.
pub fn to_multi_polygon(bytes: &[u8]) -> Result<MultiPolygon<f64>, String> {
    read(bytes).map(|(polygons, _)| polygons)
}

/// As [`to_multi_polygon`], with how many arcs were cut: none for a MultiSurface of plain
/// polygons, as GML readers often hand them over.
pub fn read(bytes: &[u8]) -> Result<(MultiPolygon<f64>, usize), String> {
    let mut reader = Reader {
        bytes,
        at: 0,
        depth: 0,
        arcs: 0,
    };
    let mut polygons = Vec::new();
    reader.surfaces(&mut polygons)?;
    if reader.at != bytes.len() {
        return Err(format!(
            "invalid WKB: {} bytes after the geometry's end (it takes {} of {})",
            bytes.len() - reader.at,
            reader.at,
            bytes.len()
        ));
    }
    Ok((MultiPolygon(polygons), reader.arcs))
}

/// The type without Z, M or SRID flags: 10 for CurvePolygon, Z, M or ZM, ISO or extended.
pub(crate) fn base_code(code: u32) -> u32 {
    (code & 0x0fff_ffff) % 1000
}

/// One geometry's header: its base type and how many ordinates each point has.
struct Header {
    little_endian: bool,
    code: u32,
    ordinates: usize,
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    /// How many collections and compound curves hold the one being read.
    depth: usize,
    /// How many arcs have been cut.
    arcs: usize,
}

/// The deepest nesting read, as the `wkb` crate reads straight geometries: a few bytes per
/// level would otherwise recurse until the stack overflows.
const MAX_DEPTH: usize = 128;

impl Reader<'_> {
    /// Reads what `read` reads one level deeper, refused past [`MAX_DEPTH`].
    fn nested<T>(
        &mut self,
        read: impl FnOnce(&mut Self) -> Result<T, String>,
    ) -> Result<T, String> {
        if self.depth >= MAX_DEPTH {
            return Err(format!(
                "invalid WKB: geometries nested more than {MAX_DEPTH} deep"
            ));
        }
        self.depth += 1;
        let read = read(self);
        self.depth -= 1;
        read
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let end = self.at + N;
        let taken = (self.bytes.get(self.at..end))
            .ok_or_else(|| format!("invalid WKB: it ends at byte {}", self.bytes.len()))?;
        self.at = end;
        Ok(taken.try_into().expect("a slice of N bytes"))
    }

    fn u32(&mut self, little_endian: bool) -> Result<u32, String> {
        let bytes = self.take::<4>()?;
        Ok(if little_endian {
            u32::from_le_bytes(bytes)
        } else {
            u32::from_be_bytes(bytes)
        })
    }

    fn f64(&mut self, little_endian: bool) -> Result<f64, String> {
        let bytes = self.take::<8>()?;
        Ok(if little_endian {
            f64::from_le_bytes(bytes)
        } else {
            f64::from_be_bytes(bytes)
        })
    }

    /// A count, refused when even that many of the smallest items could not fit in what is
    /// left, so that a corrupt count never reserves memory.
    fn count(&mut self, little_endian: bool, smallest_item: usize) -> Result<usize, String> {
        let count = self.u32(little_endian)? as usize;
        let left = self.bytes.len() - self.at;
        if count.saturating_mul(smallest_item) > left {
            return Err(format!(
                "invalid WKB: {count} items cannot fit in the {left} bytes left"
            ));
        }
        Ok(count)
    }

    fn header(&mut self) -> Result<Header, String> {
        let little_endian = match self.take::<1>()? {
            [0] => false,
            [1] => true,
            [other] => return Err(format!("invalid WKB: byte order {other}")),
        };
        let raw = self.u32(little_endian)?;
        let (mut z, mut m) = (raw & 0x8000_0000 != 0, raw & 0x4000_0000 != 0);
        match (raw & 0x0fff_ffff) / 1000 {
            0 => {}
            1 => z = true,
            2 => m = true,
            3 => (z, m) = (true, true),
            _ => return Err(format!("invalid WKB: unknown type code {raw}")),
        }
        if raw & 0x2000_0000 != 0 {
            self.take::<4>()?; // an extended WKB's SRID, which the caller's layer gives
        }
        Ok(Header {
            little_endian,
            code: base_code(raw),
            ordinates: 2 + usize::from(z) + usize::from(m),
        })
    }

    fn points(&mut self, header: &Header) -> Result<Vec<Coord<f64>>, String> {
        let count = self.count(header.little_endian, 8 * header.ordinates)?;
        let mut points = Vec::with_capacity(count);
        for _ in 0..count {
            let x = self.f64(header.little_endian)?;
            let y = self.f64(header.little_endian)?;
            for _ in 2..header.ordinates {
                self.f64(header.little_endian)?;
            }
            points.push(Coord { x, y });
        }
        Ok(points)
    }

    /// A polygonal geometry, its polygons appended to `out`.
    fn surfaces(&mut self, out: &mut Vec<Polygon<f64>>) -> Result<(), String> {
        let header = self.header()?;
        match header.code {
            POLYGON => {
                let rings = self.count(header.little_endian, 4)?;
                let rings = (0..rings)
                    .map(|_| self.points(&header))
                    .collect::<Result<Vec<_>, _>>()?;
                push_polygon(out, rings);
            }
            CURVE_POLYGON => {
                let rings = self.count(header.little_endian, 9)?;
                let rings = (0..rings)
                    .map(|_| self.curve())
                    .collect::<Result<Vec<_>, _>>()?;
                push_polygon(out, rings);
            }
            MULTI_POLYGON | MULTI_SURFACE | COLLECTION => {
                for _ in 0..self.count(header.little_endian, 9)? {
                    self.nested(|reader| reader.surfaces(out))?;
                }
            }
            other => {
                let name =
                    curved_name(other).map_or_else(|| format!("type {other}"), str::to_owned);
                return Err(format!(
                    "expected a polygon or curved polygon, got a {name}"
                ));
            }
        }
        Ok(())
    }

    /// A curve (a ring of a curved polygon, or a part of a compound curve) as its vertices,
    /// arcs linearised.
    fn curve(&mut self) -> Result<Vec<Coord<f64>>, String> {
        let header = self.header()?;
        match header.code {
            LINE_STRING => self.points(&header),
            CIRCULAR_STRING => {
                let points = self.points(&header)?;
                if points.len() > 1 && points.len() % 2 == 0 {
                    return Err(format!(
                        "invalid WKB: a circular string of {} points (it takes an odd number)",
                        points.len()
                    ));
                }
                let mut line: Vec<Coord<f64>> = points.first().copied().into_iter().collect();
                for arc in points.windows(3).step_by(2) {
                    push_arc(&mut line, arc[0], arc[1], arc[2]);
                    self.arcs += 1;
                }
                Ok(line)
            }
            COMPOUND_CURVE => {
                let mut line: Vec<Coord<f64>> = Vec::new();
                for _ in 0..self.count(header.little_endian, 9)? {
                    let part = self.nested(Reader::curve)?;
                    // Each part starts where the last ended.
                    let skip = usize::from(line.last().is_some() && line.last() == part.first());
                    line.extend(part.into_iter().skip(skip));
                }
                Ok(line)
            }
            other => Err(format!(
                "invalid WKB: a ring of type {other}, not a line, arc or compound curve"
            )),
        }
    }
}

/// Appends a polygon of `rings` (the first the exterior), skipping an empty one as the
/// straight reader does.
fn push_polygon(out: &mut Vec<Polygon<f64>>, mut rings: Vec<Vec<Coord<f64>>>) {
    if rings.first().is_none_or(Vec::is_empty) {
        return;
    }
    let exterior = LineString(rings.remove(0));
    out.push(Polygon::new(
        exterior,
        rings.into_iter().map(LineString).collect(),
    ));
}

/// Appends the arc from `start` (already in `line`) through `middle` to `end`, as chords.
fn push_arc(line: &mut Vec<Coord<f64>>, start: Coord<f64>, middle: Coord<f64>, end: Coord<f64>) {
    // The same circle whichever way the arc is drawn.
    let (first, last) = if before(end, start) {
        (end, start)
    } else {
        (start, end)
    };
    let Some(centre) = centre(first, middle, last) else {
        // Three points in a line: the arc is straight.
        push_point(line, middle);
        push_point(line, end);
        return;
    };
    // A full circle (start = end) goes anticlockwise, as GDAL draws it; any other arc the way
    // that passes its middle point.
    let anticlockwise = start == end || cross(start, middle, end) > 0.0;
    push_chords(line, centre, start, middle, anticlockwise);
    push_chords(line, centre, middle, end, anticlockwise);
}

/// Appends the chords of the arc about `centre` from `from` (already in `line`) to `to`.
fn push_chords(
    line: &mut Vec<Coord<f64>>,
    centre: Coord<f64>,
    from: Coord<f64>,
    to: Coord<f64>,
    anticlockwise: bool,
) {
    // Cut from the end first in (x, y) order, so that the arc drawn the other way round gives
    // the same points.
    let reversed = before(to, from);
    let (a, b) = if reversed { (to, from) } else { (from, to) };
    let anticlockwise = anticlockwise != reversed;
    let angle = |p: Coord<f64>| (p.y - centre.y).atan2(p.x - centre.x);
    let turn = if anticlockwise {
        angle(b) - angle(a)
    } else {
        angle(a) - angle(b)
    };
    let sweep = turn.rem_euclid(std::f64::consts::TAU);
    let chords = (sweep / ARC_STEP_DEGREES.to_radians()).ceil().max(1.0) as usize;
    let radius =
        ((a.x - centre.x).hypot(a.y - centre.y) + (b.x - centre.x).hypot(b.y - centre.y)) / 2.0;
    let step = if anticlockwise { sweep } else { -sweep } / chords as f64;
    let start = angle(a);
    let mut inner: Vec<Coord<f64>> = (1..chords)
        .map(|k| {
            let t = start + step * k as f64;
            Coord {
                x: centre.x + radius * t.cos(),
                y: centre.y + radius * t.sin(),
            }
        })
        .collect();
    if reversed {
        inner.reverse();
    }
    line.extend(inner);
    push_point(line, to);
}

/// Appends `point` unless it repeats the last one (an arc of no length).
fn push_point(line: &mut Vec<Coord<f64>>, point: Coord<f64>) {
    if line.last() != Some(&point) {
        line.push(point);
    }
}

/// Whether `a` comes before `b` in (x, y) order.
fn before(a: Coord<f64>, b: Coord<f64>) -> bool {
    (a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))) == Ordering::Less
}

/// Twice the signed area of the triangle a, b, c: positive when it turns anticlockwise.
fn cross(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// The centre of the circle through `a`, `b` and `c`; for a full circle (`a` = `c`) the
/// midpoint of `a` and `b`; `None` when the three points lie on a line (or are one point).
fn centre(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>) -> Option<Coord<f64>> {
    if a == c {
        return (a != b).then(|| (a + b) / 2.0);
    }
    let (ab, ac) = (b - a, c - a);
    let d = 2.0 * (ab.x * ac.y - ab.y * ac.x);
    let (ab2, ac2) = (ab.x * ab.x + ab.y * ab.y, ac.x * ac.x + ac.y * ac.y);
    // Collinear to within rounding: the circle would be far beyond the points.
    if d.abs() <= 1e-12 * ab2.sqrt() * ac2.sqrt() {
        return None;
    }
    Some(Coord {
        x: a.x + (ac.y * ab2 - ab.y * ac2) / d,
        y: a.y + (ab.x * ac2 - ac.x * ab2) / d,
    })
}

/// CURVEPOLYGON Z (ISO 1010), big-endian, whose ring is a CIRCULARSTRING Z (1008): the
/// circle of radius 1 through (0, 0) and (2, 0), at z 5.
#[cfg(test)]
pub(crate) fn big_endian_circle_z() -> Vec<u8> {
    let mut bytes = vec![0u8];
    bytes.extend(1010u32.to_be_bytes());
    bytes.extend(1u32.to_be_bytes());
    bytes.push(0);
    bytes.extend(1008u32.to_be_bytes());
    bytes.extend(3u32.to_be_bytes());
    for (x, y) in [(0.0f64, 0.0f64), (2.0, 0.0), (0.0, 0.0)] {
        for v in [x, y, 5.0] {
            bytes.extend(v.to_be_bytes());
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::Area;

    fn header(code: u32) -> Vec<u8> {
        let mut bytes = vec![1u8];
        bytes.extend(code.to_le_bytes());
        bytes
    }

    fn with_points(code: u32, points: &[(f64, f64)]) -> Vec<u8> {
        let mut bytes = header(code);
        bytes.extend((points.len() as u32).to_le_bytes());
        for &(x, y) in points {
            bytes.extend(x.to_le_bytes());
            bytes.extend(y.to_le_bytes());
        }
        bytes
    }

    fn with_parts(code: u32, parts: &[Vec<u8>]) -> Vec<u8> {
        let mut bytes = header(code);
        bytes.extend((parts.len() as u32).to_le_bytes());
        parts.iter().for_each(|p| bytes.extend(p));
        bytes
    }

    /// The vertices of the one ring of a one-polygon reading.
    fn ring(bytes: &[u8]) -> Vec<Coord<f64>> {
        let read = to_multi_polygon(bytes).unwrap();
        assert_eq!(read.0.len(), 1);
        read.0[0].exterior().0.clone()
    }

    #[test]
    fn a_circle_is_cut_into_chords_of_at_most_four_degrees() {
        // CURVEPOLYGON(CIRCULARSTRING(0 0, 2 0, 0 0)): the circle of radius 1 about (1, 0).
        let circle = with_parts(
            CURVE_POLYGON,
            &[with_points(
                CIRCULAR_STRING,
                &[(0.0, 0.0), (2.0, 0.0), (0.0, 0.0)],
            )],
        );
        let vertices = ring(&circle);
        assert_eq!(vertices.first(), vertices.last(), "closed");
        let centre = Coord { x: 1.0, y: 0.0 };
        for pair in vertices.windows(2) {
            let radius = (pair[0] - centre).x.hypot((pair[0] - centre).y);
            assert!((radius - 1.0).abs() < 1e-12, "{:?} off the circle", pair[0]);
            // A chord of at most 4° on the unit circle is at most 2 sin 2° long.
            let chord = (pair[1] - pair[0]).x.hypot((pair[1] - pair[0]).y);
            assert!(
                chord <= 2.0 * 2f64.to_radians().sin() + 1e-12,
                "chord {chord}"
            );
        }
        // Inscribed with chords of at most 4°: at least the 90-gon's area, 45 sin(4°), and
        // less than the circle's π.
        let area = to_multi_polygon(&circle).unwrap().unsigned_area();
        let ninety_gon = 45.0 * 4f64.to_radians().sin();
        assert!(
            area >= ninety_gon - 1e-12 && area < std::f64::consts::PI,
            "{area}"
        );
        // Anticlockwise, as GDAL draws a full circle.
        assert!(to_multi_polygon(&circle).unwrap().signed_area() > 0.0);
    }

    #[test]
    fn an_arc_shared_by_two_regions_gives_both_the_same_vertices() {
        // Below: the square (0, -2)–(2, 0) less the cap over the arc (0 0)–(1 -0.7)–(2 0),
        // drawn from (0, 0); above: the square (0, 0)–(2, 2) and that cap, drawing the same
        // arc from (2, 0) the other way.
        let below = with_parts(
            CURVE_POLYGON,
            &[with_parts(
                COMPOUND_CURVE,
                &[
                    with_points(CIRCULAR_STRING, &[(0.0, 0.0), (1.0, -0.7), (2.0, 0.0)]),
                    with_points(
                        LINE_STRING,
                        &[(2.0, 0.0), (2.0, -2.0), (0.0, -2.0), (0.0, 0.0)],
                    ),
                ],
            )],
        );
        let above = with_parts(
            CURVE_POLYGON,
            &[with_parts(
                COMPOUND_CURVE,
                &[
                    with_points(CIRCULAR_STRING, &[(2.0, 0.0), (1.0, -0.7), (0.0, 0.0)]),
                    with_points(
                        LINE_STRING,
                        &[(0.0, 0.0), (0.0, 2.0), (2.0, 2.0), (2.0, 0.0)],
                    ),
                ],
            )],
        );
        let (below, above) = (ring(&below), ring(&above));
        // The arc: the ring below up to (2, 0); the ring above from after (2, 0) to (0, 0).
        let arc_below: Vec<Coord<f64>> = below.iter().take_while(|c| c.x < 2.0).copied().collect();
        let mut arc_above: Vec<Coord<f64>> = above
            .iter()
            .skip(1)
            .take_while(|c| c.x > 0.0)
            .copied()
            .collect();
        arc_above.reverse();
        assert!(arc_below.len() > 10, "{} vertices", arc_below.len());
        assert_eq!(arc_below[1..], arc_above[..], "bit for bit");
        // The junction is not repeated.
        assert!(below.windows(2).all(|w| w[0] != w[1]));
    }

    #[test]
    fn z_m_extended_flags_and_big_endian_are_read() {
        // MULTISURFACE Z (ISO 1012) big-endian, holding a CURVEPOLYGON Z (1010) whose ring
        // is a CIRCULARSTRING Z (1008), and an extended-WKB POLYGON with an SRID.
        let mut bytes = vec![0u8];
        bytes.extend(1012u32.to_be_bytes());
        bytes.extend(2u32.to_be_bytes());
        bytes.extend(big_endian_circle_z());
        bytes.push(1);
        bytes.extend((0x2000_0000u32 | 3).to_le_bytes());
        bytes.extend(4326u32.to_le_bytes());
        bytes.extend(1u32.to_le_bytes());
        bytes.extend(4u32.to_le_bytes());
        for (x, y) in [(5.0f64, 0.0f64), (6.0, 0.0), (5.0, 1.0), (5.0, 0.0)] {
            bytes.extend(x.to_le_bytes());
            bytes.extend(y.to_le_bytes());
        }
        let read = to_multi_polygon(&bytes).unwrap();
        assert_eq!(read.0.len(), 2);
        assert_eq!(read.0[1].unsigned_area(), 0.5);
        assert!((read.0[0].unsigned_area() - std::f64::consts::PI).abs() < 0.01);
    }

    #[test]
    fn curves_that_bound_nothing_and_broken_bytes_are_refused() {
        let arc = with_points(CIRCULAR_STRING, &[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)]);
        let err = to_multi_polygon(&arc).unwrap_err();
        assert!(err.contains("got a CIRCULARSTRING"), "{err}");
        let even = with_parts(
            CURVE_POLYGON,
            &[with_points(CIRCULAR_STRING, &[(0.0, 0.0), (1.0, 1.0)])],
        );
        let err = to_multi_polygon(&even).unwrap_err();
        assert!(err.contains("circular string of 2 points"), "{err}");
        let circle = with_parts(
            CURVE_POLYGON,
            &[with_points(
                CIRCULAR_STRING,
                &[(0.0, 0.0), (2.0, 0.0), (0.0, 0.0)],
            )],
        );
        for len in 0..circle.len() {
            assert!(to_multi_polygon(&circle[..len]).is_err(), "{len} bytes");
        }
        let mut longer = circle.clone();
        longer.push(0);
        let err = to_multi_polygon(&longer).unwrap_err();
        assert!(err.contains("1 bytes after"), "{err}");
        // A count of 2³² − 1 rings in a few bytes is refused before anything is reserved.
        let mut huge = header(CURVE_POLYGON);
        huge.extend(u32::MAX.to_le_bytes());
        let err = to_multi_polygon(&huge).unwrap_err();
        assert!(err.contains("cannot fit"), "{err}");
    }

    #[test]
    fn nesting_is_refused_past_the_straight_readers_depth() {
        // 200,000 multisurfaces one inside the next: refused, not a stack overflow.
        let mut bytes = Vec::new();
        for _ in 0..200_000 {
            bytes.extend(header(MULTI_SURFACE));
            bytes.extend(1u32.to_le_bytes());
        }
        bytes.extend(header(MULTI_SURFACE));
        bytes.extend(0u32.to_le_bytes());
        let err = to_multi_polygon(&bytes).unwrap_err();
        assert!(err.contains("nested more than 128 deep"), "{err}");
        // Compound curves inside compound curves too.
        let mut ring = Vec::new();
        for _ in 0..200_000 {
            ring.extend(header(COMPOUND_CURVE));
            ring.extend(1u32.to_le_bytes());
        }
        ring.extend(with_points(LINE_STRING, &[(0.0, 0.0)]));
        let err = to_multi_polygon(&with_parts(CURVE_POLYGON, &[ring])).unwrap_err();
        assert!(err.contains("nested more than 128 deep"), "{err}");
    }

    #[test]
    fn three_points_in_a_line_are_a_straight_arc() {
        let flat = with_parts(
            CURVE_POLYGON,
            &[with_points(
                CIRCULAR_STRING,
                &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (1.0, 1.0), (0.0, 0.0)],
            )],
        );
        // (0 0)-(1 0)-(2 0) straight, then the arc (2 0)-(1 1)-(0 0) about (1, 0): a half disc.
        let area = to_multi_polygon(&flat).unwrap().unsigned_area();
        assert!((area - std::f64::consts::FRAC_PI_2).abs() < 0.005, "{area}");
    }
}
