//! Step 0 (method.md §1): from the regions, their centroids, which of them are adjacent, and the
//! outline of the whole map (every part with its holes), cleaned and simplified so it keeps about
//! two vertices per region.

use super::geometry::{nearest_on_segment, point_segment_distance2, segments_intersect, RingIndex};
use super::Params;
use geo::orient::{Direction, Orient};
use geo::{
    Area, BoundingRect, Centroid, Contains, Coord, InteriorPoint, LineString, MultiPolygon, Point,
    Polygon, SimplifyVw, SimplifyVwPreserve,
};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, RTreeObject, AABB};

/// Distance, in cells, under which two boundaries count as touching: shared borders that were
/// noded identically meet exactly, but reprojection and rounding leave tiny gaps.
const TOUCH_TOLERANCE: f64 = 1e-6;
/// Shared border length, in cells, above which two regions are adjacent rather than meeting at a
/// point.
const SHARED_LENGTH: f64 = 1e-4;
/// Holes smaller than this many cells² are slivers between regions, not lakes (§1).
const SLIVER_AREA: f64 = 0.5;
/// A centroid outside the simplified outline is moved this far inside it, in cells (§1).
const INSIDE_MARGIN: f64 = 0.05;

/// The outline of the map: closed rings (open coordinate chains) in the unit-cell frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Ring {
    pub coords: Vec<Coord<f64>>,
    /// The connected part (mainland, island) the ring belongs to.
    pub part: usize,
    pub hole: bool,
}

/// What the later steps need to know of the regions, in the unit-cell frame.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// One centroid per region (§1), inside the simplified outline: the Snake's node.
    pub centroids: Vec<Coord<f64>>,
    /// The area centroid of each region's whole (multi)polygon: what the metrics measure from
    /// (§8).
    pub area_centroids: Vec<Coord<f64>>,
    /// The union of the regions as it is, every part and hole kept: what the metrics compare
    /// the layout with.
    pub regions_union: MultiPolygon<f64>,
    /// Per region, the part of `regions_union` (its landmass) holding most of its area.
    pub landmass_of: Vec<usize>,
    /// Adjacent pairs (i < j), sorted.
    pub adjacency: Vec<(usize, usize)>,
    /// The simplified outline.
    pub rings: Vec<Ring>,
    /// Per region, the part of the simplified outline (its landmass in the layout) that holds
    /// its centroid.
    pub part_of: Vec<usize>,
}

/// Prepares `regions` (unit-cell frame, validated: non-empty, finite, positive area).
pub fn prepare(regions: &[&MultiPolygon<f64>], params: &Params) -> Prepared {
    let centroids: Vec<Coord<f64>> = regions.iter().map(|r| centroid(r)).collect();
    let area_centroids = regions
        .iter()
        .zip(&centroids)
        .map(|(r, &fallback)| r.centroid().map_or(fallback, |p| p.0))
        .collect();
    let adjacency = adjacency(regions, params.point_adjacency);
    let regions_union = merge(regions);
    let landmass_of = landmasses(regions, &regions_union, &centroids);
    let union = clean(regions_union.clone(), &centroids);
    // Small layers still keep a quadrilateral per ring on average.
    let target = ((params.vertices_per_region * regions.len() as f64).ceil() as usize)
        .max(4 * rings_of(&union).len());
    let rings = rings_of(&simplify(&union, target, params.simplify_tolerance));
    let index = RingIndex::new(&coords_of(&rings));
    let centroids: Vec<Coord<f64>> = centroids
        .into_iter()
        .map(|c| move_inside(c, &index))
        .collect();
    let part_of = parts_holding(&rings, &centroids);
    Prepared {
        centroids,
        area_centroids,
        regions_union,
        landmass_of,
        adjacency,
        rings,
        part_of,
    }
}

