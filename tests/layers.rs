//! The method on the shared real layers: what issue 2 says must hold, asserted on computed
//! results. Reads through the same GDAL reader as the command line.
// Reads and writes datasets: needs the GDAL layer.
#![cfg(feature = "gdal")]

use geo::{Area, BooleanOps, Buffer, Contains, MultiPolygon, Point, Simplify, Validation};
use snakegrid::diagnostics::SnakeNetwork;
use snakegrid::io::{read_regions, Job};
use snakegrid::params::CellShape;
use snakegrid::{
    generate, score, GridMap, HexOrientation, LayoutMetrics, Params, Region, StopReason,
};

mod common;

fn load(name: &str) -> Vec<Region> {
    let job = Job {
        src: common::shared_layer(name).to_string_lossy().into_owned(),
        id_field: Some("id".into()),
        ..Job::default()
    };
    read_regions(&job).expect("the shared layer reads").regions
}

fn run(regions: &[Region], params: &Params) -> GridMap {
    generate(regions, params, &|_, _| true).expect("a grid map")
}

/// A valid grid map (see `common`) whose squares cover exactly their count of cells, and whose
/// outline keeps the map's shape.
fn assert_valid_grid(regions: &[Region], map: &GridMap) {
    common::assert_valid_grid(regions, map);
    let area = map.cell_size * map.cell_size;
    let union = map
        .cells
        .iter()
        .fold(MultiPolygon::new(vec![]), |u, c| u.union(&c.cell));
    assert!(
        (union.unsigned_area() - area * regions.len() as f64).abs()
            < 1e-6 * area * regions.len() as f64
    );
    let m = map.metrics;
    assert!((0.0..=1.0).contains(&m.adjacent) && (0.0..=1.0).contains(&m.shape) && m.shape > 0.5);
    assert!((0.0..=180.0).contains(&m.orientation));
}

#[test]
fn us_states_beats_tilemaps_and_the_snake_does_real_work() {
    let regions = load("us_states");
    let map = run(&regions, &Params::default());
    assert_valid_grid(&regions, &map);
    assert_eq!(map.adjacency.len(), 107, "rook pairs of the shared file");
    // McNeill and Hale's tilemaps reaches 0.879 and 26.7° on this file (method.md §11).
    assert!(
        map.metrics.adjacent >= 0.88,
        "C_adjacent {}",
        map.metrics.adjacent
    );
    assert!(
        map.metrics.orientation <= 25.0,
        "C_orientation {}",
        map.metrics.orientation
    );
    assert_ne!(map.snake.stop_reason, StopReason::InvalidStep);
    assert!(map.snake.steps >= 10, "{:?}", map.snake);
    assert!(
        map.snake.spread_after < 0.8 * map.snake.spread_before,
        "{:?}",
        map.snake
    );
    // 9 lattice shifts × (the noise-free run and 2 noise levels).
    assert_eq!(map.candidates.len(), 27);
    // Ranked by their defects (pieces, holes, regions nearer another landmass: none on this one
    // landmass) first, then by TOPSIS.
    let defects = |m: &snakegrid::LayoutMetrics| m.pieces + m.holes;
    assert!(map.candidates.windows(2).all(|w| {
        let (a, b) = (defects(&w[0].metrics), defects(&w[1].metrics));
        a < b || (a == b && w[0].score >= w[1].score)
    }));
    assert_eq!(map.candidates[0].metrics, map.metrics);
    // The New York Times' hand-made layout of these states is 1 piece with no hole
    // (method.md §8); so is ours.
    assert_eq!((map.metrics.pieces, map.metrics.holes), (1, 0));
}

#[test]
fn only_the_best_candidates_before_refinement_are_refined() {
    let regions = load("nc_counties");
    let plain = run(
        &regions,
        &Params {
            refine: false,
            ..Params::default()
        },
    );
    let refined = run(
        &regions,
        &Params {
            max_refined: Some(3),
            ..Params::default()
        },
    );
    assert_eq!(plain.candidates.len(), 27);
    // The refined candidates are the first three of the ranking without refinement (the
    // plain run's candidates are those layouts as they were before the refinement).
    let key = |c: &snakegrid::CandidateReport| (c.noise.to_bits(), c.shift.map(f64::to_bits));
    let mut best: Vec<_> = plain.candidates[..3].iter().map(key).collect();
    let mut chosen: Vec<_> = refined.candidates.iter().map(key).collect();
    best.sort_unstable();
    chosen.sort_unstable();
    assert_eq!(chosen, best);
    assert!(refined.notes.iter().any(|n| n.contains("best 3 of the 27")));
    // Refined, they keep more neighbours than before.
    let winner = refined.candidates[0].clone();
    let before = (plain.candidates.iter())
        .find(|c| key(c) == key(&winner))
        .expect("the winner was a plain candidate");
    assert!(winner.metrics.adjacent > before.metrics.adjacent);
}

