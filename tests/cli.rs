//! The `snakegrid` command end to end on the shared layers: outputs are read back with GDAL.
//!
//! Inputs are copied to a scratch folder under the system temp dir (the shared data is never
//! written to). The data folder is `$SNAKEGRID_DATA`, else `../shared/data`.
// Reads and writes datasets: needs the GDAL layer.
#![cfg(feature = "gdal")]

use gdal::spatial_ref::SpatialRef;
use gdal::vector::{Feature, FieldValue, Geometry, LayerAccess, LayerOptions, OGRFieldType};
use gdal::{Dataset, DriverManager};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

mod common;
use common::cli::{assert_fails, assert_success, p, snakegrid, stderr, stdout};
use common::{shared_layer as data, Scratch};

/// One output feature: attributes as text and the ring of its square.
struct Row {
    fields: BTreeMap<String, String>,
    ring: Vec<(f64, f64)>,
}

fn text(value: Option<FieldValue>) -> String {
    match value {
        Some(FieldValue::StringValue(s)) => s,
        Some(FieldValue::IntegerValue(v)) => v.to_string(),
        Some(FieldValue::Integer64Value(v)) => v.to_string(),
        Some(FieldValue::RealValue(v)) => v.to_string(),
        Some(other) => format!("{other:?}"),
        None => String::new(),
    }
}

fn read_rows(path: &Path) -> (Vec<String>, Vec<Row>) {
    let dataset = Dataset::open(path).unwrap();
    let mut layer = dataset.layer(0).unwrap();
    let names: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
    let rows = layer
        .features()
        .map(|f| {
            let fields = names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.clone(), text(f.field(i).unwrap())))
                .collect();
            let geometry = f.geometry().unwrap();
            let polygon = if geometry.geometry_count() == 1 && geometry.geometry_name() == "POLYGON"
            {
                geometry.get_geometry(0)
            } else {
                panic!(
                    "a cell is not a simple polygon: {}",
                    geometry.geometry_name()
                )
            };
            let mut points = Vec::new();
            polygon.get_points(&mut points);
            Row {
                fields,
                ring: points.into_iter().map(|(x, y, _)| (x, y)).collect(),
            }
        })
        .collect();
    (names, rows)
}

fn source_fields(layer: &str) -> Vec<String> {
    let dataset = Dataset::open(data(layer)).unwrap();
    let layer = dataset.layer(0).unwrap();
    layer.defn().fields().map(|f| f.name()).collect()
}

const ADDED: [&str; 8] = [
    "grid_col",
    "grid_row",
    "grid_q",
    "grid_r",
    "cell_disp",
    "nbr_kept",
    "orient_err",
    "grid_group",
];

/// Every row is an axis-aligned square of the same side, placed as its (grid_col, grid_row) says
/// (so distinct cells cannot overlap), and no two rows share a cell. Returns (id → (col, row)).
fn assert_grid(rows: &[Row], id_field: &str) -> HashMap<String, (i32, i32)> {
    let square = |ring: &[(f64, f64)]| {
        assert_eq!(ring.len(), 5, "a square has 4 corners and a closing point");
        let xs: Vec<f64> = ring.iter().map(|p| p.0).collect();
        let ys: Vec<f64> = ring.iter().map(|p| p.1).collect();
        let (x0, x1) = (
            xs.iter().cloned().fold(f64::MAX, f64::min),
            xs.iter().cloned().fold(f64::MIN, f64::max),
        );
        let (y0, y1) = (
            ys.iter().cloned().fold(f64::MAX, f64::min),
            ys.iter().cloned().fold(f64::MIN, f64::max),
        );
        for &(x, y) in ring {
            assert!((x - x0).abs() < 1e-6 * (x1 - x0) || (x - x1).abs() < 1e-6 * (x1 - x0));
            assert!((y - y0).abs() < 1e-6 * (y1 - y0) || (y - y1).abs() < 1e-6 * (y1 - y0));
        }
        (x0, y1, x1 - x0, y1 - y0)
    };
    let (ox, oy, side, _) = square(&rows[0].ring);
    let cell_of = |row: &Row| -> (i32, i32) {
        (
            row.fields["grid_col"].parse().unwrap(),
            row.fields["grid_row"].parse().unwrap(),
        )
    };
    let (c0, r0) = cell_of(&rows[0]);
    let mut cells = HashMap::new();
    let mut taken = HashSet::new();
    for row in rows {
        let (x, y, w, h) = square(&row.ring);
        assert!(
            (w - side).abs() < 1e-6 * side && (h - side).abs() < 1e-6 * side,
            "unequal cells"
        );
        let (c, r) = cell_of(row);
        assert!(
            (x - (ox + f64::from(c - c0) * side)).abs() < 1e-6 * side,
            "column does not match x"
        );
        assert!(
            (y - (oy - f64::from(r - r0) * side)).abs() < 1e-6 * side,
            "row does not match y"
        );
        assert!(taken.insert((c, r)), "two regions share cell {c},{r}");
        cells.insert(row.fields[id_field].clone(), (c, r));
    }
    cells
}

/// The full check of one layer's output: one feature per input, all fields, a proper grid.
fn assert_complete(layer: &str, output: &Path) -> HashMap<String, (i32, i32)> {
    let (names, rows) = read_rows(output);
    let mut expected = source_fields(layer);
    expected.extend(ADDED.iter().map(|s| s.to_string()));
    assert_eq!(names, expected);
    let input = Dataset::open(data(layer)).unwrap();
    assert_eq!(rows.len() as u64, input.layer(0).unwrap().feature_count());
    assert_grid(&rows, "id")
}

// ---------------------------------------------------------------------------------------------
// The command line itself.

#[test]
fn help_documents_every_option_and_parameter_with_its_default() {
    let output = snakegrid(["--help"]);
    assert_success(&output);
    let help = stdout(&output);
    for option in [
        "-f <FORMAT>",
        "--nln",
        "--overwrite",
        "--update",
        "--s_srs",
        "--lco",
        "--dsco",
        "--where",
        "--id",
        "--t_srs",
        "--json",
        "--svg",
        "--label",
        "-q",
        "--version",
    ] {
        assert!(help.contains(option), "--help lacks {option}");
    }
    // Every parameter in the table's order, under its group's heading, with its summary,
    // range and default as the table gives them (whitespace folded, as clap wraps lines).
    let folded: String = help.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut at = 0;
    for p in snakegrid::PARAMETERS {
        let heading = folded[..]
            .find(p.group.title())
            .unwrap_or_else(|| panic!("no heading {}", p.group.title()));
        let entry = format!("--{} <VALUE> {}; {}", p.name, p.summary, p.range_text());
        let found = folded[at..]
            .find(&entry)
            .unwrap_or_else(|| panic!("--help lacks {entry:?} after position {at}"));
        assert!(heading < at + found, "{} comes after its heading", p.name);
        at += found;
        let default = format!("[default: {}]", p.default_text());
        assert!(
            folded[at..].split("--").nth(1).unwrap().contains(&default),
            "{} shows {default}",
            p.name
        );
    }
    // ogr2ogr spelling works for help too.
    assert_success(&snakegrid(["-help"]));
}

#[test]
fn version_names_snakegrid_and_gdal() {
    for flag in ["--version", "-version"] {
        let output = snakegrid([flag]);
        assert_success(&output);
        let text = stdout(&output);
        assert!(
            text.starts_with(&format!("snakegrid {} (GDAL 3.", env!("CARGO_PKG_VERSION"))),
            "{text}"
        );
    }
}

#[test]
fn an_unknown_option_is_a_usage_error_and_writes_nothing() {
    let scratch = Scratch::new("unknown-option");
    let src = scratch.input("us_states");
    let output = snakegrid(["-frobnicate", "3", p(&scratch.path("out.gpkg")), p(&src)]);
    assert_fails(&output, 2, "-frobnicate");
    assert_eq!(scratch.listing(), ["us_states.gpkg"]);
}

#[test]
fn a_bad_parameter_value_is_a_usage_error() {
    let scratch = Scratch::new("bad-parameter");
    let src = scratch.input("us_states");
    let output = snakegrid(["-force_cap", "2", p(&scratch.path("out.gpkg")), p(&src)]);
    assert_fails(&output, 2, "force_cap");
    let output = snakegrid(["-alpha", "-1", p(&scratch.path("out.gpkg")), p(&src)]);
    assert_fails(&output, 2, "alpha");
    assert_eq!(scratch.listing(), ["us_states.gpkg"]);
    // Values that once passed and then failed deep inside the Snake are refused by name before
    // the source is even opened (it does not exist here).
    let missing = scratch.path("no-such-source.gpkg");
    for (name, value, message) in [
        (
            "alpha",
            "1e308",
            "parameter alpha must be in [0.001, 1000], got 1e308",
        ),
        (
            "beta",
            "1e308",
            "parameter beta must be in [0.001, 1000], got 1e308",
        ),
        (
            "spring",
            "1e-300",
            "parameter spring must be in [0.0001, 1], got 1e-300",
        ),
        ("alpha", "nan", "parameter alpha: expected a finite number"),
    ] {
        let output = snakegrid([
            &format!("-{name}"),
            value,
            p(&scratch.path("out.gpkg")),
            p(&missing),
        ]);
        assert_fails(&output, 2, message);
    }
}