/// For each point, the part of the outline `rings` whose inside holds it (the nearest part for
/// a point in none, which only rounding can make).
fn parts_holding(rings: &[Ring], points: &[Coord<f64>]) -> Vec<usize> {
    let parts = rings.iter().map(|r| r.part + 1).max().unwrap_or(0);
    let indexes: Vec<RingIndex> = (0..parts)
        .map(|part| {
            let own: Vec<Ring> = rings.iter().filter(|r| r.part == part).cloned().collect();
            RingIndex::new(&coords_of(&own))
        })
        .collect();
    points
        .iter()
        .map(|&p| {
            (0..parts)
                .find(|&k| indexes[k].contains(p))
                .unwrap_or_else(|| {
                    (0..parts)
                        .min_by(|&a, &b| {
                            let d = |k: usize| indexes[k].distance(p, |_| false);
                            d(a).total_cmp(&d(b)).then(a.cmp(&b))
                        })
                        .unwrap_or(0)
                })
        })
        .collect()
}

/// For each region, the part of `union` that holds most of its area: each of a region's polygons
/// lies in one part (a connected polygon lies in one connected part of the union), found from a
/// point inside it (a region whose polygons all fail that test, by rounding, belongs to the part
/// nearest its centroid).
fn landmasses(
    regions: &[&MultiPolygon<f64>],
    union: &MultiPolygon<f64>,
    centroids: &[Coord<f64>],
) -> Vec<usize> {
    let parts: Vec<RingIndex> = union
        .0
        .iter()
        .map(|p| RingIndex::new(&coords_of(&rings_of(&MultiPolygon(vec![p.clone()])))))
        .collect();
    let boxes: RTree<GeomWithData<Rectangle<[f64; 2]>, usize>> = RTree::bulk_load(
        (union.0.iter().enumerate())
            .filter_map(|(k, p)| {
                let b = p.bounding_rect()?;
                let corners = ([b.min().x, b.min().y], [b.max().x, b.max().y]);
                Some(GeomWithData::new(
                    Rectangle::from_corners(corners.0, corners.1),
                    k,
                ))
            })
            .collect(),
    );
    let part_of = |p: Coord<f64>| {
        (boxes.locate_all_at_point(&[p.x, p.y]))
            .map(|b| b.data)
            .filter(|&k| parts[k].contains(p))
            .min()
    };
    regions
        .iter()
        .zip(centroids)
        .map(|(region, &centroid)| {
            let mut area = vec![0.0; parts.len()];
            for polygon in &region.0 {
                if let Some(k) = polygon.interior_point().and_then(|p| part_of(p.0)) {
                    area[k] += polygon.unsigned_area();
                }
            }
            let held = (0..parts.len())
                .filter(|&k| area[k] > 0.0)
                .max_by(|&a, &b| area[a].total_cmp(&area[b]).then(b.cmp(&a)));
            held.unwrap_or_else(|| {
                (0..parts.len())
                    .min_by(|&a, &b| {
                        let d = |k: usize| parts[k].distance(centroid, |_| false);
                        d(a).total_cmp(&d(b)).then(a.cmp(&b))
                    })
                    .unwrap_or(0)
            })
        })
        .collect()
}

/// The area centroid, or a point on the surface of the largest part when the centroid falls
/// outside the region (crescents, multipart regions).
fn centroid(region: &MultiPolygon<f64>) -> Coord<f64> {
    if let Some(c) = region.centroid() {
        if region.contains(&c) {
            return c.0;
        }
    }
    let largest = region
        .0
        .iter()
        .max_by(|a, b| a.unsigned_area().total_cmp(&b.unsigned_area()));
    largest
        .and_then(|p| p.interior_point())
        .or_else(|| region.interior_point())
        .map_or(Coord { x: 0.0, y: 0.0 }, |p: Point<f64>| p.0)
}

/// A boundary segment of a region, for the adjacency search.
#[derive(Clone, Copy)]
struct Edge {
    a: Coord<f64>,
    b: Coord<f64>,
    region: usize,
}

impl RTreeObject for Edge {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners([self.a.x, self.a.y], [self.b.x, self.b.y])
    }
}

