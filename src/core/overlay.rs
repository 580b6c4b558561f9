//! The union of oriented polygons exactly as geo's polygon overlay (i_overlay) writes it, without
//! running the overlay where it has nothing to do. The overlay's cost is superlinear on long
//! segments with overlapping extents (it cuts every segment at every column of its grid that the
//! segment spans: a 200,000-vertex star took 300 s), yet for the polygons of one valid region —
//! no two overlapping, no ring crossing another — the union is the polygons themselves. Later
//! steps depend on the overlay's normal form (simplification keeps each ring's first vertex), so
//! the shortcut writes that normal form, checked equal to the overlay's in the tests:
//! - coordinates snapped to the overlay's integer grid (its adapter, fitted to all the points);
//! - repeated and collinear vertices dropped;
//! - a shell starts at the vertex before its lowest (x, then y) one, a hole at its lowest one,
//!   and holes come in the order of their lowest vertices.
//!
//! One difference is left: where a ring touches another at a point inside a segment, the overlay
//! nodes the segment there and its shell may start one vertex later; the union is the same.

use super::validity;
use geo::{Coord, LineString, MultiPolygon, Polygon};
use i_float::adapter::FloatPointAdapter;
use i_float::int::point::IntPoint;

/// What [`union`] is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Given {
    /// The polygons of several regions: overlaid.
    Regions,
    /// The polygons of one region, not known to be valid in these coordinates: checked, since
    /// the rounding into the unit-cell frame can break a valid region (subnormal coordinates,
    /// found by fuzzing), which the overlay then mends.
    Region,
    /// The polygons of one region, checked valid in these very coordinates.
    ValidRegion,
}

/// The union of `polygons` (oriented: shells counter-clockwise, holes clockwise): for one valid
/// region, the polygons themselves.
pub fn union(polygons: &[Polygon<f64>], given: Given) -> Vec<Polygon<f64>> {
    let valid = match given {
        Given::Regions => false,
        Given::Region => validity::problem(&MultiPolygon(polygons.to_vec())).is_none(),
        Given::ValidRegion => true,
    };
    if !valid {
        return geo::unary_union(polygons).0;
    }
    let points: Vec<[f64; 2]> = rings(polygons)
        .flat_map(|r| open(r).iter().map(|c| [c.x, c.y]))
        .collect();
    let grid = FloatPointAdapter::<[f64; 2], f64>::with_iter(points.iter());
    let normal = |ring: &LineString<f64>, shell: bool| {
        let mut snapped: Vec<IntPoint> = open(ring)
            .iter()
            .map(|c| grid.float_to_int(&[c.x, c.y]))
            .collect();
        snapped.dedup();
        while snapped.len() > 1 && snapped.first() == snapped.last() {
            snapped.pop();
        }
        drop_collinear(&mut snapped);
        let n = snapped.len().max(1);
        let lowest = (0..snapped.len())
            .min_by_key(|&i| (snapped[i].x, snapped[i].y))
            .unwrap_or(0);
        snapped.rotate_left(if shell { (lowest + n - 1) % n } else { lowest });
        let mut coords: Vec<Coord<f64>> = (snapped.iter())
            .map(|p| {
                let [x, y] = grid.int_to_float(p);
                Coord { x, y }
            })
            .collect();
        coords.extend(coords.first().copied());
        LineString(coords)
    };
    (polygons.iter())
        .map(|p| {
            let mut holes: Vec<LineString<f64>> =
                p.interiors().iter().map(|h| normal(h, false)).collect();
            holes.sort_by(|a, b| {
                let (a, b) = (a.0[0], b.0[0]);
                a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))
            });
            Polygon::new(normal(p.exterior(), true), holes)
        })
        .collect()
}

fn rings(polygons: &[Polygon<f64>]) -> impl Iterator<Item = &LineString<f64>> {
    (polygons.iter()).flat_map(|p| std::iter::once(p.exterior()).chain(p.interiors()))
}

/// A closed ring's vertices without the closing one.
fn open(ring: &LineString<f64>) -> &[Coord<f64>] {
    &ring.0[..ring.0.len().saturating_sub(1)]
}

