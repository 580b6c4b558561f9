//! `snakegrid::io::run`, the entry point the command line and the C API share: attribute
//! fidelity, layers without a CRS, and cancellation (which leaves nothing behind).
// Reads and writes datasets: needs the GDAL layer.
#![cfg(feature = "gdal")]

use gdal::vector::{Feature, FieldDefn, Geometry, LayerAccess, LayerOptions, OGRFieldType};
use gdal::{Dataset, DriverManager};
use snakegrid::io::{run, Job};
use snakegrid::{Error, Params};
use std::path::Path;

mod common;
use common::Scratch;

fn text(path: &Path) -> String {
    path.to_str().unwrap().to_owned()
}

/// The fields of the test layer: every basic OGR type, a boolean subtype, and names that clash
/// with the output's own columns (`fid` with GeoPackage's FID column, `grid_col` with ours).
const FIELDS: [(&str, OGRFieldType::Type); 9] = [
    ("code", OGRFieldType::OFTString),
    ("fid", OGRFieldType::OFTInteger),
    ("big", OGRFieldType::OFTInteger64),
    ("ratio", OGRFieldType::OFTReal),
    ("day", OGRFieldType::OFTDate),
    ("stamp", OGRFieldType::OFTDateTime),
    ("flag", OGRFieldType::OFTInteger),
    ("blob", OGRFieldType::OFTBinary),
    ("grid_col", OGRFieldType::OFTString),
];

/// A 4 × 3 block of unit squares (km) with one value of each field type; `srs`: EPSG code.
fn write_blocks(path: &Path, srs: Option<u32>) {
    let mut dataset = DriverManager::get_driver_by_name("GPKG")
        .unwrap()
        .create_vector_only(path)
        .unwrap();
    let srs = srs.map(|code| gdal::spatial_ref::SpatialRef::from_epsg(code).unwrap());
    let layer = dataset
        .create_layer(LayerOptions {
            name: "blocks",
            srs: srs.as_ref(),
            // The source's own FID column must not be confused with its `fid` field.
            options: Some(&["FID=pk"]),
            ..Default::default()
        })
        .unwrap();
    for (name, kind) in FIELDS {
        if name != "flag" {
            FieldDefn::new(name, kind)
                .unwrap()
                .add_to_layer(&layer)
                .unwrap();
            continue;
        }
        // The binding cannot set a subtype.
        // SAFETY: the definition is created, used while alive and destroyed here; the layer is
        // alive and copies the definition it is given.
        unsafe {
            let name = std::ffi::CString::new(name).unwrap();
            let definition = gdal_sys::OGR_Fld_Create(name.as_ptr(), kind);
            gdal_sys::OGR_Fld_SetSubType(definition, gdal_sys::OGRFieldSubType::OFSTBoolean);
            let result = gdal_sys::OGR_L_CreateField(layer.c_layer(), definition, 0);
            gdal_sys::OGR_Fld_Destroy(definition);
            assert_eq!(result, gdal_sys::OGRErr::OGRERR_NONE);
        }
    }
    for k in 0..12 {
        let (x, y) = (f64::from(k % 4) * 1000.0, f64::from(k / 4) * 1000.0);
        let mut feature = Feature::new(layer.defn()).unwrap();
        let values = [
            format!("B{k:02}"),
            (100 + k).to_string(),
            (5_000_000_000_i64 + i64::from(k)).to_string(),
            format!("{}", f64::from(k) / 3.0),
            format!("2024-05-{:02}", k + 1),
            format!("2024-05-06 07:08:{:02}", k),
            (k % 2).to_string(),
            format!("CAFE{k:02X}"),
            format!("stale{k}"),
        ];
        for (i, value) in values.iter().enumerate() {
            feature.set_field_string(i, value).unwrap();
        }
        let wkt = format!(
            "POLYGON (({x} {y}, {} {y}, {} {}, {x} {}, {x} {y}))",
            x + 1000.0,
            x + 1000.0,
            y + 1000.0,
            y + 1000.0
        );
        feature
            .set_geometry(Geometry::from_wkt(&wkt).unwrap())
            .unwrap();
        feature.create(&layer).unwrap();
    }
}

/// Field (name, type, subtype) of the first layer, and each feature's values as text.
#[allow(clippy::type_complexity)]
fn fields_and_values(path: &Path) -> (Vec<(String, u32, u32)>, Vec<Vec<String>>) {
    let dataset = Dataset::open(path).unwrap();
    let mut layer = dataset.layer(0).unwrap();
    let defn = layer.defn();
    let fields: Vec<(String, u32, u32)> = defn
        .fields()
        .enumerate()
        .map(|(i, f)| {
            // SAFETY: the layer definition is alive and i < its field count; the binding has no
            // subtype getter.
            let subtype = unsafe {
                gdal_sys::OGR_Fld_GetSubType(gdal_sys::OGR_FD_GetFieldDefn(defn.c_defn(), i as i32))
            };
            (f.name(), f.field_type(), subtype)
        })
        .collect();
    let count = fields.len();
    let values = layer
        .features()
        .map(|f| {
            (0..count)
                .map(|i| f.field_as_string(i).unwrap().unwrap_or_default())
                .collect()
        })
        .collect();
    (fields, values)
}

