//! Nothing the user owns is lost, and every output is what it claims: no option makes a run write
//! to a file of the source, however the paths are spelled; a failed, refused or interrupted run
//! leaves every existing file as it was; `-overwrite -nln` replaces one layer of a GeoPackage and
//! keeps the others; outputs that would lose or change what they store are refused before the
//! run; and memory follows the regions rather than the empty space between them.
// Reads and writes datasets: needs the GDAL layer.
#![cfg(feature = "gdal")]

use gdal::vector::LayerAccess;
use gdal::Dataset;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

mod common;
use common::cli::{assert_fails, assert_success, p, snakegrid, stderr, stdout};
use common::{shared_layer, Scratch};

/// Every file in `dir` with its bytes, to prove afterwards that nothing changed.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (p, bytes)
        })
        .collect();
    files.sort();
    files
}

/// The bundled sample as a source in its own folder of `scratch`.
fn source(scratch: &Scratch) -> (PathBuf, PathBuf) {
    let dir = scratch.path("src");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let src = dir.join("us_states.gpkg");
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/us_states.gpkg"),
        &src,
    )
    .unwrap();
    (dir, src)
}

#[test]
fn no_output_may_be_the_source_however_it_is_spelled() {
    let scratch = Scratch::new("source-outputs");
    let (dir, src) = source(&scratch);
    let link = scratch.path("link.gpkg");
    std::os::unix::fs::symlink(&src, &link).unwrap();
    let before = snapshot(&dir);
    let dst = scratch.path("grid.gpkg");
    let respelled = dir.join("sub/../us_states.gpkg");
    let attempts: [Vec<&str>; 5] = [
        vec!["-json", p(&src), p(&dst)],
        vec!["-svg", p(&src), p(&dst)],
        vec![p(&respelled)],
        vec![p(&link)],
        vec![p(&dir)],
    ];
    for attempt in attempts {
        let mut args = vec!["-q", "-overwrite", "-id", "id"];
        args.extend(&attempt);
        args.push(p(&src));
        let out = snakegrid(&args);
        assert_fails(&out, 1, "refusing to write over the source");
        let message = String::from_utf8_lossy(&out.stderr);
        assert!(message.contains("us_states.gpkg"), "{message}");
        assert_eq!(
            snapshot(&dir),
            before,
            "{attempt:?} left the source as it was"
        );
        assert!(!dst.exists(), "{attempt:?} wrote nothing");
    }
}

#[test]
fn a_sidecar_of_a_shapefile_source_is_refused_as_a_destination() {
    let scratch = Scratch::new("sidecar");
    let (_, gpkg) = source(&scratch);
    let shapes = scratch.path("shapes");
    std::fs::create_dir(&shapes).unwrap();
    let shp = shapes.join("a.shp");
    assert_success(&snakegrid(["-q", "-id", "id", p(&shp), p(&gpkg)]));
    let before = snapshot(&shapes);
    assert!(
        before.len() >= 4,
        "a Shapefile with its sidecars: {before:?}"
    );
    for sidecar in ["a.dbf", "a.shx", "a.prj"] {
        let dst = shapes.join(sidecar);
        let out = snakegrid(["-q", "-overwrite", "-f", "GPKG", p(&dst), p(&shp)]);
        assert_fails(&out, 1, sidecar);
        assert_eq!(
            snapshot(&shapes),
            before,
            "{sidecar}: the source set is intact"
        );
    }
}

/// Two 3×3 clusters of unit squares `gap` cells apart, as GeoJSON in a projected CRS.
fn clusters(path: &Path, gap: f64) {
    let mut features = Vec::new();
    for cluster in 0..2 {
        for col in 0..3 {
            for row in 0..3 {
                let (x, y) = (f64::from(cluster) * gap + f64::from(col), f64::from(row));
                features.push(format!(
                    r#"{{"type":"Feature","properties":{{"id":"c{cluster}_{col}{row}"}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                    x + 1.0,
                    x + 1.0,
                    y + 1.0,
                    y + 1.0
                ));
            }
        }
    }
    let crs = r#"{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::3857"}}"#;
    std::fs::write(
        path,
        format!(
            r#"{{"type":"FeatureCollection","crs":{crs},"features":[{}]}}"#,
            features.join(",")
        ),
    )
    .unwrap();
}

#[test]
fn far_apart_clusters_each_stay_one_block() {
    let scratch = Scratch::new("clusters");
    for gap in [1e4, 1e5, 9e5] {
        let src = scratch.path(&format!("clusters-{gap}.geojson"));
        let dst = scratch.path(&format!("clusters-{gap}.out.geojson"));
        clusters(&src, gap);
        assert_success(&snakegrid(["-q", "-id", "id", p(&dst), p(&src)]));
        let written: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&dst).unwrap()).unwrap();
        let mut cells = std::collections::HashMap::new();
        for feature in written["features"].as_array().unwrap() {
            let fields = &feature["properties"];
            let cell = (
                fields["grid_col"].as_i64().unwrap() as i32,
                fields["grid_row"].as_i64().unwrap() as i32,
            );
            cells.insert(cell, fields["id"].as_str().unwrap().to_owned());
        }
        assert_eq!(cells.len(), 18, "gap {gap}: every square has its own cell");
        for cluster in ["c0", "c1"] {
            let mine: Vec<(i32, i32)> = (cells.iter())
                .filter(|(_, id)| id.starts_with(cluster))
                .map(|(cell, _)| *cell)
                .collect();
            let span = |f: fn(&(i32, i32)) -> i32| {
                mine.iter().map(f).max().unwrap() - mine.iter().map(f).min().unwrap()
            };
            assert_eq!(
                (span(|c| c.0), span(|c| c.1)),
                (2, 2),
                "gap {gap}: {cluster} is a 3×3 block"
            );
        }
    }
}