/// The defaults with hexagonal cells.
fn hexagons(orientation: HexOrientation) -> Params {
    Params {
        cell: CellShape::Hex,
        hex_orientation: orientation,
        ..Params::default()
    }
}

#[test]
fn no_region_is_left_alone_far_from_home() {
    // Before the refinement kept its company rule, Washington DC (two neighbours) was sent 3.6
    // cells off beside Arkansas at us_states seeds 1, 2, 4 and 6, and Virginia's independent
    // cities (Covington, Emporia, Richmond: one or two neighbours) 4.2 to 5.4 cells at seeds 1,
    // 3, 6 and 9, each with none of its neighbours beside it (JSON reports, BENCHMARKS.md "Left
    // alone far from home"). refine_location_far (3 cells in the refinement's frame) is the
    // limit; half a cell more allows for the fit's frame, which the displacement is measured in.
    for (layer, seeds) in [
        ("us_states", [1, 2, 4, 6]),
        ("virginia_counties", [1, 3, 6, 9]),
    ] {
        let regions = load(layer);
        for seed in seeds {
            let map = run(
                &regions,
                &Params {
                    seed,
                    ..Params::default()
                },
            );
            for cell in &map.cells {
                let m = &cell.metrics;
                assert!(
                    m.neighbours_kept > 0.0 || m.displacement <= 3.5,
                    "{layer} seed {seed}: {} {:.2} cells from home, no neighbour beside it",
                    cell.id,
                    m.displacement
                );
            }
        }
    }
}

#[test]
fn us_states_and_nc_counties_in_hexagons_beat_the_other_tools() {
    // Issue 16's bars, from the shared judge's figures for the other hexagon layouts: us_states
    // R tilemaps 0.710 and 27.8°, carto-flow 0.776 and 30.9°, NPR's hand-made map 0.776 and
    // 29.0°; nc_counties tilemaps 0.779, carto-flow 0.784. For hexagons every neighbour shares
    // an edge, so C_adjacent and its rook share are one figure.
    for orientation in [HexOrientation::Pointy, HexOrientation::Flat] {
        let regions = load("us_states");
        let map = run(&regions, &hexagons(orientation));
        assert_valid_grid(&regions, &map);
        let m = map.metrics;
        assert_eq!(m.adjacent, m.adjacent_rook);
        assert!(
            m.adjacent >= 0.80,
            "{orientation:?}: C_adjacent {}",
            m.adjacent
        );
        assert!(m.orientation <= 25.0, "{orientation:?}: {}°", m.orientation);
        assert_eq!((m.pieces, m.holes), (1, 0), "{orientation:?}");
        let regions = load("nc_counties");
        let map = run(&regions, &hexagons(orientation));
        assert_valid_grid(&regions, &map);
        assert!(
            map.metrics.adjacent >= 0.80,
            "nc {orientation:?}: {}",
            map.metrics.adjacent
        );
    }
}

#[test]
fn hexagon_layouts_do_not_depend_on_ids_or_order_and_score_again_the_same() {
    for (name, orientation) in [
        ("us_states", HexOrientation::Pointy),
        ("virginia_counties", HexOrientation::Flat),
        ("world_countries", HexOrientation::Pointy),
    ] {
        let regions = load(name);
        let params = hexagons(orientation);
        common::assert_ids_and_order_do_not_matter(&regions, &params);
        // The metrics of a written hexagon layout, read back from its cells alone.
        let map = run(&regions, &params);
        let cells: Vec<geo::Polygon<f64>> = map.cells.iter().map(|c| c.cell.clone()).collect();
        let (metrics, _) = score(&regions, &cells).unwrap();
        assert!(
            (metrics.adjacent - map.metrics.adjacent).abs() < 1e-12,
            "{name}"
        );
        assert!(
            (metrics.orientation - map.metrics.orientation).abs() < 1e-9,
            "{name}"
        );
        assert_eq!(
            (metrics.pieces, metrics.holes, metrics.notches),
            (map.metrics.pieces, map.metrics.holes, map.metrics.notches),
            "{name}"
        );
    }
}