/// Pairs of regions whose boundaries share a line of positive length (or, with
/// `point_adjacency`, any point). Works on the boundaries' segments so that it needs no exact
/// noding: a segment counts as shared where another region's segment runs along it within
/// `TOUCH_TOLERANCE`.
fn adjacency(regions: &[&MultiPolygon<f64>], point_adjacency: bool) -> Vec<(usize, usize)> {
    let edges: Vec<Edge> = regions
        .iter()
        .enumerate()
        .flat_map(|(region, mp)| {
            mp.0.iter()
                .flat_map(|p| std::iter::once(p.exterior()).chain(p.interiors()))
                .flat_map(|ring| ring.lines())
                .map(move |l| Edge {
                    a: l.start,
                    b: l.end,
                    region,
                })
        })
        .collect();
    let tree = RTree::bulk_load(edges.clone());
    let mut shared: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
    for e in &edges {
        let env = e.envelope();
        let search = AABB::from_corners(
            [
                env.lower()[0] - TOUCH_TOLERANCE,
                env.lower()[1] - TOUCH_TOLERANCE,
            ],
            [
                env.upper()[0] + TOUCH_TOLERANCE,
                env.upper()[1] + TOUCH_TOLERANCE,
            ],
        );
        for f in tree.locate_in_envelope_intersecting(&search) {
            if f.region <= e.region || !touches(e, f) {
                continue;
            }
            *shared.entry((e.region, f.region)).or_default() += overlap(e, f);
        }
    }
    shared
        .into_iter()
        .filter(|&(_, length)| point_adjacency || length > SHARED_LENGTH)
        .map(|(pair, _)| pair)
        .collect()
}

fn touches(e: &Edge, f: &Edge) -> bool {
    if segments_intersect(e.a, e.b, f.a, f.b) {
        return true;
    }
    let d2 = [
        point_segment_distance2(e.a, f.a, f.b),
        point_segment_distance2(e.b, f.a, f.b),
        point_segment_distance2(f.a, e.a, e.b),
        point_segment_distance2(f.b, e.a, e.b),
    ];
    d2.iter().any(|&d| d <= TOUCH_TOLERANCE * TOUCH_TOLERANCE)
}

/// Length along `e` that `f` runs on (both ends of `f` within tolerance of `e`'s line).
fn overlap(e: &Edge, f: &Edge) -> f64 {
    let d = e.b - e.a;
    let len = (d.x * d.x + d.y * d.y).sqrt();
    if len == 0.0 {
        return 0.0;
    }
    let u = d / len;
    let off_line = |p: Coord<f64>| ((p - e.a).x * u.y - (p - e.a).y * u.x).abs();
    if off_line(f.a) > TOUCH_TOLERANCE || off_line(f.b) > TOUCH_TOLERANCE {
        return 0.0;
    }
    let along = |p: Coord<f64>| (p - e.a).x * u.x + (p - e.a).y * u.y;
    let (s, t) = (along(f.a), along(f.b));
    (s.max(t).min(len) - s.min(t).max(0.0)).max(0.0)
}

/// The union of all regions. geo's union reads the winding of the first ring as the rule for all,
/// and layers in the wild mix windings (Shapefile rings run clockwise), so orient every polygon
/// first.
fn merge(regions: &[&MultiPolygon<f64>]) -> MultiPolygon<f64> {
    let oriented: Vec<Polygon<f64>> = regions
        .iter()
        .flat_map(|r| r.0.iter())
        .map(|p| p.orient(Direction::Default))
        .collect();
    geo::unary_union(&oriented)
}