#[test]
fn a_missing_source_fails_with_one_line() {
    let scratch = Scratch::new("missing-source");
    let output = snakegrid([
        p(&scratch.path("out.gpkg")),
        p(&scratch.path("nowhere.gpkg")),
    ]);
    assert_fails(&output, 1, "nowhere.gpkg");
    assert!(scratch.listing().is_empty());
}

#[test]
fn a_missing_layer_fails_and_lists_the_layers() {
    let scratch = Scratch::new("missing-layer");
    let src = scratch.input("us_states");
    let output = snakegrid([p(&scratch.path("out.gpkg")), p(&src), "counties"]);
    assert_fails(&output, 1, "counties");
    assert!(stderr(&output).contains("us_states"));
    assert_eq!(scratch.listing(), ["us_states.gpkg"]);
}

#[test]
fn of_several_layers_the_first_is_laid_out_and_the_others_are_named() {
    let scratch = Scratch::new("several-layers");
    let src = scratch.input("us_states");
    // Two layers in one GeoPackage: the US states' grid map, twice.
    let both = scratch.path("both.gpkg");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-nln",
        "first",
        p(&both),
        p(&src),
    ]));
    let again = [
        "-q",
        "-id",
        "id",
        "-update",
        "-nln",
        "second",
        p(&both),
        p(&src),
    ];
    assert_success(&snakegrid(again));
    let output = snakegrid(["-id", "id", p(&scratch.path("out.gpkg")), p(&both)]);
    assert_success(&output);
    assert!(
        stdout(&output).contains(
            "note: the source has 2 layers (first, second): laid out the first, \"first\""
        ),
        "{}",
        stdout(&output)
    );
    // Named, no note.
    let named = snakegrid([
        "-id",
        "id",
        p(&scratch.path("out2.gpkg")),
        p(&both),
        "second",
    ]);
    assert_success(&named);
    assert!(!stdout(&named).contains("layers ("), "{}", stdout(&named));
}

