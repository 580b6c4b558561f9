//! The working CRS of method.md §0, as a pure rule: the method is planar, so a layer in
//! longitude and latitude is projected first, to an equal-area projection chosen from the
//! regions' extents. The command line applies it with GDAL, the QGIS plugin and the Python
//! package with their own libraries; all three ask this one function, so they agree.
//!
//! - A layer whose longitudes span more than half the globe (a world map) gets Equal Earth,
//!   centred on the middle of its longitudes (EPSG:8857 for a layer centred on Greenwich): an
//!   azimuthal projection would split the Pacific and wrap America round Asia.
//! - A layer that spans more than half the globe's longitudes but lies within 45° of a pole
//!   (the Arctic, the Antarctic) gets Lambert azimuthal equal-area centred on that pole: Equal
//!   Earth would split the regions round the pole on its edge meridian and stretch them along
//!   the bottom or top of the map.
//! - Any other layer gets Lambert azimuthal equal-area centred on its extent.
//!
//! Longitudes are taken across the antimeridian where that is shorter (Fiji, Chukotka and
//! Alaska together span 40°, not 360°).

use super::Error;
use geo::{BooleanOps, BoundingRect, Coord, LineString, MapCoords, MultiPolygon, Polygon, Rect};
use std::borrow::Cow;

/// A region's extent in degrees of longitude (west, east) and latitude (south, north).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LonLatBox {
    pub west: f64,
    pub south: f64,
    pub east: f64,
    pub north: f64,
}

/// The CRS to lay a geographic layer out in.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkingCrs {
    /// Its definition as named WKT2 (ISO 19162:2019), which GDAL, PROJ and QGIS read and show
    /// by name.
    pub wkt: String,
    /// The name a GIS shows, e.g. "Lambert azimuthal equal-area at 39.5N 98.6W (snakegrid)":
    /// ASCII, because GeoPackage writers and QGIS 3.22 turn a degree sign in a CRS name into "?".
    pub name: String,
    /// What the user should be told: which projection, where, and why.
    pub note: String,
    /// Its central meridian, when the globe is split on the meridian opposite, where
    /// [`cut_at_seam`] cuts the regions before they are projected; `None` for a projection
    /// centred on a pole, which splits nothing.
    pub central_meridian: Option<f64>,
}

/// What the user should know about laying a layer out in its own projected CRS `crs` (a name
/// for messages), whose projection method GDAL or QGIS calls `method` (GDAL: "Mercator_1SP",
/// "Popular Visualisation Pseudo Mercator"; PROJ and QGIS: "merc", "webmerc"): a Mercator
/// projection (Web Mercator's too) inflates areas towards the poles, by 1/cos² of the
/// latitude, and the regions' areas set the cell size and the landmasses' budgets (method.md
/// §3, §6). `None` for other projections; a transverse or oblique Mercator (UTM, "tmerc",
/// "omerc") stays true near its line.
pub fn projected_note(method: &str, crs: &str) -> Option<String> {
    let method = method.trim().to_ascii_lowercase();
    let cylindrical_mercator = (method.contains("mercator")
        && !method.contains("transverse")
        && !method.contains("oblique"))
        || method == "merc"
        || method == "webmerc";
    cylindrical_mercator.then(|| {
        format!(
            "the source CRS {crs} is a Mercator projection, which draws areas larger towards the \
             poles (twice at 45°, four times at 60°): the regions are weighed as drawn; lay them \
             out in an equal-area CRS (-t_srs, or QGIS's target CRS; EPSG:8857 for the world) \
             to weigh them as they are"
        )
    })
}

/// Whether a layer without a CRS, whose regions have the extents `boxes`, could be in degrees:
/// every coordinate within ±180 and ±90, and the layer wider than a hundredth of a degree (a
/// layer smaller than a kilometre across is more likely a plan in its own units).
pub fn looks_like_degrees(boxes: &[LonLatBox]) -> bool {
    let (mut west, mut south, mut east, mut north) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for b in boxes {
        west = west.min(b.west);
        south = south.min(b.south);
        east = east.max(b.east);
        north = north.max(b.north);
    }
    (-180.0..=180.0).contains(&west)
        && (-180.0..=180.0).contains(&east)
        && (-90.0..=90.0).contains(&south)
        && (-90.0..=90.0).contains(&north)
        && (east - west).max(north - south) > 0.01
}