/// A row of unit squares (EPSG:3857), one per entry of `properties` (each a JSON object's
/// members, e.g. `"id":"a"`), as GeoJSON.
fn squares(path: &Path, properties: &[String]) {
    let features: Vec<String> = properties
        .iter()
        .enumerate()
        .map(|(k, members)| {
            let (x, y) = ((k % 4) as f64, (k / 4) as f64);
            format!(
                r#"{{"type":"Feature","properties":{{{members}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                x + 1.0,
                x + 1.0,
                y + 1.0,
                y + 1.0
            )
        })
        .collect();
    let crs = r#"{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::3857"}}"#;
    std::fs::write(
        path,
        format!(
            r#"{{"type":"FeatureCollection","crs":{crs},"features":[{}]}}"#,
            features.join(",")
        ),
    )
    .unwrap();
}

/// Eight squares with ids `a0`..`a7`, except those `ids` replaces.
fn ids_layer(path: &Path, ids: &[&str]) {
    let rows: Vec<String> = (0..8)
        .map(|k| {
            let id = ids
                .get(k)
                .map_or_else(|| format!("a{k}"), |id| id.to_string());
            format!(r#""id":{}"#, serde_json::Value::String(id))
        })
        .collect();
    squares(path, &rows);
}

/// The names in `dir` that a run's staging folders would have.
fn staging_left(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".snakegrid-"))
        .collect();
    names.sort();
    names
}

// ---------------------------------------------------------------------------------------------
// A failed run leaves every existing file as it was.

#[test]
fn a_folder_destination_is_refused_and_left_as_it_was() {
    // The issue's case: -overwrite onto a folder holding a Shapefile and an unrelated file
    // deleted the Shapefile, then failed to move the GeoPackage in.
    let scratch = Scratch::new("folder-destination");
    let (_, src) = source(&scratch);
    let folder = scratch.path("shapes");
    std::fs::create_dir(&folder).unwrap();
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        p(&folder.join("old.shp")),
        p(&src),
    ]));
    std::fs::write(folder.join("notes.txt"), b"unrelated").unwrap();
    let before = snapshot(&folder);
    for args in [
        vec!["-overwrite", "-f", "GPKG"],
        vec!["-overwrite", "-f", "ESRI Shapefile"],
        vec!["-update", "-f", "ESRI Shapefile"],
    ] {
        let mut all = vec!["-q", "-id", "id"];
        all.extend(&args);
        all.extend([p(&folder), p(&src)]);
        let out = snakegrid(&all);
        assert_fails(
            &out,
            1,
            "is a folder: snakegrid does not replace or update folders",
        );
        assert!(stderr(&out).contains("shapes"), "{}", stderr(&out));
        assert_eq!(snapshot(&folder), before, "{args:?}: the folder is intact");
        assert!(staging_left(&scratch.path("")).is_empty());
    }
}

#[test]
fn outputs_are_committed_together_or_not_at_all() {
    let scratch = Scratch::new("together");
    let (_, src) = source(&scratch);
    let dst = scratch.path("grid.gpkg");
    assert_success(&snakegrid(["-q", "-id", "id", p(&dst), p(&src)]));
    let old = std::fs::read(&dst).unwrap();

    // A report that cannot be written is refused before the run, and DST stays.
    let report_folder = scratch.path("report.json");
    std::fs::create_dir(&report_folder).unwrap();
    let out = snakegrid([
        "-q",
        "-overwrite",
        "-id",
        "abbr",
        "-json",
        p(&report_folder),
        p(&dst),
        p(&src),
    ]);
    assert_fails(&out, 1, "the JSON report");
    assert!(stderr(&out).contains("is a folder"), "{}", stderr(&out));
    assert_eq!(std::fs::read(&dst).unwrap(), old);

    // A sidecar of the new Shapefile that is already taken is found when the outputs are moved
    // into place, before the first of them is: neither the Shapefile nor the report appears.
    let shapes = scratch.path("shapes");
    std::fs::create_dir(&shapes).unwrap();
    std::fs::write(shapes.join("grid.dbf"), b"someone else's").unwrap();
    let report = shapes.join("report.json");
    let out = snakegrid([
        "-q",
        "-id",
        "id",
        "-json",
        p(&report),
        p(&shapes.join("grid.shp")),
        p(&src),
    ]);
    assert_fails(
        &out,
        1,
        "grid.dbf\" already exists (use -overwrite to replace it)",
    );
    let names: Vec<String> = snapshot(&shapes)
        .into_iter()
        .map(|(path, _)| path.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["grid.dbf"]);
    assert_eq!(
        std::fs::read(shapes.join("grid.dbf")).unwrap(),
        b"someone else's"
    );
    assert!(staging_left(&shapes).is_empty());
}