#[test]
fn a_polygon_that_crosses_itself_only_once_projected_is_said_to_be_valid_as_drawn() {
    let scratch = Scratch::new("projected-repair");
    let src = scratch.path("lonlat.gpkg");
    // A "C" whose east side is one edge along the meridian 170°E from 60°S to 60°N, and whose
    // notch reaches 169.5°E at the equator, half a degree inside it. Equal Earth bows a meridian
    // outwards towards the equator (x at 170°E is about 1.3 times larger on the equator than at
    // 60°) while the edge stays a straight chord between its projected ends, so the notch's tip
    // lands beyond it: valid in lon/lat, crossing itself once projected.
    let c = "POLYGON((170 -60,170 60,100 60,100 1,169.5 0,100 -1,100 -60,170 -60))";
    // A bow-tie, invalid as drawn, beside it.
    let bow = "POLYGON((0 0,10 10,10 0,0 10,0 0))";
    write_regions(
        &src,
        4326,
        &[("c".into(), c.into()), ("bow".into(), bow.into())],
    );
    let dst = scratch.path("grid.gpkg");
    let output = snakegrid(["-id", "code", "-t_srs", "EPSG:8857", p(&dst), p(&src)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(
        summary.contains("note: feature c: invalid polygon repaired")
            && summary.contains("note: feature bow: invalid polygon repaired"),
        "{summary}"
    );
    assert!(
        summary.contains("note: feature c is valid as drawn in the source's CRS")
            && !summary.contains("bow is valid"),
        "{summary}"
    );
    // Laid out where it is drawn (no projection), the bow-tie is repaired and said to be
    // invalid as drawn, with no such note.
    let planar = scratch.path("planar.gpkg");
    write_regions(&planar, 8857, &[("bow".into(), bow.into())]);
    let output = snakegrid(["-id", "code", p(&scratch.path("grid2.gpkg")), p(&planar)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(
        summary.contains("feature bow: invalid polygon repaired")
            && !summary.contains("valid as drawn"),
        "{summary}"
    );
}

#[test]
fn a_mercator_source_is_laid_out_as_drawn_with_a_note() {
    let scratch = Scratch::new("mercator");
    let src = scratch.input("us_states");
    // The US states' grid map in Web Mercator, as a source.
    let web = scratch.path("web.gpkg");
    let to_web = ["-q", "-id", "id", "-t_srs", "EPSG:3857", p(&web), p(&src)];
    assert_success(&snakegrid(to_web));
    let output = snakegrid(["-id", "id", p(&scratch.path("out.gpkg")), p(&web)]);
    assert_success(&output);
    assert!(
        stdout(&output).contains(
            "note: the source CRS EPSG:3857 (WGS 84 / Pseudo-Mercator) is a Mercator projection"
        ),
        "{}",
        stdout(&output)
    );
    // An equal-area source gets no such note.
    let plain = snakegrid(["-id", "id", p(&scratch.path("out2.gpkg")), p(&src)]);
    assert!(!stdout(&plain).contains("Mercator"), "{}", stdout(&plain));
}

#[test]
fn a_source_without_a_crs_is_planar_and_degrees_are_pointed_out() {
    let scratch = Scratch::new("no-crs");
    let src = scratch.input("us_states");
    // Grid maps of the US states as Shapefiles without their .prj: in metres and in degrees.
    for (name, srs, degrees) in [
        ("metres", "EPSG:5070", false),
        ("degrees", "EPSG:4326", true),
    ] {
        let shp = scratch.path(&format!("{name}.shp"));
        assert_success(&snakegrid([
            "-q",
            "-id",
            "id",
            "-t_srs",
            srs,
            p(&shp),
            p(&src),
        ]));
        std::fs::remove_file(scratch.path(&format!("{name}.prj"))).unwrap();
        let out = scratch.path(&format!("{name}.gpkg"));
        let output = snakegrid(["-id", "id", p(&out), p(&shp)]);
        assert_success(&output);
        let text = stdout(&output);
        assert!(
            text.contains("the source has no CRS: its coordinates are taken as planar"),
            "{text}"
        );
        assert_eq!(text.contains("-s_srs EPSG:4326"), degrees, "{name}: {text}");
    }
}

#[test]
fn a_bad_id_field_fails_and_lists_the_fields() {
    let scratch = Scratch::new("bad-id");
    let src = scratch.input("us_states");
    let output = snakegrid(["-id", "fips", p(&scratch.path("out.gpkg")), p(&src)]);
    assert_fails(&output, 1, "fips");
    assert!(stderr(&output).contains("abbr"));
    assert_eq!(scratch.listing(), ["us_states.gpkg"]);
}

#[test]
fn a_bad_where_expression_fails() {
    let scratch = Scratch::new("bad-where");
    let src = scratch.input("us_states");
    let output = snakegrid(["-where", "abbr ===", p(&scratch.path("out.gpkg")), p(&src)]);
    assert_fails(&output, 1, "-where");
    let output = snakegrid([
        "-where",
        "abbr = 'ZZ'",
        p(&scratch.path("out.gpkg")),
        p(&src),
    ]);
    assert_fails(&output, 1, "-where");
    assert_eq!(scratch.listing(), ["us_states.gpkg"]);
}

#[test]
fn an_existing_destination_is_refused_without_overwrite_and_left_untouched() {
    let scratch = Scratch::new("existing");
    let src = scratch.input("us_states");
    let dst = scratch.path("out.gpkg");
    std::fs::write(&dst, b"precious").unwrap();
    let output = snakegrid(["-id", "id", p(&dst), p(&src)]);
    assert_fails(&output, 1, "already exists");
    assert_eq!(std::fs::read(&dst).unwrap(), b"precious");
    assert_eq!(scratch.listing(), ["out.gpkg", "us_states.gpkg"]);
}

#[test]
fn a_failed_run_with_overwrite_leaves_the_old_destination() {
    let scratch = Scratch::new("overwrite-failed");
    let src = scratch.input("us_states");
    let dst = scratch.path("out.gpkg");
    std::fs::write(&dst, b"precious").unwrap();
    let output = snakegrid(["-overwrite", "-where", "abbr = 'ZZ'", p(&dst), p(&src)]);
    assert_fails(&output, 1, "-where");
    assert_eq!(std::fs::read(&dst).unwrap(), b"precious");
    assert_eq!(scratch.listing(), ["out.gpkg", "us_states.gpkg"]);
}

#[test]
fn outputs_that_would_mislead_or_hang_are_refused_before_any_work() {
    let scratch = Scratch::new("refused-outputs");
    let src = scratch.input("us_states");
    let run = |extra: &[&str], dst: &Path| {
        let mut args = vec!["-q", "-id", "id"];
        args.extend(extra);
        args.extend([p(dst), p(&src)]);
        snakegrid(args)
    };
    // This GDAL writes no Parquet: a GeoPackage named .parquet would mislead.
    let parquet = scratch.path("grid.parquet");
    assert_fails(&run(&[], &parquet), 1, ".parquet");
    // An empty layer name, a geocentric CRS (no map plane), a CRS GDAL cannot read (GDAL's
    // reason, not an error code), a destination in a folder that does not exist.
    let gpkg = scratch.path("grid.gpkg");
    assert_fails(&run(&["-nln", ""], &gpkg), 1, "-nln");
    assert_fails(&run(&["-t_srs", "EPSG:4978"], &gpkg), 1, "geocentric");
    let garbage = run(&["-t_srs", "garbage"], &gpkg);
    assert_fails(&garbage, 1, "invalid CRS \"garbage\"");
    assert!(
        !stderr(&garbage).contains("returned error"),
        "{}",
        stderr(&garbage)
    );
    assert_fails(
        &run(&[], &scratch.path("nowhere/grid.gpkg")),
        1,
        "does not exist",
    );
    // GDAL's virtual file systems but standard output, as outputs: said so, not "the folder
    // does not exist".
    let to_virtual = snakegrid(["-q", "-f", "GeoJSON", "/vsimem/grid.gpkg", p(&src)]);
    assert_fails(&to_virtual, 1, "GDAL's virtual file systems");
    // Opening a named pipe waits for a writer: as source or destination it is refused, not a
    // hang.
    let fifo = scratch.path("pipe");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    assert_fails(&run(&["-overwrite"], &fifo), 1, "named pipe");
    let from_pipe = snakegrid(["-q", p(&gpkg), p(&fifo)]);
    assert_fails(&from_pipe, 1, "named pipe");
    assert_eq!(scratch.listing(), ["pipe", "us_states.gpkg"]);
}

#[test]
fn a_table_without_geometry_is_refused_as_such() {
    let scratch = Scratch::new("table-source");
    let src = scratch.path("table.gpkg");
    {
        let mut dataset = DriverManager::get_driver_by_name("GPKG")
            .unwrap()
            .create_vector_only(&src)
            .unwrap();
        let layer = dataset
            .create_layer(LayerOptions {
                name: "attributes",
                ty: gdal::vector::OGRwkbGeometryType::wkbNone,
                ..Default::default()
            })
            .unwrap();
        gdal::vector::FieldDefn::new("code", OGRFieldType::OFTString)
            .unwrap()
            .add_to_layer(&layer)
            .unwrap();
        let mut feature = Feature::new(layer.defn()).unwrap();
        feature.set_field_string(0, "a").unwrap();
        feature.create(&layer).unwrap();
    }
    let output = snakegrid(["-q", p(&scratch.path("out.gpkg")), p(&src)]);
    assert_fails(&output, 1, "has no geometry column");
    assert_eq!(scratch.listing(), ["table.gpkg"]);
}

/// Writes layer "regions" in EPSG:`epsg` of (code, WKT) rows at `path`.
fn write_regions(path: &Path, epsg: u32, rows: &[(String, String)]) {
    let rows: Vec<(&str, Option<&str>)> = (rows.iter())
        .map(|(id, wkt)| (id.as_str(), Some(wkt.as_str())))
        .collect();
    write_layer(path, "regions", epsg, &rows);
}

/// Writes a GeoPackage layer (or a GML one, for a `.gml` path) `name` in EPSG:`epsg` (field
/// `code`, null when "") with the given WKT geometries (None: null).
fn write_layer(path: &Path, name: &str, epsg: u32, rows: &[(&str, Option<&str>)]) {
    let format = match path.extension().and_then(|e| e.to_str()) {
        Some("gml") => "GML",
        _ => "GPKG",
    };
    let driver = DriverManager::get_driver_by_name(format).unwrap();
    let mut dataset = if path.exists() {
        Dataset::open_ex(
            path,
            gdal::DatasetOptions {
                open_flags: gdal::GdalOpenFlags::GDAL_OF_UPDATE
                    | gdal::GdalOpenFlags::GDAL_OF_VECTOR,
                ..Default::default()
            },
        )
        .unwrap()
    } else {
        driver.create_vector_only(path).unwrap()
    };
    let mut srs = SpatialRef::from_epsg(epsg).unwrap();
    srs.set_axis_mapping_strategy(gdal::spatial_ref::AxisMappingStrategy::TraditionalGisOrder);
    let layer = dataset
        .create_layer(LayerOptions {
            name,
            srs: Some(&srs),
            ..Default::default()
        })
        .unwrap();
    layer
        .create_defn_fields(&[("code", OGRFieldType::OFTString)])
        .unwrap();
    for (code, wkt) in rows {
        let mut feature = Feature::new(layer.defn()).unwrap();
        if !code.is_empty() {
            feature.set_field_string(0, code).unwrap();
        }
        if let Some(wkt) = wkt {
            feature
                .set_geometry(Geometry::from_wkt(wkt).unwrap())
                .unwrap();
        }
        feature.create(&layer).unwrap();
    }
}

#[test]
fn unusable_features_are_refused_by_name() {
    let scratch = Scratch::new("bad-features");
    let src = scratch.path("bad.gpkg");
    let square = "POLYGON ((0 0, 1 0, 1 1, 0 1, 0 0))";
    write_layer(
        &src,
        "null_geometry",
        5070,
        &[("A", Some(square)), ("B", None)],
    );
    write_layer(
        &src,
        "point",
        5070,
        &[("A", Some(square)), ("C", Some("POINT (1 2)"))],
    );
    write_layer(
        &src,
        "duplicate",
        5070,
        &[("A", Some(square)), ("A", Some(square))],
    );
    write_layer(
        &src,
        "null_id",
        5070,
        &[("A", Some(square)), ("", Some(square))],
    );
    let cases = [
        ("null_geometry", "feature B: the geometry is null"),
        ("point", "feature C: the geometry is a POINT"),
        ("duplicate", "feature A: the id is not unique"),
        ("null_id", "feature FID 2: the id is null"),
    ];
    let dst = scratch.path("out.gpkg");
    for (layer, message) in cases {
        let output = snakegrid(["-id", "code", p(&dst), p(&src), layer]);
        assert_fails(&output, 1, message);
    }
    assert_eq!(scratch.listing(), ["bad.gpkg"]);
}

// ---------------------------------------------------------------------------------------------
// Whole runs (these need the method's core).

#[test]
fn us_states_end_to_end() {
    let scratch = Scratch::new("us-states");
    let src = scratch.input("us_states");
    let dst = scratch.path("grid.gpkg");
    let output = snakegrid(["-id", "id", p(&dst), p(&src)]);
    assert_success(&output);
    let cells = assert_complete("us_states", &dst);
    assert_eq!(cells.len(), 49);

    // The source attributes came along, feature by feature, in input order.
    let (_, rows) = read_rows(&dst);
    let input = Dataset::open(data("us_states")).unwrap();
    let mut layer = input.layer(0).unwrap();
    for (row, feature) in rows.iter().zip(layer.features()) {
        for (i, name) in ["id", "name", "abbr"].iter().enumerate() {
            assert_eq!(row.fields[*name], text(feature.field(i).unwrap()));
        }
        let kept: f64 = row.fields["nbr_kept"].parse().unwrap();
        assert!((0.0..=1.0).contains(&kept));
    }

    // The run's metrics and parameters are in the layer's metadata.
    let written = Dataset::open(&dst).unwrap();
    let layer = written.layer(0).unwrap();
    use gdal::Metadata;
    assert!(layer
        .metadata_item("SNAKEGRID_METRIC_ADJACENT", "")
        .is_some());
    assert!(layer
        .metadata_item("SNAKEGRID_PARAMETERS", "")
        .unwrap()
        .contains("\"alpha\""));

    let summary = stdout(&output);
    for needle in [
        "49 regions",
        "C_adjacent",
        "C_orientation",
        "snake:",
        "steps",
        "→",
    ] {
        assert!(
            summary.contains(needle),
            "summary lacks {needle:?}: {summary}"
        );
    }
    // The states enclose no lake, so the summary names none.
    assert!(!summary.contains("the regions' holes"), "{summary}");
    let progress = stderr(&output);
    assert!(
        progress.starts_with("0...10...20...30...40...50...60...70...80...90...100 - done."),
        "{progress:?}"
    );
    assert_eq!(scratch.listing(), ["grid.gpkg", "us_states.gpkg"]);

    // -q: nothing on stdout or stderr.
    let quiet = snakegrid(["-q", "-id", "id", p(&scratch.path("quiet.gpkg")), p(&src)]);
    assert_success(&quiet);
    assert!(quiet.stdout.is_empty() && quiet.stderr.is_empty());
}

#[test]
fn the_json_report_has_the_metrics_and_the_snake_run() {
    let scratch = Scratch::new("json");
    let src = scratch.input("us_states");
    let report = scratch.path("report.json");
    let output = snakegrid([
        "-q",
        "-id",
        "id",
        "-json",
        p(&report),
        p(&scratch.path("grid.gpkg")),
        p(&src),
    ]);
    assert_success(&output);
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    for metric in [
        "location",
        "location_raw",
        "adjacent",
        "adjacent_rook",
        "orientation",
        "misdirected",
        "shape",
    ] {
        assert!(
            json["metrics"][metric].is_number(),
            "metrics.{metric} missing"
        );
    }
    assert!(json["snake"]["steps"].is_u64());
    assert!(json["snake"]["stop_reason"].is_string());
    assert!(json["snake"]["spread_before"].is_number());
    assert!(json["snake"]["spread_after"].is_number());
    assert_eq!(json["parameters"]["alpha"], 1.0);
    assert_eq!(json["source"]["features"], 49);
    assert_eq!(json["source"]["id_field"], "id");
    assert_eq!(json["crs"]["projected"], false);
    assert!(json["candidates"].as_array().is_some_and(|c| !c.is_empty()));
    let regions = json["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 49);
    assert!(regions
        .iter()
        .any(|r| r["id"] == "06" && r["label"] == "CA"));
    // The shared us_states are valid: no region was repaired.
    assert!(regions.iter().all(|r| r["repair"].is_null()));
    assert!(json["cell_size"].as_f64().unwrap() > 0.0);
}

#[test]
fn two_runs_give_byte_identical_outputs() {
    let scratch = Scratch::new("identical");
    let src = scratch.input("us_states");
    let (first, second) = (
        outputs_of(&scratch, "a", &src, &[], None),
        outputs_of(&scratch, "b", &src, &[], None),
    );
    for (k, name) in ["grid.gpkg", "r.json", "p.svg"].iter().enumerate() {
        assert!(first[k] == second[k], "{name} differs between two runs");
    }
}

#[test]
fn formats_that_store_the_time_or_random_ids_give_byte_identical_outputs() {
    // netCDF's history attribute held the time of writing and the staging file's path; a File
    // Geodatabase's tables hold a GUID per item, random unless GDAL is told otherwise.
    let scratch = Scratch::new("identical-formats");
    let src = scratch.input("us_states");
    let quick = ["-refine", "false", "-noise_levels", "", "-shifts", "0:0"];
    for name in ["grid.nc", "grid.gdb"] {
        let bytes = |run: &str| -> BTreeMap<String, Vec<u8>> {
            let dir = scratch.path(&format!("{run}-{name}"));
            std::fs::create_dir(&dir).unwrap();
            let dst = dir.join(name);
            let mut args = vec!["-q", "-id", "id"];
            args.extend(quick);
            args.extend([p(&dst), p(&src)]);
            assert_success(&snakegrid(args));
            let files = if dst.is_dir() {
                (std::fs::read_dir(&dst).unwrap())
                    .map(|entry| entry.unwrap().path())
                    .collect()
            } else {
                vec![dst]
            };
            (files.into_iter())
                .map(|f| {
                    (
                        f.file_name().unwrap().to_string_lossy().into_owned(),
                        std::fs::read(&f).unwrap(),
                    )
                })
                .collect()
        };
        let first = bytes("a");
        // A second later, so that a time of writing would differ.
        std::thread::sleep(std::time::Duration::from_millis(1100));
        let second = bytes("b");
        assert_eq!(
            first.keys().collect::<Vec<_>>(),
            second.keys().collect::<Vec<_>>()
        );
        for (file, content) in &first {
            assert!(
                content == &second[file],
                "{name}: {file} differs between two runs"
            );
        }
    }
}

#[test]
fn one_worker_or_four_give_byte_identical_outputs() {
    // Above the sparse assignment's limit and with fewer layouts than workers would take in
    // parallel; fewer refinement moves keep the test short.
    let scratch = Scratch::new("workers");
    let src = scratch.input("us_counties");
    let options = ["-max_layouts", "3", "-refine_moves_per_region", "100"];
    let one = outputs_of(&scratch, "one", &src, &options, Some("1"));
    let four = outputs_of(&scratch, "four", &src, &options, Some("4"));
    for (k, name) in ["grid.gpkg", "r.json", "p.svg"].iter().enumerate() {
        assert!(one[k] == four[k], "{name} differs between 1 and 4 workers");
    }
}

/// The layer, report and picture of a run on `src` in a new folder `folder`, with `threads`
/// as RAYON_NUM_THREADS when given.
fn outputs_of(
    scratch: &Scratch,
    folder: &str,
    src: &Path,
    options: &[&str],
    threads: Option<&str>,
) -> [Vec<u8>; 3] {
    let dir = scratch.path(folder);
    std::fs::create_dir(&dir).unwrap();
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_snakegrid"));
    command.current_dir(&dir).args(options).args([
        "-q",
        "-id",
        "id",
        "-json",
        "r.json",
        "-svg",
        "p.svg",
        "grid.gpkg",
        p(src),
    ]);
    if let Some(threads) = threads {
        command.env("RAYON_NUM_THREADS", threads);
    }
    let output = command.output().unwrap();
    assert_success(&output);
    ["grid.gpkg", "r.json", "p.svg"].map(|f| std::fs::read(dir.join(f)).unwrap())
}

/// A new GeoPackage at `to` holding one empty layer `name` in `srs`.
fn new_geopackage(to: &Path, name: &str, srs: &SpatialRef) -> Dataset {
    let mut output = DriverManager::get_driver_by_name("GPKG")
        .unwrap()
        .create_vector_only(to)
        .unwrap();
    output
        .create_layer(LayerOptions {
            name,
            srs: Some(srs),
            ..Default::default()
        })
        .unwrap();
    output
}

/// A copy of layer `layer` with its features in reverse order (and so other FIDs), optionally
/// reprojected; every field is copied as text.
fn rewrite(layer: &str, to: &Path, reverse: bool, srs: Option<&SpatialRef>) {
    let input = Dataset::open(data(layer)).unwrap();
    let mut source = input.layer(0).unwrap();
    let names: Vec<String> = source.defn().fields().map(|f| f.name()).collect();
    let source_srs = source.spatial_ref().unwrap();
    let mut rows: Vec<(Vec<String>, Geometry)> = source
        .features()
        .map(|f| {
            let values = (0..names.len())
                .map(|i| text(f.field(i).unwrap()))
                .collect();
            let mut geometry = f.geometry().unwrap().clone();
            if let Some(srs) = srs {
                geometry.transform_to_inplace(srs).unwrap();
            }
            (values, geometry)
        })
        .collect();
    if reverse {
        rows.reverse();
    }
    let output = new_geopackage(to, layer, srs.unwrap_or(&source_srs));
    let layer = output.layer(0).unwrap();
    let fields: Vec<(&str, u32)> = names
        .iter()
        .map(|n| (n.as_str(), OGRFieldType::OFTString))
        .collect();
    layer.create_defn_fields(&fields).unwrap();
    for (values, geometry) in rows {
        let mut feature = Feature::new(layer.defn()).unwrap();
        for (i, v) in values.iter().enumerate() {
            feature.set_field_string(i, v).unwrap();
        }
        feature.set_geometry(geometry).unwrap();
        feature.create(&layer).unwrap();
    }
}

#[test]
fn reordering_the_features_does_not_change_the_layout() {
    let scratch = Scratch::new("reordered");
    let src = scratch.input("us_states");
    let reversed = scratch.path("reversed.gpkg");
    rewrite("us_states", &reversed, true, None);
    let (a, b) = (scratch.path("a.gpkg"), scratch.path("b.gpkg"));
    assert_success(&snakegrid(["-q", "-id", "id", p(&a), p(&src)]));
    assert_success(&snakegrid(["-q", "-id", "id", p(&b), p(&reversed)]));
    let (_, rows_a) = read_rows(&a);
    let (_, rows_b) = read_rows(&b);
    let (cells_a, cells_b) = (assert_grid(&rows_a, "id"), assert_grid(&rows_b, "id"));
    assert_eq!(cells_a, cells_b);
    // Output features follow the input order.
    assert_eq!(
        rows_b.first().unwrap().fields["id"],
        rows_a.last().unwrap().fields["id"]
    );
}

#[test]
fn a_geographic_source_is_projected_to_equal_area_and_says_so() {
    let scratch = Scratch::new("geographic");
    let lonlat = scratch.path("lonlat.gpkg");
    let mut wgs84 = SpatialRef::from_epsg(4326).unwrap();
    wgs84.set_axis_mapping_strategy(gdal::spatial_ref::AxisMappingStrategy::TraditionalGisOrder);
    rewrite("us_states", &lonlat, false, Some(&wgs84));
    let dst = scratch.path("grid.gpkg");
    let report = scratch.path("r.json");
    let output = snakegrid(["-id", "id", "-json", p(&report), p(&dst), p(&lonlat)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(
        summary.contains("geographic") && summary.contains("Lambert azimuthal equal-area"),
        "{summary}"
    );
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(json["crs"]["projected"], true);
    assert!(json["notes"][0]
        .as_str()
        .unwrap()
        .contains("Lambert azimuthal equal-area centred on the layer"));
    let (_, rows) = read_rows(&dst);
    assert_eq!(assert_grid(&rows, "id").len(), 49);
    let written = Dataset::open(&dst).unwrap();
    let srs = written.layer(0).unwrap().spatial_ref().unwrap();
    assert!(srs.to_proj4().unwrap().contains("+proj=laea"));
    // Named, so that a GIS shows what it is rather than "unknown".
    let name = srs.name().unwrap();
    assert!(
        name.starts_with("Lambert azimuthal equal-area at ") && name.ends_with("(snakegrid)"),
        "{name}"
    );
}

#[test]
fn where_selects_the_features() {
    let scratch = Scratch::new("where");
    let src = scratch.input("us_states");
    let dst = scratch.path("west.gpkg");
    let filter = "abbr IN ('WA','OR','CA','NV','ID','MT','WY','UT','CO','AZ','NM','TX','OK','KS','NE','SD','ND')";
    let output = snakegrid(["-q", "-id", "abbr", "-where", filter, p(&dst), p(&src)]);
    assert_success(&output);
    let (_, rows) = read_rows(&dst);
    assert_eq!(assert_grid(&rows, "abbr").len(), 17);
}

#[test]
fn shapefile_and_geojson_outputs() {
    let scratch = Scratch::new("formats");
    let src = scratch.input("us_states");
    let shp = scratch.path("grid.shp");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-f",
        "ESRI Shapefile",
        p(&shp),
        p(&src),
    ]));
    let geojson = scratch.path("grid.geojson");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-f",
        "GeoJSON",
        "-nln",
        "cells",
        p(&geojson),
        p(&src),
    ]));
    for output in [&shp, &geojson] {
        let (names, rows) = read_rows(output);
        for field in ["id", "name", "abbr"].iter().chain(ADDED.iter()) {
            assert!(
                names.iter().any(|n| n == field),
                "{} lacks {field}",
                output.display()
            );
        }
        assert_eq!(assert_grid(&rows, "id").len(), 49);
    }
    let listing = scratch.listing();
    assert!(
        listing.iter().all(|name| !name.starts_with('.')),
        "staging left behind: {listing:?}"
    );
    for sidecar in ["grid.dbf", "grid.prj", "grid.shx"] {
        assert!(
            listing.iter().any(|n| n == sidecar),
            "{sidecar} missing: {listing:?}"
        );
    }
    // The DBF date is fixed too, so a Shapefile is reproducible from one day to the next.
    assert_eq!(
        &std::fs::read(scratch.path("grid.dbf")).unwrap()[1..4],
        &[100, 1, 1]
    );

    // -overwrite replaces a Shapefile with its sidecars, also those GDAL does not list but
    // other programs leave: their spatial index would be corrupt beside the new file, and a
    // code page of another encoding would misread its text.
    for stale in ["grid.sbn", "grid.SBX", "grid.cpg"] {
        std::fs::write(scratch.path(stale), b"stale").unwrap();
    }
    assert_success(&snakegrid([
        "-q",
        "-overwrite",
        "-id",
        "abbr",
        "-f",
        "ESRI Shapefile",
        p(&shp),
        p(&src),
    ]));
    let (_, rows) = read_rows(&shp);
    assert_eq!(assert_grid(&rows, "abbr").len(), 49);
    let listing = scratch.listing();
    assert!(
        !listing.iter().any(|n| n == "grid.sbn" || n == "grid.SBX"),
        "stale indexes kept: {listing:?}"
    );
    let code_page = std::fs::read(scratch.path("grid.cpg")).unwrap_or_default();
    assert_ne!(code_page, b"stale", "a stale code page kept");
}

#[test]
fn overwrite_replaces_the_destination_after_success() {
    let scratch = Scratch::new("overwrite");
    let src = scratch.input("nc_counties");
    let dst = scratch.path("grid.gpkg");
    std::fs::write(&dst, b"old").unwrap();
    assert_success(&snakegrid([
        "-q",
        "-overwrite",
        "-id",
        "id",
        p(&dst),
        p(&src),
    ]));
    assert_complete("nc_counties", &dst);
    // And again, over a real GeoPackage.
    assert_success(&snakegrid([
        "-q",
        "-overwrite",
        "-id",
        "id",
        p(&dst),
        p(&src),
    ]));
    assert_complete("nc_counties", &dst);
    assert_eq!(scratch.listing(), ["grid.gpkg", "nc_counties.gpkg"]);
}

#[test]
fn the_svg_shows_both_maps_with_labelled_cells() {
    let scratch = Scratch::new("svg");
    let src = scratch.input("us_states");
    let picture = scratch.path("map.svg");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-svg",
        p(&picture),
        p(&scratch.path("g.gpkg")),
        p(&src),
    ]));
    let svg = std::fs::read_to_string(&picture).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<path ").count(), 49);
    assert!(svg.contains(">CA</text>") && svg.contains(">DC</text>"));
    // -label picks another field; text is escaped.
    let named = scratch.path("named.svg");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-label",
        "name",
        "-svg",
        p(&named),
        p(&scratch.path("h.gpkg")),
        p(&src),
    ]));
    // Names too long for a cell are abbreviated or cut, all in one font size.
    let named = std::fs::read_to_string(&named).unwrap();
    for label in [">Texas</text>", ">NY</text>", ">DC</text>", ">Cali…</text>"] {
        assert!(named.contains(label), "{label} missing");
    }
}

