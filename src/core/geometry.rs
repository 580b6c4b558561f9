//! Planar helpers the steps share: a spatial index over the segments of a set of closed rings,
//! answering "is this point inside?", "how far is the nearest segment?" and "does any segment
//! cross another?" in logarithmic time. The Snake asks these of a moving outline every step, so
//! they work on plain coordinate rings rather than on geo polygons.

use geo::kernels::{Kernel, Orientation, RobustKernel};
use geo::{Coord, MultiPolygon, Polygon, Rect};
use rstar::{PointDistance, RTree, RTreeObject, AABB};

/// Closed rings given as open coordinate chains (the last vertex joins the first).
pub type Rings = [Vec<Coord<f64>>];

/// One ring segment: from vertex `index` of ring `ring` to the next vertex.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    pub a: Coord<f64>,
    pub b: Coord<f64>,
    pub ring: usize,
    pub index: usize,
}

impl RTreeObject for Segment {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners([self.a.x, self.a.y], [self.b.x, self.b.y])
    }
}

impl PointDistance for Segment {
    fn distance_2(&self, p: &[f64; 2]) -> f64 {
        point_segment_distance2(Coord { x: p[0], y: p[1] }, self.a, self.b)
    }
}

/// The smallest rectangle holding all of `rects` (`None` for none).
pub fn bounds(rects: impl Iterator<Item = Rect<f64>>) -> Option<Rect<f64>> {
    rects.reduce(|a, b| {
        Rect::new(
            Coord {
                x: a.min().x.min(b.min().x),
                y: a.min().y.min(b.min().y),
            },
            Coord {
                x: a.max().x.max(b.max().x),
                y: a.max().y.max(b.max().y),
            },
        )
    })
}

/// The index of the lowest of `coords`: least x, then least y (the first of equals).
pub fn lowest(coords: &[Coord<f64>]) -> Option<usize> {
    (0..coords.len()).min_by(|&a, &b| {
        (coords[a].x.total_cmp(&coords[b].x)).then(coords[a].y.total_cmp(&coords[b].y))
    })
}