#[test]
fn update_adds_a_layer_and_refuses_one_that_exists() {
    let scratch = Scratch::new("update");
    let (_, src) = source(&scratch);
    let dst = scratch.path("grid.gpkg");
    let out = snakegrid(["-q", "-update", "-id", "id", p(&dst), p(&src)]);
    assert_fails(
        &out,
        1,
        "does not exist: -update adds a layer to an existing dataset",
    );
    assert!(!dst.exists());
    assert_success(&snakegrid(["-q", "-id", "id", p(&dst), p(&src)]));
    assert_success(&snakegrid([
        "-q",
        "-update",
        "-id",
        "id",
        "-nln",
        "second",
        p(&dst),
        p(&src),
    ]));
    let layers: Vec<String> = Dataset::open(&dst)
        .unwrap()
        .layers()
        .map(|l| l.name())
        .collect();
    assert_eq!(layers, ["us_states", "second"]);
    let before = std::fs::read(&dst).unwrap();
    let out = snakegrid([
        "-q",
        "-update",
        "-id",
        "id",
        "-nln",
        "SECOND",
        p(&dst),
        p(&src),
    ]);
    assert_fails(
        &out,
        1,
        "already has a layer \"second\" (use -overwrite to replace it",
    );
    assert_eq!(std::fs::read(&dst).unwrap(), before);
    // A GeoPackage another program has open is not updated behind its back.
    let wal = scratch.path("grid.gpkg-wal");
    std::fs::write(&wal, b"pages not yet in the file").unwrap();
    let out = snakegrid([
        "-q",
        "-update",
        "-id",
        "id",
        "-nln",
        "third",
        p(&dst),
        p(&src),
    ]);
    assert_fails(&out, 1, "is in use");
    assert!(stderr(&out).contains("grid.gpkg-wal"), "{}", stderr(&out));
    assert_eq!(std::fs::read(&dst).unwrap(), before);
    std::fs::remove_file(&wal).unwrap();
    // A single-layer format cannot take a second layer.
    let geojson = scratch.path("grid.geojson");
    assert_success(&snakegrid(["-q", "-id", "id", p(&geojson), p(&src)]));
    let out = snakegrid([
        "-q",
        "-update",
        "-id",
        "id",
        "-nln",
        "more",
        p(&geojson),
        p(&src),
    ]);
    assert_fails(
        &out,
        1,
        "the GeoJSON format cannot add a layer to the existing",
    );
    assert!(staging_left(&scratch.path("")).is_empty());
}

/// Every row of a SQL query on `dataset`, each value as text.
fn rows(dataset: &Dataset, sql: &str) -> Vec<Vec<String>> {
    let Some(mut result) = dataset
        .execute_sql(sql, None, gdal::vector::sql::Dialect::DEFAULT)
        .unwrap()
    else {
        return Vec::new();
    };
    let count = result.defn().fields().count();
    result
        .features()
        .map(|f| {
            (0..count)
                .map(|i| f.field_as_string(i).unwrap().unwrap_or_default())
                .collect()
        })
        .collect()
}

/// What must not change in `gpkg` when its layer `grid` is added or replaced: every other
/// layer as `ogrinfo -al` shows it, and the rows of the GeoPackage's own tables, QGIS's styles
/// and the related-tables extension that concern other tables.
#[derive(PartialEq)]
struct AllButGrid {
    ogrinfo: String,
    /// Each query with its rows.
    tables: Vec<(String, Vec<Vec<String>>)>,
}

/// Asserts that nothing but the layer `grid` changed, showing only what did.
fn assert_same(now: &AllButGrid, before: &AllButGrid, when: &str) {
    assert!(
        now.ogrinfo == before.ogrinfo,
        "{when}: ogrinfo -al of the other layers differs"
    );
    for ((query, rows), (_, old)) in now.tables.iter().zip(&before.tables) {
        assert_eq!(rows, old, "{when}: {query}");
    }
}

fn everything_but_grid(gpkg: &Path) -> AllButGrid {
    let ogrinfo = Command::new("ogrinfo")
        .args([
            "-al",
            "-q",
            p(gpkg),
            "states",
            "nc",
            "notes",
            "states_notes",
        ])
        .output()
        .unwrap();
    assert!(
        ogrinfo.status.success(),
        "{}",
        String::from_utf8_lossy(&ogrinfo.stderr)
    );
    let dataset = Dataset::open(gpkg).unwrap();
    let not_grid = "lower(table_name) <> 'grid'";
    let queries = [
        format!("SELECT * FROM gpkg_contents WHERE {not_grid}"),
        format!("SELECT * FROM gpkg_geometry_columns WHERE {not_grid}"),
        format!("SELECT * FROM gpkg_extensions WHERE table_name IS NULL OR {not_grid}"),
        "SELECT * FROM gpkg_spatial_ref_sys".to_owned(),
        format!(
            "SELECT m.* FROM gpkg_metadata m JOIN gpkg_metadata_reference r \
             ON r.md_file_id = m.id WHERE {not_grid}"
        ),
        format!("SELECT * FROM gpkg_metadata_reference WHERE {not_grid}"),
        "SELECT * FROM layer_styles WHERE lower(f_table_name) <> 'grid'".to_owned(),
        "SELECT * FROM gpkgext_relations".to_owned(),
    ];
    let tables = queries
        .into_iter()
        .map(|query| {
            let found = rows(&dataset, &query);
            assert!(!found.is_empty(), "{query} finds rows to compare");
            (query, found)
        })
        .collect();
    AllButGrid {
        ogrinfo: String::from_utf8(ogrinfo.stdout).unwrap(),
        tables,
    }
}