fn job(src: &Path, dst: &Path) -> Job {
    Job {
        src: text(src),
        dst: text(dst),
        id_field: Some("code".into()),
        ..Default::default()
    }
}

#[test]
fn every_source_field_keeps_its_name_type_subtype_and_value() {
    let scratch = Scratch::new("fields");
    let src = scratch.path("blocks.gpkg");
    write_blocks(&src, Some(3857));
    let dst = scratch.path("grid.gpkg");
    let outcome = run(&job(&src, &dst), &Params::default(), &|_, _| true).unwrap();
    assert_eq!(outcome.map.cells.len(), 12);
    assert_eq!(outcome.format, "GPKG");
    assert_eq!(outcome.layer, "blocks");
    assert!(outcome.crs.as_deref().unwrap().contains("3857"));
    assert!(
        outcome.notes.iter().any(|n| n
            == "the source field \"grid_col\" is written as \"src_grid_col\": the GPKG output \
                would otherwise give it the name of the computed field"),
        "{:?}",
        outcome.notes
    );

    let (source_fields, source_values) = fields_and_values(&src);
    let (fields, values) = fields_and_values(&dst);
    let names: Vec<&str> = fields.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "code",
            "fid",
            "big",
            "ratio",
            "day",
            "stamp",
            "flag",
            "blob",
            "src_grid_col",
            "grid_col",
            "grid_row",
            "grid_q",
            "grid_r",
            "cell_disp",
            "nbr_kept",
            "orient_err",
            "grid_group"
        ]
    );
    // Every source field is the same field with the same values, the one that collided with a
    // computed field under its new name; the computed grid_col holds the column.
    assert_eq!(fields[..8], source_fields[..8]);
    assert_eq!(fields[8].1, source_fields[8].1);
    let cells: std::collections::HashMap<&str, i32> = outcome
        .map
        .cells
        .iter()
        .map(|c| (c.id.as_str(), c.col))
        .collect();
    for (row, source_row) in values.iter().zip(&source_values) {
        assert_eq!(row[..9], source_row[..9]);
        assert_eq!(row[9], cells[row[0].as_str()].to_string());
    }

    // The metadata name the ids' field in this layer and in the source, which differ when the
    // id field is the one written under a new name.
    let id_fields = |dst: &Path| {
        use gdal::Metadata;
        let dataset = Dataset::open(dst).unwrap();
        let layer = dataset.layer(0).unwrap();
        let item = |key: &str| layer.metadata_item(key, "").unwrap();
        (
            item("SNAKEGRID_ID_FIELD"),
            item("SNAKEGRID_SOURCE_ID_FIELD"),
        )
    };
    assert_eq!(id_fields(&dst), ("code".into(), "code".into()));
    let renamed = scratch.path("by_grid_col.gpkg");
    let by_grid_col = Job {
        id_field: Some("grid_col".into()),
        ..job(&src, &renamed)
    };
    run(&by_grid_col, &Params::default(), &|_, _| true).unwrap();
    assert_eq!(
        id_fields(&renamed),
        ("src_grid_col".into(), "grid_col".into())
    );
}

#[test]
fn a_grid_layer_laid_out_again_keeps_every_field_under_a_name_of_its_own() {
    // An earlier run's output holds src_grid_col (the source's grid_col) and the computed
    // grid_col: laid out again, that grid_col is a source field to rename, and src_grid_col,
    // the name it would take, is taken.
    let scratch = Scratch::new("again");
    let src = scratch.path("blocks.gpkg");
    write_blocks(&src, Some(3857));
    let first = scratch.path("first.gpkg");
    run(&job(&src, &first), &Params::default(), &|_, _| true).unwrap();
    let second = scratch.path("second.gpkg");
    let outcome = run(&job(&first, &second), &Params::default(), &|_, _| true).unwrap();

    let (first_fields, first_values) = fields_and_values(&first);
    let (fields, values) = fields_and_values(&second);
    let names: Vec<&str> = fields.iter().map(|f| f.0.as_str()).collect();
    let first_names: Vec<&str> = first_fields.iter().map(|f| f.0.as_str()).collect();
    // The first run's fields in order, those named like a computed field written as src_…,
    // src_grid_col (the source's grid_col) kept, and the computed fields after them.
    let computed = &first_names[9..];
    assert_eq!(first_names[8], "src_grid_col");
    assert_eq!(names[..9], first_names[..9]);
    let renamed: Vec<String> = computed
        .iter()
        .map(|n| match *n {
            "grid_col" => "src_grid_col_2".to_owned(),
            n => format!("src_{n}"),
        })
        .collect();
    assert_eq!(names[9..first_names.len()], renamed);
    assert_eq!(names[first_names.len()..], *computed);
    for (row, first_row) in values.iter().zip(&first_values) {
        assert_eq!(row[..first_fields.len()], first_row[..]);
    }
    assert!(
        (outcome.notes.iter()).any(
            |n| n.starts_with("the source field \"grid_col\" is written as \"src_grid_col_2\"")
        ),
        "{:?}",
        outcome.notes
    );
}