#[test]
fn the_plain_method_is_the_paper_and_refinement_lifts_it() {
    let regions = load("us_states");
    let refined = run(&regions, &Params::default());
    let plain = run(
        &regions,
        &Params {
            refine: false,
            ..Params::default()
        },
    );
    assert_valid_grid(&regions, &plain);
    assert!(
        plain.metrics.adjacent > 0.7,
        "plain C_adjacent {}",
        plain.metrics.adjacent
    );
    assert!(refined.metrics.adjacent > plain.metrics.adjacent);
    assert!(refined.metrics.orientation < plain.metrics.orientation);
}

#[test]
fn the_outline_stays_simple_and_holds_the_centroids_at_every_step() {
    let regions = load("us_states");
    let params = Params::default();
    let network = SnakeNetwork::of(&regions, &params).unwrap();
    let mut spreads = Vec::new();
    for steps in 1..=params.max_steps {
        let moved = network
            .run(&Params {
                max_steps: steps,
                ..params.clone()
            })
            .unwrap();
        assert_eq!(moved.report.steps, steps, "no step was refused");
        assert!(
            moved.outline.is_valid(),
            "the outline is not simple after {steps} steps: {:?}",
            moved.outline.check_validation()
        );
        assert!(
            moved
                .centroids
                .iter()
                .all(|&c| moved.outline.contains(&Point(c))),
            "a centroid left the outline after {steps} steps"
        );
        spreads.push(moved.report.spread_after);
    }
    assert!(spreads.last().unwrap() < &spreads[0]);
}

#[test]
fn nc_counties_snake_runs_to_a_real_stop() {
    let regions = load("nc_counties");
    let map = run(&regions, &Params::default());
    assert_valid_grid(&regions, &map);
    assert_eq!(map.adjacency.len(), 231);
    assert_ne!(map.snake.stop_reason, StopReason::InvalidStep);
    assert!(
        map.snake.spread_after < 0.8 * map.snake.spread_before,
        "{:?}",
        map.snake
    );
    assert!(
        map.metrics.adjacent >= 0.8,
        "C_adjacent {}",
        map.metrics.adjacent
    );
    // One landmass (the Outer Banks' parts are tiny), laid out in one piece without holes.
    assert_eq!((map.metrics.pieces, map.metrics.holes), (1, 0));
}

#[test]
fn virginia_with_enclaved_cities_gives_a_complete_map() {
    let regions = load("virginia_counties");
    let map = run(&regions, &Params::default());
    assert_valid_grid(&regions, &map);
    assert_eq!(map.adjacency.len(), 287);
    // An enclaved city has exactly one neighbour: its county (data README: Winchester city lies
    // in Frederick County).
    let index = |id: &str| regions.iter().position(|r| r.id == id).unwrap();
    let (winchester, frederick) = (index("51840"), index("51069"));
    let neighbours: Vec<usize> = map
        .adjacency
        .iter()
        .filter_map(|&(a, b)| match (a == winchester, b == winchester) {
            (true, _) => Some(b),
            (_, true) => Some(a),
            _ => None,
        })
        .collect();
    assert_eq!(neighbours, [frederick]);
}

#[test]
fn world_countries_with_islands_and_an_enclave_gives_a_complete_map() {
    let regions = load("world_countries");
    let map = run(&regions, &Params::default());
    assert_valid_grid(&regions, &map);
    assert_eq!(map.adjacency.len(), 313);
    let lesotho = regions.iter().position(|r| r.id == "426").unwrap();
    let south_africa = regions.iter().position(|r| r.id == "710").unwrap();
    assert!(map
        .adjacency
        .contains(&(lesotho.min(south_africa), lesotho.max(south_africa))));
    // The landmass budgets keep the continents' cells apart and the blocks settle where the
    // judge measures them from: no hole, no region nearer another landmass than its own (of the
    // 148 on the three large ones; taking the best cells over the whole map put 8-10 % there),
    // and location within issue 13's 1.5 cells (it was 2.39 then, 1.70 without settling).
    assert_eq!(map.metrics.holes, 0);
    assert_eq!(map.metrics.wrong_landmass, 0.0);
    assert!(map.metrics.location <= 1.5, "{}", map.metrics.location);
}