/// A GeoPackage of several layers, as a user keeps them: two polygon layers, an attribute table,
/// a QGIS style for each, layer metadata and a relation.
fn multi_layer_geopackage(path: &Path) {
    let ogr2ogr = |args: &[&str]| {
        let out = Command::new("ogr2ogr").args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let states = concat!(env!("CARGO_MANIFEST_DIR"), "/data/us_states.gpkg");
    let nc = shared_layer("nc_counties");
    ogr2ogr(&["-f", "GPKG", "-nln", "states", p(path), states]);
    ogr2ogr(&["-update", "-nln", "nc", p(path), p(&nc)]);
    ogr2ogr(&[
        "-update",
        "-nln",
        "notes",
        "-nlt",
        "NONE",
        "-sql",
        "SELECT abbr, name FROM us_states",
        p(path),
        states,
    ]);
    let dataset = Dataset::open_ex(
        path,
        gdal::DatasetOptions {
            open_flags: gdal::GdalOpenFlags::GDAL_OF_UPDATE | gdal::GdalOpenFlags::GDAL_OF_VECTOR,
            ..Default::default()
        },
    )
    .unwrap();
    {
        use gdal::Metadata;
        let mut states = dataset.layer_by_name("states").unwrap();
        states
            .set_metadata_item("SOURCE", "the census", "")
            .unwrap();
    }
    for sql in [
        "CREATE TABLE layer_styles (id INTEGER PRIMARY KEY AUTOINCREMENT, f_table_catalog TEXT, \
         f_table_schema TEXT, f_table_name TEXT, f_geometry_column TEXT, styleName TEXT, \
         styleQML TEXT, styleSLD TEXT, useAsDefault BOOLEAN, description TEXT, owner TEXT, \
         ui TEXT, update_time DATETIME)",
        "INSERT INTO layer_styles (f_table_name, f_geometry_column, styleName, styleQML, \
         useAsDefault) VALUES ('states', 'geom', 'states', '<qgis/>', 1), \
         ('grid', 'geom', 'grid', '<qgis/>', 1)",
        "CREATE TABLE states_notes (base_id INTEGER NOT NULL, related_id INTEGER NOT NULL)",
        "INSERT INTO states_notes VALUES (1, 1), (2, 2)",
        "CREATE TABLE gpkgext_relations (id INTEGER PRIMARY KEY AUTOINCREMENT, \
         base_table_name TEXT NOT NULL, base_primary_column TEXT NOT NULL DEFAULT 'id', \
         related_table_name TEXT NOT NULL, related_primary_column TEXT NOT NULL DEFAULT 'id', \
         relation_name TEXT NOT NULL, mapping_table_name TEXT NOT NULL UNIQUE)",
        "INSERT INTO gpkgext_relations (base_table_name, base_primary_column, \
         related_table_name, related_primary_column, relation_name, mapping_table_name) \
         VALUES ('states', 'fid', 'notes', 'fid', 'attributes', 'states_notes')",
        "INSERT INTO gpkg_extensions VALUES ('gpkgext_relations', NULL, 'gpkg_related_tables', \
         'http://www.geopackage.org/18-000.html', 'read-write'), ('states_notes', NULL, \
         'gpkg_related_tables', 'http://www.geopackage.org/18-000.html', 'read-write')",
        "INSERT INTO gpkg_contents (table_name, data_type, identifier) VALUES \
         ('states_notes', 'attributes', 'states_notes')",
    ] {
        dataset
            .execute_sql(sql, None, gdal::vector::sql::Dialect::DEFAULT)
            .unwrap();
    }
    dataset.close().unwrap();
}

#[test]
fn overwrite_replaces_only_the_named_layer_of_a_geopackage() {
    let scratch = Scratch::new("one-layer");
    let (_, src) = source(&scratch);
    let gpkg = scratch.path("work.gpkg");
    multi_layer_geopackage(&gpkg);
    let kept = everything_but_grid(&gpkg);

    // Added, then replaced with other ids: every other layer, style, metadata and relation stays.
    assert_success(&snakegrid([
        "-q",
        "-update",
        "-id",
        "id",
        "-nln",
        "grid",
        p(&gpkg),
        p(&src),
    ]));
    assert_same(&everything_but_grid(&gpkg), &kept, "-update");
    let out = snakegrid([
        "-overwrite",
        "-id",
        "abbr",
        "-nln",
        "grid",
        p(&gpkg),
        p(&src),
    ]);
    assert_success(&out);
    assert!(
        stdout(&out).contains("(layer grid, GPKG)"),
        "{}",
        stdout(&out)
    );
    assert_same(&everything_but_grid(&gpkg), &kept, "-overwrite");
    let dataset = Dataset::open(&gpkg).unwrap();
    let layers: Vec<String> = dataset.layers().map(|l| l.name()).collect();
    for name in ["states", "nc", "notes", "grid"] {
        assert!(layers.iter().any(|l| l == name), "{name} in {layers:?}");
    }
    let mut grid = dataset.layer_by_name("grid").unwrap();
    let abbr = grid.defn().field_index("abbr").unwrap();
    let ids: Vec<String> = grid
        .features()
        .map(|f| f.field_as_string(abbr).unwrap().unwrap())
        .collect();
    assert_eq!(ids.len(), 49);
    assert!(ids.contains(&"CA".to_owned()));
    // The style the user kept for "grid" stays too: ogr2ogr does the same.
    assert_eq!(
        rows(
            &dataset,
            "SELECT styleName FROM layer_styles WHERE f_table_name = 'grid'"
        ),
        [["grid"]]
    );
    assert!(staging_left(&scratch.path("")).is_empty());
}

#[test]
fn overwrite_never_replaces_a_file_that_holds_other_layers() {
    let scratch = Scratch::new("other-layers");
    let (_, src) = source(&scratch);
    let gpkg = scratch.path("work.gpkg");
    multi_layer_geopackage(&gpkg);
    let before = std::fs::read(&gpkg).unwrap();
    let out = snakegrid([
        "-q",
        "-overwrite",
        "-f",
        "GeoJSON",
        "-id",
        "id",
        p(&gpkg),
        p(&src),
    ]);
    assert_fails(&out, 1, "is a GPKG dataset that holds layer \"states\"");
    assert!(
        stderr(&out).contains("which -overwrite would lose"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read(&gpkg).unwrap(), before);
}

#[test]
fn overwrite_through_a_symbolic_link_replaces_the_file_it_leads_to_and_keeps_the_link() {
    let scratch = Scratch::new("linked-destination");
    let (_, src) = source(&scratch);
    let folder = scratch.path("versions");
    std::fs::create_dir_all(&folder).unwrap();
    let target = folder.join("grid-v1.gpkg");
    std::fs::write(&target, b"old").unwrap();
    let link = scratch.path("grid.gpkg");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let report = scratch.path("report.json");
    let report_target = folder.join("report-v1.json");
    std::fs::write(&report_target, b"old").unwrap();
    std::os::unix::fs::symlink(&report_target, &report).unwrap();
    assert_success(&snakegrid([
        "-q",
        "-overwrite",
        "-id",
        "id",
        "-json",
        p(&report),
        p(&link),
        p(&src),
    ]));
    // The links are links still, to the same files, which now hold the run's outputs (as
    // ogr2ogr writes through a link).
    for (link, target) in [(&link, &target), (&report, &report_target)] {
        let metadata = std::fs::symlink_metadata(link).unwrap();
        assert!(metadata.file_type().is_symlink(), "{link:?} was replaced");
        assert_eq!(&std::fs::read_link(link).unwrap(), target);
    }
    let written = Dataset::open(&target).unwrap();
    assert_eq!(written.layer(0).unwrap().feature_count(), 49);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&report_target).unwrap()).unwrap();
    assert_eq!(json["regions"].as_array().unwrap().len(), 49);
}

