//! What every grid map must be, shared by the integration tests (each test file that needs it
//! says `mod common;`).

use geo::Area;
use snakegrid::{GridMap, Region};
use std::collections::HashSet;

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
    for cell in &map.cells {
        assert!(
            (cell.cell.unsigned_area() - area).abs() < 1e-6 * area,
            "cell {} is a full square",
            cell.id
        );
        assert_eq!(cell.cell.exterior().0.len(), 5);
    }
    let first = &map.cells[0];
    let origin = first.cell.exterior().0[0];
    for cell in &map.cells {
        let corner = cell.cell.exterior().0[0];
        let dx = (corner.x - origin.x) / map.cell_size - f64::from(cell.col - first.col);
        let dy = (origin.y - corner.y) / map.cell_size - f64::from(cell.row - first.row);
        assert!(
            dx.abs() < 1e-6 && dy.abs() < 1e-6,
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