#[test]
fn hexagons_come_with_a_hexjson_file_that_numbers_them_like_the_layer() {
    let scratch = Scratch::new("hexjson");
    let src = scratch.input("us_states");
    for orientation in ["pointy", "flat"] {
        let (grid, hexjson, report) = (
            scratch.path(&format!("{orientation}.gpkg")),
            scratch.path(&format!("{orientation}.hexjson")),
            scratch.path(&format!("{orientation}.json")),
        );
        assert_success(&snakegrid([
            "-q",
            "-id",
            "id",
            "-cell",
            "hex",
            "-hex_orientation",
            orientation,
            "-hexjson",
            p(&hexjson),
            "-json",
            p(&report),
            p(&grid),
            p(&src),
        ]));
        let (_, rows) = read_rows(&grid);
        // The report names the offset rows (columns): in two cells of one column (row) and
        // neighbouring rows (columns), the offset one lies half a cell right (down).
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let offset = report["cells"]["offset"].as_str().unwrap();
        let odd = offset.starts_with("odd");
        let centre = |row: &Row| {
            let n = row.ring.len() - 1;
            assert_eq!(n, 6, "a hexagon has six corners");
            let (x, y) = row.ring[..n]
                .iter()
                .fold((0.0, 0.0), |s, p| (s.0 + p.0, s.1 + p.1));
            (x / n as f64, y / n as f64)
        };
        let at: HashMap<(i64, i64), (f64, f64)> = (rows.iter())
            .map(|row| {
                let int = |name: &str| row.fields[name].parse::<i64>().unwrap();
                ((int("grid_col"), int("grid_row")), centre(row))
            })
            .collect();
        let mut pairs = 0;
        for (&(col, row), &(x, y)) in &at {
            let pointy = orientation == "pointy";
            let next = if pointy {
                (col, row + 1)
            } else {
                (col + 1, row)
            };
            let Some(&(nx, ny)) = at.get(&next) else {
                continue;
            };
            pairs += 1;
            let next_is_offset =
                (if pointy { next.1 } else { next.0 }).rem_euclid(2) == i64::from(odd);
            let (ahead, behind) = if pointy { (nx - x, 0.0) } else { (0.0, y - ny) };
            let step = ahead + behind;
            assert!(
                (step > 0.0) == next_is_offset,
                "{orientation} {offset}: ({col}, {row}) → {next:?} moves {step}"
            );
            assert!(offset.contains(if pointy { "rows right" } else { "columns down" }));
        }
        assert!(pairs > 10, "{pairs} pairs");
        // grid_q and grid_r are axial: two hexagons are neighbours (centres one width apart)
        // exactly when their axial coordinates differ by one of the six steps.
        let axial: Vec<((i64, i64), (f64, f64))> = (rows.iter())
            .map(|row| {
                let int = |name: &str| row.fields[name].parse::<i64>().unwrap();
                ((int("grid_q"), int("grid_r")), centre(row))
            })
            .collect();
        let width = {
            let (a, b) = (axial[0].1, axial[1].1);
            let d = |p: &(f64, f64)| (p.0 - a.0).hypot(p.1 - a.1);
            axial[1..]
                .iter()
                .map(|x| d(&x.1))
                .fold(f64::MAX, f64::min)
                .min(d(&b))
        };
        let steps = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, -1), (-1, 1)];
        let mut neighbours = 0;
        for (i, &((q, r), a)) in axial.iter().enumerate() {
            for &((q2, r2), b) in &axial[i + 1..] {
                let close = (a.0 - b.0).hypot(a.1 - b.1) < 1.2 * width;
                neighbours += usize::from(close);
                assert_eq!(close, steps.contains(&(q2 - q, r2 - r)), "{orientation}");
            }
        }
        assert!(neighbours > 60, "{neighbours} neighbouring pairs");
        let cells: HashMap<String, (i64, i64)> = (rows.iter())
            .map(|row| {
                let int = |name: &str| row.fields[name].parse::<i64>().unwrap();
                (row.fields["id"].clone(), (int("grid_col"), int("grid_row")))
            })
            .collect();
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&hexjson).unwrap()).unwrap();
        let layout = doc["layout"].as_str().unwrap();
        let expected: &[&str] = if orientation == "pointy" {
            &["odd-r", "even-r"]
        } else {
            &["odd-q", "even-q"]
        };
        assert!(expected.contains(&layout), "{orientation}: {layout}");
        let hexes = doc["hexes"].as_object().unwrap();
        assert_eq!(hexes.len(), 49);
        // The format counts r from the bottom: q follows grid_col and r + grid_row is the same
        // for every hexagon. The label (abbr) is the hexagon's n.
        let mut sums = HashSet::new();
        for (id, hex) in hexes {
            let (q, r) = (hex["q"].as_i64().unwrap(), hex["r"].as_i64().unwrap());
            assert!(q >= 0 && r >= 0, "{id}: {q}, {r}");
            let (col, row) = cells[id];
            assert_eq!(q - col, 1, "{id}");
            sums.insert(r + row);
        }
        assert_eq!(sums.len(), 1, "{sums:?}");
        assert_eq!(hexes["06"]["n"], "CA");
        assert_eq!(hexes["06"]["name"], "California");
    }
    // Squares have no HexJSON: refused before the layout, nothing written.
    let before = scratch.listing();
    assert_fails(
        &snakegrid([
            "-q",
            "-hexjson",
            p(&scratch.path("squares.hexjson")),
            p(&scratch.path("squares.gpkg")),
            p(&src),
        ]),
        1,
        "-cell hex",
    );
    assert_eq!(scratch.listing(), before);
}

