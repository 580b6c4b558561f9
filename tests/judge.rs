//! The core's metrics are the shared judge's (`../shared/eval/gridmap_eval.py`, the reference
//! implementation of method.md §8): every figure of the JSON report equals the judge's reading
//! of the written layer within 1e-3, on every shared layer. Needs Python 3 with shapely, numpy,
//! pyogrio and pyproj (scripts/setup.sh installs them); `$SNAKEGRID_PYTHON` names another
//! interpreter.
// Writes layers and runs the judge on them: needs the GDAL layer.
#![cfg(feature = "gdal")]

use std::path::Path;
use std::process::Command;

mod common;
use common::cli::{assert_success, p, snakegrid};
use common::{shared_layer, Scratch};

/// The report's metric and the judge's name for it.
const PAIRS: [(&str, &str); 16] = [
    ("location", "location_cells"),
    ("location_p90", "location_p90_cells"),
    ("location_max", "location_max_cells"),
    ("location_raw", "location_raw"),
    ("adjacent", "adjacency_kept_queen"),
    ("adjacent_rook", "adjacency_kept"),
    ("false_neighbours", "false_neighbours_queen"),
    ("orientation", "orientation_deg"),
    ("misdirected", "misdirected_share"),
    ("shape", "shape_fd"),
    ("pieces", "components_cells"),
    ("source_pieces", "components_regions"),
    ("holes", "holes_cells"),
    ("source_holes", "holes_regions_cells"),
    ("notches", "gap_cells"),
    ("wrong_landmass", "wrong_landmass_share"),
];

fn judge(regions: &Path, grid: &Path) -> serde_json::Value {
    let python = std::env::var("SNAKEGRID_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/eval/gridmap_eval.py");
    let output = Command::new(&python)
        .arg(&script)
        .args(["--regions", p(regions), "--grid", p(grid), "--id", "id"])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {python}: {e}"));
    assert!(
        output.status.success(),
        "the judge failed (pip install shapely numpy pyogrio pyproj): {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

/// Lays `layer` out with `extra` options and compares the report with the judge.
fn agrees(layer: &str, extra: &[&str]) {
    // A folder per layer and options: the tests run side by side.
    let options: String = (extra.concat().chars())
        .filter(char::is_ascii_alphanumeric)
        .collect();
    let scratch = Scratch::new(&format!("judge-{layer}-{options}"));
    let (grid, report) = (scratch.path("grid.gpkg"), scratch.path("report.json"));
    let source = shared_layer(layer);
    let mut args = vec!["-q", "-id", "id", "-json", p(&report)];
    args.extend(extra);
    args.extend([p(&grid), p(&source)]);
    assert_success(&snakegrid(&args));
    let ours: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let theirs = judge(&source, &grid);
    assert_eq!(
        theirs["ok"], true,
        "{layer}: the judge finds the grid valid"
    );
    for (mine, judged) in PAIRS {
        let (a, b) = (
            ours["metrics"][mine].as_f64().unwrap(),
            theirs[judged].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() <= 1e-3 * b.abs().max(1.0),
            "{layer}: {mine} {a} against the judge's {judged} {b}"
        );
    }
}

#[test]
fn the_metrics_are_the_judges_on_every_shared_layer() {
    for layer in [
        "us_states",
        "nc_counties",
        "virginia_counties",
        "world_countries",
    ] {
        agrees(layer, &[]);
    }
    // One candidate keeps the large layer quick; the metrics are the same code.
    agrees("us_counties", &["-shifts", "0:0", "-noise_levels", ""]);
}

#[test]
fn hexagon_metrics_are_the_judges_on_every_shared_layer() {
    // The judge reads hexagons from the polygons alone: six edge neighbours (centres closer
    // than 1.5 √area), gaps from the six steps. Both orientations, every shared layer.
    for layer in [
        "us_states",
        "nc_counties",
        "virginia_counties",
        "world_countries",
    ] {
        agrees(layer, &["-cell", "hex"]);
        agrees(layer, &["-cell", "hex", "-hex_orientation", "flat"]);
    }
    agrees(
        "us_counties",
        &["-cell", "hex", "-shifts", "0:0", "-noise_levels", ""],
    );
}
