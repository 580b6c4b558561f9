//! Pinned cells and re-layout after hand edits (issue 18, method.md §10), on the shared
//! us_states layer: the pins read from fields of the layer, the layout measured from the cells
//! it gives, the refusals by name.
// Reads the shared layers through GDAL.
#![cfg(feature = "gdal")]

use geo::{Area, Centroid, Coord, MapCoords};
use snakegrid::io::{read_regions, Job};
use snakegrid::pins::{from_edits, EditedCell};
use snakegrid::tiling::Tiling;
use snakegrid::{generate, Error, GridMap, Params, Region};
use std::collections::HashMap;

mod common;

/// The NYT's hand-made us_states layout's cells for five states, columns from the west and
/// rows from the top, as issue 18 gives them.
const NYT: [(&str, (i32, i32)); 5] = [
    ("WA", (1, 2)),
    ("FL", (7, 7)),
    ("ME", (11, 0)),
    ("CA", (0, 4)),
    ("TX", (3, 6)),
];

fn states() -> Vec<Region> {
    let job = Job {
        src: common::shared_layer("us_states")
            .to_string_lossy()
            .into_owned(),
        id_field: Some("abbr".into()),
        ..Job::default()
    };
    read_regions(&job).expect("the shared layer reads").regions
}

fn pinned(mut regions: Vec<Region>, pins: &[(&str, (i32, i32))]) -> Vec<Region> {
    let pins: HashMap<&str, (i32, i32)> = pins.iter().copied().collect();
    for region in &mut regions {
        region.pin = pins.get(region.id.as_str()).copied();
    }
    regions
}

fn run(regions: &[Region], params: &Params) -> Result<GridMap, Error> {
    generate(regions, params, &|_, _| true)
}

fn cell_of(map: &GridMap, id: &str) -> (i32, i32) {
    let cell = map.cells.iter().find(|c| c.id == id).expect("a cell");
    (cell.col, cell.row)
}