#[test]
fn us_counties_gives_a_complete_map() {
    let regions = load("us_counties");
    assert_eq!(regions.len(), 3107);
    // One candidate keeps the test quick; the full candidate set is the benchmark's.
    let params = Params {
        shifts: vec![[0.0, 0.0]],
        noise_levels: vec![],
        ..Params::default()
    };
    let map = run(&regions, &params);
    assert_valid_grid(&regions, &map);
    assert_eq!(map.adjacency.len(), 8707);
    // Washington's island counties, San Juan (53055, no rook neighbour: the data README) and
    // Island (53029), lie beside a Washington county's cell. Sent to their places under the fit
    // of the whole map, they sat in the layout's corner 15 cells from any (island_limit 1000, as
    // before `landmass::Anchors`): the crowded east bends the map far from that fit.
    let gap_to_washington = |map: &GridMap, island: &str| {
        let cell = |id: &str| {
            let c = map
                .cells
                .iter()
                .find(|c| c.id == id)
                .expect("the county's cell");
            (c.col, c.row)
        };
        let (col, row) = cell(island);
        (regions.iter())
            .filter(|r| r.id.starts_with("53") && !["53055", "53029"].contains(&r.id.as_str()))
            .map(|r| {
                let (c, w) = cell(&r.id);
                (c - col).abs().max((w - row).abs())
            })
            .min()
            .expect("Washington's mainland counties")
    };
    let apart = run(
        &regions,
        &Params {
            island_limit: 1000.0,
            ..params
        },
    );
    for island in ["53055", "53029"] {
        assert_eq!(gap_to_washington(&map, island), 1, "{island}");
        assert!(gap_to_washington(&apart, island) > 5, "{island}");
    }
}

#[test]
fn on_us_counties_the_refinement_keeps_more_neighbours_without_cutting_inlets() {
    // Issue 15: on us_counties the refinement improves adjacency and orientation over
    // -refine false; and a layer of uneven density keeps its outline: no more notches or holes
    // than the plain layout. With method.md §6b's squared distance cost everywhere
    // (refine_location_knee 1000), the West's counties, pulled towards their far places, left
    // inlets a cell wide: 34 notches against the plain layout's 15 (BENCHMARKS.md).
    let regions = load("us_counties");
    let one_candidate = Params {
        shifts: vec![[0.0, 0.0]],
        noise_levels: vec![],
        ..Params::default()
    };
    let refined = run(&regions, &one_candidate).metrics;
    let plain = run(
        &regions,
        &Params {
            refine: false,
            ..one_candidate
        },
    )
    .metrics;
    assert!(refined.adjacent > plain.adjacent, "{refined:?} {plain:?}");
    assert!(
        refined.orientation < plain.orientation,
        "{refined:?} {plain:?}"
    );
    assert!(refined.notches <= plain.notches, "{refined:?} {plain:?}");
    assert!(refined.holes <= plain.holes, "{refined:?} {plain:?}");
}

#[test]
fn renaming_ids_and_shuffling_features_moves_no_cell_on_any_shared_layer() {
    for name in [
        "us_states",
        "nc_counties",
        "virginia_counties",
        "world_countries",
    ] {
        common::assert_ids_and_order_do_not_matter(&load(name), &Params::default());
    }
    // One candidate keeps the large layer quick; the ordering is the same code path.
    let one_candidate = Params {
        shifts: vec![[0.0, 0.0]],
        noise_levels: vec![],
        ..Params::default()
    };
    common::assert_ids_and_order_do_not_matter(&load("us_counties"), &one_candidate);
}

#[test]
fn scoring_a_layout_again_gives_its_metrics() {
    let regions = load("us_states");
    let map = run(&regions, &Params::default());
    let cells: Vec<geo::Polygon<f64>> = map.cells.iter().map(|c| c.cell.clone()).collect();
    let (metrics, per_region) = score(&regions, &cells).unwrap();
    assert!((metrics.adjacent - map.metrics.adjacent).abs() < 1e-12);
    assert!((metrics.orientation - map.metrics.orientation).abs() < 1e-9);
    assert!((metrics.location - map.metrics.location).abs() < 1e-9);
    assert!((metrics.shape - map.metrics.shape).abs() < 1e-9);
    for (a, b) in per_region.iter().zip(&map.cells) {
        assert!((a.neighbours_kept - b.metrics.neighbours_kept).abs() < 1e-12);
    }
}

