//! The working CRS of method.md §0, as a pure rule: the method is planar, so a layer in
//! longitude and latitude is projected first, to an equal-area projection chosen from the
//! regions' extents. The command line applies it with GDAL, the QGIS plugin and the Python
//! package with their own libraries; all three ask this one function, so they agree.
//!
//! - A layer whose longitudes span more than half the globe (a world map) gets Equal Earth,
//!   centred on the middle of its longitudes (EPSG:8857 for a layer centred on Greenwich): an
//!   azimuthal projection would split the Pacific and wrap America round Asia.
//! - Any other layer gets Lambert azimuthal equal-area centred on its extent.
//!
//! Longitudes are taken across the antimeridian where that is shorter (Fiji, Chukotka and
//! Alaska together span 40°, not 360°).

use super::Error;

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
    let range = longitude_range(finite.iter().map(|b| (b.west, b.east)).collect());
    let (Some(south), Some(north), Some((west, east))) = (south, north, range) else {
        return Err(Error::input(
            None,
            "the layer has no coordinates to centre a projection on",
        ));
    };
    if south < -90.0 || north > 90.0 || west < -540.0 || east > 540.0 {
        return Err(Error::input(
            None,
            format!(
                "the layer's CRS is geographic, but its coordinates are not longitudes and \
                 latitudes (x {west} to {east}, y {south} to {north}): the layer's CRS is wrong"
            ),
        ));
    }
    let lon = wrap((west + east) / 2.0);
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
        });
    }
    let lat = (south + north) / 2.0;
    let centre = format!("{} {}", latitude_text(lat), longitude_text(lon));
    let name = format!("Lambert azimuthal equal-area at {centre} (snakegrid)");
    Ok(WorkingCrs {
        wkt: projected(
            &name,
            "Lambert Azimuthal Equal Area",
            9820,
            &[(LATITUDE_OF_ORIGIN, lat), (LONGITUDE_OF_ORIGIN, lon)],
        ),
        note: format!("projected to Lambert azimuthal equal-area centred on the layer ({centre})"),
        name,
    })
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
/// Earth. Spans outside -180..180 (a wrong CRS, which the caller refuses) are taken as they are.
fn longitude_range(mut spans: Vec<(f64, f64)>) -> Option<(f64, f64)> {
    let west = spans.iter().map(|s| s.0).reduce(f64::min)?;
    let east = spans.iter().map(|s| s.1).reduce(f64::max)?;
    if west < -180.0 || east > 180.0 {
        return Some((west, east));
    }
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    // The gap across ±180° gives the plain range; a wider one between two regions moves the
    // layer's west end to the region after it.
    let (mut widest, mut range) = (west + 360.0 - east, (west, east));
    let mut reach = spans[0].1;
    for &(start, end) in &spans[1..] {
        if start - reach > widest {
            widest = start - reach;
            range = (start, reach + 360.0);
        }
        reach = reach.max(end);
    }
    Some(range)
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
        assert_eq!(longitude_range(fiji), Some((177.0, 182.0)));
    }

    #[test]
    fn other_layers_keep_their_plain_range() {
        assert_eq!(
            longitude_range(vec![(5.0, 10.0), (-3.0, 4.0)]),
            Some((-3.0, 10.0))
        );
        // A region that spans the world leaves no gap to move the ends to.
        let world = vec![(-180.0, 180.0), (170.0, 175.0)];
        assert_eq!(longitude_range(world), Some((-180.0, 180.0)));
        assert_eq!(longitude_range(Vec::new()), None);
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