#[test]
fn fields_named_alike_but_for_case_are_written_as_ogr2ogr_writes_them() {
    // GeoJSON tells "Name" from "NAME"; GeoPackage (SQLite) and Shapefile (DBF) do not. GDAL
    // 3.6's ogr2ogr, run by hand on this very layer, writes the fields as expected below.
    let scratch = Scratch::new("case");
    let src = scratch.path("case.geojson");
    let square = |x: u32| format!("[[[{x},0],[{},0],[{},1],[{x},1],[{x},0]]]", x + 1, x + 1);
    let feature = |x: u32, name: &str, upper: &str, lower: &str| {
        format!(
            r#"{{"type":"Feature","properties":{{"code":"{name}","Name":"{upper}","NAME":"{lower}","name2":"x"}},"geometry":{{"type":"Polygon","coordinates":{}}}}}"#,
            square(x)
        )
    };
    std::fs::write(
        &src,
        format!(
            r#"{{"type":"FeatureCollection","features":[{},{}]}}"#,
            feature(0, "a", "Alpha", "ALPHA"),
            feature(1, "b", "Beta", "BETA")
        ),
    )
    .unwrap();
    for dst in ["grid.gpkg", "grid.shp", "grid.geojson"] {
        let dst = scratch.path(dst);
        let outcome = run(&job(&src, &dst), &Params::default(), &|_, _| true).unwrap();
        let (fields, values) = fields_and_values(&dst);
        let names: Vec<&str> = fields.iter().map(|f| f.0.as_str()).take(4).collect();
        // "name2" is taken (without case), so the second "Name" takes "NAME3".
        assert_eq!(
            names,
            ["code", "Name", "NAME3", "name2"],
            "{}",
            dst.display()
        );
        let rows: Vec<&[String]> = values.iter().map(|row| &row[..3]).collect();
        assert_eq!(rows, [["a", "Alpha", "ALPHA"], ["b", "Beta", "BETA"]]);
        assert!(
            (outcome.notes.iter()).any(|n| n.starts_with(
                "the source field \"NAME\" is written as \"NAME3\", as ogr2ogr writes it"
            )),
            "{:?}",
            outcome.notes
        );
    }
}

#[test]
fn a_layer_without_crs_is_taken_as_planar_with_a_note() {
    let scratch = Scratch::new("no-crs");
    let src = scratch.path("blocks.gpkg");
    write_blocks(&src, None);
    let dst = scratch.path("grid.geojson");
    let outcome = run(&job(&src, &dst), &Params::default(), &|_, _| true).unwrap();
    assert!(outcome.crs.is_none());
    assert!(
        outcome.notes.iter().any(|n| n.contains("no CRS")),
        "{:?}",
        outcome.notes
    );
    assert_eq!(outcome.format, "GeoJSON");
    // -t_srs needs a source CRS.
    let mut reprojected = job(&src, &scratch.path("other.gpkg"));
    reprojected.target_srs = Some("EPSG:4326".into());
    let error = run(&reprojected, &Params::default(), &|_, _| true).unwrap_err();
    assert!(error.to_string().contains("no CRS"), "{error}");
}

#[test]
fn a_cancelled_run_leaves_nothing_behind() {
    let scratch = Scratch::new("cancelled");
    let src = scratch.path("blocks.gpkg");
    write_blocks(&src, Some(3857));
    let dst = scratch.path("grid.gpkg");
    let mut with_extras = job(&src, &dst);
    with_extras.json_report = Some(text(&scratch.path("r.json")));
    with_extras.svg = Some(text(&scratch.path("p.svg")));
    // Cancelled while laying out, then while writing.
    for after in [0.5, 0.95] {
        let result = run(&with_extras, &Params::default(), &|fraction, _| {
            fraction < after
        });
        assert!(
            matches!(result, Err(Error::Cancelled)),
            "{:?}",
            result.err()
        );
        assert_eq!(scratch.listing(), ["blocks.gpkg"]);
    }
    // A full run then writes all three.
    run(&with_extras, &Params::default(), &|_, _| true).unwrap();
    assert_eq!(
        scratch.listing(),
        ["blocks.gpkg", "grid.gpkg", "p.svg", "r.json"]
    );
}

#[test]
fn outputs_must_differ_from_each_other_and_from_the_source() {
    let scratch = Scratch::new("distinct");
    let src = scratch.path("blocks.gpkg");
    write_blocks(&src, Some(3857));
    let mut same = job(&src, &src);
    same.overwrite = true;
    let error = run(&same, &Params::default(), &|_, _| true).unwrap_err();
    assert!(
        error
            .to_string()
            .contains("refusing to write over the source"),
        "{error}"
    );
    let mut twice = job(&src, &scratch.path("grid.gpkg"));
    twice.json_report = Some(text(&scratch.path("grid.gpkg")));
    let error = run(&twice, &Params::default(), &|_, _| true).unwrap_err();
    assert!(error.to_string().contains("are the same file"), "{error}");
    assert_eq!(scratch.listing(), ["blocks.gpkg"]);
}