// ---------------------------------------------------------------------------------------------
// Interruptions.

#[test]
fn a_signal_stops_the_run_removes_its_staging_and_ends_the_process_by_it() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let scratch = Scratch::new("signals");
    // Some 20 s of work, so that every signal comes while the run is under way.
    let src = scratch.input("us_counties");
    let dst = scratch.path("grid.gpkg");
    std::fs::write(&dst, b"precious").unwrap();
    for (signal, name) in [(SIGINT, "INT"), (SIGTERM, "TERM"), (SIGHUP, "HUP")] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_snakegrid"))
            .args(["-q", "-overwrite", "-id", "id", p(&dst), p(&src)])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The run has started writing beside the destination once its staging folder is there.
        signal_once_started(
            &mut child,
            || !staging_left(&scratch.path("")).is_empty(),
            name,
        );
        let out = child.wait_with_output().unwrap();
        // Ended by the signal itself, so a shell sees 128 + its number (130, 143, 129).
        assert_eq!(
            out.status.signal(),
            Some(signal),
            "SIG{name}: {:?}",
            out.status
        );
        assert_eq!(
            String::from_utf8_lossy(&out.stderr),
            format!("snakegrid: interrupted by SIG{name}; nothing was written\n")
        );
        assert_eq!(
            scratch.listing(),
            ["grid.gpkg", "us_counties.gpkg"],
            "SIG{name}"
        );
        assert_eq!(std::fs::read(&dst).unwrap(), b"precious", "SIG{name}");
    }
}

/// Waits until `started` holds (the run ending first fails the test), then sends `child` the
/// signal `name` (INT, TERM, HUP) with the shell's own kill, which every system has.
fn signal_once_started(child: &mut Child, started: impl Fn() -> bool, name: &str) {
    while !started() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the run ended ({status}) before its staging folder appeared");
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let kill = Command::new("sh")
        .args(["-c", &format!("kill -s {name} {}", child.id())])
        .status()
        .unwrap();
    assert!(kill.success());
}