/// Longitude spans (the antimeridian-aware range) above this get a world projection.
const WORLD_SPAN: f64 = 180.0;

/// Degrees from a pole within which a layer wider than [`WORLD_SPAN`] is taken round that pole.
/// Within 45° of its centre Lambert azimuthal equal-area changes lengths by at most 8 % (1/cos
/// 22.5° across, cos 22.5° along the radius), less than Equal Earth does at those latitudes away
/// from its central meridian; a layer reaching nearer the equator is more of a world map, and
/// its readers expect one.
const POLAR_REACH: f64 = 45.0;

/// The working CRS for a layer in longitude and latitude whose regions have the extents
/// `boxes`. Refuses coordinates that cannot be longitudes and latitudes (a layer whose CRS is
/// wrong), naming the extent found.
pub fn working_crs(boxes: &[LonLatBox]) -> Result<WorkingCrs, Error> {
    let finite: Vec<LonLatBox> = boxes
        .iter()
        .copied()
        .filter(|b| {
            [b.west, b.south, b.east, b.north]
                .iter()
                .all(|v| v.is_finite())
        })
        .collect();
    let south = finite.iter().map(|b| b.south).reduce(f64::min);
    let north = finite.iter().map(|b| b.north).reduce(f64::max);
    let west = finite.iter().map(|b| b.west).reduce(f64::min);
    let east = finite.iter().map(|b| b.east).reduce(f64::max);
    let (Some(south), Some(north), Some(west), Some(east)) = (south, north, west, east) else {
        return Err(Error::input(
            None,
            "the layer has no coordinates to centre a projection on",
        ));
    };
    // Longitudes from 0 to 360 (a Pacific-centred layer) and a ring's longitudes carried
    // across ±180° (`lon_lat_boxes`) are longitudes still.
    if south < -90.0 || north > 90.0 || west < -540.0 || east > 540.0 {
        return Err(Error::input(
            None,
            format!(
                "the layer's CRS is geographic, but its coordinates are not longitudes and \
                 latitudes (x {west} to {east}, y {south} to {north}): the layer's CRS is wrong"
            ),
        ));
    }
    let (west, east) = longitude_range(finite.iter().map(|b| (b.west, b.east)).collect());
    let lon = wrap((west + east) / 2.0);
    let pole = if south >= 90.0 - POLAR_REACH {
        Some(90.0)
    } else if north <= POLAR_REACH - 90.0 {
        Some(-90.0)
    } else {
        None
    };
    if let (true, Some(pole)) = (east - west > WORLD_SPAN, pole) {
        // The middle of the layer's longitudes runs straight up from the North Pole's
        // projection, or straight down to the South Pole's: north is up there.
        let note = |_: &str| {
            format!(
                "the layer spans {:.0}° of longitude within {POLAR_REACH:.0}° of the {} Pole, so \
                 it is projected to Lambert azimuthal equal-area centred on the pole, the meridian \
                 {} straight {} it (equal-area, keeps the regions round the pole together)",
                east - west,
                if pole > 0.0 { "North" } else { "South" },
                longitude_text(lon),
                if pole > 0.0 { "below" } else { "above" },
            )
        };
        // A projection centred on a pole splits no meridian.
        return Ok(WorkingCrs {
            central_meridian: None,
            ..lambert_azimuthal(pole, lon, note)
        });
    }
    if east - west > WORLD_SPAN {
        let name = if lon.abs() < 1e-9 {
            "WGS 84 / Equal Earth Greenwich".to_owned()
        } else {
            format!("Equal Earth at {} (snakegrid)", longitude_text(lon))
        };
        return Ok(WorkingCrs {
            wkt: projected(&name, "Equal Earth", 1078, &[(LONGITUDE_OF_ORIGIN, lon)]),
            note: format!(
                "the layer spans {:.0}° of longitude, so it is projected to Equal Earth centred \
                 on {} (equal-area, keeps the world in one piece)",
                east - west,
                longitude_text(lon)
            ),
            name,
            central_meridian: Some(lon),
        });
    }
    Ok(lambert_azimuthal((south + north) / 2.0, lon, |centre| {
        format!("projected to Lambert azimuthal equal-area centred on the layer ({centre})")
    }))
}

