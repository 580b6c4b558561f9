//! Nothing the user owns is lost: no option makes a run write to a file of the source, however
//! the paths are spelled, and memory follows the regions rather than the empty space between
//! them.
// Reads and writes datasets: needs the GDAL layer.
#![cfg(feature = "gdal")]

use std::path::{Path, PathBuf};

mod common;
use common::cli::{assert_fails, assert_success, p, snakegrid};
use common::Scratch;

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