#[test]
fn world_countries_nc_and_virginia_counties_give_complete_outputs() {
    let scratch = Scratch::new("other-layers");
    for layer in ["world_countries", "nc_counties", "virginia_counties"] {
        let src = scratch.input(layer);
        let dst = scratch.path(&format!("{layer}-grid.gpkg"));
        assert_success(&snakegrid(["-q", "-id", "id", p(&dst), p(&src)]));
        assert_complete(layer, &dst);
    }
}

#[test]
fn us_counties_end_to_end() {
    let scratch = Scratch::new("us-counties");
    let src = scratch.input("us_counties");
    let dst = scratch.path("grid.gpkg");
    assert_success(&snakegrid(["-q", "-id", "id", p(&dst), p(&src)]));
    assert_eq!(assert_complete("us_counties", &dst).len(), 3107);
}

#[test]
fn a_world_layer_in_longitude_and_latitude_is_laid_out_in_equal_earth() {
    // world_countries taken back to lon/lat (as `ogr2ogr -t_srs EPSG:4326` would): the whole
    // world, which an azimuthal projection would tear apart and GDAL would refuse to project.
    let scratch = Scratch::new("world-lonlat");
    let lonlat = scratch.path("world.gpkg");
    let mut wgs84 = SpatialRef::from_epsg(4326).unwrap();
    wgs84.set_axis_mapping_strategy(gdal::spatial_ref::AxisMappingStrategy::TraditionalGisOrder);
    rewrite("world_countries", &lonlat, false, Some(&wgs84));
    let dst = scratch.path("grid.gpkg");
    let output = snakegrid(["-id", "id", p(&dst), p(&lonlat)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(summary.contains("projected to Equal Earth"), "{summary}");
    // Issue 13's guarantees hold in lon/lat too: every country on its own landmass, location
    // within 1.5 cells.
    assert!(summary.contains("wrong landmass 0.000"), "{summary}");
    let location: f64 = (summary.split("C_location ").nth(1))
        .and_then(|rest| rest.split(' ').next())
        .and_then(|number| number.parse().ok())
        .unwrap_or_else(|| panic!("no C_location in {summary}"));
    assert!(location <= 1.5, "{summary}");
    let (_, rows) = read_rows(&dst);
    assert_eq!(assert_grid(&rows, "id").len(), 177);
    let written = Dataset::open(&dst).unwrap();
    let srs = written.layer(0).unwrap().spatial_ref().unwrap();
    assert_eq!(srs.name().unwrap(), "WGS 84 / Equal Earth Greenwich");
    assert!(srs.to_proj4().unwrap().contains("+proj=eqearth"));
}

#[test]
fn regions_drawn_across_the_antimeridian_are_one_country_not_the_world() {
    // Nine equal regions of 10° by 5° from 165°E to 165°W, the middle column across ±180°
    // drawn as d3's world-atlas and many TopoJSON files draw Chukotka: its rings step from
    // 180 to -180. Each such ring's box spans the globe, which used to make the layer a world
    // map in Equal Earth at 0°, where the middle column became bands round the globe.
    let scratch = Scratch::new("antimeridian");
    let src = scratch.path("chukotka.gpkg");
    let wrap = |x: f64| (x + 180.0).rem_euclid(360.0) - 180.0;
    let mut rows = Vec::new();
    for column in 0..3 {
        for row in 0..3 {
            let (west, south) = (165.0 + 10.0 * column as f64, 55.0 + 5.0 * row as f64);
            let corners = [(0.0, 0.0), (5.0, 0.0), (10.0, 0.0), (10.0, 5.0), (5.0, 5.0)];
            let ring: Vec<String> = (corners.iter().chain(&[(0.0, 5.0), (0.0, 0.0)]))
                .map(|(dx, dy)| format!("{} {}", wrap(west + dx), south + dy))
                .collect();
            rows.push((
                format!("c{column}r{row}"),
                format!("POLYGON(({}))", ring.join(",")),
            ));
        }
    }
    write_regions(&src, 4326, &rows);
    let dst = scratch.path("grid.gpkg");
    let output = snakegrid(["-id", "code", p(&dst), p(&src)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(
        summary.contains("Lambert azimuthal equal-area centred on the layer (62.5N 180.0E)"),
        "{summary}"
    );
    assert!(!summary.contains("repaired"), "{summary}");
    // A 3 × 3 block laid out as a 3 × 3 block keeps all 12 rook pairs (a hand count).
    assert!(summary.contains("C_adjacent 1.000"), "{summary}");
    let (_, rows) = read_rows(&dst);
    assert_eq!(assert_grid(&rows, "code").len(), 9);
}

#[test]
fn a_ring_round_a_lake_keeps_its_lake_and_the_summary_says_whose_it_is() {
    // Eight 1 km squares round a square lake of the same size: §8 counts holes in enclosed
    // positions, so the summary gives the lake's area in the same cells beside them.
    let scratch = Scratch::new("lake");
    let src = scratch.path("lake.gpkg");
    let square = |col: i32, row: i32| {
        let (x, y) = (1000.0 * f64::from(col), 1000.0 * f64::from(row));
        let ring = [
            (0.0, 0.0),
            (1000.0, 0.0),
            (1000.0, 1000.0),
            (0.0, 1000.0),
            (0.0, 0.0),
        ];
        let ring: Vec<String> = (ring.iter())
            .map(|(dx, dy)| format!("{} {}", x + dx, y + dy))
            .collect();
        format!("POLYGON(({}))", ring.join(","))
    };
    let rows: Vec<(String, String)> = (0..9)
        .filter(|&k| k != 4)
        .map(|k| (format!("r{k}"), square(k % 3, k / 3)))
        .collect();
    write_regions(&src, 3857, &rows);
    let dst = scratch.path("grid.gpkg");
    let output = snakegrid(["-id", "code", p(&dst), p(&src)]);
    assert_success(&output);
    let summary = stdout(&output);
    // One lake of one square, and cells the size of the squares (eight regions on eight
    // squares' area): a hand count. The layout that reproduces the squares keeps the lake, all
    // 8 rook pairs and every region's place; ranking its one hole a defect chose one that
    // filled the lake in instead.
    for needle in [
        "1 hole(s) (the regions' holes: 1 cells)",
        "C_adjacent 1.000 (rook 1.000",
        "C_location 0.000 cells",
    ] {
        assert!(summary.contains(needle), "lacks {needle:?}: {summary}");
    }
}

#[test]
fn a_group_field_keeps_groups_together_and_is_reported() {
    let scratch = Scratch::new("groups");
    let src = common::shared_layer("us_counties");
    let (grid, report) = (scratch.path("g.gpkg"), scratch.path("g.json"));
    let out = snakegrid([
        "-id",
        "id",
        "-where",
        "state_abbr IN ('NC', 'SC')",
        "-group",
        "state_abbr",
        "-group_gap",
        "1",
        "-json",
        p(&report),
        p(&grid),
        p(&src),
    ]);
    assert_success(&out);
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("groups: 2 in "), "{summary}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(report["source"]["group_field"], "state_abbr");
    assert_eq!(report["groups"]["groups"], 2);
    assert_eq!(report["groups"]["contacts"], 0);
    assert_eq!(report["groups"]["reach"], 2);
    // grid_group numbers the blocks from 1; each state's mainland block holds most of it.
    let (names, rows) = read_rows(&grid);
    assert_eq!(names.last().map(String::as_str), Some("grid_group"));
    let mut blocks: HashMap<(String, String), usize> = HashMap::new();
    for row in &rows {
        let key = (
            row.fields["state_abbr"].clone(),
            row.fields["grid_group"].clone(),
        );
        *blocks.entry(key).or_default() += 1;
    }
    let numbers: HashSet<&String> = blocks.keys().map(|(_, b)| b).collect();
    assert!(numbers.contains(&"1".to_owned()));
    assert_eq!(
        blocks.len(),
        numbers.len(),
        "a block belongs to one state: {blocks:?}"
    );
    // A group field the layer lacks is refused before any work, naming the option.
    assert_fails(
        &snakegrid(["-q", "-group", "nope", p(&scratch.path("x.gpkg")), p(&src)]),
        1,
        "-group \"nope\": the source layer has no such field",
    );
}

/// us_states with pin fields `pc` and `pr` (text, as a CSV source would have them) set from
/// `pins` (abbr → column, row text).
fn pinned_states(to: &Path, pins: &[(&str, (&str, &str))]) {
    let input = Dataset::open(data("us_states")).unwrap();
    let mut source = input.layer(0).unwrap();
    let srs = source.spatial_ref().unwrap();
    let output = new_geopackage(to, "us_states", &srs);
    let layer = output.layer(0).unwrap();
    let fields = [
        ("abbr", OGRFieldType::OFTString),
        ("pc", OGRFieldType::OFTString),
    ];
    layer.create_defn_fields(&fields).unwrap();
    layer
        .create_defn_fields(&[("pr", OGRFieldType::OFTReal)])
        .unwrap();
    for f in source.features() {
        let abbr = text(f.field(2).unwrap());
        let mut feature = Feature::new(layer.defn()).unwrap();
        feature.set_field_string(0, &abbr).unwrap();
        if let Some((_, (col, row))) = pins.iter().find(|(a, _)| *a == abbr) {
            feature.set_field_string(1, col).unwrap();
            if !row.is_empty() {
                feature.set_field_double(2, row.parse().unwrap()).unwrap();
            }
        }
        feature.set_geometry(f.geometry().unwrap().clone()).unwrap();
        feature.create(&layer).unwrap();
    }
}

#[test]
fn pin_fields_number_the_cells_in_the_pins_frame() {
    let scratch = Scratch::new("pins");
    let src = scratch.path("pinned.gpkg");
    // Issue 18's NYT cells, given as text and real values.
    let nyt = [
        ("WA", ("1", "2")),
        ("FL", ("7", "7")),
        ("ME", ("11", "0")),
        ("CA", ("0", "4")),
        ("TX", ("3", "6")),
    ];
    pinned_states(&src, &nyt);
    let (grid, report) = (scratch.path("g.gpkg"), scratch.path("g.json"));
    let args = ["-id", "abbr", "-pin_col", "pc", "-pin_row", "pr", "-json"];
    let mut all: Vec<&str> = args.to_vec();
    all.extend([p(&report), p(&grid), p(&src)]);
    let out = snakegrid(all);
    assert_success(&out);
    let (_, rows) = read_rows(&grid);
    for (abbr, (col, row)) in nyt {
        let cell = rows.iter().find(|r| r.fields["abbr"] == abbr).unwrap();
        assert_eq!(
            (
                cell.fields["grid_col"].as_str(),
                cell.fields["grid_row"].as_str()
            ),
            (col, row)
        );
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(report["source"]["pin_col_field"], "pc");

    // Refused by name before the layout: a value that is not whole, one of the two missing.
    for (pins, message) in [
        (
            ("2.5", "1"),
            "feature WA: the pin column 2.5 is not a whole number",
        ),
        (
            ("2", ""),
            "feature WA: the pin column is set but the pin row is not",
        ),
        (
            ("two", "1"),
            "feature WA: the pin value \"two\" is not a number",
        ),
    ] {
        let bad = scratch.path("bad.gpkg");
        let _ = std::fs::remove_file(&bad);
        pinned_states(&bad, &[("WA", pins)]);
        let out = scratch.path("bad-out.gpkg");
        let mut all: Vec<&str> = vec!["-q"];
        all.extend(&args[..6]);
        all.extend([p(&out), p(&bad)]);
        assert_fails(&snakegrid(all), 1, message);
        assert!(!out.exists());
    }
    // Only one of the two options: a usage error.
    let out = snakegrid(["-q", "-pin_col", "pc", p(&scratch.path("x.gpkg")), p(&src)]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("pin_row"), "{}", stderr(&out));
}

#[test]
fn a_layer_round_a_pole_is_laid_out_round_the_pole() {
    // Two rings of twelve 30° sectors round the South Pole (80°S to the pole, 70°S to 80°S), as
    // a layer of Antarctic regions is drawn in longitude and latitude: the inner sectors run to
    // the pole along its parallel, and the sectors on either side of ±180° meet there, at x =
    // 180 and x = -180. The layer spans 360° of longitude; in Equal Earth those two meridians
    // are the map's two edges, which parted the sectors round the pole.
    let scratch = Scratch::new("pole");
    let src = scratch.path("antarctic.gpkg");
    let mut rows = Vec::new();
    for sector in 0..12 {
        let (west, east) = (-180.0 + 30.0 * sector as f64, -150.0 + 30.0 * sector as f64);
        for (ring, (south, north)) in [(-90.0, -80.0), (-80.0, -70.0)].into_iter().enumerate() {
            // Vertices every 5° along the parallels, so that the edges follow them.
            let along = |lat: f64, from: f64, to: f64| -> Vec<String> {
                (0..=6)
                    .map(|k| format!("{} {lat}", from + (to - from) * k as f64 / 6.0))
                    .collect()
            };
            let mut ring_points = along(south, west, east);
            ring_points.extend(along(north, east, west));
            ring_points.push(ring_points[0].clone());
            rows.push((
                format!("s{sector}r{ring}"),
                format!("POLYGON(({}))", ring_points.join(",")),
            ));
        }
    }
    write_regions(&src, 4326, &rows);
    let (dst, report) = (scratch.path("grid.gpkg"), scratch.path("grid.json"));
    let output = snakegrid(["-id", "code", "-json", p(&report), p(&dst), p(&src)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(
        summary.contains(
            "within 45° of the South Pole, so it is projected to Lambert azimuthal \
                          equal-area centred on the pole"
        ),
        "{summary}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    // By hand: 12 pairs round each ring and 12 between the rings; the sectors on either side of
    // ±180° are neighbours.
    assert_eq!(report["adjacent_pairs"], 36, "{summary}");
    // The layout keeps the rings: 1.000 on 2026-12-06, where Equal Earth's map of the same
    // layer, the two rings torn open on the map's edges, kept 0.559 of 34 pairs. 0.9 allows a
    // few pairs lost to another candidate.
    let adjacent = report["metrics"]["adjacent"].as_f64().unwrap();
    assert!(adjacent >= 0.9, "{summary}");
    let written = Dataset::open(&dst).unwrap();
    let srs = written.layer(0).unwrap().spatial_ref().unwrap();
    let proj4 = srs.to_proj4().unwrap();
    assert!(proj4.contains("+proj=laea +lat_0=-90"), "{proj4}");
    let (_, rows) = read_rows(&dst);
    assert_eq!(assert_grid(&rows, "code").len(), 24);
}

/// Four 1 km squares in a 2 × 2 block, ids s0 to s3, each ring's coordinates ("x y,…") made a
/// geometry's WKT by `wkt`.
fn block_of_squares(wkt: impl Fn(&str) -> String) -> Vec<(String, String)> {
    (0..4)
        .map(|k| {
            let (x, y) = (1000 * (k % 2), 1000 * (k / 2));
            let (east, north) = (x + 1000, y + 1000);
            let ring = format!("{x} {y},{east} {y},{east} {north},{x} {north},{x} {y}");
            (format!("s{k}"), wkt(&ring))
        })
        .collect()
}

#[test]
fn curved_regions_are_linearised_and_keep_their_neighbours() {
    // Three rings of eight sectors about the origin, each sector a CurvePolygon whose inner and
    // outer edges are arcs, every arc shared with the sector across it (drawn the other way).
    let scratch = Scratch::new("curved");
    let src = scratch.path("sectors.gpkg");
    let point = |r: f64, a: f64| format!("{} {}", 1000.0 * r * a.cos(), 1000.0 * r * a.sin());
    let mut rows = Vec::new();
    for ring in 0..3 {
        let (inner, outer) = (1.0 + ring as f64, 2.0 + ring as f64);
        for sector in 0..8 {
            let step = std::f64::consts::TAU / 8.0;
            let (a0, a1) = (step * sector as f64, step * (sector + 1) as f64);
            let am = (a0 + a1) / 2.0;
            let wkt = format!(
                "CURVEPOLYGON(COMPOUNDCURVE(CIRCULARSTRING({},{},{}),({},{}),\
                 CIRCULARSTRING({},{},{}),({},{})))",
                point(outer, a0),
                point(outer, am),
                point(outer, a1),
                point(outer, a1),
                point(inner, a1),
                point(inner, a1),
                point(inner, am),
                point(inner, a0),
                point(inner, a0),
                point(outer, a0),
            );
            rows.push((format!("r{ring}s{sector}"), wkt));
        }
    }
    write_regions(&src, 3857, &rows);
    let (dst, report) = (scratch.path("grid.gpkg"), scratch.path("grid.json"));
    let output = snakegrid(["-id", "code", "-json", p(&report), p(&dst), p(&src)]);
    assert_success(&output);
    let summary = stdout(&output);
    assert!(
        summary.contains("feature r0s0 and 23 others: curved geometry (CURVEPOLYGON) linearised"),
        "{summary}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    // By hand: 8 pairs round each of the 3 rings, 8 across each of the 2 circles between them.
    assert_eq!(report["adjacent_pairs"], 40, "{summary}");
    let (_, rows) = read_rows(&dst);
    assert_eq!(assert_grid(&rows, "code").len(), 24);

    // MultiSurfaces of plain polygons, as GML readers hand them over, have nothing to
    // linearise and no note says otherwise.
    let plain_src = scratch.path("plain.gpkg");
    let squares = block_of_squares(|ring| format!("MULTISURFACE((({ring})))"));
    write_regions(&plain_src, 3857, &squares);
    let output = snakegrid([
        "-id",
        "code",
        p(&scratch.path("plain_grid.gpkg")),
        p(&plain_src),
    ]);
    assert_success(&output);
    assert!(
        !stdout(&output).contains("curved geometry"),
        "{}",
        stdout(&output)
    );
}

/// The command, its temporary files kept in `tmp`.
fn snakegrid_in_tmp(tmp: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_snakegrid"))
        .env("TMPDIR", tmp)
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn standard_output_takes_one_output_once_the_run_has_succeeded() {
    let scratch = Scratch::new("stdout");
    let src = scratch.input("us_states");
    let tmp = scratch.path("tmp");
    std::fs::create_dir(&tmp).unwrap();
    // The grid layer as GeoJSON on standard output, the summary on standard error.
    let grid = snakegrid_in_tmp(
        &tmp,
        &["-f", "GeoJSON", "-id", "id", "/vsistdout/", p(&src)],
    );
    assert_success(&grid);
    let collection: serde_json::Value = serde_json::from_slice(&grid.stdout).unwrap();
    let features = collection["features"].as_array().unwrap();
    // The 48 contiguous states and DC (the data README).
    assert_eq!(features.len(), 49);
    assert!(features[0]["properties"]["grid_col"].is_i64());
    assert!(stderr(&grid).contains("49 regions from layer us_states → /vsistdout/"));
    // The JSON report there, the grid in a file.
    let dst = scratch.path("grid.gpkg");
    let report = snakegrid_in_tmp(&tmp, &["-q", "-json", "/vsistdout/", p(&dst), p(&src)]);
    assert_success(&report);
    let report: serde_json::Value = serde_json::from_slice(&report.stdout).unwrap();
    assert_eq!(report["destination"]["dataset"], p(&dst));
    assert_eq!(read_rows(&dst).1.len(), 49);
    // Refused before any work, each with nothing on standard output.
    let refused = [
        (vec!["/vsistdout/"], "give -f"),
        (
            vec!["-f", "ESRI Shapefile", "/vsistdout/"],
            "writes a dataset of 3 files",
        ),
        (
            vec!["-f", "GeoJSON", "-json", "/vsistdout/", "/vsistdout/"],
            "only one can",
        ),
        (vec!["-f", "GeoJSON", "-update", "/vsistdout/"], "-update"),
        // A failed run sends nothing.
        (
            vec!["-f", "GeoJSON", "-where", "abbr = 'ZZ'", "/vsistdout/"],
            "-where",
        ),
    ];
    for (args, message) in refused {
        let mut args = args.clone();
        args.push(p(&src));
        let output = snakegrid_in_tmp(&tmp, &args);
        assert_fails(&output, 1, message);
        assert!(output.stdout.is_empty(), "{args:?}");
    }
    // Every temporary folder is gone.
    assert_eq!(std::fs::read_dir(&tmp).unwrap().count(), 0);
}

#[test]
fn a_field_the_source_declares_not_null_is_kept_so() {
    // GDAL reads a GML layer's gml_id as NOT NULL, as it reads a column a user constrained in
    // QGIS: the output keeps the constraint, as ogr2ogr does, and the trial layer written
    // before the layout (one blank feature) must honour it too.
    let scratch = Scratch::new("not-null");
    let src = scratch.path("squares.gml");
    write_regions(
        &src,
        3857,
        &block_of_squares(|ring| format!("POLYGON(({ring}))")),
    );
    let source = Dataset::open(&src).unwrap();
    let declared = source
        .layer(0)
        .unwrap()
        .defn()
        .fields()
        .any(|f| !f.is_nullable());
    assert!(declared, "GDAL reads gml_id as NOT NULL");
    let dst = scratch.path("grid.gpkg");
    assert_success(&snakegrid(["-q", "-id", "code", p(&dst), p(&src)]));
    let written = Dataset::open(&dst).unwrap();
    let layer = written.layer(0).unwrap();
    let gml_id = layer
        .defn()
        .fields()
        .find(|f| f.name() == "gml_id")
        .unwrap();
    assert!(!gml_id.is_nullable());
    assert_eq!(read_rows(&dst).1.len(), 4);
}

#[test]
fn kml_keeps_every_field_beside_its_own_name_and_description() {
    // GDAL's KML driver makes every layer with fields of its own (Name, Description) before
    // the source's: the cells' values must still land in their fields.
    let scratch = Scratch::new("kml");
    let src = scratch.input("us_states");
    let (kml, gpkg) = (scratch.path("grid.kml"), scratch.path("grid.gpkg"));
    assert_success(&snakegrid([
        "-q",
        "-f",
        "KML",
        "-id",
        "id",
        p(&kml),
        p(&src),
    ]));
    assert_success(&snakegrid(["-q", "-id", "id", p(&gpkg), p(&src)]));
    let in_kml = cells_by_id(&kml);
    assert_eq!(in_kml.len(), 49);
    assert_eq!(in_kml, cells_by_id(&gpkg));
}

#[test]
fn overwriting_a_geopackage_of_one_layer_keeps_the_run_in_its_metadata() {
    // A layer written in place beside others keeps its metrics in its description only (GDAL
    // would rewrite the others' metadata); with no other layer in the file, it was still left
    // without its parameters and metrics, and the note blamed other layers.
    let scratch = Scratch::new("overwrite-metadata");
    let src = scratch.input("us_states");
    let dst = scratch.path("grid.gpkg");
    assert_success(&snakegrid(["-q", "-id", "id", p(&dst), p(&src)]));
    let output = snakegrid(["-id", "id", "-seed", "3", "-overwrite", p(&dst), p(&src)]);
    assert_success(&output);
    assert!(
        !stdout(&output).contains("metadata tables"),
        "{}",
        stdout(&output)
    );
    let written = Dataset::open(&dst).unwrap();
    use gdal::Metadata;
    let parameters = (written.layer(0).unwrap())
        .metadata_item("SNAKEGRID_PARAMETERS", "")
        .expect("the run's parameters");
    assert!(parameters.contains("\"seed\":3"), "{parameters}");
    let mut count = written
        .execute_sql(
            "SELECT COUNT(*) FROM gpkg_metadata",
            None,
            gdal::vector::sql::Dialect::DEFAULT,
        )
        .unwrap()
        .expect("a result set");
    let rows = count.features().next().unwrap().field_as_integer(0);
    assert_eq!(rows.unwrap(), Some(1), "the first run's metadata is gone");
}

/// Each cell's column and row by its region's `id`, read from the fields asked for only (KML's
/// own, such as a null timestamp, do not read as text).
fn cells_by_id(path: &Path) -> BTreeMap<String, (i32, i32)> {
    let dataset = Dataset::open(path).unwrap();
    let mut layer = dataset.layer(0).unwrap();
    let index = |name: &str| layer.defn().field_index(name).unwrap();
    let (id, col, row) = (index("id"), index("grid_col"), index("grid_row"));
    layer
        .features()
        .map(|f| {
            let int = |k| f.field_as_integer(k).unwrap().unwrap();
            (
                f.field_as_string(id).unwrap().unwrap(),
                (int(col), int(row)),
            )
        })
        .collect()
}

#[test]
fn a_format_gdal_cannot_write_in_memory_is_tried_on_disk() {
    // GDAL's netCDF driver claims virtual I/O but cannot create a vector dataset in /vsimem/,
    // where the output's trial runs first: it failed with "Unable to create netCDF file
    // grid.nc (tried in memory)", as if the destination's folder were missing.
    let scratch = Scratch::new("netcdf");
    let src = scratch.input("us_states");
    let (nc, gpkg) = (scratch.path("grid.nc"), scratch.path("grid.gpkg"));
    let output = snakegrid(["-q", "-id", "id", p(&nc), p(&src)]);
    assert_success(&output);
    assert_success(&snakegrid(["-q", "-id", "id", p(&gpkg), p(&src)]));
    let in_netcdf = cells_by_id(&nc);
    assert_eq!(in_netcdf.len(), 49);
    assert_eq!(in_netcdf, cells_by_id(&gpkg));
    let leftovers: Vec<_> = (std::fs::read_dir(scratch.path("")).unwrap())
        .map(|entry| entry.unwrap().file_name())
        .filter(|name| name.to_string_lossy().contains("snakegrid"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn list_fields_a_format_lacks_are_written_as_json_text() {
    // A GeoJSON layer with array properties: FlatGeobuf takes list fields' definitions but
    // fails at the first feature with a value, and a Shapefile refuses them.
    let scratch = Scratch::new("lists");
    let src = scratch.path("lists.geojson");
    let features: Vec<serde_json::Value> = block_of_squares(|ring| ring.to_owned())
        .into_iter()
        .map(|(id, ring)| {
            let points: Vec<[f64; 2]> = ring
                .split(',')
                .map(|xy| {
                    let mut it = xy.split(' ').map(|v| v.parse::<f64>().unwrap());
                    [it.next().unwrap(), it.next().unwrap()]
                })
                .collect();
            serde_json::json!({
                "type": "Feature",
                "properties": {"code": id, "tags": ["a", "b"], "nums": [1, 2, 3]},
                "geometry": {"type": "Polygon", "coordinates": [points]}
            })
        })
        .collect();
    let collection = serde_json::json!({
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3857"}},
        "features": features
    });
    std::fs::write(&src, collection.to_string()).unwrap();
    for name in ["grid.fgb", "grid.shp"] {
        let dst = scratch.path(name);
        let output = snakegrid(["-id", "code", p(&dst), p(&src)]);
        assert_success(&output);
        assert!(
            stdout(&output)
                .contains("the source field \"tags\" (StringList) is written as JSON text"),
            "{}",
            stdout(&output)
        );
        let (_, rows) = read_rows(&dst);
        assert_eq!(rows.len(), 4);
        assert!(rows
            .iter()
            .all(|r| r.fields["tags"] == r#"["a","b"]"# && r.fields["nums"] == "[1,2,3]"));
    }
}