#[test]
fn the_number_of_threads_does_not_change_the_layout() {
    let regions = load("nc_counties");
    let on = |threads| {
        run(
            &regions,
            &Params {
                threads,
                ..Params::default()
            },
        )
    };
    let (one, three) = (on(1), on(3));
    for (a, b) in one.cells.iter().zip(&three.cells) {
        assert_eq!((a.id.as_str(), a.col, a.row), (b.id.as_str(), b.col, b.row));
        assert_eq!(a.cell, b.cell);
    }
    assert_eq!(one.metrics, three.metrics);
    assert_eq!(one.candidates, three.candidates);
}

/// `regions` with every edge cut into `pieces`, the new vertices on a small wiggle that depends
/// only on the edge (not its direction), so that both regions beside a shared edge get the same
/// vertices and adjacency is kept exactly: what scripts/make-test-layers.py's `densify` does.
fn densified(regions: &[Region], pieces: usize) -> Vec<Region> {
    use geo::{Coord, LineString, Polygon};
    let wiggled = |a: Coord<f64>, b: Coord<f64>| -> Vec<Coord<f64>> {
        let forward = (a.x, a.y) <= (b.x, b.y);
        let (p, q) = if forward { (a, b) } else { (b, a) };
        let d = q - p;
        let length = d.x.hypot(d.y);
        let normal = Coord {
            x: -d.y / length,
            y: d.x / length,
        };
        let mut points: Vec<Coord<f64>> = (1..pieces)
            .map(|k| {
                let t = k as f64 / pieces as f64;
                let w = 0.02
                    * length
                    * (std::f64::consts::PI * t).sin()
                    * (7.0 * std::f64::consts::PI * t).sin();
                p + d * t + normal * w
            })
            .collect();
        if !forward {
            points.reverse();
        }
        points
    };
    let ring = |r: &LineString<f64>| {
        let mut out = Vec::new();
        for line in r.lines() {
            out.push(line.start);
            if line.start != line.end {
                out.extend(wiggled(line.start, line.end));
            }
        }
        out.push(r.0[0]);
        LineString(out)
    };
    regions
        .iter()
        .map(|region| Region {
            id: region.id.clone(),
            geometry: MultiPolygon(
                (region.geometry.0.iter())
                    .map(|p| {
                        Polygon::new(ring(p.exterior()), p.interiors().iter().map(ring).collect())
                    })
                    .collect(),
            ),
            group: region.group.clone(),
            pin: region.pin,
        })
        .collect()
}

#[test]
fn densified_boundaries_give_the_same_neighbours_and_a_layout_as_good() {
    // Rook pairs from the data README. Densified tenfold, every layer keeps its pairs exactly;
    // us_states also keeps a layout as good as the original's. Not the same layout: a sub-cell
    // change to the outline changes the annealing's path, and so the layout, as a change of seed
    // does (BENCHMARKS.md, "Settings tried over seeds"; issue 12's "within 0.01" at 10⁶
    // vertices is missed for that reason). So each of its metrics lies within the range the
    // original's take over seeds 0–7, widened by issue 12's 0.01 (0.5° for orientation).
    let params = Params::default();
    for (name, rook_pairs) in [
        ("us_states", 107),
        ("virginia_counties", 287),
        ("nc_counties", 231),
    ] {
        let regions = load(name);
        let dense = densified(&regions, 10);
        let vertices = |rs: &[Region]| -> usize {
            rs.iter()
                .map(|r| geo::CoordsIter::coords_count(&r.geometry))
                .sum()
        };
        assert!(
            vertices(&dense) > 9 * vertices(&regions),
            "{name}: densified"
        );
        let (plain, thick) = (run(&regions, &params), run(&dense, &params));
        assert_valid_grid(&dense, &thick);
        assert_eq!(plain.adjacency.len(), rook_pairs, "{name}");
        assert_eq!(
            thick.adjacency, plain.adjacency,
            "{name}: the same rook pairs"
        );
        if name != "us_states" {
            continue;
        }
        // Seed 0 is the default's, already run.
        let seeds: Vec<_> = std::iter::once(plain.metrics)
            .chain((1..8).map(|seed| {
                run(
                    &regions,
                    &Params {
                        seed,
                        ..params.clone()
                    },
                )
                .metrics
            }))
            .collect();
        let b = thick.metrics;
        for (metric, of, margin) in [
            (
                "adjacency",
                (|m| m.adjacent) as fn(&LayoutMetrics) -> f64,
                0.01,
            ),
            ("location", |m| m.location, 0.01),
            ("shape", |m| m.shape, 0.01),
            ("orientation", |m| m.orientation, 0.5),
        ] {
            let low = seeds.iter().map(of).fold(f64::INFINITY, f64::min) - margin;
            let high = seeds.iter().map(of).fold(f64::NEG_INFINITY, f64::max) + margin;
            let dense = of(&b);
            assert!(
                (low..=high).contains(&dense),
                "{name}: {metric} {dense} outside the seeds' {low}..{high}"
            );
        }
    }
}