/// Squared distance from `p` to the segment `a`–`b`.
pub fn point_segment_distance2(p: Coord<f64>, a: Coord<f64>, b: Coord<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.x * ab.x + ab.y * ab.y;
    let t = if len2 > 0.0 {
        (((p - a).x * ab.x + (p - a).y * ab.y) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = p - (a + ab * t);
    d.x * d.x + d.y * d.y
}

/// The point of segment `a`–`b` nearest to `p`.
pub fn nearest_on_segment(p: Coord<f64>, a: Coord<f64>, b: Coord<f64>) -> Coord<f64> {
    let ab = b - a;
    let len2 = ab.x * ab.x + ab.y * ab.y;
    if len2 == 0.0 {
        return a;
    }
    let t = (((p - a).x * ab.x + (p - a).y * ab.y) / len2).clamp(0.0, 1.0);
    a + ab * t
}

/// Whether the closed segments `p1`–`p2` and `q1`–`q2` share any point (touching counts). The
/// orientations come from geo's robust (adaptive exact) predicate: near-collinear segments,
/// which dense boundaries are full of, get the exact answer instead of rounding noise.
pub fn segments_intersect(p1: Coord<f64>, p2: Coord<f64>, q1: Coord<f64>, q2: Coord<f64>) -> bool {
    let side = |a, b, c| RobustKernel::orient2d(a, b, c);
    let (d1, d2) = (side(q1, q2, p1), side(q1, q2, p2));
    let (d3, d4) = (side(p1, p2, q1), side(p1, p2, q2));
    let opposite = |a: Orientation, b: Orientation| {
        matches!(
            (a, b),
            (Orientation::Clockwise, Orientation::CounterClockwise)
                | (Orientation::CounterClockwise, Orientation::Clockwise)
        )
    };
    if opposite(d1, d2) && opposite(d3, d4) {
        return true;
    }
    // A collinear end lies on the other segment when it is within its bounding box (exact).
    let on = |o: Coord<f64>, a: Coord<f64>, p: Coord<f64>, d: Orientation| {
        d == Orientation::Collinear
            && p.x >= o.x.min(a.x)
            && p.x <= o.x.max(a.x)
            && p.y >= o.y.min(a.y)
            && p.y <= o.y.max(a.y)
    };
    on(q1, q2, p1, d1) || on(q1, q2, p2, d2) || on(p1, p2, q1, d3) || on(p1, p2, q2, d4)
}

/// Squared distance between the segments `a`–`b` and `c`–`d`: 0 where they meet, else the least
/// from an end of one to the other.
pub fn segment_distance2(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>, d: Coord<f64>) -> f64 {
    if segments_intersect(a, b, c, d) {
        return 0.0;
    }
    ends_distance2(a, b, c, d)
}

/// The least squared distance from an end of the segment `a`–`b` to `c`–`d` or from an end of
/// `c`–`d` to `a`–`b`: [`segment_distance2`] of segments that do not meet.
pub fn ends_distance2(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>, d: Coord<f64>) -> f64 {
    (point_segment_distance2(a, c, d).min(point_segment_distance2(b, c, d)))
        .min(point_segment_distance2(c, a, b).min(point_segment_distance2(d, a, b)))
}

/// A point inside `polygon` (its holes respected): the middle of the widest span of the
/// horizontal line at mid-height, moved halfway to the nearest other vertex level if a vertex
/// lies on it — geo's `InteriorPoint` rule, in O(n log n) where geo intersects every segment
/// with every other (minutes on a densified square). `None` for a polygon without height.
pub fn interior_point(polygon: &Polygon<f64>) -> Option<Coord<f64>> {
    widest_span(polygon).map(|(point, _)| point)
}

/// [`interior_point`] of the polygon whose span is the widest, as geo's rule for multipolygons.
pub fn interior_point_of_all(polygons: &MultiPolygon<f64>) -> Option<Coord<f64>> {
    widest(polygons.0.iter().filter_map(widest_span)).map(|(point, _)| point)
}

/// The widest of `spans` (a point and a width), the first among equals.
fn widest(spans: impl Iterator<Item = (Coord<f64>, f64)>) -> Option<(Coord<f64>, f64)> {
    spans.fold(None, |best, span| match best {
        Some(b) if b.1 >= span.1 => Some(b),
        _ => Some(span),
    })
}

/// The middle of the widest span of `polygon` on its interior-point line, and its width.
fn widest_span(polygon: &Polygon<f64>) -> Option<(Coord<f64>, f64)> {
    let rings = || std::iter::once(polygon.exterior()).chain(polygon.interiors());
    let levels = || rings().flat_map(|r| r.0.iter().map(|c| c.y));
    let (low, high) = levels().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    if low >= high || low.is_nan() || high.is_nan() {
        return None;
    }
    let mut y = (low + high) / 2.0;
    if levels().any(|v| v == y) {
        let nearest = (levels().filter(|&v| v != y))
            .min_by(|a, b| (a - y).abs().total_cmp(&(b - y).abs()))?;
        y = (y + nearest) / 2.0;
    }
    let mut xs: Vec<f64> = rings()
        .flat_map(|r| r.lines())
        .filter(|l| (l.start.y > y) != (l.end.y > y))
        .map(|l| l.start.x + (y - l.start.y) * (l.end.x - l.start.x) / (l.end.y - l.start.y))
        .collect();
    xs.sort_by(f64::total_cmp);
    widest(xs.chunks_exact(2).map(|span| {
        let middle = Coord {
            x: (span[0] + span[1]) / 2.0,
            y,
        };
        (middle, span[1] - span[0])
    }))
}

/// Whether the ray from `p` towards +x crosses `s`; half-open in y, so that a ray through a
/// vertex crosses one of its two segments.
pub fn crosses_ray(s: &Segment, p: Coord<f64>) -> bool {
    (s.a.y > p.y) != (s.b.y > p.y)
        && p.x < s.a.x + (p.y - s.a.y) * (s.b.x - s.a.x) / (s.b.y - s.a.y)
}

/// A segment index over closed rings.
pub struct RingIndex {
    tree: RTree<Segment>,
    ring_lengths: Vec<usize>,
}

impl RingIndex {
    pub fn new(rings: &Rings) -> RingIndex {
        let segments = rings
            .iter()
            .enumerate()
            .flat_map(|(r, ring)| {
                (0..ring.len()).map(move |i| Segment {
                    a: ring[i],
                    b: ring[(i + 1) % ring.len()],
                    ring: r,
                    index: i,
                })
            })
            .collect();
        RingIndex {
            tree: RTree::bulk_load(segments),
            ring_lengths: rings.iter().map(Vec::len).collect(),
        }
    }

    /// Even-odd containment: inside the outer rings and outside their holes.
    pub fn contains(&self, p: Coord<f64>) -> bool {
        let Some(far) = self.tree.root().envelope().upper().first().copied() else {
            return false;
        };
        let ray = AABB::from_corners([p.x, p.y], [far.max(p.x), p.y]);
        let crossings = self
            .tree
            .locate_in_envelope_intersecting(&ray)
            .filter(|s| crosses_ray(s, p))
            .count();
        crossings % 2 == 1
    }

    /// Distance from `p` to the nearest segment. rstar's plain nearest-neighbour search: its
    /// iterator, which can go on to the next nearest, builds a heap of every node that might
    /// hold the answer, and from the middle of a ring (a lake's centre) that is every node of
    /// the ring (two concentric rings of 300 regions: 35 s, nine tenths of it in that heap).
    pub fn distance(&self, p: Coord<f64>) -> f64 {
        self.nearest(p).map_or(f64::INFINITY, |(_, d)| d)
    }

    /// Like [`RingIndex::distance`], but only up to `reach`: the distance when it is below
    /// `reach`, else `reach`. A box query, with no search heap: the Snake needs a node's
    /// clearance only when it is under a few steps, and most nodes are far from every segment.
    pub fn distance_within(
        &self,
        p: Coord<f64>,
        reach: f64,
        skip: impl Fn(&Segment) -> bool,
    ) -> f64 {
        let around = AABB::from_corners([p.x - reach, p.y - reach], [p.x + reach, p.y + reach]);
        (self.tree.locate_in_envelope_intersecting(&around))
            .filter(|s| !skip(s))
            .map(|s| s.distance_2(&[p.x, p.y]).sqrt())
            .fold(reach, f64::min)
    }

    /// The segments within `reach` of `p` (at `reach` too), each with its squared distance.
    pub fn within(&self, p: Coord<f64>, reach: f64) -> impl Iterator<Item = (&Segment, f64)> {
        (self.tree.locate_within_distance([p.x, p.y], reach * reach))
            .map(move |s| (s, s.distance_2(&[p.x, p.y])))
    }

    /// The nearest segment to `p`, and its distance (the same as [`RingIndex::distance`]'s
    /// with nothing skipped, from a cheaper search).
    pub fn nearest(&self, p: Coord<f64>) -> Option<(&Segment, f64)> {
        (self.tree.nearest_neighbor(&[p.x, p.y])).map(|s| (s, s.distance_2(&[p.x, p.y]).sqrt()))
    }

    /// Whether two segments of the rings meet anywhere other than at the vertex that joins
    /// consecutive segments of one ring: a valid outline has no such pair.
    pub fn self_intersects(&self) -> bool {
        self.tree.iter().any(|s| self.meets_another(s))
    }

    /// Whether segment `s` of the rings meets another anywhere other than at the vertex it
    /// shares with the next or the previous segment of its ring.
    pub fn meets_another(&self, s: &Segment) -> bool {
        (self.tree.locate_in_envelope_intersecting(&s.envelope())).any(|t| {
            (t.ring, t.index) != (s.ring, s.index)
                && !self.consecutive(s, t)
                && segments_intersect(s.a, s.b, t.a, t.b)
        })
    }

    /// Whether `s` and `t` follow each other in one ring (so they share exactly one vertex).
    fn consecutive(&self, s: &Segment, t: &Segment) -> bool {
        if s.ring != t.ring {
            return false;
        }
        let n = self.ring_lengths[s.ring];
        (s.index + 1) % n == t.index || (t.index + 1) % n == s.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, side: f64) -> Vec<Coord<f64>> {
        vec![
            Coord { x: x0, y: y0 },
            Coord {
                x: x0 + side,
                y: y0,
            },
            Coord {
                x: x0 + side,
                y: y0 + side,
            },
            Coord {
                x: x0,
                y: y0 + side,
            },
        ]
    }

    #[test]
    fn containment_respects_holes() {
        let index = RingIndex::new(&[square(0.0, 0.0, 10.0), square(4.0, 4.0, 2.0)]);
        assert!(index.contains(Coord { x: 1.0, y: 1.0 }));
        assert!(!index.contains(Coord { x: 5.0, y: 5.0 }));
        assert!(!index.contains(Coord { x: 11.0, y: 5.0 }));
        // On the level of a vertex: counted once.
        assert!(index.contains(Coord { x: 2.0, y: 4.0 }));
    }

    #[test]
    fn a_bounded_distance_is_the_distance_below_its_reach() {
        let index = RingIndex::new(&[square(0.0, 0.0, 10.0), square(4.0, 4.0, 2.0)]);
        // (1, 5): 1 from the outer ring's left side, 3 from the hole's left side (hand count).
        let p = Coord { x: 1.0, y: 5.0 };
        assert_eq!(index.distance(p), 1.0);
        assert_eq!(index.distance_within(p, 5.0, |_| false), 1.0);
        assert_eq!(index.distance_within(p, 0.5, |_| false), 0.5);
        // Skipping the outer ring leaves the hole.
        let hole_only = |s: &Segment| s.ring == 0;
        assert_eq!(index.distance_within(p, 5.0, hole_only), 3.0);
        assert_eq!(index.distance_within(p, 2.0, hole_only), 2.0);
    }

    #[test]
    fn interior_points_lie_inside() {
        use geo::{wkt, Contains, Point};
        let cases = [
            wkt!(POLYGON((0. 0.,4. 0.,4. 4.,0. 4.,0. 0.))),
            // A U whose middle is empty: the point is in an arm.
            wkt!(POLYGON((0. 0.,3. 0.,3. 3.,2. 3.,2. 1.,1. 1.,1. 3.,0. 3.,0. 0.))),
            // A hole around the middle, and vertices at the middle level.
            wkt!(POLYGON((0. 0.,4. 0.,4. 2.,4. 4.,0. 4.,0. 0.),(1. 1.,3. 1.,3. 3.,1. 3.,1. 1.))),
        ];
        for polygon in cases {
            let p = interior_point(&polygon).expect("a point");
            assert!(polygon.contains(&Point(p)), "{p:?} outside {polygon:?}");
            // The rule is geo's, so the point is too.
            let geo_point = geo::InteriorPoint::interior_point(&polygon).map(|q| q.0);
            assert_eq!(Some(p), geo_point, "{polygon:?}");
        }
        assert_eq!(
            interior_point(&wkt!(POLYGON((0. 0.,1. 0.,2. 0.,0. 0.)))),
            None
        );
    }

    #[test]
    fn distance_and_self_intersection() {
        let index = RingIndex::new(&[square(0.0, 0.0, 10.0)]);
        assert!((index.distance(Coord { x: 3.0, y: 1.0 }) - 1.0).abs() < 1e-12);
        assert!(!index.self_intersects());
        let bowtie = vec![
            Coord { x: 0.0, y: 0.0 },
            Coord { x: 2.0, y: 2.0 },
            Coord { x: 2.0, y: 0.0 },
            Coord { x: 0.0, y: 2.0 },
        ];
        assert!(RingIndex::new(&[bowtie]).self_intersects());
        // Two rings that cross each other.
        assert!(RingIndex::new(&[square(0.0, 0.0, 2.0), square(1.0, 1.0, 2.0)]).self_intersects());
        assert!(!RingIndex::new(&[square(0.0, 0.0, 2.0), square(3.0, 3.0, 2.0)]).self_intersects());
    }
}