/// Drops parts that hold no centroid (stray islands of multipart regions) and fills holes that
/// are slivers between regions rather than lakes or missing regions.
fn clean(union: MultiPolygon<f64>, centroids: &[Coord<f64>]) -> MultiPolygon<f64> {
    let parts = union
        .0
        .into_iter()
        .filter(|part| {
            let shell = Polygon::new(part.exterior().clone(), vec![]);
            centroids.iter().any(|&c| shell.contains(&Point(c)))
        })
        .map(|part| {
            let (exterior, holes) = part.into_inner();
            let holes = holes
                .into_iter()
                .filter(|h| Polygon::new(h.clone(), vec![]).unsigned_area() >= SLIVER_AREA)
                .collect();
            Polygon::new(exterior, holes)
        });
    MultiPolygon(parts.collect())
}

fn vertex_count(p: &MultiPolygon<f64>) -> usize {
    p.0.iter()
        .flat_map(|poly| std::iter::once(poly.exterior()).chain(poly.interiors()))
        .map(|ring| ring.0.len().saturating_sub(1))
        .sum()
}

/// Topology-preserving Visvalingam simplification to about `target` vertices (§1), or with the
/// tolerance the user gave. The tolerance is found by bisection with plain Visvalingam, ten times
/// faster than the topology-preserving variant and close enough for "about", which then runs
/// once. geo preserves topology within each part only, so a result whose rings cross each other
/// is refused and the tolerance lowered.
fn simplify(union: &MultiPolygon<f64>, target: usize, tolerance: Option<f64>) -> MultiPolygon<f64> {
    let eps = match tolerance {
        Some(eps) => eps,
        None if vertex_count(union) <= target => return union.clone(),
        None => {
            let too_many = |eps: f64| vertex_count(&union.simplify_vw(eps)) > target;
            let (mut lo, mut hi) = (1e-9, 1e-3);
            while too_many(hi) && hi < 1e9 {
                lo = hi;
                hi *= 16.0;
            }
            for _ in 0..30 {
                let mid = (lo * hi).sqrt();
                if too_many(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            hi
        }
    };
    let mut eps = eps;
    while eps > 1e-12 {
        let simplified = union.simplify_vw_preserve(eps);
        if !RingIndex::new(&coords_of(&rings_of(&simplified))).self_intersects() {
            return simplified;
        }
        eps *= 0.5;
    }
    union.clone()
}

/// The rings of a multipolygon, open, with part numbers; exteriors counter-clockwise, holes
/// clockwise, so every ring keeps the interior on its left.
pub fn rings_of(p: &MultiPolygon<f64>) -> Vec<Ring> {
    let open = |ring: &LineString<f64>, ccw: bool| {
        let mut coords: Vec<Coord<f64>> = ring.0.clone();
        if coords.len() > 1 && coords.first() == coords.last() {
            coords.pop();
        }
        let area = Polygon::new(LineString(coords.clone()), vec![]).signed_area();
        if (area > 0.0) != ccw {
            coords.reverse();
        }
        coords
    };
    p.0.iter()
        .enumerate()
        .flat_map(|(part, poly)| {
            std::iter::once(Ring {
                coords: open(poly.exterior(), true),
                part,
                hole: false,
            })
            .chain(poly.interiors().iter().map(move |h| Ring {
                coords: open(h, false),
                part,
                hole: true,
            }))
        })
        .collect()
}

pub fn coords_of(rings: &[Ring]) -> Vec<Vec<Coord<f64>>> {
    rings.iter().map(|r| r.coords.clone()).collect()
}

/// A multipolygon from rings: the inverse of [`rings_of`], used to rebuild the outline at the
/// Snake's moved positions.
pub fn polygons_of(rings: &[Ring]) -> MultiPolygon<f64> {
    let parts = rings.iter().map(|r| r.part).max().map_or(0, |m| m + 1);
    let closed = |r: &Ring| {
        let mut line = r.coords.clone();
        if let Some(&first) = line.first() {
            line.push(first);
        }
        LineString(line)
    };
    let polygons = (0..parts).filter_map(|part| {
        let exterior = rings.iter().find(|r| r.part == part && !r.hole)?;
        let holes = rings
            .iter()
            .filter(|r| r.part == part && r.hole)
            .map(closed)
            .collect();
        Some(Polygon::new(closed(exterior), holes))
    });
    MultiPolygon(polygons.collect())
}

/// Moves a centroid that is outside the simplified outline to `INSIDE_MARGIN` inside it, past
/// the nearest point of the outline (§1).
fn move_inside(c: Coord<f64>, index: &RingIndex) -> Coord<f64> {
    if index.contains(c) {
        return c;
    }
    let Some(segment) = index.nearest(c) else {
        return c;
    };
    let q = nearest_on_segment(c, segment.a, segment.b);
    let away = q - c;
    let len = (away.x * away.x + away.y * away.y).sqrt();
    // The inward direction: across the nearest point, or the segment's left normal when the
    // centroid lies on the outline (rings keep the interior on their left).
    let dir = if len > 1e-12 {
        away / len
    } else {
        let t = segment.b - segment.a;
        let n = (t.x * t.x + t.y * t.y).sqrt().max(1e-300);
        Coord {
            x: -t.y / n,
            y: t.x / n,
        }
    };
    let mut margin = INSIDE_MARGIN;
    while margin > 1e-9 {
        let candidate = q + dir * margin;
        if index.contains(candidate) {
            return candidate;
        }
        margin *= 0.5;
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::polygon;

    fn square(x: f64, y: f64) -> MultiPolygon<f64> {
        MultiPolygon(vec![
            polygon![(x: x, y: y), (x: x + 1.0, y: y), (x: x + 1.0, y: y + 1.0), (x: x, y: y + 1.0)],
        ])
    }

    #[test]
    fn a_block_of_squares_has_rook_adjacency_and_one_outline() {
        let regions: Vec<MultiPolygon<f64>> = (0..3)
            .flat_map(|r| (0..3).map(move |c| square(c as f64, r as f64)))
            .collect();
        let refs: Vec<&MultiPolygon<f64>> = regions.iter().collect();
        let prepared = prepare(&refs, &Params::default());
        // 3×3 rook adjacency: 12 pairs; diagonal neighbours touch at a point only.
        assert_eq!(prepared.adjacency.len(), 12);
        assert!(prepared.adjacency.contains(&(0, 1)));
        assert!(!prepared.adjacency.contains(&(0, 4)));
        assert_eq!(prepared.rings.len(), 1);
        assert!((prepared.regions_union.unsigned_area() - 9.0).abs() < 1e-9);
        assert!((prepared.centroids[4].x - 1.5).abs() < 1e-12);
        let with_points = Params {
            point_adjacency: true,
            ..Params::default()
        };
        assert_eq!(prepare(&refs, &with_points).adjacency.len(), 20);
    }

    #[test]
    fn small_holes_are_filled_and_empty_parts_dropped() {
        let holed = MultiPolygon(vec![Polygon::new(
            LineString::from(vec![
                (0.0, 0.0),
                (4.0, 0.0),
                (4.0, 4.0),
                (0.0, 4.0),
                (0.0, 0.0),
            ]),
            vec![
                LineString::from(vec![
                    (0.5, 0.5),
                    (0.7, 0.5),
                    (0.7, 0.7),
                    (0.5, 0.7),
                    (0.5, 0.5),
                ]),
                LineString::from(vec![
                    (2.0, 2.0),
                    (3.0, 2.0),
                    (3.0, 3.0),
                    (2.0, 3.0),
                    (2.0, 2.0),
                ]),
            ],
        )]);
        let mut island = square(10.0, 10.0);
        island.0.extend(square(20.0, 20.0).0.iter().map(|p| {
            use geo::Scale;
            p.scale(0.01)
        }));
        let prepared = prepare(&[&holed, &island], &Params::default());
        let holes: Vec<&Ring> = prepared.rings.iter().filter(|r| r.hole).collect();
        assert_eq!(holes.len(), 1, "the 1-cell² lake stays, the sliver goes");
        // The island region's centroid lies in its big square; the tiny part holds no centroid.
        assert_eq!(prepared.rings.iter().filter(|r| !r.hole).count(), 2);
    }
}