/// Lambert azimuthal equal-area centred on (`lat`, `lon`), split on the meridian opposite, with
/// the `note` made from its centre as text.
fn lambert_azimuthal(lat: f64, lon: f64, note: impl Fn(&str) -> String) -> WorkingCrs {
    let centre = format!("{} {}", latitude_text(lat), longitude_text(lon));
    let name = format!("Lambert azimuthal equal-area at {centre} (snakegrid)");
    WorkingCrs {
        wkt: projected(
            &name,
            "Lambert Azimuthal Equal Area",
            9820,
            &[(LATITUDE_OF_ORIGIN, lat), (LONGITUDE_OF_ORIGIN, lon)],
        ),
        note: note(&centre),
        name,
        central_meridian: Some(lon),
    }
}

/// An EPSG projection parameter: its name and code.
type ParameterId = (&'static str, u32);
const LATITUDE_OF_ORIGIN: ParameterId = ("Latitude of natural origin", 8801);
const LONGITUDE_OF_ORIGIN: ParameterId = ("Longitude of natural origin", 8802);

/// A projected CRS on WGS 84 in metres, as WKT2: `method` with its EPSG code, the angular
/// `parameters` in degrees (rounded to 1e-6°, about 0.1 m, so that definitions stay short and
/// stable), no false easting or northing.
fn projected(name: &str, method: &str, code: u32, parameters: &[(ParameterId, f64)]) -> String {
    const DEGREE: &str = "ANGLEUNIT[\"degree\",0.0174532925199433]";
    const METRE: &str = "LENGTHUNIT[\"metre\",1]";
    let mut conversion = format!("METHOD[\"{method}\",ID[\"EPSG\",{code}]]");
    for ((parameter, id), value) in parameters {
        let value = (value * 1e6).round() / 1e6 + 0.0;
        conversion.push_str(&format!(
            ",PARAMETER[\"{parameter}\",{value},{DEGREE},ID[\"EPSG\",{id}]]"
        ));
    }
    for (parameter, id) in [("False easting", 8806), ("False northing", 8807)] {
        conversion.push_str(&format!(
            ",PARAMETER[\"{parameter}\",0,{METRE},ID[\"EPSG\",{id}]]"
        ));
    }
    format!(
        "PROJCRS[\"{name}\",BASEGEOGCRS[\"WGS 84\",DATUM[\"World Geodetic System 1984\",\
         ELLIPSOID[\"WGS 84\",6378137,298.257223563,{METRE}]],PRIMEM[\"Greenwich\",0,{DEGREE}]],\
         CONVERSION[\"{name}\",{conversion}],CS[Cartesian,2],\
         AXIS[\"easting (E)\",east,ORDER[1],{METRE}],AXIS[\"northing (N)\",north,ORDER[2],{METRE}]]"
    )
}

/// A longitude in (-180, 180].
fn wrap(lon: f64) -> f64 {
    let wrapped = (lon + 180.0).rem_euclid(360.0) - 180.0;
    if wrapped == -180.0 {
        180.0
    } else {
        wrapped
    }
}

fn longitude_text(lon: f64) -> String {
    let hemisphere = if lon < 0.0 { "W" } else { "E" };
    format!("{:.1}{hemisphere}", lon.abs())
}

fn latitude_text(lat: f64) -> String {
    let hemisphere = if lat < 0.0 { "S" } else { "N" };
    format!("{:.1}{hemisphere}", lat.abs())
}

/// The stretch of longitudes the regions' spans cover: the circle minus the widest gap between
/// them, so that a layer across ±180° is centred on the layer and not on the far side of the
/// Earth. A span is taken on the circle: from 170 to 190 crosses ±180°, as does one from 350
/// to 370, and one of 360° or more covers it all.
fn longitude_range(spans: Vec<(f64, f64)>) -> (f64, f64) {
    let mut arcs = Vec::with_capacity(spans.len());
    for (west, east) in spans {
        if east - west >= 360.0 {
            return (-180.0, 180.0);
        }
        let start = (west + 180.0).rem_euclid(360.0) - 180.0;
        let end = start + (east - west).max(0.0);
        if end > 180.0 {
            arcs.push((start, 180.0));
            arcs.push((-180.0, end - 360.0));
        } else {
            arcs.push((start, end));
        }
    }
    arcs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let west = arcs[0].0;
    let east = arcs.iter().map(|a| a.1).fold(f64::NEG_INFINITY, f64::max);
    // The gap across ±180° gives the plain range; a wider one between two arcs moves the
    // layer's west end to the arc after it.
    let (mut widest, mut range) = (west + 360.0 - east, (west, east));
    let mut reach = arcs[0].1;
    for &(start, end) in &arcs[1..] {
        if start - reach > widest {
            widest = start - reach;
            range = (start, reach + 360.0);
        }
        reach = reach.max(end);
    }
    range
}

/// Whether a ring steps more than half way round the globe between two vertices: it crosses
/// ±180° drawn the short way (Chukotka in d3's world-atlas and in many TopoJSON files), or it
/// goes round a pole.
fn jumps(ring: &LineString<f64>) -> bool {
    ring.0.windows(2).any(|w| (w[1].x - w[0].x).abs() > 180.0)
}

/// `ring` with its longitudes made continuous: each step of more than 180° is taken the short
/// way, across ±180°. `None` when the ring does not close that way, since it goes round a pole
/// (Antarctica, closed along the pole's parallel): drawn from -180 to 180, it is right as it is.
fn unwrapped(ring: &LineString<f64>) -> Option<LineString<f64>> {
    let mut shift = 0.0;
    let mut previous = ring.0.first()?.x;
    let coords = ring.0.iter().map(|c| {
        if c.x - previous > 180.0 {
            shift -= 360.0;
        } else if c.x - previous < -180.0 {
            shift += 360.0;
        }
        previous = c.x;
        Coord {
            x: c.x + shift,
            y: c.y,
        }
    });
    let coords: Vec<Coord<f64>> = coords.collect();
    (shift == 0.0).then_some(LineString(coords))
}

/// A ring as the globe has it: unwrapped where it crosses ±180°, else as drawn.
fn continuous(ring: &LineString<f64>) -> Cow<'_, LineString<f64>> {
    if jumps(ring) {
        unwrapped(ring).map_or(Cow::Borrowed(ring), Cow::Owned)
    } else {
        Cow::Borrowed(ring)
    }
}