#[test]
fn us_states_drawn_apart_or_over_each_others_borders_keeps_its_neighbours() {
    // Each state narrowed, or widened, by 40 m (a ten-thousandth of a cell): no two share a
    // border exactly, as when the regions were drawn or simplified one by one. Before the
    // borders were searched across overlaps, the layout of the widened states kept 79 of the
    // 107 pairs on neighbouring cells (drawn whole: 98).
    let whole = load("us_states");
    let pairs = run(&whole, &Params::default()).adjacency;
    assert_eq!(pairs.len(), 107, "rook pairs of the shared file");
    for distance in [-40.0, 40.0] {
        let redrawn: Vec<Region> = (whole.iter().cloned())
            .map(|mut region| {
                region.geometry = region.geometry.buffer(distance);
                region
            })
            .collect();
        let map = run(&redrawn, &Params::default());
        assert_valid_grid(&redrawn, &map);
        assert!(map.adjacency.len() < 10, "{distance}: shared exactly");
        let touching = |i: usize, j: usize| {
            let (a, b) = (&map.cells[i], &map.cells[j]);
            (a.col - b.col).abs() <= 1 && (a.row - b.row).abs() <= 1
        };
        let kept = pairs.iter().filter(|&&(i, j)| touching(i, j)).count();
        // McNeill and Hale's tilemaps keeps 0.879 of them drawn whole (method.md §11).
        assert!(
            kept as f64 >= 0.88 * pairs.len() as f64,
            "{distance}: {kept} of {} pairs kept",
            pairs.len()
        );
    }
}

#[test]
fn counties_simplified_one_by_one_leave_no_holes_in_the_layout() {
    // Each county simplified alone by 3 km (a sixteenth of a cell), as `ogr2ogr -simplify 3000`
    // does: slivers open between neighbours, and the union of the counties has hundreds of
    // small holes. Taken for lakes the source has, they let the layout keep as many holes
    // (with ogr2ogr's: 25 cells).
    let regions: Vec<Region> = (load("us_counties").into_iter())
        .map(|mut region| {
            region.geometry = region.geometry.simplify(3000.0);
            region
        })
        .collect();
    let map = run(&regions, &Params::default());
    assert!(map.metrics.source_holes > 10.0, "{:?}", map.metrics);
    assert_eq!(map.metrics.holes, 0, "{:?}", map.metrics);
}

#[test]
fn a_speck_of_an_island_leaves_no_ring_too_small_to_draw_in_the_moved_outline() {
    // A 10 m islet 20 km off North Carolina: the Snake's outline holds it as a ring of two
    // nodes, which the moved outline (the C API's, Python's and QGIS's output) wrote as a
    // polygon that shapely and GEOS refuse to read.
    let mut regions = load("nc_counties");
    let bounds = (regions.iter())
        .filter_map(|r| geo::BoundingRect::bounding_rect(&r.geometry))
        .reduce(|a, b| {
            geo::Rect::new(
                geo::coord! { x: a.min().x.min(b.min().x), y: a.min().y.min(b.min().y) },
                geo::coord! { x: a.max().x.max(b.max().x), y: a.max().y.max(b.max().y) },
            )
        })
        .unwrap();
    let (x, y) = (bounds.min().x - 20_000.0, bounds.min().y);
    regions.last_mut().unwrap().geometry =
        MultiPolygon(vec![
            geo::Rect::new((x, y), (x + 10.0, y + 10.0)).to_polygon()
        ]);
    let map = run(&regions, &Params::default());
    assert_eq!(map.cells.len(), regions.len());
    assert!(!map.moved_outline.0.is_empty());
    for polygon in &map.moved_outline {
        for ring in std::iter::once(polygon.exterior()).chain(polygon.interiors()) {
            let area = geo::Polygon::new(ring.clone(), vec![]).unsigned_area();
            assert!(ring.0.len() >= 4 && area > 0.0, "a ring of {:?}", ring.0);
        }
    }
    assert!(
        map.moved_outline.is_valid(),
        "{:?}",
        map.moved_outline.validation_errors()
    );
}
