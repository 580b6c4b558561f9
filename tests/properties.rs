//! Property tests: random Voronoi-cell layers (a tessellation, like real administrative
//! regions), random feature orders and random parameters within their documented ranges
//! (docs/c-api.md) always give a valid grid map (one distinct equal square per region on one
//! lattice, finite metrics) that does not depend on the order of the features.

use geo::{Area, Coord, LineString, MultiPolygon, Polygon};
use proptest::prelude::*;
use snakegrid::{generate, GridMap, LoadModel, Params, Region};
use std::collections::HashMap;

mod common;

/// Side of the square the points are drawn in, map units.
const SIDE: f64 = 1000.0;

/// The part of `polygon` (convex, counter-clockwise) on the side of the perpendicular bisector
/// of `p`–`q` nearer to `p`: one Sutherland–Hodgman step.
fn clip(polygon: &[Coord<f64>], p: Coord<f64>, q: Coord<f64>) -> Vec<Coord<f64>> {
    let mid = (p + q) / 2.0;
    let normal = q - p;
    let side = |c: Coord<f64>| (c - mid).x * normal.x + (c - mid).y * normal.y;
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for (k, &a) in polygon.iter().enumerate() {
        let b = polygon[(k + 1) % polygon.len()];
        let (sa, sb) = (side(a), side(b));
        if sa <= 0.0 {
            out.push(a);
        }
        if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
            out.push(a + (b - a) * (sa / (sa - sb)));
        }
    }
    out
}

/// The Voronoi cells of `points` clipped to the square, as regions "v0", "v1", …. A cell is cut
/// only by points that can reach it (within twice its current extent), which keeps 2,000 points
/// quick.
fn voronoi(points: &[Coord<f64>]) -> Vec<Region> {
    let square = [
        Coord { x: 0.0, y: 0.0 },
        Coord { x: SIDE, y: 0.0 },
        Coord { x: SIDE, y: SIDE },
        Coord { x: 0.0, y: SIDE },
    ];
    points
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let mut others: Vec<Coord<f64>> = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &q)| q)
                .collect();
            let distance2 = |q: &Coord<f64>| (q.x - p.x).powi(2) + (q.y - p.y).powi(2);
            others.sort_by(|a, b| distance2(a).total_cmp(&distance2(b)));
            let mut cell = square.to_vec();
            for q in others {
                let reach = cell.iter().map(distance2).fold(0.0, f64::max);
                if distance2(&q) > 4.0 * reach {
                    break;
                }
                cell = clip(&cell, p, q);
            }
            cell.push(cell[0]);
            Region {
                id: format!("v{i}"),
                geometry: MultiPolygon(vec![Polygon::new(LineString(cell), vec![])]),
            }
        })
        .collect()
}

/// `count` points in the square, at least a hundredth of the mean spacing apart, so no cell is
/// a sliver of nothing.
fn points(count: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Vec<Coord<f64>>> {
    prop::collection::vec((0.0..SIDE, 0.0..SIDE), count).prop_map(|raw| {
        let gap = 0.01 * SIDE / (raw.len() as f64).sqrt();
        let mut kept: Vec<Coord<f64>> = Vec::with_capacity(raw.len());
        for (x, y) in raw {
            let c = Coord { x, y };
            if kept
                .iter()
                .all(|k| (k.x - c.x).abs() > gap || (k.y - c.y).abs() > gap)
            {
                kept.push(c);
            }
        }
        kept
    })
}

/// Parameters drawn from their documented ranges, kept short where they only cost time.
fn params() -> impl Strategy<Value = Params> {
    let snake = (
        0.1..10.0f64,
        0.1..10.0f64,
        0.01..=1.0f64,
        1e-4..0.1f64,
        0..=30usize,
        1.0..10.0f64,
        1e-3..0.1f64,
        any::<bool>(),
        prop_oneof![Just(LoadModel::Nodal), Just(LoadModel::Element)],
    );
    let outline = (
        0.5..4.0f64,
        prop::option::of(0.0..0.5f64),
        any::<bool>(),
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64), 1..=4),
        prop::collection::vec(0.0..=0.1f64, 0..=2),
        any::<u64>(),
        [0.0..2.0f64, 0.1..2.0f64, 0.0..2.0f64, 0.0..2.0f64],
    );
    let refine = (
        any::<bool>(),
        0..=4000usize,
        0.0..1.0f64,
        [0.0..2.0f64, 0.0..2.0f64, 0.0..2.0f64, 0.0..2.0f64],
        1.0..2.0f64,
        0..=40usize,
    );
    (snake, outline, refine).prop_map(|(s, o, r)| Params {
        alpha: s.0,
        beta: s.1,
        force_cap: s.2,
        epsilon: s.3,
        max_steps: s.4,
        step_ratio: s.5,
        spring: s.6,
        stop_on_no_progress: s.7,
        load_model: s.8,
        vertices_per_region: o.0,
        simplify_tolerance: o.1,
        point_adjacency: o.2,
        shifts: o.3.into_iter().map(|(x, y)| [x, y]).collect(),
        noise_levels: o.4,
        seed: o.5,
        topsis_weights: o.6,
        refine: r.0,
        refine_moves: r.1,
        refine_temperature: r.2,
        refine_w_adjacent: r.3[0],
        refine_w_angle: r.3[1],
        refine_w_misdirected: r.3[2],
        refine_w_location: r.3[3],
        refine_cell_ratio: r.4,
        refine_swap_only_below: r.5,
    })
}

fn run(regions: &[Region], params: &Params) -> GridMap {
    params
        .validate()
        .expect("the strategy draws valid parameters");
    generate(regions, params, &|_, _| true).expect("a grid map")
}

/// Each region's cell, by id.
fn cells(map: &GridMap) -> HashMap<&str, (i32, i32)> {
    map.cells
        .iter()
        .map(|c| (c.id.as_str(), (c.col, c.row)))
        .collect()
}

/// A valid grid map, and the same one for the features in another order.
fn check(points: &[Coord<f64>], order: &[usize], params: &Params) {
    let regions = voronoi(points);
    let area: f64 = regions.iter().map(|r| r.geometry.unsigned_area()).sum();
    assert!(
        (area - SIDE * SIDE).abs() < 1e-6 * SIDE * SIDE,
        "the cells tile the square"
    );
    let map = run(&regions, params);
    common::assert_valid_grid(&regions, &map);
    let shuffled: Vec<Region> = order
        .iter()
        .filter(|&&k| k < regions.len())
        .map(|&k| regions[k].clone())
        .collect();
    let again = run(&shuffled, params);
    common::assert_valid_grid(&shuffled, &again);
    assert_eq!(
        cells(&map),
        cells(&again),
        "the layout depends on the order"
    );
}

/// A point set and a permutation of (at least) its indices.
fn layer(
    count: std::ops::RangeInclusive<usize>,
) -> impl Strategy<Value = (Vec<Coord<f64>>, Vec<usize>)> {
    let most = *count.end();
    (
        points(count),
        Just((0..most).collect::<Vec<usize>>()).prop_shuffle(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    #[test]
    fn tiny_random_layers_give_valid_order_independent_grid_maps(
        (points, order) in layer(2..=6),
        params in params(),
    ) {
        check(&points, &order, &params);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn small_random_layers_give_valid_order_independent_grid_maps(
        (points, order) in layer(2..=120),
        params in params(),
    ) {
        check(&points, &order, &params);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn large_random_layers_give_valid_order_independent_grid_maps(
        (points, order) in layer(1500..=2000),
        params in params(),
    ) {
        check(&points, &order, &params);
    }
}