/// The extent of each part of a region in longitude and latitude, for [`working_crs`]: a
/// region across ±180° is either drawn as parts on both sides, or as rings that step across
/// it; a box of the whole region, or of a stepping ring as drawn, would span the globe and make
/// a country a world map. A part's holes lie within its shell.
pub fn lon_lat_boxes(region: &MultiPolygon<f64>) -> Vec<LonLatBox> {
    region
        .0
        .iter()
        .filter_map(|part| continuous(part.exterior()).bounding_rect())
        .map(|b| LonLatBox {
            west: b.min().x,
            south: b.min().y,
            east: b.max().x,
            north: b.max().y,
        })
        .collect()
}

/// `region` (longitude and latitude) ready for a projection centred on `central`, which
/// splits the globe on the meridian opposite (the seam): each ring made continuous across
/// ±180°, each part moved by whole turns to within `central` ± 180°, and a part that crosses
/// the seam cut there, its pieces on either edge of the map. `None` when every ring is
/// continuous and within `central` ± 180° already (nearly every region: one pass over the
/// coordinates). A projection would otherwise draw a part that steps across ±180° as a band
/// round the globe.
pub fn cut_at_seam(region: &MultiPolygon<f64>, central: f64) -> Option<MultiPolygon<f64>> {
    let (west_edge, east_edge) = (central - 180.0, central + 180.0);
    let within = |ring: &LineString<f64>, slack: f64| {
        matches!(continuous(ring), Cow::Borrowed(_))
            && (ring.0.iter()).all(|c| (west_edge - slack..=east_edge + slack).contains(&c.x))
    };
    let all_within = |slack: f64| {
        (region.0.iter()).all(|part| {
            within(part.exterior(), slack) && part.interiors().iter().all(|r| within(r, slack))
        })
    };
    if all_within(0.0) {
        return None;
    }
    // A vertex a rounding error past the seam (180.00000000000006 after a reprojection) is
    // moved onto it: the projection would carry it to the far edge of the map.
    if all_within(SEAM_ROUNDING) {
        return Some(region.map_coords(|c| Coord {
            x: c.x.clamp(west_edge, east_edge),
            ..c
        }));
    }
    let mut pieces = Vec::new();
    for part in &region.0 {
        let exterior = continuous(part.exterior()).into_owned();
        let Some(extent) = exterior.bounding_rect() else {
            continue;
        };
        let middle = (extent.min().x + extent.max().x) / 2.0;
        // A hole unwrapped on its own may lie a whole turn from its shell.
        let holes = part.interiors().iter().map(|hole| {
            let hole = continuous(hole).into_owned();
            let centre = hole.bounding_rect().map_or(middle, |b| b.center().x);
            let turns = ((middle - centre) / 360.0).round();
            shifted(&hole, 360.0 * turns)
        });
        let part = Polygon::new(exterior, holes.collect());
        // The turns of the globe the part spans, one meridian on the seam counting to the west.
        let first = ((extent.min().x - west_edge) / 360.0).floor() as i64;
        let last = (((extent.max().x - west_edge) / 360.0).ceil() as i64 - 1).max(first);
        if first == last {
            pieces.push(shifted(&part, -360.0 * first as f64));
            continue;
        }
        for turn in first..=last {
            let offset = 360.0 * turn as f64;
            let band = Rect::new(
                Coord {
                    x: west_edge + offset,
                    y: extent.min().y - 1.0,
                },
                Coord {
                    x: east_edge + offset,
                    y: extent.max().y + 1.0,
                },
            )
            .to_polygon();
            let clipped = part.intersection(&band);
            // The overlay rounds a vertex on the seam to within about 1e-9 of the extent, and
            // one rounded past the seam would be projected to the far edge of the map.
            pieces.extend(clipped.0.into_iter().map(|p| {
                p.map_coords(|c| Coord {
                    x: (c.x - offset).clamp(west_edge, east_edge),
                    ..c
                })
            }));
        }
    }
    Some(MultiPolygon(pieces))
}

