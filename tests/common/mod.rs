//! What the integration tests share (each test file says `mod common;`): where the shared
//! layers are, scratch folders, and what every grid map must be.
// Each test crate uses a different subset of these helpers.
#![allow(dead_code)]

#[cfg(feature = "gdal")]
pub mod cli;

use geo::{Area, Centroid};
use snakegrid::tiling::Tiling;
use snakegrid::{generate, GridMap, HexOrientation, Params, Region, RegionCell};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A layer of the team's shared data: `$SNAKEGRID_DATA`, else `../shared/data` beside the
/// repository (where CI puts it).
pub fn shared_layer(name: &str) -> PathBuf {
    let folder = std::env::var("SNAKEGRID_DATA")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data").to_owned());
    Path::new(&folder).join(format!("{name}.gpkg"))
}

/// A fresh folder under the system temp dir, named after the test binary and `test`, removed at
/// the end of the test.
pub struct Scratch(PathBuf);

impl Scratch {
    pub fn new(test: &str) -> Scratch {
        let binary = std::env::current_exe()
            .ok()
            .and_then(|exe| exe.file_stem().map(|s| s.to_string_lossy().into_owned()))
            .unwrap_or_default();
        let dir =
            std::env::temp_dir().join(format!("snakegrid-{binary}-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Copies a shared layer in; returns its path.
    pub fn input(&self, layer: &str) -> PathBuf {
        let to = self.path(&format!("{layer}.gpkg"));
        std::fs::copy(shared_layer(layer), &to).unwrap();
        to
    }

    /// The names in the folder, sorted (staging folders, which start with a dot, included).
    pub fn listing(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// One distinct cell per region, in the input order, all equal squares of the map's cell size on
/// one lattice (so distinct places cannot overlap), and finite metrics.
pub fn assert_valid_grid(regions: &[Region], map: &GridMap) {
    assert_eq!(map.cells.len(), regions.len());
    let ids: Vec<&str> = map.cells.iter().map(|c| c.id.as_str()).collect();
    let expected: Vec<&str> = regions.iter().map(|r| r.id.as_str()).collect();
    assert_eq!(ids, expected, "cells come in the input order");
    let places: HashSet<(i32, i32)> = map.cells.iter().map(|c| (c.col, c.row)).collect();
    assert_eq!(places.len(), regions.len(), "every region has its own cell");
    assert!(map.cell_size.is_finite() && map.cell_size > 0.0);
    let area = map.cell_size * map.cell_size;
    // A square closes with its 5th point, a hexagon with its 7th.
    let points = if map.tiling == Tiling::Square { 5 } else { 7 };
    for cell in &map.cells {
        assert!(
            (cell.cell.unsigned_area() - area).abs() < 1e-6 * area,
            "cell {} is a full cell",
            cell.id
        );
        assert_eq!(cell.cell.exterior().0.len(), points);
    }
    // Every cell's centre sits where its column and row say, relative to the first one's: the
    // cells are distinct positions of one lattice, so they do not overlap.
    let first = &map.cells[0];
    let centre = |c: &RegionCell| c.cell.centroid().unwrap().0;
    for cell in &map.cells {
        let d = (centre(cell) - centre(first)) / map.cell_size;
        let e = lattice_offset(map, cell) - lattice_offset(map, first);
        assert!(
            (d.x - e.x).abs() < 1e-6 && (d.y - e.y).abs() < 1e-6,
            "cell {} sits on the lattice",
            cell.id
        );
    }
    let m = map.metrics;
    for v in [
        m.location,
        m.location_raw,
        m.location_moved,
        m.adjacent,
        m.adjacent_rook,
        m.orientation,
        m.misdirected,
        m.shape,
    ] {
        assert!(v.is_finite());
    }
    for cell in &map.cells {
        let r = cell.metrics;
        assert!(
            [r.displacement, r.neighbours_kept, r.orientation_error]
                .iter()
                .all(|v| v.is_finite()),
            "region {} has finite metrics",
            cell.id
        );
    }
}

/// Where the centre of `cell` lies in cells (y up) from that of column 0, row 0, as its
/// column and row say: squares one cell apart; hexagons of area 1 with every other row (pointy)
/// or column (flat) offset half a cell as `map.shifted` says (method.md §10).
pub fn lattice_offset(map: &GridMap, cell: &RegionCell) -> geo::Coord<f64> {
    let (c, r) = (f64::from(cell.col), f64::from(cell.row));
    let side = (2.0 / (3.0 * 3f64.sqrt())).sqrt();
    let width = 3f64.sqrt() * side;
    let half = |i: i32| {
        if Some(i.rem_euclid(2)) == map.shifted {
            0.5
        } else {
            0.0
        }
    };
    match map.tiling {
        Tiling::Square => geo::Coord { x: c, y: -r },
        Tiling::Hex(HexOrientation::Pointy) => geo::Coord {
            x: width * (c + half(cell.row)),
            y: -1.5 * side * r,
        },
        Tiling::Hex(HexOrientation::Flat) => geo::Coord {
            x: 1.5 * side * c,
            y: -width * (r + half(cell.col)),
        },
    }
}

/// `regions` with every id and group renamed and the features in another order.
pub fn renamed_and_shuffled(regions: &[Region]) -> Vec<Region> {
    let mut other: Vec<Region> = regions
        .iter()
        .enumerate()
        // Renamed so that the sorted order of the ids is reversed, not merely shifted.
        .map(|(k, r)| Region {
            id: format!("z{:06}-{}", regions.len() - k, r.id),
            geometry: r.geometry.clone(),
            // Groups renamed too: reversed names reorder them ("AL" and "LA" swap).
            group: (r.group.as_ref()).map(|g| g.chars().rev().collect::<String>() + "-x"),
            pin: r.pin,
        })
        .collect();
    other.reverse();
    let third = other.len() / 3;
    other.rotate_left(third);
    other
}

/// Renaming every id and shuffling the features leaves every region on the same cell, with the
/// same square (within 1e-9 cell).
pub fn assert_ids_and_order_do_not_matter(regions: &[Region], params: &Params) {
    let run = |regions: &[Region]| generate(regions, params, &|_, _| true).expect("a grid map");
    let a = run(regions);
    let shuffled = renamed_and_shuffled(regions);
    let b = run(&shuffled);
    let renamed = |id: &str| id.split_once('-').map_or(id, |(_, old)| old).to_owned();
    let by_old_id: std::collections::HashMap<String, &RegionCell> =
        b.cells.iter().map(|c| (renamed(&c.id), c)).collect();
    for cell in &a.cells {
        let other = by_old_id[&cell.id];
        assert_eq!(
            (cell.col, cell.row),
            (other.col, other.row),
            "region {}",
            cell.id
        );
        for (p, q) in cell
            .cell
            .exterior()
            .coords()
            .zip(other.cell.exterior().coords())
        {
            let off = (p.x - q.x).abs().max((p.y - q.y).abs()) / a.cell_size;
            assert!(off < 1e-9, "region {}: corners {p:?} and {q:?}", cell.id);
        }
    }
    assert_eq!(a.metrics, b.metrics);
}