/// Edge-connected pieces of the layout's cells, counted from their columns and rows.
fn pieces(map: &GridMap) -> usize {
    let cells: Vec<(i32, i32)> = map.cells.iter().map(|c| (c.col, c.row)).collect();
    let mut seen = vec![false; cells.len()];
    let mut count = 0;
    for start in 0..cells.len() {
        if seen[start] {
            continue;
        }
        count += 1;
        let mut stack = vec![start];
        seen[start] = true;
        while let Some(k) = stack.pop() {
            for (j, &(c, r)) in cells.iter().enumerate() {
                let (dc, dr) = (c - cells[k].0, r - cells[k].1);
                if !seen[j] && dc.abs() + dr.abs() == 1 {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
    }
    count
}

#[test]
fn the_nyt_pins_hold_and_the_layout_stays_whole() {
    let regions = pinned(states(), &NYT);
    let map = run(&regions, &Params::default()).expect("a grid map");
    common::assert_valid_grid(&regions, &map);
    for (id, pin) in NYT {
        assert_eq!(cell_of(&map, id), pin, "{id} keeps its pin");
    }
    // Issue 18's bars: C_adjacent ≥ 0.88 (the NYT's own layout has 0.897) and one piece.
    assert!(map.metrics.adjacent >= 0.88, "{:?}", map.metrics);
    assert_eq!(pieces(&map), 1);
    assert!(map.notes.iter().any(|n| n.contains("5 pinned regions")));
}

#[test]
fn hexagon_pins_hold_in_the_output_convention() {
    let regions = pinned(states(), &NYT);
    let mut params = Params::default();
    params.set("cell", "hex").unwrap();
    let map = run(&regions, &params).expect("a grid map");
    common::assert_valid_grid(&regions, &map);
    for (id, pin) in NYT {
        assert_eq!(cell_of(&map, id), pin, "{id} keeps its pin");
    }
    // Pinned layers number their offset rows as snakegrid's convention has them.
    assert_eq!(map.shifted, Some(1));
}

#[test]
fn two_regions_on_one_cell_are_refused_naming_both() {
    let regions = pinned(states(), &[("WA", (1, 2)), ("OR", (1, 2))]);
    let error = run(&regions, &Params::default()).unwrap_err().to_string();
    // WA comes before OR in the layer.
    assert!(
        error.contains("feature OR")
            && error.contains("feature WA")
            && error.contains("column 1, row 2"),
        "{error}"
    );
}

#[test]
fn pins_that_split_a_group_or_touch_across_a_gap_are_refused() {
    let mut regions = pinned(states(), &[("WA", (0, 0)), ("OR", (9, 0)), ("ID", (1, 0))]);
    for region in &mut regions {
        region.group = Some(if ["WA", "OR"].contains(&region.id.as_str()) {
            "northwest".into()
        } else {
            "rest".into()
        });
    }
    // WA and OR 9 cells apart in a block of 2 cells.
    let error = run(&regions, &Params::default()).unwrap_err().to_string();
    assert!(error.contains("split the group's block"), "{error}");
    for region in &mut regions {
        if region.id == "OR" {
            region.pin = Some((0, 1));
        }
    }
    assert!(run(&regions, &Params::default()).is_ok());
    // ID (another group) beside WA: refused with a gap only.
    let mut gap = Params::default();
    gap.set("group_gap", "1").unwrap();
    let error = run(&regions, &gap).unwrap_err().to_string();
    assert!(
        error.contains("feature ID") && error.contains("group_gap"),
        "{error}"
    );
}

#[test]
fn a_gap_holds_around_pins_among_another_groups_cells() {
    // Groups of scattered states (alphabetical runs of eight: a user's arbitrary grouping) and
    // pins that put a state among another group's cells. A pin cannot yield the moat, so the
    // cells around it do; before, the split dropped a pin apart from its block's main piece
    // and let other groups grow up to it.
    let pins = [("CA", (0, 3)), ("NY", (9, 1)), ("TX", (4, 7))];
    let mut regions = pinned(states(), &pins);
    let mut abbrs: Vec<String> = regions.iter().map(|r| r.id.clone()).collect();
    abbrs.sort();
    for region in &mut regions {
        let rank = abbrs.iter().position(|a| *a == region.id).unwrap();
        region.group = Some((rank / 8).to_string());
    }
    let group: HashMap<String, String> = (regions.iter())
        .map(|r| (r.id.clone(), r.group.clone().unwrap()))
        .collect();
    for (cell, tiling) in [
        ("square", Tiling::Square),
        ("hex", Tiling::Hex(snakegrid::HexOrientation::Pointy)),
    ] {
        let mut params = Params::default();
        params.set("group_gap", "1").unwrap();
        params.set("cell", cell).unwrap();
        let map = run(&regions, &params).unwrap();
        for a in &map.cells {
            for b in &map.cells {
                assert!(
                    group[&a.id] == group[&b.id] || !tiling.touching((a.q, a.r), (b.q, b.r)),
                    "{cell}: {} and {} touch across the gap",
                    a.id,
                    b.id
                );
            }
        }
        for (id, pin) in pins {
            assert_eq!(cell_of(&map, id), pin, "{cell}");
        }
    }
}

/// The cells of `map` as an edited grid layer would give them, with `moves` (id → offset in
/// cells, y up) applied to the polygons.
fn edited(map: &GridMap, moves: &[(&str, (f64, f64))], keep: &[&str]) -> Vec<EditedCell> {
    let moves: HashMap<&str, (f64, f64)> = moves.iter().copied().collect();
    map.cells
        .iter()
        .map(|cell| {
            let (dx, dy) = moves.get(cell.id.as_str()).copied().unwrap_or((0.0, 0.0));
            let polygon = cell.cell.map_coords(|c| Coord {
                x: c.x + dx * map.cell_size,
                y: c.y + dy * map.cell_size,
            });
            EditedCell {
                id: cell.id.clone(),
                position: (cell.q, cell.r),
                centre: polygon.centroid().unwrap().0,
                area: polygon.unsigned_area(),
                keep: keep.contains(&cell.id.as_str()),
            }
        })
        .collect()
}

#[test]
fn a_relayout_keeps_the_moved_and_the_kept_cells() {
    let regions = states();
    let params = Params::default();
    let first = run(&regions, &params).expect("a grid map");
    // By hand: Texas two cells down, Maine one up and one right, each onto a free position
    // beyond the layout's edge; Nevada nudged by a fifth of a cell (not moved); Ohio kept.
    let moves = [("TX", (0.0, -2.0)), ("ME", (1.0, 1.0)), ("NV", (0.2, 0.0))];
    let cells = edited(&first, &moves, &["OH"]);
    let pins = from_edits(&cells, Tiling::Square).expect("pins");
    let pinned: Vec<(&str, (i32, i32), bool)> = (cells.iter().zip(&pins))
        .filter_map(|(c, p)| p.map(|p| (c.id.as_str(), p.pin, p.moved)))
        .collect();
    let (tx, me, oh) = (
        cell_of(&first, "TX"),
        cell_of(&first, "ME"),
        cell_of(&first, "OH"),
    );
    let mut expected = vec![
        ("TX", (tx.0, tx.1 + 2), true),
        ("ME", (me.0 + 1, me.1 - 1), true),
        ("OH", oh, false),
    ];
    expected.sort_by_key(|e| first.cells.iter().position(|c| c.id == e.0));
    assert_eq!(pinned, expected);

    let by_id: HashMap<&str, (i32, i32)> = pinned.iter().map(|&(id, p, _)| (id, p)).collect();
    let again: Vec<Region> = (regions.iter().cloned())
        .map(|mut r| {
            r.pin = by_id.get(r.id.as_str()).copied();
            r
        })
        .collect();
    let map = run(&again, &params).expect("a re-layout");
    common::assert_valid_grid(&again, &map);
    for (id, pin, _) in &pinned {
        assert_eq!(cell_of(&map, id), *pin, "{id} stays where the user put it");
    }
}

#[test]
fn two_edited_cells_on_one_position_are_refused_naming_both() {
    let map = run(&states(), &Params::default()).expect("a grid map");
    let (tx, ok) = (cell_of(&map, "TX"), cell_of(&map, "OK"));
    // Texas dragged onto Oklahoma's cell.
    let offset = (f64::from(ok.0 - tx.0), f64::from(tx.1 - ok.1));
    let error = from_edits(&edited(&map, &[("TX", offset)], &[]), Tiling::Square)
        .unwrap_err()
        .to_string();
    assert!(error.contains("TX") && error.contains("OK"), "{error}");
}

#[test]
fn pins_spread_beyond_any_layout_are_refused() {
    // 49 regions span at most 2 × 49 + 2 = 100 columns by the rule; Maine 1,000 columns east.
    let regions = pinned(states(), &[("WA", (0, 0)), ("ME", (1000, 0))]);
    let error = run(&regions, &Params::default()).unwrap_err().to_string();
    assert!(
        error.contains("feature ME") && error.contains("1000 cells"),
        "{error}"
    );
}