#[test]
fn a_signal_sends_nothing_to_standard_output_and_leaves_no_temporary_folder() {
    let scratch = Scratch::new("signal-stdout");
    let src = scratch.input("us_counties");
    let tmp = scratch.path("tmp");
    std::fs::create_dir(&tmp).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_snakegrid"))
        .env("TMPDIR", &tmp)
        .args(["-q", "-f", "GeoJSON", "-id", "id", "/vsistdout/", p(&src)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The run is under way once its staging folder is in its temporary folder.
    let started = || {
        std::fs::read_dir(&tmp)
            .unwrap()
            .any(|folder| !staging_left(&folder.unwrap().path()).is_empty())
    };
    signal_once_started(&mut child, started, "INT");
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.signal(), Some(signal_hook::consts::SIGINT));
    assert!(out.stdout.is_empty(), "{} bytes sent", out.stdout.len());
    assert_eq!(std::fs::read_dir(&tmp).unwrap().count(), 0);
}

#[test]
fn a_staging_folder_a_killed_run_left_is_removed_with_a_note() {
    let scratch = Scratch::new("stale");
    let (_, src) = source(&scratch);
    let stale = scratch.path(".grid.gpkg.snakegrid-K1lled.tmp");
    let recent = scratch.path(".grid.gpkg.snakegrid-Y0ung0.tmp");
    for dir in [&stale, &recent] {
        std::fs::create_dir(dir).unwrap();
        std::fs::write(dir.join("grid.gpkg"), b"partial").unwrap();
    }
    let eleven_minutes_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(660);
    std::fs::File::open(&stale)
        .unwrap()
        .set_modified(eleven_minutes_ago)
        .unwrap();
    let out = snakegrid(["-id", "id", p(&scratch.path("grid.gpkg")), p(&src)]);
    assert_success(&out);
    assert!(
        stdout(&out).contains(&format!(
            "note: removed the staging folder {:?}, left by a run that was interrupted",
            stale.display()
        )),
        "{}",
        stdout(&out)
    );
    assert!(!stale.exists());
    assert!(
        recent.exists(),
        "a recent folder may belong to a run under way"
    );
}

// ---------------------------------------------------------------------------------------------
// Refused before the run: what the output could not store as it is.

/// A refusal that came before any work: the error line alone, not even the progress line.
fn assert_refused_up_front(out: &std::process::Output, needle: &str) {
    assert_fails(out, 1, needle);
    assert!(
        stderr(out).starts_with("snakegrid: ERROR: "),
        "refused before the run, so no progress: {}",
        stderr(out)
    );
}

#[test]
fn formats_that_cannot_store_the_grid_are_refused_before_any_feature_is_read() {
    let scratch = Scratch::new("formats");
    // Reading the features of this layer would fail ("the geometry is null"), so a refusal
    // that names the format came first.
    let bad = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/bad/null_geometry.geojson"
    );
    let cases = [
        (
            "Memory",
            "grid.mem",
            "format \"Memory\" does not write files",
        ),
        (
            "XLSX",
            "grid.xlsx",
            "format \"XLSX\" cannot store geometries",
        ),
        ("ODS", "grid.ods", "format \"ODS\" cannot store geometries"),
    ];
    for (format, name, message) in cases {
        let dst = scratch.path(name);
        let out = snakegrid(["-f", format, "-id", "code", p(&dst), bad]);
        assert_refused_up_front(&out, message);
        assert!(
            scratch.listing().is_empty(),
            "{format}: {:?}",
            scratch.listing()
        );
    }
}

#[test]
fn csv_output_holds_the_cells_as_wkt() {
    let scratch = Scratch::new("csv");
    let (_, src) = source(&scratch);
    let csv = scratch.path("grid.csv");
    let out = snakegrid(["-id", "id", p(&csv), p(&src)]);
    assert_success(&out);
    assert!(
        stdout(&out).contains("(layer grid, CSV)"),
        "{}",
        stdout(&out)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with("WKT,id,name,abbr,grid_col,grid_row,"),
        "{text:.80}"
    );
    let dataset = Dataset::open(&csv).unwrap();
    let mut layer = dataset.layer(0).unwrap();
    let polygons = layer
        .features()
        .filter(|f| f.geometry().is_some_and(|g| g.geometry_name() == "POLYGON"))
        .count();
    assert_eq!(polygons, 49);
}

#[test]
fn a_file_geodatabase_and_an_sql_dump_are_written() {
    let scratch = Scratch::new("gdb-sql");
    let (_, src) = source(&scratch);
    let gdb = scratch.path("grid.gdb");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-f",
        "OpenFileGDB",
        p(&gdb),
        p(&src),
    ]));
    let dataset = Dataset::open(&gdb).unwrap();
    assert_eq!(dataset.layer(0).unwrap().feature_count(), 49);
    // GDAL writes SQL dumps but cannot read them: written, with a note that nothing was checked.
    let sql = scratch.path("grid.sql");
    let out = snakegrid(["-id", "id", p(&sql), p(&src)]);
    assert_success(&out);
    assert!(
        stdout(&out).contains("note: GDAL cannot read the PGDUMP format, so what it stored"),
        "{}",
        stdout(&out)
    );
    let dump = std::fs::read_to_string(&sql).unwrap();
    assert!(
        dump.contains("CREATE TABLE") && dump.contains("grid_col"),
        "{dump:.200}"
    );
    assert_eq!(
        dump.matches("INSERT INTO").count(),
        49,
        "one row per region"
    );
}