/// Degrees past the seam that are a rounding error, not a crossing (about 0.1 mm).
const SEAM_ROUNDING: f64 = 1e-9;

/// `geometry` moved `dx` degrees east.
fn shifted<G: MapCoords<f64, f64>>(geometry: &G, dx: f64) -> G::Output {
    geometry.map_coords(|c| Coord { x: c.x + dx, ..c })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(spans: &[(f64, f64, f64, f64)]) -> Vec<LonLatBox> {
        spans
            .iter()
            .map(|&(west, south, east, north)| LonLatBox {
                west,
                south,
                east,
                north,
            })
            .collect()
    }

    #[test]
    fn a_layer_across_the_antimeridian_runs_past_180() {
        let fiji = vec![
            (177.0, 178.5),
            (178.5, 180.0),
            (-180.0, -178.0),
            (-179.0, -178.5),
        ];
        assert_eq!(longitude_range(fiji), (177.0, 182.0));
    }

    #[test]
    fn other_layers_keep_their_plain_range() {
        assert_eq!(
            longitude_range(vec![(5.0, 10.0), (-3.0, 4.0)]),
            (-3.0, 10.0)
        );
        // A region that spans the world leaves no gap to move the ends to.
        let world = vec![(-180.0, 180.0), (170.0, 175.0)];
        assert_eq!(longitude_range(world), (-180.0, 180.0));
    }

    #[test]
    fn spans_are_taken_on_the_circle() {
        // A ring carried across ±180° (lon_lat_boxes), and a layer drawn from 0 to 360.
        assert_eq!(
            longitude_range(vec![(170.0, 190.0), (150.0, 160.0)]),
            (150.0, 190.0)
        );
        assert_eq!(
            longitude_range(vec![(350.0, 355.0), (5.0, 10.0)]),
            (-10.0, 10.0)
        );
    }

    /// A square ring from `west` to `east` (degrees), drawn as a lon/lat file draws it: its
    /// longitudes wrapped into -180..180, so a ring across ±180° steps from 180 to -180.
    fn wrapped_square(west: f64, east: f64, south: f64, north: f64) -> Polygon<f64> {
        let steps = 8;
        let mut coords = Vec::new();
        for k in 0..=steps {
            coords.push((west + (east - west) * k as f64 / steps as f64, south));
        }
        for k in 0..=steps {
            coords.push((east - (east - west) * k as f64 / steps as f64, north));
        }
        coords.push((west, south));
        let wrap = |x: f64| (x + 180.0).rem_euclid(360.0) - 180.0;
        Polygon::new(
            coords
                .into_iter()
                .map(|(x, y)| Coord { x: wrap(x), y })
                .collect(),
            vec![],
        )
    }

    fn area(p: &MultiPolygon<f64>) -> f64 {
        use geo::Area;
        p.unsigned_area()
    }

    #[test]
    fn a_region_stepping_across_the_antimeridian_is_one_country_not_the_world() {
        // Russia as d3's world-atlas draws it: Kaliningrad, and a mainland whose rings step
        // from 180 to -180 (Chukotka); its box as drawn is the whole globe.
        let russia = MultiPolygon(vec![
            wrapped_square(19.6, 22.9, 54.3, 55.3),
            wrapped_square(27.0, 190.0, 41.2, 77.7),
        ]);
        let boxes = lon_lat_boxes(&russia);
        assert_eq!((boxes[1].west, boxes[1].east), (27.0, 190.0));
        let crs = working_crs(&boxes).unwrap();
        assert!(crs.name.starts_with("Lambert azimuthal"), "{}", crs.name);
        assert!((crs.central_meridian.unwrap() - 104.8).abs() < 1e-9);
        // Centred there, the mainland is carried across ±180° whole, not cut.
        let ready = cut_at_seam(&russia, 104.8).unwrap();
        assert_eq!(ready.0.len(), 2);
        let mainland = ready.0[1].bounding_rect().unwrap();
        assert_eq!((mainland.min().x, mainland.max().x), (27.0, 190.0));
        assert!((area(&ready) - (3.3 * 1.0 + 163.0 * 36.5)).abs() < 1e-6);
    }

    #[test]
    fn on_a_world_map_a_region_across_the_seam_is_cut_there() {
        let chukotka = MultiPolygon(vec![wrapped_square(170.0, 190.0, 62.0, 70.0)]);
        let cut = cut_at_seam(&chukotka, 0.0).unwrap();
        let mut spans: Vec<(f64, f64)> = (cut.0.iter())
            .map(|p| p.bounding_rect().unwrap())
            .map(|b| (b.min().x, b.max().x))
            .collect();
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(spans.len(), 2);
        assert!((spans[0].0 + 180.0).abs() < 1e-7 && (spans[0].1 + 170.0).abs() < 1e-7);
        assert!((spans[1].0 - 170.0).abs() < 1e-7 && (spans[1].1 - 180.0).abs() < 1e-7);
        assert!((area(&cut) - 20.0 * 8.0).abs() < 1e-6);
        // Not a hair past ±180°, which the projection would carry to the far edge.
        assert!(cut
            .0
            .iter()
            .flat_map(|p| p.exterior().0.iter())
            .all(|c| c.x.abs() <= 180.0));
        // A region within the map, as drawn, is left alone.
        let france = MultiPolygon(vec![wrapped_square(-5.0, 8.0, 42.0, 51.0)]);
        assert_eq!(cut_at_seam(&france, 0.0), None);
        assert_eq!(cut_at_seam(&chukotka, 175.0).map(|c| area(&c)), Some(160.0));
        // Fiji taken back to lon/lat from Equal Earth reaches 180.00000000000006: put on 180.
        let east = 180.00000000000006;
        let rounded = MultiPolygon(vec![Polygon::new(
            LineString::from(vec![
                (178.0, -18.0),
                (east, -18.0),
                (east, -16.0),
                (178.0, -18.0),
            ]),
            vec![],
        )]);
        let onto = cut_at_seam(&rounded, 0.0).unwrap();
        assert_eq!(
            onto.0[0].exterior().0.len(),
            rounded.0[0].exterior().0.len()
        );
        assert!(onto.0[0].exterior().0.iter().all(|c| c.x <= 180.0));
    }

    #[test]
    fn a_ring_round_the_pole_is_kept_and_cut_where_the_map_is_split() {
        // Antarctica: its coast from -180 to 180, closed along the pole's parallel.
        let antarctica = MultiPolygon(vec![Polygon::new(
            LineString::from(vec![
                (-180.0, -70.0),
                (0.0, -65.0),
                (180.0, -70.0),
                (180.0, -90.0),
                (-180.0, -90.0),
                (-180.0, -70.0),
            ]),
            vec![],
        )]);
        assert_eq!(lon_lat_boxes(&antarctica)[0].east, 180.0);
        assert_eq!(cut_at_seam(&antarctica, 0.0), None);
        let pacific = cut_at_seam(&antarctica, -160.0).unwrap();
        assert_eq!(pacific.0.len(), 2);
        // The overlay rounds a new vertex to about 1e-9 of the extent (2e-7°, 2 cm here).
        assert!(
            (area(&pacific) - area(&antarctica)).abs() < 1e-4,
            "{pacific:?}"
        );
        for part in &pacific.0 {
            let b = part.bounding_rect().unwrap();
            assert!(
                b.min().x >= -340.0 - 1e-9 && b.max().x <= 20.0 + 1e-9,
                "{b:?}"
            );
        }
    }

    #[test]
    fn a_country_gets_lambert_azimuthal_at_its_centre() {
        let crs = working_crs(&boxes(&[(-125.0, 24.0, -66.0, 50.0)])).unwrap();
        assert_eq!(
            crs.name,
            "Lambert azimuthal equal-area at 37.0N 95.5W (snakegrid)"
        );
        assert!(crs
            .wkt
            .contains("METHOD[\"Lambert Azimuthal Equal Area\",ID[\"EPSG\",9820]]"));
        assert!(crs.wkt.contains("\"Latitude of natural origin\",37,"));
        assert!(crs.wkt.contains("\"Longitude of natural origin\",-95.5,"));
        assert!(crs.note.contains("37.0N 95.5W"), "{}", crs.note);
    }

    #[test]
    fn fiji_is_centred_on_the_antimeridian() {
        let crs = working_crs(&boxes(&[
            (177.0, -19.0, 180.0, -16.0),
            (-180.0, -19.0, -178.0, -16.0),
        ]))
        .unwrap();
        assert!(crs.name.contains("179.5E"), "{}", crs.name);
    }

    #[test]
    fn coordinates_within_the_globe_look_like_degrees() {
        assert!(looks_like_degrees(&boxes(&[(-17.0, -35.0, 51.0, 37.0)])));
        // Metres; then a y beyond ±90.
        assert!(!looks_like_degrees(&boxes(&[(
            500000.0, 5000000.0, 503000.0, 5001000.0
        )])));
        assert!(!looks_like_degrees(&boxes(&[(
            -100.0, -120.0, 100.0, 80.0
        )])));
        assert!(!looks_like_degrees(&boxes(&[])));
    }

    #[test]
    fn only_a_cylindrical_mercator_gets_a_note() {
        // GDAL's WKT1 names for EPSG:3857, EPSG:3395 and a UTM zone, and an equal-area CRS.
        let web = projected_note("Mercator_1SP", "EPSG:3857").unwrap();
        assert!(web.contains("EPSG:3857") && web.contains("-t_srs"), "{web}");
        assert!(projected_note("Mercator_2SP", "EPSG:3395").is_some());
        assert!(projected_note("Popular Visualisation Pseudo Mercator", "x").is_some());
        assert_eq!(projected_note("Transverse_Mercator", "EPSG:32633"), None);
        // PROJ's and QGIS's acronyms.
        assert!(projected_note("merc", "EPSG:3857").is_some());
        assert!(projected_note("webmerc", "EPSG:3857").is_some());
        assert_eq!(projected_note("tmerc", "EPSG:32633"), None);
        assert_eq!(projected_note("omerc", "EPSG:2056"), None);
        assert_eq!(projected_note("laea", "EPSG:3035"), None);
        assert_eq!(projected_note("Hotine_Oblique_Mercator", "x"), None);
        assert_eq!(projected_note("Albers_Conic_Equal_Area", "EPSG:5070"), None);
    }

    #[test]
    fn the_world_gets_equal_earth() {
        let world = working_crs(&boxes(&[(-180.0, -90.0, 180.0, 83.0)])).unwrap();
        assert_eq!(world.name, "WGS 84 / Equal Earth Greenwich");
        assert!(world
            .wkt
            .contains("METHOD[\"Equal Earth\",ID[\"EPSG\",1078]]"));
        assert!(world.note.contains("360°"), "{}", world.note);
        // Over 180° of longitude is a world map too; centred on the middle of its longitudes.
        let pacific = working_crs(&boxes(&[
            (100.0, -50.0, 180.0, 60.0),
            (-180.0, -50.0, -60.0, 60.0),
        ]))
        .unwrap();
        assert_eq!(pacific.name, "Equal Earth at 160.0W (snakegrid)");
        // Exactly half the globe is still one country's azimuthal projection.
        let half = working_crs(&boxes(&[(-90.0, 0.0, 90.0, 10.0)])).unwrap();
        assert!(half.name.starts_with("Lambert"), "{}", half.name);
    }

    #[test]
    fn a_layer_round_a_pole_is_centred_on_the_pole() {
        // The Antarctic: all longitudes, south of 60°S; the pole's meridian points at 0°.
        let antarctic = working_crs(&boxes(&[(-180.0, -90.0, 180.0, -60.0)])).unwrap();
        assert_eq!(
            antarctic.name,
            "Lambert azimuthal equal-area at 90.0S 0.0E (snakegrid)"
        );
        assert!(antarctic.wkt.contains(
            "PARAMETER[\"Latitude of natural origin\",-90,ANGLEUNIT[\"degree\",0.0174532925199433]"
        ));
        assert_eq!(antarctic.central_meridian, None);
        assert!(antarctic.note.contains("South Pole"), "{}", antarctic.note);
        // An Arctic ring from Alaska round to Chukotka, 51°N at its southernmost, open over
        // Greenwich: centred on the middle of its longitudes, across the Bering Strait, which
        // runs straight down from the North Pole.
        let arctic = working_crs(&boxes(&[
            (-170.0, 51.0, -10.0, 83.0),
            (10.0, 60.0, 178.0, 81.0),
        ]))
        .unwrap();
        assert_eq!(
            arctic.name,
            "Lambert azimuthal equal-area at 90.0N 180.0E (snakegrid)"
        );
        assert!(arctic.note.contains("North Pole"), "{}", arctic.note);
        // A layer round the pole that reaches to 40°N is a world map (45° from the pole).
        let northern = working_crs(&boxes(&[(-180.0, 40.0, 180.0, 83.0)])).unwrap();
        assert_eq!(northern.name, "WGS 84 / Equal Earth Greenwich");
        // Near a pole but narrower than 180° (Greenland): centred on the layer, as any other.
        let greenland = working_crs(&boxes(&[(-73.0, 59.8, -11.0, 83.6)])).unwrap();
        assert!(greenland.name.contains("71.7N 42.0W"), "{}", greenland.name);
        assert_eq!(greenland.central_meridian, Some(-42.0));
    }

    #[test]
    fn coordinates_that_are_not_degrees_are_refused() {
        let err = working_crs(&boxes(&[(0.0, 0.0, 10003.0, 3.0)])).unwrap_err();
        assert!(
            err.to_string()
                .contains("not longitudes and latitudes (x 0 to 10003, y 0 to 3)"),
            "{err}"
        );
        assert!(working_crs(&[]).is_err());
    }
}