/// Drops the vertices of a closed ring that lie on the line through their neighbours (exact, in
/// integers), in passes that each drop no two neighbours, until none is left: a straight run of
/// k vertices goes in about log k passes.
fn drop_collinear(ring: &mut Vec<IntPoint>) {
    loop {
        let n = ring.len();
        if n < 3 {
            return;
        }
        let collinear = |i: usize| {
            let (a, b, c) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            let d = |p: IntPoint, q: IntPoint| {
                (
                    i64::from(q.x) - i64::from(p.x),
                    i64::from(q.y) - i64::from(p.y),
                )
            };
            let ((ux, uy), (vx, vy)) = (d(a, b), d(b, c));
            ux * vy == uy * vx
        };
        let mut kept = Vec::with_capacity(n);
        let (mut dropped_first, mut dropped_last) = (false, false);
        for (i, &vertex) in ring.iter().enumerate() {
            // The last vertex's next is the first: never drop both.
            let drop = collinear(i) && !dropped_last && !(i == n - 1 && dropped_first);
            if drop {
                dropped_first |= i == 0;
            } else {
                kept.push(vertex);
            }
            dropped_last = drop;
        }
        if kept.len() == n {
            return;
        }
        *ring = kept;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::orient::{Direction, Orient};
    use geo::polygon;
    use rand::{Rng, SeedableRng};

    /// A random star-shaped ring (simple) of `n` vertices around `centre`, radii in
    /// `scale` × [0.5, 1), counter-clockwise.
    fn star(n: usize, seed: u64, centre: (f64, f64), scale: f64) -> LineString<f64> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let coords = (0..n).map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let r = scale * rng.random_range(0.5..1.0);
            Coord {
                x: centre.0 + r * a.cos(),
                y: centre.1 + r * a.sin(),
            }
        });
        let mut ring = LineString(coords.collect());
        ring.close();
        ring
    }

    /// The parts in the order `outline::merge` puts them: by their lowest vertex.
    fn by_lowest(mut parts: Vec<Polygon<f64>>) -> Vec<Polygon<f64>> {
        let lowest = |p: &Polygon<f64>| {
            (p.exterior().0.iter()).map(|c| (c.x, c.y)).fold(
                (f64::INFINITY, f64::INFINITY),
                |a, c| if c < a { c } else { a },
            )
        };
        parts.sort_by(|a, b| lowest(a).partial_cmp(&lowest(b)).unwrap());
        parts
    }

    fn both(polygons: &[Polygon<f64>]) -> (Vec<Polygon<f64>>, Vec<Polygon<f64>>) {
        let oriented: Vec<Polygon<f64>> = (polygons.iter())
            .map(|p| p.orient(Direction::Default))
            .collect();
        (
            by_lowest(union(&oriented, Given::Region)),
            by_lowest(geo::unary_union(&oriented).0),
        )
    }

    #[test]
    fn one_region_comes_out_exactly_as_the_overlay_writes_it() {
        // Repeated and collinear vertices, a clockwise shell.
        let square = polygon![(x: 0.0, y: 0.0), (x: 0.0, y: 0.5), (x: 0.0, y: 1.0), (x: 0.0, y: 1.0),
            (x: 2.0, y: 1.0), (x: 2.0, y: 0.0), (x: 1.0, y: 0.0)];
        let (shortcut, overlay) = both(&[square]);
        assert_eq!(shortcut, overlay);
        assert_eq!(shortcut[0].exterior().0.len(), 5, "four corners, closed");
        for seed in 0..50 {
            let shell = star(40 + seed as usize, seed, (3.0, -2.0), 10.0);
            // Two holes inside the shell's inner radius (5), apart from each other; one given
            // counter-clockwise, which orienting turns.
            let holes = vec![
                star(12, seed + 100, (3.5, -2.0), 2.0),
                star(9, seed + 200, (3.0, 1.5), 0.8),
            ];
            let island = star(30, seed + 300, (30.0, 5.0), 4.0);
            let far = star(7, seed + 400, (-30.0, 50.0), 4.0);
            let cases = [
                vec![Polygon::new(shell.clone(), vec![])],
                vec![Polygon::new(shell.clone(), holes.clone())],
                vec![
                    Polygon::new(shell, holes),
                    Polygon::new(island, vec![]),
                    Polygon::new(far, vec![]),
                ],
            ];
            for polygons in cases {
                let (shortcut, overlay) = both(&polygons);
                assert_eq!(shortcut, overlay, "seed {seed}");
            }
        }
    }

    #[test]
    fn a_hole_touching_its_shell_gives_the_same_rings() {
        // The overlay nodes the shell's left side where the hole touches it, and starts the
        // shell one vertex later; the rings are the same cycles.
        let polygon = polygon!(
            exterior: [(x: 0.0, y: 0.0), (x: 4.0, y: 0.0), (x: 4.0, y: 4.0), (x: 0.0, y: 4.0)],
            interiors: [[(x: 0.0, y: 2.0), (x: 2.0, y: 1.0), (x: 2.0, y: 3.0)]],
        );
        let (shortcut, overlay) = both(&[polygon]);
        let cycle = |ring: &LineString<f64>| {
            let mut v: Vec<(f64, f64)> = open(ring).iter().map(|c| (c.x, c.y)).collect();
            let lowest = (0..v.len())
                .min_by(|&a, &b| v[a].partial_cmp(&v[b]).unwrap())
                .unwrap();
            v.rotate_left(lowest);
            v
        };
        assert_eq!(shortcut.len(), 1);
        assert_eq!(overlay.len(), 1);
        let rings = |p: &Polygon<f64>| {
            rings(std::slice::from_ref(p))
                .map(cycle)
                .collect::<Vec<_>>()
        };
        assert_eq!(rings(&shortcut[0]), rings(&overlay[0]));
    }

    #[test]
    fn collinear_runs_shrink_to_their_ends() {
        // A 4×4 square's boundary through every integer point: 16 vertices, 4 corners.
        let mut ring: Vec<IntPoint> = Vec::new();
        for i in 0..4 {
            ring.push(IntPoint::new(i, 0));
        }
        for i in 0..4 {
            ring.push(IntPoint::new(4, i));
        }
        for i in 0..4 {
            ring.push(IntPoint::new(4 - i, 4));
        }
        for i in 0..4 {
            ring.push(IntPoint::new(0, 4 - i));
        }
        drop_collinear(&mut ring);
        assert_eq!(
            ring,
            [(0, 0), (4, 0), (4, 4), (0, 4)].map(|(x, y)| IntPoint::new(x, y))
        );
    }
}