#[test]
fn ids_a_shapefile_would_change_are_refused_before_the_layout() {
    let scratch = Scratch::new("dbf-ids");
    let long = "x".repeat(300);
    let cases = [
        (vec!["a", "a  "], "feature a  : the ESRI Shapefile output drops trailing spaces, so the id would be stored as \"a\""),
        (vec![long.as_str()], "keeps only the first 254 of its 300 bytes"),
        (vec!["北京", "上海"], "cannot encode some of its characters, so the id would be stored as \"??\""),
    ];
    for (k, (ids, message)) in cases.iter().enumerate() {
        let src = scratch.path(&format!("ids{k}.geojson"));
        ids_layer(&src, ids);
        let shp = scratch.path(&format!("ids{k}.shp"));
        let out = snakegrid(["-id", "id", p(&shp), p(&src)]);
        assert_refused_up_front(&out, message);
        assert!(!shp.exists());
        // Formats that keep any text take them as they are, whatever order they store the
        // features in (FlatGeobuf sorts them along its spatial index).
        for extension in ["geojson", "fgb"] {
            let other = scratch.path(&format!("ids{k}.out.{extension}"));
            assert_success(&snakegrid(["-q", "-id", "id", p(&other), p(&src)]));
        }
    }
    // A DBF in UTF-8 holds any character.
    let shp = scratch.path("utf8.shp");
    let out = snakegrid([
        "-q",
        "-id",
        "id",
        "-lco",
        "ENCODING=UTF-8",
        p(&shp),
        p(&scratch.path("ids2.geojson")),
    ]);
    assert_success(&out);
    let dataset = Dataset::open(&shp).unwrap();
    let mut layer = dataset.layer(0).unwrap();
    let ids: Vec<String> = layer
        .features()
        .map(|f| f.field_as_string(0).unwrap().unwrap())
        .collect();
    assert_eq!(ids[..2], ["北京", "上海"]);
}

#[test]
fn numeric_ids_survive_a_shapefile_that_writes_them_with_decimals() {
    let scratch = Scratch::new("dbf-numbers");
    let src = scratch.path("reals.geojson");
    // Reals, one of them with a fraction: the DBF writes 15 decimals ("1.000000000000000").
    let rows: Vec<String> = (0..8)
        .map(|k| format!(r#""id":{}"#, k as f64 + if k == 7 { 0.5 } else { 1.0 }))
        .collect();
    squares(&src, &rows);
    let shp = scratch.path("reals.shp");
    assert_success(&snakegrid(["-q", "-id", "id", p(&shp), p(&src)]));
    let dataset = Dataset::open(&shp).unwrap();
    let mut layer = dataset.layer(0).unwrap();
    let mut ids: Vec<f64> = (layer.features())
        .map(|f| f.field_as_double(0).unwrap().unwrap())
        .collect();
    ids.sort_by(f64::total_cmp);
    assert_eq!(ids, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 7.5]);
}

#[test]
fn computed_fields_keep_their_names_and_colliding_source_fields_are_renamed() {
    let scratch = Scratch::new("collisions");
    let src = scratch.path("pins.geojson");
    let rows: Vec<String> = (0..8)
        .map(|k| {
            format!(r#""id":"r{k}","orient_error":"text {k}","grid_col":"pin {k}","GRID_ROW":{k}"#)
        })
        .collect();
    squares(&src, &rows);
    let report = scratch.path("r.json");
    for (name, renamed) in [
        ("grid.shp", ["src_orient", "src_grid_c", "src_GRID_R"]),
        (
            "grid.gpkg",
            ["orient_error", "src_grid_col", "src_GRID_ROW"],
        ),
    ] {
        let dst = scratch.path(name);
        let out = snakegrid([
            "-overwrite",
            "-id",
            "id",
            "-json",
            p(&report),
            p(&dst),
            p(&src),
        ]);
        assert_success(&out);
        let summary = stdout(&out);
        for (source, written) in [("grid_col", renamed[1]), ("GRID_ROW", renamed[2])] {
            assert!(
                summary.contains(&format!(
                    "note: the source field {source:?} is written as {written:?}"
                )),
                "{name}: {summary}"
            );
        }
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        let dataset = Dataset::open(&dst).unwrap();
        let mut layer = dataset.layer(0).unwrap();
        let names: Vec<String> = layer.defn().fields().map(|f| f.name()).collect();
        let mut expected = vec!["id".to_owned()];
        expected.extend(renamed.iter().map(|s| s.to_string()));
        expected.extend(
            [
                "grid_col",
                "grid_row",
                "grid_q",
                "grid_r",
                "cell_disp",
                "nbr_kept",
                "orient_err",
                "grid_group",
            ]
            .map(String::from),
        );
        assert_eq!(names, expected, "{name}");
        for (feature, region) in layer.features().zip(json["regions"].as_array().unwrap()) {
            let text = |i: usize| feature.field_as_string(i).unwrap().unwrap();
            let k = &text(0)[1..];
            assert_eq!(
                text(1),
                format!("text {k}"),
                "{name}: the source's text is kept"
            );
            assert_eq!(text(2), format!("pin {k}"));
            assert_eq!(
                text(4),
                region["col"].to_string(),
                "{name}: grid_col is the column"
            );
            assert_eq!(text(5), region["row"].to_string());
            let error = feature.field_as_double(8).unwrap().unwrap();
            let computed = region["orientation_error"].as_f64().unwrap();
            assert!(
                (error - computed).abs() < 1e-6,
                "{name}: orient_err is computed"
            );
        }
    }
}

#[test]
fn s_srs_lco_and_dsco_work_as_in_ogr2ogr() {
    let scratch = Scratch::new("creation-options");
    let src = scratch.path("squares.geojson");
    ids_layer(&src, &[]);
    // -s_srs replaces the source's CRS (EPSG:3857) without moving a coordinate.
    let plain = scratch.path("plain.gpkg");
    let assigned = scratch.path("assigned.gpkg");
    assert_success(&snakegrid(["-q", "-id", "id", p(&plain), p(&src)]));
    let out = snakegrid(["-id", "id", "-s_srs", "EPSG:32633", p(&assigned), p(&src)]);
    assert_success(&out);
    assert!(
        stdout(&out).contains("note: the source is taken to be in EPSG:32633"),
        "{}",
        stdout(&out)
    );
    let first_cell = |path: &Path| {
        let dataset = Dataset::open(path).unwrap();
        let mut layer = dataset.layer(0).unwrap();
        let srs = layer.spatial_ref().unwrap().auth_code().unwrap();
        let wkt = layer
            .features()
            .next()
            .unwrap()
            .geometry()
            .unwrap()
            .wkt()
            .unwrap();
        (srs, wkt)
    };
    let (plain_srs, plain_cell) = first_cell(&plain);
    let (assigned_srs, assigned_cell) = first_cell(&assigned);
    assert_eq!((plain_srs, assigned_srs), (3857, 32633));
    assert_eq!(plain_cell, assigned_cell);

    // -lco and -dsco reach the driver.
    let dst = scratch.path("options.gpkg");
    assert_success(&snakegrid([
        "-q",
        "-id",
        "id",
        "-lco",
        "FID=cell_id",
        "-lco",
        "SPATIAL_INDEX=NO",
        "-dsco",
        "VERSION=1.2",
        p(&dst),
        p(&src),
    ]));
    let dataset = Dataset::open(&dst).unwrap();
    assert_eq!(
        rows(&dataset, "SELECT count(cell_id) FROM squares"),
        [["8"]]
    );
    assert_eq!(rows(&dataset, "PRAGMA user_version"), [["10200"]]);
    assert!(rows(
        &dataset,
        "SELECT * FROM gpkg_extensions WHERE extension_name = 'gpkg_rtree_index'"
    )
    .is_empty());
    // Refused up front: not NAME=VALUE, or a value the driver rejects.
    let out = snakegrid([
        "-q",
        "-id",
        "id",
        "-lco",
        "NOEQUALS",
        p(&scratch.path("x.gpkg")),
        p(&src),
    ]);
    assert_refused_up_front(
        &out,
        "-lco \"NOEQUALS\": a creation option is written NAME=VALUE",
    );
    assert!(!scratch.path("x.gpkg").exists());
    // As ogr2ogr, GDAL's word on an option it ignores is passed on, once.
    let out = snakegrid([
        "-id",
        "id",
        "-lco",
        "NO_SUCH=1",
        p(&scratch.path("y.gpkg")),
        p(&src),
    ]);
    assert_success(&out);
    let note = format!(
        "note: dataset {} does not support layer creation option NO_SUCH\n",
        p(&scratch.path("y.gpkg"))
    );
    assert_eq!(stdout(&out).matches(&note).count(), 1, "{}", stdout(&out));
}

#[test]
fn the_svg_is_xml_with_one_label_size_and_labels_that_fit() {
    let scratch = Scratch::new("svg-labels");
    let src = scratch.path("labels.geojson");
    let names = [
        "bell \u{7} ring",
        "United States of America",
        "Kazakhstan",
        "AB",
        "<&>",
        "Tab\there",
        "x",
        "Central African Rep.",
    ];
    let rows: Vec<String> = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            format!(
                r#""id":"r{k}","name":{}"#,
                serde_json::Value::String(name.to_string())
            )
        })
        .collect();
    squares(&src, &rows);
    let world = scratch.input("world_countries");
    for (input, id) in [(&src, "id"), (&world, "id")] {
        let picture = scratch.path("map.svg");
        assert_success(&snakegrid([
            "-q",
            "-overwrite",
            "-id",
            id,
            "-label",
            "name",
            "-svg",
            p(&picture),
            p(&scratch.path("grid.gpkg")),
            p(input),
        ]));
        let text = std::fs::read_to_string(&picture).unwrap();
        let svg = roxmltree::Document::parse(&text).expect("the picture is well-formed XML");
        // Cell labels: the texts after the source map's outlines (the titles come before).
        let labels: Vec<roxmltree::Node> = svg
            .descendants()
            .skip_while(|n| !n.has_tag_name("path"))
            .filter(|n| n.has_tag_name("text"))
            .collect();
        assert!(labels.len() >= 8);
        let sizes: std::collections::BTreeSet<&str> = labels
            .iter()
            .map(|n| n.attribute("font-size").unwrap())
            .collect();
        assert_eq!(sizes.len(), 1, "one label size: {sizes:?}");
        for label in &labels {
            // The cell before the label: its polygon's width.
            let xs: Vec<f64> = (label.prev_sibling_element().unwrap())
                .attribute("points")
                .unwrap()
                .split(' ')
                .map(|p| p.split(',').next().unwrap().parse().unwrap())
                .collect();
            let side = xs.iter().copied().fold(f64::MIN, f64::max)
                - xs.iter().copied().fold(f64::MAX, f64::min);
            let font: f64 = label.attribute("font-size").unwrap().parse().unwrap();
            let chars = label.text().unwrap_or("").chars().count() as f64;
            assert!(
                chars * 0.6 * font <= 0.9 * side + 0.1,
                "{:?} fits its cell",
                label.text()
            );
        }
        if input == &src {
            let shown: Vec<&str> = labels.iter().filter_map(|n| n.text()).collect();
            assert_eq!(
                shown,
                ["bell…", "USA", "Kaza…", "AB", "<&>", "Tab…", "x", "CAR"]
            );
        }
    }
}
